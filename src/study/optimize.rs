//! The relief optimization study (`geardyn optimize`): the tip/root relief that keeps the loaded
//! STE flat across the load range ([`crate::optimize::robust`]), judged against the baselines —
//! no relief, the case's own relief (the seed paper's 20/10 µm for the embedded case) and the
//! classic rule — on the same bodies: the robust objective, the Harris map (STE peak-to-peak
//! against torque), and a lumped rpm sweep on each candidate's k(θ), e(θ). The explicit-FE
//! cross-check of the candidates is planned and tabulated here; the binary runs the scenes.
//!
//! The classic rule (Harris 1958; Smith, *Gear Noise and Vibration*, §3.3): tip relief on both
//! gears equal to the single-pair deflection δ_s at the design torque, linear, long (from the
//! HPSTC) or short (half the double-contact zone). δ_s is the largest approach r_b2(φ − φ₀) of
//! the unmodified pair over the cycle — where one pair carries the whole load — less the gear
//! bodies' twist between bore and root circle W (c_b1 + c_b2) ([`super::compare::body_twist`]):
//! that twist turns the unloaded teeth with the loaded ones and closes no flank gap, so the
//! teeth, not the hubs, set the relief (rim to rim). What the bodies share beyond the annulus
//! (the rim's bending under the loaded tooth next to the unloaded one) stays in δ_s: the rule is
//! a rule, and the LTCA judges it.

use serde::Serialize;

use crate::case::{Case, Override};
use crate::geometry::{FlankModification, ReliefShape};
use crate::ltca::LtcaModel;
use crate::optimize::relief::ReliefDesign;
use crate::optimize::robust::{
    self, end_relief, load_response, LoadRange, LoadResponse, OptimizeError, Optimum,
};
use crate::stiffness::{self, MeshStiffness};
use crate::sweep::{self, SweepPoint};

use super::{load_torque, Progress, RpmRange, StudyError};

impl From<OptimizeError> for StudyError {
    fn from(e: OptimizeError) -> Self {
        match e {
            OptimizeError::Ltca(e) => StudyError::Ltca(e),
            other => StudyError::Input(other.to_string()),
        }
    }
}

/// The load range as percentages of the design torque, `FROM:TO:N`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TorqueRange {
    pub from_percent: f64,
    pub to_percent: f64,
    pub count: usize,
}

impl std::str::FromStr for TorqueRange {
    type Err = String;

    /// Parses `FROM:TO:N` in percent of the design torque, 0 < FROM ≤ TO, N ≥ 1.
    fn from_str(text: &str) -> Result<Self, String> {
        let bad = || {
            format!(
                "{text:?} is invalid: write FROM:TO:N in percent of the design torque with \
                 0 < FROM ≤ TO and N ≥ 1 torques, e.g. 50:150:5"
            )
        };
        let parts: Vec<&str> = text.split(':').collect();
        let [from, to, n] = parts[..] else {
            return Err(bad());
        };
        let range = TorqueRange {
            from_percent: from.parse().map_err(|_| bad())?,
            to_percent: to.parse().map_err(|_| bad())?,
            count: n.parse().map_err(|_| bad())?,
        };
        let ok = range.from_percent > 0.0
            && range.to_percent >= range.from_percent
            && range.to_percent.is_finite()
            && range.count >= 1
            && (range.count > 1 || range.from_percent == range.to_percent);
        ok.then_some(range).ok_or_else(bad)
    }
}

/// A strength limit of the optimizer: absolute, or relative to the unmodified pair's peak over
/// the load range (on the same bodies, at the same torques).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum StressLimit {
    /// At most this [MPa].
    Mpa(f64),
    /// At most this percentage of the unmodified pair's peak (100: no rise).
    PercentOfUnmodified(f64),
}

impl std::str::FromStr for StressLimit {
    type Err = String;

    /// `180` (MPa) or `105%` (of the unmodified pair's peak over the load range).
    fn from_str(text: &str) -> Result<Self, String> {
        let bad = || {
            format!(
                "{text:?} is invalid: give a stress in MPa (e.g. 180) or a percentage of the \
                 unmodified pair's peak over the load range (e.g. 105%), positive"
            )
        };
        let (number, percent) = match text.trim().strip_suffix('%') {
            Some(number) => (number, true),
            None => (text.trim(), false),
        };
        let value: f64 = number.trim().parse().map_err(|_| bad())?;
        if !(value > 0.0 && value.is_finite()) {
            return Err(bad());
        }
        Ok(if percent {
            StressLimit::PercentOfUnmodified(value)
        } else {
            StressLimit::Mpa(value)
        })
    }
}

impl StressLimit {
    /// The limit [Pa] given the unmodified pair's peak `unmodified_mpa`.
    pub fn resolve(self, unmodified_mpa: f64) -> f64 {
        match self {
            StressLimit::Mpa(mpa) => mpa * 1e6,
            StressLimit::PercentOfUnmodified(percent) => percent / 100.0 * unmodified_mpa * 1e6,
        }
    }
}

/// Options of the study.
#[derive(Debug, Clone, PartialEq)]
pub struct OptimizeOptions {
    pub torque_range: TorqueRange,
    /// LTCA positions per base pitch.
    pub positions: usize,
    /// Smallest loaded contact ratio allowed at any torque of the range; None: the pair's own
    /// ([`default_min_contact_ratio`]).
    pub min_contact_ratio: Option<f64>,
    /// Largest relief amount [µm].
    pub max_relief_um: f64,
    /// Shortest relief, as a fraction of the double-contact zone.
    pub min_length: f64,
    /// Driver speeds of each candidate's lumped sweep.
    pub rpm: RpmRange,
    /// Torques of the Harris map, in percent of the design torque.
    pub harris_range: TorqueRange,
    /// Largest tooth-root tension of each gear over the load range (None: no limit; a
    /// percentage is of each gear's own unmodified peak).
    pub max_root_stress: Option<StressLimit>,
    /// Largest Hertz pressure over the load range (None: no limit).
    pub max_contact_pressure: Option<StressLimit>,
}

/// The smallest loaded contact ratio a relief may leave by default: ⌊ε_α⌋ + 0.2, at most ε_α —
/// 1.2 for a pair with 1.2 ≤ ε_α < 2 (the relief may not reduce the pair to single contact over
/// more than 80 % of a pitch; below 1.2, ε_α itself), 2.2 (or ε_α) for a high-contact-ratio
/// pair, whose zone of least contact carries two pairs and which should not fall back to single
/// contact.
pub fn default_min_contact_ratio(pair: &crate::geometry::GearPair) -> f64 {
    let ratio = pair.contact_ratio;
    (ratio.floor() + MIN_CONTACT_RATIO_MARGIN).min(ratio)
}

/// The defaults of [`OptimizeOptions`], shared with the command line's.
pub const DEFAULT_TORQUE_RANGE: &str = "50:150:5";
pub const DEFAULT_POSITIONS: usize = 64;
/// The loaded contact ratio the relief may not go below, by default, above the number of pairs
/// in the zone of least contact.
pub const MIN_CONTACT_RATIO_MARGIN: f64 = 0.2;
pub const DEFAULT_MAX_RELIEF_UM: f64 = 40.0;
pub const DEFAULT_MIN_LENGTH: f64 = 0.25;
pub const DEFAULT_RPM: &str = "100:12000:300";
const HARRIS_RANGE: &str = "10:200:20";

impl Default for OptimizeOptions {
    fn default() -> Self {
        let parse = |text: &str| text.parse::<TorqueRange>().expect("a valid default");
        OptimizeOptions {
            torque_range: parse(DEFAULT_TORQUE_RANGE),
            positions: DEFAULT_POSITIONS,
            min_contact_ratio: None,
            max_relief_um: DEFAULT_MAX_RELIEF_UM,
            min_length: DEFAULT_MIN_LENGTH,
            rpm: DEFAULT_RPM.parse().expect("a valid default"),
            harris_range: parse(HARRIS_RANGE),
            max_root_stress: None,
            max_contact_pressure: None,
        }
    }
}

/// What a candidate is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CandidateKind {
    /// No relief, the case's own variants, the classic rule.
    Baseline,
    /// A trust-region optimum.
    Optimum,
}

/// The lumped rpm sweep on one candidate's k(θ), e(θ) at the design torque.
#[derive(Debug, Clone, Serialize)]
pub struct CandidateSweep {
    pub max_dynamic_factor: f64,
    pub max_dynamic_factor_rpm: f64,
    /// Dynamic factor per speed of the up-sweep.
    pub dynamic_factor: Vec<f64>,
    /// DTE rms per speed of the up-sweep [µm].
    pub dte_rms_um: Vec<f64>,
    /// Speeds where the teeth separate.
    pub separated_points: usize,
    /// Where the lumped response grew without bound, with the cause; the lists above stop at
    /// the speed before it and the maxima are over those speeds.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub diverged: Option<String>,
}

/// One design judged by every measure of the study.
#[derive(Debug, Clone, Serialize)]
pub struct Candidate {
    pub name: String,
    pub kind: CandidateKind,
    /// The design variables (None: a case variant that is not of the optimizer's family).
    pub design: Option<ReliefDesign>,
    #[serde(skip)]
    pub modifications: [FlankModification; 2],
    /// Over the robust load range.
    pub response: LoadResponse,
    /// Over the Harris-map torques.
    pub harris: LoadResponse,
    /// Driver roll angle of the positions [°] and the STE there at the design torque [µm].
    #[serde(skip)]
    pub roll_deg: Vec<f64>,
    #[serde(skip)]
    pub ste_design_um: Vec<f64>,
    /// STE peak-to-peak at the design torque [µm].
    pub ste_pp_design_um: f64,
    /// Amplitudes of the STE's first three mesh harmonics at the design torque [µm]: the
    /// excitation a speed sweep sees.
    pub ste_harmonics_design_um: [f64; 3],
    /// Loaded contact ratio at the design torque.
    pub contact_ratio_design: f64,
    /// Combined relief at the end of recess and the start of approach [µm].
    pub end_relief_um: [f64; 2],
    /// Keeps every limit of the optimizer (baselines need not).
    pub feasible: bool,
    #[serde(skip)]
    pub mesh_stiffness: MeshStiffness,
    pub sweep: CandidateSweep,
}

/// One start of the trust-region loop.
#[derive(Debug, Clone, Serialize)]
pub struct StartSummary {
    pub shape: ReliefShape,
    pub start: String,
    pub objective_start_um: f64,
    pub objective_um: f64,
    pub iterations: usize,
    pub stop: robust::Stop,
    /// What failed when `stop` is `failed` (the last good design is the start's result).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
    pub ltca_evaluations: usize,
    pub qp_solve_wall_s: f64,
    pub wall_s: f64,
}

/// Where each relief zone of the optimum starts, as the gear's own roll angle [°] (None: no zone).
#[derive(Debug, Clone, Serialize)]
pub struct StartRoll {
    pub tip: [Option<f64>; 2],
    pub root: [Option<f64>; 2],
}

/// The headline numbers (`summary.json`).
#[derive(Debug, Clone, Serialize)]
pub struct OptimizeSummary {
    pub case: String,
    pub design_torque_nm: f64,
    pub torque_range_nm: Vec<f64>,
    pub positions: usize,
    pub limits: robust::Limits,
    /// Single-pair deflection δ_s of the unmodified pair at the design torque, rim to rim (the
    /// LTCA's largest approach less the bodies' twist between bore and root circle) [µm]: the
    /// classic rule's amount and the no-loss-of-contact limit.
    pub single_pair_deflection_um: f64,
    /// The same, hub to hub (the LTCA's largest approach r_b2 (φ − φ₀)) [µm].
    pub single_pair_deflection_hub_um: f64,
    pub shape: ReliefShape,
    pub tip_relief_um: [f64; 2],
    pub root_relief_um: [f64; 2],
    /// Relief length as the fraction λ of the double-contact zone.
    pub relief_length_fraction: f64,
    pub start_roll_deg: StartRoll,
    pub ste_pp_before_um: f64,
    pub ste_pp_after_um: f64,
    pub objective_none: f64,
    pub objective_optimum: f64,
    /// The case's own relief (the first variant with one): the seed paper's 20/10 µm here.
    pub paper_variant: Option<String>,
    pub objective_paper: Option<f64>,
    pub objective_classic: f64,
    pub objective_classic_short: f64,
    pub contact_ratio_optimum: Vec<f64>,
    /// The strength limits the optimizer kept [MPa] (None: not asked for; `--max-root-stress-mpa`
    /// per gear, `--max-contact-pressure-mpa`, a percentage resolved on the unmodified pair's
    /// peaks).
    pub max_root_stress_mpa: Option<[f64; 2]>,
    pub max_contact_pressure_mpa: Option<f64>,
    /// The largest tooth-root tension (either gear) and Hertz pressure over the load range,
    /// unmodified and at the optimum [MPa].
    pub root_stress_none_mpa: f64,
    pub root_stress_optimum_mpa: f64,
    pub contact_pressure_none_mpa: f64,
    pub contact_pressure_optimum_mpa: f64,
    /// Trust-region iterations of the winning start, and of all starts.
    pub iterations: usize,
    pub iterations_all_starts: usize,
    pub ltca_evaluations: usize,
    /// Time in Clarabel over all starts [s] (timing).
    pub qp_solve_wall_s: f64,
    /// The whole trust-region loop over all starts, LTCA evaluations included [s] (timing).
    pub qp_loop_wall_s: f64,
    /// Meshing and factorizing the bodies once [s] (timing).
    pub model_wall_s: f64,
    /// The study without the FE cross-check [s] (timing).
    pub wall_s: f64,
    pub starts: Vec<StartSummary>,
    /// Starts that broke a limit and were left out, with the reason.
    pub skipped_starts: Vec<String>,
    /// The optimum on fixed bodies against its own re-meshed LTCA.
    pub remeshed: RemeshedCheck,
    pub candidates: Vec<CandidateLine>,
    /// The explicit-FE cross-check (`--fe-check`).
    pub fe_check: Option<FeCheck>,
    /// Where a stop request ended the FE cross-check (absent when it finished or did not run).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub interrupted: Option<String>,
    pub model: &'static str,
}

/// The best optimum's LTCA at the design torque on the loop's fixed (unmodified) bodies
/// against the LTCA on bodies meshed with the relief: what the fixed-body assumption costs.
#[derive(Debug, Clone, Serialize)]
pub struct RemeshedCheck {
    pub mesh_stiffness_mean_fixed_n_per_m: f64,
    pub mesh_stiffness_mean_remeshed_n_per_m: f64,
    pub mesh_stiffness_rel: f64,
    pub ste_pp_fixed_um: f64,
    pub ste_pp_remeshed_um: f64,
    /// Fixed over re-meshed STE peak-to-peak, less 1.
    pub ste_pp_rel: f64,
    /// Largest |STE difference| over the positions [µm], and over the re-meshed peak-to-peak
    /// (mostly a uniform offset: the two meshes' nodes differ by the relief).
    pub ste_max_difference_um: f64,
    pub ste_max_difference_over_pp: f64,
}

/// [`RemeshedCheck`] of `optimum-1`.
fn remeshed_check(
    case: &Case,
    candidates: &[Candidate],
    torque: f64,
    positions: usize,
) -> Result<RemeshedCheck, StudyError> {
    let optimum = candidates
        .iter()
        .find(|c| c.name == BEST)
        .ok_or_else(|| StudyError::Input("no optimum was found".into()))?;
    let remeshed =
        super::ltca::model(case, &optimum.modifications)?.run(positions, torque, &|_| {})?;
    let rb2 = case.pair.gears[1].base_radius;
    let ste: Vec<f64> = remeshed.iter().map(|r| r.ste * rb2 * 1e6).collect();
    // Both means through the one stiffness table the lumped model reads.
    let k = stiffness::from_ltca(&case.pair, &remeshed, torque, "ltca (re-meshed optimum)")
        .map_err(StudyError::Input)?
        .mean();
    let fixed_k = optimum.mesh_stiffness.mean();
    let difference = ste
        .iter()
        .zip(&optimum.ste_design_um)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let remeshed_pp = crate::signal::peak_to_peak(&ste);
    Ok(RemeshedCheck {
        mesh_stiffness_mean_fixed_n_per_m: fixed_k,
        mesh_stiffness_mean_remeshed_n_per_m: k,
        mesh_stiffness_rel: fixed_k / k - 1.0,
        ste_pp_fixed_um: optimum.ste_pp_design_um,
        ste_pp_remeshed_um: remeshed_pp,
        ste_pp_rel: optimum.ste_pp_design_um / remeshed_pp - 1.0,
        ste_max_difference_um: difference,
        ste_max_difference_over_pp: difference / remeshed_pp,
    })
}

/// One candidate's row of the summary.
#[derive(Debug, Clone, Serialize)]
pub struct CandidateLine {
    pub name: String,
    pub kind: CandidateKind,
    /// Relief amounts [gear 1, gear 2] [µm]; the length fraction λ and shape of the
    /// optimizer's family (None for a case variant's own zones).
    pub tip_relief_um: [f64; 2],
    pub root_relief_um: [f64; 2],
    pub relief_length_fraction: Option<f64>,
    pub shape: Option<ReliefShape>,
    pub objective_um: f64,
    pub ste_pp_design_um: f64,
    pub contact_ratio_min: f64,
    /// Each gear's largest tooth-root tension over the load range [MPa] (LTCA, fixed bodies).
    pub root_stress_max_mpa: [f64; 2],
    /// The largest Hertz pressure over the load range [MPa].
    pub contact_pressure_max_mpa: f64,
    pub feasible: bool,
    pub max_dynamic_factor: f64,
    pub max_dynamic_factor_rpm: f64,
    /// Where its lumped sweep diverged (the maximum above is over the speeds before it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sweep_diverged: Option<String>,
}

/// The study's result.
pub struct OptimizeStudy {
    pub design_torque: f64,
    pub range: LoadRange,
    pub harris_range: LoadRange,
    pub rpms: Vec<f64>,
    pub optima: Vec<(String, Optimum)>,
    /// Baselines first, then the optima best first.
    pub candidates: Vec<Candidate>,
    pub summary: OptimizeSummary,
}

/// The best optimum's candidate name.
pub const BEST: &str = "optimum-1";

/// The folder of one explicit run of the cross-check: relief variant and scene.
pub fn fe_run_folder(relief: &str, scene: &str) -> String {
    format!("{relief}-{scene}")
}

/// Number of optima carried forward as candidates.
pub const CANDIDATES: usize = 3;

/// Optima closer than this in every amount [m] and in λ are one candidate: below what the
/// explicit FE's DTE can tell apart (its mesh resolves about 0.1 µm of STE).
const DISTINCT_AMOUNT: f64 = 0.5e-6;
const DISTINCT_LENGTH: f64 = 0.05;

/// Runs the study; `progress` sees the stages.
pub fn run(
    case: &Case,
    options: &OptimizeOptions,
    progress: Progress,
) -> Result<OptimizeStudy, StudyError> {
    let started = std::time::Instant::now();
    let torque = load_torque(case)?;
    let percent = |r: &TorqueRange| {
        LoadRange::uniform(
            torque,
            r.from_percent / 100.0,
            r.to_percent / 100.0,
            r.count,
        )
    };
    let range = percent(&options.torque_range)?;
    let harris_range = percent(&options.harris_range)?;
    if !(options.min_length > 0.0 && options.min_length <= 1.0) {
        return Err(StudyError::Input(format!(
            "--min-relief-length {} is invalid: give a fraction of the end zone from the HPSTC / LPSTC in (0, 1]",
            options.min_length
        )));
    }
    progress("meshing and factorizing the bodies", 0, 1);
    let none = [FlankModification::none(); 2];
    let model = super::ltca::model(case, &none)?;
    let model_s = started.elapsed().as_secs_f64();
    let pair = &case.pair;
    let rb2 = pair.gears[1].base_radius;
    let unmodified = model.run(options.positions, torque, &|_| {})?;
    let hub_deflection = unmodified
        .iter()
        .map(|r| rb2 * (r.ste - r.unloaded_te))
        .fold(0.0, f64::max);
    // The bodies' twist between bore and root circle is in series with the teeth: it turns the
    // unloaded teeth with the loaded ones and closes no flank gap, so relief need not take it up.
    let twist = super::compare::body_twist(case);
    let deflection = hub_deflection - torque / rb2 * (twist[0] + twist[1]);
    let respond = |design: &ReliefDesign| {
        robust::evaluate(&model, design, &range, options.positions).map(|e| e.response)
    };
    // A relative strength limit reads the unmodified pair's peaks over the load range (each
    // gear's own root stress).
    let relative = |l: &Option<StressLimit>| matches!(l, Some(StressLimit::PercentOfUnmodified(_)));
    let unmodified =
        if relative(&options.max_root_stress) || relative(&options.max_contact_pressure) {
            Some(respond(&ReliefDesign::none(ReliefShape::Linear))?)
        } else {
            None
        };
    let peak_of = |pick: &dyn Fn(&LoadResponse) -> f64| unmodified.as_ref().map_or(0.0, pick);
    let limits = robust::Limits {
        max_amount: options.max_relief_um * 1e-6,
        min_length: options.min_length,
        min_contact_ratio: options
            .min_contact_ratio
            .unwrap_or_else(|| default_min_contact_ratio(pair)),
        contact_deflection: deflection,
        max_root_stress: options.max_root_stress.map(|l| {
            [0, 1].map(|g| l.resolve(peak_of(&|r: &LoadResponse| r.root_stress_peak_mpa()[g])))
        }),
        max_contact_pressure: options
            .max_contact_pressure
            .map(|l| l.resolve(peak_of(&|r: &LoadResponse| r.contact_pressure_peak_mpa()))),
    };
    let settings = robust::Settings::default();
    let classic = |length: f64, shape: ReliefShape| ReliefDesign {
        tip: [deflection; 2],
        root: [0.0; 2],
        length,
        shape,
    };

    // The trust-region loop from two starts per shape.
    let loop_started = std::time::Instant::now();
    let starts = [
        (ReliefShape::Linear, "none"),
        (ReliefShape::Linear, "classic"),
        (ReliefShape::Parabolic, "none"),
        (ReliefShape::Parabolic, "classic"),
    ];
    let mut optima = Vec::new();
    let mut start_lines = Vec::new();
    let mut skipped = Vec::new();
    for (s, (shape, start_name)) in starts.iter().enumerate() {
        let stage = format!("optimizing ({} relief from {start_name})", shape.name());
        progress(&stage, s, starts.len());
        let start = match *start_name {
            "none" => ReliefDesign::none(*shape),
            _ => classic(1.0, *shape),
        };
        let t = std::time::Instant::now();
        let report = |r: &robust::IterationRecord| {
            let line = format!(
                "{stage}: iteration {}, objective {:.4} um, trust radius {:.3}",
                r.iteration, r.objective_um, r.trust_radius
            );
            progress(&line, s, starts.len());
        };
        let optimum = match robust::optimize(&respond, &start, &range, &limits, &settings, &report)
        {
            Ok(optimum) => optimum,
            Err(OptimizeError::InfeasibleStart(reason)) => {
                skipped.push(format!("{} from {start_name}: {reason}", shape.name()));
                continue;
            }
            Err(e) => return Err(e.into()),
        };
        start_lines.push(StartSummary {
            shape: *shape,
            start: start_name.to_string(),
            objective_start_um: optimum.start.response.objective_um,
            objective_um: optimum.best.response.objective_um,
            iterations: optimum.iterations.len(),
            stop: optimum.stop,
            failure: optimum.failure.clone(),
            ltca_evaluations: optimum.ltca_evaluations,
            qp_solve_wall_s: optimum.qp_solve_s,
            wall_s: t.elapsed().as_secs_f64(),
        });
        optima.push((format!("{}-from-{start_name}", shape.name()), optimum));
    }
    progress("optimizing", starts.len(), starts.len());
    let qp_loop_s = loop_started.elapsed().as_secs_f64();
    if optima.is_empty() {
        return Err(StudyError::Input(format!(
            "no start keeps the limits, so there is nothing to optimize from: {}. Loosen \
             --min-contact-ratio, --max-relief-um, --max-root-stress-mpa or \
             --max-contact-pressure-mpa",
            skipped.join("; ")
        )));
    }

    // Candidates: the baselines, then the distinct optima best first.
    let mut order: Vec<usize> = (0..optima.len()).collect();
    order.sort_by(|&a, &b| {
        optima[a]
            .1
            .best
            .response
            .objective_um
            .total_cmp(&optima[b].1.best.response.objective_um)
    });
    let mut chosen: Vec<usize> = Vec::new();
    for i in order {
        let x = optima[i].1.best.design.to_vector();
        let same = chosen.iter().any(|&j| {
            let y = optima[j].1.best.design.to_vector();
            optima[j].1.best.design.shape == optima[i].1.best.design.shape
                && (0..4).all(|k| (x[k] - y[k]).abs() < DISTINCT_AMOUNT)
                && (x[4] - y[4]).abs() < DISTINCT_LENGTH
        });
        if !same && chosen.len() < CANDIDATES {
            chosen.push(i);
        }
    }
    let mut plan: Vec<(
        String,
        CandidateKind,
        Option<ReliefDesign>,
        [FlankModification; 2],
    )> = Vec::new();
    if !case
        .relief_variants
        .iter()
        .any(|v| super::is_unmodified(&v.modifications))
    {
        let none = ReliefDesign::none(ReliefShape::Linear);
        plan.push((
            "none".into(),
            CandidateKind::Baseline,
            Some(none),
            [FlankModification::none(); 2],
        ));
    }
    for variant in &case.relief_variants {
        plan.push((
            variant.name.clone(),
            CandidateKind::Baseline,
            None,
            variant.modifications,
        ));
    }
    for (name, design) in [
        ("classic-long", classic(1.0, ReliefShape::Linear)),
        ("classic-short", classic(0.5, ReliefShape::Linear)),
    ] {
        plan.push((
            name.into(),
            CandidateKind::Baseline,
            Some(design),
            design
                .modifications(pair)
                .map_err(|e| StudyError::Input(e.to_string()))?,
        ));
    }
    for (rank, &i) in chosen.iter().enumerate() {
        let design = optima[i].1.best.design;
        plan.push((
            format!("optimum-{}", rank + 1),
            CandidateKind::Optimum,
            Some(design),
            design
                .modifications(pair)
                .map_err(|e| StudyError::Input(e.to_string()))?,
        ));
    }
    let mut candidates = Vec::new();
    let count = plan.len();
    for (c, (name, kind, design, modifications)) in plan.into_iter().enumerate() {
        progress("judging the candidates", c, count);
        candidates.push(judge(
            case,
            &model,
            (name, kind, design, modifications),
            (&range, &harris_range, torque),
            &limits,
            options,
        )?);
    }

    progress("re-meshing the optimum", 0, 1);
    let remeshed = remeshed_check(case, &candidates, torque, options.positions)?;
    let summary = summarize(
        case,
        (torque, deflection, hub_deflection),
        (&range, &limits, &optima, &chosen),
        &candidates,
        (start_lines, skipped),
        remeshed,
        (model_s, qp_loop_s, started.elapsed().as_secs_f64()),
    )?;
    Ok(OptimizeStudy {
        design_torque: torque,
        range,
        harris_range,
        rpms: options.rpm.0.clone(),
        optima,
        candidates,
        summary,
    })
}

/// One candidate through the load range, the Harris map, the design torque and the lumped sweep.
fn judge(
    case: &Case,
    model: &LtcaModel,
    (name, kind, design, modifications): (
        String,
        CandidateKind,
        Option<ReliefDesign>,
        [FlankModification; 2],
    ),
    (range, harris_range, torque): (&LoadRange, &LoadRange, f64),
    limits: &robust::Limits,
    options: &OptimizeOptions,
) -> Result<Candidate, StudyError> {
    let pair = &case.pair;
    let response = load_response(model, &modifications, range, options.positions)?;
    let harris = load_response(model, &modifications, harris_range, options.positions)?;
    let at_design = model
        .with_relief(&modifications)
        .run(options.positions, torque, &|_| {})?;
    let rb2 = pair.gears[1].base_radius;
    let ste: Vec<f64> = at_design.iter().map(|r| r.ste * rb2 * 1e6).collect();
    let mesh_stiffness = stiffness::from_ltca(pair, &at_design, torque, format!("ltca ({name})"))
        .map_err(StudyError::Input)?;
    // The sweep stage's model: with the load-dependent law, the candidate's own.
    let law = match case.lumped.force_law {
        crate::lumped::ForceLawKind::LoadDependent => Some(super::lumped::force_law_of(
            case,
            &model.with_relief(&modifications),
            torque,
            &format!("ltca ({name})"),
        )?),
        crate::lumped::ForceLawKind::Secant => None,
    };
    // The LTCA's k and law run hub to hub: the case's bodies carry the twist.
    let (rim_mesh, law) = super::lumped::to_rims(
        mesh_stiffness.clone(),
        law,
        super::lumped::structure_body_compliance(case)?,
    )?;
    let (mut lumped, _) = super::lumped::model_on(case, rim_mesh, torque)?;
    lumped.force_law = law;
    // A diverged sweep does not end the study: the candidate keeps the speeds before it.
    let progress = sweep::continue_sweep(
        &lumped,
        &options.rpm.0,
        sweep::SweepProgress::start(&lumped),
        &|| false,
    );
    let diverged = progress.diverged.as_ref().map(|d| d.to_string());
    let up = progress.up;
    let as_design = design.unwrap_or_else(|| amounts_of(&modifications));
    let ends = end_relief(&as_design);
    let feasible = robust::feasible(
        &robust::Evaluation {
            design: as_design,
            response: response.clone(),
        },
        limits,
    );
    Ok(Candidate {
        name,
        kind,
        design,
        modifications,
        ste_pp_design_um: crate::signal::peak_to_peak(&ste),
        ste_harmonics_design_um: {
            let a = crate::signal::harmonic_amplitudes(&ste, 1.0 / ste.len() as f64, 1.0, 3);
            [a[0], a[1], a[2]]
        },
        roll_deg: at_design
            .iter()
            .map(|r| r.roll_angle.to_degrees())
            .collect(),
        ste_design_um: ste,
        contact_ratio_design: model.loaded_contact_ratio(&at_design),
        end_relief_um: ends.map(|e| e * 1e6),
        feasible,
        response,
        harris,
        mesh_stiffness,
        sweep: candidate_sweep(&up, &options.rpm.0, diverged),
    })
}

/// The amounts of any modification pair as a design (length 1: a case variant's own zones
/// need not be of the optimizer's family; its amounts are what the limits read).
fn amounts_of(modifications: &[FlankModification; 2]) -> ReliefDesign {
    let amount = |z: Option<crate::geometry::ReliefZone>| z.map_or(0.0, |z| z.amount);
    ReliefDesign {
        tip: [amount(modifications[0].tip), amount(modifications[1].tip)],
        root: [amount(modifications[0].root), amount(modifications[1].root)],
        length: 1.0,
        shape: ReliefShape::Linear,
    }
}

fn candidate_sweep(up: &[SweepPoint], rpms: &[f64], diverged: Option<String>) -> CandidateSweep {
    let (at, max) = up
        .iter()
        .enumerate()
        .map(|(i, p)| (i, p.dynamic_factor))
        .fold((0, 0.0), |m, (i, d)| if d > m.1 { (i, d) } else { m });
    CandidateSweep {
        max_dynamic_factor: max,
        max_dynamic_factor_rpm: rpms[at],
        dynamic_factor: up.iter().map(|p| p.dynamic_factor).collect(),
        dte_rms_um: up.iter().map(|p| p.dte_rms * 1e6).collect(),
        separated_points: up.iter().filter(|p| p.separated).count(),
        diverged,
    }
}

#[allow(clippy::type_complexity)]
fn summarize(
    case: &Case,
    (torque, deflection, hub_deflection): (f64, f64, f64),
    (range, limits, optima, chosen): (&LoadRange, &robust::Limits, &[(String, Optimum)], &[usize]),
    candidates: &[Candidate],
    (starts, skipped_starts): (Vec<StartSummary>, Vec<String>),
    remeshed: RemeshedCheck,
    (model_s, qp_loop_s, wall_s): (f64, f64, f64),
) -> Result<OptimizeSummary, StudyError> {
    let find = |name: &str| candidates.iter().find(|c| c.name == name);
    let best = &optima[chosen[0]].1;
    let design = best.best.design;
    let deg = |z: Option<crate::geometry::ReliefZone>| z.map(|z| z.start_roll_angle.to_degrees());
    let first_relief = case
        .relief_variants
        .iter()
        .find(|v| !super::is_unmodified(&v.modifications));
    let objective = |name: &str| find(name).map(|c| c.response.objective_um);
    // The study always judges an unmodified baseline (the case's, or its own "none").
    let unmodified = candidates
        .iter()
        .find(|c| super::is_unmodified(&c.modifications))
        .expect("an unmodified baseline is always judged");
    let optimum = find(BEST).expect("the best optimum is a candidate");
    let modifications = &optimum.modifications;
    let max_of = |[a, b]: [f64; 2]| a.max(b);
    Ok(OptimizeSummary {
        case: case.name().to_string(),
        design_torque_nm: torque,
        torque_range_nm: range.torques.clone(),
        positions: optimum.response.ste_um[0].len(),
        limits: *limits,
        single_pair_deflection_um: deflection * 1e6,
        single_pair_deflection_hub_um: hub_deflection * 1e6,
        shape: design.shape,
        tip_relief_um: design.tip.map(|a| a * 1e6),
        root_relief_um: design.root.map(|a| a * 1e6),
        relief_length_fraction: design.length,
        start_roll_deg: StartRoll {
            tip: [deg(modifications[0].tip), deg(modifications[1].tip)],
            root: [deg(modifications[0].root), deg(modifications[1].root)],
        },
        ste_pp_before_um: unmodified.ste_pp_design_um,
        ste_pp_after_um: optimum.ste_pp_design_um,
        objective_none: unmodified.response.objective_um,
        objective_optimum: optimum.response.objective_um,
        paper_variant: first_relief.map(|v| v.name.clone()),
        objective_paper: first_relief.and_then(|v| objective(&v.name)),
        objective_classic: objective("classic-long").unwrap_or(f64::NAN),
        objective_classic_short: objective("classic-short").unwrap_or(f64::NAN),
        contact_ratio_optimum: optimum.response.contact_ratio.clone(),
        max_root_stress_mpa: limits.max_root_stress.map(|l| l.map(|l| l * 1e-6)),
        max_contact_pressure_mpa: limits.max_contact_pressure.map(|l| l * 1e-6),
        root_stress_none_mpa: max_of(unmodified.response.root_stress_peak_mpa()),
        root_stress_optimum_mpa: max_of(optimum.response.root_stress_peak_mpa()),
        contact_pressure_none_mpa: unmodified.response.contact_pressure_peak_mpa(),
        contact_pressure_optimum_mpa: optimum.response.contact_pressure_peak_mpa(),
        iterations: best.iterations.len(),
        iterations_all_starts: optima.iter().map(|(_, o)| o.iterations.len()).sum(),
        ltca_evaluations: optima.iter().map(|(_, o)| o.ltca_evaluations).sum(),
        qp_solve_wall_s: optima.iter().map(|(_, o)| o.qp_solve_s).sum(),
        qp_loop_wall_s: qp_loop_s,
        model_wall_s: model_s,
        wall_s,
        starts,
        skipped_starts,
        remeshed,
        candidates: candidates
            .iter()
            .map(|c| CandidateLine {
                name: c.name.clone(),
                kind: c.kind,
                tip_relief_um: amounts_of(&c.modifications).tip.map(|a| a * 1e6),
                root_relief_um: amounts_of(&c.modifications).root.map(|a| a * 1e6),
                relief_length_fraction: c.design.map(|d| d.length),
                shape: c.design.map(|d| d.shape),
                objective_um: c.response.objective_um,
                ste_pp_design_um: c.ste_pp_design_um,
                contact_ratio_min: c
                    .response
                    .contact_ratio
                    .iter()
                    .copied()
                    .fold(f64::INFINITY, f64::min),
                root_stress_max_mpa: c.response.root_stress_peak_mpa(),
                contact_pressure_max_mpa: c.response.contact_pressure_peak_mpa(),
                feasible: c.feasible,
                max_dynamic_factor: c.sweep.max_dynamic_factor,
                max_dynamic_factor_rpm: c.sweep.max_dynamic_factor_rpm,
                sweep_diverged: c.sweep.diverged.clone(),
            })
            .collect(),
        fe_check: None,
        interrupted: None,
        model: "LTCA on the unmodified bodies meshed once (case mesh); the relief enters as the initial gap of the exact modified profiles; frictionless, quasi-static; STE = r_b2 phi of the driven gear",
    })
}

/// The explicit-FE scenes of the cross-check: the case's stiffness scene (low speed, the
/// quasi-static DTE over a base pitch) and its high-speed scene (the seed paper's 3000 rpm),
/// each run with the candidate's relief.
pub const FE_CHECK_SCENES: [&str; 2] =
    [super::compare::STIFFNESS_SCENE, super::compare::SPEED_SCENE];

/// The case changes that give the cross-check scenes the unmodified pair (the case's own
/// unmodified variant, else a variant `none`): the same changes [`fe_check_overrides`] makes for
/// the unmodified baseline, so its runs are one effective case.
pub fn unmodified_fe_overrides(case: &Case) -> Vec<Override> {
    let own = case
        .relief_variants
        .iter()
        .find(|v| super::is_unmodified(&v.modifications));
    let mut overrides = Vec::new();
    let name = match own {
        Some(v) => v.name.clone(),
        None => {
            overrides.push(variant_override(
                "none",
                &[FlankModification::none(); 2],
                ReliefShape::Linear,
            ));
            "none".into()
        }
    };
    overrides.extend(scene_relief_overrides(&name));
    overrides
}

/// A relief variant `name` of `modifications` (zones with their amount, `shape` and start).
fn variant_override(
    name: &str,
    modifications: &[FlankModification; 2],
    shape: ReliefShape,
) -> Override {
    let mut table = toml::Table::new();
    table.insert("name".into(), name.into());
    for (g, modification) in modifications.iter().enumerate() {
        let mut gear = toml::Table::new();
        for (end, zone) in [("tip", modification.tip), ("root", modification.root)] {
            if let Some(zone) = zone {
                let mut spec = toml::Table::new();
                spec.insert("amount_um".into(), (zone.amount * 1e6).into());
                spec.insert("shape".into(), shape.name().into());
                spec.insert(
                    "start_roll_deg".into(),
                    zone.start_roll_angle.to_degrees().into(),
                );
                gear.insert(end.into(), spec.into());
            }
        }
        if !gear.is_empty() {
            table.insert(format!("gear{}", g + 1), gear.into());
        }
    }
    Override::Append {
        array: "relief_variant".into(),
        table,
    }
}

/// The cross-check scenes set to relief variant `name`.
fn scene_relief_overrides(name: &str) -> Vec<Override> {
    FE_CHECK_SCENES
        .iter()
        .map(|scene| Override::set(format!("scene[{scene}].relief"), name))
        .collect()
}

/// The case changes that give the cross-check scenes `candidate`'s relief: a relief variant of
/// the candidate's name (a case variant is used as it is) set as the scenes' relief.
pub fn fe_check_overrides(case: &Case, candidate: &Candidate) -> Result<Vec<Override>, StudyError> {
    let mut overrides = Vec::new();
    if let Some(design) = &candidate.design {
        if case.relief_variant(&candidate.name).is_some() {
            return Err(StudyError::Input(format!(
                "the case already has a relief variant {:?}: rename it to run the FE cross-check",
                candidate.name
            )));
        }
        overrides.push(variant_override(
            &candidate.name,
            &candidate.modifications,
            design.shape,
        ));
    }
    overrides.extend(scene_relief_overrides(&candidate.name));
    Ok(overrides)
}

/// What the cross-check reads of one explicit run.
#[derive(Debug, Clone)]
pub struct FeCheckRun {
    pub dte: super::compare::FeDte,
    pub dte_peak_to_peak_rad: f64,
    /// Of the DTE low-passed over the mesh mode's period (the quasi-static part).
    pub dte_lowpass_peak_to_peak_rad: Option<f64>,
    /// The LTCA's STE peak-to-peak on the run's own (explicit) mesh.
    pub ltca_same_mesh_peak_to_peak_rad: Option<f64>,
    pub impact_d1_max_n: Option<f64>,
    pub mesh_frequency_hz: f64,
}

/// One candidate's row of the cross-check: the LTCA's prediction against the FE's result.
#[derive(Debug, Clone, Serialize)]
pub struct FeCheckLine {
    pub candidate: String,
    pub kind: CandidateKind,
    /// LTCA at the design torque, case mesh and the explicit run's mesh [µm]; the case mesh's
    /// first mesh harmonic [µm].
    pub ltca_ste_pp_um: f64,
    pub ltca_ste_h1_um: f64,
    pub ltca_same_mesh_ste_pp_um: Option<f64>,
    /// Low speed: the quasi-static DTE peak-to-peak (low-passed) and raw [µm].
    pub fe_low_dte_lowpass_pp_um: Option<f64>,
    pub fe_low_dte_pp_um: Option<f64>,
    /// High speed: DTE peak-to-peak, first three mesh-harmonic amplitudes [µm] over the
    /// statistics window, largest db5 level-1 detail of the contact force [N].
    pub fe_high_dte_pp_um: Option<f64>,
    pub fe_high_harmonics_um: Option<[f64; 3]>,
    pub fe_high_impact_d1_max_n: Option<f64>,
    /// The lumped sweep's dynamic factor at the speed nearest the high-speed scene's.
    pub lumped_dynamic_factor_high: Option<f64>,
    /// Why a run is missing (diverged, failed).
    pub fe_errors: Vec<String>,
}

/// The cross-check table with the rankings compared.
#[derive(Debug, Clone, Serialize)]
pub struct FeCheck {
    pub lines: Vec<FeCheckLine>,
    /// Candidates by the LTCA's STE peak-to-peak at the design torque, best first.
    pub ltca_ranking: Vec<String>,
    /// By the FE's low-speed quasi-static DTE peak-to-peak, best first (runs that finished):
    /// low-passed when every run has it, else raw for all.
    pub fe_low_ranking: Vec<String>,
    pub fe_low_measure: &'static str,
    /// Candidates by the LTCA STE's first mesh harmonic, and by the FE's high-speed DTE's.
    pub ltca_h1_ranking: Vec<String>,
    pub fe_high_ranking: Vec<String>,
    /// Kendall's τ between each LTCA ranking and its FE ranking (1: the same order).
    pub kendall_tau_low: Option<f64>,
    pub kendall_tau_high: Option<f64>,
    /// The FE puts the best optimum ahead of every baseline at low speed.
    pub optimum_first_low: Option<bool>,
    pub optimum_first_high: Option<bool>,
    pub fe_wall_s: f64,
}

/// Which candidates and scenes the FE cross-check runs.
#[derive(Debug, Clone, PartialEq)]
pub struct FeCheckPlan {
    /// Only the unmodified baseline and the best optimum; else every candidate.
    pub baseline_and_best_only: bool,
    /// Only these candidates (by name), if given.
    pub only: Option<Vec<String>>,
    /// Which of [`FE_CHECK_SCENES`] (low, high).
    pub scenes: [bool; 2],
}

impl FeCheckPlan {
    /// Every candidate at both speeds.
    pub fn full() -> Self {
        FeCheckPlan {
            baseline_and_best_only: false,
            only: None,
            scenes: [true, true],
        }
    }

    /// The unmodified baseline and the best optimum at low speed: the check the main job runs.
    pub fn baseline_and_best() -> Self {
        FeCheckPlan {
            baseline_and_best_only: true,
            only: None,
            scenes: [true, false],
        }
    }

    pub fn includes(&self, candidate: &Candidate) -> bool {
        let listed = self
            .only
            .as_ref()
            .is_none_or(|names| names.contains(&candidate.name));
        listed
            && (!self.baseline_and_best_only
                || candidate.name == BEST
                || super::is_unmodified(&candidate.modifications))
    }
}

/// One checked candidate's runs, one per [`FE_CHECK_SCENES`] (None: not asked for).
pub type CandidateRuns = [Option<Result<FeCheckRun, String>>; 2];

/// Tabulates the FE runs of the candidates (`runs[i]` belongs to `study.candidates[i]`; None:
/// the candidate was not checked).
pub fn fe_check(study: &OptimizeStudy, runs: &[Option<CandidateRuns>], rb2: f64) -> FeCheck {
    let um = |rad: f64| rad * rb2 * 1e6;
    let mut lines = Vec::new();
    let mut wall = 0.0;
    for (candidate, runs) in study.candidates.iter().zip(runs) {
        let Some([low, high]) = runs else { continue };
        let mut errors = Vec::new();
        for (scene, run) in FE_CHECK_SCENES.iter().zip([low, high]) {
            match run {
                Some(Ok(r)) => wall += r.dte.wall_s,
                Some(Err(e)) => errors.push(format!("{scene}: {e}")),
                None => {}
            }
        }
        let low = low.as_ref().and_then(|r| r.as_ref().ok());
        let high = high.as_ref().and_then(|r| r.as_ref().ok());
        // Harmonics need at least one whole mesh period in the statistics window.
        let whole_period = |h: &&FeCheckRun| {
            let (_, stats) = h.dte.window_starts();
            (h.dte.dte.len() - stats) as f64 * h.dte.dt * h.mesh_frequency_hz >= 1.0
        };
        let harmonics = high.filter(whole_period).map(|h| {
            let (_, stats) = h.dte.window_starts();
            let a = crate::signal::harmonic_amplitudes(
                &h.dte.dte[stats..],
                h.dte.dt,
                h.mesh_frequency_hz,
                3,
            );
            [um(a[0]), um(a[1]), um(a[2])]
        });
        let nearest = high.and_then(|h| crate::signal::nearest_index(&study.rpms, h.dte.speed_rpm));
        lines.push(FeCheckLine {
            candidate: candidate.name.clone(),
            kind: candidate.kind,
            ltca_ste_pp_um: candidate.ste_pp_design_um,
            ltca_ste_h1_um: candidate.ste_harmonics_design_um[0],
            ltca_same_mesh_ste_pp_um: low.and_then(|l| l.ltca_same_mesh_peak_to_peak_rad.map(um)),
            fe_low_dte_lowpass_pp_um: low.and_then(|l| l.dte_lowpass_peak_to_peak_rad.map(um)),
            fe_low_dte_pp_um: low.map(|l| um(l.dte_peak_to_peak_rad)),
            fe_high_dte_pp_um: high.map(|h| um(h.dte_peak_to_peak_rad)),
            fe_high_harmonics_um: harmonics,
            fe_high_impact_d1_max_n: high.and_then(|h| h.impact_d1_max_n),
            lumped_dynamic_factor_high: nearest.map(|i| candidate.sweep.dynamic_factor[i]),
            fe_errors: errors,
        });
    }
    let ranking = |value: &dyn Fn(&FeCheckLine) -> Option<f64>| {
        let mut ranked: Vec<(&str, f64)> = lines
            .iter()
            .filter_map(|l| value(l).map(|v| (l.candidate.as_str(), v)))
            .collect();
        ranked.sort_by(|a, b| a.1.total_cmp(&b.1));
        ranked
            .into_iter()
            .map(|(n, _)| n.to_string())
            .collect::<Vec<_>>()
    };
    let ltca_ranking = ranking(&|l| Some(l.ltca_ste_pp_um));
    let lowpass_everywhere = lines
        .iter()
        .all(|l| l.fe_low_dte_pp_um.is_none() || l.fe_low_dte_lowpass_pp_um.is_some());
    let (fe_low_ranking, fe_low_measure) = if lowpass_everywhere {
        (
            ranking(&|l| l.fe_low_dte_lowpass_pp_um),
            "low-passed DTE peak-to-peak",
        )
    } else {
        (ranking(&|l| l.fe_low_dte_pp_um), "raw DTE peak-to-peak")
    };
    let ltca_h1_ranking = ranking(&|l| Some(l.ltca_ste_h1_um));
    let fe_high_ranking = ranking(&|l| l.fe_high_harmonics_um.map(|h| h[0]));
    let first = |fe: &[String]| {
        let best = study
            .candidates
            .iter()
            .find(|c| c.kind == CandidateKind::Optimum)?;
        let position = |name: &str| fe.iter().position(|n| n == name);
        let at = position(&best.name)?;
        Some(
            study
                .candidates
                .iter()
                .filter(|c| c.kind == CandidateKind::Baseline)
                .all(|c| position(&c.name).is_none_or(|p| p > at)),
        )
    };
    FeCheck {
        kendall_tau_low: kendall_tau(&ltca_ranking, &fe_low_ranking),
        kendall_tau_high: kendall_tau(&ltca_h1_ranking, &fe_high_ranking),
        optimum_first_low: first(&fe_low_ranking),
        optimum_first_high: first(&fe_high_ranking),
        lines,
        ltca_ranking,
        fe_low_ranking,
        fe_low_measure,
        ltca_h1_ranking,
        fe_high_ranking,
        fe_wall_s: wall,
    }
}

/// Kendall's τ_a of two rankings over the names both hold: (concordant − discordant) pairs over
/// all pairs; None with fewer than two common names.
pub fn kendall_tau(a: &[String], b: &[String]) -> Option<f64> {
    let common: Vec<&String> = a.iter().filter(|n| b.contains(n)).collect();
    let n = common.len();
    if n < 2 {
        return None;
    }
    let rank_b = |name: &String| b.iter().position(|m| m == name).expect("common");
    let mut score = 0i64;
    for i in 0..n {
        for j in i + 1..n {
            // In a, common[i] is ahead of common[j].
            score += if rank_b(common[i]) < rank_b(common[j]) {
                1
            } else {
                -1
            };
        }
    }
    Some(score as f64 / (n * (n - 1) / 2) as f64)
}
