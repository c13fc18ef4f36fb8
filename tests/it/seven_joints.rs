//! A seven-joint arm (`scenarios/robots/arm7-dh.toml`) through every command a campaign uses:
//! `plan`, `simulate` (its default truth: the description perturbed by the shipped default
//! manufacturing errors), `calibrate`, `validate` and `diagnose`.

use crate::common;

use crate::common::{axiscal, stderr, stdout};
use axiscal::calibration::procedure::Calibration;

#[test]
fn a_seven_joint_arm_plans_simulates_calibrates_validates_and_diagnoses() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name);
    let plan = axiscal()
        .args(["plan", "--robot", "arm7-dh", "--out"])
        .arg(path("plan.csv"))
        .assert()
        .success();
    assert!(stdout(&plan).contains("wrote"), "{}", stdout(&plan));
    let sim = axiscal()
        .args([
            "simulate", "--robot", "arm7-dh", "--sim", "analytic", "--seed", "2", "--out",
        ])
        .arg(path("data.csv"))
        .assert()
        .success();
    assert!(
        stdout(&sim).contains("perturbed by the default manufacturing errors"),
        "{}",
        stdout(&sim)
    );
    for k in 1..=7 {
        assert!(
            stdout(&sim).contains(&format!("axis{k} ")),
            "joint {k} swept: {}",
            stdout(&sim)
        );
    }
    axiscal()
        .args(["calibrate", "--robot", "arm7-dh"])
        .arg(path("data.csv"))
        .arg("--out")
        .arg(path("cal"))
        .assert()
        .success();
    let cal: Calibration = common::read_calibration(&path("cal"));
    assert_eq!(cal.axes.len(), 7);
    assert_eq!(cal.robot.joints.len(), 7);
    let urdf = std::fs::read_to_string(path("cal").join("calibrated.urdf")).unwrap();
    assert!(urdf.contains("<joint name=\"joint_7\""));
    let validate = axiscal()
        .args(["validate", "--robot", "arm7-dh", "--calibration"])
        .arg(path("cal").join("calibration.json"))
        .arg(path("data.csv"))
        .arg("--out")
        .arg(path("val"))
        .assert()
        .success();
    assert!(stdout(&validate).contains("validation"), "{}", stdout(&validate));
    let diagnose = axiscal()
        .args([
            "diagnose",
            "--robot",
            "arm7-dh",
            "--noise-trials",
            "2",
            "--noise-draws",
            "2",
        ])
        .args(["--axis-replicas", "10"])
        .arg(path("data.csv"))
        .arg("--out")
        .arg(path("diag"))
        .assert()
        .success();
    assert!(path("diag").join("diagnosis.json").is_file(), "{}", stderr(&diagnose));
}

/// A truth of another joint count than the description is refused, naming both.
#[test]
fn a_truth_of_another_robot_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let run = axiscal()
        .args(["simulate", "--robot", "arm7-dh", "--truth", "arm6-dh-truth", "--out"])
        .arg(dir.path().join("data.csv"))
        .assert()
        .code(2);
    let message = stderr(&run);
    assert!(
        message.contains("has 6 joints") && message.contains("has 7"),
        "{message}"
    );
}
