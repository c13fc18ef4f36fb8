//! What a free pose's prediction may miss by, beside the instrument's noise: the robot's
//! repeatability and the calibration's own error. `validate` tests residuals against both.
//!
//! Repeatability (as `calibrate` models it: `CalibrationOptions::repeatability_sigma_rad`,
//! default the description's `repeatability_sigma`): each joint value of an execution is off
//! by `dq ~ N(0, diag(sigma^2))`, drawn anew per pose, which moves the tool frame by `J_q dq`
//! (`J_q` the geometric Jacobian, [`geometric_jacobian`]): the pose's targets share it.
//!
//! The calibration's error: its parameters' error `d ~ N(0, C_p)` (`model_covariance`,
//! [`crate::calibration::tool_accuracy`]) moves the tool frame by `J_p d`
//! ([`ToolSensitivity::jacobian`]). With `C_p = L L^T` ([`CorrelatedNormal::factor`]),
//! `d = L e`, `e ~ N(0, I)`: one `e` for every pose, so the poses' errors are correlated
//! ([`crate::numerics::stats::SharedErrorChiSquare`]).
//!
//! Both move the tool frame by a velocity `v` (origin, instrument frame) and a rotation `w`
//! (instrument frame); a tool target at `t` (tool frame) then moves by `v + w x R t =
//! v - [R t]_x w` (`R` the tool frame's rotation), and the rotation measured in the tool
//! frame is `R^T w`. Both Jacobians are taken at the pose's calibrated joint values; the
//! calibration's without the model's carried effects (a sag or backlash moves the joints by
//! far less than the Jacobian's curvature scale).
//!
//! Where the calibration's error is wide enough for the model's curvature to count, its
//! remainder beyond the Jacobian joins the shared error as more components
//! ([`super::prediction_curvature`]), after the Jacobian's and before a free tool frame's.

use super::DiagnosisError;
use super::noise::CleanCampaign;
use super::prediction_curvature::{Curvature, DrawnFrames, with_remainder};
use crate::calibration::procedure::Calibration;
use crate::calibration::tool_accuracy::ToolSensitivity;
use crate::kinematics::{PhiModel, geometric_jacobian};
use crate::measurement::MeasurementSet;
use crate::numerics::stats::CorrelatedNormal;
use crate::robot::{Controller, RobotDescription, RobotModel};
use nalgebra::{DMatrix, Isometry3, Point3};

/// The calibration's parameter error and the robot's repeatability as factors of the tool
/// pose's error at any pose.
pub(super) struct PredictionError<'a> {
    /// The sensitivity of the tool pose to the parameters with a variance, and `L` over them;
    /// absent when the calibration has no `model_covariance`.
    calibration: Option<(ToolSensitivity<'a>, DMatrix<f64>)>,
    /// The repeatability of each joint \[rad or m\].
    repeatability: Vec<f64>,
    /// The calibrated model, and the controller its poses are commanded through.
    robot: &'a RobotModel,
    controller: &'a Controller,
    /// The models drawn from the calibration's error, when its curvature counts.
    curvature: Option<Curvature>,
}

/// The error factors of the tool pose at one pose.
pub(super) struct PoseError<'a> {
    /// The calibrated tool frame (instrument frame, m).
    world_from_tool: Isometry3<f64>,
    /// `J_p L`: rows 0-2 the origin \[mm\], rows 3-5 the rotation \[rad\]; then the free
    /// tool frame's columns ([`PoseError::with_free_tool`]).
    calibration: DMatrix<f64>,
    /// Columns of `calibration` after `J_p L`'s: the free tool frame's.
    free: usize,
    /// `J_q diag(sigma)`, the same rows.
    repeatability: DMatrix<f64>,
    /// The drawn models and their tool frames at this pose ([`super::prediction_curvature`]).
    drawn: Option<(&'a Curvature, DrawnFrames)>,
}

/// A block of residuals' covariance factors: the noise-free parts of what they may miss by.
pub(super) struct BlockFactors {
    /// Of the calibration's error (rows x rank).
    pub calibration: DMatrix<f64>,
    /// Of the repeatability (rows x joints).
    pub repeatability: DMatrix<f64>,
}

impl<'a> PredictionError<'a> {
    /// From `cal`'s `model_covariance` (none: the calibration's error is left out, for a file
    /// written before it was recorded) and the repeatability `cal` was made with. A
    /// covariance that is not one of the model's parameters
    /// ([`crate::calibration::model_parameters::ModelCovariance::validate`]) is an error.
    pub(super) fn new(
        cal: &'a Calibration,
        controller: &'a Controller,
        desc: &RobotDescription,
    ) -> Result<Self, DiagnosisError> {
        let repeatability = cal
            .options
            .joint_repeatability_rad(desc)
            .map_err(crate::calibration::procedure::ProcedureError::from)?;
        let Some(covariance) = &cal.model_covariance else {
            return Ok(PredictionError {
                calibration: None,
                repeatability,
                robot: &cal.robot,
                controller,
                curvature: None,
            });
        };
        covariance.validate(&cal.robot).map_err(|e| DiagnosisError::Model {
            message: format!("the calibration's {e}"),
        })?;
        let sensitivity = ToolSensitivity::new(&cal.robot, controller, &covariance.matrix());
        let factor = CorrelatedNormal::new(sensitivity.covariance())
            .map_err(|e| DiagnosisError::Model {
                message: format!("the calibration's `model_covariance` over the parameters the tool depends on: {e}"),
            })?
            .factor()
            .clone();
        Ok(PredictionError {
            calibration: Some((sensitivity, factor)),
            repeatability,
            robot: &cal.robot,
            controller,
            curvature: None,
        })
    }

    /// With the calibration's error also drawn ([`super::prediction_curvature`]): its
    /// remainder beyond the Jacobian among the shared components. Unchanged without a model
    /// covariance.
    pub(super) fn with_curvature(mut self) -> Self {
        self.curvature = self
            .calibration
            .as_ref()
            .map(|(sensitivity, l)| Curvature::draw(self.robot, sensitivity.parameters(), l));
        self
    }

    /// Without the drawn remainder: the linear prediction.
    pub(super) fn without_curvature(mut self) -> Self {
        self.curvature = None;
        self
    }

    /// Whether the drawn remainder is among the shared components.
    pub(super) fn has_curvature(&self) -> bool {
        self.curvature.is_some()
    }

    /// Shared components of the Jacobian (`L`'s columns), before the remainder's.
    pub(super) fn linear_rank(&self) -> usize {
        self.calibration.as_ref().map_or(0, |(_, l)| l.ncols())
    }

    /// The repeatability of each joint \[rad or m\].
    pub(super) fn repeatability(&self) -> &[f64] {
        &self.repeatability
    }

    /// Whether the calibration's error is included.
    pub(super) fn has_calibration(&self) -> bool {
        self.calibration.is_some()
    }

    /// Components of the calibration's shared error `e` (0 without it): the Jacobian's, then
    /// the remainder's draws.
    pub(super) fn rank(&self) -> usize {
        self.linear_rank() + self.curvature.as_ref().map_or(0, |_| Curvature::DRAWS)
    }

    /// The calibration's error factor (rows x rank, mm) of the points of `subset`, predicted
    /// as [`CleanCampaign`] predicts them (axis targets at their mean position in their link,
    /// estimated again on each moved model): central differences over the parameters; zero
    /// columns without a model covariance.
    pub(super) fn points(
        &self,
        subset: &MeasurementSet,
        desc: &RobotDescription,
        tool_targets_m: &[Point3<f64>],
    ) -> Result<DMatrix<f64>, DiagnosisError> {
        let n = subset.rows().len();
        let Some((sensitivity, l)) = &self.calibration else {
            return Ok(DMatrix::zeros(3 * n, 0));
        };
        let mut j = DMatrix::zeros(3 * n, l.nrows());
        let at = |robot| CleanCampaign::on_robot(subset, robot, desc, tool_targets_m).map(|c| c.positions());
        for (column, (plus, minus, step)) in sensitivity.moved_models().enumerate() {
            for (i, (a, b)) in at(plus)?.iter().zip(at(minus)?).enumerate() {
                let d_mm = (a - b) / step * 1e3;
                j.view_mut((3 * i, column), (3, 1)).copy_from(&d_mm);
            }
        }
        let linear = j * l;
        let Some(curvature) = &self.curvature else {
            return Ok(linear);
        };
        let calibrated = at(self.robot)?;
        let mut moved = DMatrix::zeros(3 * n, Curvature::DRAWS);
        for (column, robot) in curvature.models().enumerate() {
            for (i, (a, b)) in at(robot)?.iter().zip(&calibrated).enumerate() {
                moved.view_mut((3 * i, column), (3, 1)).copy_from(&((a - b) * 1e3));
            }
        }
        let remainder = curvature.remainder(&moved, &linear);
        Ok(with_remainder(&linear, linear.ncols(), &remainder))
    }

    /// The error factors of the tool pose at internal commands `cmd`, whose calibrated joint
    /// values on `phi` are `q`; `known` the drawn models' tool frames there where they were
    /// already computed ([`Curvature::tool_frames`] at the same commands), else computed.
    pub(super) fn at(
        &self,
        phi: &PhiModel,
        (cmd, q): (&[f64], &[f64]),
        known: Option<&DrawnFrames>,
    ) -> Result<PoseError<'_>, DiagnosisError> {
        let in_mm = |mut m: DMatrix<f64>| {
            m.rows_mut(0, 3).scale_mut(1e3);
            m
        };
        let calibration = match &self.calibration {
            Some((sensitivity, l)) => {
                let j = sensitivity
                    .jacobian(cmd)
                    .map_err(|e| DiagnosisError::Model { message: e.to_string() })?;
                in_mm(j * l)
            }
            None => DMatrix::zeros(6, 0),
        };
        let jq = geometric_jacobian(phi, q);
        let repeatability = in_mm(DMatrix::from_fn(6, q.len(), |r, c| jq[(r, c)] * self.repeatability[c]));
        let drawn = match &self.curvature {
            Some(curvature) => Some((
                curvature,
                match known {
                    Some(frames) => frames.clone(),
                    None => curvature
                        .tool_frames(self.robot, self.controller, cmd)
                        .map_err(|e| DiagnosisError::Model { message: e.to_string() })?,
                },
            )),
            None => None,
        };
        Ok(PoseError {
            world_from_tool: phi.world_from_tool(q),
            calibration,
            free: 0,
            repeatability,
            drawn,
        })
    }
}

impl PoseError<'_> {
    /// Components of a tool frame nobody measured ([`PoseError::with_free_tool`]).
    pub(super) const FREE_TOOL: usize = 6;

    /// With the tool frame's error as [`Self::FREE_TOOL`] more columns after the
    /// calibration's: a translation \[mm\] and a rotation \[rad\] in the tool frame, which move
    /// the tool frame by `R v` and `R w` (`R` its rotation). Free components of the test
    /// ([`crate::numerics::stats::SharedErrorChiSquare::with_free`]): a tool frame left
    /// nominal has an error no covariance holds, estimated from the poses instead.
    pub(super) fn with_free_tool(mut self) -> Self {
        let k = self.calibration.ncols();
        let rotation = self.world_from_tool.rotation.to_rotation_matrix();
        let mut columns = self.calibration.clone().resize_horizontally(k + Self::FREE_TOOL, 0.0);
        for block in [0, 3] {
            let mut view = columns.view_mut((block, k + block), (3, 3));
            view.copy_from(rotation.matrix());
        }
        self.calibration = columns;
        self.free = Self::FREE_TOOL;
        self
    }

    /// The drawn models' tool frames at this pose (none without the remainder).
    pub(super) fn into_drawn_frames(self) -> Option<DrawnFrames> {
        self.drawn.map(|(_, frames)| frames)
    }

    /// The factors of the positions of the tool targets at `targets_m` (tool frame), stacked
    /// three rows a target \[mm\].
    pub(super) fn targets(&self, targets_m: &[Point3<f64>]) -> BlockFactors {
        let stacked = |f: &DMatrix<f64>| {
            let mut out = DMatrix::zeros(3 * targets_m.len(), f.ncols());
            for (i, t) in targets_m.iter().enumerate() {
                let lever_mm = (self.world_from_tool.rotation * t.coords) * 1e3;
                let moved = f.rows(0, 3) - lever_mm.cross_matrix() * f.rows(3, 3);
                out.rows_mut(3 * i, 3).copy_from(&moved);
            }
            out
        };
        let calibration = stacked(&self.calibration);
        let calibration = match &self.drawn {
            None => calibration,
            Some((curvature, frames)) => {
                let moved = DMatrix::from_fn(3 * targets_m.len(), Curvature::DRAWS, |r, j| {
                    let t = &targets_m[r / 3];
                    ((frames.drawn[j] * t - frames.calibrated * t) * 1e3)[r % 3]
                });
                self.with_drawn(&calibration, curvature, &moved)
            }
        };
        BlockFactors {
            calibration,
            repeatability: stacked(&self.repeatability),
        }
    }

    /// `factor` (this pose's calibration columns, moved to some rows) with the remainder of
    /// `moved` (those rows' displacement under each draw) inserted before the free columns.
    fn with_drawn(&self, factor: &DMatrix<f64>, curvature: &Curvature, moved: &DMatrix<f64>) -> DMatrix<f64> {
        let k = factor.ncols() - self.free;
        let remainder = curvature.remainder(moved, &factor.columns(0, k).into_owned());
        with_remainder(factor, k, &remainder)
    }

    /// The factors of the tool frame's rotation, in the tool frame \[rad\].
    pub(super) fn rotation(&self) -> BlockFactors {
        let to_tool = self.world_from_tool.rotation.inverse().to_rotation_matrix();
        let to_tool = DMatrix::from_column_slice(3, 3, to_tool.matrix().as_slice());
        let calibration = self.calibration.rows(3, 3).into_owned();
        let calibration = match &self.drawn {
            None => calibration,
            Some((curvature, frames)) => {
                let moved = DMatrix::from_fn(3, Curvature::DRAWS, |r, j| {
                    (frames.drawn[j].rotation * frames.calibrated.rotation.inverse()).scaled_axis()[r]
                });
                self.with_drawn(&calibration, curvature, &moved)
            }
        };
        BlockFactors {
            calibration: &to_tool * calibration,
            repeatability: &to_tool * self.repeatability.rows(3, 3),
        }
    }
}
