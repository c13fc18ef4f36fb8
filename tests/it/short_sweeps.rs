//! A quick campaign of short sweeps on the UR5e: five points over 30 degrees per joint. The
//! unit checks read a sweep's radius from the circles through its point triples; five points
//! make one triple over 15 degrees, whose circle bows about half a millimetre on the wrist and
//! measures the noise more than the radius. Such arcs are not judged (the triples' sagitta below
//! the checks' millimetre): clean files calibrate, where a wrist radius 1.3-1.4 times off read
//! as a command offset by a quarter turn (seeds 42 and 44) or a column in micrometres. A column
//! in other units still moves the sweep by far more than its noise and is still named.

use crate::common::{altered_experiment, axiscal, scale_fields, stderr};
use crate::hostile_round15s::robot;
use crate::hostile_round17j::simulated_with_plan;
use std::path::{Path, PathBuf};

/// A plan sweeping each joint once over 30 degrees in 4 intervals about the zero pose.
fn short_plan(dir: &Path) -> PathBuf {
    let mut text = String::from("reference = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]\n");
    for joint in (1..=6).rev() {
        text.push_str(&format!("\n[[sweeps]]\njoint = {joint}\nspan = 30.0\nintervals = 4\n"));
    }
    let path = dir.join("short.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// The UR5e's short campaign of `seed` (analytic, 20 validation poses) in `dir`.
fn short_campaign(dir: &Path, seed: u64) -> PathBuf {
    let plan = short_plan(dir);
    simulated_with_plan(dir, "ur5e-dh", &plan, seed, &format!("short_{seed}.csv"))
}

/// `calibrate` of `file` on the UR5e: exit code and stderr.
fn calibrate(dir: &Path, file: &Path) -> (i32, String) {
    let a = axiscal()
        .current_dir(dir)
        .args(["calibrate", "--robot", &robot("ur5e-dh")])
        .arg(file)
        .args(["--out", "cal", "--force"])
        .assert();
    (a.get_output().status.code().unwrap_or(-1), stderr(&a))
}

#[test]
fn clean_short_sweeps_are_calibrated_not_read_as_a_unit_slip() {
    let dir = tempfile::tempdir().unwrap();
    for seed in [42, 44] {
        let file = short_campaign(dir.path(), seed);
        let (code, e) = calibrate(dir.path(), &file);
        assert_eq!(code, 0, "seed {seed}: {e}");
        assert!(
            !e.contains("looks offset") && !e.contains("look like"),
            "seed {seed}: {e}"
        );
    }
}

#[test]
fn a_column_in_other_units_in_a_short_sweep_is_still_named() {
    let dir = tempfile::tempdir().unwrap();
    let clean = short_campaign(dir.path(), 41);
    let scaled = |name: &str, experiment: &str, column: usize, factor: f64| {
        altered_experiment(&clean, name, experiment, |f| {
            scale_fields(f, column..column + 1, factor)
        })
    };
    for (file, field, unit) in [
        (scaled("um.csv", "axis4", 5, 1000.0), "`y_mm`", "micrometres"),
        (scaled("cm.csv", "axis2", 4, 0.1), "`x_mm`", "centimetres"),
    ] {
        let (code, e) = calibrate(dir.path(), &file);
        assert_eq!(code, 2, "{e}");
        let said = e.lines().find(|l| l.starts_with("error:")).unwrap_or_default();
        assert!(said.contains(field) && said.contains(unit), "{}: {e}", file.display());
    }
}
