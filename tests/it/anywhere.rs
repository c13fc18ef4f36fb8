//! The binary works outside the checkout: only the built binary's path is taken, and every
//! command runs in an empty temporary folder, with the shipped robot addressed by name
//! (`--robot asea-irb6l`), as after `cargo install --path .`.

use std::path::{Path, PathBuf};
use std::process::Output;

/// The built binary, by path only (nothing else of the checkout is used).
fn binary() -> PathBuf {
    assert_cmd::cargo::cargo_bin("axiscal")
}

/// Runs the binary with `args` in `dir`.
fn run_in(dir: &Path, args: &[&str]) -> Output {
    std::process::Command::new(binary())
        .current_dir(dir)
        .args(args)
        .output()
        .expect("the binary runs")
}

fn assert_ok(out: &Output, what: &str) {
    assert!(
        out.status.success(),
        "{what} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn simulate_calibrate_compensate_diagnose_from_an_empty_folder() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    assert_eq!(std::fs::read_dir(d).unwrap().count(), 0);
    let sim = run_in(
        d,
        &[
            "simulate",
            "--robot",
            "asea-irb6l",
            "--sim",
            "analytic",
            "--validation-poses",
            "12",
            "--seed",
            "3",
            "--out",
            "data.csv",
        ],
    );
    assert_ok(&sim, "simulate");
    // The robot is the default too: no --robot at all.
    assert_ok(&run_in(d, &["calibrate", "data.csv", "--out", "cal"]), "calibrate");
    assert!(d.join("cal/calibration.json").is_file());
    let pose = first_validation_pose(&d.join("cal/calibration.json"));
    std::fs::write(
        d.join("poses.csv"),
        format!("id,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg\n1,{pose}\n"),
    )
    .unwrap();
    let comp = run_in(
        d,
        &[
            "compensate",
            "--calibration",
            "cal/calibration.json",
            "--robot",
            "asea-irb6l",
            "--poses",
            "poses.csv",
            "--out",
            "commands.csv",
        ],
    );
    assert_ok(&comp, "compensate");
    let diag = run_in(
        d,
        &[
            "diagnose",
            "data.csv",
            "--robot",
            "asea-irb6l",
            "--out",
            "diag",
            "--noise-trials",
            "2",
            "--noise-draws",
            "1",
            "--axis-replicas",
            "2",
        ],
    );
    assert_ok(&diag, "diagnose");
    assert!(d.join("diag/diagnosis.json").is_file());
}

/// A reachable tool pose: the nominal robot's tool frame at a mid-range command, as
/// `x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg` (rotation `Rz(yaw) Ry(pitch) Rx(roll)`).
fn first_validation_pose(calibration: &Path) -> String {
    let cal: axiscal::calibration::procedure::Calibration = axiscal::json_file::from_str(
        axiscal::json_file::Schema::CALIBRATION,
        &std::fs::read_to_string(calibration).unwrap(),
    )
    .unwrap();
    let q = [0.1, 0.2, -0.1, 0.3, 0.4, 0.2];
    let pose = cal.robot.phi_model().world_from_tool(&q);
    let t = pose.translation.vector * 1e3;
    let (roll, pitch, yaw) = pose.rotation.euler_angles();
    format!(
        "{},{},{},{},{},{}",
        t.x,
        t.y,
        t.z,
        roll.to_degrees(),
        pitch.to_degrees(),
        yaw.to_degrees()
    )
}

#[test]
fn an_unknown_name_lists_the_shipped_robots_and_a_missing_cause_is_printed_once() {
    let dir = tempfile::tempdir().unwrap();
    let out = run_in(dir.path(), &["simulate", "--robot", "no-such-arm", "--out", "x.csv"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("no-such-arm") && err.contains("asea-irb6l") && err.contains("scara-rrpr"),
        "{err}"
    );
    let out = run_in(dir.path(), &["calibrate", "missing.csv", "--out", "cal"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("missing.csv"), "{err}");
    assert_eq!(err.matches("os error 2").count(), 1, "{err}");
}

#[test]
fn a_shipped_scenario_runs_by_name_from_an_empty_folder() {
    let dir = tempfile::tempdir().unwrap();
    let out = run_in(
        dir.path(),
        &["run", "ci-smoke", "--trials", "2", "--threads", "1", "--out", "r"],
    );
    assert!(
        matches!(out.status.code(), Some(0 | 1)),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(dir.path().join("r").is_dir());
}
