//! The robust relief optimizer: the relief that keeps the loaded static transmission error flat
//! over a load range, by sequential linearization and a Clarabel QP with a trust region.
//!
//! # Problem
//! Variables v = (C_a1, C_f1, C_a2, C_f2 in µm, 10·λ) ([`super::relief::ReliefDesign`]); loaded
//! STE s_ij(v) = r_b2 φ at position i and torque T_j from the LTCA on fixed bodies
//! ([`LtcaModel::with_relief`]). Objective, the weighted peak-to-peak over the load range plus a
//! small regularization that breaks ties between designs the STE cannot tell apart:
//! ```text
//! f(v) = Σ_j w_j (max_i s_ij − min_i s_ij) + ρ Σ_k r_k c_k,   Σ_j w_j = 1
//! ```
//! with c ≥ 0 the four amounts [µm] and r_k = 1 for tip, [`ROOT_WEIGHT`] for root relief: an L1
//! penalty, which moves a design only where the objective is flatter than ρ r_k µm per µm. It
//! decides what the STE cannot: with one λ for all zones, gear 1's tip zone and
//! gear 2's root zone cover the same stretch of the path of contact with the same shape, so the
//! STE sees only the sums C_a1 + C_f2 (end of recess) and C_a2 + C_f1 (start of approach) on the
//! path of contact (beyond its ends a root zone keeps growing where a tip zone has ended). The
//! split goes to the tips (the L1 penalty picks the corner, where a quadratic one would split
//! 4 : 1), as root relief near the fillet is the costlier to grind; root relief appears only
//! where a tip amount reaches its bound.
//!
//! Subject to bounds v_lo ≤ v ≤ v_hi; no loss of contact at the design torque — the combined
//! relief at each end of the path (C_a1 + C_f2 at the end of recess, C_a2 + C_f1 at the start of
//! approach) at most the single-pair deflection δ_s of the unmodified pair (its largest approach
//! over the cycle at the design torque, rim to rim: the one load the other pair carries alone
//! as the relieved end comes into or out of contact), beyond which the relieved end is not
//! reached under the design load (Smith, *Gear Noise and Vibration*, §3.3); and the loaded contact ratio ε_j ([`LtcaModel::loaded_contact_ratio`]) ≥ ε_min at every torque.
//! Optionally, strength limits at every position i and torque j: each gear's tooth-root tension
//! σ_ijg (the largest principal stress on the loaded fillets, [`crate::ltca::PositionResult::root_stress`])
//! ≤ σ_max,g, and the largest Hertz pressure p_ij of the pairs in contact ([`crate::strength::hertz`],
//! with the involute's curvature at every contact: continuous in the design as a pair's force
//! fades at the path's ends, where leaving out the tip zones would make p_ij jump as a relief
//! moves a contact across the zone's edge) ≤ p_max. A
//! relief moves load along the flank: it lengthens single contact towards the tip (the root
//! stress rises, as the same load acts on a longer arm) and towards the root (the curvature
//! radii shrink, the pressure rises), which these limits bound.
//!
//! # Method
//! Each iteration linearizes s_ij and ε_j about v₀ by forward differences (one LTCA per
//! variable, every torque solved on one contact search per position) and solves the epigraph QP
//! in (Δv, u, l):
//! ```text
//! minimize   Σ_j w_j (u_j − l_j) + ρ Σ_k r_k Δc_k     (a linear program in the trust region)
//! subject to l_j ≤ s_ij + ∇s_ij·Δv ≤ u_j,   ε_j + ∇ε_j·Δv ≥ ε_min,   linear limits,
//!            σ_ijg + ∇σ_ijg·Δv ≤ σ_max,   p_ij + ∇p_ij·Δv ≤ p_max   (when given),
//!            |Δv_k| ≤ Δ  (trust region),     v_lo ≤ v₀ + Δv ≤ v_hi
//! ```
//! A stress row enters the QP only where it can bind inside the trust region
//! (σ + Δ·‖∇σ‖₁ ≥ σ_max), which keeps the QP small: most positions are far below the peak.
//! The step is re-evaluated with the LTCA; with ρ = actual/predicted reduction it is accepted
//! when ρ ≥ 0.1 and ε_j ≥ ε_min holds in the LTCA (a rejected step keeps the linearization for
//! the next, smaller one), and the radius grows (×2, ρ ≥ 0.75 on the
//! boundary) or shrinks (×½, ρ < 0.25) — the basic trust-region method of Nocedal & Wright,
//! *Numerical Optimization*, Alg. 4.1, with the model's max terms kept exact by the epigraph.
//! It stops when the predicted reduction is below the tolerance or the radius below 1e-3 ([`Stop`]).

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

use super::qp::{self, QpError, QuadraticProgram};
use super::relief::{ReliefDesign, VARIABLES};
use crate::geometry::{FlankModification, GeometryError, ReliefShape};
use crate::ltca::{LtcaError, LtcaModel};
use crate::strength::hertz;
use crate::strength::iso6336::Elastic;

#[derive(Debug, thiserror::Error)]
pub enum OptimizeError {
    #[error("{0}")]
    Input(String),
    #[error(transparent)]
    Geometry(#[from] GeometryError),
    #[error(transparent)]
    Ltca(#[from] LtcaError),
    #[error(transparent)]
    Qp(#[from] QpError),
    /// The start design breaks a limit: the loop does not repair a start silently.
    #[error("{0}")]
    InfeasibleStart(String),
    /// A response with NaN or infinity in it.
    #[error("{0}")]
    NotFinite(String),
}

/// Scale of the variables: amounts in µm, λ in tenths.
const SCALE: [f64; VARIABLES] = [1e-6, 1e-6, 1e-6, 1e-6, 0.1];

/// The load range of the robust objective.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LoadRange {
    /// Torques on the driven gear [N·m].
    pub torques: Vec<f64>,
    /// Weights w_j, summing to 1.
    pub weights: Vec<f64>,
}

impl LoadRange {
    /// `count` torques evenly from `from` to `to` (fractions of `design`), equal weights.
    pub fn uniform(design: f64, from: f64, to: f64, count: usize) -> Result<Self, OptimizeError> {
        if !(from > 0.0 && to >= from && to.is_finite() && count >= 1 && (count > 1 || from == to))
        {
            return Err(OptimizeError::Input(format!(
                "torque range {from}:{to}:{count} is invalid: use FROM:TO:N with 0 < FROM ≤ TO \
                 (fractions of the design torque) and N ≥ 2 torques (N = 1 only with FROM = TO)"
            )));
        }
        let torques = (0..count)
            .map(|j| {
                let f = if count == 1 {
                    from
                } else {
                    from + (to - from) * j as f64 / (count - 1) as f64
                };
                f * design
            })
            .collect();
        Ok(LoadRange {
            torques,
            weights: vec![1.0 / count as f64; count],
        })
    }
}

/// The limits a design must keep.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Limits {
    /// Largest relief amount [m] (manufacturing).
    pub max_amount: f64,
    /// Shortest relief, as the fraction λ of the double-contact zone.
    pub min_length: f64,
    /// Smallest loaded contact ratio at any torque of the range.
    pub min_contact_ratio: f64,
    /// Single-pair deflection δ_s of the unmodified pair at the design torque, rim to rim [m]:
    /// the combined relief at each end of the path may not exceed it (no loss of contact at the
    /// design torque).
    pub contact_deflection: f64,
    /// Largest tooth-root tension of gear 1 and gear 2 at any position and torque [Pa] (None:
    /// no limit).
    pub max_root_stress: Option<[f64; 2]>,
    /// Largest Hertz pressure at any position and torque [Pa] (None: no limit).
    pub max_contact_pressure: Option<f64>,
}

/// A strength limit holds to this share of itself: the LTCA's response is piecewise smooth
/// (its maxima over nodes and pairs have kinks), so a linearized step lands a little beyond an
/// active limit; 0.1 % is below the fillet stress's own discretization error at the default
/// mesh (validation/strength: 76.9 → 77.0 → 77.1 MPa from 0.2 to 0.05 mm, 0.3 %).
pub const STRESS_LIMIT_TOLERANCE: f64 = 1e-3;

/// Settings of the iteration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Settings {
    /// ρ [µm of objective per µm of tip relief] of the L1 regularization.
    pub regularization: f64,
    /// Initial trust radius [scaled units: µm, or tenths of λ].
    pub initial_radius: f64,
    pub max_iterations: usize,
    /// Stop when the predicted reduction is below this [µm].
    pub tolerance_um: f64,
    /// Forward-difference step [scaled units].
    pub step: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            regularization: 1e-3,
            initial_radius: 4.0,
            max_iterations: 30,
            tolerance_um: 1e-5,
            step: 0.25,
        }
    }
}

/// The loaded STE of one relief over a load range.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LoadResponse {
    /// Loaded STE r_b2 φ [µm], `[torque][position]`.
    pub ste_um: Vec<Vec<f64>>,
    /// STE peak-to-peak per torque [µm].
    pub ste_pp_um: Vec<f64>,
    /// Loaded contact ratio per torque.
    pub contact_ratio: Vec<f64>,
    /// Mean secant mesh stiffness per torque [N/m].
    pub mesh_stiffness_mean: Vec<f64>,
    /// The robust objective Σ w_j pp_j [µm] (without the regularization).
    pub objective_um: f64,
    /// Largest KKT residual of the contact solves.
    pub max_kkt_residual: f64,
    /// Tooth-root tension of gear 1 and gear 2 [MPa], `[torque][position]`: the largest
    /// principal stress on each gear's loaded fillets.
    pub root_stress_mpa: Vec<Vec<[f64; 2]>>,
    /// The largest Hertz pressure of the pairs in contact [MPa] (0 where none),
    /// `[torque][position]`.
    pub contact_pressure_mpa: Vec<Vec<f64>>,
}

impl LoadResponse {
    /// Each gear's largest root tension over the load range [MPa].
    pub fn root_stress_peak_mpa(&self) -> [f64; 2] {
        std::array::from_fn(|g| {
            self.root_stress_mpa
                .iter()
                .flatten()
                .map(|s| s[g])
                .fold(f64::NEG_INFINITY, f64::max)
        })
    }

    /// The largest Hertz pressure over the load range [MPa].
    pub fn contact_pressure_peak_mpa(&self) -> f64 {
        self.contact_pressure_mpa
            .iter()
            .flatten()
            .copied()
            .fold(0.0, f64::max)
    }
}

/// Per position of `run`, the largest Hertz pressure of its pairs in contact [MPa] (0 where
/// none).
fn contact_pressures(model: &LtcaModel, run: &[crate::ltca::PositionResult]) -> Vec<f64> {
    let elastic = Elastic {
        youngs_modulus: model.material.youngs_modulus,
        poisson_ratio: model.material.poisson_ratio,
    };
    let mut peak = vec![0.0f64; run.len()];
    for point in hertz::along_path(&model.pair, [elastic; 2], run) {
        peak[point.position] = peak[point.position].max(point.pressure_pa * 1e-6);
    }
    peak
}

/// The LTCA over `range` of `modifications` on `model`'s bodies.
pub fn load_response(
    model: &LtcaModel,
    modifications: &[FlankModification; 2],
    range: &LoadRange,
    positions: usize,
) -> Result<LoadResponse, LtcaError> {
    let runs = model
        .with_relief(modifications)
        .run_torques(positions, &range.torques)?;
    let rb2 = model.pair.gears[1].base_radius;
    let ste_um: Vec<Vec<f64>> = runs
        .iter()
        .map(|run| run.iter().map(|r| r.ste * rb2 * 1e6).collect())
        .collect();
    let ste_pp_um: Vec<f64> = ste_um
        .iter()
        .map(|s| crate::signal::peak_to_peak(s))
        .collect();
    let objective_um = ste_pp_um
        .iter()
        .zip(&range.weights)
        .map(|(pp, w)| pp * w)
        .sum();
    Ok(LoadResponse {
        contact_ratio: runs
            .iter()
            .map(|run| model.loaded_contact_ratio(run))
            .collect(),
        mesh_stiffness_mean: runs
            .iter()
            .map(|run| run.iter().map(|r| r.mesh_stiffness).sum::<f64>() / run.len() as f64)
            .collect(),
        max_kkt_residual: runs
            .iter()
            .flatten()
            .map(|r| r.kkt_residual)
            .fold(0.0, f64::max),
        root_stress_mpa: runs
            .iter()
            .map(|run| {
                run.iter()
                    .map(|r| r.root_stress.map(|s| s * 1e-6))
                    .collect()
            })
            .collect(),
        contact_pressure_mpa: runs
            .iter()
            .map(|run| contact_pressures(model, run))
            .collect(),
        ste_um,
        ste_pp_um,
        objective_um,
    })
}

/// A design evaluated by the LTCA over the load range.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Evaluation {
    pub design: ReliefDesign,
    #[serde(flatten)]
    pub response: LoadResponse,
}

/// Evaluates `design` on `model`'s bodies over `range`.
pub fn evaluate(
    model: &LtcaModel,
    design: &ReliefDesign,
    range: &LoadRange,
    positions: usize,
) -> Result<Evaluation, OptimizeError> {
    let modifications = design.modifications(&model.pair)?;
    Ok(Evaluation {
        design: *design,
        response: load_response(model, &modifications, range, positions)?,
    })
}

/// Why the loop stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Stop {
    /// The linear model predicts less than the tolerance: stationary.
    PredictedReduction,
    /// The trust radius fell below 1e-3 (0.001 µm, or 1e-4 in λ): no step the LTCA can resolve
    /// improves the design — stationary to the response's resolution (its max terms are kinks).
    TrustRadius,
    /// The iteration limit was reached first: not converged.
    Iterations,
    /// A step could not be computed: the QP failed, or the response (the LTCA) failed or came
    /// back not finite. [`Optimum::failure`] says which; the last good design is kept.
    Failed,
}

impl Stop {
    pub fn converged(self) -> bool {
        !matches!(self, Stop::Iterations | Stop::Failed)
    }
}

/// One iteration of the trust-region loop.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IterationRecord {
    pub iteration: usize,
    /// Robust objective at the iterate before the step [µm].
    pub objective_um: f64,
    /// f = objective + regularization at the iterate before the step [µm]: what every accepted
    /// step lowers.
    pub merit_um: f64,
    /// Reduction of f the linear model predicts [µm].
    pub predicted_reduction_um: f64,
    /// Reduction of f the LTCA gives for the step [µm] (NaN: the step was not evaluable).
    pub actual_reduction_um: f64,
    pub trust_radius: f64,
    pub accepted: bool,
    /// The trial design's variables (C_a1, C_f1, C_a2, C_f2 [µm], λ).
    pub trial: [f64; VARIABLES],
    pub qp_iterations: u32,
    pub kkt_residual: f64,
    pub qp_solve_s: f64,
}

/// The result of one start.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Optimum {
    pub shape: ReliefShape,
    pub start: Evaluation,
    pub best: Evaluation,
    pub iterations: Vec<IterationRecord>,
    pub stop: Stop,
    /// What failed when `stop` is [`Stop::Failed`]: the iteration, the cause.
    pub failure: Option<String>,
    /// Time in Clarabel over all iterations [s].
    pub qp_solve_s: f64,
    pub ltca_evaluations: usize,
}

/// The relief amounts among the variables (the regularization's).
const AMOUNTS: usize = 4;

/// Regularization weight r_k of root relief against tip relief (variables C_a1, C_f1, C_a2, C_f2).
pub const ROOT_WEIGHT: f64 = 4.0;
const REGULARIZATION_WEIGHTS: [f64; AMOUNTS] = [1.0, ROOT_WEIGHT, 1.0, ROOT_WEIGHT];

/// f(v): the robust objective plus the regularization of the amounts.
fn merit(evaluation: &Evaluation, regularization: f64) -> f64 {
    let v = scaled(&evaluation.design);
    evaluation.response.objective_um + regularization * weighted_amounts(&v)
}

/// Σ r_k c_k over the scaled amounts (c ≥ 0).
fn weighted_amounts(v: &[f64; VARIABLES]) -> f64 {
    (0..AMOUNTS).map(|k| REGULARIZATION_WEIGHTS[k] * v[k]).sum()
}

fn scaled(design: &ReliefDesign) -> [f64; VARIABLES] {
    let x = design.to_vector();
    std::array::from_fn(|k| x[k] / SCALE[k])
}

/// The design of scaled variables; an amount below [`ZERO_AMOUNT_UM`] (an interior-point
/// solver's round-off of a bound at 0) is no relief zone.
fn unscaled(v: &[f64; VARIABLES], shape: ReliefShape) -> ReliefDesign {
    ReliefDesign::from_vector(
        &std::array::from_fn(|k| {
            if k < AMOUNTS && v[k] < ZERO_AMOUNT_UM {
                0.0
            } else {
                v[k] * SCALE[k]
            }
        }),
        shape,
    )
}

/// The smallest trust radius [scaled units].
const MIN_RADIUS: f64 = 1e-3;

/// Amounts below this [µm] are zero.
const ZERO_AMOUNT_UM: f64 = 1e-4;

/// The bounds of the scaled variables.
fn bounds(limits: &Limits) -> ([f64; VARIABLES], [f64; VARIABLES]) {
    let amount = limits.max_amount / SCALE[0];
    (
        [0.0, 0.0, 0.0, 0.0, limits.min_length / SCALE[4]],
        [amount, amount, amount, amount, 1.0 / SCALE[4]],
    )
}

/// Whether `design` keeps the limits (with a small tolerance for the LTCA's contact ratio).
pub fn feasible(evaluation: &Evaluation, limits: &Limits) -> bool {
    let v = scaled(&evaluation.design);
    let (lo, hi) = bounds(limits);
    let ends = end_relief(&evaluation.design);
    (0..VARIABLES).all(|k| v[k] >= lo[k] - 1e-9 && v[k] <= hi[k] + 1e-9)
        && ends
            .iter()
            .all(|e| *e <= limits.contact_deflection * (1.0 + 1e-9))
        && evaluation
            .response
            .contact_ratio
            .iter()
            .all(|e| *e >= limits.min_contact_ratio - 1e-6)
        && stress_limits_hold(&evaluation.response, limits)
}

/// Whether the response keeps the strength limits (to [`STRESS_LIMIT_TOLERANCE`]).
pub fn stress_limits_hold(response: &LoadResponse, limits: &Limits) -> bool {
    limited_strength(response, limits)
        .iter()
        .all(|(value, limit)| *value <= limit * (1.0 + STRESS_LIMIT_TOLERANCE))
}

/// Every strength value a given limit reads, with that limit, in MPa: each gear's root stress
/// at every torque and position (with `max_root_stress`), then the Hertz pressure (with
/// `max_contact_pressure`). The order depends on the limits and the response's shape only, so
/// the lists of two responses over the same range line up.
fn limited_strength(response: &LoadResponse, limits: &Limits) -> Vec<(f64, f64)> {
    let root = limits.max_root_stress.into_iter().flat_map(|limit| {
        response
            .root_stress_mpa
            .iter()
            .flatten()
            .flat_map(move |s| (0..2).map(move |g| (s[g], limit[g] * 1e-6)))
    });
    let pressure = limits.max_contact_pressure.into_iter().flat_map(|limit| {
        response
            .contact_pressure_mpa
            .iter()
            .flatten()
            .map(move |p| (*p, limit * 1e-6))
    });
    root.chain(pressure).collect()
}

/// Combined relief at the end of recess (C_a1 + C_f2) and at the start of approach (C_a2 + C_f1).
pub fn end_relief(design: &ReliefDesign) -> [f64; 2] {
    [
        design.tip[0] + design.root[1],
        design.tip[1] + design.root[0],
    ]
}

/// The load response of a design: [`evaluate`] on the LTCA, or a synthetic one in a test.
pub type Respond<'a> = &'a dyn Fn(&ReliefDesign) -> Result<LoadResponse, OptimizeError>;

/// Runs the trust-region loop from `start` on the responses `respond` gives (their torques are
/// `range`'s); `progress` sees each iteration's record.
pub fn optimize(
    respond: Respond,
    start: &ReliefDesign,
    range: &LoadRange,
    limits: &Limits,
    settings: &Settings,
    progress: &dyn Fn(&IterationRecord),
) -> Result<Optimum, OptimizeError> {
    let shape = start.shape;
    let (lo, hi) = bounds(limits);
    let evaluate = |design: &ReliefDesign| {
        respond(design)
            .and_then(|response| finite(design, response))
            .map(|response| Evaluation {
                design: *design,
                response,
            })
    };
    let first = evaluate(start)?;
    if !feasible(&first, limits) {
        let stress = |limit: Option<f64>, name: &str, peak: f64| {
            limit.map_or(String::new(), |l| {
                format!(", {name} {peak:.1} MPa against at most {:.1} MPa", l * 1e-6)
            })
        };
        let root = first.response.root_stress_peak_mpa();
        return Err(OptimizeError::InfeasibleStart(format!(
            "the start design {:?} breaks the limits (contact ratio {:?}, minimum {}{}{}{})",
            start,
            first.response.contact_ratio,
            limits.min_contact_ratio,
            stress(
                limits.max_root_stress.map(|l| l[0]),
                "gear 1's root stress",
                root[0]
            ),
            stress(
                limits.max_root_stress.map(|l| l[1]),
                "gear 2's root stress",
                root[1]
            ),
            stress(
                limits.max_contact_pressure,
                "contact pressure",
                first.response.contact_pressure_peak_mpa()
            ),
        )));
    }
    let mut evaluations = 1;
    let mut current = first.clone();
    let mut radius = settings.initial_radius;
    let mut records = Vec::new();
    let mut stop = Stop::Iterations;
    let mut failure = None;
    let mut qp_solve_s = 0.0;
    // The linearization of the current design (kept while steps from it are rejected).
    let mut jacobian: Option<Jacobian> = None;
    for iteration in 1..=settings.max_iterations {
        let v0 = scaled(&current.design);
        if jacobian.is_none() {
            match linearize(&evaluate, &current, (settings, limits), (&lo, &hi)) {
                Ok(linear) => jacobian = Some(linear),
                Err(e) => {
                    failure = Some(format!("iteration {iteration}, linearizing: {e}"));
                    stop = Stop::Failed;
                    break;
                }
            }
            evaluations += VARIABLES;
        }
        let linear = jacobian.as_ref().expect("linearized above");
        let problem = step_problem(
            &current,
            linear,
            range,
            limits,
            settings,
            radius,
            (&lo, &hi),
        );
        let solution = match qp::solve(&problem) {
            Ok(solution) => solution,
            Err(e) => {
                failure = Some(format!("iteration {iteration}, the step's QP: {e}"));
                stop = Stop::Failed;
                break;
            }
        };
        qp_solve_s += solution.solve_s;
        let dv: [f64; VARIABLES] = std::array::from_fn(|k| solution.x[k]);
        let f0 = merit(&current, settings.regularization);
        let constant = settings.regularization * weighted_amounts(&v0);
        // The QP objective drops the constant ρ Σ r_k c₀ₖ; the model value is it plus that.
        let predicted = f0 - (solution.objective + constant);
        let trial_v: [f64; VARIABLES] =
            std::array::from_fn(|k| (v0[k] + dv[k]).clamp(lo[k], hi[k]));
        let trial_design = unscaled(&trial_v, shape);
        let mut record = IterationRecord {
            iteration,
            objective_um: current.response.objective_um,
            merit_um: f0,
            predicted_reduction_um: predicted,
            actual_reduction_um: f64::NAN,
            trust_radius: radius,
            accepted: false,
            trial: std::array::from_fn(|k| trial_v[k] * if k == 4 { SCALE[4] } else { 1.0 }),
            qp_iterations: solution.iterations,
            kkt_residual: solution.kkt_residual,
            qp_solve_s: solution.solve_s,
        };
        if predicted < settings.tolerance_um {
            stop = Stop::PredictedReduction;
            progress(&record);
            records.push(record);
            break;
        }
        let step_norm = dv.iter().fold(0.0f64, |m, d| m.max(d.abs()));
        let mut accepted = None;
        match evaluate(&trial_design) {
            Ok(trial) => {
                evaluations += 1;
                let actual = f0 - merit(&trial, settings.regularization);
                record.actual_reduction_um = actual;
                let ratio = actual / predicted;
                if ratio >= 0.1 && feasible(&trial, limits) {
                    record.accepted = true;
                    accepted = Some(trial);
                }
                if ratio < 0.25 || !record.accepted {
                    radius *= 0.5;
                } else if ratio >= 0.75 && step_norm >= 0.99 * radius {
                    radius *= 2.0;
                }
            }
            // A step the geometry cannot carry (a relief too steep for its length) is a failed
            // step: the radius shrinks and the loop goes on from the current design.
            Err(OptimizeError::Geometry(_)) => radius *= 0.5,
            Err(e) => {
                failure = Some(format!("iteration {iteration}, the trial design: {e}"));
                stop = Stop::Failed;
                progress(&record);
                records.push(record);
                break;
            }
        }
        if let Some(trial) = accepted {
            current = trial;
            jacobian = None;
        }
        progress(&record);
        records.push(record);
        if radius < MIN_RADIUS {
            stop = Stop::TrustRadius;
            break;
        }
    }
    Ok(Optimum {
        shape,
        start: first,
        best: current,
        iterations: records,
        stop,
        failure,
        qp_solve_s,
        ltca_evaluations: evaluations,
    })
}

/// `response` if every number in it is finite; else the error that names the design.
fn finite(design: &ReliefDesign, response: LoadResponse) -> Result<LoadResponse, OptimizeError> {
    let numbers = std::iter::once(response.objective_um)
        .chain(response.ste_um.iter().flatten().copied())
        .chain(response.contact_ratio.iter().copied());
    // A body without fillet nodes reads −∞ root stress (no limit can bind there), never NaN.
    let stresses = response
        .root_stress_mpa
        .iter()
        .flatten()
        .flatten()
        .chain(response.contact_pressure_mpa.iter().flatten());
    if numbers.into_iter().all(f64::is_finite) && stresses.into_iter().all(|s| !s.is_nan()) {
        Ok(response)
    } else {
        Err(OptimizeError::NotFinite(format!(
            "the load response of the design (tip {:.3} / {:.3} µm, root {:.3} / {:.3} µm, λ {:.3}) is \
             not finite (objective {}, contact ratios {:?}): the contact solve behind it diverged",
            design.tip[0] * 1e6,
            design.tip[1] * 1e6,
            design.root[0] * 1e6,
            design.root[1] * 1e6,
            design.length,
            response.objective_um,
            response.contact_ratio
        )))
    }
}

/// Forward-difference sensitivities of the STE ([torque][position][variable], µm per scaled
/// unit), of the contact ratio ([torque][variable]) and of the limited strength values (in the
/// order of [`limited_strength`], MPa per scaled unit) about `current`. A step that would leave
/// the bounds, or that the geometry rejects, is taken backwards.
struct Jacobian {
    ste: Vec<Vec<[f64; VARIABLES]>>,
    contact_ratio: Vec<[f64; VARIABLES]>,
    strength: Vec<[f64; VARIABLES]>,
}

fn linearize(
    evaluate: &dyn Fn(&ReliefDesign) -> Result<Evaluation, OptimizeError>,
    current: &Evaluation,
    (settings, limits): (&Settings, &Limits),
    (lo, hi): (&[f64; VARIABLES], &[f64; VARIABLES]),
) -> Result<Jacobian, OptimizeError> {
    let v0 = scaled(&current.design);
    let strength = limited_strength(&current.response, limits);
    let mut jacobian = Jacobian {
        ste: current
            .response
            .ste_um
            .iter()
            .map(|s| vec![[0.0; VARIABLES]; s.len()])
            .collect(),
        contact_ratio: vec![[0.0; VARIABLES]; current.response.contact_ratio.len()],
        strength: vec![[0.0; VARIABLES]; strength.len()],
    };
    for k in 0..VARIABLES {
        let forward = v0[k] + settings.step <= hi[k];
        let attempt = |h: f64| {
            let mut v = v0;
            v[k] = (v[k] + h).clamp(lo[k], hi[k]);
            evaluate(&unscaled(&v, current.design.shape)).map(|e| (e, v[k] - v0[k]))
        };
        let (shifted, h) = match attempt(if forward {
            settings.step
        } else {
            -settings.step
        }) {
            Ok(r) => r,
            Err(OptimizeError::Geometry(_)) => attempt(if forward {
                -settings.step
            } else {
                settings.step
            })?,
            Err(e) => return Err(e),
        };
        // A variable pinned by its bounds (λ with a minimum length of 1) has no direction.
        if h == 0.0 {
            continue;
        }
        for (j, (after, before)) in shifted
            .response
            .ste_um
            .iter()
            .zip(&current.response.ste_um)
            .enumerate()
        {
            for (i, (a, b)) in after.iter().zip(before).enumerate() {
                jacobian.ste[j][i][k] = (a - b) / h;
            }
            jacobian.contact_ratio[j][k] =
                (shifted.response.contact_ratio[j] - current.response.contact_ratio[j]) / h;
        }
        let after = limited_strength(&shifted.response, limits);
        for (row, (a, b)) in jacobian
            .strength
            .iter_mut()
            .zip(after.iter().zip(&strength))
        {
            row[k] = (a.0 - b.0) / h;
        }
    }
    Ok(jacobian)
}

/// The epigraph QP of one step in (Δv, u, l).
fn step_problem(
    current: &Evaluation,
    jacobian: &Jacobian,
    range: &LoadRange,
    limits: &Limits,
    settings: &Settings,
    radius: f64,
    (lo, hi): (&[f64; VARIABLES], &[f64; VARIABLES]),
) -> QuadraticProgram {
    let torques = range.torques.len();
    let n = VARIABLES + 2 * torques;
    let (u, l) = (|j: usize| VARIABLES + j, |j: usize| VARIABLES + torques + j);
    let v0 = scaled(&current.design);
    let rho = settings.regularization;
    let p = DMatrix::zeros(n, n);
    let mut q = DVector::zeros(n);
    for k in 0..AMOUNTS {
        q[k] = rho * REGULARIZATION_WEIGHTS[k];
    }
    for j in 0..torques {
        q[u(j)] = range.weights[j];
        q[l(j)] = -range.weights[j];
    }
    let mut rows: Vec<(Vec<(usize, f64)>, f64)> = Vec::new();
    for (j, ste) in current.response.ste_um.iter().enumerate() {
        for (i, s) in ste.iter().enumerate() {
            let grad = jacobian.ste[j][i];
            // s + ∇s·Δv ≤ u  and  l ≤ s + ∇s·Δv
            let mut upper: Vec<_> = (0..VARIABLES).map(|k| (k, grad[k])).collect();
            upper.push((u(j), -1.0));
            rows.push((upper, -s));
            let mut lower: Vec<_> = (0..VARIABLES).map(|k| (k, -grad[k])).collect();
            lower.push((l(j), 1.0));
            rows.push((lower, *s));
        }
        // ε + ∇ε·Δv ≥ ε_min
        rows.push((
            (0..VARIABLES)
                .map(|k| (k, -jacobian.contact_ratio[j][k]))
                .collect(),
            (current.response.contact_ratio[j] - limits.min_contact_ratio).max(0.0),
        ));
    }
    // value + ∇value·Δv ≤ limit [MPa], where it can bind inside the trust region (the bound is
    // held at ≥ 0 so that a start a hair beyond the limit, within its tolerance, stays feasible).
    for ((value, limit), grad) in limited_strength(&current.response, limits)
        .into_iter()
        .zip(&jacobian.strength)
    {
        let reach: f64 = grad.iter().map(|g| g.abs()).sum::<f64>() * radius;
        if value.is_finite() && value + reach >= limit {
            rows.push((
                (0..VARIABLES).map(|k| (k, grad[k])).collect(),
                (limit - value).max(0.0),
            ));
        }
    }
    for k in 0..VARIABLES {
        rows.push((vec![(k, 1.0)], radius.min(hi[k] - v0[k])));
        rows.push((vec![(k, -1.0)], radius.min(v0[k] - lo[k])));
    }
    // No loss of contact: (C_a1 + C_f2), (C_a2 + C_f1) ≤ δ_s, in µm.
    let deflection = limits.contact_deflection / SCALE[0];
    for (a, b) in [(0, 3), (2, 1)] {
        rows.push((
            vec![(a, 1.0), (b, 1.0)],
            (deflection - v0[a] - v0[b]).max(0.0),
        ));
    }
    let mut g = DMatrix::zeros(rows.len(), n);
    let mut h = DVector::zeros(rows.len());
    for (r, (entries, bound)) in rows.iter().enumerate() {
        for &(c, value) in entries {
            g[(r, c)] = value;
        }
        h[r] = *bound;
    }
    QuadraticProgram {
        p,
        q,
        a: DMatrix::zeros(0, n),
        b: DVector::zeros(0),
        g,
        h,
    }
}
