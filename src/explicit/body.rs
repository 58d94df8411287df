//! An elastic body for explicit dynamics: corotational Q8 elements with lumped (HRZ) mass.
//!
//! # Corotational internal force (exact for rigid rotations of any size)
//! For each element, with reference nodes X, current nodes x and centroids X_c, x_c:
//! ```text
//! F_c = ∂x/∂X at the element centre,   R = rotation of the polar decomposition F_c = R U
//!       (2D: angle atan2(F₂₁ − F₁₂, F₁₁ + F₂₂))
//! u_loc = Rᵀ (x − x_c) − (X − X_c)        deformation in the element's rotated frame
//! f_int = R K_e u_loc                      K_e the linear Q8 stiffness in the reference frame
//! ```
//! A rigid motion x = x₀ + Q X gives R = Q and u_loc = 0, so no force and no strain energy; small
//! deformations give f_int = K u. Strain energy ½ u_locᵀ K_e u_loc per element. Stiffness-
//! proportional damping acts on the deformation rate only, v_loc = Rᵀ(v − v_c) − ω×…, written as
//! f_d = R (β_K K_e) Rᵀ (v − v̄) with v̄ the element's rigid-body velocity part removed by K_e's
//! null space (K_e annihilates translations and, to first order, the spin), so a spinning gear is
//! not braked.

use nalgebra::{Matrix2, Point2, Vector2};

use crate::fe::q8::{self, ElementMatrix, ElementVector};
use crate::fe::{elasticity_matrix, FeError, PlaneState};

/// Material data of an explicit body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExplicitMaterial {
    pub youngs_modulus: f64,
    pub poisson_ratio: f64,
    pub density: f64,
    pub plane: PlaneState,
    pub thickness: f64,
}

/// Precomputed element data and nodal masses.
pub struct ExplicitBody {
    pub reference: Vec<Point2<f64>>,
    pub elements: Vec<[usize; 8]>,
    /// K_e per element (reference frame).
    pub stiffness: Vec<ElementMatrix>,
    /// Lumped mass per node (both directions) [kg].
    pub mass: Vec<f64>,
    /// Shape-function derivatives ∂N/∂X at each element centre, for the deformation gradient.
    centre_gradients: Vec<[Vector2<f64>; 8]>,
    pub material: ExplicitMaterial,
}

/// Per-step workspace of [`ExplicitBody::internal_forces`] (no allocation in the time loop).
#[derive(Debug, Default)]
pub struct ForceOutput {
    /// Strain energy Σ ½ u_locᵀ K_e u_loc [J].
    pub strain_energy: f64,
    /// Rate of damping dissipation Σ v_locᵀ (β K_e) v_loc [W].
    pub damping_power: f64,
}

impl ExplicitBody {
    pub fn new(
        nodes: &[Point2<f64>],
        elements: &[[usize; 8]],
        material: ExplicitMaterial,
    ) -> Result<Self, FeError> {
        crate::fe::assembly::check_elements(nodes, elements)?;
        let d = elasticity_matrix(
            material.youngs_modulus,
            material.poisson_ratio,
            material.plane,
        );
        let mut mass = vec![0.0; nodes.len()];
        let mut stiffness = Vec::with_capacity(elements.len());
        let mut centre_gradients = Vec::with_capacity(elements.len());
        for e in elements {
            let xe = e.map(|i| nodes[i]);
            stiffness.push(q8::stiffness(&xe, &d, material.thickness));
            for (k, m) in q8::lumped_mass(&xe, material.density, material.thickness)
                .iter()
                .enumerate()
            {
                mass[e[k]] += m;
            }
            centre_gradients.push(centre_gradient(&xe));
        }
        Ok(ExplicitBody {
            reference: nodes.to_vec(),
            elements: elements.to_vec(),
            stiffness,
            mass,
            centre_gradients,
            material,
        })
    }

    /// Dilatational wave speed c = √(E(1−ν)/((1+ν)(1−2ν)ρ)) (seed paper eq. 31; plane strain;
    /// plane stress uses √(E/((1−ν²)ρ))).
    pub fn wave_speed(&self) -> f64 {
        let m = &self.material;
        let (e, nu, rho) = (m.youngs_modulus, m.poisson_ratio, m.density);
        match m.plane {
            PlaneState::Strain => (e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu) * rho)).sqrt(),
            PlaneState::Stress => (e / ((1.0 - nu * nu) * rho)).sqrt(),
        }
    }

    /// The seed paper's element formula Δt_cr = L/c_w with L = element area / longest edge
    /// (eqs. 28–31). Written for linear elements; a quadratic element's mid-side nodes halve the
    /// node spacing, so for Q8 this overestimates the stable step (see
    /// [`ExplicitBody::element_eigen_critical_step`]).
    pub fn paper_critical_step(&self) -> f64 {
        let c = self.wave_speed();
        self.elements
            .iter()
            .map(|e| {
                let xe = e.map(|i| self.reference[i]);
                let edges = [(0, 1), (1, 2), (2, 3), (3, 0)].map(|(a, b)| (xe[b] - xe[a]).norm());
                q8::area(&xe) / edges.iter().copied().fold(0.0, f64::max) / c
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// A rigorous bound: the global ω_max never exceeds the largest element ω_max of
    /// M_e⁻¹K_e (Irons' element eigenvalue inequality), so Δt = 2/max_e ω_e,max is stable.
    pub fn element_eigen_critical_step(&self) -> f64 {
        let mut omega2_max: f64 = 0.0;
        for (index, e) in self.elements.iter().enumerate() {
            let xe = e.map(|i| self.reference[i]);
            let m = q8::lumped_mass(&xe, self.material.density, self.material.thickness);
            let k = &self.stiffness[index];
            let scaled = ElementMatrix::from_fn(|i, j| k[(i, j)] / (m[i / 2] * m[j / 2]).sqrt());
            let max = scaled
                .symmetric_eigenvalues()
                .iter()
                .copied()
                .fold(0.0, f64::max);
            omega2_max = omega2_max.max(max);
        }
        2.0 / omega2_max.sqrt()
    }

    /// Internal (and damping) forces at positions `x` and velocities `v` (2 per node), added into
    /// `force` as −(f_int + f_damp); returns strain energy and damping power. `beta_k` is the
    /// stiffness-proportional damping coefficient [s].
    pub fn internal_forces(
        &self,
        x: &[f64],
        v: &[f64],
        beta_k: f64,
        force: &mut [f64],
    ) -> ForceOutput {
        let mut out = ForceOutput::default();
        for (index, e) in self.elements.iter().enumerate() {
            let grads = &self.centre_gradients[index];
            // Deformation gradient at the centre and its rotation.
            let mut f = Matrix2::zeros();
            for k in 0..8 {
                let xk = Vector2::new(x[2 * e[k]], x[2 * e[k] + 1]);
                f += xk * grads[k].transpose();
            }
            let angle = (f[(1, 0)] - f[(0, 1)]).atan2(f[(0, 0)] + f[(1, 1)]);
            let (s, c) = angle.sin_cos();
            // Centroids of the 8 nodes (consistent with the corner/mid-side layout).
            let (mut xc, mut yc, mut rx, mut ry) = (0.0, 0.0, 0.0, 0.0);
            for &n in e {
                xc += x[2 * n];
                yc += x[2 * n + 1];
                rx += self.reference[n].x;
                ry += self.reference[n].y;
            }
            let (xc, yc, rx, ry) = (xc / 8.0, yc / 8.0, rx / 8.0, ry / 8.0);
            let mut u_loc = ElementVector::zeros();
            let mut v_loc = ElementVector::zeros();
            let (mut vcx, mut vcy) = (0.0, 0.0);
            for &n in e {
                vcx += v[2 * n] / 8.0;
                vcy += v[2 * n + 1] / 8.0;
            }
            for (k, &n) in e.iter().enumerate() {
                let (dx, dy) = (x[2 * n] - xc, x[2 * n + 1] - yc);
                // Rᵀ d
                u_loc[2 * k] = c * dx + s * dy - (self.reference[n].x - rx);
                u_loc[2 * k + 1] = -s * dx + c * dy - (self.reference[n].y - ry);
                if beta_k > 0.0 {
                    let (wx, wy) = (v[2 * n] - vcx, v[2 * n + 1] - vcy);
                    v_loc[2 * k] = c * wx + s * wy;
                    v_loc[2 * k + 1] = -s * wx + c * wy;
                }
            }
            let k_e = &self.stiffness[index];
            let mut f_loc = k_e * u_loc;
            out.strain_energy += 0.5 * u_loc.dot(&f_loc);
            if beta_k > 0.0 {
                let f_damp = k_e * v_loc * beta_k;
                out.damping_power += v_loc.dot(&f_damp);
                f_loc += f_damp;
            }
            for (k, &n) in e.iter().enumerate() {
                let (fx, fy) = (f_loc[2 * k], f_loc[2 * k + 1]);
                force[2 * n] -= c * fx - s * fy;
                force[2 * n + 1] -= s * fx + c * fy;
            }
        }
        out
    }
}

/// ∂N/∂X at the element centre (ξ = η = 0).
fn centre_gradient(xe: &[Point2<f64>; 8]) -> [Vector2<f64>; 8] {
    let d = q8::shape_derivatives(0.0, 0.0);
    let mut j = Matrix2::zeros();
    for k in 0..8 {
        j[(0, 0)] += d[k].0 * xe[k].x;
        j[(0, 1)] += d[k].0 * xe[k].y;
        j[(1, 0)] += d[k].1 * xe[k].x;
        j[(1, 1)] += d[k].1 * xe[k].y;
    }
    let inv = j.try_inverse().unwrap_or_else(Matrix2::identity);
    std::array::from_fn(|k| inv * Vector2::new(d[k].0, d[k].1))
}
