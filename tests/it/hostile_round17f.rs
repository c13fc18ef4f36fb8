//! Session 55 (issue #33, hostile run 16's defect 1, "the column-scale screen yields to the
//! bump test on free poses"): on the KR's free poses (the independent generator's file) a
//! `cmd_5` scaled by 2.5 % was named by the column-scale screen, yet the block test on the
//! calibration that had absorbed it found a step at lines 474-482 and the warning named a bump
//! alone; an `x_mm` scaled by 2.5 % was named a bump of the poses from line 780 on by the
//! nominal model's slip search. The slip and block tests now run, where the screen named a
//! scale, on the poses with the scale undone and calibrated again, and a step is said only
//! where it remains there (beside the scale) or its block moved back fits better than the
//! scale undone: the scale is named, no bump; a real bump (the poses from row 200 on moved
//! 2 mm) is still said; the clean file says neither.
//!
//! On the 7-axis arm's free poses an `x_mm` or `y_mm` scaled by 2.5-5 % passed the screen on
//! the geometric fit (`|t|` 120-350) but the fit of every identified parameter failed on the
//! poses as read (the scale pulled a transmission's harmonics where the robot cannot go), and
//! the screen stopped: only the profile's "not named" note, or the wrong axis. That fit is now
//! made on the poses with the geometry's finding undone, and the poses as read are tested at
//! it: the column is named.

use crate::common::altered_csv;
use crate::hostile_round14a::{calibrate, free_poses_of, robot, scaled};
use std::path::{Path, PathBuf};

/// Fields of the measurement CSV: `x_mm` is 4, `z_mm` 6, `cmd_1` 7.
const X_MM: usize = 4;
const Z_MM: usize = 6;
const CMD_1: usize = 7;

/// The words of the block warnings (the slip search's and the change-point test's).
const MOVED: &str = "the instrument or the robot moved between them";

/// The independent generator's clean KR free poses, copied into `dir`, and its robot.
fn kr(dir: &Path) -> (PathBuf, PathBuf) {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/independent-freepose");
    let file = dir.join("kr.csv");
    std::fs::copy(data.join("clean.csv"), &file).unwrap();
    (file, data.join("kr-arm.toml"))
}

/// The columns the screen named first.
fn first(s: &axiscal::calibration::free_pose::FreePoseSummary) -> Option<&str> {
    s.scales.first().map(|n| n.scale.column.as_str())
}

/// The KR's `cmd_5` x1.025 and `x_mm` x1.025: each column is named and no bump is said; the
/// clean file names neither.
#[test]
fn a_column_scale_on_the_kr_is_named_not_a_bump() {
    let dir = tempfile::tempdir().unwrap();
    let (clean, robot) = kr(dir.path());
    let (e, s) = calibrate(dir.path(), &clean, &robot);
    assert!(s.scales.is_empty() && !e.contains(MOVED), "a false alarm: {e}");
    for (column, name) in [(CMD_1 + 4, "cmd_5"), (X_MM, "x_mm")] {
        let file = scaled(&clean, &format!("{name}.csv"), column, 1.025);
        let (e, s) = calibrate(dir.path(), &file, &robot);
        assert_eq!(first(&s), Some(name), "{e}");
        assert!(e.contains(&format!("`{name}` ")), "{e}");
        assert!(!e.contains(MOVED), "{name} named a bump: {e}");
    }
}

/// A real bump (`z_mm` +2 mm from the 200th data row on) beside no scale is still said.
#[test]
fn a_bump_on_the_kr_is_still_said() {
    let dir = tempfile::tempdir().unwrap();
    let (clean, robot) = kr(dir.path());
    let row = std::cell::Cell::new(0usize);
    let file = altered_csv(
        &clean,
        "bump.csv",
        |_| true,
        |f| {
            if row.get() >= 200 {
                f[Z_MM] = (f[Z_MM].parse::<f64>().unwrap() + 2.0).to_string();
            }
            row.set(row.get() + 1);
        },
    );
    let (e, _) = calibrate(dir.path(), &file, &robot);
    assert!(e.contains(MOVED), "the bump not said: {e}");
}

/// The 7-axis arm's free poses (seed 7, hostile run 16's file): clean, nothing named; `x_mm`
/// x1.025 and `y_mm` x1.05, that column named first.
#[test]
fn an_axis_scale_on_the_7_axis_arm_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let r = robot("arm7-dh");
    let clean = free_poses_of(dir.path(), "arm7-dh", 7, 150);
    let (e, s) = calibrate(dir.path(), &clean, &r);
    assert!(s.scales.is_empty(), "a false alarm: {e}");
    for (column, factor, name) in [(X_MM, 1.025, "x_mm"), (X_MM + 1, 1.05, "y_mm")] {
        let file = scaled(&clean, &format!("{name}.csv"), column, factor);
        let (e, s) = calibrate(dir.path(), &file, &r);
        assert_eq!(first(&s), Some(name), "{e}");
        let read = s.scales[0].scale.factor;
        assert!(
            (read - factor).abs() < 5.0 * s.scales[0].scale.sigma,
            "{name} read {read} for {factor}: {e}"
        );
        assert!(!e.contains("not named"), "{e}");
    }
}
