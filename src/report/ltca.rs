//! The LTCA report: per-position CSV (`ltca_<variant>.csv`, itself a stiffness file), STE,
//! stiffness and load-sharing plots, the potential-energy table and `summary.json`. Units at
//! this edge: µm, mm, degrees, N, N/m.

use crate::case::Case;
use crate::ltca::PositionResult;
use crate::report::plot::LinePlot;
use crate::report::{OutputDir, ReportError};
use crate::study::ltca::LtcaStudy;

/// Writes every file of the study.
pub fn write(out: OutputDir, case: &Case, study: &LtcaStudy) -> Result<(), ReportError> {
    out.case(case)?;
    let rb2 = case.pair.gears[1].base_radius;
    let torque = study.torque;
    let deg = |r: &PositionResult| r.roll_angle.to_degrees();
    let mut ste_series = Vec::new();
    let mut k_series = Vec::new();
    let mut pressure_series = Vec::new();
    let mut root_series = Vec::new();
    let mut pressure_markers = Vec::new();
    for cycle in &study.cycles {
        out.csv(
            &format!("contact_pressure_{}.csv", cycle.name),
            &[
                "position",
                "roll_angle_deg",
                "gear1_tooth",
                "gear2_tooth",
                "path_from_t1_mm",
                "normal_force_n",
                "curvature_radius_gear1_mm",
                "curvature_radius_gear2_mm",
                "hertz_pressure_mpa",
                "half_width_um",
                "at_tip",
                "fe_pressure_mpa",
                "fe_pressure_gear",
                "fe_pressure_roll_angle_deg",
                "fe_at_tip_corner",
            ],
            cycle.pressure.iter().map(|p| {
                let (t1, t2) = cycle.tooth_pairs[p.pair];
                let fe = cycle
                    .fe_pressure
                    .iter()
                    .find(|r| r.position == p.position && r.pair == p.pair);
                let mut row = vec![
                    p.position.to_string(),
                    format!("{:.6}", cycle.results[p.position].roll_angle.to_degrees()),
                    t1.to_string(),
                    t2.to_string(),
                    format!("{:.6}", p.path_m * 1e3),
                    format!("{:.6e}", p.force_n),
                    format!("{:.6}", p.curvature_radii_m[0] * 1e3),
                    format!("{:.6}", p.curvature_radii_m[1] * 1e3),
                    format!("{:.4}", p.pressure_pa * 1e-6),
                    format!("{:.4}", p.half_width_m * 1e6),
                    p.at_tip.to_string(),
                ];
                row.extend(match fe {
                    Some(r) => [
                        format!("{:.4}", r.pressure_mpa),
                        r.gear.to_string(),
                        format!("{:.6}", r.roll_angle_deg),
                        r.at_tip_corner.to_string(),
                    ],
                    None => Default::default(),
                });
                row
            }),
        )?;
        // The FE's own pressure at the pair's contact, away from tip corners (a corner's is
        // bound by the mesh and would squash the plot).
        pressure_markers.push((
            format!("{} FE contact (nodal tractions)", cycle.name),
            cycle
                .pressure
                .iter()
                .filter_map(|p| {
                    let fe = cycle
                        .fe_pressure
                        .iter()
                        .find(|r| r.position == p.position && r.pair == p.pair)?;
                    (!fe.at_tip_corner).then_some((p.path_m * 1e3, fe.pressure_mpa))
                })
                .collect(),
        ));
        out.csv(
            &format!("root_stress_{}.csv", cycle.name),
            &[
                "position",
                "roll_angle_deg",
                "gear",
                "tooth",
                "path_from_t1_mm",
                "tension_max_principal_mpa",
                "tension_radius_mm",
                "compression_min_principal_mpa",
                "compression_radius_mm",
            ],
            cycle.root_stress.iter().map(|r| {
                vec![
                    r.position.to_string(),
                    format!("{:.6}", r.roll_angle_deg),
                    r.gear.to_string(),
                    r.tooth.to_string(),
                    r.path_mm.map_or(String::new(), |s| format!("{s:.6}")),
                    format!("{:.4}", r.tension_mpa),
                    format!("{:.4}", r.tension_radius_mm),
                    format!("{:.4}", r.compression_mpa),
                    format!("{:.4}", r.compression_radius_mm),
                ]
            }),
        )?;
        // A loaded tooth's fillet tension against where its pair touches: every tooth of a gear
        // on one curve over its whole engagement.
        for gear in [1, 2] {
            let mut curve: Vec<(f64, f64)> = cycle
                .root_stress
                .iter()
                .filter(|r| r.gear == gear)
                .filter_map(|r| Some((r.path_mm?, r.tension_mpa)))
                .collect();
            curve.sort_by(|a, b| a.0.total_cmp(&b.0));
            if !curve.is_empty() {
                root_series.push((format!("{} gear {gear}", cycle.name), curve));
            }
        }
        // Each pair's pressure along the path, so the plot shows it entering and leaving.
        for (k, &(t1, t2)) in cycle.tooth_pairs.iter().enumerate() {
            let mut curve: Vec<(f64, f64)> = cycle
                .pressure
                .iter()
                .filter(|p| p.pair == k)
                .map(|p| (p.path_m * 1e3, p.pressure_pa * 1e-6))
                .collect();
            if curve.len() > 1 {
                curve.sort_by(|a, b| a.0.total_cmp(&b.0));
                pressure_series.push((format!("{} pair {t1}/{t2}", cycle.name), curve));
            }
        }
        let loaded = loaded_pairs(&cycle.results);
        let header = position_header(&cycle.tooth_pairs, &loaded);
        out.csv(
            &format!("ltca_{}.csv", cycle.name),
            &header.iter().map(String::as_str).collect::<Vec<_>>(),
            position_rows(&cycle.results, rb2, &loaded),
        )?;
        let results = &cycle.results;
        ste_series.push((
            format!("{} loaded", cycle.name),
            results
                .iter()
                .map(|r| (deg(r), r.ste * rb2 * 1e6))
                .collect(),
        ));
        if !cycle.modifications.iter().all(|m| m.is_none()) {
            ste_series.push((
                format!("{} unloaded", cycle.name),
                results
                    .iter()
                    .map(|r| (deg(r), r.unloaded_te * rb2 * 1e6))
                    .collect(),
            ));
        }
        k_series.push((
            cycle.name.clone(),
            results.iter().map(|r| (deg(r), r.mesh_stiffness)).collect(),
        ));
        out.chart(
            &format!("load_sharing_{}", cycle.name),
            &LinePlot {
                y_range: None,
                markers: Vec::new(),
                title: format!(
                    "{}: load per tooth pair, relief \"{}\", T = {torque} N·m",
                    case.name(),
                    cycle.name
                ),
                x_label: "driver roll angle [deg]".into(),
                y_label: "normal force [N]".into(),
                series: loaded
                    .iter()
                    .map(|&i| {
                        let (t1, t2) = cycle.tooth_pairs[i];
                        (
                            format!("pair {t1}/{t2}"),
                            results.iter().map(|r| (deg(r), r.pair_forces[i])).collect(),
                        )
                    })
                    .collect(),
            },
        )?;
    }
    let iso = &study.summary.iso_6336;
    let points = case.pair.contact_points;
    let (first, last) = (points.icp * 1e3, points.fcp * 1e3);
    for (g, p) in iso.contact_pressure_iso_mpa.iter().enumerate() {
        pressure_series.push((
            format!("ISO 6336-2 sigma_H gear {}", g + 1),
            vec![(first, *p), (last, *p)],
        ));
    }
    for (g, s) in iso.root_stress_iso_mpa.iter().enumerate() {
        root_series.push((
            format!("ISO 6336-3 sigma_F0 gear {} (method B)", g + 1),
            vec![(first, *s), (last, *s)],
        ));
    }
    out.chart(
        "root_stress",
        &LinePlot {
            y_range: None,
            markers: Vec::new(),
            title: format!(
                "{}: largest fillet tension of a loaded tooth, T = {torque} N·m",
                case.name()
            ),
            x_label: "its contact along the path of contact from T1 [mm]".into(),
            y_label: "max principal stress on the fillet [MPa]".into(),
            series: root_series,
        },
    )?;
    out.chart(
        "contact_pressure",
        &LinePlot {
            y_range: None,
            markers: pressure_markers,
            title: format!(
                "{}: Hertz pressure along the path of contact, T = {torque} N·m",
                case.name()
            ),
            x_label: "path of contact from T1 [mm]".into(),
            y_label: "contact pressure [MPa]".into(),
            series: pressure_series,
        },
    )?;
    out.chart(
        "ste",
        &LinePlot {
            y_range: None,
            markers: Vec::new(),
            title: format!(
                "{}: static transmission error, T = {torque} N·m",
                case.name()
            ),
            x_label: "driver roll angle [deg]".into(),
            y_label: "transmission error along the LOA [um]".into(),
            series: ste_series,
        },
    )?;
    let pe_curve: Vec<(f64, f64)> = study
        .potential_energy
        .samples()
        .iter()
        .map(|(x, k, _)| (x.to_degrees(), *k))
        .collect();
    k_series.push(("potential energy (unmodified)".into(), pe_curve.clone()));
    let (x0, x1) = (pe_curve[0].0, pe_curve[pe_curve.len() - 1].0);
    k_series.push((
        "ISO 6336-1 c_gamma_alpha * b".into(),
        vec![(x0, study.iso.mean_n_per_m), (x1, study.iso.mean_n_per_m)],
    ));
    out.csv(
        "stiffness_potential_energy.csv",
        &["roll_angle_deg", "mesh_stiffness_n_per_m"],
        pe_curve
            .iter()
            .map(|(x, k)| vec![format!("{x:.6}"), format!("{k:.6e}")]),
    )?;
    out.chart(
        "stiffness",
        &LinePlot {
            y_range: None,
            markers: Vec::new(),
            title: format!("{}: mesh stiffness, T = {torque} N·m", case.name()),
            x_label: "driver roll angle [deg]".into(),
            y_label: "mesh stiffness [N/m]".into(),
            series: k_series,
        },
    )?;
    if let Some(peak) = &study.peak_field {
        super::field::write(out, case, peak)?;
    }
    out.json("summary.json", &study.summary)
}

/// The study's lines for the terminal.
pub fn console(study: &LtcaStudy) -> String {
    let mut text = String::new();
    for s in study.cycles.iter().map(|c| &c.summary) {
        text.push_str(&format!(
            "{:<16} k mean {:.4e} min {:.4e} max {:.4e} N/m, STE mean {:.3} um p-p {:.3} um, KKT <= {:.1e}\n",
            s.relief_variant,
            s.mesh_stiffness_mean_n_per_m,
            s.mesh_stiffness_min_n_per_m,
            s.mesh_stiffness_max_n_per_m,
            s.ste_mean_um,
            s.ste_peak_to_peak_um,
            s.max_kkt_residual
        ));
    }
    let pe = &study.potential_energy;
    text.push_str(&format!(
        "potential energy: mean {:.4e} N/m (min {:.4e}, max {:.4e})\n",
        pe.mean(),
        pe.min(),
        pe.max()
    ));
    text.push_str(&format!(
        "ISO 6336-1 method B: c_gamma_alpha*b = {:.4e} N/m, c'*b = {:.4e} N/m\n",
        study.iso.mean_n_per_m, study.iso.single_pair_n_per_m
    ));
    for s in study.cycles.iter().map(|c| &c.summary) {
        if let Some(at) = &s.contact_pressure_max_at {
            text.push_str(&format!(
                "{:<16} Hertz pressure max {:.0} MPa at {:.3} mm from T1 (pair {}/{}, {:.0} N){}\n",
                s.relief_variant,
                s.contact_pressure_max_mpa,
                at.path_mm,
                at.teeth.0,
                at.teeth.1,
                at.force_n,
                s.contact_pressure_at_tip_max_mpa
                    .map(|p| format!(
                        "; {p:.0} MPa at a tip corner (involute Hertz does not hold there)"
                    ))
                    .unwrap_or_default()
            ));
            text.push_str(&format!(
                "{:<16} FE contact pressure (nodal tractions; not resolved where the Hertz width spans few flank elements) max {:.0} MPa{}\n",
                "",
                s.contact_pressure_fe_max_mpa,
                s.contact_pressure_fe_at_tip_corner_max_mpa
                    .map(|p| format!("; {p:.0} MPa at a loaded tip corner (edge contact: bound by the mesh, grows as it is refined)"))
                    .unwrap_or_default()
            ));
        }
    }
    for s in study.cycles.iter().map(|c| &c.summary) {
        for (g, peak) in s.root_stress.iter().enumerate() {
            if let Some(p) = peak {
                text.push_str(&format!(
                    "{:<16} gear {} fillet tension max {:.1} MPa (tooth {}, roll angle {:.2} deg, radius {:.3} mm; ISO's 30 deg tangent at {:.3} mm), compression min {:.1} MPa\n",
                    s.relief_variant,
                    g + 1,
                    p.tension_mpa,
                    p.tooth,
                    p.roll_angle_deg,
                    p.radius_mm,
                    p.iso_30_degree_tangent_radius_mm,
                    p.compression_mpa
                ));
            }
        }
    }
    let iso = &study.summary.iso_6336;
    text.push_str(&format!(
        "ISO 6336 (load factors 1): root sigma_F0 {:.1} / {:.1} MPa (method B, Y_F {:.3} / {:.3}, Y_S {:.3} / {:.3}); contact sigma_H0 {:.0} MPa, sigma_H {:.0} / {:.0} MPa (Z_H {:.3}, Z_E {:.1} sqrt(MPa), Z_eps {:.3})\n",
        iso.root_stress_iso_mpa[0],
        iso.root_stress_iso_mpa[1],
        iso.factors.root[0].method_b.form_factor,
        iso.factors.root[1].method_b.form_factor,
        iso.factors.root[0].method_b.stress_correction,
        iso.factors.root[1].method_b.stress_correction,
        iso.contact_pressure_iso_pitch_point_mpa,
        iso.contact_pressure_iso_mpa[0],
        iso.contact_pressure_iso_mpa[1],
        iso.factors.contact.zone_factor,
        iso.factors.contact.elasticity_factor_sqrt_pa * 1e-3,
        iso.factors.contact.contact_ratio_factor,
    ));
    let sf = &study.summary.safety_factors;
    let show = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{v:.2}"));
    text.push_str(&format!(
        "safety at the design torque (sigma_Flim {:.0} MPa, sigma_Hlim {:.0} MPa): S_F FE {} / {}, ISO {:.2} / {:.2}; S_H FE {}, ISO {:.2} / {:.2}\n",
        sf.root_stress_limit_mpa,
        sf.contact_stress_limit_mpa,
        show(sf.root_fe[0]),
        show(sf.root_fe[1]),
        sf.root_iso[0],
        sf.root_iso[1],
        show(sf.contact_fe),
        sf.contact_iso[0],
        sf.contact_iso[1],
    ));
    for (g, root) in iso.factors.root.iter().enumerate() {
        for note in &root.notes {
            text.push_str(&format!("  ISO 6336-3, gear {}: {note}\n", g + 1));
        }
    }
    let checks = &study.summary.self_checks;
    let failed: Vec<&crate::study::checks::Check> = checks.iter().filter(|c| !c.passed).collect();
    text.push_str(&format!(
        "self-checks: {} of {} passed\n",
        checks.len() - failed.len(),
        checks.len()
    ));
    for check in failed {
        text.push_str(&format!("  {}\n", check.line()));
    }
    text
}

/// The tooth pairs (indices into the cycle's pairs) that carry load at some position. The
/// LTCA also carries the pairs within the engagement margin of the path, in case the load
/// extends the contact; those that never touch get no column.
pub fn loaded_pairs(results: &[PositionResult]) -> Vec<usize> {
    let pairs = results.first().map_or(0, |r| r.pair_forces.len());
    (0..pairs)
        .filter(|&i| results.iter().any(|r| r.pair_forces[i] > 0.0))
        .collect()
}

/// CSV header for [`position_rows`]: columns for the tooth pairs `loaded` of `pairs`.
pub fn position_header(pairs: &[(usize, usize)], loaded: &[usize]) -> Vec<String> {
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
    for &i in loaded {
        let (t1, t2) = pairs[i];
        header.push(format!("force_pair_{t1}_{t2}_n"));
    }
    for &i in loaded {
        let (t1, t2) = pairs[i];
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
pub fn position_rows(
    results: &[PositionResult],
    base_radius_driven: f64,
    loaded: &[usize],
) -> Vec<Vec<String>> {
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
            row.extend(loaded.iter().map(|&i| format!("{:.4}", r.pair_forces[i])));
            row.extend(loaded.iter().map(|&i| {
                r.pair_positions[i].map_or(String::new(), |s| format!("{:.6}", s * 1e3))
            }));
            row.extend([
                r.active_points.to_string(),
                r.candidate_points.to_string(),
                format!("{:.3e}", r.kkt_residual),
            ]);
            row
        })
        .collect()
}
