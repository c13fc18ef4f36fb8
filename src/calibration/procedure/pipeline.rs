//! The procedure's pipeline: the axis experiments of a campaign fitted, assembled into the
//! actual phi-model at the reference pose (rows, transmissions, couplings, zero offsets, base
//! and tool frames), the held joints corrected, the sigmas propagated ([`calibrate`]); the
//! lean path a Monte-Carlo trial takes stops after the assembly ([`calibrate_model`]).

use super::assembly_cache::{AssemblyCache, CacheUse};
use super::axis_fit::{AxisFitOutcome, JointData, add_held_joint_covariances, fit_joint};
use super::experiments::actuator_commands;
use super::height::{HeightObservation, at_reference, fixed_words, height_observation, moved_along};
use super::held::{Corrector, exactly_as_designed};
use super::joints::{Assembly, Refit, swept_commands_at_target1};
use super::propagation::{Derived, Propagation, add_axis_fit, moved_point};
use super::recorded_coupling::RecordedCoupling;
use super::{
    AxisCovariance, AxisEstimator, AxisExperiment, BaseRule, Calibration, CalibrationOptions, CouplingReport,
    DerivedSigma, Detail, NoiseReport, NominalGeometry, ProcedureError, RowSigma, ToolReport, ZeroOffsetSigma,
    axis_experiments_with,
};
use crate::calibration::coupling_fit::{CouplingResponse, passive_angle_gradients};
use crate::calibration::model_parameters::ModelCovariance;
use crate::calibration::noise::{NoiseEstimate, estimate_noise};
use crate::kinematics::{AxisLine, FixedFrames, JointKind, PhiModel, rigid_fit};
use crate::measurement::MeasurementSet;
use crate::robot::commands_to_internal;
use crate::robot::{Controller, JointModel, Placement, RobotDescription, RobotModel, Transmission};
use nalgebra::{DMatrix, Isometry3, Point3, Unit, Vector3};

/// The lean result of [`calibrate_model`]: the fitted model, as [`calibrate`] would fit it
/// bit for bit, without the report.
#[derive(Clone, Debug, PartialEq)]
pub struct FittedModel {
    /// The calibrated robot (the same value as [`Calibration::robot`]).
    pub robot: RobotModel,
    /// 1-sigma of each row ([`Calibration::row_sigma`]); `Some` with
    /// [`Detail::ModelAndCovariance`] only.
    pub row_sigma: Option<Vec<RowSigma>>,
    /// Fit-and-correct passes for the held joints' recorded values.
    pub held_passes: usize,
    /// The fitted couplings' reports (their `sigma` propagated with
    /// [`Detail::ModelAndCovariance`], else the coupling fits' own a-posteriori sigma).
    pub couplings: Vec<CouplingReport>,
    /// The propagated 1-sigma of the couplings, zero offsets and tool frame; `Some` with
    /// [`Detail::ModelAndCovariance`] only.
    pub derived_sigma: Option<DerivedSigma>,
    /// The covariance of the calibrated model's parameters
    /// ([`crate::calibration::tool_accuracy`]); `Some` with [`Detail::ModelCovariance`]
    /// only.
    pub model_covariance: Option<ModelCovariance>,
}

/// Calibrates the robot described (nominally) by `desc` from the axis experiments of `set`
/// (and the tool targets at the reference pose, when observed). With
/// [`CalibrationOptions::estimate_noise`] the fits are weighted, in a second run, with the
/// noise the first run's residuals estimate. This is [`calibrate_model`]'s path with the
/// report's extras added at the end.
pub fn calibrate(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &CalibrationOptions,
) -> Result<Calibration, ProcedureError> {
    calibrate_as(
        set,
        desc,
        options,
        Detail::Report,
        &|ctx, state, reference_cmd, passes| ctx.finish(set, state, reference_cmd, passes),
    )
    .map_err(|e| e.with_lines(set))
}

/// The lean path for Monte-Carlo trials: the same procedure as [`calibrate`] (the same code,
/// the same model bit for bit), without what only a report needs: no identifiability span
/// studies, per-sweep reports, residual lists or noise report, and the axes' covariances
/// only when `detail` is [`Detail::ModelAndCovariance`] (then `row_sigma` is filled) or
/// [`Detail::ModelCovariance`] (then `model_covariance` too). [`Detail::Report`] is taken as
/// [`Detail::ModelAndCovariance`].
pub fn calibrate_model(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &CalibrationOptions,
    detail: Detail,
) -> Result<FittedModel, ProcedureError> {
    let detail = match detail {
        Detail::Model | Detail::ModelCovariance => detail,
        Detail::ModelAndCovariance | Detail::Report => Detail::ModelAndCovariance,
    };
    calibrate_as(set, desc, options, detail, &|ctx, state, reference_cmd, passes| {
        Ok(ctx.finish_model(set, &state, &reference_cmd, passes)?.0)
    })
}

/// Turns the last pass's state, the reference commands and the pass count into a result.
type Finish<'f, T> = dyn Fn(&Context<'_>, Assembled, Vec<f64>, usize) -> Result<T, ProcedureError> + 'f;

/// The procedure at `detail`, finished by `finish`; with [`CalibrationOptions::estimate_noise`]
/// run again with the noise the first run's residual moments estimate.
fn calibrate_as<T>(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &CalibrationOptions,
    detail: Detail,
    finish: &Finish<'_, T>,
) -> Result<T, ProcedureError> {
    let (first, estimate) = calibrate_at(set, desc, options, options.noise_rms_3d_mm, detail, finish)?;
    match estimate {
        Some(e) if options.estimate_noise && e.rms_3d_mm > 0.0 => {
            Ok(calibrate_at(set, desc, options, e.rms_3d_mm, detail, finish)?.0)
        }
        _ => Ok(first),
    }
}

/// Most fit-and-correct passes for recorded held joints before giving up.
const MAX_HELD_PASSES: usize = 12;

/// One state of the procedure: the fits of every joint and the model they assemble to.
struct Assembled {
    fits: Vec<Option<AxisFitOutcome>>,
    axes: Vec<Option<AxisLine>>,
    base_rule: BaseRule,
    robot: RobotModel,
    couplings: Vec<CouplingReport>,
    /// Target-0 points of each joint's sweeps as fitted (to test the passes' convergence).
    points: Vec<Point3<f64>>,
    /// Target 1 of each experiment as the couplings were fitted from it.
    target1: Vec<Vec<Point3<f64>>>,
}

/// The calibration with the fits weighted by `noise_mm` (3-D RMS), and the noise its
/// residuals estimate (when [`CalibrationOptions::estimate_noise`] asks for it).
fn calibrate_at<T>(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &CalibrationOptions,
    noise_mm: f64,
    detail: Detail,
    finish: &Finish<'_, T>,
) -> Result<(T, Option<NoiseEstimate>), ProcedureError> {
    let repeatability = options.joint_repeatability_rad(desc)?;
    let (experiments, reference_cmd) = axis_experiments_with(set, desc, options.held_tolerance)?;
    let controller = Controller::from_description(desc);
    let q_ref = commands_to_internal(desc, &reference_cmd);
    let u_ref = actuator_commands(&controller, desc, &reference_cmd);
    let target1_commands = swept_commands_at_target1(&experiments, &controller, desc);
    let nominal = NominalGeometry::new(desc.nominal_model(), &q_ref)?;
    let ctx = Context {
        desc,
        options,
        controller: &controller,
        experiments: &experiments,
        target1_commands: &target1_commands,
        q_ref: &q_ref,
        u_ref: &u_ref,
        nominal: &nominal,
        repeatability: &repeatability,
        noise_mm,
        detail,
    };
    let exact = exactly_as_designed(&experiments, &reference_cmd, desc);
    // First pass: each joint from its sweep nearest the design, as measured.
    let raw_t1: Vec<Vec<Point3<f64>>> = experiments.iter().map(|e| e.target1_m.clone()).collect();
    let (state, passes) = match ctx.assemble(|k| ctx.first_sweep(k, &reference_cmd, exact, false), &raw_t1) {
        Ok(first) if exact => (first, 1),
        Ok(first) => ctx.held_passes(first, &reference_cmd)?,
        // Held joints that wander step by step move the measured points off one arc by their
        // wander times its lever: the measured points' fit then only starts the correction,
        // and the corrected points face the gate. Data the correction does not bring onto
        // one arc keep the first refusal.
        Err(refused) if !exact && matches!(refused, ProcedureError::Absurd { .. } | ProcedureError::Misfit { .. }) => {
            ctx.assemble(|k| ctx.first_sweep(k, &reference_cmd, exact, true), &raw_t1)
                .and_then(|first| ctx.held_passes(first, &reference_cmd))
                .map_err(|_| refused)?
        }
        Err(e) => return Err(e),
    };
    let estimate = if options.estimate_noise {
        let moments: Vec<_> = state.fits.iter().flatten().filter_map(|f| f.moments).collect();
        estimate_noise(&moments)
    } else {
        None
    };
    Ok((finish(&ctx, state, reference_cmd, passes)?, estimate))
}

/// The phi-model of fitted axes, its base rule, the joint models and fitted couplings on it
/// and the last link at the reference pose ([`Context::joints_from`]).
type AssembledJoints = (PhiModel, BaseRule, Vec<JointModel>, Vec<CouplingReport>, Isometry3<f64>);

/// What the poses at the reference commands measured of the tool: the rigid fit of the three
/// tool targets (the tool frame, world) and, when no pose sees all three, the targets seen that
/// fix the position along the axes the sweeps leave open ([`super::height`]) at their measured
/// positions.
#[derive(Clone, Copy)]
struct Seen<'s> {
    tool: Option<&'s Isometry3<f64>>,
    height: Option<(&'s HeightObservation, &'s [Point3<f64>])>,
}

impl<'s> Seen<'s> {
    /// The rigid fit `tool` and the height observation of `height` at its measured points.
    fn new(tool: Option<&'s Isometry3<f64>>, height: Option<&'s (HeightObservation, Unit<Vector3<f64>>)>) -> Self {
        Seen {
            tool,
            height: height.map(|(obs, _)| (obs, obs.measured.as_slice())),
        }
    }
}

/// What every pass of the procedure shares.
struct Context<'a> {
    desc: &'a RobotDescription,
    options: &'a CalibrationOptions,
    controller: &'a Controller,
    experiments: &'a [AxisExperiment],
    /// Each experiment's swept actuator command at its target-1 steps.
    target1_commands: &'a [Vec<f64>],
    q_ref: &'a [f64],
    u_ref: &'a [f64],
    /// The nominal model's part of the frames from the axes, at `q_ref`.
    nominal: &'a NominalGeometry,
    repeatability: &'a [f64],
    noise_mm: f64,
    /// What the fits compute besides the model.
    detail: Detail,
}

impl<'a> Context<'a> {
    /// The fit-and-correct passes for the held joints' recorded values from the first pass's
    /// state `state` (`docs/formats.md#held-joints`; [`Corrector`]): the last state and the
    /// passes made, once no corrected point moves by more than a thousandth of the noise.
    fn held_passes(&self, mut state: Assembled, reference_cmd: &[f64]) -> Result<(Assembled, usize), ProcedureError> {
        let mut passes = 1;
        let tolerance_m = (1e-3 * self.noise_mm * 1e-3 / 3f64.sqrt()).max(1e-12);
        let mut change = f64::INFINITY;
        while change > tolerance_m {
            if passes >= MAX_HELD_PASSES {
                return Err(ProcedureError::HeldNotConverged {
                    passes,
                    change_mm: change * 1e3,
                });
            }
            let corrector = Corrector {
                model: &state.robot,
                controller: self.controller,
                desc: self.desc,
                reference_cmd,
            };
            let t0: Vec<Vec<Point3<f64>>> = self
                .experiments
                .iter()
                .map(|e| corrector.corrected(e, 0))
                .collect::<Result<_, _>>()?;
            let t1: Vec<Vec<Point3<f64>>> = self
                .experiments
                .iter()
                .map(|e| corrector.corrected(e, 1))
                .collect::<Result<_, _>>()?;
            let next = self
                .assemble(|k| self.all_sweeps(k, &t0), &t1)
                .map_err(|source| match source {
                    // A refused option (the paper's estimator on a joint swept twice) is
                    // refused as such, not as a divergence of the correction.
                    e @ ProcedureError::InvalidOption(_) => e,
                    source => ProcedureError::HeldDiverged {
                        pass: passes + 1,
                        cause: Box::new(source),
                    },
                })?;
            change = if next.points.len() == state.points.len() && passes > 1 {
                next.points
                    .iter()
                    .zip(&state.points)
                    .map(|(a, b)| (a - b).norm())
                    .fold(0.0, f64::max)
            } else {
                f64::INFINITY
            };
            state = next;
            passes += 1;
        }
        Ok((state, passes))
    }

    /// Joint `k`'s (0-based) data of the first pass: every sweep when the campaign is exactly
    /// as designed (one each), else the sweep nearest the design, as measured; `start_only`:
    /// its fit only starts the held joints' correction ([`JointData::start_only`]).
    fn first_sweep(&self, k: usize, reference: &[f64], exact: bool, start_only: bool) -> Option<JointData<'a>> {
        let mut sweeps: Vec<&AxisExperiment> = self.experiments.iter().filter(|e| e.joint == k + 1).collect();
        if !exact && sweeps.len() > 1 {
            let best = sweeps
                .iter()
                .copied()
                .min_by(|a, b| a.held_distance(reference).total_cmp(&b.held_distance(reference)))?;
            sweeps = vec![best];
        }
        let points = sweeps.iter().map(|e| e.target0_m.clone()).collect();
        (!sweeps.is_empty()).then_some(JointData {
            sweeps,
            points,
            start_only,
        })
    }

    /// Joint `k`'s data: every sweep with the corrected target-0 points `t0` (by experiment).
    fn all_sweeps(&self, k: usize, t0: &[Vec<Point3<f64>>]) -> Option<JointData<'a>> {
        let (sweeps, points): (Vec<&AxisExperiment>, Vec<Vec<Point3<f64>>>) = self
            .experiments
            .iter()
            .zip(t0)
            .filter(|(e, _)| e.joint == k + 1)
            .map(|(e, p)| (e, p.clone()))
            .unzip();
        (!sweeps.is_empty()).then_some(JointData {
            sweeps,
            points,
            start_only: false,
        })
    }

    /// Fits every swept joint from `data(k)` and assembles the model (target 1 of each
    /// experiment: `target1`).
    fn assemble(
        &self,
        data: impl Fn(usize) -> Option<JointData<'a>>,
        target1: &[Vec<Point3<f64>>],
    ) -> Result<Assembled, ProcedureError> {
        let n = self.desc.dof();
        let mut fits = Vec::with_capacity(n);
        let mut points = Vec::new();
        for k in 0..n {
            fits.push(match data(k) {
                Some(d) => {
                    points.extend(d.points.iter().flatten().copied());
                    Some(fit_joint(
                        &d,
                        self.desc,
                        self.controller,
                        self.options,
                        self.noise_mm,
                        self.repeatability[k],
                        self.detail,
                    )?)
                }
                None => None,
            });
        }
        let axes: Vec<Option<AxisLine>> = fits.iter().map(|f| f.as_ref().map(|f| f.axis)).collect();
        let transmissions: Vec<Option<Transmission>> = fits
            .iter()
            .map(|f| f.as_ref().map(|f| f.transmission.clone()))
            .collect();
        let (geometry, base_rule, joints, couplings, _) =
            self.joints_from(&axes, &transmissions, target1, Refit::default())?;
        let robot = calibrated_robot(self.desc, joints, &geometry);
        Ok(Assembled {
            fits,
            axes,
            base_rule,
            robot,
            couplings,
            points,
            target1: target1.to_vec(),
        })
    }

    /// The model of the last pass with its tool frame (when measured) and, unless `detail` is
    /// [`Detail::Model`], the rows' sigmas (from the axes' covariances as fitted, before the
    /// held joints' bias is added): what every path needs.
    fn finish_model(
        &self,
        set: &MeasurementSet,
        state: &Assembled,
        reference_cmd: &[f64],
        passes: usize,
    ) -> Result<(FittedModel, Option<ToolReport>), ProcedureError> {
        // The paper's estimator gives its lines no covariance: nothing to propagate, so no
        // sigma is reported (none in the file) rather than the zero the propagation of nothing
        // would give.
        let paper = self.options.estimator == AxisEstimator::Paper;
        let row_sigma = match self.detail {
            Detail::Model => None,
            _ if paper => Some(vec![]),
            _ => Some(calibrated_row_sigmas(self.nominal, &state.axes, &state.fits)?),
        };
        let mut robot = state.robot.clone();
        let mut tool = tool_frame(set, self.desc, &robot, reference_cmd, self.controller);
        if let Some(t) = &tool {
            robot.tool_frame = Placement::from_isometry(&t.last_link_from_tool);
        } else if let Some((moved, _)) = self.height(set, state, reference_cmd).and_then(|(obs, direction)| {
            moved_along(
                &robot,
                (&obs, &obs.measured),
                &direction,
                (self.desc, self.controller, self.q_ref),
            )
        }) {
            robot = moved;
        }
        let mut couplings = state.couplings.clone();
        let (derived_sigma, model_covariance) = match self.detail {
            Detail::Model => (None, None),
            _ if paper => (None, None),
            _ => {
                let (d, m) = self.derived_sigma(set, state, reference_cmd)?;
                (Some(d), m)
            }
        };
        if let Some(d) = &derived_sigma {
            for (c, s) in couplings.iter_mut().zip(&d.couplings) {
                c.sigma = s.clone();
            }
            if let Some(t) = &mut tool {
                t.sigma = d.tool;
            }
        }
        let model = FittedModel {
            robot,
            row_sigma,
            held_passes: passes,
            couplings,
            derived_sigma,
            model_covariance,
        };
        Ok((model, tool))
    }

    /// The tool targets seen at the reference pose that fix the position along the axis the
    /// base rule of `state` leaves open, with that axis's observed direction
    /// ([`super::height`]); `None` when the tool frame is measured (it takes that position) or
    /// nothing fixes it.
    fn height(
        &self,
        set: &MeasurementSet,
        state: &Assembled,
        reference_cmd: &[f64],
    ) -> Option<(HeightObservation, Unit<Vector3<f64>>)> {
        if tool_observation(set, self.desc, reference_cmd).is_some() {
            return None;
        }
        let obs = height_observation(set, self.desc, reference_cmd, &state.base_rule)?;
        let direction = state.axes.get(obs.axis).copied().flatten()?.direction;
        // A move beyond a description's error (`SIZE_TOLERANCE` of its longest length) is not
        // taken: the description is off there, which the check of the file's own validation
        // poses then says (the tool frame would have to move as far).
        let (_, delta) = moved_along(
            &state.robot,
            (&obs, &obs.measured),
            &direction,
            (self.desc, self.controller, self.q_ref),
        )?;
        let bound = super::size::SIZE_TOLERANCE * super::size::longest_length_m(self.desc);
        (delta.abs() <= bound).then_some((obs, direction))
    }

    /// The phi-model of the fitted `axes` (with its base rule) and the joint models and
    /// fitted couplings on it, from the fitted `transmissions` and the second targets
    /// `target1`. With `warm` (the couplings' responses at a previous assembly's optimum, by driven
    /// joint) the couplings are refitted by one Newton step from those
    /// ([`crate::calibration::coupling_fit::CouplingResponse::refit`]). With the last link
    /// at the reference pose: the calibrated joint values there are `q_ref` by construction
    /// (`docs/method.md`), so it is the chain's at `q_ref` (the couplings' fits use the same
    /// poses).
    fn joints_from(
        &self,
        axes: &[Option<AxisLine>],
        transmissions: &[Option<Transmission>],
        target1: &[Vec<Point3<f64>>],
        refit: Refit,
    ) -> Result<AssembledJoints, ProcedureError> {
        let (geometry, base_rule) = match refit.geometry {
            Some((geometry, rule)) => (geometry.clone(), rule.clone()),
            None => self.nominal.model_from_axes(axes)?,
        };
        let geometry = FixedFrames::new(geometry);
        let assembly = Assembly {
            desc: self.desc,
            experiments: self.experiments,
            target1_commands: self.target1_commands,
            transmissions,
            target1,
            geometry: &geometry,
            q_ref: self.q_ref,
            u_ref: self.u_ref,
            refit,
            reference_poses: std::cell::OnceCell::new(),
        };
        let (joints, couplings) = assembly.joint_models()?;
        let world_from_last_link = assembly.poses_at_reference().world_from_link[self.desc.dof() - 1];
        Ok((
            geometry.into_model(),
            base_rule,
            joints,
            couplings,
            world_from_last_link,
        ))
    }

    /// The derived quantities (couplings' parameters, zero offsets, tool frame) the fitted
    /// `axes` and `transmissions`, the second targets `target1` and the tool frame `tool`
    /// (the rigid fit of the tool targets measured at the reference pose) give; couplings refitted from `warm` as in
    /// [`Context::joints_from`]. With the calibrated robot's last link at the reference pose
    /// (when there is a tool frame), for [`Context::with_tool`].
    fn derived(
        &self,
        (axes, transmissions): (&[Option<AxisLine>], &[Option<Transmission>]),
        target1: &[Vec<Point3<f64>>],
        seen: Seen<'_>,
        refit: Refit,
    ) -> Result<(Derived, Option<Isometry3<f64>>), ProcedureError> {
        let tool = seen.tool;
        let (geometry, _, joints, couplings, last_link) = self.joints_from(axes, transmissions, target1, refit)?;
        let mut values: Vec<f64> = couplings.iter().flat_map(|c| c.parameters.iter().copied()).collect();
        values.extend(joints.iter().map(|j| j.transducer_offset));
        let world_from_link = tool.map(|_| last_link);
        let derived = Derived {
            values,
            coupling_sizes: couplings.iter().map(|c| c.parameters.len()).collect(),
            tool: None,
            robot: None,
        };
        let robot = matches!(self.detail, Detail::Report | Detail::ModelCovariance)
            .then(|| calibrated_robot(self.desc, joints, &geometry))
            .map(|robot| match seen.height {
                Some((obs, measured)) => axes
                    .get(obs.axis)
                    .copied()
                    .flatten()
                    .and_then(|axis| {
                        moved_along(
                            &robot,
                            (obs, measured),
                            &axis.direction,
                            (self.desc, self.controller, self.q_ref),
                        )
                    })
                    .map_or(robot, |(moved, _)| moved),
                None => robot,
            });
        Ok((
            self.with_tool(derived, robot, world_from_link.as_ref(), tool),
            world_from_link,
        ))
    }

    /// `derived` with the tool frame in the last link (`world_from_link`, the robot's at the
    /// reference pose) from the measured tool frame `tool` (the tool targets' rigid fit, none
    /// without) and, on the report path, the whole model `robot` with that tool frame (for
    /// its covariance).
    fn with_tool(
        &self,
        derived: Derived,
        robot: Option<RobotModel>,
        world_from_link: Option<&Isometry3<f64>>,
        tool: Option<&Isometry3<f64>>,
    ) -> Derived {
        let tool = tool
            .zip(world_from_link)
            .map(|(world_from_tool, link)| link.inverse() * world_from_tool);
        let robot = robot.map(|mut model| {
            if let Some(t) = &tool {
                model.tool_frame = Placement::from_isometry(t);
            }
            model
        });
        Derived { tool, robot, ..derived }
    }

    /// The propagated 1-sigma of the derived quantities of `state` (`propagation`): through
    /// every ML axis fit's covariance, the noise of the second targets the couplings are
    /// fitted from, and that of the tool targets. The perturbed assemblies refit the couplings
    /// by one Newton step from `state`'s (their first-order response, which is what the
    /// propagation differentiates); the tool targets move only the tool frame; the second
    /// targets move the rest only through their coupling's parameters
    /// ([`Context::second_target_sigma`]).
    fn derived_sigma(
        &self,
        set: &MeasurementSet,
        state: &Assembled,
        reference_cmd: &[f64],
    ) -> Result<(DerivedSigma, Option<ModelCovariance>), ProcedureError> {
        let transmissions: Vec<Option<Transmission>> = state
            .fits
            .iter()
            .map(|f| f.as_ref().map(|f| f.transmission.clone()))
            .collect();
        let tool_points = tool_observation(set, self.desc, reference_cmd).map(|o| o.measured);
        let tool_fit = |points: &[Point3<f64>]| rigid_fit(&self.desc.tool_targets_m(), points).map(|(w, _)| w);
        let world_from_tool = tool_points.as_deref().and_then(tool_fit);
        let tool = world_from_tool.as_ref();
        let height = self.height(set, state, reference_cmd);
        let seen = Seen::new(tool, height.as_ref());
        let (axes, target1) = (&state.axes, &state.target1);
        let cache = AssemblyCache::default();
        let recording = Refit {
            fitted: Some(&state.couplings),
            cache: Some(CacheUse::Record(&cache)),
            ..Refit::default()
        };
        let (base, world_from_link) = self.derived((axes, &transmissions), target1, seen, recording)?;
        let record = cache.take_recorded();
        let mut responses: Vec<Option<CouplingResponse>> = vec![None; self.desc.dof()];
        record.iter().for_each(|c| responses[c.k] = Some(c.response.clone()));
        let warm = Refit {
            warm: Some(&responses),
            cache: Some(CacheUse::Reuse(&cache)),
            ..Refit::default()
        };
        let geometry = self.nominal.model_from_axes(axes)?;
        // The axis fits' columns differ from the unmoved assembly refitted the same way.
        let unmoved = Refit {
            geometry: Some(&geometry),
            ..warm
        };
        let warm_base = self.derived((axes, &transmissions), target1, seen, unmoved)?.0;
        let mut prop = Propagation::new(base.len());
        for (k, local) in state.fits.iter().enumerate() {
            let Some(local) = local.as_ref().and_then(|f| f.local.as_ref()) else {
                continue;
            };
            let axis = axes[k].expect("a fitted joint has its axis");
            add_axis_fit(&mut prop, local, &axis, &warm_base, |axis, transmission| {
                let (mut a, mut t) = (axes.clone(), transmissions.clone());
                if transmission.is_some() {
                    t[k] = transmission;
                }
                let refit = match axis {
                    Some(axis) => {
                        a[k] = Some(axis);
                        warm
                    }
                    None => Refit {
                        geometry: Some(&geometry),
                        ..warm
                    },
                };
                Ok::<_, ProcedureError>(self.derived((&a, &t), target1, seen, refit)?.0)
            })?;
        }
        for coupling in record {
            let c = self.second_target_sigma(&coupling, axes, target1)?;
            let set_to = |i: usize, h: f64| {
                let mut x = coupling.parameters.clone();
                if let Some(xi) = x.get_mut(i) {
                    *xi += h;
                }
                let fixed = Refit {
                    fixed: Some((coupling.k, &x)),
                    geometry: Some(&geometry),
                    ..warm
                };
                Ok::<_, ProcedureError>(self.derived((axes, &transmissions), target1, seen, fixed)?.0)
            };
            let at_fit = set_to(usize::MAX, 0.0)?;
            prop.add(&c, &at_fit, set_to)?;
        }
        if let Some(points) = &tool_points {
            let sigma = self.noise_mm * 1e-3 / 3f64.sqrt();
            let lists = vec![points.clone()];
            let at: Vec<(usize, usize)> = (0..points.len()).map(|j| (0, j)).collect();
            prop.add_independent(3 * points.len(), sigma, &base, |k, h| {
                let moved = moved_point(&lists, &at, k, h);
                let moved_tool = tool_fit(&moved[0]);
                let mut moved = base.clone();
                let robot = moved.robot.take();
                Ok::<_, ProcedureError>(self.with_tool(moved, robot, world_from_link.as_ref(), moved_tool.as_ref()))
            })?;
        }
        height
            .as_ref()
            .map_or(Ok(()), |(o, d)| self.add_height_noise(&mut prop, &base, o, d))?;
        Ok((base.sigma(&prop.covariance), base.model_covariance(&prop.covariance)))
    }

    /// Adds to `prop` the noise of the tool targets `obs` that fixed the position along
    /// `direction` ([`super::height`]): they move the model along it only (`delta` is linear
    /// in them), so each column is the unmoved model `base` moved by the change of `delta`.
    fn add_height_noise(
        &self,
        prop: &mut Propagation,
        base: &Derived,
        obs: &HeightObservation,
        direction: &Unit<Vector3<f64>>,
    ) -> Result<(), ProcedureError> {
        let sigma = self.noise_mm * 1e-3 / 3f64.sqrt();
        let lists = vec![obs.measured.clone()];
        let at: Vec<(usize, usize)> = (0..obs.measured.len()).map(|j| (0, j)).collect();
        let context = (self.desc, self.controller, self.q_ref);
        prop.add_independent(3 * obs.measured.len(), sigma, base, |k, h| {
            let moved = moved_point(&lists, &at, k, h);
            let mut derived = base.clone();
            derived.robot = derived
                .robot
                .take()
                .and_then(|r| moved_along(&r, (obs, &moved[0]), direction, context).map(|m| m.0));
            Ok::<_, ProcedureError>(derived)
        })
    }

    /// The covariance of a fitted coupling's parameters from the noise of its second targets
    /// (each coordinate `sigma`, the measurement noise) and the swept joint's repeatability
    /// (each target turned about the driving axis, one independent angle per step), the
    /// coupling's inputs otherwise fixed: `S C_y S^T`. The passive displacements
    /// `y_j = a_j - a_0` have `C_y = diag(v_j) + v_0` (`j, l >= 1`) with
    /// `v_j = sigma^2 |g_j|^2 + rep^2 (g_j . (u x (p_j - o)))^2`, `g_j` the angle's gradient
    /// ([`passive_angle_gradients`]); `S = d x / d y` from the fit's exact Hessian at its
    /// optimum ([`RecordedCoupling::passive_sensitivity`]). Chained with the
    /// assembly's derivatives with respect to the coupling's parameters this is the
    /// propagation of the second targets' noise (they move nothing else).
    fn second_target_sigma(
        &self,
        coupling: &RecordedCoupling,
        axes: &[Option<AxisLine>],
        target1: &[Vec<Point3<f64>>],
    ) -> Result<DMatrix<f64>, ProcedureError> {
        let experiment = &self.experiments[coupling.index];
        let fit_err = |error| ProcedureError::Fit {
            experiment: experiment.name.clone(),
            joint: coupling.k,
            error,
        };
        let second = &target1[coupling.index];
        let from_start = coupling.active_from_start();
        let gradients = passive_angle_gradients(&coupling.frame_next, &coupling.axis_from, &from_start, second);
        let sigma = self.noise_mm * 1e-3 / 3f64.sqrt();
        let joint = experiment.joint - 1;
        let turn = axes[joint].filter(|_| self.repeatability[joint] > 0.0);
        let v: Vec<f64> = gradients
            .iter()
            .zip(second)
            .map(|(g, p)| {
                let jitter = turn.map_or(0.0, |a| {
                    (self.repeatability[joint] * g.dot(&a.direction.cross(&(p - a.origin_m)))).powi(2)
                });
                sigma * sigma * g.norm_squared() + jitter
            })
            .collect();
        let n = from_start.len();
        let c_y = DMatrix::from_fn(n, n, |j, l| match (j, l) {
            (0, _) | (_, 0) => 0.0,
            (j, l) => v[0] + if j == l { v[j] } else { 0.0 },
        });
        let s = coupling.passive_sensitivity().map_err(fit_err)?;
        Ok(&s * c_y * s.transpose())
    }

    /// The calibration of the last pass: [`Context::finish_model`] plus the report's extras
    /// (held joints' covariance, axis reports, noise report, residuals).
    fn finish(
        &self,
        set: &MeasurementSet,
        state: Assembled,
        reference_cmd: Vec<f64>,
        passes: usize,
    ) -> Result<Calibration, ProcedureError> {
        let (model, tool) = self.finish_model(set, &state, &reference_cmd, passes)?;
        let FittedModel {
            robot,
            row_sigma,
            couplings,
            derived_sigma,
            model_covariance,
            ..
        } = model;
        let zero_offset_sigma = zero_offset_sigmas(self.desc, derived_sigma.as_ref());
        let height = if tool.is_none() {
            self.height(set, &state, &reference_cmd)
        } else {
            None
        };
        let state_placement_mm = state.robot.placement.translation_mm;
        let Assembled {
            mut fits,
            axes,
            base_rule,
            ..
        } = state;
        let kinds: Vec<JointKind> = self.desc.joints.iter().map(|j| j.kind).collect();
        add_held_joint_covariances(&mut fits, &axes, &kinds, self.repeatability);
        let noise = self.noise_report(&fits);
        let not_calibrated = (1..=fits.len()).filter(|k| fits[k - 1].is_none()).collect();
        let mut residuals = Vec::new();
        let mut axes_reports = Vec::new();
        for f in fits.into_iter().flatten() {
            residuals.extend(f.residuals);
            axes_reports.push(f.report);
        }
        let base_rule = match height {
            Some((obs, direction)) => {
                let moved: f64 = robot.placement.translation_mm[..]
                    .iter()
                    .zip(&state_placement_mm)
                    .zip(direction.iter())
                    .map(|((a, b), d)| (a - b) * 1e-3 * d)
                    .sum();
                base_rule.with_along_fixed(obs.axis, &fixed_words(&obs, moved))
            }
            None => base_rule,
        };
        Ok(Calibration {
            robot,
            reference_cmd,
            axes: axes_reports,
            row_sigma: row_sigma.unwrap_or_default(),
            couplings,
            zero_offset_sigma,
            tool,
            options: self.options.clone(),
            base_rule: Some(base_rule),
            not_calibrated,
            noise: Some(noise),
            held_passes: passes,
            outliers: vec![],
            residuals,
            description: Some(self.desc.identity()),
            data_digest: None,
            model_digest: None,
            model_covariance,
        })
    }

    /// The noise estimate of the fits and how the noise used relates to it.
    fn noise_report(&self, fits: &[Option<AxisFitOutcome>]) -> NoiseReport {
        let moments: Vec<_> = fits.iter().flatten().filter_map(|f| f.moments).collect();
        let estimate = estimate_noise(&moments);
        let given = !self.options.estimate_noise;
        let p = estimate
            .as_ref()
            .filter(|_| given)
            .map(|e| e.p_value(self.options.noise_rms_3d_mm));
        NoiseReport {
            used_rms_3d_mm: self.noise_mm,
            // The estimate replaces the assumed noise only when it is above 0 ([`calibrate_as`]).
            source: if given {
                "given"
            } else if estimate.as_ref().is_some_and(|e| e.rms_3d_mm > 0.0) {
                "estimated"
            } else {
                "default"
            }
            .into(),
            given_p_value: p,
            given_contradicted: estimate
                .as_ref()
                .is_some_and(|e| given && e.contradicts(self.options.noise_rms_3d_mm)),
            estimate,
        }
    }
}

/// The zero offsets' 1-sigma of `derived` per joint of `desc`, in its joint's unit.
fn zero_offset_sigmas(desc: &RobotDescription, derived: Option<&DerivedSigma>) -> Vec<ZeroOffsetSigma> {
    let Some(d) = derived else {
        return vec![];
    };
    d.zero_offsets
        .iter()
        .zip(&desc.joints)
        .enumerate()
        .map(|(k, (s, j))| match j.kind {
            JointKind::Revolute => ZeroOffsetSigma {
                joint: k + 1,
                sigma_rad: Some(*s),
                sigma_mm: None,
            },
            JointKind::Prismatic => ZeroOffsetSigma {
                joint: k + 1,
                sigma_rad: None,
                sigma_mm: Some(s * 1e3),
            },
        })
        .collect()
}

/// The standard deviations of the rows (mm, deg) from the axes' covariances as fitted
/// (before the held joints' bias is added).
fn calibrated_row_sigmas(
    nominal: &NominalGeometry,
    axes: &[Option<AxisLine>],
    fits: &[Option<AxisFitOutcome>],
) -> Result<Vec<RowSigma>, ProcedureError> {
    let covariances: Vec<Option<AxisCovariance>> = fits
        .iter()
        .map(|f| f.as_ref().and_then(|f| f.report.covariance.clone()))
        .collect();
    Ok(super::uncertainty::row_sigmas_on(nominal, axes, &covariances)?
        .into_iter()
        .map(|[a, b, alpha, beta]| RowSigma {
            a_mm: a * 1e3,
            b_mm: b * 1e3,
            alpha_deg: alpha.to_degrees(),
            beta_deg: beta.to_degrees(),
        })
        .collect())
}

/// The calibrated robot: the joint models on the rows and base placement of the phi-model
/// `geometry`, with the description's tool frame (replaced when the tool is measured).
fn calibrated_robot(desc: &RobotDescription, joints: Vec<JointModel>, geometry: &PhiModel) -> RobotModel {
    RobotModel {
        name: format!("{} (calibrated)", desc.name),
        joints,
        rows: geometry.rows.iter().map(crate::robot::RowEntry::from_row).collect(),
        placement: Placement::from_isometry(&geometry.world_from_base),
        tool_frame: desc.tool.frame,
        four_bars: vec![],
        effects: Default::default(),
    }
}

/// The three tool targets as observed at the reference pose: experiment `tool`, or the first
/// validation pose whose commands are the reference.
struct ToolObservation {
    /// The experiment observed.
    experiment: String,
    /// Its step.
    step: usize,
    /// The measured targets (instrument frame) \[m\].
    measured: Vec<Point3<f64>>,
}

/// The first observation of every tool target at the reference pose, if any.
fn tool_observation(set: &MeasurementSet, desc: &RobotDescription, reference_cmd: &[f64]) -> Option<ToolObservation> {
    let count = desc.tool_targets_m().len();
    if count < 3 {
        return None;
    }
    let experiments = set.experiments();
    for e in experiments.iter().filter(|e| e.moved_joint == 0) {
        for (step, rows) in e.by_step() {
            let at_ref = at_reference(&rows, reference_cmd);
            let measured: Option<Vec<Point3<f64>>> = (0..count)
                .map(|t| rows.iter().find(|r| r.target == t).map(|r| r.position_m()))
                .collect();
            if let (true, Some(measured)) = (at_ref, measured) {
                return Some(ToolObservation {
                    experiment: e.name.to_string(),
                    step,
                    measured,
                });
            }
        }
    }
    None
}

/// The tool frame in the last link of `robot` from the tool targets `measured` at the
/// reference pose (three-point rigid fit), with the fit's RMS \[m\].
fn last_link_from_tool(
    measured: &[Point3<f64>],
    desc: &RobotDescription,
    robot: &RobotModel,
    reference_cmd: &[f64],
    controller: &Controller,
) -> Option<(Isometry3<f64>, f64)> {
    let (world_from_tool, rms_m) = rigid_fit(&desc.tool_targets_m(), measured)?;
    Some((
        last_link_from(&world_from_tool, desc, robot, reference_cmd, controller)?,
        rms_m,
    ))
}

/// The tool frame in the last link of `robot` from the measured tool frame `world_from_tool`
/// at the reference pose.
fn last_link_from(
    world_from_tool: &Isometry3<f64>,
    desc: &RobotDescription,
    robot: &RobotModel,
    reference_cmd: &[f64],
    controller: &Controller,
) -> Option<Isometry3<f64>> {
    let link = world_from_last_link(desc, robot, reference_cmd, controller)?;
    Some(link.inverse() * world_from_tool)
}

/// The last link of `robot` at the reference pose (none where its joint values cannot be
/// computed).
fn world_from_last_link(
    desc: &RobotDescription,
    robot: &RobotModel,
    reference_cmd: &[f64],
    controller: &Controller,
) -> Option<Isometry3<f64>> {
    let q = robot
        .joint_values(controller, &commands_to_internal(desc, reference_cmd))
        .ok()?;
    Some(robot.phi_model().poses(&q).world_from_link[desc.dof() - 1])
}

/// The tool frame from the three tool targets observed at the reference pose: experiment
/// `tool`, or any validation pose whose commands are the reference.
fn tool_frame(
    set: &MeasurementSet,
    desc: &RobotDescription,
    robot: &RobotModel,
    reference_cmd: &[f64],
    controller: &Controller,
) -> Option<ToolReport> {
    let seen = tool_observation(set, desc, reference_cmd)?;
    let (frame, rms_m) = last_link_from_tool(&seen.measured, desc, robot, reference_cmd, controller)?;
    Some(ToolReport {
        experiment: seen.experiment,
        step: seen.step,
        last_link_from_tool: frame,
        fit_rms_mm: rms_m * 1e3,
        sigma: None,
    })
}
