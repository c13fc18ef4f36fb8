//! The calibration's error beyond its linearisation.
//!
//! `validate` predicts how far the calibration's own error moves a point from the parameter
//! error `d = L e`, `e ~ N(0, I)`, through the model's Jacobian `G`
//! ([`super::predicted_error`]): the law of propagation of uncertainty (JCGM 100:2008, 5.1.2),
//! exact while the model is linear over `d`'s spread. A calibration whose axes are known to
//! tens of milliradians (a few points per sweep over a short span) moves a point a metre away
//! by a second-order term of millimetres, where the noise is a tenth of one: the linear
//! covariance is then too tight in the directions only the noise fills, and the chi-square
//! fails on data the model fits.
//!
//! The part the linearisation leaves out is propagated by Monte Carlo (JCGM 101:2008, 7):
//! for draws `z_j ~ N(0, I)`, `j = 1..M`, the remainder `r_j = f(theta + L z_j) - f(theta) -
//! G z_j` of each point, and `M` more shared components `r_j / sqrt(M)` beside `G`'s. Their
//! covariance is the remainder's second moment about zero (its mean, the second-order bias
//! `tr(H C) / 2`, included); the remainder is uncorrelated with `G e` to second order (odd
//! moments of a normal vanish). The draws are seeded: the same data, the same statistic.
//!
//! Added only where it counts ([`Curvature::counts`]): when the remainder's expected share of
//! the statistic, `tr(S^-1 C_r)` per pose over a sample of the poses (`S` the linear
//! prediction's covariance), scaled to all of them, is at least one unit of the statistic (a
//! quarter of the spread of the smallest, one pose's nine coordinates). Below that the
//! prediction is the linear one.

use crate::calibration::model_parameters::{model_displaced, model_parameter_names};
use crate::kinematics::PhiModel;
use crate::robot::{Controller, ModelError, RobotModel};
use nalgebra::{DMatrix, Isometry3};

/// Draws of the calibration's error and the models they give.
pub(super) struct Curvature {
    /// `z_j`, one per column (rank x [`Curvature::DRAWS`]).
    draws: DMatrix<f64>,
    /// The calibrated model moved by `L z_j`, and its phi model.
    models: Vec<(RobotModel, PhiModel)>,
}

impl Curvature {
    /// Draws `M`. The remainder's covariance has up to `n (n + 1) / 2` components (the
    /// Hessian's, `n` the parameters): a few hundred draws span the ones that carry it on a
    /// 7-axis arm's 60 poses (its chi-square then within a few percent of the exact
    /// second-order covariance's, where 64 draws leave it three times too high), and estimate
    /// each to about `sqrt(2 / M)`, 9 %.
    pub(super) const DRAWS: usize = 256;

    /// The draws' seed.
    const SEED: u64 = 0x00c0_ffee_5eed;

    /// Draws of `robot`'s parameter error `L z` over the parameters `parameters` (indices into
    /// its parameter vector, `factor`'s rows).
    pub(super) fn draw(robot: &RobotModel, parameters: &[usize], factor: &DMatrix<f64>) -> Self {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand::rngs::ChaCha12Rng::seed_from_u64(Self::SEED);
        let draws = DMatrix::from_fn(factor.ncols(), Self::DRAWS, |_, _| StandardNormal.sample(&mut rng));
        let length = model_parameter_names(robot).len();
        let models = (0..Self::DRAWS)
            .map(|j| {
                let moved = factor * draws.column(j);
                let mut delta = vec![0.0; length];
                for (k, &p) in parameters.iter().enumerate() {
                    delta[p] = moved[k];
                }
                let model = model_displaced(robot, &delta);
                let phi = model.phi_model();
                (model, phi)
            })
            .collect();
        Curvature { draws, models }
    }

    /// The drawn models, in the draws' order.
    pub(super) fn models(&self) -> impl Iterator<Item = &RobotModel> {
        self.models.iter().map(|(m, _)| m)
    }

    /// The tool frames (instrument frame, m) of `robot` and of every drawn model at internal
    /// commands `cmd`, each from its own joint values (no carried effect: the remainder is a
    /// difference of the same computation).
    pub(super) fn tool_frames(
        &self,
        robot: &RobotModel,
        controller: &Controller,
        cmd: &[f64],
    ) -> Result<DrawnFrames, ModelError> {
        let frame = |model: &RobotModel, phi: &PhiModel| -> Result<Isometry3<f64>, ModelError> {
            Ok(phi.world_from_tool(&model.joint_values(controller, cmd)?))
        };
        Ok(DrawnFrames {
            calibrated: frame(robot, &robot.phi_model())?,
            drawn: self
                .models
                .iter()
                .map(|(m, phi)| frame(m, phi))
                .collect::<Result<_, _>>()?,
        })
    }

    /// The remainder's factor (rows x [`Self::DRAWS`]): `(moved_j - linear z_j) / sqrt(M)`,
    /// `moved` the points' displacement under each draw (rows x M) and `linear` their factor
    /// `G` (rows x rank), in one unit.
    pub(super) fn remainder(&self, moved: &DMatrix<f64>, linear: &DMatrix<f64>) -> DMatrix<f64> {
        (moved - linear * &self.draws) / (Self::DRAWS as f64).sqrt()
    }

    /// Whether the remainder counts: its expected share of the statistic, `sum tr(S_i^-1
    /// C_i)` over the sampled poses' blocks (`S_i` the linear covariance, `C_i = R_i R_i^T`
    /// the remainder's), times `scale` (poses in all over poses sampled), at least one.
    pub(super) fn counts(blocks: impl Iterator<Item = (DMatrix<f64>, DMatrix<f64>)>, scale: f64) -> bool {
        let share: f64 = blocks
            .filter_map(|(covariance, remainder)| {
                let solved = covariance.cholesky()?.solve(&remainder);
                Some(solved.component_mul(&remainder).sum())
            })
            .sum();
        share * scale >= 1.0
    }
}

/// The tool frames of the calibrated model and of the drawn ones at one pose.
#[derive(Clone)]
pub(super) struct DrawnFrames {
    /// The calibrated model's.
    pub calibrated: Isometry3<f64>,
    /// Each drawn model's, in the draws' order.
    pub drawn: Vec<Isometry3<f64>>,
}

/// `factor` (rows x (k + free)) with `remainder`'s columns inserted after its first `k`.
pub(super) fn with_remainder(factor: &DMatrix<f64>, k: usize, remainder: &DMatrix<f64>) -> DMatrix<f64> {
    let free = factor.ncols() - k;
    let mut out = DMatrix::zeros(factor.nrows(), k + remainder.ncols() + free);
    out.columns_mut(0, k).copy_from(&factor.columns(0, k));
    out.columns_mut(k, remainder.ncols()).copy_from(remainder);
    out.columns_mut(k + remainder.ncols(), free)
        .copy_from(&factor.columns(k, free));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_remainder_of_a_linear_displacement_is_zero_and_of_a_square_its_second_moment() {
        // A stand-in for the model: one point moved by `a z + b z^2` under the draw `z`.
        let curvature = Curvature {
            draws: DMatrix::from_fn(1, Curvature::DRAWS, |_, j| ((j as f64) - 127.5) / 74.0),
            models: Vec::new(),
        };
        let (a, b) = (2.0, 0.5);
        let z = curvature.draws.clone();
        let moved = z.map(|z| a * z + b * z * z);
        let linear = DMatrix::from_element(1, 1, a);
        let r = curvature.remainder(&moved, &linear);
        let expected: f64 = z.iter().map(|z| (b * z * z).powi(2)).sum::<f64>() / Curvature::DRAWS as f64;
        assert!((r.norm_squared() - expected).abs() <= 1e-12 * expected);
        let none = curvature.remainder(&z.map(|z| a * z), &linear);
        assert!(none.norm() <= 1e-12);
    }

    #[test]
    fn inserted_columns_sit_between_the_shared_and_the_free_ones() {
        let factor = DMatrix::from_fn(2, 3, |r, c| (10 * r + c) as f64);
        let remainder = DMatrix::from_element(2, 2, -1.0);
        let out = with_remainder(&factor, 2, &remainder);
        assert_eq!(out.ncols(), 5);
        assert_eq!(out.columns(0, 2), factor.columns(0, 2));
        assert_eq!(out.columns(2, 2), remainder);
        assert_eq!(out.column(4), factor.column(2));
    }

    #[test]
    fn a_remainder_counts_from_one_unit_of_the_statistic() {
        let block = |c: f64| (DMatrix::identity(3, 3), DMatrix::from_element(3, 1, c));
        // tr(S^-1 R R^T) = 3 c^2 per block.
        assert!(!Curvature::counts(
            [block(0.1), block(0.1)].into_iter(),
            10.0 / 2.0 * 0.5
        ));
        assert!(Curvature::counts([block(0.5)].into_iter(), 2.0));
    }
}
