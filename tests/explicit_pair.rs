//! The explicit FE of the meshing pair on a coarse mesh (1.5 mm flank elements, 3 mm body: about
//! 4 000 elements, so each test runs in seconds): energy balance, the measured critical step as
//! the border between stable and divergent runs, the static DTE against the LTCA on the same
//! mesh, and a freely spinning body that stays unstrained.

use geardyn::case::{Case, Override};
use geardyn::explicit::far::{FarBody, FAR_BLOCK_CUTOFF};
use geardyn::explicit::pair::{Drive, ExplicitPair, PairIntegrator, PairState, Ramp, Start};
use geardyn::explicit::scene::{
    run, FineTeeth, History, Keeping, PreparedScene, RunCheckpoint, RunOutcome, SettledStop,
    TimeStep, KEEP_CHECK_STEPS,
};
use geardyn::study;

/// The paper's pair with a coarse mesh.
fn coarse_case() -> Case {
    coarse(Vec::new())
}

/// The paper's case with `overrides` and a coarse mesh: 1.5 mm flank elements, 3 mm body.
fn coarse(mut overrides: Vec<Override>) -> Case {
    overrides.extend([
        Override::set("mesh.fine_element_mm", 1.5),
        Override::set("mesh.coarse_element_mm", 3.0),
        Override::set("fe.explicit_fine_element_mm", 1.5),
    ]);
    Case::load_with(None, &overrides).unwrap()
}

/// The test matrix's pair `name` with a coarse mesh.
fn coarse_matrix_pair(name: &str) -> Case {
    coarse(
        geardyn::samples::matrix_pair(name)
            .unwrap()
            .parsed_overrides(),
    )
}

/// The low-speed scene at `rpm` for `duration` with a cosine ramp, no damping, and the contact
/// penalty factor `penalty`.
fn prepared(case: &Case, rpm: f64, duration: f64, ramp: f64, penalty: f64) -> PreparedScene {
    let mut scene = case.scene("low-unmodified").unwrap().clone();
    scene.driver_speed = rpm * std::f64::consts::TAU / 60.0;
    scene.duration = duration;
    scene.ramp_time = ramp;
    let mut case = case.clone();
    case.fe.mass_scaling_margin = None;
    case.fe.penalty_factor = penalty;
    case.fe.high_frequency_damping_ratio = 0.0;
    case.fe.mesh_damping_ratio = 0.0;
    let mut p = study::fe::prepare(&case, &scene).unwrap();
    p.drive.ramp = Ramp::Cosine;
    p
}

/// One thread and two (the lock-step's partner thread) step the pair to the same numbers, on
/// 24/40 and on its inverse 40/24 at 300 rpm through contact onset, with the bodies' stiffness
/// damping on: the integrator's own placement of the contact (beside the gear of fewer
/// elements at first, then wherever the threads' measured times balance), and the contact
/// moved to the other thread at every step, so both of the step's task layouts are held, and
/// changes between them.
#[test]
fn one_and_two_threads_step_the_pair_alike() {
    for name in ["24-40", "40-24"] {
        let case = coarse_matrix_pair(name);
        let p = prepared(&case, 300.0, 1e-3, 1e-4, 1.0);
        let run = |threads: usize, alternate: bool| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut integrator = PairIntegrator::new(&p.model, p.drive, p.dt, 0.05 * p.dt);
                assert_eq!(integrator.is_parallel(), threads > 1);
                if alternate {
                    integrator.alternate_contact_thread();
                }
                let mut state = p.model.initial_state(&p.drive);
                integrator.initialize(&mut state);
                let mut contacts = 0;
                for _ in 0..3000 {
                    integrator.step(&mut state).unwrap();
                    contacts = contacts.max(integrator.last_contact.active);
                }
                integrator.update_energy(&state).unwrap();
                let beside = integrator.phase_wall.contact_beside_steps;
                (state, integrator.energy, contacts, beside)
            })
        };
        let one = run(1, false);
        assert!(one.2 > 0, "{name}: no contact closed");
        for alternate in [false, true] {
            let two = run(2, alternate);
            assert!(
                one.0 == two.0,
                "{name}, alternating {alternate}: the states differ"
            );
            assert_eq!(
                one.1, two.1,
                "{name}, alternating {alternate}: the energy accounts"
            );
            if alternate {
                // initialize's force phase and 3000 steps, every other one on each thread.
                assert!(two.3[0].abs_diff(two.3[1]) <= 1, "{name}: {:?}", two.3);
            }
        }
    }
}

/// Without damping, kinetic + strain + contact energy equals the work of the driver and the
/// load to 1e-3 of that work, through contact onset and the ramp (central difference conserves
/// a shadow energy; the true one drifts at O(Δt²)).
#[test]
fn pair_energy_balance_without_damping() {
    let case = coarse_case();
    let p = prepared(&case, 600.0, 2.0e-4, 1.0e-4, 1.0);
    let outcome = run(&p, 2.0e-4, 5e-6, None, None, &mut |_| {}).unwrap();
    assert!(outcome.diverged.is_none(), "{:?}", outcome.diverged);
    let h = &outcome.history;
    let work = h
        .energy
        .iter()
        .map(|e| e.external_work.abs())
        .fold(0.0, f64::max);
    let worst = h
        .energy
        .iter()
        .map(|e| e.balance().abs())
        .fold(0.0, f64::max);
    eprintln!("work {work:e} J, worst balance {worst:e} J");
    assert!(work > 1e-3, "the load did work: {work}");
    assert!(worst < 1e-3 * work, "energy error {worst:e} of {work:e}");
    assert!(
        h.force_total.iter().any(|f| *f > 1000.0),
        "the teeth carry load"
    );
}

/// The measured critical step (power iteration per body, contact springs) is the border: at
/// 0.95 of it the run stays bounded, at 1.3 it diverges and the run stops with a message that
/// names the cause and the stable step, keeping the history up to the last good sample.
#[test]
fn step_above_the_critical_step_is_caught() {
    let case = coarse_case();
    let stable = prepared(&case, 600.0, 5.0e-5, 2.0e-5, 1.0);
    assert!(stable.dt_element_bound <= stable.dt_bodies[0] * (1.0 + 1e-6));
    let mut p = stable;
    p.dt = 0.95 * p.dt_critical;
    let ok = run(&p, 5.0e-5, 1e-6, None, None, &mut |_| {}).unwrap();
    assert!(ok.diverged.is_none(), "{:?}", ok.diverged);
    p.dt = 1.3 * p.dt_critical;
    let bad = run(&p, 5.0e-5, 1e-6, None, None, &mut |_| {}).unwrap();
    let message = bad
        .diverged
        .expect("a step 30 % above the critical one diverges");
    assert!(
        message.contains("diverged") && message.contains("stable step") && message.contains("kept"),
        "{message}"
    );
    let h = &bad.history;
    assert!(!h.time.is_empty() && *h.time.last().unwrap() < 5.0e-5);
    assert!(
        h.dte.iter().all(|d| d.is_finite()),
        "kept samples are finite"
    );
}

/// The pair's own stable step where the contact is — the power iteration on bodies plus penalty
/// springs (`coupled_critical_step`) — against runs continued from that state: at 1.1 of it the
/// run diverges within a few hundred steps, at the run's own step it stays balanced. With no
/// spring closed it is the bodies' own power iteration (to its convergence, 1e-3); closed springs lower it, and the step the run
/// uses (set by the contact springs' bound for every contact state) stays below it. Penalty
/// factor 16, so that the springs and not the bodies' elements limit the step on this coarse
/// mesh (at factor 1 the bodies do: 2.76e-8 s against the springs' bound 3.04e-8 s).
#[test]
fn coupled_step_is_where_the_meshing_pair_goes_unstable() {
    let case = coarse_case();
    fn start(p: &PreparedScene) -> (PairIntegrator<'_>, PairState) {
        let mut integrator = PairIntegrator::new(&p.model, p.drive, p.dt, 0.0);
        let mut state = p.model.initial_state(&p.drive);
        integrator.initialize(&mut state);
        (integrator, state)
    }
    let soft = prepared(&case, 600.0, 2.0e-4, 1.0e-4, 1.0);
    let bodies = soft.dt_bodies[0].min(soft.dt_bodies[1]);
    let (integrator, state) = start(&soft);
    let at_rest = integrator.coupled_critical_step(&state, 100);
    assert!(
        (at_rest / bodies - 1.0).abs() < 1e-3,
        "unloaded: {at_rest:e} against the bodies' {bodies:e}"
    );
    let p = prepared(&case, 600.0, 2.0e-4, 1.0e-4, 16.0);
    // Into mesh, under the full load, at the run's own step.
    let in_mesh = || {
        let (mut integrator, mut state) = start(&p);
        while state.time < 1.5e-4 {
            integrator.step(&mut state).unwrap();
        }
        (integrator, state)
    };
    let (mut unstable, mut state) = in_mesh();
    assert!(unstable.last_contact.active > 0, "in mesh");
    let coupled = unstable.coupled_critical_step(&state, 100);
    eprintln!(
        "coupled {coupled:.4e} s with {} points in contact; bodies {bodies:.4e}, contact bound {:.4e}, step {:.4e}",
        unstable.last_contact.active, p.dt_contact, p.dt
    );
    assert!(
        coupled < 0.95 * bodies,
        "the closed springs lower the stable step"
    );
    assert!(
        coupled > p.dt,
        "the run's step is stable where the contact is"
    );
    let continue_at = |integrator: &mut PairIntegrator, state: &mut PairState, steps: usize| {
        for k in 1..=steps {
            integrator.step(state)?;
            if k % 10 == 0 {
                integrator.update_energy(state)?;
            }
        }
        Ok::<(), String>(())
    };
    unstable.dt = 1.1 * coupled;
    let diverged = continue_at(&mut unstable, &mut state, 1000);
    assert!(diverged.is_err(), "1.1 x the coupled step runs on");
    // The run's own step, below every contact spring's bound, keeps the balance as points
    // close and open. (0.95 × the coupled step does not: the coupled step holds for the contact
    // set it is measured on, and each point that closes as the pair turns adds a penalty spring
    // whose own bound, 7.6e-9 s here, is below it — the balance then takes spikes of 0.1–1.6 J
    // against 5 J present. A step chosen from the coupled one must be re-checked as the contact
    // changes.)
    let (mut own, mut state) = in_mesh();
    continue_at(&mut own, &mut state, 3000).unwrap();
}

/// The pair with the driver held at the pitch-point position and the load torque ramped over
/// 0.15 ms.
fn static_scene(case: &Case, duration: f64, penalty: f64) -> PreparedScene {
    let mut p = prepared(case, 0.0, duration, 1.5e-4, penalty);
    p.drive.driver_speed = 0.0;
    p
}

/// Dynamic relaxation of a static scene for `duration`: mass-proportional damping at ζ ≈ 0.7 of
/// the mesh mode with the driver held (√(k r_b2²/I₂) ≈ 2π·2.8 kHz), the fastest settling. The
/// integrator is returned with that damping still on.
fn relaxed(p: &PreparedScene, duration: f64) -> (PairIntegrator<'_>, PairState) {
    let mut integrator = PairIntegrator::new(&p.model, p.drive, p.dt, 0.0);
    integrator.mass_damping = 1.4 * std::f64::consts::TAU * 2800.0;
    let mut state = p.model.initial_state(&p.drive);
    integrator.initialize(&mut state);
    for _ in 0..(duration / p.dt) as usize {
        integrator.step(&mut state).unwrap();
    }
    (integrator, state)
}

/// Static DTE by dynamic relaxation (driver at rest, torque ramped, mass-proportional damping
/// near the optimum for the mesh mode) against the LTCA on the same mesh at the same position.
/// Tolerance 8 %: at 1.5 mm flank elements the two contact discretizations differ by 6 % (the
/// FE's two-pass Gauss-point contact against the LTCA's exact-profile lattice) and the penalty
/// (factor 16) adds 0.2 %; the difference shrinks with refinement (validation/low-speed).
#[test]
fn static_dte_matches_the_ltca_on_the_same_mesh() {
    let case = coarse_case();
    // 0.6 ms: the contact force is within 0.2 % of T/r_b2 from 0.55 ms on.
    let duration = 6.0e-4;
    let p = static_scene(&case, duration, 16.0);
    let (integrator, state) = relaxed(&p, duration);
    let dte = state.hub[0] - p.model.kinematic_hub_rotation(0.0);
    let force = integrator.last_contact.force_on_driven.norm();
    let static_force = 143.6 / case.pair.gears[1].base_radius;
    assert!(
        (force / static_force - 1.0).abs() < 2e-3,
        "settled: {force} N vs {static_force} N"
    );
    let ltca =
        study::ltca::model(&case, &case.relief_variant("none").unwrap().modifications).unwrap();
    let ste = ltca.solve_position(0, 64, 143.6).unwrap().ste;
    eprintln!(
        "static FE DTE {dte:.5e} rad, LTCA STE {ste:.5e} rad, ratio {:.4}",
        dte / ste
    );
    assert!((dte / ste - 1.0).abs() < 0.08, "FE {dte:e} vs LTCA {ste:e}");
}

/// The same on an unequal pair, 24/40, where the old pairing (gear-1 tooth t with gear-2 tooth
/// (z₂ − t mod z₂) mod z₂) put the second tooth pair on the wrong driven tooth. At the pitch
/// point one pair carries the load; at 0.35 of a pitch two do (the entering pair from 0.143 p:
/// the approach AC is 0.857 p_b). At both, the FE's load per tooth pair (drive flanks) against
/// the LTCA's on the same mesh: the same pairs loaded (above 2 % of the load), each pair's
/// share within 0.15 of the load (measured 0.095 at 0.35 pitch: 0.367 against 0.462 for the
/// entering pair, 0.2 pitch into its contact near the driven tip, where 1.5 mm flank elements
/// resolve the contact coarsely; the converged LTCA gives 0.457). A wrong partner leaves the
/// entering pair unloaded (0.46 off) or loads a pair the LTCA does not.
#[test]
fn an_unequal_pair_shares_the_load_among_the_ltca_pairs() {
    let case = coarse_matrix_pair("24-40");
    let ltca =
        study::ltca::model(&case, &case.relief_variant("none").unwrap().modifications).unwrap();
    let static_force = 143.6 / case.pair.gears[1].base_radius;
    let duration = 8.0e-4;
    let positions = 20;
    for (position, pairs) in [(0, 1), (7, 2)] {
        let mut p = static_scene(&case, duration, 16.0);
        p.drive.start_rotation =
            case.pair.gears[0].angular_pitch() * position as f64 / positions as f64;
        let (integrator, _) = relaxed(&p, duration);
        let contact = &integrator.last_contact;
        let force = contact.force_on_driven.norm();
        assert!(
            (force / static_force - 1.0).abs() < 2e-3,
            "settled: {force} N vs {static_force} N"
        );
        let solved = ltca.solve_position(position, positions, 143.6).unwrap();
        let ltca_total: f64 = solved.pair_forces.iter().sum();
        let fe_total: f64 = p
            .model
            .flank_pairs
            .iter()
            .zip(&contact.pair_forces)
            .filter(|(fp, _)| fp.drive)
            .map(|(_, f)| f)
            .sum();
        let fe_share = |teeth: (usize, usize)| {
            p.model
                .flank_pairs
                .iter()
                .zip(&contact.pair_forces)
                .filter(|(fp, _)| fp.drive && fp.teeth == teeth)
                .map(|(_, f)| f)
                .sum::<f64>()
                / fe_total
        };
        let mut loaded = 0;
        for (i, teeth) in ltca.tooth_pairs.iter().enumerate() {
            let (fe, lt) = (fe_share(*teeth), solved.pair_forces[i] / ltca_total);
            eprintln!("24/40 at {position}/{positions} pitch, pair {teeth:?}: FE share {fe:.4}, LTCA {lt:.4}");
            assert!((fe - lt).abs() < 0.15, "pair {teeth:?}: FE {fe} LTCA {lt}");
            assert_eq!(fe > 0.02, lt > 0.02, "pair {teeth:?}: FE {fe} LTCA {lt}");
            loaded += usize::from(lt > 0.02);
        }
        assert_eq!(loaded, pairs);
        // No drive flank outside the LTCA's pairs carries load.
        let listed: f64 = ltca.tooth_pairs.iter().map(|t| fe_share(*t)).sum();
        assert!((listed - 1.0).abs() < 1e-9, "{listed}");
    }
}

/// Every back-flank contact pair of a scene is driven tooth −s + 1 for driver tooth s
/// ([`geardyn::geometry::ToothPair::back_flank_partner`]), on every tooth pair of a scene over
/// three pitches; and near the mesh (driver teeth −2 … 1, as placed) that driven flank is nearer
/// (middle node to middle node) to the driver's back flank than the one on the far side of the
/// drive partner, for the paper pair and 24/40. Far from the mesh "the nearer neighbour" is no
/// criterion (both gears curve away): it once picked the wrong tooth there for unequal pairs.
#[test]
fn back_flanks_pair_across_the_tooth_space() {
    use geardyn::geometry::Side;
    for case in [coarse_case(), coarse_matrix_pair("24-40")] {
        let z2 = case.pair.gears[1].teeth() as usize;
        // 0.1 s at 60 rpm: 0.63 rad of the driver, 3.6 pitches of 36 teeth, 2.4 of 24.
        let p = prepared(&case, 60.0, 0.1, 0.01, 1.0);
        let model = &p.model;
        let middle = |g: usize, tooth: usize| {
            let nodes = &model.meshes[g].flank(tooth, Side::Right).nodes;
            model.placement[g].to_global(&model.meshes[g].nodes[nodes[nodes.len() / 2]])
        };
        let mut checked = 0;
        for fp in model.flank_pairs.iter().filter(|fp| !fp.drive) {
            let (t1, back) = fp.teeth;
            let drive = model
                .flank_pairs
                .iter()
                .find(|d| d.drive && d.teeth.0 == t1)
                .unwrap()
                .teeth
                .1;
            assert_eq!(back, (drive + 1) % z2);
            // As placed, "nearer" tells the sides apart only near the mesh: within two pitches.
            let z1 = case.pair.gears[0].teeth() as usize;
            if !(t1 <= 1 || t1 + 2 >= z1) {
                continue;
            }
            let far = (drive + z2 - 1) % z2;
            let own = middle(0, t1);
            assert!(
                (middle(1, back) - own).norm() < (middle(1, far) - own).norm(),
                "{} teeth: driver {t1}, drive partner {drive}, back {back}",
                case.pair.gears[0].teeth()
            );
            checked += 1;
        }
        assert!(checked >= 3);
    }
}

/// The mesh dashpot: from a preloaded static state (relaxed as above, penalty factor 1 for a 4×
/// longer step), with the relaxation damping off, a 10 % load step (smoothed over 50 µs) rings
/// the mesh mode down. Three successive extremes of the DTE give the half-period ratio
/// r = e^{−πζ/√(1−ζ²)} without knowing the new equilibrium, and their spacing the damped
/// frequency. A dashpot c_t on a rigid gear of inertia I₂ gives ζ = c_t/(2 I₂ ω_n); the gear's
/// own flexibility and the contact's stiffening with load could bend that by a few per cent:
/// 5 % (measured: 0.2 %).
#[test]
fn mesh_dashpot_damps_the_mesh_mode_as_sized() {
    let case = coarse_case();
    let duration = 4.0e-4;
    let p = static_scene(&case, duration, 1.0);
    let (mut integrator, mut state) = relaxed(&p, duration);
    integrator.mass_damping = 0.0;
    let inertia = p.model.driven_inertia();
    let omega_guess = std::f64::consts::TAU * 2800.0;
    integrator.mesh_damping = 2.0 * 0.1 * inertia * omega_guess;
    let (t0, rise) = (state.time, 5.0e-5);
    let mut samples = Vec::new();
    while state.time < t0 + 6.0e-4 {
        let s = ((state.time - t0) / rise).min(1.0);
        integrator.drive.load_torque =
            143.6 * (1.0 + 0.1 * (0.5 - 0.5 * (std::f64::consts::PI * s).cos()));
        integrator.step(&mut state).unwrap();
        samples.push((
            state.time,
            state.hub[0] - p.model.kinematic_hub_rotation(0.0),
        ));
    }
    // Moving average over ~1/40 of the mode period against element-scale ripple, then the
    // extremes after the rise.
    let width = ((1.0 / 2800.0 / 40.0) / p.dt) as usize | 1;
    let smooth: Vec<(f64, f64)> = samples
        .windows(width)
        .map(|w| {
            (
                w[width / 2].0,
                w.iter().map(|s| s.1).sum::<f64>() / width as f64,
            )
        })
        .collect();
    let extremes: Vec<(f64, f64)> = smooth
        .windows(3)
        .filter(|w| w[0].0 > t0 + rise && (w[1].1 - w[0].1) * (w[2].1 - w[1].1) < 0.0)
        .map(|w| w[1])
        .collect();
    assert!(extremes.len() >= 3, "{} extremes", extremes.len());
    let [e0, e1, e2] = [extremes[0], extremes[1], extremes[2]];
    let ratio = (e1.1 - e2.1) / (e0.1 - e1.1);
    let delta = -ratio.abs().ln();
    let zeta = delta / (std::f64::consts::PI.powi(2) + delta * delta).sqrt();
    let omega_d = std::f64::consts::TAU / (e2.0 - e0.0);
    let omega_n = omega_d / (1.0 - zeta * zeta).sqrt();
    let expected = integrator.mesh_damping / (2.0 * inertia * omega_n);
    eprintln!(
        "mesh mode {:.0} Hz, damping ratio {zeta:.4} measured, {expected:.4} from c_t/(2 I₂ ω_n)",
        omega_n / std::f64::consts::TAU
    );
    assert!(ratio < 0.0, "successive extremes alternate");
    assert!(
        (zeta / expected - 1.0).abs() < 0.05,
        "ζ {zeta} vs {expected}"
    );
}

/// A tooth pair coming into mesh under load books no energy. The entering tooth's tip corner is
/// a slave point of its own, so it meets the mating flank with a spring from the first touch.
/// Without it the corner ran unresisted into the flank until the flank's last Gauss point (7 %
/// of an edge short of the corner) caught it, while the other pass, which leaves points beyond
/// its master flank's end alone, took up the corner's load only once the corner had passed its
/// points, already µm deep: ½ k g² appeared in the balance within one sample. Default explicit
/// mesh (1 mm flanks), 300 rpm, speed and load ramped over 0.5 ms, no damping, the driver
/// starting 0.012 rad past the pitch-point position so that the next pair (gear-1 tooth 35,
/// gear-2 tooth 1) takes up its load at ≈ 0.6 ms. The largest change of the balance between
/// 5 µs samples after the ramp: 8.8e-4 J without the corner point, 2.6e-6 J with it; bound
/// 5e-5 J. On the contact bound's step, as every undamped run: the pair's measured step at
/// factor 0.9 (`fe.time_step = "coupled"`) is marginal where points close and open without
/// element damping, and books jumps of 7.4e-5 J here (see the next test for the scenes).
#[test]
fn a_tooth_entering_mesh_books_no_energy() {
    let case = Case::embedded_default().unwrap();
    let (duration, ramp) = (0.8e-3, 0.5e-3);
    let mut p = prepared(&case, 300.0, duration, ramp, 1.0);
    assert_eq!(
        p.time_step,
        TimeStep::Bound,
        "an undamped run takes the bound"
    );
    p.drive.start_rotation = 0.012;
    let outcome = run(&p, duration, 5e-6, None, None, &mut |_| {}).unwrap();
    assert!(outcome.diverged.is_none(), "{:?}", outcome.diverged);
    let h = &outcome.history;
    let entering = p
        .model
        .flank_pairs
        .iter()
        .position(|fp| fp.name() == "drive_35_1")
        .expect("the entering pair is in the scene");
    let load = &h.pair_forces[entering];
    assert!(
        load[0] == 0.0 && *load.last().unwrap() > 500.0,
        "the pair comes into mesh and takes up load: {} N at the end",
        load.last().unwrap()
    );
    let (mut worst, mut at) = (0.0_f64, 0.0);
    for (k, w) in h.energy.windows(2).enumerate() {
        let jump = (w[1].balance() - w[0].balance()).abs();
        if h.time[k + 1] > ramp && jump > worst {
            (worst, at) = (jump, h.time[k + 1]);
        }
    }
    eprintln!("largest balance step after the ramp {worst:.3e} J at {at:.4e} s");
    assert!(worst < 5e-5, "{worst:e} J at {at:e} s");
}

/// The entering-tooth scene with the scenes' damping (element ζ = 0.05 at ω_max, mesh ζ = 0.05)
/// at step factor `factor`, on the pair's own step and on the bound's. On the graded tooth
/// layout, whose contact springs' bound lies well below the pair's own step (1.94e-8 against
/// 2.52e-8 s for the bodies alone): the stable-step layout's wider tip columns soften the
/// penalty, and its bound (2.60e-8 s) comes within a few percent of the pair's own step, which
/// leaves a raised step little room to differ from the bound's.
fn entering_with_damping(factor: f64) -> (PreparedScene, RunOutcome, RunOutcome) {
    let mut case = Case::embedded_default().unwrap();
    case.fe.tooth_layout = geardyn::mesh::ToothLayout::Graded;
    let (duration, ramp) = (0.8e-3, 0.5e-3);
    let mut scene = case.scene("low-unmodified").unwrap().clone();
    scene.driver_speed = 300.0 * std::f64::consts::TAU / 60.0;
    scene.duration = duration;
    scene.ramp_time = ramp;
    case.fe.mass_scaling_margin = None;
    case.fe.step_factor = factor;
    let mut p = study::fe::prepare(&case, &scene).unwrap();
    p.drive.ramp = Ramp::Cosine;
    p.drive.start_rotation = 0.012;
    assert_eq!(p.time_step, TimeStep::Coupled, "the default");
    let coupled = run(&p, duration, 5e-6, None, None, &mut |_| {}).unwrap();
    p.time_step = TimeStep::Bound;
    let bound = run(&p, duration, 5e-6, None, None, &mut |_| {}).unwrap();
    (p, coupled, bound)
}

/// The step the pair's own stable step allows (`fe.time_step = "coupled"`) against the contact
/// bound's, on the damped entering-tooth scene: the coupled run raises its step above the
/// bound's and takes fewer steps, keeps its samples at the same instants (the last one, at the
/// first step past the end, within a step), and gives the same DTE — within 2e-3 of its
/// peak-to-peak: central difference's own error at the mesh mode is O((ω Δt)²) ≈ 1e-7 here, so
/// what differs is the element-scale ringing each step leaves — and an energy balance within
/// 2e-4 of the work (the stiffness scene: 1.1e-4 coupled, 5.9e-5 bound).
#[test]
fn the_pairs_own_step_takes_fewer_steps_for_the_same_answer() {
    let (p, coupled, bound) = entering_with_damping(0.9);
    for o in [&coupled, &bound] {
        assert!(o.diverged.is_none(), "{:?}", o.diverged);
    }
    assert!(coupled.fallback.is_none(), "{:?}", coupled.fallback);
    let largest = coupled
        .step_changes
        .iter()
        .map(|c| c.dt_s)
        .fold(p.dt, f64::max);
    eprintln!(
        "steps {} against {}; largest step {largest:.4e} s against {:.4e} s; {} checks",
        coupled.steps,
        bound.steps,
        p.dt,
        coupled.coupled_steps.len()
    );
    assert!(largest > 1.1 * p.dt, "the step rose above the bound's");
    assert!(coupled.steps < bound.steps * 95 / 100, "fewer steps");
    let (a, b) = (&coupled.history, &bound.history);
    assert_eq!(a.time.len(), b.time.len());
    let last = a.time.len() - 1;
    for (k, (ta, tb)) in a.time.iter().zip(&b.time).enumerate() {
        let within = if k == last { largest } else { 1e-12 };
        assert!((ta - tb).abs() < within, "sample {k} at {ta} and {tb}");
    }
    let (low, high) = b.dte[..last]
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), d| {
            (l.min(*d), h.max(*d))
        });
    let worst = a.dte[..last]
        .iter()
        .zip(&b.dte)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    eprintln!(
        "DTE apart by {worst:.3e} rad at most, of {:.3e} rad peak-to-peak",
        high - low
    );
    assert!(worst < 2e-3 * (high - low), "{worst:e} of {:e}", high - low);
    let work = b
        .energy
        .iter()
        .map(|e| e.external_work.abs())
        .fold(0.0, f64::max);
    for h in [a, b] {
        let balance = h
            .energy
            .iter()
            .map(|e| e.balance().abs())
            .fold(0.0, f64::max);
        eprintln!("balance {balance:.3e} of {work:.3e} J");
        assert!(balance < 2e-4 * work, "balance {balance:e} of {work:e} J");
    }
}

/// A step factor above 1 on the pair's own step (1.1 × the measured critical step, while the
/// bound's is below the pair's own by more than that): the raised step diverges, and the run
/// goes back to the sample before its last passing check and ends whole on the bound's step,
/// saying why, instead of stopping.
#[test]
fn a_run_whose_raised_step_diverges_ends_on_the_bound() {
    let (p, coupled, bound) = entering_with_damping(1.1);
    assert!(
        bound.diverged.is_none(),
        "the bound holds at 1.1: {:?}",
        bound.diverged
    );
    assert!(coupled.diverged.is_none(), "{:?}", coupled.diverged);
    let why = coupled.fallback.expect("the raised step fell back");
    eprintln!("{why}");
    assert!(why.contains("diverged"), "{why}");
    let end = coupled.step_changes.last().unwrap();
    assert_eq!(end.dt_s, p.dt, "it ends on the bound's step");
    let h = &coupled.history;
    assert_eq!(h.time.len(), bound.history.time.len(), "every sample");
    let work = bound
        .history
        .energy
        .iter()
        .map(|e| e.external_work.abs())
        .fold(0.0, f64::max);
    let balance = h.energy.last().unwrap().balance().abs();
    assert!(balance < 1e-2 * work, "{balance:e} of {work:e} J");
}

/// The coarse 300 rpm scene's step, its bodies without contact surfaces (no flank pairs) and
/// its drive without load, starting at once (no ramp).
fn contactless_at_300_rpm() -> (PreparedScene, ExplicitPair, Drive) {
    let case = coarse_case();
    let p = prepared(&case, 300.0, 1e-4, 0.0, 1.0);
    let model = ExplicitPair::new(
        &case.pair,
        p.model.meshes.clone(),
        case.explicit_material(),
        Vec::new(),
        0.0,
        1.0,
    )
    .unwrap();
    let drive = Drive {
        load_torque: 0.0,
        ramp_time: 0.0,
        ..p.drive
    };
    (p, model, drive)
}

/// The mesh dashpot acts through the contact only. A pair without contact surfaces (no tooth
/// pair), the driver turning at 300 rpm from the start, the driven gear at rest with no load:
/// nothing touches the driven gear, so it stays at rest although its DTE rate is the whole
/// kinematic speed. (A dashpot on the hub against the kinematic reference, as before, would
/// drag it to 1 − e^{−c_t t/I₂} of that speed: a third within 0.1 ms here.)
#[test]
fn the_mesh_dashpot_transmits_nothing_across_open_teeth() {
    let (p, model, drive) = contactless_at_300_rpm();
    let mut integrator = PairIntegrator::new(&model, drive, p.dt, 0.0);
    let inertia = model.driven_inertia();
    integrator.mesh_damping = 4.0 * inertia / 1e-4;
    let mut state = model.initial_state(&drive);
    integrator.initialize(&mut state);
    while state.time < 1e-4 {
        integrator.step(&mut state).unwrap();
    }
    let kinematic = model.kinematic_hub_rotation(drive.driver_speed).abs();
    eprintln!(
        "driven hub speed {:.3e} rad/s after 0.1 ms, kinematic {kinematic:.3} rad/s",
        state.hub[1]
    );
    assert!(state.hub[1].abs() < 1e-9 * kinematic, "{}", state.hub[1]);
}

/// Uniform mass scaling at 60 rpm: the factor puts the mesh mode at three times the fifth mesh harmonic
/// (36 Hz × 5 × 3 = 540 Hz), and every stable step — each body's power iteration, the contact
/// springs' bound, the step used — grows by exactly √factor (all of M⁻¹K scales by 1/factor).
#[test]
fn mass_scaling_lowers_the_mesh_mode_and_lengthens_the_step_by_its_root() {
    let case = coarse_case();
    let unscaled = prepared(&case, 60.0, 1e-3, 1e-4, 1.0);
    let mut scaled_case = case.clone();
    scaled_case.fe.mass_scaling_mode = geardyn::explicit::scene::MassScalingMode::Uniform;
    scaled_case.fe.high_frequency_damping_ratio = 0.0;
    scaled_case.fe.mesh_damping_ratio = 0.0;
    let mut scene = case.scene("low-unmodified").unwrap().clone();
    (scene.duration, scene.ramp_time) = (1e-3, 1e-4);
    let scaled = study::fe::prepare(&scaled_case, &scene).unwrap();
    let s = scaled.mass_scaling;
    eprintln!("{s:?}");
    assert_eq!(unscaled.mass_scaling.factor, 1.0);
    assert!((s.scaled_mesh_mode_hz / 540.0 - 1.0).abs() < 1e-9, "{s:?}");
    assert!(s.factor > 10.0, "{s:?}");
    let root = s.factor.sqrt();
    for (a, b) in [
        (scaled.dt_bodies[0], unscaled.dt_bodies[0]),
        (scaled.dt_bodies[1], unscaled.dt_bodies[1]),
        (scaled.dt_contact, unscaled.dt_contact),
        (scaled.dt, unscaled.dt),
    ] {
        assert!(
            (a / b / root - 1.0).abs() < 1e-9,
            "{a} / {b} against {root}"
        );
    }
    assert!(
        (scaled.model.driven_inertia() / unscaled.model.driven_inertia() / s.factor - 1.0).abs()
            < 1e-12
    );
}

/// Mass scaling to a target step (`fe.mass_scaling_mode = "target-step"`) on the paper pair, 24/40,
/// 40/24 and the shifted 17/53 at 60 rpm: each gear's polar inertia is raised by exactly the uniform scaling's
/// factor s (1e-9), so the scaled mesh mode is uniform scaling's (and is what the model's
/// driven inertia gives); the integrator's inverse masses and the driven hub's inertia follow
/// the new nodal masses; each body's measured stable step is at least its T_g (Irons' element
/// bound, which the per-element factors (T_g/Δtₑ)² are built on), and the pair's step is more
/// than 1.5 × uniform scaling's: the mass goes to the small elements that set the step, not to
/// the body (2.95 × fewer steps in the stiffness scene on the paper pair's 1 mm flanks, 3 mm body).
#[test]
fn target_step_mass_scaling_keeps_the_inertia_and_lengthens_the_step() {
    use geardyn::explicit::scene::MassScalingMode;
    for name in ["paper36", "24-40", "40-24", "17-53-shift"] {
        let mut case = coarse_matrix_pair(name);
        case.fe.high_frequency_damping_ratio = 0.0;
        case.fe.mesh_damping_ratio = 0.0;
        let mut scene = case.scene("low-unmodified").unwrap().clone();
        (scene.duration, scene.ramp_time) = (1e-3, 1e-4);
        case.fe.mass_scaling_mode = MassScalingMode::Uniform;
        let uniform = study::fe::prepare(&case, &scene).unwrap();
        case.fe.mass_scaling_mode = MassScalingMode::TargetStep;
        let target = study::fe::prepare(&case, &scene).unwrap();
        let mut unscaled_case = case.clone();
        unscaled_case.fe.mass_scaling_margin = None;
        let unscaled = study::fe::prepare(&unscaled_case, &scene).unwrap();
        let s = target.mass_scaling;
        eprintln!("{name}: {s:?}");
        assert_eq!(s.mode, MassScalingMode::TargetStep);
        assert!(s.factor > 10.0, "{s:?}");
        let steps = s.target_steps_s.expect("target steps");
        let model = &target.model;
        for (g, step) in steps.into_iter().enumerate() {
            let ratio = model.inertia(g) / unscaled.model.inertia(g) / s.factor;
            assert!(
                (ratio - 1.0).abs() < 1e-9,
                "{name}: gear {g}'s inertia {ratio} × s"
            );
            assert!(
                target.dt_bodies[g] >= step * (1.0 - 1e-6),
                "{name}: gear {g}'s stable step {} under T {step}",
                target.dt_bodies[g],
            );
            let mass = &model.bodies[g].mass;
            for (d, (w, free)) in model.inverse_mass(g).iter().zip(&model.free[g]).enumerate() {
                let expected = if *free { 1.0 / mass[d / 2] } else { 0.0 };
                assert_eq!(*w, expected, "{name}: gear {g}, DOF {d}");
            }
        }
        let hub: f64 = model.meshes[1]
            .bore_nodes
            .iter()
            .map(|&n| model.bodies[1].mass[n] * model.meshes[1].nodes[n].coords.norm_squared())
            .sum();
        assert!(
            (model.hub_inertia / hub - 1.0).abs() < 1e-12,
            "{name}: hub inertia"
        );
        assert!(
            model.hub_inertia > 1.5 * unscaled.model.hub_inertia,
            "{name}: the bore elements' mass did not grow"
        );
        let mode_ratio = s.scaled_mesh_mode_hz / uniform.mass_scaling.scaled_mesh_mode_hz;
        assert!(
            (mode_ratio - 1.0).abs() < 1e-9,
            "{name}: mesh mode {mode_ratio}"
        );
        let gain = target.dt / uniform.dt;
        eprintln!(
            "{name}: T {steps:?}, step {:e} against uniform {:e}: {gain:.2} x",
            target.dt, uniform.dt
        );
        assert!(gain > 1.5, "{name}: {gain}");
    }
}

/// A start at speed ([`Start::AtSpeed`]) without load and without contact surfaces: both gears
/// turn rigidly at the kinematic speeds from t = 0 (Ω₁ = 300 rpm, Ω₂ = −(z₁/z₂)Ω₁), so the
/// initial kinetic energy is ½(I₁Ω₁² + I₂Ω₂²) of the nodal masses to round-off and is booked as
/// external work; over 0.1 ms the driven hub keeps its kinematic speed and angle (no torque
/// acts on it: 1e-6 of the speed, 1e-9 rad — what the centrifugal breathing of the corotational
/// bodies leaves) and the energy balances to 1e-6 of the kinetic energy. A sign error in the
/// driven gear's initial velocities would spin it against its hub and fail the checks after
/// 0.1 ms (the ones at t = 0 see only v²).
#[test]
fn a_start_at_speed_turns_both_gears_rigidly_at_the_kinematic_speeds() {
    use geardyn::explicit::pair::Start;
    let (p, model, unloaded) = contactless_at_300_rpm();
    let drive = Drive {
        start: Start::AtSpeed,
        ..unloaded
    };
    let mut integrator = PairIntegrator::new(&model, drive, p.dt, 0.0);
    let mut state = model.initial_state(&drive);
    integrator.initialize(&mut state);
    let driven_speed = model.kinematic_hub_rotation(drive.driver_speed);
    let kinetic = 0.5
        * (model.inertia(0) * drive.driver_speed.powi(2) + model.inertia(1) * driven_speed.powi(2));
    let e0 = integrator.energy;
    assert!(
        (e0.kinetic / kinetic - 1.0).abs() < 1e-12,
        "{e0:?} vs {kinetic}"
    );
    assert!((e0.external_work / kinetic - 1.0).abs() < 1e-12, "{e0:?}");
    assert_eq!(state.hub[1], driven_speed);
    while state.time < 1e-4 {
        integrator.step(&mut state).unwrap();
    }
    let (driver_rotation, _, _) = drive.driver_motion(state.time);
    let dte = model.kinematic_hub_rotation(driver_rotation) - state.hub[0];
    eprintln!(
        "after 0.1 ms: hub speed {:.9e} (kinematic {driven_speed:.9e}) rad/s, DTE {dte:.3e} rad, balance {:.3e} J of {kinetic:.3e} J",
        state.hub[1],
        integrator.energy.balance()
    );
    assert!((state.hub[1] / driven_speed - 1.0).abs() < 1e-6);
    assert!(dte.abs() < 1e-9, "{dte}");
    assert!(integrator.energy.balance().abs() < 1e-6 * kinetic);
}

/// Duration of [`twelve_pitch_scene`] [s].
const TWELVE_PITCH_DURATION: f64 = 1.8e-3;

/// The coarse pair's high-speed scene at 12 000 rpm over 1.8 ms, the gears turning from the start
/// and the load ramped over 0.2 ms: the driver turns
/// through twelve pitches, so a run on windows of fine teeth goes through twelve meshes.
fn twelve_pitch_scene(fine_teeth: FineTeeth) -> PreparedScene {
    twelve_pitch_scene_with(fine_teeth, FarBody::Full)
}

/// [`twelve_pitch_scene`] with its far bodies modelled as `far_body` says.
fn twelve_pitch_scene_with(fine_teeth: FineTeeth, far_body: FarBody) -> PreparedScene {
    high_speed_scene_of(&coarse_case(), fine_teeth, far_body)
}

/// `case`'s high-speed scene at 12 000 rpm over [`TWELVE_PITCH_DURATION`], turning from the
/// start, the load ramped over 0.2 ms, its teeth and far bodies as given.
fn high_speed_scene_of(case: &Case, fine_teeth: FineTeeth, far_body: FarBody) -> PreparedScene {
    high_speed_scene_over(case, fine_teeth, far_body, TWELVE_PITCH_DURATION)
}

/// [`high_speed_scene_of`] over `duration`.
fn high_speed_scene_over(
    case: &Case,
    fine_teeth: FineTeeth,
    far_body: FarBody,
    duration: f64,
) -> PreparedScene {
    let mut scene = case.scene("high-unmodified").unwrap().clone();
    scene.driver_speed = 12_000.0 * std::f64::consts::TAU / 60.0;
    scene.duration = duration;
    scene.ramp_time = 0.2e-3;
    // Turning already: a spin-up to 12 000 rpm in 0.2 ms would swing the DTE by 30 mrad.
    scene.start = Start::AtSpeed;
    let mut case = case.clone();
    case.fe.fine_teeth = fine_teeth;
    case.fe.far_body = far_body;
    study::fe::prepare(&case, &scene).unwrap()
}

/// `case`'s run of [`high_speed_scene_of`] on windows of fine teeth with its far bodies as
/// `far_body`, over [`TWELVE_PITCH_DURATION`], which must not diverge.
fn twelve_pitch_outcome(case: &Case, far_body: FarBody) -> RunOutcome {
    let prepared = high_speed_scene_of(case, FineTeeth::Window, far_body);
    let outcome = run(
        &prepared,
        TWELVE_PITCH_DURATION,
        2e-6,
        None,
        None,
        &mut |_| {},
    )
    .unwrap();
    assert!(outcome.diverged.is_none(), "{:?}", outcome.diverged);
    outcome
}

/// A run whose scene may stop once settled ([`SettledStop`]) ends at the first check where its
/// own record meets the rule, not later and not sooner, with the record of the run that went
/// on to its duration up to there, bit for bit, and says where it stopped; across windows of
/// fine teeth (the FE speed sweep's runs; full far bodies, whose blocks would take most of
/// the test's time on this coarse mesh). The rule is set to stop at
/// any drift here, with thirds of 0.1 ms, so that a short run reaches it (at 3 ms, its third check): whether the rule's
/// own drift and thirds are right is the unit test's (explicit::scene).
#[test]
fn a_run_stops_where_its_record_settled() {
    let duration = 3.1e-3;
    let mut prepared =
        high_speed_scene_over(&coarse_case(), FineTeeth::Window, FarBody::Full, duration);
    let interval = 5e-6;
    let full = run(&prepared, duration, interval, None, None, &mut |_| {}).unwrap();
    assert!(full.diverged.is_none() && full.settled_at_s.is_none());
    assert!(
        prepared.settled_stop.is_none(),
        "the case's scene does not ask for it"
    );
    let stop = SettledStop {
        from_s: 0.3e-3,
        mesh_hz: 12_000.0 / 60.0 * 36.0,
        min_third_s: 0.1e-3,
        drift: f64::INFINITY,
        growth: f64::INFINITY,
    };
    // The rule on the whole run's record, sample by sample, as the run applies it.
    let h = &full.history;
    let expected = (2..h.time.len()).find(|&n| {
        let dt = h.time[n - 1] / (n - 1) as f64;
        stop.due(&h.time[..n]) && stop.settled(&h.dte[..n], dt)
    });
    let expected = expected.expect("the rule stops the whole run's record somewhere");
    assert!(expected + 1 < h.time.len(), "not before the end");
    prepared.settled_stop = Some(stop);
    let stopped = run(&prepared, duration, interval, None, None, &mut |_| {}).unwrap();
    eprintln!(
        "stopped at {:?} s after {} windows (the whole run {} windows to {} s)",
        stopped.settled_at_s,
        stopped.windows,
        full.windows,
        h.time.last().unwrap()
    );
    assert_eq!(stopped.settled_at_s, Some(h.time[expected - 1]));
    assert_eq!(stopped.history.time, h.time[..expected]);
    assert_eq!(stopped.history.dte, h.dte[..expected]);
    assert!(stopped.windows > 1 && stopped.windows <= full.windows);
    assert!(stopped.diverged.is_none() && stopped.interrupted.is_none());
    assert!(stopped.checkpoint.is_none());
}

/// A scene that asks to stop once settled gets its rule from `prepare`: judged from the
/// statistics start, on the driver's mesh frequency, at the rule's own tolerances; also where
/// the scene is lengthened to cover a base pitch (the stiffness scene); on the paper pair, 24/40
/// and its inverse 40/24 (the driver's pitch sets the mesh frequency).
#[test]
fn a_scene_that_stops_when_settled_is_prepared_with_its_rule() {
    use geardyn::explicit::scene::statistics_start;
    let pairs = [None, Some("24-40"), Some("40-24")];
    for (pair, name) in pairs
        .into_iter()
        .flat_map(|p| ["high-unmodified", "stiffness"].map(|n| (p, n)))
    {
        let mut overrides = pair.map_or_else(Vec::new, |p| {
            geardyn::samples::matrix_pair(p).unwrap().parsed_overrides()
        });
        overrides.push(Override::set(
            format!("scene[{name}].stop_when_settled"),
            true,
        ));
        let case = coarse(overrides);
        let scene = case.scene(name).unwrap();
        assert!(scene.stop_when_settled);
        let prepared = study::fe::prepare(&case, scene).unwrap();
        let stop = prepared.settled_stop.expect("the scene asks for it");
        let mesh_hz = scene.driver_speed / case.pair.gears[0].angular_pitch();
        assert_eq!(
            stop.from_s,
            statistics_start(&prepared, scene),
            "{pair:?} {name}"
        );
        assert!(
            (stop.mesh_hz / mesh_hz - 1.0).abs() < 1e-12,
            "{pair:?} {name}"
        );
        assert_eq!(
            (stop.min_third_s, stop.drift, stop.growth),
            (
                SettledStop::MIN_THIRD_S,
                SettledStop::DRIFT,
                SettledStop::GROWTH
            )
        );
    }
}

/// An FE speed sweep run (compare's `sweep_speed_overrides`) starts at its speed with only the
/// load ramping, on a cosine over `FE_SWEEP_LOAD_RAMP_S` (the ringing π²/((ω_n t_r)² − π²), no
/// spin-up term), and its statistics (and its settled stop's thirds) start at the ramp's end
/// plus the settling time of that ringing, which is none where the ringing is under
/// `SETTLED_RINGING`: on the paper's pair (mesh mode 3.2 kHz on this coarse mesh, ringing
/// 1.0e-3), 24/40 (2.9 kHz, 1.2e-3), its inverse 40/24 (5.0 kHz, 4.0e-4) and the shifted 19/57
/// (1.9 kHz, 2.7e-3), each at 0.8 and 1.2 times its driver-held mesh resonance speed: all above
/// the 1.4 kHz where a 5 ms ramp's ringing reaches it (the settling time below that is
/// `the_ramp_leaves_the_ringing_the_settling_time_assumes`'s).
#[test]
fn a_sweep_run_starts_at_speed_and_measures_after_its_load_ramp() {
    use geardyn::explicit::scene::{statistics_start, SETTLED_RINGING};
    use study::compare::{sweep_speed_overrides, FE_SWEEP_LOAD_RAMP_S, SPEED_SCENE};
    for pair in [None, Some("24-40"), Some("40-24"), Some("19-57-shift")] {
        let pair_overrides = pair.map_or_else(Vec::new, |p| {
            geardyn::samples::matrix_pair(p).unwrap().parsed_overrides()
        });
        let base = coarse(pair_overrides.clone());
        let spin_up = study::fe::prepare(&base, base.scene(SPEED_SCENE).unwrap()).unwrap();
        assert_eq!(
            spin_up.drive.start,
            Start::Rest,
            "{pair:?}: the scene's own start"
        );
        // The driver-held mesh mode's speed: f_n over the driver's teeth.
        let mode_hz = 1.0 / spin_up.mesh_mode_period;
        let resonance_rpm = 60.0 * mode_hz / base.pair.gears[0].teeth() as f64;
        for rpm in [0.8 * resonance_rpm, 1.2 * resonance_rpm] {
            let mut overrides = pair_overrides.clone();
            overrides.extend(sweep_speed_overrides(&base, rpm));
            let case = coarse(overrides);
            let scene = case.scene(SPEED_SCENE).unwrap();
            let prepared = study::fe::prepare(&case, scene).unwrap();
            let drive = &prepared.drive;
            assert_eq!(
                (drive.start, drive.ramp, drive.ramp_time),
                (Start::AtSpeed, Ramp::Cosine, FE_SWEEP_LOAD_RAMP_S),
                "{pair:?} at {rpm:.0} rpm"
            );
            assert!((drive.driver_speed * 60.0 / std::f64::consts::TAU / rpm - 1.0).abs() < 1e-12);
            let omega = std::f64::consts::TAU / prepared.mesh_mode_period;
            let wt = omega * FE_SWEEP_LOAD_RAMP_S;
            let pi2 = std::f64::consts::PI.powi(2);
            let ringing = pi2 / (wt * wt - pi2);
            assert!(
                (prepared.ramp_ringing / ringing - 1.0).abs() < 1e-12,
                "{pair:?}: ringing {} against {ringing}",
                prepared.ramp_ringing
            );
            let start = statistics_start(&prepared, scene);
            let stop = prepared
                .settled_stop
                .expect("a sweep run stops when settled");
            assert_eq!(stop.from_s, start, "{pair:?}");
            assert_eq!(
                start,
                FE_SWEEP_LOAD_RAMP_S + prepared.settling_time,
                "{pair:?}"
            );
            assert!(ringing < SETTLED_RINGING, "{pair:?}: {ringing}");
            assert_eq!(prepared.settling_time, 0.0, "{pair:?}");
            if pair.is_none() {
                assert!(ringing < 1.2e-3, "{ringing}");
            }
        }
    }
}

/// Reduced far bodies on pairs of unequal gears (the test matrix's 24/40 and its inverse
/// 40/24, coarse: pitches of 15° and 9°, so the two gears' windows advance by different turns
/// and their blocks' patterns differ): against the same windows in full, held to the windows'
/// own tolerances, each window's blocks built or found turned into place. Measured
/// (2026-12-06, the cutoff 6 times the fine sectors' lowest mode): 24/40, 9 windows, DTE
/// peak-to-peak +0.17 %, rms of the difference 0.13 % of the peak-to-peak, pair loads within
/// 0.04 % of the largest; 40/24, 15 windows, peak-to-peak −0.62 %, rms 1.21 %, pair loads
/// within 0.35 %. Under the rule before (16 times the block's own lowest mode) 40/24 was
/// −2.9 % off: its 40-tooth block kept its modes to 178 kHz only (now 237–265 kHz). Ignored in
/// the suite (about 2 minutes): `cargo test --release --test explicit_pair -- --ignored unequal`.
#[test]
#[ignore = "about 2 minutes"]
fn reduced_far_bodies_on_unequal_gears_follow_their_full_bodies() {
    for name in ["24-40", "40-24"] {
        unequal_gears_against_their_full_bodies(name);
    }
}

/// [`reduced_far_bodies_on_unequal_gears_follow_their_full_bodies`] on the test matrix's pair
/// `name`.
fn unequal_gears_against_their_full_bodies(name: &str) {
    let case = coarse_matrix_pair(name);
    let (full, reduced) = (
        twelve_pitch_outcome(&case, FarBody::Full),
        twelve_pitch_outcome(&case, FarBody::Reduced),
    );
    assert!(full.windows >= 6, "{} windows", full.windows);
    assert_eq!(reduced.windows, full.windows);
    eprintln!(
        "{name}: {} windows, {:.0} against {:.0} elements a step; blocks built {}, reused {}",
        reduced.windows,
        reduced.element_steps / reduced.steps as f64,
        full.element_steps / full.steps as f64,
        reduced.far_blocks_built,
        reduced.far_blocks_reused
    );
    TwelvePitchAgreement::of(&reduced, &full).assert_within_the_windows_tolerances();
    assert_eq!(
        reduced.far_blocks_built + reduced.far_blocks_reused,
        2 * reduced.windows
    );
    assert!(reduced.far_blocks_reused > reduced.far_blocks_built);
}

/// A run on windows of fine teeth (`fe.fine_teeth = "window"`, the default) against the same
/// scene with every engaging tooth fine throughout: fewer elements per step, the same DTE, and
/// an energy account that closes once the remeshing's share is booked. What a switch loses is
/// what the coarser mesh cannot hold of the leaving teeth's own deformation; they leave out of
/// contact, so that is their free ringing at the element scale. Then the same windows with
/// reduced far bodies against them in full (in this test, to share its runs).
#[test]
fn a_run_on_windows_of_fine_teeth_follows_the_whole_scenes_mesh() {
    let output = 2e-6;
    let windowed_scene = twelve_pitch_scene(FineTeeth::Window);
    let whole_scene = twelve_pitch_scene(FineTeeth::Scene);
    let duration = TWELVE_PITCH_DURATION;
    let windowed = run(&windowed_scene, duration, output, None, None, &mut |_| {}).unwrap();
    let whole = run(&whole_scene, duration, output, None, None, &mut |_| {}).unwrap();
    for o in [&windowed, &whole] {
        assert!(o.diverged.is_none(), "{:?}", o.diverged);
    }
    assert_eq!(whole.windows, 0);
    assert!(windowed.windows >= 12, "{} windows", windowed.windows);
    let mean_elements = windowed.element_steps / windowed.steps as f64;
    let scene_elements = whole_scene.model.elements() as f64;
    eprintln!(
        "{} windows, {mean_elements:.0} elements per step against {scene_elements}",
        windowed.windows
    );
    // On this coarse pair a fine tooth (1.5 mm flanks) is little larger than a coarse one
    // (3 mm), so the windows save 6 % of the elements (the 3000 rpm scene at 1 mm flanks: 41 %).
    assert!(mean_elements < 0.97 * scene_elements);
    assert_eq!(whole.element_steps, whole.steps as f64 * scene_elements);

    // Measured: mean 5e-4, peak-to-peak 4e-3, rms of the difference 5e-3 and its largest
    // sample 2e-2 of the peak-to-peak. Sample by sample the runs differ by the ringing of the
    // teeth that left the mesh: nearly undamped at their own frequencies (the element damping
    // is ζ = 0.05 at ω_max, 1e-4 at 40 kHz), it goes on in the scene's mesh and is dropped at a
    // switch (validation/performance).
    let agreement = TwelvePitchAgreement::of(&windowed, &whole);
    agreement.assert_within_the_windows_tolerances();
    assert!(
        agreement.worst < 0.05 * agreement.peak_to_peak[1],
        "{:e} against {:e}",
        agreement.worst,
        agreement.peak_to_peak[1]
    );

    // The same windows with each gear's coarse sectors as one reduced block (`fe.far_body =
    // "reduced"`) against them in full: the same DTE and pair loads to within what the
    // block's truncated modes move, held to the windows' own tolerances, an energy account
    // that closes, and one block built per gear and pattern of fine teeth, turned into place
    // for the other windows, at the default cutoff (6 times the fine sectors' lowest mode).
    // 12 000 rpm turns the blocks four times as fast as the paper's 3000 rpm scene.
    let reduced_scene = twelve_pitch_scene_with(FineTeeth::Window, FarBody::Reduced);
    let reduced = run(&reduced_scene, duration, output, None, None, &mut |_| {}).unwrap();
    assert!(reduced.diverged.is_none(), "{:?}", reduced.diverged);
    assert_eq!(reduced.windows, windowed.windows);
    let per_step = |o: &RunOutcome| o.phase_wall.per_step_us().step;
    eprintln!(
        "reduced far bodies: {:.0} elements a step against {mean_elements:.0}, a step {:.1} \
         against {:.1} us",
        reduced.element_steps / reduced.steps as f64,
        per_step(&reduced),
        per_step(&windowed)
    );
    TwelvePitchAgreement::of(&reduced, &windowed).assert_within_the_windows_tolerances();
    // Each window looks up both gears' blocks: built for the first windows' patterns, then
    // turned into place (measured: 4 built, 22 reused).
    eprintln!(
        "blocks built {}, reused {}",
        reduced.far_blocks_built, reduced.far_blocks_reused
    );
    assert_eq!(
        reduced.far_blocks_built + reduced.far_blocks_reused,
        2 * reduced.windows
    );
    assert!(reduced.far_blocks_built <= 4 && windowed.far_blocks_built == 0);
}

/// Two twelve-pitch runs `a` and `b` ([`twelve_pitch_scene`]) after the load's ramp: the
/// DTE's mean and peak-to-peak of each, the rms and largest of its difference sample by
/// sample, the largest difference of the flank pairs' mean loads and the largest mean load,
/// and `a`'s energy account over its transmitted work (the largest balance error, the
/// remeshing).
struct TwelvePitchAgreement {
    mean: [f64; 2],
    peak_to_peak: [f64; 2],
    rms_difference: f64,
    worst: f64,
    worst_pair: f64,
    largest_pair: f64,
    balance: f64,
    remeshing: f64,
}

impl TwelvePitchAgreement {
    fn of(first: &RunOutcome, second: &RunOutcome) -> Self {
        let (a, b) = (&first.history, &second.history);
        assert_eq!(a.time, b.time, "the samples at the same instants");
        let from = b.time.iter().position(|t| *t > 0.2e-3).unwrap();
        let (x, y) = (&a.dte[from..], &b.dte[from..]);
        let span = |d: &[f64]| {
            d.iter().copied().fold(f64::MIN, f64::max) - d.iter().copied().fold(f64::MAX, f64::min)
        };
        let mean = |d: &[f64]| d.iter().sum::<f64>() / d.len() as f64;
        let rms_difference =
            (x.iter().zip(y).map(|(p, q)| (p - q).powi(2)).sum::<f64>() / y.len() as f64).sqrt();
        let worst = x
            .iter()
            .zip(y)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max);
        // The windows' pair forces land in the scene's columns of the history.
        let mean_load = |h: &History, k: usize| mean(&h.pair_forces[k][from..]);
        let pairs = b.pair_forces.len();
        let largest_pair = (0..pairs).map(|k| mean_load(b, k)).fold(0.0, f64::max);
        let worst_pair = (0..pairs)
            .map(|k| (mean_load(a, k) - mean_load(b, k)).abs())
            .fold(0.0, f64::max);
        let transmitted = first.final_energy.transmitted_work;
        let balance = |h: &History| {
            h.energy
                .iter()
                .map(|e| e.balance().abs())
                .fold(0.0, f64::max)
        };
        let agreement = TwelvePitchAgreement {
            mean: [mean(x), mean(y)],
            peak_to_peak: [span(x), span(y)],
            rms_difference,
            worst,
            worst_pair,
            largest_pair,
            balance: balance(a) / transmitted,
            remeshing: first.final_energy.remeshing / transmitted,
        };
        eprintln!(
            "DTE: mean {:.5e} / {:.5e} rad, peak-to-peak {:.4e} / {:.4e} rad, rms difference \
             {rms_difference:.3e}, largest {worst:.3e}; mean pair loads: largest difference \
             {worst_pair:.3e} N of {largest_pair:.3e} N; balance {:.3e} (the other run \
             {:.3e}), remeshing {:.3e} of the transmitted work",
            agreement.mean[0],
            agreement.mean[1],
            agreement.peak_to_peak[0],
            agreement.peak_to_peak[1],
            agreement.balance,
            balance(b) / transmitted,
            agreement.remeshing,
        );
        agreement
    }

    /// What a run on windows is held to against the whole scene's mesh: the DTE's mean within
    /// 0.2 % and its peak-to-peak within 2 %, the rms of the difference within 2 % of the
    /// peak-to-peak, every flank pair's mean load within 2 % of the largest (sample by sample
    /// the impacts' timing differs), the energy account closed to 1e-4 and the remeshing's
    /// share within 1e-3 of the transmitted work.
    fn assert_within_the_windows_tolerances(&self) {
        assert!((self.mean[0] / self.mean[1] - 1.0).abs() < 2e-3);
        assert!((self.peak_to_peak[0] / self.peak_to_peak[1] - 1.0).abs() < 0.02);
        assert!(self.rms_difference < 0.02 * self.peak_to_peak[1]);
        assert!(self.largest_pair > 0.0 && self.worst_pair < 0.02 * self.largest_pair);
        assert!(self.balance < 1e-4);
        assert!(self.remeshing.abs() < 1e-3);
    }
}

/// A windowed run keeps checkpoints on one clock across its windows, and one kept in a later
/// window and resumed from there (on one thread) ends with the same history, bit for bit, as
/// the run that went through (on two).
///
/// The clock counts its own reads (one at the start, one per look every `KEEP_CHECK_STEPS`
/// steps, one after each checkpoint), and a checkpoint is due every 1.3 × a twelfth of the
/// run's looks at the bound step, the smallest: the run turns 12.96 pitches in 13 windows, so
/// no window alone reaches it, a clock restarted at each window (as before dce9b99) keeps
/// none, and one across the run keeps one about every 1.4 windows.
#[test]
fn a_run_resumed_in_a_later_window_ends_as_the_whole_run() {
    resumed_in_a_later_window(FarBody::Full);
}

/// [`a_run_resumed_in_a_later_window_ends_as_the_whole_run`] with reduced far bodies: the
/// blocks' state goes into the checkpoint and comes back bit for bit. The kept checkpoint is
/// in the third window or later, whose blocks were built in the first two and turned into
/// place: the resumed run builds them again where the checkpoint says they were built (the
/// build is deterministic), not on its own window's mesh, whose block would be another basis.
#[test]
fn a_run_with_reduced_far_bodies_resumed_in_a_later_window_ends_as_the_whole_run() {
    resumed_in_a_later_window(FarBody::Reduced);
}

fn resumed_in_a_later_window(far_body: FarBody) {
    let output = 2e-6;
    let duration = TWELVE_PITCH_DURATION;
    let p = twelve_pitch_scene_with(FineTeeth::Window, far_body);
    let looks_per_window = (duration / p.dt).ceil() / 12.0 / KEEP_CHECK_STEPS as f64;
    let mut kept_windows = Vec::new();
    let mut kept = None;
    let mut keep = |c: &RunCheckpoint, h: &History| {
        let index = c.window.as_ref().expect("a run on windows").index;
        kept_windows.push(index);
        if kept.is_none() && index >= 2 {
            kept = Some((c.clone(), h.clone()));
        }
    };
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let whole = two
        .install(|| {
            let mut reads = 0.0;
            let keeping = Keeping {
                every_s: 1.3 * looks_per_window,
                keep: &mut keep,
                clock: Box::new(move || {
                    reads += 1.0;
                    reads
                }),
            };
            run(&p, duration, output, None, Some(keeping), &mut |_| {})
        })
        .unwrap();
    assert!(whole.windows >= 12, "{} windows", whole.windows);
    eprintln!("checkpoints kept in windows {kept_windows:?}");
    assert!(
        kept_windows.len() >= 5 && kept_windows.windows(2).all(|w| w[0] < w[1]),
        "checkpoints kept in windows {kept_windows:?}"
    );
    let (checkpoint, history) = kept.expect("a checkpoint in the third window or later");
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let resumed = one
        .install(|| {
            run(
                &p,
                duration,
                output,
                Some((checkpoint, history)),
                None,
                &mut |_| {},
            )
        })
        .unwrap();
    assert_eq!(resumed.windows, whole.windows);
    assert_eq!(resumed.steps, whole.steps);
    assert_eq!(resumed.element_steps, whole.element_steps);
    assert!(
        resumed.history == whole.history,
        "the resumed history differs"
    );
    assert_eq!(resumed.final_energy, whole.final_energy);
}

/// The case's stiffness scene lasts 44 ms, one base pitch of the paper pair's driver after the
/// ramp and the mesh mode's settling. With `cover_pitch` (the case's stiffness scenes) a pair
/// whose pitch or settling needs longer is prepared for longer: on 24/40 (a 15° driver pitch,
/// 41.7 ms at 60 rpm) and on the shifted 19/57 (52.6 ms, settling about 21 ms) the statistics
/// window then starts after the settling and still holds one mesh period and the low-pass
/// span. The paper pair and 40/24 (a 9° driver pitch, 25 ms) keep their duration, and a scene
/// with `cover_pitch` off keeps the duration it is given, however short.
#[test]
fn a_stiffness_scene_covers_a_base_pitch_of_any_pair() {
    use geardyn::explicit::scene::statistics_start;
    for name in ["paper36", "24-40", "40-24", "19-57-shift"] {
        let case = coarse_matrix_pair(name);
        let scene = case.scene("stiffness").unwrap();
        assert!(scene.cover_pitch);
        let prepared = study::fe::prepare(&case, scene).unwrap();
        let mesh_period = case.pair.gears[0].angular_pitch() / scene.driver_speed;
        let start = statistics_start(&prepared, scene);
        let settled = scene.ramp_time + prepared.settling_time;
        assert_eq!(prepared.scene_duration, scene.duration, "{name}");
        if matches!(name, "paper36" | "40-24") {
            assert_eq!(prepared.duration, scene.duration, "{name}");
        } else {
            assert!(
                prepared.duration > 1.2 * scene.duration,
                "{name}: {}",
                prepared.duration
            );
        }
        assert!(
            start >= settled - 1e-12,
            "{name}: starts at {start} before {settled}"
        );
        assert!(
            prepared.duration - start >= mesh_period + prepared.mesh_mode_period,
            "{name}: a window of {} s against a mesh period of {mesh_period} s",
            prepared.duration - start
        );
        let mut short = scene.clone();
        (short.duration, short.cover_pitch) = (0.004, false);
        let prepared = study::fe::prepare(&case, &short).unwrap();
        assert_eq!(prepared.duration, 0.004, "{name}");
    }
}

/// The reduced far bodies converge on the full ones as their cutoff rises: on 40/24 and 24/40
/// at 12 000 rpm ([`reduced_far_bodies_on_unequal_gears_follow_their_full_bodies`]) the rms
/// difference of the DTE falls at every step of 5, 6, 7, 8 times the fine sectors' lowest mode.
/// Measured 2026-12-06: 1.90, 1.21, 0.80, 0.54 % of the peak-to-peak on 40/24 and 0.24, 0.13,
/// 0.08, 0.05 % on 24/40 (the peak-to-peak −1.40, −0.62, −0.63, −0.25 % and −0.05, +0.17,
/// +0.04, −0.08 %). Ignored in the suite (about 6 minutes):
/// `cargo test --release --test explicit_pair -- --ignored converge --nocapture`.
#[test]
#[ignore = "about 6 minutes"]
fn reduced_far_bodies_converge_as_their_cutoff_rises() {
    for name in ["40-24", "24-40"] {
        let case = coarse_matrix_pair(name);
        let outcome = |far_body: FarBody, cutoff: f64| {
            let mut case = case.clone();
            case.fe.far_block_cutoff = cutoff;
            twelve_pitch_outcome(&case, far_body)
        };
        let full = outcome(FarBody::Full, FAR_BLOCK_CUTOFF);
        let rms: Vec<f64> = [5.0, 6.0, 7.0, 8.0]
            .into_iter()
            .map(|cutoff| {
                let agreement = TwelvePitchAgreement::of(&outcome(FarBody::Reduced, cutoff), &full);
                let rms = agreement.rms_difference / agreement.peak_to_peak[1];
                eprintln!(
                    "{name}, cutoff {cutoff}: DTE peak-to-peak {:+.3} %, rms of the difference {:.3} %",
                    100.0 * (agreement.peak_to_peak[0] / agreement.peak_to_peak[1] - 1.0),
                    100.0 * rms
                );
                rms
            })
            .collect();
        assert!(rms.windows(2).all(|w| w[1] < w[0]), "{name}: {rms:?}");
    }
}

/// [`reduced_far_bodies_on_unequal_gears_follow_their_full_bodies`] on the rest of the test
/// matrix (shifts, a hunting tooth, extreme modules, a thin rim, 25°, high contact ratios),
/// the coarse elements scaled with the module; each pair's outcome printed, then every failure
/// named. Measured 2026-12-06 (DTE peak-to-peak, rms of the difference over it, pair loads):
/// 17-53-shift +0.20 / 0.17 / 0.09 %, 31-32 +0.20 / 0.34 / 0.05 %, 19-57-shift +0.15 / 0.08 /
/// 0.04 %, 19-57-backlash +0.01 / 0.04 / 0.01 %, module-1 +0.01 / 0.02 / 0.01 %, module-8
/// +0.81 / 0.57 / 0.51 %, thin-rim −0.04 / 0.17 / 0.10 %, alpha-25 +0.04 / 0.18 / 0.22 %,
/// hcr-2.1 +0.10 / 0.23 / 0.25 %, hcr-2.4 −0.13 / 0.50 / 1.28 %, hcr-2.65 +1.01 / 0.74 /
/// 1.28 %: all within the windows' 2 %. Ignored in the suite (about 16 minutes):
/// `cargo test --release --test explicit_pair -- --ignored across_the_test_matrix --nocapture`.
#[test]
#[ignore = "about 16 minutes"]
fn reduced_far_bodies_across_the_test_matrix() {
    let mut failures = Vec::new();
    for pair in geardyn::samples::PAIR_MATRIX {
        if ["paper36", "24-40", "40-24"].contains(&pair.name) {
            continue;
        }
        let module_mm = pair.case().unwrap().pair.gears[0].module() * 1e3;
        let scale = module_mm / 3.18;
        let mut overrides = pair.parsed_overrides();
        overrides.extend([
            Override::set("mesh.fine_element_mm", 1.5 * scale),
            Override::set("mesh.coarse_element_mm", 3.0 * scale),
            Override::set("fe.explicit_fine_element_mm", 1.5 * scale),
        ]);
        let case = Case::load_with(None, &overrides).unwrap();
        let outcome = std::panic::catch_unwind(|| {
            let (full, reduced) = (
                twelve_pitch_outcome(&case, FarBody::Full),
                twelve_pitch_outcome(&case, FarBody::Reduced),
            );
            let agreement = TwelvePitchAgreement::of(&reduced, &full);
            eprintln!(
                "{}: {} windows, blocks built {}, DTE peak-to-peak {:+.3} %, rms of the difference {:.3} %, pair loads {:.3} %",
                pair.name,
                reduced.windows,
                reduced.far_blocks_built,
                100.0 * (agreement.peak_to_peak[0] / agreement.peak_to_peak[1] - 1.0),
                100.0 * agreement.rms_difference / agreement.peak_to_peak[1],
                100.0 * agreement.worst_pair / agreement.largest_pair.max(f64::MIN_POSITIVE)
            );
            agreement.assert_within_the_windows_tolerances();
        });
        if outcome.is_err() {
            failures.push(pair.name);
        }
    }
    assert!(
        failures.is_empty(),
        "outside the windows' tolerances: {failures:?}"
    );
}
