//! Why a joint's sweep fits no arc (no line) of the joint, read from its points alone, when
//! its axis fit fails or misses them ([`super::axis_fit::fit_joint`]): a few points off the
//! circle (the line) the others draw, a few points on it where the joint stands at other
//! commands, or every point on it in another order than the commands.
//!
//! A circle (a line) is fitted to the points without their commands, robustly (through the
//! two or three points the most others lie near, then to the points near it); the points
//! beyond the fence of the distances (Tukey's far-out fence of noise norms, scaled by their
//! median so that up to half may be off, and at least [`crate::numerics::stats::FAR_OUT`]
//! times the noise of a point and [`crate::numerics::stats::ABSURD_SHARE`] of the sweep's
//! spread) are off it. The kept points' places along the circle (the line) are then compared with
//! their commands: a joint turns (slides) its target as far as its command, within the
//! transmission's few per cent, so place minus command is one constant along the sweep; the
//! points off that constant by more than the fence sit where the joint stood at another
//! command. When most points are, and their places sorted match the commands sorted, the
//! points are in another order than the commands. Only a failed fit is explained: clean data
//! never reach it.

use super::{OutlierPoint, OutlierTest};
use crate::calibration::fit_circle;
use crate::kinematics::JointKind;
use crate::measurement::MeasurementSet;
use crate::numerics::stats::{ABSURD_SHARE, FAR_OUT, QuantileMethod, chi_far_out_over_median, quantile, rms_spread};
use nalgebra::{Point3, Vector3};
use std::f64::consts::{PI, TAU};

/// The fewest points a sweep's place along its circle (line) is judged on: fewer leave no
/// quartiles to fence with.
const MIN_POINTS: usize = 5;

/// What a joint's sweep points show when no arc (line) of the joint fits them.
#[derive(Clone, Debug, PartialEq)]
pub enum SweepMisfit {
    /// Some points lie off the circle (the line) the others draw.
    OffPath {
        /// The points set aside, with their distance from the others' circle \[mm\].
        points: Vec<OutlierPoint>,
        /// The fence they exceed \[mm\].
        fence_mm: f64,
        /// The joint's kind (arc or line).
        kind: JointKind,
    },
    /// Some points lie on it where the joint stands at other commands.
    OffCommand {
        /// The points, with their distance along the path from where their commands put them \[mm\].
        points: Vec<OutlierPoint>,
        /// The fence they exceed \[mm\].
        fence_mm: f64,
        /// The joint's kind.
        kind: JointKind,
    },
    /// Every point lies on it, in another order than the commands.
    Reordered {
        /// The points out of their command's place.
        moved: usize,
        /// The points.
        points: usize,
        /// The joint's kind.
        kind: JointKind,
    },
}

impl SweepMisfit {
    /// The same finding with each point's file line read from `set`.
    pub(super) fn with_lines(mut self, set: &MeasurementSet) -> Self {
        if let Self::OffPath { points, .. } | Self::OffCommand { points, .. } = &mut self {
            for o in points {
                o.line = super::outlier_point::row_of(set, o).and_then(|row| set.line_of(row));
            }
        }
        self
    }
}

fn path(kind: JointKind) -> (&'static str, &'static str) {
    match kind {
        JointKind::Revolute => ("arc", "turns"),
        JointKind::Prismatic => ("line", "slides"),
    }
}

fn named(points: &[OutlierPoint]) -> String {
    let names: Vec<String> = points
        .iter()
        .map(|o| match o.line {
            Some(line) => format!("line {line} (step {}, {:.1} mm)", o.step, o.residual_mm),
            None => format!("step {} ({:.1} mm)", o.step, o.residual_mm),
        })
        .collect();
    names.join(", ")
}

impl std::fmt::Display for SweepMisfit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::OffPath { points, fence_mm, kind } => write!(
                f,
                "{} of its points lie off the {} the others draw, beyond {fence_mm:.3} mm: {}: check those rows' \
                 coordinates (a sign or a column slipped, another target's reading); the fit cannot place the axis \
                 through them",
                points.len(),
                path(*kind).0,
                named(points)
            ),
            Self::OffCommand { points, fence_mm, kind } => write!(
                f,
                "{} of its points lie on the {} the others draw, but where the joint stands at another command (off \
                 along it by more than {fence_mm:.3} mm): {}: check those rows' commands (another unit, a typo, a \
                 reading of another step)",
                points.len(),
                path(*kind).0,
                named(points)
            ),
            Self::Reordered { moved, points, kind } => write!(
                f,
                "its {points} points lie on one {} but in another order than their commands: {moved} of them sit \
                 where the joint stood at another step's command (rows sorted or pasted in another order than the \
                 commands, or the commands of another sweep); put each row's coordinates beside its own commands",
                path(*kind).0
            ),
        }
    }
}

/// One joint's sweep points \[m\], the joint's command at each (rad or m) and each point's
/// `(experiment, step)`.
pub(super) struct SweepPoints<'a> {
    pub(super) points: &'a [Point3<f64>],
    pub(super) u: &'a [f64],
    pub(super) labels: Vec<(String, usize)>,
    pub(super) joint: usize,
}

impl SweepPoints<'_> {
    fn outlier(&self, i: usize, residual_mm: f64, fence_mm: f64, noise_mm: f64) -> OutlierPoint {
        OutlierPoint {
            experiment: self.labels[i].0.clone(),
            joint: self.joint,
            step: self.labels[i].1,
            target: 0,
            line: None,
            residual_mm,
            normalised_residual: residual_mm / (noise_mm / 3f64.sqrt()),
            fence: fence_mm / (noise_mm / 3f64.sqrt()),
            dropped: false,
            approach: None,
            test: OutlierTest::AxisFit,
        }
    }
}

/// The fence of `distances` \[mm\], each the norm of `dof` Gaussian components for a point of
/// the noise: the far-out fence of such norms over their median (Tukey's, as
/// [`crate::numerics::stats::chi_far_out_over_median`]) times their median, at least
/// `floor_mm` ([`floor_mm`]). A median, not the quartiles, scales it: up to half of the
/// points may be off.
fn fence(distances: &[f64], dof: f64, floor_mm: f64) -> f64 {
    let ratio = chi_far_out_over_median(dof);
    (ratio * quantile(distances, 0.5, QuantileMethod::Linear)).max(floor_mm)
}

/// Components of a point's distance from a circle (radial, axial) or a line (two across it).
const ACROSS: f64 = 2.0;

/// Components of a point's offset along its path.
const ALONG: f64 = 1.0;

/// The least distance \[mm\] a point named must lie off: [`FAR_OUT`] times the noise of a point,
/// and [`ABSURD_SHARE`] of the sweep's spread about its centroid: a fit fails, or misses its
/// points beyond that share, only for points that far off (nearer ones are the sweep's own
/// wander, which the held joints' correction handles).
fn floor_mm(points: &[Point3<f64>], noise_mm: f64) -> f64 {
    (FAR_OUT * noise_mm).max(ABSURD_SHARE * rms_spread(points) * 1e3)
}

/// A fitted path: each point's distance from it \[mm\] and its place along it (rad or m).
struct Placed {
    distance_mm: Vec<f64>,
    along: Vec<f64>,
}

/// The points' distances from, and places along, the circle (line) through the `kept` ones.
fn place(points: &[Point3<f64>], kept: &[usize], kind: JointKind) -> Option<Placed> {
    let sub: Vec<Point3<f64>> = kept.iter().map(|&i| points[i]).collect();
    match kind {
        JointKind::Revolute => {
            let c = fit_circle(&sub).ok()?;
            let n = c.normal.into_inner();
            let (distance_mm, along) = points
                .iter()
                .map(|p| {
                    let d = p - c.centre;
                    let axial = d.dot(&n);
                    let inplane = d - axial * n;
                    let radial = inplane.norm() - c.radius;
                    (axial.hypot(radial) * 1e3, d.dot(&c.v).atan2(d.dot(&c.u)))
                })
                .unzip();
            Some(Placed { distance_mm, along })
        }
        JointKind::Prismatic => {
            let centroid = sub.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / sub.len() as f64;
            let scatter = sub.iter().fold(nalgebra::Matrix3::zeros(), |a, p| {
                a + (p.coords - centroid) * (p.coords - centroid).transpose()
            });
            let eig = scatter.symmetric_eigen();
            let dir = eig.eigenvectors.column(eig.eigenvalues.imax()).into_owned();
            let (distance_mm, along) = points
                .iter()
                .map(|p| {
                    let d = p.coords - centroid;
                    ((d - dir * d.dot(&dir)).norm() * 1e3, d.dot(&dir))
                })
                .unzip();
            Some(Placed { distance_mm, along })
        }
    }
}

/// The points set aside as off the path the others draw (module docs), and the path through
/// the rest with the fence; `None` when no path fits them. The path is first the one through
/// two or three of the points that the most points lie near (least median of distances,
/// Rousseeuw 1984, over a deterministic set of point tuples), so that gross points do not pull
/// it; then the one fitted to the points within the fence of that one.
fn off_path(points: &[Point3<f64>], kind: JointKind, noise_mm: f64) -> Option<(Vec<usize>, Placed, f64)> {
    let n = points.len();
    let floor = floor_mm(points, noise_mm);
    let tuples =
        (0..n).flat_map(|i| [(1, 2), (n / 3, 2 * n / 3), (n / 2, n / 4)].map(|(a, b)| [i, (i + a) % n, (i + b) % n]));
    let median = |d: &[f64]| quantile(d, 0.5, QuantileMethod::Linear);
    let best = tuples
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .filter_map(|t| {
            let used = match kind {
                JointKind::Revolute => &t[..],
                JointKind::Prismatic => &t[..2],
            };
            place(points, used, kind)
        })
        .min_by(|a, b| median(&a.distance_mm).total_cmp(&median(&b.distance_mm)))?;
    let first = fence(&best.distance_mm, ACROSS, floor);
    let near: Vec<usize> = (0..n).filter(|&i| best.distance_mm[i] <= first).collect();
    if 2 * near.len() < n || near.len() < MIN_POINTS {
        return None;
    }
    let placed = place(points, &near, kind)?;
    let kept: Vec<f64> = near.iter().map(|&i| placed.distance_mm[i]).collect();
    let limit = fence(&kept, ACROSS, floor);
    let off: Vec<usize> = (0..n).filter(|&i| placed.distance_mm[i] > limit).collect();
    (2 * off.len() < n).then_some((off, placed, limit))
}

/// Each place minus its command's (`slope` per unit of command), wrapped to a half turn about
/// their median for an arc, scaled to mm along the path (`scale`: the radius in mm, or 1e3).
fn offsets(along: &[f64], u: &[f64], slope: f64, kind: JointKind, scale: f64) -> Vec<f64> {
    let raw: Vec<f64> = along.iter().zip(u).map(|(a, u)| a - slope * u).collect();
    let wrap = |x: f64| match kind {
        JointKind::Revolute => (x + PI).rem_euclid(TAU) - PI,
        JointKind::Prismatic => x,
    };
    let reference = raw[0];
    let relative: Vec<f64> = raw.iter().map(|x| wrap(x - reference)).collect();
    let middle = quantile(&relative, 0.5, QuantileMethod::Linear);
    relative.iter().map(|x| wrap(x - middle) * scale).collect()
}

/// Why the joint's sweep `s` (one experiment's points) fits no arc (line) of a joint of
/// `kind` (module docs); `None` when its points show none of these causes.
pub(super) fn sweep_misfit(s: &SweepPoints<'_>, kind: JointKind, noise_mm: f64) -> Option<SweepMisfit> {
    if s.points.len() < MIN_POINTS {
        return None;
    }
    let (off, placed, limit) = off_path(s.points, kind, noise_mm)?;
    if !off.is_empty() {
        let points = off
            .iter()
            .map(|&i| s.outlier(i, placed.distance_mm[i], limit, noise_mm))
            .collect();
        return Some(SweepMisfit::OffPath {
            points,
            fence_mm: limit,
            kind,
        });
    }
    let scale = match kind {
        JointKind::Revolute => fit_circle(s.points).ok()?.radius * 1e3,
        JointKind::Prismatic => 1e3,
    };
    off_command(s, &placed.along, kind, (scale, noise_mm))
}

/// The findings of several sweeps of one joint as one: the points off their paths, else the
/// points off their commands, else the first sweep reordered.
pub(super) fn merged(findings: Vec<SweepMisfit>) -> Option<SweepMisfit> {
    let gather = |path: bool| {
        let mut all: Option<SweepMisfit> = None;
        for f in &findings {
            match (f, &mut all, path) {
                (SweepMisfit::OffPath { .. }, None, true) | (SweepMisfit::OffCommand { .. }, None, false) => {
                    all = Some(f.clone())
                }
                (
                    SweepMisfit::OffPath { points, fence_mm, .. },
                    Some(SweepMisfit::OffPath {
                        points: to,
                        fence_mm: at,
                        ..
                    }),
                    true,
                )
                | (
                    SweepMisfit::OffCommand { points, fence_mm, .. },
                    Some(SweepMisfit::OffCommand {
                        points: to,
                        fence_mm: at,
                        ..
                    }),
                    false,
                ) => {
                    to.extend(points.iter().cloned());
                    *at = at.max(*fence_mm);
                }
                _ => {}
            }
        }
        all
    };
    gather(true).or_else(|| gather(false)).or_else(|| {
        findings
            .into_iter()
            .find(|f| matches!(f, SweepMisfit::Reordered { .. }))
    })
}

/// The points whose place along the path is off their command's (module docs), or every point
/// in another order than the commands.
fn off_command(
    s: &SweepPoints<'_>,
    along: &[f64],
    kind: JointKind,
    (scale, noise_mm): (f64, f64),
) -> Option<SweepMisfit> {
    // The path's orientation is the fit's: a joint moves its target with or against it.
    let best = [1.0, -1.0]
        .into_iter()
        .map(|slope| offsets(along, s.u, slope, kind, scale))
        .min_by(|a, b| spread(a).total_cmp(&spread(b)))?;
    let magnitudes: Vec<f64> = best.iter().map(|d| d.abs()).collect();
    let floor = floor_mm(s.points, noise_mm);
    let limit = fence(&magnitudes, ALONG, floor);
    let moved: Vec<usize> = (0..best.len()).filter(|&i| magnitudes[i] > limit).collect();
    if !moved.is_empty() && 2 * moved.len() < best.len() {
        let points = moved
            .iter()
            .map(|&i| s.outlier(i, magnitudes[i], limit, noise_mm))
            .collect();
        return Some(SweepMisfit::OffCommand {
            points,
            fence_mm: limit,
            kind,
        });
    }
    // Most points off their commands' places (their fence then spans them all): in another
    // order, when their places sorted follow the commands sorted.
    let off = magnitudes.iter().filter(|m| **m > floor).count();
    (2 * off >= best.len() && in_sorted_order(along, s.u, kind, (scale, floor))).then_some(SweepMisfit::Reordered {
        moved: off,
        points: best.len(),
        kind,
    })
}

/// The median absolute value of `v`.
fn spread(v: &[f64]) -> f64 {
    let a: Vec<f64> = v.iter().map(|x| x.abs()).collect();
    quantile(&a, 0.5, QuantileMethod::Linear)
}

/// Whether the places `along` sorted follow the commands `u` sorted (either way) within
/// `floor` \[mm\]: the points lie where the commands put them, in another order.
fn in_sorted_order(along: &[f64], u: &[f64], kind: JointKind, (scale, floor): (f64, f64)) -> bool {
    let mut places: Vec<f64> = along.to_vec();
    places.sort_by(f64::total_cmp);
    if kind == JointKind::Revolute {
        // The arc starts after the widest gap between neighbouring places, round the circle.
        let n = places.len();
        let gap = |i: usize| (places[(i + 1) % n] - places[i]).rem_euclid(TAU);
        let widest = (0..n).max_by(|a, b| gap(*a).total_cmp(&gap(*b))).unwrap_or(0);
        let start = places[(widest + 1) % n];
        places = places.iter().map(|a| (a - start).rem_euclid(TAU)).collect();
        places.sort_by(f64::total_cmp);
    }
    let mut commands = u.to_vec();
    commands.sort_by(f64::total_cmp);
    [1.0, -1.0].into_iter().any(|slope| {
        let sorted: Vec<f64> = match slope > 0.0 {
            true => places.clone(),
            false => places.iter().rev().copied().collect(),
        };
        let d = offsets(&sorted, &commands, slope, kind, scale);
        let magnitudes: Vec<f64> = d.iter().map(|x| x.abs()).collect();
        // Put in order, every point is where its command puts it: within the floor itself, not
        // a fence of these few offsets' own quartiles.
        magnitudes.iter().all(|m| *m <= floor)
    })
}
