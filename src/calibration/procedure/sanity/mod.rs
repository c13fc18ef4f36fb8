//! A calibration checked against its description before it is reported: results that no
//! instrument and robot of this description can give are said loudly, with what to check.
//!
//! - **Handedness.** The lengths of the calibrated rows (`a`, `b`, `h` of Table 2) against
//!   the description's, on the lengths of at least [`SIGNIFICANT_LENGTH`] of the longest and
//!   [`MIN_SIGNIFICANT_LENGTH_M`]. In a left-handed instrument frame (one coordinate's sign
//!   flipped on export) the lengths along a rotary axis or its common normals flip sign and keep
//!   their size (the axis is oriented by its motion: a pseudovector); no robot of the
//!   description gives that.
//! - **Size.** The least-squares factor `s = sum(|c| |n|) / sum(n^2)` of the same lengths'
//!   sizes, calibrated `c` over described `n`, each sliding joint's travel per command (its
//!   transmission's slope, described over calibrated) counted as a length of the longest's
//!   size. A robot of its description is within a few per cent of 1; other factors are a unit
//!   or scale error of the coordinates, or another robot. Beyond [`SIZE_TOLERANCE`] it is said.
//! - **Sweeps.** A joint whose fit misses its points by more than [`MISFIT_RATIO`] times the
//!   median of every joint's residual RMS: its points are not on one arc or line of the joint (a
//!   block of rows shifted, a sweep partly in other units, a target moved on its link). The
//!   noise estimate and every sigma of the calibration are inflated with it.
//! - **Directions.** Each fitted axis against the description's at the reference pose, in the
//!   instrument frame as the description places the robot. An axis beyond
//!   [`SIGNIFICANT_SIGMAS`] of its direction sigma and beyond [`PLAUSIBLE_AXIS_TILT_RAD`] from its
//!   nominal direction while every other axis is within them is no robot's deviation: opposite
//!   to its nominal, its readings count the other way (a sign convention); two such axes each
//!   along the other's nominal line, their experiments are labelled the other's. A description
//!   placed otherwise than the robot stands turns every axis, which says neither.
//! - **Tool.** The tool frame fitted from the tool observation against the description's, in
//!   the last link: beyond [`PLAUSIBLE_AXIS_TILT_RAD`] (plus [`SIGNIFICANT_SIGMAS`] of its
//!   rotation sigma) it is no tool's deviation from its drawing. Three targets in a plane fit their mirror image (two ids swapped) exactly, turned
//!   over by up to 180 deg. A mirrored frame or a flipped or swapped axis turns the tool over
//!   too: it is then left unsaid.
//! - **Tool fit.** The three-point fit of the tool frame leaves `3 n - 6` degrees of freedom
//!   (3 for three targets) to the instrument's noise alone (one pose: no joint moves between its
//!   points). Its residual sum of squares over the noise's per-coordinate variance (the
//!   calibration's 3-D RMS over root 3) is chi-square; beyond its [`TOOL_FIT_FALSE_ALARM`]
//!   upper quantile a tool row's point is off (a target id or a coordinate mistyped, the target
//!   moved on the tool), or the description's `[tool] targets_mm` are not this tool's. Not said
//!   beside a size finding or scaled coordinates, which explain it.
//! - **Scale.** A joint's fitted transmission against what a drive gives, and the sliding
//!   joints' common scale ([`scale`]): a command column or the coordinates scaled by a few per
//!   cent, which the fit absorbs into a transmission or the geometry. Not said beside a size or
//!   mirror finding, which explains it; a joint's misfit is not said beside its scale. Several
//!   joints' departures that one instrument axis' scale explains are said as that axis
//!   ([`scale_source`], [`with_column_source`]).

mod scale;
mod scale_absorption;
mod scale_source;
mod slope;
mod tool_spacing;

pub use scale::{
    DOUBT_SIGMAS, JointSlope, LEAD_SPREAD, PLAUSIBLE_LEAD_DEVIATION, PLAUSIBLE_TURN_DEVIATION, SCALE_SIGMAS,
    ScaleDoubt, ScaleReach, ScaleSlip, free_pose_scale_doubts, free_pose_scale_reach, free_pose_scale_slips,
    joint_slopes, named_joints, scale_doubts, scale_reach,
};
pub use scale_source::{ColumnSource, Refit, column_source};
pub use tool_spacing::{SPACING_SIGMAS, SpacingScale, tool_spacing_scale};

use super::{AxisReport, Calibration, SIGNIFICANT_SIGMAS};
use crate::kinematics::JointKind;
use crate::numerics::stats::{QuantileMethod, quantile};
use crate::robot::{RobotDescription, RobotModel, commands_to_internal};
use nalgebra::Vector3;

/// Lengths shorter than this share of the description's longest are left out of the size
/// factor: a nominal zero or a few millimetres of offset says nothing of the scale.
pub const SIGNIFICANT_LENGTH: f64 = 0.05;

/// Lengths shorter than this \[m\] are left out of the size factor whatever the longest: a
/// calibration moves a length by a fraction of a millimetre, which on a nominal length below
/// 20 mm is more than [`SIZE_TOLERANCE`] of it (and on a nominal zero, as coaxial axes have,
/// any factor at all).
pub const MIN_SIGNIFICANT_LENGTH_M: f64 = 0.02;

use super::size::row_lengths;
pub use super::size::{SIZE_TOLERANCE, longest_length_m};

/// A joint's residual RMS beyond this many times the median joint's is said: 9 times the
/// variance, more than the swept joints' repeatability at different radii gives (1.7 times on
/// the paper robot).
pub const MISFIT_RATIO: f64 = 3.0;

/// A fitted axis may lie this far \[rad\] (10 deg) from its nominal direction in the instrument
/// frame: a robot's axes are within a degree or two of its drawing, and a description's
/// placement (its `[placement]` measured or taken from the setup) within a few degrees of the
/// robot; a sign convention (180 deg) or two axes' labels exchanged (the angle between them,
/// 90 deg on most arms) are far beyond both.
pub const PLAUSIBLE_AXIS_TILT_RAD: f64 = std::f64::consts::PI / 18.0;

/// The chance that a clean tool observation's fit is said to miss ([`Implausible::ToolMisfit`]):
/// one in a million calibrations, the chi-square quantile 30.7 on 3 dof (3.2 times the RMS the
/// noise gives).
pub const TOOL_FIT_FALSE_ALARM: f64 = 1e-6;

/// What the checks found.
#[derive(Clone, Debug, PartialEq)]
pub enum Implausible {
    /// The calibrated robot is the mirror image of its description.
    Mirrored {
        /// Lengths whose sign flipped.
        flipped: usize,
        /// The lengths compared.
        lengths: usize,
    },
    /// The calibrated robot is `factor` times its description's size.
    Size {
        /// The least-squares factor.
        factor: f64,
        /// The lengths it was taken over.
        lengths: usize,
    },
    /// A fitted axis points opposite to its nominal direction, every other axis along its own.
    FlippedAxis {
        /// The joint.
        joint: usize,
        /// Its experiments.
        experiment: String,
        /// Whether it slides (else it turns).
        sliding: bool,
        /// The angle between the fitted and the nominal direction \[deg\].
        angle_deg: f64,
    },
    /// Two fitted axes each lie along the other's nominal line, every other axis along its own.
    SwappedAxes {
        /// The first joint.
        joint: usize,
        /// The other.
        other: usize,
        /// The angle between joint `joint`'s fitted axis and its nominal \[deg\].
        angle_deg: f64,
    },
    /// The tool frame fitted from the tool observation is turned far from the description's.
    ToolTurned {
        /// The angle between the fitted and the described tool frame (in the last link) \[deg\].
        angle_deg: f64,
    },
    /// The tool frame's fit misses its targets beyond the noise (module docs).
    ToolMisfit {
        /// The experiment observed.
        experiment: String,
        /// Its step.
        step: usize,
        /// The fit's RMS \[mm\].
        rms_mm: f64,
        /// The noise's 3-D RMS \[mm\].
        noise_mm: f64,
        /// The fit's chi-square.
        chi_square: f64,
        /// Degrees of freedom.
        dof: usize,
        /// The chi-square's upper quantile at `1 - TOOL_FIT_FALSE_ALARM`.
        limit: f64,
    },
    /// A transmission or the coordinates scaled beyond what a drive gives (`scale`).
    Scaled(ScaleSlip),
    /// A joint's fit misses its points by far more than the others'.
    Misfit {
        /// The joint.
        joint: usize,
        /// Its experiments.
        experiment: String,
        /// Its residual RMS \[mm\].
        rms_mm: f64,
        /// The median joint's \[mm\].
        median_mm: f64,
        /// A revolute joint's span where it is more than half a turn \[deg\]: its transmission's
        /// once-per-turn term cannot take up a scale of its command column there, which then
        /// shows as this misfit.
        long_sweep_deg: Option<f64>,
        /// With several sweeps: the one that carries the misfit (`misfit_sweep`).
        sweep: Option<MisfitSweep>,
    },
}

/// The sweep of a joint fitted from several whose points carry the joint's misfit: the joint's
/// other sweeps fit without it (`misfit_sweep`).
#[derive(Clone, Debug, PartialEq)]
pub struct MisfitSweep {
    /// The experiment.
    pub experiment: String,
    /// Its residual RMS in the joint fit \[mm\].
    pub rms_mm: f64,
    /// The residual RMS of the joint's fit from its other sweeps \[mm\].
    pub others_mm: f64,
    /// Its worst point: step and residual \[mm\].
    pub worst: (usize, f64),
    /// Its other points' residual RMS \[mm\].
    pub rest_mm: f64,
    /// Its first and last file lines (the caller's, from the measurement set).
    pub lines: Option<(u64, u64)>,
    /// The worst point's file line (the caller's).
    pub worst_line: Option<u64>,
}

impl MisfitSweep {
    /// Whether its worst point alone carries its misfit: the sweep's other points within
    /// [`MISFIT_RATIO`] times `median_mm`, as the joint's other sweeps are.
    fn one_point(&self, median_mm: f64) -> bool {
        self.rest_mm <= MISFIT_RATIO * median_mm
    }

    /// The words appended to the joint's misfit.
    fn words(&self, median_mm: f64) -> String {
        let lines = self
            .lines
            .map_or_else(String::new, |(a, b)| format!(" (lines {a}-{b})"));
        let head = format!(
            "; the misfit is experiment {}'s{lines}: {:.3} mm RMS in the joint's fit, where the joint's other sweeps fitted without it miss their points by {:.3} mm",
            self.experiment, self.rms_mm, self.others_mm
        );
        let (step, off) = self.worst;
        if self.one_point(median_mm) {
            let at = self.worst_line.map_or_else(String::new, |l| format!("line {l}, "));
            format!(
                "{head}, and in it one point: {at}step {step}, {off:.3} mm off the arc where its other points miss by {:.3} mm (a mistyped coordinate, a target mis-sighted): check that row",
                self.rest_mm
            )
        } else {
            format!(
                "{head}: check that sweep's rows (its block moved part-way, a bump of the instrument or the robot, or a held joint's recorded command off through it: a value typed wrong or the joint re-mastered between the sweeps)"
            )
        }
    }
}

impl Implausible {
    /// Whether this is a slip of the instrument's coordinates (an axis or all three read
    /// scaled, the robot's size or handedness off), which moves every sweep and every pose
    /// alike, so that no one sweep is its cause.
    pub fn is_coordinate_slip(&self) -> bool {
        match self {
            Implausible::Size { .. } | Implausible::Mirrored { .. } => true,
            Implausible::Scaled(slip) => matches!(slip, ScaleSlip::Column(_) | ScaleSlip::Coordinates { .. }),
            _ => false,
        }
    }
}

impl std::fmt::Display for Implausible {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Implausible::Mirrored { flipped, lengths } => write!(
                f,
                "the calibrated robot is the mirror image of its description ({flipped} of its {lengths} lengths have the description's size with the opposite sign): the instrument frame is left-handed (one coordinate's sign flipped on export); check the x_mm, y_mm, z_mm columns"
            ),
            Implausible::Size { factor, lengths } => {
                // A unit's factor within the size tolerance of the one found: that unit, named.
                let unit = crate::measurement::unit_check::LENGTH_SLIPS
                    .iter()
                    .find(|(u, _)| (factor / u - 1.0).abs() < SIZE_TOLERANCE)
                    .map_or_else(String::new, |(u, name)| {
                        let ratio = if *u < 1.0 {
                            format!("1/{}", crate::measurement::format_f64(1.0 / u))
                        } else {
                            crate::measurement::format_f64(*u)
                        };
                        format!(" ({factor:.4} is near {ratio}: the coordinates look like {name} read as millimetres)")
                    });
                write!(
                    f,
                    "the calibrated robot is {factor:.3} times its description's size (over its {lengths} lengths){unit}: check the unit and scale of x_mm, y_mm, z_mm (an instrument exporting other units), or whether the description is of this robot"
                )
            }
            Implausible::FlippedAxis {
                joint,
                experiment,
                sliding,
                angle_deg,
            } => {
                let (moves, way) = if *sliding {
                    ("slides", "along")
                } else {
                    ("turns", "about")
                };
                write!(
                    f,
                    "joint {joint} ({experiment}): the fitted axis points opposite to its nominal direction ({angle_deg:.1} deg from it, every other axis along its own): the joint {moves} the other way {way} it as its readings grow; check the sign convention of cmd_{joint} (the controller's readings negated, or the description's axis reversed)"
                )
            }
            Implausible::SwappedAxes {
                joint,
                other,
                angle_deg,
            } => write!(
                f,
                "the axis fitted for joint {joint} lies along joint {other}'s nominal axis and the one fitted for joint {other} along joint {joint}'s ({angle_deg:.1} deg from its own, every other axis along its own): are the experiment labels of joints {joint} and {other} swapped? (check the experiment ids, `moved_joint` and the cmd_{joint}, cmd_{other} columns; or the description's [placement] turns the robot)"
            ),
            Implausible::ToolTurned { angle_deg } => write!(
                f,
                "the tool frame fitted from the tool observation is turned {angle_deg:.1} deg from the description's `[tool] frame`: the tool rows' target ids swapped (three targets fit their mirror image turned over), or the description's tool frame or targets are not this tool's; check the `tool` rows' target ids against `[tool] targets_mm`"
            ),
            Implausible::ToolMisfit {
                experiment,
                step,
                rms_mm,
                noise_mm,
                chi_square,
                dof,
                limit,
            } => write!(
                f,
                "the tool frame's fit to the tool targets of `{experiment}` step {step} misses them by {rms_mm:.3} mm RMS where the noise is {noise_mm:.4} mm 3-D RMS (chi-square {chi_square:.1} on {dof} dof, beyond its 1 - {TOOL_FIT_FALSE_ALARM:e} quantile {limit:.1}): a tool row's point is off (a target id or coordinate mistyped, a target moved on the tool), or the description's [tool] targets_mm are not this tool's; the tool frame and every tool prediction carry it"
            ),
            Implausible::Scaled(slip) => slip.fmt(f),
            Implausible::Misfit {
                joint,
                experiment,
                rms_mm,
                median_mm,
                long_sweep_deg,
                sweep,
            } => {
                let scaled = long_sweep_deg.map_or_else(String::new, |span| {
                    format!(
                        ", the column `cmd_{joint}` scaled on export (over its {span:.0}-deg sweep no once-per-turn term of \
                         its transmission takes a scale up, so it shows here): check cmd_{joint} against the controller's \
                         reading at two poses"
                    )
                });
                let carrier = sweep.as_ref().map_or_else(String::new, |s| s.words(*median_mm));
                write!(
                    f,
                    "joint {joint} ({experiment}): the fit misses its points by {rms_mm:.3} mm RMS, {:.1} times the median joint's {median_mm:.3} mm: its points are not on one arc or line of the joint (a block of rows shifted, part of the sweep in other units, a target moved on its link{scaled}){carrier}; the noise estimate and every sigma are inflated by it",
                    rms_mm / median_mm
                )
            }
        }
    }
}

/// The checks of the module doc on `cal`, calibrated with the description `desc`.
pub fn implausible(cal: &Calibration, desc: &RobotDescription) -> Vec<Implausible> {
    let directions = directions(cal, desc);
    // A flipped axis flips the lengths along it too: it, not a mirrored frame, explains them.
    let mirrored_by_an_axis = |s: &Implausible| matches!(s, Implausible::Mirrored { .. }) && !directions.is_empty();
    let mut found: Vec<Implausible> = size(cal, desc)
        .into_iter()
        .filter(|s| !mirrored_by_an_axis(s))
        .collect();
    found.extend(directions);
    // A mirrored frame or a flipped axis turns the tool over too: they, not its ids, explain it.
    if !found.iter().any(|s| !matches!(s, Implausible::Size { .. })) {
        found.extend(tool_turned(cal, desc));
    }
    // A size or a mirror image explains the transmissions' scale; a joint's scale its misfit.
    if !found
        .iter()
        .any(|s| matches!(s, Implausible::Size { .. } | Implausible::Mirrored { .. }))
    {
        found.extend(scale::scale_slips(cal, desc).into_iter().map(Implausible::Scaled));
    }
    let scaled: Vec<usize> = found
        .iter()
        .filter_map(|s| match s {
            Implausible::Scaled(ScaleSlip::Command { joint, .. } | ScaleSlip::Sag { joint, .. }) => Some(*joint),
            _ => None,
        })
        .collect();
    found.extend(
        misfits(cal)
            .into_iter()
            .filter(|m| !matches!(m, Implausible::Misfit { joint, .. } if scaled.contains(joint))),
    );
    // A robot of another size, or scaled coordinates, miss the described tool targets too: the
    // size explains it.
    if !found.iter().any(|s| {
        matches!(
            s,
            Implausible::Size { .. } | Implausible::Scaled(ScaleSlip::Coordinates { .. })
        )
    }) {
        found.extend(tool_misfit(cal, desc));
    }
    found
}

/// `found` ([`implausible`]) with the command-column scales that `source` explains as one
/// instrument axis' scale ([`column_source`]) said as that, in the place of the first.
pub fn with_column_source(found: Vec<Implausible>, source: Option<&ColumnSource>) -> Vec<Implausible> {
    let Some(source) = source else {
        return found;
    };
    let explained = |f: &Implausible| matches!(f, Implausible::Scaled(ScaleSlip::Command { joint, .. }) if source.joints.iter().any(|j| j.0 == *joint));
    let Some(first) = found.iter().position(explained) else {
        return found;
    };
    let mut out: Vec<Implausible> = Vec::with_capacity(found.len());
    for (i, f) in found.into_iter().enumerate() {
        if i == first {
            out.push(Implausible::Scaled(ScaleSlip::Column(source.clone())));
        }
        if !explained(&f) {
            out.push(f);
        }
    }
    out
}

/// The tool-fit check of the module doc.
fn tool_misfit(cal: &Calibration, desc: &RobotDescription) -> Option<Implausible> {
    let tool = cal.tool.as_ref()?;
    let noise_mm = cal.noise.as_ref()?.used_rms_3d_mm;
    let n = desc.tool.targets_mm.len();
    let dof = (3 * n).checked_sub(6).filter(|d| *d > 0)?;
    // The fit's RMS is over its n points' 3-D residuals; a coordinate's variance is a third
    // of the 3-D one.
    let chi_square = n as f64 * tool.fit_rms_mm.powi(2) / (noise_mm.powi(2) / 3.0);
    let limit = crate::numerics::stats::chi_square_quantile(1.0 - TOOL_FIT_FALSE_ALARM, dof as f64);
    (noise_mm > 0.0 && chi_square > limit).then(|| Implausible::ToolMisfit {
        experiment: tool.experiment.clone(),
        step: tool.step,
        rms_mm: tool.fit_rms_mm,
        noise_mm,
        chi_square,
        dof,
        limit,
    })
}

/// The tool check of the module doc: the fitted tool frame against the described one, both in
/// the last link, beyond [`PLAUSIBLE_AXIS_TILT_RAD`] (a drawing's tool) plus
/// [`SIGNIFICANT_SIGMAS`] of the fitted frame's rotation sigma (its estimate's: a tool seen
/// from a flange the calibration knows to a few degrees is known no better; a few mrad after
/// full sweeps).
fn tool_turned(cal: &Calibration, desc: &RobotDescription) -> Option<Implausible> {
    let described = RobotModel::ideal(desc).tool_frame.to_isometry().rotation;
    let angle = described.angle_to(&cal.robot.tool_frame.to_isometry().rotation);
    let tolerance = PLAUSIBLE_AXIS_TILT_RAD + SIGNIFICANT_SIGMAS * tool_rotation_sigma_rad(cal);
    (angle > tolerance).then(|| Implausible::ToolTurned {
        angle_deg: angle.to_degrees(),
    })
}

/// The fitted tool frame's rotation 1-sigma, its covariance's largest principal one (the
/// last three of the model's parameters, [`crate::calibration::model_parameters::model_parameter_names`]);
/// 0 without a model covariance.
fn tool_rotation_sigma_rad(cal: &Calibration) -> f64 {
    let Some(covariance) = &cal.model_covariance else {
        return 0.0;
    };
    let c = covariance.matrix();
    let n = c.nrows();
    if n < 3 {
        return 0.0;
    }
    let rotation = c.view((n - 3, n - 3), (3, 3)).into_owned();
    rotation.symmetric_eigenvalues().max().max(0.0).sqrt()
}

/// Each fitted axis's direction, the nominal one at the reference pose (instrument frame, the
/// description's placement) and how far from it the fit may lie ([`PLAUSIBLE_AXIS_TILT_RAD`],
/// or [`SIGNIFICANT_SIGMAS`] of its direction sigma when larger).
fn fitted_and_nominal<'a>(
    cal: &'a Calibration,
    desc: &RobotDescription,
) -> Vec<(&'a AxisReport, Vector3<f64>, Vector3<f64>, f64)> {
    if cal.reference_cmd.len() != desc.dof() {
        return vec![];
    }
    let poses = desc
        .nominal_model()
        .poses(&commands_to_internal(desc, &cal.reference_cmd));
    cal.axes
        .iter()
        .filter(|a| (1..=desc.dof()).contains(&a.joint))
        .map(|a| {
            let tolerance = PLAUSIBLE_AXIS_TILT_RAD.max(SIGNIFICANT_SIGMAS * a.direction_sigma.major_rad);
            (
                a,
                Vector3::from(a.direction),
                poses.axis(a.joint - 1).direction.into_inner(),
                tolerance,
            )
        })
        .collect()
}

/// The directions check of the module doc: a flipped axis or two swapped ones.
fn directions(cal: &Calibration, desc: &RobotDescription) -> Vec<Implausible> {
    let axes = fitted_and_nominal(cal, desc);
    let off: Vec<usize> = (0..axes.len())
        .filter(|&i| axes[i].1.angle(&axes[i].2) > axes[i].3)
        .collect();
    match *off.as_slice() {
        [i] => {
            let (a, d, n, tolerance) = &axes[i];
            (d.angle(&-n) <= *tolerance)
                .then(|| Implausible::FlippedAxis {
                    joint: a.joint,
                    experiment: a.experiment.clone(),
                    sliding: a.kind == crate::kinematics::JointKind::Prismatic,
                    angle_deg: d.angle(n).to_degrees(),
                })
                .into_iter()
                .collect()
        }
        [i, j] => {
            let along = |x: usize, y: usize| {
                let (d, n) = (axes[x].1, axes[y].2);
                d.angle(&n).min(d.angle(&-n)) <= axes[x].3
            };
            (along(i, j) && along(j, i))
                .then(|| Implausible::SwappedAxes {
                    joint: axes[i].0.joint,
                    other: axes[j].0.joint,
                    angle_deg: axes[i].1.angle(&axes[i].2).to_degrees(),
                })
                .into_iter()
                .collect()
        }
        _ => vec![],
    }
}

/// The significant lengths' `(nominal, calibrated)` pairs.
fn lengths(cal: &Calibration, desc: &RobotDescription) -> Vec<(f64, f64)> {
    let (n, c) = (
        row_lengths(&desc.nominal_model().rows),
        row_lengths(&cal.robot.phi_model().rows),
    );
    let longest = longest_length_m(desc);
    n.into_iter()
        .zip(c)
        .filter(|(n, _)| n.abs() >= (SIGNIFICANT_LENGTH * longest).max(MIN_SIGNIFICANT_LENGTH_M))
        .collect()
}

/// The mirror image (lengths along a rotary axis flip sign, the others keep it, each its size),
/// else a size factor beyond [`SIZE_TOLERANCE`].
fn size(cal: &Calibration, desc: &RobotDescription) -> Option<Implausible> {
    let mut pairs = lengths(cal, desc);
    // A sliding joint's travel per command scales as the coordinates do: its gain counts as a
    // length of the longest's size.
    let longest = pairs.iter().fold(1.0f64, |m, (n, _)| m.max(n.abs()));
    let ideal = RobotModel::ideal(desc);
    for (nominal, fitted) in ideal.joints.iter().zip(&cal.robot.joints) {
        if nominal.kind == JointKind::Prismatic {
            let gain = nominal.transmission.slope(0.0) / fitted.transmission.slope(0.0);
            if gain.is_finite() {
                pairs.push((longest, longest * gain));
            }
        }
    }
    let near = |ratio: f64| (ratio - 1.0).abs() <= SIZE_TOLERANCE;
    let flipped = pairs.iter().filter(|(n, c)| near(-c / n)).count();
    let kept = pairs.iter().filter(|(n, c)| near(c / n)).count();
    if flipped > 0 && flipped + kept == pairs.len() {
        return Some(Implausible::Mirrored {
            flipped,
            lengths: pairs.len(),
        });
    }
    let nn: f64 = pairs.iter().map(|(n, _)| n * n).sum();
    if nn <= 0.0 {
        return None;
    }
    // Sizes only: the signs are the handedness check's.
    let factor = pairs.iter().map(|(n, c)| n.abs() * c.abs()).sum::<f64>() / nn;
    (!near(factor)).then_some(Implausible::Size {
        factor,
        lengths: pairs.len(),
    })
}

/// Half a turn \[deg\]: over a longer sweep a first harmonic's mean slope departs from 1 by
/// less than its amplitude times 2/pi and falls to nothing over a full turn, so a scale of the
/// command column stays in the fit's misses (the real SScanSS-2 table's rotation stage, swept
/// over 356 deg with `cmd_2` scaled 1 %: a misfit 14 times the median joint's, its slope 1).
const HALF_TURN_DEG: f64 = 180.0;

fn misfits(cal: &Calibration) -> Vec<Implausible> {
    let rms: Vec<f64> = cal
        .axes
        .iter()
        .map(|a| a.residual_rms_mm)
        .filter(|r| r.is_finite())
        .collect();
    if rms.len() < 3 {
        return vec![];
    }
    let median_mm = quantile(&rms, 0.5, QuantileMethod::Linear);
    cal.axes
        .iter()
        .filter(|a| median_mm > 0.0 && a.residual_rms_mm > MISFIT_RATIO * median_mm)
        .map(|a| Implausible::Misfit {
            joint: a.joint,
            experiment: a.experiment.clone(),
            rms_mm: a.residual_rms_mm,
            median_mm,
            long_sweep_deg: match a.span {
                super::AxisSpan::Deg(span) if span > HALF_TURN_DEG => Some(span),
                _ => None,
            },
            sweep: misfit_sweep(cal, a, median_mm),
        })
        .collect()
}

/// The sweep of `axis` (a joint fitted from several sweeps) that carries its misfit: the one
/// sweep without which the joint's other sweeps, fitted alone
/// ([`super::SweepReport::without_rms_mm`]), pass the joint's misfit test (within
/// [`MISFIT_RATIO`] times `median_mm`), where without any other they do not. None where no
/// sweep or several do (two sweeps that each fit alone: either could be the one). Its worst
/// point and the RMS of its other points come from the calibration's point residuals.
fn misfit_sweep(cal: &Calibration, axis: &AxisReport, median_mm: f64) -> Option<MisfitSweep> {
    let passing: Vec<(&super::SweepReport, f64)> = axis
        .sweeps
        .iter()
        .filter_map(|s| s.without_rms_mm.map(|r| (s, r)))
        .filter(|(_, r)| *r <= MISFIT_RATIO * median_mm)
        .collect();
    let [(worst, others_mm)] = passing[..] else {
        return None;
    };
    let points: Vec<(usize, f64)> = cal
        .residuals
        .iter()
        .filter(|r| r.experiment == worst.experiment && r.joint == axis.joint && r.target == 0)
        .map(|r| (r.step, r.components_mm.iter().map(|c| c * c).sum::<f64>().sqrt()))
        .collect();
    let &(step, off) = points.iter().max_by(|a, b| a.1.total_cmp(&b.1))?;
    let rest = points.iter().filter(|p| p.0 != step).map(|p| p.1 * p.1).sum::<f64>();
    Some(MisfitSweep {
        experiment: worst.experiment.clone(),
        rms_mm: worst.residual_rms_mm,
        others_mm,
        worst: (step, off),
        rest_mm: (rest / (points.len() - 1).max(1) as f64).sqrt(),
        lines: None,
        worst_line: None,
    })
}
