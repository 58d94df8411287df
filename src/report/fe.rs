//! Outputs of an explicit FE run: time histories (CSV), the DTE spectrum, the stiffness from the
//! DTE in the file format the lumped model reads, plots, and the summary's numbers.

use std::path::Path;

use crate::explicit::scene::{DteAnalysis, History, PreparedScene};
use crate::report::plot::{save_chart, LinePlot, PlotError};
use crate::signal;

/// Derived signals of a history: de-noised DTE, level-1 db5 detail of the contact force.
pub struct Derived {
    pub dte_denoised: Vec<f64>,
    pub force_detail: Vec<f64>,
}

pub fn derive(history: &History) -> Derived {
    Derived {
        dte_denoised: signal::denoise(&history.dte, 5),
        force_detail: if history.force_total.len() >= 2 {
            signal::level1_detail(&history.force_total)
        } else {
            vec![0.0; history.force_total.len()]
        },
    }
}

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

/// DTE spectrum over the statistics window (Hann), amplitudes in rad.
pub fn dte_spectrum(history: &History, from: f64) -> Vec<(f64, f64)> {
    let Some(start) = history.time.iter().position(|t| *t >= from) else {
        return Vec::new();
    };
    if history.time.len() - start < 8 {
        return Vec::new();
    }
    let dt = (history.time[history.time.len() - 1] - history.time[start])
        / (history.time.len() - 1 - start) as f64;
    signal::hann_amplitude_spectrum(&history.dte[start..], dt)
}

/// The strongest local maxima of a spectrum (bins 0 … N/2) above `min_hz`: (frequency,
/// amplitude), by the sweep's [`crate::sweep::strongest_lines`].
pub fn spectrum_peaks(spectrum: &[(f64, f64)], min_hz: f64, count: usize) -> Vec<(f64, f64)> {
    if spectrum.len() < 2 {
        return Vec::new();
    }
    let amplitudes: Vec<f64> = spectrum[1..].iter().map(|p| p.1).collect();
    crate::sweep::strongest_lines(&amplitudes, amplitudes.len())
        .into_iter()
        .map(|(line, amplitude)| (spectrum[line].0, amplitude))
        .filter(|(frequency, _)| *frequency >= min_hz)
        .take(count)
        .collect()
}

/// The plots of a run.
pub fn plot_run(
    dir: &Path,
    title: &str,
    history: &History,
    derived: &Derived,
    spectrum: &[(f64, f64)],
    analysis: Option<&DteAnalysis>,
    pair_names: &[String],
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
    time_plot(
        "impacts",
        "level-1 db5 detail of the contact force [N]",
        vec![("D1".into(), series(&derived.force_detail))],
    )?;
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
    if let Some(a) = analysis {
        save_chart(
            dir,
            "stiffness",
            &LinePlot {
                title: format!("{title}: mesh stiffness from the DTE, k = T/(theta_DTE Rb2^2)"),
                x_label: "driver roll angle [deg]".into(),
                y_label: "mesh stiffness [N/m]".into(),
                series: vec![(
                    "from DTE".into(),
                    a.stiffness
                        .iter()
                        .map(|(r, k)| (r.to_degrees(), *k))
                        .collect(),
                )],
            },
        )?;
    }
    Ok(())
}

/// Cost and step numbers of a prepared scene, for the summary.
pub fn step_summary(prepared: &PreparedScene) -> serde_json::Value {
    let edges: Vec<f64> = prepared
        .model
        .flanks
        .iter()
        .flat_map(|f| f.penalty.iter().copied())
        .collect();
    let mean = edges.iter().sum::<f64>() / edges.len().max(1) as f64;
    let (lo, hi) = edges
        .iter()
        .fold((f64::INFINITY, 0.0_f64), |(a, b), k| (a.min(*k), b.max(*k)));
    let penalty = serde_json::json!({"mean": mean, "min": lo, "max": hi});
    serde_json::json!({
        "dt_s": prepared.dt,
        "dt_critical_s": prepared.dt_critical,
        "dt_critical_bodies_s": prepared.dt_bodies,
        "dt_critical_contact_s": prepared.dt_contact,
        "dt_paper_formula_s": prepared.dt_paper,
        "dt_element_eigenvalue_bound_s": prepared.dt_element_bound,
        "stiffness_damping_beta_s": prepared.beta_k,
        "mesh_damping_n_m_s": prepared.mesh_damping,
        "mesh_damping_sized_with_stiffness_n_per_m": prepared.mesh_damping_stiffness,
        "driven_inertia_kg_m2": prepared.model.driven_inertia(),
        "penalty_stiffness_per_edge_n_per_m": penalty,
        "elements": prepared.model.elements(),
        "nodes": prepared.model.meshes.iter().map(|m| m.nodes.len()).sum::<usize>(),
        "fine_teeth": [prepared.model.meshes[0].fine_teeth.clone(), prepared.model.meshes[1].fine_teeth.clone()],
        "tooth_pairs": prepared.model.tooth_pairs,
        "setup_wall_s": prepared.setup_wall_s,
    })
}
