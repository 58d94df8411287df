//! Accuracy against cost (`geardyn compare --chart`): every way geardyn has to the pair's mesh
//! stiffness, charted by its wall time against its error on four questions a gear engineer
//! asks, each against the best estimate of the truth for that question, drawn with its own
//! uncertainty.
//!
//! # Methods (each a k(θ), e(θ) source)
//! LTCA at three mesh levels (timed here), explicit FE stiffness scenes (read from their run
//! folders: mesh level, mass scaling and wall time), ISO 6336-1 method B and the
//! potential-energy method (timed here), and the case's lumped model on the LTCA's
//! load-dependent force law (the default) beside the secant LTCA rows.
//!
//! # Questions (each answered from the method's k(θ), the same way for every method)
//! * mean stiffness k̄;
//! * peak-to-peak of the static TE the stiffness gives at the load, (T/(r_b2 k) + e)/r_b2;
//! * first resonance speed: f_mesh = f_n of the speed-driven pair with elastic bodies (the
//!   FE's lumped twin, [`super::compare::lumped_twin`]: the bodies' twist is taken out of the
//!   hub-to-hub LTCA and FE stiffness and given to the bodies; ISO and potential energy do not
//!   hold it, so it is put in series first; with the force law, its tangent at the design
//!   load), n = 60 f_n / z₁ — its error follows from the mean stiffness's (√k), so it is about
//!   half of it;
//! * DTE amplitude at the mesh frequency at the primary FE run's speed
//!   ([`super::compare::primary_run`], 3000 rpm for paper36): the lumped model's periodic
//!   steady state on that k(θ), against the explicit FE's own DTE there.
//!
//! # References ([`References`])
//! * k̄ and the static TE: the LTCA extrapolated to zero element size ([`richardson`]) from
//!   three flank sizes ([`REFERENCE_LEVELS`]), with the extrapolation's own size as its
//!   uncertainty — or, where the three do not converge monotonically, the finest with the
//!   spread of the three;
//! * the resonance speed: the explicit FE's speed sweep (its fitted undamped resonance on its
//!   finest mesh, uncertain by the larger of the fit's jackknife and the FE's shift under its
//!   last refinement) when compare ran one, else the FE modal analysis of the meshed pair on the case's mesh (driver held), with the
//!   difference to the modal analysis on the explicit FE's mesh as its uncertainty;
//! * the DTE amplitude: the explicit FE at that speed, with the difference between the two
//!   halves of its statistics window as its uncertainty.
//!
//! The cost of a lumped answer is the cost of its k(θ) plus the lumped solve.

use serde::Serialize;

use crate::case::Case;
use crate::lumped::Drive;
use crate::signal::harmonic_amplitudes;
use crate::stiffness::{self, potential_energy, ForceLaw, MeshStiffness};

use super::compare::{lumped_twin, runs_element_damping, FeDamping, FeDte};
use super::lumped::gear_inertias;
use super::{Progress, StudyError};
use crate::explicit::scene::static_te;

/// An explicit FE stiffness run read from its folder.
#[derive(Debug, Clone)]
pub struct FeStiffnessRun {
    /// The run's folder (for messages).
    pub source: String,
    /// How its mesh laid out the teeth (`fe.tooth_layout`; the chart takes the case's only).
    pub tooth_layout: crate::mesh::ToothLayout,
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

/// The best estimate of the truth for one question, with its uncertainty.
#[derive(Debug, Clone, Serialize)]
pub struct Reference {
    pub value: f64,
    /// Estimated uncertainty (absolute, the value's unit).
    pub uncertainty: f64,
    pub source: String,
}

impl Reference {
    /// The uncertainty over the value: errors below it are not resolved.
    pub fn relative_uncertainty(&self) -> f64 {
        (self.uncertainty / self.value).abs()
    }
}

/// The four references of the chart.
#[derive(Debug, Clone, Serialize)]
pub struct References {
    pub mean_stiffness: Reference,
    pub static_te_peak_to_peak: Reference,
    pub resonance_rpm: Reference,
    pub dte_mesh_amplitude: Reference,
}

/// The chart's data.
#[derive(Debug, Clone, Serialize)]
pub struct AccuracyCost {
    pub case: String,
    pub references: References,
    pub speed_rpm: f64,
    pub points: Vec<MethodPoint>,
    /// The explicit FE's own k̄ at zero flank size, held against the LTCA's (given stiffness runs
    /// at three flank sizes or more).
    pub explicit_fe_mean_stiffness_limit: Option<FeLimit>,
}

/// The explicit FE's mean stiffness extrapolated to zero flank size ([`richardson`] on its three
/// finest stiffness runs) beside the LTCA's extrapolated k̄: two fidelities that discretize the
/// contact differently (penalty springs at Gauss points against an exact active set at nodes)
/// should meet in their limit, within the two extrapolations' uncertainties. Only an
/// extrapolation is a limit: where the FE's three levels are not in their asymptotic range
/// (differences changing sign, or an observed order outside [0.5, 6], as when its steps do not
/// shrink), its finest is reported with the levels' spread and no verdict, since that spread
/// does not bound what further refinement moves.
#[derive(Debug, Clone, Serialize)]
pub struct FeLimit {
    /// The three flank sizes used, coarsest first [mm].
    pub flank_mm: [f64; 3],
    /// The FE's k̄ at each [N/m].
    pub mean_stiffness_n_per_m: [f64; 3],
    /// The extrapolated k̄ [N/m] (or the finest, `order` None), its uncertainty (the
    /// extrapolation's own size, or the three levels' spread) and the observed order.
    pub value_n_per_m: f64,
    pub uncertainty_n_per_m: f64,
    pub order: Option<f64>,
    /// value / the LTCA's extrapolated k̄ − 1.
    pub rel_to_ltca_limit: f64,
    /// The two uncertainties added, over the LTCA's k̄.
    pub combined_uncertainty_rel: f64,
    /// Whether |rel_to_ltca_limit| is within combined_uncertainty_rel; None without an
    /// extrapolation (or with an uncertainty that is not finite).
    pub agrees: Option<bool>,
}

/// [`FeLimit`] from stiffness runs given as (flank size [mm], mass-scaled, k̄ [N/m]): runs with a
/// finite k̄ only, one per size (the unscaled one where a size has both: it carries no scaling's
/// approximation), the three finest sizes. None with fewer than three sizes.
pub fn explicit_fe_limit(runs: &[(f64, bool, f64)], ltca: &Reference) -> Option<FeLimit> {
    let mut by_size: Vec<(f64, bool, f64)> = Vec::new();
    for &(mm, scaled, k) in runs.iter().filter(|r| r.2.is_finite()) {
        match by_size.iter_mut().find(|(m, _, _)| (m - mm).abs() < 1e-9) {
            Some(kept) if kept.1 && !scaled => *kept = (mm, scaled, k),
            Some(_) => {}
            None => by_size.push((mm, scaled, k)),
        }
    }
    by_size.sort_by(|a, b| b.0.total_cmp(&a.0));
    let finest = by_size.get(by_size.len().checked_sub(3)?..)?;
    let flank_mm = [finest[0].0, finest[1].0, finest[2].0];
    let k = [finest[0].2, finest[1].2, finest[2].2];
    let (value, uncertainty, order) = richardson(flank_mm, k);
    let rel_to_ltca_limit = value / ltca.value - 1.0;
    let combined_uncertainty_rel = (uncertainty + ltca.uncertainty) / ltca.value;
    Some(FeLimit {
        flank_mm,
        mean_stiffness_n_per_m: k,
        value_n_per_m: value,
        uncertainty_n_per_m: uncertainty,
        order,
        rel_to_ltca_limit,
        combined_uncertainty_rel,
        agrees: (order.is_some() && combined_uncertainty_rel.is_finite())
            .then_some(rel_to_ltca_limit.abs() <= combined_uncertainty_rel),
    })
}

/// f at zero mesh size from three sizes h₁ > h₂ > h₃ (finest last), f(h) = f₀ + c hᵖ:
/// the observed order p solves (f₁ − f₂)/(f₂ − f₃) = (h₁ᵖ − h₂ᵖ)/(h₂ᵖ − h₃ᵖ) (bisection on
/// [0.5, 6]; any ratio of sizes), then f₀ = f₃ − (f₂ − f₃) h₃ᵖ/(h₂ᵖ − h₃ᵖ), with |f₀ − f₃| as its
/// uncertainty (the extrapolation is trusted to about as much as it moved; Roache's grid
/// convergence index puts 1.25 × that on f₃). Where the differences change sign (oscillatory
/// convergence) or the order falls outside [0.5, 6], no extrapolation: f₃, with the largest
/// distance of f₁, f₂ from it as the uncertainty. Sizes not strictly falling, or a value not
/// finite: f₃ with a NaN uncertainty. Returns (value, uncertainty, order).
pub fn richardson(h: [f64; 3], f: [f64; 3]) -> (f64, f64, Option<f64>) {
    if !(f.iter().all(|v| v.is_finite()) && h[0] > h[1] && h[1] > h[2] && h[2] > 0.0) {
        return (f[2], f64::NAN, None);
    }
    let spread = (f[0] - f[2]).abs().max((f[1] - f[2]).abs());
    let fallback = (f[2], spread, None);
    let (d12, d23) = (f[0] - f[1], f[1] - f[2]);
    if d23 == 0.0 || d12 == 0.0 || d12.signum() != d23.signum() {
        return fallback;
    }
    let ratio = d12 / d23;
    let g = |p: f64| (h[0].powf(p) - h[1].powf(p)) / (h[1].powf(p) - h[2].powf(p));
    let (mut lo, mut hi) = (0.5, 6.0);
    if !(g(lo) <= ratio && ratio <= g(hi)) {
        return fallback;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if g(mid) < ratio {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let p = 0.5 * (lo + hi);
    let extrapolated = f[2] - d23 * h[2].powf(p) / (h[1].powf(p) - h[2].powf(p));
    (extrapolated, (extrapolated - f[2]).abs(), Some(p))
}

/// The LTCA flank element sizes of the k̄ and static-TE reference [mm] (body 1.5 mm): halving
/// twice from 0.4 to the 0.1 mm that resolves the Hertzian zone with several elements.
pub const REFERENCE_LEVELS: [f64; 3] = [0.4, 0.2, 0.1];

/// The resonance speed's reference, as compare found it: (speed [rpm], uncertainty [rpm],
/// source).
pub type ResonanceReference = (f64, f64, String);

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
    (mesh, laws): (&MeshStiffness, Option<&(ForceLaw, Option<ForceLaw>)>),
    holds_body_twist: bool,
    torque: f64,
    (speed_rpm, body_beta_s): (f64, f64),
) -> Result<Answers, StudyError> {
    let started = std::time::Instant::now();
    let pair = &case.pair;
    let rb = [pair.gears[0].base_radius, pair.gears[1].base_radius];
    // The FE's lumped twin: speed drive, elastic bodies. A hub-to-hub stiffness (LTCA, FE)
    // holds the bodies' twist (and sway), which the twin takes out and gives the bodies; ISO
    // 6336 and the potential-energy method stop at the tooth's foundation, so that compliance
    // is put in series first (a negative compliance "taken out"). A k too soft to hold it gets
    // rigid gears.
    let twist = super::lumped::bodies_line_compliance(case, crate::case::BodyModel::Elastic)?;
    let hub_to_hub = match holds_body_twist {
        true => mesh.clone(),
        false => mesh
            .without_series_compliance(-twist)
            .expect("adding a compliance keeps k positive"),
    };
    let m = Drive::Speed.effective_mass(gear_inertias(case), rb);
    let (law, back_law) = laws.cloned().map_or((None, None), |(l, b)| (Some(l), b));
    let damping = FeDamping {
        mesh_n_s_per_m: 2.0 * case.fe.mesh_damping_ratio * (hub_to_hub.mean() * m).sqrt(),
        stiffness_beta_s: body_beta_s,
    };
    let model = lumped_twin(
        case,
        hub_to_hub.clone(),
        (law.clone(), back_law.clone()),
        (Drive::Speed, true),
        torque,
        damping,
        None,
    )
    .or_else(|_| {
        lumped_twin(
            case,
            hub_to_hub,
            (law, back_law),
            (Drive::Speed, false),
            torque,
            damping,
            None,
        )
    })?;
    // With a force law: its tangent about the design load, what small vibrations feel.
    let f_n = match laws {
        Some(_) => model.linearized().natural_frequency(),
        None => model.natural_frequency(),
    } / std::f64::consts::TAU;
    let teeth = pair.gears[0].teeth() as f64;
    let static_te_pp = static_te_peak_to_peak(case, mesh, torque);
    let at_speed = super::fe_sweep::lumped_at(&model, speed_rpm, rb[1]);
    if at_speed.diverged {
        return Err(super::compare::lumped_diverged(speed_rpm));
    }
    let dte_amplitude = at_speed.mesh_amplitude_rad;
    Ok(Answers {
        mean: mesh.mean(),
        static_te_pp,
        resonance_rpm: 60.0 * f_n / teeth,
        dte_amplitude,
        lumped_s: started.elapsed().as_secs_f64(),
    })
}

/// The static TE's peak-to-peak [rad] that `mesh` gives under `torque`, (T/(r_b2 k) + e)/r_b2
/// over 256 positions.
fn static_te_peak_to_peak(case: &Case, mesh: &MeshStiffness, torque: f64) -> f64 {
    let pitch = case.pair.gears[0].angular_pitch();
    let bins: Vec<Option<f64>> = (0..256)
        .map(|j| Some(mesh.stiffness.at(j as f64 / 256.0 * pitch)))
        .collect();
    static_te(&case.pair, torque, &bins, &mesh.unloaded_te)
        .map_or(f64::NAN, |te| te.peak_to_peak_rad)
}

/// The k̄ and static-TE references: the LTCA at [`REFERENCE_LEVELS`] extrapolated
/// ([`richardson`]).
fn ltca_references(
    case: &Case,
    torque: f64,
    progress: Progress,
) -> Result<(Reference, Reference), StudyError> {
    let unmodified = [crate::geometry::FlankModification::none(); 2];
    let mut k = [0.0; 3];
    let mut te = [0.0; 3];
    for (i, fine) in REFERENCE_LEVELS.iter().enumerate() {
        progress("LTCA reference levels", i, REFERENCE_LEVELS.len());
        let model = super::ltca::model_with_sizes(case, &unmodified, fine * 1e-3, 1.5e-3)?;
        let results = model.run(POSITIONS, torque, &|_| {})?;
        let mesh = stiffness::from_ltca(&case.pair, &results, torque, "ltca")
            .map_err(StudyError::Input)?;
        k[i] = mesh.mean();
        te[i] = static_te_peak_to_peak(case, &mesh, torque);
    }
    progress("LTCA reference levels", 3, 3);
    let reference = |f: [f64; 3], what: &str| {
        let (value, uncertainty, order) = richardson(REFERENCE_LEVELS, f);
        let how = match order {
            Some(p) => format!("extrapolated to zero element size, observed order {p:.2}"),
            None => "the finest level, with the three levels' spread (they do not converge monotonically at an order in [0.5, 6])".into(),
        };
        Reference {
            value,
            uncertainty,
            source: format!(
                "{what}: LTCA at {:?} mm flanks (1.5 mm body), {how}",
                REFERENCE_LEVELS
            ),
        }
    };
    Ok((
        reference(k, "mean stiffness"),
        reference(te, "static TE peak-to-peak"),
    ))
}

/// Builds the chart's data from the FE stiffness runs, the explicit run at speed and the
/// resonance speed's reference (compare's FE sweep or modal analysis).
pub fn run(
    case: &Case,
    fe_runs: &[FeStiffnessRun],
    dte_run: &FeDte,
    resonance: ResonanceReference,
    progress: Progress,
) -> Result<AccuracyCost, StudyError> {
    super::compare::layouts_of_the_case(
        case,
        fe_runs
            .iter()
            .map(|r| (r.source.as_str(), r.tooth_layout))
            .chain([(dte_run.source.as_str(), dte_run.tooth_layout)]),
    )?;
    let torque = dte_run.torque_nm;
    let speed_rpm = dte_run.speed_rpm;
    // The unmodified pair, whatever the case names its variants (the runs are of it).
    let unmodified = [crate::geometry::FlankModification::none(); 2];
    type Laws = (ForceLaw, Option<ForceLaw>);
    let mut rows: Vec<(String, &'static str, f64, MeshStiffness, Option<Laws>)> = Vec::new();
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
            None,
        ));
    }
    progress("LTCA levels", LTCA_LEVELS.len(), LTCA_LEVELS.len());
    // The case's lumped model: the LTCA's load-dependent force law on the case's mesh.
    let started = std::time::Instant::now();
    let laws = super::lumped::ltca_laws(case, &unmodified, torque, "ltca force law", true)?;
    rows.push((
        format!("LTCA {} mm, force law", case.file.mesh.fine_element_mm),
        "ltca",
        started.elapsed().as_secs_f64(),
        laws.mesh,
        Some((laws.law, laws.back_law)),
    ));
    let started = std::time::Instant::now();
    let iso = stiffness::iso_6336_method_b(&case.pair, torque, case.material.youngs_modulus)
        .mesh_stiffness(&case.pair, torque);
    rows.push((
        "ISO 6336-1 B".into(),
        "analytic",
        started.elapsed().as_secs_f64(),
        iso,
        None,
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
        None,
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
            None,
        ));
    }
    let (mean_stiffness, static_te_peak_to_peak) = ltca_references(case, torque, progress)?;
    let explicit_fe_mean_stiffness_limit = explicit_fe_limit(
        &fe_runs
            .iter()
            .map(|r| (r.fine_mm, r.mass_scaling_factor > 1.0, r.stiffness.mean()))
            .collect::<Vec<_>>(),
        &mean_stiffness,
    );
    let mesh_hz = speed_rpm / 60.0 * case.pair.gears[0].teeth() as f64;
    let (_, late) = dte_run.window_starts();
    let window = &dte_run.dte[late..];
    let amplitude = |x: &[f64]| harmonic_amplitudes(x, dte_run.dt, mesh_hz, 1)[0];
    let halves = window.split_at(window.len() / 2);
    let references = References {
        mean_stiffness,
        static_te_peak_to_peak,
        resonance_rpm: Reference {
            value: resonance.0,
            uncertainty: resonance.1,
            source: resonance.2,
        },
        dte_mesh_amplitude: Reference {
            value: amplitude(window),
            uncertainty: (amplitude(halves.0) - amplitude(halves.1)).abs(),
            source: format!(
                "explicit FE at {speed_rpm:.0} rpm ({}); uncertainty: its two window halves apart",
                dte_run.source
            ),
        },
    };
    let all: Vec<Answers> = rows
        .iter()
        .map(|(_, family, _, mesh, law)| {
            answers(
                case,
                (mesh, law.as_ref()),
                *family != "analytic",
                torque,
                (
                    speed_rpm,
                    runs_element_damping(std::slice::from_ref(dte_run)),
                ),
            )
        })
        .collect::<Result<_, _>>()?;
    let error = |a: f64, r: &Reference| (a / r.value - 1.0).abs();
    let points = rows
        .iter()
        .zip(&all)
        .map(|((method, family, wall, _, _), a)| MethodPoint {
            method: method.clone(),
            family,
            wall_s: wall + a.lumped_s,
            mean_stiffness_n_per_m: a.mean,
            static_te_peak_to_peak_rad: a.static_te_pp,
            resonance_rpm: a.resonance_rpm,
            dte_mesh_amplitude_rad: a.dte_amplitude,
            mean_stiffness_error: error(a.mean, &references.mean_stiffness),
            static_te_error: error(a.static_te_pp, &references.static_te_peak_to_peak),
            resonance_error: error(a.resonance_rpm, &references.resonance_rpm),
            dte_amplitude_error: error(a.dte_amplitude, &references.dte_mesh_amplitude),
        })
        .collect();
    Ok(AccuracyCost {
        case: case.name().to_string(),
        references,
        speed_rpm,
        points,
        explicit_fe_mean_stiffness_limit,
    })
}

#[cfg(test)]
mod tests {
    use super::{explicit_fe_limit, richardson, Reference};

    /// Known answers: FE runs on k̄ = k₀ + c h² recover k₀ and the order, whatever order they
    /// come in; a size run both scaled and unscaled counts once, unscaled (the scaled before or
    /// after it); a run whose k̄ is not finite counts not; the three finest sizes are taken. A
    /// limit 1 % off the LTCA's with uncertainties of 0.62 % (the extrapolation's size) and
    /// 0.2 % (the LTCA's) does not agree, one 0.1 % off does; levels whose steps do not shrink
    /// give their finest and no verdict; two sizes give nothing.
    #[test]
    fn the_explicit_fe_limit_recovers_a_known_one() {
        let (k0, c) = (4.0e8, 2.0e7);
        let at = |h: f64| k0 + c * h * h;
        let runs = vec![
            (0.35, false, at(0.35)),
            (1.0, true, at(1.0) * 1.5),
            (0.7, true, at(0.7) * 1.1),
            (0.5, false, at(0.5)),
            (0.5, true, at(0.5) * 1.2),
            (0.25, true, f64::NAN),
            (0.7, false, at(0.7)),
        ];
        let ltca = |value: f64| Reference {
            value,
            uncertainty: 0.002 * value,
            source: String::new(),
        };
        let limit = explicit_fe_limit(&runs, &ltca(k0 / 1.01)).unwrap();
        assert_eq!(limit.flank_mm, [0.7, 0.5, 0.35]);
        assert!((limit.value_n_per_m / k0 - 1.0).abs() < 1e-9);
        assert!((limit.order.unwrap() - 2.0).abs() < 1e-6);
        assert!((limit.rel_to_ltca_limit - 0.01).abs() < 1e-9);
        let moved = (at(0.35) - k0) / (k0 / 1.01);
        assert!((limit.combined_uncertainty_rel - (moved + 0.002)).abs() < 1e-9);
        assert_eq!(limit.agrees, Some(false));
        let close = explicit_fe_limit(&runs, &ltca(k0 / 1.001)).unwrap();
        assert_eq!(close.agrees, Some(true));
        // Steps of 1 % each at 0.5, 0.35, 0.25 mm: no order in [0.5, 6] makes them shrink.
        let steady = [
            (0.5, false, 1.02 * k0),
            (0.35, false, 1.01 * k0),
            (0.25, false, k0),
        ];
        let finest = explicit_fe_limit(&steady, &ltca(k0)).unwrap();
        assert_eq!((finest.value_n_per_m, finest.order), (k0, None));
        assert_eq!(finest.agrees, None);
        let two_sizes = [(1.0, false, k0), (0.5, true, k0), (1.0, true, k0)];
        assert!(explicit_fe_limit(&two_sizes, &ltca(k0)).is_none());
    }

    /// Known answers: f = f₀ + c hᵖ at three sizes of any ratio gives f₀ and p back (no
    /// uncertainty left but the extrapolation's size); oscillating values give the finest
    /// with the spread; an order outside [0.5, 6] is not extrapolated.
    #[test]
    fn richardson_recovers_a_known_limit() {
        for (f0, c, p, h) in [
            (4.0e8, 3.0e10, 1.0, [0.4, 0.2, 0.1]),
            (5.0e-5, 2.0e-3, 2.0, [1.0, 0.5, 0.2]),
            (1.0, -0.3, 1.5, [0.4, 0.25, 0.1]),
        ] {
            let f = h.map(|h: f64| f0 + c * h.powf(p));
            let (value, uncertainty, order) = richardson(h, f);
            assert!((value / f0 - 1.0).abs() < 1e-9, "{value} vs {f0}");
            assert!((order.unwrap() - p).abs() < 1e-6);
            let moved = (f[2] - f0).abs();
            assert!((uncertainty / moved - 1.0).abs() < 1e-6);
        }
        let (value, uncertainty, order) = richardson([0.4, 0.2, 0.1], [1.0, 1.2, 1.1]);
        assert_eq!((value, order), (1.1, None));
        assert!((uncertainty - 0.1).abs() < 1e-12);
        // Differences 1e-3 then 1e-6 at halving: order ≈ 10, not believed.
        let (value, _, order) = richardson([0.4, 0.2, 0.1], [1.001001, 1.000001, 1.0]);
        assert_eq!((value, order), (1.0, None));
        // Sizes out of order, a NaN: no answer but the finest value.
        let (value, uncertainty, order) = richardson([0.1, 0.2, 0.4], [1.0, 1.1, 1.2]);
        assert!(value == 1.2 && uncertainty.is_nan() && order.is_none());
        let (_, uncertainty, _) = richardson([0.4, 0.2, 0.1], [f64::NAN, 1.1, 1.0]);
        assert!(uncertainty.is_nan());
    }
}
