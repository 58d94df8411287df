//! The same case and command give bit-identical CSV and JSON whatever the thread count: every
//! parallel loop collects in order and no floating-point reduction depends on how the work is
//! split. Only the run's timings differ, and a summary names them: their keys contain `wall`
//! (`geardyn::report::is_timing_key`).

use std::collections::BTreeMap;
use std::path::PathBuf;

mod common;

use assert_cmd::Command;
use common::{coarse_case, outputs};

/// Runs `args` (with `--out DIR` appended) under 1, 2 and 8 rayon threads and asserts that
/// every CSV and JSON file is identical once the timings are removed (CSV text byte for byte,
/// JSON value by value, so a float must round-trip to the same bits).
fn assert_deterministic(name: &str, args: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    // A coarse LTCA mesh keeps the five commands to about a minute in all.
    let case = coarse_case(dir.path());
    let mut reference: Option<(usize, BTreeMap<PathBuf, Vec<u8>>)> = None;
    for threads in [1, 2, 8] {
        let out = dir.path().join(format!("{name}-{threads}"));
        let output = Command::cargo_bin("geardyn")
            .unwrap()
            .env("RAYON_NUM_THREADS", threads.to_string())
            .args(args)
            .arg(&case)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        assert!(
            output.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        let files = outputs(&out);
        assert!(
            files.keys().any(|p| p.ends_with("summary.json")),
            "{name}: no summary"
        );
        let Some((first_threads, first)) = &reference else {
            reference = Some((threads, files));
            continue;
        };
        assert_eq!(
            first.keys().collect::<Vec<_>>(),
            files.keys().collect::<Vec<_>>(),
            "{name}: different files with {first_threads} and {threads} threads"
        );
        common::assert_same_outputs(
            first,
            &files,
            &format!("{name}: with {first_threads} and {threads} threads"),
        );
    }
}

#[test]
fn ltca_is_bit_identical_across_thread_counts() {
    assert_deterministic("ltca", &["ltca", "--positions", "16"]);
}

#[test]
fn sweep_is_bit_identical_across_thread_counts() {
    assert_deterministic("sweep", &["sweep", "--rpm", "1000:12000:60"]);
}

#[test]
fn stability_is_bit_identical_across_thread_counts() {
    assert_deterministic("stability", &["stability", "--rpm", "2000:20000:60"]);
}

#[test]
fn optimize_is_bit_identical_across_thread_counts() {
    assert_deterministic(
        "optimize",
        &["optimize", "--positions", "16", "--rpm", "1000:12000:40"],
    );
}

#[test]
fn fe_is_bit_identical_across_thread_counts() {
    assert_deterministic(
        "fe",
        &[
            "fe",
            "--scene",
            "stiffness",
            "--set",
            "scene[stiffness].duration_s=0.004",
            "--set",
            "scene[stiffness].ramp_s=0.002",
            "--set",
            "scene[stiffness].cover_pitch=false",
        ],
    );
}
