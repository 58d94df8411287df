//! `geardyn compare` at the IO edge: an explicit FE run folder read back (its DTE), and the
//! comparison written as summary.json, CSV tables, overlaid spectra and a Markdown table.

use std::path::Path;

use super::plot::{LinePlot, LogScatter};
use super::{OutputDir, ReportError};
use crate::case::Case;
use crate::study::accuracy::{AccuracyCost, FeStiffnessRun};
use crate::study::compare::{CompareSummary, FeDte, Peak};

/// A `geardyn fe` folder's summary.json, and a reader of its numbers by key path whose message
/// names the folder and the key.
pub fn fe_summary(dir: &Path) -> Result<serde_json::Value, String> {
    let shown = dir.display();
    let text = std::fs::read_to_string(dir.join("summary.json"))
        .map_err(|e| format!("{shown} is not a geardyn fe output folder (summary.json: {e})"))?;
    serde_json::from_str(&text).map_err(|e| format!("{shown}/summary.json: {e}"))
}

/// The tooth layout an FE run's summary says it was meshed with (`tooth_layout`); a summary
/// without the key is from before the key existed, when every explicit mesh was graded.
pub fn summary_tooth_layout(
    summary: &serde_json::Value,
    dir: &Path,
) -> Result<crate::mesh::ToothLayout, String> {
    match summary.get("tooth_layout") {
        None => Ok(crate::mesh::ToothLayout::Graded),
        Some(value) => serde_json::from_value(value.clone())
            .map_err(|e| format!("{}/summary.json: tooth_layout: {e}", dir.display())),
    }
}

/// The tooth layout of the FE run in folder `dir` (its summary.json).
pub fn run_tooth_layout(dir: &Path) -> Result<crate::mesh::ToothLayout, String> {
    summary_tooth_layout(&fe_summary(dir)?, dir)
}

/// The tooth layout of the FE run whose folder holds the stiffness file `file` (its
/// summary.json beside it), or None for a file without one (k(θ) from elsewhere: nothing to
/// check).
pub fn stiffness_file_layout(file: &Path) -> Result<Option<crate::mesh::ToothLayout>, String> {
    let dir = match file.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    if !dir.join("summary.json").is_file() {
        return Ok(None);
    }
    run_tooth_layout(dir).map(Some)
}

pub(crate) fn summary_number(
    summary: &serde_json::Value,
    dir: &Path,
    path: &[&str],
) -> Result<f64, String> {
    path.iter()
        .try_fold(summary, |v, key| v.get(key))
        .and_then(|v| v.as_f64())
        .ok_or_else(|| format!("{}/summary.json has no {}", dir.display(), path.join(".")))
}

/// Reads the DTE of a `geardyn fe` output folder (summary.json and history.csv). The message
/// says what is missing.
pub fn read_fe_run(dir: &Path) -> Result<FeDte, String> {
    let shown = dir.display();
    let summary = fe_summary(dir)?;
    let number = |path: &[&str]| summary_number(&summary, dir, path);
    for (key, what) in [("diverged", "diverged"), ("interrupted", "was interrupted")] {
        if summary.get(key).is_some_and(|d| !d.is_null()) {
            return Err(format!(
                "{shown}: the run {what}; compare needs a finished run"
            ));
        }
    }
    let speed = number(&["scene", "driver_speed"])?;
    let scaling = number(&["mass_scaling", "factor"]).unwrap_or(1.0);
    let target_step = summary
        .pointer("/mass_scaling/target_steps_s")
        .is_some_and(|v| !v.is_null());
    // Each gear's inertia is s times its own either way (uniformly, or element by element to
    // a target step): the dashpot 2ζ√(k r² I) of the unscaled masses is the run's over √s.
    let unscaled = |key: &str| {
        summary
            .get(key)
            .and_then(|v| v.as_f64())
            .map(|value| value / scaling.sqrt())
    };
    let mut reader = csv::Reader::from_path(dir.join("history.csv"))
        .map_err(|e| format!("{shown}/history.csv: {e}"))?;
    let headers = reader
        .headers()
        .map_err(|e| format!("{shown}/history.csv: {e}"))?
        .clone();
    let column = |name: &str| {
        headers
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| format!("{shown}/history.csv has no column {name}"))
    };
    let (time_col, dte_col) = (column("time_s")?, column("dte_rad")?);
    // The back flanks' contact forces of every pair (absent from older or synthetic runs).
    let back_cols: Vec<usize> = headers
        .iter()
        .enumerate()
        .filter(|(_, h)| h.starts_with("force_back_"))
        .map(|(i, _)| i)
        .collect();
    let (mut time, mut dte, mut back) = (Vec::new(), Vec::new(), Vec::new());
    for record in reader.records() {
        let record = record.map_err(|e| format!("{shown}/history.csv: {e}"))?;
        let value = |i: usize| {
            record[i]
                .parse::<f64>()
                .map_err(|e| format!("{shown}/history.csv: {e}"))
        };
        time.push(value(time_col)?);
        dte.push(value(dte_col)?);
        if !back_cols.is_empty() {
            back.push(
                back_cols
                    .iter()
                    .map(|&i| value(i))
                    .sum::<Result<f64, String>>()?,
            );
        }
    }
    if time.len() < 16 {
        return Err(format!("{shown}/history.csv holds {} samples", time.len()));
    }
    // The last sample closes the run wherever it ends: the interval from the others.
    let dt = (time[time.len() - 2] - time[0]) / (time.len() - 2) as f64;
    Ok(FeDte {
        source: shown.to_string(),
        speed_rpm: speed * 60.0 / std::f64::consts::TAU,
        torque_nm: number(&["scene", "torque"])?,
        fine_element_mm: summary.get("fine_element_mm").and_then(|v| v.as_f64()),
        tooth_layout: summary_tooth_layout(&summary, dir)?,
        dt,
        dte,
        back_flank_force: back,
        ramp_end_s: number(&["scene", "ramp_time"])?,
        statistics_start_s: number(&["statistics_start_s"])?,
        wall_s: number(&["total_wall_s"])?,
        // β = 2ζ/ω_max grows with √ of a uniform mass scaling: the unscaled bodies' β. A
        // target step lowers ω_max by more, by how much the summary does not say: no β then.
        stiffness_damping_beta_s: unscaled("stiffness_damping_beta_s")
            .filter(|_| scaling <= 1.0 || !target_step),
        mesh_damping_n_m_s: unscaled("mesh_damping_n_m_s"),
    })
}

fn peaks_text(peaks: &[Peak]) -> String {
    peaks
        .iter()
        .take(5)
        .map(|p| format!("{:.0} ({})", p.frequency_hz, p.label))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Writes the comparison; returns the Markdown table printed on the console.
pub fn write(dir: OutputDir, case: &Case, summary: &CompareSummary) -> Result<String, ReportError> {
    dir.case(case)?;
    dir.json("summary.json", summary)?;
    let f = |x: f64| format!("{x:.1}");
    let mut rows = Vec::new();
    for fr in [&summary.driver_held, &summary.both_free] {
        let bc = match fr.hubs {
            crate::ltca::modal::Hubs::DriverHeld => "driver held",
            crate::ltca::modal::Hubs::BothFree => "both free",
        };
        rows.push(vec![
            bc.into(),
            "lumped sqrt(k/m), k LTCA secant".into(),
            f(fr.lumped_ltca_secant_hz),
        ]);
        rows.push(vec![
            bc.into(),
            "lumped sqrt(k/m), k LTCA tangent".into(),
            f(fr.lumped_ltca_tangent_hz),
        ]);
        rows.push(vec![
            bc.into(),
            "lumped mesh mode, elastic bodies, k LTCA secant".into(),
            f(fr.lumped_ltca_elastic_hz),
        ]);
        rows.push(vec![
            bc.into(),
            "lumped mesh mode, elastic bodies, k LTCA tangent".into(),
            f(fr.lumped_ltca_tangent_elastic_hz),
        ]);
        rows.push(vec![
            bc.into(),
            "lumped sqrt(k/m), k FE DTE, rigid gears".into(),
            f(fr.lumped_fe_hz),
        ]);
        rows.push(vec![
            bc.into(),
            "lumped mesh mode, elastic bodies, k FE DTE".into(),
            f(fr.lumped_fe_elastic_hz),
        ]);
        rows.push(vec![
            bc.into(),
            "the case's lumped model (as sweep and run), linearized at the design load".into(),
            f(fr.lumped_model_hz),
        ]);
        for (rpm, hz) in &fr.floquet_hz {
            rows.push(vec![
                bc.into(),
                format!("lumped Floquet (undamped), k FE DTE, elastic bodies, {rpm:.0} rpm"),
                f(*hz),
            ]);
        }
        rows.push(vec![
            bc.into(),
            "FE modal mesh mode (mean over positions)".into(),
            f(fr.fe_modal_mean_hz),
        ]);
    }
    dir.csv(
        "frequencies.csv",
        &["boundary", "method", "frequency_hz"],
        rows.clone(),
    )?;
    modal_csv(dir, &summary.modal)?;
    dir.csv(
        "harmonics.csv",
        &[
            "speed_rpm",
            "mesh_hz",
            "harmonic",
            "fe_rad",
            "lumped_rad",
            "lumped_over_fe_minus_1",
            "lumped_rigid_gears_rad",
            "rigid_over_fe_minus_1",
        ],
        summary.speeds.iter().flat_map(|s| {
            (0..s.fe_harmonics_rad.len()).map(move |n| {
                vec![
                    format!("{:.1}", s.speed_rpm),
                    format!("{:.2}", s.mesh_hz),
                    (n + 1).to_string(),
                    format!("{:.4e}", s.fe_harmonics_rad[n]),
                    format!("{:.4e}", s.lumped_harmonics_rad[n]),
                    format!("{:+.4}", s.harmonic_error_rel[n]),
                    format!("{:.4e}", s.lumped_rigid_harmonics_rad[n]),
                    format!("{:+.4}", s.rigid_harmonic_error_rel[n]),
                ]
            })
        }),
    )?;
    dir.csv(
        "peaks.csv",
        &[
            "speed_rpm",
            "window",
            "frequency_hz",
            "amplitude_rad",
            "label",
        ],
        summary.speeds.iter().flat_map(|s| {
            [("late", &s.fe_peaks), ("early", &s.fe_early_peaks)]
                .into_iter()
                .flat_map(move |(w, peaks)| {
                    peaks.iter().map(move |p| {
                        vec![
                            format!("{:.1}", s.speed_rpm),
                            w.into(),
                            format!("{:.1}", p.frequency_hz),
                            format!("{:.4e}", p.amplitude_rad),
                            p.label.clone(),
                        ]
                    })
                })
        }),
    )?;
    for s in &summary.speeds {
        let stem = format!("spectra_{:.0}rpm", s.speed_rpm);
        let limit = (4.5 * s.mesh_hz).max(1.3 * summary.f_natural_fe_modal_hz);
        let clip = |spectrum: &[(f64, f64)]| -> Vec<(f64, f64)> {
            spectrum
                .iter()
                .copied()
                .filter(|(f, _)| *f <= limit)
                .collect()
        };
        dir.csv(
            &format!("{stem}.csv"),
            &["frequency_hz", "fe_late_rad"],
            s.fe_spectrum
                .iter()
                .map(|(f, a)| vec![format!("{f:.3}"), format!("{a:.5e}")]),
        )?;
        // The lumped model's periodic response has lines at the mesh harmonics only: spikes.
        let width = 0.2 * s.resolution_hz;
        let lumped: Vec<(f64, f64)> = s
            .lumped_harmonics_rad
            .iter()
            .enumerate()
            .flat_map(|(n, a)| {
                let f = (n + 1) as f64 * s.mesh_hz;
                [(f - width, 0.0), (f, *a), (f + width, 0.0)]
            })
            .collect();
        let labels = s
            .fe_peaks
            .iter()
            .take(4)
            .map(|p| format!("{:.0} Hz {}", p.frequency_hz, p.label))
            .collect::<Vec<_>>()
            .join("; ");
        dir.chart(
            &stem,
            &LinePlot {
                y_range: None,
                markers: Vec::new(),
                title: format!(
                    "{}: DTE spectra at {:.0} rpm (f_m {:.0} Hz, f_n held {:.0} Hz): {labels}",
                    case.name(),
                    s.speed_rpm,
                    s.mesh_hz,
                    summary.f_natural_fe_modal_driver_held_hz
                ),
                x_label: "frequency [Hz]".into(),
                y_label: "amplitude [rad]".into(),
                series: vec![
                    ("explicit FE, late window".into(), clip(&s.fe_spectrum)),
                    (
                        "explicit FE, early window".into(),
                        clip(&s.fe_early_spectrum),
                    ),
                    (
                        "lumped, k from FE, elastic bodies (harmonics)".into(),
                        lumped,
                    ),
                ],
            },
        )?;
    }
    if let Some(p) = &summary.paper_stiffness {
        let clip = |spectrum: &[(f64, f64)]| -> Vec<(f64, f64)> {
            spectrum
                .iter()
                .copied()
                .filter(|(f, _)| *f <= 5.0 * p.mesh_hz)
                .collect()
        };
        dir.csv(
            "paper_stiffness_spectrum.csv",
            &["frequency_hz", "late_rad"],
            p.late_spectrum
                .iter()
                .map(|(f, a)| vec![format!("{f:.3}"), format!("{a:.5e}")]),
        )?;
        dir.chart(
            "paper_stiffness_spectra",
            &LinePlot {
                y_range: None,
            markers: Vec::new(),
                title: format!(
                    "PAPER-STIFFNESS STUDY (k = {:.4e} N/m, lumped, speed drive) at {:.0} rpm: f_n held {:.0} Hz, free {:.0} Hz",
                    p.mean_stiffness_n_per_m, p.speed_rpm, p.f_driver_held_hz, p.f_both_free_hz
                ),
                x_label: "frequency [Hz]".into(),
                y_label: "amplitude [rad]".into(),
                series: vec![
                    ("lumped, late window".into(), clip(&p.late_spectrum)),
                    ("lumped, early window".into(), clip(&p.early_spectrum)),
                ],
            },
        )?;
    }
    let mut table = String::from("| boundary | method | mesh mode [Hz] |\n|---|---|---|\n");
    for row in &rows {
        table += &format!("| {} | {} | {} |\n", row[0], row[1], row[2]);
    }
    table += "\n| speed [rpm] | f_m [Hz] | f_m/f_n | FE peaks (late) | FE peaks (early) | harmonics FE [rad] | lumped/FE - 1 (elastic bodies) | (rigid gears) |\n|---|---|---|---|---|---|---|---|\n";
    for s in &summary.speeds {
        table += &format!(
            "| {:.0} | {:.0} | {:.2} | {} | {} | {} | {} | {} |\n",
            s.speed_rpm,
            s.mesh_hz,
            s.mesh_over_mode,
            peaks_text(&s.fe_peaks),
            peaks_text(&s.fe_early_peaks),
            s.fe_harmonics_rad
                .iter()
                .map(|a| format!("{a:.2e}"))
                .collect::<Vec<_>>()
                .join(" "),
            s.harmonic_error_rel
                .iter()
                .map(|e| format!("{:+.0} %", 100.0 * e))
                .collect::<Vec<_>>()
                .join(" "),
            s.rigid_harmonic_error_rel
                .iter()
                .map(|e| format!("{:+.0} %", 100.0 * e))
                .collect::<Vec<_>>()
                .join(" "),
        );
    }
    if let Some(p) = &summary.paper_stiffness {
        table += &format!(
            "\n{}\n\n| rigid gears, k = {:.4e} N/m | both free {:.0} Hz | driver held {:.0} Hz | {:.0} rpm peaks (late): {} | (early): {} |\n",
            p.note,
            p.mean_stiffness_n_per_m,
            p.f_both_free_hz,
            p.f_driver_held_hz,
            p.speed_rpm,
            peaks_text(&p.late_peaks),
            peaks_text(&p.early_peaks)
        );
    }
    table += &format!(
        "\nThe mesh dashpot as sized on the LTCA of the case's explicit mesh ({:.4e} N s/m on the line of action, on the driven hub's DTE rate; each run's twin carries the run's own) damps the mesh mode (driver held) by ζ = {:.4} in the lumped twin and {:.4} in the FE modal analysis (first order, c φ²/2ω of each one's mode shape)\n",
        summary.mesh_damping_n_s_per_m,
        summary.mesh_mode_damping_ratio_fe_twin,
        summary.mesh_mode_damping_ratio_fe_modal,
    );
    if let Some(sweep) = &summary.fe_sweep {
        table += &write_fe_sweep(dir, case, sweep)?;
    }
    dir.bytes("table.md", table.as_bytes())?;
    Ok(table)
}

/// The FE speed sweep: fe_sweep.csv (per FE speed: the FE and each lumped model there),
/// fe_sweep_lumped.csv (each model's dense curves: from rest, continued up, continued down),
/// fe_sweep.{png,svg} (the models' curves with the FE's points as markers) and its Markdown
/// table.
fn write_fe_sweep(
    dir: OutputDir,
    case: &Case,
    sweep: &crate::study::fe_sweep::FeSweep,
) -> Result<String, ReportError> {
    let um = |rad: f64| rad * 1e6;
    let mut header: Vec<String> = [
        "driver_rpm",
        "fe_mesh_amplitude_urad",
        "fe_dte_rms_urad",
        "fe_dte_peak_to_peak_urad",
        "fe_growth",
        "fe_settling_drift",
        "fe_settled",
        "fe_back_flank_share",
        "fe_back_flank_force_max_n",
        "fe_on_body_crossing",
    ]
    .map(String::from)
    .to_vec();
    for m in &sweep.models {
        for column in [
            "mesh_amplitude_urad",
            "dte_rms_urad",
            "dte_rms_rel_err",
            "dte_rms_rel_err_at_fe_resonance",
            "dte_rms_speed_sensitivity",
            "diverged",
        ] {
            header.push(format!("{}_{column}", m.key));
        }
    }
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    dir.csv(
        "fe_sweep.csv",
        &header,
        sweep.fe.iter().enumerate().map(|(i, s)| {
            let mut row = vec![
                format!("{:.2}", s.speed_rpm),
                format!("{:.5}", um(s.mesh_amplitude_rad)),
                format!("{:.5}", um(s.dte_rms_rad)),
                format!("{:.5}", um(s.dte_peak_to_peak_rad)),
                format!("{:.4}", s.growth),
                format!("{:.4}", s.settling_drift),
                s.settled.to_string(),
                format!("{:.4}", s.back_flank_share),
                format!("{:.1}", s.back_flank_force_max_n),
                s.on_body_crossing.to_string(),
            ];
            for m in &sweep.models {
                let l = &m.at_fe_speeds[i];
                row.extend([
                    format!("{:.5}", um(l.mesh_amplitude_rad)),
                    format!("{:.5}", um(l.dte_rms_rad)),
                    format!("{:.4}", m.dte_rms_rel_err[i]),
                    format!("{:.4}", m.dte_rms_rel_err_at_fe_resonance[i]),
                    format!("{:.3}", m.dte_rms_speed_sensitivity[i]),
                    l.diverged.to_string(),
                ]);
            }
            row
        }),
    )?;
    let rows: Vec<Vec<String>> = sweep
        .models
        .iter()
        .flat_map(|m| {
            let rest = m
                .dense
                .iter()
                .map(|p| ("rest", p.speed_rpm, p.mesh_amplitude_rad, p.dte_rms_rad));
            let up = m.curve_up.iter().map(|c| ("up", c.0, c.1, c.2));
            let down = m.curve_down.iter().map(|c| ("down", c.0, c.1, c.2));
            rest.chain(up)
                .chain(down)
                .map(|(curve, rpm, a, rms)| {
                    vec![
                        m.key.clone(),
                        curve.to_string(),
                        format!("{rpm:.2}"),
                        format!("{:.5}", um(a)),
                        format!("{:.5}", um(rms)),
                    ]
                })
                .collect::<Vec<_>>()
        })
        .collect();
    dir.csv(
        "fe_sweep_lumped.csv",
        &[
            "model",
            "curve",
            "driver_rpm",
            "mesh_amplitude_urad",
            "dte_rms_urad",
        ],
        rows,
    )?;
    let mut series = Vec::new();
    for (i, m) in sweep.models.iter().enumerate() {
        let settled = |pick: fn(&crate::study::fe_sweep::LumpedSpeed) -> f64| {
            // Diverged speeds as gaps in the line.
            m.dense
                .iter()
                .map(|p| match p.diverged {
                    true => (p.speed_rpm, f64::NAN),
                    false => (p.speed_rpm, um(pick(p))),
                })
                .collect::<Vec<_>>()
        };
        series.push((
            format!("{}, 1st mesh harmonic", m.label),
            settled(|p| p.mesh_amplitude_rad),
        ));
        if i == 0 {
            series.push((format!("{}, rms", m.label), settled(|p| p.dte_rms_rad)));
        }
    }
    let points =
        |fe: &[crate::study::fe_sweep::FeSpeed],
         pick: fn(&crate::study::fe_sweep::FeSpeed) -> f64|
         -> Vec<(f64, f64)> { fe.iter().map(|s| (s.speed_rpm, um(pick(s)))).collect() };
    let mesh = |size: Option<f64>| size.map_or(String::new(), |mm| format!(" {mm:.2} mm"));
    let mut markers = vec![
        (
            format!("FE{}, 1st mesh harmonic", mesh(sweep.fine_element_mm)),
            points(&sweep.fe, |s| s.mesh_amplitude_rad),
        ),
        (
            format!("FE{}, rms", mesh(sweep.fine_element_mm)),
            points(&sweep.fe, |s| s.dte_rms_rad),
        ),
    ];
    // The other meshes' first harmonics: how far the FE itself moves under refinement.
    for level in &sweep.mesh_levels {
        if !crate::study::fe_sweep::same_size(level.fine_element_mm, sweep.fine_element_mm) {
            markers.push((
                format!("FE{}, 1st mesh harmonic", mesh(level.fine_element_mm)),
                points(&level.fe, |s| s.mesh_amplitude_rad),
            ));
        }
    }
    if let Some(x) = &sweep.extrapolated {
        markers.push((
            "FE extrapolated to zero flank size per speed, 1st mesh harmonic".into(),
            x.speeds
                .iter()
                .map(|s| (s.speed_rpm, um(s.mesh_amplitude.value)))
                .collect(),
        ));
        if x.resonance_rpm.value.is_finite() && x.peak_dte_mesh_amplitude.value.is_finite() {
            markers.push((
                "FE's fitted peak extrapolated to zero flank size".into(),
                vec![(x.resonance_rpm.value, um(x.peak_dte_mesh_amplitude.value))],
            ));
        }
    }
    // A model that diverges (the FE-stiffness twin in its unstable band) would set the scale
    // and flatten every other curve: the FE's points and the case's model set it, a model
    // beyond runs off the top (its numbers stay in the CSVs).
    let top = markers
        .iter()
        .flat_map(|(_, points)| points)
        .chain(series.iter().take(2).flat_map(|(_, points)| points))
        .map(|p| p.1)
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let y_range = (top > 0.0).then_some((0.0, 1.25 * top));
    dir.chart(
        "fe_sweep",
        &LinePlot {
            title: format!(
                "{}: explicit FE through the resonance (markers) against the lumped models (lines, from rest)",
                case.name()
            ),
            x_label: "driver speed [rpm]".into(),
            y_label: "DTE of the driven gear [urad]".into(),
            series,
            y_range,
            markers,
        },
    )?;
    if sweep.mesh_levels.len() > 1 {
        write_fe_sweep_levels(dir, sweep)?;
    }
    let mut text = format!(
        "\nFE speed sweep ({} speeds{}, scene {}): FE resonance {:.0} rpm (fitted ζ {:.3}), peak 1st mesh harmonic {:.3} urad{}. {}. Body modes: {}\n",
        sweep.fe.len(),
        sweep
            .fine_element_mm
            .map_or(String::new(), |mm| format!(", {mm:.2} mm flanks")),
        crate::study::compare::SPEED_SCENE,
        sweep.resonance_rpm_fe,
        sweep.fitted_damping_ratio_fe,
        um(sweep.peak_dte_mesh_amplitude_fe_rad),
        peak_pinning_text(sweep),
        sweep.settling_note,
        sweep.body_mode_note,
    );
    let unpinned = match sweep.peak_pinned {
        true => "",
        false => ", against an FE peak not pinned down",
    };
    // The case's model's own errors measure nothing where its fit does not describe it.
    let case_fit = match sweep.fit_describes_lumped {
        true => "",
        false => " (its one-DOF fit does not describe its response: not measured)",
    };
    if !sweep.fit_describes_fe {
        text += "* The one-DOF fit does not describe the FE's response (its largest sample lies more than a speed spacing from the fitted resonance or more than 5 % above the fitted peak): the response is bent by the flanks, the fitted resonance and peak describe neither branch, and the errors against them below are not measured; the FE's points and the models' curves (fe_sweep.csv, fe_sweep_lumped.csv) are the comparison.\n";
    }
    for m in &sweep.models {
        text += &format!(
            "\n* {} (dashpot {:.0} N·s/m, acting on its mesh mode as the FE's on the FE modal's: ζ {:.4}): resonance {:.0} rpm ({:+.2} %), peak 1st mesh harmonic {:.3} urad ({:+.1} %{unpinned}), DTE rms largest difference {:.1} % where it settled ({:.1} % at the FE's speeds taken relative to each one's resonance, {}; the rms's log-slope over speed there up to {:.1}, so a resonance 1 % off alone moves it by about {:.0} %){}{}",
            m.label,
            m.mesh_damping_n_s_per_m,
            m.mesh_mode_damping_ratio,
            m.resonance_rpm,
            100.0 * m.resonance_rpm_rel_err,
            um(m.peak_dte_mesh_amplitude_rad),
            100.0 * m.peak_dte_mesh_amplitude_rel_err,
            100.0 * m.dte_rms_max_rel_err,
            100.0 * m.dte_rms_max_rel_err_at_fe_resonance,
            match m.resonance_rpm_sampled_like_fe.is_finite() {
                true => format!(
                    "its resonance read as the FE's {:.0} rpm ({:+.2} %; fixed point to {:.0e})",
                    m.resonance_rpm_sampled_like_fe,
                    100.0 * (m.resonance_rpm_sampled_like_fe / sweep.resonance_rpm_fe - 1.0),
                    m.held_residual
                ),
                false => "its resonance not read as the FE's (it diverged beside the FE speeds: held at its dense fit's ratio)".to_string(),
            },
            m.dte_rms_speed_sensitivity_max,
            m.dte_rms_speed_sensitivity_max,
            match m.diverged_at_fe_rpm.is_empty() {
                true => String::new(),
                false => format!("; diverged at the FE speeds {:?} rpm", m.diverged_at_fe_rpm),
            } + &match m.diverged_at_probe_rpm.is_empty() {
                true => String::new(),
                false => format!(
                    "; diverged beside the FE speeds at {} rpm (left out of the slope and the rms at the FE's resonance)",
                    m.diverged_at_probe_rpm
                        .iter()
                        .map(|r| format!("{r:.0}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            },
            m.unstable_band_rpm.map_or(String::new(), |(lo, hi)| format!(
                "; unstable (the sweep diverged) at {lo:.0}–{hi:.0} rpm"
            )) + &match m.fit_describes_response {
                true => String::new(),
                false => format!(
                    "; its one-DOF fit does NOT describe its response, which peaks at {:.3} urad at {:.0} rpm ({}): its resonance and peak errors above are not measured",
                    um(m.largest_mesh_amplitude_rad),
                    m.largest_response_rpm,
                    match m
                        .unstable_band_rpm
                        .is_some_and(|(lo, hi)| (lo..=hi).contains(&m.resonance_rpm))
                    {
                        true => "the fit puts its peak in its unstable band",
                        false => "bent by the flanks",
                    },
                ),
            },
        );
    }
    if sweep.mesh_levels.len() > 1 {
        let common = match sweep.common_rpm.is_empty() {
            true => "each fitted over its own speeds (no coarser mesh shares the headline's speeds; a mesh with fewer than three speeds is not fitted)".to_string(),
            false => format!(
                "the finest fitted one and the next coarser both ran {} speeds ({} rpm), fitted over those in parentheses",
                sweep.common_rpm.len(),
                sweep
                    .common_rpm
                    .iter()
                    .map(|r| format!("{r:.0}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        text += &format!(
            "\n* The FE on {} meshes (fe_sweep_levels.csv); {common}:",
            sweep.mesh_levels.len(),
        );
        for (i, level) in sweep.mesh_levels.iter().enumerate() {
            let name = level
                .fine_element_mm
                .map_or("mesh not recorded".to_string(), |mm| {
                    format!("{mm:.2} mm flanks")
                });
            let headline = match i == sweep.headline_level {
                true => " (the headline)",
                false => "",
            };
            // Each run sizes its dashpot on its own mesh's LTCA k̄; the model takes the level's.
            let headline = match level.mesh_damping_n_s_per_m.is_finite() {
                true => format!(
                    "{headline} (FE dashpot {:.0} N·s/m; the case's model {:.0} against it, the same acting on its mesh mode)",
                    level.mesh_damping_n_s_per_m, level.case_model_mesh_damping_n_s_per_m
                ),
                false => format!(
                    "{headline} (its runs recorded no dashpot: the case's model carries {:.0} N·s/m, sized on the LTCA of the case's explicit mesh)",
                    level.case_model_mesh_damping_n_s_per_m
                ),
            };
            if !level.resonance_rpm.is_finite() {
                text += &format!(
                    "\n  * {name}{headline}: {} speeds ({} rpm), no resonance fitted from them (it takes three speeds and a peak among them); the case's model's DTE rms against it differs by {:.1} % at most",
                    level.fe.len(),
                    level
                        .fe
                        .iter()
                        .map(|s| format!("{:.0}", s.speed_rpm))
                        .collect::<Vec<_>>()
                        .join(", "),
                    100.0 * level.case_model_dte_rms_max_rel_err,
                );
                continue;
            }
            text += &format!(
                "\n  * {name}{headline}: {} speeds, resonance {:.0} rpm, peak {:.3} urad{}; the case's model against it: resonance {:+.2} %, peak {:+.1} %{}{case_fit}, DTE rms largest difference {:.1} %",
                level.fe.len(),
                level.resonance_rpm,
                um(level.peak_dte_mesh_amplitude_rad),
                match level.common_resonance_rpm.is_finite() {
                    true => format!(
                        " ({:.0} rpm, {:.3} urad)",
                        level.common_resonance_rpm,
                        um(level.common_peak_dte_mesh_amplitude_rad)
                    ),
                    false => String::new(),
                },
                100.0 * level.case_model_resonance_rpm_rel_err,
                100.0 * level.case_model_peak_rel_err,
                match i == sweep.headline_level {
                    true => unpinned,
                    false => "",
                },
                100.0 * level.case_model_dte_rms_max_rel_err,
            );
        }
        if let Some(shift) = crate::study::fe_sweep::refinement_shift_rpm(sweep) {
            text += &format!(
                "\n  * the FE's resonance moved {shift:+.0} rpm ({:+.2} %) from the next coarser mesh to the finest: the finest mesh's own discretization error is of that order",
                100.0 * shift / sweep.resonance_rpm_fe
            );
        }
    }
    if let Some(x) = &sweep.extrapolated {
        write_fe_sweep_extrapolated(dir, x)?;
        let [h1, h2, h3] = x.fine_element_mm;
        let order = |o: Option<f64>| {
            o.map_or(
                "not extrapolated: the finest mesh's value".to_string(),
                |p| format!("order {p:.2}"),
            )
        };
        let [r1, r2, r3] = x.mesh_resonance_rpm;
        let [p1, p2, p3] = x.mesh_peak_dte_mesh_amplitude_rad.map(um);
        let fits = match x.fit_speeds {
            0..=2 => format!(
                "No three meshes share three speeds, so no mesh's resonance is fitted to extrapolate (the three finest, {h1:.2} / {h2:.2} / {h3:.2} mm, share {})",
                x.fit_speeds
            ),
            n => format!(
                "On {h1:.2} / {h2:.2} / {h3:.2} mm, over the {n} speeds all three ran, each mesh's fitted resonance {r1:.0} / {r2:.0} / {r3:.0} rpm and peak {p1:.3} / {p2:.3} / {p3:.3} urad{}, extrapolated: resonance {:.0} ± {:.0} rpm ({}), peak {:.3} ± {:.3} urad ({}); the case's model against it: resonance {:+.2} %, peak {:+.1} %{case_fit}",
                match x.fits_interpolate {
                    true => " (three speeds: each fit interpolates them)",
                    false => "",
                },
                x.resonance_rpm.value,
                x.resonance_rpm.uncertainty,
                order(x.resonance_rpm.order),
                um(x.peak_dte_mesh_amplitude.value),
                um(x.peak_dte_mesh_amplitude.uncertainty),
                order(x.peak_dte_mesh_amplitude.order),
                100.0 * x.case_model_resonance_rpm_rel_err,
                100.0 * x.case_model_peak_rel_err,
            ),
        };
        // Each run sizes its dashpot on its own mesh's LTCA k̄: the meshes' values then differ
        // in their damping too.
        let [c1, c2, c3] = x.mesh_damping_n_s_per_m;
        let spread = c1.max(c2).max(c3) / c1.min(c2).min(c3) - 1.0;
        let fits = match spread > 1e-3 {
            true => format!(
                "{fits} (the three meshes' runs carry dashpots of {c1:.0} / {c2:.0} / {c3:.0} N·s/m, each sized on its own mesh's LTCA k̄, so the extrapolation takes the dashpot's change with the mesh beside the mesh's; the case's model against it carries them extrapolated alike, {:.0} N·s/m acting on its mesh mode)",
                x.case_model_mesh_damping_n_s_per_m
            ),
            false => fits,
        };
        text += &format!(
            "\n* The FE extrapolated to zero flank size (fe_sweep_extrapolated.csv). {fits}. Speed by speed, each from the three finest meshes that ran it: {} of the {} speeds converged monotonically (the others carry the finest mesh's value), the case's model's DTE rms at most {:.1} % from it{}",
            x.speeds_extrapolated,
            x.speeds.len(),
            100.0 * x.case_model_dte_rms_max_rel_err,
            match x.pointwise_resonance_rpm.is_finite() {
                true => format!(
                    "; fitted over them: resonance {:.0} rpm, peak {:.3} urad",
                    x.pointwise_resonance_rpm,
                    um(x.pointwise_peak_dte_mesh_amplitude_rad)
                ),
                false => String::new(),
            },
        );
        for s in &x.speeds {
            text += &format!(
                "\n  * {:.0} rpm on {:.2} / {:.2} / {:.2} mm: 1st harmonic {:.1} ± {:.1} urad ({}), rms {:.1} ± {:.1} urad ({}); the case's model's rms {:+.1} %",
                s.speed_rpm,
                s.fine_element_mm[0],
                s.fine_element_mm[1],
                s.fine_element_mm[2],
                um(s.mesh_amplitude.value),
                um(s.mesh_amplitude.uncertainty),
                order(s.mesh_amplitude.order),
                um(s.dte_rms.value),
                um(s.dte_rms.uncertainty),
                order(s.dte_rms.order),
                100.0 * s.case_model_dte_rms_rel_err,
            );
        }
    }
    for b in &sweep.unstable_band_runs {
        text += &format!(
            "\n* FE at {:.0} rpm ({} the {} band {:.0}–{:.0} rpm): {}",
            b.speed_rpm,
            if b.inside { "inside" } else { "nearest to" },
            b.model,
            b.band_rpm.0,
            b.band_rpm.1,
            b.outcome
        );
    }
    Ok(text + "\n")
}

/// fe_sweep_extrapolated.csv: the FE extrapolated to zero flank size at each speed three meshes
/// ran, from the three finest that ran it (their sizes and values), and the case's model's rms
/// against it.
fn write_fe_sweep_extrapolated(
    dir: OutputDir,
    x: &crate::study::fe_sweep::ExtrapolatedFe,
) -> Result<(), ReportError> {
    let um = |rad: f64| format!("{:.5}", rad * 1e6);
    let order = |o: Option<f64>| o.map_or(String::new(), |p| format!("{p:.3}"));
    // Each speed comes from the three finest meshes that ran it, which need not be another's.
    let mut header: Vec<String> = ["driver_rpm", "mesh_1_mm", "mesh_2_mm", "mesh_3_mm"]
        .map(String::from)
        .to_vec();
    for what in ["mesh_amplitude", "dte_rms"] {
        for level in 1..=3 {
            header.push(format!("fe_{what}_mesh_{level}_urad"));
        }
        header.extend([
            format!("fe_{what}_extrapolated_urad"),
            format!("fe_{what}_uncertainty_urad"),
            format!("fe_{what}_order"),
        ]);
    }
    header.push("case_model_dte_rms_rel_err".into());
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    dir.csv(
        "fe_sweep_extrapolated.csv",
        &header,
        x.speeds.iter().map(|s| {
            let mut row = vec![format!("{:.2}", s.speed_rpm)];
            row.extend(s.fine_element_mm.map(|h| format!("{h:.3}")));
            for (values, e) in [
                (s.mesh_amplitudes_rad, s.mesh_amplitude),
                (s.dte_rms_values_rad, s.dte_rms),
            ] {
                row.extend(values.map(um));
                row.extend([um(e.value), um(e.uncertainty), order(e.order)]);
            }
            row.push(format!("{:.4}", s.case_model_dte_rms_rel_err));
            row
        }),
    )?;
    Ok(())
}

/// How well the FE speeds pin the fitted peak down, and what to run where they do not.
fn peak_pinning_text(sweep: &crate::study::fe_sweep::FeSweep) -> String {
    let error = sweep.peak_dte_mesh_amplitude_fe_uncertainty_rad;
    let measured = match error.is_finite() {
        true => format!(
            " (jackknife ± {:.3} urad, {:.1} %)",
            error * 1e6,
            100.0 * error / sweep.peak_dte_mesh_amplitude_fe_rad
        ),
        false => " (no jackknife: fewer than four fitted speeds)".to_string(),
    };
    let side = |rpm: f64, which: &str| match rpm.is_finite() {
        true => format!("{rpm:.0} rpm {which}"),
        false => format!("none {which}"),
    };
    // Speeds inside the fitted half-power band (first harmonic at least peak/√2).
    let peak = sweep.peak_dte_mesh_amplitude_fe_rad;
    let in_band: Vec<f64> = sweep
        .fe
        .iter()
        .filter(|s| s.mesh_amplitude_rad >= peak / std::f64::consts::SQRT_2)
        .map(|s| s.speed_rpm)
        .collect();
    let (nr, zeta) = (sweep.resonance_rpm_fe, sweep.fitted_damping_ratio_fe);
    match (sweep.peak_pinned, in_band.as_slice()) {
        (true, _) => measured,
        (false, [one]) => format!(
            "{measured}; NOT pinned down: one speed lies in its half-power band ({one:.0} rpm), so the fit's peak rests on it alone (without it the skirts' fit is the one-DOF shape's guess); a second speed in the band pins it, e.g. {:.0} or {:.0} rpm (the band about ± ζ n_r)",
            nr * (1.0 - zeta),
            nr * (1.0 + zeta),
        ),
        (false, _) => {
            let (below, above) = sweep.peak_bracket_rpm;
            format!(
                "{measured}; NOT pinned down by these speeds (the nearest FE speed {} and {} the fitted resonance, none in its half-power band or the leave-one-out fits apart): the peak's height and the models' peak errors are not measured; run the FE near {:.0} rpm (geardyn fe --speed-rpm, then compare --fe-run)",
                side(below, "below"),
                side(above, "above"),
                sweep.resonance_rpm_fe
            )
        }
    }
}

/// fe_sweep_levels.csv: every FE speed of every explicit mesh the sweep's runs came on.
fn write_fe_sweep_levels(
    dir: OutputDir,
    sweep: &crate::study::fe_sweep::FeSweep,
) -> Result<(), ReportError> {
    let um = |rad: f64| rad * 1e6;
    dir.csv(
        "fe_sweep_levels.csv",
        &[
            "fine_element_mm",
            "driver_rpm",
            "fe_mesh_amplitude_urad",
            "fe_dte_rms_urad",
            "fe_growth",
            "fe_settling_drift",
            "fe_back_flank_share",
            "fe_mesh_damping_n_s_per_m",
        ],
        sweep.mesh_levels.iter().flat_map(|level| {
            level.fe.iter().map(move |s| {
                vec![
                    level
                        .fine_element_mm
                        .map_or(String::new(), |mm| format!("{mm:.3}")),
                    format!("{:.2}", s.speed_rpm),
                    format!("{:.5}", um(s.mesh_amplitude_rad)),
                    format!("{:.5}", um(s.dte_rms_rad)),
                    format!("{:.4}", s.growth),
                    format!("{:.4}", s.settling_drift),
                    format!("{:.4}", s.back_flank_share),
                    s.mesh_damping_n_s_per_m
                        .map_or(String::new(), |c| format!("{c:.2}")),
                ]
            })
        }),
    )?;
    Ok(())
}

/// Reads an explicit FE stiffness run (`geardyn fe --scene stiffness`): k(θ) from its
/// stiffness.csv, its mesh level, mass scaling and wall time from summary.json.
pub fn read_fe_stiffness_run(dir: &Path, period: f64) -> Result<FeStiffnessRun, String> {
    let summary = fe_summary(dir)?;
    let number = |path: &[&str]| summary_number(&summary, dir, path);
    Ok(FeStiffnessRun {
        source: dir.display().to_string(),
        tooth_layout: summary_tooth_layout(&summary, dir)?,
        fine_mm: number(&["fine_element_mm"])?,
        mass_scaling_factor: number(&["mass_scaling", "factor"]).unwrap_or(1.0),
        stiffness: super::stiffness_csv::read_stiffness_csv(&dir.join("stiffness.csv"), period)?,
        wall_s: number(&["total_wall_s"])?,
    })
}

/// Writes the accuracy-versus-cost chart: accuracy_cost.csv, .md and the chart.
pub fn write_accuracy_cost(dir: OutputDir, chart: &AccuracyCost) -> Result<String, ReportError> {
    dir.json("accuracy_cost.json", chart)?;
    let header = [
        "method",
        "family",
        "wall_s",
        "mean_stiffness_n_per_m",
        "static_te_pp_rad",
        "resonance_rpm",
        "dte_mesh_amplitude_rad",
        "mean_stiffness_error",
        "static_te_pp_error",
        "resonance_rpm_error",
        "dte_amplitude_error",
    ];
    let rows: Vec<Vec<String>> = chart
        .points
        .iter()
        .map(|p| {
            vec![
                p.method.clone(),
                p.family.into(),
                format!("{:.4}", p.wall_s),
                format!("{:.5e}", p.mean_stiffness_n_per_m),
                format!("{:.5e}", p.static_te_peak_to_peak_rad),
                format!("{:.1}", p.resonance_rpm),
                format!("{:.5e}", p.dte_mesh_amplitude_rad),
                format!("{:.5}", p.mean_stiffness_error),
                format!("{:.5}", p.static_te_error),
                format!("{:.5}", p.resonance_error),
                format!("{:.5}", p.dte_amplitude_error),
            ]
        })
        .collect();
    dir.csv("accuracy_cost.csv", &header, rows)?;
    type Pick = fn(&crate::study::accuracy::MethodPoint) -> f64;
    let questions: [(&str, Pick); 4] = [
        ("mean stiffness", |p| p.mean_stiffness_error),
        ("static TE peak-to-peak", |p| p.static_te_error),
        ("first resonance speed", |p| p.resonance_error),
        ("DTE at f_mesh", |p| p.dte_amplitude_error),
    ];
    let short = |m: &str| {
        m.replace("explicit FE ", "FE ")
            .replace("potential energy", "PE")
            .replace("ISO 6336-1 B", "ISO")
    };
    let r = &chart.references;
    let references = [
        &r.mean_stiffness,
        &r.static_te_peak_to_peak,
        &r.resonance_rpm,
        &r.dte_mesh_amplitude,
    ];
    dir.chart(
        "accuracy_cost",
        &LogScatter {
            title: format!(
                "{}: error against the best estimate per question (dashed: its uncertainty) vs wall time",
                chart.case
            ),
            x_label: "wall time [s] (k(theta) + lumped solve)".into(),
            y_label: "|error| (fraction)".into(),
            series: questions
                .iter()
                .map(|(name, pick)| {
                    (
                        name.to_string(),
                        chart
                            .points
                            .iter()
                            .map(|p| (p.wall_s, pick(p), short(&p.method)))
                            .collect(),
                    )
                })
                .collect(),
            floors: references
                .iter()
                .map(|r| Some(r.relative_uncertainty()))
                .collect(),
        },
    )?;
    let mut table =
        String::from("| question | reference | uncertainty | source |\n|---|---|---|---|\n");
    for ((name, _), r) in questions.iter().zip(references) {
        table += &format!(
            "| {name} | {:.5e} | {:.2e} ({:.2} %) | {} |\n",
            r.value,
            r.uncertainty,
            100.0 * r.relative_uncertainty(),
            r.source
        );
    }
    table += "\n| method | wall [s] | k mean | static TE p-p | resonance rpm | DTE at f_mesh |\n|---|---|---|---|---|---|\n";
    for p in &chart.points {
        table += &format!(
            "| {} | {:.3} | {:.4e} ({:.1} %) | {:.3e} ({:.1} %) | {:.0} ({:.1} %) | {:.3e} ({:.1} %) |\n",
            p.method,
            p.wall_s,
            p.mean_stiffness_n_per_m,
            100.0 * p.mean_stiffness_error,
            p.static_te_peak_to_peak_rad,
            100.0 * p.static_te_error,
            p.resonance_rpm,
            100.0 * p.resonance_error,
            p.dte_mesh_amplitude_rad,
            100.0 * p.dte_amplitude_error
        );
    }
    if let Some(limit) = &chart.explicit_fe_mean_stiffness_limit {
        let sizes = format!("{:?} mm", limit.flank_mm);
        let off = 100.0 * limit.rel_to_ltca_limit;
        let both = 100.0 * limit.combined_uncertainty_rel;
        table += &match (limit.order, limit.agrees) {
            (Some(p), Some(agrees)) => format!(
                "\nThe explicit FE's own k̄ at zero flank size, extrapolated from {sizes} \
                 (observed order {p:.2}): {:.5e} ± {:.2e} N/m, {off:+.2} % from the LTCA's \
                 limit; the two uncertainties add to {both:.2} %: {}.\n",
                limit.value_n_per_m,
                limit.uncertainty_n_per_m,
                if agrees {
                    "the two limits meet"
                } else {
                    "they part by more than that"
                }
            ),
            (Some(p), None) => format!(
                "\nThe explicit FE's own k̄ at zero flank size, extrapolated from {sizes} \
                 (observed order {p:.2}): {:.5e} N/m, {off:+.2} % from the LTCA's limit; no \
                 verdict, as an uncertainty is not finite ({:.2e} N/m for the FE, {both:.2} % \
                 for the two).\n",
                limit.value_n_per_m, limit.uncertainty_n_per_m,
            ),
            (None, _) => format!(
                "\nThe explicit FE's k̄ over {sizes} is not in its asymptotic range (its steps \
                 change sign, or do not shrink at an order in [0.5, 6]), so it has no limit of \
                 its own to hold against the LTCA's: its finest, {:.5e} N/m, is {off:+.2} % \
                 from the LTCA's limit, the levels within {:.2} % of it.\n",
                limit.value_n_per_m,
                100.0 * limit.uncertainty_n_per_m / limit.value_n_per_m
            ),
        };
    }
    dir.bytes("accuracy_cost.md", table.as_bytes())?;
    Ok(table)
}

/// Writes `modal.csv`: every FE modal mode at every position, with its shares of the mesh's
/// compliance and of each gear's rigid rotation and translation, and its kind
/// ([`crate::ltca::modal::PairMode`]).
pub(crate) fn modal_csv(
    dir: OutputDir,
    modal: &[crate::ltca::modal::PairModes],
) -> Result<(), ReportError> {
    dir.csv(
        "modal.csv",
        &[
            "hubs",
            "driver_rotation_deg",
            "mode",
            "frequency_hz",
            "mesh_share",
            "driver_rotation_share",
            "driven_rotation_share",
            "driver_lateral_share",
            "driven_lateral_share",
            "kind",
        ],
        modal.iter().flat_map(|p| {
            p.modes.iter().enumerate().map(move |(i, m)| {
                vec![
                    format!("{:?}", p.hubs),
                    format!("{:.4}", p.driver_rotation.to_degrees()),
                    i.to_string(),
                    format!("{:.2}", m.frequency_hz),
                    format!("{:.3e}", m.mesh_share),
                    format!("{:.3e}", m.rotation_share[0]),
                    format!("{:.3e}", m.rotation_share[1]),
                    format!("{:.3e}", m.lateral_share[0]),
                    format!("{:.3e}", m.lateral_share[1]),
                    m.kind.into(),
                ]
            })
        }),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::ToothLayout;

    /// A summary names its layout; one without the key is from before it existed, when every
    /// explicit mesh was graded; a name that is no layout is an error naming the file.
    #[test]
    fn a_summary_without_a_tooth_layout_is_graded() {
        let dir = Path::new("run");
        let layout = |text: &str| summary_tooth_layout(&serde_json::from_str(text).unwrap(), dir);
        assert_eq!(layout("{}"), Ok(ToothLayout::Graded));
        assert_eq!(
            layout(r#"{"tooth_layout": "graded"}"#),
            Ok(ToothLayout::Graded)
        );
        assert_eq!(
            layout(r#"{"tooth_layout": "stable-step"}"#),
            Ok(ToothLayout::StableStep)
        );
        let bad = layout(r#"{"tooth_layout": "even"}"#).unwrap_err();
        assert!(bad.contains("run/summary.json: tooth_layout"), "{bad}");
    }

    /// A stiffness file in an FE run's folder has that run's layout; one without a
    /// summary.json beside it has none to check.
    #[test]
    fn a_stiffness_file_has_its_runs_layout() {
        let dir = std::env::temp_dir().join(format!("geardyn-layout-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("stiffness.csv");
        std::fs::write(&file, "angle_rad,stiffness_n_per_m\n").unwrap();
        assert_eq!(stiffness_file_layout(&file), Ok(None));
        std::fs::write(dir.join("summary.json"), r#"{"tooth_layout": "graded"}"#).unwrap();
        assert_eq!(stiffness_file_layout(&file), Ok(Some(ToothLayout::Graded)));
        std::fs::write(dir.join("summary.json"), "{}").unwrap();
        assert_eq!(stiffness_file_layout(&file), Ok(Some(ToothLayout::Graded)));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
