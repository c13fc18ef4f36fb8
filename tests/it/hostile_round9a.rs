//! The eighth hostile run's command columns scaled by 1.5 to 4 % that calibrate absorbed
//! silently (run 8, S1 and S7): within the old 2 % bound of a joint's slope, the fit took the
//! factor into the joint's transmission. The test is now against what a drive gives (a sigma
//! of 0.2 % on a rotary joint's slope, 0.1 % on a sliding one's) and the fit's sigma
//! combined: cmd_1 x 1.015 in sweeps and in free poses (a six-joint arm), x 1.02 in a UR5e-like
//! arm's sweeps,
//! a SCARA's cmd_4 x 1.03 with validation poses, a table's cmd_2 x 0.98, and hand-edited copies
//! of two real files (the RCT positioner's joint 1 x 1.03, SScanSS-2's table cmd_4 x 1.01) are
//! named; clean simulations of five robots and the real files are not.

use crate::common::hostile::{case, clear_outputs, run_case};
use crate::common::{altered_csv, axiscal, scale_fields};
use std::path::Path;

/// `simulate --sim analytic` of the shipped robot `robot` (seed `seed`, `poses` validation
/// poses) as `out` in `dir`.
fn simulate(dir: &Path, robot: &str, (seed, poses): (u64, usize), out: &str) {
    let robot = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenarios/robots/{robot}.toml"));
    axiscal()
        .current_dir(dir)
        .args(["simulate", "--sim", "analytic", "--robot"])
        .arg(&robot)
        .args(["--seed", &seed.to_string(), "--validation-poses", &poses.to_string()])
        .args(["--out", out])
        .assert()
        .success();
}

/// cmd_k is field 6 + k.
fn cmd(k: usize) -> std::ops::Range<usize> {
    6 + k..7 + k
}

/// The robot description `robot` as an argument.
fn robot(robot: &str) -> String {
    format!("--robot {}/scenarios/robots/{robot}.toml", env!("CARGO_MANIFEST_DIR"))
}

/// `file` in `dir` with `column` scaled by `factor` in every row (free poses only: the rows
/// of moved_joint 0, when `free`), as `name`.
fn scaled(dir: &Path, (file, name): (&str, &str), column: usize, factor: f64, free: bool) {
    let keep = |f: &[String]| !free || f[1] == "0";
    altered_csv(&dir.join(file), name, keep, |f| scale_fields(f, cmd(column), factor));
}

/// What the scale check says, which a clean file must not get.
const SCALE_WORDS: [&str; 2] = ["times as far per command", "looks scaled by"];

#[test]
fn one_command_column_scaled_by_one_and_a_half_to_four_per_cent_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    simulate(d, "ur5e-dh", (301, 0), "ur5e.csv");
    simulate(d, "arm6-dh", (302, 80), "arm6.csv");
    simulate(d, "scara-rrpr", (303, 40), "scara.csv");
    simulate(d, "table-prpp", (304, 0), "table.csv");
    scaled(d, ("ur5e.csv", "ur5e-cmd1.csv"), 1, 1.02, false);
    scaled(d, ("arm6.csv", "arm6-cmd1.csv"), 1, 1.015, false);
    scaled(d, ("arm6.csv", "arm6-fp-cmd1.csv"), 1, 1.015, true);
    scaled(d, ("scara.csv", "scara-cmd4.csv"), 4, 1.03, false);
    scaled(d, ("table.csv", "table-cmd2.csv"), 2, 0.98, false);
    for c in [
        case(
            "UR5e-like cmd_1 x 1.02, sweeps (S1: silent within 2 %; its joint 1 departs -0.34 % itself)",
            &format!("calibrate ur5e-cmd1.csv {} --out out", robot("ur5e-dh")),
            0,
            &["joint 1 (axis1) turns 0.98", "`cmd_1` looks scaled by 1.01"],
        ),
        case(
            "six-joint arm cmd_1 x 1.015, sweeps and validation poses (S1: silent)",
            &format!("calibrate arm6-cmd1.csv {} --out out", robot("arm6-dh")),
            0,
            &["joint 1 (axis1) turns 0.98", "`cmd_1` looks scaled by 1.02"],
        ),
        case(
            "six-joint arm cmd_1 x 1.015, free poses (S1: silent)",
            &format!("calibrate arm6-fp-cmd1.csv {} --out out", robot("arm6-dh")),
            0,
            &["joint 1 (free poses) turns 0.97", "`cmd_1` scaled by 1.02"],
        ),
        case(
            "SCARA cmd_4 x 1.03 with validation poses (S1: x 1.04 silent)",
            &format!("calibrate scara-cmd4.csv {} --out out", robot("scara-rrpr")),
            0,
            &["joint 4 (axis4) turns 0.96", "`cmd_4` looks scaled by 1.03"],
        ),
        case(
            "table cmd_2 x 0.98 (S1: x 0.97 silent)",
            &format!("calibrate table-cmd2.csv {} --out out", robot("table-prpp")),
            0,
            &["joint 2 (axis2) turns 1.01", "`cmd_2` looks scaled by 0.98"],
        ),
    ] {
        run_case(d, &c);
        clear_outputs(d);
    }
}

#[test]
fn clean_simulations_of_five_robots_get_no_scale_warning() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (name, seed, poses) in [
        ("ur5e-dh", 311, 0),
        ("arm7-dh", 312, 40),
        ("scara-rrpr", 313, 0),
        ("positioner-2axis", 314, 40),
        ("arm6-dh", 315, 80),
    ] {
        let clean = format!("{name}.csv");
        simulate(d, name, (seed, poses), &clean);
        let mut files = vec![clean.clone()];
        if poses == 80 {
            let free = format!("{name}-fp.csv");
            altered_csv(&d.join(&clean), &free, |f| f[1] == "0", |_| {});
            files.push(free);
        }
        for file in files {
            let what = format!("calibrate {file} {} --out out", robot(name));
            let e = run_case(d, &case("clean", &what, 0, &[]));
            for words in SCALE_WORDS {
                assert!(
                    !e.contains(words),
                    "{name} {file}: a scale slip said on a clean file: {e}"
                );
            }
            clear_outputs(d);
        }
    }
}

/// The RCT positioner's real file with joint 1 scaled (run by `make test-real`).
mod real_rct {
    use super::*;

    /// The real YAML with the first `target_joints` value of every entry (joint 1, rad)
    /// times `factor`, imported as `name` in `dir`.
    fn imported(dir: &Path, factor: f64, name: &str) {
        let source = crate::common::real_data("rct-two-axis-positioner/positioner_kinematic_measurements.yaml");
        let text = std::fs::read_to_string(source).unwrap();
        let mut out = String::new();
        let mut first = false;
        for line in text.lines() {
            match line.strip_prefix("  - ") {
                Some(value) if first => {
                    let v: f64 = value.parse().unwrap();
                    out.push_str(&format!("  - {}", v * factor));
                }
                _ => out.push_str(line),
            }
            first = line == "  target_joints:";
            out.push('\n');
        }
        std::fs::write(dir.join("rct.yaml"), out).unwrap();
        axiscal()
            .current_dir(dir)
            .args(["import", "rct", "rct.yaml", "--still-tolerance", "0.1", "--out", name])
            .args(robot("positioner-2axis").split_whitespace())
            .assert()
            .success();
    }

    #[test]
    #[ignore = "needs ../shared/data/real/rct-two-axis-positioner (run by `make test-real`)"]
    fn the_positioners_joint_1_scaled_by_three_per_cent_is_named_and_the_real_file_is_not() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        imported(d, 1.03, "x103.csv");
        imported(d, 1.0, "clean.csv");
        let positioner = robot("positioner-2axis");
        run_case(
            d,
            &case(
                "RCT joint 1 x 1.03 (S7: silent)",
                &format!("calibrate x103.csv {positioner} --out out"),
                0,
                &["joint 1 (free poses) turns 0.97", "`cmd_1` scaled by 1.0"],
            ),
        );
        clear_outputs(d);
        let e = run_case(
            d,
            &case("clean", &format!("calibrate clean.csv {positioner} --out out"), 0, &[]),
        );
        for words in SCALE_WORDS {
            assert!(!e.contains(words), "a scale slip said on the real RCT file: {e}");
        }
    }
}

/// SScanSS-2's real table with one sliding stage's column scaled (run by `make test-real`).
mod real_sscanss2 {
    use super::*;

    #[test]
    #[ignore = "needs ../shared/data/real/sscanss2-cpa (run by `make test-real`)"]
    fn the_real_tables_cmd_4_scaled_by_one_per_cent_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let source = crate::common::real_data("sscanss2-cpa").join("table.txt");
        crate::real_sscanss2::import_path(&source, "sscanss2-table", d);
        scaled(d, ("data.csv", "cmd4.csv"), 4, 1.01, false);
        let table = format!(
            "--robot {}/scenarios/robots/real/sscanss2-table.toml",
            env!("CARGO_MANIFEST_DIR")
        );
        run_case(
            d,
            &case(
                "SScanSS-2 table cmd_4 x 1.01 (silent within 1 %)",
                &format!("calibrate cmd4.csv {table} --out out"),
                0,
                &["joint 4 (joint4) travels 0.99", "`cmd_4` looks scaled by 1.0"],
            ),
        );
    }
}
