//! Hostile files of the fifth round read where they enter: two measurement files joined end
//! to end, a control byte left at a file's end, and a `calibration.json` whose joint kind or
//! transmission was edited by hand.

use crate::common::hostile::{calibrated_campaign, case, clear_outputs, edited_calibration, run_case};
use std::path::Path;

/// `campaign.csv` altered as the cases need: joined to itself (the second header kept, as
/// `cat a.csv b.csv` does), and with a DOS end-of-file byte (0x1a) on a line of its own.
fn write_joined_and_marked(dir: &Path) {
    let text = std::fs::read_to_string(dir.join("campaign.csv")).unwrap();
    std::fs::write(dir.join("joined.csv"), format!("{text}{text}")).unwrap();
    std::fs::write(dir.join("marked.csv"), format!("{text}\u{1a}\n")).unwrap();
}

#[test]
fn joined_files_and_control_bytes_are_named_by_line() {
    let dir = tempfile::tempdir().unwrap();
    calibrated_campaign(dir.path(), 23);
    write_joined_and_marked(dir.path());
    let lines = std::fs::read_to_string(dir.path().join("campaign.csv"))
        .unwrap()
        .lines()
        .count();
    let header_line = 2; // below the description's `#` record
    let repeated = format!(
        "joined.csv:{}: the line repeats the header (line {header_line})",
        lines + header_line
    );
    let marked = format!(
        "marked.csv:{}: column `experiment`: holds the control byte 0x1a",
        lines + 1
    );
    for c in [
        case(
            "two files joined",
            "calibrate joined.csv --out out",
            2,
            &[&repeated, "joined end to end"],
        ),
        case(
            "joined, validated",
            "validate joined.csv --calibration cal/calibration.json --out out",
            2,
            &[&repeated],
        ),
        case(
            "an end-of-file byte",
            "calibrate marked.csv --out out",
            2,
            &[&marked, "and nothing else"],
        ),
    ] {
        run_case(dir.path(), &c);
        clear_outputs(dir.path());
    }
}

#[test]
fn a_calibration_edited_by_hand_is_refused_or_warned() {
    let dir = tempfile::tempdir().unwrap();
    calibrated_campaign(dir.path(), 24);
    edited_calibration(dir.path(), "prismatic.json", |v| {
        v["robot"]["joints"][0]["kind"] = "prismatic".into();
    });
    edited_calibration(dir.path(), "harmonic.json", |v| {
        // Within what a transmission can be (0.9 rad is refused: `hostile_round6d`).
        v["robot"]["joints"][1]["transmission"]["sin"] = serde_json::json!([0.05]);
    });
    // Re-written without an edit (other white space, the same values): no warning.
    edited_calibration(dir.path(), "same.json", |_| {});
    let kind = "field `robot.joints[0].kind`: prismatic, but joint 1 of";
    for c in [
        case(
            "kind, joints",
            "joints --calibration prismatic.json 10 -10 5 20 30 40",
            2,
            &[kind],
        ),
        case(
            "kind, validate",
            "validate campaign.csv --calibration prismatic.json --out out",
            2,
            &[kind],
        ),
    ] {
        run_case(dir.path(), &c);
        clear_outputs(dir.path());
    }
    let edited = "`robot` was edited after `axiscal calibrate` wrote it (`model_digest`";
    let warned = run_case(
        dir.path(),
        &case(
            "an edited harmonic",
            "joints --calibration harmonic.json 10 -10 5 20 30 40",
            0,
            &[edited],
        ),
    );
    assert!(warned.contains("harmonic.json"), "{warned}");
    let quiet = run_case(
        dir.path(),
        &case("re-written", "joints --calibration same.json 10 -10 5 20 30 40", 0, &[]),
    );
    assert!(!quiet.contains("was edited"), "{quiet}");
}

/// `campaign.csv` with `edit` applied to the fields of each data row, written as `name`.
fn edited_rows(dir: &Path, name: &str, edit: impl Fn(&mut Vec<String>)) {
    let text = std::fs::read_to_string(dir.join("campaign.csv")).unwrap();
    let mut out = String::new();
    for (i, line) in text.lines().enumerate() {
        if line.starts_with('#') || line.starts_with("experiment,") {
            out.push_str(line);
        } else {
            let mut fields: Vec<String> = line.split(',').map(str::to_owned).collect();
            edit(&mut fields);
            out.push_str(&fields.join(","));
        }
        assert!(i < 100_000);
        out.push('\n');
    }
    std::fs::write(dir.join(name), out).unwrap();
}

#[test]
fn free_poses_labelled_a_sweep_and_rounded_points_are_said_as_such() {
    let dir = tempfile::tempdir().unwrap();
    calibrated_campaign(dir.path(), 25);
    edited_rows(dir.path(), "labelled.csv", |f| {
        if f[0] == "validation" {
            f[1] = "1".into();
        }
    });
    edited_rows(dir.path(), "rounded.csv", |f| {
        for v in &mut f[4..7] {
            *v = format!("{}", (v.parse::<f64>().unwrap() / 10.0).round() * 10.0);
        }
    });
    // Before: "`cmd_1`: the targets turn 13.438 times the commanded span read as degrees".
    let labelled = [
        "`moved_joint`: experiment validation (lines",
        "is labelled moved_joint 1, but its steps also move joint",
    ];
    // Before: "`cmd_5`: ... this experiment's cmd_5 looks doubled".
    let rounded = ["every coordinate is a multiple of 10 mm: the points were written rounded"];
    for c in [
        case(
            "validation rows labelled 1",
            "calibrate labelled.csv --out out",
            2,
            &labelled,
        ),
        case(
            "labelled, validated",
            "validate labelled.csv --calibration cal/calibration.json --out out",
            2,
            &labelled,
        ),
        case(
            "coordinates rounded to 1 cm",
            "calibrate rounded.csv --out out",
            2,
            &rounded,
        ),
    ] {
        let e = run_case(dir.path(), &c);
        assert!(
            !e.contains("looks doubled") && !e.contains("scaled by"),
            "{}: {e}",
            c.what
        );
        clear_outputs(dir.path());
    }
}

/// A few rows with `y_mm` negated (hand-edited sign) are outliers named by line, not a
/// command column "halved" (its turn ratio is known less well than the transmissions' band).
#[test]
fn a_few_rows_with_a_flipped_sign_are_outliers_not_a_command_factor() {
    let dir = tempfile::tempdir().unwrap();
    calibrated_campaign(dir.path(), 26);
    let flipped = std::cell::RefCell::new(Vec::new());
    edited_rows(dir.path(), "flipped.csv", |f| {
        if f[0] == "axis5" && ["4", "11"].contains(&f[2].as_str()) && f[3] == "0" {
            f[5] = format!("{}", -f[5].parse::<f64>().unwrap());
            flipped.borrow_mut().push(f[2].clone());
        }
    });
    assert_eq!(flipped.borrow().len(), 2, "two axis5 rows flipped");
    let e = run_case(
        dir.path(),
        &case(
            "y negated in two rows",
            "calibrate flipped.csv --out out",
            0,
            &[
                "outlier: experiment axis5 step 4 target 0",
                "outlier: experiment axis5 step 11 target 0",
            ],
        ),
    );
    assert!(!e.contains("looks halved") && !e.contains("looks doubled"), "{e}");
}

/// A left-handed instrument frame (two coordinate columns swapped in every row) on robots whose
/// calibrated rows cannot show it (a SCARA, a positioning table, a 2-axis positioner): the
/// points fit a mirror image of the nominal robot far better than any rotation of it.
#[test]
fn a_mirrored_frame_is_named_on_every_robot_kind() {
    let dir = tempfile::tempdir().unwrap();
    for (robot, seed) in [("scara-rrpr", 27), ("table-prpp", 28), ("positioner-2axis", 29)] {
        let description = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenarios/robots/{robot}.toml"));
        let description = description.display().to_string();
        crate::common::axiscal()
            .current_dir(dir.path())
            .args([
                "simulate",
                "--sim",
                "analytic",
                "--robot",
                &description,
                "--validation-poses",
                "20",
            ])
            .args(["--seed", &seed.to_string(), "--out", "campaign.csv"])
            .assert()
            .success();
        edited_rows(dir.path(), "swapped.csv", |f| f.swap(4, 5));
        let clean = format!("calibrate campaign.csv --robot {description} --out out");
        let e = run_case(dir.path(), &case("unswapped", &clean, 0, &[]));
        assert!(!e.contains("mirror image"), "{robot}: a false alarm: {e}");
        clear_outputs(dir.path());
        let swapped = format!("calibrate swapped.csv --robot {description} --out out");
        run_case(
            dir.path(),
            &case(
                "x and y swapped",
                &swapped,
                2,
                &["fit a mirror image of the description's robot", "left-handed"],
            ),
        );
        std::fs::remove_file(dir.path().join("campaign.csv")).unwrap();
    }
}

/// Free poses that repeat two configurations twenty times each determine fewer values than the
/// fit's parameters: said, and no slip named from them; every validation pose once is not.
#[test]
fn free_poses_repeating_a_few_configurations_are_said() {
    let dir = tempfile::tempdir().unwrap();
    calibrated_campaign(dir.path(), 30);
    let text = std::fs::read_to_string(dir.path().join("campaign.csv")).unwrap();
    let header = text.lines().find(|l| l.starts_with("experiment,")).unwrap();
    let validation: Vec<Vec<&str>> = text
        .lines()
        .filter(|l| l.starts_with("validation,"))
        .map(|l| l.split(',').collect())
        .collect();
    let mut once = format!("{header}\n");
    let mut repeated = format!("{header}\n");
    for f in &validation {
        once.push_str(&f.join(","));
        once.push('\n');
    }
    for step in 0..40 {
        for f in validation.iter().filter(|f| f[2] == (step % 2).to_string()) {
            let mut row = f.clone();
            let step = step.to_string();
            row[2] = &step;
            repeated.push_str(&row.join(","));
            repeated.push('\n');
        }
    }
    std::fs::write(dir.path().join("once.csv"), once).unwrap();
    std::fs::write(dir.path().join("repeated.csv"), repeated).unwrap();
    let few = "stand at 2 distinct configurations (commands)";
    let e = run_case(
        dir.path(),
        &case("two configurations", "calibrate repeated.csv --out out", 0, &[few]),
    );
    assert!(!e.contains("absorbed it"), "{e}");
    clear_outputs(dir.path());
    let e = run_case(
        dir.path(),
        &case("every pose once", "calibrate once.csv --out out", 0, &[]),
    );
    assert!(!e.contains("distinct configurations"), "{e}");
}
