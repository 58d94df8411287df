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

/// The unequal, shifted pair the tests hold beside the paper's: 24/40 with profile shifts
/// x = +0.3 / −0.3 on the paper's tool, load and mesh; with `inverse`, the same pair driven from
/// the 40-tooth gear (40/24, x = −0.3 / +0.3).
pub fn shifted_24_40(inverse: bool) -> Case {
    let (mut teeth, mut shifts) = ([24_i64, 40], [0.3, -0.3]);
    if inverse {
        teeth.reverse();
        shifts.reverse();
    }
    Case::load_with(
        None,
        &[
            crate::case::Override::set("gear1.teeth", teeth[0]),
            crate::case::Override::set("gear2.teeth", teeth[1]),
            crate::case::Override::set("gear1.profile_shift", shifts[0]),
            crate::case::Override::set("gear2.profile_shift", shifts[1]),
        ],
    )
    .expect("the shifted 24/40 pair is a valid case")
}

/// Gear `g` of `case` meshed as the explicit runs mesh it (the case's explicit sizes and tooth
/// layout, unmodified), fine on `fine_teeth`: e.g. teeth 0–5, a window of the 3000 rpm scene.
pub fn explicit_gear_mesh(case: &Case, g: usize, fine_teeth: Vec<usize>) -> crate::mesh::GearMesh {
    let settings = case.fe;
    crate::mesh::mesh_gear(
        &case.pair.gears[g],
        &crate::geometry::FlankModification::none(),
        &crate::mesh::MeshSpec {
            fine_size: settings.fine_size,
            coarse_size: settings.coarse_size,
            fine_teeth,
            layout: settings.tooth_layout,
        },
    )
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
    structured_q8(&corners)
}

/// A structured Q8 mesh of the rectangle with corner coordinates `xs` × `ys` (ascending;
/// graded as given). Returns (nodes, elements).
pub fn block_mesh(xs: &[f64], ys: &[f64]) -> (Vec<Point2<f64>>, Vec<[usize; 8]>) {
    let corners: Vec<Vec<Point2<f64>>> = xs
        .iter()
        .map(|&x| ys.iter().map(|&y| Point2::new(x, y)).collect())
        .collect();
    structured_q8(&corners)
}

/// The Q8 mesh of a grid of element corners `corners[i][j]` (straight edges, mid-side nodes
/// at the edge midpoints).
fn structured_q8(corners: &[Vec<Point2<f64>>]) -> (Vec<Point2<f64>>, Vec<[usize; 8]>) {
    let (nx, ny) = (corners.len() - 1, corners[0].len() - 1);
    grid_q8(nx, ny, |c, r| {
        let (i0, j0) = (c / 2, r / 2);
        let (i1, j1) = (c.div_ceil(2), r.div_ceil(2));
        Point2::from((corners[i0][j0].coords + corners[i1][j1].coords) * 0.5)
    })
}

/// A structured Q8 mesh of `nx` × `ny` elements mapped from the unit square by `map(u, v)`:
/// every node, mid-side nodes too, on the map (curved edges follow it). Returns (nodes,
/// elements).
pub fn mapped_mesh(
    nx: usize,
    ny: usize,
    map: impl Fn(f64, f64) -> Point2<f64>,
) -> (Vec<Point2<f64>>, Vec<[usize; 8]>) {
    grid_q8(nx, ny, |c, r| {
        map(c as f64 / (2 * nx) as f64, r as f64 / (2 * ny) as f64)
    })
}

/// The Q8 mesh of `nx` × `ny` elements whose node at grid point (c, r) of the
/// (2nx + 1) × (2ny + 1) node grid is `position(c, r)`.
fn grid_q8(
    nx: usize,
    ny: usize,
    position: impl Fn(usize, usize) -> Point2<f64>,
) -> (Vec<Point2<f64>>, Vec<[usize; 8]>) {
    let (cols, rows) = (2 * nx + 1, 2 * ny + 1);
    let mut nodes = Vec::new();
    let mut id = vec![vec![usize::MAX; rows]; cols];
    for (c, column) in id.iter_mut().enumerate() {
        for (r, slot) in column.iter_mut().enumerate() {
            if c % 2 == 1 && r % 2 == 1 {
                continue; // element centre: Q8 has no node there
            }
            *slot = nodes.len();
            nodes.push(position(c, r));
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
        layout: crate::mesh::ToothLayout::Graded,
    };
    crate::mesh::mesh_gear(gear, &modification, &spec)
}

/// One pair of the test matrix: the paper's case changed by `overrides` (`--set KEY=VALUE`
/// strings), and what the pair stresses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MatrixPair {
    pub name: &'static str,
    pub overrides: &'static [&'static str],
    pub what: &'static str,
}

/// The pairs every fidelity is tested on besides the paper's 36/36 (issue 28): ratios and their
/// inverse, shifts at their own centre distance and with backlash, a hunting tooth, extreme
/// modules, a thin rim, 25°, and two high contact ratios. Loads scale with the module (the tooth
/// load per face width ∝ m, as for a fixed bending stress). The 40/24 row is the 24/40 row with
/// driver and driven exchanged and the torque transferred (T₂ = T · z₁/z₂ on the new driven
/// gear), so both carry the same normal load. The rows' flank elements are about the ones the
/// LTCA's self-check recommends (`study::ltca::CONTACT_RESOLUTION_RECOMMENDED`, two Hertzian
/// half-widths under a pair's mean load, rounded to 0.01 mm) and below its limit; the paper's
/// case and the 25° row keep the paper's 0.2 mm (2.42 and 2.25 half-widths).
pub const PAIR_MATRIX: &[MatrixPair] = &[
    MatrixPair {
        name: "paper36",
        overrides: &[],
        what: "the seed paper's 36/36",
    },
    MatrixPair {
        name: "24-40",
        overrides: &[
            "mesh.fine_element_mm=0.15",
            "gear1.teeth=24",
            "gear2.teeth=40",
        ],
        what: "a ratio 5:3 (z1 not a multiple of z2)",
    },
    MatrixPair {
        name: "40-24",
        overrides: &[
            "mesh.fine_element_mm=0.15",
            "gear1.teeth=40",
            "gear2.teeth=24",
            "operating_point[0].torque_nm=86.16",
            "operating_point[1].torque_nm=86.16",
        ],
        what: "24-40 with driver and driven exchanged, the same normal load",
    },
    MatrixPair {
        name: "17-53-shift",
        overrides: &[
            "mesh.fine_element_mm=0.12",
            "gear1.teeth=17",
            "gear2.teeth=53",
            "gear1.profile_shift=0.1",
            "gear2.profile_shift=-0.1",
        ],
        what: "a pinion near its undercut limit (x_min 0.006) with a positive shift",
    },
    MatrixPair {
        name: "31-32",
        overrides: &[
            "mesh.fine_element_mm=0.17",
            "gear1.teeth=31",
            "gear2.teeth=32",
        ],
        what: "a hunting tooth pair",
    },
    MatrixPair {
        name: "19-57-shift",
        overrides: &[
            "mesh.fine_element_mm=0.12",
            "gear1.teeth=19",
            "gear2.teeth=57",
            "gear1.profile_shift=0.4",
            "gear2.profile_shift=-0.2",
        ],
        what: "shifts +0.4/−0.2 at their own zero-backlash centre distance (121.464 mm)",
    },
    MatrixPair {
        name: "19-57-backlash",
        overrides: &[
            "mesh.fine_element_mm=0.12",
            "gear1.teeth=19",
            "gear2.teeth=57",
            "gear1.profile_shift=0.4",
            "gear2.profile_shift=-0.2",
            "pair.center_distance_mm=121.6",
        ],
        what: "the same at a centre distance 0.136 mm longer (backlash)",
    },
    MatrixPair {
        name: "module-1",
        overrides: &[
            "tool.module_mm=1.0",
            "gear1.teeth=30",
            "gear2.teeth=45",
            "gear1.face_width_mm=10.0",
            "gear2.face_width_mm=10.0",
            "gear1.bore_radius_mm=5.0",
            "gear2.bore_radius_mm=8.0",
            "operating_point[0].torque_nm=7.0",
            "operating_point[1].torque_nm=7.0",
            "mesh.fine_element_mm=0.054",
            "mesh.coarse_element_mm=0.47",
            "fe.explicit_fine_element_mm=0.31",
            "fe.explicit_coarse_element_mm=0.94",
            "relief_variant[tip20-root10].gear1.tip.amount_um=6.0",
            "relief_variant[tip20-root10].gear2.tip.amount_um=6.0",
            "relief_variant[tip20-root10].gear1.root.amount_um=3.0",
            "relief_variant[tip20-root10].gear2.root.amount_um=3.0",
        ],
        what: "module 1 mm, 30/45",
    },
    MatrixPair {
        name: "module-8",
        overrides: &[
            "tool.module_mm=8.0",
            "gear1.teeth=24",
            "gear2.teeth=36",
            "gear1.face_width_mm=60.0",
            "gear2.face_width_mm=60.0",
            "gear1.bore_radius_mm=35.0",
            "gear2.bore_radius_mm=55.0",
            "operating_point[0].torque_nm=2140.0",
            "operating_point[1].torque_nm=2140.0",
            "mesh.fine_element_mm=0.38",
            "mesh.coarse_element_mm=3.8",
            "fe.explicit_fine_element_mm=2.5",
            "fe.explicit_coarse_element_mm=7.5",
            "relief_variant[tip20-root10].gear1.tip.amount_um=50.0",
            "relief_variant[tip20-root10].gear2.tip.amount_um=50.0",
            "relief_variant[tip20-root10].gear1.root.amount_um=25.0",
            "relief_variant[tip20-root10].gear2.root.amount_um=25.0",
        ],
        what: "module 8 mm, 24/36",
    },
    MatrixPair {
        name: "thin-rim",
        overrides: &["mesh.fine_element_mm=0.17", "gear2.bore_radius_mm=49.5"],
        what: "the paper's pair with a driven rim 3.8 mm (1.2 m) thick below the root",
    },
    MatrixPair {
        name: "alpha-25",
        overrides: &[
            "tool.pressure_angle_deg=25.0",
            "tool.tip_radius_coeff=0.25",
            "gear1.teeth=30",
            "gear2.teeth=45",
        ],
        what: "25° pressure angle, 30/45",
    },
    MatrixPair {
        name: "hcr-2.1",
        overrides: &[
            "mesh.fine_element_mm=0.14",
            "tool.pressure_angle_deg=18.0",
            "tool.dedendum_coeff=1.45",
            "tool.tip_radius_coeff=0.25",
            "gear1.addendum_coeff=1.2",
            "gear2.addendum_coeff=1.2",
            "gear1.teeth=32",
            "gear2.teeth=48",
        ],
        what: "high contact ratio ε_α 2.12 (18°, addendum 1.2 m)",
    },
    MatrixPair {
        name: "hcr-2.4",
        overrides: &[
            "mesh.fine_element_mm=0.11",
            "tool.pressure_angle_deg=17.0",
            "tool.dedendum_coeff=1.6",
            "tool.tip_radius_coeff=0.2",
            "gear1.addendum_coeff=1.35",
            "gear2.addendum_coeff=1.35",
            "gear1.profile_shift=0.15",
            "gear2.profile_shift=-0.15",
            "gear1.teeth=32",
            "gear2.teeth=48",
        ],
        what: "high contact ratio ε_α 2.40 (17°, addendum 1.35 m, shifts ±0.15)",
    },
    MatrixPair {
        name: "hcr-2.65",
        overrides: &[
            "mesh.fine_element_mm=0.10",
            "tool.pressure_angle_deg=16.0",
            "tool.dedendum_coeff=1.7",
            "tool.tip_radius_coeff=0.2",
            "gear1.addendum_coeff=1.4",
            "gear2.addendum_coeff=1.4",
            "gear1.profile_shift=0.1",
            "gear2.profile_shift=-0.1",
            "gear1.teeth=40",
            "gear2.teeth=60",
        ],
        what: "high contact ratio ε_α 2.65 (16°, addendum 1.4 m, shifts ±0.1)",
    },
];

impl MatrixPair {
    /// The overrides as the case loader takes them.
    pub fn parsed_overrides(&self) -> Vec<crate::case::Override> {
        self.overrides
            .iter()
            .map(|o| o.parse().expect("the matrix's overrides are KEY=VALUE"))
            .collect()
    }

    /// The pair's case (the paper's with the overrides), checked.
    pub fn case(&self) -> Result<Case, crate::case::CaseError> {
        Case::load_with(None, &self.parsed_overrides())
    }
}

/// The matrix pair called `name`.
pub fn matrix_pair(name: &str) -> Option<&'static MatrixPair> {
    PAIR_MATRIX.iter().find(|p| p.name == name)
}
