//! Canonical problems shared by tests, benchmarks and docs.
//!
//! The seed paper's pair comes from the embedded default case file (`data/cases/paper36.toml`),
//! so there is one definition of it.

use crate::case::Case;
use crate::geometry::{BasicRack, FlankReliefSpec, GearPair, GearSpec};

/// The embedded default case: the seed paper's pair (Z1 = Z2 = 36, m = 3.18 mm, α = 20°).
pub fn paper36_case() -> Case {
    Case::embedded_default().expect("the embedded default case is valid")
}

/// The explicit bodies' material of the paper's pair (steel, plane strain, 25.4 mm face width,
/// the case's mass lumping, corner-twelfth).
pub fn paper36_explicit_material() -> crate::explicit::body::ExplicitMaterial {
    paper36_case().explicit_material()
}

/// Rack and the two gear specs of the paper's pair.
pub fn paper36_specs() -> (BasicRack, GearSpec, GearSpec) {
    let spec = paper36_case().pair_spec;
    (spec.rack, spec.gears[0], spec.gears[1])
}

/// The paper's pair, checked.
pub fn paper36_pair() -> GearPair {
    paper36_case().pair
}

/// The paper's relief on one gear: 20 µm tip and 10 µm root, linear, long relief
/// (variant `tip20-root10` of the default case).
pub fn paper_relief() -> FlankReliefSpec {
    let case = paper36_case();
    let variant = case
        .relief_variant("tip20-root10")
        .expect("the default case has the paper's relief");
    variant.requests[0]
}

use nalgebra::Point2;

/// A structured Q8 mesh of the rectangle [0, length] × [−height/2, height/2] with `nx` × `ny`
/// elements; `skew` shifts interior corner columns alternately by skew·Δx (distorted elements,
/// straight edges) for patch tests. Returns (nodes, elements).
pub fn rectangle_mesh(
    length: f64,
    height: f64,
    nx: usize,
    ny: usize,
    skew: f64,
) -> (Vec<Point2<f64>>, Vec<[usize; 8]>) {
    let (cols, rows) = (2 * nx + 1, 2 * ny + 1);
    let dx = length / nx as f64;
    let corner_x = |i: usize, j: usize| {
        let base = i as f64 * dx;
        if i > 0 && i < nx && j > 0 && j < ny {
            base + skew * dx * if (i + j).is_multiple_of(2) { 1.0 } else { -1.0 }
        } else {
            base
        }
    };
    // Corner positions, then mid-sides as edge midpoints (straight edges).
    let mut corners = vec![vec![Point2::origin(); ny + 1]; nx + 1];
    for (i, column) in corners.iter_mut().enumerate() {
        for (j, p) in column.iter_mut().enumerate() {
            *p = Point2::new(
                corner_x(i, j),
                -0.5 * height + height * j as f64 / ny as f64,
            );
        }
    }
    let mut nodes = Vec::new();
    let mut id = vec![vec![usize::MAX; rows]; cols];
    for (c, column) in id.iter_mut().enumerate() {
        for (r, slot) in column.iter_mut().enumerate() {
            let (i0, j0) = (c / 2, r / 2);
            let (i1, j1) = (c.div_ceil(2), r.div_ceil(2));
            if c % 2 == 1 && r % 2 == 1 {
                continue; // element centre: Q8 has no node there
            }
            let p = Point2::from((corners[i0][j0].coords + corners[i1][j1].coords) * 0.5);
            *slot = nodes.len();
            nodes.push(p);
        }
    }
    let mut elements = Vec::new();
    for i in 0..nx {
        for j in 0..ny {
            let (c, r) = (2 * i, 2 * j);
            elements.push([
                id[c][r],
                id[c + 2][r],
                id[c + 2][r + 2],
                id[c][r + 2],
                id[c + 1][r],
                id[c + 2][r + 1],
                id[c + 1][r + 2],
                id[c][r + 1],
            ]);
        }
    }
    (nodes, elements)
}

/// The paper's driver gear meshed with the paper's relief: teeth 0, 1 and z−1 fine.
pub fn paper36_gear_mesh(fine_size: f64, coarse_size: f64) -> crate::mesh::GearMesh {
    let case = paper36_case();
    let modification = case
        .relief_variant("tip20-root10")
        .expect("paper relief")
        .modifications[0];
    let gear = &case.pair.gears[0];
    let spec = crate::mesh::MeshSpec {
        fine_size,
        coarse_size,
        fine_teeth: vec![0, 1, gear.teeth() as usize - 1],
    };
    crate::mesh::mesh_gear(gear, &modification, &spec)
}
