//! The robot model: the phi-model geometry (paper appendix, eqs. A1-A4) plus what turns
//! actuator commands into joint values (paper sections 3 and 4; semantics in
//! `docs/formats.md#controller-semantics`). One type serves every robot the program reasons
//! about: the simulated real robot (`sim`), the calibrated robot (`calibration`) and the ideal
//! nominal robot ([`RobotModel::ideal`]); which one a value holds is said by its variable or
//! field name (`truth`, `calibrated`, `nominal`), never by its type.
//!
//! Per joint `k` (1-based): the controller's actuator command `u_k` (after nominal decoupling)
//! turns the joint by the actual ACTIVE displacement `theta_act_k = f_k^-1(u_k - offset_k)`
//! (`f_k` = the joint's [`Transmission`], eq. 8; `offset_k` = transducer zero offset), and the
//! joint value used in the actual phi-model is `q_k = theta_act_k + g_{k-1,k}(theta_act_{k-1})`
//! (`g` = the actual [`CouplingFunction`] into joint `k`, eq. 15; passive motion travels one
//! joint only and is driven by the active displacement only, section 3.1).

use super::controller::Controller;
use super::description::{Placement, RobotDescription, RowEntry};
use super::effects::{ModelEffects, PoseLoad};
use super::four_bar::FourBarGeometry;
use super::functions::{CouplingFunction, Transmission};
use super::model_error::ModelError;
use crate::kinematics::{JointKind, PhiModel};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A sliding joint's transducer zero offset lies within this \[m\]: the longest stroke a
/// description's limits allow (a 100 m gantry).
pub const MAX_PRISMATIC_OFFSET_M: f64 = 100.0;

/// Why joint `j`'s transducer zero offset (the reading at the joint's zero) is implausible:
/// beyond a turn (revolute: `2 pi` rad, a value in degrees or a damaged file) or beyond
/// [`MAX_PRISMATIC_OFFSET_M`] (prismatic: millimetres read as metres); `None` within.
fn transducer_offset_problem(j: &JointModel) -> Option<String> {
    let (limit, unit, bound, slip) = match j.kind {
        JointKind::Revolute => (
            std::f64::consts::TAU,
            "rad",
            "a turn (+-6.283 rad)",
            "degrees written as radians?",
        ),
        JointKind::Prismatic => (
            MAX_PRISMATIC_OFFSET_M,
            "m",
            "the longest stroke (+-100 m)",
            "millimetres written as metres?",
        ),
    };
    (j.transducer_offset.abs() > limit).then(|| {
        format!(
            "{} {unit} is beyond {bound}: a transducer's zero offset is the reading at the joint's zero, a fraction of \
             its travel ({slip})",
            crate::measurement::format_f64(j.transducer_offset)
        )
    })
}

fn identity_transmission() -> Transmission {
    Transmission::identity()
}

/// One joint of a [`RobotModel`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct JointModel {
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// The phi angle of eq. (A2) \[deg\]; equal for the nominal and actual robots (section 4).
    #[serde(default)]
    pub phi_deg: f64,
    /// The actual transmission `theta_c = f(theta_a)` (eq. 8); default identity.
    #[serde(default = "identity_transmission")]
    pub transmission: Transmission,
    /// The actual passive coupling into this joint from the joint below (eq. 15), if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coupling_in: Option<CouplingFunction>,
    /// Transducer zero offset \[rad\] (revolute) or \[m\] (prismatic), subtracted from the actuator
    /// command (fig. 3).
    #[serde(default, rename = "transducer_offset_rad_or_m", alias = "transducer_offset")]
    pub transducer_offset: f64,
    /// Standard deviation of the Gaussian jitter of the joint value on each execution of a
    /// command \[rad\] (revolute) or \[m\] (prismatic): the robot's repeatability.
    #[serde(default, rename = "repeatability_sigma_rad_or_m", alias = "repeatability_sigma")]
    pub repeatability_sigma: f64,
}

/// A physical four-bar linkage of the robot, documented for the rigid-body simulator. The
/// analytic model uses the driven joint's `coupling_in`, which may be this geometry
/// ([`CouplingFunction::FourBar`]) or a fitted form of it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FourBarLinkage {
    /// The driving joint (1-based); the linkage drives joint `from + 1`.
    pub from: usize,
    /// Its dimensions.
    pub geometry: FourBarGeometry,
}

/// A robot as a kinematic-plus-transmission model (see module docs). Loadable from TOML.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RobotModel {
    /// Human-readable name.
    pub name: String,
    /// The joints, base first.
    pub joints: Vec<JointModel>,
    /// The ACTUAL phi-model rows (Table 2, actual columns), `joints.len() - 1` of them.
    pub rows: Vec<RowEntry>,
    /// Robot base frame (frame 1) in the instrument frame.
    #[serde(default)]
    pub placement: Placement,
    /// The tool frame in the last link's moving frame.
    #[serde(default)]
    pub tool_frame: Placement,
    /// Physical four-bar linkages (for the rigid-body simulator).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub four_bars: Vec<FourBarLinkage>,
    /// Non-geometric effects the calibration carries ([`ModelEffects`]); none by default.
    #[serde(default, skip_serializing_if = "ModelEffects::is_empty")]
    pub effects: ModelEffects,
}

impl RobotModel {
    /// A stable hash of every value of the model, as `fnv1a64:` and 16 lower-case hex digits:
    /// the model as its JSON value, walked as [`RobotDescription::geometry_hash`] walks a
    /// description's. A calibration records it (`model_digest`) so that a value edited in the
    /// file afterwards is said when the file is read.
    pub fn digest(&self) -> String {
        let mut hash = super::description::Fnv::new();
        hash.value(&serde_json::to_value(self).unwrap_or(serde_json::Value::Null));
        hash.text()
    }

    /// A robot with no errors: the nominal geometry, identity transmissions, the nominal
    /// (linear) couplings, no offsets, no jitter. It reaches exactly the commanded joint values.
    pub fn ideal(desc: &RobotDescription) -> Self {
        let joints = desc
            .joints
            .iter()
            .enumerate()
            .map(|(k, j)| JointModel {
                kind: j.kind,
                phi_deg: j.phi_deg,
                transmission: Transmission::identity(),
                coupling_in: desc.nominal_coupling_into(k + 1).map(CouplingFunction::linear),
                transducer_offset: 0.0,
                repeatability_sigma: 0.0,
            })
            .collect();
        Self {
            name: format!("{} (ideal)", desc.name),
            joints,
            rows: desc.rows.clone(),
            placement: desc.placement,
            tool_frame: desc.tool.frame,
            four_bars: vec![],
            effects: ModelEffects::default(),
        }
    }

    /// Reads and validates a robot model file (`docs/formats.md#robot-model`).
    pub fn from_file(path: &Path) -> Result<Self, ModelError> {
        Self::from_toml_str(&crate::toml_file::read(path)?, path)
    }

    /// Parses and validates robot model text; `path` labels errors only.
    /// A model file is a simulated truth: its effects are the effects file's, never `effects`
    /// (the form a calibration carries its fitted ones in, which the simulators do not read).
    pub fn from_toml_str(text: &str, path: &Path) -> Result<Self, ModelError> {
        let t: Self = crate::toml_file::parse_own(text, path, crate::toml_file::OwnToml::Model)?;
        let checked = if t.effects.is_empty() {
            t.validate()
        } else {
            Err(ModelError::Invalid {
                field: "effects".into(),
                message: "a robot model file is a simulated truth: give its effects in an effects file (`simulate --effects`, docs/formats.md#effects-file); `effects` is where a calibration carries the sag and backlash it fitted".into(),
            })
        };
        checked.map_err(|e| match e {
            ModelError::Invalid { field, message } => ModelError::InvalidIn {
                path: path.to_owned(),
                field,
                message,
            },
            other => other,
        })?;
        Ok(t)
    }

    /// Checks sizes, finiteness and linkage dimensions.
    pub fn validate(&self) -> Result<(), ModelError> {
        let bad = |field: String, message: String| ModelError::Invalid { field, message };
        let n = self.joints.len();
        if n == 0 || self.rows.len() + 1 != n {
            return Err(bad(
                "rows".into(),
                format!(
                    "{n} joints need {} rows, found {}",
                    n.saturating_sub(1),
                    self.rows.len()
                ),
            ));
        }
        for (k, j) in self.joints.iter().enumerate() {
            for (key, v) in [
                ("phi_deg", j.phi_deg),
                ("transducer_offset_rad_or_m", j.transducer_offset),
            ] {
                if !v.is_finite() {
                    return Err(bad(format!("joints[{k}].{key}"), "must be finite".into()));
                }
            }
            if let Some(why) = transducer_offset_problem(j) {
                return Err(bad(format!("joints[{k}].transducer_offset_rad_or_m"), why));
            }
            if !(j.repeatability_sigma.is_finite() && j.repeatability_sigma >= 0.0) {
                return Err(bad(
                    format!("joints[{k}].repeatability_sigma_rad_or_m"),
                    "must be finite and >= 0".into(),
                ));
            }
            if k == 0 && j.coupling_in.is_some() {
                return Err(bad(
                    "joints[0].coupling_in".into(),
                    "the first joint has no joint below it".into(),
                ));
            }
            if let Some(problem) = j.transmission.problem() {
                return Err(bad(format!("joints[{k}].transmission"), problem));
            }
            if let Some(problem) = j.coupling_in.as_ref().and_then(CouplingFunction::problem) {
                return Err(bad(format!("joints[{k}].coupling_in"), problem));
            }
            if let Some(CouplingFunction::FourBar(g)) = &j.coupling_in {
                g.validate()
                    .map_err(|e| bad(format!("joints[{k}].coupling_in"), e.to_string()))?;
            }
        }
        for (k, l) in self.four_bars.iter().enumerate() {
            if l.from == 0 || l.from >= n {
                return Err(bad(format!("four_bars[{k}].from"), format!("must be in 1..{n}")));
            }
            l.geometry
                .validate()
                .map_err(|e| bad(format!("four_bars[{k}].geometry"), e.to_string()))?;
        }
        self.effects.validate(n).map_err(|(field, message)| bad(field, message))
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// The actual phi-model geometry, placed in the instrument frame.
    pub fn phi_model(&self) -> PhiModel {
        let joints = self.joints.iter().map(|j| (j.kind, j.phi_deg));
        crate::robot::description::phi_model_of(joints, &self.rows, &self.placement, &self.tool_frame)
    }

    /// The repeatability sigmas of all joints \[rad or m\].
    pub fn repeatability_sigmas(&self) -> Vec<f64> {
        self.joints.iter().map(|j| j.repeatability_sigma).collect()
    }

    /// The actual active displacement of every joint for actuator commands `u`:
    /// `theta_act_k = f_k^-1(u_k - offset_k)` (eq. 8 inverted, fig. 3).
    pub fn active_displacements(&self, u: &[f64]) -> Result<Vec<f64>, ModelError> {
        if u.len() != self.dof() {
            return Err(ModelError::WrongLength {
                what: "actuator commands",
                expected: self.dof(),
                found: u.len(),
            });
        }
        u.iter()
            .enumerate()
            .map(|(k, &uk)| self.active_displacement(k, uk))
            .collect()
    }

    /// The actual active displacement of joint `k + 1` (0-based `k < dof`) for its actuator
    /// command `u_k`: one term of [`Self::active_displacements`].
    pub fn active_displacement(&self, k: usize, u_k: f64) -> Result<f64, ModelError> {
        let j = &self.joints[k];
        let command = u_k - j.transducer_offset;
        j.transmission
            .actual_from_command(command)
            .ok_or_else(|| ModelError::NotInvertible {
                joint: k + 1,
                command_file: j.kind.to_file_units(command),
                unit: j.kind.file_unit(),
            })
    }

    /// The joint values the robot reaches for joint commands `cmd` sent to `controller`
    /// (internal units), without repeatability jitter: `q_k = theta_act_k +
    /// g_{k-1,k}(theta_act_{k-1})`.
    pub fn joint_values(&self, controller: &Controller, cmd: &[f64]) -> Result<Vec<f64>, ModelError> {
        if controller.dof() != self.dof() {
            return Err(ModelError::WrongLength {
                what: "controller joints",
                expected: self.dof(),
                found: controller.dof(),
            });
        }
        self.joint_values_from_actuators(&controller.decouple(cmd)?)
    }

    /// The joint values the robot reaches for `cmd` under the pose's `load`, with the model's
    /// effects ([`ModelEffects`]): the backlash shifts the actuator commands, the sag (at the
    /// chain `phi`, this model's geometry) the joint values. Equal to [`Self::joint_values`]
    /// without effects.
    pub fn loaded_joint_values(
        &self,
        controller: &Controller,
        phi: &PhiModel,
        cmd: &[f64],
        load: &PoseLoad<'_>,
    ) -> Result<Vec<f64>, ModelError> {
        if self.effects.is_empty() {
            return self.joint_values(controller, cmd);
        }
        self.loaded_joint_values_from_actuators(phi, controller.decouple(cmd)?, load)
    }

    /// [`Self::loaded_joint_values`] from the actuator commands `u` (after the controller's
    /// decoupling, before the backlash).
    pub fn loaded_joint_values_from_actuators(
        &self,
        phi: &PhiModel,
        u: Vec<f64>,
        load: &PoseLoad<'_>,
    ) -> Result<Vec<f64>, ModelError> {
        Ok(self.joint_values_before_and_after_sag(phi, u, load)?.1)
    }

    /// The joint values before the sag (the backlash applied) and after it, from the actuator
    /// commands `u` ([`Self::loaded_joint_values_from_actuators`]): the sag's regressors are
    /// evaluated at the first.
    pub fn joint_values_before_and_after_sag(
        &self,
        phi: &PhiModel,
        mut u: Vec<f64>,
        load: &PoseLoad<'_>,
    ) -> Result<(Vec<f64>, Vec<f64>), ModelError> {
        self.effects.shift_actuators(&mut u, load);
        let before = self.joint_values_from_actuators(&u)?;
        if !self.effects.sags() {
            return Ok((before.clone(), before));
        }
        // The compliances' coupling slopes need the active displacements; the sag terms do not.
        let active = match self.effects.compliance.is_empty() {
            true => Vec::new(),
            false => self.active_displacements(&u)?,
        };
        let after = self.sagged(phi, &before, &active, load)?;
        Ok((before, after))
    }

    /// The joint values `q` (before the sag; `active` their active displacements, which only
    /// the compliances read) with the model's sag terms and compliances added, each evaluated
    /// at `q` on the chain `phi`.
    pub fn sagged(
        &self,
        phi: &PhiModel,
        q: &[f64],
        active: &[f64],
        load: &PoseLoad<'_>,
    ) -> Result<Vec<f64>, ModelError> {
        let mut after = q.to_vec();
        if !self.effects.sag.is_empty() {
            let frames = phi.poses(q);
            self.effects.add_sag(phi, &frames, &mut after, load);
        }
        for c in &self.effects.compliance {
            let dq = c
                .deflection(self, phi, q, active, load.payload_kg)
                .ok_or(ModelError::Buckles { joint: c.joint })?;
            for (a, d) in after.iter_mut().zip(dq) {
                *a += d;
            }
        }
        Ok(after)
    }

    /// The active displacements of joint values `q`, the couplings undone from joint 1 up
    /// (eq. 15 inverted): `theta_1 = q_1`, `theta_k = q_k - g_{k-1,k}(theta_{k-1})`.
    pub fn active_from_joint_values(&self, q: &[f64]) -> Result<Vec<f64>, ModelError> {
        let mut theta: Vec<f64> = Vec::with_capacity(q.len());
        for (k, j) in self.joints.iter().enumerate() {
            let passive = match (&j.coupling_in, k.checked_sub(1)) {
                (Some(g), Some(below)) => g.try_passive(theta[below]).map_err(|source| ModelError::Coupling {
                    joint: k + 1,
                    cause: source,
                })?,
                _ => 0.0,
            };
            theta.push(q[k] - passive);
        }
        Ok(theta)
    }

    /// The joint values for actuator commands `u` (after the controller's decoupling):
    /// `q_k = theta_act_k + g_{k-1,k}(theta_act_{k-1})`.
    pub fn joint_values_from_actuators(&self, u: &[f64]) -> Result<Vec<f64>, ModelError> {
        // q starts as theta and takes the couplings joint by joint upwards; `theta_below` keeps
        // the active displacement of the joint below (its q entry has its coupling already).
        let mut q = self.active_displacements(u)?;
        let mut theta_below = q.first().copied().unwrap_or(0.0);
        for (k, (qk, joint)) in q.iter_mut().zip(&self.joints).enumerate().skip(1) {
            let theta_k = *qk;
            if let Some(g) = &joint.coupling_in {
                *qk += g.try_passive(theta_below).map_err(|source| ModelError::Coupling {
                    joint: k + 1,
                    cause: source,
                })?;
            }
            theta_below = theta_k;
        }
        Ok(q)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A command a transmission cannot invert is named in the user's units: mm for a
    /// prismatic joint (its internal value is m).
    #[test]
    fn a_command_that_cannot_be_inverted_is_named_in_file_units() {
        let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/robots/table-prpp.toml"));
        let mut model = RobotModel::ideal(&RobotDescription::from_file(path).unwrap());
        // s + 10 s^2 never reaches -1 m.
        model.joints[0].transmission = Transmission::Polynomial {
            c0: 0.0,
            c: vec![0.0, 10.0],
        };
        let e = model.active_displacement(0, -1.0).unwrap_err().to_string();
        assert!(e.contains("command -1000 mm"), "{e}");
    }
}
