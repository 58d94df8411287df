//! `geardyn validate quick`: the validation studies that fit in a minute, re-run against their
//! references with the tolerances validation/README.md states; a broken tolerance makes the
//! command fail (CI runs it after the tests).
//!
//! * Geometry (the seed paper's pair, case `paper36`, only): the transverse contact ratio against
//!   the paper's ε_α = 1.69 (it gives two decimals: ±0.005).
//! * LTCA convergence: the mean mesh stiffness at the case's flank elements against 0.05 mm
//!   flanks, within 0.5 % ("Mesh refinement": 0.2 mm is within 0.5 % of the finest).
//! * LTCA equilibrium: Σ W = T / r_b2 at every position to 1e-3 (the tests' 0.1 %).
//! * Relief optimization: the optimum's robust objective below every baseline's (no relief, the
//!   case's relief, the classic rule long and short), and the loop's fixed bodies against the
//!   optimum's re-meshed LTCA within 1 % in the mean stiffness and the STE peak-to-peak (issue
//!   17's tolerance).

use serde::Serialize;

use crate::case::Case;
use crate::geometry::FlankModification;

use super::optimize::{OptimizeOptions, OptimizeStudy};
use super::{load_torque, Progress, StudyError};

/// The name of the seed paper's case, the one the paper's numbers belong to.
pub const PAPER_CASE: &str = "paper36";

/// The seed paper's transverse contact ratio (its Table 1).
pub const PAPER_CONTACT_RATIO: f64 = 1.69;

pub use super::checks::{Check, CheckKind};

/// The quick set's result (`summary.json`).
#[derive(Debug, Clone, Serialize)]
pub struct QuickValidation {
    pub case: String,
    pub checks: Vec<Check>,
    pub passed: usize,
    pub failed: usize,
    /// Timing.
    pub wall_s: f64,
}

/// The finest flank element of the convergence check [m].
const FINEST_FLANK: f64 = 0.05e-3;

/// Runs the quick set on `case`.
pub fn run(case: &Case, progress: Progress) -> Result<QuickValidation, StudyError> {
    let started = std::time::Instant::now();
    let mut checks = Vec::new();
    if case.name() == PAPER_CASE {
        checks.push(Check::new(
            "geometry",
            "transverse contact ratio",
            (case.pair.contact_ratio, PAPER_CONTACT_RATIO),
            "seed paper, Table 1 (two decimals)",
            (CheckKind::Absolute, 0.005),
        ));
    }

    progress("LTCA convergence", 0, 2);
    let torque = load_torque(case)?;
    let none = [FlankModification::none(); 2];
    let positions = 64;
    let rb2 = case.pair.gears[1].base_radius;
    let case_mesh = super::ltca::model(case, &none)?.run(positions, torque, &|_| {})?;
    progress("LTCA convergence", 1, 2);
    let coarse = case.file.mesh.coarse_element_mm * 1e-3;
    if case.file.mesh.fine_element_mm * 1e-3 <= FINEST_FLANK {
        return Err(StudyError::Input(format!(
            "mesh.fine_element_mm = {} is already the convergence check's reference ({} mm): \
             the check would compare the mesh with itself",
            case.file.mesh.fine_element_mm,
            FINEST_FLANK * 1e3
        )));
    }
    let finest = super::ltca::model_with_sizes(case, &none, FINEST_FLANK, coarse)?.run(
        positions,
        torque,
        &|_| {},
    )?;
    progress("LTCA convergence", 2, 2);
    let mean = |r: &[crate::ltca::PositionResult]| {
        r.iter().map(|p| p.mesh_stiffness).sum::<f64>() / r.len() as f64
    };
    checks.push(Check::new(
        "ltca",
        format!(
            "mean mesh stiffness at {} mm flanks [N/m]",
            case.file.mesh.fine_element_mm
        ),
        (mean(&case_mesh), mean(&finest)),
        "the same LTCA at 0.05 mm flanks (validation/ltca, mesh refinement)",
        (CheckKind::Relative, 0.005),
    ));
    let worst_balance = case_mesh
        .iter()
        .map(|p| (p.total_force * rb2 / torque - 1.0).abs())
        .fold(0.0, f64::max);
    // The contact solve balances Σ W a = T on each force's own moment arm a; that every arm is
    // the base radius checks the contact normals: an involute's normal is tangent to the base
    // circle, so the forces act along the line of action.
    checks.push(Check::new(
        "ltca",
        "largest abs(Σ W r_b2 / T − 1) over the cycle",
        (worst_balance, 0.0),
        "involute action: every contact force along the line of action (moment arm r_b2)",
        (CheckKind::Absolute, 1e-3),
    ));

    progress("relief optimization", 0, 1);
    let optimum: OptimizeStudy = super::optimize::run(case, &OptimizeOptions::default(), progress)?;
    let s = &optimum.summary;
    // The loop starts from no relief and from the classic rule (long) and accepts only
    // descending steps, so against those two the check asks for real progress, 10 %; the other
    // baselines it never visits.
    for (baseline, value, margin) in [
        ("no relief (a start)", Some(s.objective_none), 0.1),
        ("the case's relief", s.objective_paper, 0.0),
        (
            "the classic rule, long (a start)",
            Some(s.objective_classic),
            0.1,
        ),
        (
            "the classic rule, short",
            Some(s.objective_classic_short),
            0.0,
        ),
    ] {
        if let Some(reference) = value {
            checks.push(Check::new(
                "optimize",
                format!("robust STE peak-to-peak of the optimum against {baseline} [µm]"),
                (s.objective_optimum, reference),
                baseline,
                (CheckKind::Below, margin),
            ));
        }
    }
    let r = &s.remeshed;
    checks.push(Check::new(
        "optimize",
        "optimum's mean mesh stiffness, fixed bodies [N/m]",
        (
            r.mesh_stiffness_mean_fixed_n_per_m,
            r.mesh_stiffness_mean_remeshed_n_per_m,
        ),
        "the LTCA on bodies meshed with the optimum's relief",
        (CheckKind::Relative, 0.01),
    ));
    checks.push(Check::new(
        "optimize",
        "optimum's STE peak-to-peak, fixed bodies [µm]",
        (r.ste_pp_fixed_um, r.ste_pp_remeshed_um),
        "the LTCA on bodies meshed with the optimum's relief",
        (CheckKind::Relative, 0.01),
    ));
    let failed = checks.iter().filter(|c| !c.passed).count();
    Ok(QuickValidation {
        case: case.name().to_string(),
        passed: checks.len() - failed,
        failed,
        checks,
        wall_s: started.elapsed().as_secs_f64(),
    })
}
