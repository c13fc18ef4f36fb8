//! The arcs the unit checks judge: a circle through three points (a second, differently written
//! path from the calibrator's fits), each revolute axis experiment's target-0 arc as measured
//! and as the description gives it, and when an arc is too short to judge.

use super::RADIUS_SIGMAS;
use super::SPREAD_WARNING;
use super::median;
use super::slipped;
use crate::kinematics::JointKind;
use crate::measurement::{Measurement, MeasurementSet};
use crate::robot::{RobotDescription, commands_to_internal};
use nalgebra::{Point3, Vector3};

/// Centre, radius and the angle from `a` over `b` to `c` of the circle through three points,
/// or `None` when they are (nearly) collinear.
pub(super) fn circle_through(a: &Point3<f64>, b: &Point3<f64>, c: &Point3<f64>) -> Option<(Point3<f64>, f64, f64)> {
    let (u, v) = (b - a, c - a);
    let w = u.cross(&v);
    let w2 = w.norm_squared();
    if w2 <= 1e-12 * u.norm_squared() * v.norm_squared() {
        return None;
    }
    // Circumcentre of a triangle in 3-D.
    let centre = a + (v.cross(&w) * u.norm_squared() + w.cross(&u) * v.norm_squared()) / (2.0 * w2);
    let angle = |p: &Point3<f64>, q: &Point3<f64>| (p - centre).angle(&(q - centre));
    Some((centre, (a - centre).norm(), angle(a, b) + angle(b, c)))
}

/// One axis experiment's target-0 arc ([`arc_of`]).
pub(super) struct Arc {
    /// Median radius \[file length units\].
    pub(super) radius: f64,
    /// Component-wise median centre \[file length units\].
    pub(super) centre: Point3<f64>,
    /// Median ratio of the turned angle to the commanded span (both read in degrees).
    pub(super) turn_ratio: f64,
    /// Median absolute deviation of the point triples' radii from their median, over it: how
    /// far the points lie from one circle.
    pub(super) radius_scatter: f64,
    /// The standard error of `radius` \[file length units\]: the triples' spread (1.4826 times
    /// their median absolute deviation) times the median's 1.2533 over the square root of the
    /// triples (disjoint, so independent).
    pub(super) radius_sigma: f64,
    /// The standard error of `radius` \[mm\] at the noise the checks assume
    /// ([`noise_radius_sigma`] over the square root of the triples): what one triple's radius
    /// is worth, where its scatter gives none; in millimetres, so not for a test of the
    /// coordinates' units.
    pub(super) noise_radius_sigma: f64,
}

impl Arc {
    /// Whether the radius departs from `nominal` (the same unit) beyond [`SPREAD_WARNING`] and
    /// beyond [`RADIUS_SIGMAS`] of its standard error.
    pub(super) fn radius_off(&self, nominal: f64) -> bool {
        (self.radius / nominal).ln().abs() > SPREAD_WARNING.ln()
            && (self.radius - nominal).abs() > RADIUS_SIGMAS * self.radius_sigma
    }
}

/// `rows` in the order of command `k` (0-based) when they are not in it already (either way):
/// a sweep's rows written in another order than the joint moved (sorted by another column, a
/// shuffled export) keep each point beside its own command, and the triples of [`arc_of`] are
/// taken along the arc, not across it (which would read as a turn many times the commanded).
pub(super) fn in_command_order<'a>(rows: &[&'a Measurement], k: usize) -> Vec<&'a Measurement> {
    let monotonic = |up: bool| {
        rows.windows(2).all(|w| match up {
            true => w[1].cmd[k] >= w[0].cmd[k],
            false => w[1].cmd[k] <= w[0].cmd[k],
        })
    };
    let mut sorted = rows.to_vec();
    if !monotonic(true) && !monotonic(false) {
        sorted.sort_by(|a, b| a.cmd[k].total_cmp(&b.cmd[k]));
    }
    sorted
}

/// How far the command of joint `k` (0-based) moves from the first to the last point of a
/// triple of [`arc_of`] (`rows[i]`, `rows[i + m]`, `rows[i + 2m]` in command order, `m` a third
/// of the rows): the median over the triples, read in degrees; 0 with fewer than 3 rows. Five
/// points over 30 degrees make one triple over 15 degrees.
pub(super) fn triple_span_deg(rows: &[&Measurement], k: usize) -> f64 {
    let rows = in_command_order(rows, k);
    let m = rows.len() / 3;
    median(
        (0..m)
            .map(|i| (rows[i + 2 * m].cmd[k] - rows[i].cmd[k]).abs().min(360.0))
            .collect(),
    )
    .max(0.0)
}

/// One axis experiment's target-0 arc from the circles through its point triples, taken in the
/// order of the commands ([`in_command_order`]).
pub(super) fn arc_of(rows: &[&Measurement], k: usize) -> Option<Arc> {
    let rows = in_command_order(rows, k);
    let m = rows.len() / 3;
    if m == 0 {
        return None;
    }
    let (mut radii, mut ratios, mut centres, mut sagittas) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for i in 0..m {
        let (a, b, c) = (rows[i], rows[i + m], rows[i + 2 * m]);
        let p = |r: &Measurement| Point3::from(Vector3::from(r.position_mm));
        let commanded = (c.cmd[k] - a.cmd[k]).abs();
        if let Some((centre, radius, angle)) = circle_through(&p(a), &p(b), &p(c))
            && commanded > 0.0
        {
            centres.push(centre);
            radii.push(radius);
            ratios.push(angle.to_degrees() / commanded);
            let chord = p(c) - p(a);
            sagittas.push((p(b) - p(a)).cross(&chord).norm() / chord.norm());
        }
    }
    let turn_ratio = median(ratios);
    let centre = Point3::from(Vector3::from_fn(|k, _| median(centres.iter().map(|c| c[k]).collect())));
    let radius = median(radii.clone());
    let deviation = median(radii.iter().map(|r| (r - radius).abs()).collect());
    let triples = (radii.len() as f64).sqrt();
    Some(Arc {
        centre,
        radius,
        turn_ratio,
        radius_scatter: deviation / radius,
        radius_sigma: 1.2533 * 1.4826 * deviation / triples,
        noise_radius_sigma: 1.2533 * noise_radius_sigma(radius, median(sagittas)) / triples,
    })
}

/// The noise of a point the radius test assumes, per coordinate \[mm\]: the paper's
/// theodolites' 0.2 mm 3-D RMS, the noisiest instrument the checks expect (a laser tracker's
/// 0.02-0.05 mm leaves the test conservative).
pub(super) const ASSUMED_POINT_NOISE_MM: f64 = 0.2 / 1.7320508075688772;

/// The standard error \[mm\] of the radius of a circle through three points of sagitta
/// `sagitta_mm` (the middle point's distance from the chord) at [`ASSUMED_POINT_NOISE_MM`]:
/// `r = (c/2)^2 / (2 s) + s / 2`, so `dr/ds = 1/2 - (c/2)^2 / (2 s^2)`, about `-r / s` for a
/// short arc, and the sagitta's error is the middle point's radial error less the mean of the
/// ends', `sqrt(1 + 1/4 + 1/4)` times a point's. With a single triple the triples' scatter
/// gives no standard error; this floor is what the noise alone makes of it.
pub(super) fn noise_radius_sigma(radius_mm: f64, sagitta_mm: f64) -> f64 {
    let ds = 1.5f64.sqrt() * ASSUMED_POINT_NOISE_MM;
    (0.5 - (radius_mm - sagitta_mm / 2.0) / sagitta_mm).abs() * ds
}

/// An arc whose sagitta, as the description and the commands give it, is below this \[mm\]
/// is not judged ([`too_short_to_judge`]): a circle through three of its points
/// measures the instrument's noise (0.2 mm for the paper's theodolites, 0.02-0.05 mm for a
/// laser tracker) more than its radius.
pub(super) const MIN_JUDGED_SAGITTA_MM: f64 = 1.0;

/// The commanded span of joint `k` (0-based) over `rows` (read in degrees, at most a turn).
pub(super) fn commanded_span_deg(rows: &[&Measurement], k: usize) -> f64 {
    let (lo, hi) = rows
        .iter()
        .map(|r| r.cmd[k])
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| (lo.min(c), hi.max(c)));
    (hi - lo).abs().min(360.0)
}

/// The sagitta and the chord \[mm\] of the arc a target at `radius_mm` from its axis draws
/// over `span_deg`.
pub(super) fn arc_extent_mm(radius_mm: f64, span_deg: f64) -> (f64, f64) {
    let half = (span_deg / 2.0).to_radians();
    (radius_mm * (1.0 - half.cos()), 2.0 * radius_mm * half.sin())
}

/// The distance \[file length units\] between the points of `rows` at the lowest and the
/// highest command of joint `k` (0-based): the measured arc's chord.
pub(super) fn measured_chord(rows: &[&Measurement], k: usize) -> f64 {
    let by_command = |a: &&&Measurement, b: &&&Measurement| a.cmd[k].total_cmp(&b.cmd[k]);
    match (rows.iter().min_by(by_command), rows.iter().max_by(by_command)) {
        (Some(lo), Some(hi)) => (Vector3::from(hi.position_mm) - Vector3::from(lo.position_mm)).norm(),
        _ => 0.0,
    }
}

/// Whether the arc of `rows` (target 0 of joint `k`, 0-based, `radius_mm` from its axis by the
/// description) is too short to judge: the sagitta of the arc through one of its point triples
/// ([`triple_span_deg`]: the circles [`arc_of`] judges) by the description and the commands is
/// below [`MIN_JUDGED_SAGITTA_MM`], and its points spread either that little too or as far as
/// the commands move them (the chord of the whole sweep the description and the commands give,
/// within [`super::SLIP_FACTOR`]): a short sweep, not a slip. Commands in radians draw a chord 57 times
/// the commanded one; coordinates in metres a thousandth of it.
pub(super) fn too_short_to_judge(rows: &[&Measurement], k: usize, radius_mm: f64) -> bool {
    let (sagitta, _) = arc_extent_mm(radius_mm, triple_span_deg(rows, k));
    let (_, chord) = arc_extent_mm(radius_mm, commanded_span_deg(rows, k));
    let points: Vec<Point3<f64>> = rows.iter().map(|r| Point3::from(r.position_mm)).collect();
    sagitta < MIN_JUDGED_SAGITTA_MM
        && (crate::numerics::stats::rms_spread(&points) < MIN_JUDGED_SAGITTA_MM
            || !slipped(measured_chord(rows, k) / chord))
}

/// The radius \[mm\] target 0 of joint `joint` (1-based) turns on about its axis on `model`
/// (the description's nominal) at joint values `q`.
pub(super) fn nominal_radius_with(
    model: &crate::kinematics::PhiModel,
    desc: &RobotDescription,
    joint: usize,
    q: &[f64],
) -> Option<f64> {
    nominal_circle(model, desc, joint, q).map(|(_, r)| r)
}

/// The centre \[mm, the nominal base frame\] and radius \[mm\] of the circle target 0 of joint
/// `joint` (1-based) turns on about its axis on `model` at joint values `q`.
pub(super) fn nominal_circle(
    model: &crate::kinematics::PhiModel,
    desc: &RobotDescription,
    joint: usize,
    q: &[f64],
) -> Option<(Point3<f64>, f64)> {
    let target = desc.axis_targets_of(joint)?.target0;
    let poses = model.poses(q);
    let axis = poses.axis(joint - 1);
    let p = poses.world_from_link.get(target.link - 1)? * target.position_m();
    let d = p - axis.origin_m;
    let along = axis.direction.into_inner() * d.dot(&axis.direction);
    Some(((axis.origin_m + along) * 1e3, (d - along).norm() * 1e3))
}

/// One revolute axis experiment's target-0 arc, with what the description says of it.
pub(super) struct ExperimentArc {
    /// The moved joint (1-based).
    pub(super) joint: usize,
    /// The experiment's id.
    pub(super) name: String,
    /// The commands of its first target-0 row, as read.
    pub(super) first_cmd: Vec<f64>,
    /// The arc measured.
    pub(super) arc: Arc,
    /// The radius the description gives it at `first_cmd` \[mm\], when above 1 mm.
    pub(super) nominal_mm: Option<f64>,
    /// The centre the description gives it at `first_cmd` \[mm, the nominal base frame\].
    pub(super) nominal_centre_mm: Option<Point3<f64>>,
    /// Its target-0 rows, by step.
    pub(super) rows: Vec<Measurement>,
    /// Degrees target 0 turns per degree of the command and its sigma ([`super::commands::turn_slope`]).
    pub(super) turn: Option<(f64, f64)>,
    /// The same of the description's nominal robot at the same commands.
    pub(super) nominal_turn: Option<f64>,
}

/// The judged arcs of the revolute axis experiments' target 0 (a sweep too short to judge is
/// left out: the calibration says when it is too short to locate its axis).
pub(super) fn experiment_arcs(set: &MeasurementSet, desc: &RobotDescription) -> Vec<ExperimentArc> {
    let mut arcs = Vec::new();
    let model = desc.nominal_model();
    let ideal = crate::robot::RobotModel::ideal(desc);
    let controller = crate::robot::Controller::from_description(desc);
    for e in set.experiments().iter().filter(|e| e.moved_joint > 0) {
        let joint = e.moved_joint;
        if desc.joints.get(joint - 1).is_none_or(|j| j.kind != JointKind::Revolute) {
            continue;
        }
        let by_step = e.by_step_target();
        let rows: Vec<&Measurement> = by_step.iter().filter(|((_, t), _)| *t == 0).map(|(_, m)| *m).collect();
        let Some(first) = rows.first() else {
            continue;
        };
        let nominal = nominal_circle(&model, desc, joint, &commands_to_internal(desc, &first.cmd));
        let nominal_mm = nominal.map(|c| c.1).filter(|r| *r > 1.0);
        if nominal_mm.is_some_and(|r| too_short_to_judge(&rows, joint - 1, r)) {
            continue;
        }
        if let Some(arc) = arc_of(&rows, joint - 1) {
            let owned: Vec<Measurement> = rows.iter().map(|m| (*m).clone()).collect();
            arcs.push(ExperimentArc {
                joint,
                name: e.name.to_string(),
                first_cmd: first.cmd.clone(),
                arc,
                nominal_mm,
                nominal_centre_mm: nominal.map(|c| c.0),
                turn: super::commands::turn_slope(&owned, joint - 1),
                nominal_turn: super::commands::nominal_turn_slope(desc, &ideal, &controller, &owned, joint),
                rows: owned,
            });
        }
    }
    arcs
}
