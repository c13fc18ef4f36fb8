//! Unmodelled effects of the simulated real robot and instrument: what the calibration model
//! (paper sections 3-4) leaves out, each switched on by the presence of its table in an
//! effects file (TOML, `deny_unknown_fields`, units in key names).
//!
//! | table | effect | applied to |
//! |---|---|---|
//! | `compliance` | actuator stiffness `K_k` \[N m/rad\] under gravity: `K da = Q_gravity(q)`, the sag `da` driving the passive couplings; the part of a four-bar's load it reflects and any spring balancers | joint values (rapier: static equilibrium, four-bar as bodies; analytic: first order, [`coupled_first_order_deflection`]; exact equilibrium of the same model: [`coupled_static_deflection`]) |
//! | `payload` | the pose's `payload_kg` (from [`PoseConditions`]) at a point of the tool frame | the gravity load of `compliance` (no effect without it) |
//! | `backlash` | dead band `b_k` \[rad\]: the joint lags `b_k / 2` behind its approach direction | active displacements |
//! | `thermal` | link growth: rows' `a`, `b` scaled by `1 + alpha (T - T_ref)` | the phi-model |
//! | `gear_harmonics` | extra harmonic terms of a joint's transmission (eq. 8) | the truth's transmissions |
//! | `wobble` | bearing runout: a tilt of the joint axis that turns with the joint | link poses |
//! | `instrument_scale` | a scale error of the instrument about its origin \[ppm\] | measured coordinates |
//! | `link_masses` | the real links' masses and centres of mass (default: the description's) | the gravity load of `compliance` (and the rapier bodies) |
//!
//! [`JointDriver`] runs the joint-side effects for any [`ArmExecutor`](super::ArmExecutor):
//! commands -> fig. 3 controller -> actuators with the truth's transmissions (plus gear
//! harmonics) and backlash -> passive couplings -> repeatability jitter.

use crate::kinematics::PhiModel;
use crate::measurement::format_f64;
use crate::physics::{
    AxisWobble, BacklashEffect, ComplianceEffect, GearHarmonic, InstrumentScale, LinkMass, PayloadEffect,
    ThermalEffect, apply_wobble, with_gear_harmonics,
};
use crate::plan::PoseConditions;
use crate::robot::{RobotDescription, RobotModel};
use nalgebra::{Isometry3, Point3};
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
    /// [`EffectsError::Invalid`] in a file.
    #[error("{path}: effects field `{field}`: {message}")]
    InvalidIn {
        /// The effects file.
        path: std::path::PathBuf,
        /// The key.
        field: String,
        /// What is wrong.
        message: String,
    },
}

/// Physical ranges of the effects (beyond them a value is a slip, not an effect): the small-angle
/// forms hold up to [`MAX_SMALL_ANGLE_RAD`].
pub const MAX_SMALL_ANGLE_RAD: f64 = 0.1;
/// Largest thermal expansion coefficient accepted \[1/K\] (metals 1e-5 to 3e-5, plastics 2e-4).
pub const MAX_ALPHA_PER_K: f64 = 1e-3;
/// Largest instrument scale error accepted \[ppm\] (1 %).
pub const MAX_SCALE_PPM: f64 = 1e4;
/// Largest order of a gear harmonic or a wobble (turns per turn of its angle): a gear's
/// tooth-mesh error repeats a few hundred times a turn at most
/// ([`crate::robot::MAX_HARMONIC_ORDER`], the bound of a description's fitted orders too). A
/// harmonic's order also sizes its transmission's coefficient lists (one entry per order).
pub const MAX_EFFECT_ORDER: usize = crate::robot::MAX_HARMONIC_ORDER;

/// The unmodelled effects (module docs); every table is optional and off when absent.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
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
    /// The real links' masses, one per joint (default, empty: the description's): the
    /// simulated robot's mass distribution need not be the one the description guesses.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub link_masses: Vec<LinkMassEntry>,
}

/// The mass of one real link, as [`Effects::link_masses`] gives it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LinkMassEntry {
    /// \[kg\], > 0.
    pub mass_kg: f64,
    /// Centre of mass in the link's moving frame \[mm\].
    pub com_mm: [f64; 3],
}

/// Checks a per-row list (one value per link between two joints): `dof - 1` finite values.
fn per_joint_minus_one(field: &str, v: &[f64], dof: usize) -> Result<(), EffectsError> {
    let rows = dof.saturating_sub(1);
    if v.len() != rows {
        return Err(invalid(
            field,
            format!("needs {rows} values (one per row), found {}", v.len()),
        ));
    }
    match v.iter().position(|x| !x.is_finite()) {
        Some(k) => Err(invalid(
            format!("{field}[{k}]"),
            format!("bad value {}", format_f64(v[k])),
        )),
        None => Ok(()),
    }
}

/// Checks a per-joint list: `dof` values, each `ok`.
fn per_joint(field: &str, v: &[f64], dof: usize, ok: fn(f64) -> bool) -> Result<(), EffectsError> {
    if v.len() != dof {
        return Err(invalid(field, format!("needs {dof} values, found {}", v.len())));
    }
    match v.iter().position(|x| !ok(*x)) {
        Some(k) => Err(invalid(
            format!("{field}[{k}]"),
            format!("bad value {}", format_f64(v[k])),
        )),
        None => Ok(()),
    }
}

/// Joint `joint` of the entry at `field` is one of the robot's `1..=dof`.
fn joint_in(field: String, joint: usize, dof: usize) -> Result<(), EffectsError> {
    if joint == 0 || joint > dof {
        Err(invalid(field, format!("joint {joint} is not in 1..={dof}")))
    } else {
        Ok(())
    }
}

/// Checks `[[gear_harmonics]]` entry `i`: its joint, its order within [`MAX_EFFECT_ORDER`],
/// its coefficients within [`MAX_SMALL_ANGLE_RAD`], and its slope (order times amplitude)
/// below 1, so that the angle it is added to still turns one way.
fn check_gear_harmonic(h: &GearHarmonic, i: usize, dof: usize) -> Result<(), EffectsError> {
    let field = |key: &str| format!("gear_harmonics[{i}].{key}");
    joint_in(field("joint"), h.joint, dof)?;
    if !(1..=MAX_EFFECT_ORDER).contains(&h.order) {
        return Err(invalid(
            field("order"),
            format!(
                "{} must be in 1..={MAX_EFFECT_ORDER} (a gear's error repeats at most a few hundred times a turn)",
                h.order
            ),
        ));
    }
    for (key, v) in [("sin_rad", h.sin_rad), ("cos_rad", h.cos_rad)] {
        if !(v.is_finite() && v.abs() <= MAX_SMALL_ANGLE_RAD) {
            return Err(invalid(
                field(key),
                format!("{} must be within +-{MAX_SMALL_ANGLE_RAD} rad", format_f64(v)),
            ));
        }
    }
    let slope = h.order as f64 * h.sin_rad.hypot(h.cos_rad);
    if slope >= 1.0 {
        return Err(invalid(
            format!("gear_harmonics[{i}]"),
            format!(
                "order {} times the amplitude {} rad is a slope of {}: the angle would turn back (it must stay below 1); \
                 lower the order or the coefficients",
                h.order,
                format_f64(h.sin_rad.hypot(h.cos_rad)),
                format_f64(slope)
            ),
        ));
    }
    Ok(())
}

/// Checks `[[wobble]]` entry `i`: its joint, its order within +-[`MAX_EFFECT_ORDER`], a small
/// amplitude and a finite phase.
fn check_wobble(w: &AxisWobble, i: usize, dof: usize) -> Result<(), EffectsError> {
    joint_in(format!("wobble[{i}].joint"), w.joint, dof)?;
    if w.order.unsigned_abs() as usize > MAX_EFFECT_ORDER {
        return Err(invalid(
            format!("wobble[{i}].order"),
            format!(
                "{} must be within +-{MAX_EFFECT_ORDER} (a bearing's runout turns a few times a turn at most)",
                w.order
            ),
        ));
    }
    if !(w.amplitude_rad.is_finite() && w.amplitude_rad.abs() <= MAX_SMALL_ANGLE_RAD) {
        return Err(invalid(
            format!("wobble[{i}].amplitude_rad"),
            format!(
                "{} must be within +-{MAX_SMALL_ANGLE_RAD} rad (a bearing runout is a small tilt)",
                format_f64(w.amplitude_rad)
            ),
        ));
    }
    if !w.phase_rad.is_finite() {
        return Err(invalid(format!("wobble[{i}].phase_rad"), "must be finite"));
    }
    Ok(())
}

/// Checks the `[compliance]` table against a robot of `dof` joints.
fn check_compliance(c: &ComplianceEffect, dof: usize) -> Result<(), EffectsError> {
    per_joint("compliance.stiffness_nm_per_rad", &c.stiffness_nm_per_rad, dof, |x| {
        x.is_finite() && x > 0.0
    })?;
    if !c.gravity_m_s2.iter().all(|g| g.is_finite()) {
        return Err(invalid("compliance.gravity_m_s2", "must be finite"));
    }
    if !(0.0..=1.0).contains(&c.reflected_fraction) {
        return Err(invalid(
            "compliance.reflected_fraction",
            format!("bad value {}; must be in 0-1", format_f64(c.reflected_fraction)),
        ));
    }
    if c.balancer_fraction.is_empty() {
        return Ok(());
    }
    per_joint("compliance.balancer_fraction", &c.balancer_fraction, dof, |x| {
        (0.0..=1.0).contains(&x)
    })
    .map_err(|e| with_range(e, "in 0-1"))
}

/// `e` with the accepted range appended to its message.
fn with_range(e: EffectsError, range: &str) -> EffectsError {
    match e {
        EffectsError::Invalid { field, message } => invalid(field, format!("{message}; must be {range}")),
        other => other,
    }
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
        e.validate(dof).map_err(|err| match err {
            EffectsError::Invalid { field, message } => EffectsError::InvalidIn {
                path: path.to_owned(),
                field,
                message,
            },
            other => other,
        })?;
        Ok(e)
    }

    /// Checks lengths, ranges and joint numbers against a robot of `dof` joints.
    pub fn validate(&self, dof: usize) -> Result<(), EffectsError> {
        let per_joint = |field: &str, v: &[f64], ok: fn(f64) -> bool| per_joint(field, v, dof, ok);
        if let Some(c) = &self.compliance {
            check_compliance(c, dof)?;
        }
        if let Some(p) = &self.payload
            && !p.com_in_tool_mm.iter().all(|x| x.is_finite())
        {
            return Err(invalid("payload.com_in_tool_mm", "must be finite"));
        }
        if let Some(b) = &self.backlash {
            per_joint("backlash.band_rad", &b.band_rad, |x| {
                x.is_finite() && (0.0..=MAX_SMALL_ANGLE_RAD).contains(&x)
            })
            .map_err(|e| with_range(e, "in 0..=0.1 rad"))?;
        }
        if let Some(t) = &self.thermal {
            if !(t.alpha_per_k.is_finite() && t.alpha_per_k.abs() <= MAX_ALPHA_PER_K) {
                return Err(invalid(
                    "thermal.alpha_per_k",
                    format!(
                        "{} must be finite and within +-{MAX_ALPHA_PER_K} 1/K (steel: 1.2e-5)",
                        format_f64(t.alpha_per_k)
                    ),
                ));
            }
            if !(t.reference_c.is_finite() && t.reference_c > -273.15) {
                return Err(invalid(
                    "thermal.reference_c",
                    "must be a temperature above absolute zero",
                ));
            }
            if !t.alpha_per_k_rows.is_empty() {
                per_joint_minus_one("thermal.alpha_per_k_rows", &t.alpha_per_k_rows, dof)?;
            }
        }
        self.validate_link_masses(dof)?;
        for (i, h) in self.gear_harmonics.iter().enumerate() {
            check_gear_harmonic(h, i, dof)?;
        }
        for (i, w) in self.wobble.iter().enumerate() {
            check_wobble(w, i, dof)?;
        }
        if let Some(s) = &self.instrument_scale
            && !(s.ppm.is_finite() && s.ppm.abs() <= MAX_SCALE_PPM)
        {
            return Err(invalid(
                "instrument_scale.ppm",
                format!("{} must be within +-{MAX_SCALE_PPM} ppm (1 %)", format_f64(s.ppm)),
            ));
        }
        Ok(())
    }

    /// Checks `link_masses`: none, or one positive mass and finite centre per joint.
    fn validate_link_masses(&self, dof: usize) -> Result<(), EffectsError> {
        if self.link_masses.is_empty() {
            return Ok(());
        }
        if self.link_masses.len() != dof {
            return Err(invalid(
                "link_masses",
                format!("needs {dof} entries, found {}", self.link_masses.len()),
            ));
        }
        for (k, m) in self.link_masses.iter().enumerate() {
            if !(m.mass_kg.is_finite() && m.mass_kg > 0.0) {
                return Err(invalid(
                    format!("link_masses[{k}].mass_kg"),
                    format!("bad value {}", format_f64(m.mass_kg)),
                ));
            }
            if !m.com_mm.iter().all(|x| x.is_finite()) {
                return Err(invalid(format!("link_masses[{k}].com_mm"), "must be finite"));
            }
        }
        Ok(())
    }

    /// The real links' masses: [`Effects::link_masses`], or `desc`'s when none are given.
    pub fn truth_link_masses(&self, desc: &RobotDescription) -> Vec<LinkMassEntry> {
        if self.link_masses.is_empty() {
            desc.joints
                .iter()
                .map(|j| LinkMassEntry {
                    mass_kg: j.mass_kg,
                    com_mm: j.com_mm,
                })
                .collect()
        } else {
            self.link_masses.clone()
        }
    }

    /// [`Effects::truth_link_masses`] as the gravity model's [`LinkMass`]es.
    pub fn truth_gravity_masses(&self, desc: &RobotDescription) -> Vec<LinkMass> {
        self.truth_link_masses(desc)
            .iter()
            .map(|m| LinkMass::at(m.mass_kg, Point3::from(m.com_mm) * 1e-3))
            .collect()
    }

    /// `truth` with the extra gear harmonics added to its transmissions.
    pub fn truth_with_harmonics(&self, truth: &RobotModel) -> RobotModel {
        with_gear_harmonics(truth, &self.gear_harmonics)
    }

    /// The phi-model at temperature `temperature_c` ([`ThermalEffect::expanded`]; unchanged
    /// without a thermal effect).
    pub fn thermal_model(&self, model: &PhiModel, temperature_c: f64) -> PhiModel {
        self.expanded_model(model, temperature_c)
            .unwrap_or_else(|| model.clone())
    }

    /// [`Effects::thermal_model`] when it differs from `model` (a thermal effect in force).
    pub fn expanded_model(&self, model: &PhiModel, temperature_c: f64) -> Option<PhiModel> {
        self.thermal.as_ref().map(|t| t.expanded(model, temperature_c))
    }

    /// Applies the axis wobbles to link poses computed without them ([`apply_wobble`]).
    pub fn apply_wobble(&self, model: &PhiModel, q: &[f64], links: &mut [Isometry3<f64>]) {
        apply_wobble(&self.wobble, model, q, links);
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
