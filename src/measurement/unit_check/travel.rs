//! The sliding joints' sweeps: how far a sweep moves its points against how far the
//! description's nominal robot moves them at the same commands. A sliding joint carries every
//! point after it exactly as far as it slides, whatever the links' lengths and the targets'
//! places, so the ratio is 1 within the stage's scale error (per mille) and the instrument's;
//! coordinates in metres give 0.001, commands in metres read as millimetres 1000. The revolute
//! arcs' checks cannot see either on a robot whose sweeps slide (a positioning table of stages).
//!
//! A description without `axis_targets` (SScanSS-2's robots: each sweep measures the point at
//! the tool frame's origin, as [`super::handedness::nominal_point`] takes it) gives the revolute
//! arcs' checks no target radius to judge: its revolute sweeps are judged here the same way, on
//! the tool origin's chords ([`tool_arc_slips`]).

use super::{LENGTH_UNITS, UnitSlip, coordinates_look, median, slipped, unit_of};
use crate::kinematics::JointKind;
use crate::measurement::{Experiment, Measurement, MeasurementSet, format_f64};
use crate::robot::{Controller, RobotDescription, RobotModel};

/// A sweep whose points move less than this \[mm\], measured and nominal alike, is not judged:
/// its travel is the instrument's noise more than the stage's motion (as
/// [`super::MIN_PRISMATIC_TRAVEL_MM`] for a joint's limits).
const MIN_JUDGED_TRAVEL_MM: f64 = super::MIN_PRISMATIC_TRAVEL_MM;

/// One sliding joint's sweep, judged.
pub(super) struct Travel {
    /// The moved joint (1-based).
    pub joint: usize,
    /// The experiment's id.
    pub name: String,
    /// Measured over nominal travel (the median over the sweep's point pairs half a sweep apart).
    pub ratio: f64,
    /// The nominal travel between its lowest and its highest command \[mm\].
    pub nominal_mm: f64,
    /// The measured travel between the same rows \[file length units\].
    pub measured_mm: f64,
}

/// The measured and the nominal distance \[mm\] between rows `a` and `b`.
fn distances(
    desc: &RobotDescription,
    ideal: &RobotModel,
    controller: &Controller,
    a: &Measurement,
    b: &Measurement,
) -> Option<(f64, f64)> {
    let nominal = |m: &Measurement| super::handedness::nominal_point(desc, ideal, controller, m);
    let nominal_mm = (nominal(a)? - nominal(b)?).norm() * 1e3;
    let measured_mm = (nalgebra::Vector3::from(a.position_mm) - nalgebra::Vector3::from(b.position_mm)).norm();
    Some((measured_mm, nominal_mm))
}

/// The sweep `e` of a sliding joint, judged on its target-0 rows by step.
fn travel_of(
    e: &Experiment<'_>,
    desc: &RobotDescription,
    ideal: &RobotModel,
    controller: &Controller,
) -> Option<Travel> {
    let rows: Vec<&Measurement> = e.rows_by_step().into_iter().filter(|m| m.target == 0).collect();
    let half = rows.len() / 2;
    let k = e.moved_joint - 1;
    let ratios: Vec<f64> = (0..rows.len().saturating_sub(half))
        .filter_map(|i| distances(desc, ideal, controller, rows[i], rows[i + half]))
        .filter(|(m, n)| m.max(*n) >= MIN_JUDGED_TRAVEL_MM && *n > 0.0)
        .map(|(m, n)| m / n)
        .collect();
    let by_command = |a: &&&Measurement, b: &&&Measurement| a.cmd[k].total_cmp(&b.cmd[k]);
    let (lo, hi) = (rows.iter().min_by(by_command)?, rows.iter().max_by(by_command)?);
    let (measured_mm, nominal_mm) = distances(desc, ideal, controller, lo, hi)?;
    (half > 0 && !ratios.is_empty()).then(|| Travel {
        joint: e.moved_joint,
        name: e.name.to_owned(),
        ratio: median(ratios),
        nominal_mm,
        measured_mm,
    })
}

/// The judged sweeps of the joints of `kind` of `set`.
fn sweeps_of(set: &MeasurementSet, desc: &RobotDescription, kind: JointKind) -> Vec<Travel> {
    let ideal = RobotModel::ideal(desc);
    let controller = Controller::from_description(desc);
    set.experiments()
        .iter()
        .filter(|e| e.moved_joint > 0)
        .filter(|e| desc.joints.get(e.moved_joint - 1).is_some_and(|j| j.kind == kind))
        .filter_map(|e| travel_of(e, desc, &ideal, &controller))
        .collect()
}

/// The judged sweeps of the sliding joints of `set`.
pub(super) fn travels(set: &MeasurementSet, desc: &RobotDescription) -> Vec<Travel> {
    sweeps_of(set, desc, JointKind::Prismatic)
}

/// The judged sweeps of the revolute joints of `set` when `desc` lists no `axis_targets` (module
/// docs): their tool origin's chords.
fn tool_arcs(set: &MeasurementSet, desc: &RobotDescription) -> Vec<Travel> {
    match desc.axis_targets.is_empty() {
        true => sweeps_of(set, desc, JointKind::Revolute),
        false => Vec::new(),
    }
}

/// The coordinates' slip the revolute sweeps of a description without `axis_targets` show
/// (module docs), unless `coordinates_said`: their median chord ratio beyond the slip factor.
fn tool_arc_slips(set: &MeasurementSet, desc: &RobotDescription, coordinates_said: bool) -> Option<UnitSlip> {
    let arcs = tool_arcs(set, desc);
    let ratio = median(arcs.iter().map(|t| t.ratio).collect());
    if coordinates_said || arcs.is_empty() || !slipped(ratio) {
        return None;
    }
    let t = arcs
        .iter()
        .min_by(|a, b| (a.ratio - ratio).abs().total_cmp(&(b.ratio - ratio).abs()))?;
    Some(UnitSlip {
        field: "x_mm,y_mm,z_mm".into(),
        message: format!(
            "the revolute sweeps' arcs are {} times the size the description gives them ({}: its points half a \
             sweep apart lie {} times as far apart as the description's robot puts them; the description lists no \
             axis_targets, so each sweep's point is its tool frame's origin): the coordinates {}, or the \
             description's lengths are not this robot's",
            format_f64((ratio * 1e4).round() / 1e4),
            t.name,
            format_f64((t.ratio * 1e4).round() / 1e4),
            coordinates_look(ratio)
        ),
    })
}

/// How `t` was measured, in words.
fn example(t: &Travel) -> String {
    format!(
        "{}: the points move {} mm as read between its lowest and highest command, where the description's robot moves them {} mm",
        t.name,
        format_f64((t.measured_mm * 1e4).round() / 1e4),
        format_f64((t.nominal_mm * 1e4).round() / 1e4)
    )
}

/// What sliding commands `ratio` times the travel read as millimetres look like, in words.
fn slide_commands_look(ratio: f64) -> String {
    match unit_of(&LENGTH_UNITS, 1.0 / ratio) {
        Some(unit) => format!("look like {unit} rather than millimetres"),
        None => format!(
            "look scaled by {} against millimetres (no length unit's factor)",
            format_f64((1e4 / ratio).round() / 1e4)
        ),
    }
}

/// The sweeps whose travel is a unit slip (module docs): the sliding joints' ([`slide_slips`]),
/// then, unless they said the coordinates', the revolute tool arcs' ([`tool_arc_slips`]).
/// `coordinates_said`: the revolute arcs already said the coordinates' slip.
pub(super) fn travel_slips(set: &MeasurementSet, desc: &RobotDescription, coordinates_said: bool) -> Vec<UnitSlip> {
    let mut slips = slide_slips(set, desc, coordinates_said);
    let said = coordinates_said || slips.iter().any(|s| s.field.starts_with('x'));
    slips.extend(tool_arc_slips(set, desc, said));
    slips
}

/// The sliding joints' sweeps whose travel is a unit slip (module docs): every sweep's (the
/// coordinates, or every sliding joint's commands), else each sweep's own (its joint's
/// commands, the other sweeps moving as far as commanded). `coordinates_said`: the revolute
/// arcs already said the coordinates' slip.
fn slide_slips(set: &MeasurementSet, desc: &RobotDescription, coordinates_said: bool) -> Vec<UnitSlip> {
    let all = travels(set, desc);
    let ratio = median(all.iter().map(|t| t.ratio).collect());
    if slipped(ratio) {
        if coordinates_said {
            return Vec::new();
        }
        let t = all
            .iter()
            .min_by(|a, b| (a.ratio - ratio).abs().total_cmp(&(b.ratio - ratio).abs()))
            .expect("a median of judged sweeps");
        let joints: std::collections::BTreeSet<usize> = all.iter().map(|t| t.joint).collect();
        let columns: Vec<String> = joints.iter().map(|j| format!("cmd_{j}")).collect();
        return vec![UnitSlip {
            field: "x_mm,y_mm,z_mm".into(),
            message: format!(
                "the sliding joints' sweeps move their points {} times as far as commanded ({}; a sliding joint \
                 carries every point after it exactly as far as it slides): the coordinates {}, or the sliding \
                 joints' commands ({}) {}",
                format_f64((ratio * 1e4).round() / 1e4),
                example(t),
                coordinates_look(ratio),
                columns.join(", "),
                slide_commands_look(ratio)
            ),
        }];
    }
    all.iter()
        .filter(|t| slipped(t.ratio))
        .map(|t| UnitSlip {
            field: format!("cmd_{}", t.joint),
            message: format!(
                "{}, {} times, where the file's other sliding sweeps move as far as commanded: joint {}'s commands {}",
                example(t),
                format_f64((t.ratio * 1e4).round() / 1e4),
                t.joint,
                slide_commands_look(t.ratio)
            ),
        })
        .collect()
}

/// How many of the unit checks judge `set` (the revolute arcs, the sliding sweeps, the tool
/// arcs of a description without axis targets and the free poses' spread each count; a sweep too short and free poses too near to judge do not): a
/// reading of a file in other units that passes the checks only because they no longer judge it
/// (angles read so small that the nominal robot barely moves) has not been shown to fit.
pub fn judged_checks(set: &MeasurementSet, desc: &RobotDescription) -> usize {
    super::arcs::experiment_arcs(set, desc).len()
        + travels(set, desc).len()
        + tool_arcs(set, desc).len()
        + usize::from(super::free_poses::free_pose_spread(set, desc).is_some())
}
