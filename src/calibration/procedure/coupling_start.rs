//! The start of a coupling fit (eq. 15's passive angle at step 0): the nominal coupling's for
//! the fractional form; for a gear form, which has no free constant, the linear least squares
//! of the increments on the harmonics, and its weights (the start is linear in the passive
//! displacements), which the warm refits and the propagation's chain rule use.

use crate::calibration::coupling_fit::CouplingForm;
use nalgebra::DMatrix;

/// The absolute passive angle at step 0 the coupling fit of `form` uses: the nominal
/// coupling's for the fractional form, the harmonics' least squares for a gear.
pub(super) fn passive_start(form: &CouplingForm, slope: f64, active: &[f64], passive: &[f64]) -> f64 {
    match *form {
        CouplingForm::Fractional => slope * active[0],
        CouplingForm::Gear { order, .. } => gear_passive_start(slope, order, active, passive),
    }
}

/// The absolute passive angle at step 0 for a gear form `N t + sum (s sin kNt + c cos kNt)`,
/// which has no free constant: linear least squares of the increments `y - N t` on
/// [`gear_start_design`].
pub(super) fn gear_passive_start(ratio: f64, order: usize, active: &[f64], passive_from_start: &[f64]) -> f64 {
    let a = gear_start_design(ratio, order, active);
    let b = nalgebra::DVector::from_fn(active.len(), |j, _| passive_from_start[j] - ratio * active[j]);
    match a.svd(true, true).solve(&b, 1e-12) {
        Ok(x) => x[2 * order],
        Err(_) => ratio * active[0],
    }
}

/// [`gear_passive_start`] from its weights `w` ([`gear_passive_start_weights`]):
/// `w . (y - N t)`, or the nominal `N t_0` without weights (as there when the SVD fails).
pub(super) fn weighted_gear_start(w: &[f64], ratio: f64, active: &[f64], passive_from_start: &[f64]) -> f64 {
    if w.is_empty() {
        return ratio * active[0];
    }
    w.iter()
        .zip(active.iter().zip(passive_from_start))
        .map(|(w, (t, y))| w * (y - ratio * t))
        .sum()
}

/// The design `[sin kNt, cos kNt, -1]` of the gear form's start ([`gear_passive_start`]).
fn gear_start_design(ratio: f64, order: usize, active: &[f64]) -> DMatrix<f64> {
    let mut a = DMatrix::zeros(active.len(), 2 * order + 1);
    for (j, &t) in active.iter().enumerate() {
        for h in 0..order {
            let x = (h + 1) as f64 * ratio * t;
            a[(j, h)] = x.sin();
            a[(j, order + h)] = x.cos();
        }
        a[(j, 2 * order)] = -1.0;
    }
    a
}

/// The weights `w` of the gear form's start, `start = w . (y - N t)` ([`gear_passive_start`]
/// is linear in the increments `y`): the last row of the pseudo-inverse of
/// [`gear_start_design`] (singular values below 1e-12 dropped, as there); empty when its SVD
/// fails (the start is then the nominal `N t_0`, which `y` does not move).
pub(super) fn gear_passive_start_weights(ratio: f64, order: usize, active: &[f64]) -> Vec<f64> {
    match gear_start_design(ratio, order, active)
        .svd(true, true)
        .pseudo_inverse(1e-12)
    {
        Ok(p) => p.row(2 * order).iter().copied().collect(),
        Err(_) => Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The gear start from its weights at the angles before their zero shift (the warm
    /// refits') against the least-squares solve of the fits at the shifted angles (a second
    /// path: nalgebra's SVD solve instead of the pseudo-inverse's row): the same number to
    /// rounding (the start is ~1 rad; 1e-12 leaves the solve's rounding,
    /// ~1e-15, a thousandfold margin), for the first- and second-order gear on noisy data;
    /// with the weights of the wrong order it fails.
    #[test]
    fn weighted_gear_start_is_the_least_squares_start() {
        let active: Vec<f64> = (0..16).map(|j| -0.4 + 0.0524 * j as f64).collect();
        for order in [1, 2] {
            let ratio = -1.6;
            let passive: Vec<f64> = active
                .iter()
                .enumerate()
                .map(|(j, t)| ratio * t + 0.3 + 2e-3 * (2.1 * ratio * t).sin() + 1e-4 * ((j * 5 % 7) as f64 - 3.0))
                .map(|y| y - (ratio * active[0] + 0.3 + 2e-3 * (2.1 * ratio * active[0]).sin()))
                .collect();
            let solved = gear_passive_start(ratio, order, &active, &passive);
            // The weights of the angles before a zero shift of 0.37 rad (the warm refits').
            let raw: Vec<f64> = active.iter().map(|t| t - 0.37).collect();
            let w = gear_passive_start_weights(ratio, order, &raw);
            let weighted = weighted_gear_start(&w, ratio, &active, &passive);
            assert!((solved - weighted).abs() <= 1e-12, "order {order}: {solved} {weighted}");
            let wrong = gear_passive_start_weights(ratio, 3 - order, &active);
            let off = (weighted_gear_start(&wrong, ratio, &active, &passive) - solved).abs();
            assert!(off > 1e-6, "order {order}: {off:e}");
        }
    }
}
