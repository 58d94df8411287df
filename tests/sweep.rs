//! Speed sweeps of the lumped model: the linear model has no jumps; with backlash and strong
//! excitation the teeth separate near resonance and the up- and down-sweeps part (jump with
//! hysteresis, softening: the resonance bends to lower speed).

use geardyn::lumped::{DampingSite, MeshModel, Structure};
use geardyn::stiffness::{MeshStiffness, PeriodicTable};
use geardyn::sweep::{peaks, sweep};
use std::f64::consts::PI;

const PERIOD: f64 = 2.0 * PI / 36.0;

fn model(te_amplitude: f64, backlash: Option<f64>) -> MeshModel {
    let mut m = MeshModel {
        structure: Structure::rigid_pair(0.57),
        mesh: MeshStiffness::from_tables(
            "analytic",
            None,
            PeriodicTable::constant(PERIOD, 4e8),
            PeriodicTable::from_fn(PERIOD, 256, |t| {
                te_amplitude * (2.0 * PI * t / PERIOD).cos()
            }),
        ),
        damping: 0.0,
        damping_site: DampingSite::MeshDeflection,
        force: 2670.0,
        backlash,
        back_reflection: None,
        back_force_law: None,
        force_law: None,
    };
    m.damping = m.damping_from_ratio(0.03);
    m
}

fn rpm_of(model: &MeshModel, ratio: f64) -> f64 {
    // f_mesh = ratio · f_n  →  driver rpm = 60 f_mesh / z.
    ratio * model.natural_frequency() / (2.0 * PI) * 60.0 / 36.0
}

#[test]
fn linear_sweeps_agree_and_peak_at_the_natural_frequency() {
    let m = model(1e-6, None);
    let rpms: Vec<f64> = (0..201)
        .map(|i| rpm_of(&m, 0.8 + 0.002 * i as f64))
        .collect();
    let (up, down) = sweep(&m, &rpms).unwrap();
    for (u, d) in up.iter().zip(&down) {
        assert!(((u.dte_rms - d.dte_rms) / u.dte_rms).abs() < 1e-4);
        assert!(!u.separated);
    }
    let rms: Vec<f64> = up.iter().map(|p| p.dte_rms).collect();
    let found = peaks(&rpms, &rms);
    assert_eq!(found.len(), 1, "{found:?}");
    let expected = rpm_of(&m, (1.0 - 2.0 * 0.03f64 * 0.03).sqrt());
    assert!(
        ((found[0] - expected) / expected).abs() < 2e-3,
        "{} vs {expected}",
        found[0]
    );
}

#[test]
fn backlash_gives_a_jump_with_hysteresis() {
    // TE excitation of 2× the static deflection: the teeth leave contact near resonance.
    let static_deflection = 2670.0 / 4e8;
    let m = model(2.0 * static_deflection, Some(100e-6));
    let rpms: Vec<f64> = (0..121)
        .map(|i| rpm_of(&m, 0.6 + 0.005 * i as f64))
        .collect();
    let (up, down) = sweep(&m, &rpms).unwrap();
    assert!(up.iter().any(|p| p.separated), "no separation found");
    let parted = up
        .iter()
        .zip(&down)
        .map(|(u, d)| ((u.dte_rms - d.dte_rms) / u.dte_rms.max(d.dte_rms)).abs())
        .fold(0.0, f64::max);
    assert!(
        parted > 0.2,
        "up and down sweeps agree to {parted}: no hysteresis"
    );
    // The drive-side force never pulls: the dynamic factor is finite and ≥ 0 (it is 0 over a
    // mesh period spent entirely apart, which happens in the subharmonic responses that
    // separation brings; those points are flagged not converged to a one-period steady state).
    for p in up.iter().chain(&down) {
        assert!(
            p.dynamic_factor.is_finite() && p.dynamic_factor >= 0.0,
            "{p:?}"
        );
        assert!(
            p.converged || p.separated,
            "only separating responses may fail to settle: {p:?}"
        );
    }
}

/// The spectrum of a record of whole mesh periods: a sub-harmonic (half the mesh frequency) and
/// the third harmonic come out at their frequencies with their amplitudes, strongest first.
#[test]
fn spectrum_finds_sub_harmonics_and_harmonics() {
    use geardyn::signal::{amplitude_spectrum, strongest_lines};
    use geardyn::sweep::WINDOW_PERIODS;
    let per_period = 128;
    let n = per_period * WINDOW_PERIODS;
    let record: Vec<f64> = (0..n)
        .map(|i| {
            let orders = i as f64 / per_period as f64; // time in mesh periods
            3.0 + 2.0 * (PI * orders).cos() + 0.5 * (6.0 * PI * orders + 0.3).sin()
        })
        .collect();
    let lines = strongest_lines(&amplitude_spectrum(&record), 3);
    assert_eq!(lines.len(), 2, "{lines:?}");
    let order = |line: usize| line as f64 / WINDOW_PERIODS as f64;
    assert_eq!(order(lines[0].0), 0.5);
    assert!((lines[0].1 - 2.0).abs() < 1e-12);
    assert_eq!(order(lines[1].0), 3.0);
    assert!((lines[1].1 - 0.5).abs() < 1e-12);
}

/// A converged linear response: the strongest peak of every sweep point is the mesh frequency
/// (the TE excites only the first harmonic) with the FRF amplitude of the harmonic table.
#[test]
fn sweep_peaks_are_the_mesh_harmonics_of_a_periodic_response() {
    let m = model(1e-6, None);
    let rpms: Vec<f64> = (0..5).map(|i| rpm_of(&m, 0.5 + 0.2 * i as f64)).collect();
    let (up, _) = sweep(&m, &rpms).unwrap();
    for p in &up {
        assert!(p.converged);
        let (hz, amplitude) = p.peaks[0];
        assert!((hz / p.mesh_frequency_hz - 1.0).abs() < 1e-12, "{p:?}");
        assert!((amplitude / p.harmonics[0] - 1.0).abs() < 1e-12, "{p:?}");
    }
}

/// The overload warning reads the sweep's largest dynamic factor as one tooth pair's force at the
/// pitch point: p = p_static √DF. On the paper pair (0.622 GPa static) the 3 GPa limit sits at
/// DF = (3 / 0.622)² = 23.3: a point at 20 passes, one at 30 (3.41 GPa) is named with its speed.
#[test]
fn a_dynamic_force_beyond_the_contact_strength_is_warned_about() {
    use geardyn::study::sweep::overload_warning;
    use geardyn::sweep::SweepPoint;
    let case = geardyn::samples::paper36_case();
    let force = 143.6 / case.pair.gears[1].base_radius;
    let static_pressure = case.hertz_pressure_at(force);
    assert!(
        (static_pressure * 1e-9 - 0.622).abs() < 0.001,
        "{static_pressure}"
    );
    let point = |rpm: f64, dynamic_factor: f64| SweepPoint {
        driver_speed_rpm: rpm,
        mesh_frequency_hz: 0.0,
        dte_rms: 0.0,
        dte_peak_to_peak: 0.0,
        dynamic_factor,
        separated: false,
        harmonics: [0.0; geardyn::sweep::HARMONICS],
        peaks: Vec::new(),
        floquet_linear: 0.5,
        floquet_orbit: Some(0.5),
        periods: 1,
        converged: true,
    };
    let calm = [point(5000.0, 1.2), point(7000.0, 20.0)];
    assert_eq!(overload_warning(&case, force, &calm, &calm), None);
    let wild = [point(7000.0, 20.0), point(7500.0, 30.0)];
    let warning = overload_warning(&case, force, &calm, &wild).unwrap();
    let expected = static_pressure * 30f64.sqrt() * 1e-9;
    assert!((expected - 3.41).abs() < 0.01);
    for needed in [
        "at 7500 rpm",
        "30.0 ×",
        &format!("{expected:.1} GPa"),
        "linear contact law",
    ] {
        assert!(warning.contains(needed), "{needed:?} missing: {warning}");
    }
}

/// The sweep's shooting shortcut ([`settle`]) lands on the steady state plain integration
/// reaches ([`steady_state`]), on both branches of the hysteresis: the same continuation up and
/// down through the jump of `backlash_gives_a_jump_with_hysteresis` with each, the DTE rms equal
/// to 1e-5 at every speed where plain integration settled (both converge to 1e-7 of the static
/// deflection per period, which leaves up to 1e-7/(1 − |λ|) of it to go: |λ| ≤ 0.99 here), the
/// same speeds separated (the periodic responses, 69 of the 242; the rest, subharmonic, settle
/// with neither), and fewer than half the periods integrated where they settle.
#[test]
fn shooting_lands_where_integration_settles_on_both_branches() {
    use geardyn::lumped::{settle, steady_state, State};
    use geardyn::sweep::{steps_per_period, STEADY_TOLERANCE};
    // Fewer than the sweep's 4000: the subharmonic responses past the jump never settle.
    const MAX_PERIODS: usize = 1000;
    let static_deflection = 2670.0 / 4e8;
    let m = model(2.0 * static_deflection, Some(100e-6));
    let rpms: Vec<f64> = (0..121)
        .map(|i| rpm_of(&m, 0.6 + 0.005 * i as f64))
        .collect();
    let (mut plain_periods, mut settle_periods, mut compared) = (0, 0, 0);
    for order in [rpms.clone(), rpms.iter().rev().copied().collect()] {
        let (mut a, mut b): (State, State) = (m.static_state(), m.static_state());
        for &rpm in &order {
            let speed = rpm * 2.0 * PI / 60.0;
            let steps = steps_per_period(&m, speed);
            let plain = steady_state(&m, speed, steps, a, STEADY_TOLERANCE, MAX_PERIODS);
            let (fast, _) = settle(&m, speed, steps, b, STEADY_TOLERANCE, MAX_PERIODS);
            (a, b) = (plain.start, fast.start);
            assert_eq!(plain.converged, fast.converged, "{rpm} rpm");
            if !plain.converged {
                continue;
            }
            compared += 1;
            plain_periods += plain.periods;
            settle_periods += fast.periods;
            assert_eq!(plain.separated, fast.separated, "{rpm} rpm");
            let rms = |s: &[f64]| geardyn::signal::rms_about_mean(s);
            let (p, f) = (rms(&plain.displacement), rms(&fast.displacement));
            assert!((f / p - 1.0).abs() < 1e-5, "{rpm} rpm: rms {f} vs {p}");
        }
    }
    eprintln!("{compared} speeds compared, {settle_periods} periods against {plain_periods}");
    assert!(compared > 60, "{compared} speeds compared");
    assert!(
        settle_periods * 2 < plain_periods,
        "{settle_periods} periods against {plain_periods}"
    );
}
