//! `geardyn validate pairs`: every fidelity on the matrix of pairs
//! ([`crate::samples::PAIR_MATRIX`]), not only the seed paper's 36/36.
//!
//! Per pair:
//! * geometry: contact ratio, centre distance, backlash;
//! * the LTCA of every relief variant with its self-checks ([`super::ltca::self_checks`]:
//!   periodicity over a base pitch, KKT, torque balance, unloaded TE, the loaded pairs at low
//!   load against the path of contact), none of which may fail;
//! * mesh convergence of the mean stiffness: flank elements h, h/2 and h/4 (h the case's), the
//!   case's within 0.5 % of h/4 — the tolerance validation/ltca holds the paper's pair to;
//! * the swap test: the pair with driver and driven exchanged and the torque transferred
//!   ([`Case::swapped`]) has the same STE along the line of action, read at the mirrored
//!   position (driver rotation θ ↔ −θ′: the contact runs the path the other way): the mean within
//!   0.5 %, every position within 2 % (the node-to-surface contact's own jitter between
//!   neighbouring positions is about 1 %: which gear's nodes are the candidates changes);
//! * the lumped model on the LTCA's force law: its quasi-static TE against the LTCA from 25 to
//!   300 % of the design torque ([`super::lumped::quasi_static_checks`], judged), and its sweep
//!   (the outcome reported, not judged: a zero-backlash pair may leave the model near
//!   resonance);
//! * the relief optimizer with its defaults: the optimum's robust STE peak-to-peak at most the
//!   better of its starts (no relief, the classic rule long);
//! * optionally (the binary's `--fe`) the explicit FE's stiffness scene against the LTCA on its
//!   own mesh.

use serde::Serialize;

use crate::case::Case;
use crate::geometry::FlankModification;
use crate::samples::MatrixPair;

use super::checks::{Check, CheckKind};
use super::ltca::{model_with_sizes, LtcaOptions};
use super::{load_torque, Progress, StudyError};

/// Positions per base pitch of the matrix's LTCA runs.
pub const POSITIONS: usize = 64;

/// The case's mean stiffness against the one at a quarter of its flank elements, relative.
pub const CONVERGENCE_TOLERANCE: f64 = 0.005;

/// The swap test's tolerances on the STE along the line of action: mean and every position.
pub const SWAP_MEAN_TOLERANCE: f64 = 0.005;
pub const SWAP_POINT_TOLERANCE: f64 = 0.02;

/// One row of the table.
#[derive(Debug, Clone, Serialize)]
pub struct PairRow {
    pub name: String,
    pub what: String,
    pub teeth: [u32; 2],
    pub module_mm: f64,
    pub pressure_angle_deg: f64,
    pub contact_ratio: f64,
    pub center_distance_mm: f64,
    pub backlash_normal_um: f64,
    /// Tooth pairs the LTCA carries over its base pitch.
    pub ltca_tooth_pairs: usize,
    pub mesh_stiffness_mean_n_per_m: f64,
    pub ste_mean_um: f64,
    pub ste_peak_to_peak_um: f64,
    pub loaded_contact_ratio: f64,
    pub periodicity_ste_rel: f64,
    pub periodicity_force_rel: f64,
    /// Mean stiffness at flank elements h, h/2, h/4 [N/m] and the flank sizes [mm].
    pub convergence_fine_mm: [f64; 3],
    pub convergence_mean_stiffness_n_per_m: [f64; 3],
    pub convergence_rel: f64,
    pub swap_ste_mean_rel: f64,
    pub swap_ste_max_rel: f64,
    /// "completed", or where the sweep left the model.
    pub sweep_outcome: String,
    pub sweep_max_dynamic_factor: Option<f64>,
    pub sweep_primary_resonance_rpm: Option<f64>,
    /// The explicit FE's k(θ) over the same-mesh LTCA's: mean − 1, and its static TE mean − 1.
    pub fe_stiffness_mean_rel: Option<f64>,
    pub fe_static_te_mean_rel: Option<f64>,
    /// The relief optimizer's robust objective (STE peak-to-peak over the load range) without
    /// relief and at its optimum [µm].
    pub optimize_ste_pp_none_um: f64,
    pub optimize_ste_pp_optimum_um: f64,
    /// `geardyn run` end to end, with `--run`.
    pub run: Option<RunOutcome>,
    pub checks: Vec<Check>,
    pub passed: bool,
    pub wall_s: f64,
}

/// The whole table (`summary.json`).
#[derive(Debug, Clone, Serialize)]
pub struct PairsValidation {
    pub rows: Vec<PairRow>,
    pub passed: usize,
    pub failed: usize,
    pub wall_s: f64,
}

/// Mean over a cycle of the mesh stiffness [N/m].
fn mean_stiffness(results: &[crate::ltca::PositionResult]) -> f64 {
    results.iter().map(|r| r.mesh_stiffness).sum::<f64>() / results.len() as f64
}

/// The swap test's differences: (mean, largest at a position), relative, of the STE along the
/// line of action r_b2 φ of `forward` at position j against `swapped`'s at position −j mod N.
pub fn swap_differences(
    forward: &[crate::ltca::PositionResult],
    forward_rb2: f64,
    swapped: &[crate::ltca::PositionResult],
    swapped_rb2: f64,
) -> (f64, f64) {
    let n = forward.len();
    assert_eq!(
        n,
        swapped.len(),
        "the swap test needs equal position counts"
    );
    let a: Vec<f64> = forward.iter().map(|r| r.ste * forward_rb2).collect();
    let b: Vec<f64> = (0..n)
        .map(|j| swapped[(n - j) % n].ste * swapped_rb2)
        .collect();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / n as f64;
    let largest = crate::signal::largest(a.iter().zip(&b).map(|(x, y)| (y / x - 1.0).abs()));
    ((mean(&b) / mean(&a) - 1.0).abs(), largest)
}

/// Runs the in-process part of one row (everything but the explicit FE).
pub fn row(pair: &MatrixPair, progress: Progress) -> Result<PairRow, StudyError> {
    let started = std::time::Instant::now();
    let case = pair.case()?;
    let stage = format!("pair {}", pair.name);
    progress(&stage, 0, 5);
    let ltca = super::ltca::run(
        &case,
        &LtcaOptions {
            positions: POSITIONS,
            relief: None,
        },
        &|_, _, _| {},
    )?;
    let none = [FlankModification::none(); 2];
    let unmodified = ltca
        .cycles
        .iter()
        .find(|c| c.modifications == none)
        .ok_or_else(|| StudyError::Input("the matrix's cases carry the variant none".into()))?;
    progress(&stage, 1, 5);

    let torque = load_torque(&case)?;
    let fine = case.file.mesh.fine_element_mm * 1e-3;
    let coarse = case.file.mesh.coarse_element_mm * 1e-3;
    let sizes = [fine, fine / 2.0, fine / 4.0];
    let mut convergence = [0.0; 3];
    let mut forward = Vec::new();
    let mut model_pairs = 0;
    let mut loaded_contact_ratio = f64::NAN;
    for (i, size) in sizes.iter().enumerate() {
        let model = model_with_sizes(&case, &none, *size, coarse)?;
        let results = model.run(POSITIONS, torque, &|_| {})?;
        convergence[i] = mean_stiffness(&results);
        if i == 0 {
            model_pairs = model.pairs.len();
            loaded_contact_ratio = model.loaded_contact_ratio(&results);
            forward = results;
        }
    }
    progress(&stage, 2, 5);

    let swapped_case = case.swapped()?;
    let swapped = super::ltca::model(&swapped_case, &none)?.run(
        POSITIONS,
        load_torque(&swapped_case)?,
        &|_| {},
    )?;
    let (swap_mean, swap_max) = swap_differences(
        &forward,
        case.pair.gears[1].base_radius,
        &swapped,
        swapped_case.pair.gears[1].base_radius,
    );
    progress(&stage, 3, 5);

    let (sweep_outcome, sweep_max_dynamic_factor, sweep_primary_resonance_rpm, lumped_checks) =
        sweep_outcome(&case)?;
    progress(&stage, 4, 5);

    let mut checks: Vec<Check> = ltca.summary.self_checks.clone();
    checks.extend(lumped_checks);
    // The relief optimizer with its defaults (LTCA only): its optimum at most the better of
    // its two starts' objectives (no relief, the classic rule long), which it begins from.
    let (optimize_none, optimize_optimum) = match super::optimize::run(
        &case,
        &super::optimize::OptimizeOptions::default(),
        &|_, _, _| {},
    ) {
        Ok(study) => {
            let s = &study.summary;
            let start = s.objective_none.min(s.objective_classic);
            checks.push(Check::new(
                    "pairs",
                    "relief optimizer: robust STE peak-to-peak of the optimum over the better start [µm]",
                    (s.objective_optimum, start * (1.0 + 1e-9)),
                    "no relief and the classic rule (long), where it starts",
                    (CheckKind::Below, 0.0),
                ));
            (s.objective_none, s.objective_optimum)
        }
        Err(error) => {
            checks.push(Check::new(
                "pairs",
                format!("relief optimizer: {error}"),
                (f64::NAN, 0.0),
                "an optimizer that runs",
                (CheckKind::Absolute, 0.0),
            ));
            (f64::NAN, f64::NAN)
        }
    };
    checks.push(Check::new(
        "pairs",
        format!(
            "mean mesh stiffness at {:.3} mm flanks against {:.4} mm [N/m]",
            sizes[0] * 1e3,
            sizes[2] * 1e3
        ),
        (convergence[0], convergence[2]),
        "the same LTCA at a quarter of the flank elements",
        (CheckKind::Relative, CONVERGENCE_TOLERANCE),
    ));
    checks.push(Check::new(
        "pairs",
        "swap test: mean STE along the LOA, driver and driven exchanged, relative difference",
        (swap_mean, 0.0),
        "the same pair driven from the other gear with the same normal load",
        (CheckKind::Absolute, SWAP_MEAN_TOLERANCE),
    ));
    checks.push(Check::new(
        "pairs",
        "swap test: largest STE difference at a position, relative",
        (swap_max, 0.0),
        "the same pair driven from the other gear with the same normal load",
        (CheckKind::Absolute, SWAP_POINT_TOLERANCE),
    ));
    let s = &unmodified.summary;
    let periodicity = |needle: &str| {
        crate::signal::largest(
            ltca.summary
                .self_checks
                .iter()
                .filter(|c| c.quantity.starts_with("none:") && c.quantity.contains(needle))
                .map(|c| c.value),
        )
    };
    let passed = checks.iter().all(|c| !c.is_error());
    let p = &case.pair;
    Ok(PairRow {
        name: pair.name.into(),
        what: pair.what.into(),
        teeth: [p.gears[0].teeth(), p.gears[1].teeth()],
        module_mm: p.gears[0].module() * 1e3,
        pressure_angle_deg: case.file.tool.pressure_angle_deg,
        contact_ratio: p.contact_ratio,
        center_distance_mm: p.center_distance * 1e3,
        backlash_normal_um: p.backlash_normal * 1e6,
        ltca_tooth_pairs: model_pairs,
        mesh_stiffness_mean_n_per_m: s.mesh_stiffness_mean_n_per_m,
        ste_mean_um: s.ste_mean_um,
        ste_peak_to_peak_um: s.ste_peak_to_peak_um,
        loaded_contact_ratio,
        periodicity_ste_rel: periodicity("STE one base pitch on"),
        periodicity_force_rel: periodicity("tooth-pair force one base pitch on"),
        convergence_fine_mm: sizes.map(|h| h * 1e3),
        convergence_mean_stiffness_n_per_m: convergence,
        convergence_rel: (convergence[0] / convergence[2] - 1.0).abs(),
        swap_ste_mean_rel: swap_mean,
        swap_ste_max_rel: swap_max,
        sweep_outcome,
        sweep_max_dynamic_factor,
        sweep_primary_resonance_rpm,
        fe_stiffness_mean_rel: None,
        fe_static_te_mean_rel: None,
        optimize_ste_pp_none_um: optimize_none,
        optimize_ste_pp_optimum_um: optimize_optimum,
        run: None,
        checks,
        passed,
        wall_s: started.elapsed().as_secs_f64(),
    })
}

/// A row whose study stopped with an error (an LTCA that is not periodic, a case the geometry
/// refuses): every number NaN, one failed check that carries the message, so the matrix goes
/// on and its table names the row.
pub fn failed_row(pair: &MatrixPair, message: &str) -> PairRow {
    let case = pair.case().ok();
    let p = case.as_ref().map(|c| &c.pair);
    let nan = f64::NAN;
    PairRow {
        name: pair.name.into(),
        what: pair.what.into(),
        teeth: p.map_or([0, 0], |p| [p.gears[0].teeth(), p.gears[1].teeth()]),
        module_mm: p.map_or(nan, |p| p.gears[0].module() * 1e3),
        pressure_angle_deg: case
            .as_ref()
            .map_or(nan, |c| c.file.tool.pressure_angle_deg),
        contact_ratio: p.map_or(nan, |p| p.contact_ratio),
        center_distance_mm: p.map_or(nan, |p| p.center_distance * 1e3),
        backlash_normal_um: p.map_or(nan, |p| p.backlash_normal * 1e6),
        ltca_tooth_pairs: 0,
        mesh_stiffness_mean_n_per_m: nan,
        ste_mean_um: nan,
        ste_peak_to_peak_um: nan,
        loaded_contact_ratio: nan,
        periodicity_ste_rel: nan,
        periodicity_force_rel: nan,
        convergence_fine_mm: [nan; 3],
        convergence_mean_stiffness_n_per_m: [nan; 3],
        convergence_rel: nan,
        swap_ste_mean_rel: nan,
        swap_ste_max_rel: nan,
        sweep_outcome: "not reached".into(),
        sweep_max_dynamic_factor: None,
        sweep_primary_resonance_rpm: None,
        fe_stiffness_mean_rel: None,
        fe_static_te_mean_rel: None,
        optimize_ste_pp_none_um: nan,
        optimize_ste_pp_optimum_um: nan,
        run: None,
        checks: vec![Check::new(
            "pairs",
            format!("the row's studies: {message}"),
            (nan, 0.0),
            "a row that runs to its end",
            (CheckKind::Absolute, 0.0),
        )],
        passed: false,
        wall_s: 0.0,
    }
}

/// The lumped sweep of the case on its LTCA force law over 0.3 … 1.5 × the primary resonance
/// speed (120 speeds): its outcome, largest dynamic factor and primary resonance, and the
/// model's quasi-static checks against the LTCA.
type SweepOutcome = (String, Option<f64>, Option<f64>, Vec<Check>);
fn sweep_outcome(case: &Case) -> Result<SweepOutcome, StudyError> {
    let setup = super::lumped::setup(case)?;
    let checks = setup.self_checks.clone();
    let primary = super::lumped::speed_for_mesh_frequency(case, setup.natural_frequency_hz);
    let rpm = super::RpmRange(
        (0..120)
            .map(|i| primary * (0.3 + 1.2 * i as f64 / 119.0))
            .collect(),
    );
    let options = super::sweep::SweepOptions {
        rpm,
        run_up_s: None,
        resume: None,
    };
    Ok(match super::sweep::run(case, &options)? {
        super::sweep::SweepRun::Done(study) => (
            "completed".into(),
            Some(study.summary.max_dynamic_factor),
            study.summary.primary_resonance_rpm,
            checks,
        ),
        super::sweep::SweepRun::Diverged(checkpoint) => (
            checkpoint.progress.diverged.map_or_else(
                || "diverged".into(),
                |d| {
                    format!(
                        "diverged at {:.0} rpm ({}; backlash {:.0} µm, Floquet: orbit {}, drive flanks linearized {:.3})",
                        d.driver_speed_rpm,
                        d.direction,
                        d.backlash_m * 1e6,
                        d.orbit_floquet_max_multiplier
                            .map_or_else(|| "none found".into(), |m| format!("{m:.3}")),
                        d.floquet_max_multiplier
                    )
                },
            ),
            None,
            None,
            checks,
        ),
        super::sweep::SweepRun::Interrupted(_) => ("interrupted".into(), None, None, checks),
    })
}

/// Adds the explicit FE's stiffness scene to a row and re-judges it: the run's own checks
/// against the LTCA on its mesh ([`super::fe::self_checks`]), or the run's failure.
pub fn add_fe(row: &mut PairRow, fe: Result<&super::fe::FeSummary, String>) {
    match fe {
        Ok(summary) => {
            let difference = summary.stiffness_vs_ltca_same_mesh.as_ref();
            row.fe_stiffness_mean_rel = difference.map(|d| d.mean_rel);
            row.fe_static_te_mean_rel = difference.map(|d| d.static_te_mean_rel);
            row.checks.extend(summary.self_checks.iter().cloned());
            if summary.self_checks.is_empty() {
                row.checks
                    .push(fe_failure("the run made no checks against the LTCA"));
            }
        }
        Err(message) => row.checks.push(fe_failure(&message)),
    }
    row.passed = row.checks.iter().all(|c| !c.is_error());
}

/// What `geardyn run` on a pair left in its summary.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RunOutcome {
    pub self_check_errors: usize,
    pub self_check_warnings: usize,
    pub wall_s: f64,
}

/// Adds `geardyn run` end to end on the row's pair (the binary's `--run`): its self-check
/// errors must be none, or the run's failure fails the row.
pub fn add_run(row: &mut PairRow, run: Result<RunOutcome, String>) {
    let (errors, why) = match &run {
        Ok(outcome) => (
            outcome.self_check_errors as f64,
            "self-check errors".to_string(),
        ),
        Err(message) => (f64::NAN, format!("failed: {message}")),
    };
    row.run = run.as_ref().ok().copied();
    row.checks.push(Check::new(
        "pairs",
        format!("geardyn run end to end at coarse settings: {why}"),
        (errors, 0.0),
        "every stage's self-checks in the run's summary",
        (CheckKind::Absolute, 0.0),
    ));
    row.passed = row.checks.iter().all(|c| !c.is_error());
}

/// A failed check that stands for an explicit run that gave no comparison.
fn fe_failure(why: &str) -> Check {
    Check::new(
        "pairs",
        format!("explicit FE stiffness scene: {why}"),
        (f64::NAN, 1.0),
        "the LTCA on the explicit run's own mesh",
        (CheckKind::Relative, super::fe::FE_LTCA_ERROR_BAND),
    )
}

/// Tallies the rows.
pub fn table(rows: Vec<PairRow>, wall_s: f64) -> PairsValidation {
    let passed = rows.iter().filter(|r| r.passed).count();
    PairsValidation {
        failed: rows.len() - passed,
        passed,
        rows,
        wall_s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ltca::PositionResult;

    fn cycle(ste: impl Fn(usize) -> f64, n: usize) -> Vec<PositionResult> {
        (0..n)
            .map(|j| PositionResult {
                driver_rotation: j as f64,
                roll_angle: j as f64,
                ste: ste(j),
                unloaded_te: 0.0,
                total_force: 1.0,
                pair_forces: vec![1.0],
                pair_positions: vec![None],
                mesh_stiffness: 1.0,
                tangent_stiffness: 1.0,
                kkt_residual: 0.0,
                active_points: 1,
                candidate_points: 1,
                iterations: 1,
                root_stress: [0.0; 2],
            })
            .collect()
    }

    /// The swap metric on synthetic cycles with known answers: a cycle read backwards from
    /// position 0 (j ↔ −j mod N) with the other base radius is the same STE (0, 0); read
    /// forwards it is not (an asymmetric waveform); scaled by 1.01 it is 1 % off everywhere;
    /// one position 5 % off moves the largest difference to 5 % and the mean by 5 %/N.
    #[test]
    fn the_swap_metric_gives_the_known_answers() {
        let n = 32;
        let f = |j: usize| {
            let x = std::f64::consts::TAU * j as f64 / n as f64;
            1e-4 * (2.0 + x.sin() + 0.3 * (2.0 * x).cos() + 0.2 * (3.0 * x).sin())
        };
        let forward = cycle(f, n);
        // The swapped pair's STE at its position j′ is the forward one at −j′, scaled by
        // the base-radius ratio (angular STE on the other driven gear).
        let (rb, rb_swapped) = (0.05, 0.03);
        let mirrored = |j: usize| f((n - j) % n) * rb / rb_swapped;
        let (mean, largest) = swap_differences(&forward, rb, &cycle(mirrored, n), rb_swapped);
        assert!(mean < 1e-15 && largest < 1e-14, "{mean} {largest}");
        let (_, largest) = swap_differences(
            &forward,
            rb,
            &cycle(|j| f(j) * rb / rb_swapped, n),
            rb_swapped,
        );
        assert!(largest > 0.1, "the unmirrored cycle must differ: {largest}");
        let (mean, largest) =
            swap_differences(&forward, rb, &cycle(|j| 1.01 * mirrored(j), n), rb_swapped);
        assert!((mean - 0.01).abs() < 1e-12 && (largest - 0.01).abs() < 1e-12);
        let bumped = |j: usize| {
            if j == 5 {
                1.05 * mirrored(j)
            } else {
                mirrored(j)
            }
        };
        let (mean, largest) = swap_differences(&forward, rb, &cycle(bumped, n), rb_swapped);
        assert!((largest - 0.05).abs() < 1e-12);
        let expected = 0.05 * f(n - 5) / forward.iter().map(|r| r.ste).sum::<f64>();
        assert!((mean - expected).abs() < 1e-12, "{mean} {expected}");
    }
}
