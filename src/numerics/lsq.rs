//! Dense least squares, the one implementation every fit of the program uses: the
//! Levenberg-Marquardt / Gauss-Newton loop ([`levenberg_marquardt`]: the calibration's arc and
//! coupling fits, the paper's axis estimators, inverse kinematics, the diagnosis's refit),
//! linear least squares, covariances `(J^T J)^-1` (Cholesky of the column-scaled normal
//! equations when well conditioned, else SVD), a rank-revealing truncated SVD, and
//! column-scaled condition numbers.

use nalgebra::{DMatrix, DVector};

/// Why a least-squares problem has no answer.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LsqError {
    /// The normal matrix of a least-squares step is singular or too ill-conditioned to solve.
    #[error("{fit}: ill-conditioned Jacobian (condition number {condition_number:.3e})")]
    IllConditioned {
        /// Which fit refused.
        fit: &'static str,
        /// 2-norm condition number of the (column-scaled) Jacobian.
        condition_number: f64,
    },
    /// An iterative fit did not converge.
    #[error("{fit}: not converged after {iterations} iterations (residual RMS {residual_rms:.3e})")]
    NotConverged {
        /// Which fit failed.
        fit: &'static str,
        /// Iterations performed.
        iterations: usize,
        /// RMS of the fitted residuals at the last iterate (input units).
        residual_rms: f64,
    },
}

/// Largest column-scaled condition number a step is solved at.
pub const MAX_CONDITION: f64 = 1e12;

/// Largest 1-norm condition number of the column-scaled normal matrix `N = S^-1 J^T J S^-1`
/// inverted by Cholesky: `cond_2(N) <= cond_1(N)` for a symmetric `N` and `cond_2(J)^2 =
/// cond_2(N)`, so below it `J` has condition <= 1e4 and forming `N` costs at most ~1e-8 of
/// relative accuracy (normal equations against QR/SVD: Golub & Van Loan, *Matrix Computations*,
/// sec. 5.3);
/// above it the SVD of `J` is used, which also measures the exact condition number.
const CHOLESKY_MAX_CONDITION: f64 = 1e8;

/// Scale of each column (its 2-norm, or 1 for a zero column).
pub fn column_scales(j: &DMatrix<f64>) -> DVector<f64> {
    DVector::from_iterator(
        j.ncols(),
        j.column_iter().map(|c| {
            let n = c.norm();
            if n > 0.0 { n } else { 1.0 }
        }),
    )
}

/// `J^T J` for a tall, thin `J`: dot products of its (contiguous) columns for the upper
/// triangle only, mirrored; no transposed copy. Each entry is nalgebra's `dot` of the two
/// columns bit for bit (summed on slices in its order).
pub fn gram(j: &DMatrix<f64>) -> DMatrix<f64> {
    let m = j.ncols();
    let mut jtj = DMatrix::zeros(m, m);
    for c in 0..m {
        for b in 0..=c {
            let x = column_dot(column(j, b), column(j, c));
            jtj[(b, c)] = x;
            jtj[(c, b)] = x;
        }
    }
    jtj
}

/// `J^T r`: nalgebra's `tr_mul` bit for bit ([`column_dot`] of each column with `r`).
fn gradient(j: &DMatrix<f64>, r: &DVector<f64>) -> DVector<f64> {
    DVector::from_iterator(
        j.ncols(),
        (0..j.ncols()).map(|c| column_dot(column(j, c), r.as_slice())),
    )
}

/// Column `c` of `j` as a slice (nalgebra stores a matrix column after column).
fn column(j: &DMatrix<f64>, c: usize) -> &[f64] {
    &j.as_slice()[c * j.nrows()..(c + 1) * j.nrows()]
}

/// `a . b` summed in the order of nalgebra's `Matrix::dot` on a dynamic vector (eight partial
/// sums over blocks of eight entries, added pairwise 0+4, 1+5, 2+6, 3+7, then the tail), so
/// the same number bit for bit, on slices the compiler can vectorise (the eight sums are
/// independent; no reassociation).
fn column_dot(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len(), "dot product of columns of different lengths");
    let blocks = a.len() / 8 * 8;
    let (a8, a_tail) = a.split_at(blocks);
    let (b8, b_tail) = b.split_at(blocks);
    let mut acc = [0.0f64; 8];
    for (x, y) in a8.chunks_exact(8).zip(b8.chunks_exact(8)) {
        for k in 0..8 {
            acc[k] += x[k] * y[k];
        }
    }
    let mut res = 0.0;
    res += acc[0] + acc[4];
    res += acc[1] + acc[5];
    res += acc[2] + acc[6];
    res += acc[3] + acc[7];
    for (x, y) in a_tail.iter().zip(b_tail) {
        res += x * y;
    }
    res
}

/// The column-scaled normal matrix `N = S^-1 J^T J S^-1` (unit diagonal) and the scales `S`.
fn scaled_normal(j: &DMatrix<f64>, jtj: Option<DMatrix<f64>>) -> (DMatrix<f64>, DVector<f64>) {
    let mut n = jtj.unwrap_or_else(|| gram(j));
    let s = DVector::from_iterator(
        n.ncols(),
        n.diagonal().iter().map(|&d| if d > 0.0 { d.sqrt() } else { 1.0 }),
    );
    for c in 0..n.ncols() {
        for r in 0..n.nrows() {
            n[(r, c)] /= s[r] * s[c];
        }
    }
    (n, s)
}

/// 1-norm (largest absolute column sum).
fn norm1(m: &DMatrix<f64>) -> f64 {
    m.column_iter().map(|c| c.lp_norm(1)).fold(0.0, f64::max)
}

/// 2-norm condition number of `J` after scaling every column to unit length (invariant to
/// the parameters' units): from the eigenvalues of the scaled normal matrix when they are
/// accurate to ~1e-8 (their ratio below `CHOLESKY_MAX_CONDITION`, 1e8), else from the SVD of
/// the scaled `J`.
pub fn scaled_condition_number(j: &DMatrix<f64>) -> f64 {
    let (n, _) = scaled_normal(j, None);
    let ev = n.symmetric_eigenvalues();
    let (max, min) = (ev.max(), ev.min());
    if min > 0.0 && max / min < CHOLESKY_MAX_CONDITION {
        return (max / min).sqrt();
    }
    let s = column_scales(j);
    let mut js = j.clone();
    for (k, mut col) in js.column_iter_mut().enumerate() {
        col /= s[k];
    }
    let sv = js.singular_values();
    let max = sv.max();
    let min = sv.min();
    if min > 0.0 { max / min } else { f64::INFINITY }
}

/// `(J^T J)^-1`: by Cholesky of the column-scaled normal matrix when it is well conditioned
/// (`CHOLESKY_MAX_CONDITION`, 1e8), else by the SVD of the column-scaled `J`; error if `J` is
/// ill-conditioned (scaled condition number >= [`MAX_CONDITION`]).
pub fn inverse_normal(j: &DMatrix<f64>, fit: &'static str) -> Result<DMatrix<f64>, LsqError> {
    inverse_normal_given(j, None, fit)
}

/// [`inverse_normal`] with `J^T J` already at hand (`Some(gram(j))`, e.g.
/// [`LmOutcome::normal`]): the same arithmetic without forming it again.
pub fn inverse_normal_given(
    j: &DMatrix<f64>,
    jtj: Option<DMatrix<f64>>,
    fit: &'static str,
) -> Result<DMatrix<f64>, LsqError> {
    let (normal, s) = scaled_normal(j, jtj);
    let n = j.ncols();
    if let Some(ch) = normal.clone().cholesky() {
        let mut inv = ch.inverse();
        if norm1(&normal) * norm1(&inv) < CHOLESKY_MAX_CONDITION {
            for c in 0..n {
                for r in 0..n {
                    inv[(r, c)] /= s[r] * s[c];
                }
            }
            return Ok(inv);
        }
    }
    inverse_normal_svd(j, fit)
}

/// `(J^T J)^-1` by the SVD of the column-scaled `J`; error if it is ill-conditioned.
fn inverse_normal_svd(j: &DMatrix<f64>, fit: &'static str) -> Result<DMatrix<f64>, LsqError> {
    let s = column_scales(j);
    let mut js = j.clone();
    for (k, mut col) in js.column_iter_mut().enumerate() {
        col /= s[k];
    }
    let svd = js.svd(false, true);
    let sv = &svd.singular_values;
    let cond = if sv.min() > 0.0 {
        sv.max() / sv.min()
    } else {
        f64::INFINITY
    };
    if cond.is_nan() || cond >= MAX_CONDITION {
        return Err(LsqError::IllConditioned {
            fit,
            condition_number: cond,
        });
    }
    let vt = svd.v_t.as_ref().ok_or(LsqError::IllConditioned {
        fit,
        condition_number: cond,
    })?;
    let n = j.ncols();
    let mut inv = DMatrix::zeros(n, n);
    for (k, sk) in sv.iter().enumerate() {
        let v = vt.row(k).transpose();
        inv += &v * v.transpose() / (sk * sk);
    }
    for r in 0..n {
        for c in 0..n {
            inv[(r, c)] /= s[r] * s[c];
        }
    }
    Ok(inv)
}

/// The inverse of a symmetric matrix `h` (e.g. a cost's exact Hessian `J^T J + sum r_i
/// d2r_i`, which need not be positive definite away from a minimum): by the eigen-decomposition
/// of `S^-1 h S^-1`, `S = diag(sqrt|h_kk|)` (invariant to the parameters' units), `V diag(1 /
/// lambda) V^T`; error if that scaled matrix's condition number `max |lambda| / min |lambda|`
/// is at least [`MAX_CONDITION`] (as for `J`: the scaled normal matrix's condition is the
/// square of `J`'s, so this admits `J` up to 1e6).
pub fn inverse_symmetric(h: &DMatrix<f64>, fit: &'static str) -> Result<DMatrix<f64>, LsqError> {
    let n = h.nrows();
    let s: Vec<f64> = (0..n)
        .map(|k| {
            let d = h[(k, k)].abs();
            if d > 0.0 { d.sqrt() } else { 1.0 }
        })
        .collect();
    let scaled = DMatrix::from_fn(n, n, |r, c| h[(r, c)] / (s[r] * s[c]));
    let eigen = scaled.symmetric_eigen();
    let (max, min) = eigen
        .eigenvalues
        .iter()
        .fold((0.0f64, f64::INFINITY), |(a, b), l| (a.max(l.abs()), b.min(l.abs())));
    let cond = if min > 0.0 { max / min } else { f64::INFINITY };
    if cond.is_nan() || cond >= MAX_CONDITION {
        return Err(LsqError::IllConditioned {
            fit,
            condition_number: cond,
        });
    }
    let v = &eigen.eigenvectors;
    Ok(DMatrix::from_fn(n, n, |r, c| {
        let sum: f64 = (0..n).map(|k| v[(r, k)] * v[(c, k)] / eigen.eigenvalues[k]).sum();
        sum / (s[r] * s[c])
    }))
}

/// The pseudo-inverse of a symmetric positive semi-definite matrix `h` (a quadratic's Hessian
/// with directions it does not change along) by its eigen-decomposition `V diag(1 / lambda)
/// V^T`, the eigenvalues below `tolerance` times the largest taken as null directions (inverted
/// as 0, returned as unit vectors); `None` when an eigenvalue is below minus that (not
/// semi-definite), none is positive, or one is NaN.
pub fn pseudo_inverse_semidefinite(h: &DMatrix<f64>, tolerance: f64) -> Option<(DMatrix<f64>, Vec<DVector<f64>>)> {
    let n = h.nrows();
    let eigen = h.clone().symmetric_eigen();
    let largest = eigen.eigenvalues.iter().fold(0.0f64, |a, &l| a.max(l));
    let null_below = tolerance * largest;
    if largest.is_nan() || largest <= 0.0 || eigen.eigenvalues.iter().any(|&l| l.is_nan() || l < -null_below) {
        return None;
    }
    let v = &eigen.eigenvectors;
    let kept: Vec<usize> = (0..n).filter(|&k| eigen.eigenvalues[k] > null_below).collect();
    let inverse = DMatrix::from_fn(n, n, |r, c| {
        kept.iter().map(|&k| v[(r, k)] * v[(c, k)] / eigen.eigenvalues[k]).sum()
    });
    let null = (0..n)
        .filter(|k| !kept.contains(k))
        .map(|k| v.column(k).into_owned())
        .collect();
    Some((inverse, null))
}

/// `(x, (A^T A)^-1, residual)` of a linear least-squares problem.
pub type LinearSolution = (DVector<f64>, DMatrix<f64>, DVector<f64>);

/// Linear least squares `min |A x - y|`: `(x, (A^T A)^-1, residual)`.
pub fn linear_lsq(a: &DMatrix<f64>, y: &DVector<f64>, fit: &'static str) -> Result<LinearSolution, LsqError> {
    let inv = inverse_normal(a, fit)?;
    let x = &inv * a.tr_mul(y);
    let res = a * &x - y;
    Ok((x, inv, res))
}

/// How each step of [`levenberg_marquardt`] is solved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Damping {
    /// Levenberg-Marquardt with Marquardt's scaling (Nocedal & Wright, *Numerical
    /// Optimization*, 2nd ed., sec. 10.3): `(J^T J + lambda diag(J^T J)) delta = -J^T r`,
    /// `lambda` from 1e-3, times 10 after a step that does not lower the cost, a tenth (down to
    /// 1e-12) after one that does.
    Marquardt,
    /// Gauss-Newton (Nocedal & Wright eq. 10.24, the paper's eq. 5): `delta = -J^+ r`. With
    /// `truncate_below: Some(t)` the pseudo-inverse drops the directions of the column-scaled
    /// `J` whose singular value is below `t` times the largest ([`TruncatedSvd`]: redundant
    /// parameters are left where they are); with `None` an ill-conditioned `J` is an error
    /// ([`inverse_normal`]). With `monotone` a step that does not lower the cost ends the run
    /// ([`Stop::NoDecrease`]); without it every step is taken (the paper's iteration, which
    /// ends on a small step).
    GaussNewton {
        /// Relative singular-value threshold of the rank-revealing solve, if any.
        truncate_below: Option<f64>,
        /// Take a step only when it lowers the cost.
        monotone: bool,
    },
}

/// Why a [`levenberg_marquardt`] run stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// The residual is orthogonal to every column of `J` to 1e-9 (scale-free), or zero.
    Gradient,
    /// An accepted step lowered the cost by no more than 1e-14 of it.
    CostStalled,
    /// No step lowers the cost (at any damping): a numerical minimum.
    NoDecrease,
    /// The step was negligible by the caller's [`LmOptions::small_step`].
    SmallStep,
    /// The caller's [`LmOptions::target`] was reached.
    Target,
    /// The iteration limit was reached first.
    MaxIterations,
}

/// A test on a residual or a step.
pub type VectorTest<'a> = dyn Fn(&DVector<f64>) -> bool + 'a;

/// Options of [`levenberg_marquardt`].
pub struct LmOptions<'a> {
    /// Names the fit in errors.
    pub fit: &'static str,
    /// Steps (Jacobian evaluations after the first) at most.
    pub max_iterations: usize,
    /// How a step is solved.
    pub damping: Damping,
    /// Only the first rows of the residual enter the cost; the rest (e.g. held-out data) are
    /// evaluated and returned, not fitted. `None`: every row.
    pub fitted_rows: Option<usize>,
    /// Stop as soon as the residual satisfies this (e.g. inverse kinematics within tolerance).
    pub target: Option<&'a VectorTest<'a>>,
    /// A step for which this holds is not taken and ends the run ([`Stop::SmallStep`]).
    pub small_step: Option<&'a VectorTest<'a>>,
    /// Marquardt damping only: the run ends ([`Stop::SmallStep`]) at an iterate whose
    /// Gauss-Newton step would lower the cost by at most this, i.e. whose Newton decrement
    /// (Boyd & Vandenberghe, *Convex Optimization*, sec. 9.5.1, with the Gauss-Newton Hessian
    /// `2 J^T J`) satisfies `lambda^2 / 2 = g^T (J^T J)^-1 g <= tol`, `g = J^T r`. For whitened
    /// residuals `g^T (J^T J)^-1 g` is the squared length of the remaining step in units of the
    /// parameters' standard deviations (the metric of the covariance `(J^T J)^-1`), so `tol =
    /// 1e-10` stops within about 1e-5 sigma of the optimum instead of iterating in the cost's
    /// rounding noise. `None`: no such rule.
    pub negligible_decrease: Option<f64>,
}

impl LmOptions<'_> {
    /// Marquardt damping, every row fitted, no target, no small-step rule.
    pub fn marquardt(fit: &'static str, max_iterations: usize) -> Self {
        LmOptions {
            fit,
            max_iterations,
            damping: Damping::Marquardt,
            fitted_rows: None,
            target: None,
            small_step: None,
            negligible_decrease: None,
        }
    }
}

/// What a [`levenberg_marquardt`] run ended with.
#[derive(Clone, Debug)]
pub struct LmOutcome<S> {
    /// Final state.
    pub state: S,
    /// Iterations (Jacobian evaluations after the first) used.
    pub iterations: usize,
    /// Residual at the final state (every row, fitted or not).
    pub residual: DVector<f64>,
    /// `J = dr/d delta` at the final state (every row).
    pub jacobian: DMatrix<f64>,
    /// Why the run stopped.
    pub stop: Stop,
    /// `J^T J` ([`gram`]) of the final Jacobian when the run formed it and every row is
    /// fitted (a stop by [`LmOptions::negligible_decrease`]), for [`inverse_normal_given`].
    pub normal: Option<DMatrix<f64>>,
}

impl<S> LmOutcome<S> {
    /// The outcome, or [`LsqError::NotConverged`] when the run only hit its iteration limit.
    pub fn converged(self, fit: &'static str, fitted_rows: Option<usize>) -> Result<Self, LsqError> {
        if self.stop != Stop::MaxIterations {
            return Ok(self);
        }
        let rows = fitted_rows.unwrap_or(self.residual.len()).min(self.residual.len());
        let cost = self.residual.rows(0, rows).norm_squared();
        Err(LsqError::NotConverged {
            fit,
            iterations: self.iterations,
            residual_rms: (cost / rows.max(1) as f64).sqrt(),
        })
    }
}

/// The fitted rows of a residual and its Jacobian (borrowed when every row is fitted).
fn fitted<'m>(
    r: &'m DVector<f64>,
    j: &'m DMatrix<f64>,
    rows: Option<usize>,
) -> (std::borrow::Cow<'m, DVector<f64>>, std::borrow::Cow<'m, DMatrix<f64>>) {
    use std::borrow::Cow;
    match rows {
        Some(n) if n < r.len() => (
            Cow::Owned(r.rows(0, n).into_owned()),
            Cow::Owned(j.rows(0, n).into_owned()),
        ),
        _ => (Cow::Borrowed(r), Cow::Borrowed(j)),
    }
}

/// Nonlinear least squares `min |r(state)|^2` on a state `S` moved by `apply(state, delta)`
/// (lets callers re-anchor a local parameterisation after every step); `eval` returns the
/// residual `r` and `J = dr/d delta` at a state. One loop for every damping ([`Damping`]); it
/// stops for the reasons of [`Stop`]. Hitting the iteration limit is not an error here (the
/// refit of the diagnosis takes a fixed number of steps): callers that need convergence ask
/// [`LmOutcome::converged`].
pub fn levenberg_marquardt<S: Clone, E: From<LsqError>>(
    state0: S,
    options: &LmOptions,
    eval: impl Fn(&S) -> Result<(DVector<f64>, DMatrix<f64>), E>,
    apply: impl Fn(&S, &DVector<f64>) -> Result<S, E>,
) -> Result<LmOutcome<S>, E> {
    let first = eval(&state0)?;
    levenberg_marquardt_from(state0, first, options, eval, apply)
}

/// [`levenberg_marquardt`] from a state whose residual and Jacobian the caller already has.
pub fn levenberg_marquardt_from<S: Clone, E: From<LsqError>>(
    state0: S,
    (r0, j0): (DVector<f64>, DMatrix<f64>),
    options: &LmOptions,
    eval: impl Fn(&S) -> Result<(DVector<f64>, DMatrix<f64>), E>,
    apply: impl Fn(&S, &DVector<f64>) -> Result<S, E>,
) -> Result<LmOutcome<S>, E> {
    let rows = options.fitted_rows;
    let cost_of = |r: &DVector<f64>| match rows {
        Some(n) if n < r.len() => r.rows(0, n).norm_squared(),
        _ => r.norm_squared(),
    };
    let (mut state, mut r, mut j) = (state0, r0, j0);
    let mut cost = cost_of(&r);
    let mut lambda = 1e-3;
    let reached = |r: &DVector<f64>| options.target.is_some_and(|t| t(r));
    let monotone = !matches!(options.damping, Damping::GaussNewton { monotone: false, .. });
    let done = |state: S, r: DVector<f64>, j: DMatrix<f64>, iterations: usize, stop: Stop| LmOutcome {
        state,
        iterations,
        residual: r,
        jacobian: j,
        stop,
        normal: None,
    };
    for it in 1..=options.max_iterations {
        if reached(&r) {
            return Ok(done(state, r, j, it - 1, Stop::Target));
        }
        let step = {
            let (rf, jf) = fitted(&r, &j, rows);
            Step::new(&jf, &rf, cost, options.damping, options.fit)?
        };
        let Some(mut step) = step else {
            return Ok(done(state, r, j, it, Stop::Gradient));
        };
        if options
            .negligible_decrease
            .is_some_and(|tol| step.gauss_newton_decrease().is_some_and(|d| d <= tol))
        {
            let normal = match (&step, rows) {
                (Step::Marquardt { jtj, .. }, None) => Some(jtj.clone()),
                _ => None,
            };
            return Ok(LmOutcome {
                normal,
                ..done(state, r, j, it - 1, Stop::SmallStep)
            });
        }
        let mut accepted = None;
        while let Some(delta) = step.solve(&mut lambda) {
            if options.small_step.is_some_and(|small| small(&delta)) {
                return Ok(done(state, r, j, it, Stop::SmallStep));
            }
            let trial = apply(&state, &delta)?;
            let (rt, jt) = eval(&trial)?;
            let ct = cost_of(&rt);
            if ct < cost || reached(&rt) || !monotone {
                let stalled = monotone && cost - ct <= 1e-14 * cost;
                (state, r, j, cost) = (trial, rt, jt, ct);
                lambda = (lambda / 10.0).max(1e-12);
                accepted = Some(stalled);
                break;
            }
            lambda *= 10.0;
        }
        match accepted {
            None => return Ok(done(state, r, j, it, Stop::NoDecrease)),
            Some(true) if !reached(&r) => return Ok(done(state, r, j, it, Stop::CostStalled)),
            Some(_) => {}
        }
    }
    let stop = if reached(&r) { Stop::Target } else { Stop::MaxIterations };
    Ok(done(state, r, j, options.max_iterations, stop))
}

/// One iteration's linear algebra: the normal equations (Marquardt) or the pseudo-inverse
/// (Gauss-Newton) of the fitted rows, solved for one damping after another.
enum Step {
    Marquardt {
        jtj: DMatrix<f64>,
        diag: DVector<f64>,
        g: DVector<f64>,
    },
    GaussNewton(Option<DVector<f64>>),
}

impl Step {
    /// `None` when the residual is already orthogonal to `J` ([`Stop::Gradient`]).
    fn new(
        j: &DMatrix<f64>,
        r: &DVector<f64>,
        cost: f64,
        damping: Damping,
        fit: &'static str,
    ) -> Result<Option<Self>, LsqError> {
        let g = gradient(j, r);
        let jtj = gram(j);
        let diag = jtj.diagonal().map(|d| if d > 0.0 { d } else { 1.0 });
        let cos_max = (0..g.len())
            .map(|k| g[k].abs() / (diag[k].sqrt() * cost.sqrt()))
            .fold(0.0, f64::max);
        if cost == 0.0 || cos_max < 1e-9 {
            return Ok(None);
        }
        Ok(Some(match damping {
            Damping::Marquardt => Step::Marquardt { jtj, diag, g },
            Damping::GaussNewton {
                truncate_below: None, ..
            } => Step::GaussNewton(Some(-(inverse_normal(j, fit)? * g))),
            Damping::GaussNewton {
                truncate_below: Some(t),
                ..
            } => Step::GaussNewton(Some(-TruncatedSvd::new(j, t).solve(r))),
        }))
    }

    /// The cost decrease `g^T (J^T J)^-1 g` the undamped (Gauss-Newton) step predicts
    /// (Marquardt only; `None` when `J^T J` is not positive definite).
    fn gauss_newton_decrease(&self) -> Option<f64> {
        match self {
            Step::GaussNewton(_) => None,
            Step::Marquardt { jtj, g, .. } => jtj.clone().cholesky().map(|ch| g.dot(&ch.solve(g))),
        }
    }

    /// The step at damping `lambda` (raised while the damped normal matrix is not positive
    /// definite); `None` when no further damping is worth trying.
    fn solve(&mut self, lambda: &mut f64) -> Option<DVector<f64>> {
        match self {
            Step::GaussNewton(delta) => delta.take(),
            Step::Marquardt { jtj, diag, g } => {
                while *lambda < 1e16 {
                    let mut a = jtj.clone();
                    for k in 0..a.nrows() {
                        a[(k, k)] += *lambda * diag[k];
                    }
                    if let Some(ch) = a.cholesky() {
                        return Some(-ch.solve(g));
                    }
                    *lambda *= 10.0;
                }
                None
            }
        }
    }
}

/// The rank-revealing least-squares solve of a design `X`: the SVD of `X` with every column
/// scaled to unit length, directions whose singular value is below a fraction of the largest
/// dropped (Golub & Van Loan, *Matrix Computations*, 4th ed., sec. 5.5.4).
#[derive(Clone, Debug)]
pub struct TruncatedSvd {
    /// `X^+ = V S^-1 U^T` on the kept directions, unscaled: `p = solve * y`.
    pub solve: DMatrix<f64>,
    /// `V S^-1` on the kept directions, unscaled (`(X^T X)^+ = v_over_s v_over_s^T`).
    pub v_over_s: DMatrix<f64>,
    /// Left singular vectors of the kept directions: the span the fit absorbs.
    pub span: DMatrix<f64>,
    /// Kept directions.
    pub rank: usize,
}

impl TruncatedSvd {
    /// The truncated SVD of `x`, keeping singular values above `relative_tolerance` times the
    /// largest.
    pub fn new(x: &DMatrix<f64>, relative_tolerance: f64) -> Self {
        let norms: Vec<f64> = (0..x.ncols()).map(|c| x.column(c).norm()).collect();
        Self::scaled(x, &norms, |s_max| relative_tolerance * s_max)
    }

    /// The truncated SVD of `x` with column `c` scaled by `1 / reference_norms[c]` (instead of
    /// its own length), keeping singular values above `absolute_tolerance`: the rank of a block
    /// of columns after something was projected out of them, measured against the columns as
    /// they were before (a column lying wholly inside the projected span keeps only rounding,
    /// which must be dropped, not scaled up).
    pub fn with_reference_norms(x: &DMatrix<f64>, reference_norms: &[f64], absolute_tolerance: f64) -> Self {
        Self::scaled(x, reference_norms, |_| absolute_tolerance)
    }

    /// The SVD of `x` with column `c` divided by `norms[c]` (1 where it is 0), keeping the
    /// singular values above `threshold(s_max)`.
    fn scaled(x: &DMatrix<f64>, norms: &[f64], threshold: impl Fn(f64) -> f64) -> Self {
        let p = x.ncols();
        let norms: Vec<f64> = norms.iter().map(|&n| if n > 0.0 { n } else { 1.0 }).collect();
        let mut scaled = x.clone();
        for (c, n) in norms.iter().enumerate() {
            scaled.column_mut(c).scale_mut(1.0 / n);
        }
        let svd = super::svd::thin_svd(scaled, true);
        let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
            unreachable!("SVD computed with U and V^T")
        };
        let s_max = svd.singular_values.iter().cloned().fold(0.0, f64::max);
        let below = threshold(s_max);
        let keep: Vec<usize> = (0..svd.singular_values.len())
            .filter(|&i| svd.singular_values[i] > below && svd.singular_values[i] > 0.0)
            .collect();
        let rank = keep.len();
        let mut span = DMatrix::zeros(x.nrows(), rank);
        let mut v_over_s = DMatrix::zeros(p, rank);
        for (j, &i) in keep.iter().enumerate() {
            span.column_mut(j).copy_from(&u.column(i));
            let s = svd.singular_values[i];
            for r in 0..p {
                v_over_s[(r, j)] = v_t[(i, r)] / s / norms[r];
            }
        }
        let solve = &v_over_s * span.transpose();
        TruncatedSvd {
            solve,
            v_over_s,
            span,
            rank,
        }
    }

    /// The minimum-norm (in scaled parameters) least-squares solution for data `y`.
    pub fn solve(&self, y: &DVector<f64>) -> DVector<f64> {
        &self.solve * y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `gram` and `gradient` are nalgebra's `tr_mul` bit for bit (the normal equations every
    /// fit solved before they were summed on slices), for every length around the blocks of
    /// eight and entries of mixed sizes and signs.
    #[test]
    fn gram_and_gradient_are_nalgebras_products_bit_for_bit() {
        for rows in 0..40 {
            let j = DMatrix::from_fn(rows, 5, |r, c| {
                ((7 * r + 3 * c) as f64 * 0.37).sin() * 10f64.powi(c as i32 - 2)
            });
            let r = DVector::from_fn(rows, |k, _| (k as f64 * 1.3).cos() - 0.2);
            let bits = |m: &DMatrix<f64>| m.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&gram(&j)), bits(&j.tr_mul(&j)), "rows {rows}");
            let g = gradient(&j, &r);
            assert_eq!(
                g.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                j.tr_mul(&r).iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                "rows {rows}"
            );
        }
    }

    /// `y = a exp(b x)` with unit (whitened) noise: residual and Jacobian at `p = (a, b)`.
    fn exponential(p: &DVector<f64>) -> Result<(DVector<f64>, DMatrix<f64>), LsqError> {
        let n = 12;
        let mut r = DVector::zeros(n);
        let mut j = DMatrix::zeros(n, 2);
        for k in 0..n {
            let x = 0.25 * k as f64;
            // Data from a = 2, b = -0.7 with a fixed pattern of unit-scale "noise".
            let y = 2.0 * (-0.7 * x).exp() * 40.0 + (1.7 * k as f64).sin();
            let e = (p[1] * x).exp();
            r[k] = p[0] * e * 40.0 - y;
            j[(k, 0)] = e * 40.0;
            j[(k, 1)] = p[0] * x * e * 40.0;
        }
        Ok((r, j))
    }

    /// The symmetric inverse of an indefinite matrix with parameters of very different units
    /// (scales 1e-3 to 1e3): `h h^-1 = I` to rounding of the scaled matrix (condition ~10,
    /// so 1e-12 has a margin of ~1e3); a singular one is refused as ill-conditioned.
    #[test]
    fn symmetric_inverse_of_an_indefinite_matrix_and_a_singular_one() {
        let core = DMatrix::from_row_slice(3, 3, &[2.0, 0.5, -0.3, 0.5, -1.5, 0.2, -0.3, 0.2, 1.0]);
        let s = [1e-3, 1.0, 1e3];
        let h = DMatrix::from_fn(3, 3, |r, c| core[(r, c)] * s[r] * s[c]);
        let inv = inverse_symmetric(&h, "test").unwrap();
        let scaled_product = DMatrix::from_fn(3, 3, |r, c| (&h * &inv)[(r, c)] * s[c] / s[r]);
        assert!((scaled_product - DMatrix::identity(3, 3)).abs().max() < 1e-12);
        let singular = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 4.0]);
        assert!(matches!(
            inverse_symmetric(&singular, "test"),
            Err(LsqError::IllConditioned { .. })
        ));
    }

    #[test]
    fn negligible_decrease_stops_within_its_tolerance_in_sigma_units() {
        let start = DVector::from_vec(vec![1.0, -0.2]);
        let apply = |s: &DVector<f64>, d: &DVector<f64>| Ok::<_, LsqError>(s + d);
        let full = levenberg_marquardt(start.clone(), &LmOptions::marquardt("test", 200), exponential, apply).unwrap();
        let tol = 1e-10;
        let options = LmOptions {
            negligible_decrease: Some(tol),
            ..LmOptions::marquardt("test", 200)
        };
        let early = levenberg_marquardt(start.clone(), &options, exponential, apply).unwrap();
        assert_eq!(early.stop, Stop::SmallStep);
        assert!(early.iterations <= full.iterations);
        // The distance to the fully iterated optimum in the covariance metric (sigma units):
        // the remaining Gauss-Newton step is at most sqrt(tol) long, and near the optimum it
        // is the distance to it up to second-order terms (a factor 2 of margin).
        let d = &early.state - &full.state;
        let mahalanobis = (d.transpose() * gram(&full.jacobian) * &d)[0].sqrt();
        assert!(mahalanobis <= 2.0 * tol.sqrt(), "{mahalanobis:e}");
        // A tolerance above the first step's decrease stops before any step.
        let coarse = LmOptions {
            negligible_decrease: Some(1e12),
            ..LmOptions::marquardt("test", 200)
        };
        let none = levenberg_marquardt(start.clone(), &coarse, exponential, apply).unwrap();
        assert_eq!((none.iterations, none.state), (0, start));
    }
}
