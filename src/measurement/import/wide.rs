//! Wide-format pose tables, as FIGAROH and many lab scripts write them
//! (`docs/formats.md#wide-format`): one row per robot pose, the joint values (`q1..qN`, radians
//! or degrees) and the markers' coordinates (`m1_x,m1_y,m1_z,m2_x,...`).
//!
//! Experiments are recovered from the joint values: a run of at least three consecutive poses
//! between which only joint `k` changes, always in the same direction (and joint `k+1` with
//! it, as a hold-still command does), is an axis experiment `axis<k>` (a later run of the same joint `axis<k>-2`, ...); every
//! other pose belongs to the free-pose experiment `poses` (`moved_joint = 0`). Marker `i` is
//! target `i - 1`; an empty or `nan` marker cell is a marker not seen at that pose (no row).

use super::points::{LengthUnit, PointsError};
use super::table::{Row, Table};
use crate::csv_lines::shown_cell;
use crate::kinematics::JointKind;
use crate::measurement::{Measurement, MeasurementSet};

/// How the wide table is to be read.
#[derive(Clone, Debug, PartialEq)]
pub struct WideOptions {
    /// The robot's joints, base first (revolute values are converted to degrees).
    pub kinds: Vec<JointKind>,
    /// Whether revolute joint values are in radians (else degrees).
    pub radians: bool,
    /// Unit of the marker coordinates and of prismatic joint values.
    pub lengths: LengthUnit,
    /// Two poses whose joint value differs by at most this (file units after conversion, deg or
    /// mm) hold the joint still.
    pub still_tolerance: f64,
}

/// Joint column names accepted for joint `k` (1-based), in order of preference.
pub fn joint_column_names(k: usize) -> [String; 6] {
    [
        format!("q{k}"),
        format!("q_{k}"),
        format!("j{k}"),
        format!("joint{k}"),
        format!("joint_{k}"),
        format!("cmd_{k}"),
    ]
}

/// The poses of a wide table: per row its line, commands (file units) and markers.
pub(super) type Pose = (usize, Vec<f64>, Vec<Option<[f64; 3]>>);

/// Reads the table into measurement rows (`docs/formats.md#wide-format`).
pub fn import_wide(t: &Table, options: &WideOptions) -> Result<MeasurementSet, PointsError> {
    let joints = options
        .kinds
        .iter()
        .enumerate()
        .map(|(k, _)| {
            let names = joint_column_names(k + 1);
            t.required(&names.iter().map(String::as_str).collect::<Vec<_>>())
        })
        .collect::<Result<Vec<_>, _>>()?;
    let beyond = joint_column_names(joints.len() + 1);
    if let Some(extra) = t.column(&beyond.iter().map(String::as_str).collect::<Vec<_>>()) {
        return Err(PointsError::File {
            path: t.path.clone(),
            message: format!(
                "column `{}`: the table has more joints than the description's {}: give the description of this robot (--robot)",
                t.header[extra],
                joints.len()
            ),
        });
    }
    let markers: Vec<[usize; 3]> = (1..)
        .map_while(|i| {
            let c = |a: &str| t.column(&[&format!("m{i}_{a}")]);
            Some([c("x")?, c("y")?, c("z")?])
        })
        .collect();
    unread_markers(t, markers.len())?;
    if markers.is_empty() {
        // Marker 1 is incomplete: the first of its columns missing.
        for axis in ["m1_x", "m1_y", "m1_z"] {
            t.required(&[axis])?;
        }
    }
    let mut poses: Vec<Pose> = Vec::with_capacity(t.row_count());
    for row in t.rows() {
        let cmd = joints
            .iter()
            .zip(&options.kinds)
            .map(|(&c, kind)| {
                let v = t.number(&row, c)?;
                Ok(match kind {
                    JointKind::Revolute if options.radians => v.to_degrees(),
                    JointKind::Revolute => v,
                    JointKind::Prismatic => v * options.lengths.to_mm(),
                })
            })
            .collect::<Result<Vec<_>, PointsError>>()?;
        let seen = markers
            .iter()
            .map(|m| marker(t, &row, m, options.lengths))
            .collect::<Result<Vec<_>, _>>()?;
        poses.push((row.line, cmd, seen));
    }
    if let Some((line, first)) = repeated_pose(&poses) {
        return Err(PointsError::File {
            path: t.path.clone(),
            message: format!(
                "line {line} repeats line {first} cell for cell (every joint value and marker coordinate the same, which two measurements never are): a row written twice; delete one of them"
            ),
        });
    }
    if let Some(broken) = broken_sweep(&poses, options.still_tolerance) {
        let column = broken.columns.first().map_or(joints[broken.joint], |&j| joints[j]);
        return Err(t.row_error(broken.line, column, broken.message(&poses, t, &joints)));
    }
    rows_of(&poses, options.kinds.len(), (options.still_tolerance, true), &t.path)
}

/// The first pose with a marker whose every value (bit for bit) repeats an earlier pose's: its
/// line and the earlier one's.
fn repeated_pose(poses: &[Pose]) -> Option<(usize, usize)> {
    let mut seen: std::collections::HashMap<Vec<u64>, usize> = std::collections::HashMap::new();
    poses.iter().find_map(|(line, cmd, markers)| {
        if markers.iter().all(Option::is_none) {
            return None;
        }
        let key: Vec<u64> = cmd
            .iter()
            .map(|v| v.to_bits())
            .chain(
                markers
                    .iter()
                    .flat_map(|m| m.map_or([u64::MAX; 3], |p| p.map(f64::to_bits))),
            )
            .collect();
        seen.insert(key, *line).map(|first| (*line, first))
    })
}

/// A pose that splits a sweep: its neighbours differ in joint `joint` alone by about two
/// steps of the sweep on either side of them (the same step, the same direction), while the
/// pose is off the line between them, and back on it in another unit. One row in other units
/// (radians among degrees) does this, and would import as two short experiments.
#[derive(Clone, Debug, PartialEq)]
struct BrokenSweep {
    /// The pose's index.
    pose: usize,
    /// Its line.
    line: usize,
    /// The swept joint (0-based).
    joint: usize,
    /// The joints (0-based) whose value is off the sweep.
    columns: Vec<usize>,
    /// The unit slip that puts the row on the sweep: what it is and the factor, as said.
    unit: (&'static str, &'static str),
}

/// Unit slips a row of joint values can carry, in file units: the factor that puts it back,
/// what the slip is, and the factor as said.
const UNIT_SLIPS: [(f64, &str, &str); 4] = [
    (
        180.0 / std::f64::consts::PI,
        "radians where degrees are expected",
        "times 57.296",
    ),
    (
        std::f64::consts::PI / 180.0,
        "degrees where radians are expected",
        "divided by 57.296",
    ),
    (1e3, "metres where millimetres are expected", "times 1000"),
    (1e-3, "millimetres where metres are expected", "divided by 1000"),
];

/// The first pose of `poses` that splits a sweep ([`BrokenSweep`]).
fn broken_sweep(poses: &[Pose], tolerance: f64) -> Option<BrokenSweep> {
    let q = |i: usize| poses[i].1.as_slice();
    (2..poses.len().saturating_sub(2)).find_map(|i| {
        let k = swept_joint(q(i - 1), q(i + 1), tolerance)?;
        let sweep_step = |a: usize| (swept_joint(q(a), q(a + 1), tolerance) == Some(k)).then(|| q(a + 1)[k] - q(a)[k]);
        let (left, right) = (sweep_step(i - 2)?, sweep_step(i + 1)?);
        let gap = q(i + 1)[k] - q(i - 1)[k];
        let one_sweep = left * right > 0.0
            && gap * left > 0.0
            && (0.5..=2.0).contains(&(left / right))
            && (1.5..=2.5).contains(&(gap / (0.5 * (left + right))));
        if !one_sweep {
            return None;
        }
        let expected: Vec<f64> = q(i - 1).iter().zip(q(i + 1)).map(|(a, b)| 0.5 * (a + b)).collect();
        let off = |f: f64| -> Vec<usize> {
            (0..expected.len())
                .filter(|&j| {
                    let allowed = if j == k {
                        0.25 * gap.abs()
                    } else {
                        tolerance.max(0.01 * expected[j].abs())
                    };
                    (q(i)[j] * f - expected[j]).abs() > allowed
                })
                .collect()
        };
        let columns = off(1.0);
        // Off the sweep for no unit's reason (a held joint's jitter beyond the still
        // tolerance): the sweep splits, and the import's jitter warning names the tolerance.
        let &(_, what, factor) = UNIT_SLIPS.iter().find(|(f, ..)| off(*f).is_empty())?;
        (!columns.is_empty()).then_some(BrokenSweep {
            pose: i,
            line: poses[i].0,
            joint: k,
            columns,
            unit: (what, factor),
        })
    })
}

impl BrokenSweep {
    /// The message, naming the lines around the pose and the likely unit slip.
    fn message(&self, poses: &[Pose], t: &Table, joints: &[usize]) -> String {
        let name = |j: usize| format!("`{}`", t.header_as_written.get(joints[j]).map_or("", String::as_str));
        let (what, factor) = self.unit;
        let why = format!(
            "its joint values look like {what} ({factor} they fall on the sweep); write the row in the table's unit"
        );
        format!(
            "the row splits the sweep of joint {} (lines {} and {} around it step {} alone, in the sweep's direction): {why}",
            self.joint + 1,
            poses[self.pose - 1].0,
            poses[self.pose + 1].0,
            name(self.joint)
        )
    }
}

/// The measurement rows of `poses` in experiments recovered from their joint values
/// ([`segment`]); `path` labels errors. With `file_lines` each pose's number is its line of the
/// file, which the set keeps for later checks to name.
pub(super) fn rows_of(
    poses: &[Pose],
    joints: usize,
    (still_tolerance, file_lines): (f64, bool),
    path: &std::path::Path,
) -> Result<MeasurementSet, PointsError> {
    let experiments = segment(poses, still_tolerance);
    let mut rows = Vec::new();
    // Each row's pose line and target, for an error in the file's terms.
    let mut sources = Vec::new();
    for (pose, (name, moved_joint, step)) in poses.iter().zip(experiments) {
        for (target, p) in pose.2.iter().enumerate() {
            if let Some(p) = p {
                sources.push((pose.0, target));
                rows.push(Measurement {
                    experiment: name.clone(),
                    moved_joint,
                    step,
                    target,
                    position_mm: *p,
                    cmd: pose.1.clone(),
                    payload_kg: Measurement::DEFAULT_PAYLOAD_KG,
                    temperature_c: Measurement::DEFAULT_TEMPERATURE_C,
                });
            }
        }
    }
    let lines: Vec<u64> = sources.iter().map(|&(line, _)| line as u64).collect();
    let set = MeasurementSet::new(joints, rows).map_err(|e| match sources.get(e.row) {
        Some(&(line, target)) => PointsError::Row {
            path: path.to_owned(),
            line,
            field: source_column(&e.problem.column(), target),
            message: e.problem.to_string(),
        },
        None => PointsError::Set {
            path: path.to_owned(),
            cause: e,
        },
    })?;
    Ok(if file_lines { set.with_lines(lines) } else { set })
}

/// Refuses a marker column `m<i>_<axis>` the table has but the import would not read, with
/// `read` markers `1..=read` complete: markers counted from 0, or after a gap or an incomplete
/// marker (the reading stops at the first marker without its three columns).
fn unread_markers(t: &Table, read: usize) -> Result<(), PointsError> {
    let unread = t.header.iter().find_map(|name| {
        let (number, axis) = name.strip_prefix('m')?.split_once('_')?;
        let i: usize = number
            .parse()
            .ok()
            .filter(|_| number.bytes().all(|b| b.is_ascii_digit()))?;
        // With no marker read, marker 1's missing column is named by the caller.
        (["x", "y", "z"].contains(&axis) && (i == 0 || (read > 0 && i > read))).then_some((name, i))
    });
    let Some((name, i)) = unread else {
        return Ok(());
    };
    let why = if i == 0 {
        "markers count from 1 (m1_x is target 0): number them from 1".to_owned()
    } else {
        format!(
            "the markers read stop at m{read} because marker {} does not have all of m{0}_x, m{0}_y, m{0}_z: \
             number the markers 1, 2, 3, ... without a gap, each with its three columns",
            read + 1
        )
    };
    Err(PointsError::File {
        path: t.path.clone(),
        message: format!("column `{}`: not read: {why}", shown_cell(name)),
    })
}

/// The file's column of a measurement row's `column` (`x_mm`: marker `target + 1`'s x;
/// `cmd_k`: joint `k`).
fn source_column(column: &str, target: usize) -> String {
    match column.strip_suffix("_mm") {
        Some(axis @ ("x" | "y" | "z")) => format!("m{}_{axis}", target + 1),
        _ => match column.strip_prefix("cmd_") {
            Some(k) => format!("of joint {k}"),
            None => column.to_owned(),
        },
    }
}

/// One marker's position \[mm\], `None` when its three cells are empty or `nan`; a partly
/// given marker is an error.
fn marker(t: &Table, row: &Row<'_>, columns: &[usize; 3], unit: LengthUnit) -> Result<Option<[f64; 3]>, PointsError> {
    let absent = |c: usize| row.get(c).is_none_or(|s| s.is_empty() || s.eq_ignore_ascii_case("nan"));
    let missing = columns.iter().filter(|&&c| absent(c)).count();
    match missing {
        3 => Ok(None),
        0 => Ok(Some([
            t.number(row, columns[0])? * unit.to_mm(),
            t.number(row, columns[1])? * unit.to_mm(),
            t.number(row, columns[2])? * unit.to_mm(),
        ])),
        _ => {
            let c = columns.iter().copied().find(|&c| absent(c)).unwrap_or(columns[0]);
            let written = row
                .get(c)
                .filter(|s| !s.is_empty())
                .map_or("empty".to_owned(), |s| format!("{s:?} (missing)"));
            Err(t.row_error(
                row.line,
                c,
                format!("{written} while the marker's other coordinates are given: give all three, or leave all three empty (or nan) for a marker not seen"),
            ))
        }
    }
}

/// The lowest joint that changes between two poses, if only it (and the next joint, a
/// hold-still command) changes.
fn swept_joint(a: &[f64], b: &[f64], tolerance: f64) -> Option<usize> {
    let moved: Vec<usize> = (0..a.len()).filter(|&k| (a[k] - b[k]).abs() > tolerance).collect();
    match moved.as_slice() {
        [k] => Some(*k),
        [k, next] if *next == k + 1 => Some(*k),
        _ => None,
    }
}

/// Per pose: experiment id, moved joint (1-based, 0 for free poses) and step. Consecutive
/// poses whose joints all agree within `tolerance` (a pose measured again) are one position of
/// the robot: a sweep runs over positions, at least 3 of them, each a step of one joint in one
/// direction, and a pose measured again within a sweep stays in it (its own step).
pub(super) fn segment(poses: &[Pose], tolerance: f64) -> Vec<(String, usize, usize)> {
    let positions = positions(poses, tolerance);
    let at = |g: usize| poses[positions[g].start].1.as_slice();
    let n = positions.len();
    let mut runs: Vec<Option<(usize, usize)>> = vec![None; n];
    let mut runs_of_joint = vec![0usize; poses.first().map_or(0, |p| p.1.len())];
    let mut start = 0;
    while start + 1 < n {
        let Some(k) = swept_joint(at(start), at(start + 1), tolerance) else {
            start += 1;
            continue;
        };
        let rising = at(start + 1)[k] > at(start)[k];
        let mut end = start + 1;
        while end + 1 < n
            && swept_joint(at(end), at(end + 1), tolerance) == Some(k)
            && (at(end + 1)[k] > at(end)[k]) == rising
        {
            end += 1;
        }
        if end - start + 1 >= 3 {
            runs_of_joint[k] += 1;
            runs[start..=end].fill(Some((k, runs_of_joint[k])));
            start = end + 1;
        } else {
            start += 1;
        }
    }
    // Steps count poses: a run's from its first position, the free poses' through the file.
    let (mut run_step, mut free_step) = (0, 0);
    let mut out = Vec::with_capacity(poses.len());
    for (g, range) in positions.iter().enumerate() {
        if g == 0 || runs[g] != runs[g - 1] {
            run_step = 0;
        }
        for _ in range.clone() {
            out.push(match runs[g] {
                Some((k, run)) => {
                    run_step += 1;
                    let name = if run == 1 {
                        format!("axis{}", k + 1)
                    } else {
                        format!("axis{}-{run}", k + 1)
                    };
                    (name, k + 1, run_step - 1)
                }
                None => {
                    free_step += 1;
                    ("poses".to_owned(), 0, free_step - 1)
                }
            });
        }
    }
    out
}

/// The positions of the robot among `poses`: each a range of consecutive poses whose joints
/// all agree within `tolerance` with the pose before.
fn positions(poses: &[Pose], tolerance: f64) -> Vec<std::ops::Range<usize>> {
    let mut out: Vec<std::ops::Range<usize>> = Vec::new();
    for (i, pose) in poses.iter().enumerate() {
        let still = i > 0
            && pose
                .1
                .iter()
                .zip(&poses[i - 1].1)
                .all(|(a, b)| (a - b).abs() <= tolerance);
        match out.last_mut() {
            Some(last) if still => last.end = i + 1,
            _ => out.push(i..i + 1),
        }
    }
    out
}

/// A `--still-tolerance` that recovers the axis experiments of a table whose rows nearly all
/// became free poses: the held joints jitter (a read-back controller, encoder noise) by more
/// than the tolerance given, so no run of poses moves one joint alone.
#[derive(Clone, Debug, PartialEq)]
pub struct StillHint {
    /// Poses that became free poses with the tolerance given.
    pub free_poses: usize,
    /// Poses of the table.
    pub poses: usize,
    /// The tolerance to pass (file units: deg or mm), rounded up to two digits as written.
    pub tolerance: String,
    /// Poses that become axis-experiment poses with it.
    pub recovered: usize,
}

/// Candidate tolerances tried at most (quantiles of the consecutive poses' held jitter): each
/// is one segmentation of the table.
const HINT_CANDIDATES: usize = 32;

/// The [`StillHint`] for `set` (as [`import_wide`] writes it: rows pose by pose), imported with
/// `tolerance`: when more than half its poses are free, the smallest tolerance among the
/// consecutive poses' held jitters (the largest change of a joint other than the one that
/// changes most and the one after it, its hold-still partner) that makes the most poses axis
/// experiments, if that is more than half of them.
pub fn still_tolerance_hint(set: &MeasurementSet, tolerance: f64) -> Option<StillHint> {
    let poses = poses_of(set);
    let axis_poses = |t: f64| segment(&poses, t).iter().filter(|s| s.1 > 0).count();
    let n = poses.len();
    let free_poses = n - axis_poses(tolerance);
    if 2 * free_poses <= n {
        return None;
    }
    let mut jitters: Vec<f64> = poses.windows(2).filter_map(|w| held_jitter(&w[0].1, &w[1].1)).collect();
    jitters.retain(|&j| j > tolerance);
    jitters.sort_by(f64::total_cmp);
    jitters.dedup();
    // Two rounds of at most HINT_CANDIDATES: over all jitters, then over those between the
    // best and the next candidate above it.
    let (coarse, next) = best_tolerance(&jitters, &axis_poses);
    let finer: Vec<f64> = jitters.iter().copied().filter(|&j| j > coarse.0 && j < next).collect();
    let (fine, _) = best_tolerance(&finer, &axis_poses);
    let (best, recovered) = if fine.1 > coarse.1 { fine } else { coarse };
    (2 * recovered > n).then(|| StillHint {
        free_poses,
        poses: n,
        tolerance: rounded_up(best),
        recovered,
    })
}

/// Sweeps of one joint that are the next joint's sweeps: the joint's recorded value jitters
/// (a read-back controller, encoder noise) by more than the still tolerance while the next
/// joint turns, and the pair reads as the joint swept with a hold-still command on the next.
#[derive(Clone, Debug, PartialEq)]
pub struct JitterSweeps {
    /// The joint they claim to sweep (1-based).
    pub joint: usize,
    /// Their experiment ids.
    pub experiments: Vec<String>,
    /// The largest span of `joint` over one of them (file units: deg or mm), rounded up to two
    /// digits as written.
    pub joint_span: String,
    /// The smallest span of the next joint over one of them.
    pub next_span: f64,
    /// The tolerance to pass: above `joint`'s largest change between two consecutive poses
    /// while the next joint turns, rounded up to two digits as written.
    pub tolerance: String,
}

/// A hold-still command moves the next joint by the coupling it compensates times the swept
/// joint's turn, and wrist couplings are of order one (1 on the Boby-Klimchik arm, 1.68 on the
/// IRB/L6's joint 5): a next joint that turns more than this many times as far as the swept one
/// is the joint that moves, the other's recorded value jittering.
pub const HOLD_STILL_COUPLING_MAX: f64 = 100.0;

/// The [`JitterSweeps`] of `set` (as an import writes it) whose sweeps of one joint move the
/// next joint over [`HOLD_STILL_COUPLING_MAX`] times as far: the first such joint's.
pub fn jitter_sweeps_hint(set: &MeasurementSet) -> Option<JitterSweeps> {
    let span = |rows: &[&crate::measurement::Measurement], j: usize| {
        let values = rows.iter().map(|m| m.cmd[j]);
        values.clone().fold(f64::MIN, f64::max) - values.fold(f64::MAX, f64::min)
    };
    let experiments = set.experiments();
    let jittered: Vec<_> = experiments
        .iter()
        .filter(|e| e.moved_joint >= 1 && e.moved_joint < set.joint_count())
        .filter(|e| {
            let moved = span(&e.rows, e.moved_joint - 1);
            moved > 0.0 && span(&e.rows, e.moved_joint) > HOLD_STILL_COUPLING_MAX * moved
        })
        .collect();
    let joint = jittered.first()?.moved_joint;
    let of_joint: Vec<_> = jittered.into_iter().filter(|e| e.moved_joint == joint).collect();
    // The joint's largest jitter: its change between any two consecutive poses where the next
    // joint turns over HOLD_STILL_COUPLING_MAX times as far.
    let step = poses_of(set)
        .windows(2)
        .map(|w| {
            (
                (w[1].1[joint - 1] - w[0].1[joint - 1]).abs(),
                (w[1].1[joint] - w[0].1[joint]).abs(),
            )
        })
        .filter(|(own, next)| *next > HOLD_STILL_COUPLING_MAX * own)
        .fold(0.0, |m: f64, (own, _)| m.max(own));
    Some(JitterSweeps {
        joint,
        experiments: of_joint.iter().map(|e| e.name.to_owned()).collect(),
        joint_span: rounded_up(of_joint.iter().map(|e| span(&e.rows, joint - 1)).fold(0.0, f64::max)),
        next_span: of_joint.iter().map(|e| span(&e.rows, joint)).fold(f64::MAX, f64::min),
        tolerance: rounded_up(step),
    })
}

/// A table whose rows are sweeps out of order (shuffled, or sorted by another column): more
/// than half its poses became free poses, while the same poses sorted by their joint values
/// (the first joint first) make more than half of them axis-experiment poses.
#[derive(Clone, Debug, PartialEq)]
pub struct OrderHint {
    /// Poses that became free poses.
    pub free_poses: usize,
    /// Poses of the table.
    pub poses: usize,
    /// Poses that are axis-experiment poses once sorted.
    pub sorted_axis_poses: usize,
}

/// The [`OrderHint`] of `set` (as [`import_wide`] writes it) imported with `tolerance`.
/// Sorted by their joint values, each sweep's poses (one joint moving, the others at the
/// reference) lie together on either side of the reference, so the sweeps segment again.
pub fn sweep_order_hint(set: &MeasurementSet, tolerance: f64) -> Option<OrderHint> {
    let mut poses = poses_of(set);
    let axis_poses = |p: &[Pose]| segment(p, tolerance).iter().filter(|s| s.1 > 0).count();
    let n = poses.len();
    let free_poses = n - axis_poses(&poses);
    if 2 * free_poses <= n {
        return None;
    }
    poses.sort_by(|a, b| {
        a.1.iter()
            .zip(&b.1)
            .map(|(x, y)| x.total_cmp(y))
            .find(|o| o.is_ne())
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    let sorted_axis_poses = axis_poses(&poses);
    (2 * sorted_axis_poses > n).then_some(OrderHint {
        free_poses,
        poses: n,
        sorted_axis_poses,
    })
}

/// Of at most [`HINT_CANDIDATES`] of the sorted `candidates` (evenly among them, the last
/// included), the smallest that makes the most poses axis experiments (`axis_poses`), with
/// that count, and the candidate tried after it (infinite for the last).
fn best_tolerance(candidates: &[f64], axis_poses: &dyn Fn(f64) -> usize) -> ((f64, usize), f64) {
    let step = candidates.len().div_ceil(HINT_CANDIDATES).max(1);
    let mut tried: Vec<f64> = candidates.iter().copied().skip(step - 1).step_by(step).collect();
    if let Some(&last) = candidates.last()
        && tried.last() != Some(&last)
    {
        tried.push(last);
    }
    let counts: Vec<usize> = tried.iter().map(|&t| axis_poses(t)).collect();
    let Some(best) = (0..tried.len()).fold(None, |best: Option<usize>, i| match best {
        Some(b) if counts[b] >= counts[i] => Some(b),
        _ => Some(i),
    }) else {
        return ((f64::NAN, 0), f64::INFINITY);
    };
    (
        (tried[best], counts[best]),
        tried.get(best + 1).copied().unwrap_or(f64::INFINITY),
    )
}

/// The poses of `set` in row order (a pose: consecutive rows of one experiment and step).
fn poses_of(set: &MeasurementSet) -> Vec<Pose> {
    let rows = set.rows();
    rows.chunk_by(|a, b| a.experiment == b.experiment && a.step == b.step)
        .map(|pose| (0, pose[0].cmd.clone(), Vec::new()))
        .collect()
}

/// Between two poses: the largest change of a joint other than the one that changes most and
/// the next one (a hold-still command moves it with the swept joint); `None` with fewer than
/// three joints.
fn held_jitter(a: &[f64], b: &[f64]) -> Option<f64> {
    let change: Vec<f64> = a.iter().zip(b).map(|(x, y)| (x - y).abs()).collect();
    let swept = (0..change.len()).max_by(|&i, &j| change[i].total_cmp(&change[j]))?;
    (0..change.len())
        .filter(|&j| j != swept && j != swept + 1)
        .map(|j| change[j])
        .max_by(f64::total_cmp)
}

/// `x` rounded up to two significant digits, as text that reads back to at least `x`.
fn rounded_up(x: f64) -> String {
    let decimals = (1 - x.log10().floor() as i32).max(0) as usize;
    let scale = 10f64.powi(decimals as i32);
    let mut up = (x * scale).ceil();
    let mut text = format!("{:.decimals$}", up / scale);
    if text.parse::<f64>().is_ok_and(|v| v < x) {
        up += 1.0;
        text = format!("{:.decimals$}", up / scale);
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tolerance_is_rounded_up_to_two_digits_that_read_back_above_it() {
        for (x, text) in [
            (0.0918, "0.092"),
            (0.05, "0.050"),
            (1.23e-4, "0.00013"),
            (3.0, "3.0"),
            (47.2, "48"),
        ] {
            let got = rounded_up(x);
            assert_eq!(got, text, "{x}");
            assert!(got.parse::<f64>().unwrap() >= x);
        }
    }

    /// Poses at the joint values `q` (one marker each, unused by the segmentation).
    fn poses(q: &[[f64; 2]]) -> Vec<Pose> {
        q.iter()
            .enumerate()
            .map(|(i, q)| (i + 2, q.to_vec(), vec![Some([0.0; 3])]))
            .collect()
    }

    fn names_and_steps(q: &[[f64; 2]]) -> Vec<(String, usize)> {
        segment(&poses(q), 1e-6)
            .into_iter()
            .map(|(name, _, step)| (name, step))
            .collect()
    }

    fn named(expected: &[(&str, usize)]) -> Vec<(String, usize)> {
        expected.iter().map(|&(n, s)| (n.to_owned(), s)).collect()
    }

    #[test]
    fn sweeps_of_one_joint_in_one_direction_are_experiments_and_the_rest_free_poses() {
        let q = [
            [0.0, 5.0],
            [10.0, 5.0],
            [20.0, 5.0],
            [20.0, 15.0],
            [20.0, 25.0],
            [20.0, 35.0],
            [7.0, 3.0],
            [30.0, 5.0],
        ];
        let expected = [
            ("axis1", 0),
            ("axis1", 1),
            ("axis1", 2),
            ("axis2", 0),
            ("axis2", 1),
            ("axis2", 2),
            ("poses", 0),
            ("poses", 1),
        ];
        assert_eq!(names_and_steps(&q), named(&expected));
        // Out and back: two sweeps of joint 1, the turning position in the first.
        let q = [
            [0.0, 0.0],
            [10.0, 0.0],
            [20.0, 0.0],
            [10.0, 0.0],
            [0.0, 0.0],
            [-10.0, 0.0],
        ];
        let expected = [
            ("axis1", 0),
            ("axis1", 1),
            ("axis1", 2),
            ("axis1-2", 0),
            ("axis1-2", 1),
            ("axis1-2", 2),
        ];
        assert_eq!(names_and_steps(&q), named(&expected));
    }

    #[test]
    fn a_pose_measured_again_stays_in_its_sweep() {
        let sweep = |again: usize| -> Vec<[f64; 2]> {
            let mut q: Vec<[f64; 2]> = (0..5).map(|i| [10.0 * i as f64, 5.0]).collect();
            q.insert(again, q[again]);
            q
        };
        for again in 0..5 {
            let expected: Vec<(&str, usize)> = (0..6).map(|step| ("axis1", step)).collect();
            assert_eq!(
                names_and_steps(&sweep(again)),
                named(&expected),
                "pose {again} measured again"
            );
        }
        // Measured again within the still tolerance (a read-back that jitters).
        let mut q = sweep(2);
        q[3][1] += 0.5e-6;
        assert!(names_and_steps(&q).iter().all(|(name, _)| name == "axis1"));
    }
}
