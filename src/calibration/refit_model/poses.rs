//! Validation poses as the diagnoser sees them: commands, approach directions from the
//! command history, conditions and measured tool targets (`docs/formats.md#measurement-csv`).

use crate::measurement::TOOL_EXPERIMENT;
use crate::measurement::bounded::{configuration_key, spread_over_configurations};
use crate::measurement::{Measurement, MeasurementSet};
use crate::numerics::stats::mean;
use crate::physics::pose_approaches;
use crate::robot::RobotDescription;
use crate::robot::commands_to_internal;
use nalgebra::Point3;
use std::collections::HashMap;

/// One measured validation pose.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    /// Experiment id.
    pub experiment: String,
    /// Step.
    pub step: usize,
    /// Commands (internal units: rad, m).
    pub cmd: Vec<f64>,
    /// Approach direction of every joint's command: `sign(cmd_k(s) - cmd_k(s-1))` over the
    /// poses in file order (all experiments), the previous direction when the command did not
    /// change, 0 before any motion.
    pub approach: Vec<f64>,
    /// The same for every joint's actuator command (after the fig. 3 decoupling with the
    /// description's nominal couplings; a change of at most [`crate::physics::UNMOVED_ACTUATOR_RAD`] is no
    /// motion): where a backlash in the actuator sits.
    pub actuator_approach: Vec<f64>,
    /// Ambient temperature \[deg C\].
    pub temperature_c: f64,
    /// Payload at the tool \[kg\].
    pub payload_kg: f64,
    /// Measured tool targets: (target id, position in the instrument frame \[m\]).
    pub targets: Vec<(usize, Point3<f64>)>,
}

/// The validation poses of `rows` (`moved_joint = 0`, not the `tool` experiment), in file
/// order, with their approach directions (command and actuator) taken over every pose of the
/// file.
pub fn validation_poses(rows: &[Measurement], desc: &RobotDescription) -> Vec<Pose> {
    validation_poses_at_most(rows, desc, usize::MAX).0
}

/// [`validation_poses`], at most `max` of them, evenly spaced through the file over as many
/// distinct commands as `max` allows ([`spread_over_configurations`] over their order), and
/// how many were left out. Only the kept poses are built; the approach directions still
/// follow every pose of the file.
pub fn validation_poses_at_most(rows: &[Measurement], desc: &RobotDescription, max: usize) -> (Vec<Pose>, usize) {
    // Every pose's ordinal (the order of its first row) and whether it is a validation pose.
    let mut ordinal: HashMap<(&str, usize), usize> = HashMap::new();
    let mut validation: Vec<(usize, &[f64])> = Vec::new();
    for m in rows {
        let next = ordinal.len();
        if *ordinal.entry((m.experiment.as_str(), m.step)).or_insert(next) == next
            && m.moved_joint == 0
            && m.experiment != TOOL_EXPERIMENT
        {
            validation.push((next, &m.cmd));
        }
    }
    let count = validation.len();
    let mut slot: Vec<Option<usize>> = vec![None; ordinal.len()];
    let kept = spread_over_configurations(validation, max, |(_, cmd)| configuration_key(cmd));
    for (k, (o, _)) in kept.into_iter().enumerate() {
        slot[o] = Some(k);
    }
    let mut poses: Vec<Pose> = Vec::new();
    let mut approaches = pose_approaches(rows, desc);
    let mut built = 0;
    for m in rows {
        let o = ordinal[&(m.experiment.as_str(), m.step)];
        if o == built {
            // The pose's first row: its approach is the next one (one per pose, in this order).
            let a = approaches
                .next()
                .unwrap_or_else(|| unreachable!("one approach per distinct (experiment, step)"));
            built += 1;
            if slot[o].is_some() {
                poses.push(Pose {
                    experiment: m.experiment.clone(),
                    step: m.step,
                    cmd: commands_to_internal(desc, &m.cmd),
                    approach: a.command,
                    actuator_approach: a.actuator,
                    temperature_c: m.temperature_c,
                    payload_kg: m.payload_kg,
                    targets: Vec::new(),
                });
            }
        }
        if let Some(k) = slot[o] {
            poses[k].targets.push((m.target, m.position_m()));
        }
    }
    let left_out = count - poses.len();
    (poses, left_out)
}

/// Whether each pose is a training pose: the configurations (bit-identical commands) in the
/// order they first appear, the even ones training and the odd ones held out, so that a
/// configuration measured again never straddles the halves (the free-pose calibration's
/// `--holdout` split); with distinct commands, the even and odd file positions.
pub fn training_mask(poses: &[Pose]) -> Vec<bool> {
    let mut seen: std::collections::HashMap<Vec<u64>, usize> = std::collections::HashMap::new();
    poses
        .iter()
        .map(|p| {
            let key: Vec<u64> = p.cmd.iter().map(|c| (c + 0.0).to_bits()).collect();
            let next = seen.len();
            seen.entry(key).or_insert(next).is_multiple_of(2)
        })
        .collect()
}

/// Deterministic split into training and held-out poses ([`training_mask`]), file order
/// within each.
pub fn split(poses: &[Pose]) -> (Vec<&Pose>, Vec<&Pose>) {
    let mask = training_mask(poses);
    let half = |training: bool| {
        poses
            .iter()
            .zip(&mask)
            .filter(|(_, t)| **t == training)
            .map(|(p, _)| p)
            .collect()
    };
    (half(true), half(false))
}

/// Number of measured targets over `poses`.
pub fn target_count(poses: &[&Pose]) -> usize {
    poses.iter().map(|p| p.targets.len()).sum()
}

/// Whether `set` holds free poses only (no axis experiment).
pub fn free_poses_only(set: &MeasurementSet) -> bool {
    !set.rows().iter().any(|m| m.moved_joint > 0)
}

/// The temperature the calibration holds at: the mean of the rows it is fitted to (the axis
/// experiments', or every row's for free poses; 20 deg C without rows).
pub fn reference_temperature(set: &MeasurementSet) -> f64 {
    let free = free_poses_only(set);
    let rows: Vec<f64> = set
        .rows()
        .iter()
        .filter(|m| free || m.moved_joint > 0)
        .map(|m| m.temperature_c)
        .collect();
    if rows.is_empty() { 20.0 } else { mean(&rows) }
}
