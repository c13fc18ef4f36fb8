//! A command column of one axis experiment scaled (doubled, halved), and a command
//! column offset by a constant (another zero reference): slips a joint's transmission or the
//! arm's configuration would absorb into a wrong model without a word.
//!
//! - **Scaled.** A revolute transmission turns its joint by its command within per cent (its
//!   harmonics are a few mrad, [`MAX_TRANSMISSION_SLOPE_DEVIATION`]). The angle target 0 turns
//!   per commanded degree ([`turn_slope`]: its angle about the arc's centre against the command,
//!   by least squares) over the same slope of the description's nominal robot at the same
//!   commands (its couplings and the held joints' compensation turn the target too): a ratio
//!   near 0.5 or 2, beyond that deviation and the noise ([`SIGMAS`] times its sigma), is that
//!   experiment's `cmd_k` doubled or halved. Gradians (a ratio of 0.9) are not told from a
//!   transmission's harmonics over a sweep of tens of degrees here, on the raw points; a factor
//!   within the band (a whole column scaled by a few per cent, gradians) is judged after the fit,
//!   on the fitted transmission's slope against what a gear train gives (`calibrate`'s checks of
//!   the result, `docs/method.md#checks-of-the-result`).
//! - **Offset.** The radius each experiment's target turns on depends on the joints after the
//!   moved one; an offset `d` of one command column changes every such radius. When the
//!   measured radii miss the description's at the commands as read (beyond
//!   [`super::SPREAD_WARNING`]) and one column shifted by a quarter or half turn
//!   ([`OFFSETS_DEG`]) makes every radius match, that column is offset, not the coordinates
//!   scaled.

use super::arcs::ExperimentArc;
use super::{SPREAD_WARNING, UnitSlip};
use crate::kinematics::{JointKind, PhiModel};
use crate::measurement::{Measurement, format_f64};
use crate::robot::{Controller, LinkTarget, RobotDescription, RobotModel, commands_to_internal};
use nalgebra::{Point3, Vector3};

/// The most a revolute transmission's mean slope over a sweep differs from 1 before a factor
/// of [`COMMAND_FACTORS`] is said: its slope is `1 + sum_k k (s_k cos kx - c_k sin kx)`, whose
/// mean over a sweep of tens of degrees keeps much of its harmonics' size (the simulated paper
/// robot's joint 6 turns its target up to 11 % less than described over its 50 deg sweep);
/// a quarter leaves room for that. A doubled or halved column is 100 % or 50 % off; the gradian
/// slip (11 %) is within what harmonics give and is not said.
pub const MAX_TRANSMISSION_SLOPE_DEVIATION: f64 = 0.25;

/// A turn ratio this many of its sigmas from 1 is beyond the noise: a normal deviate beyond 5
/// has a chance of 6e-7, none in the thousands of experiments a study checks.
pub const SIGMAS: f64 = 5.0;

/// Factors a command column of one experiment may be scaled by, as the ratio of the turned
/// angle to the commanded span read as degrees they give, and in words.
const COMMAND_FACTORS: [(f64, &str); 2] = [
    (0.5, "doubled (2 times the degrees)"),
    (2.0, "halved (0.5 times the degrees)"),
];

/// The angle \[deg\] the points of `rows` (one target, in step order) turn about their arc's
/// centre per degree of command `k` (0-based), and its 1-sigma from the fit's residuals: the
/// least-squares slope of the unwrapped angles against the commands. `None` with fewer than 4
/// points or no arc.
pub(super) fn turn_slope(rows: &[Measurement], k: usize) -> Option<(f64, f64)> {
    // In the order of the commands, which the angles are unwrapped along.
    let rows = super::arcs::in_command_order(&rows.iter().collect::<Vec<_>>(), k);
    let centre = super::arcs::arc_of(&rows, k)?.centre;
    let points: Vec<Point3<f64>> = rows.iter().map(|r| Point3::from(r.position_mm)).collect();
    if points.len() < 4 {
        return None;
    }
    // The plane's normal from the widest triple, which the points then turn about.
    let (a, b, c) = (points[0], points[points.len() / 2], points[points.len() - 1]);
    let normal = (b - a).cross(&(c - a)).try_normalize(0.0)?;
    let e1: Vector3<f64> = {
        let d = a - centre;
        (d - normal * d.dot(&normal)).try_normalize(0.0)?
    };
    let e2 = normal.cross(&e1);
    let mut angles: Vec<f64> = Vec::with_capacity(points.len());
    for p in &points {
        let d = p - centre;
        let mut angle = d.dot(&e2).atan2(d.dot(&e1)).to_degrees();
        if let Some(last) = angles.last() {
            angle += 360.0 * ((last - angle) / 360.0).round();
        }
        angles.push(angle);
    }
    let commands: Vec<f64> = rows.iter().map(|r| r.cmd[k]).collect();
    let n = commands.len() as f64;
    let (mx, my) = (commands.iter().sum::<f64>() / n, angles.iter().sum::<f64>() / n);
    let sxx: f64 = commands.iter().map(|x| (x - mx).powi(2)).sum();
    let sxy: f64 = commands.iter().zip(&angles).map(|(x, y)| (x - mx) * (y - my)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let slope = sxy / sxx;
    let residual: f64 = commands
        .iter()
        .zip(&angles)
        .map(|(x, y)| (y - my - slope * (x - mx)).powi(2))
        .sum();
    Some((slope.abs(), (residual / (n - 2.0) / sxx).sqrt()))
}

/// `rows` with each point where the description's nominal robot (`ideal`, its controller
/// applying the couplings) puts `target` at the row's commands.
fn nominal_rows(
    desc: &RobotDescription,
    ideal: &RobotModel,
    controller: &Controller,
    rows: &[Measurement],
    target: LinkTarget,
) -> Option<Vec<Measurement>> {
    let model = ideal.phi_model();
    rows.iter()
        .map(|m| {
            let internal = commands_to_internal(desc, &m.cmd);
            let q = ideal.joint_values(controller, &internal).unwrap_or(internal);
            let p = model.poses(&q).world_from_link.get(target.link - 1)? * target.position_m();
            let mut m = m.clone();
            m.position_mm = (p.coords * 1e3).into();
            Some(m)
        })
        .collect()
}

/// [`turn_slope`] of `rows` as the description's nominal robot (`ideal`, its controller
/// applying the couplings) puts target 0 of joint `joint` (1-based) at their commands.
pub(super) fn nominal_turn_slope(
    desc: &RobotDescription,
    ideal: &RobotModel,
    controller: &Controller,
    rows: &[Measurement],
    joint: usize,
) -> Option<f64> {
    let target = desc.axis_targets_of(joint)?.target0;
    turn_slope(&nominal_rows(desc, ideal, controller, rows, target)?, joint - 1).map(|(slope, _)| slope)
}

/// Whether two radii or two turn slopes agree within [`SPREAD_WARNING`]: a robot within its
/// drawing's tolerances differs from its description by per cent, a slip by a factor.
fn agree(a: f64, b: f64) -> bool {
    (a / b).ln().abs() <= SPREAD_WARNING.ln()
}

/// The points labelled target 0 of experiment `a`, which miss the description's target 0 (in
/// radius or in turn), drawing the arc the description's target 1 of the joint (the coupled
/// link's) draws at the same commands, in radius and in turn: the rows' target ids 0 and 1
/// exchanged (the `target` column, or a wide table's marker columns in another order).
fn swapped_targets(
    desc: &RobotDescription,
    ideal: &RobotModel,
    controller: &Controller,
    a: &ExperimentArc,
) -> Option<UnitSlip> {
    let other = desc.axis_targets_of(a.joint)?.target1?;
    let nominal = nominal_rows(desc, ideal, controller, &a.rows, other)?;
    let arc = super::arcs::arc_of(&nominal.iter().collect::<Vec<_>>(), a.joint - 1)?;
    let (turn, _) = turn_slope(&nominal, a.joint - 1)?;
    let (measured, _) = a.turn?;
    (agree(a.arc.radius, arc.radius) && agree(measured, turn)).then(|| UnitSlip {
        field: "target".into(),
        message: format!(
            "experiment {}: the points labelled target 0 turn on a radius of {:.1} mm, {:.4} times as far per degree \
             of cmd_{} as the description's target 0 (radius {:.1} mm), as its target 1 does (radius {:.1} mm, on \
             link {}): the rows' target ids 0 and 1 look exchanged; check the `target` column (or the marker columns \
             of a wide table), not the units",
            a.name,
            a.arc.radius,
            a.nominal_turn.map_or(f64::NAN, |n| measured / n),
            a.joint,
            a.nominal_mm.unwrap_or(f64::NAN),
            arc.radius,
            other.link
        ),
    })
}

/// The experiments whose revolute commands look scaled by one of [`COMMAND_FACTORS`] (module
/// docs), or whose target ids 0 and 1 look exchanged ([`swapped_targets`]). A ratio beyond
/// [`super::SLIP_FACTOR`] is a unit slip said elsewhere. A factor is named only when applying it
/// makes the points fit the joint's arc: they lie on a circle of the description's radius
/// (within [`SPREAD_WARNING`]) and travel along it the factor times as far as the commands say;
/// points on a circle of another radius (noise far above an instrument's pulling the arc's
/// centre, another target's points) turn another angle per degree whatever the commands hold.
pub(super) fn scaled_commands(desc: &RobotDescription, arcs: &[&ExperimentArc]) -> Vec<UnitSlip> {
    let ideal = RobotModel::ideal(desc);
    let controller = Controller::from_description(desc);
    let mut slips = Vec::new();
    for a in arcs {
        let (Some((measured, sigma)), Some(nominal)) = (a.turn, a.nominal_turn) else {
            continue;
        };
        let (ratio, sigma) = (measured / nominal, sigma / nominal);
        let band = (1.0 + MAX_TRANSMISSION_SLOPE_DEVIATION).ln();
        let allowed = band + SIGMAS * sigma / ratio;
        if super::slipped(ratio) || !ratio.is_finite() {
            continue;
        }
        let on_its_circle = a.nominal_mm.is_none_or(|n| agree(a.arc.radius, n));
        if (!on_its_circle || ratio.ln().abs() > allowed)
            && let Some(swap) = swapped_targets(desc, &ideal, &controller, a)
        {
            slips.push(swap);
            continue;
        }
        // A ratio known less well than the band cannot tell one factor from a transmission's
        // deviation (points off their arc: outliers, noise the calibration's screens name).
        if !on_its_circle || ratio.ln().abs() <= allowed || SIGMAS * sigma / ratio > band {
            continue;
        }
        let Some((_, words)) = COMMAND_FACTORS
            .iter()
            .map(|(f, words)| ((f.ln() - ratio.ln()).abs(), *words))
            .filter(|(d, _)| *d <= allowed)
            .min_by(|a, b| a.0.total_cmp(&b.0))
        else {
            continue;
        };
        let joint = a.joint;
        slips.push(UnitSlip {
            field: format!("cmd_{joint}"),
            message: format!(
                "experiment {}: its target turns {ratio:.4} (+-{sigma:.4}) times as far per degree of cmd_{joint} as the \
                 description's robot turns it at the same commands, on the circle the description gives it, where a \
                 transmission turns its joint within {} % of its command: this experiment's cmd_{joint} looks {words}; \
                 the fit would take the factor for joint {joint}'s transmission",
                a.name,
                MAX_TRANSMISSION_SLOPE_DEVIATION * 100.0
            ),
        });
    }
    slips
}

/// Whether experiment `a`'s points turn in step with its commands: the slope of their angles
/// against the commands ([`turn_slope`]) known within the transmission band
/// ([`MAX_TRANSMISSION_SLOPE_DEVIATION`], [`SIGMAS`] sigmas), as commands in any unit give it
/// (a unit scales the slope, not its scatter). Points in another order than their commands turn
/// at random against them. True when no slope is taken (too few points).
pub(super) fn turns_in_step(a: &ExperimentArc) -> bool {
    let band = (1.0 + MAX_TRANSMISSION_SLOPE_DEVIATION).ln();
    a.turn.is_none_or(|(slope, sigma)| SIGMAS * sigma / slope <= band)
}

/// Offsets \[deg\] tried on each revolute command column: a zero reference of another
/// convention is a quarter or a half turn away (a DH table's zero against the maker's); any
/// other offset is a joint's own, which the calibration fits as its zero offset.
const OFFSETS_DEG: [f64; 3] = [90.0, -90.0, 180.0];

/// Each of `arcs`' `|ln(measured / nominal)|` radius ratio and what of it lies beyond the
/// noise (less [`super::RADIUS_SIGMAS`] of the radius's relative standard error, the larger of
/// its triples' scatter's and the assumed noise's), with the commands of column `column`
/// (0-based) shifted by `offset_deg` before the nominal radius is taken. A radius from one
/// triple over a short arc is off by a quarter at the noise alone: five points over 30
/// degrees, 246 mm from the axis, bow 2.1 mm, and 0.2 mm of noise moves that radius by 11 %.
/// Arcs whose radius the noise leaves uncertain by a third or more are left out: coordinates
/// in metres bow a thousandth of the noise the test assumes in millimetres, and no such arc
/// may excuse a column's offset.
fn mismatches(
    model: &PhiModel,
    desc: &RobotDescription,
    arcs: &[ExperimentArc],
    shift: (usize, f64),
) -> Vec<(f64, f64)> {
    let sigma = |a: &ExperimentArc| a.arc.radius_sigma.max(a.arc.noise_radius_sigma) / a.arc.radius;
    arcs.iter()
        .filter(|a| a.nominal_mm.is_some() && super::RADIUS_SIGMAS * sigma(a) < 1.0)
        .map(|a| {
            let mut cmd = a.first_cmd.clone();
            cmd[shift.0] += shift.1;
            let nominal = super::arcs::nominal_radius_with(model, desc, a.joint, &commands_to_internal(desc, &cmd));
            nominal.map_or((f64::INFINITY, f64::INFINITY), |n| {
                let ratio = (a.arc.radius / n).ln().abs();
                (ratio, (ratio - super::RADIUS_SIGMAS * sigma(a)).max(0.0))
            })
        })
        .collect()
}

/// The largest of [`mismatches`]' parts beyond the noise.
fn worst_mismatch(model: &PhiModel, desc: &RobotDescription, arcs: &[ExperimentArc], shift: (usize, f64)) -> f64 {
    mismatches(model, desc, arcs, shift)
        .iter()
        .map(|m| m.1)
        .fold(0.0, f64::max)
}

/// A revolute command column offset by a constant (module docs), when the measured radii miss
/// the description's at the commands as read and one column's whole-degree offset makes every
/// one match; `None` otherwise.
pub(super) fn offset_command(desc: &RobotDescription, arcs: &[ExperimentArc]) -> Option<UnitSlip> {
    let tolerance = SPREAD_WARNING.ln();
    let model = desc.nominal_model();
    let as_read = worst_mismatch(&model, desc, arcs, (0, 0.0));
    let judged = mismatches(&model, desc, arcs, (0, 0.0));
    let as_read_ratio = judged.iter().map(|m| m.0).fold(0.0, f64::max);
    if as_read <= tolerance || judged.len() < 2 {
        return None;
    }
    let revolute = desc
        .joints
        .iter()
        .enumerate()
        .filter(|(_, j)| j.kind == JointKind::Revolute);
    // A quarter turn one way and the other can both match (a half turn of a joint whose axis
    // meets the previous one mirrors the arm): the one that leaves fewer commands outside the
    // joint's limits is the robot's.
    let outside = |c: usize, d: f64| {
        let [lo, hi] = desc.joints[c].limits;
        arcs.iter()
            .flat_map(|a| a.rows.iter())
            .filter(|m| !(lo..=hi).contains(&(m.cmd[c] + d)))
            .count()
    };
    let (column, offset, _) = revolute
        .flat_map(|(c, _)| OFFSETS_DEG.map(move |d| (c, d)))
        .map(|(c, d)| (c, d, worst_mismatch(&model, desc, arcs, (c, d))))
        .filter(|(_, _, worst)| *worst <= tolerance)
        .min_by(|a, b| outside(a.0, a.1).cmp(&outside(b.0, b.1)).then(a.2.total_cmp(&b.2)))?;
    Some(UnitSlip {
        field: format!("cmd_{}", column + 1),
        message: format!(
            "the experiments' targets turn on radii up to {:.3} times off the description's at the commands as \
             read, and all within {:.0} % of them with cmd_{} {} {} deg: cmd_{} looks offset by {} deg (another \
             zero reference), not the coordinates scaled",
            as_read_ratio.exp(),
            (SPREAD_WARNING - 1.0) * 100.0,
            column + 1,
            if offset > 0.0 { "plus" } else { "minus" },
            format_f64(offset.abs()),
            column + 1,
            format_f64(-offset),
        ),
    })
}
