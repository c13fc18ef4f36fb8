//! The twelfth hostile run's column scales on free poses (UB1, UB2): a command column scaled by
//! 1-3 % on the real FANUC tracker file was read as a one-axis instrument scale (`y_mm`, the
//! wrong cause) or passed unnamed while the calibration missed its points by millimetres, and a
//! screen of outlier poses ran on a model without the scale. The free-pose fit now tests a scale
//! of every command column and every instrument axis on the geometric fit of every pose before
//! any pose is screened (`free_pose/scales.rs`: cluster-robust over the configurations, a
//! command column against a drive's departure too), names the column, says others alike, and
//! screens the poses with it undone; a clean file names none, and one pose 5 mm off is still
//! that pose.

use crate::common::{altered_csv, axiscal, read_record, scale_fields, stderr};
use std::path::{Path, PathBuf};

/// A shipped robot description.
fn robot(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenarios/robots/{name}.toml"))
}

/// The free poses (`moved_joint = 0`) of `simulate --sim analytic --validation-poses 60 --seed
/// SEED` in `dir`, as `fp_<robot>_<seed>.csv`.
fn free_poses(dir: &Path, name: &str, seed: u64) -> PathBuf {
    let source = format!("src_{name}_{seed}.csv");
    axiscal()
        .current_dir(dir)
        .args(["simulate", "--sim", "analytic", "--validation-poses", "60", "--seed"])
        .arg(seed.to_string())
        .arg("--robot")
        .arg(robot(name))
        .args(["--out", &source, "--force"])
        .assert()
        .success();
    altered_csv(
        &dir.join(source),
        &format!("fp_{name}_{seed}.csv"),
        |f| f[1] == "0",
        |_| {},
    )
}

/// `calibrate FILE --robot ROBOT` in `dir`: its stderr and the free-pose summary.
fn calibrate(dir: &Path, file: &Path, robot: &Path) -> (String, axiscal::calibration::free_pose::FreePoseSummary) {
    let out = dir.join("out");
    let a = axiscal()
        .arg("calibrate")
        .arg(file)
        .arg("--robot")
        .arg(robot)
        .arg("--out")
        .arg(&out)
        .arg("--force")
        .assert()
        .success();
    let summary = read_record(&out).reports.free_poses.expect("a free-pose calibration");
    (stderr(&a), summary)
}

/// The columns the screen named (each named one and those alike).
fn named(s: &axiscal::calibration::free_pose::FreePoseSummary) -> Vec<String> {
    s.scales
        .iter()
        .flat_map(|n| std::iter::once(&n.scale).chain(&n.alike))
        .map(|c| c.column.clone())
        .collect()
}

/// `file` with the column `column` (0-based field) multiplied by `factor`, as `name`.
fn scaled(file: &Path, name: &str, column: usize, factor: f64) -> PathBuf {
    altered_csv(file, name, |_| true, |f| scale_fields(f, column..column + 1, factor))
}

/// `file` with one coordinate of pose `step`'s first target 5 mm off along x, as `name`.
fn one_pose_off(file: &Path, name: &str, step: &str) -> PathBuf {
    altered_csv(
        file,
        name,
        |_| true,
        |f| {
            if f[2] == step && f[3] == "0" && f[0] != "tool" {
                f[4] = (f[4].parse::<f64>().unwrap() + 5.0).to_string();
            }
        },
    )
}

/// Fields of the measurement CSV: `x_mm` is 4, `cmd_1` is 7.
const X_MM: usize = 4;
const CMD_1: usize = 7;

/// On simulated free poses of the UR5e and Boby & Klimchik's arm: a wrist and a shoulder
/// command column scaled by 2 % are named as that column (not dropped as poses, not read as an
/// instrument axis), a `y_mm` scaled by 1 % as `y_mm`, and the clean file and the file with one
/// pose 5 mm off name none; that pose is flagged. Seed 1 was a tuning seed.
#[test]
fn column_scales_on_simulated_free_poses_are_named_before_outliers() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["ur5e-dh", "boby-klimchik-arm"] {
        let clean = free_poses(dir.path(), name, 1);
        let r = robot(name);
        let (e, s) = calibrate(dir.path(), &clean, &r);
        assert!(
            s.scales.is_empty() && !e.contains("a column scale"),
            "{name}: a false alarm: {e}"
        );
        for (column, factor) in [(CMD_1 + 1, 1.02), (CMD_1 + 4, 1.02), (X_MM + 1, 1.01)] {
            let file = scaled(&clean, "scaled.csv", column, factor);
            let (e, s) = calibrate(dir.path(), &file, &r);
            let want = if column >= CMD_1 {
                format!("cmd_{}", column - CMD_1 + 1)
            } else {
                "y_mm".to_owned()
            };
            assert!(named(&s).contains(&want), "{name}: {want} x{factor} not named: {e}");
            assert!(e.contains(&format!("`{want}`")), "{name}: {e}");
            assert!(!e.contains("outlier pose"), "{name}: poses dropped for a scale: {e}");
        }
        let off = one_pose_off(&clean, "off.csv", "30");
        let (e, s) = calibrate(dir.path(), &off, &r);
        assert!(s.scales.is_empty(), "{name}: one pose read as a scale: {e}");
        assert!(e.contains("outlier pose: experiment validation step 30"), "{name}: {e}");
    }
}

/// The real FANUC file: `cmd_4` scaled by 1 % is named as that column (before: a `y_mm`
/// warning), `y_mm` scaled by 1 % as `y_mm`; `cmd_1` scaled by 1 % (joint 1 moves in 3 of the
/// 24 configurations) is not read as `y_mm` any more (a note); the file as shipped names none,
/// and with one coordinate of pose 57 5 mm off that pose is flagged and no scale named.
#[test]
#[ignore = "needs ../shared/data/real/fanuc-r2000ic-tracker (run by `make test-real`)"]
fn column_scales_on_the_real_fanuc_file_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("fanuc.csv");
    let r = crate::common::import_real_fanuc(&data);
    let (e, s) = calibrate(dir.path(), &data, &r);
    assert!(s.scales.is_empty(), "a false alarm: {e}");
    let cmd_1 = scaled(&data, "scaled.csv", CMD_1, 1.01);
    let (e, _) = calibrate(dir.path(), &cmd_1, &r);
    assert!(!e.contains("the instrument's y axis reads"), "cmd_1 read as y_mm: {e}");
    for (column, want) in [(CMD_1 + 3, "cmd_4"), (X_MM + 1, "y_mm")] {
        let file = scaled(&data, "scaled.csv", column, 1.01);
        let (e, s) = calibrate(dir.path(), &file, &r);
        assert_eq!(s.scales.first().map(|n| n.scale.column.as_str()), Some(want), "{e}");
        let n = &s.scales[0];
        // The factor within 4 of its reported sigmas (a command column's with a drive's
        // departure, 0.12 %, as the test counts it).
        let drive = if want.starts_with("cmd_") { 0.0012 } else { 0.0 };
        assert!(
            (n.scale.factor - 1.01).abs() < 4.0 * n.scale.sigma.hypot(drive),
            "{want}: {:?}",
            n.scale
        );
        assert!(!e.contains("outlier pose"), "{want}: {e}");
        if want.starts_with("cmd_") {
            assert!(!e.contains("the instrument's y axis reads"), "{want} read as y_mm: {e}");
        }
    }
    let off = one_pose_off(&data, "off.csv", "57");
    let (e, s) = calibrate(dir.path(), &off, &r);
    assert!(s.scales.is_empty(), "one pose read as a scale: {e}");
    assert!(e.contains("outlier pose: experiment poses step 57"), "{e}");
}
