//! The lumped model's load-dependent mesh force law from the LTCA: its quasi-static response
//! against independent LTCA runs from 25 to 300 % of the design torque (the paper pair and an
//! unequal one), the secant law's known failure away from its torque, and the integrated
//! model's slow response settling on its quasi-static TE.

use geardyn::case::{BodySway, Case, Override};
use geardyn::lumped::{steady_state, MeshModel};
use geardyn::samples;
use geardyn::study::lumped::{force_law_loads, setup, QUASI_STATIC_LOADS, QUASI_STATIC_TOLERANCE};

fn with(case: Case, overrides: &[Override]) -> Case {
    let path = std::env::temp_dir().join(format!(
        "geardyn-force-law-{}-{}.toml",
        std::process::id(),
        case.name()
    ));
    std::fs::write(&path, &case.text).unwrap();
    let out = Case::load_with(Some(&path), overrides).unwrap();
    std::fs::remove_file(&path).ok();
    out
}

/// The load-dependent law holds the LTCA's STE at every checked torque, on the law's positions
/// and half-way between them (the knots are a 1.25 ladder half a step off the design load, so
/// every checked load falls between two of them), on the paper pair and on 24/40, and on 24/40
/// with its rims swaying (their compliance taken out of the law and carried by the structure:
/// the statics must not move): rms within 1 % of the deflection (measured ≤ 0.21 %), no
/// position beyond 10 % (measured ≤ 2.4 %).
#[test]
fn the_load_dependent_law_holds_the_ltca_from_25_to_300_percent_torque() {
    let loads = force_law_loads();
    for load in QUASI_STATIC_LOADS {
        assert!(
            !loads.iter().any(|k| (k / load - 1.0).abs() < 0.05),
            "{load} is a knot"
        );
    }
    let unequal = |sway: &str| {
        let case = samples::matrix_pair("24-40").unwrap().case().unwrap();
        with(case, &[Override::set("lumped.body_sway", sway)])
    };
    for case in [samples::paper36_case(), unequal("auto"), unequal("on")] {
        let setup = setup(&case).unwrap();
        // The rims sway where asked (their compliance out of the law, the statics the same).
        let sways = setup
            .model
            .structure
            .names
            .iter()
            .any(|n| n.ends_with(" y"));
        assert_eq!(
            sways,
            case.lumped.body_sway == BodySway::On,
            "{}",
            case.name()
        );
        assert!(setup.model.force_law.is_some());
        assert_eq!(setup.self_checks.len(), 2 * QUASI_STATIC_LOADS.len());
        for check in &setup.self_checks {
            assert!(check.passed, "{}: {}", case.name(), check.line());
            assert!(check.value.is_finite(), "{}", check.line());
        }
        for rms in setup.self_checks.iter().step_by(2) {
            assert!(rms.value < QUASI_STATIC_TOLERANCE && !rms.warning_only);
        }
    }
}

/// The secant law is the LTCA's answer at its own torque only: the same check shows it rms 2 %
/// and more off at every other torque (5 % and 7 % at a quarter and three times the load on the
/// paper pair; a warning, as documented), so the check is one that can fail.
#[test]
fn the_secant_law_misses_the_ltca_away_from_its_torque() {
    let case = with(
        samples::paper36_case(),
        &[Override::set("lumped.force_law", "secant")],
    );
    let setup = setup(&case).unwrap();
    assert!(setup.model.force_law.is_none());
    let rms: Vec<&geardyn::study::checks::Check> = setup.self_checks.iter().step_by(2).collect();
    for (load, check) in QUASI_STATIC_LOADS.iter().zip(rms) {
        if *load == 1.0 {
            assert!(check.passed && !check.warning_only, "{}", check.line());
        } else {
            assert!(!check.passed && check.warning_only, "{}", check.line());
            assert!(check.value > 0.02, "{}", check.line());
        }
    }
}

/// Integrated slowly (f_mesh = 0.25 % of f_n, ζ = 0.05, 40 RK4 steps per natural period) at
/// twice the design torque, the model's steady DTE follows its quasi-static TE within 1 % of
/// the deflection. What is left is the ringing after the STE's steps where a pair enters or
/// leaves (a step of about a third of the deflection over 1/64 of the mesh period); it shrinks
/// with the speed (1.0 % at f_mesh = 1 % of f_n). A wiring error between the law and the
/// integrator (origin, sign, flank) would show at the scale of the deflection.
#[test]
fn a_slow_run_settles_on_the_quasi_static_te() {
    let setup = setup(&samples::paper36_case()).unwrap();
    let model = MeshModel {
        force: 2.0 * setup.model.force,
        ..setup.model.clone()
    };
    let omega_n = model.natural_frequency();
    let teeth = samples::paper36_pair().gears[0].teeth() as f64;
    let driver_speed = 0.0025 * omega_n / teeth;
    let steps = 16384;
    let start = model.quasi_static_state(0.0);
    let steady = steady_state(&model, driver_speed, steps, start, 1e-7, 400);
    assert!(steady.converged && !steady.diverged && !steady.separated);
    let period = model.mesh.period();
    let mut worst: f64 = 0.0;
    let mut mean = 0.0;
    for (j, p) in steady.displacement.iter().enumerate() {
        let theta = j as f64 * period / steps as f64;
        let quasi_static = model.quasi_static_transmission_error(theta);
        worst = worst.max((p - quasi_static).abs());
        mean += quasi_static / steps as f64;
    }
    assert!(worst < 0.01 * mean, "{worst:e} against mean {mean:e}");
    // And the law is not the secant: at twice the torque the mean mesh deflection is below
    // twice the design's.
    let mean_deflection = |m: &MeshModel| {
        (0..steps)
            .map(|j| m.quasi_static_deflection(j as f64 * period / steps as f64))
            .sum::<f64>()
            / steps as f64
    };
    let (twice, design) = (mean_deflection(&model), mean_deflection(&setup.model));
    assert!(twice < 1.97 * design, "{twice:e} vs {design:e}");
}

/// With a backlash the mirror of the drive flanks is off by the backlash's rotation
/// (tests/ltca.rs), so the back flanks carry their own law, from the LTCA of the back flanks
/// under the reversed torque. Wiring check, rigid bodies and elastic ones (whose law between
/// the rims lacks the bodies' twist c_b W): at positions of the law, the back LTCA's unloaded
/// gap is where the model's back force starts, and at r_b2 × its loaded STE (less c_b W) the
/// model's back force is −T/r_b2 at the design torque and at twice it (between two knots of the
/// law's 1.25 ladder: 0.2 % of the load, the Hermite interpolation's error there, measured
/// ≤ 0.1 %).
#[test]
fn the_back_flanks_carry_their_own_law_with_backlash() {
    for bodies in ["rigid", "elastic"] {
        let case = with(
            samples::paper36_case(),
            &[
                Override::set("gear1.thickness_reduction_um", 40.0),
                Override::set("gear2.thickness_reduction_um", 20.0),
                Override::set("lumped.bodies", bodies),
            ],
        );
        let setup = setup(&case).unwrap();
        let model = &setup.model;
        let law = model
            .back_force_law
            .as_ref()
            .expect("a back law with backlash");
        assert!(
            setup.model_note.contains("their own force law"),
            "{}",
            setup.model_note
        );
        // Elastic bodies carry the twist themselves: the law between the rims holds the
        // approach less c_b W (geardyn::study::lumped::law_to_rims).
        let twist = match bodies {
            "elastic" => geardyn::study::lumped::structure_body_compliance(&case).unwrap(),
            _ => 0.0,
        };
        let none = [geardyn::geometry::FlankModification::none(); 2];
        let sizes = geardyn::study::ltca::element_sizes(&case);
        let back =
            geardyn::study::ltca::model_on_flank(&case, &none, sizes, geardyn::ltca::Flank::Back)
                .unwrap();
        let rb2 = case.pair.gears[1].base_radius;
        let pitch = case.pair.gears[0].angular_pitch();
        let positions = law.knots.len();
        for j in [0, 37, 100, 201] {
            let theta = j as f64 * pitch / positions as f64;
            for load in [1.0, 2.0] {
                let torque = load * setup.torque;
                let r = back.solve_at(j, theta, torque).unwrap();
                let first = law.first_contact(theta);
                assert!(
                    (first - rb2 * r.unloaded_te).abs() < 1e-3 * rb2 * r.unloaded_te,
                    "{bodies} {j}: first contact {first:e} vs {:e}",
                    rb2 * r.unloaded_te
                );
                assert_eq!(model.mesh_force(theta, -0.999 * first), 0.0);
                let approach = rb2 * r.ste - twist * torque / rb2;
                let force = model.mesh_force(theta, -approach);
                assert!(
                    (force / (-torque / rb2) - 1.0).abs() < 2e-3,
                    "{bodies} {j} at {load}×: {force} vs {}",
                    -torque / rb2
                );
            }
        }
    }
}

/// The period map's Jacobian by the variational equation (the sweep's orbit Floquet and its
/// shooting) against central differences, on each pair's default model (the LTCA's force law;
/// both flanks at zero backlash, the back flanks' own LTCA law with backlash): the paper pair,
/// 24/40 and its inverse 40/24, the shifted 17/53 and 19/57 with backlash, each in contact at
/// f_mesh = 0.25 f_n and near the resonance at 0.945 f_n (on the paper pair about 2 000 and
/// 7 500 rpm), where every pair leaves its drive flanks for part of each period. They agree to
/// 1e-8 of the Jacobian's largest entry on the one-coordinate models (measured at most 6e-10)
/// and 5e-7 on more (1.5e-7 on 17/53, whose rims sway: three coordinates, the pinion's sway
/// near 117 kHz, the differences' velocity perturbation h·ω at that ω; 2.9e-8 before the mesh's
/// own mass coupled the sway into the mesh; the differences' truncation: a third of their
/// perturbation, 3e-6 of the deflection instead of 1e-5, gives 1.6e-8, as h² would); across a switch
/// they average the two sides' slopes over the perturbation, which the law's continuity keeps
/// small; a wrong term of the variational equation shows at order 1), and so do the largest
/// multipliers (1e-8). And the force's slope is the one the law's force has.
#[test]
fn the_variational_jacobian_is_the_period_maps() {
    use geardyn::lumped::{largest_modulus, period_map_differences, period_map_variational};
    use geardyn::sweep::steps_per_period;
    let mut separated = Vec::new();
    for name in ["paper36", "24-40", "40-24", "17-53-shift", "19-57-backlash"] {
        let case = match name {
            "paper36" => samples::paper36_case(),
            _ => samples::matrix_pair(name).unwrap().case().unwrap(),
        };
        let model = setup(&case).unwrap().model;
        let d0 = model.force / model.mesh.mean();
        for i in 0..64 {
            let theta = i as f64 * model.mesh.period() / 64.0;
            for f in [-0.5, 0.3, 1.0, 2.5] {
                let d = f * d0;
                let (w, slope) = model.mesh_force_and_slope(theta, d);
                assert_eq!(w, model.mesh_force(theta, d), "{name}");
                let dd = 1e-6 * d0;
                let fd = (model.mesh_force(theta, d + dd) - model.mesh_force(theta, d - dd))
                    / (2.0 * dd);
                assert!(
                    (fd - slope).abs() <= 1e-4 * slope.abs().max(1e6),
                    "{name}: θ {theta}, δ {d}: {fd} vs {slope}"
                );
            }
        }
        let f_n = model.natural_frequency() / std::f64::consts::TAU;
        for ratio in [0.25, 0.945] {
            let rpm = geardyn::study::lumped::speed_for_mesh_frequency(&case, ratio * f_n);
            let speed = rpm * std::f64::consts::TAU / 60.0;
            let steps = steps_per_period(&model, speed);
            let start = steady_state(&model, speed, steps, model.static_state(), 1e-9, 4000);
            assert!(start.converged, "{name} {rpm} rpm");
            let (end_v, jac_v) = period_map_variational(&model, speed, steps, start.start);
            let (end_d, jac_d) = period_map_differences(&model, speed, steps, start.start);
            assert_eq!(end_v, end_d, "{name} {rpm} rpm: the same integration");
            let error = (&jac_v - &jac_d).amax() / jac_d.amax();
            let tolerance = if model.structure.dofs == 1 {
                1e-8
            } else {
                5e-7
            };
            assert!(error < tolerance, "{name} {rpm} rpm: {error:e}");
            let largest = |j: &nalgebra::DMatrix<f64>| {
                largest_modulus(&j.complex_eigenvalues().iter().copied().collect::<Vec<_>>())
            };
            let (lv, ld) = (largest(&jac_v), largest(&jac_d));
            assert!((lv - ld).abs() < 1e-8, "{name} {rpm} rpm: {lv} vs {ld}");
            if start.separated {
                separated.push(name);
            }
        }
    }
    // The switches are exercised: every pair's near-resonance run leaves its drive flanks.
    assert_eq!(separated.len(), 5, "{separated:?}");
}
