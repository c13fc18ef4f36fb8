//! Unit sanity checks: the slips that otherwise pass silently and give wrong numbers.
//!
//! - Coordinates in metres (or inches, micrometres) in the `x_mm, y_mm, z_mm` columns: the
//!   radius of each axis experiment's arc against the radius the description's geometry gives
//!   its target.
//! - Commands in radians in the `cmd_k` columns (degrees expected for a revolute joint): the
//!   angle the target turns through against the commanded span.
//! - Description row lengths in millimetres where metres are expected (`a_m = -690`), and a
//!   tool frame or target further from its link than any link is long.
//!
//! Each estimate is a median over many point triples of a circle through three points (a
//! second, differently written path from the calibrator's fits), and a slip is reported only
//! when the ratio is beyond [`SLIP_FACTOR`] from 1: the slips are factors of 25.4, 57.3 and
//! 1000, while a real robot differs from its nominal description by percent.

use crate::kinematics::JointKind;
use crate::measurement::{Measurement, MeasurementSet, format_f64};
use crate::robot::{RobotDescription, commands_to_internal};
use nalgebra::{Point3, Vector3};

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

/// Known slips by their factor: (factor, what data in those units look like).
const KNOWN: [(f64, &str); 6] = [
    (1e-3, "metres"),
    (1e3, "micrometres"),
    (1.0 / 25.4, "inches"),
    (1e-1, "centimetres"),
    (180.0 / std::f64::consts::PI, "radians"),
    (std::f64::consts::PI / 180.0, "another unit"),
];

/// The known unit nearest (in log scale) to `ratio`.
fn likely(ratio: f64) -> &'static str {
    KNOWN
        .iter()
        .min_by(|a, b| (a.0.ln() - ratio.ln()).abs().total_cmp(&(b.0.ln() - ratio.ln()).abs()))
        .map_or("another unit", |k| k.1)
}

fn slipped(ratio: f64) -> bool {
    ratio.is_finite() && ratio > 0.0 && !(1.0 / SLIP_FACTOR..=SLIP_FACTOR).contains(&ratio)
}

/// Lengths of a description beyond a robot's: row lengths that look like millimetres (the
/// rows are in metres), and a tool frame or targets further from their link than any link is
/// long (their millimetres are micrometres, or a slip).
pub fn description_slips(desc: &RobotDescription) -> Vec<UnitSlip> {
    let mut slips = Vec::new();
    for (i, r) in desc.rows.iter().enumerate() {
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

/// Targets this many times further from their links than the longest row is long are on
/// another robot's scale: one of the two is in the wrong unit (a factor of 1000 in practice).
pub const TARGET_OVER_ROW_FACTOR: f64 = 100.0;

/// Row lengths below this \[m\] are rounding (a converted chain's zero lengths), not a size.
const ZERO_LENGTH_M: f64 = 1e-6;

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

/// Centre, radius and the angle from `a` over `b` to `c` of the circle through three points,
/// or `None` when they are (nearly) collinear.
fn circle_through(a: &Point3<f64>, b: &Point3<f64>, c: &Point3<f64>) -> Option<(f64, f64)> {
    let (u, v) = (b - a, c - a);
    let w = u.cross(&v);
    let w2 = w.norm_squared();
    if w2 <= 1e-12 * u.norm_squared() * v.norm_squared() {
        return None;
    }
    // Circumcentre of a triangle in 3-D.
    let centre = a + (v.cross(&w) * u.norm_squared() + w.cross(&u) * v.norm_squared()) / (2.0 * w2);
    let angle = |p: &Point3<f64>, q: &Point3<f64>| (p - centre).angle(&(q - centre));
    Some(((a - centre).norm(), angle(a, b) + angle(b, c)))
}

/// Median of `values` (NaN when empty).
fn median(mut values: Vec<f64>) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// One axis experiment's target-0 arc: median radius \[file length units\] and the ratio of
/// the turned angle to the commanded span (both read in degrees).
fn arc_of(rows: &[&Measurement], k: usize) -> Option<(f64, f64)> {
    let m = rows.len() / 3;
    if m == 0 {
        return None;
    }
    let (mut radii, mut ratios) = (Vec::new(), Vec::new());
    for i in 0..m {
        let (a, b, c) = (rows[i], rows[i + m], rows[i + 2 * m]);
        let p = |r: &Measurement| Point3::from(Vector3::from(r.position_mm));
        let commanded = (c.cmd[k] - a.cmd[k]).abs();
        if let Some((radius, angle)) = circle_through(&p(a), &p(b), &p(c))
            && commanded > 0.0
        {
            radii.push(radius);
            ratios.push(angle.to_degrees() / commanded);
        }
    }
    Some((median(radii), median(ratios)))
}

/// An arc whose sagitta, as the description and the commands give it, and whose points' RMS
/// spread are both below this \[mm\] is not judged: a circle through three of its points
/// measures the instrument's noise (0.2 mm for the paper's theodolites, 0.02-0.05 mm for a
/// laser tracker) more than its radius.
const MIN_JUDGED_SAGITTA_MM: f64 = 1.0;

/// The sagitta \[mm\] of the arc a target at `radius_mm` from the axis draws over the commanded
/// span of joint `k` (0-based) in `rows` (read in degrees; at most half a turn).
fn expected_sagitta_mm(radius_mm: f64, rows: &[&Measurement], k: usize) -> f64 {
    let (lo, hi) = rows
        .iter()
        .map(|r| r.cmd[k])
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| (lo.min(c), hi.max(c)));
    let half = ((hi - lo).abs().min(360.0) / 2.0).to_radians();
    radius_mm * (1.0 - half.cos())
}

/// The radius \[mm\] the description gives the target of `rows` (target 0 of joint `joint`,
/// 1-based) about its axis at the first row's commands.
fn nominal_radius_mm(desc: &RobotDescription, joint: usize, first: &Measurement) -> Option<f64> {
    let target = desc.axis_targets_of(joint)?.target0;
    let model = desc.nominal_model();
    let q = commands_to_internal(desc, &first.cmd);
    let poses = model.poses(&q);
    let axis = poses.axis(joint - 1);
    let p = poses.world_from_link.get(target.link - 1)? * target.position_m();
    let d = p - axis.origin_m;
    Some((d - axis.direction.into_inner() * d.dot(&axis.direction)).norm() * 1e3)
}

/// Coordinates and commands whose units look wrong (module docs), judged over the revolute axis
/// experiments' target 0.
pub fn measurement_slips(set: &MeasurementSet, desc: &RobotDescription) -> Vec<UnitSlip> {
    let (mut scale, mut angle) = (Vec::new(), Vec::new());
    for e in set.experiments().iter().filter(|e| e.moved_joint > 0) {
        let joint = e.moved_joint;
        if desc.joints.get(joint - 1).is_none_or(|j| j.kind != JointKind::Revolute) {
            continue;
        }
        let by_step = e.by_step_target();
        let rows: Vec<&Measurement> = by_step.iter().filter(|((_, t), _)| *t == 0).map(|(_, m)| *m).collect();
        let nominal = nominal_radius_mm(desc, joint, rows[0]).filter(|r| *r > 1.0);
        let points: Vec<Point3<f64>> = rows.iter().map(|r| Point3::from(r.position_mm)).collect();
        if let Some(r) = nominal
            && expected_sagitta_mm(r, &rows, joint - 1) < MIN_JUDGED_SAGITTA_MM
            && crate::numerics::stats::rms_spread(&points) < MIN_JUDGED_SAGITTA_MM
        {
            // Too short an arc to judge, by its commands and by its points (commands in radians
            // draw a wide arc of points; coordinates in metres come with commands of a wide
            // one): its radius and angle would be the noise's.
            continue;
        }
        let Some((radius, turn_ratio)) = arc_of(&rows, joint - 1) else {
            continue;
        };
        if let Some(nominal) = nominal {
            scale.push((
                radius / nominal,
                format!(
                    "{}: target 0 turns on a radius of {radius:.4} where the description gives {nominal:.1} mm",
                    e.name
                ),
            ));
        }
        angle.push((turn_ratio, joint, e.name.to_string()));
    }
    let mut slips = Vec::new();
    let ratio = median(scale.iter().map(|s| s.0).collect());
    if slipped(ratio)
        && let Some((_, example)) = scale
            .iter()
            .min_by(|a, b| (a.0 - ratio).abs().total_cmp(&(b.0 - ratio).abs()))
    {
        slips.push(UnitSlip {
            field: "x_mm,y_mm,z_mm".into(),
            message: format!(
                "the measured arcs are {ratio:.4} times the size the description gives them ({example}): the \
                 coordinates look like {} rather than millimetres",
                likely(ratio)
            ),
        });
    }
    // One experiment in other units among consistent ones: the median above misses it.
    if !slipped(ratio) {
        for (r, example) in scale.iter().filter(|s| slipped(s.0)) {
            slips.push(UnitSlip {
                field: "x_mm,y_mm,z_mm".into(),
                message: format!(
                    "{example}, {r:.4} times, where the file's other arcs match the description: this \
                     experiment's coordinates look like {} rather than millimetres",
                    likely(*r)
                ),
            });
        }
    }
    let bad: Vec<&(f64, usize, String)> = angle.iter().filter(|a| slipped(a.0)).collect();
    if let (Some(lo), Some(hi)) = (
        bad.iter().map(|a| a.0).min_by(f64::total_cmp),
        bad.iter().map(|a| a.0).max_by(f64::total_cmp),
    ) {
        let columns: Vec<String> = bad.iter().map(|a| format!("cmd_{}", a.1)).collect();
        let experiments: Vec<&str> = bad.iter().map(|a| a.2.as_str()).collect();
        let times = if bad.len() == 1 {
            format!("{lo:.3}")
        } else {
            format!("{lo:.3} to {hi:.3}")
        };
        slips.push(UnitSlip {
            field: columns.join(","),
            message: format!(
                "the targets turn {times} times the commanded span read as degrees ({}): the commands look like {} \
                 rather than degrees",
                experiments.join(", "),
                likely(median(bad.iter().map(|a| a.0).collect()))
            ),
        });
    }
    slips
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_circle_through_three_points_has_its_radius_and_angle() {
        let on = |t: f64| Point3::new(1.0 + 2.0 * t.cos(), -3.0, 0.5 + 2.0 * t.sin());
        let (r, a) = circle_through(&on(0.1), &on(0.5), &on(1.2)).unwrap();
        assert!((r - 2.0).abs() < 1e-12 && (a - 1.1).abs() < 1e-12, "{r} {a}");
        assert!(circle_through(&on(0.1), &on(0.1), &on(0.2)).is_none());
    }

    #[test]
    fn the_likely_unit_is_the_nearest_known_factor() {
        assert_eq!(likely(0.0011), "metres");
        assert_eq!(likely(57.0), "radians");
        assert_eq!(likely(0.04), "inches");
        assert!(!slipped(1.3) && !slipped(0.8) && slipped(1e-3) && slipped(57.3) && !slipped(f64::NAN));
    }
}
