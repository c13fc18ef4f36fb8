//! Levenberg-Marquardt with Marquardt's column scaling and a forward-difference Jacobian
//! (Nocedal & Wright, Numerical Optimization, 2nd ed., sec. 10.3), and the parameter
//! covariance `sigma^2 (J^T J)^+` of the converged fit.

use nalgebra::{DMatrix, DVector};

/// A converged (or iteration-capped) least-squares fit.
#[derive(Clone, Debug, PartialEq)]
pub struct LsqFit {
    /// Parameters.
    pub params: Vec<f64>,
    /// Sum of squared residuals \[m^2\].
    pub ssr_m2: f64,
    /// Residual count (equations).
    pub equations: usize,
    /// `(J^T J)^+` at the solution (multiply by the per-coordinate noise variance).
    pub normal_inverse: DMatrix<f64>,
}

fn ssr(r: &[f64]) -> f64 {
    r.iter().map(|x| x * x).sum()
}

/// Forward-difference Jacobian of the PREDICTION (minus the residual) at `p`.
fn jacobian<F>(f: &F, p: &[f64], r0: &[f64], steps: &[f64]) -> Option<DMatrix<f64>>
where
    F: Fn(&[f64]) -> Option<Vec<f64>>,
{
    let mut j = DMatrix::zeros(r0.len(), p.len());
    let mut q = p.to_vec();
    for c in 0..p.len() {
        q[c] = p[c] + steps[c];
        let r = f(&q)?;
        q[c] = p[c];
        for i in 0..r0.len() {
            j[(i, c)] = -(r[i] - r0[i]) / steps[c];
        }
    }
    Some(j)
}

/// Pseudo-inverse of a symmetric positive semi-definite matrix (eigenvalues below `1e-12`
/// of the largest dropped: directions the data do not determine).
fn pinv_sym(a: &DMatrix<f64>) -> DMatrix<f64> {
    let e = a.clone().symmetric_eigen();
    let max = e.eigenvalues.iter().cloned().fold(0.0, f64::max);
    let mut inv = DMatrix::zeros(a.nrows(), a.ncols());
    for (i, &l) in e.eigenvalues.iter().enumerate() {
        if l > 1e-12 * max && l > 0.0 {
            let v = e.eigenvectors.column(i);
            inv += (v * v.transpose()) / l;
        }
    }
    inv
}

/// Minimises `|f(p)|^2` from `p0`; `f` returns residuals `measured - predicted` (or `None`
/// where the model is undefined: that step is rejected). Returns `None` when `f(p0)` fails.
pub fn levenberg_marquardt<F>(f: F, p0: &[f64], steps: &[f64], max_iterations: usize) -> Option<LsqFit>
where
    F: Fn(&[f64]) -> Option<Vec<f64>>,
{
    let mut p = p0.to_vec();
    let mut r = f(&p)?;
    let mut cost = ssr(&r);
    let mut lambda = 1e-3;
    let mut j = jacobian(&f, &p, &r, steps)?;
    for _ in 0..max_iterations {
        let jtj = j.transpose() * &j;
        let d: Vec<f64> = (0..p.len()).map(|i| jtj[(i, i)].sqrt().max(1e-300)).collect();
        let g = j.transpose() * DVector::from_column_slice(&r);
        let mut improved = false;
        for _ in 0..10 {
            let mut a = jtj.clone();
            for (i, di) in d.iter().enumerate() {
                a[(i, i)] += lambda * di * di;
            }
            let delta = pinv_sym(&a) * &g;
            let trial: Vec<f64> = p.iter().zip(delta.iter()).map(|(x, dx)| x + dx).collect();
            if let Some(rt) = f(&trial) {
                let ct = ssr(&rt);
                if ct <= cost {
                    let rel = (cost - ct) / cost.max(1e-300);
                    p = trial;
                    r = rt;
                    cost = ct;
                    lambda = (lambda / 10.0).max(1e-12);
                    improved = rel > 1e-10;
                    break;
                }
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
        j = jacobian(&f, &p, &r, steps)?;
    }
    let normal_inverse = pinv_sym(&(j.transpose() * &j));
    Some(LsqFit {
        params: p,
        ssr_m2: cost,
        equations: r.len(),
        normal_inverse,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn fits_an_exponential() {
        let xs: Vec<f64> = (0..20).map(|i| i as f64 * 0.1).collect();
        let ys: Vec<f64> = xs.iter().map(|x| 2.0 * (-1.3 * x).exp()).collect();
        let f = |p: &[f64]| Some(xs.iter().zip(&ys).map(|(x, y)| y - p[0] * (p[1] * x).exp()).collect());
        let fit = levenberg_marquardt(f, &[1.0, 0.0], &[1e-7, 1e-7], 100).unwrap();
        assert_relative_eq!(fit.params[0], 2.0, max_relative = 1e-5);
        assert_relative_eq!(fit.params[1], -1.3, max_relative = 1e-5);
    }
}
