//! The fourth hostile run's findings on the data `calibrate` reads, as a table (as
//! [`super::hostile`]): one experiment's command column scaled (doubled, halved) or
//! every row's offset by a quarter turn, one experiment's coordinate column in centimetres, a
//! tool target off, a row longer than the header (a decimal comma), files that are no CSV, and
//! a calibration of one joint. A bad input is one error line naming the file, the experiment
//! and the column, exit 2, nothing written; a suspicious one a `warning:`.

use crate::common::hostile::{Case, calibrated_campaign, case, clear_outputs, run_case};
use crate::common::{altered_csv, scale_fields};
use std::path::Path;

/// Writes the campaign, its calibration and every altered input into `dir`.
fn write_inputs(dir: &Path) {
    calibrated_campaign(dir, 5);
    let campaign = dir.join("campaign.csv");
    let all = |_: &[String]| true;
    let in_experiment = |name: &'static str, column: usize, factor: f64| {
        move |f: &mut Vec<String>| {
            if f[0] == name {
                scale_fields(f, column..column + 1, factor);
            }
        }
    };
    // cmd_k is field 6 + k.
    altered_csv(&campaign, "half-5.csv", all, in_experiment("axis5", 11, 0.5));
    altered_csv(&campaign, "double-6.csv", all, in_experiment("axis6", 12, 2.0));
    altered_csv(
        &campaign,
        "mrad-2.csv",
        all,
        in_experiment("axis2", 8, 1e3 * 1f64.to_radians()),
    );
    altered_csv(&campaign, "cm-x-2.csv", all, in_experiment("axis2", 4, 0.1));
    altered_csv(&campaign, "cm-y-2.csv", all, in_experiment("axis2", 5, 0.1));
    altered_csv(&campaign, "swap-2.csv", all, |f| {
        if f[0] == "axis2" {
            f.swap(4, 5);
        }
    });
    let offset =
        |column: usize| move |f: &mut Vec<String>| f[column] = (f[column].parse::<f64>().unwrap() + 90.0).to_string();
    altered_csv(&campaign, "off90-2.csv", all, offset(8));
    altered_csv(&campaign, "off90-3.csv", all, offset(9));
    altered_csv(&campaign, "tool-off.csv", all, |f| tool_target_off(f));
    altered_csv(&campaign, "only-axis1.csv", |f| f[0] == "axis1", |_| {});
    let text = std::fs::read_to_string(&campaign).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    lines[12].push_str(",5");
    std::fs::write(dir.join("long-row.csv"), lines.join("\n") + "\n").unwrap();
    let comma = lines.iter().position(|l| l.starts_with("axis2,")).unwrap();
    let mut cells: Vec<String> = text.lines().nth(comma).unwrap().split(',').map(str::to_owned).collect();
    cells[4] = cells[4].replacen('.', ",", 1);
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    lines[comma] = cells.join(",");
    std::fs::write(dir.join("decimal-comma.csv"), lines.join("\n") + "\n").unwrap();
    std::fs::write(dir.join("binary.csv"), (0u8..=255).collect::<Vec<u8>>()).unwrap();
    std::fs::write(dir.join("blank.csv"), "   \n\n  \n").unwrap();
    std::fs::copy(dir.join("cal/calibration.json"), dir.join("json.csv")).unwrap();
}

fn cases() -> Vec<Case> {
    vec![
        case(
            "S1: cmd_5 halved in the axis5 rows",
            "calibrate half-5.csv --out out",
            2,
            &["half-5.csv: `cmd_5`", "experiment axis5", "looks halved"],
        ),
        case(
            "S1/U4: cmd_6 doubled in the axis6 rows (was: the harmonics' slopes add up to ..)",
            "calibrate double-6.csv --out out",
            2,
            &["double-6.csv: `cmd_6`", "experiment axis6", "looks doubled"],
        ),
        case(
            "U1: cmd_2 in milliradians in the axis2 rows (was: inches)",
            "calibrate mrad-2.csv --out out",
            2,
            &["`cmd_2`", "look like milliradians"],
        ),
        case(
            "S3: x_mm in cm in the axis2 rows (the arc shifted along its axis)",
            "calibrate cm-x-2.csv --out out",
            2,
            &["cm-x-2.csv: `x_mm`", "experiment axis2", "x_mm looks like centimetres"],
        ),
        case(
            "U1: y_mm in cm in the axis2 rows (was: inches)",
            "calibrate cm-y-2.csv --out out",
            2,
            &["cm-y-2.csv: `y_mm`", "experiment axis2", "y_mm looks like centimetres"],
        ),
        case(
            "U4: x_mm and y_mm swapped in the axis2 rows (was: the data do not determine coupling 2->3 n0)",
            "calibrate swap-2.csv --out out",
            2,
            &["swap-2.csv: `x_mm,y_mm`", "experiment axis2", "look swapped"],
        ),
        case(
            "S7: cmd_2 offset by 90 deg in every row (was: the robot's size, x_mm)",
            "calibrate off90-2.csv --out out",
            2,
            &["off90-2.csv: `cmd_2`", "cmd_2 looks offset by 90 deg"],
        ),
        case(
            "U3: cmd_3 offset by 90 deg in every row (was: coordinates look like radians)",
            "calibrate off90-3.csv --out out",
            2,
            &["off90-3.csv: `cmd_3`", "cmd_3 looks offset by 90 deg"],
        ),
        case(
            "S2: one tool target 20 mm off",
            "calibrate tool-off.csv --out out",
            0,
            &["warning: the tool frame's fit", "beyond its", "tool-off.csv lines"],
        ),
        case(
            "U4: a calibration of joint 1 alone (was: covariance not positive semi-definite)",
            "calibrate only-axis1.csv --out out",
            0,
            &["joints [2, 3, 4, 5, 6] not calibrated (no axis experiment"],
        ),
        case(
            "S9: a row one field longer than the header",
            "calibrate long-row.csv --out out",
            2,
            &["long-row.csv:13:", "the row has 16 fields, the header 15"],
        ),
        case(
            "U5: a decimal comma in one cell",
            "calibrate decimal-comma.csv --out out",
            2,
            &["decimal-comma.csv:", "16 fields, the header 15", "a decimal comma"],
        ),
        case(
            "U6: random bytes",
            "calibrate binary.csv --out out",
            2,
            &["binary.csv: not a measurement CSV", "binary"],
        ),
        case(
            "U6: white space only",
            "calibrate blank.csv --out out",
            2,
            &["blank.csv: empty file"],
        ),
        case(
            "U6: a calibration.json given as the data",
            "calibrate json.csv --out out",
            2,
            &["json.csv: not a measurement CSV", "looks like JSON"],
        ),
    ]
}

#[test]
fn each_round_4a_finding_is_one_clear_error_or_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path());
    for c in cases() {
        let e = run_case(dir.path(), &c);
        if c.what.starts_with("U1") {
            assert!(!e.contains("inches") && !e.contains("like radians"), "{}: {e}", c.what);
        }
        if c.what.starts_with("S7") || c.what.starts_with("U3") {
            assert!(!e.contains("x_mm"), "{}: the coordinates blamed: {e}", c.what);
        }
        if c.what.starts_with("U4") {
            assert!(!e.contains("positive semi-definite"), "{}: {e}", c.what);
        }
        clear_outputs(dir.path());
    }
}

/// The campaign as simulated raises none of these checks: no warning, and every output.
#[test]
fn a_clean_campaign_passes_the_round_4a_checks() {
    let dir = tempfile::tempdir().unwrap();
    crate::common::simulate_analytic(dir.path(), 40, 5, "campaign.csv");
    let a = crate::common::axiscal()
        .current_dir(dir.path())
        .args(["calibrate", "campaign.csv", "--out", "out"])
        .assert()
        .success();
    let e = crate::common::stderr(&a);
    assert!(!e.contains("warning"), "{e}");
}

/// Tool target 1 moved 20 mm along x, in a row of [`altered_csv`].
fn tool_target_off(f: &mut [String]) {
    if f[0] == "tool" && f[3] == "1" {
        f[4] = (f[4].parse::<f64>().unwrap() + 20.0).to_string();
    }
}

/// Every coordinate scaled by 1.01 (an instrument's scale setting): the tool fit misses its
/// targets, and the warning reads the scale off their spacings, `1.01` within 3 of the sigma
/// it states; a target moved 20 mm (S2) fits no scale and is left a point off. Seed 5, taken
/// once (the factor's arithmetic on other poses and scales: the library's
/// `sanity::tool_spacing` tests).
#[test]
fn tool_targets_spaced_by_a_scale_are_said_as_one() {
    let seed = 5;
    let dir = tempfile::tempdir().unwrap();
    crate::common::simulate_analytic(dir.path(), 40, seed, "campaign.csv");
    let campaign = dir.path().join("campaign.csv");
    let scaled = altered_csv(&campaign, "scaled.csv", |_| true, |f| scale_fields(f, 4..7, 1.01));
    let off = altered_csv(&campaign, "tool-off.csv", |_| true, |f| tool_target_off(f));
    let said = |data: &Path| crate::common::hostile::calibrate_stderr(dir.path(), data);
    let e = said(&scaled);
    let words = "times as far apart as `[tool] targets_mm` (+- ";
    let at = e.find(words).unwrap_or_else(|| panic!("seed {seed}: {e}"));
    let factor: f64 = e[..at].rsplit(' ').nth(1).unwrap().parse().unwrap();
    let sigma: f64 = e[at + words.len()..].split(')').next().unwrap().parse().unwrap();
    assert!((factor - 1.01).abs() < 3.0 * sigma, "seed {seed}: {factor} +- {sigma}");
    let e = said(&off);
    assert!(
        e.contains("warning: the tool frame's fit") && !e.contains(words),
        "seed {seed}: {e}"
    );
}
