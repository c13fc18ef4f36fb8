//! The warnings `calibrate` gives on its results travel with the calibration: kept in
//! `calibration.json`'s `warnings` and report.md's "Warnings", said again by every command that
//! reads the file (`docs/formats.md#calibration-json`). A calibration written with a warning is
//! never used without one; a clean one carries none.

use crate::common::hostile::calibrated_campaign;
use crate::common::{altered_csv, axiscal, stderr};
use std::path::Path;

/// The words of every `warning:` line of a command's stderr.
fn warning_lines(err: &str) -> Vec<&str> {
    err.lines().filter_map(|l| l.strip_prefix("warning: ")).collect()
}

/// `calibrate DATA --out OUT` in `dir`: its stderr and the `warnings` it wrote.
fn calibrate(dir: &Path, data: &str, out: &str) -> (String, Vec<String>) {
    let err = stderr(
        &axiscal()
            .current_dir(dir)
            .args(["calibrate", data, "--out", out])
            .assert()
            .success(),
    );
    let text = std::fs::read_to_string(dir.join(out).join("calibration.json")).unwrap();
    let value: serde_json::Value = serde_json::from_str(&text).unwrap();
    let warnings = value
        .get("warnings")
        .map(|w| serde_json::from_value(w.clone()).expect("a list of strings"))
        .unwrap_or_default();
    (err, warnings)
}

/// The stderr of `joints`, `validate` and `compensate` with the calibration in `out`.
fn readers_stderr(dir: &Path, out: &str, data: &str) -> Vec<(&'static str, String)> {
    let cal = format!("{out}/calibration.json");
    std::fs::write(
        dir.join("poses.csv"),
        "id,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg\nref,-3151.5,5345.8,167.8,179.56,0.23,-89.01\n",
    )
    .unwrap();
    let joints = axiscal()
        .current_dir(dir)
        .args(["joints", "--calibration", &cal, "0", "0", "0", "0", "0", "0"])
        .assert()
        .success();
    let validate = axiscal()
        .current_dir(dir)
        .args(["validate", "--quiet", "--calibration", &cal, data, "--out"])
        .arg(format!("{out}-validated"))
        .assert();
    let compensate = axiscal()
        .current_dir(dir)
        .args(["compensate", "--calibration", &cal, "--poses", "poses.csv", "--out"])
        .arg(format!("{out}-commands.csv"))
        .assert();
    vec![
        ("joints", stderr(&joints)),
        ("validate", stderr(&validate)),
        ("compensate", stderr(&compensate)),
    ]
}

/// Each warning `calibrate` kept is one it printed, report.md lists it, and each reader of the
/// file says it again naming the file; the clean calibration keeps none and no reader says one.
fn assert_carried(dir: &Path, (err, warnings): (&str, &[String]), out: &str, data: &str) {
    let printed = warning_lines(err);
    for w in warnings {
        assert!(printed.contains(&w.as_str()), "kept but not printed: {w}\n{err}");
    }
    let report = std::fs::read_to_string(dir.join(out).join("report.md")).unwrap();
    for w in warnings {
        assert!(
            report.contains(&format!("- **{w}**")),
            "{w} not in report.md:\n{report}"
        );
    }
    let carried = format!("{out}/calibration.json: `axiscal calibrate` warned of this when it wrote the file");
    for (command, err) in readers_stderr(dir, out, data) {
        let said: Vec<&str> = warning_lines(&err)
            .into_iter()
            .filter_map(|l| l.strip_prefix(carried.as_str()))
            .collect();
        assert_eq!(said.len(), warnings.len(), "{command}:\n{err}");
        for (said, w) in said.iter().zip(warnings) {
            assert!(said.ends_with(w.as_str()), "{command}: {said} is not {w}");
        }
    }
}

#[test]
fn an_axis_calibration_s_warnings_travel_with_it() {
    let dir = tempfile::tempdir().unwrap();
    calibrated_campaign(dir.path(), 17);
    let clean = calibrate(dir.path(), "campaign.csv", "clean");
    assert!(clean.1.is_empty(), "{:?}", clean.1);
    assert_carried(dir.path(), (&clean.0, &clean.1), "clean", "campaign.csv");
    // One tool target 20 mm off: the tool fit misses it (as hostile_round4a's S2).
    altered_csv(
        &dir.path().join("campaign.csv"),
        "tool-off.csv",
        |_| true,
        |f| {
            if f[0] == "tool" && f[3] == "1" {
                f[4] = (f[4].parse::<f64>().unwrap() + 20.0).to_string();
            }
        },
    );
    let off = calibrate(dir.path(), "tool-off.csv", "off");
    assert!(
        off.1.iter().any(|w| w.starts_with("the tool frame's fit")),
        "{:?}\n{}",
        off.1,
        off.0
    );
    assert_carried(dir.path(), (&off.0, &off.1), "off", "tool-off.csv");
}

#[test]
fn a_free_pose_calibration_s_warnings_travel_with_it() {
    let dir = tempfile::tempdir().unwrap();
    crate::common::simulate_analytic(dir.path(), 120, 23, "campaign.csv");
    let free = |f: &[String]| f[1] == "0" && f[0] != "tool";
    let free_poses = altered_csv(&dir.path().join("campaign.csv"), "free.csv", free, |_| {});
    let clean = calibrate(dir.path(), "free.csv", "clean");
    assert!(clean.1.is_empty(), "{:?}", clean.1);
    assert_carried(dir.path(), (&clean.0, &clean.1), "clean", "free.csv");
    // The instrument moved 3 mm along x after the 60th pose.
    altered_csv(
        &free_poses,
        "moved.csv",
        |_| true,
        |f| {
            if f[2].parse::<usize>().unwrap() >= 60 {
                f[4] = (f[4].parse::<f64>().unwrap() + 3.0).to_string();
            }
        },
    );
    let moved = calibrate(dir.path(), "moved.csv", "moved");
    assert!(
        moved.1.iter().any(|w| w.contains("sit about (")),
        "{:?}\n{}",
        moved.1,
        moved.0
    );
    assert_carried(dir.path(), (&moved.0, &moved.1), "moved", "moved.csv");
}
