//! The sweep-cause search's size (hostile run 70): where a calibration misses the file's own
//! validation poses, `calibrate` tries each sweep's held commands, drift and moved block as
//! the cause, a calibration per trial (`src/diagnosis/sweep_causes.rs`). Their count grows as
//! the square of the joints: an 18-joint arm's 915 trials took a minute before its warning.
//! Beyond `MAX_SWEEP_SEARCH_CALIBRATIONS` the search is not run and the warning says so, with
//! the count; below it (the IRB/L6, the table, the positioner: `hostile_round18h`) it runs.

use crate::common::{altered_experiment, axiscal, stderr};
use axiscal::diagnosis::MAX_SWEEP_SEARCH_CALIBRATIONS;
use std::fmt::Write;
use std::path::Path;

/// A snake of `n` revolute joints (classic DH, successive axes crossing at right angles, 120 mm
/// between every other pair), its sweeps' targets on the last link: a robot unlike the
/// shipped ones, written here.
fn snake(dir: &Path, n: usize) -> std::path::PathBuf {
    let mut toml = format!("name = \"Snake {n}\"\ndh_convention = \"classic\"\n");
    for i in 0..n {
        let alpha = match (i + 1 == n, i % 2) {
            (true, _) => 0.0,
            (false, 0) => -90.0,
            (false, _) => 90.0,
        };
        let d = if i % 2 == 0 { 120.0 } else { 0.0 };
        writeln!(
            toml,
            "[[joints]]\nkind = \"revolute\"\nlimits = [-120.0, 120.0]\n\
             dh = {{ d_mm = {d}, theta_deg = 0.0, a_mm = 0.0, alpha_deg = {alpha} }}"
        )
        .unwrap();
    }
    toml.push_str(
        "[placement]\ntranslation_mm = [1500.0, 200.0, -300.0]\nrpy_deg = [0.0, 0.0, 40.0]\n[tool]\n\
         frame = { translation_mm = [0.0, 0.0, 60.0], rpy_deg = [0.0, 0.0, 0.0] }\n\
         targets_mm = [[0.0, 0.0, 0.0], [80.0, 0.0, 0.0], [0.0, 80.0, 0.0]]\n",
    );
    for j in 1..=n {
        writeln!(
            toml,
            "[[axis_targets]]\njoint = {j}\ntarget0 = {{ link = {n}, position_mm = [60.0, 40.0, 120.0] }}"
        )
        .unwrap();
    }
    let path = dir.join(format!("snake{n}.toml"));
    std::fs::write(&path, toml).unwrap();
    path
}

/// An 18-joint snake whose sweep `axis9` recorded its held `cmd_2` 1 deg off (seed 71, not
/// tuned): the poses miss, the warning says the search was not run and why, and the
/// calibration is written.
#[test]
fn an_eighteen_joint_arm_says_its_sweep_search_is_too_large() {
    let dir = tempfile::tempdir().unwrap();
    let robot = snake(dir.path(), 18);
    let clean = dir.path().join("clean.csv");
    axiscal()
        .current_dir(dir.path())
        .args([
            "simulate",
            "--sim",
            "analytic",
            "--instrument",
            "isotropic",
            "--validation-poses",
            "20",
        ])
        .args(["--seed", "71", "--robot"])
        .arg(&robot)
        .arg("--out")
        .arg(&clean)
        .assert()
        .success();
    let shifted = altered_experiment(&clean, "held.csv", "axis9", |f| {
        f[6 + 2] = (f[6 + 2].parse::<f64>().unwrap() + 1.0).to_string();
    });
    let a = axiscal()
        .current_dir(dir.path())
        .args(["calibrate", "--out", "cal", "--robot"])
        .arg(&robot)
        .arg(&shifted)
        .assert()
        .success();
    let err = stderr(&a);
    let warning = err
        .lines()
        .find(|l| l.contains("misses this file's own 20 validation poses"))
        .unwrap_or_else(|| panic!("no miss of the validation poses in:\n{err}"));
    let rest = warning
        .split("no sweep's held command, drift or moved block was tried as its cause (its ")
        .nth(1)
        .unwrap_or_else(|| panic!("the search not said unrun in: {warning}"));
    let hypotheses: usize = rest.split(' ').next().unwrap().parse().unwrap();
    let calibrations: usize = rest
        .split("would cost ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    // At least a held command of every sweep but the base's and two trials each.
    assert!(hypotheses >= 17 * 17, "{warning}");
    assert!(
        calibrations >= 2 * hypotheses && calibrations > MAX_SWEEP_SEARCH_CALIBRATIONS,
        "{warning}"
    );
    assert!(warning.contains(&format!("beyond the {MAX_SWEEP_SEARCH_CALIBRATIONS} the search runs")));
    assert!(dir.path().join("cal/calibration.json").exists());
}
