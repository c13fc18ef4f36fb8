//! Hostile command lines of the fourth round: options given values they refuse (negative
//! numbers, a list in one argument, `-` as an output), options that do nothing where they are
//! given, and files given to the wrong option (a URDF or a calibration as `--robot`, a CSV as
//! `--like` or as a shard folder, a point export without its header, a commented-out pose).
//! Each case is a command line, the exit code it must give and what its message must name.

use crate::common::hostile::{calibrated_campaign, case, clear_outputs, run_case};
use std::path::Path;

fn shipped(relative: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(relative)
        .display()
        .to_string()
}

/// The folder's inputs beside `campaign.csv` and `cal/`: a poses file with a commented-out
/// pose, a point export without a header, a scenario whose `[truth]` has a key `kind = "paper"`
/// does not take, a description whose first link weighs 1e30 kg, and the plan the export is
/// joined to.
fn write_inputs(dir: &Path) {
    let poses = "id,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg\np1,1200,100,900,0,0,0\n\
                 # p2,1100,200,800,0,0,0\np3,1150,150,850,0,0,0\n";
    std::fs::write(dir.join("commented.csv"), poses).unwrap();
    let export = "1,-3108.48,5269.44,13.85\n2,-3000.0,5000.0,10.0\n3,-3100.0,5100.0,20.0\n";
    std::fs::write(dir.join("no-header.csv"), export).unwrap();
    let smoke = std::fs::read_to_string(shipped("scenarios/ci-smoke.toml")).unwrap();
    let with_path = smoke.replace("kind = \"paper\"", "kind = \"paper\"\npath = \"nonexistent.toml\"");
    assert_ne!(with_path, smoke, "ci-smoke.toml names the paper truth");
    std::fs::write(dir.join("truth-path.toml"), with_path).unwrap();
    let irb = std::fs::read_to_string(shipped("scenarios/robots/asea-irb6l.toml")).unwrap();
    let at = irb.find("mass_kg = ").expect("the IRB/L6 gives its links' masses");
    let end = at + irb[at..].find('\n').unwrap();
    let heavy = format!("{}mass_kg = 1e30{}", &irb[..at], &irb[end..]);
    std::fs::write(dir.join("heavy.toml"), heavy).unwrap();
    crate::common::axiscal()
        .current_dir(dir)
        .args(["plan", "--out", "plan.csv"])
        .assert()
        .success();
}

#[test]
fn values_an_option_refuses_and_files_given_to_the_wrong_option_are_named() {
    let dir = tempfile::tempdir().unwrap();
    calibrated_campaign(dir.path(), 5);
    write_inputs(dir.path());
    let urdf = shipped("scenarios/robots/real/fanuc-r2000ic.urdf");
    let cases = [
        case(
            "a negative payload",
            "compensate --calibration cal/calibration.json --poses commented.csv --payload-kg -5 --out out.csv",
            2,
            &["--payload-kg", "-5 is out of range", "0..=100000 kg"],
        ),
        case(
            "a negative count",
            "simulate --validation-poses -1 --out out.csv",
            2,
            &["--validation-poses", "`-1` is out of range", "0..=1000000"],
        ),
        case(
            "a fractional count",
            "simulate --validation-poses 2.5 --out out.csv",
            2,
            &["--validation-poses", "`2.5` is not a whole number"],
        ),
        case(
            "a negative seed",
            "simulate --seed -5 --out out.csv",
            2,
            &["--seed", "`-5` is out of range"],
        ),
        case(
            "a negative tolerance",
            "calibrate campaign.csv --held-tolerance -1 --out out",
            2,
            &["--held-tolerance", "-1 is out of range"],
        ),
        case(
            "the commands as one comma-separated argument",
            "joints --calibration cal/calibration.json 10,10,10,10,10,10",
            2,
            &["holds several values", "its own argument"],
        ),
        case(
            "stdout as an output",
            "simulate --out -",
            2,
            &["--out `-`", "not to stdout"],
        ),
        case(
            "--refine-folds without --refine",
            "calibrate campaign.csv --refine-folds 3 --out out",
            2,
            &["--refine"],
        ),
        case(
            "more folds than free poses",
            "calibrate campaign.csv --refine --refine-folds 100000 --out out",
            2,
            &["40 free poses", "--refine-folds"],
        ),
        case(
            "a key the paper truth does not take",
            "run truth-path.toml --out out",
            2,
            &["truth-path.toml", "unknown field `path`"],
        ),
        case(
            "a URDF as --robot",
            &format!("calibrate campaign.csv --robot {urdf} --out out"),
            2,
            &["fanuc-r2000ic.urdf", "this is a URDF", "[urdf]"],
        ),
        case(
            "a calibration as --robot",
            "calibrate campaign.csv --robot cal/calibration.json --out out",
            2,
            &["calibration.json", "this is JSON, not a TOML file"],
        ),
        case(
            "a measurement CSV as the UR driver's YAML",
            "export ur-kinematics --calibration cal/calibration.json --like campaign.csv --out out.csv",
            2,
            &["campaign.csv", "a CSV table, not the UR driver's calibration YAML"],
        ),
        case(
            "a file as a shard folder",
            "merge campaign.csv --out out",
            2,
            &["campaign.csv is a file", "run --shard"],
        ),
        case(
            "a folder that is not a shard",
            "merge cal --out out",
            2,
            &["cal holds no scenario.resolved.toml"],
        ),
        case(
            "a point export without its header",
            "import points plan.csv no-header.csv --out out.csv",
            2,
            &["no-header.csv", "is data, not a header", "x or x_mm or x_m"],
        ),
        case(
            "an option the command does not have",
            "validate --json campaign.csv --calibration cal/calibration.json --out out",
            2,
            &["unexpected argument '--json'"],
        ),
        case(
            "a device as a recording",
            "view /dev/null",
            2,
            &["/dev/null is not a regular file"],
        ),
        case("a folder as a recording", "view cal", 2, &["cal is a folder"]),
        case(
            "a control character in the instrument's words",
            "report --calibration cal/calibration.json --instrument a\u{7}b --out out",
            2,
            &["--instrument", "control character"],
        ),
        case(
            "a link of 1e30 kg",
            "describe heavy.toml",
            2,
            &["heavy.toml", "joints[0].mass_kg", "1e30 kg is not a link's mass"],
        ),
        case(
            "a commented-out pose",
            "compensate --calibration cal/calibration.json --poses commented.csv --out out.csv",
            2,
            &["commented.csv: line 3", "to leave the row out, delete it"],
        ),
    ];
    for c in &cases {
        let e = run_case(dir.path(), c);
        assert!(
            !e.contains("use '-- "),
            "{}: clap's tip to pass a value after `--`: {e}",
            c.what
        );
        clear_outputs(dir.path());
    }
    assert!(!dir.path().join("-").exists(), "no file named `-`");
}

/// Options of the free-pose calibration (and `--max-poses` without `--refine`) given on a file
/// of axis experiments: the calibration runs, and a warning names each option that did nothing.
#[test]
fn options_without_effect_on_axis_experiments_are_named() {
    let dir = tempfile::tempdir().unwrap();
    calibrated_campaign(dir.path(), 6);
    let c = case(
        "free-pose options on axis experiments",
        "calibrate campaign.csv --harmonics 5 --effects none --max-poses 10 --out out",
        0,
        &[
            "warning: --harmonics has no effect here",
            "warning: --effects has no effect here",
            "warning: --max-poses has no effect here",
        ],
    );
    run_case(dir.path(), &c);
    let plain = crate::common::axiscal()
        .current_dir(dir.path())
        .args(["calibrate", "campaign.csv", "--out", "plain"])
        .assert()
        .success();
    assert!(!crate::common::stderr(&plain).contains("has no effect"));
    let json = |d: &str| std::fs::read(dir.path().join(d).join("calibration.json")).unwrap();
    assert_eq!(json("out"), json("plain"), "the ignored options change nothing");
}

/// `--noise-mm` on a file of free poses only (the run-8 hostile session: the option changed
/// nothing and nothing said so) is named as without effect, and indeed changes nothing.
#[test]
fn noise_mm_on_free_poses_is_named_as_without_effect() {
    let dir = tempfile::tempdir().unwrap();
    crate::common::simulate_analytic(dir.path(), 40, 8, "campaign.csv");
    crate::common::altered_csv(&dir.path().join("campaign.csv"), "free.csv", |f| f[1] == "0", |_| {});
    let c = case(
        "--noise-mm on free poses",
        "calibrate free.csv --noise-mm 1.0 --out out",
        0,
        &[
            "warning: --noise-mm 1 has no effect here",
            "estimates the noise from their residuals",
        ],
    );
    run_case(dir.path(), &c);
    let plain = crate::common::axiscal()
        .current_dir(dir.path())
        .args(["calibrate", "free.csv", "--out", "plain"])
        .assert()
        .success();
    assert!(!crate::common::stderr(&plain).contains("has no effect"));
    let json = |d: &str| std::fs::read(dir.path().join(d).join("calibration.json")).unwrap();
    assert_eq!(json("out"), json("plain"), "the ignored option changes nothing");
}

/// One axis experiment's commands in gradians (a factor 400/360 the transmission's fit takes
/// up, within what a real transmission's slope may be) leave a model that misses the file's
/// own validation poses: `calibrate` warns with the miss and the prediction. The same campaign
/// unaltered draws no such warning.
#[test]
fn a_model_that_misses_the_files_own_validation_poses_is_said() {
    let dir = tempfile::tempdir().unwrap();
    crate::common::simulate_analytic(dir.path(), 40, 8, "campaign.csv");
    let gradians = crate::common::altered_csv(
        &dir.path().join("campaign.csv"),
        "gradians.csv",
        |_| true,
        |f| {
            if f[0] == "axis3" {
                crate::common::scale_fields(f, 9..10, 400.0 / 360.0);
            }
        },
    );
    let own = "misses this file's own 40 validation poses";
    let calibrate = |data: &Path| crate::common::hostile::calibrate_stderr(dir.path(), data);
    let e = calibrate(&gradians);
    assert!(e.contains(own) && e.contains("mm predicted"), "{e}");
    let miss = crate::common::number_after(&e, "(not fitted) by ");
    let predicted = crate::common::number_after(&e, "mm RMS against ");
    assert!(miss > 3.0 * predicted, "{miss} against {predicted}");
    let clean = calibrate(&dir.path().join("campaign.csv"));
    assert!(!clean.contains(own), "{clean}");
}
