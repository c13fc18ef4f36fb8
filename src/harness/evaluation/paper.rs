//! The paper scenario end to end: simulate the Table-1 campaign on the paper robot, calibrate,
//! compensate the test poses (fig. 5) and run the accuracy and repeatability tests of section
//! 4 (figs. 9 and 10), next to the noise floor measured in the same run.
//!
//! **Noise floor.** The same campaign (same plan, instrument and noise seed) on the paper robot
//! with its repeatability switched off is calibrated too. The paper robot lies in the
//! calibrator's function family, so that calibration is limited only by the instrument noise
//! and the Table-1 data: it is the best achievable. Both calibrations are then evaluated on
//! the same real robot (WITH repeatability) with the same per-pose jitter and measurement
//! noise (common random numbers, [`super::pose_rng`]), so the ratio
//! `calibrated RMS / floor RMS` isolates what the campaign's own imperfections (here the
//! robot's repeatability during the axis experiments) cost.

use super::accuracy::{EvaluationError, Stats, TestBench, ToolError, pose_rng};
use super::poses::{JointRanges, Region, TestPose, largest_iso9283_cube, random_poses};
use crate::calibration::procedure::{
    Calibration, CalibrationOptions, Detail, ProcedureError, calibrate, calibrate_model,
};
use crate::compensation::{CompensationError, Compensator};
use crate::measurement::{MeasurementModel, MeasurementSet, MeasurementSetError};
use crate::plan::{CalibrationPlan, PoseConditions, ValidationPlan};
use crate::robot::{Controller, RobotDescription, RobotModel};
use crate::sim::{
    AnalyticArm, ArmExecutor, CampaignError, CampaignOptions, Effects, ExecuteError, simulate_campaign_with,
};
use nalgebra::Isometry3;
use rand::{SeedableRng, rngs::ChaCha12Rng};
use serde::{Deserialize, Serialize};

/// The paper's mean position error before / after calibration \[mm\] (section 4).
pub const PAPER_POSITION_ERROR_MM: [f64; 2] = [47.0, 1.40];
/// The paper's orientation error before / after calibration \[rad\].
pub const PAPER_ORIENTATION_ERROR_RAD: [f64; 2] = [0.05, 0.01];
/// The paper's repeatability: mean radial \[mm\] and orientation \[rad\].
pub const PAPER_REPEATABILITY: [f64; 2] = [0.34, 0.0033];

/// Settings of [`run_paper_scenario`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct PaperScenario {
    /// Seed of the campaign's measurement and repeatability noise.
    pub seed: u64,
    /// Seed of the test-pose draw and of the evaluation's jitter and noise.
    pub evaluation_seed: u64,
    /// Random test poses per region.
    pub random_poses: usize,
    /// The instrument (campaign and evaluation).
    pub instrument: MeasurementModel,
    /// Unmodelled effects of the real robot and the instrument, in the campaign and in the
    /// evaluation (not in the noise floor, whose robot is the perfect model).
    #[serde(default)]
    pub effects: Effects,
    /// Temperature of the test poses \[deg C\] (the campaign runs at 20 deg C): what the
    /// thermal effect acts on.
    #[serde(default = "default_temperature_c")]
    pub evaluation_temperature_c: f64,
}

fn default_temperature_c() -> f64 {
    PoseConditions::default().temperature_c
}

impl PaperScenario {
    /// The paper's settings: 0.19 mm theodolites, no unmodelled effects.
    pub fn paper(seed: u64, evaluation_seed: u64, random_poses: usize, instrument: MeasurementModel) -> Self {
        PaperScenario {
            seed,
            evaluation_seed,
            random_poses,
            instrument,
            effects: Effects::default(),
            evaluation_temperature_c: default_temperature_c(),
        }
    }

    /// The test bench of the scenario: `truth` with the scenario's effects, its instrument,
    /// the test poses at the evaluation temperature.
    fn test_bench(&self, truth: &RobotModel, desc: &RobotDescription) -> TestBench {
        let conditions = PoseConditions {
            temperature_c: self.evaluation_temperature_c,
            ..PoseConditions::default()
        };
        TestBench::new(truth, desc, &self.effects, self.instrument, conditions)
    }
}

/// Why the scenario could not run.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// Simulating a campaign failed.
    #[error("simulating the campaign: {0}")]
    Campaign(CampaignError),
    /// The campaign's rows do not form a set.
    #[error("assembling the measurement set: {0}")]
    Set(MeasurementSetError),
    /// Calibration failed.
    #[error("calibrating: {0}")]
    Calibrate(ProcedureError),
    /// The compensator cannot be built.
    #[error("compensation: {0}")]
    Compensation(CompensationError),
    /// The uncalibrated commands of a pose could not be evaluated.
    #[error("pose {id}: {cause}")]
    Evaluate {
        /// Pose id.
        id: String,
        /// Why.
        cause: EvaluationError,
    },
    /// No ISO 9283 cube fits inside a region.
    #[error("no ISO 9283 cube fits inside the {0} ranges")]
    NoCube(&'static str),
}

/// The result of one test pose.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct PoseResult {
    /// Pose id.
    pub id: String,
    /// Region.
    pub region: Region,
    /// `iso9283` or `random`.
    pub family: String,
    /// Nominal commands (the uncalibrated controller's) \[deg\].
    pub cmd_nominal_deg: Vec<f64>,
    /// Compensated commands \[deg\] (empty if compensation failed).
    pub cmd_compensated_deg: Vec<f64>,
    /// With the nominal commands.
    pub uncalibrated: ToolError,
    /// With the compensated commands, if compensation and execution succeeded.
    pub calibrated: Option<ToolError>,
    /// With the noise-floor calibration's compensated commands.
    pub floor: Option<ToolError>,
    /// Why compensation failed, if it did.
    pub failure: Option<String>,
}

/// One quantity of the uncalibrated robot, the calibrated one and the noise floor (a
/// calibration from noise-free-robot data); the unit is the one of the key holding it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ByCalibration<T> {
    /// With the nominal commands.
    pub uncalibrated: T,
    /// With the calibration's compensated commands.
    pub calibrated: T,
    /// With the noise-floor calibration's compensated commands.
    pub floor: T,
}

/// A dimensionless quantity of the position and of the orientation error.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct PositionOrientation {
    /// Of the position error.
    pub position: f64,
    /// Of the orientation error.
    pub orientation: f64,
}

/// Edges of the ISO 9283 cubes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CubeEdges {
    /// Inside the calibrated spans \[m\].
    pub inside_spans_m: f64,
    /// In the workspace \[m\].
    pub workspace_m: f64,
}

/// Calibrated and noise-floor values of a length \[mm\].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CalibratedFloorMm {
    /// Of the calibration \[mm\].
    pub calibrated_mm: f64,
    /// Of the noise-floor calibration \[mm\].
    pub floor_mm: f64,
}

/// Calibrated and noise-floor values of an angle \[rad\].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CalibratedFloorRad {
    /// Of the calibration \[rad\].
    pub calibrated_rad: f64,
    /// Of the noise-floor calibration \[rad\].
    pub floor_rad: f64,
}

/// Statistics of one region.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct RegionSummary {
    /// The region.
    pub region: Region,
    /// Position error \[mm\] (observed).
    pub position_mm: ByCalibration<Stats>,
    /// Orientation error \[rad\] (observed).
    pub orientation_rad: ByCalibration<Stats>,
    /// Model position error \[mm\] (no jitter, no noise).
    pub model_position_mm: ByCalibration<Stats>,
    /// Model orientation error \[rad\].
    pub model_orientation_rad: ByCalibration<Stats>,
    /// Calibrated / floor RMS (observed).
    pub ratio_to_floor: PositionOrientation,
    /// Calibrated / floor RMS of the model errors.
    pub model_ratio_to_floor: PositionOrientation,
    /// Poses whose compensation failed.
    pub failures: usize,
}

/// The repeatability test (section 4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct RepeatabilitySummary {
    /// Poses tested (each command executed twice).
    pub poses: usize,
    /// Mean radial distance between the two measured tool points \[mm\].
    pub observed_radial_mm: f64,
    /// Mean angle between the two measured tool frames \[rad\].
    pub observed_orientation_rad: f64,
    /// The same without measurement noise \[mm\].
    pub robot_radial_mm: f64,
    /// The same without measurement noise \[rad\].
    pub robot_orientation_rad: f64,
}

/// Everything the scenario measured.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct PaperReport {
    /// The settings.
    pub scenario: PaperScenario,
    /// Edges of the ISO 9283 cubes inside the spans and in the workspace.
    pub iso_cube_edge: CubeEdges,
    /// Per pose.
    pub poses: Vec<PoseResult>,
    /// Per region.
    pub regions: Vec<RegionSummary>,
    /// The repeatability test on the random poses inside the spans.
    pub repeatability: RepeatabilitySummary,
}

/// The scenario's outputs: the report and the two calibrations (scenario, floor).
#[derive(Clone, Debug)]
pub struct PaperOutcome {
    /// The report.
    pub report: PaperReport,
    /// The calibration of the paper robot.
    pub calibration: Calibration,
    /// The noise-floor calibration (same robot, repeatability off).
    pub floor_calibration: Calibration,
}

/// The analytic arm with its repeatability jitter drawn from its own stream, so that the
/// campaign's measurement noise (the stream passed to the campaign) is the same draw with and
/// without repeatability: the scenario and its noise floor then differ by the jitter alone.
struct SeparateJitter {
    arm: AnalyticArm,
    jitter: ChaCha12Rng,
}

impl ArmExecutor for SeparateJitter {
    fn execute<R: rand::Rng + ?Sized>(
        &mut self,
        cmd: &[f64],
        conditions: &PoseConditions,
        _rng: &mut R,
    ) -> Result<Vec<Isometry3<f64>>, ExecuteError> {
        self.arm.execute(cmd, conditions, &mut self.jitter)
    }

    fn last_link_from_tool(&self) -> Isometry3<f64> {
        self.arm.last_link_from_tool()
    }
}

fn campaign_calibration(
    desc: &RobotDescription,
    truth: &RobotModel,
    effects: &Effects,
    instrument: &MeasurementModel,
    seed: u64,
) -> Result<Calibration, ScenarioError> {
    let set = campaign_set(desc, truth, effects, instrument, seed)?;
    Ok(calibrate(&set, desc, &CalibrationOptions::default())?)
}

/// The Table-1 campaign of `truth` under `effects`, measured by `instrument` (seed `seed`).
fn campaign_set(
    desc: &RobotDescription,
    truth: &RobotModel,
    effects: &Effects,
    instrument: &MeasurementModel,
    seed: u64,
) -> Result<MeasurementSet, ScenarioError> {
    let plan = CalibrationPlan::table1(desc.dof());
    let validation = ValidationPlan {
        poses: 0,
        ..ValidationPlan::workspace_default(desc.dof())
    };
    let mut arm = SeparateJitter {
        arm: AnalyticArm::new(truth.clone(), Controller::from_description(desc)).with_effects(effects.clone(), desc),
        jitter: pose_rng(seed, usize::MAX),
    };
    let options = CampaignOptions {
        conditions: PoseConditions::default(),
        instrument_scale: effects.instrument_scale,
    };
    let out = simulate_campaign_with(
        desc,
        &plan,
        &validation,
        &mut arm,
        instrument,
        &options,
        &mut ChaCha12Rng::seed_from_u64(seed),
    )?;
    Ok(MeasurementSet::new(desc.dof(), out.rows)?)
}

/// The test poses of the scenario: ISO 9283 cubes (largest edge up to 0.5 m) and `n` random
/// poses, inside the calibrated spans and over the validation workspace.
pub fn scenario_poses(
    desc: &RobotDescription,
    n: usize,
    seed: u64,
) -> Result<(Vec<TestPose>, [f64; 2]), ScenarioError> {
    let model = desc.nominal_model();
    let plan = CalibrationPlan::table1(desc.dof());
    let inside = JointRanges::calibrated_spans(desc, &plan);
    let workspace = JointRanges::around_zero(desc, &ValidationPlan::workspace_default(desc.dof()).half_range);
    let mut poses = Vec::new();
    let mut edges = [0.0; 2];
    for (i, (ranges, region)) in [(&inside, Region::InsideSpans), (&workspace, Region::Workspace)]
        .into_iter()
        .enumerate()
    {
        let (edge, iso) = largest_iso9283_cube(&model, &ranges.centre(), 0.5, ranges, region)
            .ok_or(ScenarioError::NoCube(region.name()))?;
        edges[i] = edge;
        poses.extend(iso);
        poses.extend(random_poses(&model, ranges, region, n, seed.wrapping_add(i as u64)));
    }
    Ok((poses, edges))
}

/// Runs the paper scenario (module docs). Deterministic for given settings.
pub fn run_paper_scenario(s: &PaperScenario) -> Result<PaperOutcome, ScenarioError> {
    run_paper_scenario_with(s, &crate::progress::Silent)
}

/// [`run_paper_scenario`], counting the test poses evaluated on `progress`.
pub fn run_paper_scenario_with(
    s: &PaperScenario,
    progress: &dyn crate::progress::Progress,
) -> Result<PaperOutcome, ScenarioError> {
    let desc = RobotDescription::asea_irb6l();
    let truth = crate::sim::paper_robot();
    let mut perfect = truth.clone();
    for j in &mut perfect.joints {
        j.repeatability_sigma = 0.0;
    }
    let calibration = campaign_calibration(&desc, &truth, &s.effects, &s.instrument, s.seed)?;
    let floor_calibration = campaign_calibration(&desc, &perfect, &Effects::default(), &s.instrument, s.seed)?;
    let comp = Compensator::new(&calibration.robot, &desc)?;
    let floor_comp = Compensator::new(&floor_calibration.robot, &desc)?;
    let bench = s.test_bench(&truth, &desc);
    let (poses, iso_cube_edge_m) = scenario_poses(&desc, s.random_poses, s.evaluation_seed)?;
    let mut results = Vec::with_capacity(poses.len());
    progress.start(poses.len(), "test poses");
    for (i, p) in poses.iter().enumerate() {
        results.push(evaluate_pose(&bench, &comp, &floor_comp, p, s.evaluation_seed, i)?);
        progress.inc();
    }
    let regions = [Region::InsideSpans, Region::Workspace]
        .into_iter()
        .map(|r| summarise(r, &results))
        .collect();
    let repeatability = repeatability_test(&bench, &poses, s.evaluation_seed)?;
    Ok(PaperOutcome {
        report: PaperReport {
            scenario: s.clone(),
            iso_cube_edge: CubeEdges {
                inside_spans_m: iso_cube_edge_m[0],
                workspace_m: iso_cube_edge_m[1],
            },
            poses: results,
            regions,
            repeatability,
        },
        calibration,
        floor_calibration,
    })
}

/// Calibrated vs noise-floor RMS inside the spans, pooled over several campaign seeds (one
/// seed's floor alone scatters by a factor of 4: the Table-1 spans leave some transmission
/// terms poorly determined).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct FloorCheck {
    /// Seeds pooled: `first_seed .. first_seed + seeds`.
    pub first_seed: u64,
    /// Number of seeds.
    pub seeds: u64,
    /// Pooled RMS of the position error inside the spans.
    pub position_rms: CalibratedFloorMm,
    /// Pooled RMS of the orientation error inside the spans.
    pub orientation_rms: CalibratedFloorRad,
    /// Calibrated / floor pooled RMS.
    pub ratio: PositionOrientation,
}

/// Runs `template` for seeds `template.seed .. template.seed + seeds` (rayon; pooled in seed
/// order, so independent of the thread count) and pools the inside-span RMS of the calibrated
/// and the floor errors.
pub fn floor_check(template: &PaperScenario, seeds: u64) -> Result<FloorCheck, ScenarioError> {
    floor_check_with(template, seeds, &crate::progress::Silent)
}

/// [`floor_check`], counting the campaign seeds done on `progress`.
pub fn floor_check_with(
    template: &PaperScenario,
    seeds: u64,
    progress: &dyn crate::progress::Progress,
) -> Result<FloorCheck, ScenarioError> {
    use rayon::prelude::*;
    progress.start(seeds as usize, "campaign seeds");
    let regions: Vec<RegionSummary> = (0..seeds)
        .into_par_iter()
        .map(|i| {
            let s = PaperScenario {
                seed: template.seed.wrapping_add(i),
                ..template.clone()
            };
            let report = run_paper_scenario(&s)?.report;
            progress.inc();
            Ok(report
                .regions
                .into_iter()
                .find(|r| r.region == Region::InsideSpans)
                .expect("the scenario evaluates inside the spans"))
        })
        .collect::<Result<_, ScenarioError>>()?;
    let pooled = |f: fn(&RegionSummary) -> Stats| Stats::pooled(&regions.iter().map(f).collect::<Vec<_>>()).rms;
    let position_rms = CalibratedFloorMm {
        calibrated_mm: pooled(|r| r.position_mm.calibrated),
        floor_mm: pooled(|r| r.position_mm.floor),
    };
    let orientation_rms = CalibratedFloorRad {
        calibrated_rad: pooled(|r| r.orientation_rad.calibrated),
        floor_rad: pooled(|r| r.orientation_rad.floor),
    };
    Ok(FloorCheck {
        first_seed: template.seed,
        seeds,
        ratio: PositionOrientation {
            position: position_rms.calibrated_mm / position_rms.floor_mm,
            orientation: orientation_rms.calibrated_rad / orientation_rms.floor_rad,
        },
        position_rms,
        orientation_rms,
    })
}

/// The scenario's calibration alone (no noise floor) evaluated on its test poses inside the
/// calibrated spans: statistics of the observed position error \[mm\] (through the instrument,
/// as the paper measured its 1.40 mm). Poses whose compensation fails are errors.
pub fn calibrated_position_error_inside_spans(s: &PaperScenario) -> Result<Stats, ScenarioError> {
    let desc = RobotDescription::asea_irb6l();
    let truth = crate::sim::paper_robot();
    // Only the model is needed: the lean path (the same model as `campaign_calibration`'s).
    let set = campaign_set(&desc, &truth, &s.effects, &s.instrument, s.seed)?;
    let calibrated = calibrate_model(&set, &desc, &CalibrationOptions::default(), Detail::Model)?;
    let comp = Compensator::new(&calibrated.robot, &desc)?;
    let bench = s.test_bench(&truth, &desc);
    let (poses, _) = scenario_poses(&desc, s.random_poses, s.evaluation_seed)?;
    let mut errors = Vec::new();
    for (i, p) in poses
        .iter()
        .enumerate()
        .filter(|(_, p)| p.region == Region::InsideSpans)
    {
        let fail = |source| ScenarioError::Evaluate {
            id: p.id.clone(),
            cause: source,
        };
        let cmd = comp.compensate_from(&p.world_from_tool, &p.q_nominal)?.cmd;
        let e = bench
            .tool_error(&p.world_from_tool, &cmd, &mut pose_rng(s.evaluation_seed, i))
            .map_err(fail)?;
        errors.push(e.position_mm);
    }
    Ok(Stats::of(&errors))
}

/// One test pose: nominal commands, compensated commands (scenario and floor calibrations),
/// each executed with the same jitter and noise.
pub fn evaluate_pose(
    bench: &TestBench,
    comp: &Compensator,
    floor_comp: &Compensator,
    pose: &TestPose,
    seed: u64,
    index: usize,
) -> Result<PoseResult, ScenarioError> {
    let err = |source| ScenarioError::Evaluate {
        id: pose.id.clone(),
        cause: source,
    };
    let uncalibrated = bench
        .tool_error(&pose.world_from_tool, &pose.q_nominal, &mut pose_rng(seed, index))
        .map_err(err)?;
    let run = |c: &Compensator| -> Result<(Vec<f64>, ToolError), String> {
        let cmd = c
            .compensate_from(&pose.world_from_tool, &pose.q_nominal)
            .map_err(|e| e.to_string())?
            .cmd;
        let e = bench
            .tool_error(&pose.world_from_tool, &cmd, &mut pose_rng(seed, index))
            .map_err(|e| e.to_string())?;
        Ok((cmd, e))
    };
    let (calibrated, floor) = (run(comp), run(floor_comp));
    let deg = |v: &[f64]| v.iter().map(|x| x.to_degrees()).collect::<Vec<_>>();
    Ok(PoseResult {
        id: pose.id.clone(),
        region: pose.region,
        family: pose.family.to_owned(),
        cmd_nominal_deg: deg(&pose.q_nominal),
        uncalibrated,
        cmd_compensated_deg: calibrated.as_ref().map(|(c, _)| deg(c)).unwrap_or_default(),
        failure: calibrated.as_ref().err().cloned(),
        calibrated: calibrated.ok().map(|(_, e)| e),
        floor: floor.ok().map(|(_, e)| e),
    })
}

fn summarise(region: Region, results: &[PoseResult]) -> RegionSummary {
    let rs: Vec<&PoseResult> = results.iter().filter(|r| r.region == region).collect();
    let kinds = |f: fn(&ToolError) -> f64| -> ByCalibration<Stats> {
        ByCalibration {
            uncalibrated: Stats::of(&rs.iter().map(|r| f(&r.uncalibrated)).collect::<Vec<_>>()),
            calibrated: Stats::of(
                &rs.iter()
                    .filter_map(|r| r.calibrated.as_ref().map(f))
                    .collect::<Vec<_>>(),
            ),
            floor: Stats::of(&rs.iter().filter_map(|r| r.floor.as_ref().map(f)).collect::<Vec<_>>()),
        }
    };
    let position_mm = kinds(|e| e.position_mm);
    let orientation_rad = kinds(|e| e.orientation_rad);
    let model_position_mm = kinds(|e| e.model_position_mm);
    let model_orientation_rad = kinds(|e| e.model_orientation_rad);
    let ratio = |s: &ByCalibration<Stats>| s.calibrated.rms / s.floor.rms;
    RegionSummary {
        region,
        ratio_to_floor: PositionOrientation {
            position: ratio(&position_mm),
            orientation: ratio(&orientation_rad),
        },
        model_ratio_to_floor: PositionOrientation {
            position: ratio(&model_position_mm),
            orientation: ratio(&model_orientation_rad),
        },
        position_mm,
        orientation_rad,
        model_position_mm,
        model_orientation_rad,
        failures: rs.iter().filter(|r| r.calibrated.is_none()).count(),
    }
}

fn repeatability_test(bench: &TestBench, poses: &[TestPose], seed: u64) -> Result<RepeatabilitySummary, ScenarioError> {
    let mut sums = [0.0; 4];
    let tested: Vec<&TestPose> = poses
        .iter()
        .filter(|p| p.region == Region::InsideSpans && p.family == "random")
        .collect();
    for (i, p) in tested.iter().enumerate() {
        // A stream distinct from the accuracy test's (index offset by the pose count).
        let r = bench
            .repeatability(&p.q_nominal, &mut pose_rng(seed, poses.len() + i))
            .map_err(|source| ScenarioError::Evaluate {
                id: p.id.clone(),
                cause: source,
            })?;
        for (s, v) in sums.iter_mut().zip(r) {
            *s += v;
        }
    }
    let n = tested.len().max(1) as f64;
    Ok(RepeatabilitySummary {
        poses: tested.len(),
        observed_radial_mm: sums[0] / n,
        observed_orientation_rad: sums[1] / n,
        robot_radial_mm: sums[2] / n,
        robot_orientation_rad: sums[3] / n,
    })
}

impl From<CampaignError> for ScenarioError {
    fn from(e: CampaignError) -> Self {
        Self::Campaign(e)
    }
}

impl From<MeasurementSetError> for ScenarioError {
    fn from(e: MeasurementSetError) -> Self {
        Self::Set(e)
    }
}

impl From<ProcedureError> for ScenarioError {
    fn from(e: ProcedureError) -> Self {
        Self::Calibrate(e)
    }
}

impl From<CompensationError> for ScenarioError {
    fn from(e: CompensationError) -> Self {
        Self::Compensation(e)
    }
}
