//! The fifth hostile run's imports, options and file kinds: `import mat` and `import
//! sscanss2` in the wrong units (the unit check `import wide` runs), a MAT variable given for two
//! targets, `--noise-mm` in metres, `plan --min-intervals` beyond the budget, a file of another
//! kind given to an option (a scenario, plan or description TOML, a CSV as `urdf.file`), a UR
//! `kinematics.yaml` in mm or degrees, a SCARA with every link length 0 and a file given to
//! `import boby-klimchik` for its folder.

use crate::common::hostile::{Case, case, clear_outputs, run_case};
use crate::common::{axiscal, stderr};
use std::path::Path;

fn shipped(relative: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)).unwrap()
}

/// The rows of a measurement CSV: its header's columns and each row's cells.
fn rows(csv: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<String> = lines.next().unwrap().split(',').map(str::to_owned).collect();
    let rows = lines.map(|l| l.split(',').map(str::to_owned).collect()).collect();
    (header, rows)
}

/// A MAT v5 file of real double matrices (`name`, rows of values).
pub(crate) fn mat_file(vars: &[(&str, Vec<Vec<f64>>)]) -> Vec<u8> {
    let element = |kind: u32, payload: &[u8]| {
        let mut e = Vec::new();
        e.extend(kind.to_le_bytes());
        e.extend((payload.len() as u32).to_le_bytes());
        e.extend(payload);
        e.resize(e.len() + (8 - payload.len() % 8) % 8, 0);
        e
    };
    let mut out = b"MATLAB 5.0 MAT-file, written by hostile_round5c".to_vec();
    out.resize(116, b' ');
    out.extend([0u8; 8]);
    out.extend(0x0100u16.to_le_bytes());
    out.extend(b"IM");
    for (name, m) in vars {
        let (r, c) = (m.len(), m[0].len());
        let data: Vec<u8> = (0..c)
            .flat_map(|j| (0..r).map(move |i| (i, j)))
            .flat_map(|(i, j)| m[i][j].to_le_bytes())
            .collect();
        let mut body = element(6, &[6u32.to_le_bytes(), 0u32.to_le_bytes()].concat());
        body.extend(element(
            5,
            &[(r as i32).to_le_bytes(), (c as i32).to_le_bytes()].concat(),
        ));
        body.extend(element(1, name.as_bytes()));
        body.extend(element(9, &data));
        out.extend(14u32.to_le_bytes());
        out.extend((body.len() as u32).to_le_bytes());
        out.extend(body);
    }
    out
}

/// The validation poses of `campaign.csv` in `dir` as MAT files: `good.mat` (rad, m),
/// `qdeg.mat` (joints in degrees) and `pts_mm.mat` (points in mm), variables `q`, `mA`, `mB`,
/// `mC`.
pub(crate) fn write_mats(dir: &Path) {
    let (h, rows) = rows(&std::fs::read_to_string(dir.join("campaign.csv")).unwrap());
    let col = |name: &str| h.iter().position(|c| c == name).unwrap();
    let val: Vec<&Vec<String>> = rows.iter().filter(|r| r[0] == "validation").collect();
    let of_target = |t: &str| val.iter().filter(|r| r[col("target")] == t).collect::<Vec<_>>();
    let joints = |f: fn(f64) -> f64| -> Vec<Vec<f64>> {
        of_target("0")
            .iter()
            .map(|r| {
                (1..=6)
                    .map(|k| f(r[col(&format!("cmd_{k}"))].parse().unwrap()))
                    .collect()
            })
            .collect()
    };
    let points = |t: &str, scale: f64| -> Vec<Vec<f64>> {
        of_target(t)
            .iter()
            .map(|r| {
                ["x_mm", "y_mm", "z_mm"]
                    .map(|c| r[col(c)].parse::<f64>().unwrap() * scale)
                    .to_vec()
            })
            .collect()
    };
    for (file, q, scale) in [
        ("good.mat", joints(f64::to_radians), 1e-3),
        ("qdeg.mat", joints(|d| d), 1e-3),
        ("pts_mm.mat", joints(f64::to_radians), 1.0),
    ] {
        let vars = [
            ("q", q),
            ("mA", points("0", scale)),
            ("mB", points("1", scale)),
            ("mC", points("2", scale)),
        ];
        std::fs::write(dir.join(file), mat_file(&vars)).unwrap();
    }
}

/// The axis experiments' target 0 of `campaign.csv` in `dir` as SScanSS-2 files: `good.txt`,
/// `m.txt` (points in m) and `rad.txt` (joint values in rad).
fn write_sscanss2(dir: &Path) {
    let (h, rows) = rows(&std::fs::read_to_string(dir.join("campaign.csv")).unwrap());
    let col = |name: &str| h.iter().position(|c| c == name).unwrap();
    let axis: Vec<&Vec<String>> = rows
        .iter()
        .filter(|r| r[0].starts_with("axis") && r[col("target")] == "0")
        .collect();
    let home = |k: usize| -> f64 {
        let held = axis.iter().find(|r| r[col("moved_joint")] != k.to_string()).unwrap();
        held[col(&format!("cmd_{k}"))].parse().unwrap()
    };
    for (file, length, angle) in [
        ("good.txt", 1.0, 1.0),
        ("m.txt", 1e-3, 1.0),
        ("rad.txt", 1.0, 1f64.to_radians()),
    ] {
        let text: String = axis
            .iter()
            .map(|r| {
                let k: usize = r[col("moved_joint")].parse().unwrap();
                let p = |c: &str| r[col(c)].parse::<f64>().unwrap() * length;
                let value: f64 = r[col(&format!("cmd_{k}"))].parse().unwrap();
                format!(
                    "{k},{},{},{},{},revolute,{}\n",
                    p("x_mm"),
                    p("y_mm"),
                    p("z_mm"),
                    value * angle,
                    home(k) * angle
                )
            })
            .collect();
        std::fs::write(dir.join(file), text).unwrap();
    }
}

/// `import mat` and `import sscanss2` run `import wide`'s unit check: the wrong `--angles` or
/// `--units` is refused naming the value that fits, and the right ones import; a MAT
/// variable named for two targets is refused.
#[test]
fn mat_and_sscanss2_imports_check_their_units() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    crate::common::simulate_analytic(d, 40, 5, "campaign.csv");
    write_mats(d);
    write_sscanss2(d);
    let mat = "import mat --robot asea-irb6l --joints q --out out.csv";
    let cases: Vec<Case> = vec![
        case(
            "S8: joints in degrees read as radians",
            &format!("{mat} qdeg.mat --targets mA,mB,mC --angles rad --units m"),
            2,
            &[
                "qdeg.mat: read with --angles rad --units m",
                "outside the description's limits",
                "pass --angles deg",
            ],
        ),
        case(
            "S8: points in mm read as m",
            &format!("{mat} pts_mm.mat --targets mA,mB,mC --angles rad --units m"),
            2,
            &["pts_mm.mat: read with --angles rad --units m", "pass --units mm"],
        ),
        case(
            "S8: a variable given twice",
            &format!("{mat} good.mat --targets mA,mA,mC --angles rad --units m"),
            2,
            &["--targets: variable `mA` is given twice (targets 0 and 1)"],
        ),
        case(
            "S8: SScanSS-2 points in m read as mm",
            "import sscanss2 m.txt --robot asea-irb6l --out out.csv",
            2,
            &["m.txt: read with --angles deg --units mm", "pass --units m"],
        ),
        case(
            "S8: SScanSS-2 joint values in rad",
            "import sscanss2 rad.txt --robot asea-irb6l --out out.csv",
            2,
            &["rad.txt: read with --angles deg --units mm", "pass --angles rad"],
        ),
        case(
            "S8: SScanSS-2 mm read as m",
            "import sscanss2 good.txt --robot asea-irb6l --units m --out out.csv",
            2,
            &["good.txt: read with --angles deg --units m", "pass --units mm"],
        ),
    ];
    for c in &cases {
        run_case(d, c);
        clear_outputs(d);
    }
    for ok in [
        format!("{mat} good.mat --targets mA,mB,mC --angles rad --units m"),
        format!("{mat} qdeg.mat --targets mA,mB,mC --angles deg --units m"),
        format!("{mat} qdeg.mat --targets mA,mB,mC --angles rad --units m --skip-unit-check"),
        "import sscanss2 good.txt --robot asea-irb6l --out out.csv".into(),
        "import sscanss2 rad.txt --robot asea-irb6l --angles rad --out out.csv".into(),
        "import sscanss2 m.txt --robot asea-irb6l --units m --out out.csv".into(),
    ] {
        let a = axiscal().current_dir(d).args(ok.split_whitespace()).assert().success();
        assert_eq!(stderr(&a), "", "{ok}");
        clear_outputs(d);
    }
}

/// A noise in metres is refused by every `--noise-mm` as the scenario's key is;
/// `plan --optimize --min-intervals` beyond what `--points` allows is refused, saying the bound.
#[test]
fn options_out_of_their_range_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let metres = ["0.0002 mm is finer than any instrument", "looks like metres (0.2 mm?)"];
    let cases = [
        case(
            "S9: plan --noise-mm in m",
            "plan --noise-mm 0.0002 --out out.csv",
            2,
            &metres,
        ),
        case(
            "S9: study --noise-mm in m",
            "study --trials 2 --noise-mm 0.0002 --out out",
            2,
            &metres,
        ),
        case(
            "S9: calibrate --noise-mm in m",
            "calibrate campaign.csv --noise-mm 0.0002 --out out",
            2,
            &metres,
        ),
        case(
            "S9: --min-intervals beyond the points",
            "plan --optimize --min-intervals 1000 --out out.csv",
            2,
            &[
                "--min-intervals 1000: 129 axis points",
                "let each keep at most 15 intervals",
                "--points 8008 or more",
            ],
        ),
    ];
    for c in &cases {
        run_case(d, c);
        clear_outputs(d);
    }
}

/// A TOML file of another of axiscal's kinds is named for what it is; a `urdf.file` that is a
/// CSV or a TOML is named so; a file given for boby-klimchik's folder is said to be one.
#[test]
fn files_of_another_kind_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    crate::common::simulate_analytic(d, 0, 3, "campaign.csv");
    std::fs::write(d.join("robot.toml"), shipped("scenarios/robots/asea-irb6l.toml")).unwrap();
    std::fs::write(d.join("scenario.toml"), shipped("scenarios/paper.toml")).unwrap();
    std::fs::write(
        d.join("plan.toml"),
        shipped("scenarios/robots/asea-irb6l-table1-plan.toml"),
    )
    .unwrap();
    let urdf = shipped("scenarios/robots/real/fanuc-r2000ic.toml");
    std::fs::write(
        d.join("urdf-csv.toml"),
        urdf.replace("fanuc-r2000ic.urdf", "campaign.csv"),
    )
    .unwrap();
    std::fs::write(
        d.join("urdf-toml.toml"),
        urdf.replace("fanuc-r2000ic.urdf", "robot.toml"),
    )
    .unwrap();
    let description = "robot-description";
    let cases = [
        case(
            "U5: a description to run",
            "run robot.toml --out out",
            2,
            &[
                "robot.toml: this is a robot description, not a scenario file",
                description,
            ],
        ),
        case(
            "U5: a description as --plan",
            "simulate --plan robot.toml --out out.csv",
            2,
            &["this is a robot description, not a calibration plan"],
        ),
        case(
            "U5: a scenario as --robot",
            "calibrate campaign.csv --robot scenario.toml --out out",
            2,
            &[
                "this is a scenario file, not a robot description",
                "given to `axiscal run`",
            ],
        ),
        case(
            "U5: a plan as --robot",
            "calibrate campaign.csv --robot plan.toml --out out",
            2,
            &[
                "this is a calibration plan, not a robot description",
                "given with --plan",
            ],
        ),
        case(
            "U5: a scenario to describe",
            "describe scenario.toml",
            2,
            &["this is a scenario file, not a robot description"],
        ),
        case(
            "U5: urdf.file a CSV",
            "describe urdf-csv.toml",
            2,
            &["field `urdf.file`", "this is a CSV table, not a URDF"],
        ),
        case(
            "U5: urdf.file a TOML",
            "describe urdf-toml.toml",
            2,
            &[
                "field `urdf.file`",
                "this is a TOML file, a robot description, not a URDF",
            ],
        ),
        case(
            "U8: boby-klimchik given a file",
            "import boby-klimchik campaign.csv --out out.csv",
            2,
            &["campaign.csv is a file; import boby-klimchik takes the data set's folder"],
        ),
    ];
    for c in &cases {
        run_case(d, c);
        clear_outputs(d);
    }
}

/// A UR `kinematics.yaml` with its lengths in mm or its angles in degrees is refused naming
/// the unit; the driver's own file reads.
#[test]
fn a_ur_kinematics_file_in_mm_or_degrees_is_named() {
    use axiscal::calibration::export::ur::UrKinematics;
    let good = shipped("tests/data/ur5e-default-kinematics.yaml");
    assert!(UrKinematics::parse(&good, "good.yaml").is_ok());
    let mm = good.replace("x: -0.425", "x: -425.0").replace("z: 0.1625", "z: 162.5");
    let e = UrKinematics::parse(&mm, "mm.yaml").unwrap_err().to_string();
    assert!(e.contains("x, y, z look like mm (the driver's file is in m)"), "{e}");
    let deg = good.replace("roll: 1.570796327", "roll: 90");
    assert_ne!(deg, good);
    let e = UrKinematics::parse(&deg, "deg.yaml").unwrap_err().to_string();
    assert!(e.contains("roll, pitch, yaw look like degrees"), "{e}");
}

/// A SCARA with every link length 0 is warned as the arms are; the shipped SCARA is not.
#[test]
fn a_scara_without_lengths_is_warned() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scara = shipped("scenarios/robots/scara-rrpr.toml");
    let zero: String = scara
        .lines()
        .map(|l| {
            if l.trim_start().starts_with("dh = {") {
                let mut l = l.to_owned();
                for key in ["d_mm", "a_mm"] {
                    let start = l.find(&format!("{key} = ")).unwrap() + key.len() + 3;
                    let end = start + l[start..].find([',', ' ', '}']).unwrap();
                    l.replace_range(start..end, "0.0");
                }
                l + "\n"
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    std::fs::write(d.join("zero.toml"), zero).unwrap();
    let a = axiscal()
        .current_dir(d)
        .args(["describe", "zero.toml"])
        .assert()
        .success();
    let e = stderr(&a);
    assert!(
        e.contains("every link length is 0: the 3 revolute axes are one line"),
        "{e}"
    );
    let a = axiscal()
        .current_dir(d)
        .args(["describe", "scara-rrpr"])
        .assert()
        .success();
    assert!(!stderr(&a).contains("warning"), "{}", stderr(&a));
}
