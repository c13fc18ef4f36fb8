//! `calibrate --refine --carry`: a diagnosis's named effects as candidates the refined model
//! carries ([`carried_candidates`]; the refinement itself is
//! [`crate::calibration::refit_model::refine::refine_carrying`]).

use super::{Candidate, Diagnosis, validation_poses};
use crate::measurement::MeasurementSet;
use crate::physics::{ApproachSource, HarmonicPeriod};
use crate::robot::RobotDescription;

/// Whether a model can carry candidate `c` of a robot of `desc` ([`crate::calibration::refit_model::Predictor::carried_robot`]):
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
