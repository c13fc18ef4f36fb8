//! Hostile inputs across the commands, as a table: each case is a command line on files a
//! careless or hostile user writes (another separator, another unit, a device, a pipe, a nest
//! of YAML aliases, columns that would be written twice, several instrument setups, a failed
//! stdout, a folder or a pipe where a file belongs, UTF-16 text, a 5 MB cell, a number of 309
//! digits, a data row commented out by its `#` experiment id) with the exit code it must give
//! and what its message must name. A bad input is one error line naming the file and the
//! field, exit 2, no longer than a screenful (a long value is shown by its start and length);
//! nothing is written.

use crate::common::hostile::{Case, case, clear_outputs, run_case};
use crate::common::{altered_csv, axiscal, scale_fields, simulate_analytic};
use std::path::Path;
use std::process::Stdio;

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

/// `text` as UTF-16 (little-endian, with its byte-order mark), as Windows tools save "Unicode".
fn utf16(text: &str) -> Vec<u8> {
    [0xFF, 0xFE]
        .into_iter()
        .chain(text.encode_utf16().flat_map(u16::to_le_bytes))
        .collect()
}

/// A MATLAB v5 file (little-endian) holding the joint array `q` of dimensions `q_dims` and
/// the point array `mA` (5 x 3), its last value `last`.
fn mat_file(q_dims: &[i32], last: f64) -> Vec<u8> {
    fn element(ty: u32, data: &[u8]) -> Vec<u8> {
        let mut e = [ty.to_le_bytes(), (data.len() as u32).to_le_bytes()].concat();
        e.extend(data);
        e.resize(e.len().next_multiple_of(8), 0);
        e
    }
    let matrix = |name: &str, dims: &[i32], last: f64| {
        let count = dims.iter().product::<i32>();
        let values: Vec<u8> = (0..count)
            .map(|i| if i + 1 == count { last } else { f64::from(i) * 0.01 })
            .flat_map(f64::to_le_bytes)
            .collect();
        let dims: Vec<u8> = dims.iter().flat_map(|d| d.to_le_bytes()).collect();
        let double_class = [6u32.to_le_bytes(), 0u32.to_le_bytes()].concat();
        let body = [
            element(6, &double_class),
            element(5, &dims),
            element(1, name.as_bytes()),
            element(9, &values),
        ];
        element(14, &body.concat())
    };
    let mut header = format!("{:<116}", "MATLAB 5.0 MAT-file, axiscal hostile test").into_bytes();
    header.extend([0; 8]);
    header.extend([0x00, 0x01, b'I', b'M']);
    [header, matrix("q", q_dims, 0.0), matrix("mA", &[5, 3], last)].concat()
}

/// robot_cal_tools measurements of the two-axis positioner turning joint 1, with a marker
/// coordinate of 1e300 m in entry `t1`.
fn rct_with_huge_coordinate() -> String {
    (0..4)
        .map(|i| {
            let x = if i == 1 {
                "1e300".to_owned()
            } else {
                format!("{}", 1.0 + 0.01 * f64::from(i))
            };
            format!(
                "'t{i}':\n  camera_joints: []\n  pose:\n    qw: 1.0\n    qx: 0.0\n    qy: 0.0\n    qz: 0.0\n    \
                 x: {x}\n    y: 0.1\n    z: 0.5\n  target_joints:\n  - {}\n  - 0.0\n",
                0.1 * f64::from(i)
            )
        })
        .collect()
}

/// The inputs of the readers' cases: a folder and a pipe where files belong, UTF-16 text of
/// each reader, a 5 MB experiment id, an experiment id starting with `#`, numbers of 1e308,
/// a theodolite pair in line with the robot, a 3-D MAT array.
fn write_reader_inputs(dir: &Path) {
    std::fs::create_dir(dir.join("folder")).unwrap();
    let made = std::process::Command::new("mkfifo").arg(dir.join("fifo.toml")).status();
    assert!(made.is_ok_and(|s| s.success()), "mkfifo");
    let campaign = dir.join("campaign.csv");
    let first = std::cell::Cell::new(true);
    let huge_id = "x".repeat(5_000_000);
    altered_csv(
        &campaign,
        "huge-id.csv",
        |_| true,
        |f| {
            if first.replace(false) {
                f[0] = huge_id.clone();
            }
        },
    );
    let first = std::cell::Cell::new(true);
    altered_csv(
        &campaign,
        "hash-id.csv",
        |_| true,
        |f| {
            if first.replace(false) {
                f[0] = format!("#{}", f[0]);
            }
        },
    );
    let irb6l = std::fs::read_to_string(shipped("scenarios/robots/asea-irb6l.toml")).unwrap();
    let arm6 = std::fs::read_to_string(shipped("scenarios/robots/arm6-dh.toml")).unwrap();
    let text = |name: &str| std::fs::read_to_string(dir.join(name)).unwrap();
    let files: [(&str, Vec<u8>); 12] = [
        ("u16.csv", utf16(&text("campaign.csv"))),
        ("u16.toml", utf16(&irb6l)),
        ("u16.json", utf16(&text("cal/calibration.json"))),
        ("u16.yaml", utf16(&rct_with_huge_coordinate())),
        ("xbig.yaml", rct_with_huge_coordinate().into_bytes()),
        ("q3.mat", mat_file(&[5, 6, 2], 0.1)),
        ("huge.mat", mat_file(&[5, 6], 1e300)),
        (
            "theta.toml",
            arm6.replacen("theta_deg = 0.0", "theta_deg = 1e308", 1).into_bytes(),
        ),
        (
            "order.toml",
            b"[[gear_harmonics]]\njoint = 2\norder = 100000000\nsin_rad = 0.001\n".to_vec(),
        ),
        (
            "float-order.toml",
            b"[[gear_harmonics]]\njoint = 2\norder = 1e308\n".to_vec(),
        ),
        (
            "in-line.toml",
            irb6l
                .replacen("[-6284.6, 0.0, 0.0]]", "[-1571.0, 2219.0, 0.0]]", 1)
                .into_bytes(),
        ),
        ("data.csv", text("campaign.csv").into_bytes()),
    ];
    for (name, bytes) in files {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
}

/// Writes every input of the table into `dir`.
fn write_inputs(dir: &Path) {
    crate::common::hostile::calibrated_campaign(dir, 7);
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
    write_reader_inputs(dir);
    // A DH robot without a joint: the positioner without its joints and axis targets.
    let positioner = std::fs::read_to_string(shipped("scenarios/robots/positioner-2axis.toml")).unwrap();
    let head = positioner.split("[[joints]]").next().unwrap();
    std::fs::write(dir.join("no-joints.toml"), head).unwrap();
}

/// The cases of the options and descriptions the second hostile run of this round found.
fn option_cases() -> Vec<Case> {
    vec![
        case(
            "a DH robot without a joint (it panicked)",
            "describe no-joints.toml",
            2,
            &["no-joints.toml", "field `joints`", "at least one joint"],
        ),
        case(
            "a URDF name that breaks the XML",
            "calibrate campaign.csv --urdf-name </robot><x> --out out",
            2,
            &["--urdf-name", "not a ROS name", "my_robot"],
        ),
        case(
            "two plan stations in one place",
            "plan --station 0,0,0 --station 0,0,0 --out out.csv",
            2,
            &["--station", "0.0 mm from station 0", "at least 100 mm apart"],
        ),
        case(
            "an option of 1e308 (its 309 digits echoed)",
            "calibrate campaign.csv --held-tolerance 1e308 --out out",
            2,
            &["--held-tolerance: 1e308 is out of range", "0..=360"],
        ),
        case(
            "a repeatability of 10 rad",
            "calibrate campaign.csv --repeatability-rad 10 --out out",
            2,
            &["--repeatability-rad: 10 is out of range", "0..=0.05 rad"],
        ),
        case(
            "an ISO cube's edge in metres",
            "iso9283 plan --edge-mm 0.25 --out out.csv",
            2,
            &["--edge-mm: 0.25 is out of range", "1..=100000 mm"],
        ),
        case(
            "a negative still tolerance",
            "import wide wide7.csv --angles deg --units mm --still-tolerance=-1 --out out.csv",
            2,
            &["--still-tolerance: -1 is out of range", "0..=10"],
        ),
    ]
}

/// The cases of the readers: each input in [`write_reader_inputs`].
fn reader_cases() -> Vec<Case> {
    let positioner = shipped("scenarios/robots/positioner-2axis.toml");
    let fanuc = shipped("scenarios/robots/real/fanuc-r2000ic.toml");
    let joints = "-- 0 0 0 0 0 0";
    vec![
        case(
            "a folder as the robot",
            "simulate --robot folder --out out.csv",
            2,
            &["folder", "a folder, not a regular file"],
        ),
        case(
            "a pipe as the scenario",
            "run fifo.toml --out out",
            2,
            &["fifo.toml", "not a regular file"],
        ),
        case(
            "a DH angle of 1e308",
            "simulate --robot theta.toml --out out.csv",
            2,
            &["theta.toml", "`joints[0].dh.theta_deg`", "1e308 deg"],
        ),
        case(
            "an integer key given 1e308",
            "simulate --effects float-order.toml --out out.csv",
            2,
            &["float-order.toml", "line 3", "floating point `1e308`"],
        ),
        case(
            "a 5 MB experiment id",
            "calibrate huge-id.csv --out out",
            2,
            &[
                "huge-id.csv:3: column `experiment`",
                "[5000000 characters]",
                "longer than 200",
            ],
        ),
        case(
            "a UTF-16 measurement CSV",
            "calibrate u16.csv --out out",
            2,
            &["u16.csv", "UTF-16", "save it as UTF-8"],
        ),
        case(
            "a UTF-16 description",
            "describe u16.toml",
            2,
            &["u16.toml", "UTF-16", "save it as UTF-8"],
        ),
        case(
            "a UTF-16 calibration",
            &format!("joints --calibration u16.json {joints}"),
            2,
            &["u16.json", "UTF-16", "save it as UTF-8"],
        ),
        case(
            "UTF-16 YAML",
            &format!("import rct u16.yaml --robot {positioner} --out out.csv"),
            2,
            &["u16.yaml", "UTF-16", "save it as UTF-8"],
        ),
        case(
            "an experiment id starting with #",
            "calibrate hash-id.csv --out out",
            2,
            &["hash-id.csv:3:", "starts with `#` but has 15 fields", "must be quoted"],
        ),
        case(
            "--out naming the data file",
            "calibrate data.csv --out data.csv",
            2,
            &["--out `data.csv` is a file", "--out names a folder"],
        ),
        case(
            "--out of a run naming a file",
            "run ci-smoke --out data.csv",
            2,
            &["--out `data.csv` is a file", "--out names a folder"],
        ),
        case(
            "--out under a file (it said `File exists (os error 17)`)",
            "simulate --seed 1 --out data.csv/x.csv --force",
            2,
            &["creating data.csv: `data.csv` is a file, not a folder: choose another --out"],
        ),
        case(
            "--out a device (it said `is a file`)",
            "calibrate data.csv --out /dev/null --force",
            2,
            &["--out `/dev/null` is a device"],
        ),
        case(
            "a YAML coordinate of 1e300 m",
            &format!("import rct xbig.yaml --robot {positioner} --out out.csv"),
            2,
            &["xbig.yaml", "entry `t1`, field `pose.x`", "1e300 m is outside"],
        ),
        case(
            "a 3-D joint array",
            "import mat q3.mat --robot asea-irb6l --joints q --targets mA --angles rad --units m --out out.csv",
            2,
            &["q3.mat", "variable `q`", "3 dimensions (5 x 6 x 2)", "6 columns"],
        ),
        case(
            "a point of 1e300 m in a MAT file (it panicked)",
            "import mat huge.mat --robot asea-irb6l --joints q --targets mA --angles rad --units m --out out.csv",
            2,
            &[
                "huge.mat",
                "variable `mA`, row 5, column 3: 1e300 as written",
                "outside +-1e7 mm",
            ],
        ),
        case(
            "an empty experiment id for a MAT file (it panicked)",
            "import mat huge.mat --robot asea-irb6l --joints q --targets mA --angles rad --units m --experiment= --out out.csv",
            2,
            &["--experiment: experiment id \"\" is empty"],
        ),
        case(
            "theodolites in line with the robot",
            "simulate --robot in-line.toml --out out.csv",
            2,
            &[
                "in-line.toml",
                "field `instrument.stations_mm`",
                "nearly parallel",
                "further apart",
            ],
        ),
        case(
            "a gear harmonic of order 1e8",
            "simulate --effects order.toml --out out.csv",
            2,
            &["order.toml", "`gear_harmonics[0].order`", "100000000"],
        ),
        case(
            "the FANUC's own forward kinematics",
            &format!("describe {fanuc}"),
            0,
            &[],
        ),
    ]
}

fn cases() -> Vec<Case> {
    let cal = "--calibration cal/calibration.json";
    let positioner = shipped("scenarios/robots/positioner-2axis.toml");
    let mut cases = reader_cases();
    cases.extend(option_cases());
    cases.extend([
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
    ]);
    cases
}

#[test]
fn every_hostile_input_is_one_clear_error_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path());
    for c in cases() {
        let e = run_case(dir.path(), &c);
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
        clear_outputs(dir.path());
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
