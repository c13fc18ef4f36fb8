//! A slow drift through one sweep (hostile run 16's defect 4: the instrument or the robot's
//! base creeping while one sweep ran, SW on the table, the IRB/L6, the UR5e and the 7-axis
//! arm): the sweep's own fit takes most of a linear drift into its axis and the bump test (a
//! step) does not name it, so `calibrate` said only "the calibrated model misses this file's
//! own N validation poses". Now, where the file's own validation poses miss, each sweep is also
//! tried with a drift undone, the drift (three parameters) fitted by recalibrating
//! (`src/diagnosis/sweep_causes.rs`, beside the held commands), and one whose undoing makes the
//! poses pass, by an F test shared among the hypotheses, is named with the sweep's lines, the
//! drift and its 1-sigma. The second path: a drift and twice it, named apart, differ by the one
//! written within 4 of their sigmas. Where the reference-pose test reads the drift as a held
//! offset or a moved block at the reference pose and the drift fits the poses best, the
//! drift's warning says how that test read the sweep and that test's own warning of it is left
//! out. A drift through the whole file (the validation poses too) is tried the same way, in
//! file order. Not reached: a file without validation poses.

use crate::common::hostile::{assert_twice_less_once_3, lines_of};
use crate::common::{altered_csv, altered_experiment};
use crate::hostile_round15s::{calibrated, simulated};
use std::path::{Path, PathBuf};

/// The words of the drift warning before the vector (clean files: `hostile_round18h`).
pub const DRIFT: &str = "its points look to drift by (";

/// Shapes apart, seeds not tuned: (robot, experiment, drift from the sweep's first step to
/// its last in mm): the table's turning joint along y, the 6-axis arm's wrist sweep along x,
/// the UR5e's shoulder down z.
const CASES: [(&str, &str, [f64; 3]); 3] = [
    ("table-prpp", "axis2", [0.0, 3.0, 0.0]),
    ("arm6-dh", "axis4", [1.5, 0.0, 0.0]),
    ("ur5e-dh", "axis2", [0.0, 0.0, -2.0]),
];

/// `clean` with experiment `experiment`'s points moved by `t drift_mm`, `t` from 0 at its
/// first step to 1 at its last, as `name` in `dir`.
fn with_drift(dir: &Path, clean: &Path, name: &str, experiment: &str, drift_mm: [f64; 3]) -> PathBuf {
    let text = std::fs::read_to_string(clean).unwrap();
    let steps: Vec<f64> = text
        .lines()
        .filter(|l| l.split(',').next() == Some(experiment))
        .map(|l| l.split(',').nth(2).unwrap().parse().unwrap())
        .collect();
    let (first, last) = steps
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &s| (a.min(s), b.max(s)));
    altered_experiment(clean, name, experiment, |f| {
        let t = (f[2].parse::<f64>().unwrap() - first) / (last - first);
        for (c, d) in drift_mm.iter().enumerate() {
            f[4 + c] = (f[4 + c].parse::<f64>().unwrap() + t * d).to_string();
        }
    });
    dir.join(name)
}

/// The drift and its 1-sigma per axis the warning names for `owner` (`experiment E` or `the
/// whole file`), with its lines (`None` when not named).
fn named_drift(stderr: &str, owner: &str) -> Option<([f64; 3], [f64; 3], String)> {
    let line = stderr
        .lines()
        .find(|l| l.starts_with("warning:") && l.contains(&format!(": {owner} (lines ")) && l.contains(DRIFT))?;
    let lines = line.split(" (lines ").nth(1)?.split(')').next()?.to_string();
    let triple = |s: &str| -> Option<[f64; 3]> {
        let v: Vec<f64> = s.split(", ").map(|x| x.parse().ok()).collect::<Option<_>>()?;
        v.try_into().ok()
    };
    let rest = line.split(DRIFT).nth(1)?;
    let drift = triple(rest.split(')').next()?)?;
    let sigma = triple(rest.split("(1-sigma (").nth(1)?.split(')').next()?)?;
    Some((drift, sigma, lines))
}

#[test]
fn a_drift_through_one_sweep_is_named_by_the_validation_poses() {
    for (robot, experiment, drift) in CASES {
        let dir = tempfile::tempdir().unwrap();
        let clean = simulated(dir.path(), robot, 7);
        let e = calibrated(dir.path(), robot, &clean);
        assert!(!e.contains(DRIFT), "{robot}: clean file: {e}");
        let once_file = with_drift(dir.path(), &clean, "once.csv", experiment, drift);
        let e = calibrated(dir.path(), robot, &once_file);
        let (once, sigma_once, lines) = named_drift(&e, &format!("experiment {experiment}"))
            .unwrap_or_else(|| panic!("{robot}: {experiment}'s drift not named: {e}"));
        assert_eq!(lines, lines_of(&once_file, experiment), "{robot}: {e}");
        // A second path: the same sweep with twice the drift; the two named drifts differ by
        // the one written, within 4 of their sigmas on each axis (the clean file's own miss
        // cancels).
        let twice_file = with_drift(dir.path(), &clean, "twice.csv", experiment, drift.map(|d| 2.0 * d));
        let e = calibrated(dir.path(), robot, &twice_file);
        let (twice, sigma_twice, _) = named_drift(&e, &format!("experiment {experiment}"))
            .unwrap_or_else(|| panic!("{robot}: twice the drift not named: {e}"));
        assert_twice_less_once_3(
            &format!("{robot}: {e}"),
            (once, sigma_once),
            (twice, sigma_twice),
            drift,
        );
    }
}

/// `clean` with every data row `i` of `n` moved by `i / (n - 1) drift_mm`, as `name` in `dir`.
fn with_file_drift(dir: &Path, clean: &Path, name: &str, drift_mm: [f64; 3]) -> PathBuf {
    let text = std::fs::read_to_string(clean).unwrap();
    let n = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("experiment,"))
        .count();
    let row = std::cell::Cell::new(0usize);
    altered_csv(
        clean,
        name,
        |_| true,
        |f| {
            let t = row.get() as f64 / (n - 1) as f64;
            row.set(row.get() + 1);
            for (c, d) in drift_mm.iter().enumerate() {
                f[4 + c] = (f[4 + c].parse::<f64>().unwrap() + t * d).to_string();
            }
        },
    );
    dir.join(name)
}

#[test]
fn a_drift_through_the_whole_file_is_named_in_file_order() {
    // Shapes apart, seeds not tuned: the 6-axis arm rising, the UR5e drifting aslant, the
    // table along x.
    for (robot, drift) in [
        ("arm6-dh", [0.0, 0.0, 2.0]),
        ("ur5e-dh", [0.0, -2.0, 1.0]),
        ("table-prpp", [1.5, 0.0, 0.0]),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let clean = simulated(dir.path(), robot, 11);
        let once_file = with_file_drift(dir.path(), &clean, "once.csv", drift);
        let e = calibrated(dir.path(), robot, &once_file);
        let whole = "the whole file";
        let (once, sigma_once, _) =
            named_drift(&e, whole).unwrap_or_else(|| panic!("{robot}: the file's drift not named: {e}"));
        let twice_file = with_file_drift(dir.path(), &clean, "twice.csv", drift.map(|d| 2.0 * d));
        let e = calibrated(dir.path(), robot, &twice_file);
        let (twice, sigma_twice, _) =
            named_drift(&e, whole).unwrap_or_else(|| panic!("{robot}: twice the file's drift not named: {e}"));
        assert_twice_less_once_3(
            &format!("{robot}: {e}"),
            (once, sigma_once),
            (twice, sigma_twice),
            drift,
        );
    }
}

/// The reference-pose test's warning of experiment `experiment` (`... is out of place among`).
fn out_of_place<'a>(stderr: &'a str, experiment: &str) -> Option<&'a str> {
    stderr
        .lines()
        .find(|l| l.contains(&format!("experiment {experiment} (lines ")) && l.contains("is out of place among"))
}

/// Where the reference-pose test reads a sweep's drift as a move of its block (the 6-axis arm's
/// wrist sweep drifting 3 mm along x; seed 7 as above, not tuned) and the drift fits the
/// validation poses, `calibrate` says it once: the drift's warning, with how that test read the
/// sweep, and not the test's own "out of place". The same sweep's points all moved by the
/// drift's mean (a block moved, 1.5 mm along x) keep the test's warning and name no drift.
#[test]
fn a_drift_the_reference_pose_test_reads_as_a_moved_block_is_said_once() {
    let (robot, experiment) = ("arm6-dh", "axis4");
    let dir = tempfile::tempdir().unwrap();
    let clean = simulated(dir.path(), robot, 7);
    let drifted = with_drift(dir.path(), &clean, "drift.csv", experiment, [3.0, 0.0, 0.0]);
    let e = calibrated(dir.path(), robot, &drifted);
    let drift = e
        .lines()
        .find(|l| l.contains(DRIFT))
        .unwrap_or_else(|| panic!("the drift not named: {e}"));
    assert!(drift.contains("reads this sweep as a move of its block"), "{drift}");
    assert_eq!(out_of_place(&e, experiment), None, "said twice: {e}");
    let moved = altered_experiment(&clean, "moved.csv", experiment, |f| {
        f[4] = (f[4].parse::<f64>().unwrap() + 1.5).to_string();
    });
    let e = calibrated(dir.path(), robot, &moved);
    assert!(out_of_place(&e, experiment).is_some(), "a moved block not said: {e}");
    assert!(!e.contains(DRIFT), "a moved block called a drift: {e}");
}
