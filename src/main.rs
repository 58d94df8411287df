//! The `geardyn` command line: parses the arguments, turns the commands' flags into overrides of
//! the case, calls one study of `geardyn::study` and hands its result to `geardyn::report`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};

use geardyn::case::{Case, Override, StiffnessSource};
use geardyn::explicit::scene::Scene;
use geardyn::report::{self, OutputDir};
use geardyn::study::{self, fe::FeShorthands, lumped::LumpedShorthands, RpmRange};

/// Spur-gear mesh dynamics: exact geometry, loaded contact, explicit dynamics, lumped sweeps.
///
/// Every command takes an optional case file (TOML); without one it runs the embedded default
/// case, the seed paper's pair (Z1 = Z2 = 36, m = 3.18 mm, alpha = 20 deg, B = 25.4 mm).
/// `--set KEY=VALUE` changes any value of the case before it is checked (e.g. `--set
/// fe.plane=stress --set mesh.fine_element_mm=0.5`); the commands' own flags are shorthands for
/// it. Outputs go to a fresh folder under out/ unless --out is given; each holds the effective
/// case as case.toml.
#[derive(Parser)]
#[command(name = "geardyn", version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// The whole pipeline built so far on one case: geometry, meshes, LTCA (every relief
    /// variant) and the lumped speed sweep on the LTCA stiffness, each in its own sub-folder of
    /// one output folder.
    Run(CommonArgs),
    /// Derived geometry of the pair: radii, contact ratio, line of action, contact points,
    /// backlash, resolved reliefs; writes summary.json, a drawing (SVG, PNG) and profile CSVs.
    Geometry(CommonArgs),
    /// FE meshes of both gears (8-node quadrilaterals, fine on the teeth that engage at the mesh
    /// position): writes mesh_gear{1,2}.vtk (ParaView, meshio) and mesh_gear{1,2}.png, and
    /// prints element and node counts.
    Mesh {
        #[command(flatten)]
        common: CommonArgs,
        /// Relief variant of the case to mesh; default: the first one.
        #[arg(long, value_name = "NAME")]
        relief: Option<String>,
    },
    /// Quasi-static loaded tooth contact analysis over one base pitch for every relief variant
    /// (or the one named): static transmission error, load sharing and the mesh stiffness k(θ),
    /// next to ISO 6336-1 method B. Writes ltca_<variant>.csv, ste/stiffness/load-sharing plots
    /// (SVG, PNG) and summary.json.
    Ltca {
        #[command(flatten)]
        common: CommonArgs,
        /// Load torque on the driven gear [N·m] (sets operating_point[0].torque_nm).
        #[arg(long, value_name = "T", allow_negative_numbers = true)]
        torque_nm: Option<f64>,
        /// Mesh positions over one base pitch.
        #[arg(long, default_value_t = 64, value_name = "N")]
        positions: usize,
        /// Only this relief variant; default: every variant of the case.
        #[arg(long, value_name = "NAME")]
        relief: Option<String>,
    },
    /// Speed sweep of the lumped mesh model driven by the mesh stiffness k(θ): periodic steady
    /// state per driver speed (up- and down-sweep), DTE rms and peak-to-peak, dynamic factor,
    /// separation, mesh-harmonic amplitudes, Floquet stability. Writes sweep.csv, plots and
    /// summary.json.
    Sweep {
        #[command(flatten)]
        common: CommonArgs,
        /// Driver speeds FROM:TO:N in rpm.
        #[arg(long, default_value = "100:12000:600", value_name = "FROM:TO:N")]
        rpm: RpmRange,
        #[command(flatten)]
        model: LumpedShorthands,
        /// Also run up through the same speed range in this many seconds (a linear speed ramp,
        /// transient): writes runup.csv and runup.png.
        #[arg(long, value_name = "SECONDS")]
        run_up_s: Option<f64>,
    },
    /// Floquet stability map of the linear time-periodic mesh model over a speed range: the
    /// largest multiplier of the monodromy matrix per driver speed (> 1: parametric
    /// instability, near f_mesh ≈ 2 f_n / j). Writes stability.csv, a plot and summary.json.
    Stability {
        #[command(flatten)]
        common: CommonArgs,
        /// Driver speeds FROM:TO:N in rpm.
        #[arg(long, default_value = "100:20000:2000", value_name = "FROM:TO:N")]
        rpm: RpmRange,
        #[command(flatten)]
        model: LumpedShorthands,
    },
    /// Explicit dynamic contact FE of the meshing pair (central difference, penalty contact with
    /// Coulomb friction, corotational bodies on rigid hubs): a scene of the case, or a speed and
    /// a duration. Writes history.csv (DTE, speeds, contact forces, db5 impacts, energy),
    /// dte_spectrum.csv, stiffness.csv (k from the DTE, readable by sweep --stiffness), plots
    /// and summary.json; a diverged run keeps what it computed and says why.
    Fe {
        #[command(flatten)]
        common: CommonArgs,
        #[command(flatten)]
        options: FeShorthands,
    },
    /// FE versus lumped: the mesh-mode frequency by every method (lumped sqrt(k/m) with k from
    /// the LTCA and the FE DTE, Floquet, FE modal analysis of the meshed pair) for both boundary
    /// conditions (driver held, both free), and the explicit FE's DTE spectra against the lumped
    /// model's at each FE speed (labelled peaks, early vs late window, first three mesh
    /// harmonics). Writes summary.json, frequencies/modal/harmonics/peaks CSVs, spectra plots
    /// and table.md.
    Compare {
        #[command(flatten)]
        common: CommonArgs,
        /// Explicit FE runs to make: scene high-unmodified at these driver speeds [rpm], into
        /// DIR/fe-<rpm> (skipped for speeds given by --fe-run).
        #[arg(
            long,
            value_delimiter = ',',
            default_value = "1200,3000,4800",
            value_name = "RPM"
        )]
        speed_rpm: Vec<f64>,
        /// Finished `geardyn fe` output folders to use instead of running their speeds
        /// (repeatable).
        #[arg(long = "fe-run", value_name = "DIR")]
        fe_runs: Vec<PathBuf>,
        /// k(θ) from the FE DTE (stiffness.csv of `geardyn fe --scene stiffness`); default: run
        /// that scene into DIR/fe-stiffness.
        #[arg(long, value_name = "FILE")]
        fe_stiffness: Option<PathBuf>,
        /// Mesh positions over one base pitch for the FE modal analysis.
        #[arg(long, default_value_t = 16, value_name = "N")]
        positions: usize,
        /// Also the labelled paper-stiffness study: the lumped model given the seed paper's
        /// mean stiffness (1.3427e8 N/m, by a compliance in series), never a default.
        #[arg(long)]
        paper_stiffness: bool,
        /// Also the accuracy-versus-cost chart (accuracy_cost.{csv,md,png,svg}): LTCA at three
        /// mesh levels, ISO, potential energy and explicit FE stiffness runs, against the finest
        /// unscaled FE run and the primary FE run's DTE (the one nearest 3000 rpm).
        #[arg(long)]
        chart: bool,
        /// Finished stiffness-scene folders for the chart (repeatable); default: run the
        /// stiffness scene at 1.0 and 0.7 mm flanks, scaled and unscaled, into DIR/chart-fe-*.
        #[arg(long = "chart-fe-run", value_name = "DIR")]
        chart_fe_runs: Vec<PathBuf>,
    },
    /// Validation studies too wide for the test suite; each writes a table (CSV and Markdown)
    /// and summary.json.
    Validate {
        #[arg(value_enum, value_name = "STUDY")]
        study: ValidationStudy,
        #[command(flatten)]
        common: CommonArgs,
        #[command(flatten)]
        model: LumpedShorthands,
        /// The explicit FE scene of `mass-scaling` (default: stiffness).
        #[arg(long, value_name = "NAME", default_value = "stiffness")]
        scene: String,
    },
    /// Prints a case file: the given one, or the embedded default (start your own from it:
    /// `geardyn case > my.toml`); with --set, the effective case.
    Case {
        /// Case file to check and print; default: the embedded paper36 case.
        case: Option<PathBuf>,
        /// Change a value of the case, as in the other commands.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<Override>,
    },
}

#[derive(Clone, Copy, ValueEnum)]
enum ValidationStudy {
    /// Where each fixed-step scheme of the lumped model fails: stability and 1 %
    /// frequency-accuracy limits in ωh, predicted vs observed, and the order of convergence
    /// with and without tooth separation.
    Integrators,
    /// The explicit FE's low-speed mass scaling against the same scene unscaled (--scene):
    /// DTE mean and peak-to-peak, k(θ) bin by bin, the cost of each.
    MassScaling,
}

#[derive(Args, Clone)]
struct CommonArgs {
    /// Case file (TOML). Default: the embedded paper36 case.
    case: Option<PathBuf>,
    /// Output folder. Default: a fresh folder out/<command>-<case>-NNN.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Change a value of the case before it is checked, e.g. fe.plane=stress,
    /// mesh.fine_element_mm=0.05, scene[low-unmodified].duration_s=0.02 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<Override>,
}

fn main() -> ExitCode {
    let result = match Cli::parse().command {
        Command::Run(args) => run(&args),
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
        } => sweep(&common, rpm, &model, run_up_s),
        Command::Stability { common, rpm, model } => stability(&common, &rpm, &model),
        Command::Fe { common, options } => fe(&common, &options),
        Command::Validate {
            study: ValidationStudy::Integrators,
            common,
            model,
            ..
        } => validate_integrators(&common, &model),
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
        Command::Case { case, set } => Case::load_with(case.as_deref(), &set)
            .map(|c| print!("{}", c.text))
            .map_err(Into::into),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// The case with the command's shorthands, then the user's `--set`s, applied.
fn load(args: &CommonArgs, shorthands: Vec<Override>) -> Result<Case> {
    let mut overrides = shorthands;
    overrides.extend(args.set.iter().cloned());
    Ok(Case::load_with(args.case.as_deref(), &overrides)?)
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

fn run(args: &CommonArgs) -> Result<()> {
    let case = load(args, Vec::new())?;
    let dir = output_dir(args, "run", &case)?;
    let stage = |name: &str| CommonArgs {
        out: Some(dir.join(name)),
        ..args.clone()
    };
    println!("== geometry");
    geometry(&stage("geometry"))?;
    println!("\n== mesh");
    mesh(&stage("mesh"), None)?;
    println!("\n== ltca");
    ltca(&stage("ltca"), None, 64, None)?;
    println!("\n== sweep");
    let rpm = "100:12000:600".parse().map_err(anyhow::Error::msg)?;
    sweep(&stage("sweep"), rpm, &LumpedShorthands::default(), None)?;
    println!("\nall outputs in {}", dir.display());
    Ok(())
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
    let result = study::ltca::run(&case, &options, &|stage, done, total| {
        bar.set_length(total as u64);
        bar.set_message(stage.to_string());
        bar.set_position(done as u64);
    })?;
    bar.finish_and_clear();
    print!("{}", report::ltca::console(&result));
    report::ltca::write(OutputDir(&dir), &case, &result)?;
    println!("wrote {}", dir.display());
    Ok(())
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
) -> Result<()> {
    let case = lumped_case(args, options)?;
    let result = study::sweep::run(&case, &study::sweep::SweepOptions { rpm, run_up_s })?;
    print!("{}", report::lumped::setup_console(&result.setup));
    let dir = output_dir(args, "sweep", &case)?;
    report::lumped::write_sweep(OutputDir(&dir), &case, &result)?;
    print!("{}", report::lumped::sweep_console(&result));
    println!("wrote {}", dir.display());
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
    use report::compare::read_fe_run;
    let case = load(args, Vec::new())?;
    let dir = output_dir(args, "compare", &case)?;
    let read = |d: &Path| read_fe_run(d).map_err(anyhow::Error::msg);
    let mut runs = fe_runs
        .iter()
        .map(|d| read(d))
        .collect::<Result<Vec<_>>>()?;
    for &rpm in speeds {
        if runs.iter().any(|r| (r.speed_rpm - rpm).abs() < 1e-6 * rpm) {
            continue;
        }
        let key = "scene[high-unmodified].speed_rpm";
        let at_speed = load(args, vec![Override::set(key, rpm)])?;
        let out = dir.join(format!("fe-{rpm:.0}"));
        fe_run(
            &at_speed,
            study::fe::scene(&at_speed, "high-unmodified")?,
            &out,
        )?;
        runs.push(read(&out)?);
    }
    let stiffness_file = match fe_stiffness {
        Some(file) => file.to_path_buf(),
        None => {
            let out = dir.join("fe-stiffness");
            fe_run(&case, study::fe::scene(&case, "stiffness")?, &out)?;
            out.join("stiffness.csv")
        }
    };
    let pitch = case.pair.gears[0].angular_pitch();
    let fe_stiffness = report::stiffness_csv::read_stiffness_csv(&stiffness_file, pitch)
        .map_err(anyhow::Error::msg)?;
    let input = study::compare::CompareInput {
        fe_runs: runs,
        fe_stiffness,
    };
    let bar = progress_bar("{msg} [{bar:40}] {pos}/{len}");
    let summary = study::compare::run(&case, &input, positions, paper, &|stage, done, total| {
        bar.set_message(stage.to_string());
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    })?;
    bar.finish_and_clear();
    let table = report::compare::write(OutputDir(&dir), &case, &summary)?;
    println!("{table}");
    if let Some(folders) = chart {
        let primary = study::compare::primary_run(&case, &input.fe_runs)
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
        for (mm, scaled) in [(1.0, true), (1.0, false), (0.7, true), (0.7, false)] {
            let at_level = load(
                args,
                vec![
                    Override::set("fe.explicit_fine_element_mm", mm),
                    Override::set("fe.mass_scaling", scaled),
                ],
            )?;
            let tag = if scaled { "scaled" } else { "unscaled" };
            let out = dir.join(format!("chart-fe-{mm}-{tag}"));
            fe_run(&at_level, study::fe::scene(&at_level, "stiffness")?, &out)?;
            folders.push(out);
        }
    }
    let pitch = case.pair.gears[0].angular_pitch();
    let runs = folders
        .iter()
        .map(|d| report::compare::read_fe_stiffness_run(d, pitch).map_err(anyhow::Error::msg))
        .collect::<Result<Vec<_>>>()?;
    let bar = progress_bar("{msg} [{bar:40}] {pos}/{len}");
    let chart = study::accuracy::run(case, &runs, dte_run, &|stage, done, total| {
        bar.set_message(stage.to_string());
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    })?;
    bar.finish_and_clear();
    print!(
        "{}",
        report::compare::write_accuracy_cost(OutputDir(dir), &chart)?
    );
    Ok(())
}

/// Prepares and runs an explicit scene with progress (a bar, or a line every 10 % without a
/// terminal) and writes it to `dir`; a diverged run is written too, then reported as an error.
fn fe_run(case: &Case, scene: &Scene, dir: &Path) -> Result<study::fe::FeStudy> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    eprintln!("{}", report::fe::scene_line(scene));
    let prepared = study::fe::prepare(case, scene)?;
    print!("{}", report::fe::prepared_console(case, &prepared, scene));
    let bar = progress_bar("explicit FE [{bar:40}] {percent}% elapsed {elapsed}, ETA {eta}");
    bar.set_length(1000);
    // Without a terminal (a log file, CI) the bar is hidden: a line every 10 % instead.
    let plain_log = bar.is_hidden();
    let started = std::time::Instant::now();
    let mut logged = 0;
    let result = study::fe::run(case, scene, &prepared, &mut |f| {
        bar.set_position((f * 1000.0) as u64);
        let tenth = (f * 10.0).floor() as usize;
        if plain_log && tenth > logged {
            logged = tenth;
            let elapsed = started.elapsed().as_secs_f64();
            eprintln!(
                "explicit FE {:3.0} % after {elapsed:.0} s, about {:.0} s to go",
                f * 100.0,
                elapsed * (1.0 - f) / f.max(1e-9)
            );
        }
    })?;
    bar.finish_and_clear();
    report::fe::write(OutputDir(dir), case, &result)?;
    if let Some(message) = &result.summary.diverged {
        anyhow::bail!("{message}; partial results in {}", dir.display());
    }
    print!("{}", report::fe::console(&result));
    Ok(result)
}

fn progress_bar(template: &str) -> ProgressBar {
    let bar = ProgressBar::new(0);
    bar.set_style(ProgressStyle::with_template(template).expect("valid template"));
    bar
}
