//! `validate` names a block of validation poses shifted in file order (an instrument bumped
//! part-way through), on files an independent generator wrote: a mid-file block of the
//! parallelogram arm's validation poses and the KR arm's free poses from one on; and names none
//! where the miss is an effect the calibration lacks (a balancer, a weak joint, a serial sag).

use crate::common::{self, axiscal};
use std::path::{Path, PathBuf};

fn data(folder: &str, file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(folder)
        .join(file)
}

/// `axiscal calibrate` of `file` with the description `robot` into `out`.
fn calibrate(robot: &Path, file: &Path, out: &Path, extra: &[&str]) {
    axiscal()
        .args(["calibrate", "--quiet", "--robot"])
        .arg(robot)
        .arg(file)
        .args(extra)
        .arg("--out")
        .arg(out)
        .assert()
        .success();
}

/// The parallelogram arm and the KR arm, each with its calibration (in `dir`) from its
/// generator's clean file (the KR arm's without effects): (description, calibration folder).
fn clean_calibrations(dir: &Path) -> [(PathBuf, PathBuf); 2] {
    let pg = data("independent-parallelogram", "pg-arm.toml");
    let kr = data("independent-freepose", "kr-arm.toml");
    let pg_cal = dir.join("pg");
    calibrate(&pg, &data("independent-parallelogram", "none.csv"), &pg_cal, &[]);
    let kr_cal = dir.join("kr");
    calibrate(
        &kr,
        &data("independent-freepose", "clean.csv"),
        &kr_cal,
        &["--effects", "none"],
    );
    [(pg, pg_cal), (kr, kr_cal)]
}

/// `axiscal validate` of `file`: its stderr and its summary.json.
fn validate(robot: &Path, calibration: &Path, file: &Path, out: &Path) -> (String, serde_json::Value) {
    let a = axiscal()
        .args(["validate", "--robot"])
        .arg(robot)
        .arg("--calibration")
        .arg(calibration.join("calibration.json"))
        .arg(file)
        .arg("--out")
        .arg(out)
        .assert()
        .success();
    let summary = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    (common::stderr(&a), summary)
}

/// `text` with the rows of experiment `experiment` at steps `steps` moved by `shift_mm`, and
/// the file lines (1-based) of the first and last row moved.
fn shifted(
    text: &str,
    experiment: &str,
    steps: std::ops::Range<usize>,
    shift_mm: [f64; 3],
) -> (String, (usize, usize)) {
    let mut moved = vec![];
    let lines: Vec<String> = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            let mut f: Vec<String> = l.split(',').map(str::to_owned).collect();
            let hit = f[0] == experiment && f.len() > 6 && f[2].parse().is_ok_and(|s: usize| steps.contains(&s));
            if !hit {
                return l.to_owned();
            }
            moved.push(i + 1);
            for c in 0..3 {
                let x: f64 = f[4 + c].parse().unwrap();
                f[4 + c] = format!("{}", x + shift_mm[c]);
            }
            f.join(",")
        })
        .collect();
    (lines.join("\n") + "\n", (moved[0], *moved.last().unwrap()))
}

/// The shift a warning line gives: `sit about (X, Y, Z) mm off`.
fn named_shift(warning: &str) -> [f64; 3] {
    let inside = warning.split("sit about (").nth(1).unwrap().split(')').next().unwrap();
    let v: Vec<f64> = inside.split(',').map(|x| x.trim().parse().unwrap()).collect();
    [v[0], v[1], v[2]]
}

/// A block shifted on top of an effect the calibration lacks, so that no slip undone explains
/// the whole miss (a block alone is refused by the slip search, `validate`'s older check): mid-file
/// on the parallelogram arm's validation poses with its 70 % balancer (0.8 mm along y), and from
/// a pose to the end on the KR arm's free poses with backlash (0.3 mm down z). Each is named by
/// the lines of its first and last row, its shift within 4 standard errors of the one made (a
/// coordinate's standard error from the validation's RMS as written over the poses inside and
/// outside the block), and the warning is in summary.json.
#[test]
fn a_shifted_block_of_validation_poses_is_named_by_its_lines() {
    let dir = tempfile::tempdir().unwrap();
    let [(pg, pg_cal), (kr, kr_cal)] = clean_calibrations(dir.path());
    let cases = [
        (
            (&pg, &pg_cal),
            data("independent-parallelogram", "balancer-f0.7.csv"),
            ("validation", 30..50, 100),
            [0.0, 0.8, 0.0],
        ),
        (
            (&kr, &kr_cal),
            data("independent-freepose", "backlash.csv"),
            ("poses", 200..300, 300),
            [0.0, 0.0, -0.3],
        ),
    ];
    for (k, ((robot, cal), file, (experiment, steps, poses), shift)) in cases.into_iter().enumerate() {
        let text = std::fs::read_to_string(&file).unwrap();
        let (moved, (first, last)) = shifted(&text, experiment, steps.clone(), shift);
        let moved_file = dir.path().join(format!("moved{k}.csv"));
        std::fs::write(&moved_file, moved).unwrap();
        let (err, summary) = validate(robot, cal, &moved_file, &dir.path().join(format!("v{k}")));
        let warning = err
            .lines()
            .find(|l| l.contains("the validation poses of lines"))
            .unwrap_or_else(|| panic!("case {k}: no block named: {err}"));
        assert!(
            warning.contains(&format!("of lines {first}-{last} ")),
            "case {k}: lines {first}-{last}: {warning}"
        );
        let inside = steps.len() as f64;
        let per_coordinate = summary["validation"]["rms_mm"].as_f64().unwrap() / 3f64.sqrt();
        let standard_error = per_coordinate * (1.0 / inside + 1.0 / (poses as f64 - inside)).sqrt();
        let named = named_shift(warning);
        for c in 0..3 {
            assert!(
                (named[c] - shift[c]).abs() < 4.0 * standard_error,
                "case {k}: shift {named:?} against {shift:?} (standard error {standard_error:.4} mm)"
            );
        }
        let recorded = summary["warnings"].as_array().unwrap();
        assert!(
            recorded
                .iter()
                .any(|w| w.as_str() == Some(&warning["warning: ".len()..])),
            "case {k}: {recorded:?}"
        );
    }
}

/// Misses an effect the calibration lacks causes (a 70 % balancer, a weak joint 3, the KR arm's
/// serial sag, its backlash), spread over the workspace and not over a block of the file, are
/// validated without a block named.
#[test]
fn an_effects_miss_names_no_block() {
    let dir = tempfile::tempdir().unwrap();
    let [(pg, pg_cal), (kr, kr_cal)] = clean_calibrations(dir.path());
    let cases = [
        (&pg, &pg_cal, data("independent-parallelogram", "balancer-f0.7.csv")),
        (&pg, &pg_cal, data("independent-parallelogram", "joint3-hi.csv")),
        (&kr, &kr_cal, data("independent-freepose", "serial.csv")),
        (&kr, &kr_cal, data("independent-freepose", "backlash.csv")),
    ];
    for (k, (robot, cal, file)) in cases.into_iter().enumerate() {
        let (err, summary) = validate(robot, cal, &file, &dir.path().join(format!("v{k}")));
        assert_eq!(
            summary["validation"]["chi_square"]["verdict"],
            "exceeds",
            "{}: the effect must fail the validation for the check to mean anything",
            file.display()
        );
        assert!(
            !err.contains("the validation poses of lines"),
            "{}: {err}",
            file.display()
        );
    }
}

/// `diagnose` names the same block before it diagnoses (on the parallelogram arm's file with its
/// 70 % balancer and a mid-file block 0.8 mm along y, calibrated from its own sweeps), in its
/// console and in diagnosis.json's `warnings`; the file as written names none.
#[test]
fn diagnose_names_a_shifted_block_before_it_diagnoses() {
    let dir = tempfile::tempdir().unwrap();
    let robot = data("independent-parallelogram", "pg-arm.toml");
    let text = std::fs::read_to_string(data("independent-parallelogram", "balancer-f0.7.csv")).unwrap();
    let (moved, (first, last)) = shifted(&text, "validation", 30..50, [0.0, 0.8, 0.0]);
    let moved_file = dir.path().join("moved.csv");
    std::fs::write(&moved_file, moved).unwrap();
    let as_written = dir.path().join("as-written.csv");
    std::fs::write(&as_written, &text).unwrap();
    for (file, named) in [(&moved_file, true), (&as_written, false)] {
        let out = dir.path().join(format!("d-{named}"));
        let a = axiscal()
            .args(["diagnose", "--robot"])
            .arg(&robot)
            .arg(file)
            .arg("--out")
            .arg(&out)
            .assert()
            .success();
        let err = common::stderr(&a);
        let warning = err.lines().find(|l| l.contains("the validation poses of lines"));
        let d: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("diagnosis.json")).unwrap()).unwrap();
        if !named {
            assert!(warning.is_none() && d.get("warnings").is_none(), "{err}");
            continue;
        }
        let warning = warning.unwrap_or_else(|| panic!("no block named: {err}"));
        assert!(
            warning.contains(&format!("of lines {first}-{last} ")),
            "lines {first}-{last}: {warning}"
        );
        assert!(warning.contains("diagnose those rows apart"), "{warning}");
        let recorded = d["warnings"].as_array().unwrap();
        assert!(
            recorded
                .iter()
                .any(|w| w.as_str() == Some(&warning["warning: ".len()..])),
            "{recorded:?}"
        );
    }
}
