//! Lumped parametric-vibration model of the mesh (issue 5, in progress): one degree of freedom
//! along the line of action, driven by the periodic mesh stiffness k(θ) — the stiffness currency
//! from the LTCA, the explicit FE, ISO 6336 or the potential-energy method.
//!
//! # Equation (1-DOF relative displacement along the line of action)
//! ```text
//! m_e ẍ + c ẋ + k(θ) f(x − e(θ)) = F,       θ = Ω₁ t (driver roll angle), F = T / r_b2
//! m_e = I₁ I₂ / (I₁ r_b2² + I₂ r_b1²),        c = 2 ζ √(k̄ m_e)
//! f(δ) = δ           δ > 0         drive-side contact
//!      = 0           −j ≤ δ ≤ 0   tooth separation (backlash j)
//!      = δ + j       δ < −j        back-side contact
//! ```
//! e(θ) is the unloaded transmission error (relief). Integration: classical Runge–Kutta 4 with an
//! integer number of steps per mesh period, so every step lands on the same stiffness samples and
//! the periodic steady state is detected from the state at period boundaries (Poincaré map); an
//! adaptive Dormand–Prince 5(4) integration ([`reference_periods`]) is the reference it is
//! checked against, also across the kinks of the backlash law.
//!
//! # Stability (Floquet)
//! For the linear model (no separation) the monodromy matrix Φ over one mesh period T_m, from
//! the two unit initial conditions of m ẍ + c ẋ + k(θ) x = 0, has eigenvalues λ (the Floquet
//! multipliers); the motion is parametrically unstable when max |λ| > 1. For k = k̄(1 + ε cos Ω_m t)
//! the first instability region lies around Ω_m = 2ω_n with edges Ω_m ≈ 2ω_n(1 ± ε/4) for small ε
//! (Mathieu equation; Nayfeh & Mook, *Nonlinear Oscillations*, §5.2).

/// A periodic function of the driver roll angle sampled on one period (linear interpolation).
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodicTable {
    /// Period in roll angle [rad] (2π/z₁ for mesh quantities).
    pub period: f64,
    /// Values at θ = j·period/N, j = 0 … N−1.
    pub values: Vec<f64>,
}

impl PeriodicTable {
    pub fn constant(period: f64, value: f64) -> Self {
        Self {
            period,
            values: vec![value],
        }
    }

    /// Samples `f` at N points of one period.
    pub fn from_fn(period: f64, samples: usize, f: impl Fn(f64) -> f64) -> Self {
        Self {
            period,
            values: (0..samples)
                .map(|j| f(j as f64 * period / samples as f64))
                .collect(),
        }
    }

    pub fn mean(&self) -> f64 {
        self.values.iter().sum::<f64>() / self.values.len() as f64
    }

    /// Value at roll angle θ (any θ; periodic, linear between samples).
    pub fn at(&self, theta: f64) -> f64 {
        let n = self.values.len();
        if n == 1 {
            return self.values[0];
        }
        let u = (theta / self.period).rem_euclid(1.0) * n as f64;
        let i = (u.floor() as usize).min(n - 1);
        let t = u - i as f64;
        self.values[i] * (1.0 - t) + self.values[(i + 1) % n] * t
    }
}

/// The 1-DOF mesh model.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshModel {
    /// Effective mass m_e [kg].
    pub effective_mass: f64,
    /// Mesh stiffness k(θ) [N/m].
    pub stiffness: PeriodicTable,
    /// Unloaded transmission error e(θ) along the line of action [m].
    pub unloaded_te: PeriodicTable,
    /// Viscous mesh damping c [N·s/m].
    pub damping: f64,
    /// Static mesh force F = T/r_b2 [N].
    pub force: f64,
    /// Backlash j along the line of action [m]; `None`: no separation (linear contact).
    pub backlash: Option<f64>,
}

impl MeshModel {
    /// Damping coefficient for a damping ratio ζ at the mean stiffness: c = 2ζ√(k̄ m_e).
    pub fn damping_from_ratio(&self, ratio: f64) -> f64 {
        2.0 * ratio * (self.stiffness.mean() * self.effective_mass).sqrt()
    }

    /// Natural frequency of the mean stiffness, ω_n = √(k̄/m_e) [rad/s].
    pub fn natural_frequency(&self) -> f64 {
        (self.stiffness.mean() / self.effective_mass).sqrt()
    }

    /// Elastic mesh force k(θ) f(x − e(θ)) (≥ 0 on the drive side).
    pub fn mesh_force(&self, theta: f64, x: f64) -> f64 {
        let delta = x - self.unloaded_te.at(theta);
        let k = self.stiffness.at(theta);
        match self.backlash {
            None => k * delta,
            Some(_) if delta > 0.0 => k * delta,
            Some(j) if delta < -j => k * (delta + j),
            Some(_) => 0.0,
        }
    }

    /// Acceleration ẍ at roll angle θ.
    fn acceleration(&self, theta: f64, x: f64, v: f64) -> f64 {
        (self.force - self.damping * v - self.mesh_force(theta, x)) / self.effective_mass
    }
}

/// One period of the periodic steady state.
#[derive(Debug, Clone, PartialEq)]
pub struct SteadyState {
    /// Mesh periods integrated until the state repeated.
    pub periods: usize,
    pub converged: bool,
    /// Samples over one mesh period: displacement [m], velocity [m/s], mesh force [N].
    pub displacement: Vec<f64>,
    pub velocity: Vec<f64>,
    pub mesh_force: Vec<f64>,
    /// Whether the mesh force was zero (teeth apart) anywhere in the period.
    pub separated: bool,
}

/// Integrates at driver speed Ω₁ (rad/s) from (x₀, v₀) until the state at period boundaries
/// repeats to `tolerance` (relative to the static deflection), at most `max_periods`.
pub fn steady_state(
    model: &MeshModel,
    driver_speed: f64,
    steps_per_period: usize,
    initial: (f64, f64),
    tolerance: f64,
    max_periods: usize,
) -> SteadyState {
    let static_deflection = (model.force / model.stiffness.mean()).abs().max(1e-30);
    let (mut x, mut v) = initial;
    let mut out = SteadyState {
        periods: 0,
        converged: false,
        displacement: vec![0.0; steps_per_period],
        velocity: vec![0.0; steps_per_period],
        mesh_force: vec![0.0; steps_per_period],
        separated: false,
    };
    let omega_scale = model.natural_frequency().max(driver_speed);
    for period in 1..=max_periods {
        let (x_start, v_start) = (x, v);
        (x, v) = integrate_period(
            model,
            driver_speed,
            steps_per_period,
            (x, v),
            |j, theta, x, v| {
                out.displacement[j] = x;
                out.velocity[j] = v;
                out.mesh_force[j] = model.mesh_force(theta, x);
            },
        );
        out.periods = period;
        let change = (x - x_start).abs().max((v - v_start).abs() / omega_scale);
        if change < tolerance * static_deflection {
            out.converged = true;
            break;
        }
    }
    out.separated = model.backlash.is_some() && out.mesh_force.iter().any(|f| *f <= 0.0);
    out
}

/// Floquet multipliers' largest modulus of the linear model (no separation, no TE) at driver
/// speed Ω₁: eigenvalues of the 2×2 monodromy matrix over one mesh period.
pub fn floquet_max_multiplier(
    model: &MeshModel,
    driver_speed: f64,
    steps_per_period: usize,
) -> f64 {
    let linear = MeshModel {
        backlash: None,
        force: 0.0,
        unloaded_te: PeriodicTable::constant(model.stiffness.period, 0.0),
        ..model.clone()
    };
    let columns: Vec<(f64, f64)> = [(1.0, 0.0), (0.0, 1.0)]
        .iter()
        .map(|&start| {
            integrate_period(
                &linear,
                driver_speed,
                steps_per_period,
                start,
                |_, _, _, _| {},
            )
        })
        .collect();
    let (a, b, c, d) = (columns[0].0, columns[1].0, columns[0].1, columns[1].1);
    let trace = a + d;
    let det = a * d - b * c;
    let disc = trace * trace / 4.0 - det;
    if disc >= 0.0 {
        let r = disc.sqrt();
        (trace / 2.0 + r).abs().max((trace / 2.0 - r).abs())
    } else {
        det.abs().sqrt()
    }
}

/// RK4 over one mesh period in `steps` equal steps from (x, v) at θ = 0; `sample` sees the
/// state at the start of every step. Returns the state after the period.
fn integrate_period(
    model: &MeshModel,
    driver_speed: f64,
    steps: usize,
    start: (f64, f64),
    mut sample: impl FnMut(usize, f64, f64, f64),
) -> (f64, f64) {
    let h = model.stiffness.period / driver_speed / steps as f64;
    let (mut x, mut v) = start;
    for j in 0..steps {
        let theta = j as f64 * model.stiffness.period / steps as f64;
        sample(j, theta, x, v);
        (x, v) = rk4_step(model, driver_speed, h, theta, x, v);
    }
    (x, v)
}

/// One classical Runge–Kutta step of length h from roll angle θ₀.
fn rk4_step(
    model: &MeshModel,
    driver_speed: f64,
    h: f64,
    theta0: f64,
    x: f64,
    v: f64,
) -> (f64, f64) {
    let dtheta = driver_speed * h;
    let a1 = model.acceleration(theta0, x, v);
    let (x2, v2) = (x + 0.5 * h * v, v + 0.5 * h * a1);
    let a2 = model.acceleration(theta0 + 0.5 * dtheta, x2, v2);
    let (x3, v3) = (x + 0.5 * h * v2, v + 0.5 * h * a2);
    let a3 = model.acceleration(theta0 + 0.5 * dtheta, x3, v3);
    let (x4, v4) = (x + h * v3, v + h * a3);
    let a4 = model.acceleration(theta0 + dtheta, x4, v4);
    (
        x + h / 6.0 * (v + 2.0 * v2 + 2.0 * v3 + v4),
        v + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4),
    )
}

/// A run-up (or run-down): the driver speed ramps linearly from `from` to `to` [rad/s] over
/// `duration` [s]; θ(t) = Ω₀t + ½αt². Fixed RK4 steps of at most 1/32 of the natural period and
/// 1/64 of the shortest mesh period; at most `max_samples` evenly spaced steps are recorded.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RunUp {
    pub time: Vec<f64>,
    /// Driver speed [rad/s].
    pub driver_speed: Vec<f64>,
    /// Displacement along the line of action [m].
    pub displacement: Vec<f64>,
    /// Mesh force [N].
    pub mesh_force: Vec<f64>,
    pub steps: usize,
}

pub fn run_up(model: &MeshModel, from: f64, to: f64, duration: f64, max_samples: usize) -> RunUp {
    let alpha = (to - from) / duration;
    let fastest_mesh_period = model.stiffness.period / from.abs().max(to.abs()).max(1e-12);
    let natural_period = 2.0 * std::f64::consts::PI / model.natural_frequency();
    let h_max = (natural_period / 32.0).min(fastest_mesh_period / 64.0);
    let steps = (duration / h_max).ceil() as usize;
    let h = duration / steps as f64;
    let decimate = steps.div_ceil(max_samples.max(1)).max(1);
    let theta = |t: f64| from * t + 0.5 * alpha * t * t;
    let accel = |t: f64, x: f64, v: f64| model.acceleration(theta(t), x, v);
    let (mut x, mut v) = (model.force / model.stiffness.mean(), 0.0);
    let mut out = RunUp {
        steps,
        ..RunUp::default()
    };
    for i in 0..=steps {
        let t = i as f64 * h;
        if i % decimate == 0 {
            out.time.push(t);
            out.driver_speed.push(from + alpha * t);
            out.displacement.push(x);
            out.mesh_force.push(model.mesh_force(theta(t), x));
        }
        if i == steps {
            break;
        }
        let a1 = accel(t, x, v);
        let (x2, v2) = (x + 0.5 * h * v, v + 0.5 * h * a1);
        let a2 = accel(t + 0.5 * h, x2, v2);
        let (x3, v3) = (x + 0.5 * h * v2, v + 0.5 * h * a2);
        let a3 = accel(t + 0.5 * h, x3, v3);
        let (x4, v4) = (x + h * v3, v + h * a3);
        let a4 = accel(t + h, x4, v4);
        x += h / 6.0 * (v + 2.0 * v2 + 2.0 * v3 + v4);
        v += h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
    }
    out
}

/// Reference integration with the adaptive Dormand–Prince 5(4) pair (Hairer, Nørsett & Wanner,
/// *Solving ODEs I*, §II.5): error control per step (relative `tolerance`), so steps shrink by
/// themselves at the kinks of the backlash law. Integrates `periods` mesh periods from `start`
/// at θ = 0 and returns the state at the end and the number of accepted steps.
pub fn reference_periods(
    model: &MeshModel,
    driver_speed: f64,
    start: (f64, f64),
    periods: usize,
    tolerance: f64,
) -> ((f64, f64), usize) {
    const C: [f64; 7] = [0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0];
    const A: [[f64; 6]; 7] = [
        [0.0; 6],
        [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
        [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
        [
            19372.0 / 6561.0,
            -25360.0 / 2187.0,
            64448.0 / 6561.0,
            -212.0 / 729.0,
            0.0,
            0.0,
        ],
        [
            9017.0 / 3168.0,
            -355.0 / 33.0,
            46732.0 / 5247.0,
            49.0 / 176.0,
            -5103.0 / 18656.0,
            0.0,
        ],
        [
            35.0 / 384.0,
            0.0,
            500.0 / 1113.0,
            125.0 / 192.0,
            -2187.0 / 6784.0,
            11.0 / 84.0,
        ],
    ];
    const B5: [f64; 7] = [
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
        0.0,
    ];
    const B4: [f64; 7] = [
        5179.0 / 57600.0,
        0.0,
        7571.0 / 16695.0,
        393.0 / 640.0,
        -92097.0 / 339200.0,
        187.0 / 2100.0,
        1.0 / 40.0,
    ];
    let end = periods as f64 * model.stiffness.period / driver_speed;
    let rhs = |t: f64, y: [f64; 2]| [y[1], model.acceleration(driver_speed * t, y[0], y[1])];
    let scale_x = (model.force / model.stiffness.mean()).abs().max(1e-12);
    let scale_v = scale_x * model.natural_frequency();
    let (mut t, mut y) = (0.0, [start.0, start.1]);
    let mut h = 0.01 * 2.0 * std::f64::consts::PI / model.natural_frequency();
    let mut accepted = 0;
    while t < end {
        h = h.min(end - t);
        let mut k = [[0.0; 2]; 7];
        for s in 0..7 {
            let mut ys = y;
            for (j, kj) in k.iter().enumerate().take(s) {
                ys[0] += h * A[s][j] * kj[0];
                ys[1] += h * A[s][j] * kj[1];
            }
            k[s] = rhs(t + C[s] * h, ys);
        }
        let (mut y5, mut err) = (y, [0.0; 2]);
        for s in 0..7 {
            for d in 0..2 {
                y5[d] += h * B5[s] * k[s][d];
                err[d] += h * (B5[s] - B4[s]) * k[s][d];
            }
        }
        let e = (err[0] / (scale_x * tolerance))
            .abs()
            .max((err[1] / (scale_v * tolerance)).abs());
        if e <= 1.0 {
            t += h;
            y = y5;
            accepted += 1;
        }
        h *= (0.9 * e.max(1e-10).powf(-0.2)).clamp(0.2, 5.0);
    }
    ((y[0], y[1]), accepted)
}
