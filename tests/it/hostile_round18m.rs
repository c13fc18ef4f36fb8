//! Session 56 (issue #33; hostile run 16's FA 8, `cleand-keep5-*`): a clean file whose sweeps
//! were cut to their first 5 steps (24 deg each) failed its own validation poses' chi-square
//! (UR5e chi2/dof 5.10, arm6 3.28) although their RMS was within the prediction. The
//! calibration then knows joints 4-6 to 40-75 mrad, and the model's second-order terms move a
//! validation point by 1-5 mm where the noise is 0.14-0.2 mm: the linear prediction is too tight
//! where only the noise fills it. Its remainder is now drawn (`diagnosis/prediction_curvature.rs`)
//! where it counts, and the tool frame fitted on such a flange is judged against its own
//! rotation sigma. Hostile run 17's regression `swapcols-arm6-free-2-3` (a `cmd_2`/`cmd_3`
//! swap of free poses said as `cmd_2` x 1.31) is kept too.

use crate::common::{altered_csv, axiscal, read_calibration, stderr};
use crate::hostile_round16v::simulated_with_poses as simulated;
use axiscal::calibration::model_parameters::model_displaced;
use axiscal::measurement::read_measurements;
use axiscal::numerics::stats::chi_square_quantile;
use axiscal::robot::{Controller, RobotDescription, RobotModel, commands_to_internal};
use nalgebra::{DMatrix, DVector};
use std::path::{Path, PathBuf};

/// The words of `calibrate`'s warning on its own validation poses.
const OWN_VALIDATION: &str = "validation poses (not fitted)";

/// The false-alarm rate of that warning (`OWN_POSES_FALSE_ALARM` in `cli/calibrate.rs`).
const FALSE_ALARM: f64 = 1e-4;

/// `axiscal ARGS` in `dir`, expecting `code`: its stderr.
fn run(dir: &Path, args: &[&str], code: i32) -> String {
    stderr(&axiscal().current_dir(dir).args(args).assert().code(code))
}

/// `file`'s sweeps cut to their first five steps (every free pose kept), as `name`.
fn first_five_steps(file: &Path, name: &str) -> PathBuf {
    altered_csv(
        file,
        name,
        |f| f[1] == "0" || f[2].parse::<usize>().unwrap() < 5,
        |_| {},
    )
}

/// `file` with `change` applied to its validation rows only, as `name`.
fn validation_changed(file: &Path, name: &str, change: impl Fn(&mut Vec<String>)) -> PathBuf {
    altered_csv(
        file,
        name,
        |_| true,
        |f| {
            if f[0] == "validation" {
                change(f)
            }
        },
    )
}

/// Clean files of three robots (seeds 601, 605, 606: those the draws' count and the tool
/// check were settled on; 607-609 were fresh, see the changelog) with 5-point sweeps calibrate
/// without a warning on their own validation poses or on the tool frame (before: chi2/dof
/// 12.71, 171.54 and 20.22, and the tool "turned 11.7 deg").
#[test]
fn clean_five_point_sweeps_pass_their_own_validation() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (robot, seed) in [("ur5e-dh", 601), ("arm6-dh", 605), ("arm7-dh", 606)] {
        let source = simulated(d, &["--robot", robot], 60, seed, &format!("src-{robot}.csv"));
        let short = first_five_steps(&source, &format!("k5-{robot}.csv"));
        let e = run(
            d,
            &[
                "calibrate",
                "--robot",
                robot,
                short.to_str().unwrap(),
                "--out",
                robot,
                "--force",
            ],
            0,
        );
        assert!(!e.contains(OWN_VALIDATION), "{robot}: {e}");
        assert!(!e.contains("tool observation is turned"), "{robot}: {e}");
    }
}

/// The same short UR5e file with a slip on its validation rows (`cmd_2` 1 deg off; `x_mm`
/// x 1.02) is still warned of: the drawn remainder widens the prediction where the model
/// curves, not everywhere.
#[test]
fn a_slip_of_the_validation_rows_of_short_sweeps_is_still_warned_of() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let source = simulated(d, &["--robot", "ur5e-dh"], 60, 601, "src.csv");
    let short = first_five_steps(&source, "k5.csv");
    let cmd_2 = validation_changed(&short, "cmd2.csv", |f| {
        f[8] = (f[8].parse::<f64>().unwrap() + 1.0).to_string();
    });
    let x = validation_changed(&short, "x.csv", |f| {
        f[4] = (f[4].parse::<f64>().unwrap() * 1.02).to_string();
    });
    for file in [cmd_2, x] {
        let e = run(
            d,
            &[
                "calibrate",
                "--robot",
                "ur5e-dh",
                file.to_str().unwrap(),
                "--out",
                "o",
                "--force",
            ],
            0,
        );
        assert!(e.contains(OWN_VALIDATION), "{}: {e}", file.display());
    }
}

/// A second path to the premise, written apart from `validate`'s draws: the exact
/// second-order covariance `1/2 sum_kl h_kl h_kl^T` (`h_kl` the Hessian of the validation
/// points over the calibration's error in its principal coordinates, by central differences at
/// one sigma) over the short UR5e file's validation poses. With the linear covariance alone
/// the chi-square is beyond its `1 - 1e-4` quantile; with the second-order term it is within,
/// as `validate`'s verdict with the drawn remainder is.
#[test]
fn the_exact_second_order_covariance_explains_the_short_sweeps_misses() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let source = simulated(d, &["--robot", "ur5e-dh"], 60, 601, "src.csv");
    let short = first_five_steps(&source, "k5.csv");
    run(
        d,
        &["calibrate", "--robot", "ur5e-dh", "k5.csv", "--out", "cal", "-q"],
        0,
    );
    let cal = read_calibration(&d.join("cal"));
    let desc =
        RobotDescription::from_file(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/robots/ur5e-dh.toml"))
            .unwrap();
    let set = read_measurements(&short, Some(desc.dof())).unwrap();
    let poses = ValidationPoints::new(&desc, &set);
    let at = |robot: &RobotModel| poses.positions_mm(robot);
    let f0 = at(&cal.robot);
    let residual = DVector::from_iterator(f0.len(), poses.measured_mm.iter().zip(f0.iter()).map(|(m, p)| m - p));
    let covariance = cal.model_covariance.as_ref().unwrap().matrix();
    let eigen = covariance.clone().symmetric_eigen();
    let columns: Vec<DVector<f64>> = (0..covariance.nrows())
        .filter(|&k| eigen.eigenvalues[k] > 0.0)
        .map(|k| eigen.eigenvectors.column(k) * eigen.eigenvalues[k].sqrt())
        .collect();
    let moved = |a: &DVector<f64>| at(&model_displaced(&cal.robot, a.as_slice()));
    let mut linear = DMatrix::zeros(f0.len(), columns.len());
    let mut second = DMatrix::zeros(f0.len(), f0.len());
    for (k, c) in columns.iter().enumerate() {
        let (plus, minus) = (moved(c), moved(&-c));
        linear.set_column(k, &((&plus - &minus) / 2.0));
        let h = &plus + &minus - 2.0 * &f0;
        second += &h * h.transpose() / 2.0;
        for c2 in &columns[k + 1..] {
            let h = (moved(&(c + c2)) - moved(&(c - c2)) - moved(&(c2 - c)) + moved(&(-c - c2))) / 4.0;
            second += &h * h.transpose();
        }
    }
    let noise_mm = axiscal::diagnosis::ValidationOptions::of_calibration(&cal, FALSE_ALARM).noise_rms_3d_mm;
    let noise = DMatrix::identity(f0.len(), f0.len()) * (noise_mm * noise_mm / 3.0);
    let chi_square = |c: DMatrix<f64>| {
        let s = (c + &noise).cholesky().unwrap();
        residual.dot(&s.solve(&residual))
    };
    let limit = chi_square_quantile(1.0 - FALSE_ALARM, f0.len() as f64);
    let lin = chi_square(&linear * linear.transpose());
    let curved = chi_square(&linear * linear.transpose() + second);
    assert!(lin > limit, "linear {lin} within {limit}");
    assert!(curved < limit, "second order {curved} beyond {limit}");
}

/// The validation poses' tool targets of a measurement set.
struct ValidationPoints<'a> {
    desc: &'a RobotDescription,
    controller: Controller,
    /// Per point: internal commands and the target's index.
    points: Vec<(Vec<f64>, usize)>,
    measured_mm: Vec<f64>,
}

impl<'a> ValidationPoints<'a> {
    fn new(desc: &'a RobotDescription, set: &axiscal::measurement::MeasurementSet) -> Self {
        let rows: Vec<_> = set.rows().iter().filter(|m| m.experiment == "validation").collect();
        ValidationPoints {
            desc,
            controller: Controller::from_description(desc),
            points: rows
                .iter()
                .map(|m| (commands_to_internal(desc, &m.cmd), m.target))
                .collect(),
            measured_mm: rows.iter().flat_map(|m| m.position_mm).collect(),
        }
    }

    /// Every point's position on `robot`, stacked \[mm\].
    fn positions_mm(&self, robot: &RobotModel) -> DVector<f64> {
        let (phi, targets) = (robot.phi_model(), self.desc.tool_targets_m());
        DVector::from_iterator(
            3 * self.points.len(),
            self.points.iter().flat_map(|(cmd, target)| {
                let q = robot.joint_values(&self.controller, cmd).unwrap();
                let p = phi.world_from_tool(&q).transform_point(&targets[*target]);
                [p.x * 1e3, p.y * 1e3, p.z * 1e3]
            }),
        )
    }
}

/// Hostile run 17's regression (its file: the rapier arm6, seed 7, 150 poses): free poses of
/// arm6 with `cmd_2` and `cmd_3` swapped were said
/// as `cmd_2` read 1.314 times (a scale whose undoing left 5.55 of 5.85 mm); the swap, which
/// leaves 0.73 mm of 116, is said again, and nothing else of it.
#[test]
#[ignore = "minutes in a debug build (the free-pose slip search): `make test-real` runs it on the optimised build"]
fn a_swap_of_free_poses_is_not_said_as_a_scale() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let args = [
        "simulate",
        "--robot",
        "arm6-dh",
        "--seed",
        "7",
        "--validation-poses",
        "150",
    ];
    run(d, &[&args[..], &["--out", "src.csv", "-q"]].concat(), 0);
    let free = altered_csv(&d.join("src.csv"), "free.csv", |f| f[1] == "0", |f| f.swap(8, 9));
    let e = run(
        d,
        &[
            "calibrate",
            "--robot",
            "arm6-dh",
            free.to_str().unwrap(),
            "--out",
            "o",
            "--force",
        ],
        0,
    );
    assert!(e.contains("`cmd_2` and `cmd_3` are swapped"), "{e}");
    assert!(!e.contains("a column scale explains"), "{e}");
}
