//! The 1-DOF mesh model against analytic solutions: the forced response of a constant-stiffness
//! mesh (FRF), the Mathieu instability tongue from Floquet theory, and brute-force integration.

use geardyn::lumped::{
    floquet_max_multiplier, integrate_period, periodic_orbit, steady_state, DampingSite, MeshModel,
    State, Structure,
};
use geardyn::stiffness::{MeshStiffness, PeriodicTable};
use std::f64::consts::PI;

const PERIOD: f64 = 2.0 * PI / 36.0; // one base pitch of the paper's driver, in roll angle
const MASS: f64 = 0.5743; // the paper's effective mass [kg]
const K_MEAN: f64 = 4.0e8;

fn model(stiffness: PeriodicTable, te_amplitude: f64, zeta: f64) -> MeshModel {
    let mut m = MeshModel {
        structure: Structure::rigid_pair(MASS),
        mesh: MeshStiffness::from_tables(
            "analytic",
            None,
            stiffness,
            PeriodicTable::from_fn(PERIOD, 256, |t| {
                te_amplitude * (2.0 * PI * t / PERIOD).cos()
            }),
        ),
        damping: 0.0,
        damping_site: DampingSite::MeshDeflection,
        force: 2670.0,
        backlash: None,
        back_reflection: None,
        back_force_law: None,
        force_law: None,
    };
    m.damping = m.damping_from_ratio(zeta);
    m
}

/// k = k̄(1 + ε cos Ω_m t) over one mesh period (512 samples).
fn cosine_stiffness(eps: f64) -> PeriodicTable {
    PeriodicTable::from_fn(PERIOD, 512, |t| {
        K_MEAN * (1.0 + eps * (2.0 * PI * t / PERIOD).cos())
    })
}

/// The edge of an instability region between a stable and an unstable point, by bisection.
fn stability_edge(unstable: &dyn Fn(f64) -> bool, mut stable: f64, mut inside: f64) -> f64 {
    for _ in 0..50 {
        let mid = 0.5 * (stable + inside);
        if unstable(mid) {
            inside = mid;
        } else {
            stable = mid;
        }
    }
    0.5 * (stable + inside)
}

/// Driver speed [rad/s] whose mesh frequency is `omega_mesh` [rad/s].
fn driver_speed(omega_mesh: f64) -> f64 {
    omega_mesh * PERIOD / (2.0 * PI)
}

/// Constant stiffness excited by a transmission error e₀ cos(ω_m t):
/// |X| = k e₀ / √((k − m ω²)² + (c ω)²), peak at ω_n √(1 − 2ζ²).
#[test]
fn constant_stiffness_follows_the_analytic_frf() {
    let (e0, zeta) = (1e-6, 0.05);
    let m = model(PeriodicTable::constant(PERIOD, K_MEAN), e0, zeta);
    let wn = m.natural_frequency();
    let amplitude = |w: f64| {
        let s = steady_state(
            &m,
            driver_speed(w),
            256,
            (m.force / K_MEAN, 0.0),
            1e-10,
            5000,
        );
        assert!(s.converged);
        let (lo, hi) = s
            .displacement
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(*x), b.max(*x))
            });
        0.5 * (hi - lo)
    };
    for ratio in [0.5, 0.9, 1.0, 1.1, 2.0] {
        let w = ratio * wn;
        let exact =
            K_MEAN * e0 / ((K_MEAN - MASS * w * w).powi(2) + (m.damping * w).powi(2)).sqrt();
        let got = amplitude(w);
        assert!(
            ((got - exact) / exact).abs() < 1e-3,
            "ω/ωn = {ratio}: {got:e} vs {exact:e}"
        );
    }
    // Resonance: golden-section search for the peak amplitude.
    let (mut a, mut b) = (0.9 * wn, 1.05 * wn);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..40 {
        let (c, d) = (b - g * (b - a), a + g * (b - a));
        if amplitude(c) > amplitude(d) {
            b = d;
        } else {
            a = c;
        }
    }
    let peak = 0.5 * (a + b);
    let expected = wn * (1.0 - 2.0 * zeta * zeta).sqrt();
    assert!(
        ((peak - expected) / expected).abs() < 1e-3,
        "peak {peak} vs {expected}"
    );
}

/// Mathieu: ẍ + ω_n²(1 + ε cos ω_m t) x = 0. With τ = ω_m t/2 it is x″ + (a − 2q cos 2τ) x = 0,
/// a = 4ω_n²/ω_m², q = −aε/2; the first tongue is bounded by a = 1 ± q − q²/8 ∓ q³/64 − q⁴/1536
/// (McLachlan, *Theory and Application of Mathieu Functions*, §2.151). Solved for ω_m by fixed
/// point; the Floquet boundaries must agree within 0.5 % (they do to ~1e-5), and with the
/// small-ε formula 2ω_n(1 ± ε/4) to O(ε²).
#[test]
fn floquet_boundaries_match_mathieu() {
    let eps = 0.1;
    let m = model(cosine_stiffness(eps), 0.0, 0.0);
    let wn = m.natural_frequency();
    let unstable = |w: f64| floquet_max_multiplier(&m, driver_speed(w), 512) > 1.0 + 1e-7;
    assert!(unstable(2.0 * wn), "the centre of the tongue is unstable");
    assert!(!unstable(1.8 * wn) && !unstable(2.2 * wn));
    let edge = |stable: f64, inside: f64| stability_edge(&unstable, stable, inside);
    let lower = edge(1.8 * wn, 2.0 * wn);
    let upper = edge(2.2 * wn, 2.0 * wn);
    let mathieu = |sign: f64| {
        let mut a: f64 = 1.0;
        for _ in 0..100 {
            let q = a * eps / 2.0;
            a = 1.0 + sign * q - q * q / 8.0 - sign * q.powi(3) / 64.0 - q.powi(4) / 1536.0;
        }
        2.0 * wn / a.sqrt()
    };
    // a = 1 + q is the lower-frequency edge (a larger ↔ ω_m smaller).
    let (exact_lower, exact_upper) = (mathieu(1.0), mathieu(-1.0));
    eprintln!(
        "Mathieu ε = {eps}: Floquet edges {:.6} / {:.6} × 2ω_n, McLachlan {:.6} / {:.6}, small-ε {:.6} / {:.6}",
        lower / (2.0 * wn),
        upper / (2.0 * wn),
        exact_lower / (2.0 * wn),
        exact_upper / (2.0 * wn),
        1.0 - eps / 4.0,
        1.0 + eps / 4.0
    );
    assert!(
        ((lower - exact_lower) / exact_lower).abs() < 5e-3,
        "lower {lower} vs {exact_lower}"
    );
    assert!(
        ((upper - exact_upper) / exact_upper).abs() < 5e-3,
        "upper {upper} vs {exact_upper}"
    );
    assert!(
        ((lower - exact_lower) / exact_lower).abs() < 1e-4
            && ((upper - exact_upper) / exact_upper).abs() < 1e-4
    );
    // Small-ε formula, good to O(ε²) = 1 %.
    assert!((lower / (2.0 * wn) - (1.0 - eps / 4.0)).abs() < eps * eps);
    assert!((upper / (2.0 * wn) - (1.0 + eps / 4.0)).abs() < eps * eps);
}

/// With damping the tongue opens only if ε > 4ζ (small-ε theory).
#[test]
fn damping_closes_the_tongue_below_four_zeta() {
    let zeta = 0.02;
    for (eps, opens) in [(0.05, false), (0.2, true)] {
        let m = model(cosine_stiffness(eps), 0.0, zeta);
        let wn = m.natural_frequency();
        let worst = (0..41)
            .map(|i| 1.9 + 0.005 * i as f64)
            .map(|r| floquet_max_multiplier(&m, driver_speed(r * wn), 512))
            .fold(0.0, f64::max);
        assert_eq!(
            worst > 1.0,
            opens,
            "ε = {eps}, ζ = {zeta}: max |λ| = {worst}"
        );
    }
}

/// Brute force: integrating the free linear model for N periods multiplies a disturbance by
/// about max|λ|^N inside the tongue.
#[test]
fn brute_force_growth_matches_the_floquet_multiplier() {
    let eps = 0.2;
    let m = model(cosine_stiffness(eps), 0.0, 0.0);
    let free = MeshModel {
        force: 0.0,
        ..m.clone()
    };
    let w = 2.0 * m.natural_frequency();
    let lambda = floquet_max_multiplier(&m, driver_speed(w), 512);
    let periods = 40;
    let s = steady_state(&free, driver_speed(w), 512, (1e-9, 0.0), 0.0, periods);
    let (x, v) = (s.displacement[0], s.velocity[0]);
    let growth = (x * x + (v / w).powi(2)).sqrt() / 1e-9;
    let per_period = growth.powf(1.0 / (periods - 1) as f64);
    assert!(
        ((per_period - lambda) / lambda).abs() < 0.02,
        "growth {per_period} vs λ {lambda}"
    );
}

/// Where the integrator fails: RK4 on the undamped oscillator multiplies the amplitude per step
/// by |R(iωh)|, R(z) = 1 + z + z²/2 + z³/6 + z⁴/24, stable for ωh ≤ 2√2 = 2.828. Observed growth
/// over many steps matches the prediction on both sides of the limit (the sweep keeps ωh ≤ 0.2).
#[test]
fn rk4_step_limit_is_where_theory_puts_it() {
    let m = model(PeriodicTable::constant(PERIOD, K_MEAN), 0.0, 0.0);
    let free = MeshModel {
        force: 0.0,
        ..m.clone()
    };
    let wn = m.natural_frequency();
    for (omega_h, grows) in [(2.70, false), (2.95, true)] {
        // Choose the driver speed so that one mesh period holds 64 steps of ωh each.
        let steps = 64;
        let period_time = steps as f64 * omega_h / wn;
        let speed = PERIOD / period_time;
        let periods = 3;
        // The integrator alone (`steady_state` would stop the unstable case at its divergence
        // bound): the state after periods − 1 whole periods.
        let mut state = State::from((1e-9, 0.0));
        for _ in 0..periods - 1 {
            state = integrate_period(&free, speed, steps, state, |_, _, _| {});
        }
        let (x, v) = (state.q[0], state.v[0]);
        let amplitude = (x * x + (v / wn).powi(2)).sqrt() / 1e-9;
        let z2 = omega_h * omega_h;
        let (re, im) = (
            1.0 - z2 / 2.0 + z2 * z2 / 24.0,
            omega_h - omega_h * z2 / 6.0,
        );
        let predicted = (re * re + im * im)
            .sqrt()
            .powi((steps * (periods - 1)) as i32);
        assert_eq!(
            amplitude > 1.0,
            grows,
            "ωh = {omega_h}: amplitude ×{amplitude:e}"
        );
        assert!(
            (amplitude.ln() - predicted.ln()).abs() < 0.05 * predicted.ln().abs().max(1.0),
            "ωh = {omega_h}: ×{amplitude:e} vs predicted ×{predicted:e}"
        );
    }
}

/// Damped Mathieu boundaries from Hill's determinant: for x″ + 2ζx′ + (1 + ε cos Ωt)x = 0 the
/// first tongue's edges carry period-2T solutions x = Σ aₖ cos νₖt + bₖ sin νₖt, νₖ = (2k+1)Ω/2;
/// balancing harmonics gives, for k ≥ 0 (with a₋₁ → a₀, b₋₁ → −b₀ from cos Ωt·cos(Ω/2)t):
/// (1 − νₖ²) aₖ + 2ζνₖ bₖ + ε/2 (aₖ₋₁ + aₖ₊₁) = 0,  (1 − νₖ²) bₖ − 2ζνₖ aₖ + ε/2 (bₖ₋₁ + bₖ₊₁) = 0.
/// The edges are the zeros of the truncated determinant (8 harmonics); the Floquet edges of our
/// integrator with the same damping must agree within 0.5 % (they do to ~1e-5).
#[test]
fn damped_floquet_boundaries_match_hills_determinant() {
    use nalgebra::DMatrix;
    let (eps, zeta) = (0.1, 0.005);
    let hill = |omega: f64| {
        let n = 8;
        let mut m = DMatrix::<f64>::zeros(2 * n, 2 * n);
        for k in 0..n {
            let nu = (2 * k + 1) as f64 * omega / 2.0;
            let (a, b) = (2 * k, 2 * k + 1);
            m[(a, a)] = 1.0 - nu * nu;
            m[(a, b)] = 2.0 * zeta * nu;
            m[(b, b)] = 1.0 - nu * nu;
            m[(b, a)] = -2.0 * zeta * nu;
            if k + 1 < n {
                m[(a, a + 2)] += eps / 2.0;
                m[(b, b + 2)] += eps / 2.0;
            }
            if k > 0 {
                m[(a, a - 2)] += eps / 2.0;
                m[(b, b - 2)] += eps / 2.0;
            } else {
                m[(a, a)] += eps / 2.0;
                m[(b, b)] -= eps / 2.0;
            }
        }
        m.determinant()
    };
    // A sign change of the determinant, by the same bisection.
    let root = |lo: f64, hi: f64| {
        let sign_lo = hill(lo) > 0.0;
        stability_edge(&|x| (hill(x) > 0.0) != sign_lo, lo, hi)
    };
    let (hill_lower, hill_upper) = (root(1.9, 2.0), root(2.0, 2.1));

    // Our model in the same nondimensional form: ω_n = √(k̄/m), c = 2ζ√(k̄ m).
    let m = model(cosine_stiffness(eps), 0.0, zeta);
    let wn = m.natural_frequency();
    let unstable = |ratio: f64| floquet_max_multiplier(&m, driver_speed(ratio * wn), 512) > 1.0;
    let edge = |stable: f64, inside: f64| stability_edge(&unstable, stable, inside);
    let (lower, upper) = (edge(1.9, 2.0), edge(2.1, 2.0));
    eprintln!("damped Mathieu ε = {eps}, ζ = {zeta}: Floquet {lower:.6} / {upper:.6}, Hill {hill_lower:.6} / {hill_upper:.6} (× ω_n)");
    assert!(
        ((lower - hill_lower) / hill_lower).abs() < 5e-3
            && ((upper - hill_upper) / hill_upper).abs() < 5e-3
    );
    assert!(
        ((lower - hill_lower) / hill_lower).abs() < 1e-4
            && ((upper - hill_upper) / hill_upper).abs() < 1e-4
    );
    // Damping narrows the tongue compared with the undamped edges 2(1 ∓ ε/4).
    assert!(lower > 2.0 * (1.0 - eps / 4.0) - 1e-3 && upper < 2.0 * (1.0 + eps / 4.0) + 1e-3);
}

/// A slow run-up through resonance follows the steady-state response: the largest excursion is
/// within a few percent of the steady-state resonance amplitude, reached near the resonance
/// speed (a fast sweep passes the peak late and lower: the classical passage effect).
#[test]
fn slow_run_up_follows_the_steady_state_peak() {
    use geardyn::lumped::run_up;
    let (e0, zeta) = (1e-6, 0.05);
    let m = model(PeriodicTable::constant(PERIOD, K_MEAN), e0, zeta);
    let wn = m.natural_frequency();
    let peak_amplitude = K_MEAN * e0 / (m.damping * wn * (1.0 - zeta * zeta).sqrt());
    let static_x = m.force / K_MEAN;
    let excursion = |duration: f64| {
        let r = run_up(
            &m,
            driver_speed(0.7 * wn),
            driver_speed(1.3 * wn),
            duration,
            usize::MAX,
        );
        let (i, max) = r
            .displacement
            .iter()
            .enumerate()
            .map(|(i, x)| (i, (x - static_x).abs()))
            .fold(
                (0, 0.0),
                |best, (i, a)| if a > best.1 { (i, a) } else { best },
            );
        (max, r.driver_speed[i] / driver_speed(wn))
    };
    let (slow, at) = excursion(0.5);
    assert!(
        ((slow - peak_amplitude) / peak_amplitude).abs() < 0.05,
        "{slow:e} vs {peak_amplitude:e}"
    );
    assert!((at - 1.0).abs() < 0.03, "peak at {at} ω_n");
    let (fast, at_fast) = excursion(0.005);
    assert!(
        fast < slow && at_fast > at,
        "fast passage: {fast:e} at {at_fast} vs slow {slow:e} at {at}"
    );
}

/// The fixed-step RK4 against the adaptive Dormand–Prince reference on a response with tooth
/// separation (backlash 100 µm, TE twice the static deflection, below resonance where the
/// response is periodic): both start from the same state and integrate the same 40 mesh
/// periods; the end states agree to 1e-3 of the static deflection, although the backlash kinks
/// fall inside RK4 steps (RK4 drops to low order at a kink; 32 steps per natural period keep the
/// error small).
#[test]
fn rk4_across_separation_matches_the_adaptive_reference() {
    use geardyn::lumped::reference_periods;
    let static_deflection = 2670.0 / K_MEAN;
    let mut m = model(
        PeriodicTable::constant(PERIOD, K_MEAN),
        2.0 * static_deflection,
        0.05,
    );
    m.backlash = Some(100e-6);
    let w = 0.7 * m.natural_frequency();
    let speed = driver_speed(w);
    let start = (static_deflection, 0.0);
    let steps = geardyn::sweep::steps_per_period(&m, speed);
    let rk4 = steady_state(&m, speed, steps, start, 0.0, 41);
    let (x, v) = (rk4.displacement[0], rk4.velocity[0]);
    assert!(rk4.separated, "the teeth separate in this case");
    let (reference, accepted) = reference_periods(&m, speed, start, 40, 1e-10);
    let (xr, vr) = (reference.q[0], reference.v[0]);
    let dx = (x - xr).abs() / static_deflection;
    let dv = (v - vr).abs() / (static_deflection * m.natural_frequency());
    eprintln!("RK4 ({steps} steps/period) vs DOPRI5 ({accepted} steps): dx {dx:e}, dv {dv:e} of the static scale");
    assert!(dx < 1e-3 && dv < 1e-3, "dx {dx:e}, dv {dv:e}");
}

/// The failure table: each scheme's stability limit and 1 % frequency-accuracy limit observed
/// from its own one-step map agree with the textbook formulas to 1e-6; the observed orders on a
/// smooth damped response are the formal ones (±0.3; central difference is first order with its
/// lagging damping velocity); with tooth separation no scheme loses convergence (order ≥ 0.8),
/// and at 32 steps per natural period RK4's error stays below 1e-4 of the static deflection on
/// the smooth response and below 1e-2 across separation.
#[test]
fn integrator_failure_table_matches_theory() {
    use geardyn::lumped::schemes::{failure_table, SCHEMES};
    let static_deflection = 2670.0 / K_MEAN;
    let mut smooth = model(
        PeriodicTable::constant(PERIOD, K_MEAN),
        0.2 * static_deflection,
        0.05,
    );
    // A finely sampled TE: the table's linear interpolation has slope kinks that would cost
    // RK4 its order just as separation does (they shrink as 1/N²).
    smooth.mesh.unloaded_te = PeriodicTable::from_fn(PERIOD, 1 << 14, |t| {
        0.2 * static_deflection * (2.0 * PI * t / PERIOD).cos()
    });
    let mut separating = model(
        PeriodicTable::constant(PERIOD, K_MEAN),
        2.0 * static_deflection,
        0.05,
    );
    separating.backlash = Some(100e-6);
    let speed = driver_speed(0.7 * smooth.natural_frequency());
    let table = failure_table(&smooth, &separating, speed, 20);
    assert_eq!(table.len(), SCHEMES.len());
    for row in &table {
        eprintln!("{row:?}");
        match (row.predicted_limit, row.observed_limit) {
            (Some(p), Some(o)) => assert!((o / p - 1.0).abs() < 1e-6, "{row:?}"),
            (None, None) => {}
            _ => panic!("stability limit predicted/observed disagree: {row:?}"),
        }
        assert!(
            (row.observed_accuracy_limit / row.predicted_accuracy_limit - 1.0).abs() < 1e-6,
            "{row:?}"
        );
        assert!(
            (row.observed_order_smooth - row.formal_order).abs() < 0.3,
            "{row:?}"
        );
        assert!(row.observed_order_separating > 0.8, "{row:?}");
    }
    let rk4 = table.iter().find(|r| r.scheme == "RK4").unwrap();
    assert!(
        rk4.error_smooth < 1e-4 && rk4.error_separating < 1e-2,
        "{rk4:?}"
    );
}

/// Bearing translations (3 DOFs): the natural frequencies solve det(K − ω²M) = 0; with rigid
/// bearings (k_b → ∞) the mesh mode tends to √(k/m_e) and the Floquet multiplier and the steady
/// response tend to those of the 1-DOF model.
#[test]
fn bearing_model_reduces_to_the_one_dof_model_on_stiff_bearings() {
    use geardyn::lumped::Bearings;
    let eps = 0.2;
    let stiffness = cosine_stiffness(eps);
    let one = model(stiffness, 1e-6, 0.05);
    let bearings = |kb: f64| Bearings {
        mass: [1.8, 2.4],
        stiffness: [kb, 0.7 * kb],
        damping: [0.0, 0.0],
    };
    let with = |kb: f64| MeshModel {
        structure: Structure::rigid_pair_on_bearings(MASS, &bearings(kb)),
        ..one.clone()
    };
    // det(K − ω²M) = 0 at every computed frequency (relative to the product of the diagonals).
    let soft = with(3e8);
    let b = bearings(3e8);
    for w in soft.mode_frequencies(K_MEAN) {
        let w2 = w * w;
        let k = K_MEAN;
        let a = [
            [k - w2 * MASS, k, -k],
            [k, k + b.stiffness[0] - w2 * b.mass[0], -k],
            [-k, -k, k + b.stiffness[1] - w2 * b.mass[1]],
        ];
        let det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
            - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
        let scale = a[0][0].abs().max(k) * a[1][1].abs().max(k) * a[2][2].abs().max(k);
        assert!(det.abs() < 1e-9 * scale, "ω = {w}: det {det:e}");
    }
    // Stiff bearings: the 1-DOF limit.
    let stiff = with(1e14);
    let modes = stiff.mode_frequencies(K_MEAN);
    assert!(
        (modes[0] / one.natural_frequency() - 1.0).abs() < 1e-4,
        "{modes:?}"
    );
    let w = 0.6 * one.natural_frequency();
    let (s1, s3) = (
        steady_state(&one, driver_speed(w), 512, one.static_state(), 1e-9, 4000),
        steady_state(
            &stiff,
            driver_speed(w),
            4096,
            stiff.static_state(),
            1e-9,
            4000,
        ),
    );
    assert!(s1.converged && s3.converged);
    let rms = |x: &[f64]| {
        let mean = x.iter().sum::<f64>() / x.len() as f64;
        (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / x.len() as f64).sqrt()
    };
    let (r1, r3) = (rms(&s1.displacement), rms(&s3.displacement));
    assert!((r3 / r1 - 1.0).abs() < 1e-3, "rms {r1:e} vs {r3:e}");
    // Undamped, inside the principal tongue (ε = 0.2 > 4ζ would be needed with damping).
    let wp = 2.0 * one.natural_frequency();
    let undamped = |m: &MeshModel| MeshModel {
        damping: 0.0,
        ..m.clone()
    };
    let (l1, l3) = (
        floquet_max_multiplier(&undamped(&one), driver_speed(wp), 512),
        floquet_max_multiplier(&undamped(&stiff), driver_speed(wp), 4096),
    );
    assert!(l1 > 1.0 && (l3 / l1 - 1.0).abs() < 1e-3, "{l1} vs {l3}");
}

/// Separation is detected exactly when the mesh force would turn negative: at a TE amplitude
/// 1 % below the one where the linear model's minimum mesh force reaches zero, the model with
/// backlash, started on the linear steady state, never separates and stays on it; 1 % above, it
/// separates.
#[test]
fn separation_starts_where_the_linear_force_reaches_zero() {
    let unit = model(PeriodicTable::constant(PERIOD, K_MEAN), 1e-6, 0.05);
    let speed = driver_speed(0.8 * unit.natural_frequency());
    let min_force_from = |m: &MeshModel, start: State| {
        let s = steady_state(m, speed, 512, start, 1e-10, 5000);
        assert!(s.converged);
        (
            s.mesh_force.iter().copied().fold(f64::INFINITY, f64::min),
            s,
        )
    };
    let min_force = |m: &MeshModel| min_force_from(m, m.static_state());
    // The linear dynamic force is F − G·e at its minimum, so the threshold is e* = F / G.
    let (f_unit, _) = min_force(&unit);
    let threshold = 1e-6 * unit.force / (unit.force - f_unit);
    for (factor, separates) in [(0.99, false), (1.01, true)] {
        let linear = model(
            PeriodicTable::constant(PERIOD, K_MEAN),
            factor * threshold,
            0.05,
        );
        let with_backlash = MeshModel {
            backlash: Some(1e-3),
            ..linear.clone()
        };
        let (f_lin, lin) = min_force(&linear);
        // Started on the linear steady state: near resonance a separating branch may coexist
        // (hysteresis), and a start far from it could land there.
        let (_, s) = min_force_from(&with_backlash, lin.start);
        assert_eq!(
            s.separated, separates,
            "factor {factor}: min linear force {f_lin}"
        );
        assert_eq!(f_lin < 0.0, separates);
        if !separates {
            let diff = lin
                .displacement
                .iter()
                .zip(&s.displacement)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(diff < 1e-9 * threshold, "{diff:e}");
        }
    }
}

/// The Floquet frequency: ω_n for a constant stiffness on every branch of ω mod Ω_m, and for
/// k̄(1 + ε cos Ω_m t) the Mathieu characteristic exponent ν of y'' + (a − 2q cos 2z)y = 0,
/// a = ν² + q²/(2(ν²−1)) + (5ν²+7)q⁴/(32(ν²−1)³(ν²−4)) (Abramowitz & Stegun 20.3.15), with
/// z = Ω_m t/2, a = 4ω_n²/Ω_m², q = −2εω_n²/Ω_m², ω_F = νΩ_m/2.
#[test]
fn floquet_frequency_matches_mathieu_characteristic_exponent() {
    use geardyn::lumped::floquet_frequency;
    let wn = (K_MEAN / MASS).sqrt();
    let constant = model(cosine_stiffness(0.0), 0.0, 0.0);
    for ratio in [0.3, 0.7, 1.3, 3.1] {
        let w = floquet_frequency(&constant, driver_speed(ratio * wn), 512);
        assert!(
            (w / wn - 1.0).abs() < 1e-7,
            "Ω_m = {ratio} ω_n: {w} vs {wn}"
        );
    }
    let eps = 0.2;
    let ripple = model(cosine_stiffness(eps), 0.0, 0.0);
    let omega_m = 0.7 * wn;
    let a = 4.0 * wn * wn / (omega_m * omega_m);
    let q = -2.0 * eps * wn * wn / (omega_m * omega_m);
    let mut nu: f64 = a.sqrt();
    for _ in 0..50 {
        let n2 = nu * nu;
        let correction = q * q / (2.0 * (n2 - 1.0))
            + (5.0 * n2 + 7.0) * q.powi(4) / (32.0 * (n2 - 1.0).powi(3) * (n2 - 4.0));
        nu = (a - correction).sqrt();
    }
    let expected = nu * omega_m / 2.0;
    let w = floquet_frequency(&ripple, driver_speed(omega_m), 512);
    // The ripple moves ω_F by 0.3 %; the series' next term is below 3e-5.
    assert!((expected / wn - 1.0).abs() > 2e-3);
    assert!(
        (w / expected - 1.0).abs() < 2e-4,
        "{w} vs {expected} (ω_n {wn})"
    );
}

/// Back flanks with their own k and e: the back-side force at (θ, δ) is minus the drive-side
/// force of the mirrored pair at (ρ − θ, −δ − j) — the drive flanks' k and e read at the
/// mirrored angle, the relief widening the gap — and nothing is carried in between.
#[test]
fn back_flanks_carry_the_mirrored_stiffness_and_relief() {
    let mut m = model(cosine_stiffness(0.3), 0.0, 0.0);
    // An asymmetric relief-like TE (≥ 0) and stiffness, so a wrong phase shows.
    m.mesh.unloaded_te = PeriodicTable::from_fn(PERIOD, 256, |t| {
        4e-6 * (1.0 + (2.0 * PI * t / PERIOD + 0.7).sin())
    });
    m.mesh.stiffness = PeriodicTable::from_fn(PERIOD, 256, |t| {
        K_MEAN * (1.0 + 0.3 * (2.0 * PI * t / PERIOD).cos() + 0.1 * (4.0 * PI * t / PERIOD).sin())
    });
    let (rho, j) = (0.37 * PERIOD, 5e-6);
    m.backlash = Some(j);
    m.back_reflection = Some(rho);
    for i in 0..40 {
        let theta = i as f64 / 40.0 * PERIOD;
        let e_back = m.mesh.unloaded_te.at(rho - theta);
        let k_back = m.mesh.stiffness.at(rho - theta);
        for delta in [-3e-5, -j - e_back - 2e-6, -j - e_back - 1e-7] {
            let back = m.mesh_force(theta, delta);
            let mirrored = m.mesh_force(rho - theta, -delta - j);
            assert!(back < 0.0 && (back + mirrored).abs() < 1e-9 * back.abs());
            assert!((back - k_back * (delta + j + e_back)).abs() < 1e-9 * back.abs());
        }
        // Between the drive flank's first touch (e) and the back flank's (−j − e_back): free.
        let e = m.mesh.unloaded_te.at(theta);
        for delta in [e - 1e-8, 0.0, -j - e_back + 1e-8] {
            if delta <= e {
                assert_eq!(m.mesh_force(theta, delta), 0.0, "θ {theta}, δ {delta}");
            }
        }
    }
}

/// Inside the principal instability tongue without damping the response grows by the Floquet
/// multiplier every period, so it passes any bound: the steady-state search reports it as
/// diverged (instead of returning a record of 1e23 µm), within the periods the growth rate
/// predicts; with damping above the tongue's 4ζ > ε closure the same speed is bounded. The
/// run-up through the tongue stops where it leaves the model's range.
#[test]
fn unbounded_growth_is_reported_as_divergence() {
    let eps = 0.2;
    let undamped = model(cosine_stiffness(eps), 0.0, 0.0);
    let w = 2.0 * undamped.natural_frequency();
    let speed = driver_speed(w);
    let lambda = floquet_max_multiplier(&undamped, speed, 512);
    assert!(lambda > 1.05, "{lambda}");
    let s = steady_state(&undamped, speed, 512, undamped.static_state(), 1e-9, 4000);
    assert!(s.diverged && !s.converged);
    // From the static state the free part starts at the static deflection δ's order and must
    // grow by the bound's factor, 1000 (δ + TE)/δ = 1000: ln 1000 / ln λ periods, within a
    // factor of two for the transient before the growing mode dominates.
    let expected = 1000f64.ln() / lambda.ln();
    assert!(
        (s.periods as f64) < 2.0 * expected && (s.periods as f64) > 0.5 * expected,
        "diverged after {} periods; λ = {lambda} predicts about {expected:.0}",
        s.periods
    );
    let damped = model(cosine_stiffness(eps), 0.0, 0.1);
    let s = steady_state(&damped, speed, 512, damped.static_state(), 1e-9, 4000);
    assert!(!s.diverged && s.converged);
    let through = geardyn::lumped::run_up(&undamped, 0.8 * speed, 1.2 * speed, 2.0, 1000);
    let t = through
        .diverged_at
        .expect("the undamped run-up diverges in the tongue");
    assert!(t > 0.0 && t < 2.0);
    assert!(through.displacement.iter().all(|x| x.is_finite()));
}

/// On a linear model (no separation) the one-period map is affine, so the orbit's Jacobian is
/// the monodromy matrix: shooting finds the periodic orbit in one Newton step, stable or not,
/// and its multipliers equal the linear Floquet analysis's — inside the Mathieu tongue
/// (|λ| > 1, an orbit forward integration never settles on) and outside it.
#[test]
fn the_orbit_multipliers_of_a_linear_model_are_its_monodromy() {
    let eps = 0.3;
    let m = model(cosine_stiffness(eps), 1e-6, 0.02);
    let wn = m.natural_frequency();
    for ratio in [1.0, 1.5, 2.0, 2.03, 3.0] {
        let speed = driver_speed(ratio * wn);
        let steps = 512;
        let linear = floquet_max_multiplier(&m, speed, steps);
        let orbit = periodic_orbit(&m, speed, steps, State::from((m.force / K_MEAN, 0.0)), 1e-9)
            .unwrap_or_else(|| panic!("no orbit at ω_m/ω_n = {ratio}"));
        assert!(
            orbit.iterations <= 2,
            "{ratio}: {} iterations",
            orbit.iterations
        );
        let got = orbit.max_multiplier();
        assert!(
            (got / linear - 1.0).abs() < 1e-5,
            "{ratio}: {got} vs {linear}"
        );
        // The orbit returns to itself.
        let end = integrate_period(&m, speed, steps, orbit.start, |_, _, _| {});
        assert!((end.q[0] - orbit.start.q[0]).abs() < 1e-9 * m.force / K_MEAN);
    }
    // The tongue's centre is unstable, far from it stable.
    let centre = floquet_max_multiplier(&m, driver_speed(2.0 * wn), 512);
    assert!(centre > 1.0 && floquet_max_multiplier(&m, driver_speed(1.5 * wn), 512) < 1.0);
}

/// The issue's case: the paper pair (the embedded case) with the secant law and elastic
/// bodies, ζ = 0.05, zero backlash.
fn issue_secant_model() -> MeshModel {
    let case = geardyn::case::Case::load_with(
        None,
        &[
            geardyn::case::Override::set("lumped.force_law", "secant"),
            geardyn::case::Override::set("lumped.bodies", "elastic"),
        ],
    )
    .unwrap();
    geardyn::study::lumped::setup(&case).unwrap().model
}

/// Where the teeth separate and hit the back flanks the linearized drive flanks say nothing of
/// stability; the integrated model's orbit does. With the secant law, rims and ζ = 0.05 the
/// paper pair at zero backlash diverges near 7 260 rpm (issue 29; 7 330 rpm with a massless
/// mesh, before `lumped.mesh_mass`: the same dynamics 0.88 % slower) while the drive flanks
/// linearized read at most 0.71: the steady states' orbit multipliers climb towards 1 on the
/// way there (above 0.95 at 7 230 rpm), and at 7 260 rpm shooting finds no period-one orbit at
/// all — the periodic response ends there (a fold), and the divergence message says so. Far
/// below (5 000 rpm) the orbit's multiplier is the linearization's.
#[test]
fn the_orbit_of_the_switched_model_shows_where_the_sweep_diverges() {
    let m = issue_secant_model();
    let rpms = [5000.0, 7130.0, 7170.0, 7210.0, 7230.0, 7260.0];
    let done = geardyn::sweep::continue_sweep(
        &m,
        &rpms,
        geardyn::sweep::SweepProgress::start(&m),
        &|| false,
    );
    let up = &done.up;
    assert_eq!(up.len(), 5, "the up-sweep settles up to 7230 rpm");
    for p in up {
        assert!(p.floquet_linear < 0.72, "{p:?}");
    }
    let orbit: Vec<f64> = up.iter().map(|p| p.floquet_orbit.unwrap()).collect();
    assert!(
        (orbit[0] / up[0].floquet_linear - 1.0).abs() < 0.02,
        "{orbit:?}"
    );
    assert!(orbit.windows(2).skip(1).all(|w| w[1] > w[0]), "{orbit:?}");
    assert!(orbit[4] > 0.95 && orbit[4] < 1.0, "{orbit:?}");
    let divergence = done.diverged.expect("diverges at 7260 rpm");
    assert_eq!(divergence.driver_speed_rpm, 7260.0);
    assert!(divergence.floquet_max_multiplier < 1.0);
    let message = divergence.to_string();
    // The up-sweep's divergence is the one reported when both directions diverge.
    assert_eq!(divergence.direction, "up");
    assert_eq!(divergence.orbit_floquet_max_multiplier, None, "{message}");
    assert_eq!(divergence.last_orbit_floquet_max_multiplier, Some(orbit[4]));
    assert!(message.contains("ends between the two speeds"), "{message}");
}

/// The stability map predicts where the sweep will diverge before it does: on the issue's case
/// (secant law, elastic bodies, ζ = 0.05, zero backlash) the first speed of a 10 rpm grid at
/// which the map (each speed shot on its own from the quasi-static state) finds no period-one
/// orbit or one with a multiplier above 1 lies within 1 % of the speed at which the up-sweep
/// through the same grid diverges (issue 29's target; measured: both at 7 250 rpm, both at
/// 7 320 rpm with a massless mesh before `lumped.mesh_mass`).
#[test]
fn the_stability_map_predicts_the_divergence_onset() {
    let m = issue_secant_model();
    let grid: Vec<f64> = (0..=20).map(|i| 7200.0 + 10.0 * i as f64).collect();
    let map = geardyn::sweep::orbit_floquet_map(&m, &grid);
    let predicted = grid
        .iter()
        .zip(&map)
        .find(|(_, multiplier)| multiplier.is_none_or(|l| l > 1.0))
        .map(|(rpm, _)| *rpm)
        .expect("the map flags an onset in 7200-7400 rpm");
    let rpms: Vec<f64> = std::iter::once(5000.0)
        .chain(grid.iter().copied())
        .collect();
    let done = geardyn::sweep::continue_sweep(
        &m,
        &rpms,
        geardyn::sweep::SweepProgress::start(&m),
        &|| false,
    );
    assert!(
        done.up.len() < rpms.len(),
        "the up-sweep diverges in the grid"
    );
    let observed = rpms[done.up.len()];
    println!("onset: predicted {predicted} rpm, observed {observed} rpm");
    assert!(
        (predicted / observed - 1.0).abs() < 0.01,
        "predicted {predicted} rpm, observed {observed} rpm"
    );
}

/// The orbit's Floquet multipliers through the flank switches, against a switched system whose
/// growth rate is known in closed form. Zero backlash, no load, no TE, the back flanks reading
/// the drive flanks' stiffness mirrored about θ = 0 (ρ = 0), and a stiffness even in θ: a step
/// k₁ = k̄(1 + a) for |θ| < T/4 of the mesh period, k₂ = k̄(1 − a) elsewhere. Every oscillation
/// about δ = 0 crosses from the drive to the back flanks and back, twice a cycle, through the
/// model's switch; but the mirrored law makes W = k(θ) δ on both sides, so the switched model is
/// Meissner's equation, whose monodromy is the product of the segments' rotations
/// Φ = A₁(T/4) A₂(T/2) A₁(T/4), A_i(τ) = [[cos ω_iτ, sin(ω_iτ)/ω_i], [−ω_i sin ω_iτ, cos ω_iτ]],
/// and the largest multiplier (|tr Φ| + √(tr² Φ − 4))/2 inside the tongue (Richards, *Analysis of
/// periodically time-varying systems*, §4.3). The table's steps are linear ramps one sample
/// (T/4096) wide, a second-order effect: the same RK4 on the same table, re-integrated
/// independently, lands within 1.3e-7 of the closed form; 1e-6 leaves room for the central
/// differences of the orbit's Jacobian. (The switch has no kink here — the mirrored law gives
/// W = k(θ)δ on both flanks — so this holds the back flanks' mirror and the Jacobian's path
/// through the switch to an exact answer, not the saltation of a kinked one.)
#[test]
fn the_orbit_multiplier_through_the_flank_switches_is_meissners() {
    let a = 0.2;
    let samples = 4096;
    let stiffness = PeriodicTable::from_fn(PERIOD, samples, |t| {
        let centred = (t / PERIOD + 0.5).rem_euclid(1.0) - 0.5;
        match centred.abs() {
            x if (x - 0.25).abs() < 1e-12 => K_MEAN,
            x if x < 0.25 => K_MEAN * (1.0 + a),
            _ => K_MEAN * (1.0 - a),
        }
    });
    let mut m = model(stiffness, 0.0, 0.0);
    m.force = 0.0;
    m.backlash = Some(0.0);
    m.back_reflection = Some(0.0);
    let omega_bar = (K_MEAN / MASS).sqrt();
    for ratio in [1.4, 1.9, 2.0, 2.1, 2.6] {
        let omega_mesh = ratio * omega_bar;
        let period = 2.0 * PI / omega_mesh;
        let segment = |k: f64, tau: f64| {
            let w = (k / MASS).sqrt();
            let (s, c) = (w * tau).sin_cos();
            nalgebra::Matrix2::new(c, s / w, -w * s, c)
        };
        let a1 = segment(K_MEAN * (1.0 + a), period / 4.0);
        let a2 = segment(K_MEAN * (1.0 - a), period / 2.0);
        let trace = (a1 * a2 * a1).trace();
        let expected = if trace.abs() > 2.0 {
            (trace.abs() + (trace * trace - 4.0).sqrt()) / 2.0
        } else {
            1.0
        };
        let orbit = periodic_orbit(
            &m,
            driver_speed(omega_mesh),
            samples,
            State::default(),
            1e-9,
        )
        .expect("the unloaded orbit is δ = 0");
        let got = orbit.max_multiplier();
        assert!(
            (got / expected - 1.0).abs() < 1e-6,
            "ω_m/ω̄ = {ratio}: {got} against Meissner's {expected}"
        );
        // The growth rate ln|λ|/T, where it grows.
        if expected > 1.01 {
            let (rate, exact) = (got.ln() / period, expected.ln() / period);
            assert!((rate / exact - 1.0).abs() < 2e-4, "{rate} vs {exact}");
        }
    }
}

/// The FE's dashpot in the lumped twin ([`DampingSite::HubTransmissionError`]): on a speed-driven
/// pair of elastic gears (the driver's rim on its body's twist against the held hub, the driven
/// gear's free hub condensed onto its rim), the integrated free decay of the mesh mode has the
/// rate ζω of [`MeshModel::mesh_mode_damping_ratio`] (first-order modal damping,
/// c (sᵀφ)²/(2ω φᵀMφ), s = h for the hub site and g for the mesh site) to 0.5 % (the estimate's
/// own error is O(ζ) in the energy's ripple over the 1.3 decay units measured, at most 0.4 %, and
/// O(ζ²) in the formula; measured 2e-5). The two sites differ by (hᵀφ/gᵀφ)², here 1.23: the
/// test tells them apart. A rigid pair (g = h) gives back the nominal ζ at either site.
#[test]
fn the_hub_dashpot_damps_the_mesh_mode_by_its_modal_share() {
    use geardyn::lumped::{rk4_step, Drive, DrivetrainSpec, GearBody, SpringDamping};
    let body = |inertia: f64, compliance: f64| GearBody {
        hub_inertia: 0.1 * inertia,
        rim_inertia: 0.9 * inertia,
        torsional_compliance: compliance,
        translation: None,
    };
    let structure = Structure::drivetrain(&DrivetrainSpec {
        drive: Drive::Speed,
        base_radii: [0.05, 0.08],
        gears: [body(3e-3, 1e-7), body(7e-3, 5e-8)],
        shafts: [None; 2],
        bearings: None,
        spring_damping: SpringDamping::Ratio(0.0),
    })
    .unwrap();
    assert_eq!(structure.dofs, 2, "{:?}", structure.names);
    let mode = structure.mesh_mode(K_MEAN);
    let phi = nalgebra::DVector::from_vec(mode.shape.clone());
    let modal_mass = phi.dot(&(&structure.mass * &phi));
    let with = |site: DampingSite, structure: &Structure, damping: f64| MeshModel {
        structure: structure.clone(),
        damping,
        damping_site: site,
        force: 0.0,
        ..model(PeriodicTable::constant(PERIOD, K_MEAN), 0.0, 0.0)
    };
    // c for ζ = 0.005 of the mesh mode at the mesh site.
    let c = 2.0 * 0.005 * mode.frequency * modal_mass / structure.mesh_direction.dot(&phi).powi(2);
    let decay_rate = |model: &MeshModel| {
        let m_phi = &structure.mass * &phi;
        let modal_energy = |s: &State| {
            let q: f64 = (0..2).map(|i| m_phi[i] * s.q[i]).sum::<f64>() / modal_mass;
            let v: f64 = (0..2).map(|i| m_phi[i] * s.v[i]).sum::<f64>() / modal_mass;
            0.5 * modal_mass * (v * v + (mode.frequency * q).powi(2))
        };
        let mut s = State::default();
        for i in 0..2 {
            s.q[i] = 1e-6 * phi[i];
        }
        let (period, steps) = (2.0 * PI / mode.frequency, 200);
        let (h, cycles) = (period / steps as f64, 20);
        let start = modal_energy(&s);
        for n in 0..cycles * steps {
            s = rk4_step(|t, s| model.derivative(t, s), n as f64 * h, &s, h);
        }
        -(modal_energy(&s) / start).ln() / (2.0 * cycles as f64 * period)
    };
    let mut ratios = Vec::new();
    for site in [
        DampingSite::MeshDeflection,
        DampingSite::HubTransmissionError,
    ] {
        let model = with(site, &structure, c);
        let expected = model.mesh_mode_damping_ratio() * mode.frequency;
        let measured = decay_rate(&model);
        assert!(
            (measured / expected - 1.0).abs() < 0.005,
            "{site:?}: decay rate {measured:.4} vs {expected:.4} 1/s"
        );
        ratios.push(model.mesh_mode_damping_ratio());
    }
    assert!((ratios[0] / 0.005 - 1.0).abs() < 1e-12, "{ratios:?}");
    let share = (structure.te_direction.dot(&phi) / structure.mesh_direction.dot(&phi)).powi(2);
    assert!((ratios[1] / ratios[0] / share - 1.0).abs() < 1e-12);
    assert!(share > 1.15, "the sites differ by {share:.3} only");
    let rigid = Structure::rigid_pair(MASS);
    for site in [
        DampingSite::MeshDeflection,
        DampingSite::HubTransmissionError,
    ] {
        let mut model = with(site, &rigid, 0.0);
        model.damping = model.damping_from_ratio(0.03);
        assert!((model.mesh_mode_damping_ratio() / 0.03 - 1.0).abs() < 1e-12);
    }
}

/// The FE's dashpot acts only while a flank touches: a rigid pair coasting through its backlash
/// keeps its relative speed with the hub site and loses it with the mesh site's damper; in
/// contact the two sites damp alike.
#[test]
fn the_hub_dashpot_is_off_while_the_teeth_are_apart() {
    let coast = |site: DampingSite| {
        let mut model = model(PeriodicTable::constant(PERIOD, K_MEAN), 0.0, 0.05);
        model.force = 0.0;
        model.backlash = Some(1e-4);
        model.damping_site = site;
        // Inside the gap (δ = −2e-5, the back flanks touch at −1e-4), closing at 1 mm/s: it
        // stays in the gap for the 20 µs integrated.
        let s = State::from((-2e-5, -1e-3));
        let h = 1e-7;
        let end = (0..200).fold(s, |s, n| {
            geardyn::lumped::rk4_step(|t, s| model.derivative(t, s), n as f64 * h, &s, h)
        });
        end.v[0] / s.v[0]
    };
    assert_eq!(coast(DampingSite::HubTransmissionError), 1.0);
    assert!(coast(DampingSite::MeshDeflection) < 0.99);
    // With the same backlash, while the drive flanks touch, the hub site damps as the mesh
    // site does (a rigid pair: g = h): the relative speed decays alike.
    let touching = |site: DampingSite| {
        let mut model = model(PeriodicTable::constant(PERIOD, K_MEAN), 0.0, 0.05);
        model.force = 0.0;
        model.backlash = Some(1e-4);
        model.damping_site = site;
        let s = State::from((2e-6, -1e-3));
        let h = 1e-7;
        (0..100).fold(s, |s, n| {
            geardyn::lumped::rk4_step(|t, s| model.derivative(t, s), n as f64 * h, &s, h)
        })
    };
    let (hub, mesh) = (
        touching(DampingSite::HubTransmissionError),
        touching(DampingSite::MeshDeflection),
    );
    assert!(hub.q[0] > 0.0, "still in contact: {}", hub.q[0]);
    assert!(
        (hub.v[0] / mesh.v[0] - 1.0).abs() < 1e-12,
        "{} vs {}",
        hub.v[0],
        mesh.v[0]
    );
    assert!(
        (hub.v[0] / -1e-3 - 1.0).abs() > 1e-3,
        "damped: {}",
        hub.v[0]
    );
}

/// `[lumped] body_sway = "auto"` gives the rims their sway on the bores where it moves the
/// mesh mode by more than 0.5 % (driver held or both free): not on the seed paper's pair (each
/// rim's sway near 17.6 kHz, 3.6 × its both-free mesh mode), but on 17/53 shifted, whose large
/// gear sways at 10.2 kHz, 1.3 × its both-free mesh mode (validation/frequencies: without the
/// sway that mode is 8.6 % high). "on" and "off" decide alone; rigid bodies never sway.
#[test]
fn the_rims_sway_where_it_moves_the_mesh_mode() {
    use geardyn::case::{BodyModel, Case, Override};
    use geardyn::study::lumped::{case_sway_shift, gear_bodies, SWAY_MODE_SHIFT};
    let load = |overrides: &[(&str, &str)]| {
        let overrides: Vec<Override> = overrides
            .iter()
            .map(|(k, v)| format!("{k}={v}").parse::<Override>().unwrap())
            .collect();
        Case::load_with(None, &overrides).unwrap()
    };
    let sways = |case: &Case, bodies| {
        gear_bodies(case, bodies)
            .unwrap()
            .map(|b| b.translation.is_some())
    };
    let unequal = [
        ("gear1.teeth", "17"),
        ("gear2.teeth", "53"),
        ("gear1.profile_shift", "0.1"),
        ("gear2.profile_shift", "-0.1"),
    ];
    assert_eq!(sways(&load(&[]), BodyModel::Elastic), [false; 2]);
    assert_eq!(sways(&load(&unequal), BodyModel::Elastic), [true; 2]);
    // What auto decides on, the teeth's stiffness by ISO 6336 (measured 0.23 % and 2.1 %; with
    // the models' own stiffness, validation/frequencies, the sway moves the two 0.28 % and 5 %).
    let shift = |overrides: &[(&str, &str)]| case_sway_shift(&load(overrides)).unwrap();
    let (paper, shifted) = (shift(&[]), shift(&unequal));
    assert!(paper > 0.0 && paper < SWAY_MODE_SHIFT, "{paper}");
    assert!(shifted > 4.0 * SWAY_MODE_SHIFT, "{shifted}");
    assert_eq!(sways(&load(&unequal), BodyModel::Rigid), [false; 2]);
    let off = [unequal.as_slice(), &[("lumped.body_sway", "off")]].concat();
    assert_eq!(sways(&load(&off), BodyModel::Elastic), [false; 2]);
    let on = load(&[("lumped.body_sway", "on")]);
    assert_eq!(sways(&on, BodyModel::Elastic), [true; 2]);
    // The sway is the rim's with its teeth and part of the web: most of the gear's mass
    // (measured 0.70), at the body's lateral mode (17.1 kHz in the FE modal, the static shape
    // 3 % above it).
    let [a, b] = geardyn::study::lumped::rim_sway(&on).unwrap();
    // Equal gears, each solved on its own mesh (gear 2's mirrored): the same sway.
    for (x, y) in [(a.mass, b.mass), (a.stiffness, b.stiffness)] {
        assert!((x / y - 1.0).abs() < 1e-3, "{a:?} vs {b:?}");
    }
    let gear = &on.pair.gears[0];
    let mass = on.material.density * gear.spec.face_width * gear.area_moments().0;
    assert!(
        (0.5..0.9).contains(&(a.mass / mass)),
        "{} of {mass} kg",
        a.mass
    );
    let hz = (a.stiffness / a.mass).sqrt() / (2.0 * PI);
    assert!((17.1e3..18.1e3).contains(&hz), "{hz:.0} Hz");
}
