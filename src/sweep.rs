//! Speed sweeps of the lumped mesh model (issue 5, in progress): periodic steady state at every
//! driver speed, harmonics of the mesh frequency (rustfft), dynamic factor, separation and
//! Floquet stability; up- and down-sweeps continue from the neighbouring speed so jumps show.

use rayon::prelude::*;
use rustfft::{num_complex::Complex, FftPlanner};

use crate::lumped::{floquet_max_multiplier, steady_state, MeshModel};

/// Least samples per mesh period (an integer number, so the FFT sees whole periods).
pub const STEPS_PER_PERIOD: usize = 128;

/// RK4 steps per mesh period at driver speed Ω₁: at least [`STEPS_PER_PERIOD`] and 32 per natural
/// period, so low speeds (many natural periods per mesh period) stay resolved and stable
/// (RK4 needs ω_n h < 2.8; 32 steps give ω_n h = 0.2).
pub fn steps_per_period(model: &MeshModel, driver_speed: f64) -> usize {
    let mesh_omega = 2.0 * std::f64::consts::PI * driver_speed / model.stiffness.period;
    let ratio = model.natural_frequency() / mesh_omega;
    STEPS_PER_PERIOD.max((32.0 * ratio).ceil() as usize)
}
/// Mesh harmonics reported.
pub const HARMONICS: usize = 5;

/// The response at one driver speed.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepPoint {
    pub driver_speed_rpm: f64,
    pub mesh_frequency_hz: f64,
    /// Dynamic transmission error along the LOA about its mean: rms and peak-to-peak [m].
    pub dte_rms: f64,
    pub dte_peak_to_peak: f64,
    /// Max dynamic mesh force / static force.
    pub dynamic_factor: f64,
    pub separated: bool,
    /// Amplitudes of the DTE at mesh harmonics 1 … HARMONICS [m].
    pub harmonics: [f64; HARMONICS],
    /// Largest Floquet multiplier of the linear model (> 1: parametrically unstable).
    pub floquet: f64,
    pub periods: usize,
    pub converged: bool,
}

fn analyse(model: &MeshModel, rpm: f64, start: (f64, f64)) -> (SweepPoint, (f64, f64)) {
    let speed = rpm * 2.0 * std::f64::consts::PI / 60.0;
    let tolerance = 1e-7;
    let steps = steps_per_period(model, speed);
    let s = steady_state(model, speed, steps, start, tolerance, 4000);
    let n = s.displacement.len() as f64;
    let mean = s.displacement.iter().sum::<f64>() / n;
    let rms = (s
        .displacement
        .iter()
        .map(|x| (x - mean).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    let (lo, hi) = s
        .displacement
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(*x), b.max(*x))
        });
    let mut buffer: Vec<Complex<f64>> = s
        .displacement
        .iter()
        .map(|x| Complex::new(*x, 0.0))
        .collect();
    FftPlanner::new()
        .plan_fft_forward(buffer.len())
        .process(&mut buffer);
    let harmonics = std::array::from_fn(|h| 2.0 * buffer[h + 1].norm() / n);
    let max_force = s
        .mesh_force
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    let next = (s.displacement[0], s.velocity[0]);
    let point = SweepPoint {
        driver_speed_rpm: rpm,
        mesh_frequency_hz: speed / model.stiffness.period,
        dte_rms: rms,
        dte_peak_to_peak: hi - lo,
        dynamic_factor: max_force / model.force,
        separated: s.separated,
        harmonics,
        floquet: floquet_max_multiplier(model, speed, steps),
        periods: s.periods,
        converged: s.converged,
    };
    (point, next)
}

/// Up-sweep and down-sweep over `rpms` (ascending), run in parallel with each other; each
/// continues from the previous speed's steady state.
pub fn sweep(model: &MeshModel, rpms: &[f64]) -> (Vec<SweepPoint>, Vec<SweepPoint>) {
    let run = |order: Vec<f64>| {
        let mut state = (model.force / model.stiffness.mean(), 0.0);
        let mut out = Vec::with_capacity(order.len());
        for rpm in order {
            let (point, next) = analyse(model, rpm, state);
            state = next;
            out.push(point);
        }
        out
    };
    let (up, mut down) = rayon::join(
        || run(rpms.to_vec()),
        || run(rpms.iter().rev().copied().collect()),
    );
    down.reverse();
    (up, down)
}

/// Driver speeds [rpm] of the local maxima of `values` (strict, interior points).
pub fn peaks(rpms: &[f64], values: &[f64]) -> Vec<f64> {
    (1..values.len().saturating_sub(1))
        .filter(|&i| values[i] > values[i - 1] && values[i] >= values[i + 1])
        .map(|i| rpms[i])
        .collect()
}

/// Independent points in parallel (no continuation), for maps such as Floquet stability.
pub fn floquet_map(model: &MeshModel, rpms: &[f64]) -> Vec<f64> {
    rpms.par_iter()
        .map(|rpm| {
            let speed = rpm * 2.0 * std::f64::consts::PI / 60.0;
            floquet_max_multiplier(model, speed, steps_per_period(model, speed))
        })
        .collect()
}
