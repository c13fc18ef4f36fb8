//! Non-geometric effects a calibration can carry in its model (`calibration.json`'s
//! `robot.effects`, `docs/formats.md#robot-model`): each joint's sag under the gravity load, in
//! a form that assumes no load path, and each joint's backlash.
//!
//! **Sag.** A joint `j` of stiffness `k_j` bends by `tau_j / k_j` under the gravity torque
//! `tau_j` its spring carries. Carried serially, `tau_j = sum_(i >= j) g . (z_j x (m_i (o_i -
//! o_j) + R_i mu_i))` (link `i`'s mass `m_i` and first moment `mu_i` in its moving frame, `o_i`,
//! `R_i` its frame, `o_j`, `z_j` axis `j`: [`crate::physics::gravity_torques_nm`]). That torque
//! is linear in the masses and first moments, so the sag is linear in their products with the
//! compliance `1 / k_j` (Khalil & Dombre, *Modeling, Identification and Control of Robots*,
//! 2002, sec. 14.3): `dq_j = sum c_(j,i,t) r_(j,i,t)(q)` over the links `i` and the four load
//! terms `t` (mass, first moment along the link frame's x, y, z), the regressor `r` the torque
//! of a unit term. The sum runs from link `j - 1`, the one before the joint: a load that
//! reaches the actuator through a mechanism from the base side (a parallelogram drives the
//! forearm about an axis parallel to the joint's and its actuator's sag turns the forearm's
//! absolute angle) then shows in the relative joint `j` as the sag of joint `j - 1`'s links,
//! which these terms carry; the serial path is the sum from link `j`; a mix is any
//! combination. A balancer's torque is a function of the joint's own angle: the transmission's
//! first harmonic (eq. 8) carries it. With a payload that varies from pose to pose, the payload
//! `m_p` adds the last link's four terms times `m_p` (`docs/method.md`, "Effects in the model").
//!
//! Gravity points along `-z` of the robot's base frame (frame 1, the placement): a
//! floor-mounted robot's.
//!
//! **Backlash.** The active displacement lags the command by the half band `h_k` against the
//! direction of the joint's last move ([`crate::physics::ApproachTracker`] of the commands in
//! the order measured): the actuator command `u_k` acts as `u_k - s_k h_k`, `s_k` that direction
//! (+1, -1, 0 before any move).
//!
//! Both are first order: the sag's regressors are evaluated at the joint values before it
//! (their change under a sag of 1 mrad is 1e-3 of the sag).

use super::compliance::ComplianceTerm;
use crate::kinematics::{ChainPoses, JointKind, PhiModel};
use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};

/// Which load term of a link a sag coefficient multiplies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum LoadTerm {
    /// The link's mass at its frame's origin: coefficient \[rad/m\] (compliance times mass
    /// times `g`, per metre of lever).
    Mass,
    /// The link's first moment along its frame's x axis: coefficient \[rad\].
    MomentX,
    /// Along y \[rad\].
    MomentY,
    /// Along z \[rad\].
    MomentZ,
    /// The pose's payload (`payload_kg`) at the last link's origin: \[rad/(kg m)\].
    PayloadMass,
    /// The payload's first moment along the last link's x axis: \[rad/kg\].
    PayloadMomentX,
    /// Along y \[rad/kg\].
    PayloadMomentY,
    /// Along z \[rad/kg\].
    PayloadMomentZ,
}

impl LoadTerm {
    /// The four terms of a link's own load.
    pub const LINK: [LoadTerm; 4] = [LoadTerm::Mass, LoadTerm::MomentX, LoadTerm::MomentY, LoadTerm::MomentZ];
    /// The four terms of the payload.
    pub const PAYLOAD: [LoadTerm; 4] = [
        LoadTerm::PayloadMass,
        LoadTerm::PayloadMomentX,
        LoadTerm::PayloadMomentY,
        LoadTerm::PayloadMomentZ,
    ];

    /// Its name in reports (`mass`, `moment_x`, ..., `payload_moment_z`).
    pub fn name(self) -> &'static str {
        match self {
            LoadTerm::Mass => "mass",
            LoadTerm::MomentX => "moment_x",
            LoadTerm::MomentY => "moment_y",
            LoadTerm::MomentZ => "moment_z",
            LoadTerm::PayloadMass => "payload_mass",
            LoadTerm::PayloadMomentX => "payload_moment_x",
            LoadTerm::PayloadMomentY => "payload_moment_y",
            LoadTerm::PayloadMomentZ => "payload_moment_z",
        }
    }

    /// Whether it scales with the pose's payload.
    pub fn is_payload(self) -> bool {
        LoadTerm::PAYLOAD.contains(&self)
    }

    /// The axis of a first-moment term (0, 1, 2), `None` for a mass.
    fn moment_axis(self) -> Option<usize> {
        match self {
            LoadTerm::MomentX | LoadTerm::PayloadMomentX => Some(0),
            LoadTerm::MomentY | LoadTerm::PayloadMomentY => Some(1),
            LoadTerm::MomentZ | LoadTerm::PayloadMomentZ => Some(2),
            LoadTerm::Mass | LoadTerm::PayloadMass => None,
        }
    }
}

/// One coefficient of a joint's sag: `dq_joint += coefficient * r(q)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SagTerm {
    /// The joint that bends (1-based).
    pub joint: usize,
    /// The link whose load it carries (1-based; the link joint `link` moves; the last link for
    /// the payload's terms).
    pub link: usize,
    /// Which of the link's load terms.
    pub load: LoadTerm,
    /// The coefficient (units by [`LoadTerm`]).
    pub coefficient: f64,
}

/// A joint's backlash.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BacklashTerm {
    /// The joint (1-based).
    pub joint: usize,
    /// Half the dead band \[rad, or m for a sliding joint\]: the lag behind the command against
    /// the direction of the last move.
    pub half_band: f64,
}

/// The effects of a model (module docs). Empty: a purely geometric model.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ModelEffects {
    /// The sag's coefficients.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sag: Vec<SagTerm>,
    /// The joints' backlash.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub backlash: Vec<BacklashTerm>,
    /// Named joint compliances ([`ComplianceTerm`], a diagnosis's member carried by
    /// `calibrate --carry`), each sagging on top of the sag above.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub compliance: Vec<ComplianceTerm>,
}

/// The largest half band a model's backlash may carry, in size (rad, m for a sliding joint):
/// half the largest band an effects file takes (0.1 rad); beyond it a value is a slip.
pub const MAX_MODEL_HALF_BAND: f64 = 0.05;

/// What a pose's effects depend on besides its joint values.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PoseLoad<'a> {
    /// The direction of each joint's last move (+1, -1, 0), empty for none known.
    pub approach: &'a [f64],
    /// The payload \[kg\].
    pub payload_kg: f64,
}

impl ModelEffects {
    /// Whether the model has no effect.
    pub fn is_empty(&self) -> bool {
        self.sag.is_empty() && self.backlash.is_empty() && self.compliance.is_empty()
    }

    /// Whether the joint values move under gravity (a sag term or a compliance).
    pub fn sags(&self) -> bool {
        !self.sag.is_empty() || !self.compliance.is_empty()
    }

    /// Whether the payload changes the joint values: a payload sag term or a compliance
    /// carrying a payload load, with a non-zero coefficient.
    pub fn payload_sags(&self) -> bool {
        let loads = |l: &super::SpringLoad| {
            l.payload.mass_kg_rad_per_nm != 0.0 || l.payload.first_moment_kg_m_rad_per_nm.iter().any(|v| *v != 0.0)
        };
        self.sag.iter().any(|t| t.load.is_payload() && t.coefficient != 0.0)
            || self
                .compliance
                .iter()
                .any(|c| loads(&c.carried) || c.reflected.as_ref().is_some_and(loads))
    }

    /// Checks the joints and links against a model of `n` joints and the values' finiteness:
    /// the offending field (`effects.sag[2].link`) and why.
    pub fn validate(&self, n: usize) -> Result<(), (String, String)> {
        let in_range = |v: usize| (1..=n).contains(&v);
        for (k, t) in self.sag.iter().enumerate() {
            let field = |f: &str| format!("effects.sag[{k}].{f}");
            if !in_range(t.joint) {
                return Err((field("joint"), format!("must be in 1..={n}, found {}", t.joint)));
            }
            if !in_range(t.link) || (t.load.is_payload() && t.link != n) {
                return Err((
                    field("link"),
                    format!("must be in 1..={n} ({n} for a payload term), found {}", t.link),
                ));
            }
            if !t.coefficient.is_finite() {
                return Err((field("coefficient"), "must be finite".into()));
            }
        }
        for (k, b) in self.backlash.iter().enumerate() {
            if !in_range(b.joint) {
                return Err((
                    format!("effects.backlash[{k}].joint"),
                    format!("must be in 1..={n}, found {}", b.joint),
                ));
            }
            if !(b.half_band.is_finite() && b.half_band.abs() <= MAX_MODEL_HALF_BAND) {
                return Err((
                    format!("effects.backlash[{k}].half_band"),
                    format!(
                        "{}: a half band is finite and within +-{MAX_MODEL_HALF_BAND} (rad, m for a sliding joint: half \
                         the largest band an effects file takes, 0.1 rad)",
                        crate::measurement::format_f64(b.half_band)
                    ),
                ));
            }
            if self.backlash[..k].iter().any(|a| a.joint == b.joint) {
                return Err((
                    format!("effects.backlash[{k}].joint"),
                    format!("joint {} has a backlash entry already: one per joint", b.joint),
                ));
            }
        }
        for (k, c) in self.compliance.iter().enumerate() {
            c.validate(n, &format!("effects.compliance[{k}]"))?;
        }
        Ok(())
    }

    /// The actuator commands `u` shifted by the backlash: `u_k - s_k h_k`.
    pub fn shift_actuators(&self, u: &mut [f64], load: &PoseLoad<'_>) {
        for b in &self.backlash {
            let s = load.approach.get(b.joint - 1).copied().unwrap_or(0.0);
            u[b.joint - 1] -= s * b.half_band;
        }
    }

    /// The joint values `q` (before the sag) with the sag added, `frames` the chain at `q`.
    pub fn add_sag(&self, phi: &PhiModel, frames: &ChainPoses, q: &mut [f64], load: &PoseLoad<'_>) {
        for t in &self.sag {
            q[t.joint - 1] += t.coefficient * sag_regressor(phi, frames, t.joint, t.link, t.load, load.payload_kg);
        }
    }
}

/// The unit gravity direction in the instrument frame: `-z` of the base frame.
pub fn gravity_direction(phi: &PhiModel) -> Vector3<f64> {
    phi.world_from_base.rotation * -Vector3::z()
}

/// `r_(j,i,t)(q)`: the sag of revolute joint `joint` per unit coefficient of load term `load` of
/// link `link` (module docs), `frames` the chain at the pose; 0 for a sliding joint (gravity
/// along its axis is a force the structure, not the sag model, carries).
pub fn sag_regressor(
    phi: &PhiModel,
    frames: &ChainPoses,
    joint: usize,
    link: usize,
    load: LoadTerm,
    payload_kg: f64,
) -> f64 {
    if phi.joints[joint - 1].kind != JointKind::Revolute {
        return 0.0;
    }
    let g = gravity_direction(phi);
    let axis = frames.axis(joint - 1);
    let z = axis.direction.into_inner();
    let f = &frames.world_from_link[link - 1];
    // The term's first moment about axis j's origin, in the instrument frame.
    let moment = match load.moment_axis() {
        Some(a) => f.rotation * Vector3::ith(a, 1.0),
        None => (f * Point3::origin()) - axis.origin_m,
    };
    let scale = if load.is_payload() { payload_kg } else { 1.0 };
    scale * g.dot(&z.cross(&moment))
}
