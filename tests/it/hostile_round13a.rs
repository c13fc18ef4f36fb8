//! Helper h13a (hostile run 12, "the detection-limit line is false"): the line
//! `command-column scales this file cannot show: ...` promised that a column scaled beyond its
//! bound is named, yet on the real two-link arm (a 320-deg sweep) and the real positioner
//! (338 deg of joint 2 in free poses) `cmd_2` scaled by 2 % passed under "below 0.72 %" /
//! "below 0.81 %": the fitted harmonics take most of a scale up over most of a turn, and the
//! misses they leave widen the slope's sigma. The bound is now the test's minimum detectable
//! scale (Baarda's minimum detectable bias, `calibration/procedure/sanity/scale_absorption.rs`),
//! "at any size" where the fit takes a scale up as fast as it shows; and the line is printed
//! beside a transmission warning too, for the columns the warning does not name. Checked here
//! by injection: each column scaled by 1.25 times its stated bound is named, or refused.

use crate::common::{altered_csv, axiscal, real_data, stderr};
use crate::hostile_round9b::{robot_path, simulated};
use std::path::Path;

/// The console line of the command-column bounds.
const COMMAND_BOUNDS: &str = "command-column scales this file cannot show: ";

/// `calibrate FILE --robot ROBOT --out OUT` in `dir` (any exit code): the code and stderr.
fn calibrated(dir: &Path, file: &str, robot: &str, out: &str) -> (i32, String) {
    let a = axiscal()
        .current_dir(dir)
        .args(["calibrate", file, "--robot", robot, "--out", out])
        .timeout(std::time::Duration::from_secs(300))
        .assert();
    let code = a.get_output().status.code().unwrap_or(-1);
    assert!(code == 0 || code == 2, "exit {code}: {}", stderr(&a));
    (code, stderr(&a))
}

/// Each column's bound on the line (per cent), `None` for "at any size".
fn bounds(stderr: &str) -> Vec<(usize, Option<f64>)> {
    let Some(line) = stderr.lines().find(|l| l.contains(COMMAND_BOUNDS)) else {
        return Vec::new();
    };
    let body = &line[line.find(COMMAND_BOUNDS).unwrap() + COMMAND_BOUNDS.len()..];
    body.split("`cmd_")
        .skip(1)
        .map(|part| {
            let joint: usize = part[..part.find('`').unwrap()].parse().unwrap();
            let rest = &part[part.find('`').unwrap() + 1..];
            let bound = rest
                .strip_prefix(" below ")
                .and_then(|r| r.split_whitespace().next()?.parse().ok());
            (joint, bound)
        })
        .collect()
}

/// Whether a warning or note other than the bounds line names `cmd_{joint}`.
fn named(stderr: &str, joint: usize) -> bool {
    let column = format!("`cmd_{joint}`");
    stderr
        .lines()
        .filter(|l| l.starts_with("warning:") || l.starts_with("note:"))
        .any(|l| l.contains(&column) && !l.contains(COMMAND_BOUNDS))
}

/// `file` in `dir` with column `cmd_{joint}` (field `6 + joint`) times `factor`, as `name`.
fn scaled(dir: &Path, file: &str, name: &str, joint: usize, factor: f64) {
    altered_csv(
        &dir.join(file),
        name,
        |_| true,
        |f| crate::common::scale_fields(f, 6 + joint..7 + joint, factor),
    );
}

/// Every column of `file` with a finite bound, scaled by 1.25 times it (the sign alternating),
/// is named or refused (exit 2); returns `(columns injected, named, refused)`.
fn injected(dir: &Path, file: &str, robot: &str) -> (usize, usize, usize) {
    let (code, clean) = calibrated(dir, file, robot, "clean");
    assert_eq!(code, 0, "{clean}");
    let bounds = bounds(&clean);
    assert!(!bounds.is_empty(), "{clean}");
    let (mut count, mut named_count, mut refused) = (0, 0, 0);
    for (joint, bound) in bounds {
        let Some(bound) = bound else { continue };
        let sign = if joint % 2 == 1 { 1.0 } else { -1.0 };
        let name = format!("c{joint}.csv");
        scaled(dir, file, &name, joint, 1.0 + sign * 1.25 * bound / 100.0);
        let (code, e) = calibrated(dir, &name, robot, &format!("out{joint}"));
        count += 1;
        if code == 2 {
            refused += 1;
        } else {
            assert!(
                named(&e, joint),
                "{file}: cmd_{joint} scaled 1.25 x its {bound} % passed: {e}"
            );
            named_count += 1;
        }
    }
    (count, named_count, refused)
}

#[test]
fn each_sweep_column_scaled_beyond_its_bound_is_named_on_a_scara() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    simulated(d, "scara-rrpr", 1301, 0, "sw.csv");
    let (count, named, refused) = injected(d, "sw.csv", &robot_path("scara-rrpr"));
    assert!(count >= 3 && named + refused == count, "{count} {named} {refused}");
}

#[test]
fn each_free_pose_column_scaled_beyond_its_bound_is_named_on_a_positioner() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    simulated(d, "positioner-2axis", 1302, 60, "all.csv");
    altered_csv(&d.join("all.csv"), "fp.csv", |f| f[1] == "0", |_| {});
    let (count, named, refused) = injected(d, "fp.csv", &robot_path("positioner-2axis"));
    assert!(count >= 1 && named + refused == count, "{count} {named} {refused}");
}

#[test]
fn the_bounds_line_stays_beside_a_transmission_warning() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    simulated(d, "scara-rrpr", 1303, 0, "sw.csv");
    scaled(d, "sw.csv", "c1.csv", 1, 1.03);
    let (code, e) = calibrated(d, "c1.csv", &robot_path("scara-rrpr"), "out");
    assert_eq!(code, 0, "{e}");
    assert!(e.contains("warning: ") && named(&e, 1), "{e}");
    let columns: Vec<usize> = bounds(&e).iter().map(|b| b.0).collect();
    assert!(!columns.is_empty() && !columns.contains(&1), "{e}");
}

/// The real files of hostile run 12: `cmd_2` scaled by 2 % is named, refused, or within the
/// line's bound for it on that file.
#[test]
#[ignore = "needs ../shared/data/real/sscanss2-cpa and rct-two-axis-positioner (run by `make test-real`)"]
fn the_real_files_cmd_2_scaled_two_per_cent_is_named_or_within_its_bound() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_, two_link_robot) =
        crate::real_sscanss2::import_path(&real_data("sscanss2-cpa/two_link.csv"), "sscanss2-two-link", d);
    let two_link_robot = two_link_robot.display().to_string();
    let positioner = robot_path("positioner-2axis");
    axiscal()
        .args(["import", "rct"])
        .arg(real_data(
            "rct-two-axis-positioner/positioner_kinematic_measurements.yaml",
        ))
        .args(["--robot", &positioner, "--still-tolerance", "0.1", "--out"])
        .arg(d.join("rct.csv"))
        .assert()
        .success();
    for (file, robot) in [("data.csv", two_link_robot.as_str()), ("rct.csv", positioner.as_str())] {
        scaled(d, file, &format!("x-{file}"), 2, 1.02);
        let (code, e) = calibrated(d, &format!("x-{file}"), robot, &format!("out-{file}"));
        let (_, clean) = calibrated(d, file, robot, &format!("clean-{file}"));
        // The clean file's line states a bound for cmd_2 at or beyond 2 %, or "at any size",
        // or the 2 % scale is named or refused.
        let stated = bounds(&clean).into_iter().find(|b| b.0 == 2).map(|b| b.1);
        let covered = stated.is_some_and(|b| b.is_none_or(|b| b >= 2.0));
        assert!(code == 2 || named(&e, 2) || covered, "{file}: {clean}\n{e}");
    }
    let (count, named, refused) = injected(d, "data.csv", &two_link_robot);
    assert_eq!(named + refused, count);
}
