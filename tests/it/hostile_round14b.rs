//! Helper h14b (hostile run 13, Part A defect 5 / Part B S1): a one-axis instrument scale in a
//! sweep campaign was named as several command columns scaled (the IRB/L6 paper campaign's
//! `y_mm` x1.035 as `cmd_1` .. `cmd_4`, the UR5e's `z_mm` x1.03 as `cmd_2`, `cmd_3` and a `y_mm`
//! that was not scaled, the P-R-P-P table's `y_mm` x1.02 as `cmd_3`), the coordinate column
//! never named: each joint's fitted transmission takes its share of the scale, and the
//! coordinate-scale profile alone sees little of it. `calibrate` now compares one column's
//! scale (one parameter, with the points' fit counted) against a scale of each named command
//! column (`calibration/procedure/sanity/scale_source.rs`) and names the column where it
//! explains them, both where one joint departs and the two read alike; a genuine command
//! column's scale is still named as that column, and clean files stay quiet.

use crate::common::{altered_csv, axiscal, scale_fields, stderr};
use crate::hostile_round9b::{robot_path, simulated};
use std::path::Path;

/// `calibrate FILE [--robot ROBOT] --out OUT` in `dir` (exit 0): its stderr.
fn calibrated(dir: &Path, file: &str, robot: Option<&str>, out: &str) -> String {
    let mut c = axiscal();
    c.current_dir(dir).args(["calibrate", file, "--out", out]);
    if let Some(r) = robot {
        c.args(["--robot", &robot_path(r)]);
    }
    let a = c.timeout(std::time::Duration::from_secs(300)).assert().success();
    stderr(&a)
}

/// `file` in `dir` with field `field` (4 `x_mm` .. 6 `z_mm`, 7 `cmd_1`) times `factor`, the rows
/// `keep` refuses left out, as `name`.
fn scaled(dir: &Path, file: &str, name: &str, (field, factor): (usize, f64), keep: fn(&[String]) -> bool) {
    altered_csv(&dir.join(file), name, keep, |f| {
        scale_fields(f, field..field + 1, factor)
    });
}

/// The factor and sigma a warning gives a column it names (`the instrument's y axis reads F
/// times (+- S`), or `None`.
fn column_named(stderr: &str, column: &str) -> Option<(f64, f64)> {
    let label = format!("`{column}`: the instrument's {} axis reads ", &column[..1]);
    let line = stderr
        .lines()
        .find(|l| l.starts_with("warning:") && l.contains(&label))?;
    let rest = &line[line.find(&label)? + label.len()..];
    let factor = rest.split_whitespace().next()?.parse().ok()?;
    let sigma = rest.split("(+- ").nth(1)?.split([',', ')']).next()?.parse().ok()?;
    Some((factor, sigma))
}

/// The command columns a warning says look scaled, as a warning of their own.
fn commands_blamed(stderr: &str) -> Vec<String> {
    stderr
        .lines()
        .filter(|l| l.starts_with("warning: joint") && l.contains("looks scaled"))
        .filter_map(|l| Some(l.split("the column `").nth(1)?.split('`').next()?.to_owned()))
        .collect()
}

/// The factor named for `column` is within 5 sigma of `truth` (the sigma at least the 0.1 %
/// a drive departs by, which the slopes carry), and no command column is blamed.
fn named_alone(e: &str, column: &str, truth: f64) {
    let (factor, sigma) = column_named(e, column).unwrap_or_else(|| panic!("{column} not named: {e}"));
    assert!(
        (factor - truth).abs() < 5.0 * sigma.max(0.001),
        "{factor} +- {sigma} against {truth}: {e}"
    );
    assert!(commands_blamed(e).is_empty(), "{e}");
}

#[test]
fn the_paper_campaigns_one_axis_scales_are_named_as_their_column() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    axiscal()
        .current_dir(d)
        .args(["simulate", "--seed", "1401", "--out", "camp.csv"])
        .assert()
        .success();
    let clean = calibrated(d, "camp.csv", None, "clean");
    assert!(
        !clean.contains("the instrument's") && commands_blamed(&clean).is_empty(),
        "{clean}"
    );
    for (field, column, factor) in [(5, "y_mm", 1.035), (6, "z_mm", 1.05), (4, "x_mm", 0.97)] {
        let name = format!("{column}.csv");
        scaled(d, "camp.csv", &name, (field, factor), |_| true);
        let e = calibrated(d, &name, None, &format!("out-{column}"));
        named_alone(&e, column, factor);
    }
}

#[test]
fn a_ur5e_z_scale_is_named_as_z_with_and_without_validation_rows() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    simulated(d, "ur5e-dh", 1402, 20, "all.csv");
    scaled(d, "all.csv", "z.csv", (6, 1.03), |_| true);
    scaled(d, "all.csv", "zs.csv", (6, 1.03), |f| f[0] != "validation");
    for file in ["z.csv", "zs.csv"] {
        let e = calibrated(d, file, Some("ur5e-dh"), &format!("out-{file}"));
        named_alone(&e, "z_mm", 1.03);
        assert!(
            column_named(&e, "y_mm").is_none() && column_named(&e, "x_mm").is_none(),
            "{e}"
        );
    }
}

#[test]
fn a_slide_along_the_scaled_axis_says_both() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    simulated(d, "table-prpp", 1403, 20, "all.csv");
    scaled(d, "all.csv", "y.csv", (5, 1.02), |_| true);
    let e = calibrated(d, "y.csv", Some("table-prpp"), "out");
    let (factor, sigma) = column_named(&e, "y_mm").unwrap_or_else(|| panic!("{e}"));
    assert!((factor - 1.02).abs() < 5.0 * sigma.max(0.001), "{e}");
}

#[test]
fn a_genuine_command_column_scale_is_still_that_column() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (robot, joint) in [("arm6-dh", 2), ("ur5e-dh", 3)] {
        let all = format!("{robot}.csv");
        simulated(d, robot, 1404, 20, &all);
        let name = format!("c-{robot}.csv");
        scaled(d, &all, &name, (6 + joint, 1.03), |_| true);
        let e = calibrated(d, &name, Some(robot), &format!("out-{robot}"));
        assert_eq!(commands_blamed(&e), vec![format!("cmd_{joint}")], "{robot}: {e}");
        assert!(!e.contains("the instrument's"), "{robot}: {e}");
    }
}
