//! Hostile run 15, class 4 (FA, 6 cases): a clean SCARA (`scara-rrpr`, every axis vertical)
//! calibrated on one clean file and validated on another of the same truth was "exceeds"
//! (chi2/dof 1.83, 5 of 5 pairs p <= 0.004), and `report --held-out` called the calibration
//! worse than the nominal model (1.61 against 1.16 mm). The cause was the calibration: the
//! sweeps leave the position along the parallel axes open (the sequential base rule kept the
//! description's height), the tool frame is not measured (no pose at the reference commands
//! sees all three tool targets: line of sight), and nothing else fixed the height, off by the
//! simulated truth's base and row errors (a miss of about 1.5 mm along z that no covariance
//! held). The tool target seen at the reference pose now fixes it (`procedure/height.rs`), with
//! its error in the model's covariance; the base rule says so. Clean pairs are no longer off in
//! height and beat the nominal model on held-out poses; without a tool target at the reference
//! pose the height stays kept and the base rule says so. Not yet fixed: the last link's turn
//! about axis 4 at the reference pose (a convention the tool frame takes when measured) stays
//! the description's with a nominal tool frame, in no covariance, so the chi-square of such
//! pairs is not yet uniform (analytic files with the tool observation cut to target 2).

use crate::common::{altered_csv, axiscal, stderr};
use std::path::{Path, PathBuf};

/// The shipped description (or truth) `name` under `scenarios/robots/`.
fn robot(name: &str) -> String {
    format!("{}/scenarios/robots/{name}.toml", env!("CARGO_MANIFEST_DIR"))
}

/// `simulate` (analytic) of the SCARA's shipped truth with noise seed `seed` in `dir` (30
/// validation poses), its tool observation reduced to tool target 2 as the rapier simulation's
/// line of sight leaves it (the hostile run's files): `scara_<seed>.csv`.
fn scara(dir: &Path, seed: u64) -> PathBuf {
    let full = format!("full_{seed}.csv");
    axiscal()
        .current_dir(dir)
        .args(["simulate", "-q", "--sim", "analytic", "--robot", &robot("scara-rrpr")])
        .args(["--truth", &robot("scara-rrpr-truth"), "--validation-poses", "30"])
        .args(["--seed", &seed.to_string(), "--out", &full, "--force"])
        .assert()
        .success();
    altered_csv(
        &dir.join(full),
        &format!("scara_{seed}.csv"),
        |f| f[0] != "tool" || f[3] == "2",
        |_| {},
    )
}

/// `calibrate` of `file` into `out`, its stdout (the summary, with the base rule) and stderr.
fn calibrate(dir: &Path, file: &Path, out: &str) -> String {
    let a = axiscal()
        .current_dir(dir)
        .args(["calibrate", "--robot", &robot("scara-rrpr")])
        .arg(file)
        .args(["--out", out, "--force"])
        .assert()
        .success();
    format!("{}{}", String::from_utf8_lossy(&a.get_output().stdout), stderr(&a))
}

/// `validate` of `file` against `cal/calibration.json`: the summary's validation part.
fn validate(dir: &Path, cal: &str, file: &Path, out: &str) -> serde_json::Value {
    axiscal()
        .current_dir(dir)
        .args(["validate", "--robot", &robot("scara-rrpr"), "--calibration"])
        .arg(dir.join(cal).join("calibration.json"))
        .arg(file)
        .args(["--out", out, "--force"])
        .assert()
        .success();
    let text = std::fs::read_to_string(dir.join(out).join("summary.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["validation"].clone()
}

/// The rows of `kind` among the residuals (`residuals.csv` of a `validate` run): mean miss
/// along z \[mm\] and the number of points.
fn mean_dz(dir: &Path, out: &str, of_kind: &str) -> (f64, usize) {
    let text = std::fs::read_to_string(dir.join(out).join("residuals.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let (kind, dz) = (
        header.iter().position(|h| *h == "kind").unwrap(),
        header.iter().position(|h| *h == "dz_mm").unwrap(),
    );
    let v: Vec<f64> = lines
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|f| f[kind] == of_kind)
        .map(|f| f[dz].parse().unwrap())
        .collect();
    (v.iter().sum::<f64>() / v.len() as f64, v.len())
}

/// The calibrated base frame's 1-sigma along z \[mm\] (the model covariance's `base z`).
fn base_z_sigma_mm(dir: &Path, cal: &str) -> f64 {
    let text = std::fs::read_to_string(dir.join(cal).join("calibration.json")).unwrap();
    let c: serde_json::Value = serde_json::from_str(&text).unwrap();
    let names = c["model_covariance"]["names"].as_array().unwrap();
    let i = names.iter().position(|n| n == "base z [m]").unwrap();
    c["model_covariance"]["covariance"][i][i].as_f64().unwrap().sqrt() * 1e3
}

#[test]
fn clean_scara_pairs_are_no_longer_off_in_height_and_the_tool_target_fixes_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (a, b) in [(1611, 1612), (1613, 1614), (1615, 1616)] {
        let (fa, fb) = (scara(d, a), scara(d, b));
        let e = calibrate(d, &fa, "cal");
        assert!(e.contains("position along axis 1: from tool target"), "{a}: {e}");
        assert!(
            !e.contains("kept from the description's placement: position along axis 1"),
            "{a}: {e}"
        );
        let v = validate(d, "cal", &fb, "v");
        // A second, differently written check: the tool target at the reference pose, which
        // fixed the height in the first file, is missed along the vertical axes in the second
        // by the two files' noise only (one coordinate: noise / sqrt(3) each), within 4 sigma
        // (it was missed by the truth's height error, 1.26 mm at 0.17 mm noise).
        let (dz, n) = mean_dz(d, "v", "tool");
        assert_eq!(n, 1, "{a}/{b}");
        let noise = v["predicted_mm"]["noise"].as_f64().unwrap() / 3f64.sqrt();
        assert!(
            dz.abs() < 4.0 * noise * 2f64.sqrt(),
            "{a}/{b}: tool target dz {dz} mm, noise {noise}"
        );
        // The validation poses' common miss along z within 4 sigma of the base's sigma along z
        // and the noise's over the points.
        let (dz, n) = mean_dz(d, "v", "validation");
        let sigma = (base_z_sigma_mm(d, "cal").powi(2) + noise * noise / n as f64).sqrt();
        assert!(dz.abs() < 4.0 * sigma, "{a}/{b}: mean dz {dz} mm, sigma {sigma}");
    }
}

#[test]
fn clean_scara_held_out_is_not_worse_than_the_nominal_model() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (fa, fb) = (scara(d, 1621), scara(d, 1622));
    calibrate(d, &fa, "cal");
    let a = axiscal()
        .current_dir(d)
        .args([
            "report",
            "--robot",
            &robot("scara-rrpr"),
            "--calibration",
            "cal/calibration.json",
            "--data",
        ])
        .arg(&fa)
        .arg("--held-out")
        .arg(&fb)
        .args(["--out", "rep"])
        .assert()
        .success();
    let e = stderr(&a);
    assert!(!e.contains("worse than the nominal model"), "{e}");
    let line = std::fs::read_to_string(d.join("rep/certificate.json")).unwrap();
    let c: serde_json::Value = serde_json::from_str(&line).unwrap();
    let h = &c["held_out"];
    let (before, after) = (
        h["before"]["rms_mm"].as_f64().unwrap(),
        h["after"]["rms_mm"].as_f64().unwrap(),
    );
    assert!(after < before, "{h}");
}

#[test]
fn without_a_tool_target_at_the_reference_pose_the_height_is_said_kept() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let f = scara(d, 1631);
    altered_csv(&f, "notool.csv", |fields| fields[0] != "tool", |_| {});
    let e = calibrate(d, &d.join("notool.csv"), "cal");
    assert!(
        e.contains("kept from the description's placement: position along axis 1"),
        "{e}"
    );
    assert!(!e.contains("from tool target"), "{e}");
}
