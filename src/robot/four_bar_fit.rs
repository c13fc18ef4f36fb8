//! Offline fit of four-bar dimensions to a given passive curve, used to find a physically
//! consistent mechanism behind the paper's fitted fractional 2->3 function (section 4).
//!
//! Least squares on four free dimensions (rod, lever, crank angle, lever angle) with the
//! arm and crank lengths fixed: only ratios matter to an angle, so the arm (the measured
//! axis-2-to-axis-3 distance) fixes the scale, and the crank length is a design choice the
//! caller makes (left free, the fit degenerates to a vanishing crank and lever, a mechanism no
//! one would build). Jacobian by central differences: this runs once, offline, and the closure
//! solution is smooth away from the dead-centre positions.

use super::four_bar::{FourBarError, FourBarGeometry};
use crate::numerics::finite_diff::try_central_difference;
use crate::numerics::lsq::{LmOptions, LsqError, levenberg_marquardt};
use nalgebra::{DMatrix, DVector};

/// The result of [`fit_four_bar`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FourBarFit {
    /// The fitted geometry.
    pub geometry: FourBarGeometry,
    /// Largest `|g_fit(t) - g_target(t)|` over the fitted span \[rad\].
    pub max_abs_error_rad: f64,
    /// RMS of `g_fit - g_target` over the fitted span \[rad\].
    pub rms_error_rad: f64,
}

fn with_params(base: &FourBarGeometry, p: &[f64]) -> FourBarGeometry {
    FourBarGeometry {
        arm_m: base.arm_m,
        crank_m: base.crank_m,
        rod_m: p[0],
        lever_m: p[1],
        crank_angle_rad: p[2],
        lever_angle_rad: p[3],
    }
}

fn residuals(g: &FourBarGeometry, ts: &[f64], target: &dyn Fn(f64) -> f64) -> Result<DVector<f64>, FourBarError> {
    let mut r = DVector::zeros(ts.len());
    for (i, &t) in ts.iter().enumerate() {
        r[i] = g.passive(t)? - target(t);
    }
    Ok(r)
}

/// Least-squares fit of a four-bar whose passive angle matches `target` at `samples` evenly
/// spaced inputs over `[-span_rad, span_rad]`, starting from `start` (whose `arm_m` and
/// `crank_m` are kept), by the program's Levenberg-Marquardt loop
/// ([`crate::numerics::lsq::levenberg_marquardt`], Marquardt damping). Errors if the start
/// cannot be assembled over the span; a step that would break the assembly costs infinity, so
/// the loop rejects it and damps more.
pub fn fit_four_bar(
    target: &dyn Fn(f64) -> f64,
    span_rad: f64,
    samples: usize,
    start: FourBarGeometry,
) -> Result<FourBarFit, FourBarError> {
    let n = samples.max(7);
    let ts: Vec<f64> = (0..n)
        .map(|i| -span_rad + 2.0 * span_rad * i as f64 / (n - 1) as f64)
        .collect();
    residuals(&start, &ts, target)?;
    let p0 = DVector::from_vec(vec![
        start.rod_m,
        start.lever_m,
        start.crank_angle_rad,
        start.lever_angle_rad,
    ]);
    let eval = |p: &DVector<f64>| -> Result<(DVector<f64>, DMatrix<f64>), LsqError> {
        Ok(residual_and_jacobian(&start, p, &ts, target))
    };
    let apply = |p: &DVector<f64>, delta: &DVector<f64>| -> Result<DVector<f64>, LsqError> { Ok(p + delta) };
    let options = LmOptions::marquardt("four-bar dimensions", MAX_ITERATIONS);
    let outcome = levenberg_marquardt(p0, &options, eval, apply).map_err(FourBarError::Fit)?;
    Ok(finish(
        &with_params(&start, outcome.state.as_slice()),
        &outcome.residual,
        n,
    ))
}

/// Steps of [`fit_four_bar`] at most (the fit converges in a few dozen).
const MAX_ITERATIONS: usize = 200;

/// The residual at parameters `p` and its Jacobian by central differences (step `1e-7 (1 +
/// |p_j|)`); where the mechanism cannot be assembled, an infinite residual (a step there is
/// rejected), and a zero column where a difference would leave the assembly.
fn residual_and_jacobian(
    base: &FourBarGeometry,
    p: &DVector<f64>,
    ts: &[f64],
    target: &dyn Fn(f64) -> f64,
) -> (DVector<f64>, DMatrix<f64>) {
    let at = |q: &DVector<f64>| residuals(&with_params(base, q.as_slice()), ts, target);
    let mut jacobian = DMatrix::zeros(ts.len(), NP);
    let Ok(r) = at(p) else {
        return (DVector::from_element(ts.len(), f64::INFINITY), jacobian);
    };
    for j in 0..NP {
        let h = 1e-7 * (1.0 + p[j].abs());
        let moved = |t: f64| {
            let mut q = p.clone();
            q[j] += t;
            at(&q).ok()
        };
        if let Some(column) = try_central_difference(moved, h) {
            jacobian.set_column(j, &column);
        }
    }
    (r, jacobian)
}

/// Number of fitted dimensions.
const NP: usize = 4;

fn finish(geometry: &FourBarGeometry, r: &DVector<f64>, n: usize) -> FourBarFit {
    FourBarFit {
        geometry: *geometry,
        max_abs_error_rad: r.amax(),
        rms_error_rad: (r.norm_squared() / n as f64).sqrt(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::CouplingFunction;

    /// The paper's fitted 2->3 function (section 4).
    fn paper() -> CouplingFunction {
        CouplingFunction::Fractional {
            num: [-0.998132, 0.213253, -0.212863],
            den: [0.096654, -0.0006941],
        }
    }

    #[test]
    #[ignore = "offline exploration; prints the fit"]
    fn explore_paper_four_bar_fit() {
        let f = paper();
        let target = |t: f64| f.passive(t);
        let span = 45f64.to_radians();
        for crank in [0.1, 0.15, 0.2, 0.3, 0.5] {
            for ang in [45.0f64, 90.0, 135.0, -45.0, -90.0, -135.0] {
                let start = FourBarGeometry::parallelogram(0.69312, crank, ang.to_radians());
                match fit_four_bar(&target, span, 91, start) {
                    Ok(fit) => println!("{crank} {ang}: {fit:?}"),
                    Err(e) => println!("{crank} {ang}: {e}"),
                }
            }
        }
    }
}
