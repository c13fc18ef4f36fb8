//! The issue-15 test robots, unlike the IRB/L6 (`scenarios/robots/`): a P-R-P-P positioning
//! table, a two-axis positioner, a SCARA (R-R-P-R) and a six-axis arm measured with joint 2
//! swept twice and held joints whose recorded values wander by 0.01-0.1 deg. Each is described
//! by a DH table, perturbed (tests/data/test-robot-spec.toml), simulated on the analytic arm
//! and calibrated; every identified parameter must lie within 3 reported sigma of the truth
//! (in the calibration's convention: the noise-free calibration of the same robot) with a
//! normalised RMS near 1. A few seeds here; `make test-robots` runs 50 per robot and prints
//! the numbers of docs/validation.md.

use axiscal::calibration::procedure::{Calibration, CalibrationOptions, calibrate};
use axiscal::measurement::{IsotropicNoise, MeasurementModel, MeasurementSet};
use axiscal::plan::{CalibrationPlan, ValidationPlan};
use axiscal::robot::{Controller, RobotDescription, RobotModel};
use axiscal::sim::{AnalyticArm, PerturbationSpec, perturb, simulate_campaign};
use rand::{SeedableRng, rngs::ChaCha12Rng};
use std::path::Path;

/// Measurement noise of the test campaigns, 3-D RMS \[mm\].
const NOISE_MM: f64 = 0.1;

struct TestRobot {
    desc: RobotDescription,
    plan: CalibrationPlan,
    truth: RobotModel,
}

fn robot(name: &str) -> TestRobot {
    let desc = RobotDescription::from_file(Path::new(&format!("scenarios/robots/{name}.toml"))).unwrap();
    let plan_file = match name {
        "arm6-dh" => Some("scenarios/robots/arm6-jitter-plan.toml"),
        "table-prpp" => Some("scenarios/robots/table-prpp-plan.toml"),
        _ => None,
    };
    let plan = match plan_file {
        Some(path) => {
            let path = Path::new(path);
            axiscal::toml_file::parse(&axiscal::toml_file::read(path).unwrap(), path).unwrap()
        }
        None => CalibrationPlan::for_robot(&desc),
    };
    let spec =
        PerturbationSpec::from_toml_str(include_str!("../data/test-robot-spec.toml"), "test-robot-spec.toml").unwrap();
    let truth = perturb(&desc, &spec, &mut ChaCha12Rng::seed_from_u64(1)).unwrap();
    TestRobot { desc, plan, truth }
}

fn campaign(r: &TestRobot, noise_mm: f64, seed: u64) -> MeasurementSet {
    let mut arm = AnalyticArm::new(r.truth.clone(), Controller::from_description(&r.desc));
    let validation = ValidationPlan {
        poses: 0,
        ..ValidationPlan::workspace_default(r.desc.dof())
    };
    let instrument = MeasurementModel::Isotropic(IsotropicNoise {
        net_radial_rms_mm: noise_mm,
    });
    let out = simulate_campaign(
        &r.desc,
        &r.plan,
        &validation,
        &mut arm,
        &instrument,
        &mut ChaCha12Rng::seed_from_u64(seed),
    )
    .expect("the campaign runs");
    MeasurementSet::new(r.desc.dof(), out.rows).unwrap()
}

fn options() -> CalibrationOptions {
    CalibrationOptions {
        noise_rms_3d_mm: NOISE_MM,
        ..CalibrationOptions::default()
    }
}

/// Normalised errors `(estimate - reference) / sigma` of every row parameter and transmission
/// coefficient; a parameter with zero sigma is fixed by convention and must not move.
fn normalised_errors(cal: &Calibration, reference: &Calibration) -> Vec<f64> {
    let mut z = Vec::new();
    let mut push = |err: f64, sigma: f64| {
        // Rounding of the construction: a convention-fixed parameter moves by < 1e-9 mm or deg.
        if sigma < 1e-9 {
            assert!(err.abs() < 1e-6, "parameter fixed by convention moved by {err}");
        } else {
            z.push(err / sigma);
        }
    };
    for ((r, t), s) in cal.robot.rows.iter().zip(&reference.robot.rows).zip(&cal.row_sigma) {
        push((r.a_m - t.a_m) * 1e3, s.a_mm);
        push((r.b_m - t.b_m) * 1e3, s.b_mm);
        push(r.alpha_deg - t.alpha_deg, s.alpha_deg);
        push(r.beta_deg - t.beta_deg, s.beta_deg);
    }
    for (a, t) in cal.axes.iter().zip(&reference.axes) {
        for ((c, ct), s) in a
            .transmission
            .coefficients()
            .iter()
            .zip(t.transmission.coefficients())
            .zip(&a.coefficient_sigma)
        {
            push(c - ct, *s);
        }
    }
    z
}

/// `(normalised RMS, count beyond 3 sigma, count)` over `seeds`.
fn check(name: &str, seeds: std::ops::Range<u64>) -> (f64, usize, usize) {
    let r = robot(name);
    let reference = calibrate(&campaign(&r, 0.0, 1), &r.desc, &options()).unwrap();
    let mut z = Vec::new();
    for seed in seeds {
        let cal = calibrate(&campaign(&r, NOISE_MM, seed), &r.desc, &options()).unwrap();
        z.extend(normalised_errors(&cal, &reference));
    }
    let n = z.len();
    let rms = (z.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
    (rms, z.iter().filter(|v| v.abs() > 3.0).count(), n)
}

fn assert_calibrated_within_sigma(name: &str, seeds: std::ops::Range<u64>) {
    let (rms, outside, n) = check(name, seeds.clone());
    println!(
        "{name}: seeds {}..{}, {n} normalised errors, RMS {rms:.3}, {outside} beyond 3 sigma",
        seeds.start, seeds.end
    );
    assert_within_sigma(name, rms, outside, n);
}

/// The two checks of a calibration's reported sigmas over `n` normalised errors.
fn assert_within_sigma(name: &str, rms: f64, outside: usize, n: usize) {
    // RMS of n unit normals: standard error 1/sqrt(2n); 4 standard errors.
    assert!((rms - 1.0).abs() < 4.0 / (2.0 * n as f64).sqrt(), "{name}: RMS {rms}");
    // P(|z| > 3) = 0.0027: beyond n * 0.0027 + 4 sqrt(n * 0.0027) is below 1e-4 for a right sigma.
    let expected = n as f64 * 0.0027;
    assert!(
        (outside as f64) <= expected + 4.0 * expected.sqrt() + 1.0,
        "{name}: {outside} of {n} beyond 3 sigma"
    );
}

#[test]
fn table_prpp_is_calibrated_within_its_sigma() {
    assert_calibrated_within_sigma("table-prpp", 100..104);
}

#[test]
fn positioner_is_calibrated_within_its_sigma() {
    assert_calibrated_within_sigma("positioner-2axis", 100..104);
}

#[test]
fn scara_is_calibrated_within_its_sigma() {
    assert_calibrated_within_sigma("scara-rrpr", 100..104);
}

#[test]
fn arm_with_a_repeated_sweep_and_wandering_held_joints_is_calibrated_within_its_sigma() {
    assert_calibrated_within_sigma("arm6-dh", 100..103);
}

/// The full check of docs/validation.md (`make test-robots`): 50 seeds per robot.
#[test]
#[ignore = "50 seeds per robot: make test-robots"]
fn fifty_seeds_per_test_robot() {
    // Every robot is checked and printed before any assertion fails.
    let names = ["table-prpp", "positioner-2axis", "scara-rrpr", "arm6-dh"];
    let results: Vec<_> = names
        .iter()
        .map(|name| {
            let (rms, outside, n) = check(name, 1000..1050);
            println!("{name}: seeds 1000..1050, {n} normalised errors, RMS {rms:.3}, {outside} beyond 3 sigma");
            (name, rms, outside, n)
        })
        .collect();
    for (name, rms, outside, n) in results {
        assert!((0.8..=1.25).contains(&rms), "{name}: RMS {rms} outside 0.8-1.25");
        assert_within_sigma(name, rms, outside, n);
    }
}
