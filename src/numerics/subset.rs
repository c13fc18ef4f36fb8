//! Column subset selection: which parameters of a design the data identify, and how each of the
//! others is made of them.
//!
//! Gram-Schmidt in the caller's order of preference (Golub & Van Loan, *Matrix Computations*,
//! 4th ed., sec. 5.2.8, with one re-orthogonalisation, Giraud, Langou & Rozloznik, Comput.
//! Math. Appl. 50 (2005) 1069, "twice is enough"): each column, scaled to unit length, is kept
//! when its part outside the span of the columns kept before it reaches the tolerance. Exact
//! redundancies are structural (parallel axes, a zero offset and the base's rotation about the
//! same axis), so the preference order, not the data's rounding, decides which of a redundant
//! set is kept, and the same parameters are kept on every data set of one robot.

use nalgebra::{DMatrix, DVector};

/// A column whose length is at most this fraction of the longest column's is zero: 1e4 times
/// the rounding of a column computed from unit-sized terms, 1e-6 of the smallest physical
/// column a calibration meets (a 1e-4 m lever against 100 m of summed lever arms).
pub const ZERO_COLUMN: f64 = 1e-12;

/// A column left out: it lies (to the tolerance) in the span of the chosen ones.
#[derive(Clone, Debug, PartialEq)]
pub struct Rejected {
    /// The column.
    pub column: usize,
    /// Its part outside the chosen span, relative to its length (0 for a zero column).
    pub residual: f64,
    /// `x_column ~ sum coefficient * x_chosen` in the design's own units, largest
    /// `|coefficient| * |x_chosen|` first, terms below 1e-6 of the column's length left out.
    pub combination: Vec<(usize, f64)>,
}

/// The chosen columns and the rejected ones.
#[derive(Clone, Debug, PartialEq)]
pub struct ColumnSubset {
    /// Chosen columns, ascending.
    pub chosen: Vec<usize>,
    /// Rejected columns, ascending.
    pub rejected: Vec<Rejected>,
}

/// The columns of `x` kept in order (module docs): a column is rejected when its part outside
/// the span of the columns kept before it is below `tolerance` of its length.
pub fn select_columns(x: &DMatrix<f64>, tolerance: f64) -> ColumnSubset {
    select_columns_with(x, |_| tolerance)
}

/// [`select_columns`] with a tolerance per column: column `c` is kept when its part outside
/// the span of the columns kept before it reaches `tolerance(c)`.
pub fn select_columns_with(x: &DMatrix<f64>, tolerance: impl Fn(usize) -> f64) -> ColumnSubset {
    let norms: Vec<f64> = x.column_iter().map(|c| c.norm()).collect();
    // A column at rounding level (a regressor that vanishes by symmetry, e.g. a moment about
    // an axis parallel to the joint's, computed as 1e-16) is zero: scaled to unit length its
    // rounding would look independent of everything.
    let largest = norms.iter().copied().fold(0.0, f64::max);
    let norms: Vec<f64> = norms
        .into_iter()
        .map(|n| if n <= ZERO_COLUMN * largest { 0.0 } else { n })
        .collect();
    let mut basis: Vec<DVector<f64>> = Vec::new();
    let mut chosen = Vec::new();
    let mut parts = vec![0.0; x.ncols()];
    for (c, column) in x.column_iter().enumerate() {
        if norms[c] == 0.0 {
            continue;
        }
        let mut w = column / norms[c];
        for _ in 0..2 {
            for q in &basis {
                let along = q.dot(&w);
                w.axpy(-along, q, 1.0);
            }
        }
        parts[c] = w.norm();
        if parts[c] >= tolerance(c) {
            basis.push(w / parts[c]);
            chosen.push(c);
        }
    }
    let rejected: Vec<usize> = (0..x.ncols()).filter(|c| !chosen.contains(c)).collect();
    // One factorisation of the kept columns serves every rejected one.
    let kept = (!rejected.is_empty() && !chosen.is_empty()).then(|| {
        DMatrix::from_columns(&chosen.iter().map(|&k| x.column(k) / norms[k]).collect::<Vec<_>>()).svd(true, true)
    });
    let rejected = rejected
        .into_iter()
        .map(|c| Rejected {
            column: c,
            residual: parts[c],
            combination: kept
                .as_ref()
                .map_or_else(Vec::new, |svd| combination(x, &norms, &chosen, svd, c)),
        })
        .collect();
    ColumnSubset { chosen, rejected }
}

/// Column `c` of `x` as a least-squares combination of the `chosen` columns (`kept`: the SVD
/// of the chosen columns scaled to unit length).
fn combination(
    x: &DMatrix<f64>,
    norms: &[f64],
    chosen: &[usize],
    kept: &nalgebra::SVD<f64, nalgebra::Dyn, nalgebra::Dyn>,
    c: usize,
) -> Vec<(usize, f64)> {
    if norms[c] == 0.0 {
        return Vec::new();
    }
    let target = x.column(c) / norms[c];
    let Ok(beta) = kept.solve(&target, 1e-14) else {
        return Vec::new();
    };
    // In scaled units beta_k is the weight of column k's unit vector in column c's unit vector.
    let mut terms: Vec<(usize, f64, f64)> = chosen
        .iter()
        .zip(beta.iter())
        .filter(|(_, b)| b.abs() > 1e-6)
        .map(|(&k, &b)| (k, b * norms[c] / norms[k], b.abs()))
        .collect();
    terms.sort_by(|a, b| b.2.total_cmp(&a.2).then(a.0.cmp(&b.0)));
    terms.into_iter().map(|(k, coefficient, _)| (k, coefficient)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Column 2 = 2 col0 - 3 col1 exactly, column 4 is zero, column 3 independent: one of the
    /// dependent triple and the zero column are rejected, and the rejected column is rebuilt
    /// from its combination (a second path: the product of the original columns).
    #[test]
    fn rejects_exact_combinations_and_zero_columns() {
        let x = DMatrix::from_fn(6, 5, |r, c| {
            let a = (r as f64 * 0.7).sin();
            let b = (r as f64 * 1.3 + 0.2).cos();
            match c {
                0 => a,
                1 => b,
                2 => 2.0 * a - 3.0 * b,
                3 => (r * r) as f64,
                _ => 0.0,
            }
        });
        let s = select_columns(&x, 1e-7);
        assert_eq!(s.chosen.len(), 3);
        assert!(s.chosen.contains(&3));
        assert_eq!(s.rejected.len(), 2);
        let r = &s.rejected[0];
        assert!(r.column < 3 && r.residual < 1e-12);
        let rebuilt = r
            .combination
            .iter()
            .fold(DVector::zeros(6), |acc, &(k, c)| acc + x.column(k) * c);
        assert!((rebuilt - x.column(r.column)).norm() < 1e-10);
        assert!(s.rejected[1].combination.is_empty() && s.rejected[1].column == 4);
    }

    /// Two equal columns: the first is kept whichever is scaled larger.
    #[test]
    fn ties_keep_the_first_column() {
        for scale in [1e-3, 1.0, 1e3] {
            let x = DMatrix::from_fn(4, 2, |r, c| (r as f64 + 1.0) * if c == 1 { scale } else { 1.0 });
            let s = select_columns(&x, 1e-7);
            assert_eq!(s.chosen, vec![0]);
            assert!((s.rejected[0].combination[0].1 - scale).abs() < 1e-9 * scale);
        }
    }
}
