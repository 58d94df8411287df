//! The explicit FE runs of a study on a Slurm cluster: `optimize --fe-check --executor slurm`
//! gives the same fe_check.csv and run files (timings aside) as the local executor, and a task
//! cancelled mid-run is submitted again and goes on from its checkpoint.
//!
//! With `SLURM_CONF` in the environment the test uses that cluster; without, it starts the
//! one-node cluster of `contrib/slurm/local-cluster.sh` (installing Slurm with apt-get if
//! missing) and stops it at the end, and where Slurm cannot be installed it says so and skips.
//! Ignored by `cargo test` (it installs packages and starts daemons); `.ci/run` runs it by name:
//! `cargo test --release --test slurm -- --ignored`. About 2 minutes on 2 cores.

mod common;

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use common::{
    assert_no_partial_files, assert_same_outputs, coarse_case, outputs, run_ok_stderr,
    small_fe_check,
};

/// The study, with a checkpoint every second so a cancelled task loses little.
fn optimize(case: &Path, out: &Path) -> Command {
    let mut command = small_fe_check(case, "none,optimum-1", out);
    command.args(["--checkpoint-every-s", "1"]);
    command
}

/// Cancels the first task of the array in `log_dir` once its log shows the run 20 % through.
fn cancel_one_task_mid_run(log_dir: &Path, deadline: Duration) -> Option<String> {
    let start = Instant::now();
    while start.elapsed() < deadline {
        let logs = std::fs::read_dir(log_dir).into_iter().flatten().flatten();
        for log in logs {
            let name = log.file_name().to_string_lossy().into_owned();
            let Some(task) = name.strip_suffix(".log") else {
                continue;
            };
            let text = std::fs::read_to_string(log.path()).unwrap_or_default();
            if text.contains("explicit FE  20 %") {
                // "JOB_TASK": one task of the array.
                let status = Command::new("scancel").arg(task).status().unwrap();
                assert!(status.success(), "scancel {task} failed");
                return Some(name);
            }
        }
        std::thread::sleep(Duration::from_millis(200));
    }
    None
}

const LOCAL_CLUSTER: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/contrib/slurm/local-cluster.sh"
);

/// The local cluster this test started; stopped when dropped, also when an assertion fails.
struct LocalCluster;

impl Drop for LocalCluster {
    fn drop(&mut self) {
        let _ = Command::new(LOCAL_CLUSTER).arg("stop").status();
    }
}

/// The cluster to submit to: the environment's, or a local one started here (None where Slurm
/// cannot be installed: the script's exit code 3).
fn cluster() -> Option<Option<LocalCluster>> {
    if std::env::var_os("SLURM_CONF").is_some() {
        return Some(None);
    }
    let output = Command::new(LOCAL_CLUSTER).arg("start").output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    if output.status.code() == Some(3) {
        eprintln!("SKIPPED: no Slurm on this machine and none installable:\n{stderr}");
        return None;
    }
    assert!(
        output.status.success(),
        "{LOCAL_CLUSTER} start failed:\n{stderr}"
    );
    let stdout = String::from_utf8_lossy(&output.stdout);
    let conf = stdout
        .lines()
        .find_map(|l| l.strip_prefix("export SLURM_CONF="))
        .expect("the script prints the SLURM_CONF to export");
    // The test's own process and every child (sbatch, squeue, scancel, geardyn) read it.
    std::env::set_var("SLURM_CONF", conf.trim());
    Some(Some(LocalCluster))
}

#[test]
#[ignore = "installs and starts Slurm: run by .ci/run (cargo test --release --test slurm -- --ignored)"]
fn slurm_runs_equal_local_runs_and_a_cancelled_task_resumes() {
    let Some(_cluster) = cluster() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let case = coarse_case(dir.path());
    let local = dir.path().join("local");
    let slurm = dir.path().join("slurm");
    run_ok_stderr(&mut optimize(&case, &local));

    let log_dir = slurm.join("fe-check/slurm/logs");
    let canceller = {
        let log_dir = log_dir.clone();
        std::thread::spawn(move || cancel_one_task_mid_run(&log_dir, Duration::from_secs(300)))
    };
    let stderr = run_ok_stderr(optimize(&case, &slurm).args([
        "--executor",
        "slurm",
        "--poll-s",
        "1",
        "--cpus-per-task",
        "1",
    ]));
    let cancelled = canceller
        .join()
        .unwrap()
        .expect("no task log reached 20 % to cancel");
    assert!(stderr.contains("submitted Slurm job array"), "{stderr}");
    assert!(
        stderr.contains("submitting them again to go on from their checkpoints"),
        "the cancelled task {cancelled} was not submitted again:\n{stderr}"
    );
    // The second array holds the cancelled run alone, and its log says where it went on from.
    let arrays: Vec<&str> = stderr
        .lines()
        .filter_map(|l| l.strip_prefix("submitted Slurm job array "))
        .filter_map(|rest| rest.split(':').next())
        .collect();
    assert_eq!(
        arrays.len(),
        2,
        "one array, then one for the cancelled run:\n{stderr}"
    );
    let resumed_log = std::fs::read_to_string(log_dir.join(format!("{}_0.log", arrays[1])))
        .expect("the second array's task log");
    assert!(resumed_log.contains("resuming at step"), "{resumed_log}");
    assert!(stderr.contains("1 ended unfinished"), "{stderr}");
    assert_eq!(
        std::fs::read(local.join("fe_check.csv")).unwrap(),
        std::fs::read(slurm.join("fe_check.csv")).unwrap(),
        "fe_check.csv differs between the local and the Slurm executor"
    );
    // Every CSV and JSON of the study and of its runs, timings aside; the Slurm executor's own
    // folder (scripts, logs, submitted.json) is not a result.
    let mut through_slurm = outputs(&slurm);
    through_slurm.retain(|path, _| !path.starts_with("fe-check/slurm"));
    let here = outputs(&local);
    assert!(
        here.keys()
            .filter(|p| p.starts_with("fe-check") && p.ends_with("summary.json"))
            .count()
            == 2,
        "{:?}",
        here.keys()
    );
    assert_same_outputs(&here, &through_slurm, "local against Slurm");
    assert_no_partial_files(&slurm);
}
