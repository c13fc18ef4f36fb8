//! Commands to joint values on the simulated robot, with the joint-side effects.

use super::effects::Effects;
use crate::physics::{ApproachSource, ApproachTracker, BacklashEffect, GearHarmonic, add_joint_period_errors};
use crate::robot::{Controller, ModelError, RobotModel};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use std::sync::Arc;

pub use crate::physics::UNMOVED_ACTUATOR_RAD;

/// Commands to joint values with the joint-side effects: the fig. 3 controller, the truth's
/// transmissions (with [`Effects::gear_harmonics`]: transmission-period terms in the
/// transmission, joint-period ones on the active displacement), backlash on the active
/// displacements, the passive couplings, and the repeatability jitter. Keeps the last command
/// for the approach direction of the backlash (`docs/formats.md#measurement-csv`: the sign of
/// `cmd(s) - cmd(s-1)`, or of the actuator command's change for a backlash signed by the
/// actuator ([`ApproachSource`]); a joint whose command did not change keeps its previous
/// direction; before any motion the joint sits in the middle of its band).
///
/// Repeatability is a *re-positioning* error: an actuator draws a new jitter only when its
/// actuator command (after the fig. 3 decoupling) changes; an actuator the command leaves
/// where it is holds its position, and its previous error, between executions. In a
/// hold-still axis experiment only the swept actuator is re-positioned, as on the real robot;
/// every execution of a new pose re-positions every actuator. One standard normal per joint is
/// drawn from the rng per execution either way, so the random stream does not depend on which
/// actuators moved.
#[derive(Clone, Debug)]
pub struct JointDriver {
    truth: RobotModel,
    controller: Controller,
    band_rad: Vec<f64>,
    direction: ApproachSource,
    command_approach: ApproachTracker,
    actuator_approach: ApproachTracker,
    joint_harmonics: Vec<GearHarmonic>,
    /// Actuator commands of the last execution and the standard-normal jitter draws they got.
    last_actuator: Option<(Vec<f64>, Vec<f64>)>,
    /// The last actuator commands and the truth's transmissions' inverse at them: an
    /// actuator whose command is the same number again (a held joint of an axis experiment)
    /// reuses it instead of inverting again (the same function of the same input).
    last_inversion: Option<(Vec<f64>, Vec<f64>)>,
    /// Inverses computed before, shared by the drivers of a fixed truth's trials.
    table: Option<Arc<InversionTable>>,
}

/// The truth's transmission inverses `f_k^-1(u_k - offset_k)` at given actuator commands,
/// computed once and shared by the drivers of many trials of one fixed truth robot (a
/// Monte-Carlo study drives the same commands in every trial): a driver looks a command up
/// by its bits and inverts only what is not there, so the joint values are the same numbers.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InversionTable {
    /// Per joint: `(u_k.to_bits(), theta_act_k)`, sorted by the bits, one entry per bits.
    per_joint: Vec<Vec<(u64, f64)>>,
}

impl InversionTable {
    /// The inverses of `driver`'s truth ([`JointDriver::truth`], the transmissions it
    /// drives through) at the actuator commands (fig. 3 decoupling) of every joint-command
    /// vector of `commands` (internal units); a command the transmission cannot invert is left
    /// out (the driver then fails on it as without a table).
    pub fn new<'c>(driver: &JointDriver, commands: impl IntoIterator<Item = &'c [f64]>) -> Self {
        let truth = driver.truth();
        let mut per_joint = vec![Vec::new(); truth.dof()];
        for cmd in commands {
            let Ok(u) = driver.controller.decouple(cmd) else {
                continue;
            };
            for (k, (entries, uk)) in per_joint.iter_mut().zip(&u).enumerate() {
                if let Ok(a) = truth.active_displacement(k, *uk) {
                    entries.push((uk.to_bits(), a));
                }
            }
        }
        for entries in &mut per_joint {
            entries.sort_unstable_by_key(|e| e.0);
            entries.dedup_by_key(|e| e.0);
        }
        InversionTable { per_joint }
    }

    /// `theta_act_k` at actuator command `u_k` of joint `k + 1`, if in the table.
    fn get(&self, k: usize, u_k: f64) -> Option<f64> {
        let entries = self.per_joint.get(k)?;
        let bits = u_k.to_bits();
        entries.binary_search_by_key(&bits, |e| e.0).ok().map(|i| entries[i].1)
    }
}

/// What [`JointDriver::drive`] produced.
#[derive(Clone, Debug, PartialEq)]
pub struct DrivenJoints {
    /// Actual active displacement of every actuator \[rad or m\] (after backlash).
    pub active: Vec<f64>,
    /// Joint values for the phi-model (with couplings and jitter).
    pub q: Vec<f64>,
}

impl JointDriver {
    /// A driver for `truth` behind `controller`, with the joint-side `effects`.
    pub fn new(truth: &RobotModel, controller: Controller, effects: &Effects) -> Self {
        let n = truth.dof();
        JointDriver {
            truth: effects.truth_with_harmonics(truth),
            controller,
            band_rad: effects.backlash.as_ref().map_or(vec![0.0; n], |b| b.band_rad.clone()),
            direction: effects
                .backlash
                .as_ref()
                .map_or(ApproachSource::Command, |b| b.direction),
            command_approach: ApproachTracker::new(n, 0.0),
            actuator_approach: ApproachTracker::new(n, UNMOVED_ACTUATOR_RAD),
            joint_harmonics: effects.gear_harmonics.clone(),
            last_actuator: None,
            last_inversion: None,
            table: None,
        }
    }

    /// The same driver looking its inverses up in `table` first (built for this driver's
    /// truth: [`InversionTable::new`]).
    pub fn with_table(self, table: Arc<InversionTable>) -> Self {
        JointDriver {
            table: Some(table),
            ..self
        }
    }

    /// The truth model (with the gear harmonics added).
    pub fn truth(&self) -> &RobotModel {
        &self.truth
    }

    /// Executes `cmd` (internal units). Draws one standard normal per joint from `rng` and
    /// uses it for the actuators whose command changed (see the type's docs).
    pub fn drive<R: Rng + ?Sized>(&mut self, cmd: &[f64], rng: &mut R) -> Result<DrivenJoints, ModelError> {
        let u = self.controller.decouple(cmd)?;
        let mut active = self.inverted(&u)?;
        add_joint_period_errors(&self.joint_harmonics, &mut active);
        let by_command = self.command_approach.step(cmd);
        let by_actuator = self.actuator_approach.step(&u);
        let approach = match self.direction {
            ApproachSource::Command => by_command,
            ApproachSource::Actuator => by_actuator,
        };
        for ((a, dir), band) in active.iter_mut().zip(approach).zip(&self.band_rad) {
            *a = BacklashEffect::lagged(*a, *dir, *band);
        }
        let mut q = active.clone();
        for k in 1..q.len() {
            if let Some(g) = &self.truth.joints[k].coupling_in {
                q[k] += g.try_passive(active[k - 1]).map_err(|source| ModelError::Coupling {
                    joint: k + 1,
                    cause: source,
                })?;
            }
        }
        let mut draws: Vec<f64> = (0..q.len()).map(|_| StandardNormal.sample(rng)).collect();
        if let Some((last_u, last_draws)) = &self.last_actuator {
            for ((z, (now, before)), held) in draws.iter_mut().zip(u.iter().zip(last_u)).zip(last_draws) {
                if (now - before).abs() <= UNMOVED_ACTUATOR_RAD {
                    *z = *held;
                }
            }
        }
        for ((qk, j), z) in q.iter_mut().zip(&self.truth.joints).zip(&draws) {
            *qk += j.repeatability_sigma * z;
        }
        self.last_actuator = Some((u, draws));
        Ok(DrivenJoints { active, q })
    }

    /// [`RobotModel::active_displacements`] of the truth at `u`, reusing the last inversion
    /// for every actuator whose command has the same bits as then, else the table's.
    fn inverted(&mut self, u: &[f64]) -> Result<Vec<f64>, ModelError> {
        let active = match &self.last_inversion {
            Some((last_u, last_active)) if last_u.len() == u.len() && u.len() == self.truth.dof() => u
                .iter()
                .zip(last_u.iter().zip(last_active))
                .enumerate()
                .map(|(k, (now, (before, a)))| {
                    if now.to_bits() == before.to_bits() {
                        Ok(*a)
                    } else {
                        self.invert(k, *now)
                    }
                })
                .collect::<Result<Vec<f64>, ModelError>>()?,
            _ if u.len() == self.truth.dof() => u
                .iter()
                .enumerate()
                .map(|(k, uk)| self.invert(k, *uk))
                .collect::<Result<Vec<f64>, ModelError>>()?,
            _ => self.truth.active_displacements(u)?,
        };
        match &mut self.last_inversion {
            Some((last_u, last_active)) if last_u.len() == u.len() => {
                last_u.copy_from_slice(u);
                last_active.copy_from_slice(&active);
            }
            last => *last = Some((u.to_vec(), active.clone())),
        }
        Ok(active)
    }

    /// `theta_act_k` at `u_k`: from the table if there, else inverted.
    fn invert(&self, k: usize, u_k: f64) -> Result<f64, ModelError> {
        match self.table.as_ref().and_then(|t| t.get(k, u_k)) {
            Some(a) => Ok(a),
            None => self.truth.active_displacement(k, u_k),
        }
    }
}
