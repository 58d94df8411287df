//! Outputs of an explicit FE run: time histories (CSV), the DTE spectrum, the stiffness from the
//! DTE in the file format the lumped model reads, plots, and the summary's numbers.

use std::path::Path;

use crate::case::Case;
use crate::explicit::scene::{History, PreparedScene, RunCheckpoint, Scene, TimeStep};
use crate::geometry::GearPair;
use crate::report::plot::{save_chart, LinePlot, PlotError};
use crate::report::{stiffness_csv, OutputDir, ReportError};
use crate::study::fe::{Derived, FeStudy};
use crate::study::validate::MassScalingStudy;

/// Writes history.csv: one row per recorded sample.
pub fn write_history(
    path: &Path,
    history: &History,
    derived: &Derived,
    pair_names: &[String],
) -> std::io::Result<()> {
    let mut header: Vec<String> = [
        "time_s",
        "driver_rotation_rad",
        "dte_rad",
        "dte_denoised_rad",
        "driven_speed_rad_per_s",
        "theoretical_speed_rad_per_s",
        "contact_force_n",
        "force_circumferential_n",
        "force_radial_n",
        "mesh_force_n",
        "contact_force_db5_d1_n",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    header.extend(pair_names.iter().map(|n| format!("force_{n}_n")));
    header.extend(
        [
            "kinetic_j",
            "strain_j",
            "contact_j",
            "damping_j",
            "external_work_j",
            "energy_balance_j",
            "transmitted_work_j",
            "active_contact_points",
            "max_penetration_um",
        ]
        .iter()
        .map(|s| s.to_string()),
    );
    let header_refs: Vec<&str> = header.iter().map(|s| s.as_str()).collect();
    let rows = (0..history.time.len()).map(|i| {
        let e = history.energy[i];
        let mut row = vec![
            format!("{:.9e}", history.time[i]),
            format!("{:.9e}", history.driver_rotation[i]),
            format!("{:.6e}", history.dte[i]),
            format!("{:.6e}", derived.dte_denoised[i]),
            format!("{:.6e}", history.driven_speed[i]),
            format!("{:.6e}", history.theoretical_speed[i]),
            format!("{:.4}", history.force_total[i]),
            format!("{:.4}", history.force_circumferential[i]),
            format!("{:.4}", history.force_radial[i]),
            format!("{:.4}", history.mesh_force[i]),
            format!("{:.4}", derived.force_detail[i]),
        ];
        row.extend(history.pair_forces.iter().map(|f| format!("{:.4}", f[i])));
        row.extend([
            format!("{:.6e}", e.kinetic),
            format!("{:.6e}", e.strain),
            format!("{:.6e}", e.contact),
            format!("{:.6e}", e.damping),
            format!("{:.6e}", e.external_work),
            format!("{:.6e}", e.balance()),
            format!("{:.6e}", e.transmitted_work),
            history.active_contacts[i].to_string(),
            format!("{:.6}", history.max_penetration[i] * 1e6),
        ]);
        row
    });
    super::write_csv(path, &header_refs, rows)
}

/// The plots of a run; `impacts` draws the level-1 detail (not for a mass-scaled run, whose
/// body modes are lowered, so the band does not read the real pair's impacts).
pub fn plot_run(
    dir: &Path,
    title: &str,
    history: &History,
    derived: &Derived,
    spectrum: &[(f64, f64)],
    pair_names: &[String],
    impacts: bool,
) -> Result<(), PlotError> {
    let series = |values: &[f64]| -> Vec<(f64, f64)> {
        history
            .time
            .iter()
            .zip(values)
            .map(|(t, v)| (t * 1e3, *v))
            .collect()
    };
    let time_plot = |stem: &str, y_label: &str, series: Vec<(String, Vec<(f64, f64)>)>| {
        save_chart(
            dir,
            stem,
            &LinePlot {
                y_range: None,
                markers: Vec::new(),
                title: format!("{title}: {stem}"),
                x_label: "time [ms]".into(),
                y_label: y_label.into(),
                series,
            },
        )
    };
    time_plot(
        "dte",
        "angular DTE of the driven gear [rad]",
        vec![
            ("DTE".into(), series(&history.dte)),
            (
                "de-noised (db5, soft threshold)".into(),
                series(&derived.dte_denoised),
            ),
        ],
    )?;
    time_plot(
        "speed",
        "driven-gear speed [rad/s]",
        vec![
            ("FE".into(), series(&history.driven_speed)),
            (
                "theoretical (z1/z2) x driver".into(),
                series(&history.theoretical_speed),
            ),
        ],
    )?;
    time_plot(
        "contact_force",
        "contact force on the driven gear [N]",
        vec![
            ("resultant F_C".into(), series(&history.force_total)),
            (
                "circumferential".into(),
                series(&history.force_circumferential),
            ),
            ("radial".into(), series(&history.force_radial)),
        ],
    )?;
    if impacts {
        time_plot(
            "impacts",
            "level-1 db5 detail of the contact force [N]",
            vec![("D1".into(), series(&derived.force_detail))],
        )?;
    }
    time_plot(
        "pair_forces",
        "contact force per flank pair [N]",
        history
            .pair_forces
            .iter()
            .zip(pair_names)
            .filter(|(f, _)| f.iter().any(|v| *v > 0.0))
            .map(|(f, name)| (name.clone(), series(f)))
            .collect(),
    )?;
    let energy = |f: &dyn Fn(&crate::explicit::pair::PairEnergy) -> f64| -> Vec<f64> {
        history.energy.iter().map(f).collect()
    };
    time_plot(
        "energy",
        "energy [J]",
        vec![
            ("kinetic".into(), series(&energy(&|e| e.kinetic))),
            ("strain".into(), series(&energy(&|e| e.strain))),
            ("contact".into(), series(&energy(&|e| e.contact))),
            ("damping".into(), series(&energy(&|e| e.damping))),
            (
                "external work".into(),
                series(&energy(&|e| e.external_work)),
            ),
            ("balance".into(), series(&energy(&|e| e.balance()))),
        ],
    )?;
    if !spectrum.is_empty() {
        save_chart(
            dir,
            "dte_spectrum",
            &LinePlot {
                y_range: None,
                markers: Vec::new(),
                title: format!("{title}: DTE spectrum (Hann window, after the ramp)"),
                x_label: "frequency [Hz]".into(),
                y_label: "amplitude [rad]".into(),
                series: vec![(
                    "DTE".into(),
                    spectrum
                        .iter()
                        .copied()
                        .filter(|(f, _)| *f <= 20_000.0)
                        .collect(),
                )],
            },
        )?;
    }
    Ok(())
}

/// Writes every file of a run (also of a diverged one: what it computed).
pub fn write(out: OutputDir, case: &Case, study: &FeStudy) -> Result<(), ReportError> {
    out.case(case)?;
    let io = |name: &str| {
        let path = out.path(name).display().to_string();
        move |source| ReportError::Io { path, source }
    };
    let history = &study.history;
    write_history(
        &out.path("history.csv"),
        history,
        &study.derived,
        &study.pair_names,
    )
    .map_err(io("history.csv"))?;
    out.csv(
        "dte_spectrum.csv",
        &["frequency_hz", "amplitude_rad"],
        study
            .spectrum
            .iter()
            .map(|(f, a)| vec![format!("{f:.4}"), format!("{a:.6e}")]),
    )?;
    if let Some(k) = study.analysis.as_ref().and_then(|a| a.stiffness.as_ref()) {
        stiffness_csv::write_stiffness_csv(&out.path("stiffness.csv"), k)
            .map_err(io("stiffness.csv"))?;
    }
    write_stiffness_comparison(out, case, study)?;
    plot_run(
        out.0,
        &format!("{}: {}", case.name(), study.scene.name),
        history,
        &study.derived,
        &study.spectrum,
        &study.pair_names,
        study.summary.impact_d1_max_n.is_some(),
    )?;
    match &study.checkpoint {
        Some(checkpoint) => {
            write_checkpoint(&out.path(CHECKPOINT), checkpoint, history).map_err(io(CHECKPOINT))?
        }
        None => out.remove(CHECKPOINT)?,
    }
    out.json("summary.json", &study.summary)
}

/// An interrupted run's state (compact JSON, every f64 exact), where `fe --resume` and
/// `run --resume` go on from; removed when the run finishes.
pub const CHECKPOINT: &str = "checkpoint.json";

/// checkpoint.json: the run's checkpoint and its history so far.
#[derive(serde::Serialize)]
struct CheckpointFile<'a> {
    checkpoint: &'a RunCheckpoint,
    history: &'a History,
}

#[derive(serde::Deserialize)]
struct CheckpointRead {
    checkpoint: RunCheckpoint,
    history: History,
}

/// Streams the checkpoint to a temporary file and renames it (no second copy of the history in
/// memory): the stop request's, and those a run keeps as it goes.
pub fn write_checkpoint(
    path: &Path,
    checkpoint: &RunCheckpoint,
    history: &History,
) -> std::io::Result<()> {
    let tmp = super::temporary_sibling(path);
    {
        let mut file = std::io::BufWriter::new(std::fs::File::create(&tmp)?);
        serde_json::to_writer(
            &mut file,
            &CheckpointFile {
                checkpoint,
                history,
            },
        )
        .map_err(std::io::Error::other)?;
        std::io::Write::flush(&mut file)?;
        file.get_ref().sync_all()?;
    }
    std::fs::rename(&tmp, path).inspect_err(|_| {
        let _ = std::fs::remove_file(&tmp);
    })
}

/// The checkpoint in `dir` and the history recorded before it, if there is one.
pub fn read_checkpoint(dir: &Path) -> Result<Option<(RunCheckpoint, History)>, ReportError> {
    let path = dir.join(CHECKPOINT);
    let bytes = match std::fs::read(&path) {
        Ok(bytes) => bytes,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(source) => {
            return Err(ReportError::Io {
                path: path.display().to_string(),
                source,
            })
        }
    };
    serde_json::from_slice::<CheckpointRead>(&bytes)
        .map(|read| Some((read.checkpoint, read.history)))
        .map_err(|e| ReportError::Io {
            path: path.display().to_string(),
            source: std::io::Error::other(e),
        })
}

/// The prepared scene's line for the terminal: model size and time step.
pub fn prepared_console(case: &Case, prepared: &PreparedScene, scene: &Scene) -> String {
    let settings = &case.fe;
    let per_window = crate::explicit::scene::run_elements(prepared, prepared.duration);
    format!(
        "{} elements ({} tooth pairs, flank elements {:.2} mm, body {:.2} mm){}; dt_cr = {:.4e} s (bodies {:.4e} / {:.4e}, contact {:.4e}; paper's L/c {:.4e}), dt = {:.4e} s, {} steps{}\n",
        prepared.model.elements(),
        prepared.model.tooth_pairs.len(),
        settings.fine_size * 1e3,
        settings.coarse_size * 1e3,
        if per_window != prepared.model.elements() {
            format!(
                " with every engaging tooth fine, stepped on windows of {} driver pitch with the teeth that engage in each fine: {per_window} elements in the first",
                crate::explicit::scene::WINDOW_PITCHES
            )
        } else {
            String::new()
        },
        prepared.dt_critical,
        prepared.dt_bodies[0],
        prepared.dt_bodies[1],
        prepared.dt_contact,
        prepared.dt_paper,
        prepared.dt,
        (prepared.duration / prepared.dt).ceil(),
        match prepared.time_step {
            TimeStep::Coupled => " at most (the step then follows the pair's own stable step)",
            TimeStep::Bound => "",
        }
    ) + &lengthened_line(prepared, scene)
}

/// Where a scene that is to cover a base pitch was lengthened: by how much and why.
fn lengthened_line(prepared: &PreparedScene, scene: &Scene) -> String {
    if prepared.duration <= prepared.scene_duration {
        return String::new();
    }
    format!(
        "scene {} lengthened from {} s to {:.4} s (cover_pitch): its statistics window holds one base pitch of the driver after the ramp and {:.4} s of settling\n",
        scene.name, prepared.scene_duration, prepared.duration, prepared.settling_time
    )
}

/// The driver's roll angle [deg] at a bin centre `theta` (driver rotation from the
/// pitch-point position [rad]).
fn bin_roll_angle_deg(pair: &GearPair, theta: f64) -> f64 {
    (pair.roll_angle_at(1, pair.contact_points.pitch) + theta).to_degrees()
}

/// One column of paired bins (θ, a, b) against the roll angle, for a plot.
fn bin_curve(
    pair: &GearPair,
    bins: &[(f64, f64, f64)],
    pick: fn(&(f64, f64, f64)) -> f64,
) -> Vec<(f64, f64)> {
    bins.iter()
        .map(|b| (bin_roll_angle_deg(pair, b.0), pick(b)))
        .collect()
}

/// `stiffness_vs_ltca.csv` and the `stiffness` plot: k(θ) from the DTE per bin beside the
/// LTCA's on the run's mesh and on the case's.
fn write_stiffness_comparison(
    out: OutputDir,
    case: &Case,
    study: &FeStudy,
) -> Result<(), ReportError> {
    let [same, converged] = &study.stiffness_comparison;
    let Some(same) = same else {
        return Ok(());
    };
    let deg = |theta: f64| bin_roll_angle_deg(&case.pair, theta);
    let reference = |theta: f64| {
        converged.as_ref().and_then(|c| {
            c.bins
                .iter()
                .find(|b| (b.0 - theta).abs() < 1e-12)
                .map(|b| b.2)
        })
    };
    out.csv(
        "stiffness_vs_ltca.csv",
        &[
            "roll_angle_deg",
            "mesh_stiffness_fe_n_per_m",
            "mesh_stiffness_ltca_same_mesh_n_per_m",
            "mesh_stiffness_ltca_case_mesh_n_per_m",
        ],
        same.bins.iter().map(|(theta, fe, ltca)| {
            vec![
                format!("{:.6}", deg(*theta)),
                format!("{fe:.6e}"),
                format!("{ltca:.6e}"),
                reference(*theta).map_or(String::new(), |k| format!("{k:.6e}")),
            ]
        }),
    )?;
    let curve = |pick, bins: &[(f64, f64, f64)]| bin_curve(&case.pair, bins, pick);
    let mut series = vec![
        ("FE, from the DTE".to_string(), curve(|b| b.1, &same.bins)),
        (
            format!("LTCA, same mesh ({} mm)", same.summary.fine_element_mm),
            curve(|b| b.2, &same.bins),
        ),
    ];
    if let Some(c) = converged {
        series.push((
            format!("LTCA, case mesh ({} mm)", c.summary.fine_element_mm),
            curve(|b| b.2, &c.bins),
        ));
    }
    out.chart(
        "stiffness",
        &LinePlot {
            y_range: None,
            markers: Vec::new(),
            title: format!(
                "{}: {}: k = sum W / sum (Rb2 theta_DTE - e) per bin, against the LTCA",
                case.name(),
                study.scene.name
            ),
            x_label: "driver roll angle [deg]".into(),
            y_label: "mesh stiffness [N/m]".into(),
            series,
        },
    )
}

/// The scene's line before it is meshed.
pub fn scene_line(scene: &Scene) -> String {
    format!(
        "scene {}: {:.1} rpm, {} N·m, relief {}, mu {}, {} s (ramp {} s); meshing and measuring the critical step ...",
        scene.name,
        scene.driver_speed * 60.0 / std::f64::consts::TAU,
        scene.torque,
        scene.relief,
        scene.friction,
        scene.duration,
        scene.ramp_time
    )
}

/// The run's lines for the terminal.
pub fn console(study: &FeStudy) -> String {
    let s = &study.summary;
    let nan = f64::NAN;
    let ltca =
        |check: &Option<crate::study::fe::LtcaCheck>,
         f: fn(&crate::study::fe::LtcaCheck) -> f64| { check.as_ref().map_or(nan, f) };
    let mut text = format!(
        "{} steps in {:.1} s ({:.1} ns per element-step on {} threads); DTE mean {:.4e} rad (LTCA at the same positions: {:.4e} on this mesh, {:.4e} on the case's), peak-to-peak {:.4e} rad (LTCA {:.4e}, {:.4e}); k mean {:.4e} N/m; energy error {:.2e} of the net work, {:.2e} of the transmitted work\n",
        s.steps,
        s.wall_s,
        s.wall_ns_per_element_step,
        s.wall_threads,
        s.dte_mean_rad.unwrap_or(nan),
        ltca(&s.ltca_same_mesh, |l| l.ste_mean_rad),
        ltca(&s.ltca_case_mesh, |l| l.ste_mean_rad),
        s.dte_peak_to_peak_rad.unwrap_or(nan),
        ltca(&s.ltca_same_mesh, |l| l.ste_peak_to_peak_rad),
        ltca(&s.ltca_case_mesh, |l| l.ste_peak_to_peak_rad),
        s.mesh_stiffness_mean_n_per_m.unwrap_or(nan),
        s.energy_error_rel,
        s.energy_error_rel_transmitted
    );
    if let Some(t) = s.settled_at_s {
        use crate::explicit::scene::SettledStop;
        text.push_str(&format!(
            "stopped at t = {t:.4} s of {} s: the DTE had settled (stop_when_settled: the rms over the last three stretches of whole mesh periods after {:.4} s to move by under {:.0} % more and within {:.0} % from the first to the last, at {} checks in a row)\n",
            s.scene.duration,
            s.statistics_start_s,
            SettledStop::DRIFT * 100.0,
            SettledStop::GROWTH * 100.0,
            SettledStop::CHECKS
        ));
    }
    let phases = &s.wall_phases_us_per_step;
    // On one thread the contact's placement is only an order.
    let beside = if s.wall_threads > 1 {
        format!(
            ", beside gear 2's in {:.0} % of the steps",
            phases.contact_beside_gear2_share * 100.0
        )
    } else {
        String::new()
    };
    text.push_str(&format!(
        "a step's {:.1} us: drift {:.1}, forces {:.1} (contact {:.1}{beside}; element forces and kick gear 1 {:.1}, gear 2 {:.1}), flank and bore kick {:.1}, serial {:.1}\n",
        phases.step,
        phases.drift,
        phases.forces,
        phases.contact,
        phases.body_forces[0],
        phases.body_forces[1],
        phases.accelerate,
        phases.serial
    ));
    if let Some(same) = &s.stiffness_vs_ltca_same_mesh {
        text.push_str(&format!(
            "k(theta) from the DTE: mean {:.4e} N/m over {:.0} % of a base pitch; against the LTCA on this mesh {:+.2} % in the mean, {:.2} % at the worst of {} bins",
            s.mesh_stiffness_mean_n_per_m.unwrap_or(nan),
            s.stiffness_pitch_coverage.unwrap_or(0.0) * 100.0,
            same.mean_rel * 100.0,
            same.max_abs_rel * 100.0,
            same.bins
        ));
        if let Some(case_mesh) = &s.stiffness_vs_ltca_case_mesh {
            text.push_str(&format!(
                "; on the case's mesh ({} mm) {:+.2} %, {:.2} %",
                case_mesh.fine_element_mm,
                case_mesh.mean_rel * 100.0,
                case_mesh.max_abs_rel * 100.0
            ));
        }
        text.push('\n');
        if let Some(te) = &s.static_te_from_stiffness {
            text.push_str(&format!(
                "static TE from k(theta) at the load: mean {:.4e} rad, peak-to-peak {:.4e} rad; against the LTCA on this mesh {:+.2} % / {:+.2} %",
                te.mean_rad,
                te.peak_to_peak_rad,
                same.static_te_mean_rel * 100.0,
                same.static_te_peak_to_peak_rel * 100.0
            ));
            if let Some(c) = &s.stiffness_vs_ltca_case_mesh {
                text.push_str(&format!(
                    ", on the case's {:+.2} % / {:+.2} %",
                    c.static_te_mean_rel * 100.0,
                    c.static_te_peak_to_peak_rel * 100.0
                ));
            }
            text.push('\n');
        }
    }
    if let Some(coupled) = s.dt_critical_coupled_s {
        let largest = s
            .dt_changes
            .iter()
            .map(|c| c.dt_s)
            .fold(s.step.dt_s, f64::max);
        text.push_str(&format!(
            "stable step where the contact was (bodies and penalty springs, power iteration at {} instants): {coupled:.4e} s at the least, {:.2} x the largest step used ({largest:.4e} s)\n",
            s.dt_critical_coupled_checks.len(),
            coupled / largest
        ));
    }
    if let Some(last) = s.dt_changes.last() {
        text.push_str(&format!(
            "step: {:.4e} s from the start (the bound of every contact state), {} change(s) as the contact went, {:.4e} s from t = {:.4e} s on\n",
            s.step.dt_s,
            s.dt_changes.len(),
            last.dt_s,
            last.time_s
        ));
    }
    if let Some(why) = &s.dt_fallback {
        text.push_str(&format!(
            "the step went back to the bound's: {why}; the run went on from the sample before the last check that passed and is whole\n"
        ));
    }
    text
}

/// The mass-scaling study: `mass_scaling.csv` and `.md` (each quantity scaled, unscaled and
/// the difference), `mass_scaling_stiffness.csv` and its plot (k per bin of both runs over the
/// common window), `summary.json`, and the effective case. Returns the Markdown table.
pub fn write_mass_scaling(
    out: OutputDir,
    case: &Case,
    study: &MassScalingStudy,
) -> Result<String, ReportError> {
    let s = &study.summary;
    let (a, b) = (&s.scaled, &s.unscaled);
    let row = |name: &str, x: f64, y: f64, rel: f64| {
        vec![
            name.to_string(),
            format!("{x:.6e}"),
            format!("{y:.6e}"),
            format!("{:+.3}", 100.0 * rel),
        ]
    };
    let ratio = |x: f64, y: f64| x / y - 1.0;
    let rows = vec![
        row(
            "DTE mean [rad]",
            a.dte_mean_rad,
            b.dte_mean_rad,
            s.dte_mean_rel,
        ),
        row(
            "DTE peak-to-peak, raw (keeps the mesh mode's ringing) [rad]",
            a.dte_peak_to_peak_rad,
            b.dte_peak_to_peak_rad,
            s.dte_peak_to_peak_rel,
        ),
        row(
            "DTE low-passed, mean [rad]",
            a.dte_lowpass_mean_rad,
            b.dte_lowpass_mean_rad,
            s.dte_lowpass_mean_rel,
        ),
        row(
            "DTE low-passed, peak-to-peak [rad]",
            a.dte_lowpass_peak_to_peak_rad,
            b.dte_lowpass_peak_to_peak_rad,
            s.dte_lowpass_peak_to_peak_rel,
        ),
        row(
            "static TE from k(θ) at the load, mean [rad]",
            a.static_te_mean_rad,
            b.static_te_mean_rad,
            s.static_te_mean_rel,
        ),
        row(
            "static TE from k(θ) at the load, peak-to-peak [rad]",
            a.static_te_peak_to_peak_rad,
            b.static_te_peak_to_peak_rad,
            s.static_te_peak_to_peak_rel,
        ),
        row(
            &format!(
                "k mean, common window [N/m] (worst of {} bins {:.3} %)",
                s.stiffness_bins,
                100.0 * s.stiffness_max_abs_rel
            ),
            a.mesh_stiffness_mean_n_per_m,
            b.mesh_stiffness_mean_n_per_m,
            s.stiffness_mean_rel,
        ),
        row(
            &format!(
                "k mean, each run's stiffness.csv [N/m] (worst of {} bins {:.3} %)",
                s.own_table_bins,
                100.0 * s.own_table_stiffness_max_abs_rel
            ),
            a.own_table_mesh_stiffness_mean_n_per_m,
            b.own_table_mesh_stiffness_mean_n_per_m,
            s.own_table_stiffness_mean_rel,
        ),
        row(
            "mass scaling factor",
            a.mass_scaling_factor,
            b.mass_scaling_factor,
            ratio(a.mass_scaling_factor, b.mass_scaling_factor),
        ),
        row(
            "mesh mode [Hz]",
            a.mesh_mode_hz,
            b.mesh_mode_hz,
            ratio(a.mesh_mode_hz, b.mesh_mode_hz),
        ),
        row("time step [s]", a.dt_s, b.dt_s, ratio(a.dt_s, b.dt_s)),
        row(
            "steps",
            a.steps as f64,
            b.steps as f64,
            ratio(a.steps as f64, b.steps as f64),
        ),
        row(
            "explicit wall time [s]",
            a.wall_s,
            b.wall_s,
            ratio(a.wall_s, b.wall_s),
        ),
        row(
            "run wall time with the LTCA references [s]",
            a.total_wall_s,
            b.total_wall_s,
            ratio(a.total_wall_s, b.total_wall_s),
        ),
        row(
            "energy error / transmitted work",
            a.energy_error_rel_transmitted,
            b.energy_error_rel_transmitted,
            ratio(
                a.energy_error_rel_transmitted,
                b.energy_error_rel_transmitted,
            ),
        ),
    ];
    let header = [
        "quantity",
        "scaled",
        "unscaled",
        "scaled_over_unscaled_minus_1_pct",
    ];
    out.csv("mass_scaling.csv", &header, rows.clone())?;
    let mut markdown = format!(
        "scene {}, window {:.4}-{:.4} s, common low-pass {:.3} ms; speed-up {:.1}x\n\n| {} |\n|{}\n",
        s.scene,
        s.window_s[0],
        s.window_s[1],
        1e3 * s.lowpass_span_s,
        s.speedup,
        header.join(" | "),
        "---|".repeat(header.len())
    );
    for r in &rows {
        markdown.push_str(&format!("| {} |\n", r.join(" | ")));
    }
    out.bytes("mass_scaling.md", markdown.as_bytes())?;
    let deg = |theta: f64| bin_roll_angle_deg(&case.pair, theta);
    out.csv(
        "mass_scaling_stiffness.csv",
        &[
            "roll_angle_deg",
            "mesh_stiffness_scaled_n_per_m",
            "mesh_stiffness_unscaled_n_per_m",
        ],
        study.bins.iter().map(|(theta, k_scaled, k_unscaled)| {
            vec![
                format!("{:.6}", deg(*theta)),
                format!("{k_scaled:.6e}"),
                format!("{k_unscaled:.6e}"),
            ]
        }),
    )?;
    let curve = |pick| bin_curve(&case.pair, &study.bins, pick);
    out.chart(
        "mass_scaling_stiffness",
        &LinePlot {
            y_range: None,
            markers: Vec::new(),
            title: format!(
                "{}: {}: k from the DTE, mass-scaled (inertia {:.1}x) against unscaled",
                case.name(),
                s.scene,
                a.mass_scaling_factor
            ),
            x_label: "driver roll angle [deg]".into(),
            y_label: "mesh stiffness [N/m]".into(),
            series: vec![
                (
                    format!("mass-scaled, inertia {:.1}x", a.mass_scaling_factor),
                    curve(|b| b.1),
                ),
                ("unscaled".to_string(), curve(|b| b.2)),
            ],
        },
    )?;
    out.json("summary.json", s)?;
    out.case(case)?;
    Ok(markdown)
}
