//! Cramer-Rao bound of a whole campaign: every measured point predicted from the complete
//! parameter vector (the calibrated model's and every nuisance the points depend on), with
//! the gauge freedoms of that vector handled explicitly.
//!
//! For isotropic Gaussian noise of standard deviation `sigma` per coordinate the Fisher
//! information is `F = J^T J / sigma^2`, `J = d prediction / d p` (Kay, *Fundamentals of
//! Statistical Signal Processing I*, eq. 3.31 with constant covariance). A parameter vector
//! with redundant parameters (a base placement and the first row, a joint's `phi` and the row's
//! `gamma`, ...) has a singular `F`: the points do not change along its null directions, so no
//! estimator can tell those parameter values apart. A linear function `c^T p` is still
//! estimable when `c` lies in the row space of `J` (orthogonal to every null direction); its
//! bound is then `c^T F^+ c` with the Moore-Penrose pseudo-inverse, the same for every
//! generalised inverse (Rao, *Linear Statistical Inference*, 2nd ed., sec. 4a.3; Stoica &
//! Marzetta, IEEE TSP 49(1), 2001, "Parameter estimation problems with singular information
//! matrices"). Here `c = e_k` (one parameter): estimable iff `P e_k = e_k` with
//! `P = J^+ J` the projector on the row space; a parameter that is not is reported as such,
//! never given a number.
//!
//! The null directions are found by the rank-revealing SVD of the column-scaled `J`
//! ([`TruncatedSvd`], threshold [`NULL_DIRECTION_TOLERANCE`] of the largest singular value:
//! central differences resolve about 1e-10, a real direction of a campaign sits far above).

use crate::calibration::refine::NULL_DIRECTION_TOLERANCE;
use crate::numerics::lsq::TruncatedSvd;
use nalgebra::DMatrix;

/// A parameter counts as estimable when the row-space projector moves its unit vector by less
/// than this (central differences leave about 1e-8 in a projector built from a
/// tolerance-1e-7 SVD; a parameter with any share in a null direction is moved by that share,
/// of order 0.1 to 1 for a true redundancy).
pub const ESTIMABLE_TOLERANCE: f64 = 1e-5;

/// The bound of every parameter of a campaign.
#[derive(Clone, Debug, PartialEq)]
pub struct CampaignBound {
    /// Per parameter: the bound on its variance (units of the parameter, squared), `None`
    /// where it is not estimable.
    pub variance: Vec<Option<f64>>,
    /// Per parameter: the length of the part of its unit vector outside the row space (0
    /// for an estimable parameter; its share in the null directions otherwise), column-scaled.
    pub null_share: Vec<f64>,
    /// Parameters.
    pub parameters: usize,
    /// Rank of `J`: `parameters - rank` unidentifiable directions.
    pub rank: usize,
    /// Measured coordinates (rows of `J`).
    pub coordinates: usize,
}

/// The bound of `J` (predictions' Jacobian, any sign) with isotropic noise `sigma` per
/// coordinate (module docs), for every parameter.
pub fn fisher_bound(j: &DMatrix<f64>, sigma: f64) -> CampaignBound {
    fisher_bound_of(j, sigma, &DMatrix::identity(j.ncols(), j.ncols()))
}

/// The bound of the linear functions `g p` (one per row of `g`) of the parameters of `J`
/// (module docs): `g_i F^+ g_i^T` where `g_i` lies in the row space of `J`, else `None`.
pub fn fisher_bound_of(j: &DMatrix<f64>, sigma: f64, g: &DMatrix<f64>) -> CampaignBound {
    let jw = j / sigma;
    let svd = TruncatedSvd::new(&jw, NULL_DIRECTION_TOLERANCE);
    let n = j.ncols();
    // `J^+ J`: the projector on the row space (identity on every estimable function).
    let projector = &svd.solve * &jw;
    let norms: Vec<f64> = (0..n).map(|c| jw.column(c).norm()).collect();
    let mut variance = Vec::with_capacity(g.nrows());
    let mut null_share = Vec::with_capacity(g.nrows());
    for row in g.row_iter() {
        // In the column-scaled parameters `p_s = D p` (the SVD's) the function is `D^-1 g`,
        // and `D P D^-1` is the orthogonal projector there.
        let gs = nalgebra::DVector::from_fn(n, |k, _| if norms[k] > 0.0 { row[k] / norms[k] } else { row[k] });
        let blind = (0..n).any(|k| norms[k] == 0.0 && row[k] != 0.0);
        // The orthogonal projection of `D^-1 g` on the row space: `D P D^-1 (D^-1 g)`.
        let projected = nalgebra::DVector::from_fn(n, |r, _| {
            norms[r]
                * (0..n)
                    .map(|k| projector[(r, k)] * gs[k] / norms[k].max(f64::MIN_POSITIVE))
                    .sum::<f64>()
        });
        let share = if blind {
            1.0
        } else {
            (&gs - projected).norm() / gs.norm().max(f64::MIN_POSITIVE)
        };
        null_share.push(share);
        variance
            .push((share < ESTIMABLE_TOLERANCE).then(|| (svd.v_over_s.transpose() * row.transpose()).norm_squared()));
    }
    CampaignBound {
        variance,
        null_share,
        parameters: n,
        rank: svd.rank,
        coordinates: j.nrows(),
    }
}

/// The bound with the parameters held to the estimator's conventions: an estimator that fixes
/// gauge freedoms by conventions (a zero at the reference pose, a base frame on the axes) only
/// moves its parameters within a subspace `S`; with `u` a basis of `S` (columns) and the last
/// `nuisances` parameters free, the parameters are `p = U z`, `U = [u 0; 0 I]`, and the bound
/// of each parameter is [`fisher_bound_of`] the reduced Jacobian `J U` for the functions
/// `U z` (the constrained Cramer-Rao bound, Stoica & Ng, IEEE TSP 46(5), 1998, eq. 12, where
/// `J U` has full rank). Where `S` still holds a null direction of `J` (the conventions do not
/// fix every gauge), a parameter with a share in it is not estimable (`None`); every other
/// keeps its bound. On a parameter estimable without conventions it equals
/// [`fisher_bound`]'s.
pub fn convention_bound(j: &DMatrix<f64>, sigma: f64, u: &DMatrix<f64>, nuisances: usize) -> CampaignBound {
    let (m, r) = (u.nrows(), u.ncols());
    let mut full = DMatrix::zeros(m + nuisances, r + nuisances);
    full.view_mut((0, 0), (m, r)).copy_from(u);
    full.view_mut((m, r), (nuisances, nuisances)).fill_with_identity();
    fisher_bound_of(&(j * &full), sigma, &full)
}

/// An orthonormal basis (columns) of the range of a covariance `c` (symmetric, positive
/// semi-definite): of its correlation matrix `D^-1 c D^-1` (`D = sqrt(diag c)`, so that units
/// do not decide the rank) by [`TruncatedSvd`] at [`NULL_DIRECTION_TOLERANCE`], mapped back by
/// `D` and orthonormalised. Parameters without a variance are outside it. The subspace a
/// linearised estimator's parameters move in (its covariance `K C K^T` has the range of `K`).
pub fn covariance_range(c: &DMatrix<f64>) -> DMatrix<f64> {
    let d: Vec<f64> = (0..c.nrows()).map(|k| c[(k, k)].max(0.0).sqrt()).collect();
    let corr = DMatrix::from_fn(c.nrows(), c.ncols(), |r, k| {
        if d[r] > 0.0 && d[k] > 0.0 {
            c[(r, k)] / (d[r] * d[k])
        } else {
            0.0
        }
    });
    let span = TruncatedSvd::new(&corr, NULL_DIRECTION_TOLERANCE).span;
    let mapped = DMatrix::from_fn(span.nrows(), span.ncols(), |r, k| d[r] * span[(r, k)]);
    TruncatedSvd::new(&mapped, NULL_DIRECTION_TOLERANCE).span
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibration::refine::sensitivity;
    use crate::numerics::lsq::inverse_normal;

    /// Points `y_i = (a + b) x_i + c x_i^2 + d sin(x_i)`: `a` and `b` only enter as their sum
    /// (one null direction `e_a - e_b`), `c` and `d` are estimable.
    fn design() -> DMatrix<f64> {
        DMatrix::from_fn(15, 4, |i, k| {
            let x = 0.3 * i as f64 - 1.0;
            [x, x, x * x, x.sin()][k]
        })
    }

    #[test]
    fn gauge_direction_is_reported_and_estimable_parameters_match_the_gauge_fixed_inverse() {
        let j = design();
        let sigma = 0.02;
        let b = fisher_bound(&j, sigma);
        assert_eq!((b.parameters, b.rank, b.coordinates), (4, 3, 15));
        assert!(b.variance[0].is_none() && b.variance[1].is_none(), "{b:?}");
        // The null direction (1, -1, 0, 0)/sqrt(2) holds half of each of e_a, e_b (column
        // scaled, equal columns): share 1/sqrt(2).
        assert!((b.null_share[0] - 0.5f64.sqrt()).abs() < 1e-12, "{b:?}");
        // A different route: fix the gauge (drop b; `a` then stands for a + b) and invert the
        // full-rank Fisher information; the estimable parameters' bounds do not depend on the
        // gauge.
        let fixed = j.clone().remove_column(1) / sigma;
        let cov = inverse_normal(&fixed, "test").unwrap();
        for (k, kf) in [(2, 1), (3, 2)] {
            let v = b.variance[k].unwrap();
            // Both are exact linear algebra on a condition-~10 matrix: rounding only.
            assert!((v / cov[(kf, kf)] - 1.0).abs() < 1e-10, "{k}: {v} vs {}", cov[(kf, kf)]);
        }
    }

    #[test]
    fn convention_bound_is_the_bound_of_the_convention_fixed_parameters() {
        let j = design();
        let sigma = 0.02;
        let pinv = fisher_bound(&j, sigma);
        // Convention a = b: the estimator reports a = b = s / 2 with s = a + b, whose bound is
        // a quarter of s's (the gauge-fixed inverse of the other test, where a stands for s).
        let h = 0.5f64.sqrt();
        let u = DMatrix::from_row_slice(4, 3, &[h, 0.0, 0.0, h, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
        // The last parameter (d) as a free nuisance: u spans the first three.
        let u3 = u.view((0, 0), (3, 2)).into_owned();
        let c = convention_bound(&j, sigma, &u3, 1);
        let fixed = inverse_normal(&(j.clone().remove_column(1) / sigma), "test").unwrap();
        for (k, expected) in [
            (0, fixed[(0, 0)] / 4.0),
            (1, fixed[(0, 0)] / 4.0),
            (2, fixed[(1, 1)]),
            (3, fixed[(2, 2)]),
        ] {
            // Exact linear algebra on condition-~10 matrices: rounding only.
            let v = c.variance[k].unwrap();
            assert!((v / expected - 1.0).abs() < 1e-10, "{k}: {v} vs {expected}");
        }
        // On the estimable parameters both routes agree.
        for k in 2..4 {
            assert!((c.variance[k].unwrap() / pinv.variance[k].unwrap() - 1.0).abs() < 1e-10);
        }
        // A convention that does not fix the gauge (it lets a and b move apart) leaves a and b
        // without a bound, and c, d with theirs.
        let loose = DMatrix::identity(3, 3);
        let l = convention_bound(&j, sigma, &loose, 1);
        assert!(l.variance[0].is_none() && l.variance[1].is_none(), "{l:?}");
        for k in 2..4 {
            assert!((l.variance[k].unwrap() / pinv.variance[k].unwrap() - 1.0).abs() < 1e-10);
        }
    }

    #[test]
    fn covariance_range_spans_the_estimator_directions_whatever_the_units() {
        // K: two input directions into three parameters of scales 1e-6 and 1 (m and rad).
        let k = DMatrix::from_row_slice(3, 2, &[1e-6, 0.0, 0.0, 2.0, 3e-6, 1.0]);
        let c = &k * k.transpose();
        let u = covariance_range(&c);
        assert_eq!(u.ncols(), 2);
        // Orthonormal, and K's columns lie in its span: the residual of the projection is
        // rounding of the 1e-6-scale entries.
        assert!((u.transpose() * &u - DMatrix::identity(2, 2)).norm() < 1e-12);
        for col in k.column_iter() {
            let rest = col - &u * (u.transpose() * col);
            assert!(rest.norm() < 1e-12 * col.norm().max(1e-6), "{rest}");
        }
    }

    #[test]
    fn schur_complement_of_the_nuisances_gives_the_same_bound() {
        // Without a gauge: the bound of (c, d) is the inverse of the Schur complement of the
        // nuisance block (a) in F, a route that never forms the full inverse.
        let j = design().remove_column(1);
        let sigma = 0.5;
        let b = fisher_bound(&j, sigma);
        let f = j.transpose() * &j / (sigma * sigma);
        let (fnn, fnc, fcc) = (f[(0, 0)], f.view((0, 1), (1, 2)), f.view((1, 1), (2, 2)));
        let schur = fcc - fnc.transpose() * fnc / fnn;
        let inv = schur.try_inverse().unwrap();
        for k in 0..2 {
            let v = b.variance[k + 1].unwrap();
            assert!((v / inv[(k, k)] - 1.0).abs() < 1e-10, "{v} vs {}", inv[(k, k)]);
        }
        assert!(b.null_share.iter().all(|s| *s < ESTIMABLE_TOLERANCE));
    }

    #[test]
    fn central_difference_bound_of_a_nonlinear_model_matches_its_analytic_jacobian() {
        // Points on a circle of radius r about (cx, cy) at angles t_i + phase: the central
        // differences of `campaign_bound` against the analytic Jacobian.
        let t: Vec<f64> = (0..9).map(|i| 0.2 * i as f64).collect();
        let p0 = [0.3, -0.1, 0.8, 0.05];
        let predict = |p: &[f64]| -> Option<Vec<f64>> {
            Some(
                t.iter()
                    .flat_map(|&ti| [p[0] + p[2] * (ti + p[3]).cos(), p[1] + p[2] * (ti + p[3]).sin()])
                    .collect(),
            )
        };
        let b = fisher_bound(&sensitivity(predict, &p0, &[1e-6; 4]).unwrap(), 1e-3);
        let j = DMatrix::from_fn(2 * t.len(), 4, |row, k| {
            let (a, c) = (t[row / 2] + p0[3], row % 2);
            match (k, c) {
                (0, 0) | (1, 1) => 1.0,
                (0, 1) | (1, 0) => 0.0,
                (2, 0) => a.cos(),
                (2, 1) => a.sin(),
                (3, 0) => -p0[2] * a.sin(),
                _ => p0[2] * a.cos(),
            }
        });
        let exact = fisher_bound(&j, 1e-3);
        for k in 0..4 {
            // Central differences of step 1e-6 on O(1) curvature: relative error ~1e-10 in J,
            // amplified by the condition number (~1e2) of this short arc.
            let (a, e) = (b.variance[k].unwrap(), exact.variance[k].unwrap());
            assert!((a / e - 1.0).abs() < 1e-6, "{k}: {a} vs {e}");
        }
    }
}
