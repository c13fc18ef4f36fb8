//! Hostile files of the fifth round read where they enter: two measurement files joined end
//! to end, a control byte left at a file's end, and a `calibration.json` whose joint kind or
//! transmission was edited by hand.

use crate::common::hostile::{calibrated_campaign, case, clear_outputs, run_case};
use std::path::Path;

/// `campaign.csv` altered as the cases need: joined to itself (the second header kept, as
/// `cat a.csv b.csv` does), and with a DOS end-of-file byte (0x1a) on a line of its own.
fn write_joined_and_marked(dir: &Path) {
    let text = std::fs::read_to_string(dir.join("campaign.csv")).unwrap();
    std::fs::write(dir.join("joined.csv"), format!("{text}{text}")).unwrap();
    std::fs::write(dir.join("marked.csv"), format!("{text}\u{1a}\n")).unwrap();
}

/// `cal/calibration.json` with `edit` applied to its JSON value, written as `name`.
fn edited_calibration(dir: &Path, name: &str, edit: impl FnOnce(&mut serde_json::Value)) {
    let text = std::fs::read_to_string(dir.join("cal/calibration.json")).unwrap();
    let mut value: serde_json::Value = serde_json::from_str(&text).unwrap();
    edit(&mut value);
    std::fs::write(dir.join(name), serde_json::to_string(&value).unwrap()).unwrap();
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
        v["robot"]["joints"][1]["transmission"]["sin"] = serde_json::json!([0.9]);
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
