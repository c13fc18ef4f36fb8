//! `calibrate --refine`: the calibrated model refined on the file's free poses by the
//! shared refinement ([`refine_free_poses`]) through the baseline refit's model
//! ([`Predictor`], [`RefitScope::Identified`]): the same model and the same maths as the
//! diagnosis's baseline, with the noise-tied rank rule of [`crate::calibration::refine`] and
//! the tool targets fixed. With `--carry`, a diagnosis's named effects are fitted with it and
//! folded into the model ([`carried_candidates`], [`Predictor::carried_robot`]).

use super::{
    Candidate, Diagnosis, Pose, Predictor, RefitScope, reference_temperature, validation_poses,
    validation_poses_at_most,
};
use crate::calibration::free_pose::OutlierPose;
use crate::calibration::procedure::Calibration;
use crate::calibration::refine::{RefineError, RefineOptions, Refinement, refine_free_poses, unrefined_sigma};
use crate::measurement::MeasurementSet;
use crate::physics::{ApproachSource, HarmonicPeriod};
use crate::robot::RobotDescription;

/// `cal` with its robot refined on the free poses of `set` (`moved_joint = 0`, not the `tool`
/// experiment) and the refinement's summary in `refinement`.
pub fn refine_calibration(
    set: &MeasurementSet,
    desc: &RobotDescription,
    cal: &Calibration,
    options: &RefineOptions,
) -> Result<Calibration, RefineError> {
    refine_carrying(set, desc, cal, options, &[])
}

/// [`refine_calibration`] with the effects `carried` (candidates a model can carry,
/// [`carried_candidates`]) fitted with the refit and folded into the refined robot
/// ([`Predictor::carried_robot`]).
pub fn refine_carrying(
    set: &MeasurementSet,
    desc: &RobotDescription,
    cal: &Calibration,
    options: &RefineOptions,
    carried: &[Candidate],
) -> Result<Calibration, RefineError> {
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
            dropped: !options.keep_outliers,
            spacing_departure_mm: None,
            spacing_fence_mm: None,
        })
        .collect();
    let mut refined = cal.clone();
    refined.robot = predictor.carried_robot(&out.params);
    refined.refinement = Some(Refinement {
        poses_left_out: left_out,
        outliers,
        ..out.summary
    });
    Ok(refined)
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

/// Whether a model can carry candidate `c` of a robot of `desc` ([`Predictor::carried_robot`]):
/// a joint compliance (`robot.effects.compliance`); a backlash signed by the actuator's
/// direction, or by the command's on a joint whose command the controller does not couple (the
/// two directions are then one; `robot.effects.backlash`); a gear harmonic in the
/// transmission's period (into the transmission). Not a joint-period harmonic, a wobble, a
/// thermal expansion or an instrument scale: a model has no place for them.
pub fn carriable(c: &Candidate, desc: &RobotDescription) -> bool {
    match *c {
        Candidate::JointCompliance { .. } => true,
        Candidate::Backlash {
            direction: ApproachSource::Actuator,
            ..
        } => true,
        Candidate::Backlash { joint, .. } => desc.nominal_coupling_into(joint).is_none(),
        Candidate::GearHarmonic { period, .. } => period == HarmonicPeriod::Transmission,
        _ => false,
    }
}

/// Why a diagnosis's effects cannot be carried.
#[derive(Debug, thiserror::Error)]
pub enum CarryError {
    /// The diagnosis names no effect.
    #[error("the diagnosis names no effect (its verdict is `{0}`): nothing to carry")]
    NothingNamed(String),
    /// A named effect is not a candidate of this robot and data.
    #[error(
        "{effect} on joint {joint:?} ({member}) is not a candidate for this robot and data: the diagnosis was made for another"
    )]
    NotACandidate {
        /// The effect.
        effect: String,
        /// Its joint.
        joint: Option<usize>,
        /// Its member.
        member: String,
    },
    /// A named effect has no place in a model.
    #[error("{effect} ({member}) has no place in a calibrated model ({})", CARRIABLE)]
    NotCarriable {
        /// The effect.
        effect: String,
        /// Its member.
        member: String,
    },
}

/// What [`carriable`] accepts, for messages.
pub const CARRIABLE: &str = "carried: joint_compliance, backlash signed by the actuator (or by the command where the controller couples nothing into the joint), gear_harmonic in the transmission's period";

/// The effects diagnosis `d` names, as candidates of `desc` measured at `set`: the named
/// member of the main effect and, for a second, the best-scored member of its effect and
/// joint. Every one must be [`carriable`].
pub fn carried_candidates(
    d: &Diagnosis,
    desc: &RobotDescription,
    set: &MeasurementSet,
) -> Result<Vec<Candidate>, CarryError> {
    let main = (d.outcome.effect.clone(), d.outcome.joint);
    let Some(member) = d.member.clone() else {
        return Err(CarryError::NothingNamed(d.outcome.effect.clone()));
    };
    let mut named: Vec<(String, Option<usize>, String)> = vec![(main.0.clone(), main.1, member)];
    for e in d.effects.iter().filter(|e| (e.effect.clone(), e.joint) != main) {
        let best = d.candidates.iter().find(|c| c.effect == e.effect && c.joint == e.joint);
        named.push((
            e.effect.clone(),
            e.joint,
            best.map_or_else(String::new, |c| c.member.clone()),
        ));
    }
    let poses = validation_poses(set.rows(), desc);
    let library = Candidate::library(desc, &poses, crate::diagnosis::DEFAULT_MAX_HARMONIC_ORDER);
    named
        .into_iter()
        .map(|(effect, joint, member)| {
            let c = library
                .iter()
                .find(|c| c.effect_name() == effect && c.joint() == joint && c.member_name() == member)
                .copied()
                .ok_or_else(|| CarryError::NotACandidate {
                    effect: effect.clone(),
                    joint,
                    member: member.clone(),
                })?;
            if !carriable(&c, desc) {
                return Err(CarryError::NotCarriable { effect, member });
            }
            Ok(c)
        })
        .collect()
}
