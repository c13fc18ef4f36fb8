//! Uncertainty of the Table-2 rows: first-order propagation of every axis's covariance
//! through the construction of [`super::model_from_axes`] (`C_rows = J C_axes J^T`, `J` by
//! central differences of the construction; the axes are independent, each from its own
//! experiments).

use super::frames::{FramesError, NominalGeometry, model_from_axes};
use crate::kinematics::{AxisLine, PhiModel};
use nalgebra::{DMatrix, Matrix4, Unit, Vector3};
use serde::{Deserialize, Serialize};

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
    let base = row_vector(&model_from_axes(nominal, axes, q_ref)?.0);
    // The nominal model's part computed once for the perturbed models.
    let geometry = NominalGeometry::new(nominal.clone(), q_ref)?;
    let build = |axes: &[Option<AxisLine>]| geometry.model_from_axes(axes).map(|(m, _)| row_vector(&m));
    let mut total = DMatrix::<f64>::zeros(base.len(), base.len());
    // Steps well above rounding (1e-16 relative) and far below the curvature scale.
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
            let mut plus = axes.to_vec();
            plus[i] = Some(cov.perturbed(&axis, k, h));
            let mut minus = axes.to_vec();
            minus[i] = Some(cov.perturbed(&axis, k, -h));
            let (p, m) = (build(&plus)?, build(&minus)?);
            for r in 0..base.len() {
                jac[(r, k)] = (p[r] - m[r]) / (2.0 * h);
            }
        }
        let c = DMatrix::from_fn(4, 4, |a, b| cov.covariance[a][b]);
        total += &jac * c * jac.transpose();
    }
    Ok((0..nominal.rows.len())
        .map(|k| [0, 1, 2, 3].map(|p| total[(4 * k + p, 4 * k + p)].max(0.0).sqrt()))
        .collect())
}
