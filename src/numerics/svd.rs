//! The thin singular value decomposition of a tall design matrix by the R-SVD (Chan, "An
//! improved algorithm for computing the singular value decomposition", ACM TOMS 8, 1982;
//! Golub & Van Loan, *Matrix Computations*, 4th ed., sec. 8.6.3): a Householder QR first, then
//! the SVD of the small triangular factor, `X = Q R = (Q U_R) S V^T`. The bidiagonalisation and
//! the QR sweeps then act on an `n x n` matrix instead of the `m x n` design, which for the
//! refinement's designs (hundreds of rows, tens of columns) is several times less work; both
//! factorisations are backward stable, so the result is nalgebra's SVD up to rounding.

use nalgebra::{DMatrix, SVD};

/// The thin SVD of `x` (`U` only when `compute_u`; `V^T` always): the R-SVD when `x` has at
/// least twice as many rows as columns, nalgebra's one-sided bidiagonalisation otherwise
/// (where a QR first would not pay).
pub fn thin_svd(x: DMatrix<f64>, compute_u: bool) -> SVD<f64, nalgebra::Dyn, nalgebra::Dyn> {
    if x.nrows() < 2 * x.ncols() {
        return x.svd(compute_u, true);
    }
    let qr = x.qr();
    // The SVD of `R^T = V S U_R^T` (lower triangular): nalgebra's SVD of the upper triangular
    // `R` itself measured a backward error a hundred times larger on nearly dependent columns.
    let small = qr.r().transpose().svd(true, compute_u);
    SVD {
        u: small.v_t.map(|u_r_t| qr.q() * u_r_t.transpose()),
        v_t: small.u.map(|v| v.transpose()),
        singular_values: small.singular_values,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A design of `m x n` from a seed pattern, its last column the first plus `dependence` times
    /// its own pattern (nearly rank-deficient for a small `dependence`).
    fn design(m: usize, n: usize, seed: u64, dependence: f64) -> DMatrix<f64> {
        let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let mut x = DMatrix::from_fn(m, n, |_, _| next());
        let first = x.column(0).into_owned();
        x.column_mut(n - 1).axpy(1.0, &first, dependence);
        x
    }

    /// `||U S V^T - X||_F`: the factorisation's backward error, which bounds every singular
    /// value's error (Weyl: `|s_i - s~_i| <= ||E||_2 <= ||E||_F`).
    fn backward_error(svd: &SVD<f64, nalgebra::Dyn, nalgebra::Dyn>, x: &DMatrix<f64>) -> f64 {
        let (u, v_t) = (svd.u.as_ref().expect("U"), svd.v_t.as_ref().expect("V^T"));
        (u * DMatrix::from_diagonal(&svd.singular_values) * v_t - x).norm()
    }

    proptest! {
        /// Against nalgebra's direct SVD (a differently computed factorisation): the R-SVD's
        /// backward error is its small SVD's plus the QR's rounding (at most `m n` units of
        /// `||X||`), its singular values are the direct ones within both backward errors, and
        /// `U`, `V` are orthonormal.
        #[test]
        fn r_svd_agrees_with_the_direct_svd(m in 8usize..90, n in 1usize..12, seed in 0u64..1000, dependence in 0.0f64..1e-6) {
            prop_assume!(m >= 2 * n);
            let x = design(m, n, seed, dependence);
            let ours = thin_svd(x.clone(), true);
            let direct = x.clone().svd(true, true);
            let r_t = x.clone().qr().r().transpose();
            let small = r_t.clone().svd(true, true);
            let rounding = (m * n) as f64 * f64::EPSILON * x.norm();
            let (e_ours, e_direct) = (backward_error(&ours, &x), backward_error(&direct, &x));
            let e_small = backward_error(&small, &r_t);
            prop_assert!(e_ours <= e_small + rounding, "{e_ours} vs {e_small} + {rounding}");
            let mut a: Vec<f64> = ours.singular_values.iter().copied().collect();
            let mut b: Vec<f64> = direct.singular_values.iter().copied().collect();
            a.sort_by(f64::total_cmp);
            b.sort_by(f64::total_cmp);
            for (s, t) in a.iter().zip(&b) {
                prop_assert!((s - t).abs() <= e_ours + e_direct + rounding, "{s} vs {t}");
            }
            let (u, v_t) = (ours.u.expect("U asked for"), ours.v_t.expect("V^T always"));
            let eye = DMatrix::<f64>::identity(n, n);
            prop_assert!((u.transpose() * &u - &eye).amax() <= (m * n) as f64 * f64::EPSILON);
            prop_assert!((&v_t * v_t.transpose() - &eye).amax() <= (m * n) as f64 * f64::EPSILON);
        }
    }

    #[test]
    fn a_wide_or_square_matrix_takes_the_direct_path() {
        let x = design(5, 5, 3, 0.0);
        let ours = thin_svd(x.clone(), false);
        assert!(ours.u.is_none());
        assert_eq!(ours.singular_values, x.svd(false, true).singular_values);
    }
}
