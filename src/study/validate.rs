//! Validation studies too wide for the test suite (`geardyn validate STUDY`).
//!
//! **integrators**: where each fixed-step scheme of the lumped model fails — stability and 1 %
//! frequency-accuracy limits in ωh, predicted against observed, and the order of convergence
//! with and without tooth separation — on the case's effective mass and mean mesh stiffness,
//! with a cosine unloaded TE of 0.2 × the static deflection (stays in contact) and of 2 × with
//! 100 µm backlash (separates every mesh period), f_mesh = 0.7 f_n. Then the case's own model
//! (its k(θ), e(θ) and backlash; zero on the paper pair, where the back flanks engage as the
//! drive flanks open) swept up across the primary resonance,
//! from 0.85 to 1.08 of the speed where f_mesh = f_n, at 1, 2, 4 and 8 × the sweep's RK4 steps:
//! the sweep's largest dynamic factor, and any divergence, must not move as the step halves
//! for them to be the model's rather than the integrator's (RK4 straddles the contact law's
//! kinks there).
//!
//! **mass-scaling**: an explicit FE scene run twice, with the case's low-speed mass scaling and
//! without it, compared on what a quasi-static analysis reads: over the common statistics window
//! (from the later of the two starts to the end), the DTE mean and peak-to-peak through one
//! low-pass (the longer of the two mesh-mode periods, the scaled run's), k(θ) = ΣW/Σδ bin by
//! bin and the static TE each k(θ) gives at the load; also each run's own k(θ) table as `stiffness.csv` has it (over its own window), the raw
//! DTE peak-to-peak (which keeps the scaled mesh mode's ringing), and the cost of each.

use serde::Serialize;

use crate::case::Case;
use crate::explicit::scene::{
    analyse_dte, bin_difference, common_bins, paired_bins, static_te, DteAnalysis, History,
    StaticTe,
};
use crate::geometry::GearPair;
use crate::lumped::schemes::{self, SchemeReport};
use crate::stiffness::{MeshStiffness, PeriodicTable};
use crate::sweep::RefinedUpSweep;
use rayon::prelude::*;

use super::fe::FeStudy;
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
    /// The case's own model swept up across the primary resonance at 1, 2, 4 and 8 × the
    /// sweep's steps ([`crate::sweep::refined_up_sweep`]), from and to these speeds [rpm].
    pub resonance_sweep_rpm: (f64, f64),
    pub resonance_sweep: Vec<RefinedUpSweep>,
    pub wall_s: f64,
}

/// The step refinements of the resonance sweep.
pub const REFINEMENTS: [usize; 4] = [1, 2, 4, 8];
/// The resonance sweep's range, as fractions of the speed where f_mesh = f_n, and its speeds.
pub const RESONANCE_RANGE: (f64, f64) = (0.85, 1.08);
pub const RESONANCE_SPEEDS: usize = 116;

/// Runs the integrator study on the case's lumped model (1 DOF).
pub fn integrators(case: &Case) -> Result<IntegratorSummary, StudyError> {
    let setup = setup(case)?;
    if setup.model.structure.dofs != 1 {
        return Err(StudyError::Input(format!(
            "the integrator study covers the 1-DOF model, and this case's has {} coordinates ({}): drop --bearings, the shafts, or use the torque drive",
            setup.model.structure.dofs,
            setup.model.structure.names.join(", ")
        )));
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
        // The schemes are held to theory on this linear law, not the case's force law.
        m.force_law = None;
        m.back_force_law = None;
        m
    };
    let smooth = variant(0.2, None);
    let separating = variant(2.0, Some(100e-6));
    let speed = MESH_OVER_NATURAL * smooth.natural_frequency() * period / std::f64::consts::TAU;
    let started = std::time::Instant::now();
    let table = schemes::failure_table(&smooth, &separating, speed, PERIODS);
    let resonance_rpm = super::lumped::speed_for_mesh_frequency(case, setup.natural_frequency_hz);
    let (from, to) = (
        RESONANCE_RANGE.0 * resonance_rpm,
        RESONANCE_RANGE.1 * resonance_rpm,
    );
    let rpms: Vec<f64> = (0..RESONANCE_SPEEDS)
        .map(|i| from + (to - from) * i as f64 / (RESONANCE_SPEEDS - 1) as f64)
        .collect();
    let resonance_sweep = REFINEMENTS
        .par_iter()
        .map(|&r| crate::sweep::refined_up_sweep(&setup.model, &rpms, r))
        .collect();
    Ok(IntegratorSummary {
        case: case.name().to_string(),
        study: "integrators",
        effective_mass_kg: setup.model.effective_mass(),
        mean_stiffness_n_per_m: k_mean,
        natural_frequency_hz: setup.natural_frequency_hz,
        damping_ratio: setup.damping_ratio,
        mesh_frequency_over_natural: MESH_OVER_NATURAL,
        periods: PERIODS,
        errors: "end state after 20 mesh periods vs adaptive Dormand-Prince (tolerance 1e-11), in units of the static deflection, at 32 steps per natural period; orders are least-squares slopes over 16, 32, 64, 128 steps per natural period",
        schemes: table,
        resonance_sweep_rpm: (from, to),
        resonance_sweep,
        wall_s: started.elapsed().as_secs_f64(),
    })
}

/// One run of the mass-scaling study: what it cost and what it read over the common window.
#[derive(Debug, Clone, Serialize)]
pub struct MassScalingRun {
    pub mass_scaling_factor: f64,
    /// The mesh mode the run had (scaled or not) [Hz].
    pub mesh_mode_hz: f64,
    pub dt_s: f64,
    pub steps: usize,
    /// The explicit integration's wall time, and the run's with its LTCA references [s].
    pub wall_s: f64,
    pub total_wall_s: f64,
    pub energy_error_rel_transmitted: f64,
    pub dte_mean_rad: f64,
    pub dte_peak_to_peak_rad: f64,
    pub dte_lowpass_mean_rad: f64,
    pub dte_lowpass_peak_to_peak_rad: f64,
    /// The static TE its k(θ) gives at the load over the common window (mean, peak-to-peak).
    pub static_te_mean_rad: f64,
    pub static_te_peak_to_peak_rad: f64,
    /// Mean of k(θ) over the common window, and of the run's own table (stiffness.csv).
    pub mesh_stiffness_mean_n_per_m: f64,
    pub own_table_mesh_stiffness_mean_n_per_m: f64,
}

/// Headline numbers of the mass-scaling study (`summary.json`); every `_rel` is
/// scaled / unscaled − 1, every `max_abs_rel` the worst bin's |k_scaled/k_unscaled − 1|.
#[derive(Debug, Clone, Serialize)]
pub struct MassScalingSummary {
    pub case: String,
    pub study: &'static str,
    pub scene: String,
    /// The common statistics window [s] and the common low-pass span [s].
    pub window_s: [f64; 2],
    pub lowpass_span_s: f64,
    pub scaled: MassScalingRun,
    pub unscaled: MassScalingRun,
    pub dte_mean_rel: f64,
    pub dte_peak_to_peak_rel: f64,
    pub dte_lowpass_mean_rel: f64,
    pub dte_lowpass_peak_to_peak_rel: f64,
    pub static_te_mean_rel: f64,
    pub static_te_peak_to_peak_rel: f64,
    pub stiffness_mean_rel: f64,
    pub stiffness_max_abs_rel: f64,
    pub stiffness_bins: usize,
    /// The two runs' own k(θ) tables (each over its own statistics window).
    pub own_table_stiffness_mean_rel: f64,
    pub own_table_stiffness_max_abs_rel: f64,
    pub own_table_bins: usize,
    /// Unscaled over scaled wall time of the explicit integration.
    pub speedup: f64,
}

/// The study's result: the summary and k per bin, (driver rotation from the pitch-point
/// position [rad], k scaled, k unscaled) over the common window [N/m].
pub struct MassScalingStudy {
    pub summary: MassScalingSummary,
    pub bins: Vec<(f64, f64, f64)>,
}

/// A run of a scene as the comparison reads it.
#[derive(Clone, Copy)]
pub struct RunRecord<'a> {
    pub history: &'a History,
    /// The relief's unloaded TE along the line of action [m] against the driver rotation.
    pub unloaded_te: &'a PeriodicTable,
    /// Where the run's own statistics start [s].
    pub statistics_start: f64,
    pub driven_inertia: f64,
}

impl<'a> From<&'a FeStudy> for RunRecord<'a> {
    fn from(study: &'a FeStudy) -> Self {
        RunRecord {
            history: &study.history,
            unloaded_te: &study.unloaded_te,
            statistics_start: study.summary.statistics_start_s,
            driven_inertia: study.summary.step.driven_inertia_kg_m2,
        }
    }
}

/// Two runs of one scene analysed alike: each on its own (its mesh mode's low-pass, its
/// window) and both over the common window, the DTE through one low-pass.
pub struct QuasiStaticComparison {
    pub own: [DteAnalysis; 2],
    pub common: [DteAnalysis; 2],
    /// Start of the common window (the later start) and the low-pass span (the longer of the
    /// two mesh-mode periods) [s].
    pub start: f64,
    pub span: f64,
}

/// Analyses two runs of one scene of `pair` under load `torque` alike; None if either has no
/// window with a whole low-pass span (a run too short).
pub fn compare_quasi_static(
    pair: &GearPair,
    torque: f64,
    runs: [RunRecord; 2],
) -> Option<QuasiStaticComparison> {
    let analyse = |r: &RunRecord, start: f64, span: Option<f64>| {
        let a = analyse_dte(
            r.history,
            pair,
            r.driven_inertia,
            torque,
            start,
            r.unloaded_te,
            span,
        )?;
        (a.lowpass.is_some() && a.static_te.is_some()).then_some(a)
    };
    let own = [
        analyse(&runs[0], runs[0].statistics_start, None)?,
        analyse(&runs[1], runs[1].statistics_start, None)?,
    ];
    let span = own
        .iter()
        .filter_map(|a| a.filter.map(|f| f.period_s))
        .fold(0.0, f64::max);
    let start = runs[0].statistics_start.max(runs[1].statistics_start);
    let common = [
        analyse(&runs[0], start, Some(span))?,
        analyse(&runs[1], start, Some(span))?,
    ];
    Some(QuasiStaticComparison {
        own,
        common,
        start,
        span,
    })
}

/// Checks that mass scaling applied to the scaled run of the study (so the unscaled one is not
/// the same run again).
pub fn check_scaled(scaled: &FeStudy) -> Result<(), StudyError> {
    let factor = scaled.summary.mass_scaling.factor;
    if factor > 1.0 {
        return Ok(());
    }
    Err(StudyError::Input(format!(
        "scene {:?} runs unscaled (mass-scaling factor {factor}: 5 x margin x the mesh frequency is above the mesh mode, or fe.mass_scaling is off), so there is nothing to compare: pick a low-speed scene",
        scaled.scene.name
    )))
}

/// Compares a scene run with mass scaling (`scaled`) against the same scene without
/// (`unscaled`); see the module doc. Both must be runs of one scene of `pair` at one output
/// interval.
pub fn mass_scaling(
    case_name: &str,
    pair: &GearPair,
    scaled: &FeStudy,
    unscaled: &FeStudy,
) -> Result<MassScalingStudy, StudyError> {
    let too_short = || {
        StudyError::Input(format!(
            "a run of scene {:?} has no statistics window with a whole low-pass span (or no bin with contact): lengthen the scene's duration_s",
            scaled.scene.name
        ))
    };
    let c = compare_quasi_static(pair, scaled.scene.torque, [scaled.into(), unscaled.into()])
        .ok_or_else(too_short)?;
    let [a, b] = &c.common;
    // The static TE of each over the bins both have.
    let te = |study: &FeStudy, bins: Vec<Option<f64>>| {
        static_te(pair, study.scene.torque, &bins, &study.unloaded_te).ok_or_else(too_short)
    };
    let te_scaled = te(scaled, common_bins(&a.stiffness_bins, &b.stiffness_bins))?;
    let te_unscaled = te(unscaled, common_bins(&b.stiffness_bins, &a.stiffness_bins))?;
    let (stiffness_mean_rel, stiffness_max_abs_rel, stiffness_bins) =
        bin_difference(&a.stiffness_bins, &b.stiffness_bins).ok_or_else(too_short)?;
    let (own_mean, own_worst, own_bins) = bin_difference(
        &c.own[0].stiffness_bins,
        &c.own[1].stiffness_bins,
    )
    .unwrap_or((f64::NAN, f64::NAN, 0));
    let run = |study: &FeStudy, common: &DteAnalysis, own: &DteAnalysis, te: StaticTe| {
        let s = &study.summary;
        let lowpass = common
            .lowpass
            .expect("compare_quasi_static keeps low-passed runs");
        MassScalingRun {
            mass_scaling_factor: s.mass_scaling.factor,
            mesh_mode_hz: s.mass_scaling.scaled_mesh_mode_hz,
            dt_s: s.step.dt_s,
            steps: s.steps,
            wall_s: s.wall_s,
            total_wall_s: s.total_wall_s,
            energy_error_rel_transmitted: s.energy_error_rel_transmitted,
            dte_mean_rad: common.dte_mean_rad,
            dte_peak_to_peak_rad: common.dte_peak_to_peak_rad,
            dte_lowpass_mean_rad: lowpass.mean_rad,
            dte_lowpass_peak_to_peak_rad: lowpass.peak_to_peak_rad,
            static_te_mean_rad: te.mean_rad,
            static_te_peak_to_peak_rad: te.peak_to_peak_rad,
            mesh_stiffness_mean_n_per_m: common.mesh_stiffness_mean_n_per_m,
            own_table_mesh_stiffness_mean_n_per_m: own.mesh_stiffness_mean_n_per_m,
        }
    };
    let run_scaled = run(scaled, a, &c.own[0], te_scaled);
    let run_unscaled = run(unscaled, b, &c.own[1], te_unscaled);
    let rel = |f: fn(&MassScalingRun) -> f64| f(&run_scaled) / f(&run_unscaled) - 1.0;
    let bins = paired_bins(
        pair.gears[0].angular_pitch(),
        &a.stiffness_bins,
        &b.stiffness_bins,
    );
    let summary = MassScalingSummary {
        case: case_name.to_string(),
        study: "mass-scaling",
        scene: scaled.scene.name.clone(),
        window_s: [a.window.0, a.window.1],
        lowpass_span_s: c.span,
        dte_mean_rel: rel(|r| r.dte_mean_rad),
        dte_peak_to_peak_rel: rel(|r| r.dte_peak_to_peak_rad),
        dte_lowpass_mean_rel: rel(|r| r.dte_lowpass_mean_rad),
        dte_lowpass_peak_to_peak_rel: rel(|r| r.dte_lowpass_peak_to_peak_rad),
        static_te_mean_rel: rel(|r| r.static_te_mean_rad),
        static_te_peak_to_peak_rel: rel(|r| r.static_te_peak_to_peak_rad),
        stiffness_mean_rel,
        stiffness_max_abs_rel,
        stiffness_bins,
        own_table_stiffness_mean_rel: own_mean,
        own_table_stiffness_max_abs_rel: own_worst,
        own_table_bins: own_bins,
        speedup: run_unscaled.wall_s / run_scaled.wall_s,
        scaled: run_scaled,
        unscaled: run_unscaled,
    };
    Ok(MassScalingStudy { summary, bins })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::explicit::scene::STIFFNESS_BINS;

    /// A synthetic 60 rpm record: k(θ) = k̄ s_k (1 + 0.2 cos 2πθ/p), e(θ) = 5 µm sin 2πθ/p,
    /// W = F(1 + 0.05 sin 2πθ/p), the deflection δ = W/k with 10 % free ringing of a mesh mode
    /// at `mode_hz` and the force with it (W = kδ, as the contact makes them), θ_DTE =
    /// (δ + e)/R_b2; the inertia is the one whose mode that is on k̄ s_k.
    fn record(mode_hz: f64, stiffness_scale: f64) -> (History, PeriodicTable, f64) {
        let pair = crate::samples::paper36_pair();
        let rb2 = pair.gears[1].base_radius;
        let pitch = pair.gears[0].angular_pitch();
        let k_mean = 4.0e8 * stiffness_scale;
        let force = 143.6 / rb2;
        let omega = std::f64::consts::TAU * mode_hz;
        let inertia = k_mean * rb2 * rb2 / (omega * omega);
        let phase = |theta: f64| std::f64::consts::TAU * theta / pitch;
        let e = |theta: f64| 5e-6 * phase(theta).sin();
        let mut history = History::default();
        for i in 0..6000 {
            let t = i as f64 * 1e-5;
            let theta = std::f64::consts::TAU * t;
            let w = force * (1.0 + 0.05 * phase(theta).sin());
            let k = k_mean * (1.0 + 0.2 * phase(theta).cos());
            history.time.push(t);
            history.driver_rotation.push(theta);
            let delta = w / k * (1.0 + 0.1 * (omega * t).sin());
            history.mesh_force.push(k * delta);
            history.dte.push((delta + e(theta)) / rb2);
        }
        (history, PeriodicTable::from_fn(pitch, 4096, e), inertia)
    }

    fn run<'a>(r: &'a (History, PeriodicTable, f64), start: f64) -> RunRecord<'a> {
        RunRecord {
            history: &r.0,
            unloaded_te: &r.1,
            statistics_start: start,
            driven_inertia: r.2,
        }
    }

    /// The mass-scaled mode (360 Hz) and the unscaled one (3 120 Hz) ringing on the same
    /// quasi-static record: over the common window (from the later start) k agrees within
    /// 0.1 % at every bin (the ringing only reweights the samples of a bin, over which k moves
    /// by 2 %) and the DTE means through the common low-pass (the scaled mode's period) within
    /// 0.1 % — the moving average over 8.7 periods of the fast ringing passes
    /// |sin(8.7π)|/(278 sin(π/32)) = 3.2 % of its 10 %, and that alternates. A record 2 %
    /// stiffer reads −2 % (±0.2 %): the comparison sees what it must.
    #[test]
    fn one_low_pass_compares_a_scaled_and_an_unscaled_run() {
        let pair = crate::samples::paper36_pair();
        let scaled = record(360.0, 1.0);
        let mut unscaled = record(3120.0, 1.0);
        // Before the common start the unscaled record's DTE is off by 20 % (k by −17 %): only
        // a window of its own would see it.
        for (t, d) in unscaled.0.time.iter().zip(unscaled.0.dte.iter_mut()) {
            if *t < 0.005 {
                *d *= 1.2;
            }
        }
        let c = compare_quasi_static(&pair, 143.6, [run(&scaled, 0.006), run(&unscaled, 0.002)])
            .unwrap();
        assert_eq!(c.start, 0.006);
        for a in &c.common {
            assert!((a.window.0 - 0.006).abs() < 1e-9, "{:?}", a.window);
            assert_eq!(a.filter.unwrap().period_s, c.span);
        }
        // Each run's own low-pass spans its mesh mode on its mean stiffness T/(θ̄R_b2² − …),
        // 1.02 × k̄'s period here (the mean of 1/(1 + 0.2 cos) is 1/√0.96); the common one is
        // the longer, the scaled run's.
        let period = |i: usize| c.own[i].filter.unwrap().period_s;
        assert!((period(0) * 360.0 - 1.0).abs() < 0.02, "{}", period(0));
        assert!((period(1) * 3120.0 - 1.0).abs() < 0.02, "{}", period(1));
        assert_eq!(c.span, period(0));
        let (mean, worst, bins) =
            bin_difference(&c.common[0].stiffness_bins, &c.common[1].stiffness_bins).unwrap();
        assert_eq!(bins, STIFFNESS_BINS);
        assert!(mean.abs() < 1e-4 && worst < 1e-3, "{mean} {worst}");
        let lp = |a: &DteAnalysis| a.lowpass.unwrap();
        let dte = lp(&c.common[0]).mean_rad / lp(&c.common[1]).mean_rad - 1.0;
        assert!(dte.abs() < 1e-3, "{dte}");
        let stiffer = record(3120.0, 1.02);
        let c = compare_quasi_static(&pair, 143.6, [run(&scaled, 0.006), run(&stiffer, 0.002)])
            .unwrap();
        let (mean, _, _) =
            bin_difference(&c.common[0].stiffness_bins, &c.common[1].stiffness_bins).unwrap();
        assert!((mean - (1.0 / 1.02 - 1.0)).abs() < 2e-3, "{mean}");
    }
}
