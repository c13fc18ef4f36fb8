//! A sweep run from its high end down (steps numbered as the commands fall) is the same
//! campaign as one run upward: the calibration predicts the same poses, and every transmission
//! keeps its order. Such files lost every transmission's harmonics ("the sweeps do not resolve
//! order 1") and missed their validation poses by four times the clean file's error.

use crate::common::{self, axiscal};
use std::path::{Path, PathBuf};

/// `file` with each sweep's steps numbered from its last (the rows as they are).
fn steps_reversed(file: &Path, name: &str) -> PathBuf {
    let text = std::fs::read_to_string(file).unwrap();
    let mut last = std::collections::BTreeMap::<String, u64>::new();
    for line in text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("experiment,"))
    {
        let f: Vec<&str> = line.split(',').collect();
        if f[1] != "0" {
            let step: u64 = f[2].parse().unwrap();
            let top = last.entry(f[0].to_owned()).or_default();
            *top = (*top).max(step);
        }
    }
    common::altered_csv(
        file,
        name,
        |_| true,
        |f| {
            if f[1] != "0" {
                f[2] = (last[&f[0]] - f[2].parse::<u64>().unwrap()).to_string();
            }
        },
    )
}

/// `validate`'s summary of `data` against `cal` (with `robot`).
fn validated(dir: &Path, data: &Path, cal: &str, robot: &[&str]) -> serde_json::Value {
    let out = dir.join(format!("val-{cal}"));
    axiscal()
        .arg("validate")
        .arg(data)
        .arg("--calibration")
        .arg(dir.join(cal).join("calibration.json"))
        .args(robot)
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

fn calibrated(dir: &Path, data: &Path, out: &str, robot: &[&str]) -> String {
    axiscal()
        .arg("calibrate")
        .arg(data)
        .args(robot)
        .arg("--out")
        .arg(dir.join(out))
        .assert()
        .success();
    std::fs::read_to_string(dir.join(out).join("report.md")).unwrap()
}

/// The paper robot and a UR5e, seeds 61 and 62 (run once as they came): the file's own
/// validation poses are predicted by both calibrations alike, to a hundredth of the noise.
#[test]
fn a_sweep_run_downward_calibrates_as_the_same_sweep_upward() {
    for (robot, seed) in [(None, 61), (Some("ur5e-dh"), 62)] {
        let dir = tempfile::tempdir().unwrap();
        let robot_args: Vec<&str> = robot.map_or(vec![], |r| vec!["--robot", r]);
        let mut simulate = axiscal();
        simulate
            .current_dir(dir.path())
            .args(["simulate", "--sim", "analytic", "--validation-poses", "20", "--seed"])
            .arg(seed.to_string())
            .args(&robot_args)
            .args(["--out", "up.csv"]);
        simulate.assert().success();
        let up = dir.path().join("up.csv");
        let down = steps_reversed(&up, "down.csv");
        let report_up = calibrated(dir.path(), &up, "cal-up", &robot_args);
        let report_down = calibrated(dir.path(), &down, "cal-down", &robot_args);
        let lowered = "the sweeps do not resolve order";
        assert_eq!(
            report_down.matches(lowered).count(),
            report_up.matches(lowered).count(),
            "{robot:?}: {report_down}"
        );
        let a = validated(dir.path(), &up, "cal-up", &robot_args);
        let b = validated(dir.path(), &up, "cal-down", &robot_args);
        let noise = a["noise_rms_3d_mm"].as_f64().unwrap();
        let (rms_up, rms_down) = (
            a["validation"]["rms_mm"].as_f64().unwrap(),
            b["validation"]["rms_mm"].as_f64().unwrap(),
        );
        assert!(
            (rms_up - rms_down).abs() < 0.01 * noise,
            "{robot:?}: validation RMS {rms_up} upward, {rms_down} downward (noise {noise})"
        );
    }
}
