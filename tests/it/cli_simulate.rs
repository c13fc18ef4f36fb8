//! `axiscal simulate` end to end: the CSV it writes is accepted by the reader with Table 1's
//! point counts; bad input is one clear error with exit code 2.

use crate::common;

use crate::common::axiscal;
use axiscal::measurement::read_measurements;

#[test]
fn simulate_writes_a_table1_campaign_the_reader_accepts() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("campaign.csv");
    axiscal()
        .args(["simulate", "--sim", "analytic", "--seed", "3", "--out"])
        .arg(&out)
        .assert()
        .success();
    let set = read_measurements(&out, Some(6)).unwrap();
    let expect = [
        ("axis6", 17, 1),
        ("axis5", 16, 1),
        ("axis4", 16, 2),
        ("axis3", 16, 1),
        ("axis2", 16, 2),
        ("axis1", 16, 1),
    ];
    let experiments = set.experiments();
    for (e, (name, poses, targets)) in experiments.iter().zip(expect) {
        assert_eq!(e.name, name);
        assert_eq!(e.by_step().len(), poses, "{name}");
        assert_eq!(e.rows.len(), poses * targets, "{name}");
    }
    let tool = &experiments[6];
    assert_eq!(
        (tool.name, tool.moved_joint, tool.by_step().len(), tool.rows.len()),
        ("tool", 0, 1, 3)
    );
    let validation = &experiments[7];
    assert_eq!(
        (
            validation.moved_joint,
            validation.by_step().len(),
            validation.rows.len()
        ),
        (0, 60, 180)
    );

    // Same seed, same file, bit for bit; refuses to overwrite without --force.
    let again = dir.path().join("again.csv");
    axiscal()
        .args(["simulate", "--sim", "analytic", "--seed", "3", "--out"])
        .arg(&again)
        .assert()
        .success();
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&again).unwrap());
    let a = axiscal()
        .args(["simulate", "--seed", "3", "--out"])
        .arg(&out)
        .assert()
        .code(2);
    let stderr = String::from_utf8_lossy(&a.get_output().stderr).to_string();
    assert!(
        stderr.contains("--force") && stderr.contains("campaign.csv"),
        "{stderr}"
    );
}

#[test]
fn bad_robot_file_is_exit_code_2_naming_file_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let robot = dir.path().join("robot.toml");
    let text = include_str!("../../scenarios/robots/asea-irb6l.toml").replacen("mass_kg = 22.0", "mass_kg = -3.0", 1);
    std::fs::write(&robot, text).unwrap();
    let a = axiscal()
        .args(["simulate", "--robot"])
        .arg(&robot)
        .arg("--out")
        .arg(dir.path().join("x.csv"))
        .assert()
        .code(2);
    let stderr = String::from_utf8_lossy(&a.get_output().stderr).to_string();
    assert!(
        stderr.contains("robot.toml") && stderr.contains("joints[1].mass_kg"),
        "{stderr}"
    );
    assert_eq!(stderr.lines().filter(|l| l.starts_with("error")).count(), 1, "{stderr}");
}

/// The rapier arm (the default) hides targets behind the link capsules: the CLI reports the
/// occlusion counts and, with `--report-spans`, one largest-visible-span line per experiment.
#[test]
fn simulate_on_rapier_reports_occlusions_and_spans() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("campaign.csv");
    let assert = axiscal()
        .args(["simulate", "--report-spans", "--seed", "3", "--out"])
        .arg(&out)
        .assert()
        .success();
    let stdout = String::from_utf8_lossy(&assert.get_output().stdout).to_string();
    assert!(stdout.contains("occluded target observations:"), "{stdout}");
    assert_eq!(stdout.matches("span axis").count(), 6, "{stdout}");
}

/// A six-axis arm without couplings (the shipped DH arm) simulates with the default plan: the
/// paper's Table 1 measures couplings 2->3 and 4->5 with second targets, which this arm does
/// not have, so the default is the plan drawn from its own limits (every joint swept once,
/// one target each).
#[test]
fn a_six_axis_arm_without_couplings_simulates_with_the_default_plan() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("campaign.csv");
    axiscal()
        .args([
            "simulate",
            "--quiet",
            "--robot",
            "arm6-dh",
            "--truth",
            "arm6-dh-truth",
            "--sim",
            "analytic",
            "--out",
        ])
        .arg(&out)
        .assert()
        .success();
    let set = read_measurements(&out, Some(6)).unwrap();
    for joint in 1..=6 {
        let targets: std::collections::BTreeSet<usize> = set
            .rows()
            .iter()
            .filter(|m| m.moved_joint == joint)
            .map(|m| m.target)
            .collect();
        assert_eq!(targets, [0].into(), "joint {joint}");
    }
}

/// A robot's own description serves as its truth (its nominal model, said on the console), and a
/// truth given where a description belongs is an error that says what it is (both failed on an
/// unknown field before).
#[test]
fn descriptions_and_truths_are_told_apart() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("campaign.csv");
    let ran = axiscal()
        .args([
            "simulate", "--robot", "arm6-dh", "--truth", "arm6-dh", "--sim", "analytic", "--out",
        ])
        .arg(&out)
        .assert()
        .success();
    assert!(String::from_utf8_lossy(&ran.get_output().stdout).contains("nominal model"));
    let refused = axiscal()
        .args(["calibrate", "--robot", "positioner-2axis-truth", "--out"])
        .arg(dir.path().join("cal"))
        .arg(&out)
        .assert()
        .code(2);
    let message = common::stderr(&refused);
    assert!(
        message.contains("truth model") && message.contains("--truth"),
        "{message}"
    );
}

/// `describe --truth-template` writes a description's nominal model as a truth model file that
/// `simulate --truth` reads: the campaign simulated on it is the one simulated with the
/// description itself as the truth, byte for byte (a SCARA and a DH arm).
#[test]
fn a_truth_template_simulates_as_the_description_does() {
    let dir = tempfile::tempdir().unwrap();
    for robot in ["scara-rrpr", "arm6-dh"] {
        let template = axiscal()
            .args(["describe", robot, "--truth-template"])
            .assert()
            .success();
        let truth = dir.path().join(format!("{robot}-truth.toml"));
        std::fs::write(&truth, &template.get_output().stdout).unwrap();
        let simulate = |truth: &std::ffi::OsStr, out: &str| {
            axiscal()
                .args([
                    "simulate", "--robot", robot, "--sim", "analytic", "--seed", "4", "--truth",
                ])
                .arg(truth)
                .arg("--out")
                .arg(dir.path().join(out))
                .assert()
                .success();
            std::fs::read(dir.path().join(out)).unwrap()
        };
        let from_template = simulate(truth.as_os_str(), &format!("{robot}-a.csv"));
        let from_description = simulate(std::ffi::OsStr::new(robot), &format!("{robot}-b.csv"));
        assert!(from_template == from_description, "{robot}: the two campaigns differ");
    }
}

/// The stations: given on the command line they replace the description's (the IRB/L6's own,
/// given again, change nothing, byte for byte); a count the instrument cannot use, or stations
/// for isotropic noise, is one error with exit 2; a description's one `[instrument]` station
/// serves `plan` (one line-of-sight column) and is refused by the theodolites.
#[test]
fn stations_come_from_the_description_or_the_command_line() {
    let fails_with = |a: assert_cmd::assert::Assert, text: &str| {
        let a = a.code(2);
        let stderr = String::from_utf8_lossy(&a.get_output().stderr).to_string();
        assert!(stderr.contains(text), "{stderr}");
    };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let simulate = |extra: &[&str], out: &str| {
        let mut cmd = axiscal();
        cmd.args(["simulate", "--sim", "analytic", "--validation-poses", "3"])
            .args(extra)
            .arg("--out")
            .arg(d.join(out));
        cmd
    };
    simulate(&[], "default.csv").assert().success();
    simulate(&["--station=0,0,0", "--station=-6284.6,0,0"], "given.csv")
        .assert()
        .success();
    assert_eq!(
        std::fs::read(d.join("default.csv")).unwrap(),
        std::fs::read(d.join("given.csv")).unwrap()
    );
    simulate(&["--station=100,0,0", "--station=-6000,-50,0"], "moved.csv")
        .assert()
        .success();
    assert_ne!(
        std::fs::read(d.join("default.csv")).unwrap(),
        std::fs::read(d.join("moved.csv")).unwrap()
    );
    fails_with(simulate(&["--station=0,0,0"], "one.csv").assert(), "need two stations");
    fails_with(
        simulate(
            &["--instrument", "isotropic", "--station=0,0,0", "--station=1,0,0"],
            "iso.csv",
        )
        .assert(),
        "isotropic noise has no stations",
    );
    let robot = d.join("tracker.toml");
    let text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/robots/scara-rrpr.toml")).unwrap();
    std::fs::write(
        &robot,
        format!("{text}\n[instrument]\nstations_mm = [[4000.0, 0.0, -400.0]]\n"),
    )
    .unwrap();
    axiscal()
        .args(["plan", "--validation-poses", "0", "--robot"])
        .arg(&robot)
        .arg("--out")
        .arg(d.join("plan.csv"))
        .assert()
        .success();
    let plan = std::fs::read_to_string(d.join("plan.csv")).unwrap();
    assert!(plan.contains("visible_1 = station (4000, 0, -400) mm"), "{plan}");
    assert!(!plan.contains("visible_2"));
    fails_with(
        simulate(&[], "unused.csv").arg("--robot").arg(&robot).assert(),
        "need two stations",
    );
}
