//! The executors of a study's explicit FE runs: here, several at once, or as a Slurm job
//! array that the study waits for ([`geardyn::study::cluster`] writes the script and reads the
//! queue). Either way each run ends in its own folder as `geardyn fe` leaves it, and the study
//! reads the folders the same way.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result};

use geardyn::case::Case;
use geardyn::report::{self, OutputDir};
use geardyn::study::cluster::{self, ClusterOptions, PlannedRun, TaskCommand};

use super::args::{CommonArgs, Executor};
use super::progress::{fe_run_reusing, folder_verdict, run_state, RunState, RunView};

/// One explicit FE run a study asks for.
#[derive(Clone)]
pub struct FeRunRequest {
    /// What it is for, e.g. "compare 4800 rpm" (the plan's and the queue report's name).
    pub label: String,
    pub case: Case,
    pub scene: String,
    pub dir: PathBuf,
}

/// A run that did not finish: why, in words (its error, or its task log's last lines).
pub type RunOutcome = std::result::Result<(), String>;

/// The error of `--submit-only` once the array is in the queue: the command stops there, and
/// `main` exits with success.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct Submitted(pub String);

/// How many times a run whose task ended unfinished with a checkpoint (time limit, preemption,
/// a cancelled task) is submitted again before it counts as failed.
const MAX_SUBMISSIONS: usize = 3;

/// Runs `runs` with the executor `args` asks for; `batch_dir` keeps the Slurm scripts, logs and
/// the record of submitted arrays. One outcome per run, in order.
pub fn execute(
    args: &CommonArgs,
    runs: &[FeRunRequest],
    batch_dir: &Path,
) -> Result<Vec<RunOutcome>> {
    // One folder is one run: two requests for it must ask the same run, which runs once.
    let mut unique: Vec<FeRunRequest> = Vec::new();
    let mut of_request = Vec::with_capacity(runs.len());
    for run in runs {
        let run = &FeRunRequest {
            dir: absolute(&run.dir)?,
            ..run.clone()
        };
        match unique.iter().position(|u| u.dir == run.dir) {
            Some(i) => {
                anyhow::ensure!(
                    unique[i].scene == run.scene && unique[i].case.is_same_case(&run.case.text),
                    "{} and {} would both run into {}: give them different folders",
                    unique[i].label,
                    run.label,
                    run.dir.display()
                );
                of_request.push(i);
            }
            None => {
                of_request.push(unique.len());
                unique.push(run.clone());
            }
        }
    }
    let outcomes = execute_unique(args, &unique, batch_dir)?;
    Ok(of_request.iter().map(|&i| outcomes[i].clone()).collect())
}

fn execute_unique(
    args: &CommonArgs,
    runs: &[FeRunRequest],
    batch_dir: &Path,
) -> Result<Vec<RunOutcome>> {
    match args.executor.executor {
        Executor::Local => {
            anyhow::ensure!(
                !args.executor.submit_only,
                "--submit-only needs --executor slurm"
            );
            Ok(local(args, runs))
        }
        Executor::Slurm => slurm(args, runs, batch_dir),
    }
}

/// The local executor: the runs taken in order by [`cluster::local_jobs`] workers (as many as
/// the runs still to make allow), each with its own thread pool of its share of the threads
/// and of the memory limit. Alone, a run shows itself as `geardyn fe` does; side by side, each
/// line and bar carries the run's label.
fn local(args: &CommonArgs, runs: &[FeRunRequest]) -> Vec<RunOutcome> {
    let requested = args.executor.jobs.map(|n| n as usize);
    let to_make = runs
        .iter()
        .filter(|run| run_state(&run.case, &run.dir) != RunState::Finished)
        .count();
    let (jobs, threads) = cluster::local_jobs(to_make, rayon::current_num_threads(), requested);
    let one = |run: &FeRunRequest, view: &RunView| -> RunOutcome {
        if geardyn::interrupt::stop_requested() {
            return Err("not run: the study was stopped".to_string());
        }
        let ran = fe_run_reusing(&run.case, &run.scene, &run.dir, view);
        // The folder's verdict where it has one, as the Slurm executor takes it; an error the
        // folder does not show (a write after the summary) still counts.
        match (ran, folder_verdict(&run.case, &run.dir)) {
            (Err(e), Some(Ok(())) | None) => Err(super::error_text(&e)),
            (_, Some(verdict)) => verdict,
            (Ok(()), None) => Err("the run left no summary".to_string()),
        }
    };
    if jobs <= 1 {
        return runs
            .iter()
            .map(|run| one(run, &RunView::default()))
            .collect();
    }
    eprintln!("{to_make} explicit FE runs to make, {jobs} at once on {threads} thread(s) each");
    // Each run checks its models against its share of the limit: they are held side by side.
    let whole = geardyn::resources::memory_limit();
    geardyn::resources::set_memory_limit(whole.as_ref().map(|limit| limit.shared(jobs)));
    let bars = indicatif::MultiProgress::new();
    let next = std::sync::atomic::AtomicUsize::new(0);
    let outcomes = std::sync::Mutex::new(vec![None; runs.len()]);
    std::thread::scope(|scope| {
        for _ in 0..jobs {
            scope.spawn(|| {
                // Without its own pool (the system refused the threads) a worker's runs go on
                // the global one.
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .ok();
                loop {
                    let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(run) = runs.get(i) else { break };
                    let view = RunView {
                        label: Some(run.label.clone()),
                        bars: Some(bars.clone()),
                    };
                    let outcome = match &pool {
                        Some(pool) => pool.install(|| one(run, &view)),
                        None => one(run, &view),
                    };
                    outcomes.lock().expect("no worker panics holding it")[i] = Some(outcome);
                }
            });
        }
    });
    geardyn::resources::set_memory_limit(whole);
    outcomes
        .into_inner()
        .expect("no worker panicked holding it")
        .into_iter()
        .map(|o| o.expect("every run was taken by a worker"))
        .collect()
}

/// The plan of `runs`: each one's cost, timed on its prepared scene, and whether its folder
/// already holds it finished.
pub fn plan(runs: &[FeRunRequest]) -> Result<Vec<PlannedRun>> {
    // Timed on as many threads as the estimates assume, whatever this host has (a login
    // node's 64 cores would promise a task's 2 a time limit it cannot keep).
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(cluster::CALIBRATION_CORES)
        .build()
        .context("cannot start the timing's thread pool")?;
    pool.install(|| planned(runs))
}

fn planned(runs: &[FeRunRequest]) -> Result<Vec<PlannedRun>> {
    runs.iter()
        .map(|run| {
            let scene = geardyn::study::fe::scene(&run.case, &run.scene)?;
            let finished = run_state(&run.case, &run.dir) == RunState::Finished;
            let (wall_s, memory_bytes) = if finished {
                (0.0, 0.0)
            } else {
                eprintln!("timing {} ({})", run.label, run.scene);
                let prepared = geardyn::study::fe::prepare(&run.case, scene)?;
                let cost = geardyn::study::fe::CostEstimate::of(&prepared, prepared.duration);
                let memory = geardyn::explicit::scene::run_memory(
                    &prepared,
                    prepared.duration,
                    run.case.fe.output_interval,
                );
                (cost.wall_s, memory.total() + cluster::PROCESS_BYTES)
            };
            Ok(PlannedRun {
                label: run.label.clone(),
                scene: run.scene.clone(),
                dir: run.dir.clone(),
                wall_s,
                memory_bytes,
                finished,
            })
        })
        .collect()
}

/// The record of the arrays a study submitted (`batch_dir`/submitted.json): a later call with
/// the same folder waits for a job still in the queue rather than submitting its runs again.
#[derive(serde::Serialize, serde::Deserialize, Default)]
struct Submissions {
    /// Per array: its job id and the run folders of its tasks, in task order.
    arrays: Vec<(u64, Vec<PathBuf>)>,
}

const SUBMISSIONS: &str = "submitted.json";

fn slurm(args: &CommonArgs, runs: &[FeRunRequest], batch_dir: &Path) -> Result<Vec<RunOutcome>> {
    let batch_dir = absolute(batch_dir)?;
    let log_dir = batch_dir.join("logs");
    // `#SBATCH --output=` takes no quotes, and `%` starts one of its patterns.
    let shown = log_dir.display().to_string();
    anyhow::ensure!(
        !shown.contains(|c: char| c.is_whitespace() || c == '%'),
        "the Slurm logs would go to {shown}, whose path has a space or a %, which an #SBATCH \
         line cannot carry: give --out a folder without them"
    );
    std::fs::create_dir_all(&log_dir)
        .with_context(|| format!("cannot create {}", log_dir.display()))?;
    let runs: Vec<FeRunRequest> = runs
        .iter()
        .map(|r| {
            Ok(FeRunRequest {
                dir: absolute(&r.dir)?,
                ..r.clone()
            })
        })
        .collect::<Result<_>>()?;
    let options = ClusterOptions {
        partition: args.executor.partition.clone(),
        account: args.executor.account.clone(),
        sbatch_options: args.executor.sbatch_options.clone(),
        cpus_per_task: args.executor.cpus_per_task,
    };
    let command = TaskCommand {
        executable: std::env::current_exe().context("cannot find the geardyn executable")?,
        checkpoint_every_s: args.checkpoint_every_s,
        force: args.force,
    };
    let mut submissions: Submissions = std::fs::read_to_string(batch_dir.join(SUBMISSIONS))
        .ok()
        .and_then(|text| serde_json::from_str(&text).ok())
        .unwrap_or_default();
    // Where each run's latest task logs: (job, task index).
    let mut task_of: Vec<Option<(u64, usize)>> =
        runs.iter()
            .map(|run| {
                submissions.arrays.iter().rev().find_map(|(job, dirs)| {
                    dirs.iter().position(|d| d == &run.dir).map(|i| (*job, i))
                })
            })
            .collect();
    let mut submitted = vec![0usize; runs.len()];
    // The first round submits every run not finished (a failed one runs again, as the local
    // executor runs it again); later rounds only the runs left with a checkpoint.
    let mut first_round = true;
    // Runs found queued in the first round (an earlier call's tasks): one whose task never
    // ran (cancelled while pending) may go round again like a first-round run.
    let mut waited_at_start = vec![false; runs.len()];
    loop {
        // Runs whose task is still queued are waited for, not submitted again.
        // A queue that does not answer stops the study: guessing "not queued" would submit
        // the same runs twice.
        let mut queued_jobs: Vec<u64> = Vec::new();
        for job in jobs_of(&task_of) {
            if queue(job)?.in_queue() > 0 {
                queued_jobs.push(job);
            }
        }
        let waiting = |i: usize| task_of[i].is_some_and(|(job, _)| queued_jobs.contains(&job));
        let mut to_submit = Vec::new();
        for (i, run) in runs.iter().enumerate() {
            let state = run_state(&run.case, &run.dir);
            if state == RunState::Finished || waiting(i) {
                waited_at_start[i] |= first_round && waiting(i);
                continue;
            }
            let retry_other = first_round || waited_at_start[i];
            if submitted[i] >= MAX_SUBMISSIONS || (state == RunState::Other && !retry_other) {
                continue;
            }
            if state == RunState::Other {
                clear_other_case(&run.dir)?;
            }
            // The task's case: the run writes the same file first, so a folder it was
            // submitted into is a folder of this case.
            std::fs::create_dir_all(&run.dir)
                .with_context(|| format!("cannot create {}", run.dir.display()))?;
            OutputDir(&run.dir).case(&run.case)?;
            to_submit.push(i);
        }
        if !to_submit.is_empty() {
            let planned = plan(
                &to_submit
                    .iter()
                    .map(|&i| runs[i].clone())
                    .collect::<Vec<_>>(),
            )?;
            let name = format!(
                "geardyn-{}",
                batch_dir
                    .parent()
                    .and_then(|p| p.file_name())
                    .map_or("study".into(), |n| n.to_string_lossy())
            );
            let script = cluster::sbatch_script(&name, &planned, &command, &options, &log_dir);
            let script_path = batch_dir.join(format!("array-{}.sh", submissions.arrays.len() + 1));
            report::write_atomic(&script_path, script.as_bytes())?;
            let job = sbatch(&script_path)?;
            eprintln!(
                "submitted Slurm job array {job}: {} explicit runs ({}); logs in {}",
                to_submit.len(),
                script_path.display(),
                log_dir.display()
            );
            for (task, &i) in to_submit.iter().enumerate() {
                task_of[i] = Some((job, task));
                submitted[i] += 1;
            }
            submissions.arrays.push((
                job,
                to_submit.iter().map(|&i| runs[i].dir.clone()).collect(),
            ));
            report::write_atomic(
                &batch_dir.join(SUBMISSIONS),
                serde_json::to_string_pretty(&submissions)?.as_bytes(),
            )?;
            if args.executor.submit_only {
                return Err(Submitted(format!(
                    "submitted job {job} ({} tasks); when it is done, run the same command again \
                     with the same --out to finish the study (`squeue -j {job}` shows it)",
                    to_submit.len()
                ))
                .into());
            }
        }
        first_round = false;
        let jobs = jobs_of(&task_of);
        if jobs.is_empty() {
            break;
        }
        if args.executor.submit_only && !queued_jobs.is_empty() {
            return Err(Submitted(format!(
                "nothing new to submit; jobs {queued_jobs:?} are still in the queue: run the same \
                 command again with the same --out once they are done"
            ))
            .into());
        }
        wait(&jobs, &runs, args.executor.poll_s)?;
        // Ended: a run unfinished with its checkpoint goes round again (up to MAX_SUBMISSIONS).
        let again = runs.iter().enumerate().any(|(i, run)| {
            run_state(&run.case, &run.dir) == RunState::Interrupted
                && submitted[i] < MAX_SUBMISSIONS
        });
        if !again {
            break;
        }
        eprintln!("some tasks ended before their runs finished (time limit, preemption or a cancel): submitting them again to go on from their checkpoints");
    }
    Ok(runs
        .iter()
        .enumerate()
        .map(|(i, run)| match run_state(&run.case, &run.dir) {
            RunState::Finished => folder_verdict(&run.case, &run.dir)
                .unwrap_or_else(|| Err(format!("{}: no summary", run.dir.display()))),
            state => {
                let log = task_of[i]
                    .map(|(job, task)| log_dir.join(format!("{job}_{task}.log")))
                    .and_then(|path| std::fs::read_to_string(path).ok())
                    .map_or("no task log".to_string(), |t| cluster::last_lines(&t, 6));
                let what = match state {
                    RunState::Interrupted => {
                        "its task ended before the run finished (its checkpoint is kept)"
                    }
                    _ => "its task failed",
                };
                Err(format!(
                    "{}: {what}; the task log ends:\n{log}",
                    run.dir.display()
                ))
            }
        })
        .collect())
}

/// The distinct jobs of the runs' latest tasks.
fn jobs_of(task_of: &[Option<(u64, usize)>]) -> Vec<u64> {
    let mut jobs: Vec<u64> = task_of.iter().flatten().map(|(job, _)| *job).collect();
    jobs.sort_unstable();
    jobs.dedup();
    jobs
}

/// Waits until no task of `jobs` is in the queue, with a progress line.
fn wait(jobs: &[u64], runs: &[FeRunRequest], poll_s: f64) -> Result<()> {
    let mut failures = 0;
    let mut last = String::new();
    loop {
        let mut counts = cluster::QueueCounts::default();
        let mut asked = true;
        for &job in jobs {
            match queue(job) {
                Ok(c) => {
                    if let Some(stuck) = c.stuck {
                        anyhow::bail!(
                            "Slurm job {job}: {stuck}, which waiting will not change: release \
                             it (scontrol release), or cancel it (scancel {job}) and run the \
                             study again with other --partition / --sbatch-option values"
                        );
                    }
                    counts.pending += c.pending;
                    counts.running += c.running;
                    counts.other += c.other;
                }
                Err(e) => {
                    asked = false;
                    failures += 1;
                    anyhow::ensure!(
                        failures < 10,
                        "the Slurm queue does not answer ({e}); the array goes on in the queue \
                         (jobs {jobs:?}): run the same command again later to collect it"
                    );
                }
            }
        }
        if asked {
            failures = 0;
            let done = runs
                .iter()
                .filter(|r| run_state(&r.case, &r.dir) == RunState::Finished)
                .count();
            // Out of the queue and not finished: failed, or left with a checkpoint to go on.
            let ended = runs.len().saturating_sub(done + counts.in_queue());
            let line = format!(
                "slurm jobs {jobs:?}: {} pending, {} running, {} other; {done} of {} runs \
                 finished, {ended} ended unfinished",
                counts.pending,
                counts.running,
                counts.other,
                runs.len()
            );
            if line != last {
                eprintln!("{line}");
                last = line;
            }
            if counts.in_queue() == 0 {
                return Ok(());
            }
        }
        if geardyn::interrupt::stop_requested() {
            anyhow::bail!(
                "stopped waiting; the array goes on in the queue (jobs {jobs:?}): run the same \
                 command again with the same --out to collect it"
            );
        }
        std::thread::sleep(std::time::Duration::from_secs_f64(poll_s));
    }
}

/// The job's tasks in the queue.
fn queue(job: u64) -> Result<cluster::QueueCounts> {
    let output = Command::new("squeue")
        .args(["-h", "-r", "-j", &job.to_string(), "-o", "%i %T %r"])
        .output()
        .context("cannot run squeue (is Slurm's client on the PATH?)")?;
    // A job the controller has forgotten is "Invalid job id": no task of it is queued.
    let stderr = String::from_utf8_lossy(&output.stderr);
    if !output.status.success() && !stderr.contains("Invalid job id") {
        anyhow::bail!(
            "squeue failed: {} (is SLURM_CONF set for this cluster?)",
            stderr.trim()
        );
    }
    Ok(cluster::parse_squeue(&String::from_utf8_lossy(
        &output.stdout,
    )))
}

fn sbatch(script: &Path) -> Result<u64> {
    let output = Command::new("sbatch")
        .arg("--parsable")
        .arg(script)
        .output()
        .context("cannot run sbatch (is Slurm's client on the PATH?)")?;
    let stdout = String::from_utf8_lossy(&output.stdout);
    anyhow::ensure!(
        output.status.success(),
        "sbatch refused {} (is SLURM_CONF set for this cluster?): {}{}",
        script.display(),
        String::from_utf8_lossy(&output.stderr).trim(),
        stdout.trim()
    );
    cluster::parse_sbatch_job_id(&stdout)
        .with_context(|| format!("sbatch printed no job id: {stdout:?}"))
}

/// A folder holding another case's run loses its checkpoint and summary before this case's
/// run is submitted into it, so the task can neither resume nor reuse the other case's.
fn clear_other_case(dir: &Path) -> Result<()> {
    for name in [report::fe::CHECKPOINT, "summary.json"] {
        match std::fs::remove_file(dir.join(name)) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(e).with_context(|| format!("cannot clear {}", dir.display()))
            }
            _ => {}
        }
    }
    Ok(())
}

fn absolute(path: &Path) -> Result<PathBuf> {
    std::path::absolute(path).with_context(|| format!("cannot resolve {}", path.display()))
}
