//! Unmodelled effects of the simulated real robot and instrument: what the calibration model
//! (paper sections 3-4) leaves out, each switched on by the presence of its table in an
//! effects file (TOML, `deny_unknown_fields`, units in key names).
//!
//! | table | effect | applied to |
//! |---|---|---|
//! | `compliance` | actuator stiffness `K_k` \[N m/rad\] under gravity: `K da = Q_gravity(q)`, the sag `da` driving the passive couplings | joint values (rapier: static equilibrium, four-bar as bodies; analytic: first order, [`coupled_first_order_deflection`]; exact equilibrium of the same model: [`coupled_static_deflection`]) |
//! | `payload` | the pose's `payload_kg` (from [`PoseConditions`]) at a point of the tool frame | the gravity load of `compliance` (no effect without it) |
//! | `backlash` | dead band `b_k` \[rad\]: the joint lags `b_k / 2` behind its approach direction | active displacements |
//! | `thermal` | link growth: rows' `a`, `b` scaled by `1 + alpha (T - T_ref)` | the phi-model |
//! | `gear_harmonics` | extra harmonic terms of a joint's transmission (eq. 8) | the truth's transmissions |
//! | `wobble` | bearing runout: a tilt of the joint axis that turns with the joint | link poses |
//! | `instrument_scale` | a scale error of the instrument about its origin \[ppm\] | measured coordinates |
//!
//! [`JointDriver`] runs the joint-side effects for any [`ArmExecutor`](super::ArmExecutor):
//! commands -> fig. 3 controller -> actuators with the truth's transmissions (plus gear
//! harmonics) and backlash -> passive couplings -> repeatability jitter.

use super::simulate::PoseConditions;
use crate::kinematics::PhiModel;
use crate::robot::{Controller, RobotDescription, Transmission, TruthError, TruthRobot};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A problem with an effects file.
#[derive(Debug, thiserror::Error)]
pub enum EffectsError {
    /// The file could not be read or parsed.
    #[error(transparent)]
    File(#[from] crate::toml_file::TomlFileError),
    /// A value out of range or of the wrong length.
    #[error("effects field `{field}`: {message}")]
    Invalid {
        /// The key, e.g. `backlash.band_rad`.
        field: String,
        /// What is wrong.
        message: String,
    },
}

fn default_gravity() -> [f64; 3] {
    [0.0, 0.0, -9.81]
}

fn default_reference_c() -> f64 {
    20.0
}

fn default_order() -> i32 {
    1
}

/// Joint compliance: each joint's servo/drive stiffness.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ComplianceEffect {
    /// Stiffness per joint \[N m/rad\] (N/m for prismatic joints), finite and > 0.
    pub stiffness_nm_per_rad: Vec<f64>,
    /// Gravity in the instrument (world) frame \[m/s^2\]; default `(0, 0, -9.81)`.
    #[serde(default = "default_gravity")]
    pub gravity_m_s2: [f64; 3],
}

/// Payload: the pose's `payload_kg` ([`PoseConditions`]) as a point mass in the tool frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PayloadEffect {
    /// Where the payload's centre of mass sits in the tool frame \[mm\].
    #[serde(default)]
    pub com_in_tool_mm: [f64; 3],
}

/// Backlash: a direction-dependent dead band per joint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BacklashEffect {
    /// Width of the dead band of each joint \[rad\] (>= 0).
    pub band_rad: Vec<f64>,
}

/// Thermal expansion of the links.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalEffect {
    /// Linear expansion coefficient \[1/K\] (steel about 1.2e-5, aluminium 2.3e-5).
    pub alpha_per_k: f64,
    /// Temperature at which the truth's lengths hold \[deg C\]; default 20.
    #[serde(default = "default_reference_c")]
    pub reference_c: f64,
}

/// One extra harmonic term of a joint's transmission `theta_c = f(theta_a)` (eq. 8).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GearHarmonic {
    /// The joint (1-based).
    pub joint: usize,
    /// Harmonic order `n >= 1`, in the transmission's own angle (the gear angle for a
    /// [`Transmission::Gear`]).
    pub order: usize,
    /// Added sine coefficient \[rad\] (gear units for a gear).
    #[serde(default)]
    pub sin_rad: f64,
    /// Added cosine coefficient \[rad\].
    #[serde(default)]
    pub cos_rad: f64,
}

/// Axis wobble (bearing runout) of one joint: before the joint's motion, frame `k` is turned
/// by the small rotation vector `amplitude (cos(n q + phase), sin(n q + phase), 0)` (in frame
/// `k`, i.e. about an axis perpendicular to `Z_k` whose direction turns with the joint value `q`).
///
/// With `order = 1` the tilt turns with the link: the link sits tilted on its bearing, a point
/// at radius `r` leaves the nominal plane of its arc by `-amplitude r sin(phase)` and its path
/// is still a circle (about a tilted axis). Orders `n >= 3` (or `n <= -1`) bend the path out of
/// any plane by up to `amplitude r`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxisWobble {
    /// The joint (1-based).
    pub joint: usize,
    /// Tilt amplitude \[rad\].
    pub amplitude_rad: f64,
    /// Phase of the tilt direction \[rad\].
    #[serde(default)]
    pub phase_rad: f64,
    /// How many times the tilt direction turns per joint turn; default 1.
    #[serde(default = "default_order")]
    pub order: i32,
}

/// A scale error of the instrument.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InstrumentScale {
    /// Measured coordinates are `(1 + ppm 1e-6)` times the true ones, about the instrument
    /// origin \[ppm\].
    pub ppm: f64,
}

impl InstrumentScale {
    /// What the scaled instrument reports for a (noisy) measurement `p` (instrument frame).
    pub fn applied_to(&self, p: &Point3<f64>) -> Point3<f64> {
        Point3::from(p.coords * (1.0 + self.ppm * 1e-6))
    }
}

/// The unmodelled effects (module docs); every table is optional and off when absent.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Effects {
    /// Joint compliance under gravity.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub compliance: Option<ComplianceEffect>,
    /// Payload at the tool (mass per pose from [`PoseConditions`]); acts through `compliance`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub payload: Option<PayloadEffect>,
    /// Backlash.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub backlash: Option<BacklashEffect>,
    /// Thermal expansion (temperature per pose from [`PoseConditions`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thermal: Option<ThermalEffect>,
    /// Extra transmission harmonics.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub gear_harmonics: Vec<GearHarmonic>,
    /// Axis wobble.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub wobble: Vec<AxisWobble>,
    /// Instrument scale error.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub instrument_scale: Option<InstrumentScale>,
}

fn invalid(field: impl Into<String>, message: impl Into<String>) -> EffectsError {
    EffectsError::Invalid {
        field: field.into(),
        message: message.into(),
    }
}

impl Effects {
    /// Reads and validates an effects file for a robot of `dof` joints.
    pub fn from_file(path: &Path, dof: usize) -> Result<Self, EffectsError> {
        Self::from_toml_str(&crate::toml_file::read(path)?, path, dof)
    }

    /// Parses and validates effects text; `path` labels errors only.
    pub fn from_toml_str(text: &str, path: &Path, dof: usize) -> Result<Self, EffectsError> {
        let e: Self = crate::toml_file::parse(text, path)?;
        e.validate(dof)?;
        Ok(e)
    }

    /// Checks lengths, ranges and joint numbers against a robot of `dof` joints.
    pub fn validate(&self, dof: usize) -> Result<(), EffectsError> {
        let per_joint = |field: &str, v: &[f64], ok: fn(f64) -> bool| {
            if v.len() != dof {
                return Err(invalid(field, format!("needs {dof} values, found {}", v.len())));
            }
            match v.iter().position(|x| !ok(*x)) {
                Some(k) => Err(invalid(format!("{field}[{k}]"), format!("bad value {}", v[k]))),
                None => Ok(()),
            }
        };
        if let Some(c) = &self.compliance {
            per_joint("compliance.stiffness_nm_per_rad", &c.stiffness_nm_per_rad, |x| {
                x.is_finite() && x > 0.0
            })?;
            if !c.gravity_m_s2.iter().all(|g| g.is_finite()) {
                return Err(invalid("compliance.gravity_m_s2", "must be finite"));
            }
        }
        if let Some(p) = &self.payload
            && !p.com_in_tool_mm.iter().all(|x| x.is_finite())
        {
            return Err(invalid("payload.com_in_tool_mm", "must be finite"));
        }
        if let Some(b) = &self.backlash {
            per_joint("backlash.band_rad", &b.band_rad, |x| x.is_finite() && x >= 0.0)?;
        }
        if let Some(t) = &self.thermal
            && !(t.alpha_per_k.is_finite() && t.reference_c.is_finite())
        {
            return Err(invalid("thermal", "alpha_per_k and reference_c must be finite"));
        }
        let joint_ok = |field: String, joint: usize| {
            if joint == 0 || joint > dof {
                Err(invalid(field, format!("joint {joint} is not in 1..={dof}")))
            } else {
                Ok(())
            }
        };
        for (i, h) in self.gear_harmonics.iter().enumerate() {
            joint_ok(format!("gear_harmonics[{i}].joint"), h.joint)?;
            if h.order == 0 || !(h.sin_rad.is_finite() && h.cos_rad.is_finite()) {
                return Err(invalid(
                    format!("gear_harmonics[{i}]"),
                    "order must be >= 1, coefficients finite",
                ));
            }
        }
        for (i, w) in self.wobble.iter().enumerate() {
            joint_ok(format!("wobble[{i}].joint"), w.joint)?;
            if !(w.amplitude_rad.is_finite() && w.phase_rad.is_finite()) {
                return Err(invalid(format!("wobble[{i}]"), "amplitude and phase must be finite"));
            }
        }
        if let Some(s) = &self.instrument_scale
            && !s.ppm.is_finite()
        {
            return Err(invalid("instrument_scale.ppm", "must be finite"));
        }
        Ok(())
    }

    /// The truth with the extra gear harmonics added to its transmissions.
    pub fn truth_with_harmonics(&self, truth: &TruthRobot) -> TruthRobot {
        let mut t = truth.clone();
        for h in &self.gear_harmonics {
            let Some(joint) = t.joints.get_mut(h.joint - 1) else {
                continue;
            };
            let (sin, cos) = match &mut joint.transmission {
                Transmission::Harmonic { sin, cos } | Transmission::Gear { sin, cos, .. } => (sin, cos),
            };
            for v in [&mut *sin, &mut *cos] {
                if v.len() < h.order {
                    v.resize(h.order, 0.0);
                }
            }
            sin[h.order - 1] += h.sin_rad;
            cos[h.order - 1] += h.cos_rad;
        }
        t
    }

    /// The phi-model at temperature `temperature_c`: every row's `a` and `b` scaled by
    /// `1 + alpha (T - T_ref)` (thermal expansion about the base frame's origin).
    pub fn thermal_model(&self, model: &PhiModel, temperature_c: f64) -> PhiModel {
        let mut m = model.clone();
        if let Some(t) = &self.thermal {
            let s = 1.0 + t.alpha_per_k * (temperature_c - t.reference_c);
            for row in &mut m.rows {
                row.a_m *= s;
                row.b_m *= s;
            }
        }
        m
    }

    /// Applies the axis wobble to link poses computed without it (`links`, index `k` = link
    /// `k + 1`), for joint values `q` of `model`: joint `k`'s tilt `W_k` (see [`AxisWobble`])
    /// gives the world-frame correction `C_k = F_k W_k F_k^-1` (`F_k` = world_from_frame_k)
    /// applied to every link from `k` on, joints processed from the last to the first so
    /// each `F_k` is still the wobble-free one when used.
    pub fn apply_wobble(&self, model: &PhiModel, q: &[f64], links: &mut [Isometry3<f64>]) {
        let mut wobbles: Vec<&AxisWobble> = self.wobble.iter().collect();
        wobbles.sort_by_key(|w| std::cmp::Reverse(w.joint));
        for w in wobbles {
            let k = w.joint - 1;
            if k >= links.len() || k >= q.len() {
                continue;
            }
            let frame = if k == 0 {
                model.world_from_base
            } else {
                links[k - 1] * model.link_from_next_frame(k - 1)
            };
            let angle = w.order as f64 * q[k] + w.phase_rad;
            let tilt = UnitQuaternion::from_scaled_axis(Vector3::new(angle.cos(), angle.sin(), 0.0) * w.amplitude_rad);
            let correction = frame * Isometry3::from_parts(Translation3::identity(), tilt) * frame.inverse();
            for link in &mut links[k..] {
                *link = correction * *link;
            }
        }
    }

    /// The payload as `(mass, position in the last link's frame)`, if any, for `conditions`.
    pub fn payload_in_last_link(
        &self,
        last_link_from_tool: &Isometry3<f64>,
        conditions: &PoseConditions,
    ) -> Option<(f64, Point3<f64>)> {
        let p = self.payload.as_ref()?;
        (conditions.payload_kg > 0.0).then(|| {
            (
                conditions.payload_kg,
                last_link_from_tool * (Point3::from(p.com_in_tool_mm) * 1e-3),
            )
        })
    }
}

/// Mass of a link and its centre of mass in the link's moving frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkMass {
    /// \[kg\]
    pub mass_kg: f64,
    /// \[m\]
    pub com_in_link_m: Point3<f64>,
}

impl LinkMass {
    /// The masses of a robot description's links.
    pub fn from_description(desc: &RobotDescription) -> Vec<Self> {
        desc.joints
            .iter()
            .map(|j| LinkMass {
                mass_kg: j.mass_kg,
                com_in_link_m: Point3::from(j.com_mm) * 1e-3,
            })
            .collect()
    }
}

/// First-order static deflection of compliant joints under gravity: `dq = K^-1 Q(q)` with the
/// gravity generalised force `Q_j = sum_{i >= j} m_i g . (z_j x (c_i - o_j))` (revolute joints;
/// `z_j . m_i g` for prismatic ones), `c_i` the centres of mass (and the payload on the last
/// link), `o_j`, `z_j` axis `j`. The error is second order in the deflection.
pub fn first_order_deflection(
    model: &PhiModel,
    q: &[f64],
    masses: &[LinkMass],
    payload: Option<(f64, Point3<f64>)>,
    compliance: &ComplianceEffect,
) -> Vec<f64> {
    let poses = model.poses(q);
    let g = Vector3::from(compliance.gravity_m_s2);
    let n = model.dof();
    let mut loads: Vec<(usize, f64, Point3<f64>)> = masses
        .iter()
        .enumerate()
        .take(n)
        .map(|(i, m)| (i, m.mass_kg, poses.world_from_link[i] * m.com_in_link_m))
        .collect();
    if let Some((mass, p)) = payload {
        loads.push((n - 1, mass, poses.world_from_link[n - 1] * p));
    }
    (0..n)
        .map(|j| {
            let axis = poses.axis(j);
            let z = axis.direction.into_inner();
            let generalised: f64 = loads
                .iter()
                .filter(|(i, _, _)| *i >= j)
                .map(|(_, m, c)| match model.joints[j].kind {
                    crate::kinematics::JointKind::Revolute => (g * *m).dot(&z.cross(&(c - axis.origin_m))),
                    crate::kinematics::JointKind::Prismatic => (g * *m).dot(&z),
                })
                .sum();
            generalised / compliance.stiffness_nm_per_rad[j]
        })
        .collect()
}

/// An actuator command that changed by no more than this \[rad or m\] has not moved: the
/// hold-still commands of a coupled joint reproduce its actuator command only to rounding (a
/// few 1e-16 rad through the fig. 3 decoupling), and no encoder resolves 1e-12.
pub const UNMOVED_ACTUATOR_RAD: f64 = 1e-12;

/// How each joint is driven by the one below, for [`coupled_first_order_deflection`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PassiveSlope {
    /// `g'_{k-1,k}`: the slope of the passive coupling into this joint at the active
    /// displacement of the joint below (0: not coupled) \[-\].
    pub slope: f64,
    /// The coupling is a mechanism (a four-bar's bodies) that also carries this joint's load
    /// back to the actuator below; otherwise it is kinematic only (an emulated gear).
    pub reflects_load: bool,
}

impl PassiveSlope {
    /// The truth's couplings at the active displacements `active`: slopes of every
    /// `coupling_in`, reflecting the load where one of the truth's four-bars drives the joint.
    pub fn of_truth(truth: &TruthRobot, active: &[f64]) -> Vec<Self> {
        Self::of_robot(truth, active, |k, _| truth.four_bars.iter().any(|l| l.from == k))
    }

    /// `robot`'s couplings at the active displacements `active`: slopes of every
    /// `coupling_in`, reflecting the load where `reflects(k, g)` says the coupling `g` into
    /// joint `k` (0-based) is a mechanism.
    pub fn of_robot(
        robot: &TruthRobot,
        active: &[f64],
        reflects: impl Fn(usize, &crate::robot::CouplingFunction) -> bool,
    ) -> Vec<Self> {
        robot
            .joints
            .iter()
            .enumerate()
            .map(|(k, j)| match (&j.coupling_in, k.checked_sub(1)) {
                (Some(g), Some(below)) => PassiveSlope {
                    slope: g.slope(active[below]),
                    reflects_load: reflects(k, g),
                },
                _ => PassiveSlope::default(),
            })
            .collect()
    }
}

/// First-order static deflection through the passive couplings, as the rapier arm's dynamic
/// mode produces it (`sim::FourBarBodies`, `sim::CoupledTargets`): each actuator `k` sags by
/// `da_k = tau_k / K_k` and the sag drives the passive coupling into joint `k + 1` like any
/// active rotation, `dq_k = da_k + g'_{k-1,k} da_{k-1}` (eq. 15 linearised; `g'` =
/// `couplings[k].slope`). The actuator's load is the joint's gravity torque `Q_k`
/// ([`first_order_deflection`] with unit stiffness), plus, where joint `k` drives joint
/// `k + 1` through a mechanism (`couplings[k + 1].reflects_load`: a four-bar transmits torque
/// both ways), the reflected `g'_{k,k+1} Q_{k+1}` (virtual work). The other couplings are
/// kinematic only, as their rapier emulation (see `sim::CoupledTargets` for the size of the
/// missing gear reaction). Second order in the deflection, like [`first_order_deflection`].
/// Needs only coupling slopes, so a model built from the nominal description can use it.
pub fn coupled_first_order_deflection(
    model: &PhiModel,
    q: &[f64],
    masses: &[LinkMass],
    payload: Option<(f64, Point3<f64>)>,
    compliance: &ComplianceEffect,
    couplings: &[PassiveSlope],
) -> Vec<f64> {
    let unit = ComplianceEffect {
        stiffness_nm_per_rad: vec![1.0; q.len()],
        gravity_m_s2: compliance.gravity_m_s2,
    };
    let load = first_order_deflection(model, q, masses, payload, &unit);
    let coupling = |k: usize| couplings.get(k).copied().unwrap_or_default();
    let mut dq = vec![0.0; q.len()];
    let mut da_below = 0.0;
    for k in 0..q.len() {
        let mut tau = load[k];
        if k + 1 < q.len() && coupling(k + 1).reflects_load {
            tau += coupling(k + 1).slope * load[k + 1];
        }
        let da = tau / compliance.stiffness_nm_per_rad[k];
        dq[k] = da + coupling(k).slope * da_below;
        da_below = da;
    }
    dq
}

/// The fixed-point iteration of [`coupled_static_deflection`] runs to machine precision: it
/// stops at the first step that is no larger than the one before, and that step must be below
/// this \[rad or m\] (rounding: about 500 ulps of a joint angle near 1 rad), else the iteration
/// is diverging. Converging to rounding, not to a tolerance, keeps the equilibrium a smooth
/// function of the model's parameters, so central differences through it (the diagnoser's
/// refit sensitivities, steps of 1e-6) are not swamped by where a tolerance happened to stop
/// the iteration. From a 0.1 rad sag at the paper arm's worst contraction (gravity stiffness /
/// joint stiffness ~ 0.2) that is about 22 steps.
pub const STATIC_DEFLECTION_ROUNDING_RAD: f64 = 1e-13;

/// The iteration of [`coupled_static_deflection`] gives up after this many steps.
pub const STATIC_DEFLECTION_MAX_STEPS: usize = 200;

/// The static equilibrium of [`coupled_static_deflection`] was not found.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DeflectionError {
    /// The fixed-point iteration did not converge: the gravity stiffness `dQ/dq` reaches the
    /// joint stiffness (the arm buckles, or gravity restores faster than the spring).
    #[error(
        "static deflection did not converge in {steps} steps (last step {last_step_rad:e} rad, \
         contraction {contraction}): the gravity stiffness reaches the joint stiffness"
    )]
    NotConverged {
        /// Steps taken.
        steps: usize,
        /// Largest joint change of the last step \[rad or m\].
        last_step_rad: f64,
        /// Ratio of the last two steps' sizes (>= 1: the iteration diverges).
        contraction: f64,
    },
}

/// What loads the compliant joints and how they are coupled, for
/// [`coupled_static_deflection`] (the arguments of [`coupled_first_order_deflection`] after
/// the model and the joint values).
#[derive(Clone, Copy, Debug)]
pub struct CompliantLoad<'a> {
    /// The links' masses.
    pub masses: &'a [LinkMass],
    /// The payload as `(mass, position in the last link's frame)`, if any.
    pub payload: Option<(f64, Point3<f64>)>,
    /// The joints' stiffnesses and gravity.
    pub compliance: &'a ComplianceEffect,
    /// How each joint is driven by the one below.
    pub couplings: &'a [PassiveSlope],
}

/// Exact static equilibrium of the compliance model of [`coupled_first_order_deflection`]:
/// the actuators' springs balance gravity at the DEFLECTED pose, `K da = Q(q + dq)` with
/// `dq = da + g' da_below` (the coupled equilibrium of the rapier arm's dynamic mode), solved
/// by the fixed-point iteration `dq_{n+1} = C(q + dq_n)` from `dq_0 = 0`, `C` the first-order
/// map (so `dq_1` is the first-order deflection). The iteration contracts by about the ratio
/// of the gravity stiffness `|dQ/dq|` to `K` (the error of the first-order deflection,
/// `dq - dq_1 ~ K^-1 (dQ/dq) dq_1`); it runs to rounding ([`STATIC_DEFLECTION_ROUNDING_RAD`])
/// and fails with [`DeflectionError::NotConverged`] when a step above rounding stops shrinking
/// (ratio >= 1, gravity stiffness reaching the joint stiffness) or after
/// [`STATIC_DEFLECTION_MAX_STEPS`]. The
/// coupling slopes stay those at the undeflected active displacements (their change with the
/// sag is second order in it, times `g''`). Stiffnesses may be infinite (a rigid joint).
///
/// Measured against the rapier arm (`tests/effects.rs`, joint 2 at 2e3 N m/rad): 0.8 % off
/// rapier's joint-2 sag where the first order is 11.5 % off (the rest is a near-constant 2 %
/// more load in rapier: the four-bar bodies' own weight). The diagnoser's compliance candidate
/// uses it; [`AnalyticArm`](super::AnalyticArm) keeps the first order (the two agree to about
/// `K^-1 dQ/dq`, a few per cent of the sag at the blind suite's stiffnesses).
pub fn coupled_static_deflection(
    model: &PhiModel,
    q: &[f64],
    load: &CompliantLoad,
) -> Result<Vec<f64>, DeflectionError> {
    let CompliantLoad {
        masses,
        payload,
        compliance,
        couplings,
    } = *load;
    let mut dq = vec![0.0; q.len()];
    let mut last_step = f64::INFINITY;
    let mut contraction = 0.0;
    for step in 1..=STATIC_DEFLECTION_MAX_STEPS {
        let deflected: Vec<f64> = q.iter().zip(&dq).map(|(a, d)| a + d).collect();
        let next = coupled_first_order_deflection(model, &deflected, masses, payload, compliance, couplings);
        let size = next.iter().zip(&dq).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        dq = next;
        contraction = size / last_step;
        if size == 0.0 || (contraction >= 1.0 && size <= STATIC_DEFLECTION_ROUNDING_RAD) {
            return Ok(dq);
        }
        if contraction >= 1.0 || !size.is_finite() {
            return Err(DeflectionError::NotConverged {
                steps: step,
                last_step_rad: size,
                contraction,
            });
        }
        last_step = size;
    }
    Err(DeflectionError::NotConverged {
        steps: STATIC_DEFLECTION_MAX_STEPS,
        last_step_rad: last_step,
        contraction,
    })
}

/// Commands to joint values with the joint-side effects: the fig. 3 controller, the truth's
/// transmissions (with [`Effects::gear_harmonics`]), backlash on the active displacements, the
/// passive couplings, and the repeatability jitter. Keeps the last command for the approach
/// direction of the backlash (FORMATS.md section 1: the sign of `cmd(s) - cmd(s-1)`; a joint
/// whose command did not change keeps its previous direction; before any motion the joint
/// sits in the middle of its band).
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
    truth: TruthRobot,
    controller: Controller,
    band_rad: Vec<f64>,
    last_cmd: Option<Vec<f64>>,
    approach: Vec<f64>,
    /// Actuator commands of the last execution and the standard-normal jitter draws they got.
    last_actuator: Option<(Vec<f64>, Vec<f64>)>,
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
    pub fn new(truth: &TruthRobot, controller: Controller, effects: &Effects) -> Self {
        let n = truth.dof();
        JointDriver {
            truth: effects.truth_with_harmonics(truth),
            controller,
            band_rad: effects.backlash.as_ref().map_or(vec![0.0; n], |b| b.band_rad.clone()),
            last_cmd: None,
            approach: vec![0.0; n],
            last_actuator: None,
        }
    }

    /// The truth model (with the gear harmonics added).
    pub fn truth(&self) -> &TruthRobot {
        &self.truth
    }

    /// Executes `cmd` (internal units). Draws one standard normal per joint from `rng`, as
    /// [`TruthRobot::joint_values_executed`] does, and uses it for the actuators whose command
    /// changed (see the type's docs).
    pub fn drive<R: Rng + ?Sized>(&mut self, cmd: &[f64], rng: &mut R) -> Result<DrivenJoints, TruthError> {
        let u = self.controller.decouple(cmd)?;
        let mut active = self.truth.active_displacements(&u)?;
        if let Some(last) = &self.last_cmd {
            for ((dir, c), l) in self.approach.iter_mut().zip(cmd).zip(last) {
                if (c - l).abs() > 0.0 {
                    *dir = (c - l).signum();
                }
            }
        }
        self.last_cmd = Some(cmd.to_vec());
        for ((a, dir), band) in active.iter_mut().zip(&self.approach).zip(&self.band_rad) {
            *a -= dir * band / 2.0;
        }
        let mut q = active.clone();
        for k in 1..q.len() {
            if let Some(g) = &self.truth.joints[k].coupling_in {
                q[k] += g
                    .try_passive(active[k - 1])
                    .map_err(|source| TruthError::Coupling { joint: k + 1, source })?;
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
}
