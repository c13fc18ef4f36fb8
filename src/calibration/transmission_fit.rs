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

use super::CalibrationError;
use crate::numerics::lsq;
use crate::robot::{Transmission, TransmissionFitForm};

const FIT: &str = "transmission fit (eq. 8)";

/// How the fitting maths reads a [`TransmissionFitForm`] (the description's form): its
/// coefficients are ordered `[sin_1..sin_k, cos_1..cos_k]`, a polynomial's `[c_1..c_order]`
/// of `s_c = s + sum_k c_k s^k` (m), `c_1` the scale error.
impl TransmissionFitForm {
    /// Number of coefficients (`2 * order`; `order` for a polynomial).
    pub fn n_coefficients(&self) -> usize {
        match self {
            TransmissionFitForm::Harmonic { order } | TransmissionFitForm::Gear { order, .. } => 2 * order,
            TransmissionFitForm::Polynomial { order } => *order,
        }
    }

    /// The highest harmonic order (a polynomial: its highest power).
    pub fn order(&self) -> usize {
        match *self {
            TransmissionFitForm::Harmonic { order }
            | TransmissionFitForm::Gear { order, .. }
            | TransmissionFitForm::Polynomial { order } => order,
        }
    }

    /// The same form one order lower; `None` at order 0.
    pub fn one_order_lower(&self) -> Option<Self> {
        let order = self.order().checked_sub(1)?;
        Some(match *self {
            TransmissionFitForm::Harmonic { .. } => TransmissionFitForm::Harmonic { order },
            TransmissionFitForm::Gear { ratio, .. } => TransmissionFitForm::Gear { ratio, order },
            TransmissionFitForm::Polynomial { .. } => TransmissionFitForm::Polynomial { order },
        })
    }

    /// Names of the coefficients, e.g. `sin1`, `cos1` (`scale`, `c2`, .. for a polynomial).
    pub fn coefficient_names(&self) -> Vec<String> {
        if let TransmissionFitForm::Polynomial { order } = self {
            return (1..=*order)
                .map(|k| if k == 1 { "scale".to_string() } else { format!("c{k}") })
                .collect();
        }
        let k = self.n_coefficients() / 2;
        (1..=k)
            .map(|i| format!("sin{i}"))
            .chain((1..=k).map(|i| format!("cos{i}")))
            .collect()
    }

    /// The transmission with these coefficients.
    pub fn build(&self, coefficients: &[f64]) -> Transmission {
        if let TransmissionFitForm::Polynomial { .. } = self {
            return Transmission::Polynomial {
                c0: 0.0,
                c: coefficients.to_vec(),
            };
        }
        let k = self.n_coefficients() / 2;
        let sin = coefficients[..k].to_vec();
        let cos = coefficients[k..2 * k].to_vec();
        match *self {
            TransmissionFitForm::Gear { ratio, .. } => Transmission::Gear { ratio, sin, cos },
            TransmissionFitForm::Harmonic { .. } | TransmissionFitForm::Polynomial { .. } => {
                Transmission::Harmonic { sin, cos }
            }
        }
    }

    /// `(order, scale, x)`: the harmonics are in `x = theta_a / scale`, `scale` = 1 or the
    /// gear ratio.
    fn harmonic_argument(&self, theta_a: f64) -> (usize, f64, f64) {
        match *self {
            TransmissionFitForm::Harmonic { order } => (order, 1.0, theta_a),
            TransmissionFitForm::Gear { ratio, order } => (order, ratio, theta_a / ratio),
            TransmissionFitForm::Polynomial { .. } => (0, 1.0, theta_a),
        }
    }

    /// [`Self::evaluate`] of a polynomial: basis `s^k`, `k = 1..order`.
    fn evaluate_polynomial(order: usize, coefficients: &[f64], s: f64, basis: &mut [f64]) -> TransmissionValue {
        let (mut v, mut dv, mut ddv) = (0.0, 0.0, 0.0);
        let (mut power, mut power_minus) = (1.0, 0.0); // s^(k-1), s^(k-2)
        for (i, b) in basis.iter_mut().enumerate().take(order) {
            let k = (i + 1) as f64;
            let c = coefficients.get(i).copied().unwrap_or(0.0);
            *b = power * s;
            v += c * power * s;
            dv += c * k * power;
            ddv += c * k * (k - 1.0) * power_minus;
            power_minus = power;
            power *= s;
        }
        TransmissionValue {
            value: s + v,
            slope: 1.0 + dv,
            curvature: ddv,
        }
    }

    /// `d f / d c_k` at `theta_a`: the basis functions of the (linear-in-coefficients) form.
    pub fn basis(&self, theta_a: f64) -> Vec<f64> {
        let mut b = vec![0.0; self.n_coefficients()];
        self.evaluate(&[], theta_a, &mut b);
        b
    }

    /// Writes the basis at `theta_a` into `basis` (length [`Self::n_coefficients`]) and returns
    /// the slope `f'(theta_a)` of the transmission with `coefficients` (an empty slice: the
    /// identity), sharing one `sin_cos` per harmonic between them.
    pub fn basis_and_slope(&self, coefficients: &[f64], theta_a: f64, basis: &mut [f64]) -> f64 {
        self.evaluate(coefficients, theta_a, basis).slope
    }

    /// `(f(theta_a), f'(theta_a))` of the transmission with `coefficients`: the values of
    /// [`Transmission::command_from_actual`] and [`Transmission::slope`] of
    /// [`Self::build`]`(coefficients)` without building it.
    pub fn value_and_slope(&self, coefficients: &[f64], theta_a: f64) -> (f64, f64) {
        let mut basis = [0.0; 8];
        let e = if self.n_coefficients() <= basis.len() {
            self.evaluate(coefficients, theta_a, &mut basis[..self.n_coefficients()])
        } else {
            self.evaluate(coefficients, theta_a, &mut vec![0.0; self.n_coefficients()])
        };
        (e.value, e.slope)
    }

    /// `f`, `f'`, `f''` at `theta_a` with `coefficients` (missing ones are 0), and the basis
    /// into `basis`: one `sin_cos` per harmonic for all of them.
    pub(crate) fn evaluate(&self, coefficients: &[f64], theta_a: f64, basis: &mut [f64]) -> TransmissionValue {
        if let TransmissionFitForm::Polynomial { order } = *self {
            return Self::evaluate_polynomial(order, coefficients, theta_a, basis);
        }
        let (k, scale, x) = self.harmonic_argument(theta_a);
        let (mut v, mut vc, mut dv, mut dvc, mut ddv) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for i in 0..k {
            let kf = (i + 1) as f64;
            let (s, c) = (kf * x).sin_cos();
            basis[i] = scale * s;
            basis[k + i] = scale * c;
            let (a, b) = (
                coefficients.get(i).copied().unwrap_or(0.0),
                coefficients.get(k + i).copied().unwrap_or(0.0),
            );
            // Sine terms summed before cosine terms, as `Transmission` does.
            v += a * s;
            dv += a * kf * c;
            vc += b * c;
            dvc -= b * kf * s;
            ddv -= kf * kf * (a * s + b * c);
        }
        TransmissionValue {
            value: theta_a + scale * (v + vc),
            slope: 1.0 + (dv + dvc),
            curvature: ddv / scale,
        }
    }

    /// `theta_a = f^-1(theta_c)` of the transmission with `coefficients`, started from
    /// `theta_c`; see [`Self::actual_from_command_near`]. `None` where `f` is not increasing.
    pub fn actual_from_command(&self, coefficients: &[f64], theta_c: f64) -> Option<f64> {
        self.actual_from_command_near(coefficients, theta_c, theta_c)
    }

    /// `theta_a = f^-1(theta_c)` started from `guess` (e.g. the solution at the previous
    /// command of a sweep): the root of [`Transmission::actual_from_command`] to rounding.
    pub fn actual_from_command_near(&self, coefficients: &[f64], theta_c: f64, guess: f64) -> Option<f64> {
        let mut basis = vec![0.0; self.n_coefficients()];
        self.invert(coefficients, theta_c, guess, &mut basis).map(|(t, _)| t)
    }

    /// Halley's iteration for `f(t) = theta_c` from `guess` (cubic convergence; `f''` comes
    /// with the same `sin_cos` as `f` and `f'`), with the stopping rules of
    /// [`Transmission::actual_from_command`] (`|f - theta_c| < 1e-15` or a step below
    /// `1e-15 (1 + |t|)`). Returns the root and `f`, `f'`, `f''` with the basis (into
    /// `basis`) at the last point evaluated, which is the root or within that last step of
    /// it: equal to rounding. The arc model inverts every point at every iteration.
    pub(crate) fn invert(
        &self,
        coefficients: &[f64],
        theta_c: f64,
        guess: f64,
        basis: &mut [f64],
    ) -> Option<(f64, TransmissionValue)> {
        let mut t = guess;
        for _ in 0..50 {
            let e = self.evaluate(coefficients, t, basis);
            let r = e.value - theta_c;
            if r.abs() < 1e-15 {
                return Some((t, e));
            }
            if e.slope <= 0.0 || !e.slope.is_finite() {
                return None;
            }
            let newton = r / e.slope;
            let denominator = 1.0 - 0.5 * newton * e.curvature / e.slope;
            // Halley's correction only while it is a small one (far from the root, Newton).
            let step = if (0.5..2.0).contains(&denominator) {
                newton / denominator
            } else {
                newton
            };
            t -= step;
            if step.abs() < 1e-15 * (1.0 + t.abs()) {
                return Some((t, e));
            }
        }
        let e = self.evaluate(coefficients, t, basis);
        ((e.value - theta_c).abs() < 1e-12).then_some((t, e))
    }
}

/// A transmission's value and first two derivatives at one actual angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TransmissionValue {
    /// `f(theta_a)` \[rad\].
    pub value: f64,
    /// `f'(theta_a)`.
    pub slope: f64,
    /// `f''(theta_a)` \[1/rad\].
    pub curvature: f64,
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
    form: &TransmissionFitForm,
    actual_increments_rad: &[f64],
    commands_rad: &[f64],
) -> Result<TransmissionFit, CalibrationError> {
    fit_transmission_passes(form, actual_increments_rad, commands_rad, MAX_PASSES)
}

/// The fixed-point passes of [`fit_transmission`] until `theta_a^0` moves by < 1e-14 rad.
const MAX_PASSES: usize = 40;

/// [`fit_transmission`] with at most `max_passes` fixed-point passes for `theta_a^0`. Each
/// pass multiplies the error of `theta_a^0` by about the coefficients' size (the slope of
/// `f^-1` differs from 1 by that much), so a starting point that a maximum-likelihood fit
/// refines needs only one or two.
pub(crate) fn fit_transmission_passes(
    form: &TransmissionFitForm,
    actual_increments_rad: &[f64],
    commands_rad: &[f64],
    max_passes: usize,
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
    let y = DVector::from_fn(n - 1, |r, _| {
        commands_rad[r + 1] - c0 - (actual_increments_rad[r + 1] - d0)
    });
    let (mut b0, mut b) = (vec![0.0; m], vec![0.0; m]);
    let mut a = DMatrix::zeros(n - 1, m);
    for _ in 0..max_passes.max(1) {
        form.basis_and_slope(&[], start, &mut b0);
        for r in 0..n - 1 {
            form.basis_and_slope(&[], start + actual_increments_rad[r + 1] - d0, &mut b);
            for c in 0..m {
                a[(r, c)] = b[c] - b0[c];
            }
        }
        let (x, inv, res) = lsq::linear_lsq(&a, &y, FIT)?;
        coefficients = x.iter().copied().collect();
        let next = form
            .actual_from_command(&coefficients, c0)
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
            (TransmissionFitForm::Harmonic { order: 1 }, vec![0.0035, -0.0009]),
            (
                TransmissionFitForm::Gear {
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
    fn form_evaluation_matches_the_built_transmission() {
        for (form, coeffs) in [
            (TransmissionFitForm::Harmonic { order: 1 }, vec![0.0035, -0.0009]),
            (
                TransmissionFitForm::Gear { ratio: 1.7, order: 2 },
                vec![0.01, -0.02, 0.003, 0.004],
            ),
            (TransmissionFitForm::Polynomial { order: 3 }, vec![2e-4, -0.05, 0.3]),
        ] {
            let f = form.build(&coeffs);
            for k in 0..20 {
                let t = -2.0 + 0.2 * k as f64;
                let (value, slope) = form.value_and_slope(&coeffs, t);
                assert_relative_eq!(value, f.command_from_actual(t), epsilon = 1e-15);
                assert_relative_eq!(slope, f.slope(t), epsilon = 1e-15);
                let mut basis = vec![0.0; coeffs.len()];
                assert_relative_eq!(form.basis_and_slope(&coeffs, t, &mut basis), slope, epsilon = 1e-15);
                assert_eq!(basis, form.basis(t));
                let a = form.actual_from_command(&coeffs, t).unwrap();
                assert_relative_eq!(a, f.actual_from_command(t).unwrap(), epsilon = 1e-15);
            }
        }
    }

    #[test]
    fn basis_is_the_coefficient_derivative() {
        let form = TransmissionFitForm::Gear { ratio: 1.7, order: 2 };
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
