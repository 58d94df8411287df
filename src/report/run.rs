//! The report of `geardyn run`: `index.html` (self-contained: plots embedded, no network),
//! `report.md` (the same content, images by relative path), `summary.json` (the headline
//! numbers) and `tables/*.csv` (every table of the report). It reads what the stages wrote, so
//! it is a view of the output folder and never recomputes a number.

use std::path::Path;

use base64::Engine;
use serde::Serialize;
use serde_json::Value;

use super::{OutputDir, ReportError};

/// What `geardyn run` ran (`run.json`): where the report finds the stages.
#[derive(Debug, Clone, Serialize, serde::Deserialize)]
pub struct RunManifest {
    /// The unmodified pair's relief variant.
    pub unmodified_relief: String,
    /// The unmodified pair's FE stiffness run, relative to the run folder.
    pub fe_stiffness_run: String,
    pub full: bool,
    /// Where a stop request ended the run, and how to continue it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interrupted: Option<String>,
    /// The stage that failed and why (absent when none did).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failed: Option<String>,
    /// The effective case the run was made with (`--resume` refuses another).
    #[serde(default)]
    pub case_text: Option<String>,
}

/// A table of the report.
struct Table {
    /// File stem under tables/.
    name: &'static str,
    caption: String,
    header: Vec<String>,
    rows: Vec<Vec<String>>,
}

/// One section: text, tables, plots (paths relative to the output folder).
struct Section {
    title: String,
    text: Vec<String>,
    tables: Vec<Table>,
    plots: Vec<(String, String)>,
}

/// The headline numbers of the whole chain (`summary.json`); null where a stage did not run.
#[derive(Debug, Clone, Serialize)]
pub struct RunSummary {
    /// Where a stop request ended the run (absent for a run that finished).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub interrupted: Option<String>,
    /// The stage that failed and why (absent when none did).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failed: Option<String>,
    pub case: Option<String>,
    pub torque_nm: Option<f64>,
    pub mesh_stiffness_ltca_n_per_m: Option<f64>,
    pub mesh_stiffness_fe_n_per_m: Option<f64>,
    pub mesh_stiffness_iso_n_per_m: Option<f64>,
    pub mesh_stiffness_potential_energy_n_per_m: Option<f64>,
    pub fe_stiffness_vs_ltca_same_mesh_rel: Option<f64>,
    pub ste_pp_unmodified_um: Option<f64>,
    pub primary_resonance_rpm_ltca: Option<f64>,
    pub max_dynamic_factor_ltca: Option<f64>,
    pub primary_resonance_rpm_fe: Option<f64>,
    pub max_dynamic_factor_fe: Option<f64>,
    /// The sweeps' own mesh mode (their model linearized about the design load) on the LTCA's
    /// and the FE's k [Hz]: what their resonance speeds follow.
    pub natural_frequency_sweep_ltca_hz: Option<f64>,
    pub natural_frequency_sweep_fe_hz: Option<f64>,
    /// The sweeps' own warnings (an overload beyond the contact law), "LTCA k: …", "FE k: …".
    pub sweep_warnings: Vec<String>,
    pub max_floquet_multiplier: Option<f64>,
    pub tip_relief_um: Option<Value>,
    pub root_relief_um: Option<Value>,
    pub relief_length_fraction: Option<f64>,
    pub relief_shape: Option<Value>,
    pub robust_ste_pp_optimum_um: Option<f64>,
    pub robust_ste_pp_unmodified_um: Option<f64>,
    pub robust_ste_pp_classic_um: Option<f64>,
    pub robust_ste_pp_paper_um: Option<f64>,
    pub fe_low_speed_dte_pp_unmodified_um: Option<f64>,
    pub fe_low_speed_dte_pp_optimum_um: Option<f64>,
    /// The torque span of the Harris map over which the recommended relief's STE peak-to-peak
    /// is below the unmodified pair's [N·m] (its first and last such torque).
    pub relief_beats_unmodified_nm: Option<(f64, f64)>,
    /// Whether it is below at every torque of the map inside that span.
    pub relief_beats_unmodified_throughout: Option<bool>,
    /// Low-passed or raw DTE peak-to-peak (as the cross-check ranked).
    pub fe_low_speed_measure: Option<String>,
    pub mesh_mode_fe_modal_free_hz: Option<f64>,
    pub mesh_mode_lumped_free_hz: Option<f64>,
    pub mesh_mode_fe_modal_driver_held_hz: Option<f64>,
    pub mesh_mode_lumped_driver_held_hz: Option<f64>,
    /// The stages' checks of their own answers (LTCA, FE stiffness run) that failed: errors
    /// (the answer is wrong) and warnings (suspicious); the report's "Self-checks" lists them.
    pub self_check_errors: usize,
    pub self_check_warnings: usize,
    /// The smallest root and flank safety over the sweep's speeds, from the FE's static
    /// stresses scaled by the sweep's dynamic factor, and where: (S, driver rpm)
    /// (`strength_over_speed.csv`).
    pub min_root_safety: Option<(f64, f64)>,
    pub min_contact_safety: Option<(f64, f64)>,
}

fn read(dir: &Path, stage: &str) -> Option<Value> {
    let text = std::fs::read_to_string(dir.join(stage).join("summary.json")).ok()?;
    serde_json::from_str(&text).ok()
}

fn number(v: &Option<Value>, path: &[&str]) -> Option<f64> {
    path.iter()
        .try_fold(v.as_ref()?, |v, key| v.get(key))?
        .as_f64()
}

fn field(v: &Option<Value>, path: &[&str]) -> Option<Value> {
    path.iter()
        .try_fold(v.as_ref()?, |v, key| v.get(key))
        .cloned()
}

fn show(value: Option<f64>, digits: usize) -> String {
    value.map_or("–".into(), |v| format!("{v:.digits$}"))
}

/// `value` against `reference` as a signed percentage.
fn relative(value: Option<f64>, reference: Option<f64>) -> String {
    match (value, reference) {
        (Some(v), Some(r)) => format!("{:+.1} %", 100.0 * (v / r - 1.0)),
        _ => "–".into(),
    }
}

/// A JSON array of numbers, `digits` decimals, comma separated.
fn list(v: Option<Value>, digits: usize) -> String {
    v.and_then(|v| v.as_array().cloned())
        .map_or("–".into(), |a| {
            let shown: Vec<String> = a.iter().map(|x| show(x.as_f64(), digits)).collect();
            if shown.is_empty() {
                "none".into()
            } else {
                shown.join(", ")
            }
        })
}

/// A JSON array of [from, to] pairs as "from–to" (0 decimals), comma separated.
fn ranges(v: Option<Value>) -> String {
    let pairs: Vec<String> = v
        .and_then(|v| v.as_array().cloned())
        .unwrap_or_default()
        .iter()
        .filter_map(|r| {
            Some(format!(
                "{:.0}–{:.0}",
                r.get(0)?.as_f64()?,
                r.get(1)?.as_f64()?
            ))
        })
        .collect();
    if pairs.is_empty() {
        "no speed".into()
    } else {
        pairs.join(", ")
    }
}

fn show_e(value: Option<f64>) -> String {
    value.map_or("–".into(), |v| format!("{v:.4e}"))
}

/// The candidate row of an optimize fe_check by name.
fn fe_check_line<'a>(optimize: &'a Option<Value>, name: &str) -> Option<&'a Value> {
    optimize
        .as_ref()?
        .get("fe_check")?
        .get("lines")?
        .as_array()?
        .iter()
        .find(|l| l.get("candidate").and_then(|c| c.as_str()) == Some(name))
}

/// Reads the stages' outputs in `dir` and writes the report; returns the headline numbers.
pub fn write(dir: &Path) -> Result<RunSummary, ReportError> {
    let geometry = read(dir, "geometry");
    let ltca = read(dir, "ltca");
    let sweep_ltca = read(dir, "sweep-ltca");
    let sweep_fe = read(dir, "sweep-fe");
    let stability = read(dir, "stability");
    let optimize = read(dir, "optimize");
    let compare = read(dir, "compare");
    let manifest: Option<RunManifest> = std::fs::read_to_string(dir.join("run.json"))
        .ok()
        .and_then(|text| serde_json::from_str(&text).ok());
    // The FE low-speed measure the cross-check ranked by, for every candidate alike.
    let lowpass = field(&optimize, &["fe_check", "fe_low_measure"])
        .is_some_and(|m| m.as_str().is_some_and(|m| m.starts_with("low-passed")));
    let fe_low_key = if lowpass {
        "fe_low_dte_lowpass_pp_um"
    } else {
        "fe_low_dte_pp_um"
    };
    let fe_low = |name: &str| {
        fe_check_line(&optimize, name)
            .and_then(|l| l.get(fe_low_key))
            .and_then(|v| v.as_f64())
    };
    let unmodified_name = manifest
        .as_ref()
        .map_or_else(|| "none".to_string(), |m| m.unmodified_relief.clone());
    let unmodified_variant = field(&ltca, &["variants"])
        .and_then(|v| v.as_array().cloned())
        .and_then(|variants| {
            variants.into_iter().find(|v| {
                v.get("relief_variant").and_then(|x| x.as_str()) == Some(unmodified_name.as_str())
            })
        });
    let unmodified_number = |key: &str| {
        unmodified_variant
            .as_ref()
            .and_then(|v| v.get(key))
            .and_then(|v| v.as_f64())
    };
    // The unmodified pair's low-speed run (the FE stiffness stage); a diverged or interrupted
    // run counts as missing.
    let fe_run = manifest.as_ref().map_or_else(
        || format!("fe/{unmodified_name}-stiffness"),
        |m| m.fe_stiffness_run.clone(),
    );
    let harris = harris_span(dir, &unmodified_name);
    let fe = read(dir, &fe_run).filter(|s| {
        ["diverged", "interrupted"]
            .iter()
            .all(|key| s.get(key).is_none_or(|d| d.is_null()))
    });
    let checks = self_checks(&[
        ("ltca/", &ltca),
        (&format!("{fe_run}/"), &fe),
        ("sweep-ltca/", &sweep_ltca),
    ]);
    let failed = |warning: bool| {
        checks
            .iter()
            .filter(|c| c.passed == Some(false) && c.warning_only == warning)
            .count()
    };
    let over_speed = safety_over_speed(&unmodified_variant, &dynamic_factors(dir));
    let lowest = |column: usize| {
        over_speed
            .iter()
            .filter(|r| r[column].is_finite())
            .min_by(|a, b| a[column].total_cmp(&b[column]))
            .map(|r| (r[column], r[0]))
    };
    let summary = RunSummary {
        min_root_safety: lowest(1),
        min_contact_safety: lowest(3),
        self_check_errors: failed(false),
        self_check_warnings: failed(true),
        interrupted: manifest.as_ref().and_then(|m| m.interrupted.clone()),
        failed: manifest.as_ref().and_then(|m| m.failed.clone()),
        case: field(&ltca, &["case"]).and_then(|c| c.as_str().map(String::from)),
        torque_nm: number(&ltca, &["torque_nm"]),
        mesh_stiffness_ltca_n_per_m: unmodified_number("mesh_stiffness_mean_n_per_m"),
        mesh_stiffness_fe_n_per_m: number(&fe, &["mesh_stiffness_mean_n_per_m"]),
        mesh_stiffness_iso_n_per_m: number(&ltca, &["iso_c_gamma_n_per_m"]),
        mesh_stiffness_potential_energy_n_per_m: number(&ltca, &["potential_energy_mean_n_per_m"]),
        fe_stiffness_vs_ltca_same_mesh_rel: number(
            &fe,
            &["stiffness_vs_ltca_same_mesh", "mean_rel"],
        ),
        ste_pp_unmodified_um: unmodified_number("ste_peak_to_peak_um"),
        primary_resonance_rpm_ltca: number(&sweep_ltca, &["primary_resonance_rpm"]),
        max_dynamic_factor_ltca: number(&sweep_ltca, &["max_dynamic_factor"]),
        primary_resonance_rpm_fe: number(&sweep_fe, &["primary_resonance_rpm"]),
        max_dynamic_factor_fe: number(&sweep_fe, &["max_dynamic_factor"]),
        natural_frequency_sweep_ltca_hz: number(&sweep_ltca, &["natural_frequency_hz"]),
        natural_frequency_sweep_fe_hz: number(&sweep_fe, &["natural_frequency_hz"]),
        sweep_warnings: [("LTCA k", &sweep_ltca), ("FE k", &sweep_fe)]
            .into_iter()
            .flat_map(|(source, summary)| {
                let diverged = field(summary, &["diverged"]).and_then(|d| {
                    d.as_str()
                        .map(|d| format!("{source}: the sweep stopped: {d}"))
                });
                let warnings = match field(summary, &["warnings"]) {
                    Some(Value::Array(warnings)) => warnings
                        .iter()
                        .filter_map(|w| w.as_str().map(|w| format!("{source}: {w}")))
                        .collect(),
                    _ => Vec::new(),
                };
                diverged.into_iter().chain(warnings).collect::<Vec<_>>()
            })
            .collect(),
        max_floquet_multiplier: number(&stability, &["max_multiplier"]),
        tip_relief_um: field(&optimize, &["tip_relief_um"]),
        root_relief_um: field(&optimize, &["root_relief_um"]),
        relief_length_fraction: number(&optimize, &["relief_length_fraction"]),
        relief_shape: field(&optimize, &["shape"]),
        robust_ste_pp_optimum_um: number(&optimize, &["objective_optimum"]),
        robust_ste_pp_unmodified_um: number(&optimize, &["objective_none"]),
        robust_ste_pp_classic_um: number(&optimize, &["objective_classic"]),
        robust_ste_pp_paper_um: number(&optimize, &["objective_paper"]),
        fe_low_speed_dte_pp_unmodified_um: fe_low(&unmodified_name),
        fe_low_speed_dte_pp_optimum_um: fe_low(crate::study::optimize::BEST),
        relief_beats_unmodified_nm: harris.map(|h| h.0),
        relief_beats_unmodified_throughout: harris.map(|h| h.1),
        fe_low_speed_measure: field(&optimize, &["fe_check", "fe_low_measure"])
            .and_then(|m| m.as_str().map(String::from)),
        mesh_mode_fe_modal_free_hz: number(&compare, &["f_natural_fe_modal_hz"]),
        mesh_mode_lumped_free_hz: number(&compare, &["f_natural_lumped_hz"]),
        mesh_mode_fe_modal_driver_held_hz: number(&compare, &["f_natural_fe_modal_driver_held_hz"]),
        mesh_mode_lumped_driver_held_hz: number(&compare, &["f_natural_lumped_driver_held_hz"]),
    };
    let mut sections = sections(
        dir,
        &summary,
        &fe_run,
        [
            &geometry,
            &ltca,
            &unmodified_variant,
            &fe,
            &sweep_ltca,
            &stability,
            &optimize,
            &compare,
        ],
    );
    sections.insert(1, self_check_section(&checks));
    // A stop or a failed stage heads the report, the stop above the failure.
    let notices = [
        (&summary.failed, "A stage failed", "what every stage wrote"),
        (
            &summary.interrupted,
            "The run stopped early",
            "what the stages before the stop wrote",
        ),
    ];
    for (message, title, shown) in notices {
        if let Some(message) = message {
            sections.insert(
                0,
                Section {
                    title: title.into(),
                    text: vec![format!(
                        "{message}. The sections below show {shown}; a number marked – was not reached."
                    )],
                    tables: Vec::new(),
                    plots: Vec::new(),
                },
            );
        }
    }
    let out = OutputDir(dir);
    if !over_speed.is_empty() {
        out.csv(
            "strength_over_speed.csv",
            &[
                "driver_rpm",
                "root_safety_fe",
                "root_safety_iso",
                "contact_safety_fe",
                "contact_safety_iso",
            ],
            over_speed
                .iter()
                .map(|r| r.iter().map(|v| format!("{v:.6}")).collect()),
        )?;
        let curve = |column: usize| -> Vec<(f64, f64)> {
            over_speed
                .iter()
                .filter(|r| r[column].is_finite())
                .map(|r| (r[0], r[column]))
                .collect()
        };
        let (first, last) = (over_speed[0][0], over_speed[over_speed.len() - 1][0]);
        out.chart(
            "strength_over_speed",
            &super::plot::LinePlot {
                y_range: None,
                markers: Vec::new(),
                title: "Safety under the dynamic mesh force (sweep on the LTCA's force law)".into(),
                x_label: "driver speed [rpm]".into(),
                y_label: "safety factor".into(),
                series: vec![
                    ("S_F, FE root stress".into(), curve(1)),
                    ("S_F, ISO 6336-3 sigma_F0".into(), curve(2)),
                    ("S_H, LTCA Hertz pressure".into(), curve(3)),
                    ("S_H, ISO 6336-2 sigma_H".into(), curve(4)),
                    ("1".into(), vec![(first, 1.0), (last, 1.0)]),
                ],
            },
        )?;
    }
    std::fs::create_dir_all(dir.join("tables")).map_err(|source| ReportError::Io {
        path: dir.join("tables").display().to_string(),
        source,
    })?;
    for section in &sections {
        for table in section.tables.iter().filter(|t| !t.rows.is_empty()) {
            let header: Vec<&str> = table.header.iter().map(|h| h.as_str()).collect();
            out.csv(
                &format!("tables/{}.csv", table.name),
                &header,
                table.rows.clone(),
            )?;
        }
    }
    out.bytes("report.md", markdown(&summary, &sections).as_bytes())?;
    out.bytes("index.html", html(dir, &summary, &sections).as_bytes())?;
    out.json("summary.json", &summary)?;
    Ok(summary)
}

/// One self-check as a stage's summary.json holds it ([`crate::study::checks::Check`]).
struct StageCheck {
    stage: String,
    quantity: String,
    value: Option<f64>,
    reference: Option<f64>,
    rule: String,
    passed: Option<bool>,
    warning_only: bool,
}

/// The `self_checks` of each stage's summary, in order.
fn self_checks(stages: &[(&str, &Option<Value>)]) -> Vec<StageCheck> {
    stages
        .iter()
        .flat_map(|(stage, summary)| {
            field(summary, &["self_checks"])
                .and_then(|c| c.as_array().cloned())
                .unwrap_or_default()
                .into_iter()
                .map(move |c| {
                    let text = |key: &str| c.get(key).and_then(|v| v.as_str()).unwrap_or("–");
                    let tolerance = c.get("tolerance").and_then(|v| v.as_f64());
                    StageCheck {
                        stage: stage.to_string(),
                        quantity: text("quantity").to_string(),
                        value: c.get("value").and_then(|v| v.as_f64()),
                        reference: c.get("reference").and_then(|v| v.as_f64()),
                        rule: match (text("kind"), tolerance) {
                            ("relative", Some(t)) => format!("relative ≤ {t:.1e}"),
                            ("absolute", Some(t)) => format!("absolute ≤ {t:.1e}"),
                            ("below", _) => "below the reference".into(),
                            (kind, _) => kind.to_string(),
                        },
                        passed: c.get("passed").and_then(|v| v.as_bool()),
                        warning_only: c
                            .get("warning_only")
                            .and_then(|v| v.as_bool())
                            .unwrap_or(false),
                    }
                })
                .collect::<Vec<_>>()
        })
        .collect()
}

/// The section that lists every stage's checks of its own answer.
fn self_check_section(checks: &[StageCheck]) -> Section {
    let errors = checks
        .iter()
        .filter(|c| c.passed == Some(false) && !c.warning_only);
    let warnings = checks
        .iter()
        .filter(|c| c.passed == Some(false) && c.warning_only);
    let verdict = match (errors.count(), warnings.count()) {
        (0, 0) if checks.is_empty() => "No stage reached its self-checks.".to_string(),
        (0, 0) => format!("All {} checks passed.", checks.len()),
        (0, w) => format!(
            "No check failed; {w} of {} flag a result as suspicious (WARNING below).",
            checks.len()
        ),
        (e, w) => format!(
            "{e} of {} checks FAILED (the answer of that stage is wrong), {w} warnings.",
            checks.len()
        ),
    };
    Section {
        title: "Self-checks".into(),
        text: vec![format!(
            "Each stage checks its own answer: the LTCA its periodicity over a base pitch, the \
             contact conditions, the torque balance, the unloaded geometry's expectations and its \
             mesh against the Hertzian contact; the explicit FE its k(θ) and static TE against the \
             LTCA on its own mesh; the lumped model its quasi-static response against the LTCA \
             from 25 to 300 % of the design torque. {verdict}"
        )],
        tables: vec![Table {
            name: "self_checks",
            caption: "The stages' checks of their own answers".into(),
            header: ["stage", "check", "value", "reference", "rule", "verdict"]
                .map(String::from)
                .to_vec(),
            rows: checks
                .iter()
                .map(|c| {
                    row(&[
                        c.stage.clone(),
                        c.quantity.clone(),
                        show_e(c.value),
                        show_e(c.reference),
                        c.rule.clone(),
                        match (c.passed, c.warning_only) {
                            (Some(true), _) => "ok",
                            (Some(false), true) => "WARNING",
                            (Some(false), false) => "FAILED",
                            (None, _) => "–",
                        }
                        .into(),
                    ])
                })
                .collect(),
        }],
        plots: Vec::new(),
    }
}

fn row(cells: &[String]) -> Vec<String> {
    cells.to_vec()
}

/// The report's sections from the stages' summaries (and `unmodified`, ltca's summary of the
/// unmodified variant, the one the sweeps and the FE stiffness run are of).
fn sections(
    dir: &Path,
    s: &RunSummary,
    fe_run: &str,
    [geometry, ltca, unmodified, fe, sweep_ltca, stability, optimize, compare]: [&Option<Value>; 8],
) -> Vec<Section> {
    let torque = show(s.torque_nm, 1);
    let unstable = field(stability, &["unstable_rpm_ranges"])
        .filter(|r| r.as_array().is_some_and(|a| !a.is_empty()));
    let amounts = |v: &Option<Value>| {
        v.as_ref()
            .and_then(|v| v.as_array().cloned())
            .map_or("–".into(), |a| {
                a.iter()
                    .map(|x| show(x.as_f64(), 2))
                    .collect::<Vec<_>>()
                    .join(" / ")
            })
    };
    let answers = Table {
        name: "answers",
        caption: format!("The answers, at {torque} N·m on the driven gear"),
        header: vec!["question".into(), "answer".into(), "from".into()],
        rows: vec![
            row(&[
                "mean mesh stiffness [N/m]".into(),
                format!(
                    "LTCA {} · FE (DTE) {} · ISO 6336 c_γα·b {} · potential energy {}",
                    show_e(s.mesh_stiffness_ltca_n_per_m),
                    show_e(s.mesh_stiffness_fe_n_per_m),
                    show_e(s.mesh_stiffness_iso_n_per_m),
                    show_e(s.mesh_stiffness_potential_energy_n_per_m)
                ),
                format!("ltca/, {fe_run}/"),
            ]),
            row(&[
                "loaded STE peak-to-peak, unmodified [µm]".into(),
                show(s.ste_pp_unmodified_um, 3),
                "ltca/".into(),
            ]),
            row(&[
                "primary resonance, max dynamic factor".into(),
                format!(
                    "{} rpm, {} (LTCA k) · {} rpm, {} (FE k). The sweeps' model has its mesh mode at {} / {} Hz; the case's model (LTCA force law) is {} against the FE modal analysis of the pair on the case's mesh with both gears free (compare/, validation/frequencies)",
                    show(s.primary_resonance_rpm_ltca, 0),
                    show(s.max_dynamic_factor_ltca, 2),
                    show(s.primary_resonance_rpm_fe, 0),
                    show(s.max_dynamic_factor_fe, 2),
                    show(s.natural_frequency_sweep_ltca_hz, 0),
                    show(s.natural_frequency_sweep_fe_hz, 0),
                    relative(s.mesh_mode_lumped_free_hz, s.mesh_mode_fe_modal_free_hz),
                ),
                "sweep-ltca/, sweep-fe/".into(),
            ]),
            row(&[
                "other resonance peaks, tooth separation (LTCA k) [rpm]".into(),
                format!(
                    "peaks of the DTE rms at {}; teeth apart at {}",
                    list(field(sweep_ltca, &["resonance_rpm"]), 0),
                    ranges(field(sweep_ltca, &["separation_rpm_ranges"]))
                ),
                "sweep-ltca/".into(),
            ]),
            row(&[
                "parametric stability".into(),
                format!(
                    "largest Floquet multiplier {}: {}",
                    show(s.max_floquet_multiplier, 3),
                    match (s.max_floquet_multiplier, &unstable) {
                        (None, _) => "–".to_string(),
                        (Some(_), None) => "stable over the range".into(),
                        (Some(_), Some(r)) => format!("unstable at {} rpm", ranges(Some(r.clone()))),
                    }
                ),
                "stability/".into(),
            ]),
            row(&[
                "recommended relief (tip, root per gear 1 / 2) [µm]".into(),
                format!(
                    "tip {}, root {}, {} over {} of the end zone (HPSTC to tip, LPSTC to SAP)",
                    amounts(&s.tip_relief_um),
                    amounts(&s.root_relief_um),
                    s.relief_shape
                        .as_ref()
                        .and_then(|v| v.as_str())
                        .unwrap_or("–"),
                    show(s.relief_length_fraction, 2)
                ),
                "optimize/".into(),
            ]),
            row(&[
                format!(
                    "what it gains (loaded STE peak-to-peak, mean over {} N·m) [µm]",
                    list(field(optimize, &["torque_range_nm"]), 1)
                ),
                format!(
                    "{} against {} unmodified, {} classic rule, {} the case's relief",
                    show(s.robust_ste_pp_optimum_um, 3),
                    show(s.robust_ste_pp_unmodified_um, 3),
                    show(s.robust_ste_pp_classic_um, 3),
                    show(s.robust_ste_pp_paper_um, 3)
                ),
                "optimize/harris.png".into(),
            ]),
            row(&[
                "where it is quieter than no relief (Harris map, 10–200 % of the design torque)"
                    .into(),
                match (s.relief_beats_unmodified_nm, s.relief_beats_unmodified_throughout) {
                    (Some((a, b)), Some(true)) => format!(
                        "at every torque of the map from {a:.0} to {b:.0} N·m (STE peak-to-peak below the unmodified pair's)"
                    ),
                    (Some((a, b)), _) => format!(
                        "between {a:.0} and {b:.0} N·m, not at every torque of the map in between (optimize/harris.png)"
                    ),
                    _ => "at no torque of the map".into(),
                },
                "optimize/harris.csv".into(),
            ]),
            row(&[
                format!(
                    "explicit FE at low speed, {} [µm]",
                    s.fe_low_speed_measure
                        .as_deref()
                        .unwrap_or("DTE peak-to-peak")
                ),
                format!(
                    "{} unmodified, {} with the recommended relief",
                    show(s.fe_low_speed_dte_pp_unmodified_um, 3),
                    show(s.fe_low_speed_dte_pp_optimum_um, 3)
                ),
                "optimize/fe_check.md".into(),
            ]),
            row(&[
                "mesh mode, both gears free [Hz]".into(),
                format!(
                    "FE modal {} · the lumped model (as the sweeps) {}; driver held: FE modal {}, lumped {}",
                    show(s.mesh_mode_fe_modal_free_hz, 0),
                    show(s.mesh_mode_lumped_free_hz, 0),
                    show(s.mesh_mode_fe_modal_driver_held_hz, 0),
                    show(s.mesh_mode_lumped_driver_held_hz, 0)
                ),
                "compare/, sweep-fe/".into(),
            ]),
        ],
    };
    let trust = vec![
        format!(
            "LTCA (2D FE bodies, exact contact, quasi-static, frictionless; {} mm flank elements here): k(θ), STE and load sharing; the reference for relief. Its mesh convergence is in validation/ltca and `geardyn validate quick`.",
            show(number(ltca, &["fine_element_mm"]), 2)
        ),
        format!(
            "Explicit FE ({} mm flank elements here, penalty contact, friction, large rotations): what the lumped model reduces to one degree of freedom — impacts at tooth engagement, friction, the teeth's and bodies' own modes. Its k(θ) from the DTE is {} against the LTCA on its own mesh: the penalty contact's share, not a different physics.",
            show(number(fe, &["fine_element_mm"]), 2),
            s.fe_stiffness_vs_ltca_same_mesh_rel.map_or("–".into(), |r| format!("{:+.1} %", 100.0 * r))
        ),
        format!(
            "Lumped model ({}): speed sweeps, resonances, tooth separation and stability in seconds. Its mesh mode is {} (both gears free) and {} (driver held) against the FE modal analysis of the meshed pair on the case's mesh (compare/, validation/frequencies).",
            field(sweep_ltca, &["model"]).and_then(|m| m.as_str().map(String::from)).unwrap_or_else(|| "–".into()),
            relative(s.mesh_mode_lumped_free_hz, s.mesh_mode_fe_modal_free_hz),
            relative(s.mesh_mode_lumped_driver_held_hz, s.mesh_mode_fe_modal_driver_held_hz),
        ),
        "ISO 6336 and potential energy: first estimates; they do not see the bodies' compliance the FE sees.".into(),
    ];
    let mut out = vec![Section {
        title: "Answers".into(),
        text: Vec::new(),
        tables: vec![answers],
        plots: Vec::new(),
    }];
    out.push(Section {
        title: "Where each model is trusted".into(),
        text: trust,
        tables: Vec::new(),
        plots: Vec::new(),
    });
    out.push(Section {
        title: "Geometry and meshes".into(),
        text: vec![format!(
            "Contact ratio {}, center distance {} mm.",
            show(number(geometry, &["contact_ratio"]), 4),
            show(number(geometry, &["center_distance_mm"]), 3)
        )],
        tables: Vec::new(),
        plots: vec![
            (
                "The meshing pair, line of action and contact points".into(),
                "geometry/pair.png".into(),
            ),
            ("FE mesh of gear 1".into(), "mesh/mesh_gear1.png".into()),
        ],
    });
    let variants = field(ltca, &["variants"])
        .and_then(|v| v.as_array().cloned())
        .unwrap_or_default();
    out.push(Section {
        title: "Loaded tooth contact (LTCA)".into(),
        text: vec![format!(
            "{} relief variants at {torque} N·m, {} positions per base pitch.",
            variants.len(),
            show(number(ltca, &["positions"]), 0)
        )],
        tables: vec![Table {
            name: "ltca_variants",
            caption: "Per relief variant".into(),
            header: [
                "variant",
                "mean k [N/m]",
                "min k",
                "max k",
                "STE mean [µm]",
                "STE p-p [µm]",
            ]
            .map(String::from)
            .to_vec(),
            rows: variants
                .iter()
                .map(|v| {
                    let n = |k: &str| v.get(k).and_then(|x| x.as_f64());
                    vec![
                        v.get("relief_variant")
                            .and_then(|x| x.as_str())
                            .unwrap_or("")
                            .to_string(),
                        show_e(n("mesh_stiffness_mean_n_per_m")),
                        show_e(n("mesh_stiffness_min_n_per_m")),
                        show_e(n("mesh_stiffness_max_n_per_m")),
                        show(n("ste_mean_um"), 3),
                        show(n("ste_peak_to_peak_um"), 3),
                    ]
                })
                .collect(),
        }],
        plots: vec![
            ("Static transmission error".into(), "ltca/ste.png".into()),
            (
                "Mesh stiffness: LTCA, potential energy, ISO 6336".into(),
                "ltca/stiffness.png".into(),
            ),
        ],
    });
    // The unmodified pair's FE stresses and safety (the sweep scales them); ISO's alike for
    // every variant.
    let sf = |key: &str, g: Option<usize>| {
        let v = field(unmodified, &["safety_factors", key]);
        match g {
            Some(g) => v.and_then(|v| v.get(g).and_then(|x| x.as_f64())),
            None => v.and_then(|v| v.as_f64()),
        }
    };
    let per_gear = |summary: &Option<Value>, path: &[&str], g: usize| {
        field(summary, path).and_then(|v| v.get(g).and_then(|x| x.as_f64()))
    };
    let fe_root = |g: usize| {
        field(unmodified, &["root_stress"]).and_then(|v| {
            v.get(g)
                .and_then(|p| p.get("tension_mpa"))
                .and_then(|x| x.as_f64())
        })
    };
    let fe_pressure = number(unmodified, &["contact_pressure_max_mpa"]);
    let strength_rows = vec![
        row(&[
            "root stress, largest fillet tension [MPa]".into(),
            show(fe_root(0), 1),
            show(fe_root(1), 1),
            show(per_gear(ltca, &["root_stress_iso_mpa"], 0), 1),
            show(per_gear(ltca, &["root_stress_iso_mpa"], 1), 1),
        ]),
        row(&[
            "contact pressure [MPa]".into(),
            show(fe_pressure, 0),
            show(fe_pressure, 0),
            show(per_gear(ltca, &["contact_pressure_iso_mpa"], 0), 0),
            show(per_gear(ltca, &["contact_pressure_iso_mpa"], 1), 0),
        ]),
        row(&[
            "S_F at the design torque".into(),
            show(sf("root_fe", Some(0)), 2),
            show(sf("root_fe", Some(1)), 2),
            show(sf("root_iso", Some(0)), 2),
            show(sf("root_iso", Some(1)), 2),
        ]),
        row(&[
            "S_H at the design torque".into(),
            show(sf("contact_fe", None), 2),
            show(sf("contact_fe", None), 2),
            show(sf("contact_iso", Some(0)), 2),
            show(sf("contact_iso", Some(1)), 2),
        ]),
    ];
    out.push(Section {
        title: "Strength".into(),
        text: vec![
            format!(
                "At {torque} N·m, unmodified pair: the FE's largest fillet tension over the cycle (LTCA contact forces through the bodies' fillet stress, recovered at the surface) and the LTCA's largest Hertz pressure, beside ISO 6336-3 method B and ISO 6336-2 (load factors 1). Limits σ_Flim {} MPa, σ_Hlim {} MPa (`[material]`; the defaults are a case-hardened steel, an assumption); {}.",
                show(sf("root_stress_limit_mpa", None), 0),
                show(sf("contact_stress_limit_mpa", None), 0),
                field(unmodified, &["safety_factors", "basis"]).and_then(|b| b.as_str().map(String::from)).unwrap_or_default(),
            ),
            match (s.min_root_safety, s.min_contact_safety) {
                (Some((sf, sf_rpm)), Some((sh, sh_rpm))) => format!(
                    "Under the dynamic mesh force of the sweep on the LTCA's force law (root stress × K, Hertz pressure × √K, K its largest mesh force over the static one at each speed, up- or down-sweep): the smallest FE-based S_F is {sf:.2} at {sf_rpm:.0} rpm, the smallest S_H {sh:.2} at {sh_rpm:.0} rpm (strength_over_speed.csv, with ISO's beside). Not assessed: the back flanks, which a pair without backlash loads where the response is large (reversed bending, ISO's Y_M), and the damper's share of the mesh force."
                ),
                _ if field(unmodified, &["safety_factors"]).is_none() => "The LTCA stage holds no safety factors (a folder written before them, or the stage did not finish): nothing to scale over speed.".to_string(),
                _ => "The FE-based safety over speed is missing: no sweep on the LTCA's force law (sweep-ltca/sweep.csv), or no FE stress to scale.".to_string(),
            },
            field(ltca, &["iso_6336", "root"])
                .and_then(|r| r.as_array().cloned())
                .map(|gears| {
                    gears
                        .iter()
                        .enumerate()
                        .flat_map(|(g, root)| {
                            root.get("notes")
                                .and_then(|n| n.as_array().cloned())
                                .unwrap_or_default()
                                .into_iter()
                                .filter_map(move |n| n.as_str().map(|n| format!("ISO 6336-3, gear {}: {n}.", g + 1)))
                        })
                        .collect::<Vec<_>>()
                        .join(" ")
                })
                .unwrap_or_default(),
        ]
        .into_iter()
        .filter(|t| !t.is_empty())
        .collect(),
        tables: vec![Table {
            name: "strength",
            caption: "FE and ISO 6336, gear 1 and gear 2".into(),
            header: ["quantity", "FE gear 1", "FE gear 2", "ISO gear 1", "ISO gear 2"]
                .map(String::from)
                .to_vec(),
            rows: strength_rows,
        }],
        plots: vec![
            ("Fillet tension of a loaded tooth along the path of contact".into(), "ltca/root_stress.png".into()),
            ("Hertz pressure along the path of contact".into(), "ltca/contact_pressure.png".into()),
            ("The tooth with the largest fillet tension, where it peaks: max principal and von Mises (ParaView: ltca/stress_field.vtk)".into(), "ltca/stress_field.png".into()),
            ("Safety over speed".into(), "strength_over_speed.png".into()),
        ],
    });
    out.push(Section {
        title: "Explicit FE: k(θ) from the low-speed DTE".into(),
        text: vec![format!(
            "Mean {} N/m; against the LTCA on the same mesh {} in the mean, {} at the worst bin; on the case's mesh {}.",
            show_e(number(fe, &["mesh_stiffness_mean_n_per_m"])),
            number(fe, &["stiffness_vs_ltca_same_mesh", "mean_rel"]).map_or("–".into(), |r| format!("{:+.1} %", 100.0 * r)),
            number(fe, &["stiffness_vs_ltca_same_mesh", "max_abs_rel"]).map_or("–".into(), |r| format!("{:.1} %", 100.0 * r)),
            number(fe, &["stiffness_vs_ltca_case_mesh", "mean_rel"]).map_or("–".into(), |r| format!("{:+.1} %", 100.0 * r)),
        )],
        tables: Vec::new(),
        plots: vec![
            ("DTE".into(), format!("{fe_run}/dte.png")),
            ("k(θ) from the DTE against the LTCA".into(), format!("{fe_run}/stiffness.png")),
        ],
    });
    let mut sweep_text = vec![format!(
        "Lumped model on the LTCA's force law: primary resonance {} rpm, max dynamic factor {}; on the FE's k(θ): {} rpm, {}. Largest Floquet multiplier of the model's periodic orbit {} (ζ = {}; drive flanks linearized {}){}.",
        show(number(sweep_ltca, &["primary_resonance_rpm"]), 0),
        show(number(sweep_ltca, &["max_dynamic_factor"]), 2),
        show(s.primary_resonance_rpm_fe, 0),
        show(s.max_dynamic_factor_fe, 2),
        show(number(stability, &["max_multiplier"]), 3),
        show(number(stability, &["damping_ratio"]), 3),
        show(number(stability, &["max_multiplier_linear"]), 3),
        field(stability, &["no_orbit_rpm_ranges"])
            .filter(|r| r.as_array().is_some_and(|a| !a.is_empty()))
            .map_or_else(String::new, |r| format!(
                "; no period-one response found in {} rpm (past a fold, or sub-harmonic)",
                ranges(Some(r))
            )),
    )];
    sweep_text.extend(s.sweep_warnings.iter().map(|w| format!("Warning, {w}.")));
    out.push(Section {
        title: "Speed sweeps and stability".into(),
        text: sweep_text,
        tables: Vec::new(),
        plots: vec![
            (
                "Dynamic factor, LTCA k".into(),
                "sweep-ltca/dynamic_factor.png".into(),
            ),
            (
                "Dynamic factor, FE k".into(),
                "sweep-fe/dynamic_factor.png".into(),
            ),
            (
                "Waterfall, LTCA k".into(),
                "sweep-ltca/waterfall.png".into(),
            ),
            ("Stability map".into(), "stability/stability.png".into()),
        ],
    });
    let fe_lines = field(optimize, &["fe_check", "lines"])
        .and_then(|v| v.as_array().cloned())
        .unwrap_or_default();
    let fe_check_table = Table {
        name: "relief_fe_check",
        caption: "The LTCA's prediction against the explicit FE (optimize/fe_check.md)".into(),
        header: [
            "candidate",
            "LTCA STE p-p [µm]",
            "FE low speed DTE p-p, low-passed [µm]",
            "LTCA STE 1st harmonic [µm]",
            "FE high speed DTE 1st harmonic [µm]",
        ]
        .map(String::from)
        .to_vec(),
        rows: fe_lines
            .iter()
            .map(|l| {
                let v = Some(l.clone());
                vec![
                    l.get("candidate")
                        .and_then(|x| x.as_str())
                        .unwrap_or("")
                        .to_string(),
                    show(number(&v, &["ltca_ste_pp_um"]), 3),
                    show(number(&v, &["fe_low_dte_lowpass_pp_um"]), 3),
                    show(number(&v, &["ltca_ste_h1_um"]), 3),
                    show(
                        field(&v, &["fe_high_harmonics_um"])
                            .and_then(|h| h.get(0).and_then(|x| x.as_f64())),
                        3,
                    ),
                ]
            })
            .collect(),
    };
    let candidates = field(optimize, &["candidates"])
        .and_then(|v| v.as_array().cloned())
        .unwrap_or_default();
    out.push(Section {
        title: "Relief optimization".into(),
        text: vec![format!(
            "Robust objective: loaded STE peak-to-peak averaged over {} N·m. QP loop {} s.",
            list(field(optimize, &["torque_range_nm"]), 1),
            show(number(optimize, &["qp_loop_wall_s"]), 1)
        )],
        tables: vec![
            Table {
                name: "relief_candidates",
                caption: "Candidates".into(),
                header: [
                    "candidate",
                    "tip g1 / g2 [µm]",
                    "root g1 / g2 [µm]",
                    "robust STE p-p [µm]",
                    "at the design torque [µm]",
                    "max dynamic factor",
                ]
                .map(String::from)
                .to_vec(),
                rows: candidates
                    .iter()
                    .map(|c| {
                        let v = Some(c.clone());
                        vec![
                            c.get("name")
                                .and_then(|x| x.as_str())
                                .unwrap_or("")
                                .to_string(),
                            amounts(&field(&v, &["tip_relief_um"])),
                            amounts(&field(&v, &["root_relief_um"])),
                            show(number(&v, &["objective_um"]), 3),
                            show(number(&v, &["ste_pp_design_um"]), 3),
                            show(number(&v, &["max_dynamic_factor"]), 2),
                        ]
                    })
                    .collect(),
            },
            fe_check_table,
        ],
        plots: vec![
            ("Harris map".into(), "optimize/harris.png".into()),
            (
                "Trust-region iterations".into(),
                "optimize/convergence.png".into(),
            ),
            (
                "STE at the design torque".into(),
                "optimize/ste_design.png".into(),
            ),
            (
                "Lumped dynamic factor per candidate".into(),
                "optimize/sweep.png".into(),
            ),
        ],
    });
    let mut frequency_text = vec![format!(
        "Mesh mode, both gears free: FE modal {} Hz, the lumped model (as the sweeps integrate it) {} Hz; driver held: {} / {} Hz. compare/table.md lists every method.",
        show(s.mesh_mode_fe_modal_free_hz, 0),
        show(s.mesh_mode_lumped_free_hz, 0),
        show(s.mesh_mode_fe_modal_driver_held_hz, 0),
        show(s.mesh_mode_lumped_driver_held_hz, 0),
    )];
    let mut frequency_plots = spectra(dir);
    // A compare without the FE sweep writes `"fe_sweep": null`.
    if let Some(sweep) = compare
        .as_ref()
        .and_then(|c| c.get("fe_sweep"))
        .filter(|v| !v.is_null())
    {
        let n = |key: &str| number(compare, &["fe_sweep", key]);
        // A response the one-DOF fit does not describe (FE's or the case's model's: bent, or
        // the fit in an unstable band): its resonance and peak errors measure nothing.
        let bent = ["fit_describes_fe", "fit_describes_lumped"]
            .iter()
            .any(|key| sweep.get(*key).and_then(|v| v.as_bool()) == Some(false));
        frequency_text.push(format!(
            "The explicit FE through the resonance ({} speeds, speed drive as the FE): resonance {} rpm (FE) against {} rpm (the case's lumped model, {}); peak first mesh harmonic {}; DTE rms at most {} apart ({} at the FE's speeds taken relative to each one's resonance; there a resonance 1 % off alone moves the rms by up to {}). Where a lumped model's sweep diverged, compare/table.md says what the FE did there.",
            sweep.get("fe").and_then(|f| f.as_array()).map_or(0, |f| f.len()),
            show(n("resonance_rpm_fe"), 0),
            show(n("resonance_rpm_lumped"), 0),
            match bent {
                true => "not measured: the one-DOF fit does not describe the response (bent by the flanks, or in a model's unstable band; compare/table.md)".into(),
                false => n("resonance_rpm_rel_err")
                    .map_or("–".into(), |r| format!("{:+.2} %", 100.0 * r)),
            },
            match (bent, sweep.get("peak_pinned").and_then(|p| p.as_bool())) {
                (true, _) => "not measured (the fit does not describe the response)".into(),
                // Speeds only on the resonance's skirts leave the peak's height unmeasured.
                (_, Some(false)) => "not measured (the FE speeds do not pin the peak down: compare/table.md says where to run one more)".into(),
                _ => n("peak_dte_mesh_amplitude_rel_err")
                    .map_or("–".into(), |r| format!("{:+.1} %", 100.0 * r)),
            },
            n("dte_rms_max_rel_err").map_or("–".into(), |r| format!("{:.1} %", 100.0 * r)),
            n("dte_rms_max_rel_err_at_fe_resonance")
                .map_or("–".into(), |r| format!("{:.1} %", 100.0 * r)),
            n("dte_rms_speed_sensitivity_max").map_or("–".into(), |s| format!("{s:.0} %")),
        ));
        // The crossings the FE's own lines show met.
        let crossings = sweep
            .get("body_mode_crossings")
            .and_then(|c| c.as_array())
            .map_or(0, |c| {
                c.iter()
                    .filter(|c| c.get("excited").and_then(|e| e.as_bool()) == Some(true))
                    .count()
            });
        if crossings > 0 {
            frequency_text.push(format!(
                "{} of the FE speeds lie on a body mode's super-harmonic resonance, where the rms measures where each model puts that mode more than the mesh's dynamics; off them the DTE rms is at most {} apart. {}",
                crossings,
                n("dte_rms_max_rel_err_off_body_crossings")
                    .map_or("–".into(), |r| format!("{:.1} %", 100.0 * r)),
                sweep
                    .get("body_mode_note")
                    .and_then(|v| v.as_str())
                    .unwrap_or_default(),
            ));
        }
        frequency_plots.push((
            "Explicit FE through the resonance (markers) against the lumped models (lines)".into(),
            "compare/fe_sweep.png".into(),
        ));
    }
    out.push(Section {
        title: "FE against lumped frequencies".into(),
        text: frequency_text,
        tables: vec![Table {
            name: "mesh_mode",
            caption: "Mesh-mode frequency by method [Hz]".into(),
            header: ["method", "both gears free", "driver held"]
                .map(String::from)
                .to_vec(),
            rows: [
                (
                    "lumped √(k/m), rigid gears, k LTCA on the explicit mesh",
                    "lumped_ltca_secant_hz",
                ),
                (
                    "lumped, elastic bodies, k LTCA tangent on the explicit mesh",
                    "lumped_ltca_tangent_elastic_hz",
                ),
                ("lumped √(k/m), rigid gears, k FE DTE", "lumped_fe_hz"),
                ("lumped, elastic bodies, k FE DTE", "lumped_fe_elastic_hz"),
                (
                    "FE modal on the explicit mesh (mean over positions)",
                    "fe_modal_mean_hz",
                ),
                (
                    "the lumped model as the sweeps (the case's mesh)",
                    "lumped_model_hz",
                ),
                (
                    "FE modal on the case's mesh (mean over positions)",
                    "fe_modal_case_mesh_mean_hz",
                ),
            ]
            .iter()
            .map(|(method, key)| {
                vec![
                    method.to_string(),
                    show(number(compare, &["both_free", key]), 0),
                    show(number(compare, &["driver_held", key]), 0),
                ]
            })
            .collect(),
        }],
        plots: frequency_plots,
    });
    out
}

/// From optimize/harris.csv: the first and last torque at which the best optimum's STE
/// peak-to-peak is below the unmodified candidate's, and whether it is below at every torque
/// between them.
fn harris_span(dir: &Path, unmodified: &str) -> Option<((f64, f64), bool)> {
    let mut reader = csv::Reader::from_path(dir.join("optimize/harris.csv")).ok()?;
    let headers = reader.headers().ok()?.clone();
    let column = |name: String| headers.iter().position(|h| h == name);
    let best = column(format!("{}_ste_pp_um", crate::study::optimize::BEST))?;
    let none = column(format!("{unmodified}_ste_pp_um"))?;
    let mut below = Vec::new();
    for record in reader.records() {
        let record = record.ok()?;
        let value = |i: usize| record.get(i)?.parse::<f64>().ok();
        below.push((value(0)?, value(best)? < value(none)?));
    }
    let first = below.iter().position(|b| b.1)?;
    let last = below.iter().rposition(|b| b.1)?;
    let throughout = below[first..=last].iter().all(|b| b.1);
    Some(((below[first].0, below[last].0), throughout))
}

/// The sweep's dynamic factor per speed, the larger of the up- and down-sweep's:
/// (driver rpm, K) from `sweep-ltca/sweep.csv`.
fn dynamic_factors(dir: &Path) -> Vec<(f64, f64)> {
    let Ok(mut reader) = csv::Reader::from_path(dir.join("sweep-ltca/sweep.csv")) else {
        return Vec::new();
    };
    let Ok(headers) = reader.headers().cloned() else {
        return Vec::new();
    };
    let column = |name: &str| headers.iter().position(|h| h == name);
    let (Some(rpm), Some(up), Some(down)) = (
        column("driver_rpm"),
        column("dynamic_factor_up"),
        column("dynamic_factor_down"),
    ) else {
        return Vec::new();
    };
    reader
        .records()
        .filter_map(|r| {
            let r = r.ok()?;
            let value = |i: usize| r.get(i)?.parse::<f64>().ok().filter(|v| v.is_finite());
            let k = match (value(up), value(down)) {
                (Some(a), Some(b)) => a.max(b),
                (a, b) => a.or(b)?,
            };
            Some((value(rpm)?, k))
        })
        .collect()
}

/// The safety factors over the sweep's speeds from the static ones of `variant` (ltca's summary
/// of the unmodified pair, the one the sweep runs on; the smaller of the two gears'): (rpm, S_F
/// FE, S_F ISO, S_H FE, S_H ISO), NaN where a static value is missing; empty when none is there.
fn safety_over_speed(variant: &Option<Value>, factors: &[(f64, f64)]) -> Vec<[f64; 5]> {
    let smaller = |key: &str| {
        field(variant, &["safety_factors", key]).and_then(|v| match v {
            Value::Array(a) => a.iter().filter_map(|x| x.as_f64()).reduce(f64::min),
            other => other.as_f64(),
        })
    };
    let [root_fe, root_iso, contact_fe, contact_iso] =
        ["root_fe", "root_iso", "contact_fe", "contact_iso"]
            .map(|k| smaller(k).unwrap_or(f64::NAN));
    factors
        .iter()
        .map(|&(rpm, k)| {
            let (sf_fe, sh_fe) =
                crate::strength::safety::under_dynamic_load(root_fe, contact_fe, k);
            let (sf_iso, sh_iso) =
                crate::strength::safety::under_dynamic_load(root_iso, contact_iso, k);
            [rpm, sf_fe, sf_iso, sh_fe, sh_iso]
        })
        .collect()
}

/// The FE-against-lumped spectra `compare` drew (one per FE speed), if any.
fn spectra(dir: &Path) -> Vec<(String, String)> {
    let mut names: Vec<String> = std::fs::read_dir(dir.join("compare"))
        .map(|entries| {
            entries
                .filter_map(|e| e.ok()?.file_name().into_string().ok())
                .filter(|n| n.starts_with("spectra_") && n.ends_with("rpm.png"))
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
        .into_iter()
        .map(|n| {
            (
                format!(
                    "DTE spectra, FE against lumped, {}",
                    n.trim_start_matches("spectra_").trim_end_matches(".png")
                ),
                format!("compare/{n}"),
            )
        })
        .collect()
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn markdown(s: &RunSummary, sections: &[Section]) -> String {
    let mut md = format!(
        "# geardyn report: {}\n",
        s.case.as_deref().unwrap_or("case")
    );
    for section in sections {
        md += &format!("\n## {}\n\n", section.title);
        for p in &section.text {
            md += &format!("{p}\n\n");
        }
        for t in section.tables.iter().filter(|t| !t.rows.is_empty()) {
            md += &format!(
                "{} (tables/{}.csv)\n\n| {} |\n|{}|\n",
                t.caption,
                t.name,
                t.header.join(" | "),
                t.header.iter().map(|_| "---").collect::<Vec<_>>().join("|")
            );
            for r in &t.rows {
                md += &format!("| {} |\n", r.join(" | "));
            }
            md += "\n";
        }
        for (caption, path) in &section.plots {
            md += &format!("![{caption}]({path})\n\n");
        }
    }
    md
}

fn html(dir: &Path, s: &RunSummary, sections: &[Section]) -> String {
    let mut body = String::new();
    for section in sections {
        body += &format!("<section><h2>{}</h2>\n", escape(&section.title));
        for p in &section.text {
            body += &format!("<p>{}</p>\n", escape(p));
        }
        for t in section.tables.iter().filter(|t| !t.rows.is_empty()) {
            body += &format!(
                "<table><caption>{} <a href=\"tables/{}.csv\">CSV</a></caption><tr>{}</tr>\n",
                escape(&t.caption),
                t.name,
                t.header
                    .iter()
                    .map(|h| format!("<th>{}</th>", escape(h)))
                    .collect::<String>()
            );
            for r in &t.rows {
                body += &format!(
                    "<tr>{}</tr>\n",
                    r.iter()
                        .map(|c| format!("<td>{}</td>", escape(c)))
                        .collect::<String>()
                );
            }
            body += "</table>\n";
        }
        for (caption, path) in &section.plots {
            match std::fs::read(dir.join(path)) {
                Ok(png) => {
                    body += &format!(
                        "<figure><img alt=\"{0}\" src=\"data:image/png;base64,{1}\"><figcaption>{0} ({2})</figcaption></figure>\n",
                        escape(caption),
                        base64::engine::general_purpose::STANDARD.encode(png),
                        escape(path)
                    );
                }
                Err(_) => {
                    body += &format!(
                        "<p class=\"missing\">{} — not produced ({})</p>\n",
                        escape(caption),
                        escape(path)
                    )
                }
            }
        }
        body += "</section>\n";
    }
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>geardyn report: {0}</title>\n<style>\nbody{{font-family:sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222}}\ntable{{border-collapse:collapse;margin:1em 0}}td,th{{border:1px solid #bbb;padding:4px 8px;text-align:left;vertical-align:top}}\nth{{background:#eef}}caption{{text-align:left;font-weight:bold;padding:4px 0}}\nfigure{{margin:1em 0}}img{{max-width:100%;max-height:640px}}figcaption{{color:#555;font-size:90%}}.missing{{color:#a00}}\n</style></head><body>\n<h1>geardyn report: {0}</h1>\n{1}</body></html>\n",
        escape(s.case.as_deref().unwrap_or("case")),
        body
    )
}
