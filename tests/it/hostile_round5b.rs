//! The fifth hostile run's findings on `validate` blaming the model for slips in the data file
//! (S1, S3, S6, U8), as a table (as [`super::hostile`]): one axis experiment's command column
//! negated, in gradians or scaled by 1.2, its points frozen, shuffled among its steps, or its
//! block moved rigidly; `moved_joint` swapped between two sweeps, the tool rows labelled as a
//! sweep, a command column copied into another; every validation row shifted by a constant.
//! Each is refused naming the experiment (or the column) and the slip, never as a model miss;
//! the unaltered campaign validates as before.

use crate::common::altered_csv;
use crate::common::hostile::{Case, case, clear_outputs, run_case};
use std::path::Path;

/// `campaign.csv` with `change` applied to the rows of experiment `experiment`, as `name`.
fn experiment_altered(dir: &Path, name: &str, experiment: &'static str, change: impl Fn(&mut Vec<String>)) {
    altered_csv(
        &dir.join("campaign.csv"),
        name,
        |_| true,
        |f| {
            if f[0] == experiment {
                change(f);
            }
        },
    );
}

/// `f`'s field `i` times `factor`, plus `offset`.
fn affine(f: &mut [String], i: usize, factor: f64, offset: f64) {
    f[i] = (f[i].parse::<f64>().unwrap() * factor + offset).to_string();
}

/// `campaign.csv` with the coordinates of experiment `axis1`'s rows moved 5 steps on (cyclic;
/// reversed, a sweep symmetric about 0 is its command negated), as `scrambled-axis1.csv`.
fn scrambled(dir: &Path) {
    let text = std::fs::read_to_string(dir.join("campaign.csv")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let rows: Vec<usize> = (0..lines.len()).filter(|&i| lines[i].starts_with("axis1,")).collect();
    let xyz: Vec<Vec<String>> = rows
        .iter()
        .map(|&i| lines[i].split(',').skip(4).take(3).map(String::from).collect())
        .collect();
    let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    for (k, &i) in rows.iter().enumerate() {
        let mut f: Vec<String> = lines[i].split(',').map(String::from).collect();
        f.splice(4..7, xyz[(k + 5) % rows.len()].clone());
        out[i] = f.join(",");
    }
    std::fs::write(dir.join("scrambled-axis1.csv"), out.join("\n") + "\n").unwrap();
}

/// Writes the campaign, its calibration and every altered input into `dir`.
fn write_inputs(dir: &Path) {
    crate::common::hostile::calibrated_campaign(dir, 7);
    // cmd_k is field 6 + k; x, y, z are fields 4-6.
    experiment_altered(dir, "neg-axis3.csv", "axis3", |f| affine(f, 9, -1.0, 0.0));
    experiment_altered(dir, "grad-axis3.csv", "axis3", |f| affine(f, 9, 400.0 / 360.0, 0.0));
    experiment_altered(dir, "x1p2-axis3.csv", "axis3", |f| affine(f, 9, 1.2, 0.0));
    experiment_altered(dir, "frozen-axis3.csv", "axis3", |f| {
        (4..7).for_each(|i| f[i] = "100".into())
    });
    experiment_altered(dir, "z100-axis5.csv", "axis5", |f| affine(f, 6, 1.0, 100.0));
    experiment_altered(dir, "rot2-axis2.csv", "axis2", |f| {
        let (x, y): (f64, f64) = (f[4].parse().unwrap(), f[5].parse().unwrap());
        let (s, c) = 2f64.to_radians().sin_cos();
        f[4] = (c * x - s * y).to_string();
        f[5] = (s * x + c * y).to_string();
    });
    experiment_altered(dir, "shift50-validation.csv", "validation", |f| affine(f, 4, 1.0, 50.0));
    experiment_altered(dir, "tool-mj6.csv", "tool", |f| f[1] = "6".into());
    altered_csv(
        &dir.join("campaign.csv"),
        "mj-swap-34.csv",
        |_| true,
        |f| {
            f[1] = match f[1].as_str() {
                "3" => "4".into(),
                "4" => "3".into(),
                m => m.into(),
            }
        },
    );
    altered_csv(
        &dir.join("campaign.csv"),
        "cmd3-copy-cmd2.csv",
        |_| true,
        |f| f[9] = f[8].clone(),
    );
    scrambled(dir);
}

fn cases() -> Vec<Case> {
    let validate = |data: &str| format!("validate {data} --calibration cal/calibration.json --out out");
    vec![
        case(
            "S6: axis3's cmd_3 negated",
            &validate("neg-axis3.csv"),
            2,
            &[
                "neg-axis3.csv:",
                "`cmd_3`",
                "experiment axis3's",
                "(lines ",
                "is negated",
            ],
        ),
        case(
            "S1: axis3's cmd_3 in gradians",
            &validate("grad-axis3.csv"),
            2,
            &["`cmd_3`", "experiment axis3's", "holds gradians rather than degrees"],
        ),
        case(
            "S1: axis3's cmd_3 times 1.2",
            &validate("x1p2-axis3.csv"),
            2,
            &["`cmd_3`", "holds 1.2000 times", "sigma from 1"],
        ),
        case(
            "S6: axis3's points frozen",
            &validate("frozen-axis3.csv"),
            2,
            &["`x_mm,y_mm,z_mm`", "experiment axis3's", "did not follow the joint"],
        ),
        case(
            "S6: axis1's coordinates 5 steps on",
            &validate("scrambled-axis1.csv"),
            2,
            &["experiment axis1's", "not in step order"],
        ),
        case(
            "S3: axis5's block 100 mm up",
            &validate("z100-axis5.csv"),
            2,
            &["experiment axis5's", "out of place", "100.0) mm"],
        ),
        case(
            "S3: axis2's block turned 2 deg",
            &validate("rot2-axis2.csv"),
            2,
            &["experiment axis2's", "out of place", "deg and shifted"],
        ),
        case(
            "S6: every validation row x + 50 mm",
            &validate("shift50-validation.csv"),
            2,
            &["`x_mm`", "+50", "a constant added to the column"],
        ),
        case(
            "U8: held-out rows x + 50 mm",
            "report --calibration cal/calibration.json --held-out shift50-validation.csv --out out",
            2,
            &["shift50-validation.csv:", "`x_mm`", "+50"],
        ),
        case(
            "S6: the tool rows labelled moved_joint 6",
            &validate("tool-mj6.csv"),
            2,
            &["experiment tool", "single step"],
        ),
        case(
            "S6: moved_joint 3 and 4 swapped",
            &validate("mj-swap-34.csv"),
            2,
            &["rows of joint 4's sweep, not joint 3's"],
        ),
        case(
            "S6: cmd_3 a copy of cmd_2",
            &validate("cmd3-copy-cmd2.csv"),
            2,
            &["`cmd_3`", "copy of `cmd_2`"],
        ),
        case(
            "the sweep search is skipped with --skip-unit-check",
            &format!("{} --skip-unit-check", validate("neg-axis3.csv")),
            0,
            &[],
        ),
    ]
}

#[test]
fn each_round_5b_finding_names_the_slip_not_the_model() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path());
    let valid = case(
        "the campaign itself",
        "validate campaign.csv --calibration cal/calibration.json --out out",
        0,
        &[],
    );
    let e = run_case(dir.path(), &valid);
    assert!(!e.contains("skip-unit-check"), "{e}");
    clear_outputs(dir.path());
    for c in cases() {
        run_case(dir.path(), &c);
        clear_outputs(dir.path());
    }
}
