//! The public FANUC R-2000iC tracker data (`../shared/data/real/fanuc-r2000ic-tracker/`, free
//! poses only, a MATLAB file): `axiscal import mat`, then the free-pose calibration with its
//! held-out check, against an independent implementation on the same split.

use crate::common;

use crate::common::axiscal;

/// The data set.
/// Held-out RMS of a geometric calibration on the even configurations, tested on the odd ones,
/// computed by an independent numpy/scipy implementation (error transforms before each joint,
/// joint offsets, base, targets; column-scaled SVD for the identifiable subset; LM with a
/// complex-step Jacobian): 0.3370 mm, and 0.7068 mm for the nominal model with base and targets
/// fitted. Both least-squares optima of the same model class predict the same points: they
/// agree to the fits' convergence (1e-4 mm).
const REFERENCE_HELDOUT_MM: [f64; 2] = [0.7068, 0.3370];

#[test]
#[ignore = "needs ../shared/data/real/fanuc-r2000ic-tracker (run by `make test-real`)"]
fn imports_and_calibrates_the_free_poses_with_a_holdout() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("fanuc.csv");
    let robot = common::import_real_fanuc(&data);
    let rows = std::fs::read_to_string(&data)
        .unwrap()
        .lines()
        .filter(|l| l.starts_with("poses,"))
        .count();
    assert_eq!(rows, 720);
    let out = dir.path().join("cal");
    axiscal()
        .arg("calibrate")
        .arg(&data)
        .arg("--robot")
        .arg(&robot)
        .args(["--holdout", "--harmonics", "0", "--out"])
        .arg(&out)
        .assert()
        .success();
    // The real robot's geometry errors, ordered with the poses, are no block shift or slip.
    let full = dir.path().join("full");
    let a = axiscal()
        .arg("calibrate")
        .arg(&data)
        .arg("--robot")
        .arg(&robot)
        .arg("--out")
        .arg(&full)
        .assert()
        .success();
    let e = crate::common::stderr(&a);
    assert!(
        !e.contains("sit about") && !e.contains("absorbed it"),
        "a false alarm on the real data: {e}"
    );
    let record = common::read_record(&out);
    let h = record.reports.free_poses.expect("free poses").holdout.expect("holdout");
    assert_eq!((h.training_poses, h.heldout_poses), (120, 120));
    for (ours, reference) in [h.nominal_rms_mm, h.calibrated_rms_mm].iter().zip(REFERENCE_HELDOUT_MM) {
        assert!(
            (ours - reference).abs() < 1e-3,
            "held-out RMS {ours:.4} mm, reference {reference:.4} mm"
        );
    }
}

/// `cmd_1` scaled 0.98 on export: joint 1 sits at 45 deg for the first 210 poses and at 26-29
/// deg for the last 30, so the scale turns the last 30 about axis 1 against the others, which
/// the slip search reads as a block moved. The warning says the column changes at the break
/// and what to check; the file as imported names no block.
#[test]
#[ignore = "needs ../shared/data/real/fanuc-r2000ic-tracker (run by `make test-real`)"]
fn a_command_column_scaled_where_its_joint_changes_at_a_block_is_said_beside_the_block() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("fanuc.csv");
    let robot = common::import_real_fanuc(&data);
    let calibrate = |file: &std::path::Path| {
        let a = axiscal()
            .current_dir(dir.path())
            .arg("calibrate")
            .arg(file)
            .arg("--robot")
            .arg(&robot)
            .args(["--out", "cal", "--force"])
            .assert()
            .success();
        common::stderr(&a)
    };
    let clean = calibrate(&data);
    assert!(!clean.contains("sit about"), "{clean}");
    let scaled = common::column_scaled(&data, "cmd1.csv", 7, 0.98);
    let e = calibrate(&scaled);
    let block = e
        .lines()
        .find(|l| l.contains("sit about"))
        .unwrap_or_else(|| panic!("{e}"));
    assert!(
        block.contains("`cmd_1` 44.1000 before") && block.contains("check it against the controller"),
        "{e}"
    );
}
