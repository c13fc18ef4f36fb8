//! One coordinate column scaled by a factor that is no length unit (`x_mm` doubled, `z_mm` read
//! 30 % short), on files written outside axiscal (`tests/data/independent-*`: separately
//! written generators, their own robots and conventions): refused naming the column and the
//! factor, where before the calibration blamed a transmission or a few rows. The same files as
//! written stay quiet.

use crate::common::{axiscal, column_scaled, stderr};
use axiscal::measurement::unit_check::column_stretch::GRID_STEP;
use std::path::{Path, PathBuf};

fn data(folder: &str, file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(folder)
        .join(file)
}

/// `file` without its free poses (`moved_joint = 0`), as `name` in `dir`: the sweeps alone.
fn sweeps_only(file: &Path, dir: &Path, name: &str) -> PathBuf {
    let text = std::fs::read_to_string(file).unwrap();
    let kept: String = text
        .lines()
        .filter(|l| l.starts_with('#') || l.starts_with("experiment,") || l.split(',').nth(1) != Some("0"))
        .map(|l| format!("{l}\n"))
        .collect();
    let out = dir.join(name);
    std::fs::write(&out, kept).unwrap();
    out
}

/// `calibrate` of `file` for `robot` into `dir/out`: its exit code and stderr.
fn calibrate(robot: &Path, file: &Path, dir: &Path) -> (i32, String) {
    let a = axiscal()
        .args(["calibrate", "--quiet", "--force"])
        .arg("--robot")
        .arg(robot)
        .arg(file)
        .arg("--out")
        .arg(dir.join("out"))
        .assert();
    let code = a.get_output().status.code().unwrap_or(-1);
    (code, stderr(&a))
}

/// The factor the error names for `column` (`its values are F times`).
fn named_factor(err: &str, column: &str) -> f64 {
    let at = err
        .find(&format!("`{column}`: its values are "))
        .unwrap_or_else(|| panic!("{column} not named:\n{err}"));
    let rest = &err[at..];
    let after = rest.split("its values are ").nth(1).unwrap();
    after.split(' ').next().unwrap().parse().unwrap()
}

#[test]
fn a_column_scaled_by_no_unit_is_named_with_its_factor_on_other_robots_files() {
    let dir = tempfile::tempdir().unwrap();
    let kr = data("independent-freepose", "kr-arm.toml");
    let pg = data("independent-parallelogram", "pg-arm.toml");
    let free = dir.path().join("free.csv");
    std::fs::copy(data("independent-freepose", "clean.csv"), &free).unwrap();
    let mixed = dir.path().join("mixed.csv");
    std::fs::copy(data("independent-parallelogram", "none.csv"), &mixed).unwrap();
    let sweeps = sweeps_only(&mixed, dir.path(), "sweeps.csv");
    // Field index of x_mm in the measurement CSV.
    const X: usize = 4;
    let cases: [(&Path, &Path, usize, f64); 4] = [
        (&kr, &free, 0, 2.0),
        (&kr, &free, 2, 0.7),
        (&pg, &mixed, 1, 1.3),
        (&pg, &sweeps, 2, 0.8),
    ];
    for (robot, file, column, factor) in cases {
        let (code, err) = calibrate(robot, file, dir.path());
        assert_eq!(code, 0, "{} as written:\n{err}", file.display());
        assert!(!err.contains("its values are"), "{err}");
        let scaled = column_scaled(file, "scaled.csv", X + column, factor);
        let (code, err) = calibrate(robot, &scaled, dir.path());
        assert_eq!(code, 2, "{} with column {column} x {factor}:\n{err}", file.display());
        let name = ["x_mm", "y_mm", "z_mm"][column];
        let found = named_factor(&err, name);
        // The search's resolution is its grid step, refined by a parabola.
        assert!(
            (found / factor).ln().abs() < GRID_STEP.ln(),
            "{name} x {factor} read as {found}:\n{err}"
        );
        assert!(err.contains("scaled.csv"), "{err}");
    }
}
