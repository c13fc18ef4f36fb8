//! A turning joint's described target 0 on the joint's own axis: the rule by which `calibrate`
//! names a sweep whose points spread within the noise because of where the description places
//! its target, and by which `plan` and `simulate` warn before such a campaign is measured.

use crate::kinematics::JointKind;
use crate::robot::{Controller, RobotDescription, RobotModel, commands_to_internal};
use nalgebra::{Point3, Vector3};

/// How many times the least resolvable distance over a joint's whole range a described target
/// must lie off its axis not to be said on it ([`target_on_axis`]): a circle barely above the
/// noise locates no axis.
const ON_AXIS_MARGIN: f64 = 5.0;

/// Target 0 of a turning joint's sweep, placed by the description too close to the joint's
/// axis for the sweep to locate it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TargetOnAxis {
    /// The joint (1-based).
    pub joint: usize,
    /// The link the description puts the target on.
    pub link: usize,
    /// Its position in that link's frame \[mm\].
    pub position_mm: [f64; 3],
    /// Its distance from the joint's axis on the nominal robot at the sweep's first commands
    /// \[mm\].
    pub off_axis_mm: f64,
    /// The least distance off the axis to put it at \[mm\]: where the sweep's span would move
    /// it [`crate::numerics::stats::UNRESOLVED_SPREAD_OVER_NOISE`] times the noise, and no less
    /// than the margin the rule holds it to.
    pub needed_mm: f64,
}

/// Whether the description places target 0 of the sweep of turning joint `joint` (1-based),
/// which starts at the commands `first_cmd` (the file's units) and spans `span_rad`, on the
/// joint's axis at the noise `noise_mm` (3-D RMS of a point): closer, on the nominal robot at
/// `first_cmd`, than `ON_AXIS_MARGIN` (5) times the distance at which a sweep over the joint's
/// whole range (at most a turn) would move it `UNRESOLVED_SPREAD_OVER_NOISE` times the noise
/// (points along an arc of radius `r` over `theta` spread about `r theta / sqrt(12)`), so that
/// no span helps. `None` for a sliding joint, a target the description does not place, or one
/// placed farther.
pub fn target_on_axis(
    desc: &RobotDescription,
    controller: &Controller,
    joint: usize,
    first_cmd: &[f64],
    span_rad: f64,
    noise_mm: f64,
) -> Option<TargetOnAxis> {
    if desc.joints.get(joint.checked_sub(1)?)?.kind != JointKind::Revolute {
        return None;
    }
    let target = &desc.axis_targets_of(joint)?.target0;
    let ideal = RobotModel::ideal(desc);
    let internal = commands_to_internal(desc, first_cmd);
    let q = ideal.joint_values(controller, &internal).unwrap_or(internal);
    let links = ideal.phi_model().poses(&q).world_from_link;
    let point = links.get(target.link.checked_sub(1)?)? * target.position_m();
    let axis = links.get(joint - 1)?;
    let direction = axis.rotation * Vector3::z();
    let off_axis_mm = (point - Point3::from(axis.translation.vector)).cross(&direction).norm() * 1e3;
    let factor = crate::numerics::stats::UNRESOLVED_SPREAD_OVER_NOISE;
    let [low, high] = desc.limits_internal(joint - 1);
    let widest_rad = (high - low).clamp(f64::MIN_POSITIVE, std::f64::consts::TAU);
    let resolvable_mm = |theta: f64| 12f64.sqrt() * factor * noise_mm / theta.max(f64::MIN_POSITIVE);
    let threshold_mm = ON_AXIS_MARGIN * resolvable_mm(widest_rad);
    let needed_mm = resolvable_mm(span_rad).max(threshold_mm);
    (off_axis_mm < threshold_mm).then_some(TargetOnAxis {
        joint,
        link: target.link,
        position_mm: target.position_mm,
        off_axis_mm,
        needed_mm,
    })
}
