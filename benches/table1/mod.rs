//! The Table-1 campaign of the paper robot (seed 1, no validation poses) that
//! `benches/calibration.rs` and `examples/profile_speed.rs` calibrate.

use axiscal::measurement::{MeasurementModel, MeasurementSet};
use axiscal::plan::{CalibrationPlan, ValidationPlan};
use axiscal::robot::{Controller, RobotDescription};
use axiscal::sim::{AnalyticArm, simulate_campaign};
use rand::{SeedableRng, rngs::ChaCha12Rng};

/// The description and the measurement set.
pub fn campaign() -> (RobotDescription, MeasurementSet) {
    let desc = RobotDescription::asea_irb6l();
    let mut arm = AnalyticArm::new(axiscal::sim::paper_robot(), Controller::from_description(&desc));
    let validation = ValidationPlan {
        poses: 0,
        ..ValidationPlan::workspace_default(6)
    };
    let out = simulate_campaign(
        &desc,
        &CalibrationPlan::table1(6),
        &validation,
        &mut arm,
        &MeasurementModel::paper_isotropic(),
        &mut ChaCha12Rng::seed_from_u64(1),
    )
    .expect("the paper campaign simulates");
    let set = MeasurementSet::new(6, out.rows).expect("consistent rows");
    (desc, set)
}

/// The first target's points of every sweep of `set`: the baseline's six circle fits.
pub fn target0_sweeps(set: &MeasurementSet) -> Vec<Vec<nalgebra::Point3<f64>>> {
    set.experiments()
        .iter()
        .filter(|e| e.moved_joint > 0)
        .map(|e| {
            e.rows
                .iter()
                .filter(|r| r.target == 0)
                .map(|r| r.position_m())
                .collect()
        })
        .collect()
}
