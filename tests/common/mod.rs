//! Helpers shared by the integration tests that drive the binary.
// Each test crate includes this module and uses part of it.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use geardyn::report::is_timing_key;

/// Starts `command`, waits for a line containing `marker` on its stdout or stderr (`stderr`
/// picks which), waits `delay` more, sends SIGTERM and returns the finished process's status
/// code and what it printed to stderr.
pub fn interrupt(
    command: &mut Command,
    marker: &str,
    stderr: bool,
    delay: Duration,
) -> (i32, String) {
    signal_after(command, marker, stderr, delay, "TERM")
}

/// [`interrupt`] with another signal (`"KILL"`: the process cannot react; its status code is
/// then -1).
pub fn signal_after(
    command: &mut Command,
    marker: &str,
    stderr: bool,
    delay: Duration,
    signal: &str,
) -> (i32, String) {
    let mut child: Child = command
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let (watched, other): (Box<dyn std::io::Read + Send>, Box<dyn std::io::Read + Send>) = if stderr
    {
        (
            Box::new(child.stderr.take().unwrap()),
            Box::new(child.stdout.take().unwrap()),
        )
    } else {
        (
            Box::new(child.stdout.take().unwrap()),
            Box::new(child.stderr.take().unwrap()),
        )
    };
    // Drain the other pipe so the child never blocks on it.
    let other = std::thread::spawn(move || {
        let mut text = String::new();
        let _ = std::io::Read::read_to_string(&mut BufReader::new(other), &mut text);
        text
    });
    let mut lines = BufReader::new(watched).lines();
    let mut seen = String::new();
    for line in lines.by_ref() {
        let line = line.unwrap();
        seen += &line;
        seen.push('\n');
        if line.contains(marker) {
            break;
        }
    }
    assert!(
        seen.contains(marker),
        "the run ended before printing {marker:?}:\n{seen}"
    );
    std::thread::sleep(delay);
    let killed = Command::new("kill")
        .args([&format!("-{signal}"), &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    for line in lines {
        seen += &line.unwrap();
        seen.push('\n');
    }
    let status = child.wait().unwrap();
    let other = other.join().unwrap();
    let stderr_text = if stderr { seen } else { other };
    (status.code().unwrap_or(-1), stderr_text)
}

/// No temporary file of an atomic write is left anywhere under `dir`.
pub fn assert_no_partial_files(dir: &std::path::Path) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            assert_no_partial_files(&path);
        } else {
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            assert!(!name.contains(".tmp"), "{} left behind", path.display());
        }
    }
}

/// The `summary.json` (or any JSON file) at `path`.
pub fn read_json(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// The embedded case with 0.6 mm LTCA flanks (seconds instead of minutes), written to
/// `dir/case.toml`.
pub fn coarse_case(dir: &std::path::Path) -> std::path::PathBuf {
    let case = dir.join("case.toml");
    std::fs::write(
        &case,
        include_str!("../../data/cases/paper36.toml")
            .replace("fine_element_mm = 0.2", "fine_element_mm = 0.6"),
    )
    .unwrap();
    case
}

/// Every CSV and JSON file under `dir`, by path relative to it.
pub fn outputs(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
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
pub fn without_timings(value: serde_json::Value) -> serde_json::Value {
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
pub fn csv_without_timings(bytes: &[u8]) -> String {
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

/// Asserts that two folders' outputs ([`outputs`]) are the same files with the same content once
/// timings are removed: CSV text byte for byte, JSON value by value (a float must round-trip to
/// the same bits). `what` names the comparison in a failure.
pub fn assert_same_outputs(
    expected: &BTreeMap<PathBuf, Vec<u8>>,
    actual: &BTreeMap<PathBuf, Vec<u8>>,
    what: &str,
) {
    assert_eq!(
        expected.keys().collect::<Vec<_>>(),
        actual.keys().collect::<Vec<_>>(),
        "{what}: different files"
    );
    for (path, bytes) in actual {
        let want = &expected[path];
        if path.extension().is_some_and(|e| e == "json") {
            let parse = |b: &[u8]| without_timings(serde_json::from_slice(b).unwrap());
            assert_eq!(
                parse(want),
                parse(bytes),
                "{what}: {} differs",
                path.display()
            );
        } else {
            assert!(
                csv_without_timings(want) == csv_without_timings(bytes),
                "{what}: {} differs",
                path.display()
            );
        }
    }
}

/// Runs `command` and asserts it succeeded; returns what it printed to stderr.
pub fn run_ok_stderr(command: &mut Command) -> String {
    let output = command.output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "{stderr}");
    stderr
}

/// A small relief study with its FE cross-check: `optimize --fe-check` of `candidates`
/// (comma-separated) at low speed only, the stiffness scene cut to 4 ms (about 15 s of time
/// loop per run on the coarse pair), into `out`. The executors' tests run it both ways.
pub fn small_fe_check(case: &Path, candidates: &str, out: &Path) -> Command {
    let mut command = Command::new(assert_cmd::cargo::cargo_bin!("geardyn"));
    command.arg("optimize").arg(case).args([
        "--positions",
        "16",
        "--rpm",
        "1000:12000:20",
        "--fe-check",
        "--fe-check-only",
        candidates,
        "--fe-check-scenes",
        "low",
        "--set",
        "scene[stiffness].duration_s=0.004",
        "--set",
        "scene[stiffness].ramp_s=0.002",
        "--set",
        "scene[stiffness].cover_pitch=false",
        "--out",
    ]);
    command.arg(out);
    command
}
