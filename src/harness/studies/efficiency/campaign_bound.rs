//! The whole-campaign Cramer-Rao bound of the derived quantities (couplings, zero offsets,
//! tool frame) and their efficiency over the trials.
//!
//! Every measured point of the Table-1 campaign is predicted from the complete parameter
//! vector: every parameter of the calibrated model the procedure estimates (those with a
//! propagated variance in [`model_parameter_names`] order: base, rows, `phi`, zero offsets,
//! transmissions, couplings, tool frame; those fixed by convention or taken from the
//! description, e.g. `b1 = 0` or the 4->5 gear ratio, stay fixed) plus 3 nuisance coordinates
//! per axis target (its position in its link's frame, which the description does not give).
//! The prediction is the diagnosis's campaign on the calibrated robot
//! ([`CleanCampaign::positions_on`]): actuator commands through the model's transmissions
//! and couplings (the joint readings are never trusted), the chain, the target. The model is
//! moved along its vector by [`model_moved`] (the propagation's and the tool accuracy's) and
//! linearised by central differences ([`campaign_bound`]).
//!
//! It is evaluated where the estimator converges on the noise-free campaign (when the truth's
//! coupling is not of the fitted form, e.g. a four-bar against the fractional form, that point
//! is not the truth): the trials' errors are taken about that point, and the form's misfit is
//! reported apart (the noise-free coupling fit's residual).
//!
//! The vector has gauge freedoms (each joint's zero against the next row and its target, the
//! fractional coupling's constant against the driven joint's zero, ...). The rank-revealing
//! bound ([`fisher_bound`]) gives a number to the estimable parameters only; the estimator
//! fixes the freedoms by its conventions, so the derived quantities get the bound held to them
//! ([`convention_bound`]): the range of the propagated model covariance (the subspace the
//! linearised estimator moves in) intersected with each fractional coupling's start
//! convention ([`FractionalStart`]). A parameter still sharing a direction the points do not
//! determine gets no number.
//!
//! Bound for the jitter-off case only: with the repeatability jitter a held joint's error is
//! shared by a whole experiment (correlated noise the isotropic Fisher information does not
//! hold), so the study then reports no whole-campaign bound.

use super::StudyError;
use super::trial::{AxisTruth, campaign, derived_quantities};
use crate::calibration::arc_model::MeasurementNoise;
use crate::calibration::crb::{
    CampaignBound, ESTIMABLE_TOLERANCE, arc_crb_with_angle_noise, convention_bound, covariance_range, fisher_bound,
};
use crate::calibration::model_parameters::{model_moved, model_parameter_names};
use crate::calibration::procedure::{AxisExperiment, CalibrationOptions, Detail, calibrate, calibrate_model};
use crate::calibration::refine::{NULL_DIRECTION_TOLERANCE, sensitivity};
use crate::diagnosis::CleanCampaign;
use crate::measurement::MeasurementSet;
use crate::numerics::lsq::TruncatedSvd;
use crate::robot::{RobotDescription, RobotModel};
use nalgebra::{DMatrix, Vector3};
use serde::{Deserialize, Serialize};

/// Central-difference step of an axis target's position \[m\]: 1 um, far below the curvature
/// scale of the chain (the links, 0.1 to 1 m) and far above rounding (1e-16 m).
const TARGET_STEP_M: f64 = 1e-6;

/// The 1-sigma above which the model covariance marks a parameter as estimated (see
/// [`CampaignPrediction::new`]).
const FREE_SIGMA: f64 = 1e-12;

/// What the whole-campaign bound rests on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CampaignBoundSummary {
    /// Parameters of the vector (model parameters the procedure estimates, then 3 per axis
    /// target).
    pub parameters: usize,
    /// Rank of the campaign's Jacobian: `parameters - rank` directions are unidentifiable.
    pub rank: usize,
    /// The dimension of the subspace the estimator's model parameters move in (the range of
    /// the propagated model covariance: its conventions fix the rest); the bound of every
    /// derived quantity is held to it. With the axis targets it must equal `rank`.
    pub convention_rank: usize,
    /// Directions of the conventions' subspace the points do not determine (0 when the
    /// conventions fix every gauge freedom).
    pub convention_null_directions: usize,
    /// The parameters with a share in a direction the conventions leave unfixed and the
    /// points do not determine (the conventions' subspace holds a null direction of the
    /// campaign): they get no bound.
    pub convention_unidentifiable: Vec<(String, f64)>,
    /// The largest relative difference, over the estimable parameters, between the bound held
    /// to the conventions and the rank-revealing one (equal in exact arithmetic).
    pub convention_agreement: f64,
    /// Measured coordinates (3 per point).
    pub coordinates: usize,
    /// The parameters with a share in an unidentifiable direction (gauge freedoms: the points
    /// do not change along them), with that share (column-scaled unit vector's length off the
    /// row space); none of them is given a bound.
    pub unidentifiable: Vec<(String, f64)>,
    /// Per joint and harmonic order: the whole-campaign bound of `var(sin_k) + var(cos_k)`
    /// over the per-arc bound's (the axis efficiency's): the second route, 1 where the other
    /// experiments carry no information on that joint's transmission, below 1 where they add
    /// some (the whole campaign holds the arc's points and its model maps onto the arc's).
    pub transmission_bound_ratio: Vec<(String, f64)>,
    /// Per coupling: the noise-free fit's angle residual RMS \[rad\], the misfit of the fitted
    /// form to the truth's coupling (0 when the truth is of the fitted form).
    pub coupling_form_residual_rad: Vec<(String, f64)>,
}

/// The noise-free fit's derived quantities with their whole-campaign bound.
pub(super) struct ConvergedBound {
    /// Per derived quantity: name, the noise-free fit's value, the bound's variance (the
    /// quantity's unit squared; `None` if not estimable or not in the vector) and its share in
    /// a direction the conventions leave unfixed (`None` if not in the vector).
    pub(super) quantities: Vec<(String, f64, Option<f64>, Option<f64>)>,
    /// What the bound rests on.
    pub(super) summary: CampaignBoundSummary,
}

/// A campaign predicted from its parameter vector: the model and its free parameters.
pub(super) struct CampaignPrediction<'a> {
    /// The campaign on the converged model.
    pub(super) clean: CleanCampaign,
    /// The converged model.
    pub(super) robot: &'a RobotModel,
    /// Indices (in [`model_parameter_names`] order) of the parameters the procedure estimates.
    pub(super) free: Vec<usize>,
    /// Their central-difference steps, then the targets'.
    pub(super) steps: Vec<f64>,
}

impl<'a> CampaignPrediction<'a> {
    /// The rows of `set` on `robot`, its free parameters those with a positive variance in
    /// `covariance` above [`FREE_SIGMA`] (steps `1e-3 sigma`, as the propagation's).
    pub(super) fn new(
        set: &MeasurementSet,
        robot: &'a RobotModel,
        covariance: &DMatrix<f64>,
        desc: &RobotDescription,
    ) -> Result<Self, StudyError> {
        let clean = CleanCampaign::on_robot(set, robot, desc, &desc.tool_targets_m())
            .map_err(|e| StudyError::Bound(e.to_string()))?;
        // A parameter fixed by convention (b1 = 0) keeps a rounding-level variance (~1e-26 m^2):
        // free means a 1-sigma above 1e-12 (1 pm or 1 prad, far below any real uncertainty of a
        // calibration, 1e-7 and up, and far above rounding of a fixed one, 1e-16).
        let free: Vec<usize> = (0..covariance.nrows())
            .filter(|&k| covariance[(k, k)] > FREE_SIGMA * FREE_SIGMA)
            .collect();
        let mut steps: Vec<f64> = free.iter().map(|&k| 1e-3 * covariance[(k, k)].sqrt()).collect();
        steps.extend(std::iter::repeat_n(TARGET_STEP_M, 3 * clean.axis_target_count()));
        Ok(CampaignPrediction {
            clean,
            robot,
            free,
            steps,
        })
    }

    /// The predicted coordinates \[m\] at parameters `p` (model corrections, then target
    /// shifts).
    fn predict(&self, p: &[f64]) -> Option<Vec<f64>> {
        let mut robot = self.robot.clone();
        for (&k, &x) in self.free.iter().zip(p) {
            if x != 0.0 {
                robot = model_moved(&robot, k, x);
            }
        }
        let shifts: Vec<Vector3<f64>> = p[self.free.len()..]
            .chunks(3)
            .map(|c| Vector3::new(c[0], c[1], c[2]))
            .collect();
        let points = self.clean.positions_on(&robot, &shifts).ok()?;
        Some(
            points
                .iter()
                .flat_map(|x| x.coords.iter().copied().collect::<Vec<_>>())
                .collect(),
        )
    }

    /// The names of the parameters: the free model parameters, then the targets'.
    fn names(&self) -> Vec<String> {
        let all = model_parameter_names(self.robot);
        let mut names: Vec<String> = self.free.iter().map(|&k| all[k].clone()).collect();
        for g in 0..self.clean.axis_target_count() {
            names.extend(["x", "y", "z"].map(|c| format!("axis target {} {c} [m]", g + 1)));
        }
        names
    }

    /// The subspace `u` (columns, free model parameters) restricted to the directions that
    /// keep every fractional coupling's start convention (`g(theta_0) = slope theta_0` at the
    /// driving joint's active angle `theta_0` at the sweep's first step, `passive_start` of the
    /// procedure: the fractional family is closed under a constant shift, which the joint's
    /// zero absorbs, so the points do not fix it). Its gradient by central differences
    /// ([`sensitivity`], the same steps).
    fn with_starts(&self, u: DMatrix<f64>, starts: &[FractionalStart]) -> Result<DMatrix<f64>, StudyError> {
        if starts.is_empty() {
            return Ok(u);
        }
        let h = |p: &[f64]| -> Option<Vec<f64>> {
            let mut robot = self.robot.clone();
            for (&k, &x) in self.free.iter().zip(p) {
                if x != 0.0 {
                    robot = model_moved(&robot, k, x);
                }
            }
            starts
                .iter()
                .map(|s| {
                    let theta = robot.active_displacements(&s.actuators_rad).ok()?[s.to - 1];
                    let g = robot.joints[s.to].coupling_in.as_ref()?.try_passive(theta).ok()?;
                    Some(g - s.slope * theta)
                })
                .collect()
        };
        let p0 = vec![0.0; self.free.len()];
        let grad = sensitivity(h, &p0, &self.steps[..self.free.len()])
            .ok_or_else(|| StudyError::Bound("the coupling start convention cannot be evaluated".into()))?;
        // The complement of the constraints' rows within u: the null space of `grad u`.
        let gu = &grad * &u;
        let projector =
            DMatrix::identity(u.ncols(), u.ncols()) - TruncatedSvd::new(&gu, NULL_DIRECTION_TOLERANCE).solve * &gu;
        Ok(&u * TruncatedSvd::new(&projector, NULL_DIRECTION_TOLERANCE).span)
    }

    /// The bound with isotropic noise of 3-D RMS `noise_m` per point: the rank-revealing one
    /// and the one held to the estimator's conventions (the range of the model covariance
    /// `covariance`, restricted to the free parameters, and the fractional couplings' start
    /// conventions `starts`).
    pub(super) fn bound(
        &self,
        noise_m: f64,
        covariance: &DMatrix<f64>,
        starts: &[FractionalStart],
    ) -> Result<Bounds, StudyError> {
        let p0 = vec![0.0; self.steps.len()];
        let sigma = noise_m / 3f64.sqrt();
        let j = sensitivity(|p| self.predict(p), &p0, &self.steps)
            .ok_or_else(|| StudyError::Bound("the converged model cannot execute the campaign".into()))?;
        let free = DMatrix::from_fn(self.free.len(), self.free.len(), |r, c| {
            covariance[(self.free[r], self.free[c])]
        });
        let u = self.with_starts(covariance_range(&free), starts)?;
        let targets = j.ncols() - self.free.len();
        Ok(Bounds {
            names: self.names(),
            estimable: fisher_bound(&j, sigma),
            convention: convention_bound(&j, sigma, &u, targets),
            convention_rank: u.ncols(),
        })
    }
}

/// The start convention of a fractional coupling into joint `to` (0-based): the driving
/// joint's actuator commands at the sweep's first step \[rad\] and the nominal slope.
pub(super) struct FractionalStart {
    /// The driven joint (0-based).
    pub(super) to: usize,
    /// Actuator commands of the sweep's first second-target row \[rad\].
    pub(super) actuators_rad: Vec<f64>,
    /// The nominal slope.
    pub(super) slope: f64,
}

/// The start conventions of `cal`'s fractional couplings on the campaign `set`.
fn fractional_starts(
    set: &MeasurementSet,
    couplings: &[crate::calibration::procedure::CouplingReport],
    desc: &RobotDescription,
) -> Vec<FractionalStart> {
    let controller = crate::robot::Controller::from_description(desc);
    couplings
        .iter()
        .filter(|c| matches!(c.function, crate::robot::CouplingFunction::Fractional { .. }))
        .filter_map(|c| {
            let row = set
                .rows()
                .iter()
                .find(|m| m.experiment == c.experiment && m.target == 1)?;
            let actuators_rad = controller
                .decouple(&crate::robot::commands_to_internal(desc, &row.cmd))
                .ok()?;
            Some(FractionalStart {
                to: c.to - 1,
                actuators_rad,
                slope: desc.nominal_coupling_into(c.to)?,
            })
        })
        .collect()
}

/// The whole-campaign bounds of every parameter.
pub(super) struct Bounds {
    /// Parameter names.
    pub(super) names: Vec<String>,
    /// The rank-revealing bound ([`fisher_bound`]): estimable parameters only.
    pub(super) estimable: CampaignBound,
    /// The bound held to the estimator's conventions ([`convention_bound`]).
    pub(super) convention: CampaignBound,
    /// The dimension of the subspace the estimator's model parameters move in.
    pub(super) convention_rank: usize,
}

/// The vector's name of a derived quantity (`coupling 2->3 n0`, `joint 2 zero offset`, `tool x
/// mm`) and the quantity's unit per vector unit.
fn vector_name(derived: &str, names: &[String]) -> Option<(usize, f64)> {
    let (wanted, scale) = if let Some(c) = derived.strip_prefix("tool ") {
        let (axis, unit) = c.split_once(' ')?;
        let si = if unit == "mm" { "m" } else { "rad" };
        (format!("tool {axis} [{si}]"), 1e3)
    } else if derived.ends_with("zero offset") {
        (format!("{derived} [rad or m]"), 1.0)
    } else if derived.starts_with("coupling") && !derived.ends_with(')') {
        (derived.to_string(), 1.0)
    } else {
        return None;
    };
    let k = names
        .iter()
        .position(|n| *n == wanted || n.strip_prefix(wanted.as_str()).is_some_and(|r| r.starts_with(" [")))?;
    Some((k, scale))
}

/// The noise-free calibration of the campaign on `steady` (the point the estimator converges
/// to), its derived quantities and their whole-campaign bound at measurement noise of 3-D RMS
/// `noise_m`; the per-arc bounds of `truths` (experiments `experiments`) for the second route.
pub(super) fn converged_bound(
    desc: &RobotDescription,
    steady: &RobotModel,
    options: &CalibrationOptions,
    noise_m: f64,
    experiments: &[AxisExperiment],
    truths: &[AxisTruth],
) -> Result<ConvergedBound, StudyError> {
    let exact = campaign(steady, desc, 0.0, 0);
    let lean = calibrate_model(&exact, desc, options, Detail::ModelAndCovariance).map_err(StudyError::Converged)?;
    let full = calibrate(&exact, desc, options).map_err(StudyError::Converged)?;
    let covariance = full
        .model_covariance
        .as_ref()
        .ok_or_else(|| StudyError::Bound("the calibration gives no model covariance".into()))?
        .matrix();
    let prediction = CampaignPrediction::new(&exact, &full.robot, &covariance, desc)?;
    let starts = fractional_starts(&exact, &full.couplings, desc);
    let b = prediction.bound(noise_m, &covariance, &starts)?;
    let names = &b.names;
    let quantities = derived_quantities(&lean, desc)
        .into_iter()
        .map(|(name, value, _)| {
            let at = vector_name(&name, names);
            let variance = at.and_then(|(k, s)| b.convention.variance[k].map(|v| v * s * s));
            (name, value, variance, at.map(|(k, _)| b.convention.null_share[k]))
        })
        .collect();
    let transmission_bound_ratio = transmission_ratios(&b, noise_m, experiments, truths)?;
    let bound = &b.estimable;
    let summary = CampaignBoundSummary {
        parameters: bound.parameters,
        rank: bound.rank,
        coordinates: bound.coordinates,
        convention_rank: b.convention_rank,
        convention_null_directions: b.convention.parameters - b.convention.rank,
        convention_unidentifiable: names
            .iter()
            .zip(&b.convention.null_share)
            .filter(|(_, s)| **s >= ESTIMABLE_TOLERANCE)
            .map(|(n, s)| (n.clone(), *s))
            .collect(),
        convention_agreement: convention_agreement(&b),
        unidentifiable: names
            .iter()
            .zip(&bound.null_share)
            .filter(|(_, s)| **s >= ESTIMABLE_TOLERANCE)
            .map(|(n, s)| (n.clone(), *s))
            .collect(),
        transmission_bound_ratio,
        coupling_form_residual_rad: full
            .couplings
            .iter()
            .map(|c| (format!("coupling {}->{}", c.from, c.to), c.residual_rms_rad))
            .collect(),
    };
    Ok(ConvergedBound { quantities, summary })
}

/// Per joint and harmonic order: the whole-campaign bound (held to the conventions) of
/// `var(sin_k) + var(cos_k)` over the per-arc bound's (the axis efficiency's,
/// [`arc_crb_with_angle_noise`] without angle noise), where both are bounded. The sum, because
/// the model holds the transmission in the calibrated zero (`Transmission::shifted`), which
/// turns each (sin_k, cos_k) pair by a fixed angle against the arc fit's own zero: the trace
/// does not change under that turn.
fn transmission_ratios(
    b: &Bounds,
    noise_m: f64,
    experiments: &[AxisExperiment],
    truths: &[AxisTruth],
) -> Result<Vec<(String, f64)>, StudyError> {
    let mut out = Vec::new();
    for (e, t) in experiments.iter().zip(truths) {
        let arc = arc_crb_with_angle_noise(
            t.form,
            &t.commands_rad,
            &MeasurementNoise::from_rms_3d(noise_m),
            0.0,
            &t.params,
            &t.reference,
        )
        .map_err(StudyError::Reference)?;
        let names = t.form.coefficient_names();
        let arc_var = |c: &str| names.iter().position(|n| n == c).map(|i| arc.coefficient_variance[i]);
        let campaign_var = |c: &str| {
            let name = format!("joint {} transmission {c} [rad]", e.joint);
            b.names
                .iter()
                .position(|n| *n == name)
                .and_then(|k| b.convention.variance[k])
        };
        for order in 1.. {
            let (s, c) = (format!("sin{order}"), format!("cos{order}"));
            let (Some(arc_s), Some(arc_c)) = (arc_var(&s), arc_var(&c)) else {
                break;
            };
            if let (Some(w_s), Some(w_c)) = (campaign_var(&s), campaign_var(&c)) {
                out.push((
                    format!("joint {} order {order}", e.joint),
                    (w_s + w_c) / (arc_s + arc_c),
                ));
            }
        }
    }
    Ok(out)
}

/// The largest relative difference between the two bounds over the estimable parameters
/// (equal in exact arithmetic: the second route).
fn convention_agreement(b: &Bounds) -> f64 {
    b.estimable
        .variance
        .iter()
        .zip(&b.convention.variance)
        .filter_map(|(e, c)| Some((c.as_ref()? / e.as_ref()? - 1.0).abs()))
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::super::trial::reference_truths;
    use super::*;
    use crate::robot::Controller;

    const NOISE_M: f64 = 0.19e-3;

    /// The paper robot without jitter, its description and the study's calibrator options.
    fn setting() -> (RobotDescription, RobotModel, CalibrationOptions) {
        let desc = RobotDescription::asea_irb6l();
        let mut steady = crate::sim::paper_robot();
        for j in &mut steady.joints {
            j.repeatability_sigma = 0.0;
        }
        let options = CalibrationOptions {
            noise_rms_3d_mm: NOISE_M * 1e3,
            repeatability_sigma_rad: Some(vec![0.0; desc.dof()]),
            ..CalibrationOptions::default()
        };
        (desc, steady, options)
    }

    /// Relative agreement of two bounds computed by different routes: central differences at
    /// a thousandth of each sigma leave ~1e-10 of the scaled Jacobian's norm (its null
    /// singular values), amplified by the condition of the arc's information (~1e3-1e4).
    const ROUTE_TOLERANCE: f64 = 1e-5;

    #[test]
    fn neither_one_sweep_nor_the_whole_campaign_exceeds_the_per_arc_bound() {
        let (desc, steady, options) = setting();
        let controller = Controller::from_description(&desc);
        let (experiments, truths) = reference_truths(&desc, &controller, &steady, &steady, &[0.0; 6], NOISE_M).unwrap();
        let exact = campaign(&steady, &desc, 0.0, 0);
        let full = calibrate(&exact, &desc, &options).unwrap();
        let covariance = full.model_covariance.as_ref().unwrap().matrix();
        for joint in [1, 6] {
            // Only the sweep's target-0 points: the arc fit's data, through the chain.
            let k = experiments.iter().position(|e| e.joint == joint).unwrap();
            let rows = exact
                .rows()
                .iter()
                .filter(|m| m.experiment == experiments[k].name && m.target == 0)
                .cloned()
                .collect();
            let set = MeasurementSet::new(desc.dof(), rows).unwrap();
            let b = CampaignPrediction::new(&set, &full.robot, &covariance, &desc)
                .unwrap()
                .bound(NOISE_M, &covariance, &[])
                .unwrap();
            let ratios = transmission_ratios(&b, NOISE_M, &experiments[k..=k], &truths[k..=k]).unwrap();
            assert!(!ratios.is_empty(), "joint {joint}: no bounded harmonic");
            for (name, r) in ratios {
                // Never above the per-arc bound (the chain holds the arc's information). Equality
                // is expected and not reached: measured 0.99923 (joint 1) and 0.98283 (joint
                // 6), a gap not yet explained (open, docs/validation.md; the study reports the
                // ratios), so no lower limit is asserted.
                eprintln!("joint {joint} {name}: one-sweep bound / per-arc bound {r:.5}");
                assert!(r <= 1.0 + ROUTE_TOLERANCE, "{name}: {r}");
            }
        }
        // The whole campaign holds every sweep's points: never less information.
        let whole = converged_bound(&desc, &steady, &options, NOISE_M, &experiments, &truths).unwrap();
        assert!(!whole.summary.transmission_bound_ratio.is_empty());
        for (name, r) in &whole.summary.transmission_bound_ratio {
            assert!(*r <= 1.0 + ROUTE_TOLERANCE, "{name}: {r}");
        }
        assert!(
            whole.summary.convention_agreement < ROUTE_TOLERANCE,
            "{:?}",
            whole.summary
        );
    }
}
