//! The bounds and row helpers the sweep-point screen ([`super::screen_sweeps`]) and the
//! second-target screen ([`super::second_target`]) share: how many points a sweep may lose,
//! how many refits it gets, the set without the dropped points' poses.

use super::super::outlier_point::OutlierPoint;
use crate::measurement::MeasurementSet;

/// At most this share of a sweep's points may be set aside: beyond it the sweep, not single
/// points, is wrong (the one share of every outlier test).
pub use crate::numerics::outlier_rounds::OUTLIER_SHARE_MAX;

/// At most this many points of one sweep are set aside, one refit each: more gross errors in
/// one sweep make it wrong, not its points (and a million-point sweep is not refitted a
/// hundred thousand times).
pub const OUTLIER_ROUNDS_MAX: usize = 25;

/// What a sweep with too many points beyond the fence says, from those points (their place
/// among the sweep's points, step and file line, in sweep order): points in one run of
/// consecutive steps are a block of the sweep gone wrong; points apart are single rows, named.
pub(super) fn too_many_which(off: &[(usize, usize, Option<u64>)]) -> String {
    let run = off.windows(2).all(|w| w[1].0 == w[0].0 + 1);
    let lines: Option<Vec<String>> = off.iter().map(|o| o.2.map(|l| l.to_string())).collect();
    let steps: Vec<String> = off.iter().map(|o| o.1.to_string()).collect();
    let rows = match &lines {
        Some(lines) => format!("lines {}, steps {}", lines.join(", "), steps.join(", ")),
        None => format!("steps {}", steps.join(", ")),
    };
    if run {
        format!(
            " ({rows}, one run of consecutive steps): the sweep, not single points, is wrong (check its joint, its target ids, its units)"
        )
    } else {
        format!(
            ", more than the {:.0} % the test may set aside; they are single rows apart in the sweep ({rows}): check those rows' commands and coordinates (a typo, another unit, a command scaled in those rows); if they are right, the sweep itself is wrong (its joint, its target ids, its units)",
            OUTLIER_SHARE_MAX * 100.0
        )
    }
}

/// `set` without the poses of the `outliers` dropped (every target of a flagged point's step:
/// a wrong reading is wrong for each of its targets); `None` when none was dropped.
pub fn without_poses(set: &MeasurementSet, outliers: &[OutlierPoint]) -> Option<MeasurementSet> {
    let poses: std::collections::HashSet<(&str, usize)> = outliers
        .iter()
        .filter(|o| o.dropped)
        .map(|o| (o.experiment.as_str(), o.step))
        .collect();
    let dropped: Vec<usize> = (0..set.rows().len())
        .filter(|&i| poses.contains(&(set.rows()[i].experiment.as_str(), set.rows()[i].step)))
        .collect();
    (!dropped.is_empty()).then(|| set.without_rows(&dropped))
}
