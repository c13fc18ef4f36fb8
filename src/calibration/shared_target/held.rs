//! Held joints off the reference pose in the reference-pose test (hostile run 13: a held
//! joint's recorded command off the common reference through one sweep only, a value typed
//! wrong for that experiment or the joint re-mastered between the sweeps). A sweep whose held
//! joints stand (as recorded) away from the reference pose, by a real controller's wander or a
//! sweep taken at another pose, is moved back to it before its point at the reference pose is
//! compared with the others': by the product of exponentials (Brockett 1984; Lynch & Park,
//! *Modern Robotics*, 2017, eq. 4.14), a point of the last links at joint values `r + d` is
//! `E_1(d_1) E_2(d_2) ... E_n(d_n) p(r)`, each `E_j` joint `j`'s motion at the reference pose
//! `r`, which joint `j`'s own sweep measures (its circle: centre, axis and turn per command,
//! Kasa 1976; its line: travel per command, [`Motion`]). A sweep of joint `k` whose recorded held values
//! are off by `d` therefore sees `E_{<k}(d) E_k(u) E_{>k}(d) p(r)`; undoing the joints below
//! `k` in order, then those above it inside the sweep's own motion, leaves `E_k(u) p(r)`
//! ([`at_reference`]). A held value recorded off where the robot stood moves the sweep's
//! point by that joint's motion: a sweep out of place by one held joint's turn (or travel) is
//! named for that joint's recorded value ([`explained`]), with the offset in its command's
//! units. Not reached: an offset whose motion at the target runs along the sweep's own motion
//! (a held joint parallel to the swept one, the target on the line through both axes), which
//! reads as the swept joint's zero (`docs/formats.md`).

use super::sighting::{AT_REFERENCE, Curve, SHARED_TARGET_FALSE_ALARM, Sighting, noise_bound, variance};
use crate::calibration::axis_circle::fit_circle;
use crate::calibration::procedure::AxisExperiment;
use crate::kinematics::JointKind;
use crate::measurement::column_slips::GROSS_MISS_FACTOR;
use crate::numerics::stats::chi_square_quantile;
use crate::robot::{RobotDescription, commands_to_internal};
use nalgebra::{Point3, Rotation3, Unit, Vector3};
use std::f64::consts::PI;

/// A joint's motion at the reference pose as its own sweep measures it, per internal unit of
/// its command (rad or m) from the reference.
#[derive(Clone, Debug)]
pub(super) enum Motion {
    /// A turning joint: a point of its axis \[mm\], the axis (right-handed with the command)
    /// and the turn per command.
    Turn {
        centre: Vector3<f64>,
        axis: Unit<Vector3<f64>>,
        rate: f64,
    },
    /// A sliding joint: the travel per command \[mm per m\].
    Slide { per_command: Vector3<f64> },
}

impl Motion {
    /// The motion of `points` \[mm\] at the commands `u` (internal units from the reference):
    /// a turning joint's circle through them (Kasa's fit, [`fit_circle`]) and the turn per
    /// command of their angles about it (least squares; a circle of free shape in the command,
    /// [`Curve`], fits a short arc as well at another turn per command); a sliding joint's
    /// line in the command (`None` when they fix neither).
    fn of(u: &[f64], points: &[Vector3<f64>], kind: JointKind) -> Option<Motion> {
        match kind {
            JointKind::Revolute => {
                let on: Vec<Point3<f64>> = points.iter().map(|p| Point3::from(*p)).collect();
                let circle = fit_circle(&on).ok()?;
                let angle = |p: &Vector3<f64>| {
                    let r = p - circle.centre.coords;
                    r.dot(&circle.v).atan2(r.dot(&circle.u))
                };
                // In step order, each from the one before (a sweep beyond half a turn).
                let mut angles: Vec<f64> = Vec::with_capacity(points.len());
                for p in points {
                    let raw = angle(p);
                    let next = match angles.last() {
                        Some(&last) => last + (raw - last + PI).rem_euclid(2.0 * PI) - PI,
                        None => raw,
                    };
                    angles.push(next);
                }
                let n = u.len() as f64;
                let (mu, ma) = (u.iter().sum::<f64>() / n, angles.iter().sum::<f64>() / n);
                let suu: f64 = u.iter().map(|x| (x - mu).powi(2)).sum();
                let sua: f64 = u.iter().zip(&angles).map(|(x, a)| (x - mu) * (a - ma)).sum();
                (suu > 0.0).then(|| Motion::Turn {
                    centre: circle.centre.coords,
                    axis: circle.normal,
                    rate: sua / suu,
                })
            }
            JointKind::Prismatic => {
                let line = Curve::fit(u, points, kind)?;
                Some(Motion::Slide {
                    per_command: line.coefficients.row(1).transpose(),
                })
            }
        }
    }

    /// Point `p` \[mm\] moved by the joint's command changed by `du` (internal units).
    pub(super) fn apply(&self, p: Vector3<f64>, du: f64) -> Vector3<f64> {
        match self {
            Motion::Turn { centre, axis, rate } => centre + Rotation3::from_axis_angle(axis, rate * du) * (p - centre),
            Motion::Slide { per_command } => p + per_command * du,
        }
    }

    /// The motion of `p` per unit of command at no change (the derivative of [`Motion::apply`]).
    pub(super) fn velocity(&self, p: Vector3<f64>) -> Vector3<f64> {
        match self {
            Motion::Turn { centre, axis, rate } => axis.cross(&(p - centre)) * *rate,
            Motion::Slide { per_command } => *per_command,
        }
    }
}

/// Rounds of [`motions`]: the first fits each sweep's points as recorded, whose held joints'
/// wander (a controller's encoder log, 0.1 deg at a metre: 1.7 mm) scatters them; the next
/// fits them moved to the reference pose by the motions of the round before.
const MOTION_ROUNDS: usize = 3;

/// Each joint's motion (0-based index), from the sweep of it whose held joints stand nearest
/// the reference pose `reference` (file units): the path in its command of its target-0 points
/// moved to the reference pose by the previous round's motions ([`MOTION_ROUNDS`]); `None` for
/// a joint without such a sweep.
pub(super) fn motions(
    experiments: &[AxisExperiment],
    desc: &RobotDescription,
    reference: &[f64],
) -> Vec<Option<Motion>> {
    let u_ref = commands_to_internal(desc, reference);
    let nearest: Vec<Option<&AxisExperiment>> = (0..desc.dof())
        .map(|k| {
            experiments
                .iter()
                .filter(|e| e.joint == k + 1 && e.target0_m.len() >= 5)
                .map(|e| (e.held_distance(reference), e))
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map(|n| n.1)
        })
        .collect();
    let mut motions: Vec<Option<Motion>> = vec![None; desc.dof()];
    for round in 0..MOTION_ROUNDS {
        let previous = motions.clone();
        for (k, e) in nearest.iter().enumerate() {
            let Some(e) = e else { continue };
            let u: Vec<f64> = e
                .target0_steps
                .iter()
                .map(|&i| commands_to_internal(desc, &e.commands[i])[k] - u_ref[k])
                .collect();
            let points = match round {
                0 => Some(e.target0_m.iter().map(|p| p.coords * 1e3).collect()),
                _ => at_reference(e, desc, reference, (&u, &previous)),
            };
            motions[k] = points
                .and_then(|p| Motion::of(&u, &p, desc.joints[k].kind))
                .or_else(|| previous[k].clone());
        }
    }
    motions
}

/// The held joints' deviations from `reference` at step `i` of `e` (internal units, 0 for the
/// swept joint, a follower and a held joint within [`AT_REFERENCE`] of it).
fn deviations(e: &AxisExperiment, desc: &RobotDescription, reference: &[f64], i: usize) -> Vec<f64> {
    let (c, r) = (
        commands_to_internal(desc, &e.commands[i]),
        commands_to_internal(desc, reference),
    );
    (0..desc.dof())
        .map(
            |j| match e.holds_constant(j) && (e.commands[i][j] - reference[j]).abs() > AT_REFERENCE {
                true => c[j] - r[j],
                false => 0.0,
            },
        )
        .collect()
}

/// Sweep `e`'s target-0 points \[mm\] moved to where they would be with every held joint at
/// `reference` (module docs), with `u` each point's swept command from the reference
/// (internal units); the points as they are where every held joint stands at the reference.
/// `None` when a held joint off the reference has no motion measured.
pub(super) fn at_reference(
    e: &AxisExperiment,
    desc: &RobotDescription,
    reference: &[f64],
    (u, motions): (&[f64], &[Option<Motion>]),
) -> Option<Vec<Vector3<f64>>> {
    let k = e.joint - 1;
    e.target0_steps
        .iter()
        .zip(&e.target0_m)
        .zip(u)
        .map(|((&i, p), &u)| {
            let mut p = p.coords * 1e3;
            let d = deviations(e, desc, reference, i);
            for j in (0..k).filter(|&j| d[j] != 0.0) {
                p = motions[j].as_ref()?.apply(p, -d[j]);
            }
            if d[k + 1..].iter().any(|&v| v != 0.0) {
                let own = motions[k].as_ref()?;
                p = own.apply(p, -u);
                for j in (k + 1..d.len()).filter(|&j| d[j] != 0.0) {
                    p = motions[j].as_ref()?.apply(p, -d[j]);
                }
                p = own.apply(p, u);
            }
            Some(p)
        })
        .collect()
}

/// A held joint whose recorded value, off where the robot stood, explains a sweep out of place.
#[derive(Clone, Debug, PartialEq)]
pub struct HeldSlip {
    /// The joint (1-based).
    pub joint: usize,
    /// How far its recorded command in this sweep is from where the robot stood (file units:
    /// deg or mm; the recorded value minus the one the others' reference pose implies).
    pub offset: f64,
    /// The offset's standard deviation (file units): the sighting's over the motion across the
    /// sweep's that a unit of the command gives the target there.
    pub sigma: f64,
    /// The command's unit (`deg` or `mm`).
    pub unit: &'static str,
}

/// Gauss-Newton steps of a held joint's fitted offset: the motion is a rotation, nearly linear
/// over the few degrees a slip is.
const STEPS: usize = 8;

/// The held joints (each alone) whose command, off by a fitted amount, moves the others'
/// consensus `centre` \[mm\] onto sighting `k`'s point across its motion within the noise test's
/// bound at the noise `sigma2` (chi-square at [`SHARED_TARGET_FALSE_ALARM`] with the
/// dimensions across the motion less the one fitted), smallest first; empty when none does or the
/// sighting is the tool observation.
pub(super) fn explained(
    sightings: &[Sighting],
    k: usize,
    centre: Vector3<f64>,
    motions: &[Option<Motion>],
    (desc, sigma2): (&RobotDescription, f64),
) -> Vec<HeldSlip> {
    let s = &sightings[k];
    if s.joint == 0 {
        return Vec::new();
    }
    let dims = s.across.trace().round();
    let bound = chi_square_quantile(1.0 - SHARED_TARGET_FALSE_ALARM, (dims - 1.0).max(1.0));
    let sd2 = variance(s, sigma2);
    let mut found: Vec<(f64, HeldSlip)> = Vec::new();
    for (j, motion) in motions.iter().enumerate() {
        let Some(motion) = motion.as_ref().filter(|_| s.held.contains(&j)) else {
            continue;
        };
        let miss = |du: f64| s.across * (motion.apply(centre, du) - s.point);
        let mut du = 0.0;
        for _ in 0..STEPS {
            let slope = s.across * motion.velocity(motion.apply(centre, du));
            let norm2 = slope.norm_squared();
            if norm2 == 0.0 {
                break;
            }
            du -= slope.dot(&miss(du)) / norm2;
        }
        let chi2 = miss(du).norm_squared() / sd2;
        let named = s.across * (motion.apply(centre, du) - centre);
        let per_command = (s.across * motion.velocity(motion.apply(centre, du))).norm();
        if chi2 <= bound && named.norm() / sd2.sqrt() > GROSS_MISS_FACTOR * noise_bound(s) {
            let kind = desc.joints[j].kind;
            found.push((
                chi2,
                HeldSlip {
                    joint: j + 1,
                    offset: -kind.to_file_units(du),
                    sigma: kind.to_file_units(sd2.sqrt() / per_command),
                    unit: kind.file_unit(),
                },
            ));
        }
    }
    // Each explains the sighting within the noise: the smallest slip that does first.
    found.sort_by(|a, b| a.1.offset.abs().total_cmp(&b.1.offset.abs()));
    found.into_iter().map(|f| f.1).collect()
}
