//! The fits whose memory grows with the poses (`diagnose`, `calibrate --refine`, the free-pose
//! calibration) take at most `--max-poses` of a file's poses, evenly spaced through it, and
//! say how many they left out (`axiscal::measurement::bounded`). Checked against second
//! paths: the poses the diagnosis keeps against the whole file's list taken by hand, and a
//! refinement bounded inside a file against the same refinement of a file holding only the
//! kept poses.

use crate::common;

use crate::common::{axiscal, stdout};
use axiscal::calibration::procedure::{CalibrationOptions, calibrate};
use axiscal::calibration::refine::RefineOptions;
use axiscal::calibration::refit_model::refine::refine_calibration;
use axiscal::calibration::refit_model::{validation_poses, validation_poses_at_most};
use axiscal::measurement::{Measurement, MeasurementSet};
use axiscal::robot::RobotDescription;
use std::collections::BTreeSet;

/// The `(experiment, step)` of the validation poses `floor(i n / max)`, `i < max`, of `set`
/// (`n` of them in file order), by hand.
fn every_other_by_hand(set: &MeasurementSet, max: usize) -> BTreeSet<usize> {
    let steps: Vec<usize> = set
        .rows()
        .iter()
        .filter(|m| m.experiment == "validation")
        .map(|m| m.step)
        .fold(Vec::new(), |mut v, s| {
            if v.last() != Some(&s) {
                v.push(s);
            }
            v
        });
    (0..max).map(|i| steps[i * steps.len() / max]).collect()
}

/// The diagnosis's bounded poses are the evenly spaced ones, each with the approach
/// directions it has in the whole file's list (the command history of every pose before it,
/// not of the kept ones only); none left out when the bound is not reached.
#[test]
fn the_diagnosed_poses_are_evenly_spaced_with_their_approach_from_the_whole_file() {
    let desc = RobotDescription::asea_irb6l();
    let set = common::jitter_free_campaign(0.19, 41, 5);
    let all = validation_poses(set.rows(), &desc);
    assert_eq!(all.len(), 41);
    let (kept, left_out) = validation_poses_at_most(set.rows(), &desc, 13);
    assert_eq!((kept.len(), left_out), (13, 28));
    let by_hand = every_other_by_hand(&set, 13);
    let expected: Vec<_> = all.iter().filter(|p| by_hand.contains(&p.step)).cloned().collect();
    assert_eq!(
        kept, expected,
        "the kept poses, approaches included, are the whole list's"
    );
    let moved = kept
        .iter()
        .zip(&expected)
        .filter(|(k, _)| k.approach.iter().any(|a| *a != 0.0))
        .count();
    assert!(moved > 0, "the approaches compared are not all zero");
    assert_eq!(validation_poses_at_most(set.rows(), &desc, 41), (all, 0));
}

/// `--refine` bounded to 20 of a file's 50 free poses gives, bit for bit, the refinement of a
/// file holding only those 20 (the robot carries no approach-dependent effect, so nothing of
/// the left-out poses may enter), and counts the 30 it left out.
#[test]
fn a_bounded_refinement_is_the_refinement_of_the_kept_poses() {
    let desc = RobotDescription::asea_irb6l();
    let set = common::jitter_free_campaign(0.19, 50, 9);
    let options = CalibrationOptions {
        noise_rms_3d_mm: 0.19,
        ..CalibrationOptions::default()
    };
    let cal = calibrate(&set, &desc, &options).expect("calibrates");
    let bounded = RefineOptions {
        noise_rms_3d_mm: 0.19,
        max_poses: 20,
        ..RefineOptions::default()
    };
    let refined = refine_calibration(&set, &desc, &cal, &bounded).expect("refines");
    let kept = every_other_by_hand(&set, 20);
    let rows: Vec<Measurement> = set
        .rows()
        .iter()
        .filter(|m| m.experiment != "validation" || kept.contains(&m.step))
        .cloned()
        .collect();
    let small = MeasurementSet::new(6, rows).expect("a subset of valid rows");
    let unbounded = RefineOptions {
        max_poses: usize::MAX,
        ..bounded
    };
    let reference = refine_calibration(&small, &desc, &cal, &unbounded).expect("refines");
    let ((refined, a), (reference, b)) = (refined, reference);
    assert_eq!((a.poses, a.poses_left_out, b.poses_left_out), (20, 30, 0));
    assert_eq!(
        serde_json::to_string(&refined.robot).expect("JSON"),
        serde_json::to_string(&reference.robot).expect("JSON"),
        "the refined robots"
    );
    assert_eq!(
        serde_json::to_string(&a.changes).expect("JSON"),
        serde_json::to_string(&b.changes).expect("JSON")
    );
}

/// The commands say what they left out: `diagnose` on the console, in `diagnosis.json` and in
/// `diagnosis.md`; `calibrate --refine` and a free-pose `calibrate` on the console and in
/// `calibration.json`.
#[test]
fn the_commands_say_how_many_poses_they_left_out() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    common::simulate_analytic(dir.path(), 24, 3, "campaign.csv");
    let run = |args: &[&str]| {
        let a = axiscal().current_dir(dir.path()).args(args).assert().success();
        stdout(&a)
    };
    let out = run(&[
        "diagnose",
        "campaign.csv",
        "--max-poses",
        "10",
        "--noise-trials",
        "2",
        "--noise-draws",
        "2",
        "--out",
        "diag",
    ]);
    assert!(out.contains("diagnosed 10 of the file's 24 validation poses"), "{out}");
    let d: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("diag/diagnosis.json")).expect("written"))
            .expect("JSON");
    assert_eq!(
        d["poses"]["training"].as_u64().unwrap() + d["poses"]["held_out"].as_u64().unwrap(),
        10
    );
    assert_eq!(d["poses"]["left_out"], 14);
    let md = std::fs::read_to_string(dir.path().join("diag/diagnosis.md")).expect("written");
    assert!(
        md.contains("14 more validation poses of the file were left out"),
        "{md}"
    );
    // Noise-only draws beyond what is held in memory are refused before any replica, with
    // their count (10 poses x 3 targets x 3 coordinates = 90 residuals, at most).
    let a = axiscal()
        .current_dir(dir.path())
        .args([
            "diagnose",
            "campaign.csv",
            "--max-poses",
            "10",
            "--noise-trials",
            "100000",
        ])
        .args(["--noise-draws", "10000", "--out", "diag-big"])
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr).into_owned();
    assert!(
        err.contains("--noise-trials 100000 x --noise-draws 10000") && err.contains("at most 33554432 values"),
        "{err}"
    );

    let out = run(&[
        "calibrate",
        "campaign.csv",
        "--refine",
        "--max-poses",
        "12",
        "--out",
        "refined",
    ]);
    assert!(out.contains("refined on 12 of the file's 24 free poses"), "{out}");
    let r = common::read_record(&dir.path().join("refined"))
        .reports
        .refinement
        .expect("a refinement");
    assert_eq!((r.poses, r.poses_left_out), (12, 12));

    // The free poses alone: a free-pose calibration.
    let text = std::fs::read_to_string(dir.path().join("campaign.csv")).expect("written");
    let free: String = text
        .lines()
        .filter(|l| l.starts_with('#') || l.starts_with("experiment,") || l.starts_with("validation,"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(dir.path().join("free.csv"), free).expect("written");
    // --keep-outliers: 16 poses against the model's 51 parameters leave the outlier fence
    // itself noisy; the count of poses left out is what this test reads.
    let out = run(&[
        "calibrate",
        "free.csv",
        "--max-poses",
        "16",
        "--keep-outliers",
        "--out",
        "free",
    ]);
    assert!(out.contains("of the file's 24 free poses, evenly spaced"), "{out}");
    let summary = common::read_record(&dir.path().join("free"))
        .reports
        .free_poses
        .expect("a free-pose summary");
    assert_eq!(summary.poses_left_out, 8);
    assert!(summary.poses <= 16);
}

/// A file that repeats a cycle of 12 poses 4 times, bounded to 12: every pose of the cycle
/// once (evenly spaced, a stride of 4, kept 3 of them, 4 times each), in the diagnosis's
/// selection and the free-pose calibration's alike; each kept pose is the first visit of its
/// configuration, counted here over the commands by hand.
#[test]
fn a_repeated_cycle_of_poses_is_kept_whole_before_any_repeat() {
    let desc = RobotDescription::asea_irb6l();
    let set = common::jitter_free_campaign(0.19, 12, 9);
    let cycle: Vec<Measurement> = set
        .rows()
        .iter()
        .filter(|m| m.experiment == "validation")
        .cloned()
        .collect();
    let mut rows: Vec<Measurement> = set.rows().to_vec();
    for round in 1..4 {
        rows.extend(cycle.iter().map(|m| Measurement {
            step: m.step + 12 * round,
            ..m.clone()
        }));
    }
    let repeated = MeasurementSet::new(6, rows).expect("a set");
    let distinct = |cmds: Vec<Vec<f64>>| {
        let mut seen: Vec<Vec<f64>> = Vec::new();
        for c in cmds {
            if !seen.contains(&c) {
                seen.push(c);
            }
        }
        seen.len()
    };
    let (kept, left_out) = validation_poses_at_most(repeated.rows(), &desc, 12);
    assert_eq!((kept.len(), left_out), (12, 36));
    assert!(
        kept.iter().all(|p| p.step < 12),
        "{:?}",
        kept.iter().map(|p| p.step).collect::<Vec<_>>()
    );
    let free =
        axiscal::calibration::free_pose::FreePoses::from_set_at_most(&repeated, &desc, false, 12).expect("poses");
    assert_eq!(distinct(free.poses.iter().map(|p| p.cmd_file.clone()).collect()), 12);
    assert!(free.poses.iter().all(|p| p.step < 12));
}
