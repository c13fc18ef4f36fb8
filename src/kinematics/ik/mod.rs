//! Inverse kinematics for an arbitrary (calibrated, non-ideal) phi-model geometry.
//!
//! The general solver is a damped least-squares (Levenberg-Marquardt) iteration on the 6-D
//! tool pose error
//!
//! `e(q) = [p_target - p(q); rotvec(R_target R(q)^T)]` (position \[m\], orientation \[rad\]),
//!
//! whose derivative is `-J(q)` with `J` the geometric Jacobian ([`geometric_jacobian`]; exact
//! for the position rows, and for the orientation rows at `e = 0`), solved by the program's
//! one Levenberg-Marquardt loop (Marquardt's scaling, `crate::numerics::lsq`) until both
//! tolerances hold.
//!
//! A robot with fewer than six joints cannot reach every pose, and a calibrated model of one
//! generally misses the poses its nominal model reaches (a tilted axis turns its reachable
//! set). For such a model the iteration minimises `|e_p|^2 + (w |e_o|)^2` with the orientation
//! weighted by [`REDUCED_ORIENTATION_WEIGHT_M`] (position first: a positioning table or a SCARA
//! is asked for a point, its orientation about the axes it lacks is what it gives) and
//! converges at the least-squares pose: a stationary point of that cost with the position
//! error within [`REDUCED_POSITION_TOLERANCE_M`]. The report's errors are then the part of the
//! pose the robot cannot reach.
//!
//! A good seed matters for a 6R arm with up to 8 (or more) solutions: for the IRB/L6 class the
//! nominal model has a closed form ([`nominal_closed_form`]) whose branches seed the solver on
//! the actual model ([`solve_seeded_by_nominal`]).

mod closed_form;

pub use closed_form::{ClosedFormError, ClosedFormSolution, nominal_closed_form};

use super::chain::PhiModel;
use super::jacobian::geometric_jacobian;
use super::phi::JointKind;
use crate::numerics::lsq::{LmOptions, LsqError, Stop, levenberg_marquardt};
use nalgebra::{DMatrix, DVector, Isometry3, UnitQuaternion, Vector3, Vector6};
use std::f64::consts::PI;

/// Weight of the orientation error against the position error \[m/rad\] for a model with
/// fewer than six joints (module docs): 1 mrad counts as 1 um, so the position is reached first
/// and the orientation is the best the remaining freedom gives.
pub const REDUCED_ORIENTATION_WEIGHT_M: f64 = 1e-3;

/// The position error a model with fewer than six joints must reach at its least-squares
/// pose \[m\]: the weighted orientation error moves the optimum's position by about
/// `w^2 |e_o| * lever`, below 1e-8 m for `|e_o|` < 10 mrad and a 1 m lever, and 1 um is far
/// below any instrument's noise. A pose whose position the robot cannot reach (a two-axis
/// positioner asked for a point off its reachable surface) is not converged.
pub const REDUCED_POSITION_TOLERANCE_M: f64 = 1e-6;

/// Settings of the Levenberg-Marquardt IK solver.
#[derive(Clone, Debug, PartialEq)]
pub struct IkOptions {
    /// Stop when the tool position error is below this \[m\].
    pub position_tolerance_m: f64,
    /// ... and the orientation error (angle of `R_target R^T`) is below this \[rad\].
    pub orientation_tolerance_rad: f64,
    /// Maximum number of Jacobian evaluations.
    pub max_iterations: usize,
    /// Joint limits `[lower, upper]` per joint (rad or m); `None`: no limits.
    pub limits: Option<Vec<[f64; 2]>>,
    /// Project every iterate onto the limits (instead of only reporting violations).
    pub clamp_to_limits: bool,
}

impl Default for IkOptions {
    /// Tolerances of 1e-12 m and 1e-12 rad: about 100 times the rounding floor of a tool pose
    /// computed a few metres from the world origin (`5 m * 2.2e-16 * ~10 operations`).
    fn default() -> Self {
        Self {
            position_tolerance_m: 1e-12,
            orientation_tolerance_rad: 1e-12,
            max_iterations: 100,
            limits: None,
            clamp_to_limits: false,
        }
    }
}

/// How an IK iteration ended.
#[derive(Clone, Debug, PartialEq)]
pub struct IkReport {
    /// Jacobian evaluations used.
    pub iterations: usize,
    /// Final tool position error \[m\].
    pub position_error_m: f64,
    /// Final tool orientation error: the angle of `R_target R^T` \[rad\].
    pub orientation_error_rad: f64,
    /// Both errors are within the tolerances of [`IkOptions`].
    pub converged: bool,
    /// Joints (0-based) outside their limits at the final `q` (empty without limits).
    pub joints_outside_limits: Vec<usize>,
}

/// A converged IK solution.
#[derive(Clone, Debug, PartialEq)]
pub struct IkSolution {
    /// Joint values (rad or m); revolute joints wrapped into `(-pi, pi]`.
    pub q: Vec<f64>,
    /// How the iteration ended.
    pub report: IkReport,
}

/// Why inverse kinematics failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum IkError {
    /// The iteration stopped (stagnation or iteration cap) above the tolerances: the pose is
    /// out of reach, singular, or the seed was too far away.
    #[error(
        "IK did not converge after {iterations} iterations: position error {position_error_m:.3e} m, \
         orientation error {orientation_error_rad:.3e} rad"
    )]
    NotConverged {
        /// Jacobian evaluations used.
        iterations: usize,
        /// Best tool position error reached \[m\].
        position_error_m: f64,
        /// Best tool orientation error reached \[rad\].
        orientation_error_rad: f64,
    },
    /// A seed or limit vector has the wrong length.
    #[error("{what} has {found} entries, the model has {expected} joints")]
    WrongLength {
        /// Which input.
        what: &'static str,
        /// Number of joints of the model.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// The target pose or the seed holds a NaN or infinity.
    #[error("{what} is not finite")]
    NonFinite {
        /// Which input.
        what: &'static str,
    },
}

/// The rotation vector (axis times angle, angle in `[0, pi]`) of a unit quaternion, accurate
/// for tiny angles (unlike `2 acos(w)`, whose resolution near `w = 1` is only ~1e-8 rad).
pub fn rotation_vector(q: &UnitQuaternion<f64>) -> Vector3<f64> {
    let (w, v) = if q.w < 0.0 { (-q.w, -q.imag()) } else { (q.w, q.imag()) };
    let s = v.norm();
    if s < f64::MIN_POSITIVE {
        return 2.0 * v;
    }
    v * (2.0 * s.atan2(w) / s)
}

/// The 6-D pose error `[p_target - p; rotvec(R_target R^T)]` of `current` against `target`.
pub fn pose_error(target: &Isometry3<f64>, current: &Isometry3<f64>) -> Vector6<f64> {
    let dp = target.translation.vector - current.translation.vector;
    let dr = rotation_vector(&(target.rotation * current.rotation.inverse()));
    Vector6::new(dp.x, dp.y, dp.z, dr.x, dr.y, dr.z)
}

fn split_norms(e: &Vector6<f64>) -> (f64, f64) {
    (e.fixed_rows::<3>(0).norm(), e.fixed_rows::<3>(3).norm())
}

fn wrap_angle(x: f64) -> f64 {
    let y = x.rem_euclid(2.0 * PI);
    if y > PI { y - 2.0 * PI } else { y }
}

fn check_inputs(model: &PhiModel, target: &Isometry3<f64>, seed: &[f64], opts: &IkOptions) -> Result<(), IkError> {
    let n = model.dof();
    if seed.len() != n {
        return Err(IkError::WrongLength {
            what: "seed",
            expected: n,
            found: seed.len(),
        });
    }
    if let Some(l) = &opts.limits
        && l.len() != n
    {
        return Err(IkError::WrongLength {
            what: "limits",
            expected: n,
            found: l.len(),
        });
    }
    if seed.iter().any(|v| !v.is_finite()) {
        return Err(IkError::NonFinite { what: "seed" });
    }
    let t = target.to_homogeneous();
    if t.iter().any(|v| !v.is_finite()) {
        return Err(IkError::NonFinite { what: "target" });
    }
    Ok(())
}

fn clamp(q: &mut [f64], limits: &[[f64; 2]]) {
    for (v, l) in q.iter_mut().zip(limits) {
        *v = v.clamp(l[0], l[1]);
    }
}

fn outside_limits(q: &[f64], limits: Option<&Vec<[f64; 2]>>) -> Vec<usize> {
    limits.map_or_else(Vec::new, |l| {
        (0..q.len()).filter(|&k| q[k] < l[k][0] || q[k] > l[k][1]).collect()
    })
}

/// Levenberg-Marquardt ([`crate::numerics::lsq::levenberg_marquardt`]) on the tool pose
/// error from `seed`, stopping when both tolerances of `opts` hold; never fails on
/// non-convergence (see `report.converged`). Use [`solve_ik`] for a `Result`.
///
/// # Panics
/// If `seed.len()` (or the limits' length) differs from the model's number of joints, a
/// programming error; [`solve_ik`] checks its inputs and returns [`IkError`] instead.
pub fn ik_from_seed(model: &PhiModel, target: &Isometry3<f64>, seed: &[f64], opts: &IkOptions) -> IkSolution {
    let n = model.dof();
    let limits = opts.limits.as_ref().filter(|_| opts.clamp_to_limits);
    let mut q0 = seed.to_vec();
    if let Some(l) = limits {
        clamp(&mut q0, l);
    }
    // Fewer than six joints: the weighted least-squares pose (module docs).
    let reduced = n < 6;
    let w = if reduced { REDUCED_ORIENTATION_WEIGHT_M } else { 1.0 };
    let within = |e: &DVector<f64>| {
        let (p, o) = (e.fixed_rows::<3>(0).norm(), e.fixed_rows::<3>(3).norm());
        p <= opts.position_tolerance_m && o <= opts.orientation_tolerance_rad
    };
    // The pose error's derivative is -J (module docs); the orientation rows scaled by `w`.
    let eval = |q: &Vec<f64>| -> Result<(DVector<f64>, DMatrix<f64>), LsqError> {
        let mut e = pose_error(target, &model.world_from_tool(q));
        let mut j = -DMatrix::from_column_slice(6, n, geometric_jacobian(model, q).as_slice());
        e.fixed_rows_mut::<3>(3).scale_mut(w);
        j.rows_mut(3, 3).scale_mut(w);
        Ok((DVector::from_column_slice(e.as_slice()), j))
    };
    let apply = |q: &Vec<f64>, dq: &DVector<f64>| -> Result<Vec<f64>, LsqError> {
        let mut next: Vec<f64> = q.iter().zip(dq.iter()).map(|(a, b)| a + b).collect();
        if let Some(l) = limits {
            clamp(&mut next, l);
        }
        Ok(next)
    };
    let options = LmOptions {
        // An exact pose (or, reduced, an exact position with the orientation reachable).
        target: Some(&within),
        ..LmOptions::marquardt("inverse kinematics", opts.max_iterations)
    };
    // Marquardt damping never fails and neither do `eval` and `apply`; a failure would leave
    // the seed, reported as not converged.
    let Ok(outcome) = levenberg_marquardt(q0.clone(), &options, eval, apply) else {
        let e0 = pose_error(target, &model.world_from_tool(&q0));
        return finish(model, q0, e0, 0, opts, false);
    };
    let e = pose_error(target, &model.world_from_tool(&outcome.state));
    let stationary = matches!(outcome.stop, Stop::Gradient | Stop::CostStalled | Stop::NoDecrease);
    let converged = outcome.stop == Stop::Target
        || (reduced && stationary && e.fixed_rows::<3>(0).norm() <= REDUCED_POSITION_TOLERANCE_M);
    finish(model, outcome.state, e, outcome.iterations, opts, converged)
}

fn finish(
    model: &PhiModel,
    mut q: Vec<f64>,
    e: Vector6<f64>,
    iterations: usize,
    opts: &IkOptions,
    converged: bool,
) -> IkSolution {
    for (v, j) in q.iter_mut().zip(&model.joints) {
        if j.kind == JointKind::Revolute {
            *v = wrap_angle(*v);
        }
    }
    let (position_error_m, orientation_error_rad) = split_norms(&e);
    let joints_outside_limits = outside_limits(&q, opts.limits.as_ref());
    IkSolution {
        q,
        report: IkReport {
            iterations,
            position_error_m,
            orientation_error_rad,
            converged,
            joints_outside_limits,
        },
    }
}

/// Inverse kinematics of `model` for the tool pose `world_from_tool_target`, from `seed`, by
/// damped least squares (module docs). Errors on bad inputs and on non-convergence.
pub fn solve_ik(
    model: &PhiModel,
    world_from_tool_target: &Isometry3<f64>,
    seed: &[f64],
    opts: &IkOptions,
) -> Result<IkSolution, IkError> {
    check_inputs(model, world_from_tool_target, seed, opts)?;
    let s = ik_from_seed(model, world_from_tool_target, seed, opts);
    if s.report.converged {
        Ok(s)
    } else {
        Err(IkError::NotConverged {
            iterations: s.report.iterations,
            position_error_m: s.report.position_error_m,
            orientation_error_rad: s.report.orientation_error_rad,
        })
    }
}

/// IK on the `actual` (calibrated) model, seeded by the closed-form branches of the `nominal`
/// model ([`nominal_closed_form`]): branches within `opts.limits` are tried first, then the
/// others, each group nearest-to-zero first; the first one from which the iteration converges is returned. If the nominal
/// model has no closed-form solution (target out of its reach, or not of the IRB/L6 class),
/// the iteration starts from the middle of the limits (zero without limits), then from a
/// quarter of each range above and below it (+-pi/4 rad or m without limits).
pub fn solve_seeded_by_nominal(
    actual: &PhiModel,
    nominal: &PhiModel,
    world_from_tool_target: &Isometry3<f64>,
    opts: &IkOptions,
) -> Result<IkSolution, IkError> {
    // Without a closed form: the middle of the limits, then a quarter of the range to either
    // side (a SCARA's elbow is singular at the middle, straight), first converged wins.
    let fallback_seeds: Vec<Vec<f64>> = [0.0, 0.25, -0.25]
        .iter()
        .map(|f| match &opts.limits {
            Some(l) => l.iter().map(|[lo, hi]| 0.5 * (lo + hi) + f * (hi - lo)).collect(),
            None => vec![f * PI; actual.dof()],
        })
        .collect();
    check_inputs(actual, world_from_tool_target, &fallback_seeds[0], opts)?;
    let mut seeds: Vec<Vec<f64>> = nominal_closed_form(nominal, world_from_tool_target)
        .map(|branches| branches.into_iter().map(|b| b.q).collect())
        .unwrap_or_default();
    seeds.retain(|s| s.len() == actual.dof());
    // Branches within the limits first; among those, the one nearest the zero pose.
    let key = |s: &Vec<f64>| {
        let size: f64 = s.iter().map(|v| v * v).sum();
        (outside_limits(s, opts.limits.as_ref()).len(), size)
    };
    seeds.sort_by(|a, b| key(a).partial_cmp(&key(b)).unwrap_or(std::cmp::Ordering::Equal));
    seeds.extend(fallback_seeds);
    let mut best: Option<IkSolution> = None;
    for seed in &seeds {
        let s = ik_from_seed(actual, world_from_tool_target, seed, opts);
        if s.report.converged {
            return Ok(s);
        }
        let better = best.as_ref().is_none_or(|b| {
            s.report.position_error_m + s.report.orientation_error_rad
                < b.report.position_error_m + b.report.orientation_error_rad
        });
        if better {
            best = Some(s);
        }
    }
    let b = best.map(|b| b.report).unwrap_or(IkReport {
        iterations: 0,
        position_error_m: f64::INFINITY,
        orientation_error_rad: f64::INFINITY,
        converged: false,
        joints_outside_limits: Vec::new(),
    });
    Err(IkError::NotConverged {
        iterations: b.iterations,
        position_error_m: b.position_error_m,
        orientation_error_rad: b.orientation_error_rad,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::RobotDescription;

    fn model() -> PhiModel {
        RobotDescription::asea_irb6l().nominal_model()
    }

    #[test]
    fn bad_inputs_are_structured_errors() {
        let m = model();
        let t = m.world_from_tool(&[0.1; 6]);
        let opts = IkOptions::default();
        assert!(matches!(
            solve_ik(&m, &t, &[0.0; 5], &opts),
            Err(IkError::WrongLength {
                what: "seed",
                expected: 6,
                found: 5
            })
        ));
        let nan = [f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0];
        assert!(matches!(
            solve_ik(&m, &t, &nan, &opts),
            Err(IkError::NonFinite { what: "seed" })
        ));
        let short = IkOptions {
            limits: Some(vec![[-1.0, 1.0]; 2]),
            ..IkOptions::default()
        };
        assert!(matches!(
            solve_ik(&m, &t, &[0.0; 6], &short),
            Err(IkError::WrongLength { what: "limits", .. })
        ));
    }

    #[test]
    fn limits_are_reported_and_optionally_enforced() {
        let m = model();
        let q = [0.3, 0.2, -0.4, 0.5, 0.7, -1.0];
        let t = m.world_from_tool(&q);
        let tight = vec![[-0.1, 0.1]; 6];
        let report_only = IkOptions {
            limits: Some(tight.clone()),
            ..IkOptions::default()
        };
        let s = solve_ik(&m, &t, &[0.25, 0.15, -0.35, 0.45, 0.65, -0.95], &report_only).expect("converges");
        assert_eq!(s.report.joints_outside_limits, vec![0, 1, 2, 3, 4, 5]);
        let clamped = IkOptions {
            limits: Some(tight),
            clamp_to_limits: true,
            ..IkOptions::default()
        };
        let s = ik_from_seed(&m, &t, &[0.0; 6], &clamped);
        assert!(!s.report.converged);
        assert!(s.q.iter().all(|v| v.abs() <= 0.1));
    }

    #[test]
    fn rotation_vector_is_exact_for_tiny_angles() {
        let axis = Vector3::new(1.0, -2.0, 0.5).normalize();
        for angle in [1e-14, 1e-9, 0.3, 3.0] {
            let r = rotation_vector(&UnitQuaternion::from_scaled_axis(axis * angle));
            approx::assert_relative_eq!(r, axis * angle, max_relative = 1e-12);
        }
    }
}
