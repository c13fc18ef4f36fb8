//! Damaged and hostile input files (a calibration, a robot description, a URDF, a plan): each
//! is one error, exit 2, naming the file and the key (the URDF's joint or link), where they
//! panicked, were accepted with absurd results, or named a key the user never wrote. Each
//! file is a shipped one or one the test makes, with one value changed.

use crate::common::{self, axiscal, stderr};
use axiscal::calibration::procedure::{CalibrationOptions, calibrate};
use axiscal::json_file::{self, Schema};
use axiscal::measurement::MeasurementModel;
use axiscal::robot::RobotDescription;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// The single `error:` line of a command that must exit 2.
fn error_of(a: &assert_cmd::assert::Assert) -> String {
    let err = stderr(a);
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(lines.len(), 1, "one error line expected: {err}");
    assert!(!err.contains("panicked"), "{err}");
    lines[0].to_owned()
}

/// A shipped file's text.
fn shipped(relative: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)).unwrap()
}

/// `text` with its first `from` replaced by `to` (which must be there).
fn changed(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "`{from}` is not in the file");
    text.replacen(from, to, 1)
}

/// A calibration of the paper robot with its model covariance and noise, as JSON.
fn calibration_json() -> Value {
    let set = common::axes_only_campaign_of(
        &common::paper_robot_without_jitter(),
        &MeasurementModel::paper_isotropic(),
        1,
    );
    let cal = calibrate(&set, &RobotDescription::asea_irb6l(), &CalibrationOptions::default()).unwrap();
    assert!(cal.model_covariance.is_some() && cal.noise.is_some());
    serde_json::from_str(&json_file::to_string(Schema::CALIBRATION, &cal).unwrap()).unwrap()
}

/// The value at the JSON pointer `at` (which must be there).
fn at<'a>(json: &'a mut Value, pointer: &str) -> &'a mut Value {
    json.pointer_mut(pointer)
        .unwrap_or_else(|| panic!("no `{pointer}` in the calibration"))
}

/// `axiscal joints --calibration FILE -- 0 0 0 0 0 0`.
fn joints(file: &Path) -> assert_cmd::assert::Assert {
    axiscal()
        .args(["joints", "--calibration"])
        .arg(file)
        .args(["--", "0", "0", "0", "0", "0", "0"])
        .assert()
}

/// One change of a calibration file, and the key its error must name.
type CalibrationCase = (&'static str, Box<dyn Fn(&mut Value)>, &'static str);

fn calibration_cases() -> Vec<CalibrationCase> {
    let set = |pointer: &'static str, value: Value| -> Box<dyn Fn(&mut Value)> {
        Box::new(move |j| *at(j, pointer) = value.clone())
    };
    vec![
        (
            "a negative variance (it panicked)",
            set("/model_covariance/covariance/0/0", json!(-0.03)),
            "field `model_covariance.covariance[0][0]`",
        ),
        (
            "an asymmetric covariance",
            set("/model_covariance/covariance/0/1", json!(0.9999)),
            "field `model_covariance.covariance[1][0]`",
        ),
        (
            "a symmetric covariance with a negative eigenvalue",
            Box::new(|j| {
                let (a, b) = (
                    at(j, "/model_covariance/covariance/0/0").as_f64(),
                    at(j, "/model_covariance/covariance/1/1").as_f64(),
                );
                let c = 2.0 * (a.unwrap() * b.unwrap()).sqrt();
                *at(j, "/model_covariance/covariance/0/1") = json!(c);
                *at(j, "/model_covariance/covariance/1/0") = json!(c);
            }),
            "positive semi-definite",
        ),
        (
            "a variance of 1e300",
            set("/model_covariance/covariance/0/0", json!(1e300)),
            "field `model_covariance.covariance[0][0]`",
        ),
        (
            "a ragged covariance",
            Box::new(|j| {
                at(j, "/model_covariance/covariance/3").as_array_mut().unwrap().pop();
            }),
            "field `model_covariance.covariance[3]`",
        ),
        (
            "a null variance",
            set("/model_covariance/covariance/0/0", Value::Null),
            "key `model_covariance.covariance[0][0]`",
        ),
        (
            "a null row length",
            set("/robot/rows/1/a_m", Value::Null),
            "key `robot.rows[1].a_m`",
        ),
        (
            "a negative noise",
            set("/noise/used_rms_3d_mm", json!(-0.2)),
            "field `noise.used_rms_3d_mm`",
        ),
        (
            "a zero noise",
            set("/options/noise_rms_3d_mm", json!(0.0)),
            "field `options.noise_rms_3d_mm`",
        ),
        (
            "a noise of 1e300",
            set("/noise/used_rms_3d_mm", json!(1e300)),
            "field `noise.used_rms_3d_mm`",
        ),
        (
            "three reference commands",
            set("/reference_cmd", json!([0, 0, 0])),
            "field `reference_cmd`",
        ),
        (
            "sin and cos of different lengths",
            set("/robot/joints/0/transmission/sin", json!([0.001, 0.001])),
            "field `robot.joints[0].transmission`",
        ),
        (
            "a transmission that turns back",
            set("/robot/joints/0/transmission/sin", json!([2.0])),
            "field `robot.joints[0].transmission`",
        ),
    ]
}

/// Each damaged calibration is one error naming the file and the key (exit 2); the intact
/// file, with a byte-order mark, reads.
#[test]
fn a_damaged_calibration_names_its_key() {
    let dir = tempfile::tempdir().unwrap();
    let good = calibration_json();
    for (k, (what, change, key)) in calibration_cases().iter().enumerate() {
        let mut json = good.clone();
        change(&mut json);
        let file = dir.path().join(format!("cal{k}.json"));
        std::fs::write(&file, serde_json::to_string_pretty(&json).unwrap()).unwrap();
        let e = error_of(&joints(&file).code(2));
        assert!(e.contains(&format!("cal{k}.json")) && e.contains(key), "{what}: {e}");
    }
    let bom = dir.path().join("bom.json");
    std::fs::write(
        &bom,
        format!("\u{feff}{}", serde_json::to_string_pretty(&good).unwrap()),
    )
    .unwrap();
    joints(&bom).success();
}

/// A covariance that is no covariance is refused by every command that reads it: `validate`
/// panicked, `report` and `iso9283 predict` printed U = 0 or absurd predictions.
#[test]
fn every_command_refuses_a_covariance_that_is_none() {
    let dir = tempfile::tempdir().unwrap();
    let mut json = calibration_json();
    *at(&mut json, "/model_covariance/covariance/2/2") = json!(-1.0);
    let file = dir.path().join("negative.json");
    std::fs::write(&file, serde_json::to_string(&json).unwrap()).unwrap();
    let data = dir.path().join("data.csv");
    std::fs::write(&data, "experiment\n").unwrap();
    let out = |name: &str| dir.path().join(name);
    let runs: [Vec<std::ffi::OsString>; 3] = [
        vec![
            "validate".into(),
            "--calibration".into(),
            file.clone().into(),
            data.clone().into(),
            "--out".into(),
            out("v").into(),
        ],
        vec![
            "report".into(),
            "--calibration".into(),
            file.clone().into(),
            "--out".into(),
            out("r").into(),
        ],
        vec![
            "iso9283".into(),
            "predict".into(),
            "--calibration".into(),
            file.clone().into(),
            "--out".into(),
            out("i").into(),
        ],
    ];
    for args in runs {
        let e = error_of(&axiscal().args(&args).assert().code(2));
        assert!(
            e.contains("negative.json") && e.contains("`model_covariance.covariance[2][2]`"),
            "{args:?}: {e}"
        );
    }
}

/// One change of the shipped IRB/L6 description, and the key its error must name.
const DESCRIPTION_CASES: [(&str, &str, &str); 10] = [
    (
        "ratio = 1.6842105263157894",
        "ratio = 0.0",
        "joints[4].transmission_fit.ratio",
    ),
    (
        "ratio = 1.6842105263157894",
        "ratio = nan",
        "joints[4].transmission_fit.ratio",
    ),
    (
        "ratio = 1.6842105263157894",
        "ratio = 1e300",
        "joints[4].transmission_fit.ratio",
    ),
    (
        "repeatability_sigma = 1.1806e-4   #",
        "repeatability_sigma = 1e10   #",
        "joints[0].repeatability_sigma",
    ),
    (
        "position_mm = [80.0, 0.0, 150.0]",
        "position_mm = [nan, 0.0, 150.0]",
        "axis_targets[0].target0.position_mm[0]",
    ),
    ("mass_kg = 45.0", "mass_kg = nan", "joints[0].mass_kg"),
    (
        "com_mm = [0.0, 0.0, -150.0]",
        "com_mm = [0.0, inf, -150.0]",
        "joints[0].com_mm[1]",
    ),
    ("name = \"ASEA IRB/L6\"", "name = \"ASEA\\npoint,pose\"", "`name`"),
    ("[-6284.6, 0.0, 0.0]", "[0.0, 0.0, 0.0]", "instrument.stations_mm[1]"),
    (
        "[-6284.6, 0.0, 0.0]",
        "[-6.2846, 0.0, 0.0]",
        "instrument.stations_mm[1]",
    ),
];

/// Each hostile description is one error naming its key, for `describe` and `plan` alike (a
/// gear ratio of 0 or NaN panicked in `calibrate`, a NaN target was planned, a newline in the
/// name broke the outputs' comment lines).
#[test]
fn hostile_descriptions_name_their_key_in_describe_and_plan() {
    let dir = tempfile::tempdir().unwrap();
    let text = shipped("scenarios/robots/asea-irb6l.toml");
    for (k, (from, to, key)) in DESCRIPTION_CASES.iter().enumerate() {
        let robot = dir.path().join(format!("robot{k}.toml"));
        std::fs::write(&robot, changed(&text, from, to)).unwrap();
        let describe = axiscal().arg("describe").arg(&robot).assert().code(2);
        let plan = axiscal()
            .args(["plan", "--robot"])
            .arg(&robot)
            .arg("--out")
            .arg(dir.path().join("plan.csv"))
            .assert()
            .code(2);
        for e in [error_of(&describe), error_of(&plan)] {
            assert!(e.contains(&format!("robot{k}.toml")) && e.contains(key), "{to}: {e}");
        }
    }
    assert!(!dir.path().join("plan.csv").exists());
}

/// `plan` and `describe` run the unit check `simulate` and `calibrate` run (rows in mm, a
/// tool 1e12 mm long), and `--skip-unit-check` overrides it as there.
#[test]
fn plan_and_describe_check_the_descriptions_units() {
    let dir = tempfile::tempdir().unwrap();
    let text = shipped("scenarios/robots/asea-irb6l.toml");
    let cases = [
        ("a_m = -0.690", "a_m = -690.0", "rows[1].a_m"),
        (
            "[tool]\n",
            "[tool]\nframe = { translation_mm = [0.0, 0.0, 1e12] }\n",
            "tool.frame.translation_mm",
        ),
    ];
    for (k, (from, to, key)) in cases.iter().enumerate() {
        let robot = dir.path().join(format!("units{k}.toml"));
        std::fs::write(&robot, changed(&text, from, to)).unwrap();
        let plan = |extra: &[&str]| {
            axiscal()
                .args(["plan", "--no-sight", "--validation-poses", "0", "--robot"])
                .arg(&robot)
                .arg("--out")
                .arg(dir.path().join(format!("plan{k}.csv")))
                .args(extra)
                .assert()
        };
        let describe = axiscal().arg("describe").arg(&robot).assert().code(2);
        for e in [error_of(&describe), error_of(&plan(&[]).code(2))] {
            assert!(e.contains(key) && e.contains("--skip-unit-check"), "{to}: {e}");
        }
        axiscal()
            .arg("describe")
            .arg(&robot)
            .arg("--skip-unit-check")
            .assert()
            .success();
    }
}

/// A three-joint DH robot (a 290 mm column, a 270 mm upper arm, a 70 mm elbow) with its
/// lengths times `scale` and `a_mm` of the elbow `elbow_mm`, its tool targets 60 to 150 mm
/// from the flange.
fn dh_robot(scale: f64, elbow_mm: f64) -> String {
    let joint = |limit: f64, d_mm: f64, a_mm: f64, alpha_deg: f64| {
        format!(
            "[[joints]]\nkind = \"revolute\"\nlimits = [-{limit:?}, {limit:?}]\n\
             dh = {{ d_mm = {d_mm:?}, a_mm = {a_mm:?}, alpha_deg = {alpha_deg:?} }}\n\n"
        )
    };
    format!(
        "name = \"three joints\"\ndh_convention = \"classic\"\naxis_targets = []\n\n{}{}{}\
         [tool]\ntargets_mm = [[60.0, 0.0, 60.0], [60.0, 80.0, 60.0], [60.0, 0.0, 140.0]]\n",
        joint(165.0, 290.0 * scale, 0.0, -90.0),
        joint(110.0, 0.0, 270.0 * scale, 0.0),
        joint(110.0, 0.0, elbow_mm, -90.0),
    )
}

/// A DH table in metres (its lengths read as mm, the targets 500 times beyond the arm) is the
/// unit slip `simulate` refuses, in `describe` too, and `--skip-unit-check` overrides it; a
/// length of kilometres is one error naming the DH key; the same table in mm reads.
#[test]
fn a_dh_table_in_other_units_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let describe = |name: &str, text: String, extra: &[&str]| {
        let robot = dir.path().join(name);
        std::fs::write(&robot, text).unwrap();
        axiscal().arg("describe").arg(&robot).args(extra).assert()
    };
    describe("mm.toml", dh_robot(1.0, 70.0), &[]).success();
    let e = error_of(&describe("m.toml", dh_robot(1e-3, 0.07), &[]).code(2));
    assert!(
        e.contains("m.toml") && e.contains("`rows`") && e.contains("metres"),
        "{e}"
    );
    describe("m.toml", dh_robot(1e-3, 0.07), &["--skip-unit-check"]).success();
    let e = error_of(&describe("km.toml", dh_robot(1.0, 7e7), &[]).code(2));
    assert!(e.contains("`joints[2].dh.a_mm`"), "{e}");
}

/// One twist of a DH table written in radians among degrees (the elbow's `alpha_deg = -1.5708`
/// beside the column's -90): a warning naming that joint's key and the -90 deg meant; the
/// table in degrees says nothing of twists.
#[test]
fn one_dh_twist_in_radians_among_degrees_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let robot = dir.path().join("lone.toml");
    let table = dh_robot(1.0, 70.0);
    let at = table.rfind("alpha_deg = -90.0").unwrap();
    let lone = format!(
        "{}alpha_deg = -1.5708{}",
        &table[..at],
        &table[at + "alpha_deg = -90.0".len()..]
    );
    std::fs::write(&robot, lone).unwrap();
    let e = crate::common::stderr(&axiscal().arg("describe").arg(&robot).assert().success());
    assert!(
        e.contains("warning: ") && e.contains("`joints[2].dh.alpha_deg`") && e.contains("radian form of -90 deg"),
        "{e}"
    );
    std::fs::write(&robot, dh_robot(1.0, 70.0)).unwrap();
    let e = crate::common::stderr(&axiscal().arg("describe").arg(&robot).assert().success());
    assert!(!e.contains("alpha_deg"), "{e}");
}

/// The shipped classic 6R table (`arm6-dh.toml`) declared `modified`: a warning naming
/// `dh_convention` and the layout it reads as; declared as written: none.
#[test]
fn a_classic_table_declared_modified_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let table = shipped("scenarios/robots/arm6-dh.toml");
    let robot = dir.path().join("arm6.toml");
    for (convention, said) in [("modified", true), ("classic", false)] {
        std::fs::write(
            &robot,
            changed(
                &table,
                "dh_convention = \"classic\"",
                &format!("dh_convention = \"{convention}\""),
            ),
        )
        .unwrap();
        let e = crate::common::stderr(&axiscal().arg("describe").arg(&robot).assert().success());
        assert_eq!(
            e.contains("`dh_convention`: \"modified\", but the twists are laid out as a classic table's"),
            said,
            "{convention}: {e}"
        );
    }
}

/// The shipped FANUC URDF description with `from` replaced by `to` in its URDF (`urdf`) or
/// its TOML (`toml`), in `dir`: the description's path.
fn fanuc(dir: &Path, k: usize, urdf: (&str, &str), toml: (&str, &str)) -> PathBuf {
    let urdf_text = changed(&shipped("scenarios/robots/real/fanuc-r2000ic.urdf"), urdf.0, urdf.1);
    std::fs::write(dir.join(format!("arm{k}.urdf")), urdf_text).unwrap();
    let toml_text =
        shipped("scenarios/robots/real/fanuc-r2000ic.toml").replace("fanuc-r2000ic.urdf", &format!("arm{k}.urdf"));
    let path = dir.join(format!("arm{k}.toml"));
    std::fs::write(&path, changed(&toml_text, toml.0, toml.1)).unwrap();
    path
}

/// A hostile URDF is one error naming the URDF's joint or link and its attribute (reversed
/// limits became +-360 deg silently; mm origins and negative masses named TOML keys the user
/// never wrote); a base link that is not there lists the links.
#[test]
fn hostile_urdfs_name_the_urdf_joint_or_link() {
    let dir = tempfile::tempdir().unwrap();
    let none = ("[urdf]", "[urdf]");
    let cases = [
        (
            ("lower=\"-1.05\" upper=\"1.31\"", "lower=\"1.31\" upper=\"-1.05\""),
            none,
            "joint `joint_2`: `<limit",
        ),
        (
            ("xyz=\"1.075 0 0\"", "xyz=\"1075 0 0\""),
            none,
            "joint `joint_3`: `<origin",
        ),
        (
            (
                "<link name=\"link_2\"/>",
                "<link name=\"link_2\"><inertial><mass value=\"-1\"/><inertia ixx=\"0\" iyy=\"0\" izz=\"0\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link>",
            ),
            none,
            "link `link_2`: `<inertial><mass",
        ),
        (
            ("<robot", "<robot"),
            ("[urdf]", "[urdf]\nbase_link = \"nope\""),
            "no link named `nope`; the URDF's links are `base_link`, `link_1`",
        ),
        // A broken tree cut the chain and the robot lost its joints below the break silently.
        (
            (
                "<parent link=\"link_2\"/><child link=\"link_3\"/>",
                "<parent link=\"link_2x\"/><child link=\"link_3\"/>",
            ),
            none,
            "joint `joint_3`: its parent link `link_2x` is not declared",
        ),
        (
            ("<joint name=\"joint_3\"", "<joint name=\"joint_2\""),
            none,
            "joint `joint_2` is declared twice",
        ),
        (
            (
                "<link name=\"link_2\"/>",
                "<link name=\"link_2\"/><link name=\"stray\"/>",
            ),
            none,
            "2 links are no joint's child (`base_link`, `stray`)",
        ),
        (
            (
                "<parent link=\"link_2\"/><child link=\"link_3\"/>",
                "<parent link=\"link_2\"/><child link=\"link_2\"/>",
            ),
            none,
            "link `link_2` is the child of two joints",
        ),
        // Degrees where a URDF takes radians were read as 45-rad limits and a -90-rad turn.
        (
            ("lower=\"-1.05\" upper=\"1.31\"", "lower=\"-60\" upper=\"75\""),
            none,
            "joint `joint_2`: `<limit lower=\"-60\" upper=\"75\">`: 11.9 turns either way",
        ),
        (
            ("rpy=\"0 -1.5707963267948966 0\"", "rpy=\"0 -90 0\""),
            none,
            "joint `joint_2`: `<origin rpy=\"0 -90 0\">`: -90 rad is more than a turn",
        ),
        // A joint following another was calibrated as a joint of its own.
        (
            (
                "<joint name=\"joint_4\" type=\"revolute\">",
                "<joint name=\"joint_4\" type=\"revolute\"><mimic joint=\"joint_3\"/>",
            ),
            none,
            "joint `joint_4`: `<mimic joint=\"joint_3\">`",
        ),
    ];
    for (k, (urdf, toml, expected)) in cases.into_iter().enumerate() {
        let robot = fanuc(dir.path(), k, urdf, toml);
        let e = error_of(&axiscal().arg("describe").arg(&robot).assert().code(2));
        assert!(
            e.contains(&format!("arm{k}.toml")) && e.contains(&format!("arm{k}.urdf")) && e.contains(expected),
            "{e}"
        );
        assert!(!e.contains("rows[") && !e.contains("joints["), "{e}");
    }
}

/// A plan file's `held_at` of another length than the joints (it was padded with zeros) and a
/// `held_jitter` reversed, NaN or of 1e9 (accepted) are one error naming the file and the key.
#[test]
fn hostile_plan_files_name_their_key() {
    let dir = tempfile::tempdir().unwrap();
    let text = shipped("scenarios/robots/asea-irb6l-table1-plan.toml");
    let sweep = "span = 50.0\nintervals = 16\n";
    let top = "reference = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]\n";
    let cases = [
        (
            sweep,
            "span = 50.0\nintervals = 16\nheld_at = [1.0, 2.0]\n",
            "`sweeps[0].held_at`",
        ),
        (
            top,
            "reference = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]\nheld_jitter = [0.1, -0.1]\n",
            "`held_jitter`",
        ),
        (
            top,
            "reference = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]\nheld_jitter = [0.0, 1e9]\n",
            "`held_jitter`",
        ),
        (
            top,
            "reference = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]\nheld_jitter = [nan, 0.1]\n",
            "`held_jitter[0]`",
        ),
    ];
    for (k, (from, to, key)) in cases.iter().enumerate() {
        let plan = dir.path().join(format!("plan{k}.toml"));
        std::fs::write(&plan, changed(&text, from, to)).unwrap();
        let a = axiscal()
            .args(["plan", "--no-sight", "--plan"])
            .arg(&plan)
            .arg("--out")
            .arg(dir.path().join("out.csv"))
            .assert()
            .code(2);
        let e = error_of(&a);
        assert!(e.contains(&format!("plan{k}.toml")) && e.contains(key), "{to}: {e}");
    }
}

/// File names that are not UTF-8 (Latin-1 `é`, as an older system writes them) are taken
/// wherever a file may also be a shipped name: `describe ROBOT`, `simulate --robot --truth`,
/// `run SCENARIO`, a missing one refused naming it. Before, clap refused every such path:
/// "invalid UTF-8 was detected in one or more arguments".
#[cfg(unix)]
#[test]
fn paths_that_are_not_utf8_are_read() {
    use std::os::unix::ffi::OsStrExt;
    let dir = tempfile::tempdir().unwrap();
    let latin1 = |stem: &str, ext: &str| {
        dir.path().join(std::ffi::OsStr::from_bytes(
            &[stem.as_bytes(), b"\xe9.", ext.as_bytes()].concat(),
        ))
    };
    let robot = latin1("rob", "toml");
    std::fs::write(&robot, shipped("scenarios/robots/arm6-dh.toml")).unwrap();
    let described = axiscal().arg("describe").arg(&robot).assert().success();
    assert!(
        common::stdout(&described).contains("Six-axis arm"),
        "{}",
        common::stdout(&described)
    );
    let campaign = latin1("campagne", "csv");
    axiscal()
        .args(["simulate", "--quiet", "--sim", "analytic", "--robot"])
        .arg(&robot)
        .arg("--truth")
        .arg(&robot)
        .arg("--out")
        .arg(&campaign)
        .assert()
        .success();
    assert!(campaign.is_file());
    let scenario = latin1("sc", "toml");
    std::fs::write(&scenario, shipped("scenarios/ci-smoke.toml")).unwrap();
    axiscal()
        .args(["run", "--quiet", "--trials", "1", "--out"])
        .arg(dir.path().join("results"))
        .arg(&scenario)
        .assert()
        .success();
    let missing = latin1("absent", "toml");
    let e = error_of(&axiscal().arg("describe").arg(&missing).assert().code(2));
    assert!(e.contains("absent\u{fffd}.toml"), "{e}");
}
