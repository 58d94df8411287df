//! The `geardyn` command line: parses the arguments, turns the commands' flags into overrides of
//! the case, calls one study of `geardyn::study` and hands its result to `geardyn::report`.

mod args;
mod chain;
mod progress;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Parser;

use geardyn::case::{Case, Override, StiffnessSource};
use geardyn::report::{self, OutputDir};
use geardyn::study::{
    self, fe::FeShorthands, lumped::LumpedShorthands, optimize::FeCheckPlan, RpmRange,
};

use args::{Cli, Command, CommonArgs, OptimizeArgs, ValidationStudy};
use progress::{fe_check_run, fe_run, fe_run_reusing, progress_bar, stage, staged_bar};

/// The exit code of a run stopped on SIGINT or SIGTERM (128 + SIGINT, as shells report it).
const EXIT_INTERRUPTED: u8 = 130;

fn main() -> ExitCode {
    let cli = Cli::parse();
    install_stop_handler();
    if cli.command.common().is_some_and(|c| c.force) {
        progress::FORCE.store(true, std::sync::atomic::Ordering::Relaxed);
    }
    let result = match cli.command {
        Command::Run {
            common,
            full,
            resume,
        } => chain::run(&common, full, resume),
        Command::Geometry(args) => geometry(&args),
        Command::Mesh { common, relief } => mesh(&common, relief.as_deref()),
        Command::Ltca {
            common,
            torque_nm,
            positions,
            relief,
        } => ltca(&common, torque_nm, positions, relief),
        Command::Sweep {
            common,
            rpm,
            model,
            run_up_s,
            resume,
        } => sweep(&common, rpm, &model, run_up_s, resume),
        Command::Stability { common, rpm, model } => stability(&common, &rpm, &model),
        Command::Fe { common, options } => fe(&common, &options),
        Command::Validate {
            study: ValidationStudy::Quick,
            common,
            ..
        } => validate_quick(&common),
        Command::Validate {
            study: ValidationStudy::Integrators,
            common,
            model,
            ..
        } => validate_integrators(&common, &model),
        Command::Validate {
            study: ValidationStudy::Properties,
            common,
            cases,
            seed,
            ..
        } => validate_properties(&common, cases, seed),
        Command::Validate {
            study: ValidationStudy::MassScaling,
            common,
            scene,
            ..
        } => validate_mass_scaling(&common, &scene),
        Command::Compare {
            common,
            speed_rpm,
            fe_runs,
            fe_stiffness,
            positions,
            paper_stiffness,
            chart,
            chart_fe_runs,
        } => compare(
            &common,
            &speed_rpm,
            &fe_runs,
            (fe_stiffness.as_deref(), positions, paper_stiffness),
            chart.then_some(&chart_fe_runs[..]),
        ),
        Command::Optimize { common, options } => optimize(&common, &options),
        Command::Report { dir } => geardyn::report::run::write(&dir)
            .map(|_| println!("wrote {}", dir.join("index.html").display()))
            .map_err(Into::into),
        Command::Case { case, set } => Case::load_with(case.as_deref(), &set)
            .map(|c| print!("{}", c.text))
            .map_err(Into::into),
    };
    match result {
        Ok(()) if !geardyn::interrupt::stop_requested() => ExitCode::SUCCESS,
        // The command finished its work before it looked at the request: everything is
        // written, but the user asked for a stop and a script should see that.
        Ok(()) => {
            eprintln!("stopped on request after the work was done; every output is complete");
            ExitCode::from(EXIT_INTERRUPTED)
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            if geardyn::interrupt::stop_requested() {
                ExitCode::from(EXIT_INTERRUPTED)
            } else {
                ExitCode::FAILURE
            }
        }
    }
}

/// SIGINT (Ctrl-C) and SIGTERM ask the long loops to stop at their next consistent state and
/// write what they have (every file is written whole, to a temporary name renamed into place);
/// a second signal quits at once.
fn install_stop_handler() {
    let installed = ctrlc::set_handler(|| {
        if geardyn::interrupt::stop_requested() {
            eprintln!("\nsecond stop request: quitting now");
            std::process::exit(EXIT_INTERRUPTED.into());
        }
        geardyn::interrupt::request_stop();
        eprintln!(
            "\nstop requested: finishing the current step and writing what is done \
             (send it again to quit at once)"
        );
    });
    if let Err(e) = installed {
        eprintln!("warning: no stop handler ({e}); Ctrl-C ends the run without writing it");
    }
}

/// The case with the command's shorthands, then the user's `--set`s, applied.
fn load(args: &CommonArgs, shorthands: Vec<Override>) -> Result<Case> {
    let mut overrides = shorthands;
    overrides.extend(args.set.iter().cloned());
    let case = Case::load_with(args.case.as_deref(), &overrides)?;
    for warning in case.warnings() {
        eprintln!("warning: {warning}");
    }
    Ok(case)
}

/// The output folder: the one asked for (created), or a fresh one under out/.
fn output_dir(args: &CommonArgs, command: &str, case: &Case) -> Result<PathBuf> {
    match &args.out {
        Some(dir) => {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create output folder {}", dir.display()))?;
            Ok(dir.clone())
        }
        None => report::fresh_output_dir(Path::new("out"), command, case.name())
            .context("cannot create an output folder under out/"),
    }
}

fn geometry(args: &CommonArgs) -> Result<()> {
    let case = load(args, Vec::new())?;
    let dir = output_dir(args, "geometry", &case)?;
    let summary = study::geometry::GeometrySummary::new(&case);
    print!("{}", summary.table());
    report::geometry::write(OutputDir(&dir), &case, &summary)?;
    println!("\nwrote {}", dir.display());
    Ok(())
}

fn mesh(args: &CommonArgs, relief: Option<&str>) -> Result<()> {
    let case = load(args, Vec::new())?;
    let result = study::mesh::run(&case, relief)?;
    let dir = output_dir(args, "mesh", &case)?;
    print!("{}", report::mesh::console(&result));
    report::mesh::write(OutputDir(&dir), &case, &result)?;
    println!("wrote {}", dir.display());
    Ok(())
}

fn ltca(
    args: &CommonArgs,
    torque_nm: Option<f64>,
    positions: usize,
    relief: Option<String>,
) -> Result<()> {
    let case = load(
        args,
        study::torque_override(torque_nm).into_iter().collect(),
    )?;
    let dir = output_dir(args, "ltca", &case)?;
    let bar = progress_bar("{msg} [{bar:40}] {pos}/{len} positions, ETA {eta}");
    let options = study::ltca::LtcaOptions { positions, relief };
    let result = study::ltca::run(&case, &options, &stage(&bar))?;
    bar.finish_and_clear();
    print!("{}", report::ltca::console(&result));
    report::ltca::write(OutputDir(&dir), &case, &result)?;
    println!("wrote {}", dir.display());
    Ok(())
}

fn optimize(args: &CommonArgs, options: &OptimizeArgs) -> Result<()> {
    let case = load(
        args,
        study::torque_override(options.torque_nm)
            .into_iter()
            .collect(),
    )?;
    let dir = output_dir(args, "optimize", &case)?;
    let fe_check = options
        .fe_check_plan()
        .map(|plan| (dir.join("fe-check"), plan));
    optimize_into(args, options, &dir, fe_check)?;
    println!("wrote {}", dir.display());
    Ok(())
}

/// The relief optimization into `dir`, with the FE cross-check `fe_check` (its runs in
/// FE_ROOT/<candidate>-<scene>; a finished run of the same effective case there is reused; a
/// run that fails is a row with its reason, not the end of the check).
fn optimize_into(
    args: &CommonArgs,
    options: &OptimizeArgs,
    dir: &Path,
    fe_check: Option<(PathBuf, FeCheckPlan)>,
) -> Result<study::optimize::OptimizeStudy> {
    let torque = || study::torque_override(options.torque_nm).into_iter();
    let case = load(args, torque().collect())?;
    let bar = staged_bar();
    let mut result = study::optimize::run(&case, &options.options(), &stage(&bar))?;
    bar.finish_and_clear();
    print!("{}", report::optimize::console(&result));
    report::optimize::write(OutputDir(dir), &case, &result)?;
    if let Some((root, plan)) = fe_check {
        let names: Vec<&str> = result.candidates.iter().map(|c| c.name.as_str()).collect();
        if let Some(unknown) = plan
            .only
            .iter()
            .flatten()
            .find(|n| !names.contains(&n.as_str()))
        {
            anyhow::bail!(
                "--fe-check-only {unknown:?} is not a candidate; the candidates are {names:?}"
            );
        }
        let mut runs = Vec::new();
        for candidate in &result.candidates {
            if !plan.includes(candidate) {
                runs.push(None);
                continue;
            }
            let mut overrides: Vec<Override> = torque().collect();
            overrides.extend(study::optimize::fe_check_overrides(&case, candidate)?);
            let with_relief = load(args, overrides)?;
            let mut scene_runs = [None, None];
            for (s, name) in study::optimize::FE_CHECK_SCENES.iter().enumerate() {
                if plan.scenes[s] {
                    let out = root.join(format!("{}-{name}", candidate.name));
                    scene_runs[s] = Some(fe_check_run(&with_relief, name, &out));
                    if geardyn::interrupt::stop_requested() {
                        let message = format!(
                            "the FE cross-check was interrupted in {}; its finished runs in {} are taken as they are by the next run with the same --out",
                            out.display(),
                            root.display()
                        );
                        result.summary.interrupted = Some(message.clone());
                        OutputDir(dir).json("summary.json", &result.summary)?;
                        anyhow::bail!(message);
                    }
                }
            }
            runs.push(Some(scene_runs));
        }
        let rb2 = case.pair.gears[1].base_radius;
        let check = study::optimize::fe_check(&result, &runs, rb2);
        print!(
            "{}",
            report::optimize::write_fe_check(OutputDir(dir), &check)?
        );
        result.summary.fe_check = Some(check);
        OutputDir(dir).json("summary.json", &result.summary)?;
    }
    let failures: Vec<String> = result
        .summary
        .starts
        .iter()
        .filter_map(|s| {
            let failure = s.failure.as_ref()?;
            Some(format!("{} from {}: {failure}", s.shape.name(), s.start))
        })
        .collect();
    if !failures.is_empty() {
        anyhow::bail!(
            "the optimizer stopped early in {} of {} starts ({}); each keeps its last good design \
             and every output is written to {}. The cause is numerical: refine the LTCA \
             (mesh.fine_element_mm, --positions) or narrow the search (--max-relief-um)",
            failures.len(),
            result.summary.starts.len(),
            failures.join("; "),
            dir.display()
        );
    }
    Ok(result)
}

/// The case with the lumped flags applied.
fn lumped_case(args: &CommonArgs, options: &LumpedShorthands) -> Result<Case> {
    let case = load(args, options.overrides()?)?;
    if case.lumped.stiffness == StiffnessSource::Ltca {
        eprintln!("computing the LTCA stiffness ...");
    }
    Ok(case)
}

fn sweep(
    args: &CommonArgs,
    rpm: RpmRange,
    options: &LumpedShorthands,
    run_up_s: Option<f64>,
    resume: bool,
) -> Result<()> {
    let case = lumped_case(args, options)?;
    let checkpoint_file = "sweep_checkpoint.json";
    let resume = match (&args.out, resume) {
        (None, true) => anyhow::bail!("--resume needs --out DIR, the interrupted sweep's folder"),
        (Some(dir), true) => {
            let path = dir.join(checkpoint_file);
            let text = std::fs::read_to_string(&path).with_context(|| {
                format!(
                    "cannot read {}: is {} an interrupted sweep's folder?",
                    path.display(),
                    dir.display()
                )
            })?;
            let checkpoint: study::sweep::SweepCheckpoint = serde_json::from_str(&text)
                .with_context(|| format!("{} is not a sweep checkpoint", path.display()))?;
            eprintln!("resuming: {}", checkpoint.describe());
            Some(checkpoint)
        }
        (_, false) => None,
    };
    let options = study::sweep::SweepOptions {
        rpm,
        run_up_s,
        resume,
    };
    eprintln!(
        "sweeping {} speeds up and down (Ctrl-C stops and keeps the points for --resume) ...",
        options.rpm.0.len()
    );
    let outcome = study::sweep::run(&case, &options)?;
    let dir = output_dir(args, "sweep", &case)?;
    let out = OutputDir(&dir);
    let result = match outcome {
        study::sweep::SweepRun::Done(result) => result,
        study::sweep::SweepRun::Interrupted(checkpoint) => {
            let message = checkpoint.describe();
            out.case(&case)?;
            out.json(checkpoint_file, &checkpoint)?;
            out.json(
                "summary.json",
                &study::StoppedEarly {
                    case: case.name().to_string(),
                    command: "sweep".into(),
                    interrupted: Some(message.clone()),
                    diverged: None,
                    resume: Some(format!(
                        "geardyn sweep ... --resume --out {} (the same case, --set and --rpm)",
                        dir.display()
                    )),
                },
            )?;
            anyhow::bail!(
                "sweep {message}; its points are kept in {}: add --resume --out {} to continue",
                dir.join(checkpoint_file).display(),
                dir.display()
            );
        }
        study::sweep::SweepRun::Diverged(checkpoint) => {
            let divergence = checkpoint.progress.diverged.as_ref().expect("diverged");
            let message = format!("{divergence}; {}", checkpoint.describe());
            out.case(&case)?;
            out.json(checkpoint_file, &checkpoint)?;
            out.json(
                "summary.json",
                &study::StoppedEarly {
                    case: case.name().to_string(),
                    command: "sweep".into(),
                    interrupted: None,
                    diverged: Some(message.clone()),
                    resume: None,
                },
            )?;
            anyhow::bail!(
                "{message}. The points swept before it are in {}",
                dir.join(checkpoint_file).display()
            );
        }
    };
    print!("{}", report::lumped::setup_console(&result.setup));
    report::lumped::write_sweep(out, &case, &result)?;
    out.remove(checkpoint_file)?;
    print!("{}", report::lumped::sweep_console(&result));
    println!("wrote {}", dir.display());
    if let Some(message) = &result.summary.run_up_diverged {
        anyhow::bail!("{message}");
    }
    Ok(())
}

fn stability(args: &CommonArgs, rpm: &RpmRange, options: &LumpedShorthands) -> Result<()> {
    let case = lumped_case(args, options)?;
    let result = study::stability::run(&case, rpm)?;
    print!("{}", report::lumped::setup_console(&result.setup));
    let dir = output_dir(args, "stability", &case)?;
    report::lumped::write_stability(OutputDir(&dir), &case, &result)?;
    print!("{}", report::lumped::stability_console(&result));
    println!("wrote {}", dir.display());
    Ok(())
}

fn validate_quick(args: &CommonArgs) -> Result<()> {
    let case = load(args, Vec::new())?;
    let dir = output_dir(args, "validate-quick", &case)?;
    let bar = staged_bar();
    let result = study::quick_validation::run(&case, &stage(&bar))?;
    bar.finish_and_clear();
    print!(
        "{}",
        report::quick_validation::write(OutputDir(&dir), &result)?
    );
    println!("wrote {}", dir.display());
    if result.failed > 0 {
        anyhow::bail!(
            "{} of {} validation checks broke their tolerance (checks.md in {})",
            result.failed,
            result.checks.len(),
            dir.display()
        );
    }
    Ok(())
}

fn validate_properties(args: &CommonArgs, cases: usize, seed: u64) -> Result<()> {
    let case = load(args, Vec::new())?;
    if args.case.is_some() || !args.set.is_empty() {
        anyhow::bail!(
            "validate properties generates its cases from the embedded one: give no case file or --set"
        );
    }
    let dir = output_dir(args, "validate-properties", &case)?;
    let bar = staged_bar();
    // The samples' panics are caught and counted; their messages would only interleave.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let result = study::properties::run(cases, seed, &stage(&bar));
    std::panic::set_hook(hook);
    bar.finish_and_clear();
    OutputDir(&dir).json("summary.json", &result)?;
    println!(
        "{} generated cases in {:.0} s: {} valid, {} rejected with the parameter named; {} rejected \
         without it, {} with a NaN or infinite output, {} panicked; plausible-only cases valid: \
         {:.1} % of {}",
        result.cases,
        result.wall_s,
        result.valid,
        result.rejected,
        result.unnamed,
        result.not_finite,
        result.panicked,
        100.0 * result.plausible_valid_share,
        result.plausible_cases
    );
    for failure in &result.failures {
        println!(
            "  #{} {:?}: {:?}",
            failure.index, failure.changes, failure.outcome
        );
    }
    println!("wrote {}", dir.display());
    if !result.passed() {
        anyhow::bail!("the property check failed (failures above and in summary.json)");
    }
    Ok(())
}

fn validate_integrators(args: &CommonArgs, options: &LumpedShorthands) -> Result<()> {
    let case = lumped_case(args, options)?;
    let summary = study::validate::integrators(&case)?;
    let dir = output_dir(args, "validate-integrators", &case)?;
    print!(
        "{}",
        report::lumped::write_integrators(OutputDir(&dir), &summary)?
    );
    println!("wrote {}", dir.display());
    Ok(())
}

fn validate_mass_scaling(args: &CommonArgs, scene: &str) -> Result<()> {
    let scaled = load(args, Vec::new())?;
    let unscaled = load(args, vec![Override::set("fe.mass_scaling", false)])?;
    let dir = output_dir(args, "validate-mass-scaling", &scaled)?;
    let mut runs = Vec::new();
    for (case, name) in [(&scaled, "scaled"), (&unscaled, "unscaled")] {
        let out = dir.join(name);
        runs.push(fe_run(case, study::fe::scene(case, scene)?, &out)?);
        study::validate::check_scaled(&runs[0])?;
    }
    let result = study::validate::mass_scaling(scaled.name(), &scaled.pair, &runs[0], &runs[1])?;
    let table = report::fe::write_mass_scaling(OutputDir(&dir), &scaled, &result)?;
    println!("{table}wrote {}", dir.display());
    Ok(())
}

fn fe(args: &CommonArgs, options: &FeShorthands) -> Result<()> {
    let base = load(args, Vec::new())?;
    let (overrides, scene_name) = study::fe::overrides(&base, options)?;
    let case = load(args, overrides)?;
    let scene = study::fe::scene(&case, &scene_name)?;
    let dir = output_dir(args, &format!("fe-{}", scene.name), &case)?;
    fe_run(&case, scene, &dir)?;
    println!("wrote {}", dir.display());
    Ok(())
}

fn compare(
    args: &CommonArgs,
    speeds: &[f64],
    fe_runs: &[PathBuf],
    (fe_stiffness, positions, paper): (Option<&Path>, usize, bool),
    chart: Option<&[PathBuf]>,
) -> Result<()> {
    use study::compare::{self as cmp, CompareInput};
    let case = load(args, Vec::new())?;
    let dir = output_dir(args, "compare", &case)?;
    let read = |d: &Path| report::compare::read_fe_run(d).map_err(anyhow::Error::msg);
    let mut runs = fe_runs
        .iter()
        .map(|d| read(d))
        .collect::<Result<Vec<_>>>()?;
    for rpm in cmp::speeds_to_run(speeds, &runs) {
        let at_speed = load(args, cmp::speed_overrides(rpm))?;
        let out = dir.join(format!("fe-{rpm:.0}"));
        fe_run_reusing(&at_speed, cmp::SPEED_SCENE, &out)?;
        runs.push(read(&out)?);
    }
    let stiffness_file = match fe_stiffness {
        Some(file) => file.to_path_buf(),
        None => {
            let out = dir.join("fe-stiffness");
            fe_run(&case, study::fe::scene(&case, cmp::STIFFNESS_SCENE)?, &out)?;
            out.join("stiffness.csv")
        }
    };
    let pitch = case.pair.gears[0].angular_pitch();
    let fe_stiffness = report::stiffness_csv::read_stiffness_csv(&stiffness_file, pitch)
        .map_err(anyhow::Error::msg)?;
    let input = CompareInput {
        fe_runs: runs,
        fe_stiffness,
    };
    let bar = staged_bar();
    let summary = cmp::run(&case, &input, positions, paper, &stage(&bar))?;
    bar.finish_and_clear();
    println!(
        "{}",
        report::compare::write(OutputDir(&dir), &case, &summary)?
    );
    if let Some(folders) = chart {
        let primary = cmp::primary_run(&case, &input.fe_runs)
            .context("the chart needs an FE run at speed")?;
        accuracy_chart(args, &case, folders, &input.fe_runs[primary], &dir)?;
    }
    println!("wrote {}", dir.display());
    Ok(())
}

/// The accuracy-versus-cost chart of `compare --chart`, into `dir`.
fn accuracy_chart(
    args: &CommonArgs,
    case: &Case,
    folders: &[PathBuf],
    dte_run: &study::compare::FeDte,
    dir: &Path,
) -> Result<()> {
    let mut folders = folders.to_vec();
    if folders.is_empty() {
        for (mm, scaled) in study::accuracy::CHART_RUNS {
            let (overrides, name) = study::accuracy::chart_run(mm, scaled);
            let at_level = load(args, overrides)?;
            let scene = study::fe::scene(&at_level, study::compare::STIFFNESS_SCENE)?;
            fe_run(&at_level, scene, &dir.join(&name))?;
            folders.push(dir.join(name));
        }
    }
    let pitch = case.pair.gears[0].angular_pitch();
    let runs = folders
        .iter()
        .map(|d| report::compare::read_fe_stiffness_run(d, pitch).map_err(anyhow::Error::msg))
        .collect::<Result<Vec<_>>>()?;
    let bar = staged_bar();
    let chart = study::accuracy::run(case, &runs, dte_run, &stage(&bar))?;
    bar.finish_and_clear();
    print!(
        "{}",
        report::compare::write_accuracy_cost(OutputDir(dir), &chart)?
    );
    Ok(())
}
