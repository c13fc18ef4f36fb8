//! `calibrate --refine`: the calibrated model refined on the file's free poses by the
//! shared refinement ([`refine_free_poses`]) through the baseline refit's model
//! ([`Predictor`] without candidates, [`RefitScope::Identified`]): the same model and the
//! same maths as the diagnosis's baseline, with the noise-tied rank rule of
//! [`crate::calibration::refine`] and the tool targets fixed.

use super::{Pose, Predictor, RefitScope, reference_temperature, validation_poses};
use crate::calibration::procedure::Calibration;
use crate::calibration::refine::{RefineError, RefineOptions, refine_free_poses, unrefined_sigma};
use crate::measurement::MeasurementSet;
use crate::robot::RobotDescription;

/// `cal` with its robot refined on the free poses of `set` (`moved_joint = 0`, not the `tool`
/// experiment) and the refinement's summary in `refinement`.
pub fn refine_calibration(
    set: &MeasurementSet,
    desc: &RobotDescription,
    cal: &Calibration,
    options: &RefineOptions,
) -> Result<Calibration, RefineError> {
    let poses = validation_poses(set.rows(), desc);
    let predictor = Predictor::new(&cal.robot, desc, reference_temperature(set), RefitScope::Identified);
    let layout = predictor.refit_layout();
    let sigma: Vec<Option<f64>> = layout.iter().map(|p| unrefined_sigma(cal, p)).collect();
    let targets: Vec<usize> = poses.iter().map(|p| p.targets.len()).collect();
    let residuals = |p: &[f64], which: &[usize]| {
        let selected: Vec<&Pose> = which.iter().map(|&i| &poses[i]).collect();
        predictor.residuals(p, &selected)
    };
    let out = refine_free_poses(residuals, &targets, &layout, &sigma, &predictor.steps(), options)?;
    let mut refined = cal.clone();
    refined.robot = predictor.refit_robot(&out.params);
    refined.refinement = Some(out.summary);
    Ok(refined)
}
