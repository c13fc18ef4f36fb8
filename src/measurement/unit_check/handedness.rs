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
/// targets, each target's place on the tool fitted with it ([`fitted_targets`]).
pub(super) fn fitted_targets_rms(
    tools: &[nalgebra::Isometry3<f64>],
    targets: &[usize],
    measured: &[Point3<f64>],
    mirror: bool,
) -> Option<f64> {
    fitted_targets(tools, targets, measured, mirror).map(|(_, rms)| rms)
}

/// The best rigid map (of the mirror image when `mirror`) of the free poses' targets, each
/// target's place on the tool fitted with it: the tool frames `tools` of the rows (the nominal
/// robot at their commands), their target ids `targets` and measured points `measured`.
/// Starts from every target at the tool frame's origin. The nominal points as the last round
/// placed them (each the placement of its target's place on its tool, flipped when `mirror`),
/// and their RMS distance \[m\] from the measured ones.
pub(super) fn fitted_targets(
    tools: &[nalgebra::Isometry3<f64>],
    targets: &[usize],
    measured: &[Point3<f64>],
    mirror: bool,
) -> Option<(Vec<Point3<f64>>, f64)> {
    let flip = |p: Point3<f64>| if mirror { Point3::new(-p.x, p.y, p.z) } else { p };
    let ids = targets.iter().max()? + 1;
    let mut places = vec![Point3::origin(); ids];
    let mut fitted = (Vec::new(), f64::INFINITY);
    for _ in 0..TARGET_ROUNDS {
        let nominal: Vec<Point3<f64>> = tools.iter().zip(targets).map(|(w, &t)| flip(w * places[t])).collect();
        let (placement, rms) = rigid_fit(&nominal, measured)?;
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
        fitted = (nominal.iter().map(|p| placement * p).collect(), rms);
    }
    Some(fitted)
}

/// The free poses of a description that places no tool target (a free-pose calibration fits
/// them): the best rotation's and the best mirror's RMS \[m\], each with the targets' places on
/// the tool fitted ([`fitted_targets_rms`]); taken at the tool frame's origin, the targets'
/// offsets (a tool's size) would blur both fits alike and hide a mirror.
fn free_poses_fits(rows: &[Measurement], desc: &RobotDescription) -> Option<(f64, f64, usize)> {
    if !desc.tool_targets_m().is_empty() {
        return None;
    }
    let (tools, targets, measured) = free_pose_points(rows, desc)?;
    let rotation = fitted_targets_rms(&tools, &targets, &measured, false)?;
    let mirror = fitted_targets_rms(&tools, &targets, &measured, true)?;
    Some((rotation, mirror, measured.len()))
}

/// The nominal tool frames, target ids and measured points of free poses ([`free_pose_points`]).
pub(super) type FreePosePoints = (Vec<nalgebra::Isometry3<f64>>, Vec<usize>, Vec<Point3<f64>>);

/// Free poses' points to fit: the nominal robot's tool frames at the rows' commands, the
/// rows' target ids and measured points, every n-th row of a large file. `None` unless every
/// row is a free pose and there are [`MIN_POINTS`].
pub(super) fn free_pose_points(rows: &[Measurement], desc: &RobotDescription) -> Option<FreePosePoints> {
    if rows.iter().any(|m| m.moved_joint != 0) {
        return None;
    }
    let ideal = RobotModel::ideal(desc);
    let controller = Controller::from_description(desc);
    let model = ideal.phi_model();
    let every = rows.len().div_ceil(MAX_ROWS).max(1);
    let rows: Vec<&Measurement> = rows.iter().step_by(every).collect();
    if rows.len() < MIN_POINTS {
        return None;
    }
    let tools: Vec<nalgebra::Isometry3<f64>> = rows
        .iter()
        .map(|m| {
            let internal = commands_to_internal(desc, &m.cmd);
            model.world_from_tool(&ideal.joint_values(&controller, &internal).unwrap_or(internal))
        })
        .collect();
    let targets: Vec<usize> = rows.iter().map(|m| m.target).collect();
    let measured: Vec<Point3<f64>> = rows.iter().map(|m| m.position_m()).collect();
    Some((tools, targets, measured))
}

/// The nominal and the measured points of the `rows` whose targets the description places
/// (module docs), every n-th of a large file.
fn placed_points(desc: &RobotDescription, rows: &[Measurement]) -> (Vec<Point3<f64>>, Vec<Point3<f64>>) {
    let ideal = RobotModel::ideal(desc);
    let controller = Controller::from_description(desc);
    let every = rows.len().div_ceil(MAX_ROWS).max(1);
    rows.iter()
        .step_by(every)
        .filter_map(|m| Some((nominal_point(desc, &ideal, &controller, m)?, m.position_m())))
        .unzip()
}

/// `rows` with joints `j` and `k` (1-based) exchanged: their command columns and their sweeps'
/// `moved_joint` labels.
fn with_joints_swapped(rows: &[Measurement], j: usize, k: usize) -> Vec<Measurement> {
    rows.iter()
        .map(|m| {
            let mut m = m.clone();
            m.cmd.swap(j - 1, k - 1);
            m.moved_joint = match m.moved_joint {
                x if x == j => k,
                x if x == k => j,
                x => x,
            };
            m
        })
        .collect()
}

/// Relative margin within which two fits' RMS are the same fit (rounding and the rigid fits'
/// stopping rule are far below it; a real difference between a swap and a mirror is a factor).
const SAME_FIT: f64 = 0.01;

/// Pairs of joints of one kind whose labels (command columns and sweep labels) exchanged make
/// the points fit a rotation of the description's robot at least as well as the mirror fits them
/// as read (`mirror_m` \[m\]), best first, with their RMS \[m\]: exchanging two of a robot's
/// orthogonal axes reflects its motions, so such an exchange can look like a mirror.
fn swapped_joints(set: &MeasurementSet, desc: &RobotDescription, mirror_m: f64) -> Vec<(usize, usize, f64)> {
    let n = desc.dof();
    let pairs = (1..=n).flat_map(|j| (j + 1..=n).map(move |k| (j, k)));
    let mut found: Vec<(usize, usize, f64)> = pairs
        .filter(|&(j, k)| desc.joints[j - 1].kind == desc.joints[k - 1].kind)
        .filter_map(|(j, k)| {
            let rows = with_joints_swapped(set.rows(), j, k);
            let (nominal, measured) = placed_points(desc, &rows);
            (nominal.len() >= MIN_POINTS).then_some(())?;
            Some((j, k, rigid_fit(&nominal, &measured)?.1))
        })
        .filter(|&(_, _, rms)| rms <= mirror_m * (1.0 + SAME_FIT))
        .collect();
    found.sort_by(|a, b| a.2.total_cmp(&b.2));
    found
}

/// The message of a mirror seen as read (`mirror_m`, `rotation_m` \[m\] over `points`), with the
/// joint exchanges that fit as well (`swaps`, [`swapped_joints`]).
fn mirror_slip(mirror_m: f64, rotation_m: f64, points: usize, swaps: &[(usize, usize, f64)]) -> UnitSlip {
    let fits = format!(
        "the measured points fit a mirror image of the description's robot at the same commands ({:.3} mm RMS over \
         {points} points) far better than any rotation of it ({:.3} mm RMS)",
        mirror_m * 1e3,
        rotation_m * 1e3
    );
    let best = swaps.first().map(|s| s.2);
    let ties: Vec<&(usize, usize, f64)> = swaps
        .iter()
        .filter(|s| Some(s.2) <= best.map(|b| b * (1.0 + SAME_FIT)))
        .collect();
    match ties.as_slice() {
        [] => UnitSlip {
            field: "x_mm,y_mm,z_mm".into(),
            message: format!(
                "{fits}: the instrument frame is left-handed (one coordinate's sign flipped, or two coordinate columns \
                 swapped, on export); check the x_mm, y_mm, z_mm columns"
            ),
        },
        [(j, k, rms)] if *rms < mirror_m * (1.0 - SAME_FIT) => UnitSlip {
            field: format!("cmd_{j},cmd_{k}"),
            message: format!(
                "joints {j} and {k} look exchanged: {fits}, and with the two joints' command columns and sweep labels \
                 exchanged they fit the robot itself ({:.3} mm): check which column (and which sweep's label) holds \
                 joint {j} and which joint {k}",
                rms * 1e3
            ),
        },
        _ => {
            let pairs: Vec<String> = ties.iter().map(|(j, k, _)| format!("{j} and {k}")).collect();
            UnitSlip {
                field: "x_mm,y_mm,z_mm".into(),
                message: format!(
                    "{fits}: the instrument frame is left-handed (one coordinate's sign flipped, or two coordinate \
                     columns swapped, on export), or two joints' labels are exchanged: with the command columns and \
                     sweep labels of joints {} exchanged the points fit the robot itself as well (exchanging two \
                     sliding axes mirrors the motions, so these data cannot tell which); check the x_mm, y_mm, z_mm \
                     columns, and which column and sweep label holds each joint",
                    pairs.join(", or ")
                ),
            }
        }
    }
}

/// Free poses only (a sweep's targets sit where the description's `axis_targets` may not say):
/// the description's nominal robot at the rows' commands against the measured points, placed at
/// best with each target's place on the tool fitted (the rotation fit of [`mirrored`]): another robot's data (a FANUC's read with a UR5e's
/// description) miss by a good part of their spread ([`crate::numerics::stats::ABSURD_SHARE`],
/// the share past which a calibrated fit is refused), where a robot its description fits misses
/// by its drawing's tolerances, millimetres. `None` when it fits, or with too few placed points.
pub(super) fn not_this_robot(set: &MeasurementSet, desc: &RobotDescription) -> Option<UnitSlip> {
    let (tools, targets, measured) = free_pose_points(set.rows(), desc)?;
    let rotation_m = fitted_targets_rms(&tools, &targets, &measured, false)?;
    let points = measured.len();
    let all: Vec<Point3<f64>> = set.rows().iter().map(|m| m.position_m()).collect();
    let spread_m = crate::numerics::stats::rms_spread(&all);
    (rotation_m > crate::numerics::stats::ABSURD_SHARE * spread_m).then(|| UnitSlip {
        field: "x_mm,y_mm,z_mm".into(),
        message: format!(
            "these data do not look like {}: the description's nominal robot at the file's commands, placed in the \
             instrument frame at best, misses the {points} measured points by {:.1} mm RMS, {:.0} % of their spread \
             about their centroid ({:.1} mm), where a robot its description fits misses by millimetres: the data of \
             another robot, or another joint order or zero than the description's; check --robot",
            desc.name,
            rotation_m * 1e3,
            100.0 * rotation_m / spread_m,
            spread_m * 1e3
        ),
    })
}

/// The best rotation's and the best mirror's RMS \[m\] of `rows` against the description's
/// robot, and the points fitted: the free poses' fits with their targets fitted
/// ([`free_poses_fits`]) where the description places no tool target, else the placed points'.
fn fits(rows: &[Measurement], desc: &RobotDescription) -> Option<(f64, f64, usize)> {
    if let Some(fits) = free_poses_fits(rows, desc) {
        return Some(fits);
    }
    let (nominal, measured) = placed_points(desc, rows);
    if nominal.len() < MIN_POINTS {
        return None;
    }
    Some((
        rigid_fit(&nominal, &measured)?.1,
        mirror_fit_rms(&nominal, &measured)?,
        nominal.len(),
    ))
}

/// `rows` with every command's sign flipped.
fn with_commands_negated(rows: &[Measurement]) -> Vec<Measurement> {
    rows.iter()
        .map(|m| Measurement {
            cmd: m.cmd.iter().map(|c| -c).collect(),
            ..m.clone()
        })
        .collect()
}

/// A left-handed instrument frame (module docs), said as a slip of the coordinate columns; or,
/// where two joints' labels exchanged explain the points as well, said as that swap; or, where
/// every command's sign flipped makes a rotation fit the points [`MIRROR_RATIO`] times better
/// than as read (a controller that counts every joint the other way from the description) and
/// better than any mirror, said as that. Where a mirror fits as well (a table of orthogonal
/// slides: its negated motions are its mirror image), the mirror's message says both.
pub(super) fn mirrored(set: &MeasurementSet, desc: &RobotDescription) -> Option<UnitSlip> {
    let (rotation_m, mirror_m, points) = fits(set.rows(), desc)?;
    let negated_m = fits(&with_commands_negated(set.rows()), desc).map(|(rotation, _, _)| rotation);
    let negated_m = negated_m.filter(|n| rotation_m > MIRROR_RATIO * n);
    if let Some(negated_m) = negated_m.filter(|n| *n < mirror_m * (1.0 - SAME_FIT)) {
        return Some(negated_slip(negated_m, rotation_m, (points, desc.dof())));
    }
    if rotation_m <= MIRROR_RATIO * mirror_m {
        return None;
    }
    let mut slip = mirror_slip(mirror_m, rotation_m, points, &swapped_joints(set, desc, mirror_m));
    if negated_m.is_some() {
        slip.message += "; or every command's sign is flipped (negated, they fit as well)";
    }
    Some(slip)
}

/// The message of commands whose signs look flipped ([`mirrored`]), where no mirror fits as
/// well: the rotation's RMS with the commands negated and as read \[m\], over `points` of a
/// robot of `joints`.
fn negated_slip(negated_m: f64, rotation_m: f64, (points, joints): (usize, usize)) -> UnitSlip {
    UnitSlip {
        field: format!("cmd_1..cmd_{joints}"),
        message: format!(
            "every command's sign looks flipped: with each cmd_k negated the measured points fit a rotation of the \
             description's robot at {:.3} mm RMS over {points} points, against {:.3} mm as read; the \
             controller counts the joints the other way from the description (check the export's signs, or the \
             description's joint directions)",
            negated_m * 1e3,
            rotation_m * 1e3
        ),
    }
}
