//! The `geardyn` command line: parses the arguments, turns the commands' flags into overrides of
//! the case, calls one study of `geardyn::study` and hands its result to `geardyn::report`.

mod args;
mod chain;
mod executor;
mod lumped;
mod optimize;
mod plan;
mod progress;
mod validate;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Parser;

use geardyn::case::{Case, Override, StiffnessSource};
use geardyn::report::{self, OutputDir};
use geardyn::study::{
    self, fe::FeShorthands, lumped::LumpedShorthands, optimize::FeCheckPlan, RpmRange,
};

use args::{Cli, Command, CommonArgs, CompareArgs, OptimizeArgs, ValidationStudy};
use lumped::{lumped_case, stability, sweep};
use optimize::{optimize, optimize_into};
use progress::{fe_run, fe_run_reusing, progress_bar, stage, staged_bar, RunView};
use validate::{
    validate_frequencies, validate_integrators, validate_mass_scaling, validate_pairs,
    validate_properties, validate_quick,
};

/// The exit code of a run stopped on SIGINT or SIGTERM (128 + SIGINT, as shells report it).
const EXIT_INTERRUPTED: u8 = 130;

/// An error and its causes, each cause once: a cause whose text the message before it already
/// carries (our errors print their source inline) is not repeated.
pub fn error_text(error: &anyhow::Error) -> String {
    let mut text = error.to_string();
    for cause in error.chain().skip(1) {
        let cause = cause.to_string();
        if !text.contains(&cause) {
            text.push_str(": ");
            text.push_str(&cause);
        }
    }
    text
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Err(message) = geardyn::explicit::body::Kernel::cap_from_env() {
        eprintln!("error: {message}");
        return ExitCode::FAILURE;
    }
    install_stop_handler();
    if cli.command.common().is_some_and(|c| c.force) {
        geardyn::resources::set_force(true);
    }
    if let Some(common) = cli.command.common() {
        progress::set_checkpoint_every(common.checkpoint_every_s);
    }
    geardyn::resources::set_memory_limit(geardyn::resources::machine_limit());
    geardyn::resources::set_announcer(|message| eprintln!("{message}"));
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
        Command::Fe {
            common,
            options,
            resume,
            reuse,
        } => fe(&common, &options, (resume, reuse)),
        Command::Plan { command } => plan::plan(command),
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
            study: ValidationStudy::Pairs,
            common,
            only,
            fe,
            run,
            ..
        } => validate_pairs(&common, &only, fe, run),
        Command::Validate {
            study: ValidationStudy::Frequencies,
            common,
            model,
            positions,
            ..
        } => validate_frequencies(&common, &model, positions),
        Command::Validate {
            study: ValidationStudy::MassScaling,
            common,
            scene,
            ..
        } => validate_mass_scaling(&common, &scene),
        Command::Compare { common, options } => compare(&common, &options.ask()),
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
        Err(e) if e.downcast_ref::<executor::Submitted>().is_some() => {
            println!("{e}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {}", error_text(&e));
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
    let errors: Vec<String> = result
        .summary
        .self_checks
        .iter()
        .filter(|c| c.is_error())
        .map(|c| c.line())
        .collect();
    anyhow::ensure!(
        errors.is_empty(),
        "the LTCA's self-checks failed (its results are in {} for inspection, not for use):\n{}",
        dir.display(),
        errors.join("\n")
    );
    Ok(())
}

fn fe(args: &CommonArgs, options: &FeShorthands, (resume, reuse): (bool, bool)) -> Result<()> {
    anyhow::ensure!(
        !(resume || reuse) || args.out.is_some(),
        "--resume and --reuse need --out DIR, the run's folder"
    );
    let base = load(args, Vec::new())?;
    let (overrides, scene_name) = study::fe::overrides(&base, options)?;
    let case = load(args, overrides)?;
    let scene = study::fe::scene(&case, &scene_name)?;
    let dir = output_dir(args, &format!("fe-{}", scene.name), &case)?;
    if reuse {
        fe_run_reusing(&case, &scene_name, &dir, &RunView::default())?;
    } else {
        fe_run(&case, scene, &dir, resume, &RunView::default())?;
    }
    println!("wrote {}", dir.display());
    Ok(())
}

impl CompareArgs {
    pub fn ask(&self) -> CompareAsk<'_> {
        CompareAsk {
            speeds: &self.speed_rpm,
            fe_runs: &self.fe_runs,
            fe_stiffness: self.fe_stiffness.as_deref(),
            positions: self.positions,
            paper: self.paper_stiffness,
            chart: self.chart.then_some(&self.chart_fe_runs[..]),
            fe_sweep: self.fe_sweep.clone().map_or_else(Vec::new, |r| r.0),
        }
    }
}

/// What `compare` is asked for besides its case.
pub struct CompareAsk<'a> {
    pub speeds: &'a [f64],
    pub fe_runs: &'a [PathBuf],
    pub fe_stiffness: Option<&'a Path>,
    pub positions: usize,
    pub paper: bool,
    /// The chart's finished stiffness-scene folders (empty: run them), if the chart is asked for.
    pub chart: Option<&'a [PathBuf]>,
    pub fe_sweep: Vec<f64>,
}

impl CompareAsk<'_> {
    /// The sweep's speeds, with the given finished runs on the case's explicit mesh and
    /// compare's own speeds inside its range joining it (a point added near the peak), an
    /// own speed in place of an inner grid speed next to it
    /// ([`study::compare::sweep_speeds_with`]).
    fn sweep_speeds(&self, given_rpm: &[f64]) -> Vec<f64> {
        study::compare::sweep_speeds_with(&self.fe_sweep, self.speeds, given_rpm)
    }

    /// The explicit runs compare makes into `dir` (the speeds not given as finished runs on
    /// the case's explicit mesh at `given_rpm`, the stiffness scene unless given, the chart's
    /// four unless given).
    fn requests(
        &self,
        args: &CommonArgs,
        case: &Case,
        dir: &Path,
        given_rpm: &[f64],
    ) -> Result<Vec<executor::FeRunRequest>> {
        use study::compare as cmp;
        let sweep_speeds = self.sweep_speeds(given_rpm);
        let all_speeds = study::fe_sweep::distinct_speeds(
            self.speeds.iter().chain(&sweep_speeds).copied().collect(),
        );
        let mut requests = Vec::new();
        let in_sweep = |rpm: f64| {
            sweep_speeds
                .iter()
                .any(|r| study::fe_sweep::same_speed(*r, rpm))
        };
        // The sweep's longer runs first, so that two runs side by side end close together.
        let mut to_run = cmp::speeds_to_run(&all_speeds, given_rpm);
        to_run.sort_by_key(|rpm| !in_sweep(*rpm));
        for rpm in to_run {
            // A sweep speed runs long enough for the response near resonance to settle.
            let overrides = match in_sweep(rpm) {
                true => cmp::sweep_speed_overrides(case, rpm),
                false => cmp::speed_overrides(rpm),
            };
            requests.push(executor::FeRunRequest {
                label: format!("compare {rpm:.0} rpm"),
                case: load(args, overrides)?,
                scene: cmp::SPEED_SCENE.to_string(),
                dir: dir.join(format!("fe-{rpm:.0}")),
            });
        }
        if self.fe_stiffness.is_none() {
            requests.push(executor::FeRunRequest {
                label: "compare stiffness".to_string(),
                case: case.clone(),
                scene: cmp::STIFFNESS_SCENE.to_string(),
                dir: dir.join("fe-stiffness"),
            });
        }
        if self.chart.is_some_and(|folders| folders.is_empty()) {
            for (mm, scaled) in study::accuracy::CHART_RUNS {
                let (overrides, name) = study::accuracy::chart_run(mm, scaled);
                requests.push(executor::FeRunRequest {
                    label: format!("chart {name}"),
                    case: load(args, overrides)?,
                    scene: cmp::STIFFNESS_SCENE.to_string(),
                    dir: dir.join(name),
                });
            }
        }
        Ok(requests)
    }
}

/// The finished FE runs given to compare, read.
fn given_fe_runs(fe_runs: &[PathBuf]) -> Result<Vec<study::compare::FeDte>> {
    fe_runs
        .iter()
        .map(|d| report::compare::read_fe_run(d).map_err(anyhow::Error::msg))
        .collect()
}

fn compare(args: &CommonArgs, ask: &CompareAsk) -> Result<()> {
    use study::compare::{self as cmp, CompareInput};
    let case = load(args, Vec::new())?;
    let mut runs = given_fe_runs(ask.fe_runs)?;
    let given_rpm = cmp::given_rpm_on_case_mesh(&case, &runs);
    let fe_sweep = ask.sweep_speeds(&given_rpm);
    // A bad set of given runs is refused before any FE run is made for it: the speed runs, the
    // stiffness file's run (if it comes from one) and the chart's stiffness runs must all be
    // of the case's tooth layout.
    cmp::runs_of_the_case_layout(&case, &runs)?;
    let mut given: Vec<(String, geardyn::mesh::ToothLayout)> = Vec::new();
    if let Some(file) = ask.fe_stiffness {
        if let Some(layout) =
            report::compare::stiffness_file_layout(file).map_err(anyhow::Error::msg)?
        {
            given.push((file.display().to_string(), layout));
        }
    }
    for folder in ask.chart.unwrap_or_default() {
        let layout = report::compare::run_tooth_layout(folder).map_err(anyhow::Error::msg)?;
        given.push((folder.display().to_string(), layout));
    }
    cmp::layouts_of_the_case(&case, given.iter().map(|(s, l)| (s.as_str(), *l)))?;
    // The output folder once the inputs have passed: a refused compare leaves none behind.
    let dir = output_dir(args, "compare", &case)?;
    if !fe_sweep.is_empty() {
        cmp::fe_sweep_runs(&runs, &fe_sweep)?;
    }
    let requests = ask.requests(args, &case, &dir, &given_rpm)?;
    let outcomes = executor::execute(args, &requests, &dir.join("slurm"))?;
    for (request, outcome) in requests.iter().zip(outcomes) {
        outcome.map_err(anyhow::Error::msg)?;
        if request.scene == cmp::SPEED_SCENE {
            runs.push(report::compare::read_fe_run(&request.dir).map_err(anyhow::Error::msg)?);
        }
    }
    // By speed (the sweep's runs were made first): the summary's speeds in ascending order.
    runs.sort_by(|a, b| a.speed_rpm.total_cmp(&b.speed_rpm));
    let stiffness_file = match ask.fe_stiffness {
        Some(file) => file.to_path_buf(),
        None => dir.join("fe-stiffness").join("stiffness.csv"),
    };
    let pitch = case.pair.gears[0].angular_pitch();
    let fe_stiffness = report::stiffness_csv::read_stiffness_csv(&stiffness_file, pitch)
        .map_err(anyhow::Error::msg)?;
    let input = CompareInput {
        fe_runs: runs,
        fe_sweep_rpm: fe_sweep,
        fe_stiffness,
    };
    let bar = staged_bar();
    let summary = cmp::run(&case, &input, ask.positions, ask.paper, &stage(&bar))?;
    bar.finish_and_clear();
    println!(
        "{}",
        report::compare::write(OutputDir(&dir), &case, &summary)?
    );
    if let Some(folders) = ask.chart {
        let primary = cmp::primary_run(&case, &input.fe_runs)
            .context("the chart needs an FE run at speed")?;
        let resonance = cmp::resonance_reference(&case, &summary);
        let folders = match folders.is_empty() {
            true => study::accuracy::CHART_RUNS
                .iter()
                .map(|&(mm, scaled)| dir.join(study::accuracy::chart_run(mm, scaled).1))
                .collect(),
            false => folders.to_vec(),
        };
        accuracy_chart(&case, &folders, (&input.fe_runs[primary], resonance), &dir)?;
    }
    println!("wrote {}", dir.display());
    Ok(())
}

/// The accuracy-versus-cost chart of `compare --chart` from the stiffness-scene `folders`,
/// into `dir`.
fn accuracy_chart(
    case: &Case,
    folders: &[PathBuf],
    (dte_run, resonance): (&study::compare::FeDte, study::accuracy::ResonanceReference),
    dir: &Path,
) -> Result<()> {
    let pitch = case.pair.gears[0].angular_pitch();
    let runs = folders
        .iter()
        .map(|d| report::compare::read_fe_stiffness_run(d, pitch).map_err(anyhow::Error::msg))
        .collect::<Result<Vec<_>>>()?;
    let bar = staged_bar();
    let chart = study::accuracy::run(case, &runs, dte_run, resonance, &stage(&bar))?;
    bar.finish_and_clear();
    print!(
        "{}",
        report::compare::write_accuracy_cost(OutputDir(dir), &chart)?
    );
    Ok(())
}
