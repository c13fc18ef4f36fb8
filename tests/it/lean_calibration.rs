//! The lean calibration path of the Monte-Carlo trials (`calibrate_model`) against the full
//! one (`calibrate`): the same model and row sigmas, bit for bit (compared through `{:?}`,
//! which prints every f64 as its shortest round-trip text, so two values print alike only when
//! their bits are equal, NaN included), on shapes unlike each other: the paper robot with its
//! repeatability jitter, the noise estimated from the residuals (two passes), a sliding-joint
//! table, a SCARA, an arm with a repeated sweep and wandering held joints (fit-and-correct
//! passes), and the paper's estimator.

use axiscal::calibration::procedure::{AxisEstimator, CalibrationOptions, Detail, calibrate, calibrate_model};
use axiscal::measurement::{IsotropicNoise, MeasurementModel, MeasurementSet};
use axiscal::plan::{CalibrationPlan, ValidationPlan};
use axiscal::robot::{Controller, RobotDescription, RobotModel};
use axiscal::sim::{AnalyticArm, PerturbationSpec, perturb, simulate_campaign};
use rand::{SeedableRng, rngs::ChaCha12Rng};
use std::path::Path;

fn campaign(desc: &RobotDescription, plan: &CalibrationPlan, truth: &RobotModel, seed: u64) -> MeasurementSet {
    let mut arm = AnalyticArm::new(truth.clone(), Controller::from_description(desc));
    let validation = ValidationPlan {
        poses: 3,
        ..ValidationPlan::workspace_default(desc.dof())
    };
    let instrument = MeasurementModel::Isotropic(IsotropicNoise {
        net_radial_rms_mm: 0.15,
    });
    let out = simulate_campaign(
        desc,
        plan,
        &validation,
        &mut arm,
        &instrument,
        &mut ChaCha12Rng::seed_from_u64(seed),
    )
    .expect("the campaign runs");
    MeasurementSet::new(desc.dof(), out.rows).unwrap()
}

/// Asserts the lean path's model (and, with the covariance, its row sigmas) equal the full path's.
fn assert_lean_equals_full(what: &str, set: &MeasurementSet, desc: &RobotDescription, options: &CalibrationOptions) {
    let full = calibrate(set, desc, options).unwrap_or_else(|e| panic!("{what}: {e}"));
    let model = calibrate_model(set, desc, options, Detail::Model).unwrap();
    assert_eq!(
        format!("{:?}", model.robot),
        format!("{:?}", full.robot),
        "{what}: model"
    );
    assert_eq!(model.row_sigma, None, "{what}");
    assert_eq!(model.held_passes, full.held_passes, "{what}");
    let with_cov = calibrate_model(set, desc, options, Detail::ModelAndCovariance).unwrap();
    assert_eq!(
        format!("{:?}", with_cov.robot),
        format!("{:?}", full.robot),
        "{what}: model"
    );
    assert_eq!(
        format!("{:?}", with_cov.row_sigma),
        format!("{:?}", Some(&full.row_sigma)),
        "{what}: row sigmas"
    );
    assert_eq!(with_cov.model_covariance, None, "{what}");
    let with_model_cov = calibrate_model(set, desc, options, Detail::ModelCovariance).unwrap();
    assert_eq!(
        format!("{:?}", with_model_cov.model_covariance),
        format!("{:?}", full.model_covariance),
        "{what}: model covariance"
    );
}

#[test]
fn the_lean_path_fits_the_paper_robot_exactly_as_the_full_path() {
    let desc = RobotDescription::asea_irb6l();
    let plan = CalibrationPlan::table1(6);
    let truth = axiscal::sim::paper_robot();
    for seed in [3, 4] {
        let set = campaign(&desc, &plan, &truth, seed);
        assert_lean_equals_full("paper, ML", &set, &desc, &CalibrationOptions::default());
        let estimated = CalibrationOptions {
            estimate_noise: true,
            repeatability_sigma_rad: Some(vec![2e-5]),
            ..CalibrationOptions::default()
        };
        assert_lean_equals_full("paper, noise estimated, repeatability", &set, &desc, &estimated);
        let paper = CalibrationOptions {
            estimator: AxisEstimator::Paper,
            ..CalibrationOptions::default()
        };
        assert_lean_equals_full("paper's estimator", &set, &desc, &paper);
    }
}

#[test]
fn the_lean_path_fits_robots_unlike_the_paper_arm_exactly_as_the_full_path() {
    let spec =
        PerturbationSpec::from_toml_str(include_str!("../data/test-robot-spec.toml"), "test-robot-spec.toml").unwrap();
    for (name, plan_file) in [
        ("table-prpp", Some("scenarios/robots/table-prpp-plan.toml")),
        ("scara-rrpr", None),
        ("arm6-dh", Some("scenarios/robots/arm6-jitter-plan.toml")),
    ] {
        let desc = RobotDescription::from_file(Path::new(&format!("scenarios/robots/{name}.toml"))).unwrap();
        let plan = match plan_file {
            Some(path) => {
                let path = Path::new(path);
                axiscal::toml_file::parse(&axiscal::toml_file::read(path).unwrap(), path).unwrap()
            }
            None => CalibrationPlan::for_robot(&desc),
        };
        let truth = perturb(&desc, &spec, &mut ChaCha12Rng::seed_from_u64(7)).unwrap();
        let set = campaign(&desc, &plan, &truth, 11);
        let options = CalibrationOptions {
            noise_rms_3d_mm: 0.15,
            estimate_noise: name == "scara-rrpr",
            ..CalibrationOptions::default()
        };
        assert_lean_equals_full(name, &set, &desc, &options);
    }
}
