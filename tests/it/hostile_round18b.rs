//! Hostile run 16, class "bump-edge" and "bump" (defect 3, its second warnings), and
//! "short-ur5ejit-bump". A bump the sweep screen named (two points at a sweep's end, or a block
//! from a step on) was blamed a second time on a wrong cause by the checks that read the
//! sweep's fit as its joint's: "joint 3 (axis3) turns 0.9653 times as far per command" (arm7,
//! UR5e, Boby, arm4), "`z_mm`: the instrument's z axis reads 1.00559 times" (arm6), a held
//! command's offset, a joint's misfit. Those checks (the transmission findings, the
//! coordinate-scale profile, the held-offset test, the detection limits) now judge the data
//! with each named block moved back (`procedure::bumps_undone`, `cli/calibrate.rs`), so the
//! bump is said once; a real command scale beside a bump is still named. And a 2 mm bump in
//! a sweep whose held joints wander (a jittered plan) was not tested at all (the screen tests
//! only sweeps that hold still): once the model is fitted, those sweeps' points are moved to
//! the design pose as the procedure moves them and tested for a bump the same way
//! (`procedure::wandering_sweep_bumps`); clean jittered files stay quiet.

use crate::common::{altered_csv, axiscal, stderr};
use std::path::{Path, PathBuf};

/// A shipped description.
fn robot(name: &str) -> String {
    format!("{}/scenarios/robots/{name}.toml", env!("CARGO_MANIFEST_DIR"))
}

/// The UR5e plan of hostile run 16's jittered files: every joint swept once, 16 points, the
/// held joints' recorded values wandering by 0.01-0.1 deg per step.
const UR5E_JITTER_PLAN: &str = "reference = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]\nheld_jitter = [0.01, 0.1]\n\
    [[sweeps]]\njoint = 6\nspan = 60.0\nintervals = 15\n[[sweeps]]\njoint = 5\nspan = 60.0\nintervals = 15\n\
    [[sweeps]]\njoint = 4\nspan = 60.0\nintervals = 15\n[[sweeps]]\njoint = 3\nspan = 45.0\nintervals = 15\n\
    [[sweeps]]\njoint = 2\nspan = 45.0\nintervals = 15\n[[sweeps]]\njoint = 1\nspan = 60.0\nintervals = 15\n";

/// `simulate -q --seed seed` with `args` (a robot, a plan, a simulation) as `name` in `dir`.
fn simulated(dir: &Path, args: &[&str], seed: u64, name: &str) -> PathBuf {
    axiscal()
        .current_dir(dir)
        .args(["simulate", "-q", "--seed", &seed.to_string(), "--out", name, "--force"])
        .args(args)
        .assert()
        .success();
    dir.join(name)
}

/// `calibrate --robot robot file`, its stderr.
fn calibrated(dir: &Path, robot: &str, file: &Path) -> String {
    let a = axiscal()
        .current_dir(dir)
        .args(["calibrate", "--robot", robot])
        .arg(file)
        .args(["--out", "cal", "--force"])
        .assert()
        .success();
    stderr(&a)
}

/// `file` with `delta` added to coordinate `axis` (0-2) of every row of `experiment` whose
/// step is in `steps` (every target: the instrument moved), as `name`.
fn bumped(
    file: &Path,
    name: &str,
    experiment: &str,
    steps: std::ops::Range<usize>,
    axis: usize,
    delta: f64,
) -> PathBuf {
    altered_csv(
        file,
        name,
        |_| true,
        |f| {
            if f[0] == experiment && steps.contains(&f[2].parse::<usize>().unwrap()) {
                f[4 + axis] = (f[4 + axis].parse::<f64>().unwrap() + delta).to_string();
            }
        },
    )
}

/// The warnings of `e` other than those about the file's own validation poses (the calibration
/// as written misses them: the bump is in it).
fn warnings(e: &str) -> Vec<&str> {
    e.lines()
        .filter(|l| l.starts_with("warning:") && !l.contains("validation poses"))
        .collect()
}

/// The hostile run's cases where a second warning named a wrong cause (the same robots,
/// simulations, seeds and bumps): the one warning left names the bump; no transmission scale,
/// instrument-axis scale, held offset or misfit is said beside it. Main 7a44148 said a second
/// cause in each.
#[test]
fn a_named_sweep_end_is_not_blamed_on_a_scale_too() {
    let dir = tempfile::tempdir().unwrap();
    let (arm7, boby) = (robot("arm7-dh"), robot("boby-klimchik-arm"));
    for (robot, sim, seed, experiment, steps, axis, which) in [
        (arm7.as_str(), "analytic", 201, "axis3", 14..16, 0, "last 2"),
        ("ur5e-dh", "rapier", 202, "axis4", 14..16, 2, "last 2"),
        (boby.as_str(), "rapier", 201, "axis4", 14..16, 2, "last 2"),
        ("arm6-dh", "rapier", 201, "axis3", 2..16, 2, "first 2"),
    ] {
        let clean = simulated(dir.path(), &["--robot", robot, "--sim", sim], seed, "clean.csv");
        let file = bumped(&clean, "in.csv", experiment, steps, axis, 2.0);
        let e = calibrated(dir.path(), robot, &file);
        let said = warnings(&e);
        assert!(
            said.len() == 1 && said[0].contains(&format!("experiment {experiment}'s {which} of")),
            "{robot}: not one warning naming the bump: {e}"
        );
    }
}

/// A bump from a sweep's middle on (3 mm along x from axis4's step 8, arm6-dh, the hostile
/// run's case where main said a misfit of joint 4 and a held `cmd_5` offset too): one warning.
#[test]
fn a_bump_in_a_sweep_is_said_once() {
    let dir = tempfile::tempdir().unwrap();
    let clean = simulated(dir.path(), &["--robot", "arm6-dh"], 201, "clean.csv");
    let file = bumped(&clean, "in.csv", "axis4", 8..16, 0, 3.0);
    let e = calibrated(dir.path(), "arm6-dh", &file);
    let said = warnings(&e);
    assert!(
        said.len() == 1 && said[0].contains("experiment axis4's last 8 of 16 points, from step 8 on"),
        "{e}"
    );
}

/// Two causes at once: `cmd_3` scaled by 1.03 through joint 3's sweep and a 3 mm bump in
/// axis4's: both are named, the scale with the factor and sigma the file without the bump gives
/// (the block undone leaves joint 3's sweep as it is; as written, the bump inflated the noise
/// and so the sigma: main said 0.9699 (+-0.0011) where the file without it says +-0.00055).
#[test]
fn a_command_scale_beside_a_bump_is_still_named() {
    let dir = tempfile::tempdir().unwrap();
    let clean = simulated(dir.path(), &["--robot", "arm6-dh"], 201, "clean.csv");
    let scaled = altered_csv(
        &clean,
        "scaled.csv",
        |_| true,
        |f| {
            if f[0] == "axis3" {
                f[9] = (f[9].parse::<f64>().unwrap() * 1.03).to_string();
            }
        },
    );
    let alone = calibrated(dir.path(), "arm6-dh", &scaled);
    let file = bumped(&scaled, "in.csv", "axis4", 8..16, 0, 3.0);
    let e = calibrated(dir.path(), "arm6-dh", &file);
    assert!(
        e.contains("experiment axis4's last 8 of 16 points, from step 8 on"),
        "{e}"
    );
    let scale = |text: &str| -> String {
        let line = text
            .lines()
            .find(|l| l.contains("joint 3 (axis3) turns"))
            .unwrap_or_else(|| panic!("joint 3's scale not named: {text}"));
        line.split(" times as far").next().unwrap().to_string()
    };
    assert_eq!(scale(&e), scale(&alone), "{e}");
}

/// The hostile run's jittered case (UR5e, held joints wandering, z +2 mm on axis3 from step 8,
/// seed 211) names the bump, where main said only joint 3's misfit; with the shipped arm6
/// jitter plan, x +2 mm on axis4 from step 8 too. Clean jittered files (seeds 231-233 of the
/// UR5e plan, 231-232 of the arm6 plan, not those the rule was checked on) name none.
#[test]
fn a_bump_in_a_jittered_sweep_is_named_and_clean_ones_are_quiet() {
    let dir = tempfile::tempdir().unwrap();
    let plan = dir.path().join("ur5e-jitter.toml");
    std::fs::write(&plan, UR5E_JITTER_PLAN).unwrap();
    let arm6_plan = robot("arm6-jitter-plan");
    let ur5e = ["--robot", "ur5e-dh", "--plan", plan.to_str().unwrap()];
    let arm6 = ["--robot", "arm6-dh", "--plan", arm6_plan.as_str()];
    for (args, robot, seed, experiment, axis) in
        [(&ur5e, "ur5e-dh", 211, "axis3", 2), (&arm6, "arm6-dh", 211, "axis4", 0)]
    {
        let clean = simulated(dir.path(), args, seed, "clean.csv");
        let file = bumped(&clean, "in.csv", experiment, 8..100, axis, 2.0);
        let e = calibrated(dir.path(), robot, &file);
        let said = warnings(&e);
        assert!(
            said.len() == 1
                && said[0].contains("in.csv:")
                && said[0].contains(&format!("experiment {experiment}'s last"))
                && said[0].contains("from step 8 on"),
            "{robot}: {e}"
        );
    }
    for (args, robot, seeds) in [
        (&ur5e, "ur5e-dh", &[231, 232, 233][..]),
        (&arm6, "arm6-dh", &[231, 232][..]),
    ] {
        for &seed in seeds {
            let clean = simulated(dir.path(), args, seed, "clean.csv");
            let e = calibrated(dir.path(), robot, &clean);
            assert!(
                !e.contains("moved during the sweep") && !e.contains("sweep ends tried"),
                "{robot} seed {seed}: {e}"
            );
        }
    }
}

/// The instrument moved for good after axis3's first 2 points (arm6-dh, z +2 mm on every row
/// from axis3's step 2 to the file's end): the bump is named, and no `z_mm` scale beside it
/// (main said "`z_mm` reads 1.00559 times"); the validation poses, all in the new place, are
/// missed by the calibration as written, which says so.
#[test]
fn an_instrument_moved_for_good_is_not_a_scale_too() {
    let dir = tempfile::tempdir().unwrap();
    let clean = simulated(dir.path(), &["--robot", "arm6-dh"], 201, "clean.csv");
    let moved = std::cell::Cell::new(false);
    let file = altered_csv(
        &clean,
        "in.csv",
        |_| true,
        |f| {
            moved.set(moved.get() || (f[0] == "axis3" && f[2] == "2"));
            if moved.get() {
                f[6] = (f[6].parse::<f64>().unwrap() + 2.0).to_string();
            }
        },
    );
    let e = calibrated(dir.path(), "arm6-dh", &file);
    let said = warnings(&e);
    assert!(
        said.len() == 1 && said[0].contains("experiment axis3's first 2 of 16 points"),
        "{e}"
    );
}
