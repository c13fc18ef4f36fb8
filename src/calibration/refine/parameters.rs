//! The refined model's correction parameters ([`RefitParameter`]), the units they are reported
//! in ([`ParameterUnit`]) and a parameter's weight in a direction of the fit
//! ([`DirectionWeight`]): what the refinement, the refit model and the free-pose calibration
//! share.

use serde::{Deserialize, Serialize};

/// One correction parameter of the refined model, in the refit's layout.
#[derive(Clone, Debug, PartialEq)]
pub enum RefitParameter {
    /// Table-2 row `row` (1-based): `a` \[m\].
    RowA(usize),
    /// Row `b` \[m\].
    RowB(usize),
    /// Row `alpha` \[rad\].
    RowAlpha(usize),
    /// Row `beta` \[rad\].
    RowBeta(usize),
    /// A joint's zero offset (1-based joint; rad, or m for a sliding joint).
    ZeroOffset {
        /// Joint.
        joint: usize,
        /// Whether it slides.
        sliding: bool,
    },
    /// A coefficient of the passive coupling into `joint` (`ratio`, `sin1`, `cos1`, `n0`, ...).
    Coupling {
        /// The driven joint.
        joint: usize,
        /// The coefficient's name.
        coefficient: String,
    },
    /// A transmission harmonic of `joint` (eq. 8): its sine or cosine coefficient \[rad\].
    Harmonic {
        /// Joint.
        joint: usize,
        /// Order.
        order: usize,
        /// The cosine coefficient (else the sine).
        cosine: bool,
    },
    /// A tool target's position in the tool frame, coordinate `axis` \[m\]: fixed by the
    /// description (`calibration.json` has no place for it; the tool frame absorbs a common
    /// shift).
    Target {
        /// Target id.
        target: usize,
        /// 0, 1, 2 = x, y, z.
        axis: usize,
    },
    /// The base placement's correction: 0-2 translation \[m\], 3-5 rotation vector \[rad\].
    Base(usize),
    /// The tool frame's correction (in the tool frame), as [`RefitParameter::Base`].
    Tool(usize),
    /// The base placement in the instrument frame of setup `setup` (1-based beyond the first:
    /// the instrument moved), as [`RefitParameter::Base`].
    SetupBase {
        /// The setup (>= 1; setup 0's base is [`RefitParameter::Base`]).
        setup: usize,
        /// 0-2 translation, 3-5 rotation.
        axis: usize,
    },
    /// A coefficient of `joint`'s sag under the gravity load term `load` of `link`
    /// ([`crate::robot::SagTerm`]).
    Sag {
        /// The joint that bends (1-based).
        joint: usize,
        /// The link whose load it carries (1-based).
        link: usize,
        /// The load term.
        load: crate::robot::LoadTerm,
    },
    /// `joint`'s backlash half band ([`crate::robot::BacklashTerm`]) \[rad or m\].
    Backlash {
        /// The joint (1-based).
        joint: usize,
        /// Whether it slides.
        sliding: bool,
    },
    /// A parameter of a named effect carried into the model (`calibrate --carry`), in the
    /// diagnosis's units (its name says them, e.g. `joint2.joint_compliance.compliance_rad_per_nm`).
    Effect {
        /// `joint<J>.<effect>.<parameter>`, or `<effect>.<parameter>` without a joint.
        name: String,
    },
}

const AXES: [&str; 6] = ["x", "y", "z", "rx", "ry", "rz"];

impl RefitParameter {
    /// Its name in the report (`row2.a`, `joint3.zero_offset`, `joint5.transmission.sin1`, ...).
    pub fn name(&self) -> String {
        match self {
            RefitParameter::RowA(r) => format!("row{r}.a"),
            RefitParameter::RowB(r) => format!("row{r}.b"),
            RefitParameter::RowAlpha(r) => format!("row{r}.alpha"),
            RefitParameter::RowBeta(r) => format!("row{r}.beta"),
            RefitParameter::ZeroOffset { joint, .. } => format!("joint{joint}.zero_offset"),
            RefitParameter::Coupling { joint, coefficient } => {
                format!("coupling{}-{joint}.{coefficient}", joint - 1)
            }
            RefitParameter::Harmonic { joint, order, cosine } => {
                format!(
                    "joint{joint}.transmission.{}{order}",
                    if *cosine { "cos" } else { "sin" }
                )
            }
            RefitParameter::Target { target, axis } => format!("target{target}.{}", AXES[*axis]),
            RefitParameter::Base(a) => format!("base.{}", AXES[*a]),
            RefitParameter::SetupBase { setup, axis } => format!("setup{setup}.base.{}", AXES[*axis]),
            RefitParameter::Tool(a) => format!("tool.{}", AXES[*a]),
            RefitParameter::Sag { joint, link, load } => format!("joint{joint}.sag.link{link}.{}", load.name()),
            RefitParameter::Backlash { joint, .. } => format!("joint{joint}.backlash"),
            RefitParameter::Effect { name } => name.clone(),
        }
    }

    /// Its report unit.
    pub fn unit(&self) -> ParameterUnit {
        match self {
            RefitParameter::RowA(_) | RefitParameter::RowB(_) | RefitParameter::Target { .. } => ParameterUnit::Mm,
            RefitParameter::ZeroOffset { sliding: true, .. } => ParameterUnit::Mm,
            RefitParameter::Base(a) | RefitParameter::Tool(a) if *a < 3 => ParameterUnit::Mm,
            RefitParameter::SetupBase { axis, .. } if *axis < 3 => ParameterUnit::Mm,
            RefitParameter::Coupling { .. } | RefitParameter::Effect { .. } => ParameterUnit::Coefficient,
            RefitParameter::Backlash { sliding: true, .. } => ParameterUnit::Mm,
            RefitParameter::Sag { .. } => ParameterUnit::MradPerLoad,
            _ => ParameterUnit::Mrad,
        }
    }

    /// Whether the refinement leaves it at its calibrated value.
    pub fn fixed(&self) -> bool {
        matches!(self, RefitParameter::Target { .. })
    }
}

/// The unit a parameter is reported in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ParameterUnit {
    /// Millimetres (the parameter is a length in metres inside).
    Mm,
    /// Milliradians.
    Mrad,
    /// A dimensionless coefficient (a coupling's ratio or fractional coefficient).
    Coefficient,
    /// A sag coefficient: milliradians per unit of its load term's regressor (m for a mass, 1
    /// for a first moment, times kg for a payload's; [`crate::robot::LoadTerm`]).
    MradPerLoad,
}

impl ParameterUnit {
    /// Report units per internal unit.
    pub fn per_si(self) -> f64 {
        match self {
            ParameterUnit::Mm | ParameterUnit::Mrad | ParameterUnit::MradPerLoad => 1e3,
            ParameterUnit::Coefficient => 1.0,
        }
    }

    /// The scale of a parameter without an unrefined sigma: 1 mm, 1 mrad, 1e-3 (internal units).
    pub(super) fn fallback_scale(self) -> f64 {
        1e-3
    }
}

/// A parameter's weight in a direction.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct DirectionWeight {
    /// Parameter name.
    pub name: String,
    /// Weight (a unit vector's component).
    pub weight: f64,
}
