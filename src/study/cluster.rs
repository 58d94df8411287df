//! Plans of explicit FE runs and their Slurm job arrays: what a study will run, what each run
//! costs, the batch script that runs them on a cluster, and the queue's answer read back.
//!
//! Every study that runs explicit FE scenes first lists them ([`PlannedRun`]); an executor then
//! runs the list on this machine, several at once on a share of the cores each
//! ([`local_jobs`]), or submits the unfinished ones as one Slurm job array (one task per run). A task runs `geardyn fe <dir>/case.toml --scene S --out <dir>
//! --reuse`: it takes a finished run of the same case as it is, goes on from the checkpoint an
//! interrupted one left (a time limit, a preemption, a requeue) and starts the others, so the
//! folders end as a local run leaves them and the study reads them the same way.
//!
//! Nothing here runs a process; the binary does (`src/bin/geardyn/executor.rs`).

use std::fmt::Write as _;
use std::path::PathBuf;

use serde::Serialize;

use super::fe::duration_words;
use crate::resources::bytes_words;

/// How the local executor shares `threads` worker threads among `runs` explicit runs: how many
/// run at once and on how many threads each, `requested` runs at once if given (at least 1,
/// at most the runs and the threads). By default as many runs at once as there are runs, up
/// to one per thread: one run on 2 threads leaves part of both cores idle (the serial contact
/// phase and the two per-step joins, about a quarter of its wall time on this host), so two
/// runs side by side on one thread each finish together in 70 s where one after the other
/// take 98 s (the default stiffness scene cut to 0.016 s, 2 cores; validation/performance).
/// A run's results do not depend on its thread count (tests/explicit_pair.rs), so neither do
/// the study's. Threads left over when they do not divide go to none.
pub fn local_jobs(runs: usize, threads: usize, requested: Option<usize>) -> (usize, usize) {
    let threads = threads.max(1);
    let jobs = requested.unwrap_or(threads).min(runs).min(threads).max(1);
    (jobs, threads / jobs)
}

/// One explicit FE run of a study's plan.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlannedRun {
    /// The study stage or candidate it belongs to, e.g. "compare 4800 rpm".
    pub label: String,
    /// The case's scene it runs.
    pub scene: String,
    /// Its output folder (absolute where the executor submits it).
    pub dir: PathBuf,
    /// Estimated wall time on one task of [`CALIBRATION_CORES`] cores [s]
    /// ([`super::fe::CostEstimate`], timed on this machine).
    pub wall_s: f64,
    /// Estimated peak memory [bytes]: the run's history and state plus [`PROCESS_BYTES`].
    pub memory_bytes: f64,
    /// Already finished in its folder (summary.json of the same case, no checkpoint): reused.
    pub finished: bool,
}

/// The cores the cost model's rate was timed with: a task asks for as many.
pub const CALIBRATION_CORES: usize = 2;

/// What a geardyn process holds besides the run's history and state: the two bodies' meshes,
/// the explicit model and the LTCA of the dashpot's sizing (measured: 250–400 MB resident on
/// the paper pair's scenes).
pub const PROCESS_BYTES: f64 = 600e6;

/// A batch system's time limit is the estimate times this, plus [`TIME_MARGIN_S`]: the rate
/// is timed on this machine, a cluster node may be slower, and the limit only stops a run that
/// its checkpoint continues.
pub const TIME_FACTOR: f64 = 2.0;
pub const TIME_MARGIN_S: f64 = 600.0;

/// The memory asked for is the estimate times this.
pub const MEMORY_FACTOR: f64 = 1.5;

/// The whole plan's cost: the sum of the unfinished runs' wall times × cores [core-hours].
pub fn core_hours(runs: &[PlannedRun]) -> f64 {
    runs.iter()
        .filter(|r| !r.finished)
        .map(|r| r.wall_s * CALIBRATION_CORES as f64 / 3600.0)
        .sum()
}

/// The plan as a table: one row per run, then the totals, and what N nodes would take.
pub fn plan_table(runs: &[PlannedRun]) -> String {
    let mut text = String::new();
    let width = runs.iter().map(|r| r.label.len()).max().unwrap_or(5).max(5);
    let _ = writeln!(
        text,
        "{:<width$}  {:<16}  {:>12}  {:>8}  {:<8}  folder",
        "run", "scene", "wall time", "memory", "state"
    );
    for run in runs {
        let _ = writeln!(
            text,
            "{:<width$}  {:<16}  {:>12}  {:>8}  {:<8}  {}",
            run.label,
            run.scene,
            duration_words(run.wall_s),
            bytes_words(run.memory_bytes),
            if run.finished { "finished" } else { "to run" },
            run.dir.display()
        );
    }
    let left: Vec<&PlannedRun> = runs.iter().filter(|r| !r.finished).collect();
    let serial: f64 = left.iter().map(|r| r.wall_s).sum();
    let longest = left.iter().map(|r| r.wall_s).fold(0.0, f64::max);
    let _ = writeln!(
        text,
        "{} explicit runs, {} to run: {:.2} core-hours ({} one after the other on {} cores; \
         with one run per node, as long as the longest run, {})",
        runs.len(),
        left.len(),
        core_hours(runs),
        duration_words(serial),
        CALIBRATION_CORES,
        duration_words(longest)
    );
    text
}

/// The partition, account and extra options of the job arrays (`[cluster]` or the flags).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ClusterOptions {
    pub partition: Option<String>,
    pub account: Option<String>,
    /// Extra `#SBATCH` options, verbatim (e.g. "--qos=long").
    pub sbatch_options: Vec<String>,
    /// Cores per task; default [`CALIBRATION_CORES`].
    pub cpus_per_task: Option<usize>,
}

/// What one task of the array runs.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskCommand {
    /// The geardyn executable the cluster's nodes run (absolute; a shared file system).
    pub executable: PathBuf,
    /// `--checkpoint-every-s` of the runs.
    pub checkpoint_every_s: f64,
    /// `--force` of the study.
    pub force: bool,
}

/// Slurm's time format, D-HH:MM:SS, rounded up to the minute.
pub fn slurm_time(seconds: f64) -> String {
    let minutes = (seconds.max(60.0) / 60.0).ceil() as u64;
    let (days, hours, minutes) = (minutes / 1440, (minutes / 60) % 24, minutes % 60);
    format!("{days}-{hours:02}:{minutes:02}:00")
}

/// The time limit of a task whose run is estimated at `wall_s` on `cpus` cores.
pub fn time_limit_s(wall_s: f64, cpus: usize) -> f64 {
    let speedup = (cpus as f64 / CALIBRATION_CORES as f64).clamp(0.5, 1.0);
    wall_s / speedup * TIME_FACTOR + TIME_MARGIN_S
}

/// The array's batch script for `runs` (every task gets the largest run's limits; task i runs
/// `runs[i]`), its log of task i in `log_dir`/<array job>_<i>.log.
pub fn sbatch_script(
    name: &str,
    runs: &[PlannedRun],
    command: &TaskCommand,
    options: &ClusterOptions,
    log_dir: &std::path::Path,
) -> String {
    let cpus = options.cpus_per_task.unwrap_or(CALIBRATION_CORES).max(1);
    let wall = runs.iter().map(|r| r.wall_s).fold(0.0, f64::max);
    let memory = runs.iter().map(|r| r.memory_bytes).fold(0.0, f64::max);
    // Slurm's M is MiB.
    let memory_mb = (memory * MEMORY_FACTOR / 1048576.0).ceil() as u64;
    let mut s = String::new();
    let _ = writeln!(s, "#!/bin/bash");
    let _ = writeln!(
        s,
        "# Written by geardyn: {} explicit FE runs, one per task; a task that is requeued or\n\
         # resubmitted goes on from its run's checkpoint (geardyn fe --reuse).",
        runs.len()
    );
    let _ = writeln!(s, "#SBATCH --job-name={name}");
    let _ = writeln!(s, "#SBATCH --array=0-{}", runs.len().saturating_sub(1));
    let _ = writeln!(s, "#SBATCH --ntasks=1");
    let _ = writeln!(s, "#SBATCH --cpus-per-task={cpus}");
    let _ = writeln!(s, "#SBATCH --time={}", slurm_time(time_limit_s(wall, cpus)));
    let _ = writeln!(s, "#SBATCH --mem={memory_mb}M");
    let _ = writeln!(s, "#SBATCH --requeue");
    let _ = writeln!(s, "#SBATCH --open-mode=append");
    // SIGTERM this long before the limit: the run writes its checkpoint and partial results.
    // B: to the batch shell, which `exec` made the run itself (without B: only job steps
    // started by srun would get it).
    let _ = writeln!(s, "#SBATCH --signal=B:TERM@120");
    let _ = writeln!(s, "#SBATCH --output={}/%A_%a.log", log_dir.display());
    if let Some(partition) = &options.partition {
        let _ = writeln!(s, "#SBATCH --partition={partition}");
    }
    if let Some(account) = &options.account {
        let _ = writeln!(s, "#SBATCH --account={account}");
    }
    for option in &options.sbatch_options {
        let _ = writeln!(s, "#SBATCH {option}");
    }
    let _ = writeln!(s, "set -u");
    let _ = writeln!(s, "case \"$SLURM_ARRAY_TASK_ID\" in");
    for (i, run) in runs.iter().enumerate() {
        let _ = writeln!(
            s,
            "  {i}) scene={} dir={} ;;",
            shell_quote(&run.scene),
            shell_quote(&run.dir.display().to_string())
        );
    }
    let _ = writeln!(
        s,
        "  *) echo \"no run for task $SLURM_ARRAY_TASK_ID\" >&2; exit 2 ;;\nesac"
    );
    let _ = writeln!(
        s,
        "export RAYON_NUM_THREADS=\"${{SLURM_CPUS_PER_TASK:-{cpus}}}\""
    );
    let _ = writeln!(
        s,
        "echo \"task $SLURM_ARRAY_TASK_ID (job ${{SLURM_ARRAY_JOB_ID:-?}}, restart ${{SLURM_RESTART_COUNT:-0}}) on $(hostname): $scene into $dir\""
    );
    let _ = writeln!(
        s,
        "exec {} fe \"$dir/case.toml\" --scene \"$scene\" --out \"$dir\" --reuse --checkpoint-every-s {}{}",
        shell_quote(&command.executable.display().to_string()),
        command.checkpoint_every_s,
        if command.force { " --force" } else { "" }
    );
    s
}

/// `text` as one word of a POSIX shell.
pub fn shell_quote(text: &str) -> String {
    let plain = !text.is_empty()
        && text
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "/._-+=:,@".contains(c));
    if plain {
        text.to_string()
    } else {
        format!("'{}'", text.replace('\'', "'\\''"))
    }
}

/// The job id sbatch printed ("Submitted batch job 123", or "123" with --parsable).
pub fn parse_sbatch_job_id(output: &str) -> Option<u64> {
    output
        .split_whitespace()
        .rev()
        .find_map(|w| w.split(';').next()?.parse().ok())
}

/// An array's tasks as the queue lists them.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct QueueCounts {
    pub pending: usize,
    pub running: usize,
    /// Completing, requeued, suspended and the other states in between.
    pub other: usize,
    /// A task that will not start without someone's action (held, or asking more than its
    /// partition, account or QOS allows), with the queue's reason: a study waiting for it
    /// would wait for ever.
    pub stuck: Option<String>,
}

/// Pending reasons that no amount of waiting clears.
const STUCK_REASONS: [&str; 11] = [
    "JobHeldUser",
    "JobHeldAdmin",
    "PartitionTimeLimit",
    "PartitionNodeLimit",
    "BadConstraints",
    "InvalidAccount",
    "InvalidQOS",
    "DependencyNeverSatisfied",
    "QOSMaxWallDurationPerJobLimit",
    "AssocMaxWallDurationPerJobLimit",
    "AccountNotAllowed",
];

impl QueueCounts {
    pub fn in_queue(&self) -> usize {
        self.pending + self.running + self.other
    }
}

/// Reads `squeue -h -r -j JOB -o "%i %T %r"` (one task per line, "123_4 RUNNING None"; a
/// pending range not yet split, "123_[5-9%2] PENDING Priority", counts its tasks).
pub fn parse_squeue(output: &str) -> QueueCounts {
    let mut counts = QueueCounts::default();
    for line in output.lines() {
        let mut words = line.split_whitespace();
        let (Some(id), Some(state)) = (words.next(), words.next()) else {
            continue;
        };
        let reason = words.next().unwrap_or("");
        let tasks = array_range_len(id).unwrap_or(1);
        match state {
            "PENDING" | "REQUEUED" | "REQUEUE_HOLD" | "REQUEUE_FED" => counts.pending += tasks,
            "RUNNING" => counts.running += tasks,
            _ => counts.other += tasks,
        }
        let stuck = state == "REQUEUE_HOLD"
            || (state == "PENDING" && STUCK_REASONS.iter().any(|r| reason.starts_with(r)));
        if stuck && counts.stuck.is_none() {
            counts.stuck = Some(format!("task {id} is {state} ({reason})"));
        }
    }
    counts
}

/// The number of tasks of "123_[5-9,11%2]", None for a single task.
fn array_range_len(id: &str) -> Option<usize> {
    let inner = id.split_once("_[")?.1.trim_end_matches(']');
    let inner = inner.split('%').next()?;
    Some(
        inner
            .split(',')
            .map(|part| match part.split_once('-') {
                Some((a, b)) => match (a.parse::<usize>(), b.parse::<usize>()) {
                    (Ok(a), Ok(b)) if b >= a => b - a + 1,
                    _ => 1,
                },
                None => 1,
            })
            .sum(),
    )
}

/// The last `n` lines of a task's log: what a failed run's report names.
pub fn last_lines(text: &str, n: usize) -> String {
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    lines[lines.len().saturating_sub(n)..].join("\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two cores: two runs side by side on one thread each, one run on both, and what a request
    /// asks within the bounds (never more runs at once than runs or threads, never none).
    #[test]
    fn local_jobs_share_the_threads() {
        assert_eq!(local_jobs(2, 2, None), (2, 1));
        assert_eq!(local_jobs(14, 2, None), (2, 1));
        assert_eq!(local_jobs(1, 2, None), (1, 2));
        assert_eq!(local_jobs(0, 2, None), (1, 2));
        assert_eq!(local_jobs(5, 2, Some(1)), (1, 2));
        assert_eq!(local_jobs(5, 2, Some(8)), (2, 1));
        assert_eq!(local_jobs(5, 8, Some(3)), (3, 2));
        assert_eq!(local_jobs(5, 8, Some(0)), (1, 8));
        assert_eq!(local_jobs(3, 0, None), (1, 1));
    }

    fn run(label: &str, wall_s: f64, finished: bool) -> PlannedRun {
        PlannedRun {
            label: label.into(),
            scene: "high-unmodified".into(),
            dir: PathBuf::from(format!("/data/out/{label}")),
            wall_s,
            memory_bytes: 1.2e9,
            finished,
        }
    }

    #[test]
    fn core_hours_count_the_runs_left() {
        let runs = [run("a", 3600.0, false), run("b", 1800.0, true)];
        assert!((core_hours(&runs) - 2.0).abs() < 1e-12);
        let table = plan_table(&runs);
        assert!(
            table.contains("2 explicit runs, 1 to run: 2.00 core-hours"),
            "{table}"
        );
        assert!(table.contains("finished") && table.contains("/data/out/a"));
    }

    #[test]
    fn slurm_time_rounds_up_to_the_minute() {
        assert_eq!(slurm_time(61.0), "0-00:02:00");
        assert_eq!(slurm_time(10.0), "0-00:01:00");
        assert_eq!(slurm_time(90_000.0), "1-01:00:00");
        // The limit leaves the margin and the factor; fewer cores than the timing had, longer.
        assert_eq!(time_limit_s(1000.0, 2), 2600.0);
        assert_eq!(time_limit_s(1000.0, 1), 4600.0);
        assert_eq!(time_limit_s(1000.0, 8), 2600.0);
    }

    #[test]
    fn the_script_runs_each_task_on_its_folder() {
        let runs = [run("a", 100.0, false), run("b b", 4000.0, false)];
        let command = TaskCommand {
            executable: "/opt/geardyn/bin/geardyn".into(),
            checkpoint_every_s: 300.0,
            force: false,
        };
        let options = ClusterOptions {
            partition: Some("long".into()),
            sbatch_options: vec!["--qos=fe".into()],
            ..Default::default()
        };
        let script = sbatch_script(
            "geardyn-compare",
            &runs,
            &command,
            &options,
            "/logs".as_ref(),
        );
        assert!(script.contains("#SBATCH --array=0-1\n"), "{script}");
        assert!(script.contains(&format!("#SBATCH --time={}\n", slurm_time(8600.0))));
        // 1.2e9 B × 1.5 = 1.8e9 B = 1716.6 MiB.
        assert!(script.contains("#SBATCH --mem=1717M\n"), "{script}");
        assert!(script.contains("#SBATCH --signal=B:TERM@120\n"));
        assert!(script.contains("#SBATCH --cpus-per-task=2\n"));
        assert!(script.contains("#SBATCH --partition=long\n#SBATCH --qos=fe\n"));
        assert!(script.contains("  1) scene=high-unmodified dir='/data/out/b b' ;;"));
        assert!(script.contains("--output=/logs/%A_%a.log"));
        assert!(script.contains(
            "exec /opt/geardyn/bin/geardyn fe \"$dir/case.toml\" --scene \"$scene\" --out \"$dir\" --reuse --checkpoint-every-s 300\n"
        ));
    }

    #[test]
    fn quoting_survives_the_shell() {
        assert_eq!(shell_quote("/a/b-c_1.toml"), "/a/b-c_1.toml");
        assert_eq!(shell_quote("it's"), "'it'\\''s'");
        assert_eq!(shell_quote(""), "''");
    }

    #[test]
    fn the_queue_is_read_per_task() {
        assert_eq!(
            parse_sbatch_job_id("Submitted batch job 4711\n"),
            Some(4711)
        );
        assert_eq!(parse_sbatch_job_id("4712;cluster\n"), Some(4712));
        assert_eq!(
            parse_sbatch_job_id("sbatch: error: invalid partition"),
            None
        );
        let counts = parse_squeue(
            "12_0 RUNNING None\n12_[2-4,7%2] PENDING Priority\n12_1 COMPLETING None\n\n",
        );
        assert_eq!(
            counts,
            QueueCounts {
                pending: 4,
                running: 1,
                other: 1,
                stuck: None,
            }
        );
        assert_eq!(counts.in_queue(), 6);
        assert_eq!(parse_squeue(""), QueueCounts::default());
        // Waiting for resources clears itself; a hold or a limit above the partition's does not.
        assert_eq!(parse_squeue("12_0 PENDING Resources\n").stuck, None);
        assert_eq!(
            parse_squeue("12_0 RUNNING None\n12_1 PENDING PartitionTimeLimit\n").stuck,
            Some("task 12_1 is PENDING (PartitionTimeLimit)".to_string())
        );
        assert!(parse_squeue("12_0 REQUEUE_HOLD JobHeldAdmin\n")
            .stuck
            .is_some());
    }

    #[test]
    fn a_log_gives_its_last_lines() {
        assert_eq!(last_lines("a\nb\n\nc\nd\n", 2), "c\nd");
        assert_eq!(last_lines("a", 5), "a");
    }
}
