//! Legacy VTK (ASCII) output of a mesh, readable by ParaView and meshio.

use nalgebra::Point2;
use std::fmt::Write;

/// VTK cell type of the 8-node quadratic quadrilateral (same node order as ours).
const VTK_QUADRATIC_QUAD: u8 = 23;

/// The header, points (mm) and Q8 cells of a legacy VTK unstructured grid.
fn grid(title: &str, nodes: &[Point2<f64>], elements: &[[usize; 8]]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# vtk DataFile Version 3.0\n{title} (mm)\nASCII\nDATASET UNSTRUCTURED_GRID"
    );
    let _ = writeln!(s, "POINTS {} double", nodes.len());
    for p in nodes {
        let _ = writeln!(s, "{:.9} {:.9} 0", p.x * 1e3, p.y * 1e3);
    }
    let _ = writeln!(s, "CELLS {} {}", elements.len(), elements.len() * 9);
    for e in elements {
        let _ = writeln!(
            s,
            "8 {} {} {} {} {} {} {} {}",
            e[0], e[1], e[2], e[3], e[4], e[5], e[6], e[7]
        );
    }
    let _ = writeln!(s, "CELL_TYPES {}", elements.len());
    for _ in elements {
        let _ = writeln!(s, "{VTK_QUADRATIC_QUAD}");
    }
    s
}

/// The mesh as a legacy VTK unstructured grid (coordinates in mm), with an integer cell field
/// `fine` (1 for elements of fine tooth sectors).
pub fn mesh_to_vtk(
    title: &str,
    nodes: &[Point2<f64>],
    elements: &[[usize; 8]],
    fine: &[bool],
) -> String {
    let mut s = grid(title, nodes, elements);
    let _ = writeln!(
        s,
        "CELL_DATA {}\nSCALARS fine int 1\nLOOKUP_TABLE default",
        elements.len()
    );
    for f in fine {
        let _ = writeln!(s, "{}", u8::from(*f));
    }
    s
}

/// A mesh with nodal fields (coordinates in mm): named scalars and in-plane vectors, one value
/// per node, in the units their names give.
pub fn field_to_vtk(
    title: &str,
    nodes: &[Point2<f64>],
    elements: &[[usize; 8]],
    scalars: &[(&str, Vec<f64>)],
    vectors: &[(&str, Vec<[f64; 2]>)],
) -> String {
    let mut s = grid(title, nodes, elements);
    let _ = writeln!(s, "POINT_DATA {}", nodes.len());
    for (name, values) in scalars {
        let _ = writeln!(s, "SCALARS {name} double 1\nLOOKUP_TABLE default");
        for v in values {
            let _ = writeln!(s, "{v:.9e}");
        }
    }
    for (name, values) in vectors {
        let _ = writeln!(s, "VECTORS {name} double");
        for [x, y] in values {
            let _ = writeln!(s, "{x:.9e} {y:.9e} 0");
        }
    }
    s
}
