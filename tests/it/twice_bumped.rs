//! A sweep whose points shift twice (the instrument or the target bumped at two steps): the
//! change-point screen (`src/calibration/procedure/screen/bump.rs`) found no single step that
//! explains the sweep, and the validation-pose search said the sweep as a drift (a UR5e's
//! axis2 bumped 2 mm along y at two steps: a drift of (-0.156, 4.957, 0.203) mm). It now seeks a
//! second change point with the first block moved back, fits both shifts together and names
//! both steps with their lines and shifts.

use crate::common::altered_experiment;
use crate::common::hostile::assert_twice_less_once_3;
use crate::hostile_round15s::{calibrated, simulated};
use std::path::{Path, PathBuf};

/// Shapes apart: the same direction twice on a UR5e's shoulder, two directions on a 6-axis
/// arm's wrist, a table's sliding joint along its motion then across it. (robot, experiment,
/// [(first step of the block, its shift in mm); 2]).
type Case = (&'static str, &'static str, [(usize, [f64; 3]); 2]);
const CASES: [Case; 3] = [
    ("ur5e-dh", "axis2", [(5, [0.0, 2.0, 0.0]), (11, [0.0, 2.0, 0.0])]),
    ("arm6-dh", "axis4", [(4, [1.5, 0.0, 0.0]), (10, [0.0, 0.0, -2.0])]),
    ("table-prpp", "axis1", [(6, [1.5, 0.0, 0.0]), (11, [0.0, -1.5, 0.0])]),
];

/// `clean` with experiment `experiment`'s points from each block's step on moved by its
/// shift times `k`, as `name` in `dir`.
fn bumped_twice(
    dir: &Path,
    clean: &Path,
    name: &str,
    (experiment, blocks): (&str, [(usize, [f64; 3]); 2]),
    k: f64,
) -> PathBuf {
    altered_experiment(clean, name, experiment, |f| {
        let step: usize = f[2].parse().unwrap();
        for (from, shift) in blocks {
            if step >= from {
                for (c, d) in shift.iter().enumerate() {
                    f[4 + c] = (f[4 + c].parse::<f64>().unwrap() + k * d).to_string();
                }
            }
        }
    });
    dir.join(name)
}

/// Each two-step warning of `experiment`: (its step, shift, 1-sigma), in the order printed.
fn named_steps(stderr: &str, experiment: &str) -> Vec<(usize, [f64; 3], [f64; 3])> {
    let triple = |s: &str| -> Option<[f64; 3]> {
        let v: Vec<f64> = s.split(", ").map(|x| x.parse().ok()).collect::<Option<_>>()?;
        v.try_into().ok()
    };
    stderr
        .lines()
        .filter(|l| l.starts_with("warning:") && l.contains(&format!("experiment {experiment}'s last ")))
        .filter(|l| l.contains("one of two steps in this sweep"))
        .filter_map(|l| {
            let rest = l.split(" points, from step ").nth(1)?;
            let step = rest.split(' ').next()?.parse().ok()?;
            let shift = triple(rest.split(" sit (").nth(1)?.split(')').next()?)?;
            let sigma = triple(rest.split("(+- ").nth(1)?.split(')').next()?)?;
            Some((step, shift, sigma))
        })
        .collect()
}

#[test]
fn a_sweep_bumped_twice_is_named_at_both_steps() {
    for (robot, experiment, blocks) in CASES {
        let dir = tempfile::tempdir().unwrap();
        // Seed 19: not tuned on (the shapes were first tried at seeds 9 and 17).
        let clean = simulated(dir.path(), robot, 19);
        let once_file = bumped_twice(dir.path(), &clean, "once.csv", (experiment, blocks), 1.0);
        let e = calibrated(dir.path(), robot, &once_file);
        let once = named_steps(&e, experiment);
        let steps: Vec<usize> = once.iter().map(|s| s.0).collect();
        assert_eq!(steps, [blocks[0].0, blocks[1].0], "{robot}: {e}");
        // A second path: the same sweep with both shifts doubled; each block's shifts named
        // differ by the one written, within 4 of their sigmas (the fit's own take of a step,
        // along a slide's motion, cancels).
        let twice_file = bumped_twice(dir.path(), &clean, "twice.csv", (experiment, blocks), 2.0);
        let e = calibrated(dir.path(), robot, &twice_file);
        let twice = named_steps(&e, experiment);
        assert_eq!(twice.len(), 2, "{robot}: {e}");
        for (b, (_, shift)) in blocks.iter().enumerate() {
            assert_twice_less_once_3(
                &format!("{robot}, block {b}: {e}"),
                (once[b].1, once[b].2),
                (twice[b].1, twice[b].2),
                *shift,
            );
        }
    }
}
