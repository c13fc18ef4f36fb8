//! The chi-square statistic of residuals that share one error: blocks `r_i` with independent
//! noise of covariance `N_i` each, plus the error `G_i e` of one common parameter error
//! `e ~ N(0, I_k)` (e.g. a calibrated model's error, `G_i = J_i L` with `L L^T = C_p`). The
//! stacked residual has covariance `S = blockdiag(N_i) + G G^T`, dense across blocks, and
//! `chi2 = r^T S^-1 r` follows a chi-square distribution with `sum dim r_i` degrees of
//! freedom when the model holds.
//!
//! `S^-1` by the Woodbury identity with `W_i = N_i^-1`:
//! `r^T S^-1 r = sum r_i^T W_i r_i - b^T (I_k + A)^-1 b`, `A = sum G_i^T W_i G_i`,
//! `b = sum G_i^T W_i r_i` (Golub & Van Loan, *Matrix Computations*, 4th ed., section 2.1.4).
//! `I_k + A` is symmetric positive definite for any `G`, so a singular `C_p` needs no care;
//! the sums are accumulated block by block, in memory `O(k^2)` whatever the number of blocks.
//!
//! Free components ([`SharedErrorChiSquare::with_free`]): `f` more columns of `G_i` whose
//! error has no prior (a quantity the data must give, e.g. a frame nobody measured). Their
//! prior precision is 0 instead of 1, so the statistic is the minimum of
//! `(r - T d)^T S^-1 (r - T d)` over their values `d` (generalised least squares), chi-square
//! with `sum dim r_i - f'` degrees of freedom, `f'` the free components the residuals resolve.
//! `M = P + A`, `P = diag(I_k, 0_f)`, is then solved by blocks (Golub & Van Loan, section
//! 3.2.10): with `C = I_k + A_kk` (positive definite, by Cholesky) and the free block's Schur
//! complement `F = A_ff - A_fk C^-1 A_kf` (`f x f`, semidefinite), `x_f = F^+ (b_f - A_fk C^-1
//! b_k)` and `x_k = C^-1 (b_k - A_kf x_f)`, a solution of `M x = b` (`b` lies in `M`'s range, so
//! `b^T x` is the same for every solution). `F`'s numerical rank (singular values above
//! `d dim epsilon`, `d` the largest diagonal entry of `M`: the rounding of the sums) counts the
//! resolved components, and `x_f` is zero in the directions it does not resolve.

use nalgebra::{DMatrix, DVector};

/// The running sums of [`SharedErrorChiSquare::add`]; [`SharedErrorChiSquare::fit`] the
/// statistic (module docs).
#[derive(Clone, Debug)]
pub struct SharedErrorChiSquare {
    /// `sum r_i^T W_i r_i`: the statistic without the shared error.
    independent: f64,
    /// `A = sum G_i^T W_i G_i`.
    normal: DMatrix<f64>,
    /// `b = sum G_i^T W_i r_i`.
    projected: DVector<f64>,
    /// `sum trace(G_i G_i^T)`: the shared error's summed variance over every component.
    shared_variance: f64,
    /// `sum dim r_i`.
    dof: usize,
    /// The last `free` components have no prior (module docs).
    free: usize,
}

/// What the sums of a [`SharedErrorChiSquare`] give, from one factorisation
/// ([`SharedErrorChiSquare::fit`]).
#[derive(Clone, Debug)]
pub struct SharedErrorFit {
    /// `r^T S^-1 r`; NaN if a residual or factor was not finite.
    pub value: f64,
    /// Degrees of freedom: residual components added, less the free components they resolve.
    pub dof: usize,
    /// The estimate of every component from the residuals: `(I_k + A)^-1 b`, the posterior mean
    /// of the shared error `e` (`G^T S^-1 r` by the Woodbury identity), with free components
    /// the block solution of `(P + A) x = b` (module docs); NaN where a residual or factor was
    /// not finite. `G_i` times it
    /// is the part of block `i` the shared error explains.
    pub estimate: DVector<f64>,
    /// The last `free` components of `estimate` have no prior.
    free: usize,
}

impl SharedErrorFit {
    /// The free components' estimate: the last `free` entries of [`Self::estimate`], the values
    /// that minimise the statistic (module docs); empty without free components.
    pub fn free_estimate(&self) -> DVector<f64> {
        let n = self.estimate.len();
        self.estimate.rows(n - self.free, self.free).into_owned()
    }
}

impl SharedErrorChiSquare {
    /// No block yet, a shared error of `k` components.
    pub fn new(k: usize) -> Self {
        Self::with_free(k, 0)
    }

    /// No block yet, a shared error of `k` components followed by `free` components without
    /// a prior, estimated from the residuals (module docs): each block's factor has `k + free`
    /// columns.
    pub fn with_free(k: usize, free: usize) -> Self {
        SharedErrorChiSquare {
            independent: 0.0,
            normal: DMatrix::zeros(k + free, k + free),
            projected: DVector::zeros(k + free),
            shared_variance: 0.0,
            dof: 0,
            free,
        }
    }

    /// Adds block `r` with noise weight `w = N^-1` (`m x m`, symmetric positive definite) and
    /// shared-error factor `g` (`m x k`).
    pub fn add(&mut self, r: &DVector<f64>, w: &DMatrix<f64>, g: &DMatrix<f64>) {
        let wr = w * r;
        let wg = w * g;
        self.independent += r.dot(&wr);
        self.normal.gemm(1.0, &g.transpose(), &wg, 1.0);
        self.projected += g.tr_mul(&wr);
        self.shared_variance += g.columns(0, g.ncols() - self.free).norm_squared();
        self.dof += r.len();
    }

    /// The statistic, its degrees of freedom and every component's estimate, from one
    /// factorisation of the sums: `I_k + A` by Cholesky, or with free components `P + A` by
    /// blocks (module docs).
    pub fn fit(&self) -> SharedErrorFit {
        let (estimate, dof) = if self.free > 0 {
            let (estimate, resolved) = self.free_solution();
            (estimate, self.dof.saturating_sub(resolved))
        } else {
            let k = self.projected.len();
            let capacitance = DMatrix::identity(k, k) + &self.normal;
            let estimate = match capacitance.cholesky() {
                Some(ch) => ch.solve(&self.projected),
                None => DVector::from_element(k, f64::NAN),
            };
            (estimate, self.dof)
        };
        SharedErrorFit {
            value: self.independent - self.projected.dot(&estimate),
            dof,
            estimate,
            free: self.free,
        }
    }

    /// With free components: `M x = b` solved by blocks, and the free components the sums
    /// resolve (`F`'s numerical rank, module docs); NaN where a sum was not finite.
    fn free_solution(&self) -> (DVector<f64>, usize) {
        let n = self.projected.len();
        let (k, f) = (n - self.free, self.free);
        let not_finite = (DVector::from_element(n, f64::NAN), 0);
        let capacitance = DMatrix::identity(k, k) + self.normal.view((0, 0), (k, k));
        let Some(ch) = capacitance.cholesky() else {
            return not_finite;
        };
        let coupling = self.normal.view((0, k), (k, f));
        let (b_k, b_f) = (self.projected.rows(0, k), self.projected.rows(k, f));
        let solved_coupling = ch.solve(&coupling.into_owned());
        let solved_b = ch.solve(&b_k.into_owned());
        let schur = self.normal.view((k, k), (f, f)) - coupling.transpose() * &solved_coupling;
        let reduced = b_f - coupling.transpose() * &solved_b;
        if !schur.iter().chain(reduced.iter()).all(|v| v.is_finite()) {
            return not_finite;
        }
        let largest = (0..n)
            .map(|i| self.normal[(i, i)] + f64::from(i < k))
            .fold(0.0, f64::max);
        let tolerance = largest * n as f64 * f64::EPSILON;
        let svd = schur.svd(true, true);
        let resolved = svd.rank(tolerance);
        let Ok(inverse) = svd.pseudo_inverse(tolerance) else {
            return not_finite;
        };
        let x_f = inverse * reduced;
        let mut x = DVector::zeros(n);
        x.rows_mut(0, k).copy_from(&(solved_b - &solved_coupling * &x_f));
        x.rows_mut(k, f).copy_from(&x_f);
        (x, resolved)
    }

    /// Whether no block was added.
    pub fn is_empty(&self) -> bool {
        self.dof == 0
    }

    /// `sum r_i^T W_i r_i`: the statistic of the noise alone.
    pub fn noise_alone(&self) -> f64 {
        self.independent
    }

    /// The shared error's variance summed over every residual component, `trace(G G^T)`.
    pub fn shared_variance(&self) -> f64 {
        self.shared_variance
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numerics::stats::CorrelatedNormal;
    use rand::SeedableRng;
    use rand::rngs::ChaCha12Rng;
    use rand_distr::{Distribution, StandardNormal};

    /// Blocks of 3 (and one of 2) with random noise covariances and a factor of rank 2 in 4
    /// columns: what a model covariance of dependent parameters gives.
    fn problem(rng: &mut ChaCha12Rng) -> Vec<(DMatrix<f64>, DMatrix<f64>)> {
        let mut normal = || -> f64 { StandardNormal.sample(&mut *rng) };
        let mixing = DMatrix::from_fn(2, 4, |_, _| normal());
        [3, 3, 2, 3]
            .iter()
            .map(|&m| {
                let a = DMatrix::from_fn(m, m, |_, _| normal());
                let noise = &a * a.transpose() + DMatrix::identity(m, m) * 0.1;
                let g = DMatrix::from_fn(m, 2, |_, _| normal()) * &mixing;
                (noise, g)
            })
            .collect()
    }

    /// `blocks` stacked with residuals drawn from the standard normal: the dense covariance
    /// `blockdiag(N_i) + G G^T`, `G`, the residuals and their statistic.
    fn stacked(
        blocks: &[(DMatrix<f64>, DMatrix<f64>)],
        rng: &mut ChaCha12Rng,
    ) -> (DMatrix<f64>, DMatrix<f64>, DVector<f64>, SharedErrorChiSquare) {
        let n: usize = blocks.iter().map(|(noise, _)| noise.nrows()).sum();
        let (mut dense, mut g_all) = (DMatrix::zeros(n, n), DMatrix::zeros(n, 4));
        let r_all = DVector::from_fn(n, |_, _| StandardNormal.sample(rng));
        let mut chi = SharedErrorChiSquare::new(4);
        let mut at = 0;
        for (noise, g) in blocks {
            let m = noise.nrows();
            dense.view_mut((at, at), (m, m)).copy_from(noise);
            g_all.view_mut((at, 0), (m, 4)).copy_from(g);
            chi.add(
                &r_all.rows(at, m).into_owned(),
                &noise.clone().try_inverse().unwrap(),
                g,
            );
            at += m;
        }
        dense += &g_all * g_all.transpose();
        (dense, g_all, r_all, chi)
    }

    /// The accumulated Woodbury form against the dense `r^T S^-1 r` (a second path: the whole
    /// covariance built and solved by LU).
    #[test]
    fn the_woodbury_sums_equal_the_dense_quadratic_form() {
        let mut rng = ChaCha12Rng::seed_from_u64(41);
        for _ in 0..20 {
            let blocks = problem(&mut rng);
            let (dense, g_all, r_all, chi) = stacked(&blocks, &mut rng);
            let n = r_all.len();
            let expected = r_all.dot(&dense.lu().solve(&r_all).unwrap());
            assert!(
                (chi.fit().value - expected).abs() <= 1e-9 * expected,
                "{} vs {expected}",
                chi.fit().value
            );
            assert_eq!(chi.fit().dof, n);
            assert!((chi.shared_variance() - g_all.norm_squared()).abs() <= 1e-12 * g_all.norm_squared());
        }
    }

    /// The estimate against the dense posterior mean `G^T S^-1 r` (a second path: the whole
    /// covariance built and solved by LU).
    #[test]
    fn the_estimate_is_the_dense_posterior_mean() {
        let mut rng = ChaCha12Rng::seed_from_u64(44);
        for _ in 0..20 {
            let blocks = problem(&mut rng);
            let (dense, g_all, r_all, chi) = stacked(&blocks, &mut rng);
            let expected = g_all.transpose() * dense.lu().solve(&r_all).unwrap();
            assert!(
                (chi.fit().estimate - &expected).norm() <= 1e-9 * expected.norm(),
                "{} vs {expected}",
                chi.fit().estimate
            );
        }
    }

    /// Residuals drawn from the model (noise per block, one shared error for all of them):
    /// the statistic's mean over draws is its degrees of freedom within 4 standard errors
    /// (`sqrt(2 dof / draws)`), and the noise-alone statistic, which ignores the shared
    /// error, is far above it.
    #[test]
    fn drawn_residuals_give_the_degrees_of_freedom() {
        let mut rng = ChaCha12Rng::seed_from_u64(42);
        let blocks = problem(&mut rng);
        let draws = 4000;
        let (mut sum, mut sum_alone, mut dof) = (0.0, 0.0, 0);
        for _ in 0..draws {
            let shared = DVector::from_fn(4, |_, _| StandardNormal.sample(&mut rng));
            let mut chi = SharedErrorChiSquare::new(4);
            for (noise, g) in &blocks {
                let r = CorrelatedNormal::new(noise).unwrap().draw(&mut rng) + g * &shared;
                chi.add(&r, &noise.clone().try_inverse().unwrap(), g);
            }
            sum += chi.fit().value;
            sum_alone += chi.noise_alone();
            dof = chi.fit().dof;
        }
        let (mean, mean_alone) = (sum / draws as f64, sum_alone / draws as f64);
        let standard_error = (2.0 * dof as f64 / draws as f64).sqrt();
        assert!((mean - dof as f64).abs() < 4.0 * standard_error, "{mean} vs {dof}");
        assert!(mean_alone > dof as f64 + 10.0 * standard_error, "{mean_alone}");
    }

    /// Free components against the dense generalised least squares (a second path): the
    /// minimum over `d` of `(r - T d)^T S^-1 (r - T d)`, `S` the covariance of noise and shared
    /// error, with `T` two columns of unknown offsets; the degrees of freedom lose 2.
    #[test]
    fn free_components_equal_the_dense_generalised_least_squares() {
        let mut rng = ChaCha12Rng::seed_from_u64(43);
        for _ in 0..20 {
            let blocks = problem(&mut rng);
            let n: usize = blocks.iter().map(|(noise, _)| noise.nrows()).sum();
            let t_all = DMatrix::from_fn(n, 2, |_, _| StandardNormal.sample(&mut rng));
            let r_all = DVector::from_fn(n, |_, _| StandardNormal.sample(&mut rng))
                + &t_all * DVector::from_vec(vec![1e3, -4e2]);
            let (mut dense, mut g_all) = (DMatrix::zeros(n, n), DMatrix::zeros(n, 4));
            let mut chi = SharedErrorChiSquare::with_free(4, 2);
            let mut at = 0;
            for (noise, g) in &blocks {
                let m = noise.nrows();
                dense.view_mut((at, at), (m, m)).copy_from(noise);
                g_all.view_mut((at, 0), (m, 4)).copy_from(g);
                let mut factor = DMatrix::zeros(m, 6);
                factor.columns_mut(0, 4).copy_from(g);
                factor.columns_mut(4, 2).copy_from(&t_all.rows(at, m));
                chi.add(
                    &r_all.rows(at, m).into_owned(),
                    &noise.clone().try_inverse().unwrap(),
                    &factor,
                );
                at += m;
            }
            dense += &g_all * g_all.transpose();
            let s_inv = dense.try_inverse().unwrap();
            let (sr, st) = (&s_inv * &r_all, &s_inv * &t_all);
            let normal = t_all.transpose() * &st;
            let b = t_all.transpose() * &sr;
            let d = normal.try_inverse().unwrap() * &b;
            let expected = r_all.dot(&sr) - b.dot(&d);
            assert!(
                (chi.fit().value - expected).abs() <= 1e-6 * expected,
                "{} vs {expected}",
                chi.fit().value
            );
            assert_eq!(chi.fit().dof, n - 2);
            assert!(
                (chi.fit().free_estimate() - &d).norm() <= 1e-6 * d.norm(),
                "{} vs {d}",
                chi.fit().free_estimate()
            );
            assert!((chi.shared_variance() - g_all.norm_squared()).abs() <= 1e-12 * g_all.norm_squared());
        }
    }

    /// A free column that is the sum of two others (a component no residual resolves): one
    /// degree of freedom fewer than the columns, the statistic that of the two independent
    /// columns (a second path: the dense generalised least squares over them), and the estimate
    /// zero along the unresolved direction. Without shared components (`k = 0`) the same.
    #[test]
    fn an_unresolved_free_component_counts_no_degree_of_freedom() {
        let mut rng = ChaCha12Rng::seed_from_u64(45);
        for k in [4, 0] {
            let blocks = problem(&mut rng);
            let n: usize = blocks.iter().map(|(noise, _)| noise.nrows()).sum();
            let t_two = DMatrix::from_fn(n, 2, |_, _| StandardNormal.sample(&mut rng));
            let t_all = DMatrix::from_fn(n, 3, |i, j| {
                if j < 2 {
                    t_two[(i, j)]
                } else {
                    t_two[(i, 0)] + t_two[(i, 1)]
                }
            });
            let r_all = DVector::from_fn(n, |_, _| StandardNormal.sample(&mut rng))
                + &t_two * DVector::from_vec(vec![1e3, -4e2]);
            let (mut dense, mut g_all) = (DMatrix::zeros(n, n), DMatrix::zeros(n, 4));
            let mut chi = SharedErrorChiSquare::with_free(k, 3);
            let mut at = 0;
            for (noise, g) in &blocks {
                let m = noise.nrows();
                dense.view_mut((at, at), (m, m)).copy_from(noise);
                g_all.view_mut((at, 0), (m, 4)).copy_from(g);
                let mut factor = DMatrix::zeros(m, k + 3);
                factor.columns_mut(0, k).copy_from(&g.columns(0, k));
                factor.columns_mut(k, 3).copy_from(&t_all.rows(at, m));
                chi.add(
                    &r_all.rows(at, m).into_owned(),
                    &noise.clone().try_inverse().unwrap(),
                    &factor,
                );
                at += m;
            }
            let g_used = g_all.columns(0, k);
            dense += g_used * g_used.transpose();
            let s_inv = dense.try_inverse().unwrap();
            let (sr, st) = (&s_inv * &r_all, &s_inv * &t_two);
            let b = t_two.transpose() * &sr;
            let d = (t_two.transpose() * &st).try_inverse().unwrap() * &b;
            let expected = r_all.dot(&sr) - b.dot(&d);
            let fit = chi.fit();
            assert!(
                (fit.value - expected).abs() <= 1e-6 * expected,
                "k {k}: {} vs {expected}",
                fit.value
            );
            assert_eq!(fit.dof, n - 2, "k {k}");
            let x = fit.free_estimate();
            let offsets = DVector::from_vec(vec![x[0] + x[2], x[1] + x[2]]);
            assert!((&offsets - &d).norm() <= 1e-6 * d.norm(), "k {k}: {offsets} vs {d}");
            assert!((x[0] + x[1] - x[2]).abs() <= 1e-9 * d.norm(), "k {k}: {x}");
        }
    }
}
