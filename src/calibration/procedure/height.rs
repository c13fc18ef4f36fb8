//! The position along a robot's parallel axes (a SCARA's height) from the tool targets seen at
//! the reference pose, where the sweeps leave it open and the tool frame is not measured.
//!
//! When every observed rotary axis is parallel to axis `a`, no common normal places the base
//! frame along `a` (the sequential rule, [`super::BaseRule::unobserved_along`]): a move of the
//! whole model along `a` leaves every observed axis line where it is (the rotary axes are
//! parallel to it; a sliding axis has a direction only). The sweeps alone then keep the
//! description's position, off by the base's height, the rows' offsets along the axes and the
//! sliding joints' zeros, none of which any covariance holds. A tool target measured at the
//! reference pose fixes it when fewer than three are seen there (with three, the measured tool
//! frame takes it): the model is moved along `a` by the mean miss along `a` of the seen targets,
//! `delta = (1/n) sum_i d . (m_i - p_i)` with `d` the observed direction of axis `a`, `m_i` the
//! measured and `p_i` the predicted target `i` (the least-squares translation along `d`; a
//! one-parameter linear fit). Its error, the targets' noise over `n` and the chain's own error
//! along `d` at the reference pose, enters the model's covariance through the same one-sided
//! differences as the tool frame's (`docs/method.md`, "Base frame").

use super::{BaseRule, COMMAND_TOLERANCE};
use crate::measurement::{Measurement, MeasurementSet};
use crate::robot::{Controller, Placement, RobotDescription, RobotModel};
use nalgebra::{Point3, Translation3, Unit, Vector3};

/// The tool targets seen at the reference pose that fix the position along axis `axis`.
#[derive(Clone, Debug)]
pub(super) struct HeightObservation {
    /// The axis (0-based) the base rule leaves open along.
    pub(super) axis: usize,
    /// The experiment observed.
    pub(super) experiment: String,
    /// Its step.
    pub(super) step: usize,
    /// The tool targets seen (0-based, into the description's).
    pub(super) targets: Vec<usize>,
    /// Their measured positions (instrument frame) \[m\].
    pub(super) measured: Vec<Point3<f64>>,
}

/// The first pose of a `moved_joint = 0` experiment at the reference commands that sees at
/// least one tool target, when `rule` leaves the position along an axis open; `None` without.
/// The caller uses it only when no pose there sees all three (the tool frame is not measured).
pub(super) fn height_observation(
    set: &MeasurementSet,
    desc: &RobotDescription,
    reference_cmd: &[f64],
    rule: &BaseRule,
) -> Option<HeightObservation> {
    let axis = rule.unobserved_along()?;
    let count = desc.tool_targets_m().len();
    for e in set.experiments().iter().filter(|e| e.moved_joint == 0) {
        for (step, rows) in e.by_step() {
            let at_ref = at_reference(&rows, reference_cmd);
            if !at_ref {
                continue;
            }
            let seen: Vec<(usize, Point3<f64>)> = (0..count)
                .filter_map(|t| rows.iter().find(|r| r.target == t).map(|r| (t, r.position_m())))
                .collect();
            if !seen.is_empty() {
                return Some(HeightObservation {
                    axis,
                    experiment: e.name.to_string(),
                    step,
                    targets: seen.iter().map(|s| s.0).collect(),
                    measured: seen.iter().map(|s| s.1).collect(),
                });
            }
        }
    }
    None
}

/// `robot` moved along `direction` (world) by the mean miss along it of the tool targets
/// `obs.targets` measured at `measured` (the module's `delta`), at the joint values `q_ref`
/// of the reference pose, with the move \[m\]. `None` where the joint values cannot be
/// computed.
pub(super) fn moved_along(
    robot: &RobotModel,
    (obs, measured): (&HeightObservation, &[Point3<f64>]),
    direction: &Unit<Vector3<f64>>,
    (desc, controller, q_ref): (&RobotDescription, &Controller, &[f64]),
) -> Option<(RobotModel, f64)> {
    let q = robot.joint_values(controller, q_ref).ok()?;
    let link = robot.phi_model().poses(&q).world_from_link[desc.dof() - 1];
    let world_from_tool = link * robot.tool_frame.to_isometry();
    let targets = desc.tool_targets_m();
    let d = direction.into_inner();
    let n = obs.targets.len().min(measured.len());
    if n == 0 {
        return None;
    }
    let sum: f64 = obs
        .targets
        .iter()
        .zip(measured)
        .map(|(&t, m)| d.dot(&(m - world_from_tool * targets[t])))
        .sum();
    let delta = sum / n as f64;
    let mut moved = robot.clone();
    moved.placement = Placement::from_isometry(&(Translation3::from(d * delta) * robot.placement.to_isometry()));
    Some((moved, delta))
}

/// What the base rule says of the position along `obs.axis` once fixed by the tool targets
/// of `obs`, the model moved by `delta_m` along it.
pub(super) fn fixed_words(obs: &HeightObservation, delta_m: f64) -> String {
    let targets: Vec<String> = obs.targets.iter().map(|t| t.to_string()).collect();
    format!(
        "from tool target{} {} seen at the reference commands (`{}` step {}; no pose there sees all three), {:+.3} mm from the description's",
        if targets.len() == 1 { "" } else { "s" },
        targets.join(", "),
        obs.experiment,
        obs.step,
        delta_m * 1e3
    )
}

/// Whether every row of one step stands at the reference commands (within
/// [`COMMAND_TOLERANCE`]).
pub(super) fn at_reference(rows: &[&Measurement], reference_cmd: &[f64]) -> bool {
    rows.iter().all(|r| {
        r.cmd
            .iter()
            .zip(reference_cmd)
            .all(|(a, b)| (a - b).abs() <= COMMAND_TOLERANCE)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The words name the targets, the pose and the move in mm.
    #[test]
    fn words_name_targets_pose_and_move() {
        let obs = HeightObservation {
            axis: 0,
            experiment: "tool".into(),
            step: 0,
            targets: vec![2],
            measured: vec![Point3::origin()],
        };
        let w = fixed_words(&obs, -0.00147);
        assert!(w.starts_with("from tool target 2 seen"), "{w}");
        assert!(w.contains("-1.470 mm"), "{w}");
    }
}
