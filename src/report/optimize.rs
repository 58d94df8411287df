//! Writes the relief optimization study: summary.json, the iterations, the candidates, the
//! Harris map, the STE and the lumped sweep of every candidate (CSV, SVG, PNG).

use std::path::Path;

use super::plot::LinePlot;
use super::{OutputDir, ReportError};
use crate::case::Case;
use crate::study::optimize::{FeCheck, FeCheckRun, OptimizeStudy};

/// The console lines.
pub fn console(study: &OptimizeStudy) -> String {
    let s = &study.summary;
    let mut out = format!(
        "design torque {:.1} N·m, load range {:?} N·m; single-pair deflection {:.2} um\n",
        s.design_torque_nm,
        s.torque_range_nm
            .iter()
            .map(|t| (t * 10.0).round() / 10.0)
            .collect::<Vec<_>>(),
        s.single_pair_deflection_um
    );
    for start in &s.starts {
        out += &format!(
            "  {} from {}: objective {:.4} -> {:.4} um in {} iterations ({} LTCA runs, {:.2} s){}\n",
            start.shape.name(),
            start.start,
            start.objective_start_um,
            start.objective_um,
            start.iterations,
            start.ltca_evaluations,
            start.wall_s,
            match (&start.stop, &start.failure) {
                (crate::optimize::robust::Stop::Iterations, _) =>
                    ", NOT CONVERGED (iteration limit)".to_string(),
                (_, Some(failure)) => format!(", STOPPED: {failure}"),
                _ => String::new(),
            }
        );
    }
    out += &format!(
        "optimum ({} relief, length {:.3} of the end zone from the HPSTC / LPSTC): tip {:.2} / {:.2} um, root {:.2} / {:.2} um (gear 1 / gear 2)\n",
        s.shape.name(),
        s.relief_length_fraction,
        s.tip_relief_um[0],
        s.tip_relief_um[1],
        s.root_relief_um[0],
        s.root_relief_um[1]
    );
    let limit = |name: &str, l: Option<f64>| {
        l.map_or(String::new(), |l| format!(", {name} at most {l:.1} MPa"))
    };
    out += &format!(
        "strength over the load range: root stress {:.1} -> {:.1} MPa, contact pressure {:.1} -> {:.1} MPa (unmodified -> optimum){}{}\n",
        s.root_stress_none_mpa,
        s.root_stress_optimum_mpa,
        s.contact_pressure_none_mpa,
        s.contact_pressure_optimum_mpa,
        limit("gear 1's root stress", s.max_root_stress_mpa.map(|l| l[0]))
            + &limit("gear 2's", s.max_root_stress_mpa.map(|l| l[1])),
        limit("contact pressure", s.max_contact_pressure_mpa),
    );
    out += "candidate            robust STE p-p  at design  min contact ratio  root stress  contact pressure  max dyn. factor\n";
    for c in &s.candidates {
        out += &format!(
            "  {:<18} {:>10.3} um {:>8.3} um {:>12.3}{} {:>8.1} MPa {:>11.1} MPa {:>12.3} at {:.0} rpm\n",
            c.name,
            c.objective_um,
            c.ste_pp_design_um,
            c.contact_ratio_min,
            if c.feasible { " " } else { "*" },
            c.root_stress_max_mpa[0].max(c.root_stress_max_mpa[1]),
            c.contact_pressure_max_mpa,
            c.max_dynamic_factor,
            c.max_dynamic_factor_rpm
        );
    }
    for c in &study.candidates {
        if let Some(diverged) = &c.sweep.diverged {
            out += &format!("  {}'s lumped sweep stopped: {diverged}\n", c.name);
        }
    }
    out += &format!(
        "  (* breaks a limit of the optimizer)\nQP loop {:.2} s ({:.3} s in Clarabel), bodies {:.2} s, all {:.2} s\n",
        s.qp_loop_wall_s, s.qp_solve_wall_s, s.model_wall_s, s.wall_s
    );
    out
}

/// Writes everything but the FE cross-check.
pub fn write(dir: OutputDir, case: &Case, study: &OptimizeStudy) -> Result<(), ReportError> {
    dir.case(case)?;
    let f = |v: f64| format!("{v:.9e}");
    let candidates = &study.candidates;
    dir.csv(
        "iterations.csv",
        &[
            "start",
            "iteration",
            "objective_um",
            "predicted_reduction_um",
            "actual_reduction_um",
            "trust_radius",
            "accepted",
            "trial_tip1_um",
            "trial_root1_um",
            "trial_tip2_um",
            "trial_root2_um",
            "trial_length_fraction",
            "qp_iterations",
            "kkt_residual",
            "qp_solve_wall_s",
        ],
        study.optima.iter().flat_map(|(name, o)| {
            o.iterations.iter().map(move |r| {
                let mut row = vec![
                    name.clone(),
                    r.iteration.to_string(),
                    f(r.objective_um),
                    f(r.predicted_reduction_um),
                    f(r.actual_reduction_um),
                    f(r.trust_radius),
                    r.accepted.to_string(),
                ];
                row.extend(r.trial.iter().map(|v| f(*v)));
                row.extend([
                    r.qp_iterations.to_string(),
                    f(r.kkt_residual),
                    f(r.qp_solve_s),
                ]);
                row
            })
        }),
    )?;
    dir.csv(
        "candidates.csv",
        &[
            "candidate",
            "kind",
            "tip_relief_gear1_um",
            "root_relief_gear1_um",
            "tip_relief_gear2_um",
            "root_relief_gear2_um",
            "relief_length_fraction",
            "shape",
            "objective_um",
            "ste_pp_design_um",
            "contact_ratio_design",
            "end_relief_recess_um",
            "end_relief_approach_um",
            "root_stress_max_gear1_mpa",
            "root_stress_max_gear2_mpa",
            "contact_pressure_max_mpa",
            "feasible",
            "max_dynamic_factor",
            "max_dynamic_factor_rpm",
        ],
        study
            .summary
            .candidates
            .iter()
            .zip(candidates)
            .map(|(line, c)| {
                vec![
                    c.name.clone(),
                    format!("{:?}", c.kind).to_lowercase(),
                    f(line.tip_relief_um[0]),
                    f(line.root_relief_um[0]),
                    f(line.tip_relief_um[1]),
                    f(line.root_relief_um[1]),
                    line.relief_length_fraction.map_or(String::new(), f),
                    line.shape.map_or(String::new(), |s| s.name().to_string()),
                    f(c.response.objective_um),
                    f(c.ste_pp_design_um),
                    f(c.contact_ratio_design),
                    f(c.end_relief_um[0]),
                    f(c.end_relief_um[1]),
                    f(line.root_stress_max_mpa[0]),
                    f(line.root_stress_max_mpa[1]),
                    f(line.contact_pressure_max_mpa),
                    c.feasible.to_string(),
                    f(c.sweep.max_dynamic_factor),
                    f(c.sweep.max_dynamic_factor_rpm),
                ]
            }),
    )?;
    let names: Vec<&str> = candidates.iter().map(|c| c.name.as_str()).collect();
    let header = |first: &str, suffix: &str| {
        std::iter::once(first.to_string())
            .chain(names.iter().map(|n| format!("{n}{suffix}")))
            .collect::<Vec<_>>()
    };
    let harris_header = header("torque_nm", "_ste_pp_um");
    let torques = &study.harris_range.torques;
    dir.csv(
        "harris.csv",
        &harris_header.iter().map(|s| s.as_str()).collect::<Vec<_>>(),
        torques.iter().enumerate().map(|(j, t)| {
            std::iter::once(f(*t))
                .chain(candidates.iter().map(|c| f(c.harris.ste_pp_um[j])))
                .collect()
        }),
    )?;
    let ste_header = header("roll_angle_deg", "_ste_um");
    dir.csv(
        "ste_design.csv",
        &ste_header.iter().map(|s| s.as_str()).collect::<Vec<_>>(),
        (0..candidates[0].roll_deg.len()).map(|i| {
            std::iter::once(f(candidates[0].roll_deg[i]))
                .chain(candidates.iter().map(|c| f(c.ste_design_um[i])))
                .collect()
        }),
    )?;
    let sweep_header = header("driver_rpm", "_dynamic_factor");
    dir.csv(
        "sweep.csv",
        &sweep_header.iter().map(|s| s.as_str()).collect::<Vec<_>>(),
        study.rpms.iter().enumerate().map(|(i, rpm)| {
            std::iter::once(f(*rpm))
                .chain(candidates.iter().map(|c| {
                    // Empty beyond a sweep that diverged there.
                    c.sweep
                        .dynamic_factor
                        .get(i)
                        .map_or(String::new(), |d| f(*d))
                }))
                .collect()
        }),
    )?;
    let series = |points: &dyn Fn(&crate::study::optimize::Candidate) -> Vec<(f64, f64)>| {
        candidates
            .iter()
            .map(|c| (c.name.clone(), points(c)))
            .collect::<Vec<_>>()
    };
    // One candidate far above the rest (a case's long relief, whose unloaded TE dominates at
    // light load) would squash the others against the axis: cut the scale at 1.5 × the next
    // candidate's largest value when the largest is more than twice that, and say so.
    let mut tops: Vec<f64> = candidates
        .iter()
        .map(|c| crate::signal::largest(c.harris.ste_pp_um.iter().copied()))
        .filter(|v| v.is_finite())
        .collect();
    tops.sort_by(|a, b| b.total_cmp(a));
    let cut = (tops.len() > 1 && tops[0] > 2.0 * tops[1]).then(|| 1.5 * tops[1]);
    dir.chart(
        "harris",
        &LinePlot {
            y_range: cut.map(|top| (0.0, top)),
            markers: Vec::new(),
            title: format!(
                "{}: Harris map, loaded STE peak-to-peak against torque{}",
                case.name(),
                cut.map_or(String::new(), |top| format!(" (scale cut at {top:.1} um)"))
            ),
            x_label: "torque on the driven gear [N·m]".into(),
            y_label: "STE peak-to-peak [um]".into(),
            series: series(&|c| {
                torques
                    .iter()
                    .copied()
                    .zip(c.harris.ste_pp_um.iter().copied())
                    .collect()
            }),
        },
    )?;
    dir.chart(
        "ste_design",
        &LinePlot {
            y_range: None,
            markers: Vec::new(),
            title: format!(
                "{}: loaded STE at the design torque {:.1} N·m",
                case.name(),
                study.design_torque
            ),
            x_label: "driver roll angle [deg]".into(),
            y_label: "STE along the line of action [um]".into(),
            series: series(&|c| {
                c.roll_deg
                    .iter()
                    .copied()
                    .zip(c.ste_design_um.iter().copied())
                    .collect()
            }),
        },
    )?;
    dir.chart(
        "sweep",
        &LinePlot {
            y_range: None,
            markers: Vec::new(),
            title: format!("{}: lumped dynamic factor per candidate", case.name()),
            x_label: "driver speed [rpm]".into(),
            y_label: "dynamic factor".into(),
            series: series(&|c| {
                study
                    .rpms
                    .iter()
                    .copied()
                    .zip(c.sweep.dynamic_factor.iter().copied())
                    .collect()
            }),
        },
    )?;
    dir.chart(
        "convergence",
        &LinePlot {
            y_range: None,
            markers: Vec::new(),
            title: format!(
                "{}: robust objective per trust-region iteration",
                case.name()
            ),
            x_label: "iteration".into(),
            y_label: "weighted STE peak-to-peak [um]".into(),
            series: study
                .optima
                .iter()
                .map(|(name, o)| {
                    (
                        name.clone(),
                        o.iterations
                            .iter()
                            .map(|r| (r.iteration as f64, r.objective_um))
                            .chain(std::iter::once((
                                o.iterations.len() as f64 + 1.0,
                                o.best.response.objective_um,
                            )))
                            .collect(),
                    )
                })
                .collect(),
        },
    )?;
    dir.json("summary.json", &study.summary)
}

/// Reads one cross-check run back from its `geardyn fe` folder; the message says what is missing.
pub fn read_fe_check_run(dir: &Path) -> Result<FeCheckRun, String> {
    let dte = super::compare::read_fe_run(dir)?;
    let summary = super::compare::fe_summary(dir)?;
    let number = |path: &[&str]| super::compare::summary_number(&summary, dir, path);
    Ok(FeCheckRun {
        dte,
        dte_peak_to_peak_rad: number(&["dte_peak_to_peak_rad"])?,
        dte_lowpass_peak_to_peak_rad: number(&["dte_lowpass", "peak_to_peak_rad"]).ok(),
        ltca_same_mesh_peak_to_peak_rad: number(&["ltca_same_mesh", "ste_peak_to_peak_rad"]).ok(),
        impact_d1_max_n: number(&["impact_d1_max_n"]).ok(),
        mesh_frequency_hz: number(&["mesh_frequency_hz"])?,
    })
}

/// The cross-check as fe_check.csv and fe_check.md; returns the Markdown table.
pub fn write_fe_check(dir: OutputDir, check: &FeCheck) -> Result<String, ReportError> {
    let f = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.6e}"));
    let harmonic =
        |l: &crate::study::optimize::FeCheckLine, i: usize| l.fe_high_harmonics_um.map(|h| h[i]);
    dir.csv(
        "fe_check.csv",
        &[
            "candidate",
            "kind",
            "ltca_ste_pp_um",
            "ltca_ste_h1_um",
            "ltca_same_mesh_ste_pp_um",
            "fe_low_dte_lowpass_pp_um",
            "fe_low_dte_pp_um",
            "fe_high_dte_pp_um",
            "fe_high_h1_um",
            "fe_high_h2_um",
            "fe_high_h3_um",
            "fe_high_impact_d1_max_n",
            "lumped_dynamic_factor_high",
            "fe_errors",
        ],
        check.lines.iter().map(|l| {
            vec![
                l.candidate.clone(),
                format!("{:?}", l.kind).to_lowercase(),
                f(Some(l.ltca_ste_pp_um)),
                f(Some(l.ltca_ste_h1_um)),
                f(l.ltca_same_mesh_ste_pp_um),
                f(l.fe_low_dte_lowpass_pp_um),
                f(l.fe_low_dte_pp_um),
                f(l.fe_high_dte_pp_um),
                f(harmonic(l, 0)),
                f(harmonic(l, 1)),
                f(harmonic(l, 2)),
                f(l.fe_high_impact_d1_max_n),
                f(l.lumped_dynamic_factor_high),
                l.fe_errors.join("; "),
            ]
        }),
    )?;
    let g = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{v:.3}"));
    let mut md = String::from(
        "| candidate | LTCA STE p-p (case mesh) [um] | LTCA same mesh [um] | FE low speed DTE p-p, low-passed [um] | LTCA STE 1st harmonic [um] | FE high speed DTE p-p [um] | FE high speed 1st / 2nd / 3rd harmonic [um] | impact d1 max [N] | lumped K_v at that speed |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for l in &check.lines {
        md += &format!(
            "| {} | {:.3} | {} | {} | {:.3} | {} | {} | {} | {} |\n",
            l.candidate,
            l.ltca_ste_pp_um,
            g(l.ltca_same_mesh_ste_pp_um),
            g(l.fe_low_dte_lowpass_pp_um),
            l.ltca_ste_h1_um,
            g(l.fe_high_dte_pp_um),
            l.fe_high_harmonics_um.map_or("–".into(), |h| format!(
                "{:.3} / {:.3} / {:.3}",
                h[0], h[1], h[2]
            )),
            g(l.fe_high_impact_d1_max_n),
            g(l.lumped_dynamic_factor_high)
        );
    }
    md += &format!(
        "\nRanking, best first. LTCA STE peak-to-peak: {}. FE low speed ({}): {}. LTCA STE 1st harmonic: {}. FE high speed DTE 1st harmonic: {}.\nKendall tau, FE against LTCA: low speed {}, high speed {}; the best optimum ahead of every baseline: low speed {:?}, high speed {:?}. FE time {:.0} s.\n",
        check.ltca_ranking.join(", "),
        check.fe_low_measure,
        check.fe_low_ranking.join(", "),
        check.ltca_h1_ranking.join(", "),
        check.fe_high_ranking.join(", "),
        g(check.kendall_tau_low),
        g(check.kendall_tau_high),
        check.optimum_first_low,
        check.optimum_first_high,
        check.fe_wall_s
    );
    dir.bytes("fe_check.md", md.as_bytes())?;
    Ok(md)
}
