//! Hand-edited `calibration.json` files (hostile run 70): a key given twice was read as its
//! last value; a gear ratio of a million, a coupling's ratio of a billion and a backlash
//! half band of 5 rad, or two backlash entries for one joint, were used as written. Each is now
//! one error naming the file and the key's path, exit 2, from every command that reads a
//! calibration.

use crate::common::hostile::{calibrated_campaign, case, clear_outputs, edited_calibration, run_case};
use serde_json::json;

#[test]
fn an_edited_calibrations_ratio_band_or_repeated_key_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    calibrated_campaign(dir, 70);
    // The paper robot's joint 5 is geared (ratio 1.684), joint 4 couples to 5 by a gear.
    edited_calibration(dir, "ratio.json", |v| {
        v["robot"]["joints"][4]["transmission"]["ratio"] = json!(1e6);
    });
    edited_calibration(dir, "tiny-ratio.json", |v| {
        v["robot"]["joints"][4]["transmission"]["ratio"] = json!(1e-300);
    });
    edited_calibration(dir, "coupling.json", |v| {
        v["robot"]["joints"][4]["coupling_in"]["ratio"] = json!(1e9);
    });
    edited_calibration(dir, "band.json", |v| {
        v["robot"]["effects"] = json!({ "backlash": [{ "joint": 2, "half_band": 5.0 }] });
    });
    edited_calibration(dir, "twice.json", |v| {
        let b = json!({ "joint": 2, "half_band": 1e-3 });
        v["robot"]["effects"] = json!({ "backlash": [b, b] });
    });
    // A key given twice: the text of the file as written, `reference_cmd` repeated at its end.
    let text = std::fs::read_to_string(dir.join("cal/calibration.json")).unwrap();
    let end = text.rfind('}').unwrap();
    let repeated = format!(
        "{},\n  \"reference_cmd\": [0, 0, 0, 0, 0, 0]\n}}\n",
        text[..end].trim_end()
    );
    std::fs::write(dir.join("repeated.json"), &repeated).unwrap();
    let repeated_line = repeated.lines().count() - 1;
    let line = format!("repeated.json: not a calibration JSON: line {repeated_line}, ");
    let joints = |file: &str| format!("joints --calibration {file} 10 -10 5 20 30 40");
    let cases = [
        case(
            "a gear ratio of 1e6",
            &joints("ratio.json"),
            2,
            &["field `robot.joints[4].transmission`", "at most 1000"],
        ),
        case(
            "a gear ratio of 1e-300",
            &joints("tiny-ratio.json"),
            2,
            &["field `robot.joints[4].transmission`", "from 0.001 to 1000"],
        ),
        case(
            "a coupling's ratio of 1e9",
            &joints("coupling.json"),
            2,
            &["field `robot.joints[4].coupling_in`", "at most 1000"],
        ),
        case(
            "a half band of 5 rad",
            &joints("band.json"),
            2,
            &["field `robot.effects.backlash[0].half_band`", "within +-0.05"],
        ),
        case(
            "two backlash entries for joint 2",
            &joints("twice.json"),
            2,
            &["field `robot.effects.backlash[1].joint`", "one per joint"],
        ),
        case(
            "reference_cmd given twice",
            &joints("repeated.json"),
            2,
            &[line.as_str(), "key `reference_cmd`", "given twice"],
        ),
        case(
            "reference_cmd given twice, validate",
            "validate campaign.csv --calibration repeated.json --out out",
            2,
            &[line.as_str(), "given twice"],
        ),
    ];
    for c in cases {
        run_case(dir, &c);
        clear_outputs(dir);
    }
    // The file as written reads (each case above differs from it in its edit only).
    run_case(
        dir,
        &case("the file as written", &joints("cal/calibration.json"), 0, &[]),
    );
}
