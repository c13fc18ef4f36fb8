//! A gross error that a sweep whose held joints wander takes in without its axis fit failing
//! (a controller's encoder log: as measured, the sweep's points lie on no one arc or line, so
//! the sweep screen cannot test them): once the model is fitted, the sweep's points moved to
//! the design pose by it are screened as a still sweep's, and the point's pose is dropped and
//! the file calibrated again. Checked against the second path, the file with those poses'
//! rows deleted by hand, on three robots and four shapes of error: a coordinate on an arc, a
//! coordinate on a sliding joint's line and another sweep's at once, and a held joint's
//! command within the held tolerance.

use crate::common::{self, altered_csv, axiscal};
use std::path::{Path, PathBuf};

/// The SCARA's plan: every joint swept, the held joints wandering by 0.02-0.05 (deg or mm).
const SCARA_PLAN: &str = "reference = [0.0, 30.0, 0.0, 0.0]\nheld_jitter = [0.02, 0.05]\n\
    [[sweeps]]\njoint = 4\nspan = 90.0\nintervals = 15\n[[sweeps]]\njoint = 3\nspan = 120.0\nintervals = 15\n\
    [[sweeps]]\njoint = 2\nspan = 80.0\nintervals = 15\n[[sweeps]]\njoint = 1\nspan = 80.0\nintervals = 15\n";

/// The seven-joint arm's plan: every joint swept, the held joints wandering by 0.01-0.08 deg.
const ARM7_PLAN: &str = "reference = [0.0, 10.0, 0.0, 20.0, 0.0, 10.0, 0.0]\nheld_jitter = [0.01, 0.08]\n\
    [[sweeps]]\njoint = 7\nspan = 60.0\nintervals = 12\n[[sweeps]]\njoint = 6\nspan = 60.0\nintervals = 12\n\
    [[sweeps]]\njoint = 5\nspan = 60.0\nintervals = 12\n[[sweeps]]\njoint = 4\nspan = 50.0\nintervals = 12\n\
    [[sweeps]]\njoint = 3\nspan = 60.0\nintervals = 12\n[[sweeps]]\njoint = 2\nspan = 45.0\nintervals = 12\n\
    [[sweeps]]\njoint = 1\nspan = 50.0\nintervals = 12\n";

/// One gross error: `(experiment, step, column, amount added)`; a coordinate on the target-0
/// row, a command on every row of the pose.
type Error = (&'static str, &'static str, usize, f64);

/// The simulated file of `robot` (with `truth` where given) under `plan`, analytic, isotropic.
fn simulated(dir: &Path, robot: &str, truth: Option<&str>, plan: &str, seed: &str) -> PathBuf {
    let plan_file = dir.join(format!("{robot}-plan.toml"));
    let plan = match plan.starts_with("reference") {
        true => {
            std::fs::write(&plan_file, plan).unwrap();
            plan_file.display().to_string()
        }
        false => plan.to_string(),
    };
    let out = dir.join(format!("{robot}.csv"));
    let mut sim = axiscal();
    sim.args(["simulate", "--robot", robot, "--plan", &plan, "--sim", "analytic"]);
    if let Some(truth) = truth {
        sim.args(["--truth", truth]);
    }
    sim.args(["--instrument", "isotropic", "--seed", seed, "--out"])
        .arg(&out)
        .assert()
        .success();
    out
}

/// Whether row fields `f` are the target-0 row of `error`'s pose (any target for a command).
fn hit(f: &[String], (experiment, step, column, _): &Error) -> bool {
    f[0] == *experiment && f[2] == *step && (f[3] == "0" || *column >= 7)
}

/// The 1-based line of the target-0 row of `error`'s pose in `file`.
fn line_of(file: &Path, (experiment, step, ..): &Error) -> u64 {
    let text = std::fs::read_to_string(file).unwrap();
    let at = text.lines().position(|l| {
        let f: Vec<&str> = l.split(',').collect();
        f.len() > 3 && f[0] == *experiment && f[2] == *step && f[3] == "0"
    });
    at.unwrap() as u64 + 1
}

/// `clean` with the `errors` added, calibrated: the warnings name each row, the points are the
/// calibration's only outliers, dropped, and the calibration equals that of `clean` without
/// their poses.
fn dropped_as_by_hand(clean: &Path, robot: &str, errors: &[Error], name: &str) {
    let bad = altered_csv(
        clean,
        &format!("{name}-bad.csv"),
        |_| true,
        |f| {
            let hits: Vec<&Error> = errors.iter().filter(|e| hit(f, e)).collect();
            for e in hits {
                f[e.2] = (f[e.2].parse::<f64>().unwrap() + e.3).to_string();
            }
        },
    );
    let pose = |f: &[String]| errors.iter().any(|e| f[0] == e.0 && f[2] == e.1);
    let without = altered_csv(clean, &format!("{name}-without.csv"), |f| !pose(f), |_| {});
    let out = clean.with_file_name(format!("{name}-bad"));
    let run = axiscal()
        .args(["calibrate", "--robot", robot])
        .arg(&bad)
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    let stderr = common::stderr(&run);
    let record = common::read_record(&out);
    let mut lines = Vec::new();
    for error in errors {
        let line = line_of(&bad, error);
        let named = format!(
            "{}:{line}: outlier: experiment {} step {} target 0:",
            bad.display(),
            error.0,
            error.1
        );
        let warned = stderr.lines().any(|l| {
            l.starts_with("warning: ")
                && l.contains(&named)
                && l.contains("moved to the design pose by the calibrated model")
                && l.contains("calibrated again without it")
        });
        assert!(warned, "{name}: {stderr}");
        lines.push(Some(line));
    }
    let moved = axiscal::calibration::procedure::OutlierTest::Moved;
    assert!(record.calibration.outliers.iter().all(|o| o.test == moved), "{name}");
    let mut flagged: Vec<_> = record
        .calibration
        .outliers
        .iter()
        .map(|o| (o.line, o.dropped))
        .collect();
    flagged.sort();
    lines.sort();
    assert_eq!(flagged, lines.iter().map(|l| (*l, true)).collect::<Vec<_>>(), "{name}");
    let out_without = clean.with_file_name(format!("{name}-without"));
    axiscal()
        .args(["calibrate", "--robot", robot])
        .arg(&without)
        .arg("--out")
        .arg(&out_without)
        .assert()
        .success();
    let by_hand = common::read_record(&out_without).calibration;
    assert_eq!(record.calibration.robot, by_hand.robot, "{name}");
    // As written (a sliding axis's position sigma is NaN, which `==` never equals).
    let json = |a: &[axiscal::calibration::procedure::AxisReport]| serde_json::to_string(a).unwrap();
    assert_eq!(json(&record.calibration.axes), json(&by_hand.axes), "{name}");
}

/// The case of the report this test answers (seed 21; -6 mm was a joint-misfit warning only),
/// then with `--keep-outliers`: the point is named, kept, and the file calibrated with it.
#[test]
fn a_coordinate_on_an_arc_of_the_six_axis_arm() {
    let dir = tempfile::tempdir().unwrap();
    let clean = simulated(dir.path(), "arm6-dh", Some("arm6-dh-truth"), "arm6-jitter-plan", "21");
    let error: Error = ("axis3", "9", 5, -6.0);
    dropped_as_by_hand(&clean, "arm6-dh", &[error], "arm6");
    let bad = clean.with_file_name("arm6-bad.csv");
    let out = dir.path().join("kept");
    let kept = axiscal()
        .args(["calibrate", "--robot", "arm6-dh", "--keep-outliers"])
        .arg(&bad)
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    let e = common::stderr(&kept);
    let line = line_of(&bad, &error);
    assert!(
        e.lines()
            .any(|l| l.contains(&format!("{}:{line}: outlier:", bad.display())) && l.contains("kept (--keep-outliers)")),
        "{e}"
    );
    let outliers = common::read_record(&out).calibration.outliers;
    assert_eq!(
        outliers.iter().map(|o| (o.line, o.dropped)).collect::<Vec<_>>(),
        [(Some(line), false)]
    );
}

/// Two at once on the SCARA (seed 31): one on the quill's line (z), one on the elbow's arc (x).
#[test]
fn a_coordinate_on_a_line_and_one_on_an_arc_of_the_scara() {
    let dir = tempfile::tempdir().unwrap();
    let clean = simulated(dir.path(), "scara-rrpr", Some("scara-rrpr-truth"), SCARA_PLAN, "31");
    let errors: [Error; 2] = [("axis3", "7", 6, 4.0), ("axis2", "7", 4, 4.0)];
    dropped_as_by_hand(&clean, "scara-rrpr", &errors, "scara");
}

/// A held joint's command (cmd_2, +0.3 deg within the 0.5 deg held tolerance) on every row of
/// one pose of the seven-joint arm's axis-5 sweep (seed 41).
#[test]
fn a_held_command_of_the_seven_joint_arm() {
    let dir = tempfile::tempdir().unwrap();
    let clean = simulated(dir.path(), "arm7-dh", None, ARM7_PLAN, "41");
    dropped_as_by_hand(&clean, "arm7-dh", &[("axis5", "9", 8, 0.3)], "arm7");
}
