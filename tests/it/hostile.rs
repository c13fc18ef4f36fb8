//! Hostile inputs across the commands, as a table: each case is a command line on files a
//! careless or hostile user writes (another separator, another unit, a device, a pipe, a nest
//! of YAML aliases, columns that would be written twice, several instrument setups, a failed
//! stdout) with the exit code it must give and what its message must name. A bad input is one
//! error line naming the file and the field, exit 2; nothing is written.

use crate::common::{altered_csv, axiscal, scale_fields, simulate_analytic};
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::Duration;

/// One hostile try: the arguments (run in the case folder), the exit code, and what stderr
/// must hold.
struct Case {
    what: &'static str,
    args: Vec<String>,
    code: i32,
    names: &'static [&'static str],
}

fn case(what: &'static str, args: &str, code: i32, names: &'static [&'static str]) -> Case {
    Case {
        what,
        args: args.split_whitespace().map(str::to_owned).collect(),
        code,
        names,
    }
}

fn shipped(relative: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(relative)
        .display()
        .to_string()
}

/// `levels` levels of ten YAML aliases each to the level below (10^levels leaves).
fn alias_nest(levels: usize) -> String {
    let mut text = String::from("a0: &a0 [lol]\n");
    for k in 1..=levels {
        text.push_str(&format!(
            "a{k}: &a{k} [{}]\n",
            vec![format!("*a{}", k - 1); 10].join(", ")
        ));
    }
    text
}

/// Writes every input of the table into `dir`.
fn write_inputs(dir: &Path) {
    simulate_analytic(dir, 40, 7, "campaign.csv");
    axiscal()
        .current_dir(dir)
        .args(["calibrate", "campaign.csv", "--out", "cal"])
        .assert()
        .success();
    let campaign = dir.join("campaign.csv");
    let validation = |f: &[String]| f[0] == "validation";
    altered_csv(&campaign, "free-m.csv", validation, |f| scale_fields(f, 4..7, 1e-3));
    altered_csv(&campaign, "x2.csv", |_| true, |f| scale_fields(f, 4..7, 2.0));
    // The axis experiments from setup A, the validation poses from setup B.
    let setups = altered_csv(
        &campaign,
        "setups.csv",
        |_| true,
        |f| {
            let setup = if f[0] == "validation" { "B" } else { "A" };
            f.push(setup.into());
        },
    );
    let text = std::fs::read_to_string(&setups).unwrap();
    let header = text.lines().find(|l| l.starts_with("experiment,")).unwrap();
    std::fs::write(&setups, text.replacen(header, &format!("{header},setup"), 1)).unwrap();
    let files: [(&str, String); 6] = [
        (
            "poses-semicolon.csv",
            "id;x_mm;y_mm;z_mm;roll_deg;pitch_deg;yaw_deg\np1;1200;0;900;0;0;0\n".into(),
        ),
        (
            "poses-m.csv",
            "id,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg\np1,1.2,0.1,0.9,0,0,0\np2,1.1,0.2,0.8,0,0,0\n".into(),
        ),
        (
            "with-q.csv",
            "cmd_1,cmd_2,cmd_3,cmd_4,cmd_5,cmd_6,q_1\n0,0,0,0,0,0,0\n".into(),
        ),
        ("nest.yaml", alias_nest(9)),
        (
            "wide7.csv",
            "q1,q2,q3,q4,q5,q6,q7,m1_x,m1_y,m1_z\n0,0,0,0,0,0,0,1,2,3\n0,0,0,0,0,0,5,1,2,4\n".into(),
        ),
        (
            "huge.toml",
            std::fs::read_to_string(shipped("scenarios/ci-smoke.toml"))
                .unwrap()
                .replace("poses = 12", "poses = 100000000"),
        ),
    ];
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
    let made = std::process::Command::new("mkfifo").arg(dir.join("fifo.csv")).status();
    assert!(made.is_ok_and(|s| s.success()), "mkfifo");
}

fn cases() -> Vec<Case> {
    let cal = "--calibration cal/calibration.json";
    let positioner = shipped("scenarios/robots/positioner-2axis.toml");
    vec![
        case(
            "a device as poses",
            &format!("compensate {cal} --poses /dev/zero --out out.csv"),
            2,
            &["/dev/zero", "not a regular file"],
        ),
        case(
            "a pipe as poses",
            &format!("compensate {cal} --poses fifo.csv --out out.csv"),
            2,
            &["fifo.csv", "not a regular file"],
        ),
        case(
            "a pipe as joints' CSV",
            &format!("joints {cal} --csv fifo.csv"),
            2,
            &["fifo.csv", "not a regular file"],
        ),
        case(
            "poses separated by semicolons",
            &format!("compensate {cal} --poses poses-semicolon.csv --out out.csv"),
            2,
            &["poses-semicolon.csv", "line 1", "separated by `;`"],
        ),
        case(
            "poses in metres",
            &format!("compensate {cal} --poses poses-m.csv --out out.csv"),
            2,
            &["poses-m.csv", "x_mm,y_mm,z_mm", "--skip-unit-check"],
        ),
        case(
            "q columns already in the joints' CSV",
            &format!("joints {cal} --csv with-q.csv"),
            2,
            &["with-q.csv", "column `q_1`"],
        ),
        case(
            "free poses in metres",
            "calibrate free-m.csv --out out",
            2,
            &["free-m.csv", "metres", "--skip-unit-check"],
        ),
        case(
            "coordinates doubled",
            "validate --calibration cal/calibration.json x2.csv --out out",
            0,
            &["warning: x2.csv", "free poses' measured tool positions spread"],
        ),
        case(
            "two setups given to validate",
            "validate --calibration cal/calibration.json setups.csv --out out",
            2,
            &["setups.csv:", "column `setup`", "2 setups"],
        ),
        case(
            "two setups with axis experiments",
            "calibrate setups.csv --out out",
            2,
            &["setups.csv:", "column `setup`"],
        ),
        case(
            "a seventh joint's column",
            "import wide wide7.csv --angles deg --units mm --out out.csv",
            2,
            &["wide7.csv", "column `q7`", "--robot"],
        ),
        case(
            "a nest of YAML aliases",
            &format!("import rct nest.yaml --robot {positioner} --out out.csv"),
            2,
            &["nest.yaml", "aliases"],
        ),
        case(
            "validation poses beyond the cap",
            "run huge.toml --trials 1 --out out",
            2,
            &["huge.toml", "validation.poses"],
        ),
        case(
            "--json on a shard",
            "run ci-smoke --shard 1/2 --json --out out",
            2,
            &["--json", "--shard"],
        ),
    ]
}

#[test]
fn every_hostile_input_is_one_clear_error_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path());
    for c in cases() {
        let a = axiscal()
            .current_dir(dir.path())
            .args(&c.args)
            .timeout(Duration::from_secs(120))
            .assert()
            .code(c.code);
        let e = crate::common::stderr(&a);
        for name in c.names {
            assert!(e.contains(name), "{}: no {name:?} in {e}", c.what);
        }
        if c.what == "coordinates doubled" {
            // The simulated robot differs from its description by millimetres over metres.
            let ratio = crate::common::number_after(&e, "positions spread ");
            assert!((ratio / 2.0 - 1.0).abs() < 0.02, "{}: {ratio} in {e}", c.what);
            // The warning is in the summary a script reads, too.
            let summary = std::fs::read_to_string(dir.path().join("out/summary.json")).unwrap();
            let json: serde_json::Value = serde_json::from_str(&summary).unwrap();
            let warnings = json["warnings"].as_array().expect("a warnings list");
            let printed = e.lines().find(|l| l.contains("positions spread")).unwrap();
            assert_eq!(warnings.len(), 1, "{summary}");
            assert_eq!(Some(printed.trim_start_matches("warning: ")), warnings[0].as_str());
        }
        if c.code == 2 {
            assert_eq!(e.lines().count(), 1, "{}: one line: {e}", c.what);
            let written: Vec<PathBuf> = ["out", "out.csv"].iter().map(|n| dir.path().join(n)).collect();
            assert!(written.iter().all(|p| !p.exists()), "{}: nothing written", c.what);
        }
        let _ = std::fs::remove_dir_all(dir.path().join("out"));
    }
}

/// `--help`, `--version` and a completion script into a full device: exit 2 and one line,
/// not 0 (the text lost) or a panic's 101.
#[test]
fn a_full_stdout_is_exit_2() {
    for args in [&["--help"][..], &["--version"], &["completions", "bash"]] {
        let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_axiscal"))
            .args(args)
            .stdout(Stdio::from(full))
            .stderr(Stdio::piped())
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {e}");
        assert!(e.contains("No space left"), "{args:?}: {e}");
    }
}

/// A diagnosis of axis experiments only draws no candidates: an earlier run's candidates
/// plots do not stay beside it (a mixed folder), and are not removed without `--force`.
#[test]
fn a_diagnosis_replaces_an_earlier_ones_plots_as_a_set() {
    let dir = tempfile::tempdir().unwrap();
    simulate_analytic(dir.path(), 40, 3, "campaign.csv");
    let campaign = dir.path().join("campaign.csv");
    altered_csv(&campaign, "axes.csv", |f| f[0] != "validation", |_| {});
    let diagnose = |data: &str, force: bool| {
        let mut cmd = axiscal();
        cmd.current_dir(dir.path()).args(["diagnose", data, "--out", "d"]);
        if force {
            cmd.arg("--force");
        }
        cmd.assert()
    };
    diagnose("campaign.csv", false).success();
    assert!(dir.path().join("d/candidates.png").exists());
    diagnose("axes.csv", false).code(2);
    diagnose("axes.csv", true).success();
    let left: Vec<&str> = ["candidates.png", "candidates.svg"]
        .into_iter()
        .filter(|n| dir.path().join("d").join(n).exists())
        .collect();
    assert!(
        left.is_empty(),
        "an earlier run's {left:?} left beside the new diagnosis"
    );
    assert!(dir.path().join("d/where.png").exists());
}
