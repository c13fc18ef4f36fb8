//! Unit sanity checks: the slips that otherwise pass silently and give wrong numbers.
//!
//! - Coordinates in metres (or inches, micrometres) in the `x_mm, y_mm, z_mm` columns: the
//!   radius of each axis experiment's arc against the radius the description's geometry gives
//!   its target.
//! - Commands in radians in the `cmd_k` columns (degrees expected for a revolute joint): the
//!   angle the target turns through against the commanded span.
//! - Description row lengths in millimetres where metres are expected (`a_m = -690`), and a
//!   tool frame or target further from its link than any link is long.
//! - Free poses (`moved_joint = 0`: validation poses, ISO cycles) with either slip: how far
//!   their measured tool positions spread against how far the nominal model moves the tool at
//!   their commands ([`free_pose_slips`]).
//!
//! Each estimate is a median over many point triples of a circle through three points (a
//! second, differently written path from the calibrator's fits), and a slip is reported only
//! when the ratio is beyond [`SLIP_FACTOR`] from 1: the slips are factors of 25.4, 57.3 and
//! 1000, while a real robot differs from its nominal description by percent.

use crate::kinematics::JointKind;
use crate::measurement::resolution::written_step_mm;
use crate::measurement::{MeasurementSet, format_f64};
use crate::robot::{RobotDescription, RowEntry};
use nalgebra::{Point3, Vector3};

mod arcs;
pub mod axis_scale;
pub mod column_stretch;
mod commands;
mod experiments;
mod free_poses;
mod handedness;
mod sweeps;
mod travel;

use arcs::{ExperimentArc, experiment_arcs};
use free_poses::{one_scale, plausible_spread};

pub use free_poses::{FreePoseSpread, free_pose_scale_warning, free_pose_slips, free_pose_spread};
pub use travel::judged_checks;

/// How much more the point triples' radii may scatter once a column is converted than as read:
/// a column in a finer unit read as coarser carries almost none of the noise (mm read as cm:
/// a tenth), and its conversion restores it; with one of three coordinates' noise restored
/// the noise power grows by at most 3/2, and `sqrt(3)` leaves the medians' own scatter room. A
/// conversion that draws ellipses instead moves the radii by a fraction of the arc's size.
pub(super) const MAX_SCATTER_GROWTH: f64 = 1.732;

/// A ratio this far from 1 (either way) is a unit slip, not a robot's deviation.
pub const SLIP_FACTOR: f64 = 5.0;

/// The longest plausible row length \[m\] of a robot arm.
pub const MAX_ROW_LENGTH_M: f64 = 20.0;

/// One likely unit slip, in words.
#[derive(Clone, Debug, PartialEq)]
pub struct UnitSlip {
    /// Where: a column (`x_mm,y_mm,z_mm`, `cmd_3`) or a description field (`rows[1].a_m`).
    pub field: String,
    /// What was found and what it likely is.
    pub message: String,
}

/// Length units the coordinate columns may be in instead of millimetres, by the factor (the
/// file's value over the millimetres) they give.
const LENGTH_UNITS: [(f64, &str); 4] = [
    (1e-3, "metres"),
    (1e3, "micrometres"),
    (1.0 / 25.4, "inches"),
    (1e-1, "centimetres"),
];

/// The length units a coordinate column slips into, by the factor they make its values: the
/// free poses' slip search (`crate::diagnosis::explained_misses`) tries each on each column.
pub const LENGTH_SLIPS: &[(f64, &str)] = &LENGTH_UNITS;

/// Units a revolute joint's commands may be in instead of degrees, by the ratio they give of
/// the angle a target turns to the commanded span read as degrees.
const ANGLE_UNITS: [(f64, &str); 5] = [
    (180.0 / std::f64::consts::PI, "radians"),
    (180.0 / std::f64::consts::PI / 1e3, "milliradians"),
    (360.0 / 400.0, "gradians"),
    (1e-3, "millidegrees"),
    // Degrees taken for radians by a converter (an importer's `--angles rad`, a file whose
    // convention is radians): 57.3 times the degrees.
    (
        std::f64::consts::PI / 180.0,
        "degrees converted as if they were radians (57.3 times the degrees)",
    ),
];

/// A ratio is said to be a unit's when within this factor of the unit's (either way): the
/// data of a robot within its description's tolerances and an instrument within its scale's
/// give a unit's factor within per cent; [`SPREAD_WARNING`] (a quarter) is beyond both.
fn unit_of(units: &[(f64, &'static str)], ratio: f64) -> Option<&'static str> {
    units
        .iter()
        .map(|(f, unit)| ((f.ln() - ratio.ln()).abs(), *unit))
        .filter(|(d, _)| *d < SPREAD_WARNING.ln())
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, unit)| unit)
}

/// What coordinates `ratio` times the millimetres expected look like, in words: a length
/// unit ([`LENGTH_UNITS`]), or the factor when no unit gives it (never an angle's unit).
fn coordinates_look(ratio: f64) -> String {
    match unit_of(&LENGTH_UNITS, ratio) {
        Some(unit) => format!("look like {unit} rather than millimetres"),
        None => format!(
            "look scaled by {} against millimetres (no length unit's factor)",
            format_f64((ratio * 1e4).round() / 1e4)
        ),
    }
}

/// What revolute commands whose targets turn `ratio` times the commanded span read as
/// degrees look like, in words: an angle unit ([`ANGLE_UNITS`]), or the factor the commands
/// are of the degrees (never a length's unit).
fn commands_look(ratio: f64) -> String {
    match unit_of(&ANGLE_UNITS, ratio) {
        Some(unit) => format!("look like {unit} rather than degrees"),
        None => format!(
            "look scaled by {} against degrees (no angle unit's factor)",
            format_f64((1e4 / ratio).round() / 1e4)
        ),
    }
}

fn slipped(ratio: f64) -> bool {
    ratio.is_finite() && ratio > 0.0 && !(1.0 / SLIP_FACTOR..=SLIP_FACTOR).contains(&ratio)
}

/// A revolute joint's range (upper minus lower limit) below this \[deg\] is no robot joint's
/// (a wrist or a positioner turns tens of degrees, and an axis fit needs an arc of several
/// degrees to locate the axis against the noise): it is radians read as degrees, which puts
/// any range up to 1.6 turns (10 rad) below it.
pub const MIN_REVOLUTE_RANGE_DEG: f64 = 10.0;

/// A sliding joint's travel (upper minus lower limit) below this \[mm\] is no sliding
/// joint's (a sweep that short moves its target by a few times the noise of a point, 0.2 mm
/// for the paper's theodolites): it is metres read as millimetres.
pub const MIN_PRISMATIC_TRAVEL_MM: f64 = 1.0;

/// Lengths of a description beyond a robot's: row lengths that look like millimetres (the
/// rows are in metres), a tool frame, targets or centres of mass further from their link than
/// any link is long (their millimetres are micrometres, or a slip), and joint limits narrower
/// than any joint's ([`MIN_REVOLUTE_RANGE_DEG`], [`MIN_PRISMATIC_TRAVEL_MM`]).
pub fn description_slips(desc: &RobotDescription) -> Vec<UnitSlip> {
    let mut slips = row_slips(&desc.rows);
    slips.extend(narrow_limits(desc));
    let targets = desc.tool.targets_mm.iter().enumerate();
    let mut points: Vec<(String, [f64; 3])> =
        vec![("tool.frame.translation_mm".into(), desc.tool.frame.translation_mm)];
    points.extend(targets.map(|(k, t)| (format!("tool.targets_mm[{k}]"), *t)));
    for (k, a) in desc.axis_targets.iter().enumerate() {
        points.push((format!("axis_targets[{k}].target0.position_mm"), a.target0.position_mm));
        if let Some(t1) = a.target1 {
            points.push((format!("axis_targets[{k}].target1.position_mm"), t1.position_mm));
        }
    }
    points.extend(
        desc.joints
            .iter()
            .enumerate()
            .map(|(k, j)| (format!("joints[{k}].com_mm"), j.com_mm)),
    );
    let (far, near): (Vec<_>, Vec<_>) = points
        .into_iter()
        .map(|(field, p)| (field, Vector3::from(p).norm()))
        .partition(|(_, mm)| *mm > MAX_ROW_LENGTH_M * 1e3);
    for (field, mm) in far {
        slips.push(UnitSlip {
            field,
            message: format!(
                "{} mm from its link, further than any robot link is long ({MAX_ROW_LENGTH_M} m): the value is in mm",
                format_f64(mm)
            ),
        });
    }
    slips.extend(targets_beyond_the_arm(desc, &near));
    slips
}

/// The joints whose limits span less than a joint moves ([`MIN_REVOLUTE_RANGE_DEG`],
/// [`MIN_PRISMATIC_TRAVEL_MM`]): limits in radians or metres where the file's degrees or
/// millimetres are expected.
fn narrow_limits(desc: &RobotDescription) -> Vec<UnitSlip> {
    let shown = |[lo, hi]: [f64; 2]| format!("[{}, {}]", format_f64(lo), format_f64(hi));
    desc.joints
        .iter()
        .enumerate()
        .filter_map(|(k, j)| {
            let [lo, hi] = j.limits;
            let (least, what, likely, factor) = match j.kind {
                JointKind::Revolute => (MIN_REVOLUTE_RANGE_DEG, "range", "radians", 180.0 / std::f64::consts::PI),
                JointKind::Prismatic => (MIN_PRISMATIC_TRAVEL_MM, "travel", "metres", 1e3),
            };
            let unit = j.kind.file_unit();
            (hi - lo < least).then(|| UnitSlip {
                field: format!("joints[{k}].limits"),
                message: format!(
                    "{} {unit} is a {what} of {} {unit}, less than any robot joint's ({least} {unit}): the limits are \
                     in {unit}; they look like {likely} ({} {unit}?)",
                    shown(j.limits),
                    format_f64(hi - lo),
                    shown([lo * factor, hi * factor].map(|v| (v * 100.0).round() / 100.0))
                ),
            })
        })
        .collect()
}

/// Row lengths (`a_m`, `b_m`, `h_m` of a description or a robot model file) beyond
/// [`MAX_ROW_LENGTH_M`]: millimetres where metres are expected, or no unit's.
pub fn row_slips(rows: &[RowEntry]) -> Vec<UnitSlip> {
    let mut slips = Vec::new();
    for (i, r) in rows.iter().enumerate() {
        for (key, v) in [("a_m", r.a_m), ("b_m", r.b_m), ("h_m", r.h_m)] {
            if v.abs() > MAX_ROW_LENGTH_M {
                let likely = if v.abs() * 1e-3 <= MAX_ROW_LENGTH_M {
                    format!("it looks like millimetres ({} m?)", format_f64(v / 1e3))
                } else {
                    "no unit makes it a robot's".to_owned()
                };
                slips.push(UnitSlip {
                    field: format!("rows[{i}].{key}"),
                    message: format!(
                        "{} m is longer than any robot link ({MAX_ROW_LENGTH_M} m): the rows are in metres; {likely}",
                        format_f64(v)
                    ),
                });
            }
        }
    }
    slips
}

/// Targets this many times further from their links than the longest row is long are on
/// another robot's scale: one of the two is in the wrong unit (a factor of 1000 in practice).
pub const TARGET_OVER_ROW_FACTOR: f64 = 100.0;

/// Row lengths below this \[m\] are rounding (a converted chain's zero lengths), not a size.
pub(crate) const ZERO_LENGTH_M: f64 = 1e-6;

/// The rows and the targets (each with its distance from its link \[mm\]) on two scales
/// ([`TARGET_OVER_ROW_FACTOR`]): rows converted from a `dh` table or a URDF in metres where
/// mm (or m) are expected.
fn targets_beyond_the_arm(desc: &RobotDescription, points: &[(String, f64)]) -> Option<UnitSlip> {
    let longest_row_m = desc
        .rows
        .iter()
        .flat_map(|r| [r.a_m, r.b_m, r.h_m])
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    let (field, farthest_mm) = points.iter().max_by(|a, b| a.1.total_cmp(&b.1))?;
    (longest_row_m > ZERO_LENGTH_M && farthest_mm * 1e-3 > TARGET_OVER_ROW_FACTOR * longest_row_m).then(|| UnitSlip {
        field: "rows".into(),
        message: format!(
            "the longest row is {:.3} mm, but `{field}` sits {farthest_mm:.3} mm from its link: the arm's lengths (the \
             rows, or the `dh` table's `d_mm`, `a_mm` or the URDF they come from) look like metres where millimetres \
             are expected, or the targets like micrometres",
            longest_row_m * 1e3
        ),
    })
}

/// Median of `values` (NaN when empty).
fn median(mut values: Vec<f64>) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// A radius departs from the described one by more than this many of its standard errors
/// ([`arcs::Arc::radius_sigma`]) before its size is read as a unit: a sweep whose held joints wander
/// by a tenth of a degree scatters its point triples' radii by a fifth of a short wrist radius.
pub(super) const RADIUS_SIGMAS: f64 = 3.0;

/// The free poses may spread this much more or less (a ratio) than the nominal model at their
/// commands before a warning: a robot within its drawing's tolerances and
/// an instrument within its scale's spread within a few per cent; a quarter more or less is a
/// scaled export or another robot.
pub const SPREAD_WARNING: f64 = 1.25;

/// Distances of `points` to their component-wise median point.
pub fn radii(points: &[Vector3<f64>]) -> Vec<f64> {
    let centre = Vector3::from_fn(|k, _| median(points.iter().map(|p| p[k]).collect()));
    points.iter().map(|p| (p - centre).norm()).collect()
}

/// The median distance of `measured` points to their median point over that of `nominal`
/// points (the same points as a model predicts them): the measured data's scale, whatever the
/// instrument's frame. `None` with fewer than 3 points or nominal points that do not spread.
pub fn spread_ratio(measured: &[Vector3<f64>], nominal: &[Vector3<f64>]) -> Option<f64> {
    if measured.len() < 3 || measured.len() != nominal.len() {
        return None;
    }
    let n = median(radii(nominal));
    (n > 0.0).then(|| median(radii(measured)) / n)
}

/// Coordinates and commands whose units look wrong (module docs), judged over the revolute axis
/// experiments' target 0 and the free poses ([`free_pose_slips`]). When one coordinate column
/// alone is in another unit, or scaled by any factor beyond 2 % ([`column_stretch`]), that
/// column is the one slip said.
pub fn measurement_slips(set: &MeasurementSet, desc: &RobotDescription) -> Vec<UnitSlip> {
    let faults = data_faults(set, desc);
    if !faults.is_empty() {
        return faults;
    }
    let slips = slips_as_read(set, desc);
    if slips.is_empty() {
        return column_stretch::one_column_stretched(set, desc).into_iter().collect();
    }
    one_column_slip(set, desc)
        .or_else(|| column_stretch::one_column_stretched(set, desc))
        .map_or(slips, |one| vec![one])
}

/// What no other unit of a column explains and the unit checks are not judged beside: rows
/// labelled a sweep that move other joints (`sweeps`), coordinates written rounded, a
/// left-handed instrument frame (`handedness`). The first found.
pub fn data_faults(set: &MeasurementSet, desc: &RobotDescription) -> Vec<UnitSlip> {
    let mislabelled = sweeps::not_sweeps(set, desc);
    if !mislabelled.is_empty() {
        return mislabelled;
    }
    rounded_coordinates(set)
        .or_else(|| handedness::mirrored(set, desc))
        .into_iter()
        .collect()
}

/// The finest step \[mm\] coordinates are judged rounded to: a multiple of 1 mm adds
/// `1 / sqrt(12)` = 0.29 mm of noise to each coordinate, above the 0.2 mm of the paper's
/// theodolites that [`arcs::MIN_JUDGED_SAGITTA_MM`] assumes and far above a laser tracker's.
const ROUNDING_STEP_MIN_MM: f64 = 1.0;

/// Fewer rows than this are not judged rounded: a few round values happen.
const MIN_ROUNDED_ROWS: usize = 20;

/// Coordinates written rounded (every value a multiple of a step of at least
/// [`ROUNDING_STEP_MIN_MM`], [`written_step_mm`], the points not all one): the rounding is noise the arcs' checks cannot tell from a slip.
fn rounded_coordinates(set: &MeasurementSet) -> Option<UnitSlip> {
    let rows = set.rows();
    let values = || rows.iter().flat_map(|m| m.position_mm);
    let (lo, hi) = values().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if rows.len() < MIN_ROUNDED_ROWS || hi <= lo {
        return None;
    }
    let step = written_step_mm(values()).filter(|&q| q >= ROUNDING_STEP_MIN_MM)?;
    Some(UnitSlip {
        field: "x_mm,y_mm,z_mm".into(),
        message: format!(
            "every coordinate is a multiple of {} mm: the points were written rounded, which adds {:.2} mm of noise to \
             each coordinate, more than the instruments a calibration takes (0.2 mm theodolites, 0.02-0.05 mm trackers); write them with the instrument's resolution (a laser tracker \
             gives 0.001 mm)",
            format_f64(step),
            step / 12f64.sqrt()
        ),
    })
}

/// The coordinate column (`x_mm`, `y_mm` or `z_mm`) in another length unit (of [`LENGTH_UNITS`])
/// while the other two are millimetres: the one column whose conversion to millimetres leaves
/// no slip at all, when converting every column by one factor does not. A single column's slip distorts every arc and the free poses' spread, and
/// would be said as the whole file's coordinates or commands in another unit.
fn one_column_slip(set: &MeasurementSet, desc: &RobotDescription) -> Option<UnitSlip> {
    let lengths = &LENGTH_UNITS;
    // A conversion explains the slips when it leaves none and every arc judged as read is still
    // judged (a conversion that makes a sweep too short to judge says nothing of it).
    let judged = experiment_arcs(set, desc).len();
    // And the converted arcs lie on circles about as well as read: a unit is named only when
    // reading the column in it makes the data fit (a column in another unit draws ellipses).
    let scatter = |s: &MeasurementSet| median(experiment_arcs(s, desc).iter().map(|a| a.arc.radius_scatter).collect());
    let as_read = scatter(set);
    // The free poses, when judged, then spread as far as the nominal model's (within
    // [`SPREAD_WARNING`], not merely short of a slip): a conversion that only brings them within a
    // slip's factor is the best of bad explanations, not one that makes the data fit.
    let explains = |converted: &MeasurementSet| {
        slips_as_read(converted, desc).is_empty()
            && experiment_arcs(converted, desc).len() >= judged
            && scatter(converted) <= MAX_SCATTER_GROWTH * as_read
            && free_pose_spread(converted, desc).is_none_or(|s| plausible_spread(s.ratio))
            && one_scale(converted, desc).is_ok()
    };
    // Every column in one other unit: the free poses' spread may pass with one column converted
    // alone (it is mostly that column's), but the whole file's slip is the one to say.
    let all_scaled = |factor: f64| (0..3).fold(set.clone(), |s, c| s.with_coordinate_scaled(c, factor));
    if lengths.iter().any(|(ratio, _)| explains(&all_scaled(1.0 / ratio))) {
        return None;
    }
    let (column, (ratio, unit)) = (0..3)
        .flat_map(|c| lengths.iter().map(move |k| (c, *k)))
        .find(|&(c, (ratio, _))| explains(&set.with_coordinate_scaled(c, 1.0 / ratio)))?;
    let name = ["x_mm", "y_mm", "z_mm"][column];
    Some(UnitSlip {
        field: name.into(),
        message: format!(
            "the arcs and the free poses match the description once this column alone is multiplied by {}: its \
             values look like {unit} rather than millimetres, while the other coordinate columns are millimetres",
            format_f64(1.0 / ratio)
        ),
    })
}

/// [`measurement_slips`] of the file's columns as they are.
fn slips_as_read(set: &MeasurementSet, desc: &RobotDescription) -> Vec<UnitSlip> {
    let all = experiment_arcs(set, desc);
    if let Some(offset) = commands::offset_command(desc, &all) {
        return vec![offset];
    }
    let ratios: Vec<f64> = all.iter().filter_map(|a| Some(a.arc.radius / a.nominal_mm?)).collect();
    let in_scale = ratios.is_empty() || median(ratios).ln().abs() <= SPREAD_WARNING.ln();
    let (mut slips, said) = experiments::misplaced(&all, in_scale);
    let unsaid = || all.iter().enumerate().filter(|(i, _)| !said.contains(i));
    let arcs: Vec<&ExperimentArc> = unsaid().map(|(_, a)| a).collect();
    let scale: Vec<(f64, String, usize)> = unsaid()
        .filter_map(|(i, a)| {
            let nominal = a.nominal_mm?;
            Some((
                a.arc.radius / nominal,
                format!(
                    "{}: target 0 turns on a radius of {:.4} where the description gives {nominal:.1} mm",
                    a.name, a.arc.radius
                ),
                i,
            ))
        })
        .collect();
    // An angle unit is named only for points that turn in step with their commands
    // ([`commands::turns_in_step`]): points of an arc in another order than their commands turn
    // at random against them, which no unit mends (the calibration names the order).
    let angle: Vec<(f64, usize, String)> = arcs
        .iter()
        .filter(|a| commands::turns_in_step(a))
        .map(|a| (a.arc.turn_ratio, a.joint, a.name.clone()))
        .collect();
    let ratio = median(scale.iter().map(|s| s.0).collect());
    if slipped(ratio)
        && let Some((_, example, _)) = scale
            .iter()
            .min_by(|a, b| (a.0 - ratio).abs().total_cmp(&(b.0 - ratio).abs()))
    {
        slips.push(UnitSlip {
            field: "x_mm,y_mm,z_mm".into(),
            message: format!(
                "the measured arcs are {ratio:.4} times the size the description gives them ({example}): the \
                 coordinates {}",
                coordinates_look(ratio)
            ),
        });
    }
    // One experiment in other units among consistent ones: the median above misses it. Said only
    // when its coordinates scaled back put it in place among the others (a target near the axis
    // read for the one described turns on a small radius, which no scale puts in place).
    if !slipped(ratio) {
        let scaled_back = |s: &&(f64, String, usize)| experiments::in_place_scaled(s.2, &all, 1.0 / s.0);
        let off =
            |s: &&(f64, String, usize)| slipped(s.0) && all[s.2].nominal_mm.is_some_and(|n| all[s.2].arc.radius_off(n));
        for (r, example, _) in scale.iter().filter(off).filter(scaled_back) {
            slips.push(UnitSlip {
                field: "x_mm,y_mm,z_mm".into(),
                message: format!(
                    "{example}, {r:.4} times, where the file's other arcs match the description: this \
                     experiment's coordinates {}",
                    coordinates_look(*r)
                ),
            });
        }
    }
    slips.extend(commands::scaled_commands(desc, &arcs));
    let bad: Vec<&(f64, usize, String)> = angle.iter().filter(|a| slipped(a.0)).collect();
    if let (Some(lo), Some(hi)) = (
        bad.iter().map(|a| a.0).min_by(f64::total_cmp),
        bad.iter().map(|a| a.0).max_by(f64::total_cmp),
    ) {
        let joints: std::collections::BTreeSet<usize> = bad.iter().map(|a| a.1).collect();
        let columns: Vec<String> = joints.iter().map(|j| format!("cmd_{j}")).collect();
        let experiments: Vec<&str> = bad.iter().map(|a| a.2.as_str()).collect();
        let times = if bad.len() == 1 {
            format!("{lo:.3}")
        } else {
            format!("{lo:.3} to {hi:.3}")
        };
        slips.push(UnitSlip {
            field: columns.join(","),
            message: format!(
                "the targets turn {times} times the commanded span read as degrees ({}): the commands {}",
                experiments.join(", "),
                commands_look(median(bad.iter().map(|a| a.0).collect()))
            ),
        });
    }
    let coordinates_said = slips.iter().any(|s| s.field.starts_with('x'));
    slips.extend(travel::travel_slips(set, desc, coordinates_said));
    // The free poses, unless the sweeps already said the same slip of the same columns.
    for slip in free_pose_slips(set, desc) {
        let coordinates = |s: &UnitSlip| s.field.starts_with('x');
        if !slips.iter().any(|s| coordinates(s) == coordinates(&slip)) {
            slips.push(slip);
        }
    }
    slips
}

/// Data that do not look like the description's robot at all: its nominal model, placed at best,
/// misses the points by a good part of their spread (the handedness module's rotation fit).
pub fn not_this_robot(set: &MeasurementSet, desc: &RobotDescription) -> Option<UnitSlip> {
    handedness::not_this_robot(set, desc)
}

/// A payload may weigh this many times the robot's moving links (the sum of the description's
/// `mass_kg`) before a warning: an arm carries a fraction of its own mass (the paper's IRB/L6 6 kg
/// on about 90 kg of links, a UR5e 5 kg on about 18 kg, the lightest cobots up to about half), so
/// a payload heavier than the arm itself is grams written as kg, a typo or another robot.
pub const MAX_PAYLOAD_OVER_ROBOT_MASS: f64 = 1.0;

/// The first row of `set` whose `payload_kg` exceeds [`MAX_PAYLOAD_OVER_ROBOT_MASS`] times the
/// robot's moving mass (the sum of the description's `mass_kg`): `(row, its payload, robot
/// mass, rows over it)`. `None` when the description gives no masses (a description rates no payload:
/// the reader's bound of 10 t, [`crate::measurement::MAX_PAYLOAD_KG`], is then the only one).
pub fn payload_over_robot_mass(set: &MeasurementSet, desc: &RobotDescription) -> Option<(usize, f64, f64, usize)> {
    let robot_kg: f64 = desc.joints.iter().map(|j| j.mass_kg).sum();
    if !(robot_kg.is_finite() && robot_kg > 0.0) {
        return None;
    }
    let bound = MAX_PAYLOAD_OVER_ROBOT_MASS * robot_kg;
    let over: Vec<(usize, f64)> = set
        .rows()
        .iter()
        .enumerate()
        .filter(|(_, m)| m.payload_kg > bound)
        .map(|(i, m)| (i, m.payload_kg))
        .collect();
    let (row, payload) = *over.first()?;
    Some((row, payload, robot_kg, over.len()))
}

/// Required tool positions \[m, instrument frame\] whose distances from the robot's first
/// axis origin do not fit the robot: their median against half the chain's length (the sum of
/// its links' and the tool's offsets, the farthest any pose reaches) is a unit slip
/// ([`SLIP_FACTOR`]) — poses in metres read as millimetres sit inside the base.
pub fn pose_slips(positions_m: &[Point3<f64>], desc: &RobotDescription) -> Option<UnitSlip> {
    let model = desc.nominal_model();
    let q = vec![0.0; model.dof()];
    let base = model.poses(&q).axis(0).origin_m;
    let length_m: f64 = (0..model.dof() - 1)
        .map(|k| model.link_from_next_frame(k).translation.vector.norm())
        .sum::<f64>()
        + model.last_link_from_tool.translation.vector.norm();
    let distances: Vec<f64> = positions_m.iter().map(|p| (p - base).norm()).collect();
    let ratio = median(distances) / (0.5 * length_m);
    let what = if ratio > 2.0 {
        "beyond any pose's reach: another unit (poses in metres read as millimetres sit at the instrument's origin) or another frame than the instrument's?".to_string()
    } else {
        format!("they {}", coordinates_look(ratio))
    };
    slipped(ratio).then(|| UnitSlip {
        field: "x_mm,y_mm,z_mm".into(),
        message: format!(
            "the poses lie a median {ratio:.3} times half the robot's length ({:.0} mm: its links and tool) from its base, {what}",
            0.5 * length_m * 1e3,
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::arcs::{ASSUMED_POINT_NOISE_MM, circle_through, noise_radius_sigma, triple_span_deg};
    use super::*;
    use crate::measurement::Measurement;
    use crate::robot::commands_to_internal;

    /// The radius's standard error at the assumed noise against the spread of the radii of
    /// circles through three noisy points (a Monte Carlo of `circle_through`, the second path):
    /// within 3 standard errors of a standard deviation over the draws, `sigma / sqrt(2 n)`,
    /// and the first-order formula's own error, `s / r` of it, for arcs from 246 mm over 15
    /// degrees (sagitta 2.1 mm) to 500 mm over 60 (67 mm).
    #[test]
    fn the_noise_radius_sigma_matches_circles_through_noisy_triples() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        let mut rng = rand::rngs::ChaCha12Rng::seed_from_u64(9);
        let noise = Normal::new(0.0, ASSUMED_POINT_NOISE_MM).unwrap();
        let draws = 4000;
        for (radius, span_deg) in [(246.0, 15.0), (72.0, 30.0), (500.0, 60.0)] {
            let half = f64::to_radians(span_deg / 2.0);
            let on_arc = |a: f64| Point3::new(radius * a.cos(), radius * a.sin(), 0.0);
            let radii: Vec<f64> = (0..draws)
                .filter_map(|_| {
                    let mut noisy = |p: Point3<f64>| p + Vector3::from_fn(|_, _| noise.sample(&mut rng));
                    let (a, b, c) = (noisy(on_arc(-half)), noisy(on_arc(0.0)), noisy(on_arc(half)));
                    circle_through(&a, &b, &c).map(|(_, r, _)| r)
                })
                .collect();
            let n = radii.len() as f64;
            let mean = radii.iter().sum::<f64>() / n;
            let sd = (radii.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
            let sagitta = radius * (1.0 - half.cos());
            let predicted = noise_radius_sigma(radius, sagitta);
            let tolerance = 3.0 * sd / (2.0 * n).sqrt() + predicted * sagitta / radius;
            assert!(
                (predicted - sd).abs() < tolerance,
                "r {radius} over {span_deg} deg: predicted {predicted}, drawn {sd} (+- {tolerance})"
            );
        }
    }

    /// Rows of joint 1 at `commands` (degrees), the other fields irrelevant here.
    fn at_commands(commands: &[f64]) -> Vec<Measurement> {
        commands
            .iter()
            .enumerate()
            .map(|(step, c)| Measurement {
                experiment: "axis1".into(),
                moved_joint: 1,
                step,
                target: 0,
                position_mm: [0.0; 3],
                cmd: vec![*c],
                payload_kg: Measurement::DEFAULT_PAYLOAD_KG,
                temperature_c: Measurement::DEFAULT_TEMPERATURE_C,
            })
            .collect()
    }

    #[test]
    fn a_triple_spans_two_thirds_of_the_points_it_is_taken_from() {
        // The commands are whole degrees or halves: each difference is exact, to a rounding.
        let spans = |commands: &[f64], expected: f64| {
            let rows = at_commands(commands);
            let span = triple_span_deg(&rows.iter().collect::<Vec<_>>(), 0);
            assert!(
                (span - expected).abs() <= f64::EPSILON * expected,
                "{commands:?}: {span}"
            );
        };
        // Five points over 30 degrees: one triple, over its first three points.
        spans(&[0.0, 7.5, 15.0, 22.5, 30.0], 15.0);
        // Sixteen points over 45 degrees: five triples, each over ten steps of 3 degrees.
        let sixteen: Vec<f64> = (0..16).map(|i| 3.0 * i as f64).collect();
        spans(&sixteen, 30.0);
        // Written in another order (descending): the same triples.
        let reversed: Vec<f64> = sixteen.iter().rev().copied().collect();
        spans(&reversed, 30.0);
        spans(&[0.0, 10.0], 0.0);
    }

    #[test]
    fn a_circle_through_three_points_has_its_radius_and_angle() {
        let on = |t: f64| Point3::new(1.0 + 2.0 * t.cos(), -3.0, 0.5 + 2.0 * t.sin());
        let (_, r, a) = circle_through(&on(0.1), &on(0.5), &on(1.2)).unwrap();
        assert!((r - 2.0).abs() < 1e-12 && (a - 1.1).abs() < 1e-12, "{r} {a}");
        assert!(circle_through(&on(0.1), &on(0.1), &on(0.2)).is_none());
    }

    /// The validation poses of the IRB/L6's workspace plan, measured exactly on its nominal
    /// model (the instrument at its base): `coordinates` times the millimetres, the commands
    /// written `commands` times the degrees.
    fn free_poses_set(coordinates: f64, commands: f64) -> MeasurementSet {
        let desc = RobotDescription::asea_irb6l();
        let plan = crate::plan::ValidationPlan::workspace_default(6);
        let reference = crate::plan::CalibrationPlan::for_robot(&desc).reference;
        let model = desc.nominal_model();
        let mut rows = Vec::new();
        for (step, cmd) in plan.commands(&desc, &reference).into_iter().enumerate() {
            let tool = model.world_from_tool(&commands_to_internal(&desc, &cmd));
            for (target, t) in desc.tool_targets_m().iter().enumerate() {
                let p = (tool * t).coords * 1e3 * coordinates;
                rows.push(Measurement {
                    experiment: "validation".into(),
                    moved_joint: 0,
                    step,
                    target,
                    position_mm: [p.x, p.y, p.z],
                    cmd: cmd.iter().map(|c| c * commands).collect(),
                    payload_kg: 0.0,
                    temperature_c: 20.0,
                });
            }
        }
        MeasurementSet::new(6, rows).unwrap()
    }

    #[test]
    fn free_poses_in_metres_or_radians_are_slips_and_in_millimetres_and_degrees_are_not() {
        let desc = RobotDescription::asea_irb6l();
        assert_eq!(free_pose_slips(&free_poses_set(1.0, 1.0), &desc), vec![]);
        // A robot a tenth larger than its description is no slip.
        assert_eq!(free_pose_slips(&free_poses_set(1.1, 1.0), &desc), vec![]);
        let metres = free_pose_slips(&free_poses_set(1e-3, 1.0), &desc);
        assert_eq!(metres.len(), 1);
        assert_eq!(metres[0].field, "x_mm,y_mm,z_mm");
        assert!(metres[0].message.contains("look like metres"), "{}", metres[0].message);
        let radians = free_pose_slips(&free_poses_set(1.0, 1f64.to_radians()), &desc);
        assert_eq!(radians.len(), 1);
        assert_eq!(radians[0].field, "cmd_1,cmd_2,cmd_3,cmd_4,cmd_5,cmd_6");
        assert!(
            radians[0].message.contains("look like radians"),
            "{}",
            radians[0].message
        );
    }

    #[test]
    fn the_likely_unit_is_the_nearest_of_the_columns_kind() {
        assert_eq!(unit_of(&LENGTH_UNITS, 0.0011), Some("metres"));
        assert_eq!(unit_of(&LENGTH_UNITS, 0.04), Some("inches"));
        assert_eq!(unit_of(&LENGTH_UNITS, 57.0), None);
        assert!(coordinates_look(57.3).contains("scaled by 57.3"));
        assert_eq!(unit_of(&ANGLE_UNITS, 57.0), Some("radians"));
        assert_eq!(unit_of(&ANGLE_UNITS, 0.057), Some("milliradians"));
        assert_eq!(
            unit_of(&ANGLE_UNITS, 1.0 / 57.2826),
            Some("degrees converted as if they were radians (57.3 times the degrees)")
        );
        assert!(commands_look(0.04).contains("scaled by 25"));
        assert!(!slipped(1.3) && !slipped(0.8) && slipped(1e-3) && slipped(57.3) && !slipped(f64::NAN));
    }
}
