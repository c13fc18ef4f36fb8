//! The candidate effects: families of shapes, one member per shape (`docs/diagnosis.md`,
//! "Candidate families"). A real robot's effect matches no single parametric shape, so each
//! kind of effect is a family whose members cover the shapes it takes: harmonic orders and
//! periods, rotating and fixed-direction tilts, mass models of the gravity load, where the
//! spring sits, whose direction signs a backlash, uniform or per-link expansion.

use super::poses::Pose;
use crate::kinematics::JointKind;
use crate::physics::{ApproachSource, HarmonicPeriod};
use crate::robot::{CouplingFitForm, RobotDescription, TransmissionFitForm};
use serde::{Deserialize, Serialize};

pub use crate::robot::SpringSite;

/// How the gravity load of the links beyond a compliant actuator reaches it where its joint
/// drives a mechanism coupling (a four-bar, fitted in the fractional form) into the next
/// joint. A real arm's load path depends on its mechanism (where the forearm's weight is
/// carried, counterweights, a second actuator's bearing), so the family does not assume one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum LoadPath {
    /// Serially: the actuator carries the gravity torque about its own joint of every link
    /// beyond it, their own moments included; nothing is reflected. The only path of a joint
    /// that drives no mechanism, and of a spring in the joint itself.
    Serial,
    /// Through the mechanism (virtual work of a rigid four-bar): the joint's gravity torque
    /// plus the coupling's slope times the driven joint's.
    Mechanism,
    /// Both with independent loads: the serial torque of one set of masses plus the slope
    /// times the driven joint's torque of another (the mechanism carries part of the load).
    Mixed,
}

/// What the gravity load of a compliance candidate is made of.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum MassModel {
    /// The description's link masses and each pose's payload at the tool frame's origin; one
    /// parameter, the compliance (reported with the stiffness).
    Description,
    /// As `Description`, plus the payload's centre of mass offset from the tool frame's origin
    /// (three more parameters, products of compliance and offset): only when payloads vary.
    PayloadOffset,
    /// No mass trusted: per link beyond the joint its mass and first moment, and the
    /// payload's compliance and offset, each times the compliance (the identifiable products
    /// of stiffness and mass moments, Khalil & Dombre, *Modeling, Identification and Control
    /// of Robots*, sec. 14.3: the gravity torque is linear in them).
    Lumped,
}

/// Which links a thermal candidate expands.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ThermalLinks {
    /// Every row by one coefficient.
    Uniform,
    /// Each row long enough to show it ([`MIN_THERMAL_ROW_M`]) by its own coefficient.
    PerLink,
}

/// The shape of a tilt candidate ([`crate::physics::AxisTiltSeries`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum TiltShape {
    /// A tilt whose direction turns `order` times per joint turn: two parameters.
    Rotating,
    /// The general tilt of its order: rotating, counter-rotating, about a fixed direction
    /// (swash) or any sum of these; four parameters.
    General,
}

/// A row of the phi-model shorter than this \[m\] is left out of the per-link thermal
/// candidate: at the largest plausible expansion (`MAX_ALPHA_PER_K`, 1e-4 /K) over a 20 K
/// range it moves its frames by under 10 micrometres, a twentieth of the instruments' noise,
/// so its coefficient could only be fitted to noise.
pub const MIN_THERMAL_ROW_M: f64 = 0.05;

/// Default highest harmonic order of the gear-harmonic family.
pub const DEFAULT_MAX_HARMONIC_ORDER: usize = 8;

/// A candidate unmodelled effect: a member of a family (`docs/formats.md#diagnosis-json`
/// names the families).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "effect", rename_all = "snake_case")]
pub enum Candidate {
    /// Joint `joint` sags under gravity by the static equilibrium `K dq = tau(q + dq)`
    /// ([`crate::physics::coupled_static_deflection`]), `tau` the gravity load of `masses`
    /// about it (plus, with the spring in the actuator, what a four-bar reflects).
    JointCompliance {
        /// 1-based joint.
        joint: usize,
        /// Where the spring sits.
        spring: SpringSite,
        /// What loads it.
        masses: MassModel,
        /// How the load of the links beyond reaches the spring.
        load: LoadPath,
    },
    /// The active displacement of `joint` lags by `h` against its approach direction (half
    /// band `h` \[rad\]), the direction of the command or of the actuator command.
    Backlash {
        /// 1-based joint.
        joint: usize,
        /// Whose direction signs the lag.
        direction: ApproachSource,
    },
    /// Row lengths `a`, `b` scale by `1 + alpha (T - T_ref)`, `T_ref` the axis experiments'
    /// mean temperature.
    ThermalExpansion {
        /// One coefficient or one per row.
        links: ThermalLinks,
    },
    /// An extra harmonic (sin, cos \[rad\]) of order `order` in the transmission's angle
    /// (eq. 8; the orders the calibrator does not fit) or in the joint's own.
    GearHarmonic {
        /// 1-based joint.
        joint: usize,
        /// Harmonic order.
        order: usize,
        /// The angle it is periodic in.
        period: HarmonicPeriod,
    },
    /// A tilt of the joint's axis varying `order` times per joint turn
    /// ([`crate::physics::AxisTiltSeries`]).
    AxisWobble {
        /// 1-based joint.
        joint: usize,
        /// Order (1 or 2).
        order: i32,
        /// Rotating or general.
        shape: TiltShape,
    },
    /// Measured coordinates `(1 + ppm 1e-6)` times the true ones about the instrument origin.
    InstrumentScale,
}

/// What the parameter layout of a candidate depends on besides the candidate: the joint count
/// and the rows of the per-link thermal candidate.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelShape {
    /// Number of joints.
    pub dof: usize,
    /// Rows (0-based) of the per-link thermal candidate.
    pub thermal_rows: Vec<usize>,
}

impl ModelShape {
    /// The shape of `desc`'s model.
    pub fn of(desc: &RobotDescription) -> Self {
        ModelShape {
            dof: desc.dof(),
            thermal_rows: desc
                .rows
                .iter()
                .enumerate()
                .filter(|(_, r)| r.a_m.hypot(r.b_m) >= MIN_THERMAL_ROW_M)
                .map(|(k, _)| k)
                .collect(),
        }
    }
}

/// The lowest transmission harmonic of `joint` (1-based) that the calibrator does NOT fit:
/// one above the order of the joint's declared `transmission_fit` (eq. 8), in the
/// transmission's own angle (the gear angle for a gear form). An extra harmonic of a fitted
/// order would be a calibration error, not an unmodelled effect.
pub fn unmodelled_harmonic_order(desc: &RobotDescription, joint: usize) -> usize {
    match desc
        .joints
        .get(joint.wrapping_sub(1))
        .map(|j| j.transmission_fit_form())
    {
        Some(
            TransmissionFitForm::Harmonic { order }
            | TransmissionFitForm::Gear { order, .. }
            | TransmissionFitForm::Polynomial { order },
        ) => order + 1,
        None => 1,
    }
}

/// Whether `joint` (1-based) is geared: its transmission fit is periodic in a gear angle, not
/// in the joint's own.
pub fn is_geared(desc: &RobotDescription, joint: usize) -> bool {
    matches!(
        desc.joints
            .get(joint.wrapping_sub(1))
            .map(|j| j.transmission_fit_form()),
        Some(TransmissionFitForm::Gear { .. })
    )
}

/// Whether `joint` (1-based) drives a mechanism coupling (fitted in the fractional form) into
/// the next joint: the only joints with a [`LoadPath`] to choose.
pub fn drives_mechanism(desc: &RobotDescription, joint: usize) -> bool {
    desc.couplings
        .iter()
        .any(|c| c.from == joint && c.fit == Some(CouplingFitForm::Fractional))
}

/// The parameter names of one load of a compliance member, `prefix` after `compliance_`
/// (`""` for the serial load, `"reflected_"` for a mixed path's reflected one): with the
/// description's masses one compliance (and the payload offset's products); lumped, per link
/// `first_link..=dof` its mass and first moment, then the payload's compliance and offset,
/// each times the compliance.
fn load_names(masses: MassModel, prefix: &str, first_link: usize, dof: usize) -> Vec<String> {
    let offset = || ["x", "y", "z"].map(|a| format!("compliance_{prefix}payload_offset_{a}_m_rad_per_nm"));
    let mut out = Vec::new();
    match masses {
        MassModel::Description => out.push(format!("compliance_{prefix}rad_per_nm")),
        MassModel::PayloadOffset => {
            out.push(format!("compliance_{prefix}rad_per_nm"));
            out.extend(offset());
        }
        MassModel::Lumped => {
            for link in first_link..=dof {
                out.push(format!("compliance_{prefix}mass_link{link}_kg_rad_per_nm"));
                for axis in ["x", "y", "z"] {
                    out.push(format!("compliance_{prefix}moment_link{link}_{axis}_kg_m_rad_per_nm"));
                }
            }
            out.push(format!("compliance_{prefix}payload_rad_per_nm"));
            out.extend(offset());
        }
    }
    out
}

/// Number of parameters of a compliance member's serial load ([`load_names`] without a
/// prefix): the reflected load's, for a mixed path, follow them.
pub fn serial_load_count(masses: MassModel, joint: usize, dof: usize) -> usize {
    load_names(masses, "", joint, dof).len()
}

impl Candidate {
    /// The family's effect name of `diagnosis.json` (`docs/formats.md#diagnosis-json`).
    pub fn effect_name(&self) -> &'static str {
        match self {
            Candidate::JointCompliance { .. } => "joint_compliance",
            Candidate::Backlash { .. } => "backlash",
            Candidate::ThermalExpansion { .. } => "thermal_expansion",
            Candidate::GearHarmonic { .. } => "gear_harmonic",
            Candidate::AxisWobble { .. } => "axis_wobble",
            Candidate::InstrumentScale => "instrument_scale",
        }
    }

    /// The member's name within its family (`docs/diagnosis.md`), e.g.
    /// `order_3_transmission_period`.
    pub fn member_name(&self) -> String {
        match *self {
            Candidate::JointCompliance {
                spring, masses, load, ..
            } => {
                format!(
                    "{}_spring_{}_load_{}",
                    spring_name(spring),
                    load_name(load),
                    masses_name(masses)
                )
            }
            Candidate::Backlash { direction, .. } => format!("{}_direction", direction_name(direction)),
            Candidate::ThermalExpansion {
                links: ThermalLinks::Uniform,
            } => "uniform".into(),
            Candidate::ThermalExpansion {
                links: ThermalLinks::PerLink,
            } => "per_link".into(),
            Candidate::GearHarmonic { order, period, .. } => format!("order_{order}_{}_period", period_name(period)),
            Candidate::AxisWobble { order, shape, .. } => format!(
                "order_{order}_{}",
                match shape {
                    TiltShape::Rotating => "rotating",
                    TiltShape::General => "general",
                }
            ),
            Candidate::InstrumentScale => "uniform".into(),
        }
    }

    /// The joint, or `None` for whole-robot and instrument effects.
    pub fn joint(&self) -> Option<usize> {
        match *self {
            Candidate::JointCompliance { joint, .. }
            | Candidate::Backlash { joint, .. }
            | Candidate::GearHarmonic { joint, .. }
            | Candidate::AxisWobble { joint, .. } => Some(joint),
            Candidate::ThermalExpansion { .. } | Candidate::InstrumentScale => None,
        }
    }

    /// Whether `other` is of the same kind: the same family on the same joint.
    pub fn same_kind(&self, other: &Candidate) -> bool {
        self.effect_name() == other.effect_name() && self.joint() == other.joint()
    }

    /// Names (with units) of the member's parameters.
    pub fn parameter_names(&self, shape: &ModelShape) -> Vec<String> {
        let owned = |v: &[&str]| v.iter().map(|s| (*s).to_owned()).collect();
        match self {
            Candidate::JointCompliance {
                masses, joint, load, ..
            } => {
                let mut v = load_names(*masses, "", *joint, shape.dof);
                if *load == LoadPath::Mixed {
                    v.extend(load_names(*masses, "reflected_", joint + 1, shape.dof));
                }
                v
            }
            Candidate::Backlash { .. } => owned(&["half_band_rad"]),
            Candidate::ThermalExpansion {
                links: ThermalLinks::Uniform,
            } => owned(&["alpha_per_k"]),
            Candidate::ThermalExpansion {
                links: ThermalLinks::PerLink,
            } => shape
                .thermal_rows
                .iter()
                .map(|r| format!("alpha_row{}_per_k", r + 1))
                .collect(),
            Candidate::GearHarmonic { .. } => owned(&["sin_rad", "cos_rad"]),
            Candidate::AxisWobble {
                shape: TiltShape::Rotating,
                ..
            } => owned(&["tilt_x_rad", "tilt_y_rad"]),
            Candidate::AxisWobble {
                shape: TiltShape::General,
                ..
            } => owned(&["tilt_cos_x_rad", "tilt_cos_y_rad", "tilt_sin_x_rad", "tilt_sin_y_rad"]),
            Candidate::InstrumentScale => owned(&["scale_ppm"]),
        }
    }

    /// Finite-difference steps of the parameters: small enough that the model is linear in
    /// them to rounding (sags and tilts of 1e-6 to 1e-5 rad), large enough for central
    /// differences to resolve.
    pub fn steps(&self, shape: &ModelShape) -> Vec<f64> {
        let n = self.parameter_names(shape).len();
        let step = match self {
            // Compliance products: a 1e-8 rad/(N m) compliance under 100 N m sags 1e-6 rad;
            // mass and moment products 1e-7 kg rad/(N m) under 9.81 m/s^2 and a 1 m lever too.
            Candidate::JointCompliance {
                masses: MassModel::Description | MassModel::PayloadOffset,
                ..
            } => 1e-8,
            Candidate::JointCompliance { .. } => 1e-7,
            Candidate::InstrumentScale => 10.0,
            _ => 1e-5,
        };
        vec![step; n]
    }

    /// Every member of every family for a robot of `desc` measured at `poses` (module docs of
    /// [`crate::diagnosis`]): per revolute joint the compliance members (three mass models,
    /// two spring sites on a joint that drives a coupling; the payload offset only when
    /// payloads vary), backlash signed by the command and, where it differs over the poses,
    /// by the actuator (only when the joint's approach direction changes), the gear harmonics
    /// from the first unfitted order to `max_harmonic_order` in the transmission's angle and,
    /// for a geared joint, from order 1 in the joint's own, the wobbles of order 1 (general)
    /// and 2 (rotating and general); thermal expansion uniform and per link only when the
    /// validation temperatures differ; the instrument scale.
    pub fn library(desc: &RobotDescription, poses: &[Pose], max_harmonic_order: usize) -> Vec<Candidate> {
        let varies = |f: &dyn Fn(&Pose) -> f64| {
            let first = poses.first().map_or(0.0, f);
            // Copied file values: any difference at all is a variation.
            poses.iter().any(|p| f(p).to_bits() != first.to_bits())
        };
        let payload_varies = varies(&|p| p.payload_kg);
        let mut out = Vec::new();
        for (k, j) in desc.joints.iter().enumerate() {
            if j.kind != JointKind::Revolute {
                continue;
            }
            let joint = k + 1;
            out.extend(compliance_members(desc, joint, payload_varies));
            out.extend(backlash_members(poses, joint));
            out.extend(harmonic_members(desc, joint, max_harmonic_order));
            for (order, shape) in [
                (1, TiltShape::General),
                (2, TiltShape::Rotating),
                (2, TiltShape::General),
            ] {
                out.push(Candidate::AxisWobble { joint, order, shape });
            }
        }
        if varies(&|p| p.temperature_c) {
            out.push(Candidate::ThermalExpansion {
                links: ThermalLinks::Uniform,
            });
            if ModelShape::of(desc).thermal_rows.len() >= 2 {
                out.push(Candidate::ThermalExpansion {
                    links: ThermalLinks::PerLink,
                });
            }
        }
        out.push(Candidate::InstrumentScale);
        out
    }
}

/// The compliance members of `joint`: per mass model (the payload offset only when payloads
/// vary) the spring in the actuator, along each load path where the joint drives a mechanism
/// ([`drives_mechanism`]; the mixed path with the description's masses or lumped, not with
/// the payload offset), and on a joint that drives a coupling the spring in the joint.
fn compliance_members(desc: &RobotDescription, joint: usize, payload_varies: bool) -> Vec<Candidate> {
    let drives_coupling = desc.nominal_coupling_from(joint).is_some();
    let paths: &[LoadPath] = if drives_mechanism(desc, joint) {
        &[LoadPath::Mechanism, LoadPath::Serial, LoadPath::Mixed]
    } else {
        &[LoadPath::Serial]
    };
    let mut out = Vec::new();
    for masses in [MassModel::Description, MassModel::PayloadOffset, MassModel::Lumped] {
        if masses == MassModel::PayloadOffset && !payload_varies {
            continue;
        }
        for &load in paths {
            if !(load == LoadPath::Mixed && masses == MassModel::PayloadOffset) {
                out.push(Candidate::JointCompliance {
                    joint,
                    spring: SpringSite::Actuator,
                    masses,
                    load,
                });
            }
        }
        if drives_coupling {
            out.push(Candidate::JointCompliance {
                joint,
                spring: SpringSite::Joint,
                masses,
                load: LoadPath::Serial,
            });
        }
    }
    out
}

fn backlash_members(poses: &[Pose], joint: usize) -> Vec<Candidate> {
    let k = joint - 1;
    let flips = |dir: &dyn Fn(&Pose) -> f64| poses.iter().any(|p| dir(p) > 0.0) && poses.iter().any(|p| dir(p) < 0.0);
    let mut out = Vec::new();
    if flips(&|p| p.approach[k]) {
        out.push(Candidate::Backlash {
            joint,
            direction: ApproachSource::Command,
        });
    }
    // Directions are exactly -1, 0 or 1.
    let differs = poses
        .iter()
        .any(|p| p.actuator_approach[k].to_bits() != p.approach[k].to_bits());
    if differs && flips(&|p| p.actuator_approach[k]) {
        out.push(Candidate::Backlash {
            joint,
            direction: ApproachSource::Actuator,
        });
    }
    out
}

fn harmonic_members(desc: &RobotDescription, joint: usize, max_order: usize) -> Vec<Candidate> {
    let mut out: Vec<Candidate> = (unmodelled_harmonic_order(desc, joint)..=max_order)
        .map(|order| Candidate::GearHarmonic {
            joint,
            order,
            period: HarmonicPeriod::Transmission,
        })
        .collect();
    if is_geared(desc, joint) {
        out.extend((1..=max_order).map(|order| Candidate::GearHarmonic {
            joint,
            order,
            period: HarmonicPeriod::Joint,
        }));
    }
    out
}

fn spring_name(s: SpringSite) -> &'static str {
    match s {
        SpringSite::Actuator => "actuator",
        SpringSite::Joint => "joint",
    }
}

fn load_name(l: LoadPath) -> &'static str {
    match l {
        LoadPath::Serial => "serial",
        LoadPath::Mechanism => "mechanism",
        LoadPath::Mixed => "mixed",
    }
}

fn masses_name(m: MassModel) -> &'static str {
    match m {
        MassModel::Description => "description_masses",
        MassModel::PayloadOffset => "payload_offset",
        MassModel::Lumped => "lumped_moments",
    }
}

fn direction_name(d: ApproachSource) -> &'static str {
    match d {
        ApproachSource::Command => "command",
        ApproachSource::Actuator => "actuator",
    }
}

fn period_name(p: HarmonicPeriod) -> &'static str {
    match p {
        HarmonicPeriod::Transmission => "transmission",
        HarmonicPeriod::Joint => "joint",
    }
}
