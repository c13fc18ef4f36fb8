//! ISO 9283 figures predicted before anything is measured: a Monte-Carlo of the planned test
//! on the robots a calibration cannot tell from its calibrated model.
//!
//! Each trial draws the calibration's parameter error from its covariance, `d ~ N(0, C_p)`
//! ([`crate::calibration::tool_accuracy`]: the true robot is `p_hat + d`,
//! [`model_displaced`]), runs the planned cycles on that robot with the robot's repeatability
//! jitter (the noise-only replicas of the diagnosis, [`crate::diagnosis::replica`]: each joint
//! value drawn anew whenever its actuator moves), measures every target with the instrument's
//! noise ([`MeasurementModel::measure`]: a tracker's isotropic noise, or theodolites' elongated
//! along the lines of sight), and evaluates the figures as a measured test is
//! evaluated ([`super::evaluate()`]): attained poses fitted to the tool targets, commanded ones
//! from the calibrated model. Accuracy `AP` comes mostly from `d`, repeatability `RP` from the
//! jitter and the noise.

use super::evaluate::{EvaluateOptions, IsoError, IsoFigures, evaluate};
use crate::calibration::model_parameters::{model_displaced, model_parameter_names};
use crate::diagnosis::{CleanCampaign, NoiseModel, replica};
use crate::measurement::{Measurement, MeasurementModel, MeasurementSet};
use crate::numerics::stats::{CorrelatedNormal, Stats};
use crate::robot::{RobotDescription, RobotModel};
use nalgebra::DMatrix;
use rand::SeedableRng;
use rand::rngs::ChaCha12Rng;

/// What a prediction cannot be made from.
#[derive(Debug, thiserror::Error)]
pub enum PredictionError {
    /// The covariance does not match the model's parameter vector.
    #[error("the covariance is {found} x {found}; the calibrated model has {expected} parameters")]
    Covariance {
        /// Rows of the covariance.
        found: usize,
        /// Parameters of the model.
        expected: usize,
    },
    /// A simulated test could not be run or evaluated.
    #[error("simulated test {trial}: {message}")]
    Trial {
        /// 0-based trial.
        trial: usize,
        /// Why.
        message: String,
    },
    /// The covariance has no factor to draw the calibration's error from
    /// ([`CorrelatedNormal::new`]).
    #[error("the calibration's covariance: {0}")]
    Factor(String),
    /// Fewer than one trial.
    #[error("a prediction needs at least one trial")]
    NoTrials,
}

/// What the test is predicted from.
#[derive(Clone, Debug)]
pub struct PredictionInputs<'a> {
    /// The calibrated model: it commands the poses.
    pub model: &'a RobotModel,
    /// The covariance of its parameter vector ([`model_parameter_names`] order).
    pub covariance: &'a DMatrix<f64>,
    /// The nominal description: tool targets, controller.
    pub desc: &'a RobotDescription,
    /// The robot's repeatability: each joint's standard deviation per re-positioning \[rad or
    /// m\].
    pub repeatability_rad_or_m: &'a [f64],
    /// The instrument: its noise is drawn for every measured target.
    pub instrument: &'a MeasurementModel,
}

/// A joint's repeatability: the standard deviation of its value per re-positioning.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, schemars::JsonSchema)]
pub struct JointRepeatability {
    /// 1-based joint.
    pub joint: usize,
    /// \[rad\] for a revolute joint, \[m\] for a sliding one.
    pub sigma_rad_or_m: f64,
}

/// One pose's predicted figures over the trials.
#[derive(Clone, Debug, PartialEq, serde::Serialize, schemars::JsonSchema)]
pub struct PredictedPose {
    /// `k` of `P<k>`.
    pub pose: usize,
    /// `AP_P` over the trials \[mm\].
    pub ap_p_mm: Stats,
    /// `RP_l` over the trials \[mm\]; absent with one cycle.
    pub rp_l_mm: Option<Stats>,
}

/// The predicted figures: each one's distribution over the simulated tests.
#[derive(Clone, Debug, PartialEq, serde::Serialize, schemars::JsonSchema)]
pub struct IsoPrediction {
    /// Simulated tests.
    pub trials: usize,
    /// Seed of the trials' random stream.
    pub seed: u64,
    /// The repeatability drawn, per joint.
    pub repeatability: Vec<JointRepeatability>,
    /// Per pose, `P1` first.
    pub poses: Vec<PredictedPose>,
    /// The mean of `AP_P` over the poses, over the trials \[mm\].
    pub mean_ap_p_mm: Stats,
    /// The mean of `RP_l` over the poses, over the trials \[mm\]; absent with one cycle.
    pub mean_rp_l_mm: Option<Stats>,
    /// The largest `AP_P` over the poses, over the trials \[mm\].
    pub worst_ap_p_mm: Stats,
    /// `AD_P` between `P2` and `P4` over the trials \[mm\]; absent with one cycle.
    pub ad_p_mm: Option<Stats>,
    /// `RD_P` between `P2` and `P4` over the trials \[mm\]; absent with one cycle.
    pub rd_p_mm: Option<Stats>,
}

/// The rows of an ISO test of `cycles` cycles of the points commanded by `commands` (`P1` ..
/// `P5`, file units) in the order `P1, P5, P4, P3, P2`, every tool target of `desc` measured
/// at each (positions zero: a template to simulate).
pub fn cycle_rows(desc: &RobotDescription, commands: &[Vec<f64>], cycles: usize) -> Vec<Measurement> {
    let targets = desc.tool_targets_m().len();
    let mut rows = Vec::with_capacity(cycles * commands.len() * targets);
    for cycle in 0..cycles {
        for k in CYCLE_ORDER.iter().filter(|&&k| k <= commands.len()) {
            for target in 0..targets {
                rows.push(Measurement {
                    experiment: format!("iso-P{k}"),
                    moved_joint: 0,
                    step: cycle,
                    target,
                    position_mm: [0.0; 3],
                    cmd: commands[k - 1].clone(),
                    payload_kg: 0.0,
                    temperature_c: 20.0,
                });
            }
        }
    }
    rows
}

/// The order of the points in a cycle (ISO 9283 7.2.1: `P1`, then `P5` down to `P2`).
pub const CYCLE_ORDER: [usize; 5] = [1, 5, 4, 3, 2];

/// The figures of `trials` simulated tests of `cycles` cycles of the points commanded by
/// `commands` (`P1` .. `P5`, file units), drawn from `seed` (module docs).
pub fn predict(
    inputs: &PredictionInputs<'_>,
    commands: &[Vec<f64>],
    cycles: usize,
    trials: usize,
    seed: u64,
) -> Result<IsoPrediction, PredictionError> {
    if trials == 0 {
        return Err(PredictionError::NoTrials);
    }
    let expected = model_parameter_names(inputs.model).len();
    if inputs.covariance.nrows() != expected || inputs.covariance.ncols() != expected {
        return Err(PredictionError::Covariance {
            found: inputs.covariance.nrows(),
            expected,
        });
    }
    let template = MeasurementSet::new(inputs.desc.dof(), cycle_rows(inputs.desc, commands, cycles)).map_err(|e| {
        PredictionError::Trial {
            trial: 0,
            message: e.to_string(),
        }
    })?;
    let error = CorrelatedNormal::new(inputs.covariance).map_err(PredictionError::Factor)?;
    let jitter = NoiseModel {
        noise_rms_3d_m: 0.0,
        repeatability_rad: inputs.repeatability_rad_or_m.to_vec(),
    };
    let targets = inputs.desc.tool_targets_m();
    let mut rng = ChaCha12Rng::seed_from_u64(seed);
    let mut figures = Vec::with_capacity(trials);
    for trial in 0..trials {
        let failed = |message: String| PredictionError::Trial { trial, message };
        let d = error.draw(&mut rng);
        let truth = model_displaced(inputs.model, d.as_slice());
        let clean = CleanCampaign::on_robot(&template, &truth, inputs.desc, &targets)
            .map_err(|e| failed(format!("the drawn robot: {e}")))?;
        let jittered = replica(&template, &clean, &jitter, true, &mut rng).map_err(|e| failed(e.to_string()))?;
        let measured = measured(jittered, inputs.instrument, &mut rng).map_err(failed)?;
        // Every simulated cycle counts: the draws make no gross errors to screen.
        let options = EvaluateOptions {
            register_base: false,
            keep_outliers: true,
            screen: false,
            unit_check: false,
        };
        let f = evaluate(&measured, inputs.model, inputs.desc, options).map_err(|e: IsoError| failed(e.to_string()))?;
        figures.push(f);
    }
    Ok(summarise(&figures, inputs.repeatability_rad_or_m, seed))
}

/// `set`'s rows as `instrument` measures them (its noise drawn for each, in row order).
fn measured<R: rand::Rng + ?Sized>(
    set: MeasurementSet,
    instrument: &MeasurementModel,
    rng: &mut R,
) -> Result<MeasurementSet, String> {
    let joints = set.joint_count();
    let mut rows = set.into_rows();
    for r in &mut rows {
        let p = instrument
            .measure(&r.position_m(), rng)
            .map_err(|e| format!("experiment {} step {} target {}: {e}", r.experiment, r.step, r.target))?;
        r.position_mm = (p.coords * 1e3).into();
    }
    MeasurementSet::new(joints, rows).map_err(|e| e.to_string())
}

/// [`Stats`] of `f` over the trials where every trial has it.
fn over<F: Fn(&IsoFigures) -> Option<f64>>(figures: &[IsoFigures], f: F) -> Option<Stats> {
    let v: Option<Vec<f64>> = figures.iter().map(f).collect();
    v.map(|v| Stats::of(&v))
}

/// The distributions of the figures of the simulated tests.
fn summarise(figures: &[IsoFigures], repeatability: &[f64], seed: u64) -> IsoPrediction {
    let poses = figures[0]
        .poses
        .iter()
        .enumerate()
        .map(|(i, p)| PredictedPose {
            pose: p.pose,
            ap_p_mm: Stats::of(&figures.iter().map(|f| f.poses[i].accuracy.ap_p_mm).collect::<Vec<_>>()),
            rp_l_mm: over(figures, |f| f.poses[i].repeatability.map(|r| r.rp_l_mm)),
        })
        .collect();
    IsoPrediction {
        trials: figures.len(),
        seed,
        repeatability: repeatability
            .iter()
            .enumerate()
            .map(|(k, &sigma_rad_or_m)| JointRepeatability {
                joint: k + 1,
                sigma_rad_or_m,
            })
            .collect(),
        poses,
        mean_ap_p_mm: Stats::of(&figures.iter().map(IsoFigures::mean_ap_p_mm).collect::<Vec<_>>()),
        mean_rp_l_mm: over(figures, IsoFigures::mean_rp_l_mm),
        worst_ap_p_mm: Stats::of(&figures.iter().map(|f| f.worst_ap_p_mm).collect::<Vec<_>>()),
        ad_p_mm: over(figures, |f| f.distance_p2_p4.map(|d| d.ad_p_mm)),
        rd_p_mm: over(figures, |f| f.distance_p2_p4.map(|d| d.rd_p_mm)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibration::tool_accuracy::ToolSensitivity;
    use crate::compensation::Compensator;
    use crate::iso9283::plan_cube;
    use crate::robot::{Controller, commands_to_internal};

    /// A covariance of 0.2 mm / 0.2 mrad on every length and angle of `model`'s vector, none on
    /// its dimensionless coefficients.
    fn covariance(model: &RobotModel) -> DMatrix<f64> {
        let names = model_parameter_names(model);
        DMatrix::from_fn(names.len(), names.len(), |r, c| {
            let unit = names[r].ends_with("[m]") || names[r].ends_with("[rad]");
            if r == c && unit { 4e-8 } else { 0.0 }
        })
    }

    /// Without jitter or noise, `AP_P` of a pose is the length of the tool point's error, whose
    /// first-order covariance is `J C J^T` ([`ToolSensitivity`]: a linear Jacobian, not the
    /// displaced model and the fitted targets the prediction goes through). The mean length of
    /// 200,000 draws of that 3-D Gaussian and the prediction's mean over 300 trials agree
    /// within 4 standard errors of the prediction's mean; `RP_l` is then 0 to rounding.
    #[test]
    fn accuracy_without_jitter_or_noise_is_the_propagated_tool_error() {
        let desc = RobotDescription::asea_irb6l();
        let model = RobotModel::ideal(&desc);
        let c = covariance(&model);
        let compensator = Compensator::new(&model, &desc).unwrap();
        let centre = crate::plan::CalibrationPlan::for_robot(&desc).reference;
        let cube = plan_cube(&compensator, &desc, &centre, 0.3).unwrap();
        let exact = MeasurementModel::Isotropic(crate::measurement::IsotropicNoise { net_radial_rms_mm: 0.0 });
        let inputs = PredictionInputs {
            model: &model,
            covariance: &c,
            desc: &desc,
            repeatability_rad_or_m: &[0.0; 6],
            instrument: &exact,
        };
        let trials = 300;
        let p = predict(&inputs, &cube.commands, 3, trials, 17).unwrap();
        let controller = Controller::from_description(&desc);
        let sensitivity = ToolSensitivity::new(&model, &controller, &c);
        let mut rng = ChaCha12Rng::seed_from_u64(4);
        assert_eq!(p.poses.len(), 5);
        for pose in &p.poses {
            let cmd = commands_to_internal(&desc, &cube.commands[pose.pose - 1]);
            let j = sensitivity.jacobian(&cmd).unwrap();
            let cov = j.rows(0, 3) * sensitivity_covariance(&c) * j.rows(0, 3).transpose();
            let dist = CorrelatedNormal::new(&cov).unwrap();
            let n = 200_000;
            let reference = (0..n).map(|_| dist.draw(&mut rng).norm()).sum::<f64>() / n as f64 * 1e3;
            let stats = &pose.ap_p_mm;
            let sd = ((stats.rms.powi(2) - stats.mean.powi(2)) * trials as f64 / (trials - 1) as f64).sqrt();
            let se = sd / (trials as f64).sqrt();
            assert!(
                (stats.mean - reference).abs() <= 4.0 * se,
                "P{}: predicted {:.4} mm, propagated {reference:.4} mm, se {se:.4}",
                pose.pose,
                stats.mean
            );
            assert!(pose.rp_l_mm.unwrap().max < 1e-9, "P{}: {:?}", pose.pose, pose.rp_l_mm);
        }
    }

    /// The covariance of the parameters with a variance, as [`ToolSensitivity`] orders them.
    fn sensitivity_covariance(c: &DMatrix<f64>) -> DMatrix<f64> {
        let used: Vec<usize> = (0..c.nrows()).filter(|&k| c[(k, k)] > 0.0).collect();
        DMatrix::from_fn(used.len(), used.len(), |r, k| c[(used[r], used[k])])
    }
}
