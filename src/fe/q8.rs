//! The 8-node serendipity quadrilateral (Q8) in plane stress or plane strain.
//!
//! Natural coordinates (ξ, η) ∈ [−1, 1]², corners (ξᵢ, ηᵢ) = (−1,−1), (1,−1), (1,1), (−1,1), then
//! the mid-side nodes of edges 0-1, 1-2, 2-3, 3-0 (Zienkiewicz & Taylor, *The Finite Element
//! Method*, vol. 1, §6.4):
//! ```text
//! corners   Nᵢ = ¼ (1 + ξξᵢ)(1 + ηηᵢ)(ξξᵢ + ηηᵢ − 1)
//! mid-sides N  = ½ (1 − ξ²)(1 + ηηᵢ)   (ξᵢ = 0),     N = ½ (1 + ξξᵢ)(1 − η²)   (ηᵢ = 0)
//! K_e = ∫ Bᵀ D B t dA,   M_e = ∫ ρ t NᵀN dA        (3 × 3 Gauss points; lumped: [`MassLumping`])
//! ```
//! Quadratic displacements represent linear bending stress exactly on straight-sided elements,
//! so Q8 does not lock in tooth bending (plain bilinear Q4 does). 3 × 3 integration is full for
//! undistorted elements and avoids the zero-energy mode of 2 × 2 reduced integration.

use nalgebra::{Matrix3, Point2, SMatrix, SVector, Vector3};

/// Element stiffness and mass matrices (16 × 16, DOF order u₀, v₀, u₁, v₁, …).
pub type ElementMatrix = SMatrix<f64, 16, 16>;
pub type ElementVector = SVector<f64, 16>;

/// Plane stress (thin body, σ_zz = 0) or plane strain (ε_zz = 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PlaneState {
    Stress,
    Strain,
}

/// Elasticity matrix D (Voigt: σ_xx, σ_yy, τ_xy from ε_xx, ε_yy, γ_xy).
/// ```text
/// plane stress: E/(1−ν²)        [[1, ν, 0], [ν, 1, 0], [0, 0, (1−ν)/2]]
/// plane strain: E/((1+ν)(1−2ν)) [[1−ν, ν, 0], [ν, 1−ν, 0], [0, 0, (1−2ν)/2]]
/// ```
pub fn elasticity_matrix(
    youngs_modulus: f64,
    poisson_ratio: f64,
    plane: PlaneState,
) -> Matrix3<f64> {
    let (e, nu) = (youngs_modulus, poisson_ratio);
    match plane {
        PlaneState::Stress => {
            let c = e / (1.0 - nu * nu);
            Matrix3::new(
                c,
                c * nu,
                0.0,
                c * nu,
                c,
                0.0,
                0.0,
                0.0,
                c * (1.0 - nu) / 2.0,
            )
        }
        PlaneState::Strain => {
            let c = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
            Matrix3::new(
                c * (1.0 - nu),
                c * nu,
                0.0,
                c * nu,
                c * (1.0 - nu),
                0.0,
                0.0,
                0.0,
                c * (1.0 - 2.0 * nu) / 2.0,
            )
        }
    }
}

const CORNERS: [(f64, f64); 4] = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
/// Natural coordinates (ξ, η) of the 8 nodes: the corners, then the mid-sides of edges 0-1, 1-2,
/// 2-3, 3-0.
pub const NODES: [(f64, f64); 8] = [
    (-1.0, -1.0),
    (1.0, -1.0),
    (1.0, 1.0),
    (-1.0, 1.0),
    (0.0, -1.0),
    (1.0, 0.0),
    (0.0, 1.0),
    (-1.0, 0.0),
];
const GAUSS_3: [(f64, f64); 3] = [
    (-0.774_596_669_241_483_4, 5.0 / 9.0),
    (0.0, 8.0 / 9.0),
    (0.774_596_669_241_483_4, 5.0 / 9.0),
];

/// Shape functions N(ξ, η).
pub fn shape(xi: f64, eta: f64) -> [f64; 8] {
    let mut n = [0.0; 8];
    for (i, (xi_i, eta_i)) in CORNERS.iter().enumerate() {
        n[i] = 0.25 * (1.0 + xi * xi_i) * (1.0 + eta * eta_i) * (xi * xi_i + eta * eta_i - 1.0);
    }
    n[4] = 0.5 * (1.0 - xi * xi) * (1.0 - eta);
    n[5] = 0.5 * (1.0 + xi) * (1.0 - eta * eta);
    n[6] = 0.5 * (1.0 - xi * xi) * (1.0 + eta);
    n[7] = 0.5 * (1.0 - xi) * (1.0 - eta * eta);
    n
}

/// Derivatives (∂N/∂ξ, ∂N/∂η).
pub fn shape_derivatives(xi: f64, eta: f64) -> [(f64, f64); 8] {
    let mut d = [(0.0, 0.0); 8];
    for (i, (xi_i, eta_i)) in CORNERS.iter().enumerate() {
        d[i] = (
            0.25 * xi_i * (1.0 + eta * eta_i) * (2.0 * xi * xi_i + eta * eta_i),
            0.25 * eta_i * (1.0 + xi * xi_i) * (xi * xi_i + 2.0 * eta * eta_i),
        );
    }
    d[4] = (-xi * (1.0 - eta), -0.5 * (1.0 - xi * xi));
    d[5] = (0.5 * (1.0 - eta * eta), -(1.0 + xi) * eta);
    d[6] = (-xi * (1.0 + eta), 0.5 * (1.0 - xi * xi));
    d[7] = (-0.5 * (1.0 - eta * eta), -(1.0 - xi) * eta);
    d
}

/// Strain-displacement matrix B (3 × 16) and det J at (ξ, η).
pub fn strain_matrix(nodes: &[Point2<f64>; 8], xi: f64, eta: f64) -> (SMatrix<f64, 3, 16>, f64) {
    let d = shape_derivatives(xi, eta);
    let (mut j11, mut j12, mut j21, mut j22) = (0.0, 0.0, 0.0, 0.0);
    for (k, (dxi, deta)) in d.iter().enumerate() {
        j11 += dxi * nodes[k].x;
        j12 += dxi * nodes[k].y;
        j21 += deta * nodes[k].x;
        j22 += deta * nodes[k].y;
    }
    let det = j11 * j22 - j12 * j21;
    let mut b = SMatrix::<f64, 3, 16>::zeros();
    for (k, (dxi, deta)) in d.iter().enumerate() {
        let dx = (j22 * dxi - j12 * deta) / det;
        let dy = (-j21 * dxi + j11 * deta) / det;
        b[(0, 2 * k)] = dx;
        b[(1, 2 * k + 1)] = dy;
        b[(2, 2 * k)] = dy;
        b[(2, 2 * k + 1)] = dx;
    }
    (b, det)
}

/// Smallest det J over the 3 × 3 Gauss points (≤ 0: the element is inverted or degenerate).
pub fn min_jacobian(nodes: &[Point2<f64>; 8]) -> f64 {
    let mut min = f64::INFINITY;
    for (xi, _) in GAUSS_3 {
        for (eta, _) in GAUSS_3 {
            min = min.min(strain_matrix(nodes, xi, eta).1);
        }
    }
    min
}

/// Element stiffness K_e = Σ Bᵀ D B t det J w over 3 × 3 Gauss points.
pub fn stiffness(nodes: &[Point2<f64>; 8], d: &Matrix3<f64>, thickness: f64) -> ElementMatrix {
    let mut k = ElementMatrix::zeros();
    for (xi, wx) in GAUSS_3 {
        for (eta, wy) in GAUSS_3 {
            let (b, det) = strain_matrix(nodes, xi, eta);
            k += b.transpose() * d * b * (det * wx * wy * thickness);
        }
    }
    k
}

/// Element area ∫ dA.
pub fn area(nodes: &[Point2<f64>; 8]) -> f64 {
    let mut a = 0.0;
    for (xi, wx) in GAUSS_3 {
        for (eta, wy) in GAUSS_3 {
            a += strain_matrix(nodes, xi, eta).1 * wx * wy;
        }
    }
    a
}

/// How the element mass is put on the nodes (a diagonal mass for explicit dynamics).
///
/// Both are positive and conserve the element mass ρ t A, and both converge to the consistent
/// mass's frequencies under refinement; they differ in the corner share, which sets the highest
/// frequency of the mesh (the explicit step) and, in a penalty contact, the frequency of the
/// light surface nodes against their contact springs. The row sums of the Q8 consistent mass
/// are negative at the corners, so row-sum lumping is not usable.
/// (The case file and the command line spell it alike: `corner-twelfth`, `hrz`.)
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum MassLumping {
    /// Diagonal of the consistent mass scaled to the element mass (Hinton, Rock & Zienkiewicz
    /// 1976): about 4 % of the element mass at each corner and 21 % at each mid-side node of a
    /// square. The more accurate frequencies of the two.
    Hrz,
    /// 1/12 of the element mass at each corner and 1/6 at each mid-side node, whatever the
    /// shape: the r = 1/12 member of the positive family m_corner = r·m_e, m_mid = (1 − 4r)/4·m_e
    /// studied for Q8 dispersion (Kolman, Plešek et al. 2007; Hou et al. 2024). Heavier
    /// corners: the highest element frequency drops by about 20 % and the contact springs on
    /// the flank's corner nodes stop limiting the step (the pair's stable step 1.49× HRZ's at
    /// the explicit default mesh), for frequency errors about 1.6× HRZ's (converging as fast:
    /// a tooth-sized cantilever's first four modes within 1.8 % at 1 mm elements, HRZ 1.2 %).
    #[default]
    CornerTwelfth,
}

impl MassLumping {
    /// How a case file names it.
    pub fn name(self) -> &'static str {
        match self {
            MassLumping::Hrz => "hrz",
            MassLumping::CornerTwelfth => "corner-twelfth",
        }
    }
}

/// Lumped (diagonal) mass per node (the same for both directions), by `lumping`.
pub fn lumped_mass(
    nodes: &[Point2<f64>; 8],
    density: f64,
    thickness: f64,
    lumping: MassLumping,
) -> [f64; 8] {
    match lumping {
        MassLumping::Hrz => {
            let diag = consistent_mass(nodes, density, thickness).diagonal();
            let diag: [f64; 8] = std::array::from_fn(|k| diag[2 * k]);
            let sum: f64 = diag.iter().sum();
            let mass = density * thickness * area(nodes);
            diag.map(|m| m * mass / sum)
        }
        MassLumping::CornerTwelfth => {
            let mass = density * thickness * area(nodes);
            std::array::from_fn(|k| if k < 4 { mass / 12.0 } else { mass / 6.0 })
        }
    }
}

/// Consistent mass M_e = ∫ ρ t NᵀN dA (3 × 3 Gauss points), DOF order u₀, v₀, u₁, v₁, …: the
/// reference the lumped masses are checked against.
pub fn consistent_mass(nodes: &[Point2<f64>; 8], density: f64, thickness: f64) -> ElementMatrix {
    let mut m = ElementMatrix::zeros();
    for (xi, wx) in GAUSS_3 {
        for (eta, wy) in GAUSS_3 {
            let n = shape(xi, eta);
            let dv = strain_matrix(nodes, xi, eta).1 * wx * wy * density * thickness;
            for a in 0..8 {
                for b in 0..8 {
                    let mab = n[a] * n[b] * dv;
                    m[(2 * a, 2 * b)] += mab;
                    m[(2 * a + 1, 2 * b + 1)] += mab;
                }
            }
        }
    }
    m
}

/// Strain energy of the element under a displacement of any size, with the Green–Lagrange
/// strain (total Lagrangian, St Venant–Kirchhoff material):
/// ```text
/// F = I + ∂u/∂X,   E = ½ (Fᵀ F − I),   W = ½ ∫ {E}ᵀ D {E} t dA,   {E} = (E_xx, E_yy, 2E_xy)
/// ```
/// E vanishes for every rigid rotation, however large, so W = 0 there; for small displacements
/// W → ½ uᵀ K_e u. This is the measure the explicit solver's large-rotation check uses.
pub fn green_lagrange_strain_energy(
    nodes: &[Point2<f64>; 8],
    d: &Matrix3<f64>,
    displacement: &ElementVector,
    thickness: f64,
) -> f64 {
    let mut energy = 0.0;
    for (xi, wx) in GAUSS_3 {
        for (eta, wy) in GAUSS_3 {
            let (b, det) = strain_matrix(nodes, xi, eta);
            // Displacement gradient from the B matrix rows: b[(0, 2k)] = ∂N_k/∂x, b[(1, 2k+1)] = ∂N_k/∂y.
            let (mut ux, mut uy, mut vx, mut vy) = (0.0, 0.0, 0.0, 0.0);
            for k in 0..8 {
                let (dx, dy) = (b[(0, 2 * k)], b[(1, 2 * k + 1)]);
                ux += dx * displacement[2 * k];
                uy += dy * displacement[2 * k];
                vx += dx * displacement[2 * k + 1];
                vy += dy * displacement[2 * k + 1];
            }
            let e_xx = ux + 0.5 * (ux * ux + vx * vx);
            let e_yy = vy + 0.5 * (uy * uy + vy * vy);
            let gamma = uy + vx + ux * uy + vx * vy;
            let e = Vector3::new(e_xx, e_yy, gamma);
            energy += 0.5 * e.dot(&(d * e)) * det * wx * wy * thickness;
        }
    }
    energy
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> [Point2<f64>; 8] {
        [
            Point2::new(0.0, 0.0),
            Point2::new(2.0, 0.0),
            Point2::new(2.0, 1.0),
            Point2::new(0.0, 1.0),
            Point2::new(1.0, 0.0),
            Point2::new(2.0, 0.5),
            Point2::new(1.0, 1.0),
            Point2::new(0.0, 0.5),
        ]
    }

    #[test]
    fn shape_functions_partition_unity_and_interpolate_nodes() {
        for (i, (xi, eta)) in NODES.iter().enumerate() {
            let n = shape(*xi, *eta);
            for (j, v) in n.iter().enumerate() {
                assert!((v - if i == j { 1.0 } else { 0.0 }).abs() < 1e-15);
            }
        }
        let n = shape(0.3, -0.7);
        assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        let d = shape_derivatives(0.3, -0.7);
        assert!(d.iter().map(|p| p.0).sum::<f64>().abs() < 1e-15);
        assert!(d.iter().map(|p| p.1).sum::<f64>().abs() < 1e-15);
    }

    #[test]
    fn stiffness_is_symmetric_with_three_rigid_modes() {
        let d = elasticity_matrix(206e9, 0.3, PlaneState::Strain);
        let k = stiffness(&square(), &d, 0.01);
        assert!((k - k.transpose()).norm() < 1e-6 * k.norm());
        let eig = k.symmetric_eigen().eigenvalues;
        let mut sorted: Vec<f64> = eig.iter().copied().collect();
        sorted.sort_by(f64::total_cmp);
        let scale = sorted[15];
        assert!(
            sorted[..3].iter().all(|v| v.abs() < 1e-10 * scale),
            "{sorted:?}"
        );
        assert!(
            sorted[3] > 1e-6 * scale,
            "a spurious zero-energy mode: {sorted:?}"
        );
    }

    /// A rigid rotation of any angle stores no Green–Lagrange strain energy; a small stretch
    /// stores ½ uᵀ K u.
    #[test]
    fn finite_rotation_has_zero_green_lagrange_energy() {
        let nodes = square();
        let d = elasticity_matrix(206e9, 0.3, PlaneState::Strain);
        for angle in [1e-3, 0.3, 1.0, 2.5, std::f64::consts::PI, 5.0] {
            let (s, c) = f64::sin_cos(angle);
            let u = ElementVector::from_fn(|i, _| {
                let p = nodes[i / 2];
                let rotated = (c * p.x - s * p.y, s * p.x + c * p.y);
                if i % 2 == 0 {
                    rotated.0 - p.x
                } else {
                    rotated.1 - p.y
                }
            });
            let w = green_lagrange_strain_energy(&nodes, &d, &u, 0.01);
            // Against the energy of a unit strain over the element; round-off in E is ~1e-16, so
            // W is ~1e-32 of it. Linear strain would give (1 − cos θ)² of it instead.
            let unit_strain_energy: f64 = 0.5 * 206e9 * 2.0 * 0.01;
            assert!(
                w.abs() < 1e-24 * unit_strain_energy,
                "angle {angle}: W = {w:e}"
            );
        }
        let u = ElementVector::from_fn(|i, _| {
            if i % 2 == 0 {
                1e-7 * nodes[i / 2].x
            } else {
                0.0
            }
        });
        let k = stiffness(&nodes, &d, 0.01);
        let linear = 0.5 * u.dot(&(k * u));
        let w = green_lagrange_strain_energy(&nodes, &d, &u, 0.01);
        assert!(((w - linear) / linear).abs() < 1e-6, "{w:e} vs {linear:e}");
    }

    #[test]
    fn lumped_masses_are_positive_and_sum_to_the_element_mass() {
        let total = 7850.0 * 0.01 * 2.0;
        for lumping in [MassLumping::Hrz, MassLumping::CornerTwelfth] {
            let m = lumped_mass(&square(), 7850.0, 0.01, lumping);
            assert!(m.iter().all(|v| *v > 0.0));
            assert!((m.iter().sum::<f64>() - total).abs() < 1e-9);
        }
        // HRZ on a square: the consistent diagonal's shares, corner 6/152 = 3/76.
        let hrz = lumped_mass(&square(), 7850.0, 0.01, MassLumping::Hrz);
        assert!((hrz[0] / total - 3.0 / 76.0).abs() < 1e-12);
        let consistent = consistent_mass(&square(), 7850.0, 0.01);
        let rigid = ElementVector::from_fn(|i, _| if i % 2 == 0 { 1.0 } else { 0.0 });
        assert!(((rigid.transpose() * consistent * rigid)[0] - total).abs() < 1e-9);
        assert!((area(&square()) - 2.0).abs() < 1e-14);
    }
}
