//! Writes `geardyn validate pairs`: pairs.csv (a row per pair), checks.csv (every check of
//! every pair), pairs.md (the table) and summary.json.

use super::{OutputDir, ReportError};
use crate::study::pairs::PairsValidation;

/// Writes the table; returns its Markdown.
pub fn write(dir: OutputDir, result: &PairsValidation) -> Result<String, ReportError> {
    let opt = |v: Option<f64>, digits: usize| v.map_or(String::new(), |v| format!("{v:.digits$}"));
    dir.csv(
        "pairs.csv",
        &[
            "pair",
            "z1",
            "z2",
            "module_mm",
            "pressure_angle_deg",
            "contact_ratio",
            "center_distance_mm",
            "backlash_normal_um",
            "ltca_tooth_pairs",
            "mesh_stiffness_mean_n_per_m",
            "ste_mean_um",
            "ste_peak_to_peak_um",
            "loaded_contact_ratio",
            "periodicity_ste_rel",
            "periodicity_force_rel",
            "k_mean_h_n_per_m",
            "k_mean_h2_n_per_m",
            "k_mean_h4_n_per_m",
            "convergence_rel",
            "swap_ste_mean_rel",
            "swap_ste_max_rel",
            "sweep_outcome",
            "sweep_max_dynamic_factor",
            "fe_stiffness_mean_rel",
            "run_self_check_errors",
            "run_self_check_warnings",
            "run_wall_s",
            "optimize_ste_pp_none_um",
            "optimize_ste_pp_optimum_um",
            "passed",
        ],
        result.rows.iter().map(|r| {
            vec![
                r.name.clone(),
                r.teeth[0].to_string(),
                r.teeth[1].to_string(),
                format!("{}", r.module_mm),
                format!("{}", r.pressure_angle_deg),
                format!("{:.5}", r.contact_ratio),
                format!("{:.4}", r.center_distance_mm),
                format!("{:.3}", r.backlash_normal_um),
                r.ltca_tooth_pairs.to_string(),
                format!("{:.6e}", r.mesh_stiffness_mean_n_per_m),
                format!("{:.5}", r.ste_mean_um),
                format!("{:.5}", r.ste_peak_to_peak_um),
                format!("{:.5}", r.loaded_contact_ratio),
                format!("{:.3e}", r.periodicity_ste_rel),
                format!("{:.3e}", r.periodicity_force_rel),
                format!("{:.6e}", r.convergence_mean_stiffness_n_per_m[0]),
                format!("{:.6e}", r.convergence_mean_stiffness_n_per_m[1]),
                format!("{:.6e}", r.convergence_mean_stiffness_n_per_m[2]),
                format!("{:.3e}", r.convergence_rel),
                format!("{:.3e}", r.swap_ste_mean_rel),
                format!("{:.3e}", r.swap_ste_max_rel),
                r.sweep_outcome.clone(),
                opt(r.sweep_max_dynamic_factor, 4),
                opt(r.fe_stiffness_mean_rel, 5),
                r.run
                    .map_or(String::new(), |o| o.self_check_errors.to_string()),
                r.run
                    .map_or(String::new(), |o| o.self_check_warnings.to_string()),
                opt(r.run.map(|o| o.wall_s), 1),
                format!("{:.4}", r.optimize_ste_pp_none_um),
                format!("{:.4}", r.optimize_ste_pp_optimum_um),
                r.passed.to_string(),
            ]
        }),
    )?;
    dir.csv(
        "checks.csv",
        &[
            "pair",
            "quantity",
            "value",
            "tolerance",
            "passed",
            "warning_only",
        ],
        result.rows.iter().flat_map(|r| {
            r.checks.iter().map(move |c| {
                vec![
                    r.name.clone(),
                    c.quantity.clone(),
                    format!("{:.6e}", c.value),
                    format!("{:e}", c.tolerance),
                    c.passed.to_string(),
                    c.warning_only.to_string(),
                ]
            })
        }),
    )?;
    let mut md = String::from(
        "| pair | z1/z2 | m [mm] | α [°] | ε_α | pairs | k̄ [N/m] | STE p-p [µm] | ε_load | periodic (STE) | k̄(h)/k̄(h/4) − 1 | swap mean / max | sweep | relief: robust STE p-p none → optimum [µm] | FE k̄/LTCA − 1 | run: errors / warnings | |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in &result.rows {
        let failed: Vec<&str> = r
            .checks
            .iter()
            .filter(|c| !c.passed)
            .map(|c| c.quantity.as_str())
            .collect();
        md += &format!(
            "| {} | {}/{} | {} | {} | {:.3} | {} | {:.4e} | {:.3} | {:.3} | {:.1e} | {:+.2} % | {:.2} % / {:.2} % | {} | {:.3} → {:.3} | {} | {} | {} |\n",
            r.name,
            r.teeth[0],
            r.teeth[1],
            r.module_mm,
            r.pressure_angle_deg,
            r.contact_ratio,
            r.ltca_tooth_pairs,
            r.mesh_stiffness_mean_n_per_m,
            r.ste_peak_to_peak_um,
            r.loaded_contact_ratio,
            r.periodicity_ste_rel,
            100.0 * (r.convergence_mean_stiffness_n_per_m[0] / r.convergence_mean_stiffness_n_per_m[2] - 1.0),
            100.0 * r.swap_ste_mean_rel,
            100.0 * r.swap_ste_max_rel,
            match r.sweep_max_dynamic_factor {
                Some(df) => format!("DF {df:.2}"),
                None => r.sweep_outcome.clone(),
            },
            r.optimize_ste_pp_none_um,
            r.optimize_ste_pp_optimum_um,
            r.fe_stiffness_mean_rel
                .map_or("—".into(), |v| format!("{:+.2} %", 100.0 * v)),
            r.run.map_or("—".into(), |o| format!(
                "{} / {} ({:.0} s)",
                o.self_check_errors, o.self_check_warnings, o.wall_s
            )),
            if r.passed {
                if failed.is_empty() {
                    "ok".to_string()
                } else {
                    format!("ok (warning: {})", failed.join("; "))
                }
            } else {
                format!("**FAILED**: {}", failed.join("; "))
            }
        );
    }
    md += &format!(
        "\n{} passed, {} failed ({:.0} s)\n",
        result.passed, result.failed, result.wall_s
    );
    dir.bytes("pairs.md", md.as_bytes())?;
    dir.json("summary.json", result)?;
    Ok(md)
}
