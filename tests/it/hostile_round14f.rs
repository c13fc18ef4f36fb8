//! Helper h14f (hostile run 13, issue #33): `validate` and `diagnose` verdicts that were false
//! or missing, and messages that did not name the file, line, field or option at fault.
//!
//! Kept here, with what now happens:
//! - Part A defect 2 (FA): a clean SCARA file validated against the calibration of another clean
//!   file of the same robot was refused as "`cmd_3` ... offset by -1.474 mm" although its miss
//!   was within the calibration's predicted error. A slip is now said only when one of its
//!   rewrites moves its block's points beyond the predicted error (noise, repeatability and the
//!   calibration's own) at the false-alarm rate; a real offset beyond it is still named.
//! - Part A defect 6 (SW): `diagnose` of an arm6-dh file whose validation rows carry `cmd_2`
//!   +0.3 deg read `none` with no warning; it now warns, as `calibrate` does, that the
//!   validation poses are missed beyond the prediction.
//! - Part A defect 9 (U): the paper campaign with `cmd_4` negated named `cmd_5`, no line, and a
//!   151.6 deg miss "at step 0"; the error now names `cmd_4` (negated), the columns the bevel
//!   gear's hold-still formula reads, the sweep's lines and the fix.
//! - Part B U2-U8: merge of a shard with a trial missing or twice names the shard folder and the
//!   trials file's lines; a UTF-16 trials.csv gets the documented UTF-16 message; a 1e308 in a
//!   Boby-Klimchik file or a points export names the input's line and field;
//!   a plan's `reference` outside the limits names the key; `plan --span` too long names the
//!   option; a description with one theodolite station is named with its key.

use crate::common::{altered_csv, axiscal, stderr, stdout};
use std::path::{Path, PathBuf};

/// The shipped robot description `name`.
fn robot(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios/robots")
        .join(format!("{name}.toml"))
}

/// `simulate` (the default rapier arm) of the SCARA with its shipped true robot, seed `seed`,
/// as `out` in `dir`: the hostile run's clean SCARA files.
fn scara(dir: &Path, seed: u64, out: &str) -> PathBuf {
    axiscal()
        .current_dir(dir)
        .args(["simulate", "-q", "--robot"])
        .arg(robot("scara-rrpr"))
        .arg("--truth")
        .arg(robot("scara-rrpr-truth"))
        .args(["--seed", &seed.to_string(), "--out", out])
        .assert()
        .success();
    dir.join(out)
}

/// `calibrate` of `data` on `robot` into `out` (in `dir`).
fn calibrate(dir: &Path, robot_path: &Path, data: &str, out: &str) {
    axiscal()
        .current_dir(dir)
        .args(["calibrate", "-q", data, "--robot"])
        .arg(robot_path)
        .args(["--out", out])
        .assert()
        .success();
}

/// `validate` of `data` against `cal/calibration.json` on the SCARA: exit code and all output.
fn validate_scara(dir: &Path, data: &str, out: &str) -> (i32, String) {
    let o = axiscal()
        .current_dir(dir)
        .args(["validate", data, "--robot"])
        .arg(robot("scara-rrpr"))
        .args(["--calibration", "cal/calibration.json", "--out", out])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    (o.status.code().unwrap_or(-1), text)
}

/// Defect 2: the clean second SCARA file validates (exit 0) without a slip said; the same file
/// with `cmd_3` 8 mm more on its validation rows (beyond the 1.9 mm the calibration predicts)
/// is still refused naming `cmd_3`.
#[test]
fn a_clean_scara_file_is_not_refused_and_a_real_offset_still_is() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    scara(d, 1, "a.csv");
    let b = scara(d, 2, "b.csv");
    calibrate(d, &robot("scara-rrpr"), "a.csv", "cal");
    let (code, text) = validate_scara(d, "b.csv", "v-clean");
    assert_eq!(code, 0, "{text}");
    assert!(!text.contains("slip") && !text.contains("offset by"), "{text}");
    // The injected effect: cmd_3 (field 9) + 8 mm on the validation rows only.
    altered_csv(
        &b,
        "slipped.csv",
        |_| true,
        |f| {
            if f[0] == "validation" {
                f[9] = (f[9].parse::<f64>().unwrap() + 8.0).to_string();
            }
        },
    );
    let (code, text) = validate_scara(d, "slipped.csv", "v-slipped");
    assert_eq!(code, 2, "{text}");
    assert!(text.contains("slipped.csv:") && text.contains("`cmd_3`"), "{text}");
    // The offset said is the injected 8 mm less the calibration's own height error (about
    // 1.4 mm, within its prediction): beyond the 1.9 mm predicted.
    let said = crate::common::number_after(&text, "is offset by ");
    assert!((5.0..=8.5).contains(&said), "{said}: {text}");
}

/// Defect 6: `diagnose` of an arm6-dh file whose validation rows' `cmd_2` is 0.3 deg off warns
/// that the validation poses are missed beyond the prediction (was: `none`, no warning); the
/// clean file gets no such warning.
#[test]
fn diagnose_warns_of_validation_poses_missed_beyond_the_prediction() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    crate::hostile_round9b::simulated(d, "arm6-dh", 1, 60, "clean.csv");
    altered_csv(
        &d.join("clean.csv"),
        "slipped.csv",
        |_| true,
        |f| {
            if f[0] == "validation" {
                f[8] = (f[8].parse::<f64>().unwrap() + 0.3).to_string();
            }
        },
    );
    let diagnose = |data: &str, out: &str| {
        axiscal()
            .current_dir(d)
            .args(["diagnose", data, "--robot"])
            .arg(robot("arm6-dh"))
            .args(["--out", out])
            .output()
            .unwrap()
    };
    let o = diagnose("slipped.csv", "d-slipped");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.code() == Some(0) || o.status.code() == Some(2), "{err}");
    assert!(
        err.contains("warning: ") && err.contains("slipped.csv") && err.contains("validation poses"),
        "{err}"
    );
    assert!(err.contains("predicted"), "{err}");
    let o = diagnose("clean.csv", "d-clean");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(!err.contains("validation poses (not fitted)"), "{err}");
}

/// Defect 9: the paper campaign with `cmd_4` negated names `cmd_4`, the formula's columns, the
/// sweep's lines and the fix.
#[test]
fn a_negated_bevel_gear_column_is_named_with_its_lines() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    axiscal()
        .current_dir(d)
        .args(["simulate", "-q", "--sim", "analytic", "--out", "paper.csv"])
        .assert()
        .success();
    altered_csv(
        &d.join("paper.csv"),
        "neg.csv",
        |_| true,
        |f| {
            let v: f64 = f[10].parse().unwrap();
            f[10] = (-v).to_string();
        },
    );
    let a = axiscal()
        .current_dir(d)
        .args(["calibrate", "neg.csv", "--out", "cal"])
        .assert()
        .code(2);
    let err = stderr(&a);
    assert!(err.contains("neg.csv") && err.contains("column cmd_4"), "{err}");
    assert!(err.contains("negated") && err.contains("cmd_4 and cmd_5"), "{err}");
    assert!(err.contains("lines "), "{err}");
}

/// Two shards of `ci-smoke` (2 trials each side) in `dir`: `s1`, `s2`.
fn shards(dir: &Path) {
    for k in 1..=2 {
        axiscal()
            .current_dir(dir)
            .args([
                "run",
                "scenarios/ci-smoke.toml",
                "--trials",
                "4",
                "--threads",
                "1",
                "--shard",
            ])
            .arg(format!("{k}/2"))
            .arg("--out")
            .arg(format!("s{k}"))
            .assert()
            .code(0);
    }
}

/// U2/U3: merge with a trial missing, a trial twice, a UTF-16 trials file: each names the shard
/// folder and file, with lines where a row is at fault.
#[test]
fn merge_names_the_shard_and_line_of_a_missing_or_repeated_trial() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    std::fs::create_dir_all(d.join("scenarios")).unwrap();
    std::fs::copy(root.join("scenarios/ci-smoke.toml"), d.join("scenarios/ci-smoke.toml")).unwrap();
    shards(d);
    let trials = d.join("s2/trials.csv");
    let text = std::fs::read_to_string(&trials).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let merge = |out: &str| {
        axiscal()
            .current_dir(d)
            .args(["merge", "s1", "s2", "--out", out])
            .assert()
            .code(2)
    };
    // The last row dropped.
    std::fs::write(&trials, lines[..lines.len() - 1].join("\n") + "\n").unwrap();
    let err = stderr(&merge("o1"));
    assert!(err.contains("missing") && err.contains("s2"), "{err}");
    assert!(err.contains("shard 2 of 2"), "{err}");
    // The last row twice.
    std::fs::write(&trials, text.clone() + lines[lines.len() - 1] + "\n").unwrap();
    let err = stderr(&merge("o2"));
    assert!(err.contains("more than once"), "{err}");
    let last = lines.len();
    assert!(
        err.contains(&format!("trials.csv:{last}")) && err.contains(&format!("trials.csv:{}", last + 1)),
        "{err}"
    );
    // UTF-16.
    let utf16: Vec<u8> = [0xFF, 0xFE]
        .into_iter()
        .chain(text.encode_utf16().flat_map(u16::to_le_bytes))
        .collect();
    std::fs::write(&trials, utf16).unwrap();
    let err = stderr(&merge("o3"));
    assert!(
        err.contains("trials.csv") && err.contains("UTF-16") && err.contains("save it as UTF-8"),
        "{err}"
    );
}

/// U4: a Boby-Klimchik file with 1e308 in field 1 of line 5 names that line and field.
#[test]
fn boby_klimchik_out_of_range_names_the_input_line_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("bk")).unwrap();
    let line = |i: usize| {
        let mut v = vec!["100.0".to_string(); 21];
        if i == 4 {
            v[0] = "1e308".into();
        }
        v.join(" ")
    };
    let text: Vec<String> = (0..36).map(line).collect();
    std::fs::write(d.join("bk/N1N2N3Jval.csv"), text.join("\n") + "\n").unwrap();
    let a = axiscal()
        .current_dir(d)
        .args(["import", "boby-klimchik", "bk", "--out", "b.csv"])
        .assert()
        .code(2);
    let err = stderr(&a);
    assert!(err.contains("N1N2N3Jval.csv:5: field 1 (SMR 1 x_mm)"), "{err}");
    assert!(err.contains("outside"), "{err}");
    assert!(!err.contains("row "), "{err}");
}

/// U5: a points export with `y` = 1e308 on line 7 names line 7 and column `y` (its range check);
/// a one-cell slip of 500 mm in `z` on line 5 still names line 5 (the plan-distance check).
#[test]
fn import_points_names_the_coordinate_column_at_fault() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    axiscal()
        .current_dir(d)
        .args(["plan", "--out", "plan.csv"])
        .assert()
        .success();
    let plan = std::fs::read_to_string(d.join("plan.csv")).unwrap();
    let mut rows = plan.lines().filter(|l| !l.starts_with('#'));
    let head: Vec<&str> = rows.next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let (id, x, y, z) = (
        col("point"),
        col("nominal_x_mm"),
        col("nominal_y_mm"),
        col("nominal_z_mm"),
    );
    let points: Vec<Vec<String>> = rows
        .take(20)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            vec![f[id].into(), f[x].into(), f[y].into(), f[z].into()]
        })
        .collect();
    let export = |name: &str, line: usize, column: usize, value: &dyn Fn(&str) -> String| {
        let mut out = String::from("id,x,y,z\n");
        for (i, p) in points.iter().enumerate() {
            let mut p = p.clone();
            if i + 2 == line {
                p[column] = value(&p[column]);
            }
            out.push_str(&(p.join(",") + "\n"));
        }
        std::fs::write(d.join(name), out).unwrap();
    };
    export("big.csv", 7, 2, &|_| "1e308".into());
    export("slip.csv", 5, 3, &|v| (v.parse::<f64>().unwrap() + 500.0).to_string());
    let import = |name: &str| {
        let a = axiscal()
            .current_dir(d)
            .args([
                "import",
                "points",
                "plan.csv",
                name,
                "--allow-missing",
                "--out",
                "d.csv",
                "--force",
            ])
            .assert()
            .code(2);
        stderr(&a)
    };
    let err = import("big.csv");
    assert!(
        err.contains("big.csv") && err.contains("line 7, column y") && err.contains("outside"),
        "{err}"
    );
    let err = import("slip.csv");
    assert!(err.contains("slip.csv") && err.contains("line 5"), "{err}");
}

/// U6/U7: a plan's `reference` outside the limits names the key; `plan --span 1=1000` names
/// the option.
#[test]
fn plan_limits_name_the_key_or_option() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let plan = std::fs::read_to_string(robot("asea-irb6l-table1-plan")).unwrap();
    let at = plan.find("reference = [").unwrap() + "reference = [".len();
    let end = at + plan[at..].find([',', ']']).unwrap();
    let edited = format!("{}500.0{}", &plan[..at], &plan[end..]);
    std::fs::write(d.join("pl.toml"), edited).unwrap();
    let a = axiscal()
        .current_dir(d)
        .args(["simulate", "--plan", "pl.toml", "--out", "s.csv"])
        .assert()
        .code(2);
    let err = stderr(&a);
    assert!(
        err.contains("pl.toml") && err.contains("`reference`") && err.contains("joint 1"),
        "{err}"
    );
    assert!(!err.contains("sweep 0"), "{err}");
    let a = axiscal()
        .current_dir(d)
        .args(["plan", "--out", "p.csv", "--span", "1=1000"])
        .assert()
        .code(2);
    let err = stderr(&a);
    assert!(err.contains("--span 1=1000") && err.contains("limits"), "{err}");
}

/// U8: a description with one theodolite station names the description file and its key.
#[test]
fn one_station_names_the_description_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let text = std::fs::read_to_string(robot("asea-irb6l")).unwrap();
    let start = text.find("stations_mm").unwrap();
    let end = start + text[start..].find("\n").unwrap();
    let edited = format!("{}stations_mm = [[0.0, 0.0, 0.0]]{}", &text[..start], &text[end..]);
    std::fs::write(d.join("r.toml"), edited).unwrap();
    let a = axiscal()
        .current_dir(d)
        .args(["simulate", "--robot", "r.toml", "--out", "s.csv"])
        .assert()
        .code(2);
    let err = stderr(&a);
    assert!(
        err.contains("r.toml") && err.contains("instrument.stations_mm"),
        "{err}"
    );
    let _ = stdout(&a);
}
