//! The third hostile run's values, as a table: joint limits in radians or metres, an empty
//! name, a centre of mass in micrometres, tool targets in metres, a truth model's row in
//! millimetres, a CSV given where TOML is read, a cut-short description record in a
//! measurement CSV, and scenarios with a noise in metres, half-ranges in radians, a sweep value
//! given twice or a coupling no sweep measures. A bad input is one error line naming the file
//! and the key, exit 2, nothing written; a simulated ISO test is not screened as user data.

use crate::common::hostile::{Case, case, clear_outputs, run_case};
use crate::common::{axiscal, simulate_analytic, stdout};
use std::path::Path;
use std::time::Duration;

fn shipped(relative: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)).unwrap()
}

/// `text` with `from` replaced once by `to`, which must be there.
fn edited(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "no {from:?} to replace");
    text.replacen(from, to, 1)
}

/// The truth template of the IRB/L6 with its second row's `a_m` written in millimetres.
fn truth_in_mm(dir: &Path) -> String {
    let a = axiscal()
        .current_dir(dir)
        .args(["describe", "asea-irb6l", "--truth-template"])
        .assert()
        .success();
    let template = stdout(&a);
    let line = template
        .lines()
        .find(|l| l.starts_with("a_m = -0.69"))
        .expect("the template's second row");
    edited(&template, line, "a_m = -690.0")
}

/// Writes every input of the table into `dir`: a simulated campaign and files made from it or
/// from shipped files with one value changed.
fn write_inputs(dir: &Path) {
    simulate_analytic(dir, 10, 5, "campaign.csv");
    let campaign = std::fs::read_to_string(dir.join("campaign.csv")).unwrap();
    let first = campaign.lines().next().unwrap();
    assert!(first.starts_with("# axiscal.description {"), "{first}");
    let cut = edited(&campaign, first, "# axiscal.description {\"name\":\"ASEA IRB/L6\",");
    let scara = shipped("scenarios/robots/scara-rrpr.toml");
    let irb = shipped("scenarios/robots/asea-irb6l.toml");
    let smoke = shipped("scenarios/ci-smoke.toml");
    let quill = "limits = [-100.0, 100.0]";
    let half = "half_range = [40.0, 30.0, 35.0, 60.0, 90.0, 90.0]";
    let noise = "net_radial_rms_mm = 0.19";
    let files = [
        ("cut.csv", cut),
        ("tt.toml", truth_in_mm(dir)),
        ("quill-m.toml", edited(&scara, quill, "limits = [-0.1, 0.1]")),
        ("quill-um.toml", edited(&scara, quill, "limits = [0.0, 0.001]")),
        (
            "rad.toml",
            edited(&scara, "limits = [-130.0, 130.0]", "limits = [-2.27, 2.27]"),
        ),
        (
            "unnamed.toml",
            edited(&scara, "name = \"SCARA R-R-P-R\"", "name = \"\""),
        ),
        (
            "targets-m.toml",
            edited(
                &scara,
                "targets_mm = [[60.0, 0.0, 0.0], [0.0, 60.0, 0.0], [-50.0, -40.0, 10.0]]",
                "targets_mm = [[0.06, 0.0, 0.0], [0.0, 0.06, 0.0], [-0.05, -0.04, 0.01]]",
            ),
        ),
        (
            "com.toml",
            edited(&irb, "com_mm = [-345.0, 0.0, 0.0]", "com_mm = [175000.0, 0.0, 0.0]"),
        ),
        ("noise-m.toml", edited(&smoke, noise, "net_radial_rms_mm = 0.00019")),
        (
            "half-rad.toml",
            edited(&smoke, half, "half_range = [0.7, 0.52, 0.61, 1.05, 1.57, 1.57]"),
        ),
        (
            "twice.toml",
            format!("{smoke}\n[sweep]\nnet_radial_rms_mm = [0.1, 0.1]\n"),
        ),
        (
            "uncoupled.toml",
            format!("{smoke}\n[[plan.sweeps]]\njoint = 2\nspan = 60.0\nintervals = 15\n"),
        ),
    ];
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
}

/// The descriptions, truth models and measurement files of the table.
fn file_cases() -> Vec<Case> {
    vec![
        case(
            "S9: a sliding joint's limits in metres",
            "describe quill-m.toml",
            2,
            &[
                "quill-m.toml",
                "`joints[2].limits`",
                "0.2 mm",
                "metres",
                "[-100, 100] mm?",
                "--skip-unit-check",
            ],
        ),
        case(
            "S9: a sliding joint's limits of 1 um",
            "simulate --robot quill-um.toml --out out.csv",
            2,
            &["quill-um.toml", "`joints[2].limits`", "metres"],
        ),
        case(
            "S9: a revolute joint's limits in radians",
            "describe rad.toml",
            2,
            &[
                "rad.toml",
                "`joints[0].limits`",
                "4.54 deg",
                "radians",
                "[-130.06, 130.06] deg?",
            ],
        ),
        case(
            "S9: a real narrow joint passes",
            "describe rad.toml --skip-unit-check",
            0,
            &[],
        ),
        case(
            "S20: an empty name",
            "describe unnamed.toml",
            2,
            &["unnamed.toml", "field `name`", "empty"],
        ),
        case(
            "S21: a centre of mass 175 m from its link",
            "describe com.toml",
            2,
            &["com.toml", "`joints[1].com_mm`", "175000 mm from its link"],
        ),
        case(
            "S22: a cut-short description record",
            "calibrate cut.csv --out out",
            2,
            &[
                "cut.csv:1",
                "`# axiscal.description` line",
                "cut short",
                "restore the line",
            ],
        ),
        case(
            "U3: tool targets in metres",
            "describe targets-m.toml",
            2,
            &["targets-m.toml", "field `tool.targets_mm`", "within 0.1", "metres"],
        ),
        case(
            "U9: a truth model's row in millimetres",
            "simulate --sim analytic --truth tt.toml --out out.csv",
            2,
            &["tt.toml", "`rows[1].a_m`", "(-0.69 m?)"],
        ),
        case(
            "U17: a CSV given to --truth",
            "simulate --truth campaign.csv --out out.csv",
            2,
            &["campaign.csv", "this is a CSV table", "experiment,moved_joint"],
        ),
        case(
            "U17: a CSV given to --effects",
            "simulate --effects campaign.csv --out out.csv",
            2,
            &["campaign.csv", "this is a CSV table"],
        ),
        case(
            "U17: a CSV given to describe",
            "describe campaign.csv",
            2,
            &["campaign.csv", "this is a CSV table"],
        ),
        case(
            "U17: a CSV given as a scenario",
            "run campaign.csv --out out",
            2,
            &["campaign.csv", "this is a CSV table"],
        ),
    ]
}

/// The scenarios of the table.
fn scenario_cases() -> Vec<Case> {
    vec![
        case(
            "S10: a scenario noise in metres",
            "run noise-m.toml --trials 1 --out out",
            2,
            &[
                "noise-m.toml",
                "`measurement.net_radial_rms_mm`",
                "0.00019 mm",
                "metres (0.19 mm?)",
                "--skip-unit-check",
            ],
        ),
        case(
            "S11: validation half-ranges in radians",
            "run half-rad.toml --trials 1 --out out",
            2,
            &[
                "half-rad.toml",
                "`validation.half_range`",
                "radians",
                "1.57 rad is 90.0 deg",
            ],
        ),
        case(
            "S19: a sweep value given twice",
            "run twice.toml --trials 1 --out out",
            2,
            &["twice.toml", "key `sweep.net_radial_rms_mm`", "0.1 is given twice"],
        ),
        case(
            "U5: a coupled joint swept without its second target",
            "run uncoupled.toml --trials 1 --out out",
            2,
            &[
                "uncoupled.toml",
                "key `plan.sweeps[0].second_target`",
                "joint 2",
                "second_target = true",
            ],
        ),
    ]
}

#[test]
fn every_hostile_value_of_round_three_is_one_clear_error_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path());
    let mut cases = file_cases();
    cases.extend(scenario_cases());
    for c in cases {
        run_case(dir.path(), &c);
        clear_outputs(dir.path());
    }
}

/// U6: a scenario with an empty `[iso9283]` table (its defaults) runs every trial: the
/// simulated cycles are not screened for gross errors as a measured file's are (trial 2 of
/// this scenario used to fail on the screen, in its prediction's simulated test 81).
#[test]
fn a_scenario_iso_test_with_defaults_fails_no_trial() {
    let dir = tempfile::tempdir().unwrap();
    let smoke = shipped("scenarios/ci-smoke.toml");
    let scenario = edited(&smoke, "[truth]", "[iso9283]\n\n[truth]");
    std::fs::write(dir.path().join("iso.toml"), scenario).unwrap();
    let a = axiscal()
        .current_dir(dir.path())
        .args(["run", "iso.toml", "--trials", "3", "--out", "out"])
        .timeout(Duration::from_secs(600))
        .assert()
        .success();
    let e = crate::common::stderr(&a);
    assert!(!e.contains("failed"), "{e}");
}
