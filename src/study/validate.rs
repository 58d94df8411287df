//! Validation studies too wide for the test suite (`geardyn validate STUDY`).
//!
//! **integrators**: where each fixed-step scheme of the lumped model fails — stability and 1 %
//! frequency-accuracy limits in ωh, predicted against observed, and the order of convergence
//! with and without tooth separation — on the case's effective mass and mean mesh stiffness,
//! with a cosine unloaded TE of 0.2 × the static deflection (stays in contact) and of 2 × with
//! 100 µm backlash (separates every mesh period), f_mesh = 0.7 f_n.

use serde::Serialize;

use crate::case::Case;
use crate::lumped::schemes::{self, SchemeReport};
use crate::stiffness::{MeshStiffness, PeriodicTable};

use super::lumped::setup;
use super::StudyError;

/// Mesh periods integrated per run.
pub const PERIODS: usize = 20;
/// f_mesh / f_n of the test speed.
pub const MESH_OVER_NATURAL: f64 = 0.7;

/// Headline numbers (`summary.json`).
#[derive(Debug, Clone, Serialize)]
pub struct IntegratorSummary {
    pub case: String,
    pub study: &'static str,
    pub effective_mass_kg: f64,
    pub mean_stiffness_n_per_m: f64,
    pub natural_frequency_hz: f64,
    pub damping_ratio: f64,
    pub mesh_frequency_over_natural: f64,
    pub periods: usize,
    pub errors: &'static str,
    pub schemes: Vec<SchemeReport>,
    pub wall_s: f64,
}

/// Runs the integrator study on the case's lumped model (1 DOF).
pub fn integrators(case: &Case) -> Result<IntegratorSummary, StudyError> {
    let setup = setup(case)?;
    if setup.model.bearings.is_some() {
        return Err(StudyError::Input(
            "the integrator study covers the 1-DOF model: drop --bearings (or bearings = true in the case)".into(),
        ));
    }
    let period = setup.model.mesh.period();
    let k_mean = setup.model.mesh.mean();
    let static_deflection = setup.model.force / k_mean;
    let variant = |te_ratio: f64, backlash: Option<f64>| {
        let mut m = setup.model.clone();
        m.mesh = MeshStiffness::from_tables(
            "mean stiffness, cosine unloaded TE",
            None,
            PeriodicTable::constant(period, k_mean),
            PeriodicTable::from_fn(period, 1 << 14, |t| {
                te_ratio * static_deflection * (std::f64::consts::TAU * t / period).cos()
            }),
        );
        m.backlash = backlash;
        m
    };
    let smooth = variant(0.2, None);
    let separating = variant(2.0, Some(100e-6));
    let speed = MESH_OVER_NATURAL * smooth.natural_frequency() * period / std::f64::consts::TAU;
    let started = std::time::Instant::now();
    let table = schemes::failure_table(&smooth, &separating, speed, PERIODS);
    Ok(IntegratorSummary {
        case: case.name().to_string(),
        study: "integrators",
        effective_mass_kg: setup.model.effective_mass,
        mean_stiffness_n_per_m: k_mean,
        natural_frequency_hz: setup.natural_frequency_hz,
        damping_ratio: setup.damping_ratio,
        mesh_frequency_over_natural: MESH_OVER_NATURAL,
        periods: PERIODS,
        errors: "end state after 20 mesh periods vs adaptive Dormand-Prince (tolerance 1e-11), in units of the static deflection, at 32 steps per natural period; orders are least-squares slopes over 16, 32, 64, 128 steps per natural period",
        schemes: table,
        wall_s: started.elapsed().as_secs_f64(),
    })
}
