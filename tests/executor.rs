//! The Slurm executor's own path without a cluster: `tests/fake-slurm` stands in for sbatch
//! (runs every task of the array script at once, with Slurm's variables and log names) and
//! squeue (nothing queued). The array script must run as written, and the study must read its
//! runs to the same outputs as the local executor. The real cluster, with a cancelled task, is
//! tests/slurm.rs.

mod common;

use std::path::Path;
use std::process::Command;

use common::{
    assert_no_partial_files, assert_same_outputs, coarse_case, outputs, run_ok_stderr,
    small_fe_check,
};

fn optimize(case: &Path, out: &Path) -> Command {
    small_fe_check(case, "none", out)
}

#[test]
fn the_array_script_runs_and_the_study_reads_its_runs_as_the_local_executor_does() {
    let dir = tempfile::tempdir().unwrap();
    let case = coarse_case(dir.path());
    let local = dir.path().join("local");
    let slurm = dir.path().join("slurm");
    run_ok_stderr(&mut optimize(&case, &local));

    let fake = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fake-slurm");
    let path = format!("{fake}:{}", std::env::var("PATH").unwrap_or_default());
    let state = dir.path().join("fake-slurm-state");
    std::fs::create_dir_all(&state).unwrap();
    let through_fake = || {
        let mut command = optimize(&case, &slurm);
        command
            .args(["--executor", "slurm", "--poll-s", "0.1"])
            .env("PATH", &path)
            .env("FAKE_SLURM_DIR", &state);
        command
    };
    let stderr = run_ok_stderr(&mut through_fake());
    assert!(
        stderr.contains("submitted Slurm job array 101: 1 explicit runs"),
        "{stderr}"
    );
    let log = std::fs::read_to_string(slurm.join("fe-check/slurm/logs/101_0.log")).unwrap();
    assert!(
        log.contains("task 0 (job 101, restart 0)") && log.contains("wrote "),
        "{log}"
    );
    let mut through_slurm = outputs(&slurm);
    through_slurm.retain(|path, _| !path.starts_with("fe-check/slurm"));
    assert_same_outputs(
        &outputs(&local),
        &through_slurm,
        "local against the array script",
    );

    // The same command again finds the run finished: nothing is submitted.
    let again = run_ok_stderr(&mut through_fake());
    assert!(!again.contains("submitted Slurm job array"), "{again}");
    assert_no_partial_files(&slurm);
}

/// The local executor's runs side by side (by default as many at once as threads, one thread
/// each) give the same outputs as one after the other on both threads (`--jobs 1`): a run's
/// results do not depend on its thread count, and each run keeps its own folder.
#[test]
fn local_runs_side_by_side_give_what_they_give_one_after_the_other() {
    let dir = tempfile::tempdir().unwrap();
    let case = coarse_case(dir.path());
    let (side_by_side, one_by_one) = (dir.path().join("side"), dir.path().join("serial"));
    let stderr = run_ok_stderr(
        small_fe_check(&case, "none,optimum-1", &side_by_side).env("RAYON_NUM_THREADS", "2"),
    );
    assert!(
        stderr.contains("2 explicit FE runs to make, 2 at once on 1 thread(s) each"),
        "{stderr}"
    );
    let serial = run_ok_stderr(
        small_fe_check(&case, "none,optimum-1", &one_by_one)
            .args(["--jobs", "1"])
            .env("RAYON_NUM_THREADS", "2"),
    );
    assert!(!serial.contains("at once"), "{serial}");
    assert_same_outputs(
        &outputs(&one_by_one),
        &outputs(&side_by_side),
        "side by side against one after the other",
    );
    assert_no_partial_files(&side_by_side);
}
