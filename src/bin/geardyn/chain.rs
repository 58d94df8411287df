//! `geardyn run`: the mission's chain on one case, each stage in its own sub-folder of one
//! output folder — geometry, LTCA, the relief optimization with its explicit-FE cross-check,
//! the explicit FE's k(θ) from a low-speed DTE against the LTCA's, rpm sweeps on both
//! stiffnesses and the stability map, FE against lumped frequencies.
//!
//! The explicit runs live in DIR/fe/<relief>-<scene>; a finished run of the same effective case
//! is reused, so the unmodified stiffness run serves the FE stiffness stage, the cross-check's
//! baseline and the frequency comparison, and an interrupted `run` resumes its FE stages.

use std::path::Path;

use anyhow::{Context, Result};

use geardyn::case::StiffnessSource;
use geardyn::report::run::RunManifest;
use geardyn::report::OutputDir;
use geardyn::study::optimize::fe_run_folder;
use geardyn::study::{self, lumped::LumpedShorthands};

use super::args::{CommonArgs, OptimizeArgs};
use super::progress::{folder_verdict, run_state, RunState};
use super::{compare, geometry, load, ltca, mesh, optimize_into, output_dir, stability, sweep};
use geardyn::report;

/// The stages' own folders (the explicit runs live in fe/ and are kept).
const STAGE_FOLDERS: [&str; 9] = [
    "geometry",
    "mesh",
    "ltca",
    "sweep-ltca",
    "sweep-fe",
    "stability",
    "optimize",
    "compare",
    "tables",
];

pub fn run(args: &CommonArgs, full: bool, resume: bool) -> Result<()> {
    let case = load(args, Vec::new())?;
    // --resume takes the folder of an earlier run, with its --full.
    let full = match (&args.out, resume) {
        (None, true) => anyhow::bail!("--resume needs --out DIR, the interrupted run's folder"),
        (Some(dir), true) => {
            let path = dir.join("run.json");
            let earlier: RunManifest = std::fs::read_to_string(&path)
                .ok()
                .and_then(|text| serde_json::from_str(&text).ok())
                .with_context(|| {
                    format!(
                        "{} is not a `geardyn run` folder (no readable run.json)",
                        dir.display()
                    )
                })?;
            if !earlier
                .case_text
                .as_deref()
                .is_some_and(|t| case.is_same_case(t))
            {
                anyhow::bail!(
                    "{} holds a run of another case (or other --set values): resume it with the \
                     case it ran, or start a new run with another --out",
                    dir.display()
                );
            }
            eprintln!(
                "resuming the run in {}: finished explicit FE runs of the same case are taken \
                 as they are, the other stages (seconds each) run again",
                dir.display()
            );
            full || earlier.full
        }
        (_, false) => full,
    };
    let dir = output_dir(args, "run", &case)?;
    let started = std::time::Instant::now();
    let unmodified = study::unmodified_name(&case);
    // The report finds the stages through this manifest (and is written even when a stage
    // fails, with what the stages before it left).
    let mut manifest = RunManifest {
        unmodified_relief: unmodified.clone(),
        fe_stiffness_run: format!(
            "fe/{}",
            fe_run_folder(&unmodified, study::compare::STIFFNESS_SCENE)
        ),
        full,
        interrupted: None,
        failed: None,
        case_text: Some(case.text.clone()),
    };
    // Every stage but the explicit runs (which carry and check their own case) starts from an
    // empty folder, so the report never shows a stage an earlier run left.
    for stage in STAGE_FOLDERS {
        clear_stage(&dir.join(stage))?;
    }
    for file in ["summary.json", "report.md", "index.html"] {
        OutputDir(&dir).remove(file)?;
    }
    OutputDir(&dir).json("run.json", &manifest)?;
    let plan = study::run::RunPlan::new(full);
    let mut reached = 0;
    let result = stages(args, &case, &dir, (&manifest, &plan), started, &mut reached);
    if let Err(e) = &result {
        if let Some(submitted) = e.downcast_ref::<super::executor::Submitted>() {
            manifest.interrupted = Some(format!(
                "stage {reached}/{} waits for its explicit FE runs: {submitted}; `geardyn run \
                 --resume --out {} --executor slurm` goes on once they are done",
                study::run::STAGES.len(),
                dir.display()
            ));
            OutputDir(&dir).json("run.json", &manifest)?;
        } else if geardyn::interrupt::stop_requested() {
            let stages = study::run::STAGES;
            manifest.interrupted = Some(format!(
                "interrupted in stage {reached}/{} ({}): {}. `geardyn run --resume --out {}` continues it, taking the finished explicit FE runs as they are",
                stages.len(),
                stages[reached.max(1) - 1],
                super::error_text(e),
                dir.display()
            ));
            OutputDir(&dir).json("run.json", &manifest)?;
        } else {
            let stages = study::run::STAGES;
            manifest.failed = Some(match e.downcast_ref::<StageFailed>() {
                Some(failed) => failed.to_string(),
                None => format!(
                    "stage {reached}/{} ({}) failed: {}",
                    stages.len(),
                    stages[reached.max(1) - 1],
                    super::error_text(e)
                ),
            });
            OutputDir(&dir).json("run.json", &manifest)?;
        }
    }
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

/// Empties a stage's folder, except the explicit runs the compare stage makes in it (`fe-*`,
/// `chart-fe-*`, which carry and check their own case) and the Slurm executor's record of them
/// (`slurm/`): a resumed run takes them as they are, or waits for them while still queued.
fn clear_stage(stage: &Path) -> Result<()> {
    let entries = match std::fs::read_dir(stage) {
        Ok(entries) => entries,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(e).with_context(|| format!("cannot clear {}", stage.display())),
    };
    for entry in entries {
        let path = entry?.path();
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
        let kept = path.is_dir()
            && name.is_some_and(|n| {
                n.starts_with("fe-") || n.starts_with("chart-fe-") || n == "slurm"
            });
        let removed = match (kept, path.is_dir()) {
            (true, _) => Ok(()),
            (false, true) => std::fs::remove_dir_all(&path),
            (false, false) => std::fs::remove_file(&path),
        };
        removed.with_context(|| format!("cannot clear {}", path.display()))?;
    }
    Ok(())
}

/// A sweep that diverged has written its points up to there and its summary says where and
/// why: the chain goes on (the report names the divergence); any other failure stops it.
fn keeping_divergence(dir: &Path, outcome: Result<()>) -> Result<()> {
    let Err(error) = outcome else {
        return Ok(());
    };
    let diverged = std::fs::read_to_string(dir.join("summary.json"))
        .ok()
        .and_then(|text| serde_json::from_str::<study::StoppedEarly>(&text).ok())
        .and_then(|stopped| stopped.diverged);
    match diverged {
        Some(message) => {
            eprintln!(
                "warning: {message}; the chain goes on, the report names the divergence ({})",
                dir.display()
            );
            Ok(())
        }
        None => Err(error),
    }
}

fn stages(
    args: &CommonArgs,
    case: &geardyn::case::Case,
    dir: &Path,
    (manifest, plan): (&RunManifest, &study::run::RunPlan),
    started: std::time::Instant,
    reached: &mut usize,
) -> Result<()> {
    let sub = |name: &str| CommonArgs {
        out: Some(dir.join(name)),
        ..args.clone()
    };
    // The LTCA, its sweep and the stability map are of the unmodified pair (added to the case
    // when it has none), whatever the case's first variant is.
    let unmodified = |name: &str| {
        let mut with = sub(name);
        with.set
            .extend(study::optimize::unmodified_fe_overrides(case));
        with.set.push(geardyn::case::Override::set(
            "lumped.relief",
            manifest.unmodified_relief.clone(),
        ));
        with
    };
    let stages = study::run::STAGES;
    // Each stage begins by checking for a stop request: a stage that polls none (seconds
    // long) finishes, and the run stops before the next.
    let mut announce = || -> Result<()> {
        if geardyn::interrupt::stop_requested() {
            anyhow::bail!("stopped on request after stage {}", *reached);
        }
        *reached += 1;
        println!(
            "\n== {}/{} {} ({:.0} s so far)",
            *reached,
            stages.len(),
            stages[*reached - 1],
            started.elapsed().as_secs_f64()
        );
        Ok(())
    };

    announce()?;
    geometry(&sub("geometry"))?;
    mesh(&sub("mesh"), None)?;
    announce()?;
    ltca(&unmodified("ltca"), None, plan.ltca_positions, None)?;

    announce()?;
    // The relief cross-check before the FE stiffness stage: its explicit runs (the unmodified
    // pair's stiffness run, which that stage takes as it is, and the optimum's) then run side by
    // side, one thread each (executor::local), instead of one after the other on both.
    let fe_root = dir.join("fe");
    let optimize_dir = dir.join("optimize");
    std::fs::create_dir_all(&optimize_dir)?;
    let relief = optimize_into(
        &sub("optimize"),
        &OptimizeArgs::default_for_run(),
        &optimize_dir,
        Some((fe_root.clone(), plan.fe_check.clone())),
    );
    // A failed relief stage does not cost the stages after it, which do not need it; a stop
    // request or a submitted array stops the chain here.
    let relief_failed = match relief {
        Ok(_) => None,
        Err(e)
            if geardyn::interrupt::stop_requested()
                || e.downcast_ref::<super::executor::Submitted>().is_some() =>
        {
            return Err(e)
        }
        Err(e) => {
            let failed = StageFailed {
                stage: RELIEF_STAGE,
                message: super::error_text(&e),
            };
            eprintln!("warning: {failed}; the chain goes on and reports it at the end");
            Some(failed)
        }
    };

    announce()?;
    // The unmodified pair's runs are the cross-check's baseline runs: one effective case.
    let unmodified_case = load(args, study::optimize::unmodified_fe_overrides(case))?;
    let stiffness_run = dir.join(&manifest.fe_stiffness_run);
    // A failed run the cross-check left is its verdict here too, not a reason to run it again;
    // an interrupted one (the relief stage failed before its cross-check) goes on.
    let interrupted = run_state(&unmodified_case, &stiffness_run) == RunState::Interrupted;
    let outcome = match folder_verdict(&unmodified_case, &stiffness_run) {
        Some(Err(failed)) if !interrupted => Err(failed),
        _ => {
            let request = stiffness_request(unmodified_case, &stiffness_run);
            super::executor::execute(args, &[request], &fe_root.join("slurm"))?
                .into_iter()
                .next()
                .expect("one outcome per run")
        }
    };
    outcome
        .and_then(|_| report::optimize::read_fe_check_run(&stiffness_run).map(|_| ()))
        .map_err(anyhow::Error::msg)?;
    let stiffness_csv = stiffness_run.join("stiffness.csv");

    announce()?;
    let rpm = plan.sweep_rpm.clone();
    // A summary left by an earlier attempt must not speak for this one.
    for folder in ["sweep-ltca", "sweep-fe"] {
        match std::fs::remove_file(dir.join(folder).join("summary.json")) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(e.into()),
            _ => {}
        }
    }
    keeping_divergence(
        &dir.join("sweep-ltca"),
        sweep(
            &unmodified("sweep-ltca"),
            rpm.clone(),
            &LumpedShorthands::default(),
            None,
            false,
        ),
    )?;
    let fe_k = LumpedShorthands {
        stiffness: Some(StiffnessSource::Csv(stiffness_csv.clone())),
        ..LumpedShorthands::default()
    };
    keeping_divergence(
        &dir.join("sweep-fe"),
        sweep(&sub("sweep-fe"), rpm, &fe_k, None, false),
    )?;
    stability(
        &unmodified("stability"),
        &plan.stability_rpm,
        &LumpedShorthands::default(),
    )?;

    announce()?;
    let high_run = fe_root.join(fe_run_folder(
        &manifest.unmodified_relief,
        study::compare::SPEED_SCENE,
    ));
    let runs: Vec<std::path::PathBuf> = plan
        .compare_high_speed_run
        .then_some(high_run)
        .into_iter()
        .collect();
    compare(
        &sub("compare"),
        &compare_ask(case, plan, &runs, &stiffness_csv)?,
    )?;
    relief_failed.map_or(Ok(()), |failed| Err(failed.into()))
}

/// The relief stage's number (1-based) in [`study::run::STAGES`].
const RELIEF_STAGE: usize = 3;

/// A stage that failed and that the chain went past, the stages after it not needing it.
#[derive(Debug, thiserror::Error)]
#[error(
    "stage {stage}/{} ({}) failed: {message}; the stages after it ran",
    study::run::STAGES.len(),
    study::run::STAGES[stage - 1]
)]
struct StageFailed {
    stage: usize,
    message: String,
}

/// The unmodified pair's stiffness scene into `dir`: the chain's FE stiffness stage.
pub fn stiffness_request(
    unmodified_case: geardyn::case::Case,
    dir: &Path,
) -> super::executor::FeRunRequest {
    super::executor::FeRunRequest {
        label: "FE stiffness (unmodified)".to_string(),
        case: unmodified_case,
        scene: study::compare::STIFFNESS_SCENE.to_string(),
        dir: dir.to_path_buf(),
    }
}

/// The chain's comparison stage: `plan`'s speeds and sweep, the cross-check's high-speed run
/// `runs` and the FE stiffness stage's k(θ).
pub fn compare_ask<'a>(
    case: &geardyn::case::Case,
    plan: &'a study::run::RunPlan,
    runs: &'a [std::path::PathBuf],
    stiffness_csv: &'a Path,
) -> Result<super::CompareAsk<'a>> {
    Ok(super::CompareAsk {
        speeds: &plan.compare_speeds_rpm,
        fe_runs: runs,
        fe_stiffness: Some(stiffness_csv),
        positions: plan.modal_positions,
        paper: plan.paper_stiffness,
        chart: None,
        fe_sweep: match plan.fe_sweep {
            true => study::compare::fe_sweep_speeds(case)?,
            false => Vec::new(),
        },
    })
}

#[cfg(test)]
mod tests {
    /// The number the chain names the relief stage by is that stage's.
    #[test]
    fn the_relief_stage_number_is_the_relief_stage() {
        let name = geardyn::study::run::STAGES[super::RELIEF_STAGE - 1];
        assert!(name.starts_with("relief optimization"), "{name}");
    }
}
