//! The LTCA report: per-position CSV rows and the headline numbers. Units at this edge: µm, mm,
//! degrees, N, N/m.

use serde::Serialize;

use crate::ltca::PositionResult;
use crate::stiffness::StiffnessTable;

/// Headline numbers of one relief variant.
#[derive(Debug, Clone, Serialize)]
pub struct LtcaVariantSummary {
    pub relief_variant: String,
    pub mesh_stiffness_mean_n_per_m: f64,
    pub mesh_stiffness_min_n_per_m: f64,
    pub mesh_stiffness_max_n_per_m: f64,
    /// Linear loaded STE r_b2·φ along the line of action.
    pub ste_mean_um: f64,
    pub ste_peak_to_peak_um: f64,
    pub unloaded_te_peak_to_peak_um: f64,
    /// Largest total-force error |Σ F aₖ − T| relative, and largest KKT residual over the cycle.
    pub max_kkt_residual: f64,
    pub elements: [usize; 2],
    pub free_dofs: [usize; 2],
    pub factorization_s: f64,
    pub condensation_s: f64,
    pub cycle_s: f64,
}

/// Summary of a variant's cycle.
pub fn variant_summary(
    name: &str,
    results: &[PositionResult],
    base_radius_driven: f64,
    elements: [usize; 2],
    free_dofs: [usize; 2],
    times: (f64, f64, f64),
) -> LtcaVariantSummary {
    let table = stiffness_table(results);
    let ste: Vec<f64> = results
        .iter()
        .map(|r| r.ste * base_radius_driven * 1e6)
        .collect();
    let te0: Vec<f64> = results
        .iter()
        .map(|r| r.unloaded_te * base_radius_driven * 1e6)
        .collect();
    let spread = |v: &[f64]| {
        v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - v.iter().copied().fold(f64::INFINITY, f64::min)
    };
    LtcaVariantSummary {
        relief_variant: name.into(),
        mesh_stiffness_mean_n_per_m: table.mean(),
        mesh_stiffness_min_n_per_m: table.min(),
        mesh_stiffness_max_n_per_m: table.max(),
        ste_mean_um: ste.iter().sum::<f64>() / ste.len() as f64,
        ste_peak_to_peak_um: spread(&ste),
        unloaded_te_peak_to_peak_um: spread(&te0),
        max_kkt_residual: results.iter().map(|r| r.kkt_residual).fold(0.0, f64::max),
        elements,
        free_dofs,
        factorization_s: times.0,
        condensation_s: times.1,
        cycle_s: times.2,
    }
}

/// The periodic stiffness table of an LTCA cycle.
pub fn stiffness_table(results: &[PositionResult]) -> StiffnessTable {
    StiffnessTable {
        source: "ltca".into(),
        roll_angles: results.iter().map(|r| r.roll_angle).collect(),
        stiffness: results.iter().map(|r| r.mesh_stiffness).collect(),
    }
}

/// CSV header for [`position_rows`] with `pairs` tooth pairs.
pub fn position_header(pairs: &[(usize, usize)]) -> Vec<String> {
    let mut header: Vec<String> = [
        "roll_angle_deg",
        "driver_rotation_deg",
        "ste_urad",
        "ste_um",
        "unloaded_te_um",
        "mesh_stiffness_n_per_m",
        "total_force_n",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    for (t1, t2) in pairs {
        header.push(format!("force_pair_{t1}_{t2}_n"));
    }
    for (t1, t2) in pairs {
        header.push(format!("position_pair_{t1}_{t2}_mm"));
    }
    header.extend(
        ["active_points", "candidate_points", "kkt_residual"]
            .iter()
            .map(|s| s.to_string()),
    );
    header
}

/// One CSV row per position.
pub fn position_rows(results: &[PositionResult], base_radius_driven: f64) -> Vec<Vec<String>> {
    results
        .iter()
        .map(|r| {
            let mut row = vec![
                format!("{:.6}", r.roll_angle.to_degrees()),
                format!("{:.6}", r.driver_rotation.to_degrees()),
                format!("{:.6}", r.ste * 1e6),
                format!("{:.6}", r.ste * base_radius_driven * 1e6),
                format!("{:.6}", r.unloaded_te * base_radius_driven * 1e6),
                format!("{:.6e}", r.mesh_stiffness),
                format!("{:.4}", r.total_force),
            ];
            row.extend(r.pair_forces.iter().map(|f| format!("{f:.4}")));
            row.extend(
                r.pair_positions
                    .iter()
                    .map(|p| p.map_or(String::new(), |s| format!("{:.6}", s * 1e3))),
            );
            row.extend([
                r.active_points.to_string(),
                r.candidate_points.to_string(),
                format!("{:.3e}", r.kkt_residual),
            ]);
            row
        })
        .collect()
}
