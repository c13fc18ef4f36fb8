//! The calibrated joint models, in ascending order: each joint's zero from the reference pose
//! and the coupling into it from the joint below, fitted from the second target of that
//! joint's sweep when observed (eqs. 14-15), else the nominal one. A joint no experiment
//! sweeps keeps its nominal model (identity transmission, nominal coupling, zero offset).

use super::assembly_cache::{CacheUse, CouplingInputs};
use super::coupling_start::{gear_passive_start_weights, passive_start, weighted_gear_start};
use super::experiments::actuator_commands;
use super::recorded_coupling::RecordedCoupling;
use super::{AxisExperiment, CouplingReport, ProcedureError, SecondTargetData};
use crate::calibration::CalibrationError;
use crate::calibration::coupling_fit::{
    CouplingFit, CouplingForm, CouplingResponse, fit_coupling, fixed_coupling, passive_displacements,
    second_target_lever_arms_m,
};
use crate::kinematics::{ChainPoses, FixedFrames, PhiModel};
use crate::robot::{Controller, CouplingFitForm, CouplingFunction, JointModel, RobotDescription, Transmission};
use nalgebra::Point3;
use std::cell::OnceCell;

/// The fitted axes of a campaign and the reference pose the joint models are assembled from.
pub(super) struct Assembly<'a> {
    /// The nominal description.
    pub(super) desc: &'a RobotDescription,
    /// The axis experiments.
    pub(super) experiments: &'a [AxisExperiment],
    /// Each experiment's swept actuator command (rad) at the steps its target 1 was seen
    /// ([`swept_commands_at_target1`]; they do not depend on the model).
    pub(super) target1_commands: &'a [Vec<f64>],
    /// Each joint's fitted transmission, in the fit's own zero (`None`: not swept).
    pub(super) transmissions: &'a [Option<Transmission>],
    /// Target 1 of each experiment (same order), at its design pose.
    pub(super) target1: &'a [Vec<Point3<f64>>],
    /// The phi-model of the fitted axes, with its constant frames.
    pub(super) geometry: &'a FixedFrames,
    /// The joint values at the reference pose (rad).
    pub(super) q_ref: &'a [f64],
    /// The actuator commands at the reference pose (rad).
    pub(super) u_ref: &'a [f64],
    /// How the couplings are fitted (from scratch, refitted, fixed) and whether their inputs
    /// are recorded.
    pub(super) refit: Refit<'a>,
    /// The chain's poses at `q_ref`, once computed ([`Assembly::poses_at_reference`]).
    pub(super) reference_poses: OnceCell<ChainPoses>,
}

/// How [`Assembly::joint_models`] fits the couplings: by default from scratch.
#[derive(Clone, Copy, Default)]
pub(super) struct Refit<'a> {
    /// The couplings' responses at the optimum of a previous assembly of nearly the same
    /// data, by driven joint (0-based): refitted by one Newton step from that optimum instead
    /// of from scratch ([`CouplingResponse::refit`]).
    pub(super) warm: Option<&'a [Option<CouplingResponse>]>,
    /// The coupling into this joint (0-based) not fitted but set to these parameters.
    pub(super) fixed: Option<(usize, &'a [f64])>,
    /// The phi-model of the axes when it is already known (the axes are those it was built
    /// from): not built again.
    pub(super) geometry: Option<&'a (PhiModel, super::BaseRule)>,
    /// The couplings as an assembly of the same axes, transmissions and second targets
    /// fitted them (the calibration's): taken, not fitted again.
    pub(super) fitted: Option<&'a [CouplingReport]>,
    /// The propagation's cache: recorded into by its first assembly, reused by the others.
    pub(super) cache: Option<CacheUse<'a>>,
}

impl Assembly<'_> {
    /// The chain's poses at the reference joint values `q_ref`, computed once.
    pub(super) fn poses_at_reference(&self) -> &ChainPoses {
        self.reference_poses.get_or_init(|| self.geometry.poses(self.q_ref))
    }

    /// The joint models with the fitted couplings' reports. Ascending: joint k's zero needs the
    /// coupling into k, which needs joint k-1's zero.
    pub(super) fn joint_models(&self) -> Result<(Vec<JointModel>, Vec<CouplingReport>), ProcedureError> {
        let (desc, q_ref, u_ref) = (self.desc, self.q_ref, self.u_ref);
        let n = desc.dof();
        let mut joints: Vec<JointModel> = Vec::with_capacity(n);
        let mut couplings = Vec::new();
        let mut theta_ref: Vec<f64> = Vec::with_capacity(n);
        // The calibrated active angle of joint k is `f_k^-1(u) + shift[k]`.
        let mut shift: Vec<f64> = Vec::with_capacity(n);
        for k in 0..n {
            let coupling_in: Option<CouplingFunction> = if k == 0 {
                None
            } else {
                self.coupling_into(k, &shift, &mut couplings)?
            };
            let passive_ref = match (&coupling_in, k) {
                (Some(g), k) if k > 0 => g
                    .try_passive(theta_ref[k - 1])
                    .map_err(|_| self.not_invertible(k, u_ref[k - 1]))?,
                _ => 0.0,
            };
            let theta_a_ref = q_ref[k] - passive_ref;
            let Some(transmission) = &self.transmissions[k] else {
                // Not swept: the nominal joint (its value at the reference is the command).
                theta_ref.push(theta_a_ref);
                shift.push(theta_a_ref - u_ref[k]);
                joints.push(JointModel {
                    kind: desc.joints[k].kind,
                    phi_deg: desc.joints[k].phi_deg,
                    transmission: Transmission::identity_for(desc.joints[k].kind),
                    coupling_in,
                    transducer_offset: u_ref[k] - theta_a_ref,
                    repeatability_sigma: 0.0,
                });
                continue;
            };
            let raw_ref = transmission
                .actual_from_command(u_ref[k])
                .ok_or_else(|| self.not_invertible(k, u_ref[k]))?;
            let c = theta_a_ref - raw_ref;
            theta_ref.push(theta_a_ref);
            shift.push(c);
            joints.push(JointModel {
                kind: desc.joints[k].kind,
                phi_deg: desc.joints[k].phi_deg,
                transmission: transmission.shifted(c),
                coupling_in,
                transducer_offset: -c,
                repeatability_sigma: 0.0,
            });
        }
        Ok((joints, couplings))
    }

    /// The error of joint `k`'s (0-based) calibrated transmission not inverting the command
    /// `u` (rad).
    fn not_invertible(&self, k: usize, u: f64) -> ProcedureError {
        ProcedureError::Fit {
            experiment: self
                .experiments
                .iter()
                .find(|e| e.joint == k + 1)
                .map(|e| e.name.clone())
                .unwrap_or_default(),
            joint: k + 1,
            error: CalibrationError::NotInvertible {
                fit: "calibrated transmission",
                command_rad: u,
            },
        }
    }

    /// The coupling into joint `k` (0-based) from joint `k-1`: fitted from the second target of
    /// the joint-`k` sweep (1-based `k`) when observed (eqs. 14-15), else the nominal one.
    /// `shift` holds the zero shifts of the joints below; a fitted coupling's report is pushed
    /// onto `couplings`.
    fn coupling_into(
        &self,
        k: usize,
        shift: &[f64],
        couplings: &mut Vec<CouplingReport>,
    ) -> Result<Option<CouplingFunction>, ProcedureError> {
        let desc = self.desc;
        let from = k; // 1-based number of the driving joint
        let Some(slope) = desc.nominal_coupling_from(from) else {
            return Ok(None);
        };
        let nominal = CouplingFunction::linear(slope);
        let form = desc.couplings.iter().find(|c| c.from == from).and_then(|c| c.fit);
        // The driving joint's sweep that measures the coupling: the first with target 1 seen
        // at three or more steps while actuator k+1 is held, else the first sweep.
        let sweeps: Vec<(usize, &AxisExperiment)> = self
            .experiments
            .iter()
            .enumerate()
            .filter(|(_, e)| e.joint == from)
            .collect();
        let (Some(form), Some(&(first_index, first))) = (form, sweeps.first()) else {
            return Ok(Some(nominal));
        };
        if self.transmissions[k - 1].is_none() {
            return Ok(Some(nominal));
        }
        let (index, e) = sweeps
            .iter()
            .copied()
            .find(|(_, e)| e.target1_m.len() >= 3 && e.holds_next_still)
            .unwrap_or((first_index, first));
        if e.target1_m.len() < 3 {
            return Err(ProcedureError::SecondTargetMissing {
                experiment: e.name.clone(),
                joint: from,
                seen: e.target1_m.len(),
            });
        }
        if !e.holds_next_still {
            return Err(ProcedureError::InconsistentCommands {
                experiment: e.name.clone(),
                step: 0,
                joint: from + 1,
                reason: "a coupling is measured only while actuator k+1 is held still (`docs/formats.md#controller-semantics`)".into(),
            });
        }
        self.memoized(k, shift, couplings, || {
            self.fit_measured_coupling(k, (index, e), slope, form, shift)
        })
        .map(Some)
    }

    /// The coupling into joint `k` (0-based) that `fit` fits from the zero shifts `shift` of
    /// the joints below, its report pushed onto `couplings`; taken from the propagation's cache
    /// ([`Refit::cache`]) when its inputs are the recorded ones and already refitted there.
    fn memoized(
        &self,
        k: usize,
        shift: &[f64],
        couplings: &mut Vec<CouplingReport>,
        fit: impl FnOnce() -> Result<(CouplingFunction, CouplingReport), ProcedureError>,
    ) -> Result<CouplingFunction, ProcedureError> {
        let inputs = CouplingInputs {
            world_from_base: self.geometry.model().world_from_base,
            rows: self.geometry.model().rows[..k].to_vec(),
            transmission: self.transmissions[k - 1].clone(),
            shift: shift[k - 1],
        };
        let fixed_here = self.refit.fixed.is_some_and(|(j, _)| j == k);
        let reuse = (self.refit.warm.is_some() && !fixed_here)
            .then(|| self.refit.cache.and_then(CacheUse::reusing))
            .flatten();
        if let Some((function, report)) = reuse.and_then(|c| c.memo_refit(k, &inputs)) {
            couplings.push(report);
            return Ok(function);
        }
        let (function, report) = fit()?;
        if let Some(cache) = reuse {
            cache.keep_refit(k, &inputs, (function.clone(), report.clone()));
        } else if let Some(cache) = self.refit.cache.and_then(CacheUse::recording) {
            cache.record_inputs(k, inputs);
        }
        couplings.push(report);
        Ok(function)
    }

    /// Fits the coupling into joint `k` (0-based) from the second target of sweep `e` of joint
    /// `k-1` (eqs. 14-15), nominal slope `slope` (or refits it, as `refit` asks), with its
    /// report.
    fn fit_measured_coupling(
        &self,
        k: usize,
        (index, e): (usize, &AxisExperiment),
        slope: f64,
        form: CouplingFitForm,
        shift: &[f64],
    ) -> Result<(CouplingFunction, CouplingReport), ProcedureError> {
        let (geometry, q_ref) = (self.geometry, self.q_ref);
        let from = k;
        let second = &self.target1[index];
        let fit_err = |source| fit_error(e, from, source);
        let cform = match form {
            CouplingFitForm::Fractional => CouplingForm::Fractional,
            CouplingFitForm::Gear { order, fit_ratio } => CouplingForm::Gear {
                ratio: slope,
                fit_ratio,
                order,
            },
        };
        if let Some((_, x)) = self.refit.fixed.filter(|&(j, _)| j == k) {
            // Set, not fitted: its data (those of the recording assembly) are not needed.
            let fit = fixed_coupling(&cform, x);
            let report = CouplingReport::new(from, e, &fit, &cform);
            return Ok((fit.function, report));
        }
        let (raw, raw_ref) = self.raw_active_angles(k, (index, e))?;
        let active: Vec<f64> = raw.iter().map(|t| t + shift[k - 1]).collect();
        let theta_ref_from = raw_ref.map(|t| t + shift[k - 1]).unwrap_or(q_ref[k - 1]);
        // Axis k+1 (1-based) at step 0 of this sweep: the reference frame turned about axis k by
        // the active motion from the reference to step 0.
        let mut q0 = q_ref.to_vec();
        q0[k - 1] += active[0] - theta_ref_from;
        let frame_next = geometry.poses(&q0).world_from_frame[k];
        let axis_from = self.poses_at_reference().axis(k - 1);
        let t_from_start: Vec<f64> = active.iter().map(|a| a - active[0]).collect();
        let passive = passive_displacements(&frame_next, &axis_from, &t_from_start, second).map_err(fit_err)?;
        let warm = self.refit.warm.and_then(|w| w[k].as_ref());
        let start = match warm {
            Some(_) => self.warm_start(&cform, slope, (&raw, &active), &passive),
            None => passive_start(&cform, slope, &active, &passive),
        };
        let known = self.refit.fitted.and_then(|f| f.iter().find(|c| c.from == from));
        let data_of = || SecondTargetData {
            steps: e.target1_steps.iter().map(|&i| e.steps[i]).collect(),
            active_rad: active.clone(),
            passive_rad: passive.clone(),
            lever_arms_m: second_target_lever_arms_m(&frame_next, &axis_from, &t_from_start, second),
        };
        // A warm refit (the propagation's finite differences) reads the couplings' values only:
        // the points they were fitted to are kept for the reports of the fit itself.
        let data = warm.is_none().then(data_of);
        let fit = match (warm, known) {
            (Some(response), _) => response.refit(&active, &passive, start),
            (None, Some(c)) => Ok(CouplingFit {
                function: c.function.clone(),
                parameters: c.parameters.clone(),
                sigma: c.fit_only_sigma.clone(),
                residual_rms_rad: c.residual_rms_rad,
            }),
            (None, None) => fit_coupling(&cform, &active, &passive, start),
        }
        .map_err(|source| ProcedureError::CouplingFit {
            experiment: e.name.clone(),
            joint: from,
            cause: source,
            data: Box::new(data.clone().unwrap_or_else(data_of)),
        })?;
        if let Some(cache) = self.refit.cache.and_then(CacheUse::recording) {
            let response = CouplingResponse::at(&cform, &active, &passive, start, &fit.parameters).map_err(fit_err)?;
            cache.record_coupling(RecordedCoupling {
                response,
                k,
                index,
                frame_next,
                axis_from,
                active,
                form: cform,
                slope,
                parameters: fit.parameters.clone(),
            });
        }
        let mut report = CouplingReport::new(from, e, &fit, &cform);
        report.second_target = data.unwrap_or_default();
        Ok((fit.function, report))
    }

    /// The start of a warm refit ([`passive_start`]): a gear's from its weights,
    /// `w . (y - N t)` ([`gear_passive_start_weights`], the same least squares as
    /// [`gear_passive_start`]'s solve). The weights are those of the raw angles `raw` (the
    /// driving transmission's inversions, before the zero shift that makes them the active
    /// angles `t`): a constant shift of the angles turns each harmonic's sine and cosine
    /// columns into combinations of each other, so the design's column space and the
    /// constant's weights do not change. Taken from the propagation's cache when known there
    /// for these raw angles (a column that does not move the driving transmission), else
    /// computed and kept.
    fn warm_start(&self, form: &CouplingForm, slope: f64, (raw, active): (&[f64], &[f64]), passive: &[f64]) -> f64 {
        let cache = self.refit.cache.and_then(CacheUse::reusing);
        let (CouplingForm::Gear { order, .. }, Some(cache)) = (form, cache) else {
            return passive_start(form, slope, active, passive);
        };
        cache.with_gear_weights(
            raw,
            || gear_passive_start_weights(slope, *order, raw),
            |weights| weighted_gear_start(weights, slope, active, passive),
        )
    }

    /// The driving joint `k-1`'s (0-based) transmission inverted (rad, before its zero shift)
    /// at the steps of sweep `index` where its second target was seen, and at the reference
    /// command (`None`: not invertible there); taken from the propagation's cache when that
    /// transmission's are recorded there (the same arithmetic), recorded by a recording
    /// assembly.
    fn raw_active_angles(
        &self,
        k: usize,
        (index, e): (usize, &AxisExperiment),
    ) -> Result<(Vec<f64>, Option<f64>), ProcedureError> {
        let from_transmission = self.transmissions[k - 1].as_ref().expect("checked by coupling_into");
        if let Some(hit) = self
            .refit
            .cache
            .and_then(|c| c.cache().raw_angles(index, from_transmission))
        {
            return Ok(hit);
        }
        let u = &self.target1_commands[index];
        let raw: Vec<f64> = u
            .iter()
            .map(|&uj| from_transmission.actual_from_command(uj))
            .collect::<Option<_>>()
            .ok_or_else(|| {
                fit_error(
                    e,
                    k,
                    CalibrationError::NotInvertible {
                        fit: "coupling active angles",
                        command_rad: u[0],
                    },
                )
            })?;
        let raw_ref = from_transmission.actual_from_command(self.u_ref[k - 1]);
        if let Some(cache) = self.refit.cache.and_then(CacheUse::recording) {
            cache.record_raw_angles(index, from_transmission, (&raw, raw_ref));
        }
        Ok((raw, raw_ref))
    }
}

/// Each experiment's swept actuator command (rad) at the steps where its target 1 was seen
/// (what [`Assembly::target1_commands`] holds).
pub(super) fn swept_commands_at_target1(
    experiments: &[AxisExperiment],
    controller: &Controller,
    desc: &RobotDescription,
) -> Vec<Vec<f64>> {
    experiments
        .iter()
        .map(|e| {
            e.target1_steps
                .iter()
                .map(|&j| actuator_commands(controller, desc, &e.commands[j])[e.joint - 1])
                .collect()
        })
        .collect()
}

/// The error of a coupling fit of sweep `e` driven by joint `from` (1-based).
fn fit_error(e: &AxisExperiment, from: usize, source: CalibrationError) -> ProcedureError {
    ProcedureError::Fit {
        experiment: e.name.clone(),
        joint: from,
        error: source,
    }
}
