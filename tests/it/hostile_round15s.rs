//! Hostile runs 13 and 15, an instrument bumped part-way through a sweep (run 13 defect 4b):
//! an arm6-dh sweep file with y +3 mm from data row 60 (inside axis3's sweep) on was misnamed
//! "the column `cmd_3` looks scaled by 1.0098". The sweeps' screen now tests each sweep's fit
//! for a change point (`procedure/screen/bump.rs`) and names the experiment, the line, and the
//! shift with its sigma; clean files of six robots stay quiet.

use crate::common::{altered_csv, axiscal, number_after, stderr};
use std::cell::Cell;
use std::path::{Path, PathBuf};

/// The shipped description of `robot`.
pub fn robot(name: &str) -> String {
    format!("{}/scenarios/robots/{name}.toml", env!("CARGO_MANIFEST_DIR"))
}

/// `simulate --seed seed` of `name` as `<name>_<seed>.csv` in `dir` (`asea-irb6l`: the paper
/// robot with the rapier simulation, as `simulate` runs it by default; any other: analytic).
pub fn simulated(dir: &Path, name: &str, seed: u64) -> PathBuf {
    let out = format!("{name}_{seed}.csv");
    let mut cmd = axiscal();
    cmd.current_dir(dir)
        .args(["simulate", "-q", "--seed", &seed.to_string(), "--out", &out, "--force"]);
    if name != "asea-irb6l" {
        cmd.args(["--sim", "analytic", "--robot", &robot(name)]);
    }
    cmd.assert().success();
    dir.join(out)
}

/// `calibrate` of `file`, its stderr.
pub fn calibrated(dir: &Path, name: &str, file: &Path) -> String {
    let mut cmd = axiscal();
    cmd.current_dir(dir).arg("calibrate");
    if name != "asea-irb6l" {
        cmd.args(["--robot", &robot(name)]);
    }
    let a = cmd.arg(file).args(["--out", "cal", "--force"]).assert().success();
    stderr(&a)
}

/// `file` with `delta_mm` added to coordinate `axis` (0-2) of every data row from the
/// `from`-th (1-based) on, as `name`; returns it and the first moved row's experiment.
fn bumped(file: &Path, name: &str, axis: usize, delta_mm: f64, from: usize) -> (PathBuf, String) {
    let (row, experiment) = (Cell::new(0), std::cell::RefCell::new(String::new()));
    let path = altered_csv(
        file,
        name,
        |_| true,
        |f| {
            row.set(row.get() + 1);
            if row.get() == from {
                *experiment.borrow_mut() = f[0].clone();
            }
            if row.get() >= from {
                f[4 + axis] = (f[4 + axis].parse::<f64>().unwrap() + delta_mm).to_string();
            }
        },
    );
    (path, experiment.into_inner())
}

/// The hostile run's case, and a sliding sweep's (table-prpp's second experiment, z): the
/// warning names the experiment and the first moved row's line (two lines of header), and the
/// shift it reports lies within 4 of its sigmas of the one made on each axis.
#[test]
fn a_bump_inside_a_sweep_is_named_by_its_line_and_shift() {
    let dir = tempfile::tempdir().unwrap();
    for (name, axis, delta, from) in [("arm6-dh", 1, 3.0, 61), ("table-prpp", 2, 2.0, 27)] {
        let clean = simulated(dir.path(), name, 31);
        let (file, experiment) = bumped(&clean, &format!("bumped_{name}.csv"), axis, delta, from);
        let e = calibrated(dir.path(), name, &file);
        let line = from + 2;
        let said = e
            .lines()
            .find(|l| l.contains(&format!("bumped_{name}.csv:{line}: experiment {experiment}'s last")))
            .unwrap_or_else(|| panic!("{name}: no bump named at line {line} ({experiment}): {e}"));
        let inside = |l: &str, open: &str| -> Vec<f64> {
            let rest = l.split(open).nth(1).unwrap();
            rest[..rest.find(')').unwrap()]
                .split(',')
                .map(|v| v.trim().parse().unwrap())
                .collect()
        };
        let shift = inside(said, "sit (");
        let sigma = inside(said, "(+- ");
        for c in 0..3 {
            let made = if c == axis { delta } else { 0.0 };
            assert!(
                (shift[c] - made).abs() < 4.0 * sigma[c],
                "{name} axis {c}: {} against {made} (+- {}): {said}",
                shift[c],
                sigma[c]
            );
        }
        assert!(number_after(said, "(p = ") < 1e-4, "{said}");
    }
}

/// Clean files of six robots (seeds nobody tuned on) are not told a sweep was bumped.
#[test]
fn clean_sweeps_of_six_robots_are_quiet() {
    let dir = tempfile::tempdir().unwrap();
    for name in [
        "asea-irb6l",
        "arm6-dh",
        "ur5e-dh",
        "scara-rrpr",
        "table-prpp",
        "positioner-2axis",
    ] {
        for seed in [33, 34] {
            let file = simulated(dir.path(), name, seed);
            let e = calibrated(dir.path(), name, &file);
            assert!(!e.contains("moved during the sweep"), "{name} seed {seed}: {e}");
        }
    }
}
