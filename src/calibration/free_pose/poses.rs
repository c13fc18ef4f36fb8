//! The measured free poses of a measurement set: each pose's commands and its targets' points,
//! and how many configurations they stand at against the parameters a geometry has.

use super::FreePoseError;
use crate::kinematics::JointKind;
use crate::measurement::MeasurementSet;
use crate::measurement::bounded::{configuration_key, spread_over_configurations};
use crate::numerics::stats::{SIGMA_PER_MAD, median};
use crate::robot::{RobotDescription, commands_to_internal};
use nalgebra::Point3;
use std::collections::{HashMap, HashSet};

/// One free pose: the robot stood still at `cmd` while the instrument measured its targets.
#[derive(Clone, Debug, PartialEq)]
pub struct FreePose {
    /// Its experiment.
    pub experiment: String,
    /// Its step in the experiment.
    pub step: usize,
    /// The commands as recorded (file units: deg or mm).
    pub cmd_file: Vec<f64>,
    /// The commands in internal units (rad or m).
    pub cmd: Vec<f64>,
    /// The measured points: (target slot in [`FreePoses::target_ids`], position \[m\]), by target.
    pub points_m: Vec<(usize, Point3<f64>)>,
    /// The setup it was measured from (the instrument's placement; 0 without a `setup` column).
    pub setup: usize,
    /// The payload \[kg\] (`payload_kg` of its first row).
    pub payload_kg: f64,
    /// The direction of each joint's actuator command's last move into it, over every pose of
    /// the file in file order ([`crate::physics::PoseApproach::actuator`]): what signs a
    /// backlash.
    pub approach: Vec<f64>,
}

impl FreePose {
    /// What its effects depend on besides the joint values.
    pub fn load(&self) -> crate::robot::PoseLoad<'_> {
        crate::robot::PoseLoad {
            approach: &self.approach,
            payload_kg: self.payload_kg,
        }
    }

    /// `experiment step S` for messages.
    pub fn label(&self) -> String {
        format!("{} step {}", self.experiment, self.step)
    }
}

/// The free poses of a file, in file order.
#[derive(Clone, Debug, PartialEq)]
pub struct FreePoses {
    /// The poses, in the order of their first row.
    pub poses: Vec<FreePose>,
    /// The target ids seen, ascending.
    pub target_ids: Vec<usize>,
    /// Each target as the file wrote it (its name, or the integer id), in the order of
    /// `target_ids`.
    pub target_names: Vec<String>,
    /// The setups' labels, by setup id (one, `0`, without a `setup` column).
    pub setup_names: Vec<String>,
    /// Free poses of the file left out ([`FreePoses::from_set_at_most`]).
    pub left_out: usize,
}

/// Why the axis experiments' rows of `set` cannot be fitted as free poses, if so: a swept
/// joint's target on a link before the last (a free pose's targets ride on the last link). A
/// sweep's target elsewhere on the last link than the tool's target of its id is a target of
/// its own ([`FreePoses::from_set`]).
pub fn why_sweeps_are_not_poses(set: &MeasurementSet, desc: &RobotDescription) -> Option<String> {
    let last = desc.dof();
    for e in set.experiments().iter().filter(|e| e.moved_joint > 0) {
        let Some(t) = desc.axis_targets_of(e.moved_joint) else {
            continue;
        };
        for (id, target) in [Some(t.target0), t.target1].iter().enumerate() {
            if let Some(target) = target.filter(|t| t.link != last) {
                return Some(format!(
                    "joint {}'s target {id} sits on link {}, not on the last link {last} (the description's axis_targets)",
                    e.moved_joint, target.link
                ));
            }
        }
    }
    None
}

/// A point the description places on the last link, to the nanometre (mm times 1e6): what
/// tells two targets of one id apart.
type PointKey = [i64; 3];

/// Where the description places target `id` of a row of `moved_joint` on the last link, when
/// that is not where it places the tool's target `id`: a sweep's `axis_targets` point, which
/// then is a target of its own; `None` for the tool's target (or a point the description does
/// not give).
fn sweep_only_point(desc: &RobotDescription, moved_joint: usize, id: usize) -> Option<PointKey> {
    let key = |p: Point3<f64>| p.coords.map(|c| (c * 1e6).round() as i64).into();
    let tool = desc
        .tool
        .targets_mm
        .get(id)
        .map(|t| key(desc.tool.frame.to_isometry() * Point3::from(*t)));
    let axis = desc.axis_targets_of(moved_joint).and_then(|t| match id {
        0 => Some(t.target0),
        1 => t.target1,
        _ => None,
    });
    let swept = axis.map(|t| key(Point3::from(t.position_mm)));
    swept.filter(|p| Some(*p) != tool)
}

/// The targets of the rows `free` of `set` keep: each id, and each sweep's point the
/// description puts elsewhere than the tool's target of its id ([`sweep_only_point`]) as a
/// target of its own, after the file's ids (and the tool's). Returns the targets' ids
/// (ascending), their names, and each row's slot (`None` for rows not free).
fn target_slots(
    set: &MeasurementSet,
    desc: &RobotDescription,
    free: impl Fn(&crate::measurement::Measurement) -> bool,
) -> (Vec<usize>, Vec<String>, Vec<Option<usize>>) {
    let key_of = |r: &crate::measurement::Measurement| {
        let point = (r.moved_joint > 0)
            .then(|| sweep_only_point(desc, r.moved_joint, r.target))
            .flatten();
        (r.target, point)
    };
    let keys: std::collections::BTreeSet<(usize, Option<PointKey>)> =
        set.rows().iter().filter(|r| free(r)).map(key_of).collect();
    let keys: Vec<(usize, Option<PointKey>)> = keys.into_iter().collect();
    let first_own = (keys.iter().map(|k| k.0 + 1).max().unwrap_or(0)).max(desc.tool.targets_mm.len());
    let mut own = first_own..;
    let ids: Vec<usize> = keys
        .iter()
        .map(|(id, point)| match point {
            None => *id,
            Some(_) => own.next().unwrap_or(usize::MAX),
        })
        .collect();
    let names: Vec<String> = keys
        .iter()
        .map(|(id, point)| match point {
            None => set.target_name(*id),
            Some(p) => {
                let joints: std::collections::BTreeSet<usize> = (set.rows().iter())
                    .filter(|r| free(r) && key_of(r) == (*id, Some(*p)))
                    .map(|r| r.moved_joint)
                    .collect();
                let joints: Vec<String> = joints.iter().map(usize::to_string).collect();
                format!("{} of the sweeps of joint {}", set.target_name(*id), joints.join(", "))
            }
        })
        .collect();
    // `keys` ascend by id first and the own targets' ids follow every file id: slots ascend.
    let mut order: Vec<usize> = (0..ids.len()).collect();
    order.sort_by_key(|&i| ids[i]);
    let ids_sorted: Vec<usize> = order.iter().map(|&i| ids[i]).collect();
    let names_sorted: Vec<String> = order.iter().map(|&i| names[i].clone()).collect();
    let slot_of_key = |k: &(usize, Option<PointKey>)| {
        let i = keys.binary_search(k).unwrap_or_default();
        ids_sorted.binary_search(&ids[i]).unwrap_or_default()
    };
    let slots = (set.rows().iter())
        .map(|r| free(r).then(|| slot_of_key(&key_of(r))))
        .collect();
    (ids_sorted, names_sorted, slots)
}

impl FreePoses {
    /// Every pose of the `moved_joint = 0` experiments of `set`, or of every experiment with
    /// `all_rows` (sweeps too, their targets on the last link).
    pub fn from_set(set: &MeasurementSet, desc: &RobotDescription, all_rows: bool) -> Result<Self, FreePoseError> {
        Self::from_set_at_most(set, desc, all_rows, usize::MAX)
    }

    /// [`FreePoses::from_set`], at most `max` poses, evenly spaced through the file over as
    /// many distinct commands as `max` allows ([`spread_over_configurations`]; each pose's
    /// approach still from every pose of the file).
    pub fn from_set_at_most(
        set: &MeasurementSet,
        desc: &RobotDescription,
        all_rows: bool,
        max: usize,
    ) -> Result<Self, FreePoseError> {
        let free = |r: &crate::measurement::Measurement| all_rows || r.moved_joint == 0;
        let (target_ids, target_names, target_slot) = target_slots(set, desc, free);
        // Every pose's ordinal (the order of its first row, all experiments: the approaches
        // follow every pose) and its first row; the free ones in order.
        let mut ordinal: HashMap<(&str, usize), usize> = HashMap::new();
        let mut first_row: Vec<usize> = Vec::new();
        let mut free_ordinals: Vec<usize> = Vec::new();
        for (row, r) in set.rows().iter().enumerate() {
            let next = ordinal.len();
            if *ordinal.entry((r.experiment.as_str(), r.step)).or_insert(next) == next {
                first_row.push(row);
                if free(r) {
                    free_ordinals.push(next);
                }
            }
        }
        let count = free_ordinals.len();
        let mut slot: Vec<Option<usize>> = vec![None; first_row.len()];
        let configuration = |o: &usize| configuration_key(&set.rows()[first_row[*o]].cmd);
        for (k, o) in spread_over_configurations(free_ordinals, max, configuration)
            .into_iter()
            .enumerate()
        {
            slot[o] = Some(k);
        }
        let mut approaches = crate::physics::pose_approaches(set.rows(), desc);
        let mut poses: Vec<FreePose> = Vec::new();
        for (row, r) in set.rows().iter().enumerate() {
            let o = ordinal[&(r.experiment.as_str(), r.step)];
            let first = &set.rows()[first_row[o]];
            if row == first_row[o] {
                // One approach per pose, in ordinal order: this pose's is the next.
                let approach = approaches.next().map(|a| a.actuator);
                if let Some(k) = slot[o] {
                    debug_assert_eq!(k, poses.len());
                    poses.push(FreePose {
                        experiment: r.experiment.clone(),
                        step: r.step,
                        cmd_file: r.cmd.clone(),
                        cmd: commands_to_internal(desc, &r.cmd),
                        points_m: Vec::new(),
                        setup: set.setup_of(row),
                        payload_kg: r.payload_kg,
                        approach: approach.unwrap_or_else(|| vec![0.0; r.cmd.len()]),
                    });
                }
            }
            if !free(r) {
                continue;
            }
            // Every pose's rows are checked, the left-out ones' too (their commands agree: a
            // `MeasurementSet` invariant).
            let label = || format!("{} step {}", first.experiment, first.step);
            if set.setup_of(first_row[o]) != set.setup_of(row) {
                return Err(FreePoseError::SetupsDiffer { pose: label() });
            }
            if let Some(k) = slot[o] {
                poses[k]
                    .points_m
                    .push((target_slot[row].unwrap_or_default(), r.position_m()));
            }
        }
        for p in &mut poses {
            p.points_m.sort_by_key(|(slot, _)| *slot);
        }
        let left_out = count - poses.len();
        let setup_names = match set.setup_names() {
            [] => vec!["0".to_string()],
            names => names.to_vec(),
        };
        Ok(FreePoses {
            poses,
            target_ids,
            target_names,
            setup_names,
            left_out,
        })
    }

    /// The range each joint's command covers over the poses `which` (internal units).
    pub fn spans(&self, which: &[usize]) -> Vec<f64> {
        let n = self.poses.first().map_or(0, |p| p.cmd.len());
        (0..n)
            .map(|k| {
                let values = which.iter().map(|&i| self.poses[i].cmd[k]);
                let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
                (hi - lo).max(0.0)
            })
            .collect()
    }

    /// The most targets measured at one pose.
    pub fn targets_per_pose_max(&self) -> usize {
        self.poses.iter().map(|p| p.points_m.len()).max().unwrap_or(0)
    }

    /// Measured points in all.
    pub fn points(&self) -> usize {
        self.poses.iter().map(|p| p.points_m.len()).sum()
    }

    /// Each pose's configuration: the index of its commands among the distinct commands of the
    /// file (equal as recorded), in the order they first appear: repeated visits of one
    /// configuration share it.
    pub fn configurations(&self) -> Vec<usize> {
        let mut seen: HashMap<Vec<u64>, usize> = HashMap::new();
        self.poses
            .iter()
            .map(|p| {
                let key: Vec<u64> = p.cmd_file.iter().map(|c| (c + 0.0).to_bits()).collect();
                let next = seen.len();
                *seen.entry(key).or_insert(next)
            })
            .collect()
    }
}

/// The targets of one pose form a rigid figure on the tool: their spacings are the same in
/// every pose up to the noise, whatever the robot's model. What each pose's spacings say of its
/// rows, without the kinematic model ([`FreePoses::spacings`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Spacings {
    /// Each pose's largest departure of a spacing between two of its targets from that
    /// spacing's median over the poses \[m\] (`None`: fewer than two targets in it).
    pub worst_m: Vec<Option<f64>>,
    /// The departure a pose of the noise passes with probability `1 - SPACINGS_FALSE_ALARM /
    /// tested` \[m\]: the spacings' own noise (1.4826 times the median absolute departure over
    /// every pose and pair, the normal's standard deviation) times the normal quantile.
    pub fence_m: f64,
}

/// The family-wise false-alarm rate of the spacing test over a file's poses (the sweeps' rate,
/// [`crate::calibration::procedure::SWEEP_POINTS_FALSE_ALARM`]).
pub const SPACINGS_FALSE_ALARM: f64 = crate::calibration::procedure::SWEEP_POINTS_FALSE_ALARM;

impl FreePoses {
    /// The spacings' test of every pose ([`Spacings`]); `None` when no two targets share a
    /// pose, or their spacings show no noise to scale by.
    pub fn spacings(&self) -> Option<Spacings> {
        let slots = self.target_ids.len();
        let pair_distances = |p: &FreePose| {
            let mut d = Vec::new();
            for (i, (a, pa)) in p.points_m.iter().enumerate() {
                for (b, pb) in &p.points_m[i + 1..] {
                    d.push(((*a).min(*b) * slots + (*a).max(*b), (pa - pb).norm()));
                }
            }
            d
        };
        let per_pose: Vec<Vec<(usize, f64)>> = self.poses.iter().map(pair_distances).collect();
        let mut by_pair: HashMap<usize, Vec<f64>> = HashMap::new();
        per_pose
            .iter()
            .flatten()
            .for_each(|&(k, d)| by_pair.entry(k).or_default().push(d));
        let median_of: HashMap<usize, f64> = by_pair.iter().map(|(k, v)| (*k, median(v))).collect();
        let departures: Vec<Vec<f64>> = per_pose
            .iter()
            .map(|d| d.iter().map(|(k, x)| (x - median_of[k]).abs()).collect())
            .collect();
        let all: Vec<f64> = departures.iter().flatten().copied().collect();
        if all.is_empty() {
            return None;
        }
        let sigma = SIGMA_PER_MAD * median(&all);
        if sigma.is_nan() || sigma <= 0.0 {
            return None;
        }
        let tail = SPACINGS_FALSE_ALARM / all.len() as f64;
        let z = crate::numerics::stats::chi_square_quantile(1.0 - tail, 1.0).sqrt();
        Some(Spacings {
            worst_m: departures.iter().map(|d| d.iter().copied().reduce(f64::max)).collect(),
            fence_m: z * sigma,
        })
    }
}

/// Independent values one configuration of the tool gives at most: its pose (a target's
/// position, 3, when fewer than three targets are seen).
pub const POSE_VALUES: usize = 6;

/// The fewest parameters a robot's geometry with its base placement has, `4 R + 2 P + 6` for `R`
/// revolute and `P` prismatic joints (Everett, Driels & Mooring 1987, the minimal complete
/// model): fewer independent values than these leave the geometry free.
pub fn minimal_geometry_parameters(desc: &RobotDescription) -> usize {
    let revolute = desc.joints.iter().filter(|j| j.kind == JointKind::Revolute).count();
    4 * revolute + 2 * (desc.joints.len() - revolute) + 6
}

/// How many configurations a set's free poses stand at ([`configurations`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Configurations {
    /// The free poses (experiment and step).
    pub poses: usize,
    /// Their distinct configurations (commands equal to 1e-6).
    pub distinct: usize,
    /// The independent values those configurations give at most: [`POSE_VALUES`] each, 3 per
    /// target below three targets.
    pub values: usize,
}

/// The configurations of the free poses of `set` (with `all_rows`, every row counts as a pose:
/// the sweeps fitted as free poses).
pub fn configurations(set: &MeasurementSet, all_rows: bool) -> Configurations {
    let free = set.rows().iter().filter(|m| all_rows || m.moved_joint == 0);
    let distinct: HashSet<Vec<i64>> = free.clone().map(|m| configuration_key(&m.cmd)).collect();
    let targets: HashSet<usize> = free.clone().map(|m| m.target).collect();
    let poses: HashSet<(&str, usize)> = free.map(|m| (m.experiment.as_str(), m.step)).collect();
    Configurations {
        poses: poses.len(),
        distinct: distinct.len(),
        values: distinct.len() * POSE_VALUES.min(3 * targets.len()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measurement::Measurement;

    /// A row of `experiment` (moving `moved_joint`) at `step` measuring `target`.
    fn row(experiment: &str, moved_joint: usize, step: usize, target: usize) -> Measurement {
        let mut cmd = vec![0.0; 7];
        if moved_joint > 0 {
            cmd[moved_joint - 1] = 5.0 * step as f64;
        }
        Measurement {
            experiment: experiment.into(),
            moved_joint,
            step,
            target,
            position_mm: [1000.0 + step as f64, 100.0 * target as f64, 50.0 * moved_joint as f64],
            cmd,
            payload_kg: Measurement::DEFAULT_PAYLOAD_KG,
            temperature_c: Measurement::DEFAULT_TEMPERATURE_C,
        }
    }

    /// The seven-axis arm's sweeps measure one point of the last link, not the tool's target
    /// 0: with every row a pose that point is a target of its own, after the file's ids; the
    /// tool's rows keep theirs. With only the free poses nothing changes.
    #[test]
    fn a_sweeps_own_point_is_a_target_of_its_own() {
        let desc = RobotDescription::from_file(std::path::Path::new("scenarios/robots/arm7-dh.toml")).expect("shipped");
        let mut rows: Vec<Measurement> = (0..3).map(|t| row("tool", 0, 0, t)).collect();
        rows.extend((0..3).flat_map(|s| [row("axis7", 7, s, 0), row("axis1", 1, s, 0)]));
        let set = MeasurementSet::new(7, rows).expect("set");
        let poses = FreePoses::from_set(&set, &desc, true).expect("poses");
        assert_eq!(poses.target_ids, [0, 1, 2, 3]);
        assert_eq!(poses.target_names[3], "0 of the sweeps of joint 1, 7");
        for p in &poses.poses {
            let slots: Vec<usize> = p.points_m.iter().map(|(slot, _)| *slot).collect();
            match p.experiment.as_str() {
                "tool" => assert_eq!(slots, [0, 1, 2]),
                _ => assert_eq!(slots, [3], "{}", p.label()),
            }
        }
        let free_only = FreePoses::from_set(&set, &desc, false).expect("poses");
        assert_eq!(free_only.target_ids, [0, 1, 2]);
        assert_eq!(why_sweeps_are_not_poses(&set, &desc), None);
        // The sweeps' point moved onto the tool's target 0 (to a rounding): one target again.
        let mut shared = desc.clone();
        let on_link = shared.tool.frame.to_isometry() * Point3::from(shared.tool.targets_mm[0]);
        for a in &mut shared.axis_targets {
            a.target0.position_mm = (on_link.coords + nalgebra::Vector3::repeat(1e-12)).into();
        }
        let poses = FreePoses::from_set(&set, &shared, true).expect("poses");
        assert_eq!(poses.target_ids, [0, 1, 2]);
    }
}
