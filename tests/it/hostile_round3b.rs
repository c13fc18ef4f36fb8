//! Hostile inputs of the third round to the importers, `plan`, `iso9283`, `export`, `merge`,
//! `blind` and `view`, as a table: each case is a command line on files made wrong in a known
//! way (rows sorted by step, a row in radians, a header where none belongs, another robot's
//! kinematics, an option given twice), with the exit code it must give and what its message
//! must name. A bad input is one error line naming the file, the line and the field, exit 2,
//! and nothing written.

use crate::common::{altered_csv, axiscal, simulate_analytic};
use std::path::Path;
use std::time::Duration;

/// One hostile try: the arguments (run in the case folder), the exit code, what stderr must
/// hold, and what must not have been written.
struct Case {
    what: &'static str,
    args: Vec<String>,
    code: i32,
    names: &'static [&'static str],
    written: &'static [&'static str],
}

fn case(what: &'static str, args: &str, names: &'static [&'static str], written: &'static [&'static str]) -> Case {
    Case {
        what,
        args: args.split_whitespace().map(str::to_owned).collect(),
        code: 2,
        names,
        written,
    }
}

fn shipped(relative: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(relative)
        .display()
        .to_string()
}

/// SScanSS-2 rows of a six-joint arm, three points a joint, every joint at home 0:
/// `by_step` lists them step by step (joint 6, 5, .., 1, then again), else joint by joint.
fn sscanss2_rows(by_step: bool) -> String {
    let row = |joint: usize, step: usize| {
        let (j, s) = (joint as f64, step as f64);
        format!(
            "{joint},{},{},{},{},revolute,0\n",
            100.0 * j + s,
            10.0 * s,
            j,
            5.0 * s - 5.0
        )
    };
    let mut text = String::new();
    if by_step {
        for step in 0..3 {
            for joint in (1..=6).rev() {
                text += &row(joint, step);
            }
        }
    } else {
        for joint in (1..=6).rev() {
            for step in 0..3 {
                text += &row(joint, step);
            }
        }
    }
    text
}

/// A wide table sweeping joint 3 from -22.5 deg in 3 deg steps, joints 1 and 2 held at 10 and
/// 20 deg, one marker; the fourth pose (line 5) written in radians.
fn wide_with_a_row_in_radians() -> String {
    let mut text = String::from("q1,q2,q3,q4,q5,q6,m1_x,m1_y,m1_z\n");
    for step in 0..12 {
        let s = f64::from(step);
        let mut q = [10.0, 20.0, -22.5 + 3.0 * s, 0.0, 0.0, 0.0];
        if step == 3 {
            q = q.map(f64::to_radians);
        }
        let cells: Vec<String> = q.iter().map(|v| v.to_string()).collect();
        text += &format!("{},{},{},{}\n", cells.join(","), 1000.0 + s, 20.0 * s, 300.0);
    }
    text
}

/// Writes every input of the table into `dir`.
fn write_inputs(dir: &Path) {
    simulate_analytic(dir, 40, 5, "good.csv");
    let run = |args: &[&str]| {
        axiscal()
            .current_dir(dir)
            .args(args)
            .timeout(Duration::from_secs(300))
            .assert()
            .success();
    };
    run(&["calibrate", "good.csv", "--out", "cal"]);
    run(&["plan", "--no-sight", "--validation-poses", "0", "--out", "plan.csv"]);
    run(&["run", "ci-smoke", "--trials", "2", "--shard", "1/2", "--out", "sh12"]);
    // The same shard as if split three ways.
    std::fs::create_dir(dir.join("sh13")).unwrap();
    for name in ["scenario.resolved.toml", "trials.csv"] {
        std::fs::copy(dir.join("sh12").join(name), dir.join("sh13").join(name)).unwrap();
    }
    std::fs::write(dir.join("sh13/shard.txt"), "1/3\nunits 0..1\n").unwrap();
    let iso = crate::iso9283::simulated_iso_csv(dir, 2, 7);
    altered_csv(
        &iso,
        "iso-moved.csv",
        |_| true,
        |f| {
            if f[0].starts_with("iso-P") {
                f[1] = "1".into();
            }
        },
    );
    let files: [(&str, String); 7] = [
        ("ss-by-step.txt", sscanss2_rows(true)),
        (
            "ss-header.txt",
            format!("joint,x,y,z,value,type,home\n{}", sscanss2_rows(false)),
        ),
        ("wide-rad-row.csv", wide_with_a_row_in_radians()),
        (
            "sa-no-header.txt",
            "G 1 -3108.48 5269.52 13.80\nG 2 -3112.39 5267.63 13.87\n".into(),
        ),
        (
            "sa-commas.txt",
            "// SA export\nG 1 -3108,48 5269,52 13,80\nG 2 -3112,39 5267,63 13,87\n".into(),
        ),
        ("rct-list.yaml", "observations: []\n".into()),
        ("not-rrd.csv", std::fs::read_to_string(dir.join("good.csv")).unwrap()),
    ];
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
}

fn cases() -> Vec<Case> {
    let positioner = shipped("scenarios/robots/positioner-2axis.toml");
    let ur5e = shipped("tests/data/ur5e-default-kinematics.yaml");
    vec![
        case(
            "S6: a UR5e kinematics.yaml as --like of the paper robot's calibration",
            &format!(
                "export ur-kinematics --calibration cal/calibration.json --like {ur5e} --approximate --out k.yaml"
            ),
            &[
                "--like",
                "ur5e-default-kinematics.yaml",
                "mrad from the robot description's",
                "another robot's kinematics",
            ],
            &["k.yaml"],
        ),
        case(
            "S14: SScanSS-2 rows sorted by step",
            "import sscanss2 ss-by-step.txt --robot asea-irb6l --out x.csv",
            &[
                "ss-by-step.txt: line 1, column joint",
                "stands alone (line 2 is joint 5",
                "18 of the file's 18 runs",
                "sort the rows by joint",
            ],
            &["x.csv"],
        ),
        case(
            "S15: one wide row in radians among degrees",
            "import wide wide-rad-row.csv --robot asea-irb6l --angles deg --units mm --out x.csv",
            &[
                "wide-rad-row.csv: line 5",
                "splits the sweep of joint 3 (lines 4 and 6",
                "radians where degrees are expected",
            ],
            &["x.csv"],
        ),
        case(
            "S17: ISO cycles marked as an axis experiment",
            "iso9283 evaluate iso-moved.csv --out iso-out",
            &[
                "iso-moved.csv",
                "experiment `iso-P1` (line 2): moved_joint 1",
                "moved_joint 0",
            ],
            &["iso-out"],
        ),
        case(
            "S18: one joint's span given twice",
            "plan --span 2=30 --span 2=40 --out p.csv",
            &["--span 2=40", "joint 2 given twice (also --span 2=30)"],
            &["p.csv"],
        ),
        case(
            "S24: a CSV given to view",
            "view not-rrd.csv",
            &["not-rrd.csv", "not a rerun recording (.rrd"],
            &[],
        ),
        case(
            "U4: too few points for the seed plan's fits",
            "plan --optimize --points 40 --max-rounds 2 --out o.csv",
            &["--points 40 is too few", "joint 2", "raise --points to"],
            &["o.csv", "o.toml"],
        ),
        case(
            "U10: three --station options",
            "simulate --sim analytic --station 0,0,0 --station -6284.6,0,0 --station 100,100,100 --out s.csv",
            &["--station given 3 times", "need two stations"],
            &["s.csv"],
        ),
        case(
            "U11: --poses 4 with free poses only",
            "blind --campaign free-poses --poses 4 --cases 1 --out bl",
            &["--poses 4", "--campaign free-poses", "at least"],
            &["bl"],
        ),
        case(
            "U12: shards of two splits",
            "merge sh12 sh13 --out m",
            &["sh12 is shard 1 of 2, sh13 is shard 1 of 3", "different splits"],
            &["m"],
        ),
        case(
            "U13: a SpatialAnalyzer export without its // line",
            "import points plan.csv sa-no-header.txt --out x.csv",
            &["sa-no-header.txt: line 1", "--format spatialanalyzer"],
            &["x.csv"],
        ),
        case(
            "U13: a SpatialAnalyzer export with decimal commas",
            "import points plan.csv sa-commas.txt --out x.csv",
            &["sa-commas.txt", "line 2: decimal commas (`-3108,48`)", "decimal point"],
            &["x.csv"],
        ),
        case(
            "U14: a SScanSS-2 file with a header",
            "import sscanss2 ss-header.txt --robot asea-irb6l --out x.csv",
            &["ss-header.txt", "line 1 is a header", "remove the line"],
            &["x.csv"],
        ),
        case(
            "U15: robot_cal_tools observations listed under one key",
            &format!("import rct rct-list.yaml --robot {positioner} --out x.csv"),
            &[
                "rct-list.yaml",
                "entry `observations` is an empty list",
                "map of observations",
            ],
            &["x.csv"],
        ),
        case(
            "U18: an ISO cube for a two-joint positioner",
            &format!("iso9283 plan --robot {positioner} --out cube.csv"),
            &["an ISO 9283 cube needs", "Two-axis positioner has 2"],
            &["cube.csv"],
        ),
    ]
}

#[test]
fn each_hostile_input_of_round_3b_is_one_clear_error_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path());
    let mut failed = Vec::new();
    for c in cases() {
        let out = axiscal()
            .current_dir(dir.path())
            .env("AXISCAL_RERUN", dir.path().join("no-viewer"))
            .args(&c.args)
            .timeout(Duration::from_secs(120))
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&out.stderr).into_owned();
        let mut wrong: Vec<String> = c
            .names
            .iter()
            .filter(|name| !e.contains(*name))
            .map(|name| format!("no {name:?}"))
            .collect();
        if out.status.code() != Some(c.code) {
            wrong.push(format!("exit {:?}, not {}", out.status.code(), c.code));
        }
        if e.lines().count() != 1 {
            wrong.push(format!("{} lines", e.lines().count()));
        }
        wrong.extend(
            c.written
                .iter()
                .filter(|name| dir.path().join(name).exists())
                .map(|name| format!("{name} written")),
        );
        if !wrong.is_empty() {
            failed.push(format!("{}: {}: {e}", c.what, wrong.join("; ")));
        }
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}
