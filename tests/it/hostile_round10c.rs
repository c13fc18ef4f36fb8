//! The ninth hostile run's findings on the free-pose outlier fence, the validation points'
//! outlier fence and the free-pose slip search, as a table (as [`super::hostile`]):
//! - FA1: every clean free-pose file of the ASEA IRB/L6 flagged poses 5 and 28 as outliers
//!   ("check its rows"): the free-pose model lacked the paper robot's joint-5 gear forms (the
//!   transmission's harmonic in the gear angle, the bevel gear coupling's in `N theta_4`) and
//!   missed clean data by 2 mm RMS; it now carries them and fits to the noise, and a pose's bad
//!   rows (ids swapped, shifted 5 mm, one target off 5 mm, a command slipped 1 deg) are still
//!   flagged, on the IRB/L6 and on a UR5e;
//! - FA4: `diagnose` set aside a clean point at 4.7 sigma of a 40-pose file;
//! - NU2: a real positioner's `cmd_2` scaled 1.2 % was said to be "`cmd_1` is negated".

use crate::common::altered_csv;
use crate::common::hostile::{Case, case, clear_outputs, run_case};
use std::path::{Path, PathBuf};

/// A shipped robot description.
fn robot(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenarios/robots/{name}.toml"))
}

/// `simulate --robot ROBOT --sim analytic --validation-poses 40 --seed SEED` in `dir` as
/// `campaign_<robot>.csv`, and its free poses (`moved_joint` 0) as `fp_<robot>.csv`.
fn free_poses(dir: &Path, name: &str, seed: u64) {
    let campaign = format!("campaign_{name}.csv");
    crate::common::axiscal()
        .current_dir(dir)
        .args(["simulate", "--sim", "analytic", "--validation-poses", "40", "--seed"])
        .arg(seed.to_string())
        .arg("--robot")
        .arg(robot(name))
        .args(["--out", &campaign, "--force"])
        .assert()
        .success();
    altered_csv(&dir.join(&campaign), &format!("fp_{name}.csv"), |f| f[1] == "0", |_| {});
}

/// `fp_<robot>.csv` with `change` applied to the rows of validation step 12, as `name`.
fn step_12(dir: &Path, robot: &str, name: &str, change: impl Fn(&mut Vec<String>)) {
    altered_csv(
        &dir.join(format!("fp_{robot}.csv")),
        name,
        |_| true,
        |f| {
            if f[0] == "validation" && f[2] == "12" {
                change(f)
            }
        },
    );
}

/// Adds `by` to field `k`.
fn add(f: &mut [String], k: usize, by: f64) {
    f[k] = (f[k].parse::<f64>().unwrap() + by).to_string();
}

/// The calibrated RMS \[mm\] of `out/report.md` (its row `| calibrated | X |`).
fn calibrated_rms_mm(dir: &Path) -> f64 {
    let report = std::fs::read_to_string(dir.join("out/report.md")).unwrap();
    let row = report
        .lines()
        .find(|l| l.starts_with("| calibrated |"))
        .expect("the calibrated RMS");
    row.split('|').nth(2).unwrap().trim().parse().unwrap()
}

/// FA1: clean free poses of the IRB/L6 (the paper robot, two seeds not tuned on) flag no pose,
/// and the fit reaches the noise (0.3 mm; it was 1.4-2.0 mm, poses 5 and 28 flagged "check
/// its rows").
#[test]
fn clean_irb_free_poses_fit_to_the_noise_and_flag_no_pose() {
    let dir = tempfile::tempdir().unwrap();
    for seed in [201, 202] {
        free_poses(dir.path(), "asea-irb6l", seed);
        let e = run_case(
            dir.path(),
            &case("clean IRB free poses", "calibrate fp_asea-irb6l.csv --out out", 0, &[]),
        );
        assert!(!e.contains("outlier pose"), "seed {seed}: a clean pose flagged: {e}");
        let rms = calibrated_rms_mm(dir.path());
        assert!(rms < 0.4, "seed {seed}: the fit misses clean data by {rms} mm RMS: {e}");
        clear_outputs(dir.path());
    }
}

/// The bad rows of one pose a free-pose file can hold.
fn bad_pose_cases(robot_name: &str, rows: &[&'static str; 4]) -> Vec<Case> {
    let flagged = "outlier pose: experiment validation step 12";
    let r = robot(robot_name);
    let args = |file: &str| format!("calibrate {file} --robot {} --out out", r.display());
    rows.iter()
        .map(|what| {
            case(
                what,
                &args(&format!("{robot_name}_{}.csv", what.split(':').next().unwrap())),
                0,
                &[flagged],
            )
        })
        .collect()
}

/// The free poses of `robot` with step 12's rows made bad four ways (ids of targets 0 and 1
/// swapped, every point 5 mm off in x, target 0 alone 5 mm off in y, `cmd_1` 1 deg off): each
/// is flagged as an outlier pose (the IRB/L6's old fence, 4-6 mm, passed the one target 5 mm
/// off).
fn bad_rows_are_flagged_on(robot_name: &str, seed: u64) {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    free_poses(d, robot_name, seed);
    step_12(d, robot_name, &format!("{robot_name}_swap.csv"), |f| {
        f[3] = match f[3].as_str() {
            "0" => "1".into(),
            "1" => "0".into(),
            other => other.into(),
        }
    });
    step_12(d, robot_name, &format!("{robot_name}_shift.csv"), |f| add(f, 4, 5.0));
    step_12(d, robot_name, &format!("{robot_name}_target.csv"), |f| {
        if f[3] == "0" {
            add(f, 5, 5.0)
        }
    });
    step_12(d, robot_name, &format!("{robot_name}_cmd.csv"), |f| add(f, 7, 1.0));
    let rows = [
        "swap: target ids 0 and 1 swapped in one pose",
        "shift: one pose's points 5 mm off in x",
        "target: one pose's target 0 5 mm off in y",
        "cmd: one pose's cmd_1 1 deg off",
    ];
    for c in bad_pose_cases(robot_name, &rows) {
        run_case(d, &c);
        clear_outputs(d);
    }
}

#[test]
fn bad_rows_of_one_irb_pose_are_still_flagged() {
    bad_rows_are_flagged_on("asea-irb6l", 203);
}

#[test]
fn bad_rows_of_one_ur5e_pose_are_still_flagged() {
    bad_rows_are_flagged_on("ur5e-dh", 204);
}

/// FA4: `diagnose` of a clean 40-pose file of the boby-klimchik arm (run 9's seed) sets no
/// point aside (it set aside one at 4.7 sigma, beyond Tukey's fence 4.3 but within what 120
/// points of the noise reach); one target 5 mm off in a pose is still set aside.
#[test]
fn diagnose_sets_aside_no_clean_point_and_still_a_bad_one() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    crate::common::axiscal()
        .current_dir(d)
        .args([
            "simulate",
            "--sim",
            "analytic",
            "--validation-poses",
            "40",
            "--seed",
            "91",
            "--robot",
        ])
        .arg(robot("boby-klimchik-arm"))
        .args(["--out", "vp.csv"])
        .assert()
        .success();
    altered_csv(
        &d.join("vp.csv"),
        "vp_bad.csv",
        |_| true,
        |f| {
            if f[0] == "validation" && f[2] == "12" && f[3] == "0" {
                add(f, 5, 5.0)
            }
        },
    );
    let r = robot("boby-klimchik-arm");
    let args = |file: &str| format!("diagnose {file} --robot {} --noise-trials 2 --out out", r.display());
    let e = run_case(d, &case("clean boby-klimchik file", &args("vp.csv"), 0, &[]));
    assert!(!e.contains("outlier:"), "a clean point set aside: {e}");
    clear_outputs(d);
    run_case(
        d,
        &case(
            "one target 5 mm off",
            &args("vp_bad.csv"),
            0,
            &["outlier: experiment validation step 12 target 0"],
        ),
    );
}

/// NU2: the real positioner's `cmd_2` scaled by 1.012 is no negated `cmd_1` (the slip search
/// said so: the nominal model missed by 14.1 mm as written, 12.1 mm with `cmd_1` negated, where
/// the calibration leaves 4.7 mm).
#[test]
#[ignore = "needs ../shared/data/real/rct-two-axis-positioner (run by `make test-real`)"]
fn a_scaled_real_column_is_no_sign_flip_of_another() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let r = robot("positioner-2axis");
    crate::common::axiscal()
        .current_dir(d)
        .args(["import", "rct"])
        .arg(crate::common::real_data(
            "rct-two-axis-positioner/positioner_kinematic_measurements.yaml",
        ))
        .arg("--robot")
        .arg(&r)
        .args(["--still-tolerance", "0.1", "--out", "rct.csv"])
        .assert()
        .success();
    // cmd_2 is field 8 of the positioner's rows.
    altered_csv(
        &d.join("rct.csv"),
        "rct_x.csv",
        |_| true,
        |f| crate::common::scale_fields(f, 8..9, 1.012),
    );
    let e = run_case(
        d,
        &case(
            "cmd_2 x1.012",
            &format!("calibrate rct_x.csv --robot {} --out out", r.display()),
            0,
            &[],
        ),
    );
    assert!(!e.contains("is negated"), "a sign flip said: {e}");
}
