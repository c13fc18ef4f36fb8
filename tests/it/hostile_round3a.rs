//! The third hostile run's findings on reading data, calibrations and poses, as a table (as
//! [`super::hostile`]): a validation row whose commands are radians, an `axis3` experiment of
//! free poses, a calibration row in millimetres, a `--noise-mm` in metres given to `validate`
//! and `diagnose`, one coordinate column in other units, a validation pose read as 0,0,0,
//! another campaign given to `report --data`, pose ids used twice, empty or holding a line
//! break, and `--payload-kg` for a model without a payload. A bad input is one error line
//! naming the file and the field, exit 2, nothing written; a suspicious one a `warning:`.

use crate::common::hostile::{Case, case, clear_outputs, run_case};
use crate::common::{altered_csv, scale_fields, simulate_analytic};
use std::cell::RefCell;
use std::path::Path;

/// The tool poses of the README (reachable by the IRB/L6 in its instrument frame).
const POSES: &str = "ref,-3151.5,5345.8,167.8,179.56,0.23,-89.01\nlow,-2992.7,5292.7,-544.2,-152.04,-25.32,-70.69\n";
const POSE_HEADER: &str = "id,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg\n";

/// Writes the campaign, its calibration and every altered input into `dir`; returns the step
/// of the validation pose one of whose rows has its commands in radians.
fn write_inputs(dir: &Path) -> String {
    crate::common::hostile::calibrated_campaign(dir, 5);
    simulate_analytic(dir, 40, 6, "other.csv");
    let campaign = dir.join("campaign.csv");
    let all = |_: &[String]| true;
    // The third target's row of one validation pose, its commands in radians.
    let step = RefCell::new(None);
    altered_csv(&campaign, "radians-row.csv", all, |f| {
        if f[0] == "validation" && f[3] == "2" && step.borrow().is_none() {
            step.replace(Some(f[2].clone()));
            scale_fields(f, 7..13, std::f64::consts::PI / 180.0);
        }
    });
    altered_csv(&campaign, "axis3-free.csv", all, |f| {
        if f[0] == "axis3" {
            f[1] = "0".into();
        }
    });
    altered_csv(&campaign, "z-cm.csv", all, |f| scale_fields(f, 6..7, 0.1));
    altered_csv(&campaign, "x-m.csv", all, |f| scale_fields(f, 4..5, 1e-3));
    altered_csv(&campaign, "lost-pose.csv", all, |f| {
        if f[0] == "validation" && f[2] == "3" {
            f[4..7].iter_mut().for_each(|v| *v = "0".into());
        }
    });
    altered_csv(&campaign, "shifted.csv", all, |f| {
        if f[0] == "axis3" {
            f[4] = (f[4].parse::<f64>().unwrap() + 50.0).to_string();
        }
    });
    let text = std::fs::read_to_string(dir.join("cal/calibration.json")).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json["robot"]["rows"][1]["a_m"] = serde_json::json!(690.0);
    std::fs::write(dir.join("row-mm.json"), json.to_string()).unwrap();
    let files = [
        ("poses.csv", format!("{POSE_HEADER}{POSES}")),
        ("poses-twice.csv", format!("{POSE_HEADER}{POSES}{POSES}")),
        (
            "poses-empty-id.csv",
            format!("{POSE_HEADER}{}", POSES.replacen("ref", "", 1)),
        ),
        (
            "poses-newline.csv",
            format!("{POSE_HEADER}{}", POSES.replacen("ref", "\"r\nef\"", 1)),
        ),
    ];
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
    step.into_inner().expect("a validation row of target 2")
}

fn cases(step: &str) -> Vec<Case> {
    let cal = "--calibration cal/calibration.json";
    let radians_step = format!("\"validation\" step {step}");
    let mut cases = vec![
        case(
            "S2: one row of a validation pose with its commands in radians",
            "calibrate radians-row.csv --out out",
            2,
            &[
                "radians-row.csv:",
                "column `cmd_",
                "a row of the same pose",
                "look like radians",
            ],
        ),
        case(
            "S2: the same file given to validate",
            &format!("validate {cal} radians-row.csv --out out"),
            2,
            &["radians-row.csv:", "a row of the same pose"],
        ),
        case(
            "S3: experiment axis3 of free poses",
            "calibrate axis3-free.csv --out out",
            2,
            &[
                "axis3-free.csv:",
                "column `moved_joint`",
                "names joint 3",
                "moved_joint is 0",
            ],
        ),
        case(
            "S5: --payload-kg with a model without a payload",
            &format!("compensate {cal} --poses poses.csv --out out.csv --payload-kg 5"),
            0,
            &["warning: --payload-kg 5 has no effect", "no payload term"],
        ),
        case(
            "S7: another campaign of the same plan given to report",
            &format!("report {cal} --data other.csv --out out"),
            2,
            &["other.csv: not the data", "`data_digest`", "--allow-other-data"],
        ),
        case(
            "S7: one experiment shifted by 50 mm given to report",
            &format!("report {cal} --data shifted.csv --out out"),
            2,
            &["shifted.csv: not the data", "`data_digest`"],
        ),
        case(
            "S12: validate with --noise-mm in metres",
            &format!("validate {cal} campaign.csv --noise-mm 0.0002 --out out"),
            2,
            &[
                "--noise-mm: 0.0002 mm is finer than any instrument",
                "looks like metres",
            ],
        ),
        case(
            "S13: a calibration row length in millimetres",
            "validate --calibration row-mm.json campaign.csv --out out",
            2,
            &["row-mm.json", "field `robot.rows[1].a_m`", "690 m", "millimetres"],
        ),
        case(
            "S23: a validation pose read as 0,0,0",
            &format!("validate {cal} lost-pose.csv --out out"),
            0,
            &[
                "warning: lost-pose.csv:",
                "outlier: experiment validation step 3",
                "validated without it",
            ],
        ),
        case(
            "S24: a pose id twice",
            &format!("compensate {cal} --poses poses-twice.csv --out out.csv"),
            2,
            &["poses-twice.csv: line 4, column id", "\"ref\" is the id of line 2 too"],
        ),
        case(
            "S24: an empty pose id",
            &format!("compensate {cal} --poses poses-empty-id.csv --out out.csv"),
            2,
            &["poses-empty-id.csv: line 2, column id", "empty"],
        ),
        case(
            "U1: only the z column in centimetres",
            "calibrate z-cm.csv --out out",
            2,
            &["z-cm.csv", "`z_mm`", "multiplied by 10", "centimetres"],
        ),
        case(
            "U2: only the x column in metres",
            "calibrate x-m.csv --out out",
            2,
            &["x-m.csv", "`x_mm`", "multiplied by 1000", "metres"],
        ),
        case(
            "U8: diagnose with --noise-mm in metres",
            "diagnose campaign.csv --noise-mm 0.0002 --out out",
            2,
            &[
                "--noise-mm: 0.0002 mm is finer than any instrument",
                "looks like metres",
            ],
        ),
        case(
            "U16: a quoted pose id holding a line break",
            &format!("compensate {cal} --poses poses-newline.csv --out out.csv"),
            2,
            &[
                "poses-newline.csv: line 2, column id",
                "quoted cell runs past the end of its line",
            ],
        ),
    ];
    cases[0].names.push(radians_step.clone());
    cases[1].names.push(radians_step);
    cases
}

#[test]
fn each_round_3a_finding_is_one_clear_error_or_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let step = write_inputs(dir.path());
    for c in cases(&step) {
        let e = run_case(dir.path(), &c);
        if c.what.starts_with("U1") || c.what.starts_with("U2") {
            assert!(!e.contains("radians"), "{}: the commands blamed: {e}", c.what);
        }
        if c.what.starts_with("S23") {
            // The warning is in the summary a script reads, and the pose is left out.
            let summary = std::fs::read_to_string(dir.path().join("out/summary.json")).unwrap();
            assert!(summary.contains("outlier: experiment validation step 3"), "{summary}");
            assert!(!e.contains("misses these data"), "{}: the model blamed: {e}", c.what);
        }
        clear_outputs(dir.path());
    }
}
