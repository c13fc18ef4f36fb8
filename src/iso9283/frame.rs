//! The instrument frame of ISO cycles checked against the description before their figures
//! are trusted. An attained pose is the description's tool targets fitted to the measured
//! points, so coordinates in another scale or a left-handed frame give figures that look like
//! a robot's errors (hundreds of millimetres of `AP_P`, radians of `AP_a`) without a word.
//!
//! - **Scale.** The distance between two tool targets measured in one cycle over the
//!   description's, the median over every cycle and pair of targets: a rigid tool keeps its
//!   targets' distances whatever the robot does, so the ratio is the instrument's scale against
//!   the description's millimetres. Beyond [`SIZE_TOLERANCE`] of 1 (the calibration's check of
//!   a robot's size against its description) it is said.
//! - **Handedness.** Every measured target against the commanded tool pose applied to the
//!   description's target: the best rotation ([`rigid_fit`]) against the best mirror image
//!   ([`mirror_fit_rms`]). In a right-handed frame a rotation fits at least as well as any
//!   mirror (Kabsch); where the points are nearly flat, both fit about equally. The rotation
//!   leaving more than [`MIRROR_RATIO`] times the mirror's RMS is a left-handed frame.

use super::evaluate::Cycle;
use crate::calibration::procedure::SIZE_TOLERANCE;
use crate::kinematics::{MIRROR_RATIO, mirror_fit_rms, rigid_fit};
use crate::numerics::stats::{QuantileMethod, quantile};
use nalgebra::Point3;
use std::collections::BTreeMap;

/// Tool targets closer than this on the description \[m\] give no distance to compare.
const MIN_TARGET_DISTANCE_M: f64 = 1e-3;

/// The warnings of the module doc's checks on `cycles`, in words.
pub(super) fn frame_warnings(cycles: &BTreeMap<usize, Vec<Cycle>>) -> Vec<String> {
    let all: Vec<&Cycle> = cycles.values().flatten().collect();
    scale_warning(&all).into_iter().chain(mirror_warning(&all)).collect()
}

/// The median ratio of measured to described tool-target distances, beyond
/// [`SIZE_TOLERANCE`] of 1.
fn scale_warning(cycles: &[&Cycle]) -> Option<String> {
    let mut ratios: Vec<(f64, &Cycle, f64, f64)> = Vec::new();
    for c in cycles {
        for (i, (ti, mi)) in c.targets.iter().enumerate() {
            for (tj, mj) in &c.targets[i + 1..] {
                let described = (ti - tj).norm();
                if described >= MIN_TARGET_DISTANCE_M {
                    let measured = (mi - mj).norm();
                    ratios.push((measured / described, c, measured, described));
                }
            }
        }
    }
    let median = quantile(
        &ratios.iter().map(|r| r.0).collect::<Vec<_>>(),
        0.5,
        QuantileMethod::Linear,
    );
    if !median.is_finite() || (median - 1.0).abs() <= SIZE_TOLERANCE {
        return None;
    }
    let (_, c, measured, described) = ratios
        .iter()
        .min_by(|a, b| (a.0 - median).abs().total_cmp(&(b.0 - median).abs()))?;
    Some(format!(
        "the tool targets are measured {median:.4} times as far apart as the description gives them (median over {} pairs; e.g. experiment {} cycle (step) {}: {:.3} where `tool.targets_mm` gives {:.3} mm): check the unit and scale of x_mm, y_mm, z_mm (an instrument exporting other units) and the description's tool targets; every figure is in the instrument's scale",
        ratios.len(),
        c.experiment,
        c.step,
        measured * 1e3,
        described * 1e3
    ))
}

/// Every measured target against the commanded tool pose's: a mirror image fitting
/// [`MIRROR_RATIO`] times better than any rotation.
fn mirror_warning(cycles: &[&Cycle]) -> Option<String> {
    let (commanded, measured): (Vec<Point3<f64>>, Vec<Point3<f64>>) = cycles
        .iter()
        .flat_map(|c| c.targets.iter().map(|(t, m)| (c.commanded * t, *m)))
        .unzip();
    let (_, rotation_m) = rigid_fit(&commanded, &measured)?;
    let mirror_m = mirror_fit_rms(&commanded, &measured)?;
    (rotation_m > MIRROR_RATIO * mirror_m).then(|| {
        format!(
            "the measured targets fit a mirror image of the commanded ones ({:.3} mm RMS) far better than any rotation of them ({:.3} mm RMS): the instrument frame is left-handed (one coordinate's sign flipped on export), and the orientation figures (AP_a, AP_b, AP_c) are meaningless; check the x_mm, y_mm, z_mm columns",
            mirror_m * 1e3,
            rotation_m * 1e3
        )
    })
}
