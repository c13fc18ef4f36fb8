//! Helper h18h, keeping hostile run 16's defect 2 (a held joint's recorded command off where
//! the robot stood through one sweep, SW on the P-R-P-P table, the two-axis positioner and the
//! IRB/L6 paper robot): on these robots the offset turns the swept arc rigidly about the held
//! joint's axis, the sweep's own axis fit takes it in and the reference-pose test has nothing to
//! see, so `calibrate` said only "the calibrated model misses this file's own N validation
//! poses". Now, where the file's own validation poses miss, each held command of each sweep is
//! tried corrected by a fitted amount (recalibrating, `src/diagnosis/sweep_causes.rs`), and one whose
//! correction makes the poses pass, by an F test shared among the hypotheses, is named with
//! the sweep's lines, the offset and its 1-sigma: "in.csv:19: experiment axis3 (lines 19-34):
//! the held `cmd_2` looks offset by +1.0 deg". Clean files of six robots stay quiet. Not
//! reached: a file without validation poses, and an offset the poses do not miss by
//! (`docs/formats.md`).

use crate::common::altered_experiment;
use crate::common::hostile::{assert_twice_less_once, lines_of};
use crate::hostile_round15s::{calibrated, simulated};
use std::path::Path;

/// The words of the held-offset warning before the joint.
const HELD: &str = "the held `cmd_";

/// The hostile run's cases, shapes apart: (robot, experiment, held joint, offset in deg): the
/// table's turning joint held through a slide's sweep, the positioner's tilt held through the
/// turntable's sweep, the IRB/L6's base held through a wrist sweep (rapier simulation). (The
/// positioner at 4 deg is named by the reference-pose test: "axis2 and axis1 disagree".)
const CASES: [(&str, &str, usize, f64); 3] = [
    ("table-prpp", "axis3", 2, 1.0),
    ("positioner-2axis", "axis2", 1, 1.0),
    ("asea-irb6l", "axis5", 1, 1.0),
];

/// `clean` with `cmd_{joint}` moved by `delta` in experiment `experiment`'s rows, as `name` in
/// `dir`.
fn with_held_offset(dir: &Path, clean: &Path, name: &str, (experiment, joint, delta): (&str, usize, f64)) {
    altered_experiment(clean, name, experiment, |f| {
        let c = 6 + joint;
        f[c] = (f[c].parse::<f64>().unwrap() + delta).to_string();
    });
    assert!(dir.join(name).exists());
}

/// The offset and 1-sigma the warning names for the held `cmd_{joint}` of `experiment`, with
/// the sweep's lines in the file (`None` when not named).
fn named_offset(stderr: &str, experiment: &str, joint: usize) -> Option<(f64, f64, String)> {
    let line = stderr
        .lines()
        .find(|l| l.starts_with("warning:") && l.contains(&format!("experiment {experiment} (lines ")))?;
    let lines = line.split(" (lines ").nth(1)?.split(')').next()?.to_string();
    let rest = line.split(&format!("{HELD}{joint}` looks offset by ")).nth(1)?;
    let offset: f64 = rest.split(' ').next()?.parse().ok()?;
    let sigma: f64 = rest.split("(1-sigma ").nth(1)?.split(')').next()?.parse().ok()?;
    Some((offset, sigma, lines))
}

#[test]
fn a_held_offset_the_sweep_absorbs_is_named_by_the_validation_poses() {
    for (robot, experiment, joint, delta) in CASES {
        let dir = tempfile::tempdir().unwrap();
        let clean = simulated(dir.path(), robot, 7);
        let e = calibrated(dir.path(), robot, &clean);
        assert!(!e.contains(HELD), "{robot}: clean file: {e}");
        with_held_offset(dir.path(), &clean, "once.csv", (experiment, joint, delta));
        let e = calibrated(dir.path(), robot, &dir.path().join("once.csv"));
        let (once, sigma_once, lines) =
            named_offset(&e, experiment, joint).unwrap_or_else(|| panic!("{robot}: cmd_{joint} not named: {e}"));
        assert_eq!(
            lines,
            lines_of(&dir.path().join("once.csv"), experiment),
            "{robot}: {e}"
        );
        // A second path: the same sweep with twice the offset; the two named offsets differ by
        // the one written, within 4 of their sigmas (the clean file's own miss cancels).
        with_held_offset(dir.path(), &clean, "twice.csv", (experiment, joint, 2.0 * delta));
        let e = calibrated(dir.path(), robot, &dir.path().join("twice.csv"));
        let (twice, sigma_twice, _) =
            named_offset(&e, experiment, joint).unwrap_or_else(|| panic!("{robot}: cmd_{joint} not named: {e}"));
        assert_twice_less_once(
            &format!("{robot}: {e}"),
            (once, sigma_once),
            (twice, sigma_twice),
            delta,
        );
    }
}

#[test]
fn clean_files_of_six_robots_name_no_held_offset_drift_or_block() {
    for robot in [
        "table-prpp",
        "positioner-2axis",
        "asea-irb6l",
        "scara-rrpr",
        "arm6-dh",
        "ur5e-dh",
    ] {
        let dir = tempfile::tempdir().unwrap();
        let clean = simulated(dir.path(), robot, 8);
        let e = calibrated(dir.path(), robot, &clean);
        for cause in [HELD, crate::hostile_round19d::DRIFT, "its block looks moved by ("] {
            assert!(!e.contains(cause), "{robot}: {e}");
        }
    }
}

/// `simulate` of `robot` without validation poses (seed `seed`) as `name` in `dir`.
fn without_poses(dir: &Path, robot: &str, seed: u64, name: &str) -> std::path::PathBuf {
    let mut cmd = crate::common::axiscal();
    cmd.current_dir(dir).args([
        "simulate",
        "-q",
        "--validation-poses",
        "0",
        "--seed",
        &seed.to_string(),
        "--out",
        name,
    ]);
    if robot != "asea-irb6l" {
        cmd.args(["--sim", "analytic", "--robot", &crate::hostile_round15s::robot(robot)]);
    }
    cmd.assert().success();
    dir.join(name)
}

/// The held-reach note's words for `experiment`'s `cmd_{joint}`: `Some(None)` at any size,
/// `Some(Some(deg))` below about `deg`, `None` when the note does not name it.
fn held_reach(stderr: &str, experiment: &str, joint: usize) -> Option<Option<f64>> {
    let note = stderr
        .lines()
        .find(|l| l.starts_with("note:") && l.contains("held joint's recorded command off"))?;
    let list = note.split(" here (").nth(1)?.split("), and the file").next()?;
    let part = list
        .split("; ")
        .find(|p| p.starts_with(&format!("experiment {experiment}'s ")) && p.contains(&format!("`cmd_{joint}`")))?;
    if part.ends_with("at any size") {
        return Some(None);
    }
    Some(part.split("below about ").nth(1)?.trim_end_matches(" deg").parse().ok())
}

#[test]
fn without_validation_poses_the_note_names_the_sweeps_a_held_offset_passes_in() {
    // The hostile run's silent cases: the positioner's axis2 (its `cmd_1` held by that sweep
    // only) and the table's axis3 (`cmd_2` turns its arc about the joint's own axis).
    for (robot, experiment, joint) in [("positioner-2axis", "axis2", 1), ("table-prpp", "axis3", 2)] {
        let dir = tempfile::tempdir().unwrap();
        let clean = without_poses(dir.path(), robot, 9, "clean.csv");
        let e = calibrated(dir.path(), robot, &clean);
        // At any size, or from beyond the 1-deg claim.
        let passes = match held_reach(&e, experiment, joint) {
            Some(None) => true,
            Some(Some(deg)) => deg > 1.0,
            None => false,
        };
        assert!(passes, "{robot}: {e}");
        // A second path: twice the size the note gives (1 deg, the claim, where it names none)
        // is named by the reference-pose test (the table's axis4 with `cmd_2` off).
        if robot == "table-prpp" {
            let deg = match held_reach(&e, "axis4", 2) {
                Some(Some(deg)) => deg,
                Some(None) => panic!("{robot}: axis4's `cmd_2` at any size: {e}"),
                None => 1.0,
            };
            with_held_offset(dir.path(), &clean, "slip.csv", ("axis4", 2, 2.0 * deg));
            let e = calibrated(dir.path(), robot, &dir.path().join("slip.csv"));
            let named = e
                .lines()
                .any(|l| l.starts_with("warning:") && l.contains("axis4") && l.contains("at the reference pose"));
            assert!(named, "{robot}: axis4 `cmd_2` +{} deg: {e}", 2.0 * deg);
        }
    }
}
