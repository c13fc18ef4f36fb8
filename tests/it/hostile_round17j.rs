//! Hostile run 16, defect 6 (FA): a clean UR5e file whose held joints wander 0.01-0.1 deg a
//! step (a plan's `held_jitter`) was refused as "the points are not on one arc or line of this
//! joint": the first pass fits the points as measured, and on the UR5e's wrist (joint 4's
//! target 18 mm from its centroid) the wander of joints 1-3 at a metre's lever misses one arc
//! by 6.7 % of the spread, beyond the gate's 5 %. The first pass's fit of a campaign not at its
//! design pose now only starts the held joints' correction when its gate refuses it, and the
//! corrected points face the gate; data the correction does not bring onto one arc keep the
//! first refusal. Jittered clean UR5e, six-axis and seven-axis files calibrate without a
//! warning and predict their own validation poses; a sweep's commands shuffled on a jittered
//! file are still refused with the words of that cause, and a held command offset through one
//! sweep of a jittered file (a refusal before) is named.
//!
//! Defect 10 (U): a held-command slip, a bump or an outlier in one of a joint's several short
//! sweeps was said only as the joint's misfit over all its sweeps; the misfit now names the
//! sweep (the one without which the joint's other sweeps fit) with its lines, and the row of a
//! one-point outlier. Defect 11 (U): `validate` named a held command recorded 1 deg off through
//! one sweep as two columns swapped; the held offset is now tried first and named.

use crate::common::{altered_csv, altered_experiment, axiscal, stderr};
use std::path::{Path, PathBuf};

/// The shipped description `name` under `scenarios/robots/`.
fn robot(name: &str) -> String {
    format!("{}/scenarios/robots/{name}.toml", env!("CARGO_MANIFEST_DIR"))
}

/// A plan sweeping each of `dof` joints once (joints 2 and 3 over 45 deg, the others over 60)
/// from the zero pose, the held joints wandering 0.01-0.1 deg a step, written in `dir`.
fn jitter_plan(dir: &Path, dof: usize) -> PathBuf {
    let mut text = format!(
        "reference = [{}]\nheld_jitter = [0.01, 0.1]\n",
        vec!["0.0"; dof].join(", ")
    );
    for joint in (1..=dof).rev() {
        let span = if joint == 2 || joint == 3 { 45.0 } else { 60.0 };
        text.push_str(&format!(
            "\n[[sweeps]]\njoint = {joint}\nspan = {span:.1}\nintervals = 15\n"
        ));
    }
    let path = dir.join(format!("jitter{dof}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// `simulate --sim analytic` of `name` with the jitter plan of `dof` joints and `seed`, 40
/// validation poses: `name_seed.csv` in `dir`.
fn jittered(dir: &Path, name: &str, dof: usize, seed: u64) -> PathBuf {
    let plan = jitter_plan(dir, dof);
    let out = dir.join(format!("{name}_{seed}.csv"));
    axiscal()
        .args(["simulate", "-q", "--sim", "analytic", "--robot", &robot(name)])
        .arg("--plan")
        .arg(&plan)
        .args(["--validation-poses", "40", "--seed", &seed.to_string(), "--out"])
        .arg(&out)
        .arg("--force")
        .assert()
        .success();
    out
}

/// `calibrate FILE --robot ROBOT --out DIR/out_NAME`: exit code and stderr.
fn calibrate(dir: &Path, file: &Path, name: &str) -> (i32, String) {
    let out = dir.join(format!("out_{}", file.file_stem().unwrap().to_string_lossy()));
    let a = axiscal()
        .arg("calibrate")
        .arg(file)
        .args(["--robot", &robot(name), "--out"])
        .arg(&out)
        .arg("--force")
        .assert();
    let code = a.get_output().status.code().unwrap_or(-1);
    (code, stderr(&a))
}

/// `validate` of the calibration of `file` on `file` itself (its validation poses, not
/// fitted): the validation line's RMS and predicted RMS \[mm\].
fn own_validation(dir: &Path, file: &Path, name: &str) -> (f64, f64) {
    let stem = file.file_stem().unwrap().to_string_lossy().into_owned();
    let a = axiscal()
        .arg("validate")
        .args(["--robot", &robot(name), "--calibration"])
        .arg(dir.join(format!("out_{stem}/calibration.json")))
        .arg(file)
        .arg("--out")
        .arg(dir.join(format!("v_{stem}")))
        .arg("--force")
        .assert()
        .success();
    let text = crate::common::stdout(&a) + &stderr(&a);
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with("validation "))
        .unwrap_or_else(|| panic!("no validation line: {text}"));
    (
        crate::common::number_after(line, "RMS "),
        crate::common::number_after(line, "predicted "),
    )
}

/// The lines of `stderr` that warn or refuse.
fn alarms(stderr: &str) -> Vec<&str> {
    stderr
        .lines()
        .filter(|l| l.starts_with("warning") || l.starts_with("error"))
        .collect()
}

/// Clean jittered files of the UR5e (seeds 31, 32: not the hostile run's 211, 212 that showed
/// the refusal), the six-axis arm and the seven-axis arm calibrate without a warning, and the
/// calibration misses the file's own validation poses by no more than twice its predicted RMS
/// (the chi-square of such files is this plan's, jitter or not: the tool frame is nominal).
#[test]
fn clean_jittered_files_calibrate_quietly() {
    let dir = tempfile::tempdir().unwrap();
    for (name, dof, seed) in [
        ("ur5e-dh", 6, 31),
        ("ur5e-dh", 6, 32),
        ("arm6-dh", 6, 33),
        ("arm7-dh", 7, 34),
    ] {
        let file = jittered(dir.path(), name, dof, seed);
        let (code, e) = calibrate(dir.path(), &file, name);
        assert_eq!(code, 0, "{name} seed {seed}: {e}");
        assert!(alarms(&e).is_empty(), "{name} seed {seed}: a false alarm: {e}");
        let (rms, predicted) = own_validation(dir.path(), &file, name);
        assert!(
            rms < 2.0 * predicted,
            "{name} seed {seed}: {rms} mm against {predicted} mm"
        );
    }
}

/// The jittered UR5e file with one sweep's swept command shuffled among its rows (points on
/// one arc in another order than their commands) is refused as before, with that cause: the
/// correction does not bring such points onto one arc.
#[test]
fn a_shuffled_sweep_of_a_jittered_file_is_still_refused() {
    let dir = tempfile::tempdir().unwrap();
    let clean = jittered(dir.path(), "ur5e-dh", 6, 35);
    // cmd_3 (field 9) of axis3's rows, each step's value taken from step (7 step + 5) mod 16.
    let text = std::fs::read_to_string(&clean).unwrap();
    let values: Vec<String> = text
        .lines()
        .filter(|l| l.starts_with("axis3,"))
        .map(|l| l.split(',').nth(9).unwrap().to_string())
        .collect();
    assert_eq!(values.len(), 16);
    let file = altered_csv(
        &clean,
        "shuffled.csv",
        |_| true,
        |f| {
            if f[0] == "axis3" {
                let step: usize = f[2].parse().unwrap();
                f[9] = values[(7 * step + 5) % 16].clone();
            }
        },
    );
    let (code, e) = calibrate(dir.path(), &file, "ur5e-dh");
    assert_eq!(code, 2, "{e}");
    assert!(
        e.contains("experiment axis3 (joint 3)") && e.contains("in another order than their commands"),
        "{e}"
    );
}

/// `cmd_2` recorded 1 deg off through axis4 of a jittered UR5e file (hostile run 16's
/// `held-ur5e-jitter-s211-cmd_2-1-axis4`, refused as "not on one arc" before): the held
/// offset is named with its experiment and lines.
#[test]
fn a_held_offset_in_a_jittered_file_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let clean = jittered(dir.path(), "ur5e-dh", 6, 36);
    let file = altered_csv(
        &clean,
        "held.csv",
        |_| true,
        |f| {
            if f[0] == "axis4" {
                f[8] = (f[8].parse::<f64>().unwrap() + 1.0).to_string();
            }
        },
    );
    let (code, e) = calibrate(dir.path(), &file, "ur5e-dh");
    assert_eq!(code, 0, "{e}");
    assert!(
        e.lines()
            .any(|l| l.contains("experiment axis4 (lines") && l.contains("the held `cmd_2` looks offset by +")),
        "{e}"
    );
}

/// A plan sweeping each of the six-axis arm's joints three times over 4 intervals: at the zero
/// pose, with joint 1 at 20 deg, and with joint 1 at -20 deg and joint 2 at 10 deg (hostile
/// run 16's `arm6-manyfew`), written in `dir`.
fn manyfew_plan(dir: &Path) -> PathBuf {
    three_pose_plan(
        dir,
        "manyfew.toml",
        |joint| if joint == 2 || joint == 3 { 45.0 } else { 60.0 },
    )
}

/// A plan sweeping each of the six-axis arm's joints over `span(joint)` degrees in 4 intervals
/// three times: at the zero pose, with joint 1 at 20 deg, and with joint 1 at -20 deg and
/// joint 2 at 10 deg; written as `name` in `dir`.
pub fn three_pose_plan(dir: &Path, name: &str, span: impl Fn(usize) -> f64) -> PathBuf {
    three_pose_plan_of(dir, name, 6, span)
}

/// [`three_pose_plan`] for a robot of `joints` joints.
pub fn three_pose_plan_of(dir: &Path, name: &str, joints: usize, span: impl Fn(usize) -> f64) -> PathBuf {
    let zeros = |from: usize| vec!["0"; joints - from].join(", ");
    let mut text = format!("reference = [{}]\n", vec!["0.0"; joints].join(", "));
    for joint in (1..=joints).rev() {
        for held in [
            String::new(),
            format!("held_at = [20.0, {}]\n", zeros(1)),
            format!("held_at = [-20.0, 10.0, {}]\n", zeros(2)),
        ] {
            text.push_str(&format!(
                "\n[[sweeps]]\njoint = {joint}\nspan = {:.1}\nintervals = 4\n{held}",
                span(joint)
            ));
        }
    }
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// The many-few campaign of robot `name` and `seed` (analytic, 20 validation poses) in `dir`.
fn manyfew(dir: &Path, name: &str, seed: u64) -> PathBuf {
    let plan = manyfew_plan(dir);
    simulated_with_plan(dir, name, &plan, seed, &format!("manyfew_{name}_{seed}.csv"))
}

/// `simulate --sim analytic` of robot `name` with `plan` and `seed` (20 validation poses) as
/// `file` in `dir`.
pub fn simulated_with_plan(dir: &Path, name: &str, plan: &Path, seed: u64, file: &str) -> PathBuf {
    simulated_with(dir, (name, plan), seed, 20, file)
}

/// `simulate --sim analytic` of robot `name` with `plan`, `seed` and `validation_poses` as
/// `file` in `dir`: one truth per seed, whatever the plan and the validation poses.
pub fn simulated_with(
    dir: &Path,
    (name, plan): (&str, &Path),
    seed: u64,
    validation_poses: usize,
    file: &str,
) -> PathBuf {
    let out = dir.join(file);
    axiscal()
        .args(["simulate", "-q", "--sim", "analytic", "--robot", &robot(name)])
        .arg("--plan")
        .arg(plan)
        .args([
            "--validation-poses",
            &validation_poses.to_string(),
            "--seed",
            &seed.to_string(),
            "--out",
        ])
        .arg(&out)
        .arg("--force")
        .assert()
        .success();
    out
}

/// The first and last file line (1-based, the header on line 2) of `experiment` in `file`.
fn lines_of(file: &Path, experiment: &str) -> (usize, usize) {
    let text = std::fs::read_to_string(file).unwrap();
    let lines: Vec<usize> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| l.starts_with(&format!("{experiment},")))
        .map(|(i, _)| i + 1)
        .collect();
    (lines[0], *lines.last().unwrap())
}

/// Hostile run 16, defect 10: on a campaign sweeping each joint three times at other poses, a
/// held `cmd_1` recorded 1 deg off through axis3-2, a 2 mm bump of `y_mm` in it from its step 2
/// on, and a 4 mm outlier in one point of axis2-2 were said only as the joint's misfit over all
/// its sweeps. The misfit now names the sweep that carries it with its lines (the joint fitted
/// without it passes), and the outlier's row where one point carries it; the clean file says
/// nothing.
#[test]
fn a_slip_in_one_of_several_sweeps_is_named_with_its_lines() {
    let dir = tempfile::tempdir().unwrap();
    let clean = manyfew(dir.path(), "arm6-dh", 41);
    let (code, e) = calibrate(dir.path(), &clean, "arm6-dh");
    assert_eq!(code, 0, "{e}");
    assert!(alarms(&e).is_empty(), "a false alarm: {e}");
    let change =
        |name: &str, experiment: &str, edit: fn(&mut Vec<String>)| altered_experiment(&clean, name, experiment, edit);
    let held = change("held.csv", "axis3-2", |f| {
        f[7] = (f[7].parse::<f64>().unwrap() + 1.0).to_string()
    });
    let bumped = change("bumped.csv", "axis3-2", |f| {
        if f[2].parse::<usize>().unwrap() >= 2 {
            f[5] = (f[5].parse::<f64>().unwrap() + 2.0).to_string()
        }
    });
    let outlier = change("outlier.csv", "axis2-2", |f| {
        if f[2] == "2" && f[3] == "0" {
            f[4] = (f[4].parse::<f64>().unwrap() + 4.0).to_string()
        }
    });
    for (file, joint, experiment) in [(held, 3, "axis3-2"), (bumped, 3, "axis3-2"), (outlier, 2, "axis2-2")] {
        let (a, b) = lines_of(&clean, experiment);
        let (code, e) = calibrate(dir.path(), &file, "arm6-dh");
        assert_eq!(code, 0, "{e}");
        let sweep = format!("the misfit is experiment {experiment}'s (lines {a}-{b})");
        let said = e
            .lines()
            .find(|l| l.starts_with(&format!("warning: joint {joint} (")) && l.contains(&sweep))
            .unwrap_or_else(|| panic!("{}: {e}", file.display()));
        if said.contains("one point") {
            // Only the outlier is one point: line of axis2-2's step 2 (target 0).
            let text = std::fs::read_to_string(&clean).unwrap();
            let line = 1 + text.lines().position(|l| l.starts_with("axis2-2,2,2,0,")).unwrap();
            assert!(said.contains(&format!("one point: line {line}, step 2")), "{said}");
        }
    }
}

/// The same plan on the UR5e (seed 41, as above): a held `cmd_1` recorded 1 deg off through
/// axis3-2 makes the correction for the held joints' recorded values diverge, and the
/// calibration fails (the sweeps cannot be free poses either); the error used to name joint 3's
/// three sweeps together. It now names axis3-2 with its lines: without it the procedure passes,
/// without either other sweep of joint 3 it fails.
#[test]
fn a_sweep_that_fails_the_calibration_is_named_with_its_lines() {
    let dir = tempfile::tempdir().unwrap();
    let clean = manyfew(dir.path(), "ur5e-dh", 41);
    let (code, e) = calibrate(dir.path(), &clean, "ur5e-dh");
    assert_eq!(code, 0, "{e}");
    assert!(alarms(&e).is_empty(), "a false alarm: {e}");
    let held = altered_experiment(&clean, "held.csv", "axis3-2", |f| {
        f[7] = (f[7].parse::<f64>().unwrap() + 1.0).to_string()
    });
    let (code, e) = calibrate(dir.path(), &held, "ur5e-dh");
    assert_eq!(code, 2, "{e}");
    let (a, b) = lines_of(&clean, "axis3-2");
    let named = format!("the failure is experiment axis3-2's (lines {a}-{b}): without it the calibration passes");
    assert!(e.lines().any(|l| l.starts_with("error:") && l.contains(&named)), "{e}");
}

/// `simulate --sim analytic` of the six-axis arm's shipped truth with `seed` (30 validation
/// poses): `arm6_seed.csv` in `dir`.
fn arm6_of_truth(dir: &Path, seed: u64) -> PathBuf {
    let out = dir.join(format!("arm6_{seed}.csv"));
    axiscal()
        .args(["simulate", "-q", "--sim", "analytic", "--robot", &robot("arm6-dh")])
        .args(["--truth", &robot("arm6-dh-truth"), "--validation-poses", "30"])
        .args(["--seed", &seed.to_string(), "--out"])
        .arg(&out)
        .arg("--force")
        .assert()
        .success();
    out
}

/// Hostile run 16, defect 11: `validate` of a second file whose `cmd_1` is recorded 1 deg off
/// through axis3 named `cmd_1` and `cmd_6` swapped (`cmd_6` is 0 there, and joint 6 barely
/// moves the target). The held offset now competes with the column slips and, explaining the
/// rows better, is named; the swap is not.
#[test]
fn validate_names_a_held_offset_not_a_swap() {
    let dir = tempfile::tempdir().unwrap();
    let first = arm6_of_truth(dir.path(), 51);
    let (code, e) = calibrate(dir.path(), &first, "arm6-dh");
    assert_eq!(code, 0, "{e}");
    let second = altered_csv(
        &arm6_of_truth(dir.path(), 52),
        "held.csv",
        |_| true,
        |f| {
            if f[0] == "axis3" {
                f[7] = (f[7].parse::<f64>().unwrap() + 1.0).to_string();
            }
        },
    );
    let a = axiscal()
        .arg("validate")
        .args(["--robot", &robot("arm6-dh"), "--calibration"])
        .arg(dir.path().join("out_arm6_51/calibration.json"))
        .arg(&second)
        .arg("--out")
        .arg(dir.path().join("v_held"))
        .arg("--force")
        .assert();
    let e = stderr(&a);
    assert!(e.contains("the held `cmd_1` is recorded +1.000 deg off"), "{e}");
    assert!(!e.contains("swapped"), "{e}");
}
