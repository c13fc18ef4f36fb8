//! Held joints as recorded (`docs/formats.md#held-joints`): every step's recorded commands of
//! every joint enter the model. Each observed point is moved from the pose the robot stood at
//! to the experiment's *design* pose, by the current calibrated model:
//! `p' = W_L(q_design) W_L(q_recorded)^-1 p`, `W_L` the pose of the link `L` carrying the
//! target (the description's `axis_targets`, else the last link).
//!
//! The design pose of target 0 of a sweep of joint `k` has every joint at its reference value
//! except joint `k`, whose active angle is the recorded one (its passive part from joint
//! `k-1` at the reference); target 1 (the coupling into `k+1`) also keeps actuator `k+1` at the
//! sweep's held value and its passive motion. Joints held at other values in a whole sweep
//! (a sweep at another pose) are moved the same way, so several sweeps of one joint lie on one
//! arc or line. The procedure alternates fits and this correction until it stops changing
//! ([`super::calibrate`]).

use super::experiments::AxisExperiment;
use crate::numerics::stats::{QuantileMethod, quantile};
use crate::robot::{Controller, ModelError, RobotDescription, RobotModel, commands_to_internal};
use nalgebra::{Isometry3, Point3};

/// Recorded commands that differ from the design by at most this \[deg or mm\] are the design:
/// the rounding of commands printed with 9 or more significant digits.
pub const DESIGN_TOLERANCE: f64 = 1e-9;

/// Whether every experiment stands exactly at its design pose (held joints at the reference,
/// a follower joint on its hold-still formula) with one sweep per joint: then no correction
/// is needed and the first fits are the calibration.
pub(super) fn exactly_as_designed(experiments: &[AxisExperiment], reference: &[f64], desc: &RobotDescription) -> bool {
    let mut swept: Vec<usize> = experiments.iter().map(|e| e.joint).collect();
    swept.sort_unstable();
    if swept.windows(2).any(|w| w[0] == w[1]) {
        return false;
    }
    experiments.iter().all(|e| {
        let k = e.joint - 1;
        e.commands.iter().all(|c| {
            c.iter().enumerate().all(|(j, v)| {
                if j == k {
                    true
                } else if j == k + 1 && e.holds_next_still {
                    let slope = desc.nominal_coupling_from(e.joint).unwrap_or(0.0);
                    (v - (e.commands[0][j] + slope * (c[k] - e.commands[0][k]))).abs() <= DESIGN_TOLERANCE
                } else {
                    (v - reference[j]).abs() <= DESIGN_TOLERANCE
                }
            })
        })
    })
}

/// The model and reference the design poses are computed with.
pub(super) struct Corrector<'a> {
    /// The current calibrated robot.
    pub model: &'a RobotModel,
    /// The nominal controller.
    pub controller: &'a Controller,
    /// The description (target links, units).
    pub desc: &'a RobotDescription,
    /// The reference commands (file units).
    pub reference_cmd: &'a [f64],
}

impl Corrector<'_> {
    /// The points of target `target` (0 or 1) of `e`, moved to the design pose.
    pub(super) fn corrected(&self, e: &AxisExperiment, target: usize) -> Result<Vec<Point3<f64>>, ModelError> {
        let (points, steps) = match target {
            0 => (&e.target0_m, &e.target0_steps),
            _ => (&e.target1_m, &e.target1_steps),
        };
        let n = self.desc.dof();
        let k = e.joint - 1;
        let link = target_link(self.desc, e.joint, target);
        let u_ref = self
            .controller
            .decouple(&commands_to_internal(self.desc, self.reference_cmd))?;
        let q_ref = self.model.joint_values_from_actuators(&u_ref)?;
        let u_all: Vec<Vec<f64>> = e
            .commands
            .iter()
            .map(|c| self.controller.decouple(&commands_to_internal(self.desc, c)))
            .collect::<Result<_, _>>()?;
        // Actuator k+1's held value in this sweep (target 1 keeps it).
        let next_held = (k + 1 < n).then(|| {
            let v: Vec<f64> = u_all.iter().map(|u| u[k + 1]).collect();
            quantile(&v, 0.5, QuantileMethod::Linear)
        });
        let free = if target == 0 { k } else { (k + 1).min(n - 1) };
        let phi = self.model.phi_model();
        let w = |q: &[f64]| -> Isometry3<f64> { phi.poses(q).world_from_link[link] };
        points
            .iter()
            .zip(steps)
            .map(|(p, &i)| {
                let u = &u_all[i];
                let q_rec = self.model.joint_values_from_actuators(u)?;
                let mut u_design = u_ref.clone();
                u_design[k] = u[k];
                if target == 1
                    && let Some(h) = next_held
                {
                    u_design[k + 1] = h;
                }
                let mut q_design = self.model.joint_values_from_actuators(&u_design)?;
                q_design[free + 1..].copy_from_slice(&q_ref[free + 1..]);
                Ok(w(&q_design) * w(&q_rec).inverse_transform_point(p))
            })
            .collect()
    }
}

/// The link (0-based) carrying target `target` (0 or 1) of a sweep of `joint` (1-based): the
/// description's `axis_targets`, else the last link.
pub(super) fn target_link(desc: &RobotDescription, joint: usize, target: usize) -> usize {
    desc.axis_targets_of(joint)
        .and_then(|t| if target == 0 { Some(t.target0) } else { t.target1 })
        .map_or(desc.dof() - 1, |t| t.link - 1)
}
