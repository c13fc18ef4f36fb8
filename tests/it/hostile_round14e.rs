//! Hostile run 13, free poses (defects 4, 7, 8 and the report's rows). A block of the IRB/L6
//! paper robot's free poses shifted by the instrument (z +2 mm from a row on, x +2 mm between
//! two rows) passed silently, the fit RMS taken as noise: it is now named by its lines (a
//! change-point test on the calibrated residuals, `free_pose/block.rs`); clean files of six
//! robots stay quiet. Five free poses (4 degrees of freedom for the noise) predicted an
//! accuracy twice too good in silence: warned now, with the numbers. The real FANUC's
//! `zero_offsets.csv` was not written (its tool point on joint 6's axis kept the fit from
//! converging): written now, joint 6 named. A free-pose `report.json` listed its rows "(no
//! sigma)": they carry the model covariance's sigma, checked against the fitted parameters'
//! own sigmas (a second path: those are the fit's covariance, the rows its central-difference
//! propagation).

use crate::common::hostile::{case, run_case};
use crate::common::{altered_csv, axiscal};
use std::cell::Cell;
use std::path::{Path, PathBuf};

/// The shipped description of `robot`.
fn robot(name: &str) -> String {
    format!("{}/scenarios/robots/{name}.toml", env!("CARGO_MANIFEST_DIR"))
}

/// The `moved_joint = 0` rows of `simulate --validation-poses poses --seed seed` of `name`
/// (`asea-irb6l`: the paper robot with the rapier simulation, as `simulate` runs it by
/// default; any other: `--sim analytic`) as `fp_<name>_<seed>.csv` in `dir`.
fn free_poses(dir: &Path, name: &str, seed: u64, poses: usize) -> PathBuf {
    let source = format!("src_{name}_{seed}.csv");
    let mut cmd = axiscal();
    cmd.current_dir(dir)
        .args(["simulate", "-q", "--validation-poses", &poses.to_string()]);
    cmd.args(["--seed", &seed.to_string(), "--out", &source, "--force"]);
    if name != "asea-irb6l" {
        cmd.args(["--sim", "analytic", "--robot", &robot(name)]);
    }
    cmd.assert().success();
    altered_csv(
        &dir.join(source),
        &format!("fp_{name}_{seed}.csv"),
        |f| f[1] == "0",
        |_| {},
    )
}

/// `file` with `delta` added to coordinate `axis` (0-2: x, y, z) of the data rows `rows`
/// (1-based, in file order), as `name`.
fn shifted(file: &Path, name: &str, axis: usize, delta: f64, rows: std::ops::RangeInclusive<usize>) -> PathBuf {
    let row = Cell::new(0);
    altered_csv(
        file,
        name,
        |_| true,
        |f| {
            row.set(row.get() + 1);
            if rows.contains(&row.get()) {
                f[4 + axis] = (f[4 + axis].parse::<f64>().unwrap() + delta).to_string();
            }
        },
    )
}

/// The first integer after `after` in `text`.
fn number_after(text: &str, after: &str) -> Option<u64> {
    let rest = &text[text.find(after)? + after.len()..];
    rest.split(|c: char| !c.is_ascii_digit()).next()?.parse().ok()
}

/// Defect 4: the paper robot's free poses (seed 1, the rule's tuning seed, and seed 2) with the
/// instrument bumped z +2 mm from data row 120 on, and x +2 mm over rows 60-150: each block is
/// named, its first line within the pose of the first row moved (a pose has up to three rows;
/// the header and the description line come first), the middle block with its last line too.
#[test]
fn paper_robot_blocks_are_named_by_line() {
    let dir = tempfile::tempdir().unwrap();
    for seed in [1, 2] {
        let clean = free_poses(dir.path(), "asea-irb6l", seed, 150);
        let z = shifted(&clean, "z.csv", 2, 2.0, 120..=usize::MAX);
        let args = format!("calibrate {} --out out --force", z.display());
        let e = run_case(
            dir.path(),
            &case("z +2 mm from row 120", &args, 0, &["sit about", "from line"]),
        );
        let first = number_after(&e, "the free poses from line ").expect("a line");
        assert!(first.abs_diff(122) <= 3, "seed {seed}: from line {first}: {e}");
        let x = shifted(&clean, "x.csv", 0, 2.0, 60..=150);
        let args = format!("calibrate {} --out out --force", x.display());
        let e = run_case(
            dir.path(),
            &case("x +2 mm rows 60-150", &args, 0, &["sit about", "of lines"]),
        );
        let first = number_after(&e, "the free poses of lines ").expect("a line");
        let last = number_after(&e, &format!("of lines {first}-")).expect("a last line");
        assert!(
            first.abs_diff(62) <= 3 && last.abs_diff(152) <= 3,
            "seed {seed}: {first}-{last}: {e}"
        );
    }
}

/// Clean free poses of six robots (the paper robot with its four-bar and bevel-gear wrist in the
/// rapier simulation, five analytic ones) stay quiet: no block, no few-degrees-of-freedom
/// warning.
#[test]
fn clean_free_poses_name_no_block() {
    let dir = tempfile::tempdir().unwrap();
    for name in [
        "asea-irb6l",
        "arm6-dh",
        "ur5e-dh",
        "scara-rrpr",
        "table-prpp",
        "positioner-2axis",
    ] {
        let file = free_poses(dir.path(), name, 3, 120);
        let mut args = format!("calibrate {} --out out --force", file.display());
        if name != "asea-irb6l" {
            args += &format!(" --robot {}", robot(name));
        }
        let e = run_case(dir.path(), &case("clean free poses", &args, 0, &[]));
        assert!(
            !e.contains("sit about") && !e.contains("degrees of freedom"),
            "{name}: a false alarm: {e}"
        );
    }
}

/// Defect 7: the first 10 rows (5 poses) of arm6-dh free poses leave 4 degrees of freedom for
/// 26 parameters: warned with the degrees of freedom, the noise interval and the poses needed.
#[test]
fn few_free_poses_are_warned_with_the_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let clean = free_poses(dir.path(), "arm6-dh", 1, 150);
    let row = Cell::new(0);
    let few = altered_csv(
        &clean,
        "few.csv",
        |_| {
            row.set(row.get() + 1);
            row.get() <= 10
        },
        |_| {},
    );
    let args = format!(
        "calibrate {} --robot {} --out out --force",
        few.display(),
        robot("arm6-dh")
    );
    let e = run_case(
        dir.path(),
        &case(
            "5 free poses",
            &args,
            0,
            &["degrees of freedom (10 points", "measure about"],
        ),
    );
    let dof = number_after(&e, "the fit leaves ").expect("degrees of freedom");
    assert!(dof < 8, "{dof} degrees of freedom: {e}");
}

/// Each row finding of `report.json` in `out` that has a sigma equals the fitted parameter's own
/// sigma in `calibration.json`'s `free_poses.parameters` (`rowI.a`, `rowI.alpha`, ...) to 1e-3
/// relative; returns the row findings checked. No row finding lacks a sigma.
fn row_sigmas_match(out: &Path) -> usize {
    let read = |f: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(out.join(f)).unwrap()).unwrap()
    };
    let (report, cal) = (read("report.json"), read("calibration.json"));
    let parameters = cal["free_poses"]["parameters"].as_array().unwrap();
    let mut checked = 0;
    for f in report["findings"].as_array().unwrap() {
        let subject = f["subject"].as_str().unwrap();
        let Some(rest) = subject.strip_prefix("row ") else {
            continue;
        };
        let (row, scalar) = rest.split_once(": ").unwrap();
        let sigma = f["sigma"].as_f64().unwrap_or_else(|| panic!("{subject}: no sigma"));
        let name = format!("row{row}.{scalar}");
        let p = parameters.iter().find(|p| p["name"] == name.as_str()).expect(&name);
        let (own, unit) = (p["sigma"].as_f64().unwrap(), p["unit"].as_str().unwrap());
        let own = match unit {
            "mm" => own,
            "mrad" => (own * 1e-3).to_degrees(),
            other => panic!("{name}: unit {other}"),
        };
        assert!((sigma - own).abs() <= 1e-3 * own, "{subject}: {sigma} against {own}");
        assert!(!f["text"].as_str().unwrap().contains("no sigma"), "{subject}");
        checked += 1;
    }
    checked
}

/// The report's rows on a clean simulated arm6-dh file and the paper robot: every row listed has
/// its sigma, the parameter's own.
#[test]
fn free_pose_report_rows_carry_their_sigma() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["arm6-dh", "asea-irb6l"] {
        let file = free_poses(dir.path(), name, 4, 100);
        let mut args = format!("calibrate {} --out out --force", file.display());
        if name != "asea-irb6l" {
            args += &format!(" --robot {}", robot(name));
        }
        run_case(dir.path(), &case("clean free poses", &args, 0, &[]));
        assert!(row_sigmas_match(&dir.path().join("out")) > 4, "{name}: rows listed");
    }
}

/// Defect 8 and the real FANUC's 1 mm z block (defect 4): the documented calibration writes
/// `zero_offsets.csv` (joint 6 named: confounded with the targets the free-pose calibration
/// fitted off its axis, the description's tool point being on it; h16v), no block on the file as
/// recorded, its rows with their sigmas; z +1 mm from data row 400 on is named from its first
/// line (403, the pose of row 400; the block's end is read at line 633, where the file's own
/// drift of about 0.07 mm over its second half meets it), not as a z scale.
#[test]
#[ignore = "needs ../shared/data/real/fanuc-r2000ic-tracker (run by `make test-real`)"]
fn real_fanuc_zero_offsets_rows_and_a_block() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("fanuc.csv");
    let desc = crate::common::import_real_fanuc(&data);
    let args = format!(
        "calibrate {} --robot {} --out out --force",
        data.display(),
        desc.display()
    );
    let e = run_case(dir.path(), &case("real FANUC", &args, 0, &[]));
    assert!(!e.contains("not converged") && !e.contains("sit about"), "{e}");
    let offsets = std::fs::read_to_string(dir.path().join("out/zero_offsets.csv")).unwrap();
    assert!(
        offsets.contains("# joint 6: its offset is confounded with the tool targets' positions"),
        "{offsets}"
    );
    assert!(row_sigmas_match(&dir.path().join("out")) > 4);
    let z = shifted(&data, "z.csv", 2, 1.0, 400..=usize::MAX);
    let args = format!("calibrate {} --robot {} --out out --force", z.display(), desc.display());
    let e = run_case(
        dir.path(),
        &case("z +1 mm from row 400", &args, 0, &["sit about", " 403"]),
    );
    assert!(!e.contains("reads 1.0"), "a z scale named: {e}");
}
