//! Accuracy against cost (`geardyn compare --chart`): every way geardyn has to the pair's mesh
//! stiffness, charted by its wall time against its error on four questions a gear engineer
//! asks, each measured against the finest explicit FE run given.
//!
//! # Methods (each a k(θ), e(θ) source)
//! LTCA at three mesh levels (timed here), explicit FE stiffness scenes (read from their run
//! folders: mesh level, mass scaling and wall time), ISO 6336-1 method B and the
//! potential-energy method (timed here).
//!
//! # Questions (each answered from the method's k(θ), the same way for every method)
//! * mean stiffness k̄;
//! * peak-to-peak of the static TE the stiffness gives at the load, (T/(r_b2 k) + e)/r_b2;
//! * first resonance speed: f_mesh = f_n of the speed-driven pair with elastic bodies (the
//!   FE's lumped twin, [`super::compare::lumped_twin`]: the bodies' twist is taken out of the
//!   hub-to-hub LTCA and FE stiffness and given to the bodies; ISO and potential energy do not
//!   hold it, so it is put in series first), n = 60 f_n / z₁ — its error follows
//!   from the mean stiffness's (√k), so it is about half of it;
//! * DTE amplitude at the mesh frequency at the primary FE run's speed
//!   ([`super::compare::primary_run`], 3000 rpm for paper36): the lumped model's periodic
//!   steady state on that k(θ), against the explicit FE's own DTE there.
//!
//! The cost of a lumped answer is the cost of its k(θ) plus the lumped solve. The reference is
//! the finest unscaled FE run (ties broken by the longest wall time); the DTE reference is the
//! explicit run at speed.

use serde::Serialize;

use crate::case::Case;
use crate::lumped::{steady_state, Drive};
use crate::signal::{amplitude_spectrum, harmonic_amplitudes};
use crate::stiffness::{self, potential_energy, MeshStiffness};

use super::compare::{lumped_twin, FeDte};
use super::lumped::gear_inertias;
use super::{Progress, StudyError};
use crate::explicit::scene::static_te;

/// An explicit FE stiffness run read from its folder.
#[derive(Debug, Clone)]
pub struct FeStiffnessRun {
    pub fine_mm: f64,
    pub mass_scaling_factor: f64,
    pub stiffness: MeshStiffness,
    pub wall_s: f64,
}

/// One method's answers, cost and errors.
#[derive(Debug, Clone, Serialize)]
pub struct MethodPoint {
    pub method: String,
    pub family: &'static str,
    pub wall_s: f64,
    pub mean_stiffness_n_per_m: f64,
    pub static_te_peak_to_peak_rad: f64,
    pub resonance_rpm: f64,
    pub dte_mesh_amplitude_rad: f64,
    /// |answer / reference − 1| per question.
    pub mean_stiffness_error: f64,
    pub static_te_error: f64,
    pub resonance_error: f64,
    pub dte_amplitude_error: f64,
}

/// The chart's data.
#[derive(Debug, Clone, Serialize)]
pub struct AccuracyCost {
    pub case: String,
    pub reference: String,
    pub dte_reference: String,
    pub speed_rpm: f64,
    pub reference_dte_mesh_amplitude_rad: f64,
    pub points: Vec<MethodPoint>,
}

/// LTCA mesh levels: flank / body element sizes [mm].
pub const LTCA_LEVELS: [(f64, f64); 3] = [(1.0, 3.0), (0.5, 1.5), (0.2, 1.5)];

/// The explicit stiffness runs the chart makes when none are given: flank element size [mm]
/// and mass scaling.
pub const CHART_RUNS: [(f64, bool); 4] = [(1.0, true), (1.0, false), (0.7, true), (0.7, false)];

/// The case overrides of one of [`CHART_RUNS`], and its folder name.
pub fn chart_run(fine_mm: f64, scaled: bool) -> (Vec<crate::case::Override>, String) {
    use crate::case::Override;
    let tag = if scaled { "scaled" } else { "unscaled" };
    (
        vec![
            Override::set("fe.explicit_fine_element_mm", fine_mm),
            Override::set("fe.mass_scaling", scaled),
        ],
        format!("chart-fe-{fine_mm}-{tag}"),
    )
}

/// LTCA positions per base pitch for the chart.
const POSITIONS: usize = 64;

struct Answers {
    mean: f64,
    static_te_pp: f64,
    resonance_rpm: f64,
    dte_amplitude: f64,
    lumped_s: f64,
}

/// The four answers from one k(θ).
fn answers(
    case: &Case,
    mesh: &MeshStiffness,
    holds_body_twist: bool,
    torque: f64,
    speed_rpm: f64,
) -> Result<Answers, StudyError> {
    let started = std::time::Instant::now();
    let pair = &case.pair;
    let rb = [pair.gears[0].base_radius, pair.gears[1].base_radius];
    // The FE's lumped twin: speed drive, elastic bodies. A hub-to-hub stiffness (LTCA, FE)
    // holds the bodies' twist, which the twin takes out and gives the bodies; ISO 6336 and the
    // potential-energy method stop at the tooth's foundation, so the twist is put in series
    // first (a negative compliance "taken out"). A k too soft to hold the twist gets rigid gears.
    let twist: f64 = super::compare::body_twist(case).iter().sum();
    let hub_to_hub = match holds_body_twist {
        true => mesh.clone(),
        false => mesh
            .without_series_compliance(-twist)
            .expect("adding a compliance keeps k positive"),
    };
    let m = Drive::Speed.effective_mass(gear_inertias(case), rb);
    let damping = 2.0 * case.fe.mesh_damping_ratio * (hub_to_hub.mean() * m).sqrt();
    let model = lumped_twin(
        case,
        hub_to_hub.clone(),
        None,
        (Drive::Speed, true),
        torque,
        damping,
    )
    .or_else(|_| {
        lumped_twin(
            case,
            hub_to_hub,
            None,
            (Drive::Speed, false),
            torque,
            damping,
        )
    })?;
    let f_n = model.natural_frequency() / std::f64::consts::TAU;
    let teeth = pair.gears[0].teeth() as f64;
    let pitch = pair.gears[0].angular_pitch();
    let bins: Vec<Option<f64>> = (0..256)
        .map(|j| Some(mesh.stiffness.at(j as f64 / 256.0 * pitch)))
        .collect();
    let static_te_pp = static_te(pair, torque, &bins, &mesh.unloaded_te)
        .map_or(f64::NAN, |te| te.peak_to_peak_rad);
    let speed = speed_rpm * std::f64::consts::TAU / 60.0;
    let steps = crate::sweep::steps_per_period(&model, speed);
    let steady = steady_state(&model, speed, steps, model.static_state(), 1e-9, 2000);
    if steady.diverged {
        return Err(super::compare::lumped_diverged(speed_rpm));
    }
    let dte_amplitude = amplitude_spectrum(&steady.displacement)
        .first()
        .copied()
        .unwrap_or(0.0)
        / rb[1];
    Ok(Answers {
        mean: mesh.mean(),
        static_te_pp,
        resonance_rpm: 60.0 * f_n / teeth,
        dte_amplitude,
        lumped_s: started.elapsed().as_secs_f64(),
    })
}

/// Builds the chart's data from the FE stiffness runs (at least one unscaled) and the explicit
/// run at speed.
pub fn run(
    case: &Case,
    fe_runs: &[FeStiffnessRun],
    dte_run: &FeDte,
    progress: Progress,
) -> Result<AccuracyCost, StudyError> {
    let torque = dte_run.torque_nm;
    let speed_rpm = dte_run.speed_rpm;
    // The unmodified pair, whatever the case names its variants (the runs are of it).
    let unmodified = [crate::geometry::FlankModification::none(); 2];
    let mut rows: Vec<(String, &'static str, f64, MeshStiffness)> = Vec::new();
    for (i, (fine, coarse)) in LTCA_LEVELS.iter().enumerate() {
        progress("LTCA levels", i, LTCA_LEVELS.len());
        let started = std::time::Instant::now();
        let model = super::ltca::model_with_sizes(case, &unmodified, fine * 1e-3, coarse * 1e-3)?;
        let results = model.run(POSITIONS, torque, &|_| {})?;
        let mesh = stiffness::from_ltca(&case.pair, &results, torque, "ltca")
            .map_err(StudyError::Input)?;
        rows.push((
            format!("LTCA {fine} mm"),
            "ltca",
            started.elapsed().as_secs_f64(),
            mesh,
        ));
    }
    progress("LTCA levels", LTCA_LEVELS.len(), LTCA_LEVELS.len());
    let started = std::time::Instant::now();
    let iso = stiffness::iso_6336_method_b(&case.pair, torque, case.material.youngs_modulus)
        .mesh_stiffness(&case.pair, torque);
    rows.push((
        "ISO 6336-1 B".into(),
        "analytic",
        started.elapsed().as_secs_f64(),
        iso,
    ));
    let started = std::time::Instant::now();
    let pe = potential_energy::potential_energy_table(
        &case.pair,
        POSITIONS,
        case.material.youngs_modulus,
        case.material.poisson_ratio,
        case.plane,
    );
    rows.push((
        "potential energy".into(),
        "analytic",
        started.elapsed().as_secs_f64(),
        pe,
    ));
    for run in fe_runs {
        let scaling = if run.mass_scaling_factor > 1.0 {
            format!("mass x{:.0}", run.mass_scaling_factor)
        } else {
            "unscaled".into()
        };
        rows.push((
            format!("explicit FE {} mm, {scaling}", run.fine_mm),
            "explicit",
            run.wall_s,
            run.stiffness.clone(),
        ));
    }
    let reference = fe_runs
        .iter()
        .enumerate()
        .filter(|(_, r)| r.mass_scaling_factor <= 1.0)
        .min_by(|(_, a), (_, b)| {
            a.fine_mm
                .total_cmp(&b.fine_mm)
                .then(b.wall_s.total_cmp(&a.wall_s))
        })
        .map(|(i, _)| LTCA_LEVELS.len() + 2 + i)
        .ok_or_else(|| {
            StudyError::Input(
                "the chart needs an unscaled explicit FE stiffness run as its reference".into(),
            )
        })?;
    let mesh_hz = speed_rpm / 60.0 * case.pair.gears[0].teeth() as f64;
    let late = ((dte_run.statistics_start_s / dte_run.dt) as usize).min(dte_run.dte.len());
    let reference_dte = harmonic_amplitudes(&dte_run.dte[late..], dte_run.dt, mesh_hz, 1)[0];
    let all: Vec<Answers> = rows
        .iter()
        .map(|(_, family, _, mesh)| answers(case, mesh, *family != "analytic", torque, speed_rpm))
        .collect::<Result<_, _>>()?;
    let r = &all[reference];
    let error = |a: f64, b: f64| (a / b - 1.0).abs();
    let points = rows
        .iter()
        .zip(&all)
        .map(|((method, family, wall, _), a)| MethodPoint {
            method: method.clone(),
            family,
            wall_s: wall + a.lumped_s,
            mean_stiffness_n_per_m: a.mean,
            static_te_peak_to_peak_rad: a.static_te_pp,
            resonance_rpm: a.resonance_rpm,
            dte_mesh_amplitude_rad: a.dte_amplitude,
            mean_stiffness_error: error(a.mean, r.mean),
            static_te_error: error(a.static_te_pp, r.static_te_pp),
            resonance_error: error(a.resonance_rpm, r.resonance_rpm),
            dte_amplitude_error: error(a.dte_amplitude, reference_dte),
        })
        .collect();
    Ok(AccuracyCost {
        case: case.name().to_string(),
        reference: rows[reference].0.clone(),
        dte_reference: format!("explicit FE at {speed_rpm:.0} rpm ({})", dte_run.source),
        speed_rpm,
        reference_dte_mesh_amplitude_rad: reference_dte,
        points,
    })
}
