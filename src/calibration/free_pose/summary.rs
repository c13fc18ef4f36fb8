//! The free-pose calibration's summary: parameters with their sigmas, what was not identified,
//! the outliers, the residuals before and after, and the held-out check.

use super::error::FreePoseError;
use super::fit::{Fitted, Flag, Problem};
use super::identify::{Identification, Unidentified};
use super::model::FreePoseModel;
use crate::calibration::model_parameters::{ModelCovariance, model_difference, model_parameter_names};
use crate::calibration::noise::{NoiseEstimate, ResidualMoments, estimate_noise};
use crate::calibration::procedure::{Calibration, CalibrationOptions, NoiseReport, ZeroOffsetSigma};
use crate::calibration::refine::{ParameterUnit, RefitParameter};
use crate::kinematics::JointKind;
use crate::kinematics::rigid_fit;
use crate::robot::RobotDescription;
use crate::robot::{Placement, RobotModel};
use nalgebra::{DMatrix, DVector, Point3};
use serde::{Deserialize, Serialize};

/// One fitted parameter.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ParameterEstimate {
    /// Name (`row2.a`, `joint3.zero_offset`, `base.rz`, `target1.x`).
    pub name: String,
    /// Unit of `value`, `change` and `sigma`.
    pub unit: ParameterUnit,
    /// The fitted value \[unit\]; null for the base's components (its placement is
    /// `robot.placement`).
    pub value: Option<f64>,
    /// Fitted minus the registered nominal value \[unit\] (the base: the translation from the
    /// registered base along the instrument's axes, the rotation about the base's own axes).
    pub change: f64,
    /// Standard uncertainty (1-sigma) \[unit\].
    pub sigma: f64,
}

/// A target's fitted position on the last link.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct TargetEstimate {
    /// Target id.
    pub id: usize,
    /// The target as the data file wrote it: its name (`T1`, `SMR2`) or the integer id.
    pub name: String,
    /// Position in the tool frame of the nominal description \[mm\].
    pub position_mm: [f64; 3],
    /// 1-sigma of each coordinate \[mm\] (null where a coordinate was not identified).
    pub sigma_mm: [Option<f64>; 3],
}

/// A pose the outlier test flagged.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct OutlierPose {
    /// Its experiment.
    pub experiment: String,
    /// Its step.
    pub step: usize,
    /// RMS distance of its points from the last fit \[mm\].
    pub rms_mm: f64,
    /// The fence it exceeds \[mm\]: the RMS at which its normalised residual (studentised by
    /// its leverage, against its neighbours' noise) meets the fence of the family-wise
    /// `false_alarm` rate; without it (a refinement's), Tukey's far-out fence `Q3 + 3 IQR` of the
    /// poses' RMS.
    pub fence_mm: f64,
    /// The family-wise false-alarm rate of the test over the file's poses (a free-pose
    /// calibration's); absent for Tukey's fence.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub false_alarm: Option<f64>,
    /// Whether the fit was redone without it (`false` with `--keep-outliers`).
    pub dropped: bool,
    /// The largest departure of a spacing between two of its targets from that spacing's
    /// median over the poses \[mm\]: a model-free test of its rows (ids swapped, one target's
    /// point off, other units); absent with fewer than two targets in the pose.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spacing_departure_mm: Option<f64>,
    /// What the spacings' own noise reaches at a family-wise 1 % over the file's poses \[mm\]
    /// ([`super::poses::Spacings::fence_m`]); absent with `spacing_departure_mm`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spacing_fence_mm: Option<f64>,
}

/// The check on held-out poses.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Holdout {
    /// How the poses were split.
    pub split: String,
    /// Poses fitted.
    pub training_poses: usize,
    /// Held-out poses the RMS below covers: the held-out poses but the unexecutable ones and
    /// the outliers left out.
    pub heldout_poses: usize,
    /// RMS distance of the held-out points from the nominal model registered on the training
    /// poses \[mm\].
    pub nominal_rms_mm: f64,
    /// The same from the calibrated model \[mm\].
    pub calibrated_rms_mm: f64,
    /// Largest distance of a held-out point from the calibrated model \[mm\].
    pub calibrated_max_mm: f64,
    /// Held-out poses the calibrated model cannot execute (a fitted transmission not
    /// invertible there: its harmonics extrapolated beyond the fitted poses' range); left out
    /// of the RMS above.
    pub unexecutable_poses: usize,
    /// Held-out poses the outlier test flags (the training poses' test, each held-out pose
    /// studentised as outside the fit): left out of the RMS above (`dropped`), or kept in it
    /// with `--keep-outliers`.
    #[serde(default)]
    pub outliers: Vec<OutlierPose>,
}

/// The summary (`calibration.json`'s `free_poses`, `docs/formats.md#calibration-json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct FreePoseSummary {
    /// Poses fitted (after the outliers).
    pub poses: usize,
    /// Free poses of the file left out (beyond `calibrate --max-poses`, evenly spaced through
    /// the file; absent when every pose is used).
    #[serde(default, skip_serializing_if = "crate::json_file::is_zero_count")]
    pub poses_left_out: usize,
    /// Points fitted.
    pub points: usize,
    /// RMS distance of the points from the nominal model placed by the closed-form
    /// registration \[mm\].
    pub closed_form_rms_mm: f64,
    /// The same after the base and the targets were refined by least squares: the nominal
    /// model at its best \[mm\].
    pub nominal_rms_mm: f64,
    /// RMS distance from the calibrated model \[mm\].
    pub calibrated_rms_mm: f64,
    /// Levenberg-Marquardt steps of the final fit.
    pub iterations: usize,
    /// Condition number of the fitted parameters' column-scaled design.
    pub condition_number: f64,
    /// Fitted parameters.
    pub parameters: Vec<ParameterEstimate>,
    /// Parameters the poses do not identify (kept nominal).
    pub unidentified: Vec<Unidentified>,
    /// The targets on the last link.
    pub targets: Vec<TargetEstimate>,
    /// The tool frame fitted to the description's `tool.targets_mm` (RMS of that rigid fit
    /// \[mm\]); null when the description gives no tool targets matching the data's ids 0-2
    /// (the tool frame then stays nominal).
    pub tool_fit_rms_mm: Option<f64>,
    /// Poses flagged by the outlier test.
    pub outliers: Vec<OutlierPose>,
    /// The parameters' correlation matrix, in the order of `parameters`.
    pub correlation: Vec<Vec<f64>>,
    /// The held-out check (`--holdout`).
    pub holdout: Option<Holdout>,
    /// The robot's base in the instrument frame of each setup (the `setup` column's labels;
    /// one, `0`, without it): setup 0's is `robot.placement`.
    pub setups: Vec<SetupPlacement>,
    /// Why the axis experiments' rows were fitted as free poses (`--free-poses`, or sweeps
    /// the independent-axis procedure could not use); absent when the file has free poses
    /// only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis_rows_as_poses: Option<String>,
    /// The effects tried in the model (`--effects auto`), each with its cross-validated RMS:
    /// the one chosen is in `robot.effects`; empty with `--effects none`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub effects_tried: Vec<EffectTrial>,
    /// The kept effects joint by joint (sag first, then backlash, joints ascending).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub effect_joints: Vec<EffectJoint>,
    /// The column scales the geometric fit of every pose names before the outlier screen
    /// (a command column or an instrument axis, with the others alike on these data); the
    /// screen ran with them undone (absent when none is named).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub scales: Vec<super::NamedScale>,
}

/// One joint's part of the effects the model keeps.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct EffectJoint {
    /// The joint (1-based).
    pub joint: usize,
    /// `sag` or `backlash`.
    pub effect: String,
    /// Sag: the RMS of the joint's sag over the fitted poses; backlash: the half band
    /// \[mrad, or mm for a sliding joint's backlash\].
    pub rms: f64,
    /// Sag: the largest sag over the fitted poses; backlash: the half band.
    pub max: f64,
    /// Backlash: the half band's 1-sigma; sag: null (its terms' sigmas are in `parameters`).
    pub sigma: Option<f64>,
}

impl FreePoseSummary {
    /// The calibration predicts poses it was not fitted to no better than the nominal model
    /// fits every pose (its base registered, 6 parameters): the chosen effects'
    /// cross-validated RMS, or the held-out poses' calibrated RMS, at or above the nominal's.
    /// A model of more parameters that predicts no better has fitted something no robot
    /// parameter is (a column slip, a moved block, swapped ids, a missing effect): the
    /// comparison of a model's out-of-sample error with a simpler model's is the
    /// cross-validation criterion of Stone (*J. R. Statist. Soc. B* 36, 1974). Returns the
    /// words of what predicts no better, and `None` otherwise.
    pub fn predicts_no_better_than_nominal(&self) -> Option<String> {
        let held = self
            .holdout
            .as_ref()
            .filter(|h| h.calibrated_rms_mm >= h.nominal_rms_mm)
            .map(|h| {
                format!(
                    "the {} held-out poses by {:.4} mm RMS where the nominal model misses them by {:.4} mm",
                    h.heldout_poses, h.calibrated_rms_mm, h.nominal_rms_mm
                )
            });
        let cross = self
            .effects_tried
            .iter()
            .find(|t| t.chosen && t.cross_validated_rms_mm >= self.nominal_rms_mm)
            .map(|t| {
                format!(
                    "each configuration's poses, fitted without them, by {:.4} mm RMS (cross-validated, effects: {}) where the nominal model fits every pose to {:.4} mm",
                    t.cross_validated_rms_mm, t.effects, self.nominal_rms_mm
                )
            });
        cross.or(held)
    }
}

/// One set of effects tried in the free-pose model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct EffectTrial {
    /// `none`, `backlash`, `sag` or `sag+backlash`.
    pub effects: String,
    /// Its effect parameters the data identify (`docs/method.md`, "Effects in the model").
    pub parameters: usize,
    /// RMS distance of the held-out points over the cross-validation's folds \[mm\].
    pub cross_validated_rms_mm: f64,
    /// Whether the calibration keeps it: tried in this list's order, a set replaces the one
    /// kept before it only when its cross-validated sum of squares is lower by more than two
    /// standard errors of the paired per-pose differences.
    pub chosen: bool,
}

/// Where the instrument saw the robot's base from one setup.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct SetupPlacement {
    /// The setup's label.
    pub setup: String,
    /// The base in that setup's instrument frame.
    pub placement: Placement,
}

/// The stages a summary is made of.
pub(super) struct Stages<'a> {
    pub problem: &'a Problem<'a>,
    pub start: &'a FreePoseModel,
    pub registered: &'a Fitted,
    pub identification: &'a Identification,
    pub fitted: Fitted,
    pub kept: &'a [usize],
    pub flags: &'a [Flag],
    pub test: &'a [usize],
    pub keep_outliers: bool,
    pub effects_tried: Vec<EffectTrial>,
    pub scales: Vec<super::NamedScale>,
}

/// The calibration of the stages.
pub(super) fn summarise(s: Stages<'_>) -> Result<FreePoseCalibration, FreePoseError> {
    let variance = s.fitted.variance().unwrap_or(0.0);
    let covariance = s.fitted.covariance(variance)?;
    let layout = s.problem.layout;
    let fitted_columns = &s.identification.fitted;
    let parameters: Vec<ParameterEstimate> = fitted_columns
        .iter()
        .enumerate()
        .map(|(k, &c)| {
            estimate(
                &layout[c],
                &s.registered.model,
                &s.fitted.model,
                covariance[(k, k)].sqrt(),
            )
        })
        .collect();
    let (robot, tool_fit_rms_mm) = with_tool_frame(&s.fitted.model, s.problem);
    let effect_joints = effect_joints(&s.fitted.model, s.problem, s.kept, &parameters)?;
    let summary = FreePoseSummary {
        poses: s.kept.len(),
        poses_left_out: s.problem.poses.left_out,
        points: s.fitted.residual.len() / 3,
        closed_form_rms_mm: rms_of(s.start, s.problem, s.kept)? * 1e3,
        nominal_rms_mm: rms_of(&s.registered.model, s.problem, s.kept)? * 1e3,
        calibrated_rms_mm: s.fitted.rms_m() * 1e3,
        iterations: s.fitted.iterations,
        condition_number: crate::numerics::lsq::scaled_condition_number(&s.fitted.jacobian),
        targets: targets(&s.fitted.model, &parameters, &s.problem.poses.target_names),
        parameters,
        unidentified: s.identification.unidentified.clone(),
        tool_fit_rms_mm,
        outliers: outliers(s.flags, s.problem, s.kept),
        correlation: correlation(&covariance),
        holdout: holdout(&s)?,
        setups: s
            .problem
            .poses
            .setup_names
            .iter()
            .enumerate()
            .map(|(k, name)| SetupPlacement {
                setup: name.clone(),
                placement: Placement::from_isometry(&s.fitted.model.world_from_base(k)),
            })
            .collect(),
        axis_rows_as_poses: None,
        effects_tried: s.effects_tried.clone(),
        effect_joints,
        scales: s.scales.clone(),
    };
    let model_covariance = model_covariance(&s, &covariance, &robot);
    Ok(FreePoseCalibration {
        robot,
        model_covariance,
        noise: noise_of(&s.fitted),
        model: s.fitted.model,
        summary,
    })
}

/// The kept effects joint by joint: each sagging joint's RMS and largest sag over the poses
/// `kept`, each backlash's half band with its sigma (from `parameters`).
fn effect_joints(
    m: &FreePoseModel,
    problem: &Problem<'_>,
    kept: &[usize],
    parameters: &[ParameterEstimate],
) -> Result<Vec<EffectJoint>, FreePoseError> {
    let effects = &m.robot.effects;
    let mut joints: Vec<usize> = effects.sag.iter().map(|t| t.joint).collect();
    joints.dedup();
    let mut sags = vec![Vec::with_capacity(kept.len()); joints.len()];
    if !joints.is_empty() {
        for &i in kept {
            let sag = m
                .sag_at(problem.controller, problem.poses, i)
                .map_err(|u| u.error(problem.poses))?;
            for (list, &j) in sags.iter_mut().zip(&joints) {
                list.push(sag[j - 1]);
            }
        }
    }
    let mut out: Vec<EffectJoint> = joints
        .iter()
        .zip(&sags)
        .map(|(&joint, values)| EffectJoint {
            joint,
            effect: "sag".into(),
            rms: (values.iter().map(|v| v * v).sum::<f64>() / values.len().max(1) as f64).sqrt() * 1e3,
            max: values.iter().fold(0.0, |a: f64, v| a.max(v.abs())) * 1e3,
            sigma: None,
        })
        .collect();
    for b in &effects.backlash {
        let sliding = m.phi.joints[b.joint - 1].kind == crate::kinematics::JointKind::Prismatic;
        let name = RefitParameter::Backlash {
            joint: b.joint,
            sliding,
        }
        .name();
        out.push(EffectJoint {
            joint: b.joint,
            effect: "backlash".into(),
            rms: b.half_band.abs() * 1e3,
            max: b.half_band.abs() * 1e3,
            sigma: parameters.iter().find(|p| p.name == name).map(|p| p.sigma),
        });
    }
    Ok(out)
}

/// RMS distance of the points of the poses `which` from `model` \[m\].
fn rms_of(model: &FreePoseModel, problem: &Problem<'_>, which: &[usize]) -> Result<f64, FreePoseError> {
    let r = model
        .residuals(problem.controller, problem.poses, which)
        .map_err(|u| u.error(problem.poses))?;
    Ok((r.norm_squared() / (r.len() / 3).max(1) as f64).sqrt())
}

/// One parameter's estimate.
fn estimate(p: &RefitParameter, registered: &FreePoseModel, fitted: &FreePoseModel, sigma: f64) -> ParameterEstimate {
    let unit = p.unit();
    let scale = unit.per_si();
    let value = value_of(p, fitted);
    let change = match (value, value_of(p, registered)) {
        (Some(after), Some(before)) => after - before,
        _ => base_change(p, registered, fitted),
    };
    ParameterEstimate {
        name: p.name(),
        unit,
        value: value.map(|v| v * scale),
        change: change * scale,
        sigma: sigma * scale,
    }
}

/// A parameter's value in internal units (none for the base's components).
pub(super) fn value_of(p: &RefitParameter, m: &FreePoseModel) -> Option<f64> {
    match p {
        RefitParameter::RowA(r) => Some(m.phi.rows[r - 1].a_m),
        RefitParameter::RowB(r) => Some(m.phi.rows[r - 1].b_m),
        RefitParameter::RowAlpha(r) => Some(m.phi.rows[r - 1].alpha_rad),
        RefitParameter::RowBeta(r) => Some(m.phi.rows[r - 1].beta_rad),
        RefitParameter::ZeroOffset { joint, .. } => Some(m.robot.joints[joint - 1].transducer_offset),
        RefitParameter::Harmonic { joint, order, cosine } => match &m.robot.joints[joint - 1].transmission {
            crate::robot::Transmission::Harmonic { sin, cos } | crate::robot::Transmission::Gear { sin, cos, .. } => {
                Some(if *cosine { cos } else { sin }.get(order - 1).copied().unwrap_or(0.0))
            }
            _ => None,
        },
        RefitParameter::Coupling { joint, coefficient } => match &m.robot.joints[joint - 1].coupling_in {
            Some(crate::robot::CouplingFunction::Gear { sin, cos, .. }) => {
                let cosine = coefficient.starts_with("cos");
                let order = super::model::harmonic_order(p)?;
                Some(if cosine { cos } else { sin }.get(order - 1).copied().unwrap_or(0.0))
            }
            _ => None,
        },
        RefitParameter::Target { target, axis } => {
            let slot = m.target_ids.binary_search(target).ok()?;
            Some(m.targets_in_tool_m[slot][*axis])
        }
        RefitParameter::Sag { joint, link, load } => Some(
            m.robot
                .effects
                .sag
                .iter()
                .find(|t| (t.joint, t.link, t.load) == (*joint, *link, *load))
                .map_or(0.0, |t| t.coefficient),
        ),
        RefitParameter::Backlash { joint, .. } => Some(
            m.robot
                .effects
                .backlash
                .iter()
                .find(|b| b.joint == *joint)
                .map_or(0.0, |b| b.half_band),
        ),
        _ => None,
    }
}

/// The base's change from `before` to `after` along base parameter `p`: translation, or the
/// rotation vector of `R_before^T R_after` (the fit's local parameterisation, base axes).
fn base_change(p: &RefitParameter, before: &FreePoseModel, after: &FreePoseModel) -> f64 {
    let (setup, axis) = match p {
        RefitParameter::Base(i) => (0, *i),
        RefitParameter::SetupBase { setup, axis } => (*setup, *axis),
        _ => return 0.0,
    };
    let (b, a) = (before.world_from_base(setup), after.world_from_base(setup));
    match axis {
        i if i < 3 => a.translation.vector[i] - b.translation.vector[i],
        i => (b.rotation.inverse() * a.rotation).scaled_axis()[i - 3],
    }
}

/// The targets' positions with the sigmas of their fitted coordinates.
fn targets(m: &FreePoseModel, parameters: &[ParameterEstimate], names: &[String]) -> Vec<TargetEstimate> {
    m.target_ids
        .iter()
        .zip(&m.targets_in_tool_m)
        .zip(names)
        .map(|((&id, p), name)| {
            let sigma = |axis: usize| {
                let name = RefitParameter::Target { target: id, axis }.name();
                parameters.iter().find(|e| e.name == name).map(|e| e.sigma)
            };
            TargetEstimate {
                id,
                name: name.clone(),
                position_mm: [p.x * 1e3, p.y * 1e3, p.z * 1e3],
                sigma_mm: [sigma(0), sigma(1), sigma(2)],
            }
        })
        .collect()
}

/// The fitted robot with its tool frame moved onto the description's tool targets (ids 0, 1,
/// 2 and beyond, where the data have them): the rigid fit of the described positions onto the
/// fitted ones, and its RMS \[mm\]. Without three such targets the tool frame stays nominal.
fn with_tool_frame(m: &FreePoseModel, problem: &Problem<'_>) -> (crate::robot::RobotModel, Option<f64>) {
    let mut robot = m.to_robot();
    let described = &problem.description_targets_m;
    let pairs: Vec<(Point3<f64>, Point3<f64>)> = m
        .target_ids
        .iter()
        .zip(&m.targets_in_tool_m)
        .filter_map(|(&id, fitted)| described.get(id).map(|d| (*d, *fitted)))
        .collect();
    let (src, dst): (Vec<_>, Vec<_>) = pairs.into_iter().unzip();
    match rigid_fit(&src, &dst) {
        Some((nominal_tool_from_tool, rms)) => {
            let tool = m.phi.last_link_from_tool * nominal_tool_from_tool;
            robot.tool_frame = Placement::from_isometry(&tool);
            (robot, Some(rms * 1e3))
        }
        None => (robot, None),
    }
}

/// The covariance of the calibrated robot's parameters, `G C G^T`: `C` the fitted
/// parameters' covariance, `G` the central differences of the robot's parameter vector
/// ([`model_difference`]) over each fitted parameter's own update ([`FreePoseModel::moved`],
/// a step of 1e-3 of its sigma: the model is linear over it to ~1e-6 of the sigma). `None`
/// when a step changes the model's structure.
fn model_covariance(s: &Stages<'_>, covariance: &DMatrix<f64>, robot: &RobotModel) -> Option<ModelCovariance> {
    let names = model_parameter_names(robot);
    let columns = &s.identification.fitted;
    let mut g = DMatrix::zeros(names.len(), columns.len());
    for (i, &c) in columns.iter().enumerate() {
        let h = 1e-3 * covariance[(i, i)].sqrt().max(f64::MIN_POSITIVE);
        let at = |step: f64| {
            let moved = s
                .fitted
                .model
                .moved(s.problem.layout, &[c], &DVector::from_element(1, step));
            with_tool_frame(&moved, s.problem).0
        };
        let (plus, minus) = (at(h), at(-h));
        if model_parameter_names(&plus) != names || model_parameter_names(&minus) != names {
            return None;
        }
        g.set_column(i, &DVector::from_vec(model_difference(&plus, &minus, 2.0 * h)));
    }
    Some(ModelCovariance::new(names, &(&g * covariance * g.transpose())))
}

/// The flagged poses in the summary's terms.
fn outliers(flags: &[Flag], problem: &Problem<'_>, kept: &[usize]) -> Vec<OutlierPose> {
    let spacings = if flags.is_empty() {
        None
    } else {
        problem.poses.spacings()
    };
    flags
        .iter()
        .map(|f| {
            let pose = &problem.poses.poses[f.pose];
            let departure = spacings.as_ref().and_then(|s| Some((s.worst_m[f.pose]?, s.fence_m)));
            OutlierPose {
                experiment: pose.experiment.clone(),
                step: pose.step,
                rms_mm: f.rms_m * 1e3,
                fence_mm: f.fence_m * 1e3,
                false_alarm: Some(super::fit::FREE_POSES_FALSE_ALARM),
                dropped: !kept.contains(&f.pose),
                spacing_departure_mm: departure.map(|(d, _)| d * 1e3),
                spacing_fence_mm: departure.map(|(_, fence)| fence * 1e3),
            }
        })
        .collect()
}

/// The correlation matrix of a covariance.
fn correlation(c: &DMatrix<f64>) -> Vec<Vec<f64>> {
    let d: Vec<f64> = (0..c.nrows()).map(|i| c[(i, i)].sqrt()).collect();
    (0..c.nrows())
        .map(|i| (0..c.ncols()).map(|j| c[(i, j)] / (d[i] * d[j])).collect())
        .collect()
}

/// The held-out check, when poses were held out. The held-out poses are screened by the
/// training poses' outlier test ([`super::fit::flag_outside`]): one gross row among them would otherwise
/// make the held-out RMS its own; a flagged pose is left out of the RMS (kept with
/// `--keep-outliers`) and listed.
fn holdout(s: &Stages<'_>) -> Result<Option<Holdout>, FreePoseError> {
    if s.test.is_empty() {
        return Ok(None);
    }
    let (executable, unexecutable): (Vec<usize>, Vec<usize>) = s.test.iter().partition(|&&i| {
        s.fitted
            .model
            .residuals(s.problem.controller, s.problem.poses, &[i])
            .is_ok()
    });
    let flags = super::fit::flag_outside(
        s.problem,
        &s.fitted.model,
        s.kept,
        &executable,
        &s.identification.fitted,
    )?;
    let counted: Vec<usize> = executable
        .iter()
        .copied()
        .filter(|i| s.keep_outliers || !flags.iter().any(|f| f.pose == *i))
        .collect();
    let r = s
        .fitted
        .model
        .residuals(s.problem.controller, s.problem.poses, &counted)
        .map_err(|u| u.error(s.problem.poses))?;
    let max = (0..r.len() / 3)
        .map(|k| r.fixed_rows::<3>(3 * k).norm())
        .fold(0.0, f64::max);
    Ok(Some(Holdout {
        split: "configurations in order of first appearance: even ones fitted, odd ones held out (repeated visits of one configuration stay together)".into(),
        training_poses: s.kept.len(),
        heldout_poses: counted.len(),
        nominal_rms_mm: rms_of(&s.registered.model, s.problem, &counted)? * 1e3,
        calibrated_rms_mm: (r.norm_squared() / (r.len() / 3).max(1) as f64).sqrt() * 1e3,
        calibrated_max_mm: max * 1e3,
        unexecutable_poses: unexecutable.len(),
        outliers: outliers(&flags, s.problem, &counted),
    }))
}

/// A free-pose calibration: the fitted model and its summary.
#[derive(Clone, Debug)]
pub struct FreePoseCalibration {
    /// The calibrated robot (rows, zero offsets, base placement; transmissions and couplings
    /// nominal).
    pub robot: RobotModel,
    /// The fitted model (with the targets).
    pub model: FreePoseModel,
    /// The summary (`calibration.json`'s `free_poses`).
    pub summary: FreePoseSummary,
    /// The noise estimated from the residuals.
    pub noise: Option<NoiseEstimate>,
    /// The covariance of `robot`'s parameters (base, every scalar, tool frame;
    /// [`crate::calibration::model_parameters::model_parameter_names`]) propagated from the fitted
    /// parameters': what the predicted tool accuracy reads. `None` when a parameter's step
    /// changes the model's structure.
    pub model_covariance: Option<ModelCovariance>,
}

/// The noise estimate of a fit (isotropic, no jitter).
fn noise_of(fitted: &Fitted) -> Option<NoiseEstimate> {
    estimate_noise(&[ResidualMoments {
        rss_m2: fitted.residual.norm_squared(),
        dof: fitted.dof(),
        ..ResidualMoments::default()
    }])
}

impl FreePoseCalibration {
    /// The calibration in the shape every command reads (`calibration.json`): the calibrated
    /// robot, the zero offsets' sigmas and the noise, no axis reports; with the summary, which
    /// `calibration.json` holds beside it as `free_poses`.
    pub fn into_calibration(self, desc: &RobotDescription) -> (Calibration, FreePoseSummary) {
        let sigma = |name: String| {
            self.summary
                .parameters
                .iter()
                .find(|p| p.name == name)
                .map(|p| p.sigma / p.unit.per_si())
        };
        let zero_offset_sigma = (1..=desc.dof())
            .filter_map(|joint| {
                let sliding = desc.joints[joint - 1].kind == JointKind::Prismatic;
                let s = sigma(RefitParameter::ZeroOffset { joint, sliding }.name())?;
                Some(ZeroOffsetSigma {
                    joint,
                    sigma_rad: (!sliding).then_some(s),
                    sigma_mm: sliding.then_some(s * 1e3),
                })
            })
            .collect();
        let used_rms_3d_mm = self.noise.as_ref().map_or(0.0, |n| n.rms_3d_mm);
        let calibration = Calibration {
            robot: self.robot,
            reference_cmd: vec![0.0; desc.dof()],
            axes: vec![],
            row_sigma: vec![],
            couplings: vec![],
            zero_offset_sigma,
            tool: None,
            options: CalibrationOptions::default(),
            description: Some(desc.identity()),
            data_digest: None,
            model_digest: None,
            base_rule: None,
            not_calibrated: vec![],
            noise: Some(NoiseReport {
                estimate: self.noise,
                used_rms_3d_mm,
                source: "estimated".into(),
                given_p_value: None,
                given_contradicted: false,
            }),
            held_passes: 1,
            model_covariance: self.model_covariance,
            outliers: vec![],
            residuals: vec![],
        };
        (calibration, self.summary)
    }
}
