//! The same case and command give bit-identical CSV and JSON whatever the thread count: every
//! parallel loop collects in order and no floating-point reduction depends on how the work is
//! split. Only the run's timings differ, and a summary names them: their keys contain `wall`
//! (`geardyn::report::is_timing_key`).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

mod common;

use assert_cmd::Command;
use common::coarse_case;
use geardyn::report::is_timing_key;

/// Every CSV and JSON file under `dir`, by path relative to it.
fn outputs(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut files = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(folder) = stack.pop() {
        for entry in std::fs::read_dir(&folder).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if matches!(
                path.extension().and_then(|e| e.to_str()),
                Some("csv" | "json")
            ) {
                let bytes = std::fs::read(&path).unwrap();
                files.insert(path.strip_prefix(dir).unwrap().to_path_buf(), bytes);
            }
        }
    }
    files
}

/// A JSON value with every timing key removed, at any depth.
fn without_timings(value: serde_json::Value) -> serde_json::Value {
    match value {
        serde_json::Value::Object(map) => map
            .into_iter()
            .filter(|(key, _)| !is_timing_key(key))
            .map(|(key, v)| (key, without_timings(v)))
            .collect(),
        serde_json::Value::Array(items) => items.into_iter().map(without_timings).collect(),
        other => other,
    }
}

/// A CSV's text with every timing column (by header) removed.
fn csv_without_timings(bytes: &[u8]) -> String {
    let text = std::str::from_utf8(bytes).unwrap();
    let mut lines = text.lines();
    let Some(header) = lines.next() else {
        return String::new();
    };
    let keep: Vec<bool> = header.split(',').map(|h| !is_timing_key(h)).collect();
    std::iter::once(header)
        .chain(lines)
        .map(|line| {
            line.split(',')
                .zip(&keep)
                .filter(|(_, keep)| **keep)
                .map(|(cell, _)| cell)
                .collect::<Vec<_>>()
                .join(",")
        })
        .collect::<Vec<_>>()
        .join("\n")
}

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
        for (path, bytes) in &files {
            let expected = &first[path];
            if path.extension().is_some_and(|e| e == "json") {
                let parse = |b: &[u8]| without_timings(serde_json::from_slice(b).unwrap());
                assert_eq!(
                    parse(expected),
                    parse(bytes),
                    "{name}: {} differs between {first_threads} and {threads} threads",
                    path.display()
                );
            } else {
                assert!(
                    csv_without_timings(expected) == csv_without_timings(bytes),
                    "{name}: {} differs between {first_threads} and {threads} threads",
                    path.display()
                );
            }
        }
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
        ],
    );
}
