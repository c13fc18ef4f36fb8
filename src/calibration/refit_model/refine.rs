//! `calibrate --refine`: the calibrated model refined on the file's free poses by the shared
//! refinement ([`refine_free_poses`]) through the refit model ([`Predictor`],
//! [`RefitScope::Identified`]): the same model and the same maths as the diagnosis's baseline,
//! with the noise-tied rank rule of [`crate::calibration::refine`] and the tool targets fixed.
//! With `--carry`, a diagnosis's named effects are fitted with it and folded into the model
//! ([`Predictor::carried_robot`]).

use super::{Candidate, Pose, Predictor, RefitScope, reference_temperature, validation_poses_at_most};
use crate::calibration::free_pose::OutlierPose;
use crate::calibration::procedure::Calibration;
use crate::calibration::refine::{RefineError, RefineOptions, Refinement, refine_free_poses, unrefined_sigma};
use crate::measurement::MeasurementSet;
use crate::robot::RobotDescription;

/// `cal` with its robot refined on the free poses of `set` (`moved_joint = 0`, not the `tool`
/// experiment), and the refinement's summary.
pub fn refine_calibration(
    set: &MeasurementSet,
    desc: &RobotDescription,
    cal: &Calibration,
    options: &RefineOptions,
) -> Result<(Calibration, Refinement), RefineError> {
    refine_carrying(set, desc, cal, options, &[])
}

/// [`refine_calibration`] with the effects `carried` (candidates a model can carry, as
/// `crate::diagnosis::carried_candidates` picks them) fitted with the refit and folded into the
/// refined robot ([`Predictor::carried_robot`]).
pub fn refine_carrying(
    set: &MeasurementSet,
    desc: &RobotDescription,
    cal: &Calibration,
    options: &RefineOptions,
    carried: &[Candidate],
) -> Result<(Calibration, Refinement), RefineError> {
    let (poses, left_out) = validation_poses_at_most(set.rows(), desc, options.max_poses);
    let predictor =
        Predictor::new(&cal.robot, desc, reference_temperature(set), RefitScope::Identified).with_candidates(carried);
    let mut layout = predictor.refit_layout();
    layout.extend(predictor.effect_layout());
    let sigma: Vec<Option<f64>> = layout.iter().map(|p| unrefined_sigma(cal, p)).collect();
    let targets: Vec<usize> = poses.iter().map(|p| p.targets.len()).collect();
    let residuals = |p: &[f64], which: &[usize]| {
        let selected: Vec<&Pose> = which.iter().map(|&i| &poses[i]).collect();
        predictor.residuals(p, &selected)
    };
    let labels: Vec<String> = poses.iter().map(|p| pose_label(set, p)).collect();
    let out = refine_free_poses(
        residuals,
        &targets,
        &labels,
        &layout,
        &sigma,
        &predictor.steps(),
        options,
    )?;
    let outliers = out
        .outliers
        .iter()
        .map(|f| OutlierPose {
            experiment: poses[f.group].experiment.clone(),
            step: poses[f.group].step,
            rms_mm: f.rms,
            fence_mm: f.fence,
            false_alarm: None,
            dropped: !options.keep_outliers,
            spacing_departure_mm: None,
            spacing_fence_mm: None,
        })
        .collect();
    let mut refined = cal.clone();
    refined.robot = predictor.carried_robot(&out.params);
    let refinement = Refinement {
        poses_left_out: left_out,
        outliers,
        ..out.summary
    };
    Ok((refined, refinement))
}

/// `validation step 5 (line 150)`: pose `p` of `set` in messages.
pub(crate) fn pose_label(set: &MeasurementSet, p: &Pose) -> String {
    let row = set
        .rows()
        .iter()
        .position(|m| m.experiment == p.experiment && m.step == p.step);
    match row.and_then(|r| set.line_of(r)) {
        Some(line) => format!("{} step {} (line {line})", p.experiment, p.step),
        None => format!("{} step {}", p.experiment, p.step),
    }
}
