//! Where fixed-step schemes fail on the lumped model: the step at which each goes unstable or
//! inaccurate, predicted vs observed, and what tooth separation does to each.
//!
//! # Predictions (undamped oscillator ẍ + ω²x = 0, step h, z = ωh)
//! ```text
//! central difference   x_{n+1} − 2x_n + x_{n−1} = −z² x_n         stable z ≤ 2
//!                      ω̃h = 2 asin(z/2)         → frequency error +z²/24
//! Newmark β=¼, γ=½     (trapezoidal, implicit)                      stable for every z
//!                      ω̃h = 2 atan(z/2)         → frequency error −z²/12
//! RK4                  λ = R(iz), R(w) = 1 + w + w²/2 + w³/6 + w⁴/24   stable z ≤ 2√2
//!                      ω̃h = arg R(iz)           → frequency error −z⁴/120 (and |λ| < 1: damping)
//! ```
//! (Hughes, *The Finite Element Method*, §9.3; Hairer & Wanner, *Solving ODEs II*, §IV.2.)
//! "Observed" is measured from the implementation itself: the one-step amplification matrix of
//! the stepper, built column by column from unit states, and its eigenvalues λ; the scheme is
//! unstable when max|λ| > 1 and its frequency is arg λ / h.
//!
//! Separation: the backlash law f(u) has kinks, so the solution's third derivative jumps at every
//! contact loss and impact. Fixed steps straddle the kinks; the observed order of convergence on
//! a separating response shows what that costs each scheme.

use super::{reference_periods, rk4_step, MeshModel, State};

/// The fixed-step schemes compared.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scheme {
    /// Explicit central difference with half-step velocities (the explicit FE's integrator;
    /// velocity-proportional forces use the lagging half-step velocity, as explicit FE codes do).
    CentralDifference,
    /// Newmark average acceleration (β = ¼, γ = ½), implicit; the piecewise-linear mesh law is
    /// solved exactly per step (1-DOF models only).
    NewmarkAverage,
    /// Classical Runge–Kutta 4 (the sweep's integrator).
    Rk4,
}

pub const SCHEMES: [Scheme; 3] = [
    Scheme::CentralDifference,
    Scheme::NewmarkAverage,
    Scheme::Rk4,
];

impl Scheme {
    pub fn name(self) -> &'static str {
        match self {
            Scheme::CentralDifference => "central difference",
            Scheme::NewmarkAverage => "Newmark average acceleration",
            Scheme::Rk4 => "RK4",
        }
    }

    /// Formal order of accuracy on smooth problems. Central difference drops to first order
    /// when there is viscous damping: the damping force at step n uses the half-step velocity
    /// v_{n−½} = v_n + O(h).
    pub fn order(self, damped: bool) -> f64 {
        match self {
            Scheme::CentralDifference if damped => 1.0,
            Scheme::CentralDifference | Scheme::NewmarkAverage => 2.0,
            Scheme::Rk4 => 4.0,
        }
    }

    /// Predicted stability limit ωh of the undamped oscillator (`None`: unconditionally stable).
    pub fn predicted_limit(self) -> Option<f64> {
        match self {
            Scheme::CentralDifference => Some(2.0),
            Scheme::NewmarkAverage => None,
            Scheme::Rk4 => Some(2.0 * std::f64::consts::SQRT_2),
        }
    }

    /// Predicted relative frequency error ω̃/ω − 1 at z = ωh (exact for the linear scheme).
    pub fn predicted_frequency_error(self, z: f64) -> f64 {
        let omega_h = match self {
            Scheme::CentralDifference => 2.0 * (z / 2.0).asin(),
            Scheme::NewmarkAverage => 2.0 * (z / 2.0).atan(),
            Scheme::Rk4 => {
                let z2 = z * z;
                (z - z * z2 / 6.0).atan2(1.0 - z2 / 2.0 + z2 * z2 / 24.0)
            }
        };
        omega_h / z - 1.0
    }

    /// One step of length h from time t (θ = Ω₁t). Central difference reads and returns the
    /// velocity at the half step before/after.
    pub fn step(self, model: &MeshModel, driver_speed: f64, t: f64, s: &State, h: f64) -> State {
        match self {
            Scheme::Rk4 => rk4_step(|t, s| model.derivative(driver_speed * t, s), t, s, h),
            Scheme::CentralDifference => {
                let a = model.derivative(driver_speed * t, s).v;
                let v: [f64; super::MAX_DOFS] = std::array::from_fn(|i| s.v[i] + h * a[i]);
                State {
                    q: std::array::from_fn(|i| s.q[i] + h * v[i]),
                    v,
                }
            }
            Scheme::NewmarkAverage => newmark_step(model, driver_speed, t, s, h),
        }
    }
}

/// Newmark average acceleration on the 1-DOF model: m a₁ + c v₁ + k f(x₁ − e) = F with
/// x₁ = x₀ + h v₀ + h²/4 (a₀ + a₁), v₁ = v₀ + h/2 (a₀ + a₁). The residual is monotone in a₁ and
/// piecewise linear, so each branch of f is solved and the consistent one kept.
fn newmark_step(model: &MeshModel, driver_speed: f64, t: f64, s: &State, h: f64) -> State {
    assert!(
        model.structure.dofs == 1,
        "the Newmark comparison covers the 1-DOF model"
    );
    let (x0, v0) = (s.q[0], s.v[0]);
    let (m, c) = (model.structure.mass[(0, 0)], model.damping);
    // m a₀ = F − W₀ divided by m, as a₁ is below (M⁻¹ rounded once would break the scheme's
    // exact energy balance at ωh ~ 10³ by more than the 1e-12 the stability test resolves).
    let a0 = (model.force - model.mesh_force(driver_speed * t, x0) - c * v0) / m;
    let theta = driver_speed * (t + h);
    let (k, e) = (
        model.mesh.stiffness.at(theta),
        model.mesh.unloaded_te.at(theta),
    );
    let u0 = x0 + h * v0 + h * h / 4.0 * a0 - e;
    // Branches (slope, offset) of f(u) = slope·u + offset and their ranges in u.
    let branches: Vec<(f64, f64, f64, f64)> = match model.backlash {
        None => vec![(1.0, 0.0, f64::NEG_INFINITY, f64::INFINITY)],
        Some(j) => vec![
            (1.0, 0.0, 0.0, f64::INFINITY),
            (0.0, 0.0, -j, 0.0),
            (1.0, j, f64::NEG_INFINITY, -j),
        ],
    };
    let a1 = branches
        .iter()
        .map(|&(slope, offset, lo, hi)| {
            let a = (model.force - c * (v0 + 0.5 * h * a0) - k * (slope * u0 + offset))
                / (m + 0.5 * h * c + k * slope * h * h / 4.0);
            let u = u0 + h * h / 4.0 * a;
            let outside = (lo - u).max(u - hi).max(0.0);
            (outside, a)
        })
        .min_by(|p, q| p.0.total_cmp(&q.0))
        .expect("at least one branch")
        .1;
    State::from((
        x0 + h * v0 + h * h / 4.0 * (a0 + a1),
        v0 + 0.5 * h * (a0 + a1),
    ))
}

/// Eigenvalues' largest modulus and the frequency ω̃ = arg λ / h of the one-step map of `scheme`
/// on the free undamped linear model (no load, no TE, no backlash, no damping) at time 0: the
/// observed behaviour. (With damping ζ the central-difference limit with lagging velocity drops
/// to 2(√(1+ζ²) − ζ).)
pub fn observed_amplification(scheme: Scheme, model: &MeshModel, h: f64) -> (f64, f64) {
    let free = MeshModel {
        damping: 0.0,
        ..model.linearized()
    };
    let column = |s: State| {
        let n = scheme.step(&free, 0.0, 0.0, &s, h);
        (n.q[0], n.v[0])
    };
    let (a, c) = column(State::from((1.0, 0.0)));
    let (b, d) = column(State::from((0.0, 1.0)));
    let (trace, det) = (a + d, a * d - b * c);
    let disc = trace * trace / 4.0 - det;
    if disc >= 0.0 {
        let r = disc.sqrt();
        ((trace / 2.0 + r).abs().max((trace / 2.0 - r).abs()), 0.0)
    } else {
        let modulus = det.sqrt();
        (modulus, (-disc).sqrt().atan2(trace / 2.0) / h)
    }
}

/// The border between `good` and `bad` (bad(bad) holds, bad(good) does not), by 60 bisections.
fn border(mut good: f64, mut bad: f64, is_bad: impl Fn(f64) -> bool) -> f64 {
    for _ in 0..60 {
        let mid = 0.5 * (good + bad);
        if is_bad(mid) {
            bad = mid;
        } else {
            good = mid;
        }
    }
    0.5 * (good + bad)
}

/// The largest ωh at which `scheme` is still stable on the free oscillator, by bisection on the
/// observed amplification (None: stable up to ωh = 1000).
pub fn observed_limit(scheme: Scheme, model: &MeshModel) -> Option<f64> {
    let omega = model.natural_frequency();
    let unstable = |z: f64| observed_amplification(scheme, model, z / omega).0 > 1.0 + 1e-12;
    unstable(1000.0).then(|| border(1e-3, 1000.0, unstable))
}

/// The largest ωh at which the observed frequency error stays within `tolerance` (e.g. 0.01), by
/// bisection below the stability limit.
pub fn observed_accuracy_limit(scheme: Scheme, model: &MeshModel, tolerance: f64) -> f64 {
    let omega = model.natural_frequency();
    let bad = |z: f64| {
        let (_, frequency) = observed_amplification(scheme, model, z / omega);
        (frequency / omega - 1.0).abs() > tolerance
    };
    border(
        1e-3,
        scheme.predicted_limit().unwrap_or(1000.0) * 0.999,
        bad,
    )
}

/// Error of `scheme` after `periods` mesh periods at `steps_per_period`, against the adaptive
/// Dormand–Prince reference at tolerance 1e-11, in units of the static deflection (max over p
/// and ṗ/ω_n).
pub fn end_state_error(
    scheme: Scheme,
    model: &MeshModel,
    driver_speed: f64,
    steps_per_period: usize,
    periods: usize,
) -> f64 {
    let start = model.static_state();
    let h = model.mesh.period() / driver_speed / steps_per_period as f64;
    let mut state = start;
    if scheme == Scheme::CentralDifference {
        // Start the half-step velocity: v_{−½} = v₀ − ½h a₀.
        let a0 = model.derivative(0.0, &state).v;
        state.v = std::array::from_fn(|i| state.v[i] - 0.5 * h * a0[i]);
    }
    let total = steps_per_period * periods;
    for n in 0..total {
        state = scheme.step(model, driver_speed, n as f64 * h, &state, h);
    }
    if scheme == Scheme::CentralDifference {
        // Back from v_{N+½} to v_N.
        let a = model.derivative(driver_speed * total as f64 * h, &state).v;
        state.v = std::array::from_fn(|i| state.v[i] - 0.5 * h * a[i]);
    }
    let (reference, _) = reference_periods(model, driver_speed, start, periods, 1e-11);
    let scale = (model.force / model.mesh.mean()).abs();
    let omega = model.natural_frequency();
    (state.q[0] - reference.q[0])
        .abs()
        .max((state.v[0] - reference.v[0]).abs() / omega)
        / scale
}

/// Observed order of convergence: the least-squares slope of log(error) against log(steps) over
/// `steps`, 2·`steps`, 4·`steps`, 8·`steps` per period (a single pair of step sizes is noisy when
/// kinks fall at different places inside the steps). Returns the order and the errors.
pub fn observed_order(
    scheme: Scheme,
    model: &MeshModel,
    driver_speed: f64,
    steps: usize,
    periods: usize,
) -> (f64, Vec<f64>) {
    let errors: Vec<f64> = (0..4)
        .map(|level| end_state_error(scheme, model, driver_speed, steps << level, periods))
        .collect();
    let points: Vec<(f64, f64)> = errors
        .iter()
        .enumerate()
        .map(|(level, e)| (level as f64 * std::f64::consts::LN_2, e.max(1e-300).ln()))
        .collect();
    let n = points.len() as f64;
    let (mx, my) = (
        points.iter().map(|p| p.0).sum::<f64>() / n,
        points.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let slope = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>()
        / points.iter().map(|p| (p.0 - mx).powi(2)).sum::<f64>();
    (-slope, errors)
}

/// One row of the failure table.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SchemeReport {
    pub scheme: &'static str,
    /// Stability limit ωh: predicted (None: unconditionally stable) and observed.
    pub predicted_limit: Option<f64>,
    pub observed_limit: Option<f64>,
    /// Largest ωh with a frequency error within 1 %: predicted (from the formula) and observed.
    pub predicted_accuracy_limit: f64,
    pub observed_accuracy_limit: f64,
    /// Formal order (for the damping of the smooth model), and the observed order (16 … 128
    /// steps per natural period) on a smooth response and on one with tooth separation.
    pub formal_order: f64,
    pub observed_order_smooth: f64,
    pub observed_order_separating: f64,
    /// Errors at 32 steps per natural period (units of the static deflection).
    pub error_smooth: f64,
    pub error_separating: f64,
}

/// The failure table of every scheme on `model` (1-DOF): stability and 1 % accuracy limits from
/// the free oscillator, orders of convergence on `smooth` and `separating` variants at driver
/// speed `driver_speed`, integrated over `periods` mesh periods.
pub fn failure_table(
    smooth: &MeshModel,
    separating: &MeshModel,
    driver_speed: f64,
    periods: usize,
) -> Vec<SchemeReport> {
    let steps_for = |model: &MeshModel, per_natural: f64| {
        let mesh_period = model.mesh.period() / driver_speed;
        let natural_period = 2.0 * std::f64::consts::PI / model.natural_frequency();
        (per_natural * mesh_period / natural_period).ceil() as usize
    };
    SCHEMES
        .iter()
        .map(|&scheme| {
            let predicted_accuracy_limit =
                border(1e-3, scheme.predicted_limit().unwrap_or(1000.0), |z| {
                    scheme.predicted_frequency_error(z).abs() > 0.01
                });
            let (order_smooth, errors_smooth) = observed_order(
                scheme,
                smooth,
                driver_speed,
                steps_for(smooth, 16.0),
                periods,
            );
            let (order_separating, errors_separating) = observed_order(
                scheme,
                separating,
                driver_speed,
                steps_for(separating, 16.0),
                periods,
            );
            SchemeReport {
                scheme: scheme.name(),
                predicted_limit: scheme.predicted_limit(),
                observed_limit: observed_limit(scheme, smooth),
                predicted_accuracy_limit,
                observed_accuracy_limit: observed_accuracy_limit(scheme, smooth, 0.01),
                formal_order: scheme.order(smooth.damping > 0.0),
                observed_order_smooth: order_smooth,
                observed_order_separating: order_separating,
                error_smooth: errors_smooth[1],
                error_separating: errors_separating[1],
            }
        })
        .collect()
}
