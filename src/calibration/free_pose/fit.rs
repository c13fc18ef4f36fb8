//! The least-squares fit of the free-pose model and its outlier test.

use super::FreePoseError;
use super::model::FreePoseModel;
use super::poses::FreePoses;
use crate::calibration::refine::RefitParameter;
use crate::numerics::lsq::{LmOptions, LsqError, inverse_normal, levenberg_marquardt};
use crate::numerics::stats::f_upper_quantile;
use crate::robot::Controller;
use nalgebra::{DMatrix, DVector, Point3, Vector3};

/// Levenberg-Marquardt steps at most.
const MAX_ITERATIONS: usize = 200;

/// The run ends where the remaining Gauss-Newton step would lower the cost by at most this
/// fraction of the starting cost per measured coordinate (module docs of
/// [`crate::numerics::lsq::LmOptions::negligible_decrease`]; with the noise at most the start's
/// RMS, a step below 1e-5 of a standard deviation).
const NEGLIGIBLE_DECREASE: f64 = 1e-8;

/// What every fit of one calibration shares.
pub(super) struct Problem<'a> {
    /// The controller (nominal couplings).
    pub controller: &'a Controller,
    /// The measured poses.
    pub poses: &'a FreePoses,
    /// The parameter layout.
    pub layout: &'a [RefitParameter],
    /// The description's tool targets (by id) in the nominal tool frame \[m\].
    pub description_targets_m: Vec<nalgebra::Point3<f64>>,
}

/// A converged fit.
#[derive(Clone, Debug)]
pub(super) struct Fitted {
    /// The fitted model.
    pub model: FreePoseModel,
    /// Residual `measured - predicted` at the fit \[m\], 3 rows a point of the fitted poses.
    pub residual: DVector<f64>,
    /// `d residual / d parameter` of the fitted columns at the fit.
    pub jacobian: DMatrix<f64>,
    /// Levenberg-Marquardt steps taken.
    pub iterations: usize,
}

impl Fitted {
    /// RMS 3-D distance of the points \[m\].
    pub fn rms_m(&self) -> f64 {
        (self.residual.norm_squared() / (self.residual.len() / 3).max(1) as f64).sqrt()
    }

    /// Degrees of freedom `3 points - parameters`.
    pub fn dof(&self) -> usize {
        self.residual.len().saturating_sub(self.jacobian.ncols())
    }

    /// Per-coordinate variance from the residuals, `rss / dof` \[m^2\] (`None` without dof).
    pub fn variance(&self) -> Option<f64> {
        (self.dof() > 0).then(|| self.residual.norm_squared() / self.dof() as f64)
    }

    /// The parameters' covariance `s^2 (J^T J)^-1` with `s^2` the per-coordinate variance.
    pub fn covariance(&self, variance: f64) -> Result<DMatrix<f64>, FreePoseError> {
        Ok(inverse_normal(&self.jacobian, "free-pose calibration")? * variance)
    }
}

/// Fits the parameters `columns` of `start` to the poses `which` by Levenberg-Marquardt
/// (the program's one least-squares loop) with the analytic Jacobian.
pub(super) fn fit(
    problem: &Problem<'_>,
    start: &FreePoseModel,
    which: &[usize],
    columns: &[usize],
) -> Result<Fitted, FreePoseError> {
    let eval = |m: &FreePoseModel| -> Result<(DVector<f64>, DMatrix<f64>), FreePoseError> {
        m.residuals_and_jacobian(problem.controller, problem.poses, which, problem.layout, columns)
            .map_err(|u| u.error(problem.poses))
    };
    let first = eval(start)?;
    let per_coordinate = first.0.norm_squared() / first.0.len().max(1) as f64;
    let options = LmOptions {
        negligible_decrease: Some(NEGLIGIBLE_DECREASE * per_coordinate),
        ..LmOptions::marquardt("free-pose calibration", MAX_ITERATIONS)
    };
    let apply = |m: &FreePoseModel, d: &DVector<f64>| Ok::<_, FreePoseError>(m.moved(problem.layout, columns, d));
    let out = levenberg_marquardt(start.clone(), &options, eval, apply)?.converged("free-pose calibration", None)?;
    Ok(Fitted {
        model: out.state,
        residual: out.residual,
        jacobian: out.jacobian,
        iterations: out.iterations,
    })
}

/// The family-wise false-alarm rate of the free poses' outlier test: on clean data about this
/// share of files has a pose flagged, the same footing as the sweep points' test
/// ([`crate::calibration::procedure::SWEEP_POINTS_FALSE_ALARM`]; measured in
/// `docs/validation.md`, "Outliers").
pub const FREE_POSES_FALSE_ALARM: f64 = crate::calibration::procedure::SWEEP_POINTS_FALSE_ALARM;

/// The poses nearest a pose whose residuals give its noise: an instrument's noise grows with
/// the distance (a tracker's or a theodolite's angles), so a pose is judged by the noise of its
/// neighbourhood; 20 poses of one point leave about 50 degrees of freedom.
const NOISE_NEIGHBOURS: usize = 20;

/// A pose whose points the fit does not explain.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Flag {
    /// The pose.
    pub pose: usize,
    /// RMS 3-D distance of its points \[m\].
    pub rms_m: f64,
    /// The RMS its points would have at the fence, with their leverage and their neighbours'
    /// noise \[m\].
    pub fence_m: f64,
}

/// The poses of `which` that the fit `model` of the poses `kept` (parameters `columns`) does not
/// explain. A pose's normalised residual is `r^T (I -+ H)^-1 r` over its `3 p` coordinates and
/// the noise per coordinate of its [`NOISE_NEIGHBOURS`] nearest kept poses but itself
/// (`H = J_i (J^T J)^-1 J_i^T`, its leverage: a pose in the fit pulls it towards itself,
/// `I - H`; a pose outside it adds the fit's own error, `I + H`): an externally studentised
/// residual. With the noise along one direction per point it is about `F(p, nu / 3)`
/// (Satterthwaite's `m = 1` of the sweep points' test), and the fence is its
/// `1 - FREE_POSES_FALSE_ALARM / poses` quantile. A pose is flagged beyond it and beyond
/// `tukey_m` too ([`outlier_fence`]): an effect the model lacks spreads the residuals with
/// heavier tails than the noise's (real data), and the far-out fence keeps the test from peeling
/// off the poses such an effect moves most; the flag's fence is the larger. No flag without
/// degrees of freedom to test.
pub(super) fn flag_outliers(
    problem: &Problem<'_>,
    model: &FreePoseModel,
    which: &[usize],
    kept: &[usize],
    columns: &[usize],
    tukey_m: f64,
) -> Result<Vec<Flag>, FreePoseError> {
    let Some(all) = tested(problem, model, which, kept, columns)? else {
        return Ok(vec![]);
    };
    let tail = FREE_POSES_FALSE_ALARM / which.len().max(1) as f64;
    Ok(all
        .iter()
        .filter_map(|t| judge(t, &all, problem, tail))
        .filter(|f| f.rms_m > tukey_m)
        .map(|f| Flag {
            fence_m: f.fence_m.max(tukey_m),
            ..f
        })
        .collect())
}

/// The poses `outside` (held out, or set aside before the fit) that the fit `model` of the poses
/// `kept` does not explain: [`flag_outliers`] with each of them outside the fit (studentised by
/// `I + H`) against the noise of the kept poses near it, and beyond Tukey's far-out fence of the
/// per-pose RMS of all of them.
pub(super) fn flag_outside(
    problem: &Problem<'_>,
    model: &FreePoseModel,
    kept: &[usize],
    outside: &[usize],
    columns: &[usize],
) -> Result<Vec<Flag>, FreePoseError> {
    if outside.is_empty() {
        return Ok(vec![]);
    }
    let which: Vec<usize> = kept.iter().chain(outside).copied().collect();
    let r = model
        .residuals(problem.controller, problem.poses, &which)
        .map_err(|u| u.error(problem.poses))?;
    let tukey = outlier_fence(&r, problem.poses, &which);
    let flags = flag_outliers(problem, model, &which, kept, columns, tukey)?;
    Ok(flags.into_iter().filter(|f| outside.contains(&f.pose)).collect())
}

/// Tukey's far-out fence ([`crate::numerics::stats::far_out_fence`]) of the per-pose RMS of
/// the fit's residual `residual` over the poses `which` \[m\].
pub(super) fn outlier_fence(residual: &DVector<f64>, poses: &FreePoses, which: &[usize]) -> f64 {
    crate::numerics::stats::far_out_fence(&pose_rms(residual, poses, which))
}

/// One pose of the test: its coordinates, whether the fit holds it, its own squared normalised
/// residual `r^T (I -+ H)^-1 r` (`None`: a pose that alone determines a parameter), its squared
/// residual, the degrees of freedom it leaves the fit (`3 p - tr H`) and its points' centroid.
struct Tested {
    pose: usize,
    coordinates: usize,
    inside: bool,
    normalised_sq: Option<f64>,
    sum_sq: f64,
    dof: f64,
    centroid: Point3<f64>,
}

/// The poses `which` tested against the fit `model` of `kept`; `None` without degrees of
/// freedom or with a singular design.
fn tested(
    problem: &Problem<'_>,
    model: &FreePoseModel,
    which: &[usize],
    kept: &[usize],
    columns: &[usize],
) -> Result<Option<Vec<Tested>>, FreePoseError> {
    let (residual, jacobian) = model
        .residuals_and_jacobian(problem.controller, problem.poses, which, problem.layout, columns)
        .map_err(|u| u.error(problem.poses))?;
    let mut kept_rows = Vec::new();
    let mut row = 0;
    for &i in which {
        let coordinates = 3 * problem.poses.poses[i].points_m.len();
        if kept.contains(&i) {
            kept_rows.extend(row..row + coordinates);
        }
        row += coordinates;
    }
    if kept_rows.len() <= jacobian.ncols() {
        return Ok(None);
    }
    let Ok(c) = inverse_normal(&jacobian.select_rows(&kept_rows), "free-pose outlier test") else {
        return Ok(None);
    };
    let mut row = 0;
    let poses = which
        .iter()
        .map(|&i| {
            let pose = &problem.poses.poses[i];
            let n = 3 * pose.points_m.len();
            let j = jacobian.rows(row, n);
            let r = residual.rows(row, n).into_owned();
            row += n;
            let h = j * &c * j.transpose();
            let inside = kept.contains(&i);
            let a = if inside {
                DMatrix::identity(n, n) - &h
            } else {
                DMatrix::identity(n, n) + &h
            };
            let sum: Vector3<f64> = pose.points_m.iter().map(|p| p.1.coords).sum();
            Tested {
                pose: i,
                coordinates: n,
                inside,
                normalised_sq: a.cholesky().map(|ch| r.dot(&ch.solve(&r))),
                sum_sq: r.norm_squared(),
                dof: n as f64 - h.trace(),
                centroid: Point3::from(sum / pose.points_m.len().max(1) as f64),
            }
        })
        .collect();
    Ok(Some(poses))
}

/// The flag of `t` at the upper tail `tail`, judged by the noise of its [`NOISE_NEIGHBOURS`]
/// nearest kept poses of its setup (by their points' centroid). The noise is taken along one
/// direction per point (`m = 1` of the sweep points' test, the heaviest tail): a theodolite
/// pair's depth error lies along a line of sight that turns with the pose, which no
/// neighbourhood's scatter resolves (with the scatter's `m`, 2 of 64 clean files lost a pose).
fn judge(t: &Tested, all: &[Tested], problem: &Problem<'_>, tail: f64) -> Option<Flag> {
    let d = t.normalised_sq?;
    let setup = problem.poses.poses[t.pose].setup;
    let mut others: Vec<&Tested> = all
        .iter()
        .filter(|o| o.inside && o.pose != t.pose && problem.poses.poses[o.pose].setup == setup)
        .collect();
    others.sort_by(|a, b| {
        (a.centroid - t.centroid)
            .norm()
            .total_cmp(&(b.centroid - t.centroid).norm())
    });
    others.truncate(NOISE_NEIGHBOURS);
    let (sum_sq, dof) = others.iter().fold((0.0, 0.0), |(s, f), o| (s + o.sum_sq, f + o.dof));
    if dof < 1.0 || sum_sq <= 0.0 {
        return None;
    }
    let n = t.coordinates as f64;
    let ratio = d / n / (sum_sq / dof);
    let fence = f_upper_quantile(tail, n / 3.0, dof / 3.0);
    let rms_m = (3.0 * t.sum_sq / n).sqrt();
    (ratio > fence).then(|| Flag {
        pose: t.pose,
        rms_m,
        fence_m: rms_m * (fence / ratio).sqrt(),
    })
}

/// The RMS 3-D distance of each pose's points \[m\].
pub(super) fn pose_rms(residual: &DVector<f64>, poses: &FreePoses, which: &[usize]) -> Vec<f64> {
    let mut row = 0;
    which
        .iter()
        .map(|&i| {
            let coordinates = 3 * poses.poses[i].points_m.len();
            let r = residual.rows(row, coordinates);
            row += coordinates;
            (r.norm_squared() / (coordinates / 3) as f64).sqrt()
        })
        .collect()
}

impl From<LsqError> for FreePoseError {
    fn from(e: LsqError) -> Self {
        FreePoseError::Fit(e)
    }
}
