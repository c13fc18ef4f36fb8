//! The data a certificate summarises, and whether they are the data the calibration was made
//! from. A calibration written by `axiscal calibrate` records the digest of its data's rows
//! ([`MeasurementSet::digest`]): the data must have it (the same rows, measured points and
//! commands). A calibration does not record its file, and one written before the digest was
//! recorded is checked by what it does record: each axis fit's sweeps with
//! the poses of target 0 each used and the points the outlier screen set aside: the data must
//! hold the same axis experiments, moving the same joints, with as many poses
//! ([`data_mismatches`]). A calibration from free poses records how many poses it fitted, set
//! aside as outliers (by experiment and step), held out and left out: the data must hold as
//! many free poses, and the outliers among them. A certificate listing other data would
//! misstate what was measured.

use crate::calibration::free_pose::FreePoseSummary;
use crate::calibration::procedure::Calibration;
use crate::calibration::record::CalibrationRecord;
use crate::measurement::MeasurementSet;
use serde::Serialize;
use std::collections::{BTreeMap, BTreeSet};

/// The data the calibration was made from.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct DataSection {
    /// The file.
    pub file: String,
    /// Rows (measured points).
    pub rows: usize,
    /// Per experiment.
    pub experiments: Vec<ExperimentLine>,
}

/// One experiment of the data.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct ExperimentLine {
    /// Its name.
    pub name: String,
    /// The joint it moves (0: none).
    pub moved_joint: usize,
    /// Poses (steps).
    pub poses: usize,
    /// Rows.
    pub rows: usize,
}

/// The data section of `set` read from `file`.
pub(super) fn data_section(file: &str, set: &MeasurementSet) -> DataSection {
    DataSection {
        file: file.to_string(),
        rows: set.rows().len(),
        experiments: set
            .experiments()
            .into_iter()
            .map(|e| ExperimentLine {
                name: e.name.to_string(),
                moved_joint: e.moved_joint,
                poses: e.by_step().len(),
                rows: e.rows.len(),
            })
            .collect(),
    }
}

/// How `set` differs from the data `record` records (module doc), one sentence each; empty
/// when it matches.
pub fn data_mismatches(record: &CalibrationRecord, set: &MeasurementSet) -> Vec<String> {
    let cal = &record.calibration;
    let mismatches = structure_mismatches(cal, record.reports.free_poses.as_ref(), set);
    let digest = set.digest();
    match &cal.data_digest {
        Some(recorded) if mismatches.is_empty() && *recorded != digest => vec![format!(
            "its rows (measured points and commands) differ from those the calibration was made from (`data_digest` \
             {recorded}, the data's {digest})"
        )],
        _ => mismatches,
    }
}

/// How the experiments and poses of `set` differ from those `cal` (with its free-pose
/// summary, for a free-pose calibration) records.
fn structure_mismatches(cal: &Calibration, free_poses: Option<&FreePoseSummary>, set: &MeasurementSet) -> Vec<String> {
    if let Some(fp) = free_poses {
        return free_pose_mismatches(fp, set);
    }
    if cal.axes.is_empty() {
        return Vec::new();
    }
    // Per experiment of the data: the joint it moves and its steps with target 0.
    let mut data: BTreeMap<&str, (usize, BTreeSet<usize>)> = BTreeMap::new();
    for m in set.rows().iter().filter(|m| m.moved_joint > 0) {
        let e = data
            .entry(m.experiment.as_str())
            .or_insert((m.moved_joint, BTreeSet::new()));
        if m.target == 0 {
            e.1.insert(m.step);
        }
    }
    let mut out = Vec::new();
    let mut recorded = BTreeSet::new();
    for axis in &cal.axes {
        let sweeps: Vec<(&str, usize)> = if axis.sweeps.is_empty() {
            vec![(axis.experiment.as_str(), axis.points)]
        } else {
            axis.sweeps.iter().map(|s| (s.experiment.as_str(), s.points)).collect()
        };
        for (name, points) in sweeps {
            recorded.insert(name);
            let Some((joint, steps)) = data.get(name) else {
                out.push(format!(
                    "the calibration fitted joint {} to experiment `{name}` ({points} poses), which the data do not hold",
                    axis.joint
                ));
                continue;
            };
            if *joint != axis.joint {
                out.push(format!(
                    "experiment `{name}` moves joint {joint} in the data and joint {} in the calibration",
                    axis.joint
                ));
            }
            let dropped: BTreeSet<usize> = cal
                .outliers
                .iter()
                .filter(|o| o.dropped && o.experiment == name)
                .map(|o| o.step)
                .collect();
            let used = steps.difference(&dropped).count();
            if used != points {
                out.push(format!(
                    "experiment `{name}` has {used} poses of target 0 in the data (outliers set aside) and {points} in the calibration"
                ));
            }
        }
    }
    for (name, (joint, _)) in &data {
        if !recorded.contains(name) {
            out.push(format!(
                "the data's experiment `{name}` (joint {joint}) is not one the calibration fitted"
            ));
        }
    }
    out
}

/// How `set` differs from the free poses the summary `fp` records (module doc).
fn free_pose_mismatches(fp: &FreePoseSummary, set: &MeasurementSet) -> Vec<String> {
    let all_rows = fp.axis_rows_as_poses.is_some();
    let poses: BTreeSet<(&str, usize)> = set
        .rows()
        .iter()
        .filter(|m| all_rows || m.moved_joint == 0)
        .map(|m| (m.experiment.as_str(), m.step))
        .collect();
    let dropped = fp.outliers.iter().filter(|o| o.dropped).count();
    let held = fp.holdout.as_ref().map_or(0, |h| {
        h.heldout_poses + h.unexecutable_poses + h.outliers.iter().filter(|o| o.dropped).count()
    });
    let recorded = fp.poses + dropped + held + fp.poses_left_out;
    let mut out = Vec::new();
    if poses.len() != recorded {
        out.push(format!(
            "the data hold {} free poses, the calibration {recorded} ({} fitted, {dropped} set aside as outliers, {held} held out, {} left out)",
            poses.len(),
            fp.poses,
            fp.poses_left_out
        ));
    }
    for o in fp
        .outliers
        .iter()
        .filter(|o| !poses.contains(&(o.experiment.as_str(), o.step)))
    {
        out.push(format!(
            "the calibration's outlier pose `{}` step {} is not in the data",
            o.experiment, o.step
        ));
    }
    out
}
