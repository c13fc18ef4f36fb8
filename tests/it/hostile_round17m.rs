//! Session 55 (issue #33; hostile run 16's FA 9, `fa-bigval-slice`): `validate` called a clean
//! point an outlier, 4.67 mm off in a 2000-pose slice of a simulated file where the
//! calibration's own error dominates the prediction (2.28 mm RMS): its fence was in units of
//! the noise. A point the noise fences flag is now an outlier only if it stays beyond them once
//! the calibration's error, which every pose's residuals estimate together, is taken out; a
//! corrupted cell about that clean point's miss (5 mm) is still named by its line.
//!
//! The same file with one corrupted cell made `validate` take 21 GB and more: the slip search
//! held every run of consecutive free poses (cubic in the poses) and a dense 3N x 3N weight
//! matrix. It now finishes in bounded memory.

use crate::common::{altered_csv, axiscal, stderr};
use crate::hostile_round16v::simulated_with_poses as simulated;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The three rows of pose 67049 of hostile run 16's part B `big.csv` (`simulate --sim analytic
/// --validation-poses 333000`, clean): target 2 misses the calibration of `simulate --seed 1`
/// by 4.67 mm, its pose's other targets by 3.33 and 2.83 mm.
const POSE_67049: &str = "validation,0,67049,0,-3245.2405438577125,5120.740472900244,-721.7247767763484,20.083864909914965,-27.640575853487157,-31.21936070086653,-22.913243824250166,-78.78917221763557,65.4612147759122,0,20
validation,0,67049,1,-3234.8847226350417,5044.993278088415,-697.989703104632,20.083864909914965,-27.640575853487157,-31.21936070086653,-22.913243824250166,-78.78917221763557,65.4612147759122,0,20
validation,0,67049,2,-3245.555581281969,5096.53469684905,-797.8333540445377,20.083864909914965,-27.640575853487157,-31.21936070086653,-22.913243824250166,-78.78917221763557,65.4612147759122,0,20
";

/// Field `x_mm` of the measurement CSV.
const X_MM: usize = 4;

/// `axiscal ARGS` in `dir`, expecting `code`: its stderr.
fn run(dir: &Path, args: &[&str], code: i32) -> String {
    stderr(&axiscal().current_dir(dir).args(args).assert().code(code))
}

/// `file` with `x_mm` of data row `row` (0-based) moved by `mm`, as `name`.
fn cell_moved(file: &Path, name: &str, row: usize, mm: f64) -> PathBuf {
    let at = AtomicUsize::new(0);
    altered_csv(
        file,
        name,
        |_| true,
        |f| {
            if at.fetch_add(1, Ordering::Relaxed) == row {
                f[X_MM] = (f[X_MM].parse::<f64>().unwrap() + mm).to_string();
            }
        },
    )
}

/// The outlier lines of `stderr`.
fn outliers(stderr: &str) -> Vec<&str> {
    stderr.lines().filter(|l| l.contains(": outlier: ")).collect()
}

/// The clean point run 16 flagged, among 2000 clean poses (seed 11) validated against the
/// calibration of `simulate --seed 1` (the paper robot): no outlier (before: "39.7 times the
/// noise, beyond the fence 31.6"). Fresh clean files (seeds 12, 13, not tuned on) stay quiet;
/// a cell moved 5 mm, about that clean point's 4.67 mm miss, is named by its line, and so
/// is one moved 10 mm, whose failing test runs the slip search over 2000 poses (before: more
/// than 21 GB).
#[test]
fn a_point_the_calibration_error_explains_is_no_outlier() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    run(d, &["simulate", "--seed", "1", "--out", "camp.csv", "-q"], 0);
    run(d, &["calibrate", "camp.csv", "--out", "cal", "-q"], 0);
    let validate = |file: &str| {
        run(
            d,
            &[
                "validate",
                file,
                "--calibration",
                "cal/calibration.json",
                "--out",
                "o",
                "--force",
            ],
            0,
        )
    };
    let clean = simulated(d, &[], 2000, 11, "src11.csv");
    let clean = altered_csv(&clean, "v11.csv", |f| f[0] == "validation", |_| {});
    let mut text = std::fs::read_to_string(&clean).unwrap();
    text.push_str(POSE_67049);
    std::fs::write(d.join("with.csv"), text).unwrap();
    let e = validate("with.csv");
    assert!(outliers(&e).is_empty(), "a clean point flagged: {e}");
    for seed in [12, 13] {
        let source = simulated(d, &[], 2000, seed, "src.csv");
        altered_csv(&source, "v.csv", |f| f[0] == "validation", |_| {});
        let e = validate("v.csv");
        assert!(outliers(&e).is_empty(), "seed {seed}: {e}");
    }
    // Data row 1000 (0-based; line 1003 after a comment line and the header) is pose 333's
    // target 1.
    for (mm, name) in [(5.0, "cell5.csv"), (10.0, "cell10.csv")] {
        cell_moved(&clean, name, 1000, mm);
        let e = validate(name);
        let expected = format!("{name}:1003: outlier: experiment validation step 333 target 1");
        assert!(
            outliers(&e).len() == 1 && outliers(&e)[0].contains(&expected),
            "{mm} mm: {e}"
        );
    }
}

/// Other robots, calibrated on a file's sweeps and its first 60 validation poses and validated
/// on its other 200 poses (the same truth, seeds 31 and 32, not tuned on): no outlier on the
/// clean poses, and a cell moved 10 mm named by its line.
#[test]
fn clean_held_out_poses_of_other_robots_have_no_outlier_and_a_cell_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let robots = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/robots");
    for (name, seed) in [("ur5e-dh", 31), ("scara-rrpr", 32)] {
        let robot = robots.join(format!("{name}.toml"));
        let robot = robot.to_str().unwrap();
        let all = simulated(d, &["--robot", robot], 260, seed, "all.csv");
        let held_out = |f: &[String]| f[0] == "validation" && f[2].parse::<usize>().unwrap() >= 60;
        altered_csv(&all, "fit.csv", |f| !held_out(f), |_| {});
        let check = altered_csv(&all, "check.csv", held_out, |_| {});
        run(
            d,
            &[
                "calibrate",
                "fit.csv",
                "--robot",
                robot,
                "--out",
                "cal",
                "--force",
                "-q",
            ],
            0,
        );
        let validate = |file: &str| {
            let args = [
                "validate",
                file,
                "--robot",
                robot,
                "--calibration",
                "cal/calibration.json",
                "--out",
                "o",
                "--force",
            ];
            run(d, &args, 0)
        };
        let e = validate("check.csv");
        assert!(outliers(&e).is_empty(), "{name}: {e}");
        cell_moved(&check, "cell.csv", 301, 10.0);
        let e = validate("cell.csv");
        assert!(
            outliers(&e).len() == 1 && outliers(&e)[0].contains("cell.csv:304: outlier: "),
            "{name}: {e}"
        );
    }
}
