//! Explicit dynamics kernels: corotation is exact for rigid motions, linear for small ones;
//! energy is conserved without damping; the measured critical step separates stable from
//! divergent runs, and divergence is caught with a clear message.

use geardyn::explicit::body::{ExplicitBody, ExplicitMaterial};
use geardyn::explicit::solver::{critical_step, CentralDifference, ExplicitError, State};
use geardyn::fe::assembly::{stiffness_triplets, symmetric_product, FactorizedStiffness};
use geardyn::fe::{elasticity_matrix, MassLumping, PlaneState};
use geardyn::samples;

fn steel(thickness: f64) -> ExplicitMaterial {
    ExplicitMaterial {
        youngs_modulus: 206e9,
        poisson_ratio: 0.3,
        density: 7850.0,
        plane: PlaneState::Strain,
        thickness,
        lumping: MassLumping::default(),
    }
}

#[test]
fn corotational_forces_vanish_for_rigid_motions_and_are_linear_for_small_ones() {
    let mesh = samples::paper36_gear_mesh(0.8e-3, 2.0e-3);
    let body = ExplicitBody::new(&mesh.nodes, &mesh.elements, steel(0.0254)).unwrap();
    let n = 2 * mesh.nodes.len();
    let zero = vec![0.0; n];
    let d = elasticity_matrix(206e9, 0.3, PlaneState::Strain);
    let triplets = stiffness_triplets(&mesh.nodes, &mesh.elements, &d, 0.0254);
    // Force scale: K times a 1 µm displacement.
    let scale = triplets.iter().map(|t| t.2.abs()).fold(0.0, f64::max) * 1e-6;
    for angle in [0.3_f64, 2.0, 3.0] {
        let (s, c) = angle.sin_cos();
        let x: Vec<f64> = mesh
            .nodes
            .iter()
            .flat_map(|p| [c * p.x - s * p.y + 0.01, s * p.x + c * p.y - 0.02])
            .collect();
        let mut force = vec![0.0; n];
        let out = body.internal_forces(&x, &zero, 0.0, &mut force);
        let worst = force.iter().map(|f| f.abs()).fold(0.0, f64::max);
        assert!(
            worst < 1e-6 * scale,
            "angle {angle}: force {worst:e} vs scale {scale:e}"
        );
        assert!(
            out.strain_energy.abs() < 1e-18,
            "angle {angle}: energy {:e}",
            out.strain_energy
        );
    }
    // Small deformation: f = −K u.
    let u: Vec<f64> = mesh
        .nodes
        .iter()
        .flat_map(|p| [1e-8 * (p.y * 300.0).sin(), 1e-8 * (p.x * 200.0).cos()])
        .collect();
    let x: Vec<f64> = mesh
        .nodes
        .iter()
        .zip(u.chunks(2))
        .flat_map(|(p, w)| [p.x + w[0], p.y + w[1]])
        .collect();
    let mut force = vec![0.0; n];
    body.internal_forces(&x, &zero, 0.0, &mut force);
    let ku = symmetric_product(&triplets, &u);
    let norm = ku.iter().map(|f| f.abs()).fold(0.0, f64::max);
    let diff = force
        .iter()
        .zip(&ku)
        .map(|(f, k)| (f + k).abs())
        .fold(0.0, f64::max);
    assert!(
        diff < 1e-5 * norm,
        "corotational vs linear: {diff:e} of {norm:e}"
    );
}

/// A clamped cantilever released from its static deflection under a tip load.
fn cantilever() -> (ExplicitBody, Vec<bool>, State) {
    let (nodes, elements) = samples::rectangle_mesh(0.1, 0.01, 20, 4, 0.0);
    let body = ExplicitBody::new(&nodes, &elements, steel(0.02)).unwrap();
    let n = 2 * nodes.len();
    let fixed: Vec<bool> = (0..n).map(|d| nodes[d / 2].x.abs() < 1e-12).collect();
    let d = elasticity_matrix(206e9, 0.3, PlaneState::Strain);
    let triplets = stiffness_triplets(&nodes, &elements, &d, 0.02);
    let fixed_dofs: Vec<usize> = (0..n).filter(|&d| fixed[d]).collect();
    let mut load = vec![0.0; n];
    let tip = (0..nodes.len())
        .filter(|&i| (nodes[i].x - 0.1).abs() < 1e-12)
        .count() as f64;
    for i in 0..nodes.len() {
        if (nodes[i].x - 0.1).abs() < 1e-12 {
            load[2 * i + 1] = 500.0 / tip;
        }
    }
    let u = FactorizedStiffness::new(n, triplets.clone(), &fixed_dofs)
        .unwrap()
        .solve(&load);
    let x: Vec<f64> = nodes
        .iter()
        .enumerate()
        .flat_map(|(i, p)| [p.x + u[2 * i], p.y + u[2 * i + 1]])
        .collect();
    let state = State {
        time: 0.0,
        x,
        v: vec![0.0; n],
        a: vec![0.0; n],
    };
    (body, fixed, state)
}

#[test]
fn free_vibration_conserves_energy_without_damping() {
    let (body, fixed, mut state) = cantilever();
    let dt_cr = critical_step(&body, &fixed, 300);
    let mut solver = CentralDifference::new(&body, 0.9 * dt_cr, 0.0, fixed, dt_cr);
    let none = |_: f64, _: &mut [f64]| {};
    solver.initialize(&mut state, &none);
    let initial = solver.energy.kinetic + solver.energy.strain;
    let mut worst: f64 = 0.0;
    for _ in 0..4000 {
        solver.step(&mut state, &none).unwrap();
        worst = worst.max((solver.energy.balance() - initial).abs() / initial);
    }
    // Central difference conserves a shadow energy; the drift of the true energy stays O(Δt²).
    assert!(worst < 1e-2, "energy error {worst:e}");
    assert!(
        solver.energy.kinetic > 0.1 * initial,
        "the beam is vibrating"
    );
}

#[test]
fn measured_critical_step_separates_stable_from_divergent_runs() {
    let (body, fixed, state0) = cantilever();
    let dt_cr = critical_step(&body, &fixed, 300);
    let bound = body.element_eigen_critical_step();
    let paper = body.paper_critical_step();
    eprintln!("critical step: power iteration {dt_cr:.4e} s, element eigenvalue bound {bound:.4e} s, paper L/c {paper:.4e} s");
    // The element bound is rigorous (never above the true step) and not far below it.
    assert!(
        bound <= dt_cr * (1.0 + 1e-6) && bound > 0.5 * dt_cr,
        "element bound {bound:e} vs {dt_cr:e}"
    );
    let none = |_: f64, _: &mut [f64]| {};
    let run = |factor: f64, steps: usize| -> Result<(), ExplicitError> {
        let mut state = state0.clone();
        let mut solver = CentralDifference::new(&body, factor * dt_cr, 0.0, fixed.clone(), dt_cr);
        solver.initialize(&mut state, &none);
        for _ in 0..steps {
            solver.step(&mut state, &none)?;
        }
        Ok(())
    };
    run(0.98, 3000).expect("stable just below the critical step");
    let err = run(1.05, 3000).expect_err("diverges just above it");
    let message = err.to_string();
    assert!(
        message.contains("diverged") && message.contains("stable step"),
        "{message}"
    );
}

/// Sharing element data between the rotated sectors of a gear changes nothing but the memory:
/// on the paper's mesh, and on the same mesh with one node of a coarse tooth moved by 2e-11 m
/// (about the mismatch where a fine and a coarse tooth layout meet the base: an element
/// congruent to its sector's copies only to that tolerance must get its own prototype, or the
/// copies' reference shape strains it by ~1e-7 at rest); and on both gears of the unequal
/// 24/40 pair.
#[test]
fn sector_prototypes_give_the_same_forces() {
    let mesh = samples::paper36_gear_mesh(0.8e-3, 2.0e-3);
    let prototypes = assert_sector_prototypes_give_the_same_forces(&mesh);
    assert!(
        prototypes * 10 < mesh.elements.len(),
        "{prototypes} prototypes"
    );
    let mut moved = mesh.clone();
    let node = mesh.elements[mesh.elements.len() / 2][4];
    moved.nodes[node].x += 2e-11;
    assert_sector_prototypes_give_the_same_forces(&moved);
    // An unequal pair's two gears (24 and 40 teeth), with the paper's relief.
    let case = samples::matrix_pair("24-40").unwrap().case().unwrap();
    let relief = case.relief_variant("tip20-root10").unwrap();
    let layouts = [
        geardyn::mesh::ToothLayout::Graded,
        geardyn::mesh::ToothLayout::StableStep,
    ];
    for ((gear, modification), layout) in case
        .pair
        .gears
        .iter()
        .zip(&relief.modifications)
        .flat_map(|g| layouts.map(|l| (g, l)))
    {
        let z = gear.teeth() as usize;
        let spec = geardyn::mesh::MeshSpec {
            fine_size: 0.8e-3,
            coarse_size: 2.0e-3,
            fine_teeth: vec![0, 1, z - 1],
            layout,
        };
        let mesh = geardyn::mesh::mesh_gear(gear, modification, &spec);
        let prototypes = assert_sector_prototypes_give_the_same_forces(&mesh);
        // Fewer teeth, fewer copies of each layout: 137 of 1 344 (24), 199 of 3 495 (40), graded.
        assert!(
            prototypes * 5 < mesh.elements.len(),
            "{z} teeth: {prototypes} prototypes"
        );
    }
}

/// Asserts the forces of `mesh`'s body with and without shared sector prototypes agree; returns
/// the number of prototypes.
fn assert_sector_prototypes_give_the_same_forces(mesh: &geardyn::mesh::GearMesh) -> usize {
    let teeth = mesh.flanks.len() / 2;
    let plain = ExplicitBody::new(&mesh.nodes, &mesh.elements, steel(0.0254)).unwrap();
    let shared =
        ExplicitBody::with_symmetry(&mesh.nodes, &mesh.elements, steel(0.0254), Some(teeth))
            .unwrap();
    let (s, c) = 0.7_f64.sin_cos();
    let x: Vec<f64> = mesh
        .nodes
        .iter()
        .flat_map(|p| {
            [
                c * p.x - s * p.y + 1e-7 * (p.y * 500.0).sin(),
                s * p.x + c * p.y + 1e-7 * (p.x * 300.0).cos(),
            ]
        })
        .collect();
    let v: Vec<f64> = x.iter().map(|q| 1e-3 * (q * 1e3).sin()).collect();
    let (mut fa, mut fb) = (vec![0.0; x.len()], vec![0.0; x.len()]);
    let a = plain.internal_forces(&x, &v, 1e-8, &mut fa);
    let b = shared.internal_forces(&x, &v, 1e-8, &mut fb);
    let scale = fa.iter().map(|f| f.abs()).fold(0.0, f64::max);
    let diff = fa
        .iter()
        .zip(&fb)
        .map(|(p, q)| (p - q).abs())
        .fold(0.0, f64::max);
    assert!(
        diff < 1e-8 * scale,
        "forces differ by {diff:e} of {scale:e}"
    );
    assert!(((a.strain_energy - b.strain_energy) / a.strain_energy).abs() < 1e-8);
    assert!(((a.damping_power - b.damping_power) / a.damping_power).abs() < 1e-8);
    assert!(
        (plain.element_eigen_critical_step() / shared.element_eigen_critical_step() - 1.0).abs()
            < 1e-9
    );
    shared.prototypes.len()
}

/// A free body spun as a rigid body for a whole revolution (ω = 500 rad/s) carries only the
/// strain the spin itself causes: the centrifugal stretch. For a slender bar (1D, plane-strain
/// modulus E' = E/(1 − ν²)) the static centrifugal strain energy is
/// U = (2/15) A ρ² ω⁴ a⁵ / E' (a = L/2); released unstressed, the bar overshoots to about 4 U
/// (a suddenly applied load). Observed: the peak within [3.5, 4.2]·U, total energy conserved to
/// 1e-6, and the body back at its orientation after 2π/ω within 1e-3 rad (the Coriolis force
/// excites a little bending). A rigidly rotated body stores no strain at all (see above).
#[test]
fn spinning_body_carries_only_centrifugal_strain() {
    let (length, height, thickness) = (0.1, 0.01, 0.02);
    let (nodes, elements) = samples::rectangle_mesh(length, height, 20, 4, 0.0);
    let body = ExplicitBody::new(&nodes, &elements, steel(thickness)).unwrap();
    let n = 2 * nodes.len();
    let free = vec![false; n];
    let omega = 500.0;
    let centre = (0.5 * length, 0.0);
    let dt_cr = critical_step(&body, &free, 300);
    let period = std::f64::consts::TAU / omega;
    let steps = (period / (0.5 * dt_cr)).ceil() as usize;
    let dt = period / steps as f64;
    let mut state = State {
        time: 0.0,
        x: nodes.iter().flat_map(|p| [p.x, p.y]).collect(),
        v: nodes
            .iter()
            .flat_map(|p| [-omega * (p.y - centre.1), omega * (p.x - centre.0)])
            .collect(),
        a: vec![0.0; n],
    };
    let mut solver = CentralDifference::new(&body, dt, 0.0, free, dt_cr);
    let none = |_: f64, _: &mut [f64]| {};
    solver.initialize(&mut state, &none);
    let energy0 = solver.energy.kinetic;
    let mut peak_strain: f64 = 0.0;
    for _ in 0..steps {
        solver.step(&mut state, &none).unwrap();
        peak_strain = peak_strain.max(solver.energy.strain);
    }
    let drift = (solver.energy.kinetic + solver.energy.strain) / energy0 - 1.0;
    let (e, nu, rho) = (206e9, 0.3, 7850.0);
    let a = 0.5 * length;
    let static_strain = 2.0 / 15.0 * height * thickness * rho * rho * omega.powi(4) * a.powi(5)
        / (e / (1.0 - nu * nu));
    let (first, last) = (0, nodes.len() - 1);
    let axis = (
        state.x[2 * last] - state.x[2 * first],
        state.x[2 * last + 1] - state.x[2 * first + 1],
    );
    let axis0 = (
        nodes[last].x - nodes[first].x,
        nodes[last].y - nodes[first].y,
    );
    let turn = (axis0.0 * axis.1 - axis0.1 * axis.0).atan2(axis0.0 * axis.0 + axis0.1 * axis.1);
    eprintln!(
        "{steps} steps: peak strain energy {peak_strain:e} J = {:.3} x the static centrifugal {static_strain:e} J; energy drift {drift:e}; orientation error {turn:e} rad",
        peak_strain / static_strain
    );
    let ratio = peak_strain / static_strain;
    assert!((3.5..4.2).contains(&ratio), "peak/static {ratio}");
    assert!(drift.abs() < 1e-6, "{drift:e}");
    assert!(turn.abs() < 1e-3, "orientation error {turn:e}");
}

/// Natural frequencies [Hz] (lowest `count`) and the highest circular frequency [rad/s] of a
/// clamped plane-strain cantilever of Q8 elements, with a lumped mass or (None) the consistent
/// mass, from the dense generalized eigenproblem K φ = ω² M φ.
fn cantilever_frequencies(
    (length, height): (f64, f64),
    (nx, ny): (usize, usize),
    lumping: Option<MassLumping>,
    count: usize,
) -> (Vec<f64>, f64) {
    use geardyn::fe::q8;
    use nalgebra::DMatrix;
    let (nodes, elements) = samples::rectangle_mesh(length, height, nx, ny, 0.0);
    let (rho, t) = (7850.0, 0.0254);
    let d = elasticity_matrix(206e9, 0.3, PlaneState::Strain);
    let n = 2 * nodes.len();
    let mut k = DMatrix::<f64>::zeros(n, n);
    let mut m = DMatrix::<f64>::zeros(n, n);
    for e in &elements {
        let xe = e.map(|i| nodes[i]);
        let ke = q8::stiffness(&xe, &d, t);
        let me = match lumping {
            Some(l) => q8::ElementMatrix::from_diagonal(&q8::ElementVector::from_fn(|i, _| {
                q8::lumped_mass(&xe, rho, t, l)[i / 2]
            })),
            None => q8::consistent_mass(&xe, rho, t),
        };
        for a in 0..16 {
            for b in 0..16 {
                let (p, q) = (2 * e[a / 2] + a % 2, 2 * e[b / 2] + b % 2);
                k[(p, q)] += ke[(a, b)];
                m[(p, q)] += me[(a, b)];
            }
        }
    }
    let free: Vec<usize> = (0..n).filter(|&i| nodes[i / 2].x > 1e-12).collect();
    let pick =
        |a: &DMatrix<f64>| DMatrix::from_fn(free.len(), free.len(), |p, q| a[(free[p], free[q])]);
    let (k, m) = (pick(&k), pick(&m));
    // M = L Lᵀ: K φ = λ M φ ⇔ (L⁻¹ K L⁻ᵀ) ψ = λ ψ.
    let l = m.cholesky().expect("mass is positive definite").l();
    let y = l.solve_lower_triangular(&k).unwrap();
    let a = l.solve_lower_triangular(&y.transpose()).unwrap();
    let mut eigen: Vec<f64> = a.symmetric_eigenvalues().iter().copied().collect();
    eigen.sort_by(f64::total_cmp);
    let hz = eigen[..count]
        .iter()
        .map(|l| l.sqrt() / std::f64::consts::TAU)
        .collect();
    (hz, eigen.last().unwrap().sqrt())
}

/// Both lumped masses converge to the consistent mass's frequencies; the corner-twelfth one
/// trades a larger (still small) frequency error for a lower highest frequency — a longer
/// explicit step. Tooth-sized cantilever (8 × 4 mm, plane strain); reference: the consistent
/// mass on the mesh twice as fine (its own error against a 4× finer mesh is ≈ 0.1 %).
#[test]
fn lumped_masses_converge_to_the_consistent_frequencies() {
    let size = (8e-3, 4e-3);
    let (reference, _) = cantilever_frequencies(size, (16, 8), None, 4);
    let error = |hz: &[f64]| {
        hz.iter()
            .zip(&reference)
            .map(|(f, r)| (f / r - 1.0).abs())
            .fold(0.0, f64::max)
    };
    let mut worst = Vec::new();
    for lumping in [MassLumping::Hrz, MassLumping::CornerTwelfth] {
        let (coarse, omega_coarse) = cantilever_frequencies(size, (4, 2), Some(lumping), 4);
        let (fine, omega_fine) = cantilever_frequencies(size, (8, 4), Some(lumping), 4);
        let (e2, e1) = (error(&coarse), error(&fine));
        eprintln!(
            "{lumping:?}: first four modes {:.0} Hz …; worst error {:.2} % at 2 mm, {:.2} % at 1 mm; ω_max {omega_coarse:.4e} / {omega_fine:.4e} rad/s",
            fine[0],
            100.0 * e2,
            100.0 * e1
        );
        // Converging (second order would divide the error by 4; the mesh is coarse) and small.
        assert!(e1 < 0.5 * e2 && e1 < 0.02, "{lumping:?}: {e2:e} → {e1:e}");
        worst.push((e1, omega_fine));
    }
    let [(hrz_error, hrz_omega), (twelfth_error, twelfth_omega)] = [worst[0], worst[1]];
    assert!(twelfth_error > hrz_error, "HRZ is the more accurate");
    assert!(
        twelfth_omega < 0.85 * hrz_omega,
        "corner-twelfth lowers ω_max: {twelfth_omega:e} vs {hrz_omega:e}"
    );
}
