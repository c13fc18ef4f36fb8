//! Noise-only replicas of a campaign: the same commands on the CALIBRATED robot, each target
//! where the calibrated model puts it, plus isotropic Gaussian noise of the stated 3-D RMS
//! (the "Monte-Carlo of the same commands on the calibrated robot" of the diagnosis).

use super::DiagnosisError;
use crate::calibration::procedure::Calibration;
use crate::measurement::{Measurement, MeasurementSet};
use crate::plan::TOOL_EXPERIMENT;
use crate::robot::commands_to_internal;
use crate::robot::{Controller, RobotDescription};
use nalgebra::{Point3, Vector3};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use std::collections::HashMap;

/// Noise-free positions of every row of `set` on the calibrated robot \[m\]. Axis-experiment
/// targets sit at their mean position in their link's frame (target 0's link for a target the
/// description does not place) (estimated from the measurements
/// through the calibrated model); tool targets at the description's tool targets.
pub fn clean_positions(
    set: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
) -> Result<Vec<Point3<f64>>, DiagnosisError> {
    let controller = Controller::from_description(desc);
    let model = cal.robot.phi_model();
    let tool_targets = desc.tool_targets_m();
    let link_of = |m: &Measurement| -> Option<usize> {
        let t = desc.axis_targets_of(m.moved_joint)?;
        // A target the description does not place (e.g. a third reflector) turns rigidly with
        // target 0: only the experiment's joint moves.
        match (m.target, t.target1) {
            (1, Some(t1)) => Some(t1.link - 1),
            _ => Some(t.target0.link - 1),
        }
    };
    let mut frames = Vec::with_capacity(set.rows().len());
    for m in set.rows() {
        let q = calibrated_joint_values(cal, &controller, desc, m)?;
        frames.push(model.poses(&q));
    }
    // Mean link-frame position of each axis target.
    let mut sums: HashMap<(&str, usize), (Vector3<f64>, usize)> = HashMap::new();
    for (m, f) in set.rows().iter().zip(&frames) {
        if m.moved_joint > 0
            && let Some(l) = link_of(m)
        {
            let p = f.world_from_link[l].inverse() * m.position_m();
            let e = sums
                .entry((m.experiment.as_str(), m.target))
                .or_insert((Vector3::zeros(), 0));
            e.0 += p.coords;
            e.1 += 1;
        }
    }
    set.rows()
        .iter()
        .zip(&frames)
        .map(|(m, f)| {
            if m.moved_joint > 0 {
                let l = link_of(m).ok_or_else(|| DiagnosisError::Model {
                    message: format!(
                        "experiment {}: target {} of joint {} is not in the description",
                        m.experiment, m.target, m.moved_joint
                    ),
                })?;
                let (s, n) = sums[&(m.experiment.as_str(), m.target)];
                Ok(f.world_from_link[l] * Point3::from(s / n as f64))
            } else {
                let t = tool_targets.get(m.target).ok_or_else(|| DiagnosisError::Model {
                    message: format!(
                        "experiment {}: tool target {} is not in the description",
                        m.experiment, m.target
                    ),
                })?;
                Ok(f.world_from_tool * t)
            }
        })
        .collect()
}

/// The calibrated joint values of `m`'s commands (the controller, then `cal`'s transmissions
/// and couplings).
pub(super) fn calibrated_joint_values(
    cal: &Calibration,
    controller: &Controller,
    desc: &RobotDescription,
    m: &Measurement,
) -> Result<Vec<f64>, DiagnosisError> {
    cal.robot
        .joint_values(controller, &commands_to_internal(desc, &m.cmd))
        .map_err(|e| DiagnosisError::Model {
            message: format!("experiment {} step {}: {e}", m.experiment, m.step),
        })
}

/// Whether `m` is a validation measurement (`docs/formats.md#measurement-csv`: `moved_joint = 0`, not the
/// tool experiment).
pub fn is_validation(m: &Measurement) -> bool {
    m.moved_joint == 0 && m.experiment != TOOL_EXPERIMENT
}

/// One noise-only replica: `set`'s rows at `clean` plus isotropic noise of 3-D RMS
/// `noise_rms_3d_m` (each coordinate `noise_rms_3d_m / sqrt(3)`); validation rows get noise
/// only when `validation_noise` (the diagnoser draws theirs separately, many per replica).
pub fn replica<R: Rng + ?Sized>(
    set: &MeasurementSet,
    clean: &[Point3<f64>],
    noise_rms_3d_m: f64,
    validation_noise: bool,
    rng: &mut R,
) -> Result<MeasurementSet, DiagnosisError> {
    let sigma = noise_rms_3d_m / 3f64.sqrt();
    let rows = set
        .rows()
        .iter()
        .zip(clean)
        .map(|(m, p)| {
            let noisy = validation_noise || !is_validation(m);
            let mut m = m.clone();
            for (c, x) in m.position_mm.iter_mut().zip(p.iter()) {
                let z: f64 = if noisy { StandardNormal.sample(rng) } else { 0.0 };
                *c = (x + sigma * z) * 1e3;
            }
            m
        })
        .collect();
    MeasurementSet::new(set.joint_count(), rows).map_err(|e| DiagnosisError::Model {
        message: format!("noise replica: {e}"),
    })
}
