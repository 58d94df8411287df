//! Central-difference time integration (seed paper eqs. 24–26 in velocity-Verlet form, which is
//! the same method):
//! ```text
//! v_{n+½} = v_n + ½ Δt a_n,   x_{n+1} = x_n + Δt v_{n+½},
//! a_{n+1} = M⁻¹ (f_ext − f_int(x_{n+1}) − f_damp),   v_{n+1} = v_{n+½} + ½ Δt a_{n+1}
//! ```
//! (the damping force uses v_{n+½}, which keeps the scheme explicit). Stable for
//! Δt ≤ Δt_cr = 2/ω_max, ω_max² the largest eigenvalue of M⁻¹K; [`critical_step`] measures it by
//! power iteration, [`ExplicitBody::element_eigen_critical_step`] bounds it per element.

use super::body::{ExplicitBody, ForceOutput};

/// Positions, velocities and accelerations of all DOFs (2 per node).
#[derive(Debug, Clone)]
pub struct State {
    pub time: f64,
    pub x: Vec<f64>,
    pub v: Vec<f64>,
    pub a: Vec<f64>,
}

/// Energy bookkeeping of a run [J].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Energy {
    pub kinetic: f64,
    pub strain: f64,
    pub damping: f64,
    pub external_work: f64,
}

impl Energy {
    /// kinetic + strain + dissipated − external work: zero for an exact integrator.
    pub fn balance(&self) -> f64 {
        self.kinetic + self.strain + self.damping - self.external_work
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ExplicitError {
    #[error(
        "the explicit run diverged at t = {time:.6e} s (step {step}): {cause}. The time step {dt:.4e} s is \
         above the stable step {dt_critical:.4e} s (2/ω_max); use a step factor below 1 (default 0.9). \
         Results up to the last finite step are kept"
    )]
    Diverged {
        time: f64,
        step: usize,
        dt: f64,
        dt_critical: f64,
        cause: String,
    },
}

/// Largest ω² of M⁻¹K (linear K at the reference) by power iteration with the symmetric form
/// M^{-½} K M^{-½}; `fixed` DOFs are removed. Returns Δt_cr = 2/ω_max.
pub fn critical_step(body: &ExplicitBody, fixed: &[bool], iterations: usize) -> f64 {
    let n = 2 * body.reference.len();
    let inv_sqrt_m: Vec<f64> = (0..n).map(|d| 1.0 / body.mass[d / 2].sqrt()).collect();
    // A deterministic start with content in the highest modes: alternating signs.
    let mut y: Vec<f64> = (0..n)
        .map(|d| {
            if fixed[d] {
                0.0
            } else if (d / 2 + d) % 2 == 0 {
                1.0
            } else {
                -0.7
            }
        })
        .collect();
    let mut lambda = 0.0;
    let reference: Vec<f64> = body.reference.iter().flat_map(|p| [p.x, p.y]).collect();
    let zero = vec![0.0; n];
    for _ in 0..iterations {
        let norm = y.iter().map(|v| v * v).sum::<f64>().sqrt();
        y.iter_mut().for_each(|v| *v /= norm);
        // z = M^{-½} K M^{-½} y, with K u = −(force at x = X + u) for a small u.
        let scale = 1e-9;
        let x: Vec<f64> = (0..n)
            .map(|d| reference[d] + scale * inv_sqrt_m[d] * y[d])
            .collect();
        let mut force = vec![0.0; n];
        body.internal_forces(&x, &zero, 0.0, &mut force);
        let z: Vec<f64> = (0..n)
            .map(|d| {
                if fixed[d] {
                    0.0
                } else {
                    -force[d] / scale * inv_sqrt_m[d]
                }
            })
            .collect();
        lambda = y.iter().zip(&z).map(|(a, b)| a * b).sum::<f64>();
        y = z;
    }
    2.0 / lambda.sqrt()
}

/// Integrator for one body with fixed DOFs and an external-force callback.
pub struct CentralDifference<'a> {
    pub body: &'a ExplicitBody,
    pub dt: f64,
    pub beta_k: f64,
    pub fixed: Vec<bool>,
    pub dt_critical: f64,
    force: Vec<f64>,
    external: Vec<f64>,
    pub energy: Energy,
    pub steps: usize,
    /// Kinetic + strain energy at the start, the scale for divergence detection.
    initial_energy: f64,
}

impl<'a> CentralDifference<'a> {
    pub fn new(
        body: &'a ExplicitBody,
        dt: f64,
        beta_k: f64,
        fixed: Vec<bool>,
        dt_critical: f64,
    ) -> Self {
        let n = 2 * body.reference.len();
        CentralDifference {
            body,
            dt,
            beta_k,
            fixed,
            dt_critical,
            force: vec![0.0; n],
            external: vec![0.0; n],
            energy: Energy::default(),
            steps: 0,
            initial_energy: 0.0,
        }
    }

    /// Net nodal forces f_ext − f_int − f_damp at the state's time, positions and velocities,
    /// into `self.force` (external part kept in `self.external`).
    fn net_forces(&mut self, state: &State, external: &dyn Fn(f64, &mut [f64])) -> ForceOutput {
        self.external.iter_mut().for_each(|f| *f = 0.0);
        external(state.time, &mut self.external);
        self.force.copy_from_slice(&self.external);
        self.body
            .internal_forces(&state.x, &state.v, self.beta_k, &mut self.force)
    }

    /// Initial accelerations and energies for a state.
    pub fn initialize(&mut self, state: &mut State, external: &dyn Fn(f64, &mut [f64])) {
        let out = self.net_forces(state, external);
        for d in 0..state.a.len() {
            state.a[d] = if self.fixed[d] {
                0.0
            } else {
                self.force[d] / self.body.mass[d / 2]
            };
        }
        self.energy.strain = out.strain_energy;
        self.energy.kinetic = kinetic(self.body, &state.v);
        self.initial_energy = self.energy.kinetic + self.energy.strain;
    }

    /// One step; no allocation.
    pub fn step(
        &mut self,
        state: &mut State,
        external: &dyn Fn(f64, &mut [f64]),
    ) -> Result<(), ExplicitError> {
        let (dt, n) = (self.dt, state.x.len());
        // Work of the external forces over the step (trapezoid in force, exact displacement).
        let mut work = 0.0;
        for d in 0..n {
            if self.fixed[d] {
                state.v[d] = 0.0;
                continue;
            }
            state.v[d] += 0.5 * dt * state.a[d];
            let dx = dt * state.v[d];
            work += 0.5 * self.external[d] * dx;
            state.x[d] += dx;
        }
        state.time += dt;
        let out = self.net_forces(state, external);
        for d in 0..n {
            if self.fixed[d] {
                continue;
            }
            work += 0.5 * self.external[d] * dt * state.v[d];
            state.a[d] = self.force[d] / self.body.mass[d / 2];
            state.v[d] += 0.5 * dt * state.a[d];
        }
        self.steps += 1;
        self.energy.external_work += work;
        self.energy.damping += out.damping_power * dt;
        self.energy.strain = out.strain_energy;
        self.energy.kinetic = kinetic(self.body, &state.v);
        let total = self.energy.kinetic + self.energy.strain;
        let reference =
            (self.initial_energy + self.energy.external_work.abs() + self.energy.damping)
                .max(1e-300);
        let cause = if !total.is_finite() {
            Some("the energy is not finite (NaN or infinity)".to_string())
        } else if self.steps > 10 && total > 1e3 * reference && total > 1e-12 {
            Some(format!(
                "the energy grew to {total:.3e} J, {:.1e} times the energy put in",
                total / reference
            ))
        } else {
            None
        };
        match cause {
            Some(cause) => Err(ExplicitError::Diverged {
                time: state.time,
                step: self.steps,
                dt,
                dt_critical: self.dt_critical,
                cause,
            }),
            None => Ok(()),
        }
    }
}

fn kinetic(body: &ExplicitBody, v: &[f64]) -> f64 {
    0.5 * v
        .iter()
        .enumerate()
        .map(|(d, vd)| body.mass[d / 2] * vd * vd)
        .sum::<f64>()
}
