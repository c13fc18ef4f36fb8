//! The sixth hostile run's scale slips that a calibration of axis experiments used to absorb
//! silently (as [`super::hostile`]): one command column scaled by 5 % in every row (a SCARA's
//! elbow and wrist, a table's sliding stage), the coordinates scaled by 0.5 % (a table's
//! sliding joints all travel too far), the IRB/L6's cmd_2 scaled, which used to be named as its
//! follower cmd_3, and in files of free poses a SCARA's cmd_4 scaled and the IRB/L6's cmd_3 in
//! gradians (a sag took it); clean files of the same robots get none of these warnings.

use crate::common::hostile::{Case, case, clear_outputs, run_case};
use crate::common::{altered_csv, axiscal, scale_fields};
use std::path::Path;

/// `simulate --sim analytic` of the shipped robot `robot` (seed `seed`) as `out` in `dir`.
fn simulate(dir: &Path, robot: &str, seed: u64, out: &str) {
    let robot = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenarios/robots/{robot}.toml"));
    axiscal()
        .current_dir(dir)
        .args(["simulate", "--sim", "analytic", "--robot"])
        .arg(&robot)
        .args(["--seed", &seed.to_string(), "--out", out])
        .assert()
        .success();
}

/// `file` in `dir` with `change` applied to every row, written as `name`.
fn every_row(dir: &Path, file: &str, name: &str, change: impl Fn(&mut Vec<String>)) {
    altered_csv(&dir.join(file), name, |_| true, change);
}

/// cmd_k is field 6 + k; x_mm, y_mm, z_mm are fields 4 to 6.
fn cmd(k: usize) -> std::ops::Range<usize> {
    6 + k..7 + k
}

/// Writes the clean and altered files of the SCARA, the table and the IRB/L6 into `dir`.
fn write_inputs(dir: &Path) {
    simulate(dir, "scara-rrpr", 23, "scara.csv");
    simulate(dir, "table-prpp", 23, "table.csv");
    crate::common::simulate_analytic(dir, 20, 23, "irb.csv");
    every_row(dir, "scara.csv", "scara-cmd2.csv", |f| scale_fields(f, cmd(2), 1.05));
    every_row(dir, "scara.csv", "scara-cmd4.csv", |f| scale_fields(f, cmd(4), 0.95));
    every_row(dir, "table.csv", "table-cmd4.csv", |f| scale_fields(f, cmd(4), 0.95));
    every_row(dir, "table.csv", "table-xyz.csv", |f| scale_fields(f, 4..7, 1.005));
    every_row(dir, "irb.csv", "irb-cmd2.csv", |f| scale_fields(f, cmd(2), 1.05));
    // Free poses: the validation rows alone.
    crate::common::simulate_analytic(dir, 40, 5, "irb40.csv");
    let poses = |f: &[String]| f[0] == "validation";
    altered_csv(&dir.join("irb40.csv"), "irb-fp.csv", poses, |_| {});
    altered_csv(&dir.join("irb40.csv"), "irb-fp-grad3.csv", poses, |f| {
        scale_fields(f, cmd(3), 400.0 / 360.0)
    });
    altered_csv(&dir.join("scara.csv"), "scara-fp.csv", poses, |_| {});
    altered_csv(&dir.join("scara.csv"), "scara-fp-cmd4.csv", poses, |f| {
        scale_fields(f, cmd(4), 1.05)
    });
}

/// The robot description `robot` as an argument.
fn robot(robot: &str) -> String {
    format!("--robot {}/scenarios/robots/{robot}.toml", env!("CARGO_MANIFEST_DIR"))
}

fn cases() -> Vec<Case> {
    let (scara, table) = (robot("scara-rrpr"), robot("table-prpp"));
    vec![
        case(
            "SCARA cmd_2 x 1.05 (S1: silent, the elbow's transmission took 5 %)",
            &format!("calibrate scara-cmd2.csv {scara} --out out"),
            0,
            &[
                "joint 2 (axis2) turns 0.95",
                "`cmd_2` looks scaled by 1.04",
                "calibration.json is wrong",
            ],
        ),
        case(
            "SCARA cmd_4 x 0.95 (S1: silent)",
            &format!("calibrate scara-cmd4.csv {scara} --out out"),
            0,
            &["joint 4 (axis4) turns 1.0", "`cmd_4` looks scaled by 0.9"],
        ),
        case(
            "table cmd_4 x 0.95, a sliding stage (S1: silent)",
            &format!("calibrate table-cmd4.csv {table} --out out"),
            0,
            &[
                "joint 4 (axis4) travels 1.05",
                "`cmd_4` looks scaled by 0.9",
                "its screw's lead",
                "coordinates of axis4 alone",
            ],
        ),
        case(
            "table coordinates x 1.005 (S1: silent, every length 0.5 % long)",
            &format!("calibrate table-xyz.csv {table} --out out"),
            0,
            &[
                "the sliding joints 1, 3, 4 all travel 1.00",
                "the coordinates look scaled by 1.00",
            ],
        ),
        case(
            "IRB/L6 cmd_2 x 1.05 (U4: named as its follower cmd_3)",
            "calibrate irb-cmd2.csv --out out",
            2,
            &["column cmd_2", "cmd_2 looks scaled by 1.0500", "or cmd_3 by 0.9524"],
        ),
        case(
            "IRB/L6 free poses, cmd_3 in gradians (run 5 S1: the sag took it, 34 mm wrong)",
            "calibrate irb-fp-grad3.csv --out out",
            0,
            &["`cmd_3` holds gradians rather than degrees"],
        ),
        case(
            "SCARA free poses, cmd_4 x 1.05 (S1-fp: silent)",
            &format!("calibrate scara-fp-cmd4.csv {scara} --out out"),
            0,
            &["joint 4 (free poses) turns 0.9", "`cmd_4` scaled by 1.0"],
        ),
    ]
}

#[test]
fn scale_slips_of_axis_experiments_are_named_with_their_column() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path());
    for c in cases() {
        run_case(dir.path(), &c);
        clear_outputs(dir.path());
    }
}

/// What the checks of this module say, which a clean file must not get.
const SCALE_WORDS: [&str; 3] = ["times as far per command", "looks scaled by", "hold-still formula"];

#[test]
fn clean_files_get_no_scale_warning() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path());
    for (file, robot) in [
        ("scara.csv", robot("scara-rrpr")),
        ("table.csv", robot("table-prpp")),
        ("irb.csv", String::new()),
        ("irb-fp.csv", String::new()),
        ("scara-fp.csv", robot("scara-rrpr")),
    ] {
        let e = run_case(
            dir.path(),
            &case("clean", &format!("calibrate {file} {robot} --out out"), 0, &[]),
        );
        for words in SCALE_WORDS {
            assert!(!e.contains(words), "{file}: a scale slip said on a clean file: {e}");
        }
        clear_outputs(dir.path());
    }
}

/// The same on hand-edited copies of SScanSS-2's real table (run by `make test-real`).
mod real_sscanss2 {
    use super::*;

    /// The real table's import as `data.csv` in `dir`, and the description as an argument.
    fn real_table(dir: &Path) -> String {
        let source = crate::common::real_data("sscanss2-cpa").join("table.txt");
        crate::real_sscanss2::import_path(&source, "sscanss2-table", dir);
        format!(
            "--robot {}/scenarios/robots/real/sscanss2-table.toml",
            env!("CARGO_MANIFEST_DIR")
        )
    }

    #[test]
    #[ignore = "needs ../shared/data/real/sscanss2-cpa (run by `make test-real`)"]
    fn the_real_tables_scaled_copies_are_named_and_the_table_is_clean() {
        let dir = tempfile::tempdir().unwrap();
        let robot = real_table(dir.path());
        every_row(dir.path(), "data.csv", "xyz.csv", |f| scale_fields(f, 4..7, 1.005));
        every_row(dir.path(), "data.csv", "cmd1.csv", |f| scale_fields(f, cmd(1), 1.05));
        for c in [
            case(
                "coordinates x 1.005",
                &format!("calibrate xyz.csv {robot} --out out"),
                0,
                &["the coordinates look scaled by 1.005"],
            ),
            case(
                "cmd_1 x 1.05",
                &format!("calibrate cmd1.csv {robot} --out out"),
                0,
                &["joint 1 (joint1) travels 0.95", "`cmd_1` looks scaled by 1.05"],
            ),
        ] {
            run_case(dir.path(), &c);
            clear_outputs(dir.path());
        }
        let e = run_case(
            dir.path(),
            &case("clean", &format!("calibrate data.csv {robot} --out out"), 0, &[]),
        );
        for words in SCALE_WORDS {
            assert!(!e.contains(words), "a scale slip said on the real table: {e}");
        }
    }
}
