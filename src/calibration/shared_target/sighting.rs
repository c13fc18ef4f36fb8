//! What the reference-pose test's files share (`shared_target` and its children `held` and
//! `backlash` import it; it imports none of them): a sweep's sighting of its target at the
//! reference pose ([`Sighting`]), the sweep's path in its command it is interpolated from
//! ([`Curve`]: a circle `c + a cos(b u) + d sin(b u)` for a turning joint, least squares on that
//! basis, the turn per command `b` by bisection of the residuals' slope; a line for a sliding
//! one), a turning sweep's axis and the backlash its first point shows ([`Turning`]: the axis is
//! `a x d` of the circle's coefficients), a sighting's variance and the noise test's bound
//! (the chi-square quantile at [`SHARED_TARGET_FALSE_ALARM`] with its dimensions across its
//! motion).

use crate::calibration::procedure::SIZE_TOLERANCE;
use crate::kinematics::JointKind;
use crate::numerics::roots::{Bisection, bisect_infallible};
use crate::numerics::stats::chi_square_quantile;
use nalgebra::{Matrix3, Vector3};

/// The test's false-alarm rate: a warning on consistent sweeps once in ten thousand files (the
/// rate of `calibrate`'s test of its own validation poses).
pub const SHARED_TARGET_FALSE_ALARM: f64 = 1e-4;

/// A turning sweep's fitted turn per command lies within this factor of the description's
/// either way: a command column halved or doubled is a unit slip the unit checks name.
const TURN_RATE_RANGE: f64 = 2.0;

/// Commands within this of the reference pose's are at it (file units: the tool frame's rule,
/// `docs/formats.md#experiments-and-targets`).
pub(super) const AT_REFERENCE: f64 = 1e-6;

/// One sighting of a shared target at the reference pose.
pub(super) struct Sighting {
    /// The experiment (`tool` observation or sweep).
    pub(super) experiment: String,
    /// Its lines in the file.
    pub(super) lines: Option<(u64, u64)>,
    /// The point \[mm\].
    pub(super) point: Vector3<f64>,
    /// Its coordinates' variance over a point's (leverage of the interpolation).
    pub(super) leverage: f64,
    /// The variance its point gets from the joints positioned once for it \[mm²\]
    /// (the parent's `held_variance_mm2`).
    pub(super) held_mm2: f64,
    /// The projection across the sweep's motion (identity for a measured point).
    pub(super) across: Matrix3<f64>,
    /// The swept joint (0: the tool observation).
    pub(super) joint: usize,
    /// A turning sweep's axis and the backlash its first point shows ([`Turning`]).
    pub(super) turning: Option<Turning>,
    /// The joints (0-based) the sweep holds at a constant command (none: the tool observation).
    pub(super) held: Vec<usize>,
}

/// The least squares of `points` on the basis `basis(u)` (3 functions of the command; a line's
/// unused third, zero at every command, padded with a unit diagonal): the coefficients (one row
/// per function), the inverse normal matrix and the residual sum of squares, or `None` when the
/// normal equations are singular.
fn basis_fit(
    u: &[f64],
    points: &[Vector3<f64>],
    basis: &dyn Fn(f64) -> Vector3<f64>,
) -> Option<(Matrix3<f64>, Matrix3<f64>, f64)> {
    let mut normal = Matrix3::zeros();
    let mut right = Matrix3::zeros();
    for (&v, p) in u.iter().zip(points) {
        let f = basis(v);
        normal += f * f.transpose();
        right += f * p.transpose();
    }
    if normal[(2, 2)] == 0.0 {
        normal[(2, 2)] = 1.0;
    }
    let inverse = normal.try_inverse()?;
    let coefficients = inverse * right;
    let rss: f64 = u
        .iter()
        .zip(points)
        .map(|(&v, p)| (p - coefficients.transpose() * basis(v)).norm_squared())
        .sum();
    Some((coefficients, inverse, rss))
}

/// A sweep's path in its command (`u` relative to the reference, internal units): a circle
/// `c + a cos(b u) + d sin(b u)` for a turning joint (its turn per command `b` the one of least
/// residuals within [`TURN_RATE_RANGE`] of 1), a line `c + d u` for a sliding one; the rows of
/// `coefficients` are `c`, `a` (a line: `d`) and `d` (a line: zero).
pub(super) struct Curve {
    pub(super) kind: JointKind,
    /// The turn per command (0 for a line).
    pub(super) b: f64,
    pub(super) coefficients: Matrix3<f64>,
    /// The inverse normal matrix of the least squares.
    inverse: Matrix3<f64>,
}

impl Curve {
    /// The path through `points` \[mm\] at the commands `u`; `None` when they do not fix one.
    pub(super) fn fit(u: &[f64], points: &[Vector3<f64>], kind: JointKind) -> Option<Curve> {
        let b = match kind {
            JointKind::Prismatic => 0.0,
            JointKind::Revolute => {
                let rss = |b: f64| basis_fit(u, points, &|v| circle(b, v)).map_or(f64::INFINITY, |f| f.2);
                let h = 1e-6;
                let least = |from: f64, to: f64| {
                    let stop = Bisection::to_width(1e-6);
                    let [lo, hi] = bisect_infallible(from, to, stop, |x| rss(x + h) < rss(x - h));
                    0.5 * (lo + hi)
                };
                let b = least(1.0 / TURN_RATE_RANGE, TURN_RATE_RANGE);
                // Beyond SIZE_TOLERANCE of the description's, an alias of the circle its
                // points do not fix (six points 144 deg apart over two turns fit one at 1.49
                // as well as at 1): the least residuals within that tolerance instead.
                match (b - 1.0).abs() > SIZE_TOLERANCE {
                    true => least(1.0 - SIZE_TOLERANCE, 1.0 + SIZE_TOLERANCE),
                    false => b,
                }
            }
        };
        let curve = Curve {
            kind,
            b,
            coefficients: Matrix3::zeros(),
            inverse: Matrix3::zeros(),
        };
        let (coefficients, inverse, _) = basis_fit(u, points, &|v| curve.basis(v))?;
        Some(Curve {
            coefficients,
            inverse,
            ..curve
        })
    }

    /// The basis functions at command `v`.
    fn basis(&self, v: f64) -> Vector3<f64> {
        match self.kind {
            JointKind::Prismatic => Vector3::new(1.0, v, 0.0),
            JointKind::Revolute => circle(self.b, v),
        }
    }

    /// The path's point at command `v` \[mm\].
    pub(super) fn point(&self, v: f64) -> Vector3<f64> {
        self.coefficients.transpose() * self.basis(v)
    }

    /// The path's direction of motion at command `v` \[mm per unit command\].
    pub(super) fn slope(&self, v: f64) -> Vector3<f64> {
        let derivative = match self.kind {
            JointKind::Prismatic => Vector3::new(0.0, 1.0, 0.0),
            JointKind::Revolute => Vector3::new(0.0, -self.b * (self.b * v).sin(), self.b * (self.b * v).cos()),
        };
        self.coefficients.transpose() * derivative
    }

    /// The point at command 0 (the reference), the interpolation's leverage there and the
    /// direction of motion.
    pub(super) fn at_reference(&self) -> (Vector3<f64>, f64, Vector3<f64>) {
        let at0 = self.basis(0.0);
        let leverage = (at0.transpose() * self.inverse * at0)[0];
        (self.point(0.0), leverage, self.slope(0.0))
    }
}

/// The circle's basis `(1, cos(b v), sin(b v))`.
fn circle(b: f64, v: f64) -> Vector3<f64> {
    Vector3::new(1.0, (b * v).cos(), (b * v).sin())
}

/// The variance \[mm²\] of a sighting's point at the noise `sigma2` of a coordinate: its
/// interpolation's and the joints' positioned once for it.
pub(super) fn variance(s: &Sighting, sigma2: f64) -> f64 {
    s.leverage * sigma2 + s.held_mm2
}

/// The noise test's bound on a sighting's offset over its standard deviation: the chi-square
/// quantile at [`SHARED_TARGET_FALSE_ALARM`] with its dimensions across its motion.
pub(super) fn noise_bound(s: &Sighting) -> f64 {
    chi_square_quantile(1.0 - SHARED_TARGET_FALSE_ALARM, s.across.trace().round()).sqrt()
}

/// A turning sweep's axis, and the backlash its first point shows.
pub(super) struct Turning {
    /// A point of the axis (the circle's centre) \[mm\].
    pub(super) centre: Vector3<f64>,
    /// The axis's unit direction, positive turn right-handed about it.
    pub(super) axis: Vector3<f64>,
    /// How far \[rad of the joint\] the first point, taken before the joint moved, runs ahead
    /// along the sweep's motion of the path of the others (`None`: not beyond the noise or
    /// not ahead; the first step not seen).
    pub(super) lead_rad: Option<f64>,
    /// The miss \[mm\] along the motion that lead is (its significance is judged at the noise).
    pub(super) lead_mm: f64,
}

impl Turning {
    /// The axis of the circle `curve` and, where `first` (the sweep's first step is its first
    /// point) and `u`, `points` hold enough points, the first point's lead.
    pub(super) fn of(curve: &Curve, (u, points): (&[f64], &[Vector3<f64>]), first: bool) -> Option<Turning> {
        if curve.kind != JointKind::Revolute {
            return None;
        }
        let [c, a, d] = [0, 1, 2].map(|i| curve.coefficients.row(i).transpose());
        let axis = a.cross(&d).try_normalize(1e-12)?;
        let (lead_rad, lead_mm) = match first && u.len() >= 6 {
            true => lead(u, points).unwrap_or((None, 0.0)),
            false => (None, 0.0),
        };
        Some(Turning {
            centre: c,
            axis,
            lead_rad,
            lead_mm,
        })
    }
}

/// The first point's miss along the sweep's motion of the circle through the others \[mm\],
/// and that miss in the joint's turn where it runs ahead (`None` when behind).
fn lead(u: &[f64], points: &[Vector3<f64>]) -> Option<(Option<f64>, f64)> {
    let rest = Curve::fit(&u[1..], &points[1..], JointKind::Revolute)?;
    let slope = rest.slope(u[0]) * (u[1] - u[0]).signum();
    let ahead = (points[0] - rest.point(u[0])).dot(&slope.try_normalize(1e-12)?);
    // The turn of the joint is the command's times the circle's turn per command.
    let turn = ahead / slope.norm() * rest.b;
    Some(((ahead > 0.0).then_some(turn), ahead))
}
