//! SIGTERM to a running `geardyn`: the run stops at its next consistent state, every file on
//! disk is whole (no temporary file left), the summary says where it stopped, the exit code is
//! 130, and `--resume` finishes a sweep with the points an uninterrupted sweep gives.

mod common;

use std::path::Path;
use std::process::Command;
use std::time::Duration;

use common::{assert_no_partial_files, coarse_case, interrupt, read_json, signal_after};

use geardyn::report::is_timing_key;

fn geardyn() -> Command {
    Command::new(assert_cmd::cargo::cargo_bin!("geardyn"))
}

#[test]
fn an_interrupted_fe_run_keeps_its_history_and_says_where_it_stopped() {
    let dir = tempfile::tempdir().unwrap();
    let case = coarse_case(dir.path());
    let out = dir.path().join("fe");
    // The stiffness scene runs for minutes: the signal comes 2 s into the time loop.
    let (code, stderr) = interrupt(
        geardyn()
            .args(["fe", "--scene", "stiffness"])
            .arg(&case)
            .arg("--out")
            .arg(&out),
        " steps",
        false,
        Duration::from_secs(2),
    );
    assert_eq!(code, 130, "{stderr}");
    assert!(stderr.contains("interrupted at t ="), "{stderr}");
    let summary = read_json(&out.join("summary.json"));
    let message = summary["interrupted"].as_str().unwrap();
    assert!(message.contains("results up to t ="), "{message}");
    assert!(summary["diverged"].is_null());
    let mut history = csv::Reader::from_path(out.join("history.csv")).unwrap();
    let rows = history
        .records()
        .collect::<Result<Vec<_>, _>>()
        .unwrap()
        .len();
    assert!(rows > 1, "history.csv has {rows} rows");
    assert_no_partial_files(&out);
}

/// SIGTERM 1.5 s into the time loop of a 1 ms scene (about 14 s of loop on the coarse pair):
/// the run leaves its checkpoint, `fe --resume` goes on from it, and every CSV and the summary
/// (timings aside) equal the uninterrupted run's, byte for byte. Two scenes: 3000 rpm without
/// relief or friction, and 60 rpm with the paper's relief and μ = 0.15 (the friction history
/// crosses the checkpoint). At 3000 rpm a run killed outright (SIGKILL, 4 s into its loop) with
/// `--checkpoint-every-s 1` goes on from the last checkpoint it kept, to the same bytes. A
/// checkpoint is refused by another case and by another scene of the same case file and flags.
#[test]
fn an_interrupted_fe_run_resumes_to_the_uninterrupted_result() {
    let dir = tempfile::tempdir().unwrap();
    let case = coarse_case(dir.path());
    // The scenes shortened in the case itself, so two scenes share one effective case.
    let fe = |scene: &str, out: &Path| {
        let mut command = geardyn();
        command.args(["fe", "--scene", scene]).arg(&case);
        for shortened in ["high-unmodified", "high-modified", "low-modified-friction"] {
            command
                .arg("--set")
                .arg(format!("scene[{shortened}].duration_s=0.001"))
                .arg("--set")
                .arg(format!("scene[{shortened}].ramp_s=0.0003"));
        }
        command.arg("--out").arg(out);
        command
    };
    for scene in ["high-unmodified", "low-modified-friction"] {
        let parted = dir.path().join(format!("{scene}-parted"));
        let (code, stderr) = interrupt(
            &mut fe(scene, &parted),
            " steps",
            false,
            Duration::from_millis(1500),
        );
        assert_eq!(code, 130, "{stderr}");
        assert!(stderr.contains("--resume --out"), "{stderr}");
        assert!(parted.join("checkpoint.json").exists());
        assert_no_partial_files(&parted);
        if scene == "high-unmodified" {
            // The same case file and flags, another scene: the relief differs.
            let other = fe("high-modified", &parted)
                .arg("--resume")
                .output()
                .unwrap();
            assert!(!other.status.success());
            let stderr = String::from_utf8_lossy(&other.stderr);
            assert!(stderr.contains("made on another scene"), "{stderr}");
        } else {
            let other = fe(scene, &parted)
                .args(["--set", "fe.step_factor=0.8", "--resume"])
                .output()
                .unwrap();
            assert!(!other.status.success());
            let stderr = String::from_utf8_lossy(&other.stderr);
            assert!(stderr.contains("no run of this case"), "{stderr}");
        }
        let resumed = fe(scene, &parted).arg("--resume").output().unwrap();
        let resumed_err = String::from_utf8_lossy(&resumed.stderr);
        assert!(resumed.status.success(), "{resumed_err}");
        assert!(resumed_err.contains("resuming at step"), "{resumed_err}");
        assert!(
            !parted.join("checkpoint.json").exists(),
            "removed once finished"
        );

        let mut resumed_runs = vec![parted];
        if scene == "high-unmodified" {
            // Killed outright 4 s into the loop, keeping a checkpoint every second: it goes on
            // from the last one it kept.
            let killed = dir.path().join(format!("{scene}-killed"));
            let (code, _) = signal_after(
                fe(scene, &killed).args(["--checkpoint-every-s", "1"]),
                " steps",
                false,
                Duration::from_secs(4),
                "KILL",
            );
            assert_eq!(code, -1, "killed by the signal");
            assert!(killed.join("checkpoint.json").exists());
            assert!(!killed.join("summary.json").exists());
            let resumed = fe(scene, &killed).arg("--resume").output().unwrap();
            let resumed_err = String::from_utf8_lossy(&resumed.stderr);
            assert!(resumed.status.success(), "{resumed_err}");
            assert!(resumed_err.contains("resuming at step"), "{resumed_err}");
            resumed_runs.push(killed);
        }

        let whole = dir.path().join(format!("{scene}-whole"));
        assert!(fe(scene, &whole).output().unwrap().status.success());
        for run in &resumed_runs {
            for file in [
                "history.csv",
                "dte_spectrum.csv",
                "stiffness.csv",
                "stiffness_vs_ltca.csv",
            ] {
                assert_eq!(
                    std::fs::read(whole.join(file)).unwrap(),
                    std::fs::read(run.join(file)).unwrap(),
                    "{scene} {file}: the resumed run {} differs from the uninterrupted one",
                    run.display()
                );
            }
        }
        let parted = &resumed_runs[0];
        fn strip(v: &mut serde_json::Value) {
            if let Some(object) = v.as_object_mut() {
                object.retain(|k, _| !is_timing_key(k));
                object.values_mut().for_each(strip);
            }
        }
        let (mut a, mut b) = (
            read_json(&whole.join("summary.json")),
            read_json(&parted.join("summary.json")),
        );
        strip(&mut a);
        strip(&mut b);
        assert_eq!(a, b, "{scene}");
    }
}

#[test]
fn an_interrupted_sweep_resumes_to_the_uninterrupted_result() {
    let dir = tempfile::tempdir().unwrap();
    let rpm = "100:12000:20000";
    let sweep = |out: &Path| {
        let mut command = geardyn();
        command
            // ζ = 0.1: bounded through the resonance (at 0.05 this pair's response grows
            // without bound there, tests/divergence.rs).
            .args([
                "sweep",
                "--stiffness",
                "pe",
                "--damping-ratio",
                "0.1",
                "--rpm",
                rpm,
                "--out",
            ])
            .arg(out);
        command
    };
    let whole = dir.path().join("whole");
    let status = sweep(&whole).output().unwrap();
    assert!(status.status.success());

    let parted = dir.path().join("parted");
    let (code, stderr) = interrupt(
        &mut sweep(&parted),
        "sweeping",
        true,
        Duration::from_millis(1500),
    );
    assert_eq!(code, 130, "{stderr}");
    assert!(stderr.contains("--resume"), "{stderr}");
    let summary = read_json(&parted.join("summary.json"));
    assert!(
        summary["interrupted"]
            .as_str()
            .unwrap()
            .contains("of 20000 speeds up"),
        "{summary}"
    );
    assert!(parted.join("sweep_checkpoint.json").exists());
    assert!(!parted.join("sweep.csv").exists());
    assert_no_partial_files(&parted);

    // The wrong speeds are refused; the same ones finish the sweep.
    let wrong = geardyn()
        .args([
            "sweep",
            "--stiffness",
            "pe",
            "--damping-ratio",
            "0.1",
            "--rpm",
            "100:12000:300",
            "--resume",
            "--out",
        ])
        .arg(&parted)
        .output()
        .unwrap();
    assert!(!wrong.status.success());
    assert!(String::from_utf8_lossy(&wrong.stderr).contains("same --rpm"));
    let other_case = geardyn()
        .args([
            "sweep",
            "--stiffness",
            "pe",
            "--damping-ratio",
            "0.2",
            "--rpm",
            rpm,
        ])
        .args(["--resume", "--out"])
        .arg(&parted)
        .output()
        .unwrap();
    assert!(!other_case.status.success());
    assert!(String::from_utf8_lossy(&other_case.stderr).contains("another case"));
    let resumed = sweep(&parted).arg("--resume").output().unwrap();
    assert!(
        resumed.status.success(),
        "{}",
        String::from_utf8_lossy(&resumed.stderr)
    );
    assert!(!parted.join("sweep_checkpoint.json").exists());
    assert_eq!(
        std::fs::read(whole.join("sweep.csv")).unwrap(),
        std::fs::read(parted.join("sweep.csv")).unwrap(),
        "the resumed sweep differs from the uninterrupted one"
    );
    let strip = |mut v: serde_json::Value| {
        v.as_object_mut().unwrap().retain(|k, _| !is_timing_key(k));
        v
    };
    assert_eq!(
        strip(read_json(&whole.join("summary.json"))),
        strip(read_json(&parted.join("summary.json")))
    );
}

/// SIGTERM during `optimize --fe-check`'s first explicit run: the optimization's files are
/// whole, summary.json says the cross-check was interrupted and where its finished runs are,
/// exit code 130.
#[test]
fn an_interrupted_relief_cross_check_says_where_it_stopped() {
    let dir = tempfile::tempdir().unwrap();
    let case = coarse_case(dir.path());
    let out = dir.path().join("optimize");
    let (code, stderr) = interrupt(
        geardyn()
            .arg("optimize")
            .arg(&case)
            .args([
                "--positions",
                "16",
                "--rpm",
                "1000:12000:20",
                "--fe-check",
                "--out",
            ])
            .arg(&out),
        " steps",
        false,
        Duration::from_secs(1),
    );
    assert_eq!(code, 130, "{stderr}");
    let summary = read_json(&out.join("summary.json"));
    let message = summary["interrupted"].as_str().unwrap();
    assert!(message.contains("FE cross-check"), "{message}");
    assert!(out.join("iterations.csv").exists() && out.join("candidates.csv").exists());
    assert_no_partial_files(dir.path());
}
