//! Helper h10e: `validate` named no cause when a file carried two slips at once (a command
//! column and the coordinates scaled together) or a slip in a block of consecutive free poses
//! (shifted, scaled, one command offset), and blamed the model: "the calibrated model misses
//! these data ... model error beyond the prediction 6.6047 mm RMS", exit 0 (hostile run 9,
//! Part A U1). The greedy search of `diagnosis::combined_slips` now names them, and a clean
//! second file of the same robot still validates without a word of a slip.

use crate::common::altered_csv;
use crate::common::hostile::{case, clear_outputs, run_case};
use std::path::Path;

/// The robot description of the shipped scenarios named `name`.
fn robot(name: &str) -> String {
    format!("{}/scenarios/robots/{name}.toml", env!("CARGO_MANIFEST_DIR"))
}

/// `simulate --sim analytic` of the SCARA with its scenario's true robot (`--truth`), 40
/// validation poses, seed `seed`, as `out` in `dir`.
fn simulate_truth(dir: &Path, seed: u64, out: &str) {
    crate::common::axiscal()
        .current_dir(dir)
        .args(["simulate", "--sim", "analytic", "--validation-poses", "40", "--robot"])
        .arg(robot("scara-rrpr"))
        .arg("--truth")
        .arg(robot("scara-rrpr-truth"))
        .args(["--seed", &seed.to_string(), "--out", out])
        .assert()
        .success();
}

/// `a.csv` (seed 1041) and its calibration `cal/`, `b.csv` (seed 1042) of the same true robot,
/// and `b.csv`'s slipped copies.
fn write_inputs(dir: &Path) {
    simulate_truth(dir, 1041, "a.csv");
    simulate_truth(dir, 1042, "b.csv");
    crate::common::axiscal()
        .current_dir(dir)
        .args(["calibrate", "a.csv", "--robot"])
        .arg(robot("scara-rrpr"))
        .args(["--out", "cal"])
        .assert()
        .success();
    let b = dir.join("b.csv");
    let all = |_: &[String]| true;
    // Fields: experiment, moved_joint, step, target, x_mm, y_mm, z_mm, cmd_1, ...
    altered_csv(&b, "two.csv", all, |f| {
        crate::common::scale_fields(f, 7..8, 1.03);
        crate::common::scale_fields(f, 4..7, 1.003);
    });
    altered_csv(&b, "block.csv", all, |f| {
        if f[0] == "validation" && f[2].parse::<usize>().unwrap() >= 20 {
            f[4] = (f[4].parse::<f64>().unwrap() + 2.0).to_string();
        }
    });
}

/// The validation of `data` against `cal/` (the SCARA).
fn validate_args(data: &str) -> String {
    format!(
        "validate {data} --robot {} --calibration cal/calibration.json --out out",
        robot("scara-rrpr")
    )
}

/// `cmd_1` 1.03 times and every coordinate 1.003 times in every row: both named, with the
/// file passing every test once both are undone (was: exit 0, "model error beyond the
/// prediction").
#[test]
fn two_slips_at_once_are_named() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path());
    let c = case(
        "cmd_1 scaled 1.03 and the coordinates 1.003 in every row",
        &validate_args("two.csv"),
        2,
        &[
            "two.csv:",
            "2 slips undone",
            "`cmd_1` of every row of the file holds 1.0",
            "read 1.00",
        ],
    );
    let e = run_case(dir.path(), &c);
    assert!(!e.contains("model error beyond"), "{e}");
    clear_outputs(dir.path());
}

/// `x_mm` 2 mm more in the validation poses of steps 20-39: the block and its shift named
/// (was: exit 0, "the calibrated model misses these data").
#[test]
fn a_block_of_shifted_free_poses_is_named() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path());
    let c = case(
        "x_mm + 2 mm in the validation poses of steps 20-39",
        &validate_args("block.csv"),
        2,
        &[
            "block.csv:",
            "`x_mm,y_mm,z_mm`",
            "poses of steps 20-39",
            "sit shifted by (1.9",
        ],
    );
    run_case(dir.path(), &c);
    clear_outputs(dir.path());
}

/// The clean second file of the same true robot: validated (exit 0) with no slip said.
#[test]
fn a_clean_second_file_names_no_slip() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path());
    let a = crate::common::axiscal()
        .current_dir(dir.path())
        .args(validate_args("b.csv").split_whitespace())
        .assert()
        .success();
    let text = crate::common::stdout(&a) + &crate::common::stderr(&a);
    assert!(!text.contains("slip"), "{text}");
}
