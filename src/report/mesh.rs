//! The mesh report: each gear's mesh as VTK (ParaView, meshio) and a PNG of its engaging teeth.

use crate::case::Case;
use crate::geometry::Side;
use crate::report::plot::{draw_png, MeshDrawing};
use crate::report::{vtk, OutputDir, ReportError};
use crate::study::mesh::MeshStudy;

/// Writes `mesh_gear{1,2}.vtk` and `.png`.
pub fn write(out: OutputDir, case: &Case, study: &MeshStudy) -> Result<(), ReportError> {
    out.case(case)?;
    for (i, run) in study.gears.iter().enumerate() {
        let index = i + 1;
        let gear = case.pair.gear(index);
        let mesh = &run.mesh;
        let title = format!("{} gear{index}, relief \"{}\"", case.name(), study.relief);
        let text = vtk::mesh_to_vtk(&title, &mesh.nodes, &mesh.elements, &mesh.element_fine);
        out.bytes(&format!("mesh_gear{index}.vtk"), text.as_bytes())?;
        let centre = nalgebra::Point2::new(0.0, gear.reference_radius);
        let drawing = MeshDrawing::new(
            mesh,
            centre,
            2.2 * gear.module() * std::f64::consts::PI / 2.0 + gear.module(),
            title,
        );
        draw_png(
            &out.path(&format!("mesh_gear{index}.png")),
            (1800, 900),
            &drawing,
        )?;
    }
    Ok(())
}

/// One line per gear for the terminal.
pub fn console(study: &MeshStudy) -> String {
    study
        .gears
        .iter()
        .enumerate()
        .map(|(i, run)| {
            let mesh = &run.mesh;
            format!(
                "gear{}: {} elements ({} on fine teeth), {} nodes, {} bore nodes, {} nodes on a fine flank; meshed in {:.3} s\n",
                i + 1,
                mesh.elements.len(),
                mesh.element_fine.iter().filter(|f| **f).count(),
                mesh.nodes.len(),
                mesh.bore_nodes.len(),
                mesh.flank(0, Side::Left).nodes.len(),
                run.wall_s
            )
        })
        .collect()
}
