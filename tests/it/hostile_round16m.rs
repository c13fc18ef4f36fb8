//! Session 54 (issue #33, hostile run 15's "free-pose output is noisy"): beside an instrument
//! axis scale the free-pose screen named (`x_mm` read 2.5 % long), the joints' transmission
//! tests ran on the calibration that had absorbed the scale, and said a joint-2 sag and a
//! joint-4 slope that the scale alone explains. They now run on the poses calibrated again with
//! the named scale undone: no slope is said that the scale explains, and a real second slip (a
//! command column scaled too) is said on the undone calibration, with the undo in its words.

use crate::hostile_round14a::{calibrate, free_poses, robot, scaled};

/// Fields of the measurement CSV: `x_mm` is 4, `cmd_1` 7.
const X_MM: usize = 4;
const CMD_1: usize = 7;

/// The lines of `stderr` that say a joint's transmission slope (`joint K (free poses) turns`).
fn slope_lines(stderr: &str) -> Vec<&str> {
    stderr.lines().filter(|l| l.contains("(free poses) turns")).collect()
}

/// `x_mm` x1.025 on the free poses of the six-axis arm and the UR5e: the scale is named, and
/// every slope line (if any) is said with the scale undone; the clean files say none.
#[test]
fn an_axis_scale_is_named_without_the_slopes_it_explains() {
    let dir = tempfile::tempdir().unwrap();
    for (name, seed) in [("arm6-dh", 5), ("ur5e-dh", 6)] {
        let r = robot(name);
        let clean = free_poses(dir.path(), name, seed);
        let (e, s) = calibrate(dir.path(), &clean, &r);
        assert!(
            s.scales.is_empty() && slope_lines(&e).is_empty(),
            "{name}: a false alarm: {e}"
        );
        let file = scaled(&clean, "x.csv", X_MM, 1.025);
        let (e, s) = calibrate(dir.path(), &file, &r);
        assert_eq!(
            s.scales.first().map(|n| n.scale.column.as_str()),
            Some("x_mm"),
            "{name}: {e}"
        );
        let undone = "with `x_mm` divided by";
        for line in slope_lines(&e) {
            assert!(line.contains(undone), "{name}: a slope the scale explains: {line}");
        }
        assert!(!e.contains("sagging"), "{name}: {e}");
    }
}

/// `x_mm` x1.025 and `cmd_3` x1.02 at once (two slips): `x_mm` is named by the screen, and
/// `cmd_3` in a slope line said on the calibration with `x_mm` undone.
#[test]
fn a_command_scale_behind_an_axis_scale_is_said_with_the_axis_undone() {
    let dir = tempfile::tempdir().unwrap();
    let r = robot("arm6-dh");
    let clean = free_poses(dir.path(), "arm6-dh", 7);
    let x = scaled(&clean, "x.csv", X_MM, 1.025);
    let both = scaled(&x, "both.csv", CMD_1 + 2, 1.02);
    let (e, s) = calibrate(dir.path(), &both, &r);
    let columns: Vec<&str> = s.scales.iter().map(|n| n.scale.column.as_str()).collect();
    assert!(columns.contains(&"x_mm"), "{e}");
    let said = columns.contains(&"cmd_3")
        || slope_lines(&e)
            .iter()
            .any(|l| l.contains("with `x_mm` divided by") && l.contains("`cmd_3`"));
    assert!(said, "cmd_3 not said: {e}");
}

/// The real FANUC file with `cmd_4` scaled by 2 % (hostile run 16's `colf-fanuc-cmd_4`): the
/// column-scale screen names nothing and the fit took the scale into a 1.5-degree joint-4
/// backlash, calibrated RMS 4.96 mm where the file as shipped gives 0.13 mm. The calibrated
/// model predicts the poses it was not fitted to (cross-validated) worse than the nominal
/// model fits them, which is now said; the file as shipped, whose cross-validated RMS is a
/// third of the nominal's, says nothing of the kind.
#[test]
#[ignore = "needs ../shared/data/real/fanuc-r2000ic-tracker (run by `make test-real`)"]
fn a_calibration_that_predicts_no_better_than_the_nominal_model_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("fanuc.csv");
    let r = crate::common::import_real_fanuc(&data);
    let words = "it explains nothing the description does not";
    let (e, s) = calibrate(dir.path(), &data, &r);
    assert!(!e.contains(words), "a false alarm: {e}");
    let kept = s.effects_tried.iter().find(|t| t.chosen).expect("effects tried");
    assert!(kept.cross_validated_rms_mm < s.nominal_rms_mm, "{kept:?}");
    let file = scaled(&data, "cmd4.csv", CMD_1 + 3, 1.02);
    let (e, s) = calibrate(dir.path(), &file, &r);
    let kept = s.effects_tried.iter().find(|t| t.chosen).expect("effects tried");
    assert!(
        kept.cross_validated_rms_mm >= s.nominal_rms_mm,
        "{kept:?} vs {}",
        s.nominal_rms_mm
    );
    assert!(e.contains(words), "{e}");
}

/// Hostile run 16's `axs-arm7-free-z_mm`: the seven-axis arm's 150 free poses (seed 7) with
/// `z_mm` x1.025. The screen names `z_mm`; the fit of the file as written took the scale into
/// the geometry, which left joint 7's harmonic free, and the refusal blamed the description's
/// rows and the sweeps' spans (the file has no sweep). It now names the scale and its undo;
/// the file with `z_mm` divided by that factor calibrates.
#[test]
fn a_parameter_left_free_by_an_absorbed_axis_scale_names_the_scale() {
    use crate::common::{altered_csv, axiscal, scale_fields, stderr};
    let dir = tempfile::tempdir().unwrap();
    axiscal()
        .current_dir(dir.path())
        .args([
            "simulate",
            "--sim",
            "analytic",
            "--validation-poses",
            "150",
            "--seed",
            "7",
            "--robot",
        ])
        .arg(robot("arm7-dh"))
        .args(["--out", "src.csv"])
        .assert()
        .success();
    let free = altered_csv(&dir.path().join("src.csv"), "free.csv", |f| f[1] == "0", |_| {});
    let z = scaled(&free, "z.csv", X_MM + 2, 1.025);
    let run = |file: &std::path::Path| {
        axiscal()
            .current_dir(dir.path())
            .arg("calibrate")
            .arg(file)
            .arg("--robot")
            .arg(robot("arm7-dh"))
            .args(["--out", "out", "--force"])
            .assert()
    };
    let a = run(&z).code(2);
    let e = stderr(&a);
    let factor: f64 = e
        .split("(`z_mm` divided by ")
        .nth(1)
        .and_then(|rest| rest.split(')').next())
        .and_then(|f| f.parse().ok())
        .unwrap_or_else(|| panic!("the scale's undo not named: {e}"));
    assert!(!e.contains("the sweeps' spans"), "{e}");
    let fixed = altered_csv(
        &z,
        "fixed.csv",
        |_| true,
        |f| scale_fields(f, X_MM + 2..X_MM + 3, 1.0 / factor),
    );
    run(&fixed).success();
}
