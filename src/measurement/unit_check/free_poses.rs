//! The free poses' unit checks: how far their measured tool positions spread against how far
//! the nominal model moves the tool at their commands ([`free_pose_slips`]).

use super::SPREAD_WARNING;
use super::UnitSlip;
use super::coordinates_look;
use super::median;
use super::radii;
use super::slipped;
use super::{ANGLE_UNITS, unit_of};
use crate::kinematics::JointKind;
use crate::measurement::MeasurementSet;
use crate::robot::{RobotDescription, commands_to_internal};
use nalgebra::{Point3, Vector3};

/// Free poses whose tool positions spread less than this \[mm\], measured and nominal alike,
/// are not judged: their spread is the instrument's noise more than the robot's motion (as
/// [`super::arcs::MIN_JUDGED_SAGITTA_MM`] for an arc).
pub(super) const MIN_JUDGED_SPREAD_MM: f64 = 1.0;

/// Fewer free poses than this are not judged: two poses make one distance, which a robot far
/// from its description could stretch.
pub(super) const MIN_FREE_POSES: usize = 3;

/// One free pose: the centroid of its measured tool targets \[file length units\] and of the
/// same targets on the nominal model at its commands (read in degrees) \[mm\].
pub(super) struct FreePose {
    /// Its first row in the set.
    pub(super) row: usize,
    pub(super) setup: usize,
    pub(super) measured: Vector3<f64>,
    pub(super) nominal: Vector3<f64>,
    pub(super) targets: usize,
}

/// The free poses of `set` (rows with `moved_joint = 0` whose target is one of the
/// description's tool targets), in order of first appearance. A description that places no
/// tool target (a free-pose calibration fits them) has each target taken at the tool frame's
/// origin, as the handedness check takes it: the targets' unknown offsets, a tool's size, move
/// both spreads alike by far less than the arm's reach that a slip scales them by.
pub(super) fn free_poses(set: &MeasurementSet, desc: &RobotDescription) -> Vec<FreePose> {
    let mut tool_targets = desc.tool_targets_m();
    if tool_targets.is_empty() {
        tool_targets = vec![Point3::origin(); set.rows().iter().map(|m| m.target + 1).max().unwrap_or(0)];
    }
    let ideal = crate::robot::RobotModel::ideal(desc);
    let controller = crate::robot::Controller::from_description(desc);
    let model = ideal.phi_model();
    // The joint values the nominal robot reaches for the commands (the controller's couplings
    // applied); the commands read as joint values where they cannot be decoupled.
    let joint_values = |cmd: &[f64]| {
        let internal = commands_to_internal(desc, cmd);
        ideal.joint_values(&controller, &internal).unwrap_or(internal)
    };
    let mut index: std::collections::HashMap<(&str, usize), usize> = std::collections::HashMap::new();
    let mut poses: Vec<(FreePose, nalgebra::Isometry3<f64>)> = Vec::new();
    for (i, m) in set.rows().iter().enumerate() {
        let Some(target) = tool_targets.get(m.target).filter(|_| m.moved_joint == 0) else {
            continue;
        };
        let k = *index.entry((m.experiment.as_str(), m.step)).or_insert_with(|| {
            let world_from_tool = model.world_from_tool(&joint_values(&m.cmd));
            let pose = FreePose {
                row: i,
                setup: set.setup_of(i),
                measured: Vector3::zeros(),
                nominal: Vector3::zeros(),
                targets: 0,
            };
            poses.push((pose, world_from_tool));
            poses.len() - 1
        });
        let (pose, world_from_tool) = &mut poses[k];
        pose.measured += Vector3::from(m.position_mm);
        pose.nominal += (*world_from_tool * target).coords * 1e3;
        pose.targets += 1;
    }
    poses
        .into_iter()
        .map(|(mut p, _)| {
            p.measured /= p.targets as f64;
            p.nominal /= p.targets as f64;
            p
        })
        .collect()
}

/// The RMS distance of `points` from their setup's centroid (each setup its own instrument
/// placement).
pub(super) fn spread(points: &[(usize, Vector3<f64>)]) -> f64 {
    let mut centroids: std::collections::BTreeMap<usize, (Vector3<f64>, usize)> = std::collections::BTreeMap::new();
    for (setup, p) in points {
        let c = centroids.entry(*setup).or_insert((Vector3::zeros(), 0));
        c.0 += p;
        c.1 += 1;
    }
    let sum: f64 = points
        .iter()
        .map(|(setup, p)| {
            let (sum, n) = centroids[setup];
            (p - sum / n as f64).norm_squared()
        })
        .sum();
    (sum / points.len() as f64).sqrt()
}

/// A pose whose measured distance from the median point over its nominal one is beyond this
/// factor of the poses' median ratio is in other units than most ([`bulk`]): a robot within its
/// description keeps every ratio within per cent of the median away from the median point
/// (near it both distances are small and their ratio noisy: such poses count little in a
/// spread), and the slips are 25.4 (inches), 57 (radians) or 1000 (metres).
pub(super) const BULK_RATIO_FACTOR: f64 = 3.0;

/// Each point's distance from its setup's component-wise median point, in the order given.
pub(super) fn radii_by_setup(points: &[(usize, Vector3<f64>)]) -> Vec<f64> {
    let mut setups: std::collections::BTreeMap<usize, Vec<usize>> = std::collections::BTreeMap::new();
    for (i, (setup, _)) in points.iter().enumerate() {
        setups.entry(*setup).or_default().push(i);
    }
    let mut out = vec![0.0; points.len()];
    for members in setups.values() {
        let r = radii(&members.iter().map(|&i| points[i].1).collect::<Vec<_>>());
        members.iter().zip(r).for_each(|(&i, r)| out[i] = r);
    }
    out
}

/// The poses whose own ratio of measured to nominal distance from the median point lies within
/// [`BULK_RATIO_FACTOR`] of the median ratio of those distances: a few poses in other units
/// than the rest (a tool row in mm beside validation rows in metres) move neither median and
/// are left out of the spreads, so the ratio is the bulk's. All of them when no median ratio
/// can be taken.
pub(super) fn bulk(measured: &[(usize, Vector3<f64>)], nominal: &[(usize, Vector3<f64>)]) -> Vec<usize> {
    let (m, n) = (radii_by_setup(measured), radii_by_setup(nominal));
    let typical = median(m.clone()) / median(n.clone());
    let all: Vec<usize> = (0..measured.len()).collect();
    if !(typical.is_finite() && typical > 0.0) {
        return all;
    }
    let near = |i: &usize| {
        let r = m[*i] / n[*i] / typical;
        r.is_finite() && (1.0 / BULK_RATIO_FACTOR..=BULK_RATIO_FACTOR).contains(&r)
    };
    let kept: Vec<usize> = all.iter().copied().filter(near).collect();
    if kept.len() < MIN_FREE_POSES { all } else { kept }
}

/// How far the free poses' measured tool positions spread against the nominal model's at
/// their commands ([`free_pose_slips`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FreePoseSpread {
    /// Free poses judged.
    pub poses: usize,
    /// RMS distance of the measured positions from their setup's centroid, over the poses in
    /// the units of most \[file length units\].
    pub measured_mm: f64,
    /// The same of the nominal model's positions \[mm\].
    pub nominal_mm: f64,
    /// `measured_mm / nominal_mm`.
    pub ratio: f64,
}

/// The free poses' spread, or `None` when too few poses or too little motion to judge.
pub fn free_pose_spread(set: &MeasurementSet, desc: &RobotDescription) -> Option<FreePoseSpread> {
    let poses = free_poses(set, desc);
    if poses.len() < MIN_FREE_POSES {
        return None;
    }
    let measured: Vec<(usize, Vector3<f64>)> = poses.iter().map(|p| (p.setup, p.measured)).collect();
    let nominal: Vec<(usize, Vector3<f64>)> = poses.iter().map(|p| (p.setup, p.nominal)).collect();
    let kept = bulk(&measured, &nominal);
    let of = |points: &[(usize, Vector3<f64>)]| spread(&kept.iter().map(|&i| points[i]).collect::<Vec<_>>());
    let (measured, nominal) = (of(&measured), of(&nominal));
    (measured.max(nominal) >= MIN_JUDGED_SPREAD_MM).then_some(FreePoseSpread {
        poses: poses.len(),
        measured_mm: measured,
        nominal_mm: nominal,
        ratio: measured / nominal,
    })
}

/// Whether a spread ratio is a robot's within its drawing's tolerances ([`SPREAD_WARNING`]).
pub(super) fn plausible_spread(ratio: f64) -> bool {
    (1.0 / SPREAD_WARNING..=SPREAD_WARNING).contains(&ratio)
}

/// A warning when the free poses spread beyond [`SPREAD_WARNING`] of the nominal model's but
/// not as far as a slip ([`free_pose_slips`]): coordinates scaled on export, or another robot,
/// when every pose is scaled alike (`one_scale`); else the poses whose commands and
/// coordinates disagree, with their lines.
pub fn free_pose_scale_warning(set: &MeasurementSet, desc: &RobotDescription) -> Option<UnitSlip> {
    let s = free_pose_spread(set, desc)?;
    if plausible_spread(s.ratio) || slipped(s.ratio) {
        return None;
    }
    let spread = format!(
        "the {} free poses' measured tool positions spread {:.3} times as far as the nominal model at their commands",
        s.poses, s.ratio
    );
    let message = match one_scale(set, desc) {
        Ok(()) => format!("{spread}: coordinates scaled on export, or another robot than the description?"),
        Err(uneven) => format!("{spread}, but {uneven}"),
    };
    Some(UnitSlip {
        field: "x_mm,y_mm,z_mm".into(),
        message,
    })
}

/// The most lines a warning names.
pub(super) const NAMED_LINES: usize = 5;

/// `Ok` when the free poses' spread is one scale of the nominal model's, pose by pose: over the
/// poses farther out than the median (near the centre a distance is mostly the robot's own
/// deviation), each pose's distance from its setup's median point over its nominal one; their
/// median is the bulk's scale and their quartiles lie within [`SPREAD_WARNING`] of it, as
/// coordinates scaled on export make them (every pose alike, within the robot's per cent). Else
/// the words of what the data show instead, with the lines of the poses farthest off: most poses
/// match the model and a few do not (rows slipped), or the poses match no one scale.
pub(super) fn one_scale(set: &MeasurementSet, desc: &RobotDescription) -> Result<(), String> {
    let poses = free_poses(set, desc);
    let measured: Vec<(usize, Vector3<f64>)> = poses.iter().map(|p| (p.setup, p.measured)).collect();
    let nominal: Vec<(usize, Vector3<f64>)> = poses.iter().map(|p| (p.setup, p.nominal)).collect();
    let (m, n) = (radii_by_setup(&measured), radii_by_setup(&nominal));
    let outer = median(n.clone());
    let ratios: Vec<(usize, f64)> = (0..poses.len())
        .filter(|&i| n[i] >= outer && n[i] > 0.0)
        .map(|i| (i, m[i] / n[i]))
        .collect();
    let values: Vec<f64> = ratios.iter().map(|r| r.1).collect();
    let q = |p: f64| crate::numerics::stats::quantile(&values, p, crate::numerics::stats::QuantileMethod::Linear);
    let (q1, mid, q3) = (q(0.25), q(0.5), q(0.75));
    let off = |r: f64| (r / mid).ln().abs();
    let alike = mid / q1 <= SPREAD_WARNING && q3 / mid <= SPREAD_WARNING;
    let every = values.iter().all(|r| off(*r) <= SPREAD_WARNING.ln());
    if values.len() < MIN_FREE_POSES || q1.is_nan() || q1 <= 0.0 || (alike && (every || !plausible_spread(mid))) {
        return Ok(());
    }
    let mut worst = ratios.clone();
    worst.sort_by(|a, b| off(b.1).total_cmp(&off(a.1)));
    let lines = |poses_off: &[(usize, f64)]| -> String {
        let named: Vec<String> = poses_off
            .iter()
            .take(NAMED_LINES)
            .map(|(i, r)| {
                let row = poses[*i].row;
                let m = &set.rows()[row];
                match set.line_of(row) {
                    Some(line) => format!("line {line} ({r:.2} times)"),
                    None => format!("experiment {} step {} ({r:.2} times)", m.experiment, m.step),
                }
            })
            .collect();
        named.join(", ")
    };
    if alike {
        let beyond: Vec<(usize, f64)> = worst.into_iter().filter(|r| off(r.1) > SPREAD_WARNING.ln()).collect();
        return Err(format!(
            "not by one scale: most poses match the model (pose by pose their distances from the centre are {mid:.2} \
             times the model's, the quartiles over the outer half of the poses within a quarter of it), and {} of \
             those {} are not: {}: check those rows' coordinates and commands (a sign or a column slipped in some \
             rows, another pose's reading), not the units",
            beyond.len(),
            values.len(),
            lines(&beyond)
        ));
    }
    Err(format!(
        "not by one scale: pose by pose their distances from the centre are {q1:.2} to {q3:.2} times the model's (the \
         quartiles over the outer half of the poses), where coordinates scaled on export scale every pose alike: the \
         poses' commands and coordinates do not match each other (rows whose commands or coordinates slipped, rows in \
         another order than their commands; the farthest off: {}), or the description is not this robot's",
        lines(&worst)
    ))
}

/// Coordinates or commands of the free poses whose units look wrong: the RMS spread of the
/// poses' measured tool positions over the spread of the nominal model's at their commands (the
/// same targets, each setup about its own centroid, so where the robot stands does not count).
/// A robot differs from its description by per cent; coordinates in metres give 0.001,
/// commands in radians (read as degrees) about 57.
pub fn free_pose_slips(set: &MeasurementSet, desc: &RobotDescription) -> Vec<UnitSlip> {
    let Some(spread) = free_pose_spread(set, desc).filter(|s| slipped(s.ratio)) else {
        return Vec::new();
    };
    let (ratio, measured, nominal) = (spread.ratio, spread.measured_mm, spread.nominal_mm);
    let radians = unit_of(&ANGLE_UNITS[..1], ratio).is_some();
    let what = format!(
        "the {} free poses' (moved_joint = 0) measured tool positions spread {measured:.4} (RMS about their centroid) where the nominal model at their commands spreads them {nominal:.1} mm, {ratio:.4} times",
        spread.poses
    );
    // A unit is named only when it scales every pose alike ([`one_scale`]).
    if let Err(uneven) = one_scale(set, desc) {
        return vec![UnitSlip {
            field: "x_mm,y_mm,z_mm".into(),
            message: format!("{what}, but {uneven}"),
        }];
    }
    let revolute: Vec<String> = desc
        .joints
        .iter()
        .enumerate()
        .filter(|(_, j)| j.kind == JointKind::Revolute)
        .map(|(k, _)| format!("cmd_{}", k + 1))
        .collect();
    let slip = if radians && !revolute.is_empty() {
        UnitSlip {
            field: revolute.join(","),
            message: format!("{what}: the commands look like radians rather than degrees"),
        }
    } else {
        UnitSlip {
            field: "x_mm,y_mm,z_mm".into(),
            message: format!("{what}: the coordinates {}", coordinates_look(ratio)),
        }
    };
    vec![slip]
}
