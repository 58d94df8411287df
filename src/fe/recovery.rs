//! Stresses at nodes, for the surface of a body: from the 2 × 2 Gauss points of each Q8 (its
//! Barlow points, where the stress of a quadratic element is most accurate), extrapolated
//! bilinearly to the element's nodes, then averaged over the elements that share a node
//! (Zienkiewicz & Taylor, *The Finite Element Method*, vol. 1, §14.2–14.3).
//!
//! ```text
//! σ_g = D B(ξ_g, η_g) u_e                     ξ_g, η_g = ±1/√3
//! σ(ξ, η) = Σ_g ¼ (1 + 3 ξ ξ_g)(1 + 3 η η_g) σ_g     (the bilinear field through the four σ_g)
//! σ_node = mean over the elements at the node of σ(ξ_node, η_node)
//! ```
//! Every step is linear in the displacements, so a node's stress is a fixed row of coefficients
//! over the DOFs ([`NodalStress`]), which can be applied to many load cases (the LTCA's
//! influence of each flank node's force on the fillet stress). On a free surface the largest
//! in-plane principal stress is the tangential stress there.

use nalgebra::{Matrix3, Point2, SMatrix};

use super::q8;

/// The 3 × 16 maps from an element's displacements to the stress (σ_xx, σ_yy, τ_xy)
/// extrapolated from its 2 × 2 Gauss points to each of its 8 nodes.
pub fn element_nodal_stress(
    nodes: &[Point2<f64>; 8],
    d: &Matrix3<f64>,
) -> [SMatrix<f64, 3, 16>; 8] {
    let g = 1.0 / 3f64.sqrt();
    let points = [(-g, -g), (g, -g), (g, g), (-g, g)];
    let at_points = points.map(|(xi, eta)| d * q8::strain_matrix(nodes, xi, eta).0);
    q8::NODES.map(|(xi, eta)| {
        let mut map = SMatrix::<f64, 3, 16>::zeros();
        for ((xg, eg), s) in points.iter().zip(&at_points) {
            let weight = 0.25 * (1.0 + 3.0 * xi * xg) * (1.0 + 3.0 * eta * eg);
            map += s * weight;
        }
        map
    })
}

/// The stress at some nodes as rows over the DOFs: for node i of `targets`, component c
/// (σ_xx, σ_yy, τ_xy) is Σ coefficient · u[dof] over `rows[i][c]`.
#[derive(Debug, Clone, Default)]
pub struct NodalStress {
    pub rows: Vec<[Vec<(usize, f64)>; 3]>,
}

impl NodalStress {
    /// The recovered stress at `targets` (node indices) of the mesh `nodes`/`elements` with
    /// elasticity `d`.
    pub fn new(
        nodes: &[Point2<f64>],
        elements: &[[usize; 8]],
        d: &Matrix3<f64>,
        targets: &[usize],
    ) -> Self {
        let mut wanted = vec![None; nodes.len()];
        for (i, &n) in targets.iter().enumerate() {
            wanted[n] = Some(i);
        }
        // Per target: Σ over its elements of the extrapolation row, and the count.
        let mut sums: Vec<Vec<(usize, [f64; 3])>> = vec![Vec::new(); targets.len()];
        let mut counts = vec![0usize; targets.len()];
        for element in elements {
            let local: Vec<(usize, usize)> = element
                .iter()
                .enumerate()
                .filter_map(|(k, &n)| wanted[n].map(|i| (k, i)))
                .collect();
            if local.is_empty() {
                continue;
            }
            let xe = element.map(|n| nodes[n]);
            let maps = element_nodal_stress(&xe, d);
            for (k, i) in local {
                counts[i] += 1;
                for (j, &n) in element.iter().enumerate() {
                    for axis in 0..2 {
                        let column = 2 * j + axis;
                        let entry = [0, 1, 2].map(|c| maps[k][(c, column)]);
                        sums[i].push((2 * n + axis, entry));
                    }
                }
            }
        }
        let rows = sums
            .into_iter()
            .zip(counts)
            .map(|(mut entries, count)| {
                entries.sort_by_key(|(dof, _)| *dof);
                let scale = 1.0 / count.max(1) as f64;
                let mut merged: Vec<(usize, [f64; 3])> = Vec::new();
                for (dof, value) in entries {
                    match merged.last_mut() {
                        Some((last, sum)) if *last == dof => {
                            for c in 0..3 {
                                sum[c] += value[c];
                            }
                        }
                        _ => merged.push((dof, value)),
                    }
                }
                [0, 1, 2].map(|c| merged.iter().map(|(dof, v)| (*dof, v[c] * scale)).collect())
            })
            .collect();
        NodalStress { rows }
    }

    /// The stress (σ_xx, σ_yy, τ_xy) at target `i` under the displacements `u`.
    pub fn at(&self, i: usize, u: &[f64]) -> [f64; 3] {
        self.rows[i]
            .each_ref()
            .map(|row| row.iter().map(|(dof, c)| c * u[*dof]).sum())
    }
}

/// The normal traction along a surface of quadratic edges from the nodal forces on it: the
/// pressure p(s) = Σ N_i(s) p_i whose consistent nodal forces are the given ones,
/// ```text
/// F_i = B ∫ N_i p ds  →  M p = F / B,   M_ab = ∫ N_a N_b |dx/dξ| dξ   (ξ ∈ [−1, 1])
/// ```
/// with the edge's own isoparametric map x(ξ) = Σ N_k x_k (a straight edge with its mid-side
/// node at the middle gives L/30 [[4, 2, −1], [2, 16, 2], [−1, 2, 4]]), by 4-point Gauss
/// quadrature; B the thickness. `points` run corner, mid-side, corner, … (2n + 1 points of n
/// edges), `forces` [N] at them; returns p_i [Pa]. A uniform pressure's consistent forces come
/// back uniform.
pub fn edge_traction(points: &[Point2<f64>], forces: &[f64], thickness: f64) -> Vec<f64> {
    let n = points.len();
    assert!(
        n >= 3 && n % 2 == 1 && forces.len() == n,
        "2n + 1 points of n quadratic edges"
    );
    let mut m = nalgebra::DMatrix::<f64>::zeros(n, n);
    let (g1, g2) = (0.339_981_043_584_856, 0.861_136_311_594_053);
    let (w1, w2) = (0.652_145_154_862_546, 0.347_854_845_137_454);
    for e in (0..n - 1).step_by(2) {
        for (xi, w) in [(-g2, w2), (-g1, w1), (g1, w1), (g2, w2)] {
            let shape = [0.5 * xi * (xi - 1.0), 1.0 - xi * xi, 0.5 * xi * (xi + 1.0)];
            let slope = [xi - 0.5, -2.0 * xi, xi + 0.5];
            let tangent = (0..3).fold(nalgebra::Vector2::zeros(), |t, k| {
                t + points[e + k].coords * slope[k]
            });
            let jacobian = tangent.norm();
            for a in 0..3 {
                for b in 0..3 {
                    m[(e + a, e + b)] += w * shape[a] * shape[b] * jacobian;
                }
            }
        }
    }
    let f = nalgebra::DVector::from_iterator(n, forces.iter().map(|f| f / thickness));
    match m.cholesky() {
        Some(llt) => llt.solve(&f).iter().copied().collect(),
        None => vec![f64::NAN; n],
    }
}

/// The larger in-plane principal stress of (σ_xx, σ_yy, τ_xy).
pub fn max_principal([sx, sy, txy]: [f64; 3]) -> f64 {
    0.5 * (sx + sy) + (0.25 * (sx - sy) * (sx - sy) + txy * txy).sqrt()
}

/// The smaller in-plane principal stress (the compressive side's).
pub fn min_principal([sx, sy, txy]: [f64; 3]) -> f64 {
    0.5 * (sx + sy) - (0.25 * (sx - sy) * (sx - sy) + txy * txy).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fe::{elasticity_matrix, PlaneState};

    /// Consistent nodal forces of a uniform and of a linear pressure on a polyline of unequal
    /// straight edges come back as that pressure at every node; and on a curved edge.
    #[test]
    fn edge_traction_inverts_consistent_nodal_forces() {
        let xs = [0.0, 0.5, 1.0, 1.75, 2.5, 2.8, 3.1];
        let points: Vec<Point2<f64>> = xs.iter().map(|&x| Point2::new(x, 0.2 * x)).collect();
        let stretch = (1.0f64 + 0.04).sqrt();
        for (a, b) in [(3.0, 0.0), (1.0, 2.0)] {
            let p = |x: f64| a + b * x;
            // Simpson's rule is exact for the quadratic N_i · linear p per edge.
            let mut forces = vec![0.0; xs.len()];
            for e in (0..xs.len() - 1).step_by(2) {
                let (x0, x2) = (xs[e], xs[e + 2]);
                let length = (x2 - x0) * stretch;
                let shape = |s: f64| [0.5 * s * (s - 1.0), 1.0 - s * s, 0.5 * s * (s + 1.0)];
                for (s, w) in [(-1.0, 1.0 / 6.0), (0.0, 4.0 / 6.0), (1.0, 1.0 / 6.0)] {
                    let x = x0 + (s + 1.0) * 0.5 * (x2 - x0);
                    for (k, n) in shape(s).iter().enumerate() {
                        forces[e + k] += 0.1 * length * w * n * p(x);
                    }
                }
            }
            let traction = edge_traction(&points, &forces, 0.1);
            for (x, t) in xs.iter().zip(&traction) {
                assert!((t - p(*x)).abs() < 1e-12, "{t} against {}", p(*x));
            }
        }
        // A curved edge with its mid-side node off the middle (as a flank's, uniform in roll
        // angle): a uniform pressure's forces, integrated finely along the edge's own map, come
        // back uniform to the 4-point rule's accuracy.
        let points = [
            Point2::new(0.0, 0.0),
            Point2::new(0.55, 0.05),
            Point2::new(1.0, 0.2),
        ];
        let mut forces = [0.0; 3];
        let steps = 2000;
        for k in 0..=steps {
            let xi = -1.0 + 2.0 * k as f64 / steps as f64;
            let simpson = if k == 0 || k == steps {
                1.0
            } else if k % 2 == 1 {
                4.0
            } else {
                2.0
            } * (2.0 / steps as f64)
                / 3.0;
            let shape = [0.5 * xi * (xi - 1.0), 1.0 - xi * xi, 0.5 * xi * (xi + 1.0)];
            let slope = [xi - 0.5, -2.0 * xi, xi + 0.5];
            let tangent = (0..3).fold(nalgebra::Vector2::zeros(), |t, j| {
                t + points[j].coords * slope[j]
            });
            for j in 0..3 {
                forces[j] += 0.1 * 5.0 * shape[j] * tangent.norm() * simpson;
            }
        }
        for t in edge_traction(&points, &forces, 0.1) {
            assert!((t / 5.0 - 1.0).abs() < 1e-5, "{t}");
        }
    }

    /// A linear displacement field gives its constant stress at every node of a distorted
    /// element: the assembly of the rows (DOFs, components, averaging) is right. (Any weights
    /// that sum to one pass this; the beam test in tests/fe_elements.rs holds the
    /// extrapolation's own.)
    #[test]
    fn a_linear_field_recovers_its_stress_exactly() {
        let (nodes, elements) = crate::samples::rectangle_mesh(2.0, 1.0, 3, 3, 0.2);
        let d = elasticity_matrix(200e9, 0.3, PlaneState::Strain);
        let targets: Vec<usize> = (0..nodes.len()).collect();
        let stress = NodalStress::new(&nodes, &elements, &d, &targets);
        let (a, b, c, e) = (1e-4, 2e-4, -1e-4, 5e-5);
        let u: Vec<f64> = nodes
            .iter()
            .flat_map(|p| [a * p.x + b * p.y, c * p.x + e * p.y])
            .collect();
        let exact = d * nalgebra::Vector3::new(a, e, b + c);
        for i in 0..targets.len() {
            let s = stress.at(i, &u);
            for k in 0..3 {
                assert!(
                    (s[k] - exact[k]).abs() < 1e-6 * exact.norm(),
                    "{s:?} {exact}"
                );
            }
        }
    }
}
