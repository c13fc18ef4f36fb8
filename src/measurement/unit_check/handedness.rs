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
pub(super) fn nominal_point(
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

/// Rounds of [`fitted_targets_rms`]: each refits the placement to the targets, then the targets
/// to the placement, which never raises the RMS; a handful settle a tool's offsets far below the
/// arm's reach that a mirror moves the points by.
const TARGET_ROUNDS: usize = 10;

/// The RMS \[m\] of the best rigid map (of the mirror image when `mirror`) of the free poses'
/// targets, each target's place on the tool fitted with it: the tool frames `tools` of the rows
/// (the nominal robot at their commands), their target ids `targets` and measured points
/// `measured`. Starts from every target at the tool frame's origin.
fn fitted_targets_rms(
    tools: &[nalgebra::Isometry3<f64>],
    targets: &[usize],
    measured: &[Point3<f64>],
    mirror: bool,
) -> Option<f64> {
    let flip = |p: Point3<f64>| if mirror { Point3::new(-p.x, p.y, p.z) } else { p };
    let ids = targets.iter().max()? + 1;
    let mut places = vec![Point3::origin(); ids];
    let mut rms = f64::INFINITY;
    for _ in 0..TARGET_ROUNDS {
        let nominal: Vec<Point3<f64>> = tools.iter().zip(targets).map(|(w, &t)| flip(w * places[t])).collect();
        let (placement, fitted) = rigid_fit(&nominal, measured)?;
        rms = fitted;
        let mut sums = vec![(nalgebra::Vector3::zeros(), 0usize); ids];
        for ((w, &t), m) in tools.iter().zip(targets).zip(measured) {
            let on_tool = w.inverse() * flip(placement.inverse() * m);
            sums[t].0 += on_tool.coords;
            sums[t].1 += 1;
        }
        places = sums
            .iter()
            .map(|(sum, n)| Point3::from(sum / (*n).max(1) as f64))
            .collect();
    }
    Some(rms)
}

/// The free poses of a description that places no tool target (a free-pose calibration fits
/// them): the best rotation's and the best mirror's RMS \[m\], each with the targets' places on
/// the tool fitted ([`fitted_targets_rms`]); taken at the tool frame's origin, the targets'
/// offsets (a tool's size) would blur both fits alike and hide a mirror.
fn free_poses_fits(set: &MeasurementSet, desc: &RobotDescription) -> Option<(f64, f64, usize)> {
    if !desc.tool_targets_m().is_empty() || set.rows().iter().any(|m| m.moved_joint != 0) {
        return None;
    }
    let ideal = RobotModel::ideal(desc);
    let controller = Controller::from_description(desc);
    let model = ideal.phi_model();
    let every = set.rows().len().div_ceil(MAX_ROWS).max(1);
    let rows: Vec<&Measurement> = set.rows().iter().step_by(every).collect();
    let tools: Vec<nalgebra::Isometry3<f64>> = rows
        .iter()
        .map(|m| {
            let internal = commands_to_internal(desc, &m.cmd);
            model.world_from_tool(&ideal.joint_values(&controller, &internal).unwrap_or(internal))
        })
        .collect();
    let targets: Vec<usize> = rows.iter().map(|m| m.target).collect();
    let measured: Vec<Point3<f64>> = rows.iter().map(|m| m.position_m()).collect();
    if rows.len() < MIN_POINTS {
        return None;
    }
    let rotation = fitted_targets_rms(&tools, &targets, &measured, false)?;
    let mirror = fitted_targets_rms(&tools, &targets, &measured, true)?;
    Some((rotation, mirror, rows.len()))
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
    let (rotation_m, mirror_m, points) = match free_poses_fits(set, desc) {
        Some(fits) => fits,
        None if nominal.len() < MIN_POINTS => return None,
        None => (
            rigid_fit(&nominal, &measured)?.1,
            mirror_fit_rms(&nominal, &measured)?,
            nominal.len(),
        ),
    };
    (rotation_m > MIRROR_RATIO * mirror_m).then(|| UnitSlip {
        field: "x_mm,y_mm,z_mm".into(),
        message: format!(
            "the measured points fit a mirror image of the description's robot at the same commands ({:.3} mm RMS \
             over {} points) far better than any rotation of it ({:.3} mm RMS): the instrument frame is left-handed \
             (one coordinate's sign flipped, or two coordinate columns swapped, on export); check the x_mm, y_mm, \
             z_mm columns",
            mirror_m * 1e3,
            points,
            rotation_m * 1e3
        ),
    })
}
