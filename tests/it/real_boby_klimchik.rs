//! The real laser-tracker data of Boby & Klimchik (`../shared/data/real/boby-klimchik-tracker/`,
//! beside the repository): `axiscal import boby-klimchik`, its error handling on broken copies,
//! and the calibration's structural facts (`docs/real-data.md`, "Real-data worked example").

use crate::common;

use crate::common::axiscal;
use axiscal::calibration::procedure::{AxisReport, Calibration};
use nalgebra::{Matrix2, Vector2, Vector3};
use std::path::{Path, PathBuf};

/// Laser-tracker noise assumed by the worked example: 3-D RMS of a point \[mm\].
const TRACKER_NOISE_MM: f64 = 0.05;

/// The data set's folder.
fn data_dir() -> PathBuf {
    common::real_data("boby-klimchik-tracker/N1N2N3Jval.csv")
        .parent()
        .expect("the data file's folder")
        .to_owned()
}

fn robot() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/robots/boby-klimchik-arm.toml")
}

#[test]
#[ignore = "needs ../shared/data/real/boby-klimchik-tracker (run by `make test-real`)"]
fn imports_the_real_file() {
    let set = axiscal::measurement::import::boby_klimchik::import_dir(&data_dir()).unwrap();
    let experiments = set.experiments();
    assert_eq!(experiments.len(), 6);
    for (k, e) in experiments.iter().enumerate() {
        assert_eq!(e.moved_joint, k + 1);
        assert_eq!(e.rows.len(), 18, "{}", e.name);
    }
    // The J2 block reads J3 = -J2: a constant joint 3 relative to the upper arm.
    for m in set.experiment("axis2").unwrap().rows {
        approx::assert_relative_eq!(m.cmd[2], 0.0);
    }
}

/// Copies the real file into a temporary folder with line `line` (1-based) edited.
fn broken_copy(edit: impl Fn(&str) -> String, line: usize) -> tempfile::TempDir {
    let text = std::fs::read_to_string(data_dir().join("N1N2N3Jval.csv")).unwrap();
    let lines: Vec<String> = text
        .lines()
        .enumerate()
        .map(|(i, l)| if i + 1 == line { edit(l) } else { l.to_owned() })
        .collect();
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("N1N2N3Jval.csv"), lines.join("\n")).unwrap();
    dir
}

fn import_fails(dir: &Path, expected: &[&str]) {
    let out = dir.join("out.csv");
    let a = axiscal()
        .args(["import", "boby-klimchik"])
        .arg(dir)
        .arg("--out")
        .arg(&out)
        .assert()
        .code(2);
    let stderr = String::from_utf8_lossy(&a.get_output().stderr).into_owned();
    for e in expected {
        assert!(stderr.contains(e), "{e:?} not in {stderr:?}");
    }
    assert!(!out.exists(), "no output for a bad file");
}

#[test]
#[ignore = "needs ../shared/data/real/boby-klimchik-tracker (run by `make test-real`)"]
fn broken_copies_are_one_clear_error() {
    let short = broken_copy(|l| l.split_whitespace().skip(1).collect::<Vec<_>>().join(" "), 3);
    import_fails(short.path(), &["N1N2N3Jval.csv:3:", "20 fields, expected 21"]);
    let word = broken_copy(
        |l| {
            let mut f: Vec<&str> = l.split_whitespace().collect();
            f[4] = "12,5";
            f.join(" ")
        },
        10,
    );
    import_fails(word.path(), &["N1N2N3Jval.csv:10:", "field 5 (SMR 2 y_mm)", "\"12,5\""]);
    let missing = tempfile::tempdir().unwrap();
    import_fails(missing.path(), &["N1N2N3Jval.csv"]);
}

/// The direction of `a` in the `(u, v)` basis across it and its 2 x 2 tilt covariance.
fn tilt_covariance(a: &AxisReport) -> (Vector3<f64>, Vector3<f64>, Matrix2<f64>) {
    let c = a.covariance.as_ref().expect("the ML estimator reports a covariance");
    let m = Matrix2::new(
        c.covariance[0][0],
        c.covariance[0][1],
        c.covariance[1][0],
        c.covariance[1][1],
    );
    (Vector3::from(c.u), Vector3::from(c.v), m)
}

#[test]
#[ignore = "needs ../shared/data/real/boby-klimchik-tracker (run by `make test-real`)"]
fn calibrates_six_axes_and_finds_axes_2_and_3_parallel() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("boby-klimchik.csv");
    axiscal()
        .args(["import", "boby-klimchik"])
        .arg(data_dir())
        .arg("--out")
        .arg(&data)
        .assert()
        .success();
    let out = tmp.path().join("cal");
    let run = axiscal()
        .arg("calibrate")
        .arg(&data)
        .arg("--robot")
        .arg(robot())
        .arg("--out")
        .arg(&out)
        .args(["--noise-mm", &TRACKER_NOISE_MM.to_string()])
        .assert()
        .success();
    println!("{}", String::from_utf8_lossy(&run.get_output().stdout));
    let cal: Calibration = axiscal::json_file::from_str(
        axiscal::json_file::Schema::CALIBRATION,
        &std::fs::read_to_string(out.join("calibration.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(cal.axes.len(), 6);
    for a in &cal.axes {
        assert!(a.residual_rms_mm.is_finite() && a.residual_rms_mm > 0.0, "{a:?}");
    }
    assert!(cal.tool.is_none(), "no tool observation at the reference pose");

    // Axes 2 and 3 are parallel as lines; their directions are opposite (the controller
    // turns joint 3 the other way). The angle between them is tested against its
    // uncertainty: each axis's tilt covariance, scaled by its Birge ratio
    // max(1, residual RMS / assumed noise)^2 (axis 2's residual, 0.23 mm, is 4.6 times the
    // tracker noise: the 2.6 m arm sags differently over its 80 deg swing, which the noise
    // model does not carry), projected on axis 2's (u, v) basis.
    let (a2, a3) = (&cal.axes[1], &cal.axes[2]);
    let (d2, d3) = (Vector3::from(a2.direction), Vector3::from(a3.direction));
    assert!(d2.dot(&d3) < 0.0, "axis 3 runs against axis 2");
    let birge = |a: &AxisReport| (a.residual_rms_mm / TRACKER_NOISE_MM).max(1.0).powi(2);
    let (u, v, c2) = tilt_covariance(a2);
    let (u3, v3, c3) = tilt_covariance(a3);
    let r = Matrix2::new(u3.dot(&u), v3.dot(&u), u3.dot(&v), v3.dot(&v));
    let cov = c2 * birge(a2) + r * c3 * r.transpose() * birge(a3);
    let delta = Vector2::new((-d3 - d2).dot(&u), (-d3 - d2).dot(&v));
    let sigmas = delta
        .dot(&(cov.try_inverse().expect("positive definite") * delta))
        .sqrt();
    let angle_rad = d2.cross(&d3).norm();
    let sigma_angle_rad = (delta.dot(&(cov * delta)) / delta.norm_squared()).sqrt();
    println!(
        "angle(axis 2, axis 3 reversed) = {:.3} mrad, 1-sigma along it {:.3} mrad: {sigmas:.2} sigma",
        angle_rad * 1e3,
        sigma_angle_rad * 1e3
    );
    assert!(sigmas < 3.0, "axes 2 and 3 are {sigmas:.2} sigma from parallel");

    // The certificate of this real calibration: every expanded uncertainty twice the sigma
    // calibration.json reports.
    let cert = tmp.path().join("cert");
    axiscal()
        .args(["report", "--calibration"])
        .arg(out.join("calibration.json"))
        .arg("--robot")
        .arg(robot())
        .arg("--data")
        .arg(&data)
        .args(["--instrument", "laser tracker (Boby & Klimchik's data set)", "--out"])
        .arg(&cert)
        .assert()
        .success();
    crate::certificate::check_certificate(&cert, &out.join("calibration.json"));
}

/// `axiscal diagnose` without validation poses: the axis-experiments-only mode puts axis 2's
/// arc (the sagging 2.6 m arm) beyond the noise-only replicas and the wrist axes within them.
#[test]
#[ignore = "needs ../shared/data/real/boby-klimchik-tracker (run by `make test-real`)"]
fn diagnosis_from_arcs_alone_flags_axis_2() {
    let set = axiscal::measurement::import::boby_klimchik::import_dir(&data_dir()).unwrap();
    let desc = axiscal::robot::RobotDescription::from_file(&robot()).unwrap();
    let options = axiscal::diagnosis::DiagnosisOptions {
        noise_rms_3d_mm: TRACKER_NOISE_MM,
        axis_replicas: 50,
        ..Default::default()
    };
    let d = axiscal::diagnosis::diagnose_axes(&set, &desc, &options).unwrap();
    assert_eq!(d.outcome.effect, "unexplained", "{}", d.verdict);
    assert_eq!(d.where_[0].joint, Some(2));
    assert!(d.flagged.iter().any(|f| f.joint == 2));
    for joint in 4..=6 {
        assert!(!d.flagged.iter().any(|f| f.joint == joint), "{}", d.verdict);
    }
    let dir = tempfile::tempdir().unwrap();
    let written = axiscal::diagnosis::write_axes_plots(&d, dir.path()).unwrap();
    assert_eq!(written.len(), axiscal::diagnosis::AXES_PLOT_FILES.len());
    for f in written {
        assert!(std::fs::metadata(&f).unwrap().len() > 1000, "{} is empty", f.display());
    }
}
