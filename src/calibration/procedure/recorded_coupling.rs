//! A coupling fitted by the recording assembly of the covariance propagation: its inputs
//! other than the second targets, its parameters and its first-order response to its data,
//! from which the propagation carries the second targets' noise into the couplings
//! (`S C_y S^T`, [`RecordedCoupling::passive_sensitivity`]).

use super::coupling_start::gear_passive_start_weights;
use crate::calibration::CalibrationError;
use crate::calibration::coupling_fit::{CouplingForm, CouplingResponse};
use crate::kinematics::AxisLine;
use nalgebra::{DMatrix, Isometry3};

/// A fitted coupling's inputs other than the second targets, its parameters and its
/// first-order response to its data (the propagation's).
pub(super) struct RecordedCoupling {
    /// Driven joint (0-based).
    pub(super) k: usize,
    /// Index of the experiment whose second targets it is fitted from.
    pub(super) index: usize,
    /// Calibrated frame `k` at step 0 of the sweep.
    pub(super) frame_next: Isometry3<f64>,
    /// Calibrated axis `k-1`.
    pub(super) axis_from: AxisLine,
    /// Absolute active angles of the driving joint (rad).
    pub(super) active: Vec<f64>,
    /// The form fitted.
    pub(super) form: CouplingForm,
    /// The nominal slope (the fractional form's passive start is `slope * active[0]`).
    pub(super) slope: f64,
    /// The fitted parameters.
    pub(super) parameters: Vec<f64>,
    /// The fit's response at these parameters to its data.
    pub(super) response: CouplingResponse,
}

impl RecordedCoupling {
    /// The active motion since step 0 (rad).
    pub(super) fn active_from_start(&self) -> Vec<f64> {
        self.active.iter().map(|a| a - self.active[0]).collect()
    }

    /// `S = d x / d y`, the fitted parameters' derivative with respect to the passive
    /// displacements they are fitted to (`y`; eq. 15's targets are `y_j + start`):
    /// `S = H^-1 J^T (I + 1 w^T)` ([`CouplingResponse::target_sensitivity`]), `w = d start /
    /// d y` (zero for the fractional form, whose start is the nominal coupling's; a gear's
    /// start is linear in `y`, [`gear_passive_start_weights`]).
    pub(super) fn passive_sensitivity(&self) -> Result<DMatrix<f64>, CalibrationError> {
        let mut s = self.response.target_sensitivity(&self.active)?;
        if let CouplingForm::Gear { order, .. } = self.form {
            let w = gear_passive_start_weights(self.slope, order, &self.active);
            let row_sums: Vec<f64> = s.row_iter().map(|r| r.sum()).collect();
            for (i, total) in row_sums.iter().enumerate() {
                for (j, wj) in w.iter().enumerate() {
                    s[(i, j)] += total * wj;
                }
            }
        }
        Ok(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibration::coupling_fit::fit_coupling;
    use crate::calibration::procedure::coupling_start::passive_start;
    use nalgebra::{Point3, Unit, Vector3};

    /// `passive_sensitivity` against central differences (the project's finite-difference
    /// tool, [`crate::calibration::refine::sensitivity`]) of the Newton refit with the start
    /// recomputed from the moved displacements (the refit's derivative at the optimum is the
    /// optimum's: [`CouplingResponse`]), for the fractional form (start fixed) and a fitted
    /// gear (start a least-squares function of the displacements, which the chain rule's
    /// `w` carries): agreement to the differences' truncation at steps of 1e-7 rad (~1e-6
    /// relative; the refit is linear in the displacements, so only rounding is left),
    /// checked at 1e-5 of the largest entry.
    #[test]
    fn passive_sensitivity_matches_central_differences_of_the_refit() {
        let active: Vec<f64> = (0..16).map(|j| -0.4 + 0.0524 * j as f64).collect();
        // The nominal slope: the parallelogram's for the four-bar, the gear's own ratio.
        let cases = crate::calibration::coupling_fit::tests::paper_couplings().map(|(form, truth, _)| {
            let slope = match form {
                CouplingForm::Gear { ratio, .. } => ratio,
                CouplingForm::Fractional => -1.0,
            };
            (form, truth, slope)
        });
        for (form, truth, slope) in cases {
            let g: Vec<f64> = active
                .iter()
                .enumerate()
                .map(|(j, t)| truth.passive(*t) + 1e-4 * ((j * 5 % 7) as f64 - 3.0))
                .collect();
            let passive: Vec<f64> = g.iter().map(|v| v - g[0]).collect();
            let start = passive_start(&form, slope, &active, &passive);
            let fit = fit_coupling(&form, &active, &passive, start).unwrap();
            let response = CouplingResponse::at(&form, &active, &passive, start, &fit.parameters).unwrap();
            let coupling = RecordedCoupling {
                k: 1,
                index: 0,
                frame_next: Isometry3::identity(),
                axis_from: AxisLine {
                    origin_m: Point3::origin(),
                    direction: Unit::new_normalize(Vector3::z()),
                },
                active: active.clone(),
                form,
                slope,
                parameters: fit.parameters.clone(),
                response: response.clone(),
            };
            let analytic = coupling.passive_sensitivity().unwrap();
            let refit = |y: &[f64]| {
                let start = passive_start(&form, slope, &active, y);
                let x = response.refit(&active, y, start).unwrap().parameters;
                Some(x.iter().map(|v| -v).collect())
            };
            let fd = crate::calibration::refine::sensitivity(refit, &passive, &vec![1e-7; passive.len()]).unwrap();
            let scale = analytic.abs().max();
            let diff = (&analytic - &fd).abs().max();
            assert!(diff <= 1e-5 * scale, "{form:?}: {diff:e} of {scale:e}");
        }
    }
}
