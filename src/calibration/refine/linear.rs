//! Linearised least squares of a refinement on free poses (the diagnoser's and `calibrate
//! --refine`'s): the residuals of the calibrated model are linear in the small refit and
//! effect parameters (Gauss-Newton's model, Nocedal & Wright,
//! Numerical Optimization, 2nd ed., eq. 10.24), so every fit is one truncated-SVD solve on
//! the training rows ([`TruncatedSvd`]), and its
//! held-out residuals are a fixed linear map of the data: `r_h - X_h X_t^+ r_t`, applied as
//! `r_h - X_h (X_t^+ r_t)` (through the few parameters, never the rows-by-rows matrix).

use crate::numerics::finite_diff::central_jacobian;
use crate::numerics::lsq::TruncatedSvd;
use nalgebra::{DMatrix, DVector};

/// Directions of the column-scaled training design whose singular value is below this
/// fraction of the largest are exact redundancies (central differences resolve about 1e-10):
/// they are dropped, not fitted.
pub const NULL_DIRECTION_TOLERANCE: f64 = 1e-7;

/// Central-difference sensitivity `X = d prediction / d p = -d residual / d p` at `p0` of a
/// residual function `f` (`measured - predicted`): the residuals' Jacobian
/// ([`central_jacobian`], its columns in parallel, bit for bit the serial result) negated;
/// `None` when an evaluation fails or two differ in length.
pub fn sensitivity<F>(f: F, p0: &[f64], steps: &[f64]) -> Option<DMatrix<f64>>
where
    F: Fn(&[f64]) -> Option<Vec<f64>> + Sync,
{
    central_jacobian(f, p0, steps).map(|j| -j)
}

/// A linear least-squares fit `r_t ~ X_t p` on training rows, truncated to the identifiable
/// directions, and the map it induces on held-out rows.
#[derive(Clone, Debug)]
pub struct LinearFit {
    /// `p = solve * r_t` (parameters \[model units\]).
    solve: DMatrix<f64>,
    /// `X_h`: the design's held-out rows (the fit's held-out prediction is `X_h p`).
    x_held: DMatrix<f64>,
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
        LinearFit {
            solve: svd.solve,
            x_held: x_held.clone(),
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
    /// rows (one column per data set): `held - X_h (X_t^+ train)`, about `rows / (2 rank)`
    /// times fewer operations than through `X_h X_t^+`.
    pub fn heldout(&self, train: &DMatrix<f64>, held: &DMatrix<f64>) -> DMatrix<f64> {
        held - &self.x_held * (&self.solve * train)
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

/// Columns added on top of a fit by the Frisch-Waugh-Lovell theorem (Davidson & MacKinnon,
/// *Econometric Theory and Methods*, sec. 2.4): the fit of `[X_below, X]` on the training rows
/// leaves the same residual as the fit of `X` residualised against `X_below` on the data
/// residualised against `X_below`, and its parameters for `X` are those of the second fit. So
/// a candidate effect is scored on top of the refit (and of an effect already named) with one
/// small solve of its own columns, the refit's solve shared by all, and the held-out residual
/// follows as `e_h - X_h^res p` with `X_h^res = X_h - (held-out prediction of X_t by the fit
/// below)`.
#[derive(Clone, Debug)]
pub struct Block {
    /// Training rows residualised against the fit below \[m per parameter unit\].
    pub train: DMatrix<f64>,
    /// Held-out rows minus the fit below's held-out prediction of the training rows.
    pub held: DMatrix<f64>,
    /// `p = solve * e_t` on the kept directions.
    solve: DMatrix<f64>,
    /// `(train^T train)^+` on the kept directions (times the per-coordinate noise variance:
    /// the covariance of the block's parameters in the joint fit).
    pub normal_inverse: DMatrix<f64>,
    /// Kept directions.
    pub rank: usize,
    /// Fraction of the block's training-row norm outside the span of the fit below.
    pub outside_fraction: f64,
    /// Left singular vectors `U` of the kept directions of `train` (orthonormal columns).
    span: DMatrix<f64>,
    /// `held V S^-1` on the kept directions: the held-out prediction of a unit fit along each
    /// column of `span` (`held * solve = held_basis * span^T`).
    held_basis: DMatrix<f64>,
    /// `held_basis^T held_basis`.
    held_gram: DMatrix<f64>,
}

impl LinearFit {
    /// Training and held-out residuals of data columns (training rows `train`, held-out rows
    /// `held`) after this fit.
    pub fn residualise(&self, train: &DMatrix<f64>, held: &DMatrix<f64>) -> (DMatrix<f64>, DMatrix<f64>) {
        let inside = &self.span * (self.span.transpose() * train);
        (train - inside, self.heldout(train, held))
    }

    /// The columns `x_train`, `x_held` of one candidate as a [`Block`] on top of this fit and of
    /// the blocks `below` (each residualised against the fit and the blocks before it). A
    /// direction of the block whose length, against the columns' own before residualisation,
    /// is below [`NULL_DIRECTION_TOLERANCE`] lies inside what is below: it is dropped.
    pub fn block(&self, below: &[&Block], x_train: &DMatrix<f64>, x_held: &DMatrix<f64>) -> Block {
        let norms: Vec<f64> = x_train.column_iter().map(|c| c.norm()).collect();
        let (train, held) = self.residualise(x_train, x_held);
        let (train, held) = Block::residualise_below(below, train, held);
        Block::of_residualised(&norms, train, held)
    }

    /// [`LinearFit::block`] for the columns of several candidates (`xs`: each one's training
    /// and held-out rows) at once: their residualisation against this fit is one product
    /// over all their columns (a blocked kernel; a candidate's few columns alone take an
    /// unblocked path), the rest per candidate as in [`LinearFit::block`].
    pub fn blocks(&self, below: &[&Block], xs: &[(DMatrix<f64>, DMatrix<f64>)]) -> Vec<Block> {
        let (Some((t0, h0)), total) = (xs.first(), xs.iter().map(|x| x.0.ncols()).sum::<usize>()) else {
            return Vec::new();
        };
        let (mut train, mut held) = (DMatrix::zeros(t0.nrows(), total), DMatrix::zeros(h0.nrows(), total));
        let mut at = 0;
        for (t, h) in xs {
            train.columns_mut(at, t.ncols()).copy_from(t);
            held.columns_mut(at, h.ncols()).copy_from(h);
            at += t.ncols();
        }
        let (train, held) = self.residualise(&train, &held);
        let (train, held) = Block::residualise_below(below, train, held);
        let mut at = 0;
        xs.iter()
            .map(|(t, _)| {
                let k = t.ncols();
                let norms: Vec<f64> = t.column_iter().map(|c| c.norm()).collect();
                let b = Block::of_residualised(
                    &norms,
                    train.columns(at, k).into_owned(),
                    held.columns(at, k).into_owned(),
                );
                at += k;
                b
            })
            .collect()
    }
}

impl Block {
    /// Columns residualised against a fit (`train`, `held`) residualised against the blocks
    /// `below` too, each against the fit and the blocks before it.
    fn residualise_below(
        below: &[&Block],
        mut train: DMatrix<f64>,
        mut held: DMatrix<f64>,
    ) -> (DMatrix<f64>, DMatrix<f64>) {
        for b in below {
            let coef = &b.solve * &train;
            train -= &b.train * &coef;
            held -= &b.held * &coef;
        }
        (train, held)
    }

    /// The block of columns residualised against everything below (`train`, `held`), of
    /// training-row norms `norms` before that.
    fn of_residualised(norms: &[f64], train: DMatrix<f64>, held: DMatrix<f64>) -> Block {
        let total: f64 = norms.iter().map(|n| n * n).sum::<f64>().sqrt();
        let outside_fraction = if total > 0.0 { train.norm() / total } else { 0.0 };
        let svd = TruncatedSvd::with_reference_norms(&train, norms, NULL_DIRECTION_TOLERANCE);
        let held_basis = &held * &svd.v_over_s;
        Block {
            normal_inverse: &svd.v_over_s * svd.v_over_s.transpose(),
            held_gram: held_basis.tr_mul(&held_basis),
            held_basis,
            span: svd.span,
            solve: svd.solve,
            rank: svd.rank,
            outside_fraction,
            train,
            held,
        }
    }
}

impl Block {
    /// The block's fitted parameters for residualised training data `e_train` (one column per
    /// data set).
    pub fn params(&self, e_train: &DMatrix<f64>) -> DMatrix<f64> {
        &self.solve * e_train
    }

    /// The residuals of data residualised below (`e_train`, `e_held`) after this block too.
    pub fn apply(&self, e_train: &DMatrix<f64>, e_held: &DMatrix<f64>) -> (DMatrix<f64>, DMatrix<f64>) {
        let p = self.params(e_train);
        (e_train - &self.train * &p, e_held - &self.held * &p)
    }

    /// The held-out residuals only (the cheaper half of [`Block::apply`]).
    pub fn held_after(&self, e_train: &DMatrix<f64>, e_held: &DMatrix<f64>) -> DMatrix<f64> {
        e_held - &self.held * self.params(e_train)
    }

    /// The held-out sums of squares (one per data column) of [`Block::held_after`] for each of
    /// `blocks`, all on top of the fit the data `e_train`, `e_held` are residualised against,
    /// computed for every block at once. With the block's training fit `U S V^T` (kept
    /// directions), `Q = U^T e_t` and `W = held V S^-1`, the held-out residual is
    /// `e_h - W Q`, whose sum of squares is `|e_h|^2 - 2 (W^T e_h) . Q + Q^T (W^T W) Q`: the
    /// products with the data are two matrix products over the columns of all blocks
    /// (`[U_1 U_2 ...]^T e_t`, `[W_1 W_2 ...]^T e_h`, blocked kernels), the rest `k^2` per
    /// block and data column (before: two thin products per block, `k <= 5` columns of which
    /// take an unblocked path). Rounding: every term is bounded by `|e_h|^2 + |W Q|^2`, so the
    /// sum is exact to a few `eps` of that (`U` orthonormal: no conditioning enters through
    /// `Q`); against [`Block::held_after`] in the unit test.
    pub fn heldout_ssr_of(blocks: &[&Block], e_train: &DMatrix<f64>, e_held: &DMatrix<f64>) -> Vec<Vec<f64>> {
        let total: usize = blocks.iter().map(|b| b.rank).sum();
        let (mut u_all, mut w_all) = (
            DMatrix::zeros(e_train.nrows(), total),
            DMatrix::zeros(e_held.nrows(), total),
        );
        let mut at = 0;
        for b in blocks {
            u_all.columns_mut(at, b.rank).copy_from(&b.span);
            w_all.columns_mut(at, b.rank).copy_from(&b.held_basis);
            at += b.rank;
        }
        let q = u_all.transpose() * e_train;
        let c = w_all.transpose() * e_held;
        let e2: Vec<f64> = e_held.column_iter().map(|e| e.norm_squared()).collect();
        let mut at = 0;
        let mut out = Vec::with_capacity(blocks.len());
        for b in blocks {
            let (k, gram) = (b.rank, &b.held_gram);
            let (q_b, c_b) = (q.rows(at, k), c.rows(at, k));
            let ssr = (0..e_held.ncols())
                .map(|j| {
                    let (qj, cj) = (q_b.column(j), c_b.column(j));
                    let quadratic: f64 = (0..k).map(|l| gram.column(l).dot(&qj) * qj[l]).sum();
                    (e2[j] - 2.0 * qj.dot(&cj) + quadratic).max(0.0)
                })
                .collect();
            out.push(ssr);
            at += k;
        }
        out
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

    /// The held-out sums of squares of several blocks at once ([`Block::heldout_ssr_of`],
    /// through their orthonormal training bases) are those of each block's own held-out
    /// residuals ([`Block::held_after`], the direct product: a second path), for blocks of one
    /// to three columns, one of which lies partly inside the fit below, and data columns of
    /// pure noise and with an effect. Tolerance: both sums are of terms bounded by
    /// `|e_h|^2 + |W Q|^2` (here of the order of the data's sum of squares), computed to a few
    /// `eps` times that per operation over 30-row sums; 1e-12 relative leaves a factor of
    /// about 10 over `30 eps`.
    #[test]
    fn heldout_sums_of_many_blocks_are_each_blocks() {
        let n = 30;
        let t: Vec<f64> = (0..2 * n).map(|i| i as f64 / (2 * n) as f64).collect();
        let mut rng = <rand::rngs::ChaCha12Rng as rand::SeedableRng>::seed_from_u64(7);
        let mut noise = move || -> f64 { rand_distr::Distribution::sample(&rand_distr::StandardNormal, &mut rng) };
        let g = DMatrix::from_fn(2 * n, 2, |r, c| if c == 0 { 1.0 } else { t[r] });
        let xs = [
            DMatrix::from_fn(2 * n, 1, |r, _| (3.0 * t[r]).sin()),
            DMatrix::from_fn(2 * n, 2, |r, c| if c == 0 { 2.0 - 4.0 * t[r] } else { t[r] * t[r] }),
            DMatrix::from_fn(2 * n, 3, |r, c| (t[r] * (c + 2) as f64).cos() + 0.1 * c as f64),
        ];
        let data = DMatrix::from_fn(2 * n, 7, |r, c| {
            0.3 * noise() + if c == 0 { (5.0 * t[r]).sin() } else { 0.0 }
        });
        let split = |m: &DMatrix<f64>| (m.rows(0, n).into_owned(), m.rows(n, n).into_owned());
        let base = LinearFit::new(&split(&g).0, &split(&g).1);
        let blocks: Vec<Block> = xs.iter().map(|x| base.block(&[], &split(x).0, &split(x).1)).collect();
        assert_eq!(blocks[1].rank, 1, "2 - 4x lies inside the fit below");
        let (et, eh) = base.residualise(&split(&data).0, &split(&data).1);
        let all = Block::heldout_ssr_of(&blocks.iter().collect::<Vec<_>>(), &et, &eh);
        for (b, ssr) in blocks.iter().zip(&all) {
            let direct: Vec<f64> = b.held_after(&et, &eh).column_iter().map(|c| c.norm_squared()).collect();
            assert_eq!(ssr.len(), direct.len());
            for (a, d) in ssr.iter().zip(&direct) {
                assert!(
                    (a - d).abs() <= 1e-12 * d.max(eh.norm_squared() / 7.0),
                    "{a} against {d}"
                );
            }
        }
    }

    /// A block on top of a fit leaves the residuals, held-out residuals and block parameters of
    /// the joint fit of all columns at once (an independent solve), and drops a column that
    /// lies inside the fit below.
    #[test]
    fn a_block_on_top_of_a_fit_is_the_joint_fit() {
        let n = 30;
        let t: Vec<f64> = (0..2 * n).map(|i| i as f64 / (2 * n) as f64).collect();
        let col = |f: &dyn Fn(f64) -> f64| DMatrix::from_fn(2 * n, 1, |r, _| f(t[r]));
        let g = DMatrix::from_columns(&[col(&|_| 1.0).column(0), col(&|x| x).column(0)]);
        let x1 = DMatrix::from_columns(&[col(&|x| (3.0 * x).sin()).column(0), col(&|x| 2.0 - 4.0 * x).column(0)]);
        let x2 = col(&|x| x * x * x);
        let y = col(&|x| 0.3 + x + 0.2 * (3.0 * x).sin() - 0.7 * x * x * x + 0.01 * (17.0 * x).cos());
        let split = |m: &DMatrix<f64>| (m.rows(0, n).into_owned(), m.rows(n, n).into_owned());
        let base = LinearFit::new(&split(&g).0, &split(&g).1);
        let b1 = base.block(&[], &split(&x1).0, &split(&x1).1);
        assert_eq!(b1.rank, 1, "2 - 4x lies inside the fit below");
        let b2 = base.block(&[&b1], &split(&x2).0, &split(&x2).1);
        let (et, eh) = base.residualise(&split(&y).0, &split(&y).1);
        let (et, eh) = b1.apply(&et, &eh);
        let p2 = b2.params(&et);
        let (et, eh) = b2.apply(&et, &eh);
        let all = DMatrix::from_columns(&[g.column(0), g.column(1), x1.column(0), x1.column(1), x2.column(0)]);
        let joint = LinearFit::new(&split(&all).0, &split(&all).1);
        let yt = split(&y).0;
        let p = joint.params(&DVector::from_column_slice(yt.as_slice()));
        let r_t = &yt - &split(&all).0 * &p;
        let r_h = joint.heldout(&yt, &split(&y).1);
        assert_relative_eq!(et.column(0).into_owned(), r_t.column(0).into_owned(), epsilon = 1e-12);
        assert_relative_eq!(eh, r_h, epsilon = 1e-12);
        assert_relative_eq!(p2[(0, 0)], p[4], max_relative = 1e-9);
        assert_relative_eq!(
            b2.normal_inverse[(0, 0)],
            joint.normal_inverse[(4, 4)],
            max_relative = 1e-9
        );
    }
}
