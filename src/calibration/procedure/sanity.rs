//! A calibration checked against its description before it is reported: results that no
//! instrument and robot of this description can give are said loudly, with what to check.
//!
//! - **Handedness.** The lengths of the calibrated rows (`a`, `b`, `h` of Table 2) against
//!   the description's, on the lengths of at least [`SIGNIFICANT_LENGTH`] of the longest. In a
//!   left-handed instrument frame (one coordinate's sign flipped on export) the lengths along a
//!   rotary axis or its common normals flip sign and keep their size (the axis is oriented by
//!   its motion: a pseudovector); no robot of the description gives that.
//! - **Size.** The least-squares factor `s = sum(|c| |n|) / sum(n^2)` of the same lengths'
//!   sizes, calibrated `c` over described `n`, each sliding joint's travel per command (its
//!   transmission's slope, described over calibrated) counted as a length of the longest's
//!   size. A robot of its description is within a few per cent of 1; other factors are a unit
//!   or scale error of the coordinates, or another robot. Beyond [`SIZE_TOLERANCE`] it is said.
//! - **Sweeps.** A joint whose fit misses its points by more than [`MISFIT_RATIO`] times the
//!   median of every joint's residual RMS: its points are not on one arc or line of the joint (a
//!   block of rows shifted, a sweep partly in other units, a target moved on its link). The
//!   noise estimate and every sigma of the calibration are inflated with it.

use super::Calibration;
use crate::kinematics::JointKind;
use crate::numerics::stats::{QuantileMethod, quantile};
use crate::robot::{RobotDescription, RobotModel};

/// Lengths shorter than this share of the description's longest are left out of the size
/// factor: a nominal zero or a few millimetres of offset says nothing of the scale.
pub const SIGNIFICANT_LENGTH: f64 = 0.05;

/// The size factor may differ from 1 by this much before it is said: a description of the
/// robot measured is within a few per cent of it.
pub const SIZE_TOLERANCE: f64 = 0.2;

/// A joint's residual RMS beyond this many times the median joint's is said: 9 times the
/// variance, more than the swept joints' repeatability at different radii gives (1.7 times on
/// the paper robot).
pub const MISFIT_RATIO: f64 = 3.0;

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
    },
}

impl std::fmt::Display for Implausible {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Implausible::Mirrored { flipped, lengths } => write!(
                f,
                "the calibrated robot is the mirror image of its description ({flipped} of its {lengths} lengths have the description's size with the opposite sign): the instrument frame is left-handed (one coordinate's sign flipped on export); check the x_mm, y_mm, z_mm columns"
            ),
            Implausible::Size { factor, lengths } => write!(
                f,
                "the calibrated robot is {factor:.3} times its description's size (over its {lengths} lengths): check the unit and scale of x_mm, y_mm, z_mm (an instrument exporting other units), or whether the description is of this robot"
            ),
            Implausible::Misfit {
                joint,
                experiment,
                rms_mm,
                median_mm,
            } => write!(
                f,
                "joint {joint} ({experiment}): the fit misses its points by {rms_mm:.3} mm RMS, {:.1} times the median joint's {median_mm:.3} mm: its points are not on one arc or line of the joint (a block of rows shifted, part of the sweep in other units, a target moved on its link); the noise estimate and every sigma are inflated by it",
                rms_mm / median_mm
            ),
        }
    }
}

/// The checks of the module doc on `cal`, calibrated with the description `desc`.
pub fn implausible(cal: &Calibration, desc: &RobotDescription) -> Vec<Implausible> {
    let mut found: Vec<Implausible> = size(cal, desc).into_iter().collect();
    found.extend(misfits(cal));
    found
}

/// The significant lengths' `(nominal, calibrated)` pairs.
fn lengths(cal: &Calibration, desc: &RobotDescription) -> Vec<(f64, f64)> {
    let of =
        |rows: &[crate::kinematics::PhiRow]| -> Vec<f64> { rows.iter().flat_map(|r| [r.a_m, r.b_m, r.h_m]).collect() };
    let (n, c) = (of(&desc.nominal_model().rows), of(&cal.robot.phi_model().rows));
    let longest = n.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    n.into_iter()
        .zip(c)
        .filter(|(n, _)| longest > 0.0 && n.abs() >= SIGNIFICANT_LENGTH * longest)
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
        })
        .collect()
}
