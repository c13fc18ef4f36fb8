//! robot_cal_tools' two-axis positioner measurements (`../shared/data/real/rct-two-axis-positioner/`,
//! a fixed camera's poses of a target on the table): `axiscal import rct`, then `calibrate`,
//! which finds the joint-2 turns at their own joint-1 values unusable by the independent-axis
//! procedure and fits every observation as a free pose; held out, the model is checked against
//! a second estimate of the data's floor that uses no robot model (a circle fitted to each
//! turn). `diagnose` takes the turns as free poses too.

use crate::common;

use crate::common::{axiscal, stderr};
use nalgebra::{DMatrix, DVector, Point3};
use std::path::{Path, PathBuf};

/// The data file.
fn data_file() -> PathBuf {
    common::real_data("rct-two-axis-positioner/positioner_kinematic_measurements.yaml")
}

/// A generic two-axis positioner (tilt axis, rotary table): the nominal the calibration starts
/// from; the real positioner's dimensions are not published with the data.
fn robot() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/robots/positioner-2axis.toml")
}

/// A measured point \[mm\] and the joint-2 reading \[rad\] at it.
type Reading = (Point3<f64>, f64);

/// Per experiment, its rows' points \[mm\] and joint-2 readings \[rad\] (the measurement CSV's
/// x, y, z and cmd_2).
fn turns_of(csv: &Path) -> Vec<Vec<Reading>> {
    let text = std::fs::read_to_string(csv).unwrap();
    let mut out: Vec<(String, Vec<Reading>)> = Vec::new();
    for line in text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("experiment,"))
    {
        let cells: Vec<&str> = line.split(',').collect();
        let number = |k: usize| cells[k].parse::<f64>().unwrap();
        let row = (Point3::new(number(4), number(5), number(6)), number(8).to_radians());
        match out.iter_mut().find(|(name, _)| name == cells[0]) {
            Some((_, rows)) => rows.push(row),
            None => out.push((cells[0].to_owned(), vec![row])),
        }
    }
    out.into_iter().map(|(_, rows)| rows).collect()
}

/// One turn on its own: the points on a circle in their principal plane at the angles the
/// joint-2 readings give plus a phase, `s = c_s + A cos q - B sin q`, `t = c_t + A sin q + B
/// cos q` (linear in `c_s, c_t, A, B`; either sense of rotation, the better kept). Returns the
/// sum of squared 3-D distances (in-plane and out of it) and the degrees of freedom `3 n - 7`
/// (plane 3, centre 2, radius and phase 2).
fn turn_misfit(rows: &[Reading]) -> (f64, usize) {
    let points: Vec<Point3<f64>> = rows.iter().map(|r| r.0).collect();
    let (centroid, [u, v, w]) = common::principal_axes(&points);
    let out_of_plane: f64 = rows.iter().map(|r| (r.0 - centroid).dot(&w).powi(2)).sum();
    let in_plane = |sense: f64| {
        let m = rows.len();
        let a = DMatrix::from_fn(2 * m, 4, |i, c| {
            let (s, co) = (sense * rows[i / 2].1).sin_cos();
            match (i % 2, c) {
                (0, 0) | (1, 1) => 1.0,
                (0, 2) | (1, 3) => co,
                (0, 3) => -s,
                (1, 2) => s,
                _ => 0.0,
            }
        });
        let b = DVector::from_fn(2 * m, |i, _| {
            let d = rows[i / 2].0 - centroid;
            if i % 2 == 0 { d.dot(&u) } else { d.dot(&v) }
        });
        let x = a.clone().svd(true, true).solve(&b, 1e-12).unwrap();
        (a * x - b).norm_squared()
    };
    (out_of_plane + in_plane(1.0).min(in_plane(-1.0)), 3 * rows.len() - 7)
}

#[test]
#[ignore = "needs ../shared/data/real/rct-two-axis-positioner (run by `make test-real`)"]
fn imports_and_calibrates_the_positioner_to_the_turns_floor() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("rct.csv");
    let imported = axiscal()
        .args(["import", "rct"])
        .arg(data_file())
        .arg("--robot")
        .arg(robot())
        .args(["--still-tolerance", "0.1", "--out"])
        .arg(&data)
        .assert()
        .success();
    let listing = common::stdout(&imported);
    assert!(listing.contains("imported 205 rows"), "{listing}");
    let turns = turns_of(&data);
    assert_eq!(turns.len(), 13, "one joint-2 turn per joint-1 value: {listing}");

    // The default path: the turns stand at their own joint-1 values, so the independent-axis
    // procedure hands over to the free-pose fit and says so.
    let out = dir.path().join("cal");
    let run = axiscal()
        .arg("calibrate")
        .arg(&data)
        .arg("--robot")
        .arg(robot())
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    assert!(stderr(&run).contains("every point is fitted as a free pose instead"));

    // Held out: even configurations fitted, odd ones predicted.
    let held = dir.path().join("held");
    axiscal()
        .arg("calibrate")
        .arg(&data)
        .arg("--robot")
        .arg(robot())
        .args(["--free-poses", "--holdout", "--out"])
        .arg(&held)
        .assert()
        .success();
    let summary = common::read_record(&held)
        .reports
        .free_poses
        .expect("a free-pose calibration");
    let h = summary.holdout.expect("the held-out check");

    // The floor without a robot model: each turn on its own circle at its readings' angles,
    // the misfit pooled over the turns' degrees of freedom, as a 3-D RMS.
    let (sse, dof) = turns
        .iter()
        .map(|t| turn_misfit(t))
        .fold((0.0, 0), |(s, d), (s1, d1)| (s + s1, d + d1));
    let floor_mm = (3.0 * sse / dof as f64).sqrt();
    // The held-out RMS of a model at the floor exceeds it by its own parameters' error,
    // `sqrt(1 + p / n)` (p fitted parameters over n fitted coordinates), and by the sampling
    // spread of the two estimates (relative standard error `1 / sqrt(2 dof)` each, 4 of them).
    let p = summary.parameters.len() as f64;
    let n = 3.0 * summary.points as f64;
    let spread = 4.0 * ((1.0 / (2.0 * dof as f64)) + 1.0 / (2.0 * 3.0 * h.heldout_poses as f64)).sqrt();
    let bound_mm = floor_mm * (1.0 + p / n).sqrt() * (1.0 + spread);
    eprintln!(
        "nominal {:.4} mm, held out {:.4} mm; turns' floor {floor_mm:.4} mm, bound {bound_mm:.4} mm",
        h.nominal_rms_mm, h.calibrated_rms_mm
    );
    assert!(
        h.calibrated_rms_mm <= bound_mm,
        "held-out RMS {:.4} mm above the turns' floor {floor_mm:.4} mm (bound {bound_mm:.4})",
        h.calibrated_rms_mm
    );
    assert!(h.calibrated_rms_mm < h.nominal_rms_mm / 5.0);

    // `diagnose` takes the turns as free poses too (it refused them before), with the turns'
    // floor as the noise: the held-out RMS of its own refit stays within the same bound.
    let diagnosis = dir.path().join("diagnosis");
    let run = axiscal()
        .arg("diagnose")
        .arg(&data)
        .arg("--robot")
        .arg(robot())
        .args(["--noise-mm", &format!("{floor_mm}"), "--out"])
        .arg(&diagnosis)
        .assert()
        .success();
    assert!(stderr(&run).contains("every row is diagnosed as a free pose instead"));
    let d: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(diagnosis.join("diagnosis.json")).unwrap()).unwrap();
    let heldout_mm = d["heldout_rms_before_mm"].as_f64().unwrap();
    eprintln!("diagnose: {} ({heldout_mm:.4} mm held out)", d["verdict"]);
    assert!(
        heldout_mm <= bound_mm,
        "diagnosis's held-out RMS {heldout_mm:.4} mm above {bound_mm:.4} mm"
    );
}
