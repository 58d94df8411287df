//! Helpers shared by the integration tests that drive the binary.
// Each test crate includes this module and uses part of it.
#![allow(dead_code)]

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

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
