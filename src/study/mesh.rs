//! The mesh study (`geardyn mesh`): both gears meshed as the LTCA meshes them, fine on the
//! tooth at the pitch point and its neighbours, checked element by element.

use crate::case::Case;
use crate::mesh::{mesh_gear, GearMesh};

use super::StudyError;

/// One gear's mesh and what it cost.
pub struct GearMeshRun {
    pub mesh: GearMesh,
    pub wall_s: f64,
}

/// The meshes of both gears for a relief variant.
pub struct MeshStudy {
    pub relief: String,
    pub gears: Vec<GearMeshRun>,
}

/// Meshes both gears with the relief variant named (default: the first).
pub fn run(case: &Case, relief: Option<&str>) -> Result<MeshStudy, StudyError> {
    let variant = super::relief_variant(case, relief)?;
    let mut gears = Vec::new();
    // The LTCA's meshes: fine the teeth that engage over its base pitch.
    let fine = crate::ltca::engaging_teeth(&case.pair);
    for index in 1..=2 {
        let gear = case.pair.gear(index);
        let started = std::time::Instant::now();
        let mesh = mesh_gear(
            gear,
            &variant.modifications[index - 1],
            &case.mesh_spec(fine[index - 1].clone()),
        );
        let wall_s = started.elapsed().as_secs_f64();
        crate::fe::assembly::check_elements(&mesh.nodes, &mesh.elements)?;
        gears.push(GearMeshRun { mesh, wall_s });
    }
    Ok(MeshStudy {
        relief: variant.name.clone(),
        gears,
    })
}
