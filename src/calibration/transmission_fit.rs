//! Transmission-function fit, eq. (8): least squares of `theta_c = f(theta_a)` over the
//! observed actual displacements of one joint sweep.
//!
//! The observed angles (eq. 7) are increments from step 0, while `f` is a function of the
//! absolute actual displacement. The fit is therefore written on increments,
//! `theta_c^j - theta_c^0 - (theta_a^j - theta_a^0) = sum_k c_k (b_k(theta_a^j) - b_k(theta_a^0))`
//! with `theta_a^0 = f^-1(theta_c^0)` refined by a fixed-point iteration. A constant offset in
//! `f` cannot be seen by increments (it is the transducer offset's business), so an order-1
//! cosine coefficient is identified only through the curvature of `cos` over the span.

use nalgebra::{DMatrix, DVector};

use super::{CalibrationError, lsq};
use crate::robot::Transmission;

const FIT: &str = "transmission fit (eq. 8)";

/// The form of a transmission function to fit; its coefficients are ordered
/// `[sin_1..sin_k, cos_1..cos_k]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TransmissionForm {
    /// [`Transmission::Harmonic`] of the given order (the paper's joints 1, 2, 3, 6: order 1).
    Harmonic {
        /// Number of harmonics.
        order: usize,
    },
    /// [`Transmission::Gear`] of a known ratio with harmonics in the gear angle.
    Gear {
        /// Gear ratio `N` (joint turns per gear turn), not fitted.
        ratio: f64,
        /// Number of harmonics.
        order: usize,
    },
}

impl TransmissionForm {
    /// Number of coefficients (`2 * order`).
    pub fn n_coefficients(&self) -> usize {
        match self {
            TransmissionForm::Harmonic { order } | TransmissionForm::Gear { order, .. } => 2 * order,
        }
    }

    /// Names of the coefficients, e.g. `sin1`, `cos1`.
    pub fn coefficient_names(&self) -> Vec<String> {
        let k = self.n_coefficients() / 2;
        (1..=k)
            .map(|i| format!("sin{i}"))
            .chain((1..=k).map(|i| format!("cos{i}")))
            .collect()
    }

    /// The transmission with these coefficients.
    pub fn build(&self, coefficients: &[f64]) -> Transmission {
        let k = self.n_coefficients() / 2;
        let sin = coefficients[..k].to_vec();
        let cos = coefficients[k..2 * k].to_vec();
        match *self {
            TransmissionForm::Harmonic { .. } => Transmission::Harmonic { sin, cos },
            TransmissionForm::Gear { ratio, .. } => Transmission::Gear { ratio, sin, cos },
        }
    }

    /// `d f / d c_k` at `theta_a`: the basis functions of the (linear-in-coefficients) form.
    pub fn basis(&self, theta_a: f64) -> Vec<f64> {
        let (k, scale, x) = match *self {
            TransmissionForm::Harmonic { order } => (order, 1.0, theta_a),
            TransmissionForm::Gear { ratio, order } => (order, ratio, theta_a / ratio),
        };
        let mut b = vec![0.0; 2 * k];
        for i in 0..k {
            let (s, c) = ((i + 1) as f64 * x).sin_cos();
            b[i] = scale * s;
            b[k + i] = scale * c;
        }
        b
    }
}

/// The result of eq. (8).
#[derive(Clone, Debug, PartialEq)]
pub struct TransmissionFit {
    /// The fitted function.
    pub transmission: Transmission,
    /// Its coefficients `[sin.., cos..]` \[rad\].
    pub coefficients: Vec<f64>,
    /// 1-sigma of each coefficient \[rad\], from the a-posteriori residual variance
    /// (`s^2 (A^T A)^-1`, `s^2 = |res|^2 / (n - 1 - m)`).
    pub sigma: Vec<f64>,
    /// `theta_a^0 = f^-1(theta_c^0)`: the absolute actual displacement at step 0 \[rad\].
    pub actual_start_rad: f64,
    /// RMS of the fit residuals \[rad\].
    pub residual_rms_rad: f64,
}

/// Fit eq. (8): `actual_increments_rad[j]` = observed actual displacement from step 0
/// (eq. 7 accumulated; element 0 is 0), `commands_rad[j]` = absolute command \[rad\].
pub fn fit_transmission(
    form: &TransmissionForm,
    actual_increments_rad: &[f64],
    commands_rad: &[f64],
) -> Result<TransmissionFit, CalibrationError> {
    let n = commands_rad.len();
    let m = form.n_coefficients();
    if actual_increments_rad.len() != n {
        return Err(CalibrationError::LengthMismatch {
            fit: FIT,
            what: "actual increments",
            got: actual_increments_rad.len(),
            expected: n,
        });
    }
    if n < m + 2 {
        return Err(CalibrationError::TooFewPoints {
            fit: FIT,
            got: n,
            needed: m + 2,
        });
    }
    let span = commands_rad.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b))
        - commands_rad.iter().fold(f64::INFINITY, |a, &b| a.min(b));
    if span.is_nan() || span <= 0.0 {
        return Err(CalibrationError::ZeroSpan { fit: FIT });
    }
    let c0 = commands_rad[0];
    let d0 = actual_increments_rad[0];
    let mut start = c0;
    let mut coefficients = vec![0.0; m];
    let mut result = None;
    for _ in 0..40 {
        let b0 = form.basis(start);
        let a = DMatrix::from_fn(n - 1, m, |r, c| {
            form.basis(start + actual_increments_rad[r + 1] - d0)[c] - b0[c]
        });
        let y = DVector::from_fn(n - 1, |r, _| {
            commands_rad[r + 1] - c0 - (actual_increments_rad[r + 1] - d0)
        });
        let (x, inv, res) = lsq::linear_lsq(&a, &y, FIT)?;
        coefficients = x.iter().copied().collect();
        let next = form
            .build(&coefficients)
            .actual_from_command(c0)
            .ok_or(CalibrationError::NotInvertible {
                fit: FIT,
                command_rad: c0,
            })?;
        let moved = (next - start).abs();
        start = next;
        result = Some((inv, res));
        if moved < 1e-14 {
            break;
        }
    }
    let (inv, res) = result.ok_or(CalibrationError::ZeroSpan { fit: FIT })?;
    let dof = (n - 1 - m).max(1) as f64;
    let s2 = res.norm_squared() / dof;
    Ok(TransmissionFit {
        transmission: form.build(&coefficients),
        sigma: (0..m).map(|k| (s2 * inv[(k, k)]).sqrt()).collect(),
        coefficients,
        actual_start_rad: start,
        residual_rms_rad: (res.norm_squared() / (n - 1) as f64).sqrt(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn recovers_a_paper_like_harmonic_and_a_gear() {
        for (form, coeffs) in [
            (TransmissionForm::Harmonic { order: 1 }, vec![0.0035, -0.0009]),
            (
                TransmissionForm::Gear {
                    ratio: 32.0 / 19.0,
                    order: 1,
                },
                vec![0.041227, -0.000013],
            ),
        ] {
            let f = form.build(&coeffs);
            let commands: Vec<f64> = (0..16).map(|j| -0.3 + 0.06 * j as f64).collect();
            let actual: Vec<f64> = commands.iter().map(|&c| f.actual_from_command(c).unwrap()).collect();
            let inc: Vec<f64> = actual.iter().map(|a| a - actual[0]).collect();
            let fit = fit_transmission(&form, &inc, &commands).unwrap();
            for (a, b) in fit.coefficients.iter().zip(&coeffs) {
                assert_relative_eq!(a, b, epsilon = 1e-10);
            }
            assert_relative_eq!(fit.actual_start_rad, actual[0], epsilon = 1e-12);
        }
    }

    #[test]
    fn basis_is_the_coefficient_derivative() {
        let form = TransmissionForm::Gear { ratio: 1.7, order: 2 };
        let c = [0.01, -0.02, 0.003, 0.004];
        let h = 1e-7;
        for k in 0..4 {
            let mut cp = c;
            cp[k] += h;
            let mut cm = c;
            cm[k] -= h;
            let fd = (form.build(&cp).command_from_actual(0.4) - form.build(&cm).command_from_actual(0.4)) / (2.0 * h);
            assert_relative_eq!(fd, form.basis(0.4)[k], epsilon = 1e-7);
        }
    }
}
