//! Passive couplings, eqs. (14)-(15): while actuator `i` moves (actuator `i+1` held still), a
//! second target on link `i+1` is expressed in the moving, already calibrated frame `i+1`
//! (eq. 14), projected and its angle taken (eqs. 6-7) to give the passive displacement of
//! joint `i+1`; a coupling function `g(theta_i)` is then fitted by least squares (eq. 15).
//!
//! Both forms are fitted to absolute passive values `g(t_j) = passive_start + y_j`, with the
//! passive displacement at step 0 supplied by the caller (usually the nominal coupling at the
//! start): increments alone cannot fix the fractional form, whose family is closed under a
//! constant shift (rotating the `(x, y)` pair of the atan), so its Jacobian on increments is
//! singular.

use nalgebra::{DMatrix, DVector, Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

use super::CalibrationError;
use crate::kinematics::AxisLine;
use crate::numerics::lsq;
use crate::robot::CouplingFunction;

const FIT: &str = "coupling fit (eqs. 14-15)";

/// Passive displacements of joint `i+1` from step 0 \[rad\], eqs. (14), (6), (7).
///
/// `base_from_next_axis_start` is the calibrated frame `i+1` at step 0, `axis_i` the
/// calibrated axis `i` (base frame), `active_from_start_rad[j]` the observed active motion of
/// joint `i` since step 0 (eq. 7) and `second_target[j]` the observed second target (base).
pub fn passive_displacements(
    base_from_next_axis_start: &Isometry3<f64>,
    axis_i: &AxisLine,
    active_from_start_rad: &[f64],
    second_target: &[Point3<f64>],
) -> Result<Vec<f64>, CalibrationError> {
    let n = second_target.len();
    if active_from_start_rad.len() != n {
        return Err(CalibrationError::LengthMismatch {
            fit: FIT,
            what: "active displacements",
            got: active_from_start_rad.len(),
            expected: n,
        });
    }
    if n < 2 {
        return Err(CalibrationError::TooFewPoints {
            fit: FIT,
            got: n,
            needed: 2,
        });
    }
    let mut out = Vec::with_capacity(n);
    let mut last = 0.0;
    for (t, p) in active_from_start_rad.iter().zip(second_target) {
        let local = in_next_frame(base_from_next_axis_start, axis_i, *t, p);
        if local.x == 0.0 && local.y == 0.0 {
            return Err(CalibrationError::InvalidInput {
                fit: FIT,
                what: "second target lies on axis i+1",
            });
        }
        let a = local.y.atan2(local.x);
        let k = ((last - a) / std::f64::consts::TAU).round();
        last = a + k * std::f64::consts::TAU;
        out.push(last);
    }
    let a0 = out[0];
    Ok(out.into_iter().map(|a| a - a0).collect())
}

/// The second target `p` (base frame) in frame `i+1` turned about axis `i` by the active motion
/// `t` since step 0 ([`passive_displacements`]).
fn in_next_frame(
    base_from_next_axis_start: &Isometry3<f64>,
    axis_i: &AxisLine,
    t: f64,
    p: &Point3<f64>,
) -> Point3<f64> {
    let o = axis_i.origin_m.coords;
    let turn = Translation3::from(o) * UnitQuaternion::from_axis_angle(&axis_i.direction, t) * Translation3::from(-o);
    (turn * base_from_next_axis_start).inverse() * p
}

/// Each second target's distance \[m\] from axis `i+1` (the arguments of
/// [`passive_displacements`]): what turns an error of its passive angle into a distance.
pub fn second_target_lever_arms_m(
    base_from_next_axis_start: &Isometry3<f64>,
    axis_i: &AxisLine,
    active_from_start_rad: &[f64],
    second_target: &[Point3<f64>],
) -> Vec<f64> {
    active_from_start_rad
        .iter()
        .zip(second_target)
        .map(|(t, p)| {
            let local = in_next_frame(base_from_next_axis_start, axis_i, *t, p);
            local.x.hypot(local.y)
        })
        .collect()
}

/// The parameterisation eq. (15) is fitted in. The description's
/// [`CouplingFitForm`](crate::robot::CouplingFitForm) says which form a user asks for; this is
/// that form resolved for one sweep: a gear carries the ratio it starts from (the slope the
/// sweep measured) or keeps, so that the function it builds and its derivatives need nothing else.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CouplingForm {
    /// [`CouplingFunction::Gear`] with `order` harmonics; the ratio fixed at `ratio` or
    /// fitted from it.
    Gear {
        /// The ratio (start value when fitted).
        ratio: f64,
        /// Fit the ratio too.
        fit_ratio: bool,
        /// Number of harmonics.
        order: usize,
    },
    /// [`CouplingFunction::Fractional`]: parameters `[n0, n1, n2, d0, d1]`.
    Fractional,
}

/// The result of eq. (15).
#[derive(Clone, Debug, PartialEq)]
pub struct CouplingFit {
    /// The fitted function.
    pub function: CouplingFunction,
    /// Fitted parameters: gear `[ratio?, sin.., cos..]`, fractional `[n0, n1, n2, d0, d1]`.
    pub parameters: Vec<f64>,
    /// 1-sigma of each parameter, a-posteriori (`s^2 (J^T J)^-1`).
    pub sigma: Vec<f64>,
    /// RMS of the residuals \[rad\].
    pub residual_rms_rad: f64,
}

fn build(form: &CouplingForm, x: &[f64]) -> CouplingFunction {
    match *form {
        CouplingForm::Gear {
            ratio,
            fit_ratio,
            order,
        } => {
            let (n, h) = if fit_ratio { (x[0], &x[1..]) } else { (ratio, x) };
            CouplingFunction::Gear {
                ratio: n,
                sin: h[..order].to_vec(),
                cos: h[order..2 * order].to_vec(),
            }
        }
        CouplingForm::Fractional => CouplingFunction::Fractional {
            num: [x[0], x[1], x[2]],
            den: [x[3], x[4]],
        },
    }
}

/// `d g / d x` at `t` into `row` (one entry per parameter), `g` = `build(form, x)` (eq. 15's
/// coupling at these parameters). Writes in place: the fit's Jacobian is filled row by row
/// with no allocation per point.
fn gradient_into(form: &CouplingForm, x: &[f64], g: &CouplingFunction, t: f64, row: &mut [f64]) {
    match *form {
        CouplingForm::Gear {
            ratio,
            fit_ratio,
            order,
        } => {
            let n = if fit_ratio { x[0] } else { ratio };
            let first = usize::from(fit_ratio);
            if fit_ratio {
                row[0] = t * g.slope(t) / n;
            }
            for k in 1..=order {
                row[first + k - 1] = (k as f64 * n * t).sin();
                row[first + order + k - 1] = (k as f64 * n * t).cos();
            }
        }
        CouplingForm::Fractional => {
            let (s, c) = t.sin_cos();
            let y = x[0] * s + x[1] * c + x[2];
            let xx = c + x[3] * s + x[4];
            let r2 = xx * xx + y * y;
            let (gy, gx) = (xx / r2, -y / r2);
            row.copy_from_slice(&[gy * s, gy * c, gy, gx * s, gx]);
        }
    }
}

/// The starting parameters of the eq. (15) fit of `form` to the absolute passive angles
/// `target_rad`: the nominal ratio and no harmonics for a gear; for the fractional form, the
/// linear least squares `n0 s + n1 c + n2 - tan(g) (d0 s + d1) = tan(g) c`.
fn initial_parameters(
    form: &CouplingForm,
    active_rad: &[f64],
    target_rad: &[f64],
) -> Result<Vec<f64>, CalibrationError> {
    let n = active_rad.len();
    let target = target_rad;
    Ok(match *form {
        CouplingForm::Gear {
            ratio,
            fit_ratio,
            order,
        } => {
            let mut x = if fit_ratio { vec![ratio] } else { vec![] };
            x.extend(std::iter::repeat_n(0.0, 2 * order));
            x
        }
        CouplingForm::Fractional => {
            // Linear start: n0 s + n1 c + n2 - tan(g) (d0 s + d1) = tan(g) c.
            let a = DMatrix::from_fn(n, 5, |r, k| {
                let (s, c) = active_rad[r].sin_cos();
                let tg = target[r].tan();
                [s, c, 1.0, -tg * s, -tg][k]
            });
            let y = DVector::from_fn(n, |r, _| target[r].tan() * active_rad[r].cos());
            if n < 5 {
                return Err(CalibrationError::TooFewPoints {
                    fit: FIT,
                    got: n,
                    needed: 6,
                });
            }
            lsq::linear_lsq(&a, &y, FIT)?.0.iter().copied().collect()
        }
    })
}

/// The residuals `g(active) - target` (rad) of the coupling `form` with parameters `x`, and
/// their Jacobian.
fn residuals_and_jacobian(
    form: &CouplingForm,
    active_rad: &[f64],
    target_rad: &[f64],
    x: &DVector<f64>,
) -> Result<(DVector<f64>, DMatrix<f64>), CalibrationError> {
    let (n, m) = (active_rad.len(), x.len());
    let target = target_rad;
    let g = build(form, x.as_slice());
    let r = residuals_of(&g, active_rad, target);
    // One scratch row for all points, copied into the column-major Jacobian.
    let mut j = DMatrix::zeros(n, m);
    let mut row = vec![0.0; m];
    for (k, t) in active_rad.iter().enumerate() {
        gradient_into(form, x.as_slice(), &g, *t, &mut row);
        j.row_mut(k).iter_mut().zip(&row).for_each(|(a, b)| *a = *b);
    }
    Ok((r, j))
}

/// The residuals `g(t_k) - target_k` of the coupling `g`.
fn residuals_of(g: &CouplingFunction, active_rad: &[f64], target_rad: &[f64]) -> DVector<f64> {
    DVector::from_fn(active_rad.len(), |k, _| g.passive(active_rad[k]) - target_rad[k])
}

/// 1-sigma of each of the `m` parameters, a-posteriori (`s^2 (J^T J)^-1`) from the residuals
/// `r` of `n` points and their Jacobian `j`.
fn a_posteriori_sigma(r: &DVector<f64>, j: &DMatrix<f64>, n: usize, m: usize) -> Result<Vec<f64>, CalibrationError> {
    let s2 = r.norm_squared() / (n - m).max(1) as f64;
    Ok(if m == 0 {
        vec![]
    } else {
        let inv = lsq::inverse_normal(j, FIT)?;
        (0..m).map(|k| (s2 * inv[(k, k)]).sqrt()).collect()
    })
}

/// The absolute passive angles `passive_start + y_j` the eq. (15) fit is fitted to, checked
/// to be one per active angle (`n`).
fn absolute_targets(
    n: usize,
    passive_from_start_rad: &[f64],
    passive_start_rad: f64,
) -> Result<Vec<f64>, CalibrationError> {
    if passive_from_start_rad.len() != n {
        return Err(CalibrationError::LengthMismatch {
            fit: FIT,
            what: "passive displacements",
            got: passive_from_start_rad.len(),
            expected: n,
        });
    }
    Ok(passive_from_start_rad.iter().map(|y| y + passive_start_rad).collect())
}

/// Fit eq. (15): `active_rad[j]` = absolute active displacement of joint `i`,
/// `passive_from_start_rad[j]` = passive displacement of joint `i+1` since step 0,
/// `passive_start_rad` = its absolute value at step 0.
pub fn fit_coupling(
    form: &CouplingForm,
    active_rad: &[f64],
    passive_from_start_rad: &[f64],
    passive_start_rad: f64,
) -> Result<CouplingFit, CalibrationError> {
    let n = active_rad.len();
    let target = absolute_targets(n, passive_from_start_rad, passive_start_rad)?;
    let x0 = initial_parameters(form, active_rad, &target)?;
    let m = x0.len();
    if n <= m {
        return Err(CalibrationError::TooFewPoints {
            fit: FIT,
            got: n,
            needed: m + 1,
        });
    }
    let eval = |x: &DVector<f64>| residuals_and_jacobian(form, active_rad, &target, x);
    let out = if m == 0 {
        DVector::zeros(0)
    } else {
        lsq::levenberg_marquardt(
            DVector::from_vec(x0),
            &lsq::LmOptions::marquardt(FIT, 200),
            eval,
            |x, d| Ok(x + d),
        )?
        .converged(FIT, None)?
        .state
    };
    let (r, j) = eval(&out)?;
    let sigma = a_posteriori_sigma(&r, &j, n, m)?;
    Ok(CouplingFit {
        function: build(form, out.as_slice()),
        parameters: out.iter().copied().collect(),
        sigma,
        residual_rms_rad: (r.norm_squared() / n as f64).sqrt(),
    })
}

/// Adds `weight * d2 g / dx2` at `t` to `hessian`, `g` = `build(form, x)` (eq. 15's coupling):
/// for the fractional form `g = atan2(Y, X)` with `Y = n0 s + n1 c + n2`, `X = c + d0 s + d1`
/// linear in the parameters (`a = dY/dx`, `b = dX/dx`, `rho = X^2 + Y^2`):
/// `-2XY/rho^2 a a^T + 2XY/rho^2 b b^T + (Y^2 - X^2)/rho^2 (a b^T + b a^T)`; for a gear
/// `N t + sum_k (s_k sin kNt + c_k cos kNt)` only the ratio's terms,
/// `d2g/dN2 = -sum (kt)^2 (s_k sin kNt + c_k cos kNt)`, `d2g/dN ds_k = kt cos kNt`,
/// `d2g/dN dc_k = -kt sin kNt` (none with the ratio fixed: `g` is then linear in `x`).
fn add_hessian(form: &CouplingForm, x: &[f64], t: f64, weight: f64, hessian: &mut DMatrix<f64>) {
    match *form {
        CouplingForm::Gear { fit_ratio, order, .. } => {
            if !fit_ratio {
                return;
            }
            let n = x[0];
            for k in 1..=order {
                let kt = k as f64 * t;
                let (s, c) = (kt * n).sin_cos();
                let (a, b) = (x[k], x[order + k]);
                hessian[(0, 0)] -= weight * kt * kt * (a * s + b * c);
                for (col, v) in [(k, kt * c), (order + k, -kt * s)] {
                    hessian[(0, col)] += weight * v;
                    hessian[(col, 0)] += weight * v;
                }
            }
        }
        CouplingForm::Fractional => {
            let (s, c) = t.sin_cos();
            let y = x[0] * s + x[1] * c + x[2];
            let xx = c + x[3] * s + x[4];
            let rho2 = (xx * xx + y * y).powi(2);
            let (g_yy, g_xy) = (-2.0 * xx * y / rho2, (y * y - xx * xx) / rho2);
            let a = [s, c, 1.0, 0.0, 0.0];
            let b = [0.0, 0.0, 0.0, s, 1.0];
            for r in 0..5 {
                for k in 0..5 {
                    let v = g_yy * (a[r] * a[k] - b[r] * b[k]) + g_xy * (a[r] * b[k] + b[r] * a[k]);
                    hessian[(r, k)] += weight * v;
                }
            }
        }
    }
}

/// The first-order response of the eq. (15) fit to its data, at a fitted optimum `x0`: one
/// Newton step with the cost's exact Hessian at the optimum,
/// `x1 = x0 - H^-1 J(x0)^T r(x0)` with `H = J^T J + sum_i r_i d2r_i/dx2` (Nocedal & Wright,
/// *Numerical Optimization*, 2nd ed., eq. 10.5 and sec. 10.3; the curvature term is what a
/// Gauss-Newton step leaves out: 2-3 % of the four-bar's propagated sigmas on the Table-1 campaign,
/// whose fractional form is nearly degenerate). Its difference between two nearby data sets
/// is the derivative of the optimum to first order in the change (the implicit function
/// theorem on `J^T r = 0`), the one evaluation of the residuals and their Jacobian per data
/// set. Used by the procedure's first-order propagation, whose perturbations are a thousandth
/// of a sigma; the Hessian is computed once per coupling.
#[derive(Clone, Debug)]
pub struct CouplingResponse {
    form: CouplingForm,
    parameters: DVector<f64>,
    /// `H^-1` at the optimum.
    inverse_hessian: DMatrix<f64>,
}

impl CouplingResponse {
    /// The response of the fit of `form` to the data of [`fit_coupling`] at its optimum `x0`
    /// (error if the Hessian there is singular).
    pub fn at(
        form: &CouplingForm,
        active_rad: &[f64],
        passive_from_start_rad: &[f64],
        passive_start_rad: f64,
        x0: &[f64],
    ) -> Result<Self, CalibrationError> {
        let target = absolute_targets(active_rad.len(), passive_from_start_rad, passive_start_rad)?;
        let x = DVector::from_column_slice(x0);
        let (r, j) = residuals_and_jacobian(form, active_rad, &target, &x)?;
        let mut hessian = j.tr_mul(&j);
        for (t, ri) in active_rad.iter().zip(r.iter()) {
            add_hessian(form, x0, *t, *ri, &mut hessian);
        }
        let inverse_hessian = if x0.is_empty() {
            hessian
        } else {
            lsq::inverse_symmetric(&hessian, FIT)?
        };
        Ok(CouplingResponse {
            form: *form,
            parameters: x,
            inverse_hessian,
        })
    }

    /// The fitted parameters the response is taken at.
    pub fn parameters(&self) -> &[f64] {
        self.parameters.as_slice()
    }

    /// The Newton step's parameters for the data of [`fit_coupling`] (slightly moved from
    /// those of the optimum): `x0 - H^-1 J(x0)^T r(x0)`. No a-posteriori sigma and no residual
    /// RMS (NaN): the propagation reads only the parameters.
    pub fn refit(
        &self,
        active_rad: &[f64],
        passive_from_start_rad: &[f64],
        passive_start_rad: f64,
    ) -> Result<CouplingFit, CalibrationError> {
        let target = absolute_targets(active_rad.len(), passive_from_start_rad, passive_start_rad)?;
        let x = if self.parameters.is_empty() {
            self.parameters.clone()
        } else {
            let (r, j) = residuals_and_jacobian(&self.form, active_rad, &target, &self.parameters)?;
            &self.parameters - &self.inverse_hessian * j.tr_mul(&r)
        };
        Ok(CouplingFit {
            function: build(&self.form, x.as_slice()),
            sigma: vec![f64::NAN; x.len()],
            parameters: x.iter().copied().collect(),
            residual_rms_rad: f64::NAN,
        })
    }

    /// `d x / d target`: the optimum's derivative with respect to the absolute passive angles
    /// it is fitted to, at the active angles `active_rad` of the fit: `H^-1 J^T` (from
    /// `J^T r = 0`, `dr / d target = -I`).
    pub fn target_sensitivity(&self, active_rad: &[f64]) -> Result<DMatrix<f64>, CalibrationError> {
        let target = vec![0.0; active_rad.len()];
        let (_, j) = residuals_and_jacobian(&self.form, active_rad, &target, &self.parameters)?;
        Ok(&self.inverse_hessian * j.transpose())
    }
}

/// The coupling of `form` at the parameters `x`, not fitted (no sigma, no residuals): for
/// the propagation's derivatives with respect to a coupling's parameters.
pub fn fixed_coupling(form: &CouplingForm, x: &[f64]) -> CouplingFit {
    CouplingFit {
        function: build(form, x),
        parameters: x.to_vec(),
        sigma: vec![0.0; x.len()],
        residual_rms_rad: 0.0,
    }
}

/// The gradient (base frame, rad/m) of each passive angle of [`passive_displacements`] with
/// respect to its own second target `second_target[j]` (before the step-0 angle is
/// subtracted): `R_j (-l_y, l_x, 0) / (l_x^2 + l_y^2)`, `l` the target in the moving frame
/// `M_j` (eq. 14) and `R_j` its rotation, the derivative of `atan2(l_y, l_x)` (eq. 6).
pub fn passive_angle_gradients(
    base_from_next_axis_start: &Isometry3<f64>,
    axis_i: &AxisLine,
    active_from_start_rad: &[f64],
    second_target: &[Point3<f64>],
) -> Vec<Vector3<f64>> {
    let o = axis_i.origin_m.coords;
    active_from_start_rad
        .iter()
        .zip(second_target)
        .map(|(t, p)| {
            let turn =
                Translation3::from(o) * UnitQuaternion::from_axis_angle(&axis_i.direction, *t) * Translation3::from(-o);
            let frame = turn * base_from_next_axis_start;
            let l = frame.inverse() * p;
            let rho2 = l.x * l.x + l.y * l.y;
            frame.rotation * Vector3::new(-l.y / rho2, l.x / rho2, 0.0)
        })
        .collect()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::{Unit, Vector3};

    /// The paper's four-bar (fractional form) and bevel gear couplings with the forms that
    /// fit them, and their parameters in the fits' order.
    pub(crate) fn paper_couplings() -> [(CouplingForm, CouplingFunction, Vec<f64>); 2] {
        [
            (
                CouplingForm::Fractional,
                CouplingFunction::Fractional {
                    num: [-0.998132, 0.213253, -0.212863],
                    den: [0.096654, -0.0006941],
                },
                vec![-0.998132, 0.213253, -0.212863, 0.096654, -0.0006941],
            ),
            (
                CouplingForm::Gear {
                    ratio: 1.6,
                    fit_ratio: true,
                    order: 1,
                },
                CouplingFunction::Gear {
                    ratio: 32.0 / 19.0,
                    sin: vec![-0.040562],
                    cos: vec![0.000018],
                },
                vec![32.0 / 19.0, -0.040562, 0.000018],
            ),
        ]
    }

    #[test]
    fn recovers_the_paper_four_bar_and_bevel_gear() {
        let t: Vec<f64> = (0..16).map(|j| -0.4 + 0.0524 * j as f64).collect();
        let cases = paper_couplings();
        for (form, truth, params) in cases {
            let g: Vec<f64> = t.iter().map(|x| truth.passive(*x)).collect();
            let y: Vec<f64> = g.iter().map(|v| v - g[0]).collect();
            let fit = fit_coupling(&form, &t, &y, g[0]).unwrap();
            for (a, b) in fit.parameters.iter().zip(&params) {
                assert_relative_eq!(a, b, epsilon = 1e-7);
            }
        }
    }

    /// The forms and parameters the derivatives are checked at: the fractional form and gears
    /// with the ratio fitted or fixed, two harmonics.
    fn derivative_cases() -> [(CouplingForm, Vec<f64>); 3] {
        let gear = |fit_ratio| CouplingForm::Gear {
            ratio: 1.7,
            fit_ratio,
            order: 2,
        };
        [
            (CouplingForm::Fractional, vec![-0.99, 0.21, -0.21, 0.097, -0.0007]),
            (gear(true), vec![1.69, -0.04, 0.002, 0.01, -0.003]),
            (gear(false), vec![-0.04, 0.002, 0.01, -0.003]),
        ]
    }

    /// Noisy data of `form` (seeded, as they come), the fit's optimum polished to the cost's
    /// stationary point, and that optimum's data moved by `h` noise levels along an uneven
    /// direction.
    struct Moved {
        t: Vec<f64>,
        y: Vec<f64>,
        moved: Vec<f64>,
        start: f64,
        x0: Vec<f64>,
    }

    fn moved_data(form: &CouplingForm, truth: &CouplingFunction, seed: u64, h: f64) -> Moved {
        use rand::{RngExt, SeedableRng, rngs::ChaCha12Rng};
        let t: Vec<f64> = (0..16).map(|j| -0.4 + 0.0524 * j as f64).collect();
        let mut rng = ChaCha12Rng::seed_from_u64(seed);
        let noise_rad = 2e-4;
        let g: Vec<f64> = t
            .iter()
            .map(|x| truth.passive(*x) + noise_rad * (rng.random::<f64>() - 0.5))
            .collect();
        let y: Vec<f64> = g.iter().map(|v| v - g[0]).collect();
        let fit = fit_coupling(form, &t, &y, g[0]).unwrap();
        let x0 = polished(form, &t, &y, g[0], &fit.parameters);
        let moved = y
            .iter()
            .enumerate()
            .map(|(k, v)| v + h * noise_rad * ((k * 7 % 5) as f64 - 2.0))
            .collect();
        Moved {
            t,
            y,
            moved,
            start: g[0],
            x0,
        }
    }

    /// The exact optimum near `x0` by the second, differently computed path: undamped
    /// Gauss-Newton steps (the project's least squares) taken to convergence (their linear
    /// rate, a few percent, leaves nothing after 60 steps).
    fn polished(form: &CouplingForm, t: &[f64], y: &[f64], start: f64, x0: &[f64]) -> Vec<f64> {
        let target = absolute_targets(t.len(), y, start).unwrap();
        let options = lsq::LmOptions {
            damping: lsq::Damping::GaussNewton {
                truncate_below: None,
                monotone: false,
            },
            ..lsq::LmOptions::marquardt(FIT, 60)
        };
        let eval = |x: &DVector<f64>| residuals_and_jacobian(form, t, &target, x);
        lsq::levenberg_marquardt(DVector::from_column_slice(x0), &options, eval, |x, d| {
            Ok::<_, CalibrationError>(x + d)
        })
        .unwrap()
        .state
        .iter()
        .copied()
        .collect()
    }

    /// The Newton response against the exact optimum of the moved data (undamped Gauss-Newton
    /// steps to convergence, [`polished`]), on noisy data of both forms moved by a thousandth
    /// of the noise (as the propagation moves them): what is left is second order in the move,
    /// ~1e-6 of the change at this step (a move of ~1e-7 rad against the fits' curvature scale
    /// of ~1e-1 rad), so 1e-4 of the largest change holds with margin; one Gauss-Newton step,
    /// which leaves out the residuals' curvature, misses the fractional form's response on
    /// these data by 1.6e-3 of the largest change and fails. Seeds of the noise as they come.
    #[test]
    fn newton_response_is_the_refit_optimum() {
        for (seed, (form, truth, _)) in paper_couplings().iter().enumerate() {
            let d = moved_data(form, truth, seed as u64 + 11, 1e-3);
            let full = polished(form, &d.t, &d.moved, d.start, &d.x0);
            let response = CouplingResponse::at(form, &d.t, &d.y, d.start, &d.x0).unwrap();
            let newton = response.refit(&d.t, &d.moved, d.start).unwrap();
            let scale = (0..d.x0.len()).map(|k| (full[k] - d.x0[k]).abs()).fold(0.0, f64::max);
            for (k, (exact, start)) in full.iter().zip(&d.x0).enumerate() {
                let change = exact - start;
                let diff = newton.parameters[k] - exact;
                assert!(change.abs() > 0.0, "{form:?} parameter {k} did not move");
                assert!(
                    diff.abs() <= 1e-4 * scale,
                    "{form:?} parameter {k}: {diff:e} of {change:e}"
                );
            }
        }
    }

    /// `target_sensitivity` (`H^-1 J^T`) against central differences
    /// ([`crate::calibration::refine::sensitivity`], the project's finite-difference tool) of
    /// the exact optimum of the data with each target moved, at steps of 1e-3 of the noise:
    /// agreement to the differences' truncation (relative ~1e-6, see
    /// [`newton_response_is_the_refit_optimum`]), checked at 1e-4 of the largest entry.
    #[test]
    fn target_sensitivity_matches_central_differences_of_the_refit() {
        for (seed, (form, truth, _)) in paper_couplings().iter().enumerate() {
            let d = moved_data(form, truth, seed as u64 + 21, 0.0);
            let response = CouplingResponse::at(form, &d.t, &d.y, d.start, &d.x0).unwrap();
            let analytic = response.target_sensitivity(&d.t).unwrap();
            // `sensitivity` differentiates `-f`: hand it the negated optimum.
            let optimum = |y: &[f64]| Some(polished(form, &d.t, y, d.start, &d.x0).iter().map(|v| -v).collect());
            let fd = crate::calibration::refine::sensitivity(optimum, &d.y, &vec![2e-7; d.y.len()]).unwrap();
            let scale = analytic.abs().max();
            let diff = (&analytic - &fd).abs().max();
            assert!(diff <= 1e-4 * scale, "{form:?}: {diff:e} of {scale:e}");
        }
    }

    proptest::proptest! {
        /// The residuals' second derivatives ([`add_hessian`]) against central differences
        /// of the analytic gradient ([`gradient_into`], through the project's
        /// finite-difference tool) for the fractional form and gears with the ratio fitted or
        /// fixed, two harmonics, at any angle in [-1, 1] rad and parameters moved by up to
        /// 0.05 from [`derivative_cases`]: step 1e-6, truncation O(h^2 g^(4)) ~ 1e-12 and
        /// rounding ~ eps / h ~ 2e-10 of O(1) values, so 1e-8 (plus 1e-8 of the largest
        /// entry) bounds both.
        #[test]
        fn residual_hessians_match_central_differences_of_the_gradient(
            t in -1.0..1.0f64,
            moves in proptest::collection::vec(-0.05..0.05f64, 5),
        ) {
            for (form, x0) in derivative_cases() {
                let m = x0.len();
                let x: Vec<f64> = x0.iter().zip(&moves).map(|(a, b)| a + b).collect();
                let mut hessian = DMatrix::zeros(m, m);
                add_hessian(&form, &x, t, 1.0, &mut hessian);
                let gradient = |p: &[f64]| {
                    let mut row = vec![0.0; m];
                    gradient_into(&form, p, &build(&form, p), t, &mut row);
                    Some(row.iter().map(|v| -v).collect())
                };
                let fd = crate::calibration::refine::sensitivity(gradient, &x, &vec![1e-6; m]).unwrap();
                let tolerance = 1e-8 * (1.0 + hessian.abs().max());
                proptest::prop_assert!(
                    (&hessian - &fd).abs().max() <= tolerance,
                    "{:?} at {}: {} vs {}", form, t, hessian, fd
                );
            }
        }
    }

    /// The passive angles' gradients against central differences of
    /// [`passive_displacements`] (each target's angle less that of step 0, so the moved
    /// target's own column is read off at steps >= 1 and step 0's through the others):
    /// agreement to the differences' truncation, `h^2` of the curvature at a 0.1-0.3 m
    /// radius (~1e-8 relative at `h = 1e-6` m), not to a tuned tolerance.
    #[test]
    fn passive_angle_gradients_match_central_differences() {
        let axis_i = AxisLine {
            origin_m: Point3::new(0.1, 0.2, -0.05),
            direction: Unit::new_normalize(Vector3::new(0.2, 0.1, 1.0)),
        };
        let next0 = Isometry3::new(Vector3::new(0.8, 0.2, 0.3), Vector3::new(1.4, 0.2, 0.3));
        let active = [0.0, 0.1, 0.25, 0.3];
        let pts: Vec<Point3<f64>> = (0..4)
            .map(|j| next0 * Point3::new(0.15 - 0.02 * j as f64, 0.05 + 0.03 * j as f64, 0.2))
            .collect();
        let g = passive_angle_gradients(&next0, &axis_i, &active, &pts);
        let h = 1e-6;
        for j in 0..pts.len() {
            for c in 0..3 {
                let moved = |s: f64| {
                    let mut p = pts.clone();
                    p[j][c] += s;
                    passive_displacements(&next0, &axis_i, &active, &p).unwrap()
                };
                let (plus, minus) = (moved(h), moved(-h));
                // Step `l`'s displacement is `a_l - a_0`: moving target 0 moves every other
                // step by `-da_0`, moving target `j >= 1` moves step `j` by `da_j`.
                let (l, sign) = if j == 0 { (1, -1.0) } else { (j, 1.0) };
                let fd = sign * (plus[l] - minus[l]) / (2.0 * h);
                assert!(
                    (fd - g[j][c]).abs() <= 1e-6 * g[j].norm(),
                    "target {j} coordinate {c}: {fd} vs {}",
                    g[j][c]
                );
            }
        }
    }

    #[test]
    fn passive_angles_from_a_moving_frame() {
        let axis_i = AxisLine {
            origin_m: Point3::new(0.1, 0.2, 0.0),
            direction: Unit::new_normalize(Vector3::new(0.0, 0.1, 1.0)),
        };
        let next0 = Isometry3::new(Vector3::new(0.8, 0.2, 0.3), Vector3::new(1.4, 0.2, 0.0));
        let active = [0.0, 0.1, 0.25, 0.3];
        let passive = [0.0, -0.12, -0.2, -0.35];
        let o = axis_i.origin_m.coords;
        let target_local = Point3::new(0.15, 0.05, 0.2);
        let pts: Vec<Point3<f64>> = active
            .iter()
            .zip(passive)
            .map(|(a, p)| {
                let turn = Translation3::from(o)
                    * UnitQuaternion::from_axis_angle(&axis_i.direction, *a)
                    * Translation3::from(-o);
                turn * next0 * Isometry3::rotation(Vector3::z() * p) * target_local
            })
            .collect();
        let got = passive_displacements(&next0, &axis_i, &active, &pts).unwrap();
        for (a, b) in got.iter().zip(passive) {
            assert_relative_eq!(*a, b, epsilon = 1e-12);
        }
    }

    /// The eq.-15 Jacobian against central differences of the residuals, for the fractional
    /// form and gears with the ratio fitted or fixed, two harmonics. Step 1e-6: the truncation
    /// error is O(h^2 g''') ~ 1e-12 and the rounding error ~ eps / h ~ 2e-10 of O(1) values, so
    /// 1e-8 bounds their sum with a margin of 50.
    #[test]
    fn the_coupling_jacobian_matches_central_differences() {
        let t: Vec<f64> = (0..9).map(|j| -0.6 + 0.17 * j as f64).collect();
        let target = vec![0.0; t.len()];
        let cases = derivative_cases();
        for (form, x) in cases {
            let x = DVector::from_vec(x);
            let (_, j) = residuals_and_jacobian(&form, &t, &target, &x).unwrap();
            let h = 1e-6;
            for c in 0..x.len() {
                let (mut up, mut down) = (x.clone(), x.clone());
                up[c] += h;
                down[c] -= h;
                let (ru, _) = residuals_and_jacobian(&form, &t, &target, &up).unwrap();
                let (rd, _) = residuals_and_jacobian(&form, &t, &target, &down).unwrap();
                for k in 0..t.len() {
                    let fd = (ru[k] - rd[k]) / (2.0 * h);
                    assert!(
                        (j[(k, c)] - fd).abs() < 1e-8,
                        "{form:?} d r_{k} / d x_{c}: {} vs {fd}",
                        j[(k, c)]
                    );
                }
            }
        }
    }
}
