//! The speed-sweep study (`geardyn sweep`): the periodic steady state of the case's lumped model
//! at every speed (up and down), its resonances, separation ranges, strongest lines, and an
//! optional transient run-up through the same range.

use serde::Serialize;

use crate::case::Case;
use crate::lumped::{run_up, RunUp};
use crate::sweep::{self, SweepPoint};

use super::lumped::{mode_frequencies_hz, setup, LumpedSetup};
use super::{RpmRange, StudyError};

/// Options of the study.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepOptions {
    pub rpm: RpmRange,
    /// Also run up through the range in this many seconds (a linear speed ramp).
    pub run_up_s: Option<f64>,
}

/// Samples kept of the run-up.
pub const RUN_UP_SAMPLES: usize = 200_000;

/// One line of the strongest spectral lines over the whole up-sweep.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SpectralLine {
    pub driver_rpm: f64,
    pub frequency_hz: f64,
    pub amplitude_um: f64,
}

/// Headline numbers (`summary.json`).
#[derive(Debug, Clone, Serialize)]
pub struct SweepSummary {
    pub case: String,
    pub stiffness_source: String,
    pub drive: crate::lumped::Drive,
    pub mean_stiffness_n_per_m: f64,
    pub modes_hz: Vec<f64>,
    pub effective_mass_kg: f64,
    pub inertia_kg_mm2: [f64; 2],
    pub natural_frequency_hz: f64,
    pub damping_ratio: f64,
    pub torque_nm: f64,
    /// The response peak nearest f_mesh = f_n.
    pub primary_resonance_rpm: Option<f64>,
    pub resonance_rpm: Vec<f64>,
    pub max_dynamic_factor: f64,
    pub separation_rpm_ranges: Vec<(f64, f64)>,
    pub unstable_rpm: Vec<f64>,
    pub points: usize,
    pub all_converged: bool,
    pub wall_s: f64,
    pub stiffness_wall_s: f64,
    pub total_wall_s: f64,
    pub strongest_peaks: Vec<SpectralLine>,
    pub model: String,
}

/// The study's result.
pub struct SweepStudy {
    pub setup: LumpedSetup,
    pub rpms: Vec<f64>,
    pub up: Vec<SweepPoint>,
    pub down: Vec<SweepPoint>,
    /// The run-up, with its duration [s].
    pub run_up: Option<(f64, RunUp)>,
    /// Driver speed where f_mesh = f_n [rpm].
    pub primary_rpm_expected: f64,
    pub summary: SweepSummary,
}

/// Sweeps the case's lumped model over `options.rpm`.
pub fn run(case: &Case, options: &SweepOptions) -> Result<SweepStudy, StudyError> {
    let started = std::time::Instant::now();
    let setup = setup(case)?;
    let rpms = options.rpm.0.clone();
    let model = &setup.model;
    let sweep_started = std::time::Instant::now();
    let (up, down) = sweep::sweep(model, &rpms);
    let wall_s = sweep_started.elapsed().as_secs_f64();
    let run_up = match options.run_up_s {
        Some(duration) if !(duration > 0.0 && duration.is_finite()) => {
            return Err(StudyError::Input(format!(
                "--run-up-s {duration} is invalid: give a duration > 0 in seconds"
            )))
        }
        Some(duration) => {
            let to_speed = |rpm: f64| rpm * std::f64::consts::TAU / 60.0;
            let (from, to) = (rpms[0], rpms[rpms.len() - 1]);
            Some((
                duration,
                run_up(
                    model,
                    to_speed(from),
                    to_speed(to),
                    duration,
                    RUN_UP_SAMPLES,
                ),
            ))
        }
        None => None,
    };
    let rms: Vec<f64> = up.iter().map(|p| p.dte_rms).collect();
    let resonance_rpm = sweep::peaks(&rpms, &rms);
    let z1 = case.pair.gears[0].teeth() as f64;
    let primary_rpm_expected = setup.natural_frequency_hz * 60.0 / z1;
    let primary = resonance_rpm.iter().copied().min_by(|a, b| {
        (a - primary_rpm_expected)
            .abs()
            .total_cmp(&(b - primary_rpm_expected).abs())
    });
    let mut separation_ranges: Vec<(f64, f64)> = Vec::new();
    for p in &up {
        if p.separated {
            match separation_ranges.last_mut() {
                Some(r) if (p.driver_speed_rpm - r.1) <= (rpms[1] - rpms[0]) * 1.0001 => {
                    r.1 = p.driver_speed_rpm
                }
                _ => separation_ranges.push((p.driver_speed_rpm, p.driver_speed_rpm)),
            }
        }
    }
    let mut strongest: Vec<SpectralLine> = up
        .iter()
        .flat_map(|p| {
            p.peaks.iter().map(move |(hz, a)| SpectralLine {
                driver_rpm: p.driver_speed_rpm,
                frequency_hz: *hz,
                amplitude_um: a * 1e6,
            })
        })
        .collect();
    strongest.sort_by(|a, b| b.amplitude_um.total_cmp(&a.amplitude_um));
    strongest.truncate(10);
    let summary = SweepSummary {
        case: case.name().to_string(),
        stiffness_source: model.mesh.source.clone(),
        drive: setup.drive,
        mean_stiffness_n_per_m: model.mesh.mean(),
        modes_hz: mode_frequencies_hz(model),
        effective_mass_kg: model.effective_mass,
        inertia_kg_mm2: setup.inertias.map(|i| i * 1e6),
        natural_frequency_hz: setup.natural_frequency_hz,
        damping_ratio: setup.damping_ratio,
        torque_nm: setup.torque,
        primary_resonance_rpm: primary,
        resonance_rpm,
        max_dynamic_factor: up
            .iter()
            .chain(&down)
            .map(|p| p.dynamic_factor)
            .fold(0.0, f64::max),
        separation_rpm_ranges: separation_ranges,
        unstable_rpm: up
            .iter()
            .filter(|p| p.floquet > 1.0)
            .map(|p| p.driver_speed_rpm)
            .collect(),
        points: rpms.len(),
        all_converged: up.iter().chain(&down).all(|p| p.converged),
        wall_s,
        stiffness_wall_s: setup.stiffness_wall_s,
        total_wall_s: started.elapsed().as_secs_f64(),
        strongest_peaks: strongest,
        model: setup.model_note.clone(),
    };
    Ok(SweepStudy {
        setup,
        rpms,
        up,
        down,
        run_up,
        primary_rpm_expected,
        summary,
    })
}
