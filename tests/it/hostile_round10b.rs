//! Helper h10b (hostile run 9, NS3): one coordinate column scaled, an instrument axis 0.3 %
//! off (`x_mm` x1.003 in every row), passed `calibrate` silently: each arc or pose alone takes
//! the stretch as a tilt. `calibrate` now re-fits with the column rescaled (a profile of the
//! residual sum of squares) and names the axis when the robot's arcs and poses together
//! determine it; `validate` fits the column's scale against the fixed calibration as it does a
//! whole file's.

use crate::common::altered_csv;
use crate::common::hostile::{case, run_case};
use crate::hostile_round9b::{robot_path, simulated};
use std::path::Path;

/// The calibrate warning's words.
const AXIS_READS: &str = "axis reads";

/// The free poses (`moved_joint = 0`) of a simulation of `robot` as `fp.csv` in `dir`.
fn free_poses(dir: &Path, robot: &str, seed: u64) -> std::path::PathBuf {
    simulated(dir, robot, seed, 80, "all.csv");
    altered_csv(&dir.join("all.csv"), "fp.csv", |f| f[1] == "0", |_| {})
}

/// `file` (in `dir`) with its `x_mm` column (field 4) times 1.003, as `name`.
fn x_long(file: &Path, name: &str) -> std::path::PathBuf {
    altered_csv(
        file,
        name,
        |_| true,
        |f| {
            f[4] = (f[4].parse::<f64>().unwrap() * 1.003).to_string();
        },
    )
}

/// `calibrate FILE --robot ROBOT` in `dir`, its stderr.
fn calibrated(dir: &Path, file: &str, robot: &str, out: &str) -> String {
    let args = format!("calibrate {file} --robot {} --out {out}", robot_path(robot));
    run_case(dir, &case("calibrate", &args, 0, &[]))
}

#[test]
fn one_coordinate_column_scaled_in_free_poses_is_named() {
    for (robot, seed) in [("ur5e-dh", 1011), ("arm6-dh", 1012)] {
        let dir = tempfile::tempdir().unwrap();
        let clean = free_poses(dir.path(), robot, seed);
        x_long(&clean, "x.csv");
        let e = calibrated(dir.path(), "fp.csv", robot, "c");
        assert!(!e.contains(AXIS_READS), "{robot}: clean free poses: {e}");
        let e = calibrated(dir.path(), "x.csv", robot, "x");
        // Named by the coordinate-scale profile, or on free poses by the column-scale screen
        // before it (`free_pose/scales.rs`, which then leaves the profile unsaid).
        let profile = e.contains("`x_mm`: the instrument's x axis reads 1.00")
            && e.contains("check the instrument's scale along x");
        let screen = e.contains("a column scale explains the poses' residuals: `x_mm` reads 1.00")
            && e.contains("the instrument's axis scale");
        assert!(profile || screen, "{robot}: {e}");
    }
}

#[test]
fn one_coordinate_column_scaled_in_sweeps_is_named() {
    let robot = "boby-klimchik-arm";
    let dir = tempfile::tempdir().unwrap();
    simulated(dir.path(), robot, 1013, 0, "sw.csv");
    x_long(&dir.path().join("sw.csv"), "x.csv");
    let e = calibrated(dir.path(), "sw.csv", robot, "c");
    assert!(!e.contains(AXIS_READS), "clean sweeps: {e}");
    let e = calibrated(dir.path(), "x.csv", robot, "x");
    assert!(e.contains("`x_mm`: the instrument's x axis reads 1.00"), "{e}");
}

#[test]
fn validate_names_one_coordinate_column_scaled() {
    let robot = "ur5e-dh";
    let dir = tempfile::tempdir().unwrap();
    let clean = free_poses(dir.path(), robot, 1014);
    x_long(&clean, "x.csv");
    calibrated(dir.path(), "fp.csv", robot, "cal");
    let args = format!(
        "validate x.csv --calibration cal/calibration.json --robot {} --out v",
        robot_path(robot)
    );
    let e = crate::common::hostile::stderr_of_case(dir.path(), &case("validate", &args, 2, &[]));
    assert!(e.contains("with the `x_mm` column alone divided by 1.00"), "{e}");
    assert!(e.contains("the instrument's x axis reads 1.00"), "{e}");
}
