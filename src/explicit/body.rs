//! An elastic body for explicit dynamics: corotational Q8 elements with a lumped mass
//! ([`MassLumping`]).
//!
//! # Corotational internal force (exact for rigid rotations of any size)
//! For each element, with reference nodes X, current nodes x and centroids X_c, x_c:
//! ```text
//! F_c = ∂x/∂X at the element centre,   R = rotation of the polar decomposition F_c = R U
//!       (2D: (cos, sin) ∝ (F₁₁ + F₂₂, F₂₁ − F₁₂))
//! u_loc = Rᵀ (x − x_c) − (X − X_c)        deformation in the element's rotated frame
//! f_int = R K_e u_loc                      K_e the linear Q8 stiffness in the reference frame
//! ```
//! A rigid motion x = x₀ + Q X gives R = Q and u_loc = 0, so no force and no strain energy; small
//! deformations give f_int = K u. Strain energy ½ u_locᵀ K_e u_loc per element. Stiffness-
//! proportional damping f_d = R (β_K K_e) Rᵀ (v − v_c) acts on the deformation rate only: K_e
//! annihilates the translation and, to first order, the spin part of the velocity, so a spinning
//! gear is not braked.

use nalgebra::{Matrix2, Point2, Vector2};

use crate::fe::q8::{self, ElementMatrix};
use crate::fe::{elasticity_matrix, FeError, MassLumping, PlaneState};

/// Material data of an explicit body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExplicitMaterial {
    pub youngs_modulus: f64,
    pub poisson_ratio: f64,
    pub density: f64,
    pub plane: PlaneState,
    pub thickness: f64,
    /// How the element masses go on the nodes.
    pub lumping: MassLumping,
}

/// The shared data of congruent elements: stiffness, centre gradients and node offsets from the
/// centroid, all in the prototype's reference frame.
pub struct Prototype {
    pub stiffness: ElementMatrix,
    /// The same matrix as plain rows, for the time-loop kernel (K_e is symmetric, so rows are
    /// columns: nalgebra stores column-major, and this copy keeps the kernel free of its
    /// generic product).
    rows: [[f64; 16]; 16],
    /// ∂N/∂X at the element centre (prototype frame), for the deformation gradient.
    centre_gradients: [Vector2<f64>; 8],
    /// Reference node positions minus the centroid of the 8 nodes (prototype frame).
    offsets: [Vector2<f64>; 8],
}

/// Precomputed element data and nodal masses.
///
/// A gear's sectors are rotated copies of a few layouts. With `symmetry = Some(z)`, elements that
/// are the same element turned by a multiple of 2π/z share one [`Prototype`]: the corotational
/// frame absorbs the sector rotation (F is taken against the prototype's coordinates, so its
/// rotation R includes the turn), and the stiffness data stay cache-resident instead of being
/// streamed from memory every step.
pub struct ExplicitBody {
    pub reference: Vec<Point2<f64>>,
    pub elements: Vec<[usize; 8]>,
    /// Prototype index of each element.
    pub prototype_of: Vec<u32>,
    /// Elements in batches of one prototype: consecutive batches share their matrix, which then
    /// stays in the L1 cache.
    batches: Vec<Batch<LANES>>,
    /// The same elements for the AVX-512 kernel: [`WIDE_LANES`] to a batch, a prototype's last
    /// four or fewer in a batch of [`LANES`] (in prototype order, as `batches`).
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    wide_batches: Vec<WideOrNarrow>,
    pub prototypes: Vec<Prototype>,
    /// Lumped mass per node (both directions) [kg].
    pub mass: Vec<f64>,
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
    /// Body without symmetry: one prototype per element.
    pub fn new(
        nodes: &[Point2<f64>],
        elements: &[[usize; 8]],
        material: ExplicitMaterial,
    ) -> Result<Self, FeError> {
        Self::with_symmetry(nodes, elements, material, None)
    }

    /// Body whose congruent elements under rotation by k·2π/z share their data.
    pub fn with_symmetry(
        nodes: &[Point2<f64>],
        elements: &[[usize; 8]],
        material: ExplicitMaterial,
        symmetry: Option<usize>,
    ) -> Result<Self, FeError> {
        crate::fe::assembly::check_elements(nodes, elements)?;
        let d = elasticity_matrix(
            material.youngs_modulus,
            material.poisson_ratio,
            material.plane,
        );
        let mut prototypes = Vec::new();
        let mut prototype_of = Vec::with_capacity(elements.len());
        let mut index = std::collections::HashMap::new();
        let scale = nodes
            .iter()
            .map(|p| p.coords.norm())
            .fold(0.0, f64::max)
            .max(1e-12);
        for e in elements {
            let xe = e.map(|i| nodes[i]);
            // Turn the element back into sector 0 (tooth-local frame: tooth k at k·2π/z).
            let local = match symmetry {
                Some(z) => {
                    let pitch = 2.0 * std::f64::consts::PI / z as f64;
                    let c = xe.iter().fold(Vector2::zeros(), |a, p| a + p.coords) / 8.0;
                    let sector = ((-c.x).atan2(c.y) / pitch).round();
                    let back = nalgebra::Rotation2::new(-sector * pitch);
                    xe.map(|p| Point2::from(back * p.coords))
                }
                None => xe,
            };
            // Congruent elements agree to round-off (1e-16 of the body size); quantize at 1e-12
            // of it. A coarser key shared elements that are congruent only to the mesher's
            // tolerance: a fine sector's base element and a coarse sector's differ by 2e-11 m
            // where the two tooth layouts meet the base, and a prototype's reference shape off
            // by that much strains the element by ~1e-7 at rest (forces 1e-3 off under a
            // 5e-5 strain, tests/explicit.rs `sector_prototypes_give_the_same_forces`).
            let key: Vec<i64> = match symmetry {
                Some(_) => local
                    .iter()
                    .flat_map(|p| {
                        [
                            (p.x / scale * 1e12).round() as i64,
                            (p.y / scale * 1e12).round() as i64,
                        ]
                    })
                    .collect(),
                None => vec![prototype_of.len() as i64],
            };
            let id = *index.entry(key).or_insert_with(|| {
                let centroid = local.iter().fold(Vector2::zeros(), |a, p| a + p.coords) / 8.0;
                let stiffness = q8::stiffness(&local, &d, material.thickness);
                prototypes.push(Prototype {
                    rows: std::array::from_fn(|i| std::array::from_fn(|j| stiffness[(i, j)])),
                    stiffness,
                    centre_gradients: centre_gradient(&local),
                    offsets: local.map(|p| p.coords - centroid),
                });
                prototypes.len() - 1
            });
            prototype_of.push(id as u32);
        }
        let members = prototype_members(&prototype_of, prototypes.len());
        let batches = make_batches(elements, &members);
        let wide_batches = make_wide_batches(elements, &members);
        let mut body = ExplicitBody {
            reference: nodes.to_vec(),
            elements: elements.to_vec(),
            prototype_of,
            batches,
            wide_batches,
            prototypes,
            mass: vec![0.0; nodes.len()],
            material,
        };
        body.set_element_mass_factors(&vec![1.0; elements.len()]);
        Ok(body)
    }

    /// Number of element batches of the kernel this CPU runs (elements / batches: the lane
    /// fill, at most [`WIDE_LANES`] with AVX-512, [`LANES`] otherwise).
    pub fn batch_count(&self) -> usize {
        match Kernel::best() {
            Kernel::Avx512 => self.wide_batches.len(),
            Kernel::Avx2 | Kernel::Portable => self.batches.len(),
        }
    }

    /// The element's stiffness matrix in its prototype frame.
    pub fn element_stiffness(&self, element: usize) -> &ElementMatrix {
        &self.prototypes[self.prototype_of[element] as usize].stiffness
    }

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
        self.paper_critical_steps()
            .into_iter()
            .fold(f64::INFINITY, f64::min)
    }

    /// [`ExplicitBody::paper_critical_step`] of each element.
    pub fn paper_critical_steps(&self) -> Vec<f64> {
        let c = self.wave_speed();
        self.elements
            .iter()
            .map(|e| {
                let xe = e.map(|i| self.reference[i]);
                let edges = [(0, 1), (1, 2), (2, 3), (3, 0)].map(|(a, b)| (xe[b] - xe[a]).norm());
                q8::area(&xe) / edges.iter().copied().fold(0.0, f64::max) / c
            })
            .collect()
    }

    /// A rigorous bound: the global ω_max never exceeds the largest element ω_max of
    /// M_e⁻¹K_e (Irons' element eigenvalue inequality), so Δt = 2/max_e ω_e,max is stable.
    pub fn element_eigen_critical_step(&self) -> f64 {
        self.element_critical_steps()
            .into_iter()
            .fold(f64::INFINITY, f64::min)
    }

    /// Each element's own stable step 2/ω_e,max, ω_e,max² the largest eigenvalue of M_e⁻¹K_e
    /// with the element's own lumped masses at the material's density (what a group of
    /// elements stepped on its own would allow: validation/performance, subcycling).
    /// Congruent elements share their prototype, so the eigenvalue problem is solved once per
    /// prototype (on its first element).
    pub fn element_critical_steps(&self) -> Vec<f64> {
        let mut first = vec![usize::MAX; self.prototypes.len()];
        for (e, &p) in self.prototype_of.iter().enumerate().rev() {
            first[p as usize] = e;
        }
        let per_prototype: Vec<f64> = first
            .iter()
            .map(|&index| {
                let m = self.element_masses(index);
                let k = self.element_stiffness(index);
                let scaled =
                    ElementMatrix::from_fn(|i, j| k[(i, j)] / (m[i / 2] * m[j / 2]).sqrt());
                let omega2 = scaled
                    .symmetric_eigenvalues()
                    .iter()
                    .copied()
                    .fold(0.0, f64::max);
                2.0 / omega2.sqrt()
            })
            .collect();
        self.prototype_of
            .iter()
            .map(|&p| per_prototype[p as usize])
            .collect()
    }

    /// The lumped masses element `element` puts on its 8 nodes at the material's density [kg].
    pub fn element_masses(&self, element: usize) -> [f64; 8] {
        let xe = self.elements[element].map(|i| self.reference[i]);
        q8::lumped_mass(
            &xe,
            self.material.density,
            self.material.thickness,
            self.material.lumping,
        )
    }

    /// Sets the nodal masses to Σₑ sₑ mₑ: each element's lumped masses times its factor
    /// `factors[e]` (per-element mass scaling; all ones give the body's own masses).
    pub fn set_element_mass_factors(&mut self, factors: &[f64]) {
        assert_eq!(factors.len(), self.elements.len(), "one factor per element");
        self.mass.iter_mut().for_each(|m| *m = 0.0);
        for (e, &s) in factors.iter().enumerate() {
            let m = self.element_masses(e);
            for (k, &node) in self.elements[e].iter().enumerate() {
                self.mass[node] += s * m[k];
            }
        }
    }

    /// Internal (and damping) forces at positions `x` and velocities `v` (2 per node), added into
    /// `force` as −(f_int + f_damp); returns strain energy and damping power. `beta_k` is the
    /// stiffness-proportional damping coefficient [s].
    ///
    /// Elements run in batches of [`LANES`] congruent elements (one prototype, different
    /// sectors), lane l of every vector one element. On x86-64 with AVX2 and FMA (chosen at run
    /// time) the kernel is written with intrinsics (`avx2` below), and with AVX-512 (F and DQ)
    /// eight elements go side by side (`avx512`: a prototype's batches of four paired); elsewhere
    /// the portable [`ExplicitBody::batched_forces`] does the same arithmetic on plain arrays.
    /// Each element's forces are the same operations in every kernel (the portable one without
    /// fused multiply-adds); only the order in which elements sharing a node add into it, and
    /// the order of the energy sums, differ between them. (Tried and
    /// dropped: the 16×16 product in single precision, 8-wide, no faster; the damping folded into
    /// one product K (u_loc + β v_loc), which halves the multiply-adds but leaves the strain
    /// energy and the damping power, both needed for the energy account, unknown.)
    pub fn internal_forces(
        &self,
        x: &[f64],
        v: &[f64],
        beta_k: f64,
        force: &mut [f64],
    ) -> ForceOutput {
        assert!(
            x.len() == 2 * self.reference.len() && v.len() == x.len() && force.len() == x.len()
        );
        self.forces_on(Kernel::best(), x, v, beta_k, force)
    }

    /// [`ExplicitBody::internal_forces`] on the given kernel, if this CPU has it (for the
    /// tests that hold the kernels against each other); None if it does not.
    pub fn internal_forces_on(
        &self,
        kernel: Kernel,
        x: &[f64],
        v: &[f64],
        beta_k: f64,
        force: &mut [f64],
    ) -> Option<ForceOutput> {
        assert!(
            x.len() == 2 * self.reference.len() && v.len() == x.len() && force.len() == x.len()
        );
        kernel
            .available()
            .then(|| self.forces_on(kernel, x, v, beta_k, force))
    }

    /// The kernel's forces; `kernel` must be available on this CPU and the slices checked as
    /// in [`ExplicitBody::internal_forces`].
    fn forces_on(
        &self,
        kernel: Kernel,
        x: &[f64],
        v: &[f64],
        beta_k: f64,
        force: &mut [f64],
    ) -> ForceOutput {
        debug_assert!(kernel.available());
        match kernel {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: the callers pass a kernel this CPU has (`Kernel::best`, or checked by
            // `available`): AVX-512 F and DQ, AVX2 and FMA; every node index is below
            // reference.len() (checked at construction) and the slices hold 2 values per node
            // (the callers' assert), which the kernel's unchecked indexing relies on.
            Kernel::Avx512 => unsafe { avx512::internal_forces(self, x, v, beta_k, force) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as above, for AVX2 and FMA.
            Kernel::Avx2 => unsafe { avx2::internal_forces(self, x, v, beta_k, force) },
            // Elsewhere `available` holds for the portable kernel only.
            #[cfg(not(target_arch = "x86_64"))]
            Kernel::Avx512 | Kernel::Avx2 => self.batched_forces(x, v, beta_k, force),
            Kernel::Portable => self.batched_forces(x, v, beta_k, force),
        }
    }

    /// The portable kernel. Positions go in lanes 0..LANES of the work arrays and velocities in
    /// LANES..2·LANES (zero without damping), so one pass over K_e gives both K u_loc and K v_loc.
    fn batched_forces(&self, x: &[f64], v: &[f64], beta_k: f64, force: &mut [f64]) -> ForceOutput {
        const W: usize = 2 * LANES;
        let damped = beta_k > 0.0;
        let mut strain = [0.0; LANES];
        let mut power = [0.0; LANES];
        for batch in &self.batches {
            let proto = &self.prototypes[batch.prototype as usize];
            let nodes = &batch.nodes;
            // Gather: g[dof][lane], positions then velocities. Every node index is
            // < reference.len() (checked at construction), so x[2n + 1] is in bounds by the
            // assert of `internal_forces`.
            let mut g = [[0.0; W]; 16];
            for k in 0..8 {
                for l in 0..LANES {
                    let n = nodes[k][l] as usize;
                    g[2 * k][l] = x[2 * n];
                    g[2 * k + 1][l] = x[2 * n + 1];
                    if damped {
                        g[2 * k][LANES + l] = v[2 * n];
                        g[2 * k + 1][LANES + l] = v[2 * n + 1];
                    }
                }
            }
            // Deformation gradient at the centre against the prototype frame, its rotation
            // (c, s), and the centroids of positions and velocities.
            let mut f11 = [0.0; LANES];
            let mut f12 = [0.0; LANES];
            let mut f21 = [0.0; LANES];
            let mut f22 = [0.0; LANES];
            let mut centroid = [[0.0; W]; 2];
            for k in 0..8 {
                let (gx, gy) = (proto.centre_gradients[k].x, proto.centre_gradients[k].y);
                for l in 0..LANES {
                    let (px, py) = (g[2 * k][l], g[2 * k + 1][l]);
                    f11[l] += px * gx;
                    f12[l] += px * gy;
                    f21[l] += py * gx;
                    f22[l] += py * gy;
                }
                for l in 0..W {
                    centroid[0][l] += g[2 * k][l];
                    centroid[1][l] += g[2 * k + 1][l];
                }
            }
            let mut c = [0.0; W];
            let mut s = [0.0; W];
            for l in 0..LANES {
                let (a, b) = (f11[l] + f22[l], f21[l] - f12[l]);
                let inv_norm = 1.0 / (a * a + b * b).sqrt();
                c[l] = a * inv_norm;
                s[l] = b * inv_norm;
                c[LANES + l] = c[l];
                s[LANES + l] = s[l];
            }
            // Into the element frame: u_loc = Rᵀ(x − x_c) − (X − X_c) and, relative to the
            // centroid's velocity, v_loc = Rᵀ(v − v_c) (its spin part K_e annihilates to first
            // order).
            let mut loc = [[0.0; W]; 16];
            for k in 0..8 {
                let (ox, oy) = (proto.offsets[k].x, proto.offsets[k].y);
                for l in 0..W {
                    let dx = g[2 * k][l] - 0.125 * centroid[0][l];
                    let dy = g[2 * k + 1][l] - 0.125 * centroid[1][l];
                    // The reference shape comes off the positions only.
                    let (rx, ry) = if l < LANES { (ox, oy) } else { (0.0, 0.0) };
                    loc[2 * k][l] = c[l] * dx + s[l] * dy - rx;
                    loc[2 * k + 1][l] = c[l] * dy - s[l] * dx - ry;
                }
            }
            let k_loc = mat_vec_lanes::<W, 4>(&proto.rows, &loc);
            let energies = lane_dots::<W>(&loc, &k_loc);
            let mut f_loc = [[0.0; LANES]; 16];
            for (f, k) in f_loc.iter_mut().zip(&k_loc) {
                for l in 0..LANES {
                    f[l] = beta_k * k[LANES + l] + k[l];
                }
            }
            for l in 0..LANES {
                strain[l] += 0.5 * energies[l] * batch.weight[l];
                power[l] += beta_k * energies[LANES + l] * batch.weight[l];
            }
            // Scatter the real lanes (padding lanes repeat a real element).
            for l in 0..batch.count as usize {
                for k in 0..8 {
                    let n = nodes[k][l] as usize;
                    let (fx, fy) = (f_loc[2 * k][l], f_loc[2 * k + 1][l]);
                    force[2 * n] -= c[l] * fx - s[l] * fy;
                    force[2 * n + 1] -= s[l] * fx + c[l] * fy;
                }
            }
        }
        ForceOutput {
            strain_energy: strain.iter().sum(),
            damping_power: power.iter().sum(),
        }
    }
}

/// The kernel of [`ExplicitBody::batched_forces`] written with AVX2 intrinsics: the same
/// arithmetic, lane l of every register one element of the batch. Written out because the
/// compiler's version of the generic kernel fills the lanes of its work arrays one scalar at a
/// time and reads them back as vectors (a store-forwarding stall on each); here the nodes go
/// from memory to registers as (x, y) pairs and back the same way, and the kernel takes 1.4×
/// less time on the 3000 rpm body (validation/performance).
#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::{Batch, ExplicitBody, ForceOutput, LANES};
    use std::arch::x86_64::*;

    /// The (x, y) pairs at `values[index[l]..]` of the four lanes, transposed into an x and a
    /// y register: 16-byte loads, lanes 0 and 2 in the low halves, 1 and 3 in the high ones,
    /// then unpacked (no round trip through memory).
    #[inline(always)]
    unsafe fn gather_pairs(values: &[f64], index: [usize; LANES]) -> (__m256d, __m256d) {
        let pair = |l: usize| _mm_loadu_pd(values.as_ptr().add(index[l]));
        let even = _mm256_insertf128_pd::<1>(_mm256_castpd128_pd256(pair(0)), pair(2));
        let odd = _mm256_insertf128_pd::<1>(_mm256_castpd128_pd256(pair(1)), pair(3));
        (_mm256_unpacklo_pd(even, odd), _mm256_unpackhi_pd(even, odd))
    }

    /// # Safety
    /// The CPU must support AVX2 and FMA; `x`, `v` and `force` hold 2 values per node of the
    /// body (checked by the caller).
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn internal_forces(
        body: &ExplicitBody,
        x: &[f64],
        v: &[f64],
        beta_k: f64,
        force: &mut [f64],
    ) -> ForceOutput {
        if beta_k > 0.0 {
            kernel::<true>(body, x, v, beta_k, force)
        } else {
            kernel::<false>(body, x, v, beta_k, force)
        }
    }

    /// With `DAMPED` false the velocities are not read and K v_loc is not formed.
    #[inline(always)]
    unsafe fn kernel<const DAMPED: bool>(
        body: &ExplicitBody,
        x: &[f64],
        v: &[f64],
        beta_k: f64,
        force: &mut [f64],
    ) -> ForceOutput {
        let mut strain = _mm256_setzero_pd();
        let mut power = _mm256_setzero_pd();
        for batch in &body.batches {
            batch_forces::<DAMPED>(body, batch, x, v, beta_k, force, &mut strain, &mut power);
        }
        let (strain, power) = (lanes(strain), lanes(power));
        ForceOutput {
            strain_energy: 0.5 * strain.iter().sum::<f64>(),
            damping_power: beta_k * power.iter().sum::<f64>(),
        }
    }

    /// One batch: its forces subtracted from `force`, its lanes' u·Ku and v·Kv (weighted)
    /// added to `strain` and `power`. Called from the kernels that enable AVX2 and FMA.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) unsafe fn batch_forces<const DAMPED: bool>(
        body: &ExplicitBody,
        batch: &Batch<LANES>,
        x: &[f64],
        v: &[f64],
        beta_k: f64,
        force: &mut [f64],
        strain: &mut __m256d,
        power: &mut __m256d,
    ) {
        let beta = _mm256_set1_pd(beta_k);
        let eighth = _mm256_set1_pd(0.125);
        let mut pos = [_mm256_setzero_pd(); 16];
        let mut vel = [_mm256_setzero_pd(); 16];
        let proto = &body.prototypes[batch.prototype as usize];
        let nodes = &batch.nodes;
        // Gather; deformation gradient at the centre (prototype frame) and centroids.
        let (mut f11, mut f12, mut f21, mut f22) = (
            _mm256_setzero_pd(),
            _mm256_setzero_pd(),
            _mm256_setzero_pd(),
            _mm256_setzero_pd(),
        );
        let (mut cx, mut cy, mut cvx, mut cvy) = (
            _mm256_setzero_pd(),
            _mm256_setzero_pd(),
            _mm256_setzero_pd(),
            _mm256_setzero_pd(),
        );
        for k in 0..8 {
            let base = nodes[k].map(|n| 2 * n as usize);
            let (px, py) = gather_pairs(x, base);
            pos[2 * k] = px;
            pos[2 * k + 1] = py;
            if DAMPED {
                (vel[2 * k], vel[2 * k + 1]) = gather_pairs(v, base);
            }
            let gx = _mm256_set1_pd(proto.centre_gradients[k].x);
            let gy = _mm256_set1_pd(proto.centre_gradients[k].y);
            f11 = _mm256_fmadd_pd(px, gx, f11);
            f12 = _mm256_fmadd_pd(px, gy, f12);
            f21 = _mm256_fmadd_pd(py, gx, f21);
            f22 = _mm256_fmadd_pd(py, gy, f22);
            cx = _mm256_add_pd(cx, px);
            cy = _mm256_add_pd(cy, py);
            if DAMPED {
                cvx = _mm256_add_pd(cvx, vel[2 * k]);
                cvy = _mm256_add_pd(cvy, vel[2 * k + 1]);
            }
        }
        let a = _mm256_add_pd(f11, f22);
        let b = _mm256_sub_pd(f21, f12);
        let norm = _mm256_sqrt_pd(_mm256_fmadd_pd(a, a, _mm256_mul_pd(b, b)));
        let inv_norm = _mm256_div_pd(_mm256_set1_pd(1.0), norm);
        let (c, s) = (_mm256_mul_pd(a, inv_norm), _mm256_mul_pd(b, inv_norm));
        let (cx, cy) = (_mm256_mul_pd(cx, eighth), _mm256_mul_pd(cy, eighth));
        let (cvx, cvy) = (_mm256_mul_pd(cvx, eighth), _mm256_mul_pd(cvy, eighth));
        // u_loc = Rᵀ(x − x_c) − (X − X_c), v_loc = Rᵀ(v − v_c), in place.
        for k in 0..8 {
            let ox = _mm256_set1_pd(proto.offsets[k].x);
            let oy = _mm256_set1_pd(proto.offsets[k].y);
            let dx = _mm256_sub_pd(pos[2 * k], cx);
            let dy = _mm256_sub_pd(pos[2 * k + 1], cy);
            pos[2 * k] = _mm256_sub_pd(_mm256_fmadd_pd(c, dx, _mm256_mul_pd(s, dy)), ox);
            pos[2 * k + 1] = _mm256_sub_pd(_mm256_fmsub_pd(c, dy, _mm256_mul_pd(s, dx)), oy);
            if DAMPED {
                let ex = _mm256_sub_pd(vel[2 * k], cvx);
                let ey = _mm256_sub_pd(vel[2 * k + 1], cvy);
                vel[2 * k] = _mm256_fmadd_pd(c, ex, _mm256_mul_pd(s, ey));
                vel[2 * k + 1] = _mm256_fmsub_pd(c, ey, _mm256_mul_pd(s, ex));
            }
        }
        // K u_loc and K v_loc, four rows at a time (8 accumulators in registers); the
        // forces f_loc = K u_loc + β K v_loc go back to the global frame and are scattered.
        // Four partial sums each: one running sum would be a chain of 16 dependent
        // multiply-adds per batch.
        let mut batch_strain = [_mm256_setzero_pd(); 4];
        let mut batch_power = [_mm256_setzero_pd(); 4];
        for block in 0..4 {
            let mut ku = [_mm256_setzero_pd(); 4];
            let mut kv = [_mm256_setzero_pd(); 4];
            for j in 0..16 {
                let column = &proto.rows[j];
                for r in 0..4 {
                    let kij = _mm256_broadcast_sd(column.get_unchecked(4 * block + r));
                    ku[r] = _mm256_fmadd_pd(kij, pos[j], ku[r]);
                    if DAMPED {
                        kv[r] = _mm256_fmadd_pd(kij, vel[j], kv[r]);
                    }
                }
            }
            for r in 0..4 {
                let i = 4 * block + r;
                batch_strain[r] = _mm256_fmadd_pd(pos[i], ku[r], batch_strain[r]);
                if DAMPED {
                    batch_power[r] = _mm256_fmadd_pd(vel[i], kv[r], batch_power[r]);
                    ku[r] = _mm256_fmadd_pd(beta, kv[r], ku[r]);
                }
            }
            // Rows (x, y) of nodes 2·block and 2·block + 1: global force −R f_loc.
            for half in 0..2 {
                let (fx, fy) = (ku[2 * half], ku[2 * half + 1]);
                let gx = _mm256_fmsub_pd(c, fx, _mm256_mul_pd(s, fy));
                let gy = _mm256_fmadd_pd(s, fx, _mm256_mul_pd(c, fy));
                // Back into (x, y) pairs: lanes 0 and 2 in `even`, 1 and 3 in `odd`.
                let (even, odd) = (_mm256_unpacklo_pd(gx, gy), _mm256_unpackhi_pd(gx, gy));
                let pairs = [
                    _mm256_castpd256_pd128(even),
                    _mm256_castpd256_pd128(odd),
                    _mm256_extractf128_pd::<1>(even),
                    _mm256_extractf128_pd::<1>(odd),
                ];
                let node = &nodes[2 * block + half];
                for (l, pair) in pairs.iter().enumerate().take(batch.count as usize) {
                    let at = force.as_mut_ptr().add(2 * node[l] as usize);
                    _mm_storeu_pd(at, _mm_sub_pd(_mm_loadu_pd(at), *pair));
                }
            }
        }
        // Padding lanes repeat a real element: their weight 0 takes them out of the sums.
        let weight = _mm256_loadu_pd(batch.weight.as_ptr());
        let sum =
            |p: [__m256d; 4]| _mm256_add_pd(_mm256_add_pd(p[0], p[1]), _mm256_add_pd(p[2], p[3]));
        *strain = _mm256_fmadd_pd(sum(batch_strain), weight, *strain);
        *power = _mm256_fmadd_pd(sum(batch_power), weight, *power);
    }

    /// The lanes of a register as an array.
    #[inline(always)]
    pub(super) unsafe fn lanes(v: __m256d) -> [f64; LANES] {
        let mut out = [0.0; LANES];
        _mm256_storeu_pd(out.as_mut_ptr(), v);
        out
    }
}

/// The kernel of [`ExplicitBody::batched_forces`] eight elements wide, with AVX-512 F and DQ:
/// the AVX2 kernel's arithmetic lane for lane (each element's forces and energies are the same
/// operations), on registers twice as wide, the 16×16 products eight rows at a time (16
/// accumulators; AVX-512 has 32 registers). A prototype's last four or fewer elements go
/// through the AVX2 kernel's batch (`WideOrNarrow::Narrow`).
#[cfg(target_arch = "x86_64")]
mod avx512 {
    use super::{avx2, Batch, ExplicitBody, ForceOutput, WideOrNarrow, WIDE_LANES};
    use std::arch::x86_64::*;

    /// The (x, y) pairs at `values[index[l]..]` of the eight lanes, transposed into an x and a
    /// y register: pairs of the even lanes in the four 128-bit parts of one register, of the
    /// odd lanes in the other, then unpacked part by part (x₀ x₁ | x₂ x₃ | …).
    #[inline(always)]
    unsafe fn gather_pairs(values: &[f64], index: [usize; WIDE_LANES]) -> (__m512d, __m512d) {
        let pair = |l: usize| _mm_loadu_pd(values.as_ptr().add(index[l]));
        let parts = |first: usize| {
            let mut r = _mm512_castpd128_pd512(pair(first));
            r = _mm512_insertf64x2::<1>(r, pair(first + 2));
            r = _mm512_insertf64x2::<2>(r, pair(first + 4));
            _mm512_insertf64x2::<3>(r, pair(first + 6))
        };
        let (even, odd) = (parts(0), parts(1));
        (_mm512_unpacklo_pd(even, odd), _mm512_unpackhi_pd(even, odd))
    }

    /// # Safety
    /// The CPU must support AVX-512 F and DQ, AVX2 and FMA; `x`, `v` and `force` hold 2 values
    /// per node of the body (checked by the caller).
    #[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
    pub(super) unsafe fn internal_forces(
        body: &ExplicitBody,
        x: &[f64],
        v: &[f64],
        beta_k: f64,
        force: &mut [f64],
    ) -> ForceOutput {
        if beta_k > 0.0 {
            kernel::<true>(body, x, v, beta_k, force)
        } else {
            kernel::<false>(body, x, v, beta_k, force)
        }
    }

    #[inline(always)]
    unsafe fn kernel<const DAMPED: bool>(
        body: &ExplicitBody,
        x: &[f64],
        v: &[f64],
        beta_k: f64,
        force: &mut [f64],
    ) -> ForceOutput {
        let mut strain = _mm512_setzero_pd();
        let mut power = _mm512_setzero_pd();
        let mut narrow_strain = _mm256_setzero_pd();
        let mut narrow_power = _mm256_setzero_pd();
        for batch in &body.wide_batches {
            match batch {
                WideOrNarrow::Wide(batch) => {
                    wide_batch::<DAMPED>(body, batch, x, v, beta_k, force, &mut strain, &mut power)
                }
                WideOrNarrow::Narrow(batch) => avx2::batch_forces::<DAMPED>(
                    body,
                    batch,
                    x,
                    v,
                    beta_k,
                    force,
                    &mut narrow_strain,
                    &mut narrow_power,
                ),
            }
        }
        let sum = |wide: __m512d, narrow: __m256d| {
            let mut out = [0.0; WIDE_LANES];
            _mm512_storeu_pd(out.as_mut_ptr(), wide);
            out.iter().sum::<f64>() + avx2::lanes(narrow).iter().sum::<f64>()
        };
        ForceOutput {
            strain_energy: 0.5 * sum(strain, narrow_strain),
            damping_power: beta_k * sum(power, narrow_power),
        }
    }

    /// [`avx2::batch_forces`] for eight elements.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    unsafe fn wide_batch<const DAMPED: bool>(
        body: &ExplicitBody,
        batch: &Batch<WIDE_LANES>,
        x: &[f64],
        v: &[f64],
        beta_k: f64,
        force: &mut [f64],
        strain: &mut __m512d,
        power: &mut __m512d,
    ) {
        let beta = _mm512_set1_pd(beta_k);
        let eighth = _mm512_set1_pd(0.125);
        let mut pos = [_mm512_setzero_pd(); 16];
        let mut vel = [_mm512_setzero_pd(); 16];
        let proto = &body.prototypes[batch.prototype as usize];
        let nodes = &batch.nodes;
        let zero = _mm512_setzero_pd();
        let (mut f11, mut f12, mut f21, mut f22) = (zero, zero, zero, zero);
        let (mut cx, mut cy, mut cvx, mut cvy) = (zero, zero, zero, zero);
        for k in 0..8 {
            let base = nodes[k].map(|n| 2 * n as usize);
            let (px, py) = gather_pairs(x, base);
            pos[2 * k] = px;
            pos[2 * k + 1] = py;
            if DAMPED {
                (vel[2 * k], vel[2 * k + 1]) = gather_pairs(v, base);
            }
            let gx = _mm512_set1_pd(proto.centre_gradients[k].x);
            let gy = _mm512_set1_pd(proto.centre_gradients[k].y);
            f11 = _mm512_fmadd_pd(px, gx, f11);
            f12 = _mm512_fmadd_pd(px, gy, f12);
            f21 = _mm512_fmadd_pd(py, gx, f21);
            f22 = _mm512_fmadd_pd(py, gy, f22);
            cx = _mm512_add_pd(cx, px);
            cy = _mm512_add_pd(cy, py);
            if DAMPED {
                cvx = _mm512_add_pd(cvx, vel[2 * k]);
                cvy = _mm512_add_pd(cvy, vel[2 * k + 1]);
            }
        }
        let a = _mm512_add_pd(f11, f22);
        let b = _mm512_sub_pd(f21, f12);
        let norm = _mm512_sqrt_pd(_mm512_fmadd_pd(a, a, _mm512_mul_pd(b, b)));
        let inv_norm = _mm512_div_pd(_mm512_set1_pd(1.0), norm);
        let (c, s) = (_mm512_mul_pd(a, inv_norm), _mm512_mul_pd(b, inv_norm));
        let (cx, cy) = (_mm512_mul_pd(cx, eighth), _mm512_mul_pd(cy, eighth));
        let (cvx, cvy) = (_mm512_mul_pd(cvx, eighth), _mm512_mul_pd(cvy, eighth));
        for k in 0..8 {
            let ox = _mm512_set1_pd(proto.offsets[k].x);
            let oy = _mm512_set1_pd(proto.offsets[k].y);
            let dx = _mm512_sub_pd(pos[2 * k], cx);
            let dy = _mm512_sub_pd(pos[2 * k + 1], cy);
            pos[2 * k] = _mm512_sub_pd(_mm512_fmadd_pd(c, dx, _mm512_mul_pd(s, dy)), ox);
            pos[2 * k + 1] = _mm512_sub_pd(_mm512_fmsub_pd(c, dy, _mm512_mul_pd(s, dx)), oy);
            if DAMPED {
                let ex = _mm512_sub_pd(vel[2 * k], cvx);
                let ey = _mm512_sub_pd(vel[2 * k + 1], cvy);
                vel[2 * k] = _mm512_fmadd_pd(c, ex, _mm512_mul_pd(s, ey));
                vel[2 * k + 1] = _mm512_fmsub_pd(c, ey, _mm512_mul_pd(s, ex));
            }
        }
        // Eight rows at a time; row i's energy term goes to partial sum i mod 4, in the order
        // of the AVX2 kernel's.
        let mut batch_strain = [zero; 4];
        let mut batch_power = [zero; 4];
        for block in 0..2 {
            let mut ku = [zero; 8];
            let mut kv = [zero; 8];
            for j in 0..16 {
                let column = &proto.rows[j];
                for r in 0..8 {
                    let kij = _mm512_set1_pd(*column.get_unchecked(8 * block + r));
                    ku[r] = _mm512_fmadd_pd(kij, pos[j], ku[r]);
                    if DAMPED {
                        kv[r] = _mm512_fmadd_pd(kij, vel[j], kv[r]);
                    }
                }
            }
            for r in 0..8 {
                let i = 8 * block + r;
                batch_strain[r % 4] = _mm512_fmadd_pd(pos[i], ku[r], batch_strain[r % 4]);
                if DAMPED {
                    batch_power[r % 4] = _mm512_fmadd_pd(vel[i], kv[r], batch_power[r % 4]);
                    ku[r] = _mm512_fmadd_pd(beta, kv[r], ku[r]);
                }
            }
            // Rows (x, y) of nodes 4·block … 4·block + 3: global force −R f_loc.
            for quarter in 0..4 {
                let (fx, fy) = (ku[2 * quarter], ku[2 * quarter + 1]);
                let gx = _mm512_fmsub_pd(c, fx, _mm512_mul_pd(s, fy));
                let gy = _mm512_fmadd_pd(s, fx, _mm512_mul_pd(c, fy));
                // Back into (x, y) pairs: even lanes' pairs in `even`, odd lanes' in `odd`.
                let (even, odd) = (_mm512_unpacklo_pd(gx, gy), _mm512_unpackhi_pd(gx, gy));
                let pairs = [
                    _mm512_castpd512_pd128(even),
                    _mm512_castpd512_pd128(odd),
                    _mm512_extractf64x2_pd::<1>(even),
                    _mm512_extractf64x2_pd::<1>(odd),
                    _mm512_extractf64x2_pd::<2>(even),
                    _mm512_extractf64x2_pd::<2>(odd),
                    _mm512_extractf64x2_pd::<3>(even),
                    _mm512_extractf64x2_pd::<3>(odd),
                ];
                let node = &nodes[4 * block + quarter];
                for (l, pair) in pairs.iter().enumerate().take(batch.count as usize) {
                    let at = force.as_mut_ptr().add(2 * node[l] as usize);
                    _mm_storeu_pd(at, _mm_sub_pd(_mm_loadu_pd(at), *pair));
                }
            }
        }
        let weight = _mm512_loadu_pd(batch.weight.as_ptr());
        let sum =
            |p: [__m512d; 4]| _mm512_add_pd(_mm512_add_pd(p[0], p[1]), _mm512_add_pd(p[2], p[3]));
        *strain = _mm512_fmadd_pd(sum(batch_strain), weight, *strain);
        *power = _mm512_fmadd_pd(sum(batch_power), weight, *power);
    }
}

/// Elements processed side by side (4 doubles fill an AVX2 register).
pub const LANES: usize = 4;

/// Elements processed side by side by the AVX-512 kernel (8 doubles fill its register).
pub const WIDE_LANES: usize = 8;

/// The element kernels, chosen at run time by what the CPU has.
/// Ordered by width: a cap admits the kernels up to it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Kernel {
    /// Plain arrays, any CPU.
    Portable,
    /// Four elements side by side (x86-64 with AVX2 and FMA).
    Avx2,
    /// Eight elements side by side (x86-64 with AVX-512 F and DQ, AVX2 and FMA).
    Avx512,
}

impl Kernel {
    /// Whether this CPU runs the kernel.
    pub fn available(self) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            let avx2 = std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma");
            match self {
                Kernel::Portable => true,
                Kernel::Avx2 => avx2,
                Kernel::Avx512 => {
                    avx2 && std::arch::is_x86_feature_detected!("avx512f")
                        && std::arch::is_x86_feature_detected!("avx512dq")
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            self == Kernel::Portable
        }
    }

    /// The cap `GEARDYN_KERNEL` sets: `avx2` or `portable`, for a comparison on one machine
    /// (validation/performance); `avx512` or unset, none. Any other value is an error naming
    /// the values (the CLI checks it before it runs anything).
    pub fn cap_from_env() -> Result<Kernel, String> {
        match std::env::var("GEARDYN_KERNEL") {
            Err(_) => Ok(Kernel::Avx512),
            Ok(value) => match value.as_str() {
                "portable" => Ok(Kernel::Portable),
                "avx2" => Ok(Kernel::Avx2),
                "avx512" => Ok(Kernel::Avx512),
                _ => Err(format!(
                    "GEARDYN_KERNEL={value:?}: use avx512, avx2 or portable, or leave it unset"
                )),
            },
        }
    }

    /// The widest kernel this CPU runs, capped by `GEARDYN_KERNEL` ([`Kernel::cap_from_env`];
    /// an invalid value panics here, so a caller that did not check it does not run on a
    /// kernel it did not ask for).
    pub fn best() -> Kernel {
        static BEST: std::sync::OnceLock<Kernel> = std::sync::OnceLock::new();
        *BEST.get_or_init(|| {
            let cap = Kernel::cap_from_env().unwrap_or_else(|message| panic!("{message}"));
            [Kernel::Avx512, Kernel::Avx2, Kernel::Portable]
                .into_iter()
                .find(|&k| k <= cap && k.available())
                .unwrap_or(Kernel::Portable)
        })
    }
}

/// Up to `L` elements of one prototype. Unused lanes repeat the first element with weight 0,
/// so the arithmetic stays branch-free and only the scatter looks at `count`.
struct Batch<const L: usize> {
    prototype: u32,
    count: u8,
    /// Node indices, [element node][lane].
    nodes: [[u32; L]; 8],
    /// 1 for a real lane, 0 for padding (energy sums).
    weight: [f64; L],
}

impl<const L: usize> Batch<L> {
    /// The batch of `members` (1 to `L` elements of prototype `prototype`).
    fn new(prototype: usize, members: &[usize], elements: &[[usize; 8]]) -> Self {
        let lane = |l: usize| members[l.min(members.len() - 1)];
        Batch {
            prototype: prototype as u32,
            count: members.len() as u8,
            nodes: std::array::from_fn(|k| std::array::from_fn(|l| elements[lane(l)][k] as u32)),
            weight: std::array::from_fn(|l| if l < members.len() { 1.0 } else { 0.0 }),
        }
    }
}

/// A batch of the AVX-512 kernel: eight elements, or a prototype's last four or fewer (which
/// would leave half of an eight-wide register idle).
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
enum WideOrNarrow {
    Wide(Batch<WIDE_LANES>),
    Narrow(Batch<LANES>),
}

/// Each prototype's elements, in element order (the mesh builds elements sector by sector, so
/// consecutive batches touch the same sectors' nodes).
fn prototype_members(prototype_of: &[u32], prototypes: usize) -> Vec<Vec<usize>> {
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); prototypes];
    for (e, &p) in prototype_of.iter().enumerate() {
        members[p as usize].push(e);
    }
    members
}

/// Groups the elements of each prototype into batches of [`LANES`].
fn make_batches(elements: &[[usize; 8]], members: &[Vec<usize>]) -> Vec<Batch<LANES>> {
    let mut batches = Vec::new();
    for (p, list) in members.iter().enumerate() {
        for chunk in list.chunks(LANES) {
            batches.push(Batch::new(p, chunk, elements));
        }
    }
    batches
}

/// Groups the elements of each prototype into batches of [`WIDE_LANES`], a last chunk of
/// [`LANES`] or fewer into a narrow batch.
fn make_wide_batches(elements: &[[usize; 8]], members: &[Vec<usize>]) -> Vec<WideOrNarrow> {
    let mut batches = Vec::new();
    for (p, list) in members.iter().enumerate() {
        for chunk in list.chunks(WIDE_LANES) {
            batches.push(if chunk.len() > LANES {
                WideOrNarrow::Wide(Batch::new(p, chunk, elements))
            } else {
                WideOrNarrow::Narrow(Batch::new(p, chunk, elements))
            });
        }
    }
    batches
}

/// Σ_i a[i][l]·b[i][l] for each lane l, in four partial sums: a single running sum over every
/// element of the body would be one chain of dependent additions, the kernel's slowest path.
#[inline(always)]
fn lane_dots<const W: usize>(a: &[[f64; W]; 16], b: &[[f64; W]; 16]) -> [f64; W] {
    let mut partial = [[0.0; W]; 4];
    for (i, (ai, bi)) in a.iter().zip(b).enumerate() {
        for l in 0..W {
            partial[i % 4][l] += ai[l] * bi[l];
        }
    }
    std::array::from_fn(|l| (partial[0][l] + partial[1][l]) + (partial[2][l] + partial[3][l]))
}

/// K U for a symmetric 16×16 matrix given by rows (= columns) and `W` vectors side by side:
/// F[i][l] = Σ_j K[j][i] U[j][l], so each (i, j) is one vector multiply-add over the `W` lanes.
/// Done in blocks of `R` rows so the R·W accumulators stay in registers.
#[inline(always)]
fn mat_vec_lanes<const W: usize, const R: usize>(
    rows: &[[f64; 16]; 16],
    u: &[[f64; W]; 16],
) -> [[f64; W]; 16] {
    let mut f = [[0.0; W]; 16];
    for block in 0..16 / R {
        let mut acc = [[0.0; W]; R];
        for (column, uj) in rows.iter().zip(u) {
            for (a, &kij) in acc.iter_mut().zip(&column[R * block..R * block + R]) {
                for l in 0..W {
                    a[l] += kij * uj[l];
                }
            }
        }
        f[R * block..R * block + R].copy_from_slice(&acc);
    }
    f
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The portable kernel and the intrinsic ones this CPU has (AVX2; AVX-512, eight lanes with
    /// a prototype's last four or fewer on the AVX2 batch) are the same arithmetic (the latter
    /// with fused multiply-adds): their forces and energies agree to round-off, damped and
    /// undamped, on three layouts of batches:
    /// * 3 fine teeth, 36-fold symmetry: a fine element's 3 copies in one padded narrow batch,
    ///   a coarse element's 33 in four full wide batches and a narrow one;
    /// * 6 fine teeth: 6 copies in a wide batch with two padding lanes, 30 in three full wide
    ///   batches and one with two padding lanes;
    /// * no symmetry: one element per batch, three padding lanes.
    #[test]
    fn portable_and_dispatched_kernels_agree() {
        let case = crate::samples::paper36_case();
        let six_fine = crate::mesh::mesh_gear(
            &case.pair.gears[0],
            &case.relief_variant("tip20-root10").unwrap().modifications[0],
            &crate::mesh::MeshSpec {
                fine_size: 1.5e-3,
                coarse_size: 3.0e-3,
                fine_teeth: vec![0, 1, 2, 33, 34, 35],
                layout: crate::mesh::ToothLayout::Graded,
            },
        );
        let three_fine = crate::samples::paper36_gear_mesh(1.5e-3, 3.0e-3);
        for (mesh, symmetry) in [
            (&three_fine, Some(36)),
            (&six_fine, Some(36)),
            (&three_fine, None),
        ] {
            kernels_agree_on(mesh, symmetry);
        }
    }

    fn kernels_agree_on(mesh: &crate::mesh::GearMesh, symmetry: Option<usize>) {
        let material = crate::samples::paper36_explicit_material();
        let (s, c) = 0.4_f64.sin_cos();
        let x: Vec<f64> = mesh
            .nodes
            .iter()
            .flat_map(|p| {
                [
                    c * p.x - s * p.y + 1e-7 * (p.y * 700.0).sin(),
                    s * p.x + c * p.y,
                ]
            })
            .collect();
        let v: Vec<f64> = x.iter().map(|q| 1e-2 * (q * 2e3).cos()).collect();
        {
            let body = ExplicitBody::with_symmetry(&mesh.nodes, &mesh.elements, material, symmetry)
                .unwrap();
            let padded_wide = body.wide_batches.iter().any(|b| match b {
                WideOrNarrow::Wide(b) => (b.count as usize) < WIDE_LANES,
                WideOrNarrow::Narrow(_) => false,
            });
            let fine = mesh.fine_teeth.len();
            eprintln!(
                "{fine} fine teeth, symmetry {symmetry:?}: padded wide batches {padded_wide}"
            );
            assert_eq!(padded_wide, symmetry.is_some() && fine == 6);
            for (kernel, beta_k) in [Kernel::Avx2, Kernel::Avx512]
                .into_iter()
                .flat_map(|k| [(k, 1e-8), (k, 0.0)])
            {
                let (mut fa, mut fb) = (vec![0.0; x.len()], vec![0.0; x.len()]);
                let Some(a) = body.internal_forces_on(kernel, &x, &v, beta_k, &mut fa) else {
                    eprintln!("this CPU has no {kernel:?} kernel: not compared");
                    continue;
                };
                let b = body.batched_forces(&x, &v, beta_k, &mut fb);
                let scale = fa.iter().map(|f| f.abs()).fold(0.0, f64::max);
                let diff = fa
                    .iter()
                    .zip(&fb)
                    .map(|(p, q)| (p - q).abs())
                    .fold(0.0, f64::max);
                // u_loc is a difference of positions (~1e-3 m apart within an element) that
                // leaves deformations of ~1e-7 m, so one rounding more or less (fused or not)
                // moves it by ε·1e-3/1e-7 ≈ 2e-12 relative; the 16-term product with K_e's mixed
                // signs amplifies that by about ten. A wrong index or lane would be off by O(1).
                let case = format!(
                    "{kernel:?}, {fine} fine teeth, symmetry {symmetry:?}, beta {beta_k:e}"
                );
                assert!(diff <= 1e-10 * scale, "{case}: {diff:e} of {scale:e}");
                assert!(
                    (a.strain_energy / b.strain_energy - 1.0).abs() < 1e-10,
                    "{case}: strain {} vs {}",
                    a.strain_energy,
                    b.strain_energy
                );
                if beta_k > 0.0 {
                    assert!(
                        (a.damping_power / b.damping_power - 1.0).abs() < 1e-10,
                        "{case}"
                    );
                } else {
                    assert_eq!((a.damping_power, b.damping_power), (0.0, 0.0), "{case}");
                }
            }
            // AVX-512 against AVX2: each element's forces and energy terms are the same
            // operations, so only the order of the sums differs (elements sharing a node, lanes
            // and batches of the energies): a few roundings of the largest force, not 1e-10.
            for beta_k in [1e-8, 0.0] {
                let (mut f2, mut f8) = (vec![0.0; x.len()], vec![0.0; x.len()]);
                let (Some(e2), Some(e8)) = (
                    body.internal_forces_on(Kernel::Avx2, &x, &v, beta_k, &mut f2),
                    body.internal_forces_on(Kernel::Avx512, &x, &v, beta_k, &mut f8),
                ) else {
                    eprintln!("this CPU has no AVX-512 kernel: not compared with AVX2");
                    return;
                };
                let scale = f2.iter().map(|f| f.abs()).fold(0.0, f64::max);
                for (p, q) in f2.iter().zip(&f8) {
                    assert!((p - q).abs() <= 1e-14 * scale, "{fine}, {p:e} vs {q:e}");
                }
                assert!((e2.strain_energy / e8.strain_energy - 1.0).abs() < 1e-13);
                if beta_k > 0.0 {
                    assert!((e2.damping_power / e8.damping_power - 1.0).abs() < 1e-13);
                }
            }
        }
    }
}
