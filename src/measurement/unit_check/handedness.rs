//! The instrument frame's handedness, from the data as read against the description: every
//! point whose target the description places (an axis experiment's target 0 and 1 on their
//! links, a free pose's tool targets) against the nominal robot's at the row's commands. The
//! best rotation ([`rigid_fit`], which also takes the unknown placement) against the best
//! mirror image ([`mirror_fit_rms`]): a rotation fits a right-handed frame's points at least
//! as well as any mirror (Kabsch), whatever the robot's deviations from its description; a
//! left-handed frame (one coordinate's sign flipped, two columns swapped on export) fits the
//! mirror [`MIRROR_RATIO`] times better. Points nearly in a plane fit both alike and say
//! nothing. Unlike the calibrated rows' signs (the calibration's own handedness check), this
//! holds for every robot kind and for free poses.

use super::UnitSlip;
use crate::kinematics::{MIRROR_RATIO, mirror_fit_rms, rigid_fit};
use crate::measurement::{Measurement, MeasurementSet};
use crate::robot::{Controller, RobotDescription, RobotModel, commands_to_internal};
use nalgebra::Point3;

/// At most this many rows are compared (every n-th of a larger file): the fits' answer does
/// not change with more, and a file of millions of rows is checked in a bounded time.
const MAX_ROWS: usize = 20_000;

/// Fewer placed points than this are not judged (a rigid fit of 6 parameters needs several
/// times that many to tell a mirror).
const MIN_POINTS: usize = 12;

/// The described position \[m\] of `m`'s target at its commands on the nominal robot. A
/// target the description does not place (a free pose's without `[tool] targets_mm`, a
/// sweep's without `axis_targets`, which then sits on the last link) is taken at the tool
/// frame's origin: its unknown offset adds its size to both fits alike, far below an arm's
/// reach that a mirror moves the points by.
fn nominal_point(
    desc: &RobotDescription,
    ideal: &RobotModel,
    controller: &Controller,
    m: &Measurement,
) -> Option<Point3<f64>> {
    let internal = commands_to_internal(desc, &m.cmd);
    let q = ideal.joint_values(controller, &internal).unwrap_or(internal);
    let model = ideal.phi_model();
    let on_tool = |target: Point3<f64>| Some(model.world_from_tool(&q) * target);
    if m.moved_joint == 0 {
        let targets = desc.tool_targets_m();
        return match targets.get(m.target) {
            Some(target) => on_tool(*target),
            None if targets.is_empty() => on_tool(Point3::origin()),
            None => None,
        };
    }
    let Some(targets) = desc.axis_targets_of(m.moved_joint) else {
        return on_tool(Point3::origin());
    };
    let target = match m.target {
        0 => &targets.target0,
        1 => targets.target1.as_ref()?,
        _ => return None,
    };
    Some(model.poses(&q).world_from_link.get(target.link - 1)? * target.position_m())
}

/// A left-handed instrument frame (module docs), said as a slip of the coordinate columns.
pub(super) fn mirrored(set: &MeasurementSet, desc: &RobotDescription) -> Option<UnitSlip> {
    let ideal = RobotModel::ideal(desc);
    let controller = Controller::from_description(desc);
    let every = set.rows().len().div_ceil(MAX_ROWS).max(1);
    let (nominal, measured): (Vec<Point3<f64>>, Vec<Point3<f64>>) = set
        .rows()
        .iter()
        .step_by(every)
        .filter_map(|m| Some((nominal_point(desc, &ideal, &controller, m)?, m.position_m())))
        .unzip();
    if nominal.len() < MIN_POINTS {
        return None;
    }
    let (_, rotation_m) = rigid_fit(&nominal, &measured)?;
    let mirror_m = mirror_fit_rms(&nominal, &measured)?;
    (rotation_m > MIRROR_RATIO * mirror_m).then(|| UnitSlip {
        field: "x_mm,y_mm,z_mm".into(),
        message: format!(
            "the measured points fit a mirror image of the description's robot at the same commands ({:.3} mm RMS \
             over {} points) far better than any rotation of it ({:.3} mm RMS): the instrument frame is left-handed \
             (one coordinate's sign flipped, or two coordinate columns swapped, on export); check the x_mm, y_mm, \
             z_mm columns",
            mirror_m * 1e3,
            nominal.len(),
            rotation_m * 1e3
        ),
    })
}
