//! Axis experiments that are no sweep of one joint: rows labelled with a `moved_joint` whose
//! steps move other joints as far. A unit check of such an "arc" would name a command factor
//! no unit gives; the label is the slip.

use super::UnitSlip;
use crate::measurement::{Experiment, MeasurementSet, format_f64};
use crate::robot::{RobotDescription, file_unit};

/// A held joint of a sweep moves by less than this fraction of the swept joint's span: its
/// recorded values differ by the controller's jitter (hundredths of a degree) or by the
/// follower's hold-still motion (the next joint, excluded), not by a sizeable share of the sweep.
const HELD_SHARE: f64 = 0.1;

/// Other joints that move this far in one experiment make it a set of free poses: one joint
/// moving with the sweep is a coupled follower or a hand-moved joint, two are no sweep.
const MOVED_OTHERS: usize = 2;

/// The span of joint `k`'s (0-based) commands over `e`'s rows, in its file unit.
fn span(e: &Experiment<'_>, k: usize) -> f64 {
    let (lo, hi) = e
        .rows
        .iter()
        .map(|r| r.cmd[k])
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| (lo.min(c), hi.max(c)));
    hi - lo
}

/// The axis experiments of `set` whose steps move [`MOVED_OTHERS`] or more joints besides
/// their `moved_joint` and its follower by more than [`HELD_SHARE`] of its own span.
pub(super) fn not_sweeps(set: &MeasurementSet, desc: &RobotDescription) -> Vec<UnitSlip> {
    let mut slips = Vec::new();
    for e in set.experiments().iter().filter(|e| e.moved_joint > 0) {
        let k = e.moved_joint - 1;
        let own = span(e, k);
        let others: Vec<(usize, f64)> = (0..set.joint_count())
            .filter(|&j| j != k && j != k + 1)
            .map(|j| (j, span(e, j)))
            .filter(|(_, s)| *s > HELD_SHARE * own)
            .collect();
        if others.len() < MOVED_OTHERS {
            continue;
        }
        let moved: Vec<String> = others
            .iter()
            .map(|(j, s)| format!("joint {} by {} {}", j + 1, format_f64(s.round()), file_unit(desc, *j)))
            .collect();
        let lines = e.lines.map_or_else(String::new, |(a, b)| format!(" (lines {a}-{b})"));
        slips.push(UnitSlip {
            field: "moved_joint".into(),
            message: format!(
                "experiment {}{lines} is labelled moved_joint {}, but its steps also move {} (joint {} by {} {}): its \
                 rows are no sweep of one joint, so no unit of the commands or coordinates is judged in them; free \
                 poses take moved_joint 0 (docs/formats.md#measurement-csv)",
                e.name,
                e.moved_joint,
                moved.join(", "),
                e.moved_joint,
                format_f64(own.round()),
                file_unit(desc, k)
            ),
        });
    }
    slips
}
