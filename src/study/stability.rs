//! The stability study (`geardyn stability`): at every speed the largest Floquet multiplier of
//! the period-one orbit of the model as it is integrated (load, force law, contact loss and
//! back flanks; found by shooting from the quasi-static state, [`crate::lumped::periodic_orbit`])
//! and of the linearized drive flanks alone (the tangent stiffness about the quasi-static state,
//! no separation), the unstable ranges of each, and where the principal parametric regions of a
//! cosine stiffness lie (f_mesh ≈ 2 f_i / j for each mode i).

use serde::Serialize;

use crate::case::Case;

use super::lumped::{mode_frequencies_hz, setup, LumpedSetup};
use super::{RpmRange, StudyError};

/// Headline numbers (`summary.json`).
#[derive(Debug, Clone, Serialize)]
pub struct StabilitySummary {
    pub case: String,
    pub stiffness_source: String,
    pub drive: crate::lumped::Drive,
    pub model: String,
    pub mean_stiffness_n_per_m: f64,
    pub natural_frequency_hz: f64,
    pub modes_hz: Vec<f64>,
    pub damping_ratio: f64,
    /// Where the integrated model's periodic orbit is unstable (multiplier > 1).
    pub unstable_rpm_ranges: Vec<(f64, f64)>,
    /// Where the linearized drive flanks are parametrically unstable.
    pub linear_unstable_rpm_ranges: Vec<(f64, f64)>,
    /// Where shooting found no period-one orbit: past a fold the periodic response has ended
    /// (a zero-backlash pair's sweep diverges there), or a switch was too sharp for the
    /// differences.
    pub no_orbit_rpm_ranges: Vec<(f64, f64)>,
    pub parametric_region_centres_rpm: Vec<f64>,
    /// Largest multiplier of the integrated model's orbits over the speeds where one was found.
    pub max_multiplier: f64,
    pub max_multiplier_linear: f64,
    pub points: usize,
    pub wall_s: f64,
    pub stiffness_wall_s: f64,
}

/// The study's result.
pub struct StabilityStudy {
    pub setup: LumpedSetup,
    pub rpms: Vec<f64>,
    /// Largest |λ| of the integrated model's period-one orbit per speed (`None`: none found).
    pub multipliers: Vec<Option<f64>>,
    /// Largest |λ| of the linearized drive flanks per speed.
    pub linear_multipliers: Vec<f64>,
    pub summary: StabilitySummary,
}

/// The Floquet map of the case's lumped model over `rpm`.
pub fn run(case: &Case, rpm: &RpmRange) -> Result<StabilityStudy, StudyError> {
    let setup = setup(case)?;
    let rpms = rpm.0.clone();
    let model = &setup.model;
    let started = std::time::Instant::now();
    let multipliers = crate::sweep::orbit_floquet_map(model, &rpms);
    let linear_multipliers = crate::sweep::floquet_map(model, &rpms);
    let wall_s = started.elapsed().as_secs_f64();
    let unstable = |m: &[f64]| ranges_where(&rpms, m, |m| m > 1.0);
    let orbit: Vec<f64> = multipliers.iter().map(|m| m.unwrap_or(f64::NAN)).collect();
    let modes_hz = mode_frequencies_hz(model);
    // Principal regions: f_mesh = 2 f_n / j.
    let theory: Vec<f64> = modes_hz
        .iter()
        .flat_map(|f| {
            (1..=3).map(move |j| super::lumped::speed_for_mesh_frequency(case, 2.0 * f / j as f64))
        })
        .collect();
    let summary = StabilitySummary {
        case: case.name().to_string(),
        stiffness_source: model.mesh.source.clone(),
        drive: setup.drive,
        model: setup.model_note.clone(),
        mean_stiffness_n_per_m: model.mesh.mean(),
        natural_frequency_hz: setup.natural_frequency_hz,
        modes_hz,
        damping_ratio: setup.damping_ratio,
        unstable_rpm_ranges: unstable(&orbit),
        linear_unstable_rpm_ranges: unstable(&linear_multipliers),
        no_orbit_rpm_ranges: ranges_where(&rpms, &orbit, f64::is_nan),
        parametric_region_centres_rpm: theory,
        max_multiplier: multipliers.iter().flatten().copied().fold(0.0, f64::max),
        max_multiplier_linear: linear_multipliers.iter().copied().fold(0.0, f64::max),
        points: rpms.len(),
        wall_s,
        stiffness_wall_s: setup.stiffness_wall_s,
    };
    Ok(StabilityStudy {
        setup,
        rpms,
        multipliers,
        linear_multipliers,
        summary,
    })
}

/// The runs of neighbouring speeds whose multiplier meets `holds`, as (first, last) rpm.
fn ranges_where(rpms: &[f64], multipliers: &[f64], holds: impl Fn(f64) -> bool) -> Vec<(f64, f64)> {
    let mut ranges: Vec<(f64, f64)> = Vec::new();
    for (i, m) in multipliers.iter().enumerate() {
        if holds(*m) {
            match ranges.last_mut() {
                Some(range) if i > 0 && holds(multipliers[i - 1]) => range.1 = rpms[i],
                _ => ranges.push((rpms[i], rpms[i])),
            }
        }
    }
    ranges
}
