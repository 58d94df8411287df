//! The command line's arguments (clap): the commands, their flags and help texts.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

use geardyn::case::Override;
use geardyn::study::{fe::FeShorthands, lumped::LumpedShorthands, optimize, RpmRange};

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
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand)]
pub enum Command {
    /// The main job, the whole chain on one case, each stage in its own sub-folder: geometry,
    /// LTCA (every relief variant), the explicit FE's k(θ) from a low-speed DTE against the
    /// LTCA's, rpm sweeps on both stiffnesses and the stability map, the relief optimization with
    /// the explicit FE of the unmodified pair and the optimum, FE against lumped frequencies.
    /// About 5 minutes on 2 cores; --full: every relief candidate at low and high speed and the
    /// FE spectra at 1200, 3000 and 4800 rpm (hours).
    Run {
        #[command(flatten)]
        common: CommonArgs,
        /// The full cross-checks (every candidate at the case's low and high speed, FE spectra
        /// at three speeds, the paper-stiffness study).
        #[arg(long)]
        full: bool,
        /// Continue the interrupted run in --out DIR: finished explicit FE runs of the same case
        /// are taken as they are, the other stages run again (seconds each).
        #[arg(long)]
        resume: bool,
    },
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
        /// Continue the interrupted sweep in --out DIR (same case, --set and --rpm) from its
        /// sweep_checkpoint.json; the result is the uninterrupted sweep's.
        #[arg(long)]
        resume: bool,
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
        /// Go on with the interrupted run in --out DIR (same case, --set and flags) from its
        /// checkpoint.json; the result is the uninterrupted run's.
        #[arg(long)]
        resume: bool,
        /// What a batch task that may be requeued runs: take a finished run of the same case in
        /// --out as it is, go on from the checkpoint of an interrupted one, else start.
        #[arg(long, conflicts_with = "resume")]
        reuse: bool,
    },
    /// The explicit FE runs a command would make, with their estimated wall time and memory
    /// (timed on this machine) and the total core-hours, without running them: `geardyn plan
    /// run --full`, `geardyn plan compare --fe-sweep 4400:6600:8`. The lumped and LTCA stages
    /// that decide the runs (the relief optimizer's candidates) do run.
    Plan {
        /// The command and its arguments, as they would be given.
        #[arg(
            trailing_var_arg = true,
            allow_hyphen_values = true,
            required = true,
            value_name = "COMMAND"
        )]
        command: Vec<String>,
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
        #[command(flatten)]
        options: CompareArgs,
    },
    /// Re-writes the report of a `geardyn run` folder (index.html, report.md, summary.json,
    /// tables/) from what its stages wrote, e.g. after a stage was re-run.
    Report {
        /// The output folder of `geardyn run`.
        #[arg(value_name = "DIR")]
        dir: PathBuf,
    },
    /// Tip/root relief optimization: the relief (amount per gear and end, relief length, linear
    /// or parabolic) that minimizes the loaded STE peak-to-peak averaged over a torque range,
    /// by LTCA sensitivities and a Clarabel QP in a trust region, against no relief, the
    /// case's relief and the classic rule; Harris map and a lumped sweep per candidate; with
    /// --fe-check the explicit FE at low and high speed. Writes summary.json, iterations,
    /// candidates, harris, ste and sweep CSVs with plots.
    Optimize {
        #[command(flatten)]
        common: CommonArgs,
        #[command(flatten)]
        options: OptimizeArgs,
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
        /// Generated cases of `properties`.
        #[arg(long, value_name = "N", default_value_t = 100_000)]
        cases: usize,
        /// Seed of `properties`' generator.
        #[arg(long, value_name = "S", default_value_t = 1)]
        seed: u64,
        /// `pairs`: only these pairs of the matrix (repeatable; default: all).
        #[arg(long, value_name = "PAIR")]
        only: Vec<String>,
        /// `pairs`: also the explicit FE's stiffness scene of each pair against its LTCA
        /// (about two minutes a pair on 2 cores).
        #[arg(long)]
        fe: bool,
        /// `pairs`: also `geardyn run` end to end on each pair at coarse settings (the stiffness
        /// scene 4 ms with a 2 ms ramp), its self-checks held (a few minutes a pair).
        #[arg(long)]
        run: bool,
        /// `frequencies`: FE modal positions over one base pitch.
        #[arg(long, value_name = "N", default_value_t = 8)]
        positions: usize,
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
pub enum ValidationStudy {
    /// The quick set (about 20 s): contact ratio against the paper, LTCA mesh convergence
    /// and equilibrium, the relief optimum against every baseline and against its re-meshed
    /// LTCA; exits non-zero when a stated tolerance is broken (CI runs it).
    Quick,
    /// Where each fixed-step scheme of the lumped model fails: stability and 1 %
    /// frequency-accuracy limits in ωh, predicted vs observed, and the order of convergence
    /// with and without tooth separation.
    Integrators,
    /// The explicit FE's low-speed mass scaling against the same scene unscaled (--scene):
    /// DTE mean and peak-to-peak, k(θ) bin by bin, the cost of each.
    MassScaling,
    /// Case parsing and geometry over --cases generated cases (the embedded case with keys
    /// changed to plausible, out-of-range or wrong-typed values, or removed): a finite result
    /// or an error naming the parameter, never a panic; exits non-zero otherwise.
    Properties,
    /// Every fidelity on the matrix of pairs (unequal ratios and their inverse, shifts,
    /// backlash, hunting tooth, modules 1 and 8, thin rim, 25°, ε_α 2.1 and 2.4): geometry, the
    /// LTCA's self-checks, mesh convergence, the swap test, the lumped sweep, and with --fe the
    /// explicit FE's stiffness scene; exits non-zero when a row fails (validation/pairs).
    Pairs,
    /// The case's lumped model's mesh mode (as sweep and run integrate it) against the FE
    /// modal analysis of the meshed pair on the case's mesh, driver held and both free, with
    /// its bodies and with rigid gears; exits non-zero beyond 2 % (validation/frequencies).
    Frequencies,
}

impl Command {
    /// The options every case-driven command shares.
    pub fn common(&self) -> Option<&CommonArgs> {
        match self {
            Command::Run { common, .. }
            | Command::Mesh { common, .. }
            | Command::Ltca { common, .. }
            | Command::Sweep { common, .. }
            | Command::Stability { common, .. }
            | Command::Fe { common, .. }
            | Command::Compare { common, .. }
            | Command::Optimize { common, .. }
            | Command::Validate { common, .. } => Some(common),
            Command::Geometry(common) => Some(common),
            Command::Report { .. } | Command::Case { .. } | Command::Plan { .. } => None,
        }
    }
}

/// What `compare` runs and compares besides its case (`geardyn plan compare` reads the same).
#[derive(Args, Clone)]
pub struct CompareArgs {
    /// Explicit FE runs to make: scene high-unmodified at these driver speeds [rpm], into
    /// DIR/fe-<rpm> (skipped for speeds given by --fe-run).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "1200,3000,4800",
        value_name = "RPM"
    )]
    pub speed_rpm: Vec<f64>,
    /// Finished `geardyn fe` output folders to use instead of running their speeds
    /// (repeatable).
    #[arg(long = "fe-run", value_name = "DIR")]
    pub fe_runs: Vec<PathBuf>,
    /// k(θ) from the FE DTE (stiffness.csv of `geardyn fe --scene stiffness`); default: run
    /// that scene into DIR/fe-stiffness.
    #[arg(long, value_name = "FILE")]
    pub fe_stiffness: Option<PathBuf>,
    /// Mesh positions over one base pitch for the FE modal analysis.
    #[arg(long, default_value_t = 16, value_name = "N")]
    pub positions: usize,
    /// Also the labelled paper-stiffness study: the lumped model given the seed paper's
    /// mean stiffness (1.3427e8 N/m, by a compliance in series), never a default.
    #[arg(long)]
    pub paper_stiffness: bool,
    /// Also the accuracy-versus-cost chart (accuracy_cost.{csv,md,png,svg}): LTCA at three
    /// mesh levels, ISO, potential energy and explicit FE stiffness runs, against the finest
    /// unscaled FE run and the primary FE run's DTE (the one nearest 3000 rpm).
    #[arg(long)]
    pub chart: bool,
    /// Finished stiffness-scene folders for the chart (repeatable); default: run the
    /// stiffness scene at 1.0 and 0.7 mm flanks, scaled and unscaled, into DIR/chart-fe-*.
    #[arg(long = "chart-fe-run", value_name = "DIR")]
    pub chart_fe_runs: Vec<PathBuf>,
    /// The explicit FE's speed sweep through the mesh resonance: scene high-unmodified at N
    /// speeds from FROM to TO [rpm] (e.g. 4400:6600:8 on the paper pair, 0.8–1.2 × the
    /// driver-held resonance; --fe-run folders at those speeds are reused, and those and
    /// --speed-rpm speeds elsewhere inside the range join the sweep, in place of a grid
    /// speed within a quarter of its spacing; each run up to 0.05 s, ended once its DTE has
    /// settled: the scene's stop_when_settled), against the
    /// lumped twin swept four times as densely: resonance speeds, the peak mesh-harmonic
    /// amplitude and the DTE rms (fe_sweep in summary.json, fe_sweep.csv, fe_sweep.png).
    #[arg(long, value_name = "FROM:TO:N")]
    pub fe_sweep: Option<RpmRange>,
}

#[derive(Args, Clone)]
pub struct CommonArgs {
    /// Case file (TOML). Default: the embedded paper36 case.
    pub case: Option<PathBuf>,
    /// Output folder. Default: a fresh folder out/<command>-<case>-NNN.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Run what is estimated above a limit anyway: an explicit scene's wall time (elements ×
    /// steps × the rate timed on the scene) above 4 hours, a model's memory above 80 % of the
    /// memory available (or GEARDYN_MEMORY_LIMIT_MB).
    #[arg(long)]
    pub force: bool,
    /// Explicit runs keep a checkpoint.json this often [s of wall time], so a process killed
    /// outright (SIGKILL, a batch job's limit) goes on from it with --resume.
    #[arg(long, value_name = "SECONDS", default_value_t = 600.0, value_parser = positive_seconds)]
    pub checkpoint_every_s: f64,
    /// Change a value of the case before it is checked, e.g. fe.plane=stress,
    /// mesh.fine_element_mm=0.05, scene[low-unmodified].duration_s=0.02 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<Override>,
    #[command(flatten)]
    pub executor: ExecutorArgs,
}

/// Where the explicit FE runs of a study run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Default)]
pub enum Executor {
    /// On this machine: several at once, each on a share of the cores (--jobs).
    #[default]
    Local,
    /// As one Slurm job array (one task per run), waited for; the study then goes on here.
    Slurm,
}

/// The executor's flags (every command that runs explicit FE).
#[derive(Args, Clone, Debug)]
pub struct ExecutorArgs {
    /// Run the study's explicit FE runs here (local) or as a Slurm job array (slurm).
    #[arg(long, value_enum, default_value = "local")]
    pub executor: Executor,
    /// With --executor slurm: submit the array and stop; the same command run again later
    /// (same --out) waits for it and finishes the study.
    #[arg(long, requires = "out")]
    pub submit_only: bool,
    /// Slurm partition of the array.
    #[arg(long, value_name = "NAME")]
    pub partition: Option<String>,
    /// Slurm account of the array.
    #[arg(long, value_name = "NAME")]
    pub account: Option<String>,
    /// An extra #SBATCH option, verbatim, e.g. --sbatch-option=--qos=long (repeatable).
    #[arg(
        long = "sbatch-option",
        value_name = "OPTION",
        allow_hyphen_values = true
    )]
    pub sbatch_options: Vec<String>,
    /// Cores per task (default 2, the cores the cost model is timed with).
    #[arg(long, value_name = "N")]
    pub cpus_per_task: Option<usize>,
    /// How often the queue is asked while the study waits [s].
    #[arg(long, value_name = "SECONDS", default_value_t = 20.0, value_parser = positive_seconds)]
    pub poll_s: f64,
    /// With --executor local: explicit runs at once, the threads and the memory limit shared
    /// among them (default: as many as there are runs to make, up to one per thread,
    /// RAYON_NUM_THREADS or the cores; 1: one after the other on all). The results do not
    /// depend on it.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    pub jobs: Option<u64>,
}

impl Default for ExecutorArgs {
    fn default() -> Self {
        ExecutorArgs {
            executor: Executor::Local,
            submit_only: false,
            partition: None,
            account: None,
            sbatch_options: Vec::new(),
            cpus_per_task: None,
            poll_s: 20.0,
            jobs: None,
        }
    }
}

/// A scene of the relief cross-check.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FeCheckScene {
    Low,
    High,
}

/// The flags of `geardyn optimize`.
#[derive(Debug, Clone, clap::Args)]
pub struct OptimizeArgs {
    /// Load torque on the driven gear [N·m] (sets operating_point[0].torque_nm): the design
    /// torque.
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub torque_nm: Option<f64>,
    /// Torques of the robust objective, FROM:TO:N in percent of the design torque.
    #[arg(long, default_value = optimize::DEFAULT_TORQUE_RANGE, value_name = "FROM:TO:N")]
    pub torque_range: optimize::TorqueRange,
    /// LTCA positions per base pitch.
    #[arg(long, default_value_t = optimize::DEFAULT_POSITIONS, value_name = "N")]
    pub positions: usize,
    /// Smallest loaded contact ratio allowed at any torque of the range. Default: ⌊ε_α⌋ + 0.2,
    /// at most ε_α (1.2 for ε_α < 2; 2.2 for a high-contact-ratio pair)
    #[arg(long, value_name = "EPS")]
    pub min_contact_ratio: Option<f64>,
    /// Largest relief amount [µm].
    #[arg(long, default_value_t = optimize::DEFAULT_MAX_RELIEF_UM, value_name = "UM")]
    pub max_relief_um: f64,
    /// Shortest relief, as a fraction of the double-contact zone (1 = long relief).
    #[arg(long, default_value_t = optimize::DEFAULT_MIN_LENGTH, value_name = "FRACTION")]
    pub min_relief_length: f64,
    /// Largest tooth-root tension of each gear at any position and torque of the range: MPa
    /// (e.g. 90), or a percentage of that gear's unmodified peak (e.g. 105%). Default: no limit
    #[arg(long, value_name = "MPA|PCT%", allow_hyphen_values = true)]
    pub max_root_stress_mpa: Option<optimize::StressLimit>,
    /// Largest Hertz contact pressure at any position and torque of the range: MPa (e.g. 800),
    /// or a percentage of the unmodified pair's peak (e.g. 102%). Default: no limit
    #[arg(long, value_name = "MPA|PCT%", allow_hyphen_values = true)]
    pub max_contact_pressure_mpa: Option<optimize::StressLimit>,
    /// Driver speeds of each candidate's lumped sweep, FROM:TO:N in rpm.
    #[arg(long, default_value = optimize::DEFAULT_RPM, value_name = "FROM:TO:N")]
    pub rpm: RpmRange,
    /// Also run the explicit FE cross-check of the candidates at the case's low and high speed
    /// (long: about 14 minutes per candidate on 2 cores).
    #[arg(long)]
    pub fe_check: bool,
    /// With --fe-check: only these candidates (names as in candidates.csv, comma-separated).
    #[arg(
        long,
        value_delimiter = ',',
        value_name = "NAMES",
        requires = "fe_check"
    )]
    pub fe_check_only: Option<Vec<String>>,
    /// With --fe-check: the scenes, `low` (the stiffness scene), `high` (the high-speed scene)
    /// or both.
    #[arg(
        long,
        value_delimiter = ',',
        value_name = "low,high",
        default_value = "low,high",
        requires = "fe_check"
    )]
    pub fe_check_scenes: Vec<FeCheckScene>,
}

impl OptimizeArgs {
    /// The cross-check the flags ask for.
    pub fn fe_check_plan(&self) -> Option<geardyn::study::optimize::FeCheckPlan> {
        self.fe_check
            .then(|| geardyn::study::optimize::FeCheckPlan {
                baseline_and_best_only: false,
                only: self.fe_check_only.clone(),
                scenes: [
                    self.fe_check_scenes.contains(&FeCheckScene::Low),
                    self.fe_check_scenes.contains(&FeCheckScene::High),
                ],
            })
    }

    /// The command's defaults, as `geardyn optimize` parses them.
    pub fn default_for_run() -> Self {
        #[derive(Parser)]
        struct Defaults {
            #[command(flatten)]
            options: OptimizeArgs,
        }
        Defaults::parse_from(["optimize"]).options
    }

    pub fn options(&self) -> geardyn::study::optimize::OptimizeOptions {
        geardyn::study::optimize::OptimizeOptions {
            torque_range: self.torque_range,
            positions: self.positions,
            min_contact_ratio: self.min_contact_ratio,
            max_relief_um: self.max_relief_um,
            min_length: self.min_relief_length,
            rpm: self.rpm.clone(),
            max_root_stress: self.max_root_stress_mpa,
            max_contact_pressure: self.max_contact_pressure_mpa,
            ..Default::default()
        }
    }
}

/// A wall-time interval: a positive, finite number of seconds.
fn positive_seconds(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(s) if s > 0.0 && s.is_finite() => Ok(s),
        _ => Err(format!(
            "{text:?} is not a positive number of seconds, e.g. 600"
        )),
    }
}
