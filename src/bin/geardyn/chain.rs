//! `geardyn run`: the mission's chain on one case, each stage in its own sub-folder of one
//! output folder — geometry, LTCA, the explicit FE's k(θ) from a low-speed DTE against the
//! LTCA's, rpm sweeps on both stiffnesses and the stability map, the relief optimization with
//! its explicit-FE cross-check, FE against lumped frequencies.
//!
//! The explicit runs live in DIR/fe/<relief>-<scene>; a finished run of the same effective case
//! is reused, so the unmodified stiffness run serves the FE stiffness stage, the cross-check's
//! baseline and the frequency comparison, and an interrupted `run` resumes its FE stages.

use std::path::Path;

use anyhow::Result;

use geardyn::case::StiffnessSource;
use geardyn::report::run::RunManifest;
use geardyn::report::OutputDir;
use geardyn::study::optimize::{fe_run_folder, FeCheckPlan};
use geardyn::study::{self, lumped::LumpedShorthands, RpmRange};

use super::args::{CommonArgs, OptimizeArgs};
use super::progress::fe_check_run;
use super::{compare, geometry, load, ltca, mesh, optimize_into, output_dir, stability, sweep};

/// Speeds of the sweeps [rpm] and of the stability map.
const SWEEP_RPM: &str = "100:12000:600";
const STABILITY_RPM: &str = "100:20000:2000";

/// Extra FE speeds of the frequency comparison with `--full` (3000 rpm comes from the
/// cross-check's high-speed run).
const FULL_COMPARE_RPM: [f64; 2] = [1200.0, 4800.0];

pub fn run(args: &CommonArgs, full: bool) -> Result<()> {
    let case = load(args, Vec::new())?;
    let dir = output_dir(args, "run", &case)?;
    let started = std::time::Instant::now();
    let unmodified = study::unmodified_name(&case);
    // The report finds the stages through this manifest (and is written even when a stage
    // fails, with what the stages before it left).
    let manifest = RunManifest {
        unmodified_relief: unmodified.clone(),
        fe_stiffness_run: format!(
            "fe/{}",
            fe_run_folder(&unmodified, study::compare::STIFFNESS_SCENE)
        ),
        full,
    };
    OutputDir(&dir).json("run.json", &manifest)?;
    let result = stages(args, &case, &dir, &manifest, started);
    geardyn::report::run::write(&dir)?;
    println!("report: {}", dir.join("index.html").display());
    result?;
    println!(
        "\nall outputs in {} ({:.0} s)",
        dir.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

fn stages(
    args: &CommonArgs,
    case: &geardyn::case::Case,
    dir: &Path,
    manifest: &RunManifest,
    started: std::time::Instant,
) -> Result<()> {
    let full = manifest.full;
    let sub = |name: &str| CommonArgs {
        out: Some(dir.join(name)),
        ..args.clone()
    };
    let stages = [
        "geometry and meshes",
        "LTCA",
        "FE stiffness from the low-speed DTE",
        "rpm sweeps (LTCA and FE k) and stability",
        "relief optimization and its FE cross-check",
        "FE against lumped frequencies",
    ];
    let mut stage_number = 0;
    let mut announce = || {
        stage_number += 1;
        println!(
            "\n== {stage_number}/{} {} ({:.0} s so far)",
            stages.len(),
            stages[stage_number - 1],
            started.elapsed().as_secs_f64()
        );
    };

    announce();
    geometry(&sub("geometry"))?;
    mesh(&sub("mesh"), None)?;
    announce();
    ltca(&sub("ltca"), None, 64, None)?;

    announce();
    // The unmodified pair's runs are the cross-check's baseline runs: one effective case.
    let unmodified_case = load(args, study::optimize::unmodified_fe_overrides(case))?;
    let fe_root = dir.join("fe");
    let stiffness_run = dir.join(&manifest.fe_stiffness_run);
    fe_check_run(
        &unmodified_case,
        study::compare::STIFFNESS_SCENE,
        &stiffness_run,
    )
    .map_err(anyhow::Error::msg)?;
    let stiffness_csv = stiffness_run.join("stiffness.csv");

    announce();
    let rpm: RpmRange = SWEEP_RPM.parse().map_err(anyhow::Error::msg)?;
    sweep(
        &sub("sweep-ltca"),
        rpm.clone(),
        &LumpedShorthands::default(),
        None,
    )?;
    let fe_k = LumpedShorthands {
        stiffness: Some(StiffnessSource::Csv(stiffness_csv.clone())),
        ..LumpedShorthands::default()
    };
    sweep(&sub("sweep-fe"), rpm, &fe_k, None)?;
    let stability_rpm: RpmRange = STABILITY_RPM.parse().map_err(anyhow::Error::msg)?;
    stability(
        &sub("stability"),
        &stability_rpm,
        &LumpedShorthands::default(),
    )?;

    announce();
    let plan = if full {
        FeCheckPlan::full()
    } else {
        FeCheckPlan::baseline_and_best()
    };
    let optimize_dir = dir.join("optimize");
    std::fs::create_dir_all(&optimize_dir)?;
    optimize_into(
        &sub("optimize"),
        &OptimizeArgs::default_for_run(),
        &optimize_dir,
        Some((fe_root.clone(), plan)),
    )?;

    announce();
    let high_run = fe_root.join(fe_run_folder(
        &manifest.unmodified_relief,
        study::compare::SPEED_SCENE,
    ));
    let (speeds, runs): (&[f64], Vec<std::path::PathBuf>) = if full {
        (&FULL_COMPARE_RPM, vec![high_run])
    } else {
        (&[], Vec::new())
    };
    compare(
        &sub("compare"),
        speeds,
        &runs,
        (Some(stiffness_csv.as_path()), 16, full),
        None,
    )
}
