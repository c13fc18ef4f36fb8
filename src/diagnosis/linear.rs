//! Linearised least squares of the diagnoser: the residuals of the calibrated model are
//! linear in the small refit and effect parameters (Gauss-Newton's model, Nocedal & Wright,
//! Numerical Optimization, 2nd ed., eq. 10.24), so every fit is one truncated-SVD solve on
//! the training rows ([`TruncatedSvd`]), and its
//! held-out residuals are a fixed linear map of the data: `r_h - X_h X_t^+ r_t`.

use crate::numerics::lsq::TruncatedSvd;
use nalgebra::{DMatrix, DVector};

/// Directions of the column-scaled training design whose singular value is below this
/// fraction of the largest are exact redundancies (central differences resolve about 1e-10):
/// they are dropped, not fitted.
pub const NULL_DIRECTION_TOLERANCE: f64 = 1e-7;

/// Central-difference sensitivity `X = d prediction / d p = -d residual / d p` at `p0` of a
/// residual function `f` (`measured - predicted`).
pub fn sensitivity<F>(f: F, p0: &[f64], steps: &[f64]) -> Option<DMatrix<f64>>
where
    F: Fn(&[f64]) -> Option<Vec<f64>>,
{
    let n = f(p0)?.len();
    let mut x = DMatrix::zeros(n, p0.len());
    let mut q = p0.to_vec();
    for c in 0..p0.len() {
        q[c] = p0[c] + steps[c];
        let plus = f(&q)?;
        q[c] = p0[c] - steps[c];
        let minus = f(&q)?;
        q[c] = p0[c];
        for i in 0..n {
            x[(i, c)] = -(plus[i] - minus[i]) / (2.0 * steps[c]);
        }
    }
    Some(x)
}

/// A linear least-squares fit `r_t ~ X_t p` on training rows, truncated to the identifiable
/// directions, and the map it induces on held-out rows.
#[derive(Clone, Debug)]
pub struct LinearFit {
    /// `p = solve * r_t` (parameters \[model units\]).
    solve: DMatrix<f64>,
    /// `X_h X_t^+`: the held-out prediction of the fit per training residual.
    pub heldout_from_train: DMatrix<f64>,
    /// `(X_t^T X_t)^+` on the kept directions (times the per-coordinate noise variance: the
    /// parameter covariance).
    pub normal_inverse: DMatrix<f64>,
    /// Left singular vectors of the kept directions (training rows): the span the fit absorbs.
    pub span: DMatrix<f64>,
    /// Kept directions.
    pub rank: usize,
}

impl LinearFit {
    /// Fits the design `x_train` (training rows) and maps onto `x_held` (held-out rows).
    pub fn new(x_train: &DMatrix<f64>, x_held: &DMatrix<f64>) -> Self {
        let svd = TruncatedSvd::new(x_train, NULL_DIRECTION_TOLERANCE);
        let normal_inverse = &svd.v_over_s * svd.v_over_s.transpose();
        let heldout_from_train = x_held * &svd.solve;
        LinearFit {
            solve: svd.solve,
            heldout_from_train,
            normal_inverse,
            span: svd.span,
            rank: svd.rank,
        }
    }

    /// The fitted parameters for training residuals `r_train`.
    pub fn params(&self, r_train: &DVector<f64>) -> DVector<f64> {
        &self.solve * r_train
    }

    /// Held-out residuals after the fit, for data columns split into training and held-out
    /// rows (one column per data set).
    pub fn heldout(&self, train: &DMatrix<f64>, held: &DMatrix<f64>) -> DMatrix<f64> {
        held - &self.heldout_from_train * train
    }

    /// Fraction of the norm of `x` (training rows) outside the fit's span: how much of a
    /// signature the fit cannot absorb.
    pub fn outside_fraction(&self, x: &DMatrix<f64>) -> f64 {
        let total = x.norm();
        if total == 0.0 {
            return 0.0;
        }
        let inside = &self.span * (self.span.transpose() * x);
        (x - inside).norm() / total
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn drops_a_redundant_column_and_fits_the_rest() {
        // Columns 0 and 1 identical (a redundancy), column 2 independent.
        let xs: Vec<f64> = (0..12).map(|i| i as f64 * 0.25).collect();
        let x = DMatrix::from_fn(12, 3, |r, c| if c < 2 { 1.0 } else { xs[r] });
        let y = DVector::from_fn(12, |r, _| 2.0 + 0.5 * xs[r]);
        let fit = LinearFit::new(&x, &x);
        assert_eq!(fit.rank, 2);
        let p = fit.params(&y);
        assert_relative_eq!(p[0] + p[1], 2.0, max_relative = 1e-10);
        assert_relative_eq!(p[2], 0.5, max_relative = 1e-10);
        let held = fit.heldout(
            &DMatrix::from_column_slice(12, 1, y.as_slice()),
            &DMatrix::from_column_slice(12, 1, y.as_slice()),
        );
        assert!(held.norm() < 1e-10 * y.norm());
        assert!(fit.outside_fraction(&DMatrix::from_fn(12, 1, |r, _| xs[r] * xs[r])) > 0.0);
        assert!(fit.outside_fraction(&DMatrix::from_fn(12, 1, |r, _| 3.0 - xs[r])) < 1e-10);
    }

    #[test]
    fn sensitivity_matches_a_linear_model() {
        let f = |p: &[f64]| Some(vec![1.0 - 2.0 * p[0], 3.0 - p[0] - 4.0 * p[1]]);
        let x = sensitivity(f, &[0.1, 0.2], &[1e-6, 1e-6]).unwrap();
        assert_relative_eq!(
            x,
            DMatrix::from_row_slice(2, 2, &[2.0, 0.0, 1.0, 4.0]),
            max_relative = 1e-8
        );
    }
}
