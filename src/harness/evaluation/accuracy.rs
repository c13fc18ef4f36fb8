//! The accuracy and repeatability tests: commands executed by the (simulated) real robot,
//! the three tool targets measured, errors against the required pose.
//!
//! Definitions (per pose):
//! - **position error** \[mm\]: the distance between the measured tool point and where the
//!   required pose puts it. The tool point is tool target 0 (`(0, 0, 150)` mm on the tool's Z
//!   axis, the point the tool presents): it is measured directly, so the instrument noise
//!   enters once (0.19 mm 3-D RMS), whereas the tool-frame origin fitted from the three
//!   targets lies 150 mm behind them and would add the fit's rotation noise times 150 mm
//!   (about 0.3 mm more).
//! - **orientation error** \[rad\]: the angle of `R_required^T R_fit`, with `R_fit` the rigid
//!   fit ([`rigid_fit`]: Horn's quaternion) of the three measured targets to their tool-frame positions.
//! - The same two errors **without measurement noise and jitter** (`model_*`): what the
//!   robot's kinematic model error alone leaves, the quantity the calibration controls.

use crate::kinematics::{rigid_fit, rotation_vector};
use crate::measurement::{MeasurementModel, TriangulationError};
pub use crate::numerics::stats::Stats;
use crate::physics::InstrumentScale;
use crate::plan::PoseConditions;
use crate::robot::{Controller, RobotDescription, RobotModel};
use crate::sim::{AnalyticArm, ArmExecutor, Effects, ExecuteError};
use nalgebra::{Isometry3, Point3};
use rand::{RngExt, SeedableRng, rngs::ChaCha12Rng};
use serde::{Deserialize, Serialize};

/// Errors of one execution of one command against the required pose.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ToolError {
    /// Measured tool point vs required \[mm\].
    pub position_mm: f64,
    /// Rigid fit of the measured targets vs required orientation \[rad\].
    pub orientation_rad: f64,
    /// Actual tool point (no jitter, no measurement noise) vs required \[mm\].
    pub model_position_mm: f64,
    /// Actual tool orientation (no jitter, no noise) vs required \[rad\].
    pub model_orientation_rad: f64,
}

/// Why a pose could not be evaluated.
#[derive(Debug, thiserror::Error)]
pub enum EvaluationError {
    /// The robot cannot execute the command.
    #[error("executing the command: {0}")]
    Execute(ExecuteError),
    /// The instrument cannot see a target.
    #[error("measuring a tool target: {0}")]
    Measure(TriangulationError),
    /// The three targets are collinear (a bad tool description).
    #[error("the tool targets do not define a frame")]
    DegenerateTool,
}

/// The simulated real robot behind its unchanged controller, with its unmodelled effects, the
/// tool targets and the instrument (with its scale error, if any).
#[derive(Clone, Debug)]
pub struct TestBench {
    /// The real robot (truth, controller, effects, repeatability jitter).
    arm: AnalyticArm,
    /// The same robot without repeatability: its model error alone.
    exact_arm: AnalyticArm,
    /// Tool targets in the tool frame \[m\]; target 0 is the tool point.
    tool_targets_m: Vec<Point3<f64>>,
    /// The instrument.
    instrument: MeasurementModel,
    /// Its scale error (from the effects).
    instrument_scale: Option<InstrumentScale>,
    /// Conditions of every test pose.
    conditions: PoseConditions,
}

/// How far below or above each joint's command the robot starts \[rad or m\], so that every
/// joint reaches the test pose moving (a backlash band then shows, a jitter is drawn). The
/// direction per joint is random per pose (the robot reaches test poses along arbitrary paths).
pub const APPROACH_STEP: f64 = 0.05;

/// Per-pose random stream: `seed` and the pose index mixed (SplitMix64), so every command
/// kind evaluated at pose `i` sees the same jitter and measurement noise (common random
/// numbers) and the result does not depend on the evaluation order.
pub fn pose_rng(seed: u64, index: usize) -> ChaCha12Rng {
    let mut z = seed ^ (index as u64).wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    ChaCha12Rng::seed_from_u64(z ^ (z >> 31))
}

fn angle_between(a: &Isometry3<f64>, b: &Isometry3<f64>) -> f64 {
    rotation_vector(&(a.rotation.inverse() * b.rotation)).norm()
}

impl TestBench {
    /// `truth` behind the nominal controller of `desc`, with `effects` (link masses for
    /// compliance from `desc`), measured by `instrument`; every test pose under `conditions`.
    pub fn new(
        truth: &RobotModel,
        desc: &RobotDescription,
        effects: &Effects,
        instrument: MeasurementModel,
        conditions: PoseConditions,
    ) -> Self {
        let controller = Controller::from_description(desc);
        let mut exact = truth.clone();
        for j in &mut exact.joints {
            j.repeatability_sigma = 0.0;
        }
        TestBench {
            arm: AnalyticArm::new(truth.clone(), controller.clone()).with_effects(effects.clone(), desc),
            exact_arm: AnalyticArm::new(exact, controller).with_effects(effects.clone(), desc),
            tool_targets_m: desc.tool_targets_m(),
            instrument,
            instrument_scale: effects.instrument_scale,
            conditions,
        }
    }

    /// Executes `cmd` on a fresh copy of `prototype` after an approach from
    /// [`APPROACH_STEP`] away in every joint, the directions drawn from `approach`; the
    /// command's jitter is drawn from `rng`. Returns the tool pose.
    fn execute(
        &self,
        prototype: &AnalyticArm,
        cmd: &[f64],
        approach: &mut ChaCha12Rng,
        rng: &mut ChaCha12Rng,
    ) -> Result<Isometry3<f64>, EvaluationError> {
        let mut arm = prototype.clone();
        let start: Vec<f64> = cmd
            .iter()
            .map(|c| c - APPROACH_STEP * if approach.random::<bool>() { 1.0 } else { -1.0 })
            .collect();
        arm.execute(&start, &self.conditions, approach)?;
        let links = arm.execute(cmd, &self.conditions, rng)?;
        Ok(links[links.len() - 1] * arm.last_link_from_tool())
    }

    /// One execution of `cmd` (jitter drawn from `rng`; approach directions from a stream
    /// derived from it), the three targets measured. Returns the measured targets \[m\] and the
    /// tool pose without jitter.
    fn execute_and_measure(
        &self,
        cmd: &[f64],
        rng: &mut ChaCha12Rng,
    ) -> Result<(Vec<Point3<f64>>, Isometry3<f64>), EvaluationError> {
        let approach_seed: u64 = rng.random();
        let exact = self.execute(
            &self.exact_arm,
            cmd,
            &mut ChaCha12Rng::seed_from_u64(approach_seed),
            &mut ChaCha12Rng::seed_from_u64(0),
        )?;
        let executed = self.execute(&self.arm, cmd, &mut ChaCha12Rng::seed_from_u64(approach_seed), rng)?;
        Ok((self.measure_tool_targets(&executed, rng)?, exact))
    }

    /// The tool targets of a tool pose as the instrument (with its scale error) reports them.
    fn measure_tool_targets(
        &self,
        world_from_tool: &Isometry3<f64>,
        rng: &mut ChaCha12Rng,
    ) -> Result<Vec<Point3<f64>>, TriangulationError> {
        self.tool_targets_m
            .iter()
            .map(|t| {
                let m = self.instrument.measure(&(world_from_tool * t), rng)?;
                Ok(self.instrument_scale.map_or(m, |s| s.applied_to(&m)))
            })
            .collect()
    }

    /// Executes `cmd` once and scores it against `required` (module docs).
    pub fn tool_error(
        &self,
        required: &Isometry3<f64>,
        cmd: &[f64],
        rng: &mut ChaCha12Rng,
    ) -> Result<ToolError, EvaluationError> {
        let (measured, exact) = self.execute_and_measure(cmd, rng)?;
        let (fit, _) = rigid_fit(&self.tool_targets_m, &measured).ok_or(EvaluationError::DegenerateTool)?;
        let tool_point = self.tool_targets_m[0];
        Ok(ToolError {
            position_mm: (measured[0] - required * tool_point).norm() * 1e3,
            orientation_rad: angle_between(required, &fit),
            model_position_mm: (exact * tool_point - required * tool_point).norm() * 1e3,
            model_orientation_rad: angle_between(required, &exact),
        })
    }

    /// The repeatability test of paper section 4: `cmd` executed twice (each time reached
    /// from elsewhere), the tool measured each time. Returns `(observed radial mm, observed
    /// orientation rad, robot-only radial mm, robot-only orientation rad)`: the distance
    /// between the two measured tool points and the angle between the two fitted frames, then
    /// the same without measurement noise.
    pub fn repeatability(&self, cmd: &[f64], rng: &mut ChaCha12Rng) -> Result<[f64; 4], EvaluationError> {
        let mut observed = Vec::new();
        let mut actual = Vec::new();
        for _ in 0..2 {
            let approach_seed: u64 = rng.random();
            let pose = self.execute(&self.arm, cmd, &mut ChaCha12Rng::seed_from_u64(approach_seed), rng)?;
            let measured = self.measure_tool_targets(&pose, rng)?;
            let (fit, _) = rigid_fit(&self.tool_targets_m, &measured).ok_or(EvaluationError::DegenerateTool)?;
            observed.push((measured[0], fit));
            actual.push(pose);
        }
        let t0 = self.tool_targets_m[0];
        Ok([
            (observed[0].0 - observed[1].0).norm() * 1e3,
            angle_between(&observed[0].1, &observed[1].1),
            (actual[0] * t0 - actual[1] * t0).norm() * 1e3,
            angle_between(&actual[0], &actual[1]),
        ])
    }
}

impl From<ExecuteError> for EvaluationError {
    fn from(e: ExecuteError) -> Self {
        Self::Execute(e)
    }
}

impl From<TriangulationError> for EvaluationError {
    fn from(e: TriangulationError) -> Self {
        Self::Measure(e)
    }
}
