//! A quick campaign of short sweeps on the UR5e: five points over 30 degrees per joint. The
//! unit checks read a sweep's radius from the circles through its point triples; five points
//! make one triple over 15 degrees, whose circle bows about half a millimetre on the wrist and
//! measures the noise more than the radius. Such arcs are not judged (the triples' sagitta below
//! the checks' millimetre): clean files calibrate, where a wrist radius 1.3-1.4 times off read
//! as a command offset by a quarter turn (seeds 42 and 44) or a column in micrometres. A column
//! in other units still moves the sweep by far more than its noise and is still named.
//!
//! The same short sweeps three times per joint at other poses (joint 1 at 20 deg, or joint 1
//! at -20 deg and joint 2 at 10 deg) enter each joint's fit through the held joints'
//! correction, whose model is uncertain by millimetres: the corrected sweeps miss one another
//! beyond their noise, and the coordinate-scale profile read part of that model error as an
//! instrument axis 0.7-0.9 % long at 6-7 sigma (seeds 45, 46, 47). Such a scale is named only
//! where, with it undone, the sweeps agree; a note says they do not. Where they agree within
//! that test, the same error still reads as a scale beyond the noise (seeds 42 and 60), and a
//! scale is named only beyond what files simulated from the calibration without one read.

use crate::common::{altered_experiment, axiscal, column_scaled, scale_fields, stderr};
use crate::hostile_round15s::robot;
use crate::hostile_round17j::{simulated_with_plan, three_pose_plan};
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

/// The sweeps' disagreement is said, and no axis scale named from it.
const DISAGREE: &str = "miss one another, once the held joints' correction has moved them to one pose";

#[test]
fn short_sweeps_at_three_poses_are_not_read_as_an_instrument_axis_scale() {
    let dir = tempfile::tempdir().unwrap();
    let plan = three_pose_plan(dir.path(), "three_30.toml", |_| 30.0);
    for seed in [45, 46, 47] {
        let file = simulated_with_plan(dir.path(), "ur5e-dh", &plan, seed, &format!("three_{seed}.csv"));
        let (code, e) = calibrate(dir.path(), &file);
        assert_eq!(code, 0, "seed {seed}: {e}");
        assert!(
            !e.contains("the instrument's"),
            "seed {seed}: a scale named on a clean file: {e}"
        );
        assert!(e.contains(DISAGREE), "seed {seed}: {e}");
    }
}

/// Clean 30-degree sweeps at three poses whose held joints' correction reads as a scale the
/// noise test names (seeds 42 and 60: `y_mm` 1.0060 and `x_mm` 0.9902 at 5 and 8 of the
/// noise's sigmas; they were warned of it): files simulated from the calibration without a
/// scale read it as far from 1, so it is a note, not a warning.
#[test]
fn a_scale_the_correction_error_explains_is_a_note_not_named() {
    let dir = tempfile::tempdir().unwrap();
    let plan = three_pose_plan(dir.path(), "three_30.toml", |_| 30.0);
    for seed in [42, 60] {
        let file = simulated_with_plan(dir.path(), "ur5e-dh", &plan, seed, &format!("three_{seed}.csv"));
        let (code, e) = calibrate(dir.path(), &file);
        assert_eq!(code, 0, "seed {seed}: {e}");
        assert!(!e.contains("the instrument's"), "seed {seed}: {e}");
        let note = e
            .lines()
            .find(|l| l.contains("the coordinate-scale profile reads"))
            .unwrap_or_else(|| panic!("seed {seed}: no note: {e}"));
        assert!(
            note.contains("20 files simulated from this calibration") && note.ends_with("not named"),
            "seed {seed}: {note}"
        );
    }
}

/// The factor a named scale's warning reads and the spread of the files simulated without a
/// scale (`... reads F times ... read it C times (+- S; p = ...`).
fn factor_and_spread(warning: &str) -> (f64, f64) {
    let number = |text: &str, after: &str, before: char| -> Option<f64> {
        text.split(after).nth(1)?.split(before).next()?.parse().ok()
    };
    let simulated = warning.split("read it ").nth(1).unwrap_or_default();
    let factor = number(warning, "reads ", ' ');
    let spread = number(simulated, "times (+- ", ';');
    factor.zip(spread).unwrap_or_else(|| panic!("{warning}"))
}

/// 60-degree sweeps at three poses: the correction's model error reads as a scale about
/// 1.8 times the noise's sigma (the simulated files' spread), so `y_mm` x1.005 (7.5 of the
/// noise's sigmas, 4 of the spread's) is a note, and `y_mm` x1.01 is named, its factor within
/// 3 of that spread, with the simulated files said. Seed 43 as the clean file's test.
#[test]
fn an_axis_scale_beyond_the_correction_error_is_still_named() {
    let dir = tempfile::tempdir().unwrap();
    let plan = three_pose_plan(dir.path(), "three_60.toml", |_| 60.0);
    let clean = simulated_with_plan(dir.path(), "ur5e-dh", &plan, 43, "three_60.csv");
    let (code, e) = calibrate(dir.path(), &clean);
    assert_eq!(code, 0, "{e}");
    assert!(
        !e.contains(DISAGREE) && !e.contains("the instrument's") && !e.contains("coordinate-scale profile reads"),
        "{e}"
    );
    let (code, e) = calibrate(dir.path(), &column_scaled(&clean, "three_60_y5.csv", 5, 1.005));
    assert_eq!(code, 0, "{e}");
    assert!(
        !e.contains("the instrument's") && e.contains("the coordinate-scale profile reads `y_mm`"),
        "{e}"
    );
    let (code, e) = calibrate(dir.path(), &column_scaled(&clean, "three_60_y10.csv", 5, 1.01));
    assert_eq!(code, 0, "{e}");
    let warning = e
        .lines()
        .find(|l| l.contains("the instrument's y axis reads"))
        .unwrap_or_else(|| panic!("`y_mm` x1.01 not named: {e}"));
    assert!(
        warning.contains("20 files simulated from this calibration"),
        "{warning}"
    );
    let (factor, spread) = factor_and_spread(warning);
    assert!((factor - 1.01).abs() < 3.0 * spread, "{factor} +- {spread}: {warning}");
}
