//! The speed-sweep study (`geardyn sweep`): the periodic steady state of the case's lumped model
//! at every speed (up and down), its resonances, separation ranges, strongest lines, and an
//! optional transient run-up through the same range.

use serde::Serialize;

use crate::case::Case;
use crate::lumped::{run_up, RunUp};
use crate::sweep::{self, SweepPoint, SweepProgress};

use super::lumped::{mode_frequencies_hz, setup, LumpedSetup};
use super::{RpmRange, StudyError};

/// Options of the study.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepOptions {
    pub rpm: RpmRange,
    /// Also run up through the range in this many seconds (a linear speed ramp).
    pub run_up_s: Option<f64>,
    /// Continue this interrupted sweep (made with the same case and speeds).
    pub resume: Option<SweepCheckpoint>,
}

/// What an interrupted sweep leaves (`sweep_checkpoint.json`): the case and speeds it ran
/// with and the points and states of both directions, so `--resume` finishes it with the
/// points an uninterrupted sweep gives.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SweepCheckpoint {
    /// The effective case file.
    pub case_text: String,
    pub rpm: Vec<f64>,
    pub progress: SweepProgress,
}

impl SweepCheckpoint {
    /// Where the sweep stopped, in words.
    pub fn describe(&self) -> String {
        let n = self.rpm.len();
        let (up, down) = (self.progress.up.len(), self.progress.down.len());
        let last = |points: &[SweepPoint]| {
            points.last().map_or(String::new(), |p| {
                format!(" (to {:.1} rpm)", p.driver_speed_rpm)
            })
        };
        format!(
            "stopped after {up} of {n} speeds up{} and {down} of {n} down{}",
            last(&self.progress.up),
            last(&self.progress.down)
        )
    }
}

/// How a sweep ended.
pub enum SweepRun {
    Done(Box<SweepStudy>),
    /// Stopped on request ([`crate::interrupt`]) before every speed was swept.
    Interrupted(SweepCheckpoint),
    /// A direction diverged (`progress.diverged` says where and why); the points before it are
    /// kept.
    Diverged(SweepCheckpoint),
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
    /// What the sweep's own response says the model cannot answer faithfully.
    pub warnings: Vec<String>,
    /// Where the `--run-up-s` transient diverged, the cause and the remedy.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub run_up_diverged: Option<String>,
    /// The model's checks of its own answer (its quasi-static response against the LTCA).
    pub self_checks: Vec<super::checks::Check>,
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

/// Sweeps the case's lumped model over `options.rpm`, from the start or from
/// `options.resume`; a stop request ([`crate::interrupt`]) ends it between two speeds.
pub fn run(case: &Case, options: &SweepOptions) -> Result<SweepRun, StudyError> {
    let started = std::time::Instant::now();
    let setup = setup(case)?;
    let rpms = options.rpm.0.clone();
    let model = &setup.model;
    let progress = match &options.resume {
        None => SweepProgress::start(model),
        Some(checkpoint) if !case.is_same_case(&checkpoint.case_text) => {
            return Err(StudyError::Input(
                "the interrupted sweep ran another case (or other --set values); run it again \
                 without --resume, or resume with the case it ran"
                    .into(),
            ))
        }
        Some(checkpoint) if checkpoint.rpm != rpms => {
            return Err(StudyError::Input(format!(
            "the interrupted sweep ran {} speeds from {} to {} rpm; resume it with the same --rpm",
            checkpoint.rpm.len(),
            checkpoint.rpm[0],
            checkpoint.rpm[checkpoint.rpm.len() - 1]
        )))
        }
        Some(checkpoint) => checkpoint.progress.clone(),
    };
    let sweep_started = std::time::Instant::now();
    let progress = sweep::continue_sweep(model, &rpms, progress, &crate::interrupt::stop_requested);
    if !progress.is_complete(rpms.len()) {
        let diverged = progress.diverged.is_some();
        let checkpoint = SweepCheckpoint {
            case_text: case.text.clone(),
            rpm: rpms,
            progress,
        };
        return Ok(if diverged {
            SweepRun::Diverged(checkpoint)
        } else {
            SweepRun::Interrupted(checkpoint)
        });
    }
    let (up, down) = progress.into_points();
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
            let run_up = run_up(
                model,
                to_speed(from),
                to_speed(to),
                duration,
                RUN_UP_SAMPLES,
            );
            Some((duration, run_up))
        }
        None => None,
    };
    // A diverged run-up is kept up to where it left the model's range; the sweep stands.
    let run_up_diverged = run_up
        .as_ref()
        .and_then(|(duration, r)| r.diverged_at.map(|t| (*duration, t)))
        .map(|(duration, t)| {
            let (from, to) = (rpms[0], rpms[rpms.len() - 1]);
            format!(
                "the run-up diverged at t = {t:.4} s ({:.0} rpm): the response left the model's \
                 range (1000 static deflections); runup.csv holds it up to there. Raise the \
                 damping (lumped.damping_ratio or --damping-ratio) or run up faster through the \
                 parametric-instability regions `geardyn stability` maps",
                from + (to - from) * t / duration
            )
        });
    let rms: Vec<f64> = up.iter().map(|p| p.dte_rms).collect();
    let resonance_rpm = sweep::peaks(&rpms, &rms);
    let primary_rpm_expected =
        super::lumped::speed_for_mesh_frequency(case, setup.natural_frequency_hz);
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
    let warnings = overload_warning(case, model.force, &up, &down)
        .into_iter()
        .collect();
    let summary = SweepSummary {
        case: case.name().to_string(),
        stiffness_source: model.mesh.source.clone(),
        drive: setup.drive,
        mean_stiffness_n_per_m: model.mesh.mean(),
        modes_hz: mode_frequencies_hz(model),
        effective_mass_kg: model.effective_mass(),
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
            // A speed that settled sits on a stable orbit (a multiplier a hair above 1 there is
            // the differences' noise at a fold); one that did not, on an unstable one.
            .filter(|p| !p.converged && p.floquet_orbit.is_some_and(|m| m > 1.0))
            .map(|p| p.driver_speed_rpm)
            .collect(),
        points: rpms.len(),
        all_converged: up.iter().chain(&down).all(|p| p.converged),
        wall_s,
        stiffness_wall_s: setup.stiffness_wall_s,
        total_wall_s: started.elapsed().as_secs_f64(),
        strongest_peaks: strongest,
        model: setup.model_note.clone(),
        warnings,
        run_up_diverged,
        self_checks: setup.self_checks.clone(),
    };
    Ok(SweepRun::Done(Box::new(SweepStudy {
        setup,
        rpms,
        up,
        down,
        run_up,
        primary_rpm_expected,
        summary,
    })))
}

/// A warning where the largest dynamic mesh force of the sweep, carried by one tooth pair at the
/// pitch point, gives a Hertzian pressure above [`crate::case::HERTZ_PRESSURE_LIMIT`]
/// ([`Case::hertz_pressure_at`]): the flanks may yield there, and the lumped model's linear
/// contact (and any response it gives near that speed) no longer describes the gears. A nominal
/// figure: the pitch point is in single-tooth contact on the paper pair (ε = 1.69), the lowest
/// point of single contact has smaller radii of curvature, and a back-flank force is not in the
/// dynamic factor. The static load alone is the case's own warning.
pub fn overload_warning(
    case: &Case,
    static_force: f64,
    up: &[SweepPoint],
    down: &[SweepPoint],
) -> Option<String> {
    let worst = up
        .iter()
        .chain(down)
        .max_by(|a, b| a.dynamic_factor.total_cmp(&b.dynamic_factor))?;
    let pressure = case.hertz_pressure_at(static_force * worst.dynamic_factor);
    (pressure > crate::case::HERTZ_PRESSURE_LIMIT).then(|| {
        format!(
            "at {:.0} rpm the dynamic mesh force reaches {:.1} × the static one, a nominal \
             Hertzian pressure of {:.1} GPa (one tooth pair at the pitch point), above the 3 GPa \
             limit the case check uses (twice the allowable contact stress of the strongest \
             case-hardened gear steels, ISO 6336-5): the flanks may yield, and the linear \
             contact law of the lumped model no longer describes the teeth there; near that \
             speed its numbers are the model's, not the gears' (more damping or backlash bounds \
             the response)",
            worst.driver_speed_rpm,
            worst.dynamic_factor,
            pressure * 1e-9
        )
    })
}
