//! The data a certificate summarises, and whether they are the data the calibration was made
//! from. A calibration does not record its file, but it records each axis fit's sweeps with
//! the poses of target 0 each used and the points the outlier screen set aside: the data must
//! hold the same axis experiments, moving the same joints, with as many poses
//! ([`data_mismatches`]). A certificate listing other data would misstate what was measured.

use crate::calibration::procedure::Calibration;
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

/// How `set` differs from the data `cal` records (module doc), one sentence each; empty when it
/// matches, and for a calibration from free poses (which records no sweeps).
pub fn data_mismatches(cal: &Calibration, set: &MeasurementSet) -> Vec<String> {
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
