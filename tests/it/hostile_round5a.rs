//! The fifth hostile run's findings on calibrating a file of free poses, as a table (as
//! [`super::hostile`]): a command column negated, in gradians or radians, two command columns
//! swapped, the coordinates mirrored, the tool target ids in another order (in every pose, in
//! some, or mirrored on a symmetric target set) or the later poses shifted as a block are
//! named with the column, where the free-pose fit used to absorb them silently or blame the
//! description; a clean free-pose file gets none of these warnings.

use crate::common::hostile::{Case, case, clear_outputs, run_case};
use crate::common::{altered_csv, scale_fields};
use std::path::Path;

/// `campaign.csv`'s validation rows only, with `change` applied, written as `name`.
fn free_poses(dir: &Path, name: &str, change: impl Fn(&mut Vec<String>)) {
    altered_csv(&dir.join("campaign.csv"), name, |f| f[0] == "validation", change);
}

/// The target ids `map` (from, to) applied to the rows from step `from` on.
fn renumber(f: &mut [String], map: &[(&str, &str)], from: usize) {
    if f[2].parse::<usize>().unwrap() >= from
        && let Some((_, to)) = map.iter().find(|(a, _)| *a == f[3])
    {
        f[3] = (*to).into();
    }
}

/// Writes the campaign and every altered free-pose file into `dir`.
fn write_inputs(dir: &Path) {
    crate::common::simulate_analytic(dir, 40, 5, "campaign.csv");
    // cmd_k is field 6 + k; x_mm, y_mm are fields 4, 5.
    free_poses(dir, "fp.csv", |_| {});
    free_poses(dir, "neg-cmd2.csv", |f| scale_fields(f, 8..9, -1.0));
    free_poses(dir, "grad-cmd1.csv", |f| scale_fields(f, 7..8, 400.0 / 360.0));
    free_poses(dir, "rad-cmd1.csv", |f| {
        scale_fields(f, 7..8, std::f64::consts::PI / 180.0)
    });
    free_poses(dir, "swap-cmd23.csv", |f| f.swap(8, 9));
    free_poses(dir, "swap-xy.csv", |f| f.swap(4, 5));
    free_poses(dir, "tswap01.csv", |f| renumber(f, &[("0", "1"), ("1", "0")], 0));
    free_poses(dir, "tswap12.csv", |f| renumber(f, &[("1", "2"), ("2", "1")], 0));
    free_poses(dir, "tswap01-late.csv", |f| renumber(f, &[("0", "1"), ("1", "0")], 30));
    free_poses(dir, "shift-half.csv", |f| {
        if f[2].parse::<usize>().unwrap() >= 20 {
            f[4] = (f[4].parse::<f64>().unwrap() + 50.0).to_string();
        }
    });
}

fn cases() -> Vec<Case> {
    vec![
        case(
            "cmd_2 negated (S5: silent, 596 mm wrong)",
            "calibrate neg-cmd2.csv --out out",
            0,
            &["`cmd_2` is negated", "calibration.json is wrong"],
        ),
        case(
            "cmd_1 in gradians (S1-fp: silent, 30 mm wrong)",
            "calibrate grad-cmd1.csv --out out",
            0,
            &["`cmd_1` holds gradians rather than degrees"],
        ),
        case(
            "cmd_2 and cmd_3 swapped (S5: silent)",
            "calibrate swap-cmd23.csv --out out",
            0,
            &["`cmd_2` and `cmd_3` are swapped"],
        ),
        case(
            "cmd_1 in radians (U2: blamed on the description)",
            "calibrate rad-cmd1.csv --out out",
            2,
            &["`cmd_1` holds radians rather than degrees", "fix `cmd_1`"],
        ),
        case(
            "x and y swapped (U2: blamed on the description)",
            "calibrate swap-xy.csv --out out",
            2,
            &["fit a mirror image of the description's robot", "left-handed"],
        ),
        case(
            "target ids 0 and 1 swapped (S4: silent, 64 mm wrong)",
            "calibrate tswap01.csv --out out",
            0,
            &[
                "in every one of its 40 free poses",
                "target ids read as (0 is 1, 1 is 0)",
            ],
        ),
        case(
            "target ids 1 and 2 swapped on a symmetric target set (S4: silent, 92 mm wrong)",
            "calibrate tswap12.csv --out out",
            0,
            &["targets_mm` turns 1", "read as 1 is 2, 2 is 1", "mirror image"],
        ),
        case(
            "target ids 0 and 1 swapped from step 30 on (refused, blamed on the description; now the fit with the IRB/L6's gear forms converges and the ids are a warning, as in every pose)",
            "calibrate tswap01-late.csv --out out",
            0,
            &["lines ", "(10 of its 40 free poses)", "(0 is 1, 1 is 0)"],
        ),
        case(
            "the poses from step 20 on shifted 50 mm in x (S3-fp: silent, 27 mm wrong)",
            "calibrate shift-half.csv --out out",
            0,
            &["the poses from line 63 on (20 of 40)", "own `setup` label"],
        ),
    ]
}

#[test]
fn free_pose_slips_are_named_with_their_column() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path());
    for c in cases() {
        run_case(dir.path(), &c);
        clear_outputs(dir.path());
    }
}

#[test]
fn a_clean_free_pose_file_gets_no_slip_warning() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path());
    let e = run_case(dir.path(), &case("clean", "calibrate fp.csv --out out", 0, &[]));
    for slip in ["and calibrate again", "target ids read as", "mirror image"] {
        assert!(!e.contains(slip), "a slip said on a clean file: {e}");
    }
}
