//! Sweeps that see one target at the reference pose (`calibrate`): every axis experiment holds
//! the other joints at the common reference pose and passes through it where its own joint is
//! at its held value, so two sweeps whose target 0 the description places at the same point of
//! the same link (a target every sweep reads on the last link, as most campaigns place it), and
//! the tool observation of a tool target at that point, all see one point there. A sweep whose
//! block was moved (the instrument or the robot bumped, a re-setup) or whose coordinates were
//! scaled sees it elsewhere, and a calibration of the sweeps absorbs that into its axis (a moved
//! axis, a longer link): nothing else in the sweeps contradicts it.
//!
//! Each sweep's point at the reference pose is interpolated from its own points
//! (`Curve`: a circle in the command for a turning joint, with its turn per command
//! fitted; a line for a sliding one), with the variance its least squares give at the noise of
//! a point. Only the part across the sweep's motion is compared: a joint's zero, its backlash or
//! a transmission error move the point along the arc, not off it. The points of one target are
//! tested against their weighted consensus by a chi-square test at [`SHARED_TARGET_FALSE_ALARM`]
//! (each point's variance: the interpolation's at the noise of a point, plus what the joints
//! positioned once for it give at the description's repeatability, `held_variance_mm2`);
//! the sweep without which the others agree is named, with its offset, when that offset is
//! beyond [`GROSS_MISS_FACTOR`] times the test's bound for it: sag bending one sweep's arc moves
//! a sweep's point by tenths of a millimetre, a moved block by millimetres; a held joint's
//! backlash taken up on another side between the sweeps moves it by the band times the lever
//! arm (a millimetre for a milliradian at a metre): where the held joints, turned within the band
//! their own sweeps' first points show, explain the offset (`backlash`), the sweep is named for
//! that, not a moved block; a circle whose turn per command is beyond `SIZE_TOLERANCE` of the
//! description's, an alias its points do not tell apart, is sought within it. Where no sweep's
//! removal lets the others agree at the noise (a real robot whose effects scatter every sweep's
//! point: Boby & Klimchik's arm), each sweep is tested against the others' scatter instead
//! (`scattered_odd_one_out`, an F ratio). A description without `axis_targets` (SScanSS-2's
//! robots) has every sweep read the tool frame's origin; a sweep whose held joints stand, as
//! recorded, off the reference pose is moved to it by their motions, which their own sweeps
//! measure, and a sweep out of place by one held joint's motion is named for that joint's
//! recorded command (`held`); a noise-free file's points are as exact
//! as their printed decimals (`printed_step_mm`); where every sweep moves the point along one
//! direction (a planar robot) that direction is left out (`pseudo_inverse`). No model of the
//! robot: the data against themselves and the description's word that the targets are one. Not
//! reached (`docs/formats.md`): a move along a sweep's own motion, a sweep no other meets at the
//! reference pose, every row moved alike; [`block_reach`] says so in a file where a sweep is
//! compared with none or a 1 mm move across its motion would pass.

mod backlash;
mod held;
mod sighting;

pub use held::HeldSlip;
pub use sighting::SHARED_TARGET_FALSE_ALARM;

use super::procedure::{AxisExperiment, axis_experiments};
use crate::kinematics::JointKind;
use crate::measurement::MeasurementSet;
use crate::measurement::column_slips::GROSS_MISS_FACTOR;
use crate::numerics::stats::{chi_square_quantile, f_upper_quantile};
use crate::robot::{RobotDescription, commands_to_internal};
use nalgebra::{Matrix3, Point3, Vector3};
use sighting::{AT_REFERENCE, Curve, Sighting, Turning, noise_bound, variance};
use std::collections::BTreeMap;
use std::f64::consts::PI;

/// The sightings of each shared target (by [`key`]): its link and place \[mm\], and the sightings.
type Groups = BTreeMap<String, ((usize, [f64; 3]), Vec<Sighting>)>;

/// The tool observation's points of each tool target, the experiment and the first line.
type ToolPoints = BTreeMap<usize, (Vec<Vector3<f64>>, String, Option<u64>)>;

/// A sweep whose point at the reference pose contradicts the other sightings of its target.
#[derive(Clone, Debug, PartialEq)]
pub struct MovedSweep {
    /// The experiment.
    pub experiment: String,
    /// Its first and last lines.
    pub lines: Option<(u64, u64)>,
    /// Its offset from the others' consensus, across its motion \[mm\].
    pub offset_mm: [f64; 3],
    /// The offset over its standard deviation.
    pub sigmas: f64,
    /// The experiments it is compared with (when `ambiguous`: the ones that could be out of
    /// place instead).
    pub others: Vec<String>,
    /// The description's place of the target: link and position \[mm\].
    pub target: (usize, [f64; 3]),
    /// Whether another sighting could as well be the one out of place (two sightings only, or
    /// several sweeps without each of which the others agree): `others` then names those.
    pub ambiguous: bool,
    /// The held joints' turns \[rad\] within the backlash band their own sweeps' first points
    /// show that put the target where this sweep sees it (`(joint, turn)`); empty when no
    /// such turns explain it (then the block was moved).
    pub backlash: Vec<(usize, f64)>,
    /// The held joints whose recorded command, off where the robot stood by the offset given,
    /// puts the target where this sweep sees it (the smallest first; the `held` test); empty when none does or
    /// the held joints' backlash explains it.
    pub held: Vec<HeldSlip>,
}

impl std::fmt::Display for MovedSweep {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [x, y, z] = self.offset_mm;
        let lines = self.lines.map_or(String::new(), |(a, b)| format!(" (lines {a}-{b})"));
        let (link, place) = self.target;
        // The description's numbers, without a double's trailing digits.
        let [px, py, pz] = place.map(|v| (v * 1e3).round() / 1e3 + 0.0);
        let who = if self.ambiguous {
            format!(
                "experiment {}{lines} and {} disagree",
                self.experiment,
                self.others.join(", ")
            )
        } else {
            format!(
                "experiment {}{lines} is out of place among {}",
                self.experiment,
                self.others.join(", ")
            )
        };
        if !self.backlash.is_empty() {
            return self.fmt_backlash(f, &lines);
        }
        // A held slide's offset moves the point as a moved block does (a translation): named
        // beside the block, not for it; a held turn moves it about an axis (h15d).
        let slides = match self.held.first() {
            Some(h) if h.unit == "deg" => return self.fmt_held(f, &lines),
            Some(_) => self.held_slides(),
            None => String::new(),
        };
        write!(
            f,
            "{who}: at the reference pose (every joint at its held value), which each sweep passes through, its \
             target 0 (the description places it on link {link} at ({px}, {py}, {pz}) mm, as it does the others') \
             sits ({x:.2}, {y:.2}, {z:.2}) mm ({:.2} mm across its motion, {:.0} times the noise of that comparison) \
             from where the others see it: the block was moved (the instrument or the robot bumped or set up again between \
             the sweeps) or its coordinates shifted or scaled; the calibration absorbs it into the axis, so \
             calibration.json is wrong for the robot: check these rows and measure the sweep again (if the targets \
             are different ones, give each its own place in `axis_targets`; a held joint's backlash taken up on \
             another side between the sweeps moves a sweep too, by its band times the target's distance from that \
             joint, 0.9 mm for 1 mrad at 0.9 m: then approach the reference pose from one side before every sweep){slides}",
            Vector3::new(x, y, z).norm(),
            self.sigmas,
        )
    }
}

impl MovedSweep {
    /// The held joints (a slide first) whose recorded command, off where the robot stood, moves
    /// the point as the block moved does: a clause for the moved-block warning.
    fn held_slides(&self) -> String {
        let each: Vec<String> = self
            .held
            .iter()
            .map(|h| {
                format!(
                    "`cmd_{}` by {:+.3} {} (1-sigma {:.3})",
                    h.joint, h.offset, h.unit, h.sigma
                )
            })
            .collect();
        format!(
            "; a held joint's recorded command off where the robot stood moves it the same way ({}): check \
             those in these rows against the controller too",
            each.join(", or ")
        )
    }

    /// The warning for a sweep out of place by what a held joint's recorded command explains.
    fn fmt_held(&self, f: &mut std::fmt::Formatter<'_>, lines: &str) -> std::fmt::Result {
        let [x, y, z] = self.offset_mm;
        let slip = &self.held[0];
        let (j, unit) = (slip.joint, slip.unit);
        let or: Vec<String> = self.held[1..]
            .iter()
            .map(|h| format!(", or the held `cmd_{}` by {:+.3} {}", h.joint, h.offset, h.unit))
            .collect();
        let among = match self.ambiguous {
            true => format!("{} (either may be the one out of place)", self.others.join(", ")),
            false => self.others.join(", "),
        };
        write!(
            f,
            "experiment {}{lines}: the held `cmd_{j}` looks offset by {:+.3} {unit} (1-sigma {:.3}) from where the robot \
             stood{}: at \
             the reference pose its target 0 sits ({x:.2}, {y:.2}, {z:.2}) mm ({:.2} mm across its motion, {:.0} times the \
             noise of that comparison) from where {among} see it, where joint {j} turned by {:+.3} {unit} from its \
             recorded value (about the axis its own sweep gives) puts it: a value typed wrong for this experiment, or the \
             joint re-mastered between the sweeps; the calibration places the sweep's axis by the recorded value, so \
             calibration.json is wrong for the robot: check `cmd_{j}` in these rows against the controller, or measure \
             the sweep again",
            self.experiment,
            slip.offset,
            slip.sigma,
            or.concat(),
            Vector3::new(x, y, z).norm(),
            self.sigmas,
            -slip.offset,
        )
    }

    /// The note for a sweep out of place by what the held joints' backlash explains.
    fn fmt_backlash(&self, f: &mut std::fmt::Formatter<'_>, lines: &str) -> std::fmt::Result {
        let [x, y, z] = self.offset_mm;
        let turns: Vec<String> = self
            .backlash
            .iter()
            .map(|(j, t)| format!("joint {j} by {:.2} mrad", t * 1e3))
            .collect();
        write!(
            f,
            "experiment {}{lines} sees its target at the reference pose ({x:.2}, {y:.2}, {z:.2}) mm ({:.2} mm across its \
             motion, {:.0} times the noise of that comparison) from where {} see it, as the joints it holds turned \
             within the backlash their own sweeps' first points show would put it ({}, each about its own sweep's \
             axis): a held joint's backlash taken up on another side between the sweeps, not a moved block. \
             Approach the reference pose from one side before every sweep to keep the sweeps alike",
            self.experiment,
            Vector3::new(x, y, z).norm(),
            self.sigmas,
            self.others.join(", "),
            turns.join(", "),
        )
    }
}

/// The sweeps of `set` out of place among the sightings of their shared target (module docs),
/// with `noise_rms_3d_mm` the noise of a point; empty when the description shares no target.
pub fn moved_sweeps(set: &MeasurementSet, desc: &RobotDescription, noise_rms_3d_mm: f64) -> Vec<MovedSweep> {
    let Some(seen) = sightings(set, desc, noise_rms_3d_mm) else {
        return Vec::new();
    };
    let context = Context {
        desc,
        motions: &seen.motions,
        sigma2: seen.sigma2,
    };
    seen.groups
        .into_values()
        .filter_map(|(target, sightings)| odd_one_out(&sightings, &context, target))
        .collect()
}

/// What [`odd_one_out`] names a sweep by beside the sightings: the description, each joint's
/// motion ([`held::motions`]) and the variance of a point's coordinate \[mm²\].
struct Context<'a> {
    desc: &'a RobotDescription,
    motions: &'a [Option<held::Motion>],
    sigma2: f64,
}

/// The sightings of a file ([`sightings`]).
struct Seen {
    /// The axis experiments' names.
    names: Vec<String>,
    /// The sightings of each shared target.
    groups: Groups,
    /// The variance of a point's coordinate \[mm²\].
    sigma2: f64,
    /// Each joint's motion at the reference pose ([`held::motions`]).
    motions: Vec<Option<held::Motion>>,
}

/// The axis experiments' names, the sightings of each shared target, the variance of a
/// point's coordinate \[mm²\] at the noise `noise_rms_3d_mm` (at least the rounding of the
/// file's printed coordinates) and each joint's motion; `None` when the file has no axis
/// experiments.
fn sightings(set: &MeasurementSet, desc: &RobotDescription, noise_rms_3d_mm: f64) -> Option<Seen> {
    let (experiments, reference) = axis_experiments(set, desc).ok()?;
    let reach = reach_mm(desc);
    let motions = held::motions(&experiments, desc, &reference);
    let mut groups: Groups = BTreeMap::new();
    for e in &experiments {
        let Some((link, place)) = sweep_target(desc, e.joint) else {
            continue;
        };
        if let Some(s) = sweep_sighting(e, (desc, &motions), &reference, reach) {
            let entry = groups.entry(key(link, place)).or_insert(((link, place), Vec::new()));
            entry.1.push(s);
        }
    }
    for (target, s) in tool_sightings(set, desc, &reference, reach) {
        if let Some(entry) = groups.get_mut(&key(desc.dof(), target)) {
            entry.1.push(s);
        }
    }
    // A file without noise (SScanSS-2's two-link example) is still only as exact as its printed
    // coordinates: their rounding, uniform over one step, is the floor of a point's variance.
    let sigma2 = (noise_rms_3d_mm.powi(2) / 3.0).max(printed_step_mm(set).powi(2) / 12.0);
    Some(Seen {
        names: experiments.into_iter().map(|e| e.name).collect(),
        groups,
        sigma2,
        motions,
    })
}

/// The move of a sweep's block the test of the module docs is meant to name wherever the
/// sweeps share a target (1 mm across its motion): the bump of an instrument stand or a
/// tripod our hostile runs try, which costs a calibration several times its predicted error.
pub const BLOCK_REACH_CLAIM_MM: f64 = 1.0;

/// The moves of a sweep's block the test of the module docs lets pass in a file
/// ([`block_reach`]).
#[derive(Clone, Debug, PartialEq)]
pub struct BlockReach {
    /// The sweeps no other sighting meets at the reference pose (a target 0 of their own in
    /// `axis_targets`, or a sweep that does not pass through the reference pose): a move of
    /// their block passes whatever its size.
    pub alone: Vec<String>,
    /// The sweeps compared whose smallest move named across their motion is beyond
    /// [`BLOCK_REACH_CLAIM_MM`]: the experiment and that move \[mm\].
    pub across: Vec<(String, f64)>,
}

/// How large a move of a sweep's block the test of the module docs lets pass, where it is
/// beyond [`BLOCK_REACH_CLAIM_MM`] across some sweep's motion or a sweep is compared with none;
/// `None` where every sweep is compared and a 1 mm move across its motion is named. A sweep's
/// smallest move named: [`GROSS_MISS_FACTOR`] times the noise test's bound times its point's
/// standard deviation, times the root of its target's sightings' chi-square per degree of
/// freedom where they scatter beyond the noise (the scatter test's scale).
pub fn block_reach(set: &MeasurementSet, desc: &RobotDescription, noise_rms_3d_mm: f64) -> Option<BlockReach> {
    let Seen {
        names, groups, sigma2, ..
    } = sightings(set, desc, noise_rms_3d_mm)?;
    let mut compared: BTreeMap<String, f64> = BTreeMap::new();
    for (_, group) in groups.values().filter(|(_, g)| g.len() >= 2) {
        let all: Vec<&Sighting> = group.iter().collect();
        let Some((_, chi2, dof)) = consensus(&all, sigma2) else {
            continue;
        };
        let scatter = if dof > 0 { (chi2 / dof as f64).max(1.0) } else { 1.0 };
        for s in group.iter().filter(|s| s.across != Matrix3::identity()) {
            let smallest = GROSS_MISS_FACTOR * noise_bound(s) * (variance(s, sigma2) * scatter).sqrt();
            compared.insert(s.experiment.clone(), smallest);
        }
    }
    let reach = BlockReach {
        alone: names.iter().filter(|n| !compared.contains_key(*n)).cloned().collect(),
        across: names
            .iter()
            .filter_map(|n| compared.get(n).map(|r| (n.clone(), *r)))
            .filter(|(_, r)| *r > BLOCK_REACH_CLAIM_MM)
            .collect(),
    };
    (!reach.alone.is_empty() || !reach.across.is_empty()).then_some(reach)
}

impl std::fmt::Display for BlockReach {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut parts: Vec<String> = Vec::new();
        if !self.alone.is_empty() {
            parts.push(format!(
                "experiment {} not at all (no other sweep, nor the tool observation, sees its target 0 at the \
                 reference pose: the description gives it a place of its own in `axis_targets`, or the sweep does not \
                 pass through the reference pose)",
                self.alone.join(", ")
            ));
        }
        // Sweeps whose reach reads alike, together.
        let mut alike: Vec<(String, Vec<&str>)> = Vec::new();
        for (name, mm) in &self.across {
            let shown = format!("{mm:.1}");
            match alike.iter_mut().find(|(s, _)| *s == shown) {
                Some((_, names)) => names.push(name),
                None => alike.push((shown, vec![name])),
            }
        }
        parts.extend(alike.iter().map(|(mm, names)| {
            format!(
                "experiment {} only from about {mm} mm across its motion (its point's noise and scatter there)",
                names.join(", ")
            )
        }));
        write!(
            f,
            "the reference-pose test cannot name a sweep's block moved here (the instrument or the robot bumped \
             between sweeps): {}. It names a move of {BLOCK_REACH_CLAIM_MM:.0} mm across a sweep's motion where the \
             sweeps share a target; a move along a sweep's own motion at the reference pose reads as its joint's zero \
             and passes at any size. `validate` of a second file's sweeps against this calibration shows such a move",
            parts.join("; ")
        )
    }
}

/// The held turning joint's offset through one sweep the reference-pose test is meant to name
/// wherever that offset moves the sweep's point across its motion (1 deg; hostile runs write
/// 0.5 to 2 deg).
pub const HELD_REACH_CLAIM_DEG: f64 = 1.0;

/// Half a turn \[deg\]: an offset named only beyond it is named at no size.
const HALF_TURN_DEG: f64 = 180.0;

/// The held turning joints' recorded commands off through one sweep that the reference-pose
/// test lets pass in a file ([`held_reach`]): each is `(experiment, joint (1-based), smallest
/// offset named in deg)`, the offset `None` where the sweep is compared with no other, the
/// held joint has no sweep of its own (its motion unmeasured) or is held by this sweep only, or
/// the offset named is beyond half a turn: any size passes.
#[derive(Clone, Debug, PartialEq)]
pub struct HeldReach {
    /// The sweeps' held joints beyond [`HELD_REACH_CLAIM_DEG`].
    pub passing: Vec<(String, usize, Option<f64>)>,
}

/// The held turning joints whose recorded command off through one sweep by
/// [`HELD_REACH_CLAIM_DEG`] the reference-pose test lets pass, with the smallest offset it
/// names: the sweep's smallest move named across its motion (`block_reach`'s rule) over what a
/// degree of the held joint moves its point across that motion (the joint's motion at the
/// reference pose, as its own sweep measures it, `held::Motion`); `None` when every one is named.
pub fn held_reach(set: &MeasurementSet, desc: &RobotDescription, noise_rms_3d_mm: f64) -> Option<HeldReach> {
    let Seen {
        groups,
        sigma2,
        motions,
        ..
    } = sightings(set, desc, noise_rms_3d_mm)?;
    // A joint held by one sweep only has that sweep's value as its reference: nothing to compare.
    let holding = |j: usize| {
        groups
            .values()
            .flat_map(|g| &g.1)
            .filter(|s| s.held.contains(&j))
            .count()
    };
    let mut passing: Vec<(String, usize, Option<f64>)> = Vec::new();
    for (_, group) in groups.values() {
        let all: Vec<&Sighting> = group.iter().collect();
        let scatter = match consensus(&all, sigma2) {
            Some((_, chi2, dof)) if dof > 0 && group.len() >= 2 => Some((chi2 / dof as f64).max(1.0)),
            Some(_) if group.len() >= 2 => Some(1.0),
            _ => None,
        };
        for s in group.iter().filter(|s| s.joint > 0) {
            let smallest_mm = scatter.map(|c| GROSS_MISS_FACTOR * noise_bound(s) * (variance(s, sigma2) * c).sqrt());
            for &j in s.held.iter().filter(|&&j| desc.joints[j].kind == JointKind::Revolute) {
                let per_deg = motions[j]
                    .as_ref()
                    .map(|m| (s.across * m.velocity(s.point)).norm() * PI / 180.0);
                let deg = smallest_mm
                    .zip(per_deg)
                    .map(|(mm, v)| mm / v)
                    .filter(|d| *d <= HALF_TURN_DEG && holding(j) > 1);
                if deg.is_none_or(|d| d > HELD_REACH_CLAIM_DEG) {
                    passing.push((s.experiment.clone(), j + 1, deg));
                }
            }
        }
    }
    (!passing.is_empty()).then_some(HeldReach { passing })
}

impl std::fmt::Display for HeldReach {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // The held commands of one sweep whose reach reads alike, together.
        let mut alike: Vec<(String, String, Vec<String>)> = Vec::new();
        for (e, j, deg) in &self.passing {
            let reach = deg.map_or("at any size".to_string(), |d| format!("below about {d:.1} deg"));
            match alike.iter_mut().find(|(x, r, _)| x == e && *r == reach) {
                Some((_, _, joints)) => joints.push(format!("`cmd_{j}`")),
                None => alike.push((e.clone(), reach, vec![format!("`cmd_{j}`")])),
            }
        }
        let each: Vec<String> = alike
            .iter()
            .map(|(e, reach, joints)| format!("experiment {e}'s {} {reach}", joints.join(", ")))
            .collect();
        write!(
            f,
            "a held joint's recorded command off where the robot stood through one sweep passes the reference-pose \
             test unnamed here ({}), and the file has no validation poses, against which `calibrate` seeks one: such an \
             offset turns the sweep's arc about the held joint's axis and the sweep's axis fit takes it in (a joint \
             held by one sweep only takes that sweep's value as its reference). `validate` of a second file's sweeps \
             against this calibration shows it",
            each.join("; ")
        )
    }
}

/// The variance \[mm²\] a sighting's point gets from the robot's repeatability (the
/// description's `repeatability_sigma`): every joint but the swept one (`swept`, 0 for the tool
/// observation: none) is positioned once for the sighting, and its error moves the point by its
/// repeatability times its lever arm (a sliding joint's by its repeatability), which is at most
/// the robot's reach ([`reach_mm`]). An upper bound, so that a sweep of a robot with a stated
/// repeatability is not said out of place for it (the IRB/L6's moves its clean sweeps' points
/// by up to 1.4 mm, 23 times the measurement noise).
fn held_variance_mm2(desc: &RobotDescription, swept: usize, reach_mm: f64) -> f64 {
    desc.joints
        .iter()
        .enumerate()
        .filter(|(k, _)| k + 1 != swept)
        .map(|(_, j)| match j.kind {
            JointKind::Revolute => (j.repeatability_sigma * reach_mm).powi(2),
            JointKind::Prismatic => (j.repeatability_sigma * 1e3).powi(2),
        })
        .sum()
}

/// The robot's reach \[mm\]: its description's row lengths and its farthest tool target, a
/// bound on any joint's lever arm to a target.
fn reach_mm(desc: &RobotDescription) -> f64 {
    let rows_mm: f64 = desc
        .nominal_model()
        .rows
        .iter()
        .map(|r| (r.a_m.abs() + r.b_m.abs() + r.h_m.abs()) * 1e3)
        .sum();
    let targets_mm = desc
        .tool
        .targets_mm
        .iter()
        .map(|t| Vector3::from(*t).norm())
        .fold(0.0f64, f64::max);
    rows_mm + targets_mm
}

/// Where the description places sweep `joint`'s target 0: its `axis_targets` entry (link and
/// position \[mm\]); in a description without any (SScanSS-2's robots, whose sweeps each measure
/// the tool frame's origin, `docs/formats.md`), the tool frame's origin on the last link.
fn sweep_target(desc: &RobotDescription, joint: usize) -> Option<(usize, [f64; 3])> {
    if let Some(a) = desc.axis_targets_of(joint) {
        return Some((a.target0.link, a.target0.position_mm));
    }
    desc.axis_targets
        .is_empty()
        .then(|| (desc.dof(), desc.tool.frame.translation_mm))
}

/// Decimal places a coordinate is printed with at most: beyond them a double's digits are
/// not the file's.
const MAX_PRINTED_DECIMALS: i32 = 9;

/// The step \[mm\] of the finest printed coordinate of `set`: `10^-d` for the most decimal
/// places `d` any coordinate needs (at most [`MAX_PRINTED_DECIMALS`]).
fn printed_step_mm(set: &MeasurementSet) -> f64 {
    let decimals = |v: f64| {
        (0..MAX_PRINTED_DECIMALS)
            .find(|&d| {
                let scaled = v * 10f64.powi(d);
                (scaled - scaled.round()).abs() <= 1e-6
            })
            .unwrap_or(MAX_PRINTED_DECIMALS)
    };
    let most = set
        .rows()
        .iter()
        .flat_map(|m| m.position_mm)
        .map(decimals)
        .max()
        .unwrap_or(0);
    10f64.powi(-most)
}

/// The key of a place on a link (to a micrometre: the description's numbers).
fn key(link: usize, p: [f64; 3]) -> String {
    format!("{link}:{:.3},{:.3},{:.3}", p[0], p[1], p[2])
}

/// The tool observation's points at the reference pose, each with its tool target's place on
/// the last link \[mm\].
fn tool_sightings(
    set: &MeasurementSet,
    desc: &RobotDescription,
    reference: &[f64],
    reach_mm: f64,
) -> Vec<([f64; 3], Sighting)> {
    let frame = desc.tool.frame.to_isometry();
    let mut seen: ToolPoints = BTreeMap::new();
    for (i, m) in set.rows().iter().enumerate() {
        let at = m.cmd.iter().zip(reference).all(|(a, b)| (a - b).abs() <= AT_REFERENCE);
        if m.moved_joint == 0 && at && m.target < desc.tool.targets_mm.len() {
            let entry = seen
                .entry(m.target)
                .or_insert((Vec::new(), m.experiment.clone(), set.line_of(i)));
            entry.0.push(Vector3::from(m.position_mm));
        }
    }
    seen.into_iter()
        .map(|(t, (points, experiment, line))| {
            let on_link = frame * Point3::from(desc.tool.targets_mm[t]).map(|c| c * 1e-3);
            let n = points.len() as f64;
            let sighting = Sighting {
                experiment,
                lines: line.map(|l| (l, l)),
                point: points.iter().sum::<Vector3<f64>>() / n,
                leverage: 1.0 / n,
                held_mm2: held_variance_mm2(desc, 0, reach_mm),
                across: Matrix3::identity(),
                joint: 0,
                turning: None,
                held: Vec::new(),
            };
            ((on_link.coords * 1e3).into(), sighting)
        })
        .collect()
}

/// Sweep `e`'s sighting of its target 0 at the reference pose `reference` (file units), when
/// its own command spans the reference's; a sweep whose held joints stand elsewhere is moved
/// to it by their motions (`motions`, [`held::at_reference`]), when those are measured.
fn sweep_sighting(
    e: &AxisExperiment,
    (desc, motions): (&RobotDescription, &[Option<held::Motion>]),
    reference: &[f64],
    reach_mm: f64,
) -> Option<Sighting> {
    let k = e.joint - 1;
    let u_ref = commands_to_internal(desc, reference)[k];
    let u: Vec<f64> = e
        .target0_steps
        .iter()
        .map(|&i| commands_to_internal(desc, &e.commands[i])[k] - u_ref)
        .collect();
    let spans = u.iter().any(|&v| v <= 0.0) && u.iter().any(|&v| v >= 0.0);
    if !spans || u.len() < 5 {
        return None;
    }
    let points = held::at_reference(e, desc, reference, (&u, motions))?;
    let kind = desc.joints[k].kind;
    let curve = Curve::fit(&u, &points, kind)?;
    let (point, leverage, tangent) = curve.at_reference();
    let t = tangent.try_normalize(1e-12)?;
    let first = e.target0_steps.first() == Some(&0);
    Some(Sighting {
        experiment: e.name.clone(),
        lines: e.lines,
        point,
        leverage,
        held_mm2: held_variance_mm2(desc, e.joint, reach_mm),
        across: Matrix3::identity() - t * t.transpose(),
        joint: e.joint,
        turning: Turning::of(&curve, (&u, &points), first),
        held: (0..desc.dof()).filter(|&j| e.holds_constant(j)).collect(),
    })
}

/// The weighted consensus of `sightings` (the point whose offsets across each one's motion,
/// over its variance, are least) and the chi-square of their offsets with its degrees of
/// freedom; `None` when they do not fix a point.
fn consensus(sightings: &[&Sighting], sigma2: f64) -> Option<(Vector3<f64>, f64, usize)> {
    let weight = |s: &Sighting| weight(s, sigma2);
    let total: Matrix3<f64> = sightings.iter().map(|s| weight(s)).sum();
    let (inverse, rank) = pseudo_inverse(&total)?;
    let right: Vector3<f64> = sightings.iter().map(|s| weight(s) * s.point).sum();
    let centre = inverse * right;
    let chi2 = sightings
        .iter()
        .map(|s| {
            let d = s.point - centre;
            (d.transpose() * weight(s) * d)[0]
        })
        .sum();
    let observed: usize = sightings.iter().map(|s| s.across.trace().round() as usize).sum();
    Some((centre, chi2, observed.checked_sub(rank)?))
}

/// The inverse of a consensus's total weight `total` and its rank; where the sightings all
/// move along one direction (a planar robot's sweeps at the reference pose), the inverse on the
/// directions they observe, the point along the other undetermined and untested. `None` when
/// they observe fewer than two directions.
fn pseudo_inverse(total: &Matrix3<f64>) -> Option<(Matrix3<f64>, usize)> {
    let eigen = total.symmetric_eigen();
    let largest = eigen.eigenvalues.max();
    let kept: Vec<usize> = (0..3).filter(|&i| eigen.eigenvalues[i] > 1e-9 * largest).collect();
    match kept.len() {
        3 => Some((total.try_inverse()?, 3)),
        2 => {
            let inverse = kept
                .iter()
                .map(|&i| {
                    let v = eigen.eigenvectors.column(i);
                    v * v.transpose() / eigen.eigenvalues[i]
                })
                .sum();
            Some((inverse, 2))
        }
        _ => None,
    }
}

/// A sighting's weight in a consensus: its projection across its motion over its variance.
fn weight(s: &Sighting, sigma2: f64) -> Matrix3<f64> {
    s.across / variance(s, sigma2)
}

/// Whether a chi-square `chi2` with `dof` degrees of freedom exceeds the test's quantile.
fn exceeds(chi2: f64, dof: usize) -> bool {
    dof > 0 && chi2 > chi_square_quantile(1.0 - SHARED_TARGET_FALSE_ALARM, dof as f64)
}

/// The sweep among `sightings` of one `target` without which the others agree, when all of
/// them do not (module docs); with two sightings either may be the moved one. Named for the
/// held joints' backlash where that explains it, else for a held joint's recorded command
/// ([`held::explained`]) where one explains it.
fn odd_one_out(sightings: &[Sighting], context: &Context, target: (usize, [f64; 3])) -> Option<MovedSweep> {
    let sigma2 = context.sigma2;
    let all: Vec<&Sighting> = sightings.iter().collect();
    let (_, chi2, dof) = consensus(&all, sigma2)?;
    if !exceeds(chi2, dof) {
        return None;
    }
    let mut passing: Vec<(usize, Vector3<f64>, f64)> = (0..sightings.len())
        .filter(|&k| sightings[k].across != Matrix3::identity())
        .filter_map(|k| {
            let rest = without(sightings, k);
            let (centre, chi2, dof) = consensus(&rest, sigma2).or_else(|| Some((rest.first()?.point, 0.0, 0)))?;
            (!exceeds(chi2, dof)).then_some((k, centre, chi2))
        })
        .collect();
    passing.sort_by(|a, b| a.2.total_cmp(&b.2));
    let Some(&(k, centre, _)) = passing.first() else {
        return scattered_odd_one_out(sightings, sigma2, target);
    };
    let s = &sightings[k];
    let offset = s.across * (s.point - centre);
    let sigmas = offset.norm() / variance(s, sigma2).sqrt();
    if sigmas <= GROSS_MISS_FACTOR * noise_bound(s) {
        return None;
    }
    let backlash = backlash::explained(sightings, k, centre, offset, sigma2).unwrap_or_default();
    let held = match backlash.is_empty() {
        true => held::explained(sightings, k, centre, context.motions, (context.desc, sigma2)),
        false => Vec::new(),
    };
    // Several sweeps without each of which the others agree, or two sightings: either may be
    // the one out of place.
    let rivals: Vec<usize> = passing[1..].iter().map(|p| p.0).collect();
    let ambiguous = sightings.len() == 2;
    let moved = moved_sweep(sightings, (k, &rivals, ambiguous), offset, sigmas, target);
    Some(MovedSweep {
        backlash,
        held,
        ..moved
    })
}

/// Sighting `k` of `sightings` said out of place, with `rivals` the other sightings that could
/// be (`ambiguous` too when there are any): the others it is compared with when there are none.
fn moved_sweep(
    sightings: &[Sighting],
    (k, rivals, ambiguous): (usize, &[usize], bool),
    offset: Vector3<f64>,
    sigmas: f64,
    target: (usize, [f64; 3]),
) -> MovedSweep {
    let s = &sightings[k];
    let others: Vec<String> = if rivals.is_empty() {
        (0..sightings.len())
            .filter(|&j| j != k)
            .map(|j| sightings[j].experiment.clone())
            .collect()
    } else {
        rivals.iter().map(|&j| sightings[j].experiment.clone()).collect()
    };
    MovedSweep {
        experiment: s.experiment.clone(),
        lines: s.lines,
        offset_mm: [offset.x, offset.y, offset.z],
        sigmas,
        ambiguous: ambiguous || !rivals.is_empty(),
        others,
        target,
        backlash: Vec::new(),
        held: Vec::new(),
    }
}

/// Every sighting of `sightings` but the `k`-th.
fn without(sightings: &[Sighting], k: usize) -> Vec<&Sighting> {
    sightings
        .iter()
        .enumerate()
        .filter(|(j, _)| *j != k)
        .map(|(_, s)| s)
        .collect()
}

/// The sweep out of the others' scatter, when no sighting's removal lets the others agree at
/// the noise (module docs: a real robot's effects the model lacks scatter every sighting):
/// each sweep's offset from the others' consensus, over its variance and the consensus's, per
/// dimension, over the others' chi-square per degree of freedom (their scatter over the noise,
/// at least 1), is an F ratio; the sweep is named when that ratio is beyond its quantile at
/// [`SHARED_TARGET_FALSE_ALARM`] shared among the sweeps tested, and its offset beyond
/// [`GROSS_MISS_FACTOR`] times the noise test's bound ([`odd_one_out`]'s rule).
fn scattered_odd_one_out(sightings: &[Sighting], sigma2: f64, target: (usize, [f64; 3])) -> Option<MovedSweep> {
    let sweeps: Vec<usize> = (0..sightings.len())
        .filter(|&k| sightings[k].across != Matrix3::identity())
        .collect();
    let tests = sweeps.len() as f64;
    let mut beyond: Vec<(usize, f64, Vector3<f64>, f64)> = sweeps
        .iter()
        .filter_map(|&k| {
            let (ratio, offset, sigmas) = scatter_ratio(sightings, k, sigma2, tests)?;
            (ratio > 1.0).then_some((k, ratio, offset, sigmas))
        })
        .collect();
    beyond.sort_by(|a, b| b.1.total_cmp(&a.1));
    let &(k, _, offset, sigmas) = beyond.first()?;
    let rivals: Vec<usize> = beyond[1..].iter().map(|b| b.0).collect();
    Some(moved_sweep(sightings, (k, &rivals, false), offset, sigmas, target))
}

/// Sweep `k`'s F ratio over its quantile among `tests` sweeps ([`scattered_odd_one_out`]; beyond
/// 1: out of the others' scatter), its offset across its motion from the others' consensus
/// \[mm\], and that offset over its standard deviation at the others' scatter; `None` when the
/// others fix no point or have no degree of freedom left, or the offset is within
/// [`GROSS_MISS_FACTOR`] times the noise test's bound.
fn scatter_ratio(sightings: &[Sighting], k: usize, sigma2: f64, tests: f64) -> Option<(f64, Vector3<f64>, f64)> {
    let rest = without(sightings, k);
    let (centre, chi2, dof) = consensus(&rest, sigma2)?;
    let s = &sightings[k];
    let offset = s.across * (s.point - centre);
    if dof == 0 || offset.norm() / variance(s, sigma2).sqrt() <= GROSS_MISS_FACTOR * noise_bound(s) {
        return None;
    }
    let (consensus_covariance, _) = pseudo_inverse(&rest.iter().map(|r| weight(r, sigma2)).sum())?;
    // The unit variance along the motion makes the matrix invertible; the offset has no part there.
    let along = Matrix3::identity() - s.across;
    let covariance = s.across * (Matrix3::identity() * variance(s, sigma2) + consensus_covariance) * s.across + along;
    let chi2_k = (offset.transpose() * covariance.try_inverse()? * offset)[0];
    let scatter = (chi2 / dof as f64).max(1.0);
    let dim = s.across.trace().round();
    let quantile = f_upper_quantile(SHARED_TARGET_FALSE_ALARM / tests, dim, dof as f64);
    Some((chi2_k / dim / scatter / quantile, offset, (chi2_k / scatter).sqrt()))
}
