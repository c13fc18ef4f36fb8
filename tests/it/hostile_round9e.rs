//! Helper h9e: the unit and scale checks name a unit or a scale only when applying it makes the
//! data fit, never as the best of bad explanations (hostile run 8, Part A UNCLEAR). Target ids 0
//! and 1 exchanged in one sweep were said as a halved command, commands swapped in the
//! validation rows as coordinates scaled on export, points scattering 5 mm about their arcs as a
//! column in micrometres or a halved command, a real file's two tracker targets exchanged as one
//! experiment's coordinates scaled by 0.0081. Each now names what the data show, or nothing
//! where the calibration's own checks say it.

use crate::common::altered_csv;
use crate::common::hostile::{case, clear_outputs, run_case};
use std::cell::Cell;
use std::path::Path;

/// The words of a unit or a scale named.
const UNIT_WORDS: [&str; 5] = ["looks halved", "looks doubled", "look like", "looks like", "scaled by"];

/// A deterministic normal deviate from `state` (a 64-bit linear congruential generator and the
/// Box-Muller transform): the same noise on every machine.
fn normal(state: &Cell<u64>) -> f64 {
    let uniform = || {
        state.set(
            state
                .get()
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407),
        );
        ((state.get() >> 11) as f64 / (1u64 << 53) as f64).max(1e-300)
    };
    let (u, v) = (uniform(), uniform());
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

/// The campaign (`simulate --sim analytic`, seed 9, 40 validation poses) and its slipped copies.
fn write_inputs(dir: &Path) {
    crate::common::simulate_analytic(dir, 40, 9, "campaign.csv");
    let campaign = dir.join("campaign.csv");
    let all = |_: &[String]| true;
    altered_csv(&campaign, "targets-4.csv", all, |f| {
        if f[0] == "axis4" {
            f[3] = if f[3] == "0" { "1".into() } else { "0".into() };
        }
    });
    // cmd_k is field 6 + k.
    altered_csv(&campaign, "swap16-val.csv", all, |f| {
        if f[0] == "validation" {
            f.swap(7, 12);
        }
    });
    let state = Cell::new(12345);
    altered_csv(&campaign, "noise5.csv", all, |f| {
        for v in &mut f[4..7] {
            *v = (v.parse::<f64>().unwrap() + 5.0 * normal(&state)).to_string();
        }
    });
}

/// Target ids 0 and 1 exchanged in the axis4 rows (the IRB/L6's target 1 is on the coupled
/// link 6): named as such (was: "cmd_4 looks halved (0.5 times the degrees)").
#[test]
fn exchanged_target_ids_are_named_not_a_halved_command() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path());
    let c = case(
        "target ids 0 and 1 exchanged in the axis4 rows",
        "calibrate targets-4.csv --out out",
        2,
        &[
            "targets-4.csv: `target`",
            "experiment axis4",
            "target ids 0 and 1 look exchanged",
        ],
    );
    let e = run_case(dir.path(), &c);
    assert!(!e.contains("halved"), "{e}");
    clear_outputs(dir.path());
}

/// cmd_1 and cmd_6 swapped in every validation row: the free poses spread 0.76 times the
/// model's, but no one scale fits them pose by pose; the lines are named (was: "coordinates
/// scaled on export, or another robot than the description?").
#[test]
fn commands_swapped_in_the_validation_rows_are_no_scale() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path());
    let c = case(
        "cmd_1 and cmd_6 swapped in the validation rows",
        "calibrate swap16-val.csv --out out",
        0,
        &[
            "swap16-val.csv: `x_mm,y_mm,z_mm`",
            "but not by one scale",
            "the farthest off: line ",
        ],
    );
    let e = run_case(dir.path(), &c);
    assert!(!e.contains("coordinates scaled on export, or another robot"), "{e}");
}

/// 5 mm of noise on every coordinate (25 times a theodolite's): no unit and no factor is named
/// (was: "z_mm looks like micrometres" for the axis5 rows; run 8's file: "cmd_2 looks halved").
#[test]
fn points_scattering_far_beyond_the_noise_name_no_unit() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path());
    let c = case(
        "5 mm of noise on every coordinate",
        "calibrate noise5.csv --out out",
        2,
        &["noise5.csv", "the noise is far above the instrument's"],
    );
    let e = run_case(dir.path(), &c);
    for words in UNIT_WORDS {
        assert!(!e.contains(words), "{words}: {e}");
    }
}

/// The real Boby-Klimchik file with its first two tracker targets (SMR1, SMR2) exchanged in every
/// row: target 0 of the axis4 and axis6 sweeps is then the one near their axes, which no scale
/// puts in place; no scale is named (was: "axis4: ... coordinates look scaled by 0.0081").
#[test]
#[ignore = "needs ../shared/data/real/boby-klimchik-tracker (run by `make test-real`)"]
fn real_tracker_targets_exchanged_name_no_scale() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("bk");
    std::fs::create_dir(&folder).unwrap();
    let text = std::fs::read_to_string(crate::common::real_data("boby-klimchik-tracker/N1N2N3Jval.csv")).unwrap();
    let swapped: Vec<String> = text
        .lines()
        .map(|l| {
            let mut c: Vec<&str> = l.split_whitespace().collect();
            c[..6].rotate_left(3);
            c.join(" ")
        })
        .collect();
    std::fs::write(folder.join("N1N2N3Jval.csv"), swapped.join("\n") + "\n").unwrap();
    crate::common::axiscal()
        .current_dir(dir.path())
        .args(["import", "boby-klimchik", "bk", "--out", "bk.csv"])
        .assert()
        .success();
    let robot = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/robots/boby-klimchik-arm.toml");
    let a = crate::common::axiscal()
        .current_dir(dir.path())
        .args(["calibrate", "bk.csv", "--noise-mm", "0.05", "--out", "out", "--robot"])
        .arg(&robot)
        .assert();
    let e = crate::common::stderr(&a);
    assert!(!e.contains("scaled by"), "{e}");
}
