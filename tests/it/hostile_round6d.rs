//! Round 6d of the hostile findings (run 5's S1 and S7, as a table as [`super::hostile`]):
//! `diagnose` of a campaign one of whose sweeps holds a slip (a command column in gradians,
//! scaled by 1.2 or negated) names the experiment, its lines and the column, as `validate` does
//! against a calibration, instead of ranking physical effects on the miss; on another robot
//! (the UR5e) too. A calibration file whose transmission was edited beyond what a joint's
//! transmission can be (a harmonic of 0.9 rad, a sliding joint's scale turning it back), or
//! whose sigmas were, is refused by every command that reads it when its `robot` cannot be
//! traced to `calibrate` (no `model_digest`, or one that no longer matches); a file without
//! `model_digest` is said unverifiable.

use crate::common::altered_csv;
use crate::common::hostile::{
    Case, calibrated_campaign, case, clear_outputs, edited_calibration, run_case, stderr_of_case,
};
use std::path::Path;

/// `campaign.csv` in `dir` with `factor` applied to command column `k` (1-based) of the rows of
/// experiment `experiment`, as `name`.
fn sweep_scaled(dir: &Path, source: &str, name: &str, experiment: &'static str, k: usize, factor: f64) {
    altered_csv(
        &dir.join(source),
        name,
        |_| true,
        |f| {
            if f[0] == experiment {
                f[6 + k] = (f[6 + k].parse::<f64>().unwrap() * factor).to_string();
            }
        },
    );
}

/// `diagnose DATA` with few replicas (the slip search runs before them), with `extra` options.
fn diagnose(data: &str, extra: &str) -> String {
    format!("diagnose {data} --noise-trials 4 --noise-draws 4 --axis-replicas 20 --out out {extra}")
}

#[test]
fn diagnose_names_a_sweep_slip_as_validate_does() {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    crate::common::simulate_analytic(dir, 40, 29, "campaign.csv");
    sweep_scaled(dir, "campaign.csv", "grad-axis3.csv", "axis3", 3, 400.0 / 360.0);
    sweep_scaled(dir, "campaign.csv", "x1p2-axis3.csv", "axis3", 3, 1.2);
    sweep_scaled(dir, "campaign.csv", "neg-axis1.csv", "axis1", 1, -1.0);
    crate::common::axiscal()
        .current_dir(dir)
        .args(["simulate", "--robot", "ur5e-dh", "--sim", "analytic"])
        .args(["--validation-poses", "40", "--seed", "31", "--out", "ur.csv"])
        .assert()
        .success();
    sweep_scaled(dir, "ur.csv", "ur-neg2.csv", "axis2", 2, -1.0);
    let cases: Vec<Case> = vec![
        case(
            "S1: axis3's cmd_3 in gradians",
            &diagnose("grad-axis3.csv", ""),
            2,
            &[
                "grad-axis3.csv:",
                "`cmd_3`",
                "experiment axis3's",
                "(lines ",
                "free poses (the calibration of its axis experiments misses them by",
                "holds gradians rather than degrees",
            ],
        ),
        case(
            "S1: axis3's cmd_3 times 1.2",
            &diagnose("x1p2-axis3.csv", ""),
            2,
            &[
                "`cmd_3`",
                "experiment axis3's",
                "times (+-",
                "sigma from 1",
                "the column scaled",
            ],
        ),
        case(
            "S6: axis1's cmd_1 negated",
            &diagnose("neg-axis1.csv", ""),
            2,
            &["`cmd_1`", "experiment axis1's", "(lines ", "is negated"],
        ),
        case(
            "UR5e: axis2's cmd_2 negated",
            &diagnose("ur-neg2.csv", "--robot ur5e-dh"),
            2,
            &["`cmd_2`", "experiment axis2's", "is negated"],
        ),
        case(
            "the search is skipped with --skip-unit-check",
            &diagnose("grad-axis3.csv", "--skip-unit-check"),
            0,
            &[],
        ),
    ];
    for data in ["campaign.csv", "ur.csv --robot ur5e-dh"] {
        let e = run_case(dir, &case("the campaign itself", &diagnose(data, ""), 0, &[]));
        assert!(!e.contains("free poses"), "{data}: {e}");
        clear_outputs(dir);
    }
    for c in cases {
        refused_after_warnings(dir, &c);
        clear_outputs(dir);
    }
}

/// Runs `c` in `dir` ([`run_case`]'s checks, but the refusal may follow warnings: the sign's
/// slip is also warned of by the sweeps' calibration): the exit code, the names in stderr, the
/// refusal on its last line and nothing written.
fn refused_after_warnings(dir: &Path, c: &Case) {
    let e = stderr_of_case(dir, c);
    if c.code == 2 {
        let last = e.lines().last().unwrap_or_default();
        assert!(last.starts_with("error: "), "{}: {e}", c.what);
        assert!(
            e.lines().filter(|l| l.starts_with("error: ")).count() == 1,
            "{}: {e}",
            c.what
        );
        assert!(!dir.join("out").exists(), "{}: nothing written", c.what);
    }
}

#[test]
fn an_implausible_calibration_is_refused_whatever_its_age() {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    calibrated_campaign(dir, 33);
    // S7: a calibration written before `model_digest`, its joint-2 harmonic edited to 0.9 rad.
    edited_calibration(dir, "sin-big.json", |v| {
        v["robot"]["joints"][1]["transmission"]["sin"] = serde_json::json!([0.9]);
        v.as_object_mut().unwrap().remove("model_digest");
    });
    edited_calibration(dir, "sigma-neg.json", |v| {
        v["row_sigma"][2]["beta_deg"] = (-0.5).into();
        v.as_object_mut().unwrap().remove("model_digest");
    });
    // The same harmonic in a file whose `model_digest` no longer matches: edited, refused too.
    edited_calibration(dir, "sin-big-digest.json", |v| {
        v["robot"]["joints"][1]["transmission"]["sin"] = serde_json::json!([0.9]);
    });
    edited_calibration(dir, "old.json", |v| {
        v.as_object_mut().unwrap().remove("model_digest");
    });
    let poses = "id,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg\np1,-3142.3,5341.9,-26.1,180,0,0\n";
    std::fs::write(dir.join("poses.csv"), poses).unwrap();
    let harmonic = [
        "sin-big.json: field `robot.joints[1].transmission`",
        "amplitude of 0.9 rad",
        "beyond the 0.1 rad",
    ];
    let cases = [
        case(
            "S7: validate",
            "validate campaign.csv --calibration sin-big.json --out out",
            2,
            &harmonic,
        ),
        case(
            "S7: joints",
            "joints --calibration sin-big.json 10 -10 5 20 30 40",
            2,
            &harmonic,
        ),
        case(
            "S7: compensate",
            "compensate --calibration sin-big.json --poses poses.csv --out out.csv",
            2,
            &harmonic,
        ),
        case(
            "S7 with a model_digest that no longer matches",
            "joints --calibration sin-big-digest.json 10 -10 5 20 30 40",
            2,
            &[
                "sin-big-digest.json: field `robot.joints[1].transmission`",
                "amplitude of 0.9 rad",
            ],
        ),
        case(
            "a negative sigma",
            "joints --calibration sigma-neg.json 10 -10 5 20 30 40",
            2,
            &["field `row_sigma[2].beta_deg`", "-0.5"],
        ),
        case(
            "no model_digest",
            "joints --calibration old.json 10 -10 5 20 30 40",
            0,
            &["old.json: records no `model_digest`", "cannot be told"],
        ),
    ];
    for c in cases {
        run_case(dir, &c);
        clear_outputs(dir);
    }
    let quiet = run_case(
        dir,
        &case(
            "as written",
            "joints --calibration cal/calibration.json 10 -10 5 20 30 40",
            0,
            &[],
        ),
    );
    assert!(quiet.is_empty(), "{quiet}");
}

#[test]
fn a_sliding_transmission_that_turns_back_within_the_limits_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    crate::common::axiscal()
        .current_dir(dir)
        .args(["simulate", "--robot", "table-prpp", "--sim", "analytic", "--seed", "8"])
        .args(["--out", "campaign.csv"])
        .assert()
        .success();
    crate::common::axiscal()
        .current_dir(dir)
        .args(["calibrate", "campaign.csv", "--robot", "table-prpp", "--out", "cal"])
        .assert()
        .success();
    // A scale error of -1.5: the slide moves backwards as its command grows.
    edited_calibration(dir, "backwards.json", |v| {
        v["robot"]["joints"][0]["transmission"]["c"] = serde_json::json!([-1.5]);
    });
    run_case(
        dir,
        &case(
            "a polynomial turning back",
            "validate campaign.csv --robot table-prpp --calibration backwards.json --out out",
            2,
            &[
                "field `robot.joints[0].transmission`",
                "within joint 1's limits [-300, 300] mm",
                "turns back",
            ],
        ),
    );
}
