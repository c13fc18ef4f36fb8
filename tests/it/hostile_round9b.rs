//! Helper h9b (hostile run 8, S2, U1, U2): slips a calibration absorbs and `validate` did not
//! name. In a file of sweeps only, one sweep's block moved 2 mm or its coordinates scaled
//! x1.003 passed `calibrate` silently (the sweep's axis took it); `calibrate` now compares the
//! sweeps that see one target at the reference pose. Against a fixed calibration, a whole
//! file's coordinates scaled x1.003 were blamed on the model; `validate` now fits and names the
//! scale. A sweep shifted 2 mm was named as its command scaled (one parameter against the rigid
//! move's six, tried first); the rigid move now wins when it fits significantly better.

use crate::common::altered_csv;
use crate::common::hostile::{case, clear_outputs, run_case};
use std::path::Path;

/// The shared-target warning's words.
const SHARED: &str = "at the reference pose (every joint at its held value)";

/// The shipped description of `robot`.
pub(crate) fn robot_path(robot: &str) -> String {
    format!("{}/scenarios/robots/{robot}.toml", env!("CARGO_MANIFEST_DIR"))
}

/// `simulate --sim analytic` of `robot` (seed `seed`, `poses` validation poses) as `out` in `dir`.
pub(crate) fn simulated(dir: &Path, robot: &str, seed: u64, poses: usize, out: &str) {
    crate::common::axiscal()
        .current_dir(dir)
        .args(["simulate", "--sim", "analytic", "--robot", &robot_path(robot)])
        .args([
            "--validation-poses",
            &poses.to_string(),
            "--seed",
            &seed.to_string(),
            "--out",
            out,
        ])
        .assert()
        .success();
}

/// [`simulated`] `clean.csv` of `robot` (seed `seed`, 20 validation poses) in `dir` and its
/// calibration `cal/`; the description's path.
fn calibrated(dir: &Path, robot: &str, seed: u64) -> String {
    simulated(dir, robot, seed, 20, "clean.csv");
    let path = robot_path(robot);
    run_case(
        dir,
        &case(
            "calibrate",
            &format!("calibrate clean.csv --robot {path} --out cal"),
            0,
            &[],
        ),
    );
    path
}

/// Coordinates `x_mm, y_mm, z_mm` of a row (fields 4..7) changed by `f`.
fn moved(fields: &mut [String], f: impl Fn(usize, f64) -> f64) {
    for c in 0..3 {
        let v: f64 = fields[4 + c].parse().unwrap();
        fields[4 + c] = f(c, v).to_string();
    }
}

/// A robot, the sweep edited, the edit of a coordinate (its index, its value) and the words
/// naming the sweep.
type Edit = (&'static str, &'static str, fn(usize, f64) -> f64, &'static str);

/// A sweep-only file: its clean form passes `calibrate` without the shared-target warning; one
/// sweep's block moved 2 mm in x (arm6) or its coordinates scaled x1.003 (UR5e, a positioner)
/// is named, with its lines, among the sweeps that see the same target.
#[test]
fn calibrate_names_a_sweep_out_of_place_among_its_shared_target() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let edits: [Edit; 3] = [
        (
            "arm6-dh",
            "axis6",
            |c, v| if c == 0 { v + 2.0 } else { v },
            "experiment axis6 (lines ",
        ),
        ("ur5e-dh", "axis6", |_, v| v * 1.003, "experiment axis6 (lines "),
        (
            "positioner-2axis",
            "axis2",
            |_, v| v * 1.003,
            "experiment axis2 (lines ",
        ),
    ];
    for (i, (robot, sweep, edit, named)) in edits.into_iter().enumerate() {
        let clean = format!("{robot}.csv");
        simulated(d, robot, 4100 + i as u64, 0, &clean);
        let c = case(
            "a clean sweep-only file",
            &format!("calibrate {clean} --robot {} --out out", robot_path(robot)),
            0,
            &[],
        );
        let e = run_case(d, &c);
        assert!(!e.contains(SHARED), "{robot}: a false alarm: {e}");
        clear_outputs(d);
        let slipped = format!("{robot}-slipped.csv");
        altered_csv(
            &d.join(&clean),
            &slipped,
            |_| true,
            |f| {
                if f[0] == sweep {
                    moved(f, edit)
                }
            },
        );
        let c = case(
            "one sweep moved or scaled",
            &format!("calibrate {slipped} --robot {} --out out", robot_path(robot)),
            0,
            &[SHARED, named, "measure the sweep again"],
        );
        run_case(d, &c);
        clear_outputs(d);
    }
}

/// `validate` of a file whose every coordinate is scaled x1.003 (an instrument's scale) against
/// the clean file's calibration names the scale and its factor; the clean file validates.
#[test]
fn validate_names_a_whole_file_scaled() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let robot = calibrated(d, "arm7-dh", 4201);
    altered_csv(
        &d.join("clean.csv"),
        "scaled.csv",
        |_| true,
        |f| moved(f, |_, v| v * 1.003),
    );
    let line = |file: &str| format!("validate {file} --robot {robot} --calibration cal/calibration.json --out out");
    let e = run_case(d, &case("clean", &line("clean.csv"), 0, &[]));
    assert!(!e.contains("every coordinate of the file reads"), "a false alarm: {e}");
    clear_outputs(d);
    let c = case(
        "every coordinate x1.003",
        &line("scaled.csv"),
        2,
        &[
            "scaled.csv:3: `x_mm,y_mm,z_mm`",
            "every coordinate of the file reads 1.00",
            "the instrument's scale",
        ],
    );
    run_case(d, &c);
}

/// `validate` of a SCARA file whose joint-4 sweep is shifted 2 mm in x names the block moved,
/// not `cmd_4` scaled (the one-parameter scale also passes the test, but the rigid move fits
/// significantly better).
#[test]
fn validate_prefers_the_block_moved_over_a_command_scaled() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let robot = calibrated(d, "scara-rrpr", 4301);
    altered_csv(
        &d.join("clean.csv"),
        "shifted.csv",
        |_| true,
        |f| {
            if f[0] == "axis4" {
                moved(f, |c, v| if c == 0 { v + 2.0 } else { v })
            }
        },
    );
    let c = case(
        "joint 4's sweep shifted 2 mm",
        &format!("validate shifted.csv --robot {robot} --calibration cal/calibration.json --out out"),
        2,
        &["experiment axis4's", "with the block moved back"],
    );
    let e = run_case(d, &c);
    assert!(!e.contains("`cmd_4` divided by"), "the command blamed first: {e}");
}
