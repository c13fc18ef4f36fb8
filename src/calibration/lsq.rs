//! Small dense least-squares helpers shared by the fits: a Levenberg-Marquardt loop
//! (Marquardt's diagonal scaling, Nocedal & Wright section 10.3), a Gauss-Newton step and
//! covariance (Cholesky of the normal equations when well conditioned, else SVD), and
//! column-scaled condition numbers.

use nalgebra::{DMatrix, DVector};

use super::CalibrationError;

/// Largest column-scaled condition number a step is solved at.
pub(crate) const MAX_CONDITION: f64 = 1e12;

/// Largest 1-norm condition number of the column-scaled normal matrix `N = S^-1 J^T J S^-1`
/// inverted by Cholesky: `cond_2(N) <= cond_1(N)` for a symmetric `N` and `cond_2(J)^2 =
/// cond_2(N)`, so below it `J` has condition <= 1e4 and forming `N` costs at most ~1e-8 of
/// relative accuracy (normal equations against QR/SVD: Golub & Van Loan, *Matrix Computations*,
/// sec. 5.3);
/// above it the SVD of `J` is used, which also measures the exact condition number.
const CHOLESKY_MAX_CONDITION: f64 = 1e8;

/// Scale of each column (its 2-norm, or 1 for a zero column).
fn column_scales(j: &DMatrix<f64>) -> DVector<f64> {
    DVector::from_iterator(
        j.ncols(),
        j.column_iter().map(|c| {
            let n = c.norm();
            if n > 0.0 { n } else { 1.0 }
        }),
    )
}

/// `J^T J` for a tall, thin `J`: dot products of its (contiguous) columns for the upper
/// triangle only, mirrored; no transposed copy.
pub(crate) fn gram(j: &DMatrix<f64>) -> DMatrix<f64> {
    let m = j.ncols();
    let mut jtj = DMatrix::zeros(m, m);
    for c in 0..m {
        let col_c = j.column(c);
        for b in 0..=c {
            let x = j.column(b).dot(&col_c);
            jtj[(b, c)] = x;
            jtj[(c, b)] = x;
        }
    }
    jtj
}

/// The column-scaled normal matrix `N = S^-1 J^T J S^-1` (unit diagonal) and the scales `S`.
fn scaled_normal(j: &DMatrix<f64>) -> (DMatrix<f64>, DVector<f64>) {
    let mut n = gram(j);
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
/// accurate to ~1e-8 (their ratio below [`CHOLESKY_MAX_CONDITION`]), else from the SVD of
/// the scaled `J`.
pub(crate) fn scaled_condition_number(j: &DMatrix<f64>) -> f64 {
    let (n, _) = scaled_normal(j);
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
/// ([`CHOLESKY_MAX_CONDITION`]), else by the SVD of the column-scaled `J`; error if `J` is
/// ill-conditioned (scaled condition number >= [`MAX_CONDITION`]).
pub(crate) fn inverse_normal(j: &DMatrix<f64>, fit: &'static str) -> Result<DMatrix<f64>, CalibrationError> {
    let (normal, s) = scaled_normal(j);
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
fn inverse_normal_svd(j: &DMatrix<f64>, fit: &'static str) -> Result<DMatrix<f64>, CalibrationError> {
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
        return Err(CalibrationError::IllConditioned {
            fit,
            condition_number: cond,
        });
    }
    let vt = svd.v_t.as_ref().ok_or(CalibrationError::IllConditioned {
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

/// The Gauss-Newton step `delta = -(J^T J)^-1 J^T r` (eq. 5 with `e = -r`).
pub(crate) fn gauss_newton_step(
    j: &DMatrix<f64>,
    r: &DVector<f64>,
    fit: &'static str,
) -> Result<DVector<f64>, CalibrationError> {
    let inv = inverse_normal(j, fit)?;
    Ok(-(inv * j.tr_mul(r)))
}

/// `(x, (A^T A)^-1, residual)` of a linear least-squares problem.
pub(crate) type LinearSolution = (DVector<f64>, DMatrix<f64>, DVector<f64>);

/// Linear least squares `min |A x - y|`: `(x, (A^T A)^-1, residual)`.
pub(crate) fn linear_lsq(
    a: &DMatrix<f64>,
    y: &DVector<f64>,
    fit: &'static str,
) -> Result<LinearSolution, CalibrationError> {
    let inv = inverse_normal(a, fit)?;
    let x = &inv * a.tr_mul(y);
    let res = a * &x - y;
    Ok((x, inv, res))
}

/// What a Levenberg-Marquardt run ended with.
#[derive(Clone, Debug)]
pub(crate) struct LmOutcome<S> {
    /// Final state.
    pub state: S,
    /// Iterations (Jacobian evaluations) used.
    pub iterations: usize,
    /// Residual at the final state.
    pub residual: DVector<f64>,
    /// `J` at the final state.
    pub jacobian: DMatrix<f64>,
}

/// Levenberg-Marquardt with Marquardt scaling on a state `S` updated by `apply(state, delta)`
/// (lets callers re-anchor a local parameterisation after every step). `eval` returns the
/// residual `r` and `J = dr/d delta` at a state. Converged when the residual is orthogonal to
/// every column of `J` to 1e-9 (scale-free) or the cost stops decreasing to 1e-14.
pub(crate) fn levenberg_marquardt<S: Clone>(
    fit: &'static str,
    state0: S,
    max_iterations: usize,
    eval: impl Fn(&S) -> Result<(DVector<f64>, DMatrix<f64>), CalibrationError>,
    apply: impl Fn(&S, &DVector<f64>) -> Result<S, CalibrationError>,
) -> Result<LmOutcome<S>, CalibrationError> {
    let mut state = state0;
    let (mut r, mut j) = eval(&state)?;
    let mut cost = r.norm_squared();
    let mut lambda = 1e-3;
    for it in 1..=max_iterations {
        let g = j.tr_mul(&r);
        let jtj = gram(&j);
        let diag = jtj.diagonal().map(|d| if d > 0.0 { d } else { 1.0 });
        let cos_max = (0..g.len())
            .map(|k| g[k].abs() / (diag[k].sqrt() * cost.sqrt()))
            .fold(0.0, f64::max);
        if cost == 0.0 || cos_max < 1e-9 {
            return Ok(LmOutcome {
                state,
                iterations: it,
                residual: r,
                jacobian: j,
            });
        }
        let mut accepted = false;
        while lambda < 1e16 {
            let mut a = jtj.clone();
            for k in 0..a.nrows() {
                a[(k, k)] += lambda * diag[k];
            }
            let Some(ch) = a.cholesky() else {
                lambda *= 10.0;
                continue;
            };
            let delta = -ch.solve(&g);
            let trial = apply(&state, &delta)?;
            let (rt, jt) = eval(&trial)?;
            let ct = rt.norm_squared();
            if ct < cost {
                let small = cost - ct <= 1e-14 * cost;
                state = trial;
                r = rt;
                j = jt;
                cost = ct;
                lambda = (lambda / 10.0).max(1e-12);
                accepted = true;
                if small {
                    return Ok(LmOutcome {
                        state,
                        iterations: it,
                        residual: r,
                        jacobian: j,
                    });
                }
                break;
            }
            lambda *= 10.0;
        }
        if !accepted {
            // No decrease possible at any damping: a (numerical) minimum.
            return Ok(LmOutcome {
                state,
                iterations: it,
                residual: r,
                jacobian: j,
            });
        }
    }
    Err(CalibrationError::NotConverged {
        fit,
        iterations: max_iterations,
        residual_rms: (cost / r.len().max(1) as f64).sqrt(),
    })
}
