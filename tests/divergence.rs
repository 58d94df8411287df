//! Divergence on the command line: a run whose response blows up stops with a message that names
//! the cause and the remedy, exits non-zero, and leaves every result up to that point on disk.
//! (The optimizer's failure path and the contact solve's are tested on synthetic inputs in
//! tests/optimize.rs and src/ltca/contact.rs; the lumped integrator's in tests/lumped.rs.)

mod common;

use assert_cmd::Command;

use common::{coarse_case, read_json};

fn geardyn() -> Command {
    Command::cargo_bin("geardyn").unwrap()
}

/// An explicit step 2.5× the stable one: the energy balance catches the blow-up within a few
/// dozen steps, the message says to lower fe.step_factor, the partial run is written.
#[test]
fn an_unstable_explicit_step_is_stopped_and_explained() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("fe");
    let output = geardyn()
        .args([
            "fe",
            "--scene",
            "stiffness",
            "--set",
            "fe.step_factor=2.5",
            "--set",
            "scene[stiffness].duration_s=0.004",
            "--set",
            "scene[stiffness].ramp_s=0.002",
            "--set",
            "scene[stiffness].cover_pitch=false",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("diverged") && stderr.contains("fe.step_factor below 1"),
        "{stderr}"
    );
    let summary = read_json(&out.join("summary.json"));
    assert!(summary["diverged"]
        .as_str()
        .is_some_and(|m| m.contains("energy")));
    assert!(out.join("history.csv").exists() && out.join("dte.png").exists());
}

/// The undamped lumped model inside its principal parametric-instability region (Floquet
/// multiplier 1.23 at 16 550 rpm on the potential-energy stiffness): the response grows without
/// bound. The sweep stops there with the multiplier and the remedy (damping), and keeps the
/// points swept before it. (In this switched system the unbounded growth holds only in a narrow
/// band of the region — elsewhere in it the up-sweep reaches a large bounded response, up to
/// 250 × the static force — so the grid is fine, 50 rpm. The speed moved from 16 700 rpm,
/// 100 rpm steps, when the model took the mesh's own mass, m_d = 10.2 g on m_e = 0.57 kg: the
/// same 1-DOF dynamics 0.88 % slower, √(m_e/(m_e + m_d)).)
#[test]
fn an_unbounded_lumped_response_is_stopped_and_explained() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sweep");
    let output = geardyn()
        .args([
            "sweep",
            "--stiffness",
            "pe",
            "--damping-ratio",
            "0",
            "--rpm",
            "16000:17500:31",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("diverged at 16550.0 rpm")
            && stderr.contains("parametric-instability")
            && stderr.contains("--damping-ratio"),
        "{stderr}"
    );
    let summary = read_json(&out.join("summary.json"));
    assert!(summary["diverged"].as_str().is_some());
    let checkpoint = read_json(&out.join("sweep_checkpoint.json"));
    let up = checkpoint["progress"]["up"].as_array().unwrap();
    assert_eq!(up.len(), 11, "the eleven speeds below 16 550 rpm");
    for point in up {
        let factor = point["dynamic_factor"].as_f64().unwrap();
        assert!(factor.is_finite() && factor < 100.0, "{point}");
    }
    // With damping the same speeds are a bounded steady state.
    let damped = geardyn()
        .args([
            "sweep",
            "--stiffness",
            "pe",
            "--damping-ratio",
            "0.05",
            "--rpm",
            "16000:17500:31",
            "--out",
        ])
        .arg(dir.path().join("damped"))
        .output()
        .unwrap();
    assert!(damped.status.success());
}

/// Resources up front: the paper's 3000 rpm scene on the LTCA's 0.2 mm mesh (51 000 elements,
/// 10 million steps) is announced with its estimate and refused before the time loop starts,
/// with the ways out (coarser mesh, shorter scene, --force).
#[test]
fn an_explicit_run_estimated_above_the_limit_is_refused_up_front() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("fe");
    let output = geardyn()
        .args([
            "fe",
            "--scene",
            "high-unmodified",
            "--fine-element-mm",
            "0.2",
            "--coarse-element-mm",
            "1.5",
            // Every engaging tooth fine for the whole run: on windows of fine teeth (the
            // default) this mesh is estimated at under the limit, and would run for hours.
            "--set",
            "fe.fine_teeth=scene",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("estimated: ") && stderr.contains("hours"),
        "{stderr}"
    );
    assert!(
        stderr.contains("above the 4.0 hours limit") && stderr.contains("--force"),
        "{stderr}"
    );
    assert!(!out.join("history.csv").exists(), "refused before it ran");
}

/// Memory up front, against a limit set for the test (GEARDYN_MEMORY_LIMIT_MB; the machine's
/// own is 80 % of its available memory): a mesh too large to build is refused on its counted
/// size before it is meshed; a stiffness factor too large is refused after the symbolic
/// analysis, before it is computed; --force builds it anyway.
#[test]
fn models_estimated_above_the_memory_limit_are_refused_up_front() {
    let dir = tempfile::tempdir().unwrap();
    let ltca = |limit_mb: &str, extra: &[&str]| {
        let output = geardyn()
            .env("GEARDYN_MEMORY_LIMIT_MB", limit_mb)
            .args(["ltca", "--relief", "none", "--positions", "8", "--out"])
            .arg(dir.path().join("ltca"))
            .args(extra)
            .output()
            .unwrap();
        (
            output.status.code(),
            String::from_utf8_lossy(&output.stderr).to_string(),
        )
    };
    // Elements of 0.02 mm everywhere: about 49 GB of triplets, refused at once.
    let (code, stderr) = ltca(
        "2000",
        &[
            "--set",
            "mesh.fine_element_mm=0.02",
            "--set",
            "mesh.coarse_element_mm=0.02",
        ],
    );
    assert_eq!(code, Some(1));
    for needed in [
        "stiffness matrices at 0.02 / 0.02 mm",
        "GB",
        "limit of 2.0 GB",
        "coarsen the mesh",
        "--force",
    ] {
        assert!(stderr.contains(needed), "{needed:?} missing: {stderr}");
    }
    // 0.2 mm everywhere: its meshes, triplets and K (718 MB) fit in 850 MB, a factor and its
    // workspace (993 MB) do not — refused after the symbolic analysis, before it is computed.
    let (code, stderr) = ltca(
        "850",
        &[
            "--set",
            "mesh.fine_element_mm=0.2",
            "--set",
            "mesh.coarse_element_mm=0.2",
        ],
    );
    assert_eq!(code, Some(1));
    assert!(
        stderr.contains("the Cholesky factor of a stiffness matrix of")
            && stderr.contains("limit of 850 MB"),
        "{stderr}"
    );
    // The default mesh under 30 MB is refused, and runs with --force.
    let (code, _) = ltca("30", &[]);
    assert_eq!(code, Some(1));
    let (code, stderr) = ltca("30", &["--force"]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(dir.path().join("ltca/summary.json").exists());
}

/// The relief study with an undamped lumped model on the secant force law: the candidates'
/// sweeps diverge near their resonances (on the default load-dependent law the stiffening holds
/// them even undamped on this coarse case). The optimization still finishes and writes
/// everything, each diverged sweep keeps its speeds before the divergence, and the command
/// names them and exits non-zero.
#[test]
fn a_diverging_candidate_sweep_keeps_the_optimization_and_fails_the_command() {
    let dir = tempfile::tempdir().unwrap();
    let case = coarse_case(dir.path());
    let out = dir.path().join("optimize");
    let output = geardyn()
        .arg("optimize")
        .arg(&case)
        .args([
            "--positions",
            "16",
            "--rpm",
            "1000:12000:40",
            "--set",
            "lumped.damping_ratio=0",
            "--set",
            "lumped.force_law=secant",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("lumped sweeps of") && stderr.contains("diverged"),
        "{stderr}"
    );
    let summary = read_json(&out.join("summary.json"));
    let candidates = summary["candidates"].as_array().unwrap();
    assert!(summary["objective_optimum"].as_f64().unwrap().is_finite());
    assert!(out.join("sweep.csv").exists() && out.join("harris.csv").exists());
    assert!(candidates.iter().any(|c| c["sweep_diverged"]
        .as_str()
        .is_some_and(|m| m.contains("rpm"))));
}
