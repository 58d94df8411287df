//! Reports of the lumped-model studies: the speed sweep (`sweep.csv`, response, dynamic factor,
//! harmonics, stability and waterfall plots, the run-up), the Floquet map (`stability.csv`) and
//! the integrator table. Units at this edge: µm, rpm, Hz.

use crate::case::Case;
use crate::report::plot::{ColourMap, LinePlot};
use crate::report::{stiffness_csv, OutputDir, ReportError};
use crate::study::lumped::LumpedSetup;
use crate::study::stability::StabilityStudy;
use crate::study::sweep::SweepStudy;
use crate::study::validate::IntegratorSummary;
use crate::sweep::{SweepPoint, HARMONICS, PEAKS};

/// The model's line for the terminal: stiffness, inertias, m_e, f_n, backlash and the model.
pub fn setup_console(setup: &LumpedSetup) -> String {
    let model = &setup.model;
    format!(
        "stiffness {}: mean {:.4e} N/m; I1 = {:.1} kg·mm², I2 = {:.1} kg·mm², m_e = {:.4} kg; f_n = {:.1} Hz; {}\nmodel: {}\n",
        model.mesh.source,
        model.mesh.mean(),
        setup.inertias[0] * 1e6,
        setup.inertias[1] * 1e6,
        model.effective_mass(),
        setup.natural_frequency_hz,
        match model.backlash {
            Some(j) => format!("backlash {:.2} um (separation modelled)", j * 1e6),
            None => "zero backlash (no separation: the back flank engages at once)".into(),
        },
        setup.model_note
    )
}

/// Writes every file of a sweep.
pub fn write_sweep(out: OutputDir, case: &Case, study: &SweepStudy) -> Result<(), ReportError> {
    out.case(case)?;
    let model = &study.setup.model;
    // The stiffness the sweep used, hub to hub (the mesh with the bodies' twist in series, as
    // the LTCA and the FE give it), in the file format every source reads back: a sweep that
    // reads it (a hub-to-hub source) takes the twist out again and integrates the same model.
    let hub_to_hub = model
        .mesh
        .without_series_compliance(-study.setup.body_compliance)
        .expect("adding a compliance keeps k positive");
    stiffness_csv::write_stiffness_csv(&out.path("stiffness.csv"), &hub_to_hub).map_err(|e| {
        ReportError::Io {
            path: out.path("stiffness.csv").display().to_string(),
            source: e,
        }
    })?;
    let mut header: Vec<String> = [
        "driver_rpm",
        "mesh_hz",
        "dte_rms_up_um",
        "dte_rms_down_um",
        "dte_pp_up_um",
        "dynamic_factor_up",
        "dynamic_factor_down",
        "separated_up",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    header.extend((1..=HARMONICS).map(|h| format!("h{h}_um")));
    header.extend(
        [
            "floquet_max_multiplier_linear",
            "floquet_max_multiplier_orbit",
            "periods_up",
            "converged_up",
        ]
        .map(String::from),
    );
    for k in 1..=PEAKS {
        header.extend([format!("peak{k}_hz"), format!("peak{k}_um")]);
    }
    let rows = study.up.iter().zip(&study.down).map(|(u, d)| {
        let mut row = vec![
            format!("{:.3}", u.driver_speed_rpm),
            format!("{:.3}", u.mesh_frequency_hz),
            format!("{:.6}", u.dte_rms * 1e6),
            format!("{:.6}", d.dte_rms * 1e6),
            format!("{:.6}", u.dte_peak_to_peak * 1e6),
            format!("{:.6}", u.dynamic_factor),
            format!("{:.6}", d.dynamic_factor),
            u.separated.to_string(),
        ];
        row.extend(u.harmonics.iter().map(|h| format!("{:.6}", h * 1e6)));
        row.extend([
            format!("{:.6}", u.floquet_linear),
            u.floquet_orbit
                .map_or_else(String::new, |m| format!("{m:.6}")),
            u.periods.to_string(),
            u.converged.to_string(),
        ]);
        for k in 0..PEAKS {
            match u.peaks.get(k) {
                Some((hz, a)) => row.extend([format!("{hz:.3}"), format!("{:.6}", a * 1e6)]),
                None => row.extend([String::new(), String::new()]),
            }
        }
        row
    });
    out.csv(
        "sweep.csv",
        &header.iter().map(String::as_str).collect::<Vec<_>>(),
        rows,
    )?;

    let (up, down) = (&study.up, &study.down);
    let curve = |points: &[SweepPoint], f: &dyn Fn(&SweepPoint) -> f64| -> Vec<(f64, f64)> {
        points.iter().map(|p| (p.driver_speed_rpm, f(p))).collect()
    };
    // The source's name without the folders of the machine it ran on.
    let source = &crate::report::plot::without_folders(&model.mesh.source);
    let zeta = study.setup.damping_ratio;
    let plots = [
        (
            "response",
            "DTE rms along the LOA [um]",
            vec![
                ("up-sweep".to_string(), curve(up, &|p| p.dte_rms * 1e6)),
                ("down-sweep".to_string(), curve(down, &|p| p.dte_rms * 1e6)),
            ],
        ),
        (
            "dynamic_factor",
            "max dynamic mesh force / static",
            vec![
                ("up-sweep".to_string(), curve(up, &|p| p.dynamic_factor)),
                ("down-sweep".to_string(), curve(down, &|p| p.dynamic_factor)),
            ],
        ),
        (
            "harmonics",
            "DTE amplitude at mesh harmonic [um]",
            (0..HARMONICS)
                .map(|h| {
                    (
                        format!("order {} x z1", h + 1),
                        curve(up, &|p| p.harmonics[h] * 1e6),
                    )
                })
                .collect(),
        ),
        (
            "stability",
            "largest Floquet multiplier |lambda| (> 1 unstable)",
            vec![
                (
                    "periodic orbit of the integrated model".to_string(),
                    curve(up, &|p| p.floquet_orbit.unwrap_or(f64::NAN)),
                ),
                (
                    "drive flanks linearized".to_string(),
                    curve(up, &|p| p.floquet_linear),
                ),
            ],
        ),
    ];
    for (stem, label, series) in plots {
        out.chart(
            stem,
            &LinePlot {
                y_range: None,
                markers: Vec::new(),
                title: format!("{}: {stem}, stiffness {source}, zeta = {zeta}", case.name()),
                x_label: "driver speed [rpm]".into(),
                y_label: label.into(),
                series,
            },
        )?;
    }

    // Order map (the waterfall): the DTE amplitude of each mesh harmonic over speed, a row per
    // harmonic filling the plane, with the natural frequencies as curves n = f_j / f_mesh: where
    // a curve crosses a row, that harmonic meets that mode.
    let rpms = &study.rpms;
    let step_rpm = if rpms.len() > 1 {
        rpms[1] - rpms[0]
    } else {
        1.0
    };
    let mesh_hz_per_rpm = case.pair.gears[0].teeth() as f64 / 60.0;
    let linear = model.linearized();
    let overlays = linear
        .structure
        .modes(linear.mesh.mean())
        .iter()
        .map(|m| {
            let hz = m.frequency / std::f64::consts::TAU;
            (
                format!("mode {hz:.0} Hz"),
                rpms.iter()
                    .map(|rpm| (*rpm, hz / (rpm * mesh_hz_per_rpm)))
                    .filter(|p| p.1 <= HARMONICS as f64 + 0.5)
                    .collect(),
            )
        })
        .collect();
    out.chart(
        "waterfall",
        &ColourMap {
            title: format!(
                "{}: order map of the DTE (log colour), {source}",
                case.name()
            ),
            x_label: "driver speed [rpm]".into(),
            y_label: "mesh harmonic order (frequency / f_mesh)".into(),
            cells: up
                .iter()
                .flat_map(|p| {
                    p.harmonics
                        .iter()
                        .enumerate()
                        .map(move |(h, a)| (p.driver_speed_rpm, (h + 1) as f64, a * 1e6))
                })
                .collect(),
            cell_size: (step_rpm, 1.0),
            decades: 3.0,
            value_label: "um".into(),
            overlays,
        },
    )?;
    campbell(out, case, model, rpms)?;
    if let Some((duration, r)) = &study.run_up {
        let static_x = model.transmission_error(&model.static_state());
        let rpm_of = |speed: f64| speed * 60.0 / std::f64::consts::TAU;
        out.csv(
            "runup.csv",
            &[
                "time_s",
                "driver_rpm",
                "dte_about_static_um",
                "mesh_force_n",
            ],
            (0..r.time.len()).map(|i| {
                vec![
                    format!("{:.9}", r.time[i]),
                    format!("{:.4}", rpm_of(r.driver_speed[i])),
                    format!("{:.6}", (r.displacement[i] - static_x) * 1e6),
                    format!("{:.4}", r.mesh_force[i]),
                ]
            }),
        )?;
        let (from, to) = (rpms[0], rpms[rpms.len() - 1]);
        out.chart(
            "runup",
            &LinePlot {
                y_range: None,
                markers: Vec::new(),
                title: format!(
                    "{}: run-up {from:.0} -> {to:.0} rpm in {duration} s, stiffness {source}",
                    case.name()
                ),
                x_label: "driver speed [rpm]".into(),
                y_label: "DTE about the static deflection [um]".into(),
                series: vec![(
                    "run-up".into(),
                    (0..r.time.len())
                        .step_by((r.time.len() / 20_000).max(1))
                        .map(|i| {
                            (
                                rpm_of(r.driver_speed[i]),
                                (r.displacement[i] - static_x) * 1e6,
                            )
                        })
                        .collect(),
                )],
            },
        )?;
    }
    out.json("summary.json", &study.summary)
}

/// The sweep's lines for the terminal.
pub fn sweep_console(study: &SweepStudy) -> String {
    let s = &study.summary;
    let mut text = String::new();
    if let Some((_, r)) = &study.run_up {
        text.push_str(&format!(
            "run-up: {} RK4 steps, {} samples in runup.csv\n",
            r.steps,
            r.time.len()
        ));
    }
    text.push_str(&format!(
        "{} points in {:.2} s (stiffness {:.2} s); resonances at {:?} rpm; primary {} rpm (f_mesh = f_n at {:.0} rpm); max dynamic factor {:.3}\n",
        s.points,
        s.wall_s,
        s.stiffness_wall_s,
        s.resonance_rpm,
        s.primary_resonance_rpm
            .map_or("none".into(), |r| format!("{r:.0}")),
        study.primary_rpm_expected,
        s.max_dynamic_factor
    ));
    for warning in &s.warnings {
        text.push_str(&format!("warning: {warning}\n"));
    }
    text
}

/// Writes the Floquet map.
pub fn write_stability(
    out: OutputDir,
    case: &Case,
    study: &StabilityStudy,
) -> Result<(), ReportError> {
    out.case(case)?;
    let z1 = case.pair.gears[0].teeth() as f64;
    let rpms = &study.rpms;
    out.csv(
        "stability.csv",
        &[
            "driver_rpm",
            "mesh_hz",
            "floquet_max_multiplier_orbit",
            "floquet_max_multiplier_linear",
        ],
        rpms.iter()
            .zip(&study.multipliers)
            .zip(&study.linear_multipliers)
            .map(|((r, m), l)| {
                vec![
                    format!("{r:.3}"),
                    format!("{:.3}", r / 60.0 * z1),
                    m.map_or_else(String::new, |m| format!("{m:.8}")),
                    format!("{l:.8}"),
                ]
            }),
    )?;
    out.chart(
        "stability",
        &LinePlot {
            y_range: None,
            markers: Vec::new(),
            title: format!(
                "{}: Floquet stability, stiffness {}, zeta = {}",
                case.name(),
                study.summary.stiffness_source,
                study.summary.damping_ratio
            ),
            x_label: "driver speed [rpm]".into(),
            y_label: "largest Floquet multiplier |lambda|".into(),
            series: vec![
                (
                    "periodic orbit of the integrated model".into(),
                    rpms.iter()
                        .copied()
                        .zip(study.multipliers.iter().map(|m| m.unwrap_or(f64::NAN)))
                        .collect(),
                ),
                (
                    "drive flanks linearized".into(),
                    rpms.iter()
                        .copied()
                        .zip(study.linear_multipliers.iter().copied())
                        .collect(),
                ),
                (
                    "stability limit |lambda| = 1".into(),
                    vec![(rpms[0], 1.0), (rpms[rpms.len() - 1], 1.0)],
                ),
            ],
        },
    )?;
    out.json("summary.json", &study.summary)
}

/// The Floquet map's line for the terminal.
pub fn stability_console(study: &StabilityStudy) -> String {
    let s = &study.summary;
    format!(
        "{} speeds in {:.3} s; unstable ranges {:?} rpm (the integrated model's periodic orbit; drive flanks linearized: {:?}); principal regions expected near {:?} rpm; max |lambda| {:.4} (linearized {:.4}){}\n",
        s.points,
        s.wall_s,
        s.unstable_rpm_ranges,
        s.linear_unstable_rpm_ranges,
        s.parametric_region_centres_rpm
            .iter()
            .map(|r| r.round())
            .collect::<Vec<_>>(),
        s.max_multiplier,
        s.max_multiplier_linear,
        if s.no_orbit_rpm_ranges.is_empty() {
            String::new()
        } else {
            format!(
                "; no period-one response found in {:?} rpm (past a fold, where a sweep at zero backlash diverges, or sub-harmonic)",
                s.no_orbit_rpm_ranges
            )
        }
    )
}

/// Writes the integrator table (CSV and Markdown) and its summary; returns the Markdown.
pub fn write_integrators(
    out: OutputDir,
    summary: &IntegratorSummary,
) -> Result<String, ReportError> {
    let limit = |l: Option<f64>| {
        l.map_or("none (unconditionally stable)".to_string(), |v| {
            format!("{v:.6}")
        })
    };
    let header = [
        "scheme",
        "stability_limit_predicted_wh",
        "stability_limit_observed_wh",
        "accuracy_1pct_predicted_wh",
        "accuracy_1pct_observed_wh",
        "formal_order",
        "observed_order_smooth",
        "observed_order_separating",
        "error_smooth_32",
        "error_separating_32",
    ];
    let rows: Vec<Vec<String>> = summary
        .schemes
        .iter()
        .map(|r| {
            vec![
                r.scheme.to_string(),
                limit(r.predicted_limit),
                limit(r.observed_limit),
                format!("{:.6}", r.predicted_accuracy_limit),
                format!("{:.6}", r.observed_accuracy_limit),
                format!("{:.1}", r.formal_order),
                format!("{:.3}", r.observed_order_smooth),
                format!("{:.3}", r.observed_order_separating),
                format!("{:.3e}", r.error_smooth),
                format!("{:.3e}", r.error_separating),
            ]
        })
        .collect();
    out.csv("integrators.csv", &header, rows.clone())?;
    let mut markdown = format!(
        "| {} |\n|{}\n",
        header.join(" | "),
        "---|".repeat(header.len())
    );
    for row in &rows {
        markdown.push_str(&format!("| {} |\n", row.join(" | ")));
    }
    markdown.push_str(&resonance_sweep_table(out, summary)?);
    out.bytes("integrators.md", markdown.as_bytes())?;
    out.json("summary.json", summary)?;
    Ok(markdown)
}

/// `resonance_sweep.csv` and its Markdown: the case's model swept across the primary resonance
/// at each step refinement, the largest dynamic factor against the finest step's.
fn resonance_sweep_table(
    out: OutputDir,
    summary: &IntegratorSummary,
) -> Result<String, ReportError> {
    let header = [
        "refinement",
        "steps_per_period",
        "unsettled_speeds",
        "max_dynamic_factor",
        "at_rpm",
        "change_against_finest",
        "diverged_rpm",
        "diverged_after_periods",
    ];
    let finest = summary
        .resonance_sweep
        .last()
        .map_or(f64::NAN, |r| r.max_dynamic_factor);
    let rows: Vec<Vec<String>> = summary
        .resonance_sweep
        .iter()
        .map(|r| {
            vec![
                format!("{}", r.refinement),
                format!("{}", r.steps_per_period),
                format!("{}", r.unsettled),
                format!("{:.4}", r.max_dynamic_factor),
                format!("{:.1}", r.max_dynamic_factor_rpm),
                format!("{:+.2e}", r.max_dynamic_factor / finest - 1.0),
                r.diverged_rpm.map_or("-".into(), |v| format!("{v:.1}")),
                r.diverged_periods.map_or("-".into(), |v| v.to_string()),
            ]
        })
        .collect();
    out.csv("resonance_sweep.csv", &header, rows.clone())?;
    let (from, to) = summary.resonance_sweep_rpm;
    let refinements: Vec<String> = summary
        .resonance_sweep
        .iter()
        .map(|r| r.refinement.to_string())
        .collect();
    let mut markdown = format!(
        "\nThe case's model swept up from {from:.0} to {to:.0} rpm across the primary resonance \
         at {} × the sweep's RK4 steps (the largest dynamic factor over the speeds that \
         settled):\n\n| {} |\n|{}\n",
        refinements.join(", "),
        header.join(" | "),
        "---|".repeat(header.len())
    );
    for row in &rows {
        markdown.push_str(&format!("| {} |\n", row.join(" | ")));
    }
    Ok(markdown)
}

/// Writes `validate frequencies`: mesh_modes.csv (per position), modal.csv, frequencies.md and
/// summary.json; returns the Markdown table.
pub fn write_mesh_modes(
    out: OutputDir,
    case: &Case,
    result: &crate::study::frequencies::MeshModes,
) -> Result<String, ReportError> {
    out.case(case)?;
    out.json("summary.json", result)?;
    super::compare::modal_csv(out, &result.modal)?;
    let both = [&result.driver_held, &result.both_free];
    out.csv(
        "mesh_modes.csv",
        &["hubs", "driver_rotation_deg", "fe_modal_hz", "lumped_hz"],
        both.iter().flat_map(|c| {
            c.fe_modal_hz.iter().zip(&c.lumped_hz_per_position).map(
                move |((deg, hz), (_, lumped))| {
                    vec![
                        format!("{:?}", c.hubs),
                        format!("{deg:.4}"),
                        format!("{hz:.2}"),
                        format!("{lumped:.2}"),
                    ]
                },
            )
        }),
    )?;
    let mut markdown = format!(
        "Mesh mode, lumped model against the FE modal analysis ({} positions, mesh {} / {} mm, {:.1} N·m)\n\n\
         Both frozen at the same positions, each column the mean of the per-position mesh modes \
         (the lumped model's mode of the rank its mesh mode has at the mean stiffness, the FE modal's mode paired with it by shape); \
         the last column is the lumped mode at the mean tangent stiffness (what the sweep's resonance follows).\n\n\
         | boundary | lumped drive | FE modal mean [Hz] | lumped, case's bodies [Hz] | rel | rigid gears [Hz] | rel | within 2 % | worst position | lumped at mean k [Hz] |\n|---|---|---|---|---|---|---|---|---|---|\n",
        result.positions,
        result.fine_element_mm,
        result.coarse_element_mm,
        result.torque_nm
    );
    for c in both {
        markdown.push_str(&format!(
            "| {:?} | {} | {:.1} | {:.1} | {:+.2} % | {:.1} | {:+.2} % | {} | {:+.2} % | {:.1} |\n",
            c.hubs,
            c.drive.name(),
            c.fe_modal_mean_hz,
            c.lumped_hz,
            100.0 * c.lumped_rel,
            c.lumped_rigid_hz,
            100.0 * c.lumped_rigid_rel,
            if c.pass { "yes" } else { "**no**" },
            100.0 * c.lumped_rel_worst_position,
            c.lumped_at_mean_stiffness_hz
        ));
    }
    for c in both {
        if c.positions_paired_off_largest_share > 0 {
            markdown.push_str(&format!(
                "\n{:?}: at {} of {} positions the FE mode paired by shape with the lumped mesh mode is not the FE modal's own mesh mode (its largest compliance share; their mean {:.1} Hz): a body mode near the mesh mode shares its compliance, and the two are compared mode for mode (modal.csv has every mode's shares).\n",
                c.hubs,
                c.positions_paired_off_largest_share,
                result.positions,
                c.fe_modal_largest_share_mean_hz
            ));
        }
    }
    let held = &result.driver_held;
    markdown.push_str(&match (
        held.driver_torsion_fe_modal_hz,
        held.driver_torsion_lumped_hz,
    ) {
        (Some(fe), Some(lumped)) => format!(
            "\nDriver body's torsion, driver held (its rim against the held hub; the FE modal's mode paired with the lumped model's by shape): FE modal {fe:.0} Hz, lumped {lumped:.0} Hz ({:+.2} %).\n",
            100.0 * (lumped / fe - 1.0)
        ),
        (Some(fe), None) => format!(
            "\nDriver body's torsion, driver held: FE modal {fe:.0} Hz; the lumped model has rigid bodies.\n"
        ),
        (None, _) => "\nDriver body's torsion, driver held: not among the FE modal's ten lowest modes.\n".into(),
    });
    let lateral: Vec<String> = held
        .excited_body_modes_fe_modal
        .iter()
        .filter(|m| m.kind.contains("lateral"))
        .map(|m| format!("{} {:.0} Hz", m.kind, m.hz))
        .collect();
    if !lateral.is_empty() {
        markdown.push_str(&format!(
            "Lateral body modes the mesh drives (a rim swaying on its body against the held bore, along the line of action; in the lumped model only as its rims' sway where `lumped.body_sway` gives it, see its note): {}.\n",
            lateral.join(", ")
        ));
    }
    markdown.push_str(&format!("\nmodel: {}\n", result.model_note));
    out.bytes("frequencies.md", markdown.as_bytes())?;
    Ok(markdown)
}

/// The Campbell diagram of the lumped structure: its natural frequencies linearized about the
/// design load (the force law's mean tangent stiffness) against the mesh-harmonic lines
/// n z₁ n_rpm / 60 over the sweep's speeds (a torsional model has no gyroscopic terms, so the
/// modes are flat lines); where a line crosses a mode, the sweep's resonances sit. Writes
/// `modes.csv` (frequency, mesh energy share, shape over the coordinates), `campbell.csv` (each
/// crossing's speed) and `campbell.{png,svg}`.
fn campbell(
    out: OutputDir,
    case: &Case,
    model: &crate::lumped::MeshModel,
    rpms: &[f64],
) -> Result<(), ReportError> {
    let linear = model.linearized();
    let structure = &linear.structure;
    let modes = structure.modes(linear.mesh.mean());
    let mut header = vec![
        "mode".to_string(),
        "frequency_hz".to_string(),
        "mesh_energy_share".to_string(),
    ];
    header.extend(structure.names.iter().map(|n| format!("shape_{n}")));
    out.csv(
        "modes.csv",
        &header.iter().map(String::as_str).collect::<Vec<_>>(),
        modes.iter().enumerate().map(|(j, m)| {
            let mut row = vec![
                (j + 1).to_string(),
                format!("{:.3}", m.frequency / std::f64::consts::TAU),
                format!("{:.4}", m.mesh_energy_share),
            ];
            row.extend(m.shape.iter().map(|x| format!("{x:.5}")));
            row
        }),
    )?;
    let teeth = case.pair.gears[0].teeth() as f64;
    let crossings: Vec<Vec<String>> = modes
        .iter()
        .enumerate()
        .flat_map(|(j, m)| {
            (1..=HARMONICS).map(move |n| {
                let hz = m.frequency / std::f64::consts::TAU;
                vec![
                    (j + 1).to_string(),
                    n.to_string(),
                    format!("{hz:.3}"),
                    format!("{:.2}", hz * 60.0 / (n as f64 * teeth)),
                ]
            })
        })
        .collect();
    out.csv(
        "campbell.csv",
        &["mode", "mesh_harmonic", "frequency_hz", "crossing_rpm"],
        crossings,
    )?;
    let (from, to) = (
        rpms.first().copied().unwrap_or(0.0),
        rpms.last().copied().unwrap_or(1.0),
    );
    let mut series: Vec<(String, Vec<(f64, f64)>)> = (1..=HARMONICS)
        .map(|n| {
            let line = |rpm: f64| (rpm, n as f64 * teeth * rpm / 60.0);
            (format!("{n} x f_mesh"), vec![line(from), line(to)])
        })
        .collect();
    series.extend(modes.iter().enumerate().map(|(j, m)| {
        let hz = m.frequency / std::f64::consts::TAU;
        (
            format!(
                "mode {} {:.0} Hz (mesh share {:.0} %)",
                j + 1,
                hz,
                100.0 * m.mesh_energy_share
            ),
            vec![(from, hz), (to, hz)],
        )
    }));
    out.chart(
        "campbell",
        &LinePlot {
            y_range: None,
            markers: Vec::new(),
            title: format!(
                "{}: Campbell diagram of the lumped model ({})",
                case.name(),
                structure.names.join(", ")
            ),
            x_label: "driver speed [rpm]".into(),
            y_label: "frequency [Hz]".into(),
            series,
        },
    )?;
    Ok(())
}
