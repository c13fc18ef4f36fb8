//! The repeatability model of the truth robot: independent Gaussian jitter of each joint value
//! per execution, with sigmas calibrated to the paper's measured repeatability (section 4:
//! mean radial repeatable error 0.34 mm, mean orientation repeatable error 0.0033 rad of the
//! tool frame, between executions of the same command).
//!
//! Shape of the model: every joint but the last shares one sigma (`sigma_arm`), the last joint
//! has its own (`sigma_last`). Two numbers for two measured statistics. On the IRB/L6 the
//! tool-frame origin lies on axis 6, so `sigma_arm` alone sets the radial repeatability; since
//! the paper's orientation figure is ten times the radial one divided by the reach, the
//! orientation repeatability then has to come mostly from joint 6.

use crate::kinematics::{PhiModel, geometric_jacobian, point_jacobian};
use crate::robot::ModelError;
use nalgebra::{DVector, Matrix3, Matrix6xX, Point3, Vector3, Vector6};
use rand::{Rng, RngExt};
use rand_distr::{Distribution, StandardNormal};

/// Mean repeatable errors of the tool frame between two executions of one command.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RepeatabilityTarget {
    /// Mean distance between the two tool-frame origins \[mm\].
    pub mean_radial_mm: f64,
    /// Mean rotation angle between the two tool frames \[rad\].
    pub mean_orientation_rad: f64,
}

impl RepeatabilityTarget {
    /// The paper's measured repeatability of the ASEA IRB/L6 (section 4).
    pub const PAPER: Self = Self {
        mean_radial_mm: 0.34,
        mean_orientation_rad: 0.0033,
    };
}

/// Monte-Carlo estimate of the repeatability of a jitter model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RepeatabilityStats {
    /// Mean tool-origin distance between two executions \[mm\].
    pub mean_radial_mm: f64,
    /// Standard error of that mean \[mm\].
    pub radial_standard_error_mm: f64,
    /// Mean tool rotation angle between two executions \[rad\].
    pub mean_orientation_rad: f64,
    /// Standard error of that mean \[rad\].
    pub orientation_standard_error_rad: f64,
    /// Number of execution pairs.
    pub pairs: usize,
}

/// `count` joint vectors drawn uniformly within `limits` (internal units) from `rng`.
pub fn workspace_poses<R: Rng + ?Sized>(limits: &[[f64; 2]], count: usize, rng: &mut R) -> Vec<Vec<f64>> {
    (0..count)
        .map(|_| limits.iter().map(|[lo, hi]| rng.random_range(*lo..*hi)).collect())
        .collect()
}

/// Mean and standard error of `values`.
fn mean_and_se(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, (var / n).sqrt())
}

/// Full nonlinear Monte-Carlo of the repeatability: at each pose, `pairs_per_pose` pairs of
/// executions, each joint jittered by `sigmas` (forward kinematics of `model`, eq. A1).
pub fn repeatability_stats<R: Rng + ?Sized>(
    model: &PhiModel,
    poses: &[Vec<f64>],
    sigmas: &[f64],
    pairs_per_pose: usize,
    rng: &mut R,
) -> RepeatabilityStats {
    let mut radial = Vec::with_capacity(poses.len() * pairs_per_pose);
    let mut angle = Vec::with_capacity(radial.capacity());
    let jitter = |q: &[f64], rng: &mut R| -> Vec<f64> {
        q.iter()
            .zip(sigmas)
            .map(|(qk, s)| {
                let z: f64 = StandardNormal.sample(rng);
                qk + s * z
            })
            .collect()
    };
    for q in poses {
        for _ in 0..pairs_per_pose {
            let a = model.world_from_tool(&jitter(q, rng));
            let b = model.world_from_tool(&jitter(q, rng));
            radial.push((a.translation.vector - b.translation.vector).norm() * 1e3);
            angle.push(a.rotation.angle_to(&b.rotation));
        }
    }
    let (mean_radial_mm, radial_standard_error_mm) = mean_and_se(&radial);
    let (mean_orientation_rad, orientation_standard_error_rad) = mean_and_se(&angle);
    RepeatabilityStats {
        mean_radial_mm,
        radial_standard_error_mm,
        mean_orientation_rad,
        orientation_standard_error_rad,
        pairs: radial.len(),
    }
}

/// Linearised repeatability with fixed standard-normal draws (common random numbers, so the
/// means are deterministic, convex, even functions of the sigmas): the difference of two
/// executions is `J (sqrt(2) sigma .* z)` to first order in sigma, `J` the geometric Jacobian.
/// Each draw is split into the part scaled by `sigma_arm` and the part scaled by `sigma_last`,
/// for the tool-origin displacement \[m\] and the rotation vector \[rad\].
struct Linearised {
    /// `(position_arm, position_last, rotation_arm, rotation_last)` per draw (plain arrays:
    /// this inner loop runs some 10^7 times per calibration, also in debug builds).
    parts: Vec<[[f64; 3]; 4]>,
}

impl Linearised {
    fn new<R: Rng + ?Sized>(jacobians: &[Matrix6xX<f64>], pairs_per_pose: usize, rng: &mut R) -> Self {
        let mut parts = Vec::with_capacity(jacobians.len() * pairs_per_pose);
        for j in jacobians {
            let n = j.ncols();
            for _ in 0..pairs_per_pose {
                let mut arm = Vector6::zeros();
                let mut last = Vector6::zeros();
                for k in 0..n {
                    let z: f64 = StandardNormal.sample(rng);
                    let col: Vector6<f64> = j.column(k) * (std::f64::consts::SQRT_2 * z);
                    if k + 1 == n { last += col } else { arm += col }
                }
                let pick = |v: &Vector6<f64>, o: usize| [v[o], v[o + 1], v[o + 2]];
                parts.push([pick(&arm, 0), pick(&last, 0), pick(&arm, 3), pick(&last, 3)]);
            }
        }
        Self { parts }
    }

    /// `(mean radial [mm], mean orientation [rad])`.
    fn means(&self, sigma_arm: f64, sigma_last: f64) -> (f64, f64) {
        let (mut r, mut o) = (0.0, 0.0);
        let combine = |a: &[f64; 3], b: &[f64; 3]| {
            let x = [0, 1, 2].map(|i| a[i] * sigma_arm + b[i] * sigma_last);
            (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt()
        };
        for [pa, pl, ra, rl] in &self.parts {
            r += combine(pa, pl) * 1e3;
            o += combine(ra, rl);
        }
        let n = self.parts.len() as f64;
        (r / n, o / n)
    }
}

/// Smallest `s >= 0` with `f(s) = target` for a nondecreasing `f`, by bracketing and bisection;
/// `None` when `f(0)` already exceeds the target.
fn solve_increasing(f: impl Fn(f64) -> f64, target: f64, scale: f64) -> Option<f64> {
    if f(0.0) > target {
        return None;
    }
    let (mut lo, mut hi) = (0.0, scale);
    while f(hi) < target {
        lo = hi;
        hi *= 2.0;
        if hi > 1.0 {
            return None;
        }
    }
    let stop = crate::numerics::roots::Bisection::to_relative_width(1e-12);
    let [lo, hi] = crate::numerics::roots::bisect_infallible(lo, hi, stop, |mid| f(mid) < target);
    Some(0.5 * (lo + hi))
}

/// How a repeatability figure was observed: the distance between two measurements of one
/// tool point, each through an instrument with the given noise covariance.
pub struct ObservedThrough<'a> {
    /// The measured tool point, in the tool frame \[m\].
    pub point_in_tool_m: Point3<f64>,
    /// The instrument's noise covariance of a measured point at a world position \[m^2\]
    /// (`None` where the instrument cannot measure that point).
    pub covariance_m2: &'a dyn Fn(&Point3<f64>) -> Option<Matrix3<f64>>,
}

/// Calibrates ONE jitter sigma shared by every joint \[rad\] so that the mean distance between
/// two *observed* executions of the same command matches `mean_radial_mm` over `poses` (the
/// orientation repeatability then follows).
///
/// Model: the two observations of the tool point differ by `J_p sqrt(2) sigma z + sqrt(2) L w`
/// to first order in sigma (`J_p` the point Jacobian, eq. A1 differentiated; `L L^T` the
/// instrument covariance at the point; `z`, `w` standard normal), solved for sigma on
/// `pairs_per_pose` common random draws per pose (a deterministic, increasing function of sigma).
///
/// This is the model the paper robot ships with: the paper's repeatability (0.34 mm, 0.0033 rad)
/// was observed with its theodolites. The orientation figure is about what the instrument alone
/// gives for three targets 80 mm apart (`sqrt(2) * 0.19 mm / 80 mm`), so fitting it with joint
/// jitter (the two-sigma model below) would put an unphysical 2.8 mrad jitter on joint 6; and the
/// radial figure contains the instrument's share too, which the robot's jitter must not repeat.
/// Poses where the instrument cannot measure are skipped; an error if none is left or if the
/// instrument alone already exceeds the target.
pub fn calibrate_uniform_sigma<R: Rng + ?Sized>(
    model: &PhiModel,
    poses: &[Vec<f64>],
    mean_radial_mm: f64,
    observed: &ObservedThrough<'_>,
    pairs_per_pose: usize,
    rng: &mut R,
) -> Result<f64, ModelError> {
    let invalid = |message: String| ModelError::Invalid {
        field: "repeatability target".into(),
        message,
    };
    let n = model.dof();
    let point_in_last_link = model.last_link_from_tool * observed.point_in_tool_m;
    // Per draw: (robot part per unit sigma, instrument part) of the difference [m].
    let mut draws: Vec<(Vector3<f64>, Vector3<f64>)> = Vec::with_capacity(poses.len() * pairs_per_pose);
    for q in poses {
        let world = model.point_on_link(q, n - 1, &point_in_last_link);
        let Some(cov) = (observed.covariance_m2)(&world) else {
            continue;
        };
        let l = cov
            .cholesky()
            .ok_or_else(|| invalid(format!("instrument covariance at {world} is not positive definite")))?
            .l();
        let j = point_jacobian(model, q, n - 1, &point_in_last_link);
        for _ in 0..pairs_per_pose {
            let z = DVector::from_fn(n, |_, _| StandardNormal.sample(rng));
            let w = Vector3::from_fn(|_, _| StandardNormal.sample(rng));
            draws.push((&j * z * std::f64::consts::SQRT_2, l * w * std::f64::consts::SQRT_2));
        }
    }
    if draws.is_empty() || pairs_per_pose == 0 {
        return Err(ModelError::Invalid {
            field: "poses".into(),
            message: "at least one measurable pose and one pair per pose are needed".into(),
        });
    }
    let mean_mm = |s: f64| draws.iter().map(|(a, b)| (a * s + b).norm()).sum::<f64>() * 1e3 / draws.len() as f64;
    solve_increasing(mean_mm, mean_radial_mm, 1e-5).ok_or_else(|| {
        invalid(format!(
            "a mean radial repeatability of {mean_radial_mm} mm cannot be met (the instrument alone gives {:.4} mm)",
            mean_mm(0.0)
        ))
    })
}

/// Calibrates the jitter sigmas `[sigma_arm; N-1] ++ [sigma_last]` \[rad\] so that the mean
/// repeatable errors over `poses` match `target` (model in the module docs). Solved on the
/// linearised model with `pairs_per_pose` common random draws per pose (the linearisation
/// error is O(sigma), below 1e-3 relative here); check the result with
/// [`repeatability_stats`]. Errors if the target cannot be met with non-negative sigmas.
pub fn calibrate_repeatability_sigmas<R: Rng + ?Sized>(
    model: &PhiModel,
    poses: &[Vec<f64>],
    target: RepeatabilityTarget,
    pairs_per_pose: usize,
    rng: &mut R,
) -> Result<Vec<f64>, ModelError> {
    let n = model.dof();
    if poses.is_empty() || pairs_per_pose == 0 {
        return Err(ModelError::Invalid {
            field: "poses".into(),
            message: "at least one pose and one pair per pose are needed".into(),
        });
    }
    let jacobians: Vec<Matrix6xX<f64>> = poses.iter().map(|q| geometric_jacobian(model, q)).collect();
    let lin = Linearised::new(&jacobians, pairs_per_pose, rng);
    let infeasible = |what: &str| ModelError::Invalid {
        field: "repeatability target".into(),
        message: format!("cannot be met with this sigma model: {what}"),
    };
    let (mut arm, mut last) = (0.0, 0.0);
    // Alternate the two 1-D solves; each map is a contraction when the tool origin is near
    // the last axis (exact in two sweeps when it is on it).
    for _ in 0..50 {
        let new_arm = solve_increasing(|s| lin.means(s, last).0, target.mean_radial_mm, 1e-5)
            .ok_or_else(|| infeasible("the last joint alone exceeds the radial target"))?;
        let new_last = solve_increasing(|s| lin.means(new_arm, s).1, target.mean_orientation_rad, 1e-5)
            .ok_or_else(|| infeasible("the other joints alone exceed the orientation target"))?;
        let done = (new_arm - arm).abs() <= 1e-9 * new_arm && (new_last - last).abs() <= 1e-9 * new_last;
        (arm, last) = (new_arm, new_last);
        if done {
            break;
        }
    }
    let mut sigmas = vec![arm; n];
    sigmas[n - 1] = last;
    Ok(sigmas)
}
