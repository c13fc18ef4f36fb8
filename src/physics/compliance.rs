//! Joint compliance under gravity: each actuator a spring of stiffness `K_k` that sags under
//! its gravity load, the sag driving the passive coupling above it (paper section 3.1), to
//! first order and as the exact static equilibrium. The simulated robot and the diagnosis's
//! compliance candidate use the same physics.

use super::gravity::{LinkMass, STANDARD_GRAVITY_M_S2, gravity_torques_at_nm};
use crate::kinematics::{ChainPoses, PhiModel};
use crate::robot::{CouplingFunction, RobotModel};
use nalgebra::Point3;
use serde::{Deserialize, Serialize};

fn default_gravity() -> [f64; 3] {
    STANDARD_GRAVITY_M_S2
}

fn one() -> f64 {
    1.0
}

/// The default exactly (a file's `1.0` is written back as absent).
fn is_one(x: &f64) -> bool {
    x.to_bits() == 1f64.to_bits()
}

/// Joint compliance: each joint's servo/drive stiffness.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ComplianceEffect {
    /// Stiffness per joint \[N m/rad\] (N/m for prismatic joints), finite and > 0.
    pub stiffness_nm_per_rad: Vec<f64>,
    /// Gravity in the instrument (world) frame \[m/s^2\]; default `(0, 0, -9.81)`.
    #[serde(default = "default_gravity")]
    pub gravity_m_s2: [f64; 3],
    /// The load path of a mechanism coupling (a four-bar): the fraction in 0-1 of the driven
    /// joint's gravity torque the mechanism carries back to the actuator below (virtual work,
    /// [`coupled_first_order_deflection`]); default 1, the rigid-body four-bar. At 0 the
    /// actuator carries the serial chain's gravity torque about its own joint (the links
    /// beyond, their own moments included) and the driven joint's load goes elsewhere.
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub reflected_fraction: f64,
    /// Per joint (empty: none), the fraction in 0-1 of its own link's gravity torque about it
    /// that a spring balancer takes off the actuator: the load is `Q_k - f_k Q_k(link k)`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub balancer_fraction: Vec<f64>,
}

impl ComplianceEffect {
    /// Stiffnesses `stiffness_nm_per_rad` under `gravity_m_s2`, the four-bars carrying their
    /// whole load, no balancer.
    pub fn new(stiffness_nm_per_rad: Vec<f64>, gravity_m_s2: [f64; 3]) -> Self {
        ComplianceEffect {
            stiffness_nm_per_rad,
            gravity_m_s2,
            reflected_fraction: 1.0,
            balancer_fraction: Vec::new(),
        }
    }
}

/// Payload: the pose's `payload_kg` ([`PoseConditions`](crate::plan::PoseConditions)) as a point mass in the tool frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PayloadEffect {
    /// Where the payload's centre of mass sits in the tool frame \[mm\].
    #[serde(default)]
    pub com_in_tool_mm: [f64; 3],
}

/// First-order static deflection of compliant joints under gravity: `dq = K^-1 Q(q)`, `Q` the
/// gravity generalised force ([`gravity_torques_nm`](super::gravity_torques_nm)). The error is second order in the
/// deflection.
pub fn first_order_deflection(
    model: &PhiModel,
    q: &[f64],
    masses: &[LinkMass],
    payload: Option<(f64, Point3<f64>)>,
    compliance: &ComplianceEffect,
) -> Vec<f64> {
    first_order_deflection_at(model, &model.poses(q), masses, payload, compliance)
}

/// [`first_order_deflection`] with `model`'s frames at the joint values already computed
/// (`poses = model.poses(q)`): the same numbers bit for bit.
fn first_order_deflection_at(
    model: &PhiModel,
    poses: &ChainPoses,
    masses: &[LinkMass],
    payload: Option<(f64, Point3<f64>)>,
    compliance: &ComplianceEffect,
) -> Vec<f64> {
    gravity_torques_at_nm(model, poses, masses, payload, compliance.gravity_m_s2)
        .iter()
        .zip(&compliance.stiffness_nm_per_rad)
        .map(|(tau, k)| tau / k)
        .collect()
}

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
    /// `model`'s couplings at the active displacements `active`: slopes of every
    /// `coupling_in`, reflecting the load where one of the model's physical four-bar linkages
    /// (`four_bars`) drives the joint.
    pub fn of_linkages(model: &RobotModel, active: &[f64]) -> Vec<Self> {
        Self::of_robot(model, active, |k, _| model.four_bars.iter().any(|l| l.from == k))
    }

    /// `robot`'s couplings at the active displacements `active`: slopes of every
    /// `coupling_in`, reflecting the load where `reflects(k, g)` says the coupling `g` into
    /// joint `k` (0-based) is a mechanism.
    pub fn of_robot(
        robot: &RobotModel,
        active: &[f64],
        reflects: impl Fn(usize, &CouplingFunction) -> bool,
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
/// ([`first_order_deflection`] with unit stiffness) less what a balancer takes
/// (`balancer_fraction[k]` of link `k`'s own torque `Q_k(link k)`), plus, where joint `k`
/// drives joint `k + 1` through a mechanism (`couplings[k + 1].reflects_load`: a four-bar
/// transmits torque both ways), the reflected `g'_{k,k+1} Q'_{k+1}` (virtual work), `Q'` the
/// torque of `load.reflected_masses` (default: the same load). The other couplings are
/// kinematic only, as their rapier emulation (see `sim::CoupledTargets` for the size of the
/// missing gear reaction). Second order in the deflection, like [`first_order_deflection`].
/// Needs only coupling slopes, so a model built from the nominal description can use it.
pub fn coupled_first_order_deflection(model: &PhiModel, q: &[f64], load: &CompliantLoad) -> Vec<f64> {
    coupled_first_order_deflection_at(model, &model.poses(q), load)
}

/// [`coupled_first_order_deflection`] with `model`'s frames at the joint values already
/// computed (`poses = model.poses(q)`), for several loads of one pose (the diagnosis's
/// compliance sensitivities): the same numbers bit for bit.
pub fn coupled_first_order_deflection_at(model: &PhiModel, poses: &ChainPoses, load: &CompliantLoad) -> Vec<f64> {
    let CompliantLoad {
        masses,
        payload,
        compliance,
        couplings,
        reflected_masses,
    } = *load;
    let n = model.dof();
    let torques = |m: &[LinkMass], p| gravity_torques_at_nm(model, poses, m, p, compliance.gravity_m_s2);
    let gravity = torques(masses, payload);
    let reflected = reflected_masses.map(|m| torques(m, None));
    let reflected = reflected.as_ref().unwrap_or(&gravity);
    let coupling = |k: usize| couplings.get(k).copied().unwrap_or_default();
    let mut dq = vec![0.0; n];
    let mut da_below = 0.0;
    for k in 0..n {
        let mut tau = gravity[k] - balancer_torque_nm(model, poses, masses, compliance, k);
        if k + 1 < n && coupling(k + 1).reflects_load {
            tau += coupling(k + 1).slope * reflected[k + 1];
        }
        let da = tau / compliance.stiffness_nm_per_rad[k];
        dq[k] = da + coupling(k).slope * da_below;
        da_below = da;
    }
    dq
}

/// The masses whose load the mechanisms reflect under `compliance`'s `reflected_fraction`
/// (for [`CompliantLoad::reflected_masses`]): `masses` with the payload `(mass, position in
/// the last link's frame)` folded into the last link, all scaled by the fraction; `None` at
/// the default fraction 1 (the load itself).
pub fn reflected_masses(
    compliance: &ComplianceEffect,
    masses: &[LinkMass],
    payload: Option<(f64, Point3<f64>)>,
) -> Option<Vec<LinkMass>> {
    let f = compliance.reflected_fraction;
    if is_one(&f) {
        return None;
    }
    let mut out: Vec<LinkMass> = masses.to_vec();
    if let (Some((mass_kg, at)), Some(last)) = (payload, out.last_mut()) {
        last.mass_kg += mass_kg;
        last.first_moment_kg_m += at.coords * mass_kg;
    }
    for m in &mut out {
        m.mass_kg *= f;
        m.first_moment_kg_m *= f;
    }
    Some(out)
}

/// Calls `f` with the load the simulators put on compliant joints: `masses` and `payload`
/// under `compliance` through `couplings`, the mechanisms reflecting the
/// `reflected_fraction` of it ([`reflected_masses`]).
pub fn with_simulated_load<R>(
    masses: &[LinkMass],
    payload: Option<(f64, Point3<f64>)>,
    compliance: &ComplianceEffect,
    couplings: &[PassiveSlope],
    f: impl FnOnce(&CompliantLoad) -> R,
) -> R {
    let reflected = reflected_masses(compliance, masses, payload);
    f(&CompliantLoad {
        masses,
        payload,
        compliance,
        couplings,
        reflected_masses: reflected.as_deref(),
    })
}

/// What joint `k`'s (0-based) balancer takes off its actuator: `balancer_fraction[k]` of the
/// gravity torque of link `k`'s own mass about the joint \[N m\]; 0 without one.
fn balancer_torque_nm(
    model: &PhiModel,
    poses: &ChainPoses,
    masses: &[LinkMass],
    compliance: &ComplianceEffect,
    k: usize,
) -> f64 {
    let fraction = compliance.balancer_fraction.get(k).copied().unwrap_or(0.0);
    if fraction == 0.0 || k >= masses.len() {
        return 0.0;
    }
    let own: Vec<LinkMass> = (0..masses.len())
        .map(|i| if i == k { masses[i] } else { LinkMass::default() })
        .collect();
    fraction * gravity_torques_at_nm(model, poses, &own, None, compliance.gravity_m_s2)[k]
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
    /// The masses whose load a mechanism coupling reflects to the actuator below (`None`:
    /// `masses`): a load path other than the rigid mechanism's.
    pub reflected_masses: Option<&'a [LinkMass]>,
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
/// Measured against the rapier arm (`tests/it/effects.rs`, joint 2 at 2e3 N m/rad): 0.8 % off
/// rapier's joint-2 sag where the first order is 11.5 % off (the rest is a near-constant 2 %
/// more load in rapier: the four-bar bodies' own weight). The diagnoser's compliance candidate
/// uses it; the analytic arm (`sim::AnalyticArm`) keeps the first order (the two agree to about
/// `K^-1 dQ/dq`, a few per cent of the sag at the blind suite's stiffnesses).
pub fn coupled_static_deflection(
    model: &PhiModel,
    q: &[f64],
    load: &CompliantLoad,
) -> Result<Vec<f64>, DeflectionError> {
    let mut dq = vec![0.0; q.len()];
    let mut last_step = f64::INFINITY;
    let mut contraction = 0.0;
    for step in 1..=STATIC_DEFLECTION_MAX_STEPS {
        let deflected: Vec<f64> = q.iter().zip(&dq).map(|(a, d)| a + d).collect();
        let next = coupled_first_order_deflection(model, &deflected, load);
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
