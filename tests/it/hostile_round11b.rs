//! Helper h11b (hostile run 10, PS2 / PU1 / K-S1): the coordinate-scale profile of `calibrate`
//! read a sliding joint's command scale as the scale of the instrument axis it travels along,
//! a scale of every coordinate as one column's, and said nothing on sweep files whose arcs
//! cannot pin a one-axis scale. The profile now tries each slide's commands and the three
//! columns together beside each column, and a file that lets a per-mille axis scale pass says
//! how large one would.

use crate::common::altered_csv;
use crate::common::hostile::{case, run_case};
use crate::hostile_round9b::{robot_path, simulated};
use std::path::{Path, PathBuf};

/// The calibrate warning's words for one instrument axis.
const AXIS_READS: &str = "axis reads";

/// The free poses (`moved_joint = 0`) of a simulation of `robot` as `fp.csv` in `dir`.
fn free_poses(dir: &Path, robot: &str, seed: u64) -> PathBuf {
    simulated(dir, robot, seed, 80, "all.csv");
    altered_csv(&dir.join("all.csv"), "fp.csv", |f| f[1] == "0", |_| {})
}

/// `file` with the fields `fields` of every row times `factor`, as `name`.
fn scaled(file: &Path, name: &str, fields: std::ops::Range<usize>, factor: f64) -> PathBuf {
    altered_csv(
        file,
        name,
        |_| true,
        |f| crate::common::scale_fields(f, fields.clone(), factor),
    )
}

/// `calibrate FILE --robot ROBOT` in `dir`, its stderr.
fn calibrated(dir: &Path, file: &str, robot: &str, out: &str) -> String {
    let args = format!("calibrate {file} --robot {} --out {out}", robot_path(robot));
    run_case(dir, &case("calibrate", &args, 0, &[]))
}

#[test]
fn a_slides_command_scale_is_not_an_instrument_axis() {
    let robot = "table-prpp";
    let dir = tempfile::tempdir().unwrap();
    let clean = free_poses(dir.path(), robot, 1111);
    // cmd_3 (field 9) of a slide read 0.8 % long.
    scaled(&clean, "c3.csv", 9..10, 1.008);
    let e = calibrated(dir.path(), "fp.csv", robot, "c");
    assert!(!e.contains(AXIS_READS) && !e.contains("slides) holds"), "clean: {e}");
    let e = calibrated(dir.path(), "c3.csv", robot, "x");
    // Named by the slide's profile, or on free poses by the column-scale screen before it.
    let profile = e.contains("`cmd_3` (joint 3 slides) holds 1.00");
    let screen = e.contains("a column scale explains the poses' residuals: `cmd_3` holds 1.00");
    assert!(profile || screen, "{e}");
    assert!(!e.contains("the instrument's y axis reads"), "{e}");
}

#[test]
fn every_coordinate_scaled_is_said_as_a_length_scale() {
    let robot = "table-prpp";
    let dir = tempfile::tempdir().unwrap();
    let clean = free_poses(dir.path(), robot, 1112);
    scaled(&clean, "xyz.csv", 4..7, 1.005);
    let e = calibrated(dir.path(), "xyz.csv", robot, "x");
    assert!(e.contains("every coordinate reads 1.00"), "{e}");
    assert!(e.contains("length standard"), "{e}");
    assert!(!e.contains(AXIS_READS), "{e}");
}

#[test]
fn a_sweep_file_that_cannot_pin_an_axis_scale_says_how_large_would_pass() {
    let robot = "asea-irb6l";
    let dir = tempfile::tempdir().unwrap();
    simulated(dir.path(), robot, 1113, 0, "sw.csv");
    scaled(&dir.path().join("sw.csv"), "y.csv", 5..6, 1.003);
    for file in ["sw.csv", "y.csv"] {
        let e = calibrated(dir.path(), file, robot, &file.replace(".csv", ""));
        assert!(!e.contains(AXIS_READS), "{file}: {e}");
        assert!(
            e.contains("one-axis instrument scales this file cannot show: "),
            "{file}: {e}"
        );
        assert!(
            e.contains("`y_mm` below") || e.contains("`y_mm` at any size"),
            "{file}: {e}"
        );
    }
}
