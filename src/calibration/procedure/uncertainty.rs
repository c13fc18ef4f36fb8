//! Uncertainty of the Table-2 rows: first-order propagation of every axis's covariance
//! through the construction of [`super::model_from_axes`] (`C_rows = J C_axes J^T`, `J` by
//! one-sided differences of the construction; the axes are independent, each from its own
//! experiments).

use super::frames::{FramesError, NominalGeometry};
use crate::kinematics::{AxisLine, PhiModel};
use nalgebra::{DMatrix, Matrix4, Unit, Vector3};
use serde::{Deserialize, Serialize};

/// Significance threshold in sigmas: a deviation below it is "not resolved by the data".
pub const SIGNIFICANT_SIGMAS: f64 = 3.0;

/// Covariance of one axis line: `[tilt_u, tilt_v, shift_u, shift_v]` in the basis `(u, v)`
/// perpendicular to it (direction components \[rad\], position \[m\]; a sliding axis has no
/// position: its shift block is zero).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct AxisCovariance {
    /// First basis vector across the axis.
    pub u: [f64; 3],
    /// Second basis vector across the axis.
    pub v: [f64; 3],
    /// 4 x 4 covariance, row-major.
    pub covariance: [[f64; 4]; 4],
}

impl AxisCovariance {
    /// From a 4 x 4 matrix.
    pub fn new(u: Vector3<f64>, v: Vector3<f64>, c: &Matrix4<f64>) -> Self {
        let mut covariance = [[0.0; 4]; 4];
        for (i, row) in covariance.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x = c[(i, j)];
            }
        }
        AxisCovariance {
            u: u.into(),
            v: v.into(),
            covariance,
        }
    }

    fn perturbed(&self, axis: &AxisLine, k: usize, h: f64) -> AxisLine {
        let (u, v) = (Vector3::from(self.u), Vector3::from(self.v));
        let mut out = *axis;
        match k {
            0 => out.direction = Unit::new_normalize(axis.direction.into_inner() + u * h),
            1 => out.direction = Unit::new_normalize(axis.direction.into_inner() + v * h),
            2 => out.origin_m += u * h,
            _ => out.origin_m += v * h,
        }
        out
    }
}

/// The Table-2 parameters of a model as one vector: per row `[a (m), b (m), alpha, beta]`.
fn row_vector(m: &PhiModel) -> Vec<f64> {
    m.rows
        .iter()
        .flat_map(|r| [r.a_m, r.b_m, r.alpha_rad, r.beta_rad])
        .collect()
}

/// 1-sigma of every row's `[a_m, b_m, alpha_rad, beta_rad]`, from the axes' covariances
/// (`None` for an axis without one contributes nothing: the result is then a lower bound).
pub fn row_sigmas(
    nominal: &PhiModel,
    axes: &[Option<AxisLine>],
    q_ref: &[f64],
    covariances: &[Option<AxisCovariance>],
) -> Result<Vec<[f64; 4]>, FramesError> {
    row_sigmas_on(&NominalGeometry::new(nominal.clone(), q_ref)?, axes, covariances)
}

/// [`row_sigmas`] on the nominal model's part of the construction, computed once
/// ([`NominalGeometry`]). The columns are one-sided differences from the unmoved
/// construction, steps `h = 1e-7` (rad, m): well above rounding (1e-16 of the metre-scale
/// rows, 1e-9 of a column) and far below the curvature scale (the rows bend on the scale of
/// the axes' distances, 0.1-1 m: truncation `h f'' / 2` ~ 1e-6 of a column at most).
pub(super) fn row_sigmas_on(
    geometry: &NominalGeometry,
    axes: &[Option<AxisLine>],
    covariances: &[Option<AxisCovariance>],
) -> Result<Vec<[f64; 4]>, FramesError> {
    let build = |axes: &[Option<AxisLine>]| geometry.model_from_axes(axes).map(|(m, _)| row_vector(&m));
    let base = build(axes)?;
    let mut total = DMatrix::<f64>::zeros(base.len(), base.len());
    let h = 1e-7;
    for (i, cov) in covariances.iter().enumerate() {
        let (Some(cov), Some(axis)) = (cov, axes[i]) else {
            continue;
        };
        let mut jac = DMatrix::<f64>::zeros(base.len(), 4);
        for k in 0..4 {
            if cov.covariance[k][k] == 0.0 {
                continue;
            }
            let mut moved = axes.to_vec();
            moved[i] = Some(cov.perturbed(&axis, k, h));
            let p = build(&moved)?;
            for r in 0..base.len() {
                jac[(r, k)] = (p[r] - base[r]) / h;
            }
        }
        let c = DMatrix::from_fn(4, 4, |a, b| cov.covariance[a][b]);
        total += &jac * c * jac.transpose();
    }
    Ok((0..base.len() / 4)
        .map(|k| [0, 1, 2, 3].map(|p| total[(4 * k + p, 4 * k + p)].max(0.0).sqrt()))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::RobotDescription;

    /// The one-sided row sigmas against a second path: central differences of the
    /// construction through the project's finite-difference tool
    /// ([`crate::calibration::refine::sensitivity`], steps 1e-6: truncation ~1e-12 relative),
    /// on the nominal IRB/L6 at a reference away from zero, each axis with its own correlated
    /// covariance (0.1-0.6 mrad, 0.05-0.3 mm). Agreement within 1e-5 of each sigma (the
    /// one-sided truncation is ~1e-6 of a column) plus 1e-12 (the central differences'
    /// rounding, 1e-16 of the metre-scale rows over the 1e-6 step, times sigmas below 1e-3,
    /// for the parameters the axes do not move); a column off by more fails it (one-sided
    /// steps of 1e-3 instead of 1e-7: 2.7e-5, fails).
    #[test]
    fn one_sided_row_sigmas_match_central_differences() {
        let nominal = RobotDescription::asea_irb6l().nominal_model();
        let q_ref = [0.1, -0.2, 0.15, 0.3, -0.25, 0.4];
        let poses = nominal.poses(&q_ref);
        let axes: Vec<Option<AxisLine>> = (0..nominal.dof()).map(|k| Some(poses.axis(k))).collect();
        let covariances: Vec<Option<AxisCovariance>> = axes
            .iter()
            .enumerate()
            .map(|(k, a)| {
                let d = a.expect("every axis").direction.into_inner();
                let pick = if d.x.abs() < 0.6 { Vector3::x() } else { Vector3::y() };
                let u = d.cross(&pick).normalize();
                let v = d.cross(&u);
                let s = [1e-4 * (1 + k) as f64, 2e-4, 5e-5 * (1 + k) as f64, 3e-4];
                let c = Matrix4::from_fn(|i, j| s[i] * s[j] * if i == j { 1.0 } else { 0.3 });
                Some(AxisCovariance::new(u, v, &c))
            })
            .collect();
        let got = row_sigmas(&nominal, &axes, &q_ref, &covariances).unwrap();
        let geometry = NominalGeometry::new(nominal.clone(), &q_ref).unwrap();
        let rows_at = |x: &[f64]| {
            let moved: Vec<Option<AxisLine>> = axes
                .iter()
                .zip(&covariances)
                .enumerate()
                .map(|(i, (a, c))| {
                    let (mut a, c) = (a.expect("every axis"), c.as_ref().expect("every axis"));
                    for k in (0..4).filter(|&k| x[4 * i + k] != 0.0) {
                        a = c.perturbed(&a, k, x[4 * i + k]);
                    }
                    Some(a)
                })
                .collect();
            // `sensitivity` differentiates `-f`.
            Some(
                row_vector(&geometry.model_from_axes(&moved).ok()?.0)
                    .iter()
                    .map(|v| -v)
                    .collect(),
            )
        };
        let n = 4 * axes.len();
        let j = crate::calibration::refine::sensitivity(rows_at, &vec![0.0; n], &vec![1e-6; n]).unwrap();
        let c = DMatrix::from_fn(n, n, |a, b| match (a / 4 == b / 4, &covariances[a / 4]) {
            (true, Some(cov)) => cov.covariance[a % 4][b % 4],
            _ => 0.0,
        });
        let expected = &j * c * j.transpose();
        for (row, sigmas) in got.iter().enumerate() {
            for (p, s) in sigmas.iter().enumerate() {
                let e = expected[(4 * row + p, 4 * row + p)].max(0.0).sqrt();
                assert!(
                    (s - e).abs() <= 1e-5 * e + 1e-12,
                    "row {} parameter {p}: {s:e} vs {e:e}",
                    row + 1
                );
            }
        }
        assert!(got.iter().flatten().filter(|s| **s > 0.0).count() >= 12, "{got:?}");
    }
}
