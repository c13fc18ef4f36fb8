//! The robot description file (TOML): joint kinds, phi angles, nominal phi-model rows,
//! nominal couplings, joint limits, link masses, calibration and tool targets.
//!
//! Units in the file are those engineers read off drawings (mm, deg, kg); inside, everything
//! is SI with angles in radians. See `scenarios/robots/asea-irb6l.toml` for a documented example.

mod identity;
mod validate;
pub use validate::{
    MAX_ANGLE_DEG, MAX_GEAR_RATIO, MAX_HARMONIC_ORDER, MAX_INSTRUMENT_FRAME_MM, MAX_REPEATABILITY_SIGMA,
    MIN_STATION_DISTANCE_MM, angle_deg_problem, station_problem,
};

mod convert;
mod instrument;
mod urdf_text;

pub use identity::DescriptionIdentity;
pub(crate) use identity::Fnv;
pub use instrument::InstrumentEntry;

use crate::kinematics::{JointKind, PhiJoint, PhiModel, PhiRow, SourceChain};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A problem with a robot description file.
#[derive(Debug, thiserror::Error)]
pub enum DescriptionError {
    /// The file could not be read or parsed.
    #[error(transparent)]
    File(#[from] crate::toml_file::TomlFileError),
    /// A value is out of range or inconsistent with the rest.
    #[error("{path}: field `{field}`: {message}")]
    Invalid {
        /// The file (or `<string>`).
        path: PathBuf,
        /// The offending key, e.g. `rows\[2\].alpha_deg`.
        field: String,
        /// What is wrong.
        message: String,
    },
}

/// One joint as written in the file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct JointEntry {
    /// `revolute` or `prismatic`.
    pub kind: JointKind,
    /// The phi angle of eq. (A2) \[deg\].
    #[serde(default)]
    pub phi_deg: f64,
    /// Lower and upper joint limit \[deg\] (revolute) or \[mm\] (prismatic).
    pub limits: [f64; 2],
    /// Mass of the link this joint moves \[kg\]; default 0 (needed only where gravity and
    /// compliance are simulated).
    #[serde(default)]
    pub mass_kg: f64,
    /// Centre of mass of that link in its moving frame \[mm\]; default the origin.
    #[serde(default)]
    pub com_mm: [f64; 3],
    /// The transmission form the calibrator fits; default
    /// [`JointEntry::transmission_fit_form`] (harmonic of order 1 for a revolute joint, a
    /// scale error for a prismatic one).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transmission_fit: Option<TransmissionFitForm>,
    /// The joint's row of a Denavit-Hartenberg table (the description's `dh_convention`);
    /// converted to `phi_deg` and `rows` when the file is read.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dh: Option<DhEntry>,
    /// The robot's known repeatability: standard deviation of the joint-value error drawn
    /// each time the actuator is re-positioned \[rad\] (revolute) or \[m\] (prismatic); finite
    /// and >= 0; default 0 (unknown: the calibrator models measurement noise only). The
    /// calibrator weights its axis fits with it (`calibration::fit_arc_with_angle_noise`).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub repeatability_sigma: f64,
    /// Largest joint speed \[deg/s\] (revolute) or \[mm/s\] (prismatic), from the robot's
    /// data sheet; optional, used by exports (the URDF's `<limit velocity>`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_velocity: Option<f64>,
    /// Largest actuator effort \[N m\] (revolute) or \[N\] (prismatic), from the robot's data
    /// sheet; optional, used by exports (the URDF's `<limit effort>`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_effort: Option<f64>,
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

impl JointEntry {
    /// The transmission form the calibrator fits: the file's `transmission_fit`, else a
    /// harmonic of order 1 (revolute, eq. 8) or a scale error (prismatic, eq. 13).
    pub fn transmission_fit_form(&self) -> TransmissionFitForm {
        self.transmission_fit.unwrap_or(match self.kind {
            JointKind::Revolute => TransmissionFitForm::Harmonic { order: 1 },
            JointKind::Prismatic => TransmissionFitForm::Polynomial { order: 1 },
        })
    }
}

/// One row of a Denavit-Hartenberg table as written in the file (file units).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DhEntry {
    /// Offset along the joint axis \[mm\] (a prismatic joint's command adds to it).
    pub d_mm: f64,
    /// Angle about the joint axis \[deg\] (a revolute joint's command adds to it).
    #[serde(default)]
    pub theta_deg: f64,
    /// Length of the common normal \[mm\].
    pub a_mm: f64,
    /// Twist about the common normal \[deg\].
    pub alpha_deg: f64,
}

/// Which Denavit-Hartenberg convention the `dh` rows follow.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum DhConventionEntry {
    /// Classic DH: `Rz(theta) Tz(d) Tx(a) Rx(alpha)` per joint, joint `i` about `z_{i-1}`.
    Classic,
    /// Modified DH (Craig): `Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(theta_i) Tz(d_i)`, joint `i` about `z_i`.
    Modified,
}

/// A URDF file the joints and geometry come from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct UrdfEntry {
    /// The URDF file, relative to the description file.
    pub file: PathBuf,
    /// The link the chain starts from (default: the URDF's root link).
    #[serde(default)]
    pub base_link: Option<String>,
    /// The link the tool is fixed to (default: the end of the only chain from the base).
    #[serde(default)]
    pub tip_link: Option<String>,
}

/// The form of a joint's transmission function that the calibrator fits (eq. 8).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "form", rename_all = "snake_case", deny_unknown_fields)]
pub enum TransmissionFitForm {
    /// `theta_c = theta_a + sum_k (s_k sin k theta_a + c_k cos k theta_a)`.
    Harmonic {
        /// Number of harmonics (the paper: 1).
        order: usize,
    },
    /// A gear of ratio `N` with harmonics in the gear angle (the paper's joint 5).
    Gear {
        /// Joint turns per gear turn.
        ratio: f64,
        /// Number of harmonics.
        order: usize,
    },
    /// A sliding joint's `S_c = S + sum_k c_k S^k`, `k = 1..order` (eq. 13): order 1 is a
    /// scale error, higher orders its nonlinearity.
    Polynomial {
        /// Highest power.
        order: usize,
    },
}

/// The form of a passive coupling function that the calibrator fits (eq. 15).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "form", rename_all = "snake_case", deny_unknown_fields)]
pub enum CouplingFitForm {
    /// A gear of the nominal ratio with harmonics (the bevel gear 4->5).
    Gear {
        /// Number of harmonics.
        order: usize,
        /// Fit the ratio too (otherwise the nominal slope is kept).
        #[serde(default)]
        fit_ratio: bool,
    },
    /// The paper's fractional four-bar form (2->3).
    Fractional,
}

/// The phi-model of a table as written in a file: each joint's kind and phi \[deg\], the rows,
/// the placement in the instrument frame and the tool frame on the last link.
pub(crate) fn phi_model_of(
    joints: impl Iterator<Item = (JointKind, f64)>,
    rows: &[RowEntry],
    placement: &Placement,
    tool_frame: &Placement,
) -> PhiModel {
    PhiModel {
        joints: joints
            .map(|(kind, phi_deg)| PhiJoint {
                kind,
                phi_rad: phi_deg.to_radians(),
            })
            .collect(),
        rows: rows.iter().map(RowEntry::to_row).collect(),
        world_from_base: placement.to_isometry(),
        last_link_from_tool: tool_frame.to_isometry(),
    }
}

/// One row of Table 2 as written in the file.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RowEntry {
    /// \[m\]
    pub a_m: f64,
    /// \[m\]
    pub b_m: f64,
    /// \[deg\]
    pub alpha_deg: f64,
    /// \[deg\]
    pub beta_deg: f64,
    /// \[deg\], default 0
    #[serde(default)]
    pub gamma_deg: f64,
    /// \[m\], default 0
    #[serde(default)]
    pub h_m: f64,
}

impl RowEntry {
    /// A row in file units from internal units.
    pub fn from_row(r: &PhiRow) -> Self {
        RowEntry {
            a_m: r.a_m,
            b_m: r.b_m,
            alpha_deg: r.alpha_rad.to_degrees(),
            beta_deg: r.beta_rad.to_degrees(),
            gamma_deg: r.gamma_rad.to_degrees(),
            h_m: r.h_m,
        }
    }

    /// The row in internal units.
    pub fn to_row(&self) -> PhiRow {
        PhiRow {
            a_m: self.a_m,
            b_m: self.b_m,
            alpha_rad: self.alpha_deg.to_radians(),
            beta_rad: self.beta_deg.to_radians(),
            gamma_rad: self.gamma_deg.to_radians(),
            h_m: self.h_m,
        }
    }
}

/// A nominal passive coupling as the controller models it (`docs/formats.md#controller-semantics`):
/// `nominal_passive_{from,to}(u_from) = slope * u_from`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NominalCoupling {
    /// The driving joint (1-based).
    pub from: usize,
    /// The driven joint, always `from + 1` (paper section 3.1).
    pub to: usize,
    /// Passive motion of `to` per unit active motion of `from`.
    pub slope: f64,
    /// The form the calibrator fits when a second target measures this coupling; default a
    /// gear of ratio `slope` with one harmonic.
    #[serde(default)]
    pub fit: Option<CouplingFitForm>,
}

/// A rigid placement: translation \[mm\] and roll-pitch-yaw \[deg\] (`Rz(yaw) Ry(pitch) Rx(roll)`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Placement {
    /// \[mm\]
    #[serde(default)]
    pub translation_mm: [f64; 3],
    /// \[deg\]
    #[serde(default)]
    pub rpy_deg: [f64; 3],
}

impl Placement {
    /// The placement of an isometry (metres) in file units.
    pub fn from_isometry(iso: &Isometry3<f64>) -> Self {
        let t = iso.translation.vector * 1e3;
        Placement {
            translation_mm: [t.x, t.y, t.z],
            rpy_deg: crate::kinematics::roll_pitch_yaw(&iso.rotation).map(f64::to_degrees),
        }
    }

    /// The origin of the placed frame \[m\] (e.g. a robot base in the instrument frame).
    pub fn origin_m(&self) -> Point3<f64> {
        Point3::from(Vector3::from(self.translation_mm) * 1e-3)
    }

    /// The yaw about the outer frame's `z` \[rad\] (the last of `rpy_deg`).
    pub fn yaw_rad(&self) -> f64 {
        self.rpy_deg[2].to_radians()
    }

    /// The placement as an isometry in metres.
    pub fn to_isometry(&self) -> Isometry3<f64> {
        let t = Vector3::from(self.translation_mm) * 1e-3;
        let [r, p, y] = self.rpy_deg.map(f64::to_radians);
        Isometry3::from_parts(Translation3::from(t), UnitQuaternion::from_euler_angles(r, p, y))
    }
}

/// The tool: its frame in the last link and the three targets used for validation.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ToolEntry {
    /// The tool frame in the last link's moving frame (with `dh` rows: in the last DH frame;
    /// with `urdf`: in the tip link).
    #[serde(default)]
    pub frame: Placement,
    /// Tool targets 0, 1, 2 in the tool frame \[mm\] (three non-collinear points), or none: the
    /// tool frame then stays nominal in a calibration.
    #[serde(default)]
    pub targets_mm: Vec<[f64; 3]>,
}

/// A target fixed on a link: which link (1-based) and where in its moving frame \[mm\].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LinkTarget {
    /// The link carrying the target (1-based; link `k` is moved by joint `k`).
    pub link: usize,
    /// Position in that link's moving frame \[mm\].
    pub position_mm: [f64; 3],
}

impl LinkTarget {
    /// Position in the link's moving frame \[m\].
    pub fn position_m(&self) -> Point3<f64> {
        Point3::from(self.position_mm) * 1e-3
    }
}

/// The targets observed while joint `joint` is swept (`docs/formats.md#measurement-csv`): target 0 on the
/// moved link or beyond (rigidly moved by that joint alone), target 1 (optional) on the next
/// link out or beyond, for the passive motion (eq. 14).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AxisTargets {
    /// The swept joint (1-based).
    pub joint: usize,
    /// Target 0.
    pub target0: LinkTarget,
    /// Target 1, when the experiment measures a passive coupling into `joint + 1`.
    #[serde(default)]
    pub target1: Option<LinkTarget>,
}

/// A description's source chain (DH table or URDF) and its base's placement in the instrument
/// frame, for checking the conversion.
pub type SourceCheck = (SourceChain, Isometry3<f64>);

/// A robot description file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RobotDescription {
    /// Human-readable name.
    pub name: String,
    /// The joints, base first (from `urdf` when absent there).
    #[serde(default)]
    pub joints: Vec<JointEntry>,
    /// The convention of the joints' `dh` rows, when the geometry is given as a DH table.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dh_convention: Option<DhConventionEntry>,
    /// A URDF file giving the geometry (and the joints when `joints` is empty).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub urdf: Option<UrdfEntry>,
    /// The nominal phi-model rows (Table 2, nominal), `joints.len() - 1` of them (converted
    /// from `dh` or `urdf` when those are given).
    #[serde(default)]
    pub rows: Vec<RowEntry>,
    /// Nominal passive couplings known to the controller.
    #[serde(default)]
    pub couplings: Vec<NominalCoupling>,
    /// Robot base frame (frame 1) in the instrument frame, for simulated set-ups.
    #[serde(default)]
    pub placement: Placement,
    /// The tool (default: the last link's frame, no targets).
    #[serde(default)]
    pub tool: ToolEntry,
    /// Targets for the axis experiments, one entry per joint (simulation and diagnosis).
    #[serde(default)]
    pub axis_targets: Vec<AxisTargets>,
    /// The instrument's stations in the instrument frame (default: chosen for the robot by
    /// `plan::instrument_stations_m`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub instrument: Option<InstrumentEntry>,
}

impl RobotDescription {
    /// Reads and validates a description file. A file that is a robot model instead (a
    /// simulated truth, `docs/formats.md#robot-model`) is an error that says so.
    pub fn from_file(path: &Path) -> Result<Self, DescriptionError> {
        let text = crate::toml_file::read(path)?;
        Self::from_toml_str(&text, path).map_err(|e| match e {
            DescriptionError::File(_) if crate::robot::RobotModel::from_toml_str(&text, path).is_ok() => {
                DescriptionError::Invalid {
                    path: path.to_owned(),
                    field: "name".into(),
                    message: "this is a robot model (a simulated truth: give it with `--truth`), not a robot description (docs/formats.md#robot-description)".into(),
                }
            }
            other => other,
        })
    }

    /// Parses and validates description text; `path` names the file in messages and locates
    /// a `urdf` file. `dh` rows and `urdf` geometry are converted to the phi-model.
    pub fn from_toml_str(text: &str, path: &Path) -> Result<Self, DescriptionError> {
        Ok(Self::with_source(text, path)?.0)
    }

    /// [`Self::from_toml_str`] with the chain the geometry was converted from (`dh` or
    /// `urdf`) and its base's placement in the instrument frame as written, for checking the
    /// conversion (`axiscal describe`).
    pub fn with_source(text: &str, path: &Path) -> Result<(Self, Option<SourceCheck>), DescriptionError> {
        let mut d: Self = crate::toml_file::parse_own(text, path, crate::toml_file::OwnToml::Description)?;
        let source = d.convert_source(path)?;
        d.validate(path)?;
        Ok((d, source))
    }

    /// The shipped ASEA IRB/L6 description (`scenarios/robots/asea-irb6l.toml`).
    pub fn asea_irb6l() -> Self {
        let text = include_str!("../../../scenarios/robots/asea-irb6l.toml");
        Self::from_toml_str(text, Path::new("scenarios/robots/asea-irb6l.toml"))
            .expect("the shipped ASEA IRB/L6 description is valid (checked by tests)")
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// The nominal phi-model geometry, placed in the instrument frame by `placement`.
    pub fn nominal_model(&self) -> PhiModel {
        let joints = self.joints.iter().map(|j| (j.kind, j.phi_deg));
        phi_model_of(joints, &self.rows, &self.placement, &self.tool.frame)
    }

    /// The nominal slope of the coupling that drives joint `to` (1-based), if any.
    pub fn nominal_coupling_into(&self, to: usize) -> Option<f64> {
        self.couplings.iter().find(|c| c.to == to).map(|c| c.slope)
    }

    /// The nominal slope of the coupling driven by joint `from` (1-based), if any.
    pub fn nominal_coupling_from(&self, from: usize) -> Option<f64> {
        self.couplings.iter().find(|c| c.from == from).map(|c| c.slope)
    }

    /// Tool targets in the tool frame \[m\].
    pub fn tool_targets_m(&self) -> Vec<Point3<f64>> {
        self.tool.targets_mm.iter().map(|p| Point3::from(*p) * 1e-3).collect()
    }

    /// The axis-experiment targets of joint `joint` (1-based), if the file gives them.
    pub fn axis_targets_of(&self, joint: usize) -> Option<&AxisTargets> {
        self.axis_targets.iter().find(|a| a.joint == joint)
    }

    /// Joint limits in internal units (rad or m).
    pub fn limits_internal(&self, k: usize) -> [f64; 2] {
        let j = &self.joints[k];
        match j.kind {
            JointKind::Revolute => j.limits.map(f64::to_radians),
            JointKind::Prismatic => j.limits.map(|v| v * 1e-3),
        }
    }
}

/// Converts file-unit commands (deg / mm) to internal units (rad / m).
pub fn commands_to_internal(desc: &RobotDescription, cmd_file: &[f64]) -> Vec<f64> {
    cmd_file
        .iter()
        .zip(&desc.joints)
        .map(|(c, j)| match j.kind {
            JointKind::Revolute => c.to_radians(),
            JointKind::Prismatic => c * 1e-3,
        })
        .collect()
}

/// Converts internal-unit joint values or commands (rad / m) to file units (deg / mm), the
/// inverse of [`commands_to_internal`].
pub fn commands_to_file(desc: &RobotDescription, cmd_internal: &[f64]) -> Vec<f64> {
    cmd_internal
        .iter()
        .zip(&desc.joints)
        .map(|(c, j)| j.kind.to_file_units(*c))
        .collect()
}

/// The unit suffix of joint `k`'s file values: `deg` (revolute) or `mm` (prismatic).
pub fn file_unit(desc: &RobotDescription, k: usize) -> &'static str {
    desc.joints[k].kind.file_unit()
}
