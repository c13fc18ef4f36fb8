//! Warnings on a robot description that reads and converts but describes no robot: its `dh`
//! twists written in radians, every link length zero, an arm smaller than any arm (its lengths
//! in centimetres or inches) or targets far beyond its links. The description's refusals (row
//! lengths in millimetres, limits in radians) are [`super::unit_check::description_slips`]; these
//! are warnings, as a valid description may be unusual, and each names what to check.
//!
//! None fires on a shipped description (`tests/it/hostile_round4c.rs` checks every one).

use super::format_f64;
use super::unit_check::{UnitSlip, ZERO_LENGTH_M};
use crate::kinematics::{DhConvention, DhParams, JointKind, SourceChain};
use crate::robot::RobotDescription;
use nalgebra::{Point3, Vector3};
use std::f64::consts::PI;

/// A twist within this \[deg\] of 1.5708 or 3.1416 (pi/2, pi) is the radian form of 90 or
/// 180 deg: the twists of the genr-written tables are rounded to six decimals, a hand-written
/// one to four.
pub const RADIAN_TWIST_TOLERANCE_DEG: f64 = 0.01;

/// An arm of three or more revolute joints whose links add up to less than this \[mm\] is no
/// arm: the smallest industrial and desktop six-axis arms (Meca500, myCobot 280) have links of
/// 400-500 mm in all, the shipped ones 960-1310 mm; lengths in centimetres or inches give a
/// tenth or a 25th of that.
pub const MIN_ARM_LENGTH_MM: f64 = 150.0;

/// Targets (tool and axis targets) further from their links than this many times the whole
/// chain's length are on another scale than the links (`dh` lengths in centimetres or inches,
/// the targets in millimetres): the shipped descriptions' are within 1.4 times (a positioner's
/// table beside its short offsets), an arm's within a fifth.
pub const TARGET_OVER_CHAIN_FACTOR: f64 = 3.0;

/// The description's problems that are not refusals (module docs), each one field and one
/// sentence; `source` is the chain its geometry was converted from, as written (`dh` rows or a
/// URDF: [`RobotDescription::with_source`]), when known.
pub fn description_warnings(desc: &RobotDescription, source: Option<&SourceChain>) -> Vec<UnitSlip> {
    let dh = match source {
        Some(SourceChain::Dh { rows, .. }) => rows.as_slice(),
        _ => &[],
    };
    let fields = match source {
        Some(SourceChain::Dh { .. }) => "joints[].dh.d_mm,a_mm",
        Some(SourceChain::Urdf { .. }) => "urdf",
        None => "rows",
    };
    let written = Written { desc, dh, fields };
    let mut warnings: Vec<UnitSlip> = twists_in_radians(dh).into_iter().collect();
    warnings.extend(lone_radian_twists(written_twists(desc, dh, source.is_none())));
    if let Some(SourceChain::Dh { convention, rows, .. }) = source {
        warnings.extend(other_convention(*convention, rows));
    }
    warnings.extend(
        zero_lengths(&written)
            .or_else(|| arm_too_small(&written))
            .or_else(|| targets_beyond_chain(&written)),
    );
    warnings
}

/// A description with its `dh` rows as written (none when its geometry is a URDF or rows) and
/// the fields its lengths were written in.
struct Written<'a> {
    desc: &'a RobotDescription,
    dh: &'a [DhParams],
    fields: &'static str,
}

/// Every nonzero `dh` twist at most pi, one of them pi/2 or pi
/// ([`RADIAN_TWIST_TOLERANCE_DEG`]): radians in the degree field. A twist of 0 is legal
/// (parallel axes: a SCARA's, a UR's shoulder and elbow), so the zeros say nothing.
fn twists_in_radians(dh: &[DhParams]) -> Option<UnitSlip> {
    let twists: Vec<f64> = dh
        .iter()
        .map(|r| r.alpha_rad.to_degrees())
        .filter(|a| *a != 0.0)
        .collect();
    let radian_form = |a: f64| {
        [PI / 2.0, PI]
            .iter()
            .any(|r| (a.abs() - r).abs() <= RADIAN_TWIST_TOLERANCE_DEG)
    };
    let below_pi = twists.iter().all(|a| a.abs() <= PI + RADIAN_TWIST_TOLERANCE_DEG);
    (below_pi && twists.iter().any(|a| radian_form(*a))).then(|| {
        let shown = |v: &[f64]| v.iter().map(|a| format_f64(*a)).collect::<Vec<_>>().join(", ");
        let degrees: Vec<f64> = twists
            .iter()
            .map(|a| (a.to_degrees() * 100.0).round() / 100.0)
            .collect();
        UnitSlip {
            field: "joints[].dh.alpha_deg".into(),
            message: format!(
                "every nonzero twist ({}) is below pi: alpha_deg looks like radians ({} deg?); the description \
                 turns its axes by these few degrees",
                shown(&twists),
                shown(&degrees)
            ),
        }
    })
}

/// The twists as the file writes them, each with its field \[deg\]: the `dh` rows' `alpha_deg`,
/// or the rows' `alpha_deg` and `beta_deg` when the file writes `rows` (`as_rows`); none for a
/// URDF (its angles are radians by the format).
fn written_twists(desc: &RobotDescription, dh: &[DhParams], as_rows: bool) -> Vec<(String, f64)> {
    let mut twists: Vec<(String, f64)> = dh
        .iter()
        .enumerate()
        .map(|(k, r)| (format!("joints[{k}].dh.alpha_deg"), r.alpha_rad.to_degrees()))
        .collect();
    if as_rows {
        for (i, r) in desc.rows.iter().enumerate() {
            twists.push((format!("rows[{i}].alpha_deg"), r.alpha_deg));
            twists.push((format!("rows[{i}].beta_deg"), r.beta_deg));
        }
    }
    twists
}

/// A twist of `twists` in the radian form of 90 or 180 deg ([`RADIAN_TWIST_TOLERANCE_DEG`])
/// where another twist of the file is plainly in degrees (beyond pi): one value written in
/// radians among degrees, which turns its axis by a degree and a half (or three). Every twist
/// in radians is [`twists_in_radians`]'s.
fn lone_radian_twists(twists: Vec<(String, f64)>) -> Vec<UnitSlip> {
    let in_degrees: Vec<&(String, f64)> = twists
        .iter()
        .filter(|(_, a)| a.abs() > PI + RADIAN_TWIST_TOLERANCE_DEG)
        .collect();
    let Some((other, other_deg)) = in_degrees.first() else {
        return Vec::new();
    };
    twists
        .iter()
        .filter_map(|(field, a)| {
            let radians = [PI / 2.0, PI]
                .into_iter()
                .find(|r| (a.abs() - r).abs() <= RADIAN_TWIST_TOLERANCE_DEG)?;
            let meant = a.signum() * radians.to_degrees();
            Some(UnitSlip {
                field: field.clone(),
                message: format!(
                    "{} deg is the radian form of {} deg, where the file's other twists are in degrees (`{other}` {}): \
                     the description turns this axis by {} deg; write {}",
                    format_f64(*a),
                    format_f64(meant),
                    format_f64(*other_deg),
                    format_f64(*a),
                    format_f64(meant)
                ),
            })
        })
        .collect()
}

/// A `dh` table whose twists are laid out as the other convention lays them out: a classic
/// table gives the last frame the last joint's axis (the last twist 0, the flange turning with
/// it) and twists the first row off the base's z; a modified one gives the base frame the first
/// joint's axis (the first twist 0) and twists the last row. Said on a table with a twist of 0 at
/// one end and not at the other, the ends the declared `dh_convention` does not fix. Every
/// shipped DH description passes (a SCARA's twists are 0 at both ends).
fn other_convention(convention: DhConvention, rows: &[DhParams]) -> Option<UnitSlip> {
    let (first, last) = (rows.first()?.alpha_rad, rows.last()?.alpha_rad);
    let zero = |a: f64| a.to_degrees().abs() < RADIAN_TWIST_TOLERANCE_DEG;
    let (declared, laid_out) = match convention {
        DhConvention::Modified if !zero(first) && zero(last) => ("modified", "classic"),
        DhConvention::Classic if zero(first) && !zero(last) => ("classic", "modified"),
        _ => return None,
    };
    Some(UnitSlip {
        field: "dh_convention".into(),
        message: format!(
            "\"{declared}\", but the twists are laid out as a {laid_out} table's (the first row's alpha_deg {}, the last \
             row's {}: a {laid_out} table twists its {} row and not its {} one); read as {declared}, the description is \
             another robot: check the convention of the table's source",
            format_f64(first.to_degrees()),
            format_f64(last.to_degrees()),
            if laid_out == "classic" { "first" } else { "last" },
            if laid_out == "classic" { "last" } else { "first" },
        ),
    })
}

/// The revolute joints of `desc`.
fn revolute(desc: &RobotDescription) -> usize {
    desc.joints.iter().filter(|j| j.kind == JointKind::Revolute).count()
}

/// Whether every revolute axis of `desc` at its zero pose is parallel to the first (a stack of
/// coaxial turntables: every row length 0 is then its geometry, not lengths left out).
fn revolute_axes_parallel(desc: &RobotDescription) -> bool {
    let model = desc.nominal_model();
    let poses = model.poses(&vec![0.0; model.dof()]);
    let mut directions = (0..model.dof())
        .filter(|&k| desc.joints[k].kind == JointKind::Revolute)
        .map(|k| poses.axis(k).direction.into_inner());
    let Some(first) = directions.next() else {
        return true;
    };
    directions.all(|d| d.cross(&first).norm() < PARALLEL_SINE)
}

/// Two axes whose directions' cross product is below this (the sine of the angle between
/// them) are parallel: a converted chain's rounding is 1e-15, a drawn twist a degree or more.
const PARALLEL_SINE: f64 = 1e-9;

/// Every row length zero while two or more joints turn, not all about one line: every revolute
/// axis through one point, as a gimbal's and no arm's or positioner's; or all about one line in
/// a chain with prismatic joints too (a SCARA's columns left out: only a stack of turntables,
/// every joint revolute, turns coaxially by design). When the `dh` table has lengths, its convention
/// is what put them there (a classic table read as modified moves each offset to the joint
/// before, where it may fall along an axis).
fn zero_lengths(w: &Written<'_>) -> Option<UnitSlip> {
    let desc = w.desc;
    let zero = desc
        .rows
        .iter()
        .flat_map(|r| [r.a_m, r.b_m, r.h_m])
        .all(|v| v.abs() < ZERO_LENGTH_M);
    if !zero || desc.rows.is_empty() || revolute(desc) < 2 {
        return None;
    }
    let prismatic = desc.dof() - revolute(desc);
    let through_one_point = if !revolute_axes_parallel(desc) {
        format!(
            "the {} revolute axes all pass through one point, as a gimbal's do and no arm's or positioner's",
            revolute(desc)
        )
    } else if prismatic > 0 {
        format!(
            "the {} revolute axes are one line, so their turns add up as one joint's (a stack of turntables \
             alone is built so, not a chain with {prismatic} prismatic joint(s) such as a SCARA)",
            revolute(desc)
        )
    } else {
        return None;
    };
    if w.dh.iter().any(|r| r.d_m != 0.0 || r.a_m != 0.0) {
        return Some(UnitSlip {
            field: "dh_convention".into(),
            message: format!(
                "read in this convention the `dh` lengths leave every link length 0: {through_one_point}; is the \
                 table in the other convention (classic or modified)?"
            ),
        });
    }
    Some(UnitSlip {
        field: w.fields.into(),
        message: format!("every link length is 0: {through_one_point}; the description's lengths are missing"),
    })
}

/// The length of the chain \[mm\] as written: its `dh` rows' offsets (`d_mm`, `a_mm`) added,
/// else the converted links' offsets from one joint frame to the next and the tool frame's (a
/// converted table puts its last row's offset there).
fn chain_length_mm(w: &Written<'_>) -> f64 {
    if !w.dh.is_empty() {
        return w.dh.iter().map(|r| r.d_m.hypot(r.a_m)).sum::<f64>() * 1e3;
    }
    let model = w.desc.nominal_model();
    let links: f64 = (0..model.dof().saturating_sub(1))
        .map(|k| model.link_from_next_frame(k).translation.vector.norm())
        .sum();
    (links + model.last_link_from_tool.translation.vector.norm()) * 1e3
}

/// The lengths that a description in centimetres or inches would have in millimetres.
fn as_cm_or_inches(length_mm: f64) -> String {
    format!(
        "lengths in centimetres ({} mm) or inches ({} mm)?",
        format_f64((length_mm * 10.0).round()),
        format_f64((length_mm * 25.4).round())
    )
}

/// An arm (three or more revolute joints) shorter than [`MIN_ARM_LENGTH_MM`].
fn arm_too_small(w: &Written<'_>) -> Option<UnitSlip> {
    let (desc, length_mm) = (w.desc, chain_length_mm(w));
    (revolute(desc) >= 3 && length_mm > 0.0 && length_mm < MIN_ARM_LENGTH_MM).then(|| UnitSlip {
        field: w.fields.into(),
        message: format!(
            "the arm's links add up to {} mm, less than any arm of {} revolute joints ({MIN_ARM_LENGTH_MM} mm): {}",
            format_f64((length_mm * 10.0).round() / 10.0),
            revolute(desc),
            as_cm_or_inches(length_mm)
        ),
    })
}

/// The farthest tool or axis target from its link \[mm\], and its field.
fn farthest_target_mm(desc: &RobotDescription) -> Option<(String, f64)> {
    let tool = desc.nominal_model().last_link_from_tool;
    let mut points: Vec<(String, f64)> = desc
        .tool
        .targets_mm
        .iter()
        .enumerate()
        .map(|(k, t)| {
            (
                format!("tool.targets_mm[{k}]"),
                (tool * Point3::from(*t) * 1e-3).coords.norm() * 1e3,
            )
        })
        .collect();
    for (k, a) in desc.axis_targets.iter().enumerate() {
        points.push((
            format!("axis_targets[{k}].target0.position_mm"),
            Vector3::from(a.target0.position_mm).norm(),
        ));
    }
    points.into_iter().max_by(|a, b| a.1.total_cmp(&b.1))
}

/// Targets further from their links than [`TARGET_OVER_CHAIN_FACTOR`] times the chain's length.
fn targets_beyond_chain(w: &Written<'_>) -> Option<UnitSlip> {
    let length_mm = chain_length_mm(w);
    let (field, target_mm) = farthest_target_mm(w.desc)?;
    (length_mm > ZERO_LENGTH_M * 1e3 && target_mm > TARGET_OVER_CHAIN_FACTOR * length_mm).then(|| UnitSlip {
        field: w.fields.into(),
        message: format!(
            "the links add up to {} mm, but `{field}` sits {} mm from its link, {:.1} times as far: {}",
            format_f64((length_mm * 10.0).round() / 10.0),
            format_f64(target_mm.round()),
            target_mm / length_mm,
            as_cm_or_inches(length_mm)
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 6R arm's classic twists read as modified, or its modified ones as classic: said; each
    /// under its own convention, and a SCARA's (0 at both ends) under either: not.
    #[test]
    fn a_table_laid_out_in_the_other_convention_is_said() {
        let classic = rows(&[-90.0, 0.0, -90.0, 90.0, -90.0, 0.0]);
        let modified = rows(&[0.0, -90.0, 0.0, -90.0, 90.0, -90.0]);
        let scara = rows(&[0.0, 180.0, 0.0, 0.0]);
        let said = other_convention(DhConvention::Modified, &classic).expect("classic read as modified");
        assert!(
            said.message.contains("laid out as a classic table's"),
            "{}",
            said.message
        );
        assert!(other_convention(DhConvention::Classic, &modified).is_some());
        assert_eq!(other_convention(DhConvention::Classic, &classic), None);
        assert_eq!(other_convention(DhConvention::Modified, &modified), None);
        for convention in [DhConvention::Classic, DhConvention::Modified] {
            assert_eq!(other_convention(convention, &scara), None);
        }
    }

    fn rows(twists_deg: &[f64]) -> Vec<DhParams> {
        twists_deg
            .iter()
            .map(|a| DhParams {
                d_m: 0.1,
                theta_rad: 0.0,
                a_m: 0.2,
                alpha_rad: a.to_radians(),
            })
            .collect()
    }

    #[test]
    fn twists_in_radians_are_said_and_degrees_or_small_misalignments_are_not() {
        let said = twists_in_radians(&rows(&[0.0, PI / 2.0, -PI / 2.0, 0.0])).expect("radians");
        assert!(said.message.contains("(90, -90 deg?)"), "{}", said.message);
        assert!(twists_in_radians(&rows(&[PI, 0.0])).is_some());
        // Degrees, parallel axes, and a calibrated table's small twists of parallel axes.
        assert_eq!(twists_in_radians(&rows(&[90.0, 0.0, -90.0])), None);
        assert_eq!(twists_in_radians(&rows(&[0.0, 0.0])), None);
        assert_eq!(twists_in_radians(&rows(&[0.12, 180.0, 0.03])), None);
        // One twist in radians among degrees: that one, by its field; degrees alone: none.
        let field = |k: usize, deg: f64| (format!("rows[{k}].alpha_deg"), deg);
        // Radians as a hand-written file rounds them, to four decimals.
        let written = |r: f64| (r * 1e4).round() / 1e4;
        let (half, whole) = (written(PI / 2.0), written(PI));
        let lone = lone_radian_twists(vec![field(0, 90.0), field(1, -half), field(2, 0.0), field(3, whole)]);
        let fields: Vec<&str> = lone.iter().map(|s| s.field.as_str()).collect();
        assert_eq!(fields, ["rows[1].alpha_deg", "rows[3].alpha_deg"]);
        assert!(
            lone[0].message.contains("radian form of -90 deg"),
            "{}",
            lone[0].message
        );
        assert!(lone_radian_twists(vec![field(0, 90.0), field(1, -90.0), field(2, 1.2)]).is_empty());
        assert!(lone_radian_twists(vec![field(0, half), field(1, 0.0)]).is_empty());
        assert_eq!(twists_in_radians(&rows(&[0.12, -0.4])), None);
    }
}
