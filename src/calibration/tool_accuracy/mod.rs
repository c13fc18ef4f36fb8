//! Predicted tool accuracy: the calibrated model's parameter covariance propagated to the
//! tool point \[mm\] and orientation \[mrad\] at any joint pose.
//!
//! The model's numbers form one vector `p` ([`model_parameter_names`](crate::calibration::model_parameters::model_parameter_names)). Its covariance `C_p`
//! is first-order propagation from the inputs the procedure fits (`calibration::procedure`'s
//! propagation): every axis fit's local covariance, the second and tool targets' noise. Those
//! input blocks are independent (each axis from its own sweep, each point's noise its own), so
//! their covariance is block-diagonal, `C_p = sum_k J_k C_k J_k^T`, and `C_p` itself is full:
//! the rows, offsets, couplings and tool frame built on the same axis are correlated through it.
//!
//! At a joint pose (controller commands `c`) the compensated tool pose's error is, to first
//! order, the calibrated model's prediction error at `c` (fig. 5 inverts the same model), so
//! its covariance is `J C_p J^T` with `J = d T(p, c) / d p` (6 x n: position in the
//! instrument frame \[m\], rotation vector in the instrument frame \[rad\]) by central
//! differences with steps `h_k = 1e-3 sqrt(C_kk)` (as the propagation: far below the
//! curvature scale, far above rounding). The 1-sigma per axis is `sqrt(diag(J C_p J^T))`, the
//! position 1-sigma norm `sqrt(trace)` of its position block (the RMS length of the error
//! vector), the orientation's likewise.

use crate::calibration::model_parameters::model_moved;
use crate::calibration::procedure::{AxisExperiment, Calibration};
use crate::kinematics::FixedFrames;
use crate::robot::{Controller, ModelError, RobotDescription, RobotModel, commands_to_internal};
use nalgebra::{DMatrix, Isometry3, Matrix6, Point3};
use serde::{Deserialize, Serialize};

/// The 1-sigma of the tool pose at one joint pose.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct PoseSigma {
    /// Tool point along the instrument's x, y, z \[mm\].
    pub position_mm: [f64; 3],
    /// `sqrt(sx^2 + sy^2 + sz^2)`: the RMS length of the tool point's error \[mm\].
    pub position_norm_mm: f64,
    /// Tool orientation about the instrument's x, y, z \[mrad\].
    pub orientation_mrad: [f64; 3],
    /// The RMS angle of the orientation error \[mrad\].
    pub orientation_norm_mrad: f64,
}

impl PoseSigma {
    /// From the 6 x 6 covariance of (position \[m\], rotation vector \[rad\]).
    pub fn from_covariance(c: &Matrix6<f64>) -> Self {
        let s = |i: usize| c[(i, i)].max(0.0).sqrt() * 1e3;
        let position_mm = [s(0), s(1), s(2)];
        let orientation_mrad = [s(3), s(4), s(5)];
        let norm = |v: [f64; 3]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        PoseSigma {
            position_mm,
            position_norm_mm: norm(position_mm),
            orientation_mrad,
            orientation_norm_mrad: norm(orientation_mrad),
        }
    }
}

/// The calibrated model and the models moved along every parameter with a variance: what
/// [`ToolSensitivity::sigma_at`] needs, built once for any number of poses.
pub struct ToolSensitivity<'a> {
    robot: &'a RobotModel,
    controller: &'a Controller,
    /// The calibrated model's constant frames, the moved models' frames start from.
    frames: FixedFrames,
    /// Per parameter with a variance: the models at `+h` and `-h` and `2 h`.
    moved: Vec<(Moved, Moved, f64)>,
    /// The parameters with a variance (indices into the model's parameter vector).
    used: Vec<usize>,
    /// The covariance of those parameters.
    covariance: DMatrix<f64>,
}

impl<'a> ToolSensitivity<'a> {
    /// For `robot` with parameter covariance `covariance` (in [`model_parameter_names`](crate::calibration::model_parameters::model_parameter_names)
    /// order), poses commanded through `controller`.
    pub fn new(robot: &'a RobotModel, controller: &'a Controller, covariance: &DMatrix<f64>) -> Self {
        let used: Vec<usize> = (0..covariance.nrows()).filter(|&k| covariance[(k, k)] > 0.0).collect();
        let frames = robot.phi_model().fixed_frames();
        let moved = used
            .iter()
            .map(|&k| {
                let h = 1e-3 * covariance[(k, k)].sqrt();
                let at = |h: f64| Moved::new(model_moved(robot, k, h), robot, &frames);
                (at(h), at(-h), 2.0 * h)
            })
            .collect();
        let covariance = DMatrix::from_fn(used.len(), used.len(), |r, c| covariance[(used[r], used[c])]);
        ToolSensitivity {
            robot,
            controller,
            frames,
            moved,
            used,
            covariance,
        }
    }

    /// The parameters with a variance, in the order of [`Self::jacobian`]'s columns: indices
    /// into the model's parameter vector ([`model_parameter_names`](crate::calibration::model_parameters::model_parameter_names)).
    pub fn parameters(&self) -> &[usize] {
        &self.used
    }

    /// Per parameter with a variance (the columns of [`Self::jacobian`], in order): the
    /// models moved by `+h` and `-h`, and `2 h`.
    pub fn moved_models(&self) -> impl Iterator<Item = (&RobotModel, &RobotModel, f64)> {
        self.moved
            .iter()
            .map(|(plus, minus, step)| (&plus.robot, &minus.robot, *step))
    }

    /// The covariance of the parameters with a variance (the columns of [`Self::jacobian`]).
    pub fn covariance(&self) -> &DMatrix<f64> {
        &self.covariance
    }

    /// The Jacobian of the tool pose (position \[m\], rotation vector \[rad\], instrument
    /// frame) at internal commands `cmd` w.r.t. the parameters with a variance.
    ///
    /// Each moved model's chain is continued from the calibrated model's links below the
    /// first frame or joint value it changes ([`FixedFrames::world_from_last_link_near`]):
    /// the same products in the same order as its full forward kinematics, bit for bit, at a
    /// fraction of the cost (a 1 M-row file has 330 k poses, each with two models per parameter).
    pub fn jacobian(&self, cmd: &[f64]) -> Result<DMatrix<f64>, ModelError> {
        let mut j = DMatrix::zeros(6, self.moved.len());
        let q = self.robot.joint_values(self.controller, cmd)?;
        let links = self.frames.world_from_links(&q);
        let near = (&self.frames, q.as_slice(), links.as_slice());
        for (col, (plus, minus, step)) in self.moved.iter().enumerate() {
            let (a, b) = (
                plus.tool_pose(self.controller, cmd, near)?,
                minus.tool_pose(self.controller, cmd, near)?,
            );
            let dp = (a.translation.vector - b.translation.vector) / *step;
            let dr = (a.rotation * b.rotation.inverse()).scaled_axis() / *step;
            for r in 0..3 {
                j[(r, col)] = dp[r];
                j[(r + 3, col)] = dr[r];
            }
        }
        Ok(j)
    }

    /// The tool pose's 1-sigma at internal commands `cmd`: `sqrt(diag(J C J^T))`.
    pub fn sigma_at(&self, cmd: &[f64]) -> Result<PoseSigma, ModelError> {
        let j = self.jacobian(cmd)?;
        let c = &j * &self.covariance * j.transpose();
        Ok(PoseSigma::from_covariance(&Matrix6::from_fn(|r, k| c[(r, k)])))
    }

    /// The tool point of the calibrated model at internal commands `cmd` \[m\].
    pub fn tool_point(&self, cmd: &[f64]) -> Result<Point3<f64>, ModelError> {
        Ok(Point3::from(
            tool_pose(self.robot, self.controller, cmd)?.translation.vector,
        ))
    }
}

/// A moved model with its phi-model's constant frames, and whether its joints are the
/// calibrated model's (a moved row, base or tool: the joint values are then the same at any
/// pose).
struct Moved {
    robot: RobotModel,
    frames: FixedFrames,
    same_joints: bool,
}

/// The calibrated model's frames, its joint values at a pose and its links there
/// ([`FixedFrames::world_from_links`]).
type Near<'a> = (&'a FixedFrames, &'a [f64], &'a [Isometry3<f64>]);

impl Moved {
    /// `robot`, moved from `calibrated` whose frames are `near` (the unchanged frames are
    /// taken from them, [`FixedFrames::new_near`]).
    fn new(robot: RobotModel, calibrated: &RobotModel, near: &FixedFrames) -> Self {
        Moved {
            frames: FixedFrames::new_near(robot.phi_model(), near),
            same_joints: robot.joints == calibrated.joints,
            robot,
        }
    }

    /// Its tool frame at internal commands `cmd`, `near` the calibrated model's frames, joint
    /// values and links there: `PhiModel::world_from_tool` bit for bit (the last link's frame
    /// times the tool frame, the same products in the same order).
    fn tool_pose(&self, controller: &Controller, cmd: &[f64], near: Near<'_>) -> Result<Isometry3<f64>, ModelError> {
        let (frames, q, links) = near;
        let own;
        let at = match self.same_joints {
            true => q,
            false => {
                own = self.robot.joint_values(controller, cmd)?;
                own.as_slice()
            }
        };
        let last = self.frames.world_from_last_link_near(at, frames, q, links);
        Ok(last * self.frames.model().last_link_from_tool)
    }
}

/// The tool frame of `robot` in the instrument frame at internal commands `cmd`.
pub fn tool_pose(robot: &RobotModel, controller: &Controller, cmd: &[f64]) -> Result<Isometry3<f64>, ModelError> {
    let q = robot.joint_values(controller, cmd)?;
    Ok(robot.phi_model().world_from_tool(&q))
}

/// The predicted tool 1-sigma over a set of poses: RMS and largest of the norms.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ToolSigmaSummary {
    /// Poses evaluated.
    pub poses: usize,
    /// Per joint, the command range the poses are drawn from (uniform, seeded).
    pub ranges: Vec<CommandRange>,
    /// RMS over the poses of the position 1-sigma norm \[mm\].
    pub position_rms_mm: f64,
    /// Its largest value \[mm\].
    pub position_max_mm: f64,
    /// RMS over the poses of the orientation 1-sigma norm \[mrad\].
    pub orientation_rms_mrad: f64,
    /// Its largest value \[mrad\].
    pub orientation_max_mrad: f64,
}

/// One joint's command range.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CommandRange {
    /// Joint (1-based).
    pub joint: usize,
    /// Lowest command \[deg or mm\].
    pub low_deg_or_mm: f64,
    /// Highest command \[deg or mm\].
    pub high_deg_or_mm: f64,
}

impl ToolSigmaSummary {
    /// The summary of `sigmas`, drawn from `ranges`.
    pub fn of(sigmas: &[PoseSigma], ranges_deg_or_mm: Vec<[f64; 2]>) -> Self {
        let rms = |f: &dyn Fn(&PoseSigma) -> f64| {
            (sigmas.iter().map(|s| f(s).powi(2)).sum::<f64>() / sigmas.len().max(1) as f64).sqrt()
        };
        let max = |f: &dyn Fn(&PoseSigma) -> f64| sigmas.iter().map(f).fold(0.0, f64::max);
        ToolSigmaSummary {
            poses: sigmas.len(),
            ranges: ranges_deg_or_mm
                .iter()
                .enumerate()
                .map(|(k, &[low_deg_or_mm, high_deg_or_mm])| CommandRange {
                    joint: k + 1,
                    low_deg_or_mm,
                    high_deg_or_mm,
                })
                .collect(),
            position_rms_mm: rms(&|s| s.position_norm_mm),
            position_max_mm: max(&|s| s.position_norm_mm),
            orientation_rms_mrad: rms(&|s| s.orientation_norm_mrad),
            orientation_max_mrad: max(&|s| s.orientation_norm_mrad),
        }
    }
}

/// The predicted tool 1-sigma of a calibration (`calibration.json`'s `tool_accuracy`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ToolAccuracy {
    /// Poses drawn inside the calibrated spans: every swept joint within the commands of its
    /// sweeps, the others at the reference.
    pub spans: ToolSigmaSummary,
    /// Poses drawn over the workspace: every joint within its limits.
    pub workspace: ToolSigmaSummary,
    /// Seed of the pose draws.
    pub seed: u64,
}

/// How many poses [`predict`] draws and with what seed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PredictionOptions {
    /// Poses inside the spans.
    pub span_poses: usize,
    /// Poses over the workspace (also the map's).
    pub workspace_poses: usize,
    /// Seed of the draws.
    pub seed: u64,
}

impl Default for PredictionOptions {
    /// 200 poses inside the spans (the 1-sigma norm varies by a factor of ~2 there: the RMS
    /// over the draw is within ~3 % of its mean over the spans) and 600 over the workspace
    /// (a factor ~5: within ~3 % too; ~5 poses per occupied cell of the 12 x 9 map). Each
    /// pose costs two forward kinematics per uncertain parameter: 800 poses are ~0.15 s.
    fn default() -> Self {
        PredictionOptions {
            span_poses: 200,
            workspace_poses: 600,
            seed: 16,
        }
    }
}

/// One workspace pose of a prediction: where the tool point is and its 1-sigma.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapPoint {
    /// Distance of the tool point from the base's z axis \[m\].
    pub reach_m: f64,
    /// Height of the tool point above the base's xy plane \[m\].
    pub height_m: f64,
    /// Its predicted 1-sigma.
    pub sigma: PoseSigma,
    /// Whether the pose is one of those drawn inside the calibrated spans (else over the
    /// joint limits).
    pub inside_spans: bool,
}

/// `count` command vectors (file units) drawn uniformly (seeded) in `ranges` per joint.
pub fn draw_poses(ranges: &[[f64; 2]], count: usize, seed: u64) -> Vec<Vec<f64>> {
    use rand::{RngExt, SeedableRng, rngs::ChaCha12Rng};
    let mut rng = ChaCha12Rng::seed_from_u64(seed);
    (0..count)
        .map(|_| {
            ranges
                .iter()
                .map(|&[lo, hi]| if hi > lo { rng.random_range(lo..=hi) } else { lo })
                .collect()
        })
        .collect()
}

/// Per joint the commands its sweeps cover (file units); `[reference, reference]` for a
/// joint no experiment sweeps.
pub fn swept_ranges(experiments: &[AxisExperiment], reference_cmd: &[f64]) -> Vec<[f64; 2]> {
    (0..reference_cmd.len())
        .map(|k| {
            let values = experiments
                .iter()
                .filter(|e| e.joint == k + 1)
                .flat_map(|e| e.commands.iter().map(move |c| c[k]));
            values.fold([reference_cmd[k]; 2], |[lo, hi], v| [lo.min(v), hi.max(v)])
        })
        .collect()
}

/// The predicted tool 1-sigma of `cal` (with its `model_covariance`; `None` without one)
/// over poses drawn in `span_ranges` and within the joint limits of `desc`, and every
/// workspace pose for a map.
pub fn predict(
    cal: &Calibration,
    desc: &RobotDescription,
    span_ranges: Vec<[f64; 2]>,
    options: PredictionOptions,
) -> Result<Option<(ToolAccuracy, Vec<MapPoint>)>, ModelError> {
    let Some(cov) = &cal.model_covariance else {
        return Ok(None);
    };
    let controller = Controller::from_description(desc);
    let sensitivity = ToolSensitivity::new(&cal.robot, &controller, &cov.matrix());
    let sigmas = |ranges: &[[f64; 2]], count: usize, seed: u64| -> Result<Vec<(Vec<f64>, PoseSigma)>, ModelError> {
        draw_poses(ranges, count, seed)
            .into_iter()
            .map(|c| {
                let internal = commands_to_internal(desc, &c);
                Ok((internal.clone(), sensitivity.sigma_at(&internal)?))
            })
            .collect()
    };
    let limits: Vec<[f64; 2]> = desc.joints.iter().map(|j| j.limits).collect();
    let in_spans = sigmas(&span_ranges, options.span_poses, options.seed)?;
    let workspace = sigmas(&limits, options.workspace_poses, options.seed.wrapping_add(1))?;
    let base_from_world = cal.robot.placement.to_isometry().inverse();
    let spans_flagged = workspace
        .iter()
        .map(|p| (p, false))
        .chain(in_spans.iter().map(|p| (p, true)));
    let map = spans_flagged
        .map(|((cmd, sigma), inside_spans)| {
            let p = base_from_world * sensitivity.tool_point(cmd)?;
            Ok(MapPoint {
                reach_m: p.x.hypot(p.y),
                height_m: p.z,
                sigma: *sigma,
                inside_spans,
            })
        })
        .collect::<Result<_, ModelError>>()?;
    let only = |v: &[(Vec<f64>, PoseSigma)]| v.iter().map(|(_, s)| *s).collect::<Vec<_>>();
    let accuracy = ToolAccuracy {
        spans: ToolSigmaSummary::of(&only(&in_spans), span_ranges),
        workspace: ToolSigmaSummary::of(&only(&workspace), limits),
        seed: options.seed,
    };
    Ok(Some((accuracy, map)))
}

#[cfg(test)]
mod tests;
