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
//! - **Tool fit, cycle by cycle.** The scale is a median, so one pose written in another unit,
//!   or with two targets' numbers swapped, or a target moved on the tool, does not move it; nor
//!   does the outlier screen see a fault its pose's cycles share. Each cycle's measured targets
//!   are fitted to the description's ([`rigid_fit`]): the misfit `sqrt(SS / (3n - 6))` of `n`
//!   targets is the same in every cycle of a rigid tool (its noise, and the description's
//!   error in placing the targets, which moves with the tool). A cycle whose misfit is beyond
//!   Tukey's far-out fence of such misfits over their median
//!   ([`chi_far_out_over_median`] of `3n - 6` components, so that up to half the cycles may be
//!   off), and beyond [`FAR_OUT`] times the least standard deviation of a coordinate
//!   (`super::outliers`: the written step or an instrument's resolution), is said, per
//!   experiment, with its line. At least [`MIN_CYCLES_JUDGED`] cycles are needed for a median.
//!   A median misfit beyond [`ABSURD_SHARE`] of the described targets' spread
//!   ([`rms_spread`]) is a description whose tool targets are not where the tool's are, in
//!   every cycle: said too.
//!
//! Not seen: two targets' numbers swapped where the description places them symmetrically
//! about the third (the swap is then a rotation of the tool, and reads as an orientation
//! error of the pose).

use super::evaluate::Cycle;
use super::outliers::least_target_sigma_m;
use crate::calibration::procedure::SIZE_TOLERANCE;
use crate::kinematics::{MIRROR_RATIO, mirror_fit_rms, rigid_fit};
use crate::numerics::stats::{ABSURD_SHARE, FAR_OUT, QuantileMethod, chi_far_out_over_median, quantile, rms_spread};
use nalgebra::Point3;
use std::collections::BTreeMap;

/// Tool targets closer than this on the description \[m\] give no distance to compare.
const MIN_TARGET_DISTANCE_M: f64 = 1e-3;

/// The fewest cycles whose tool fits are judged against their median.
pub const MIN_CYCLES_JUDGED: usize = 5;

/// The warnings of the module doc's checks on `cycles`, in words.
pub(super) fn frame_warnings(cycles: &BTreeMap<usize, Vec<Cycle>>) -> Vec<String> {
    let all: Vec<&Cycle> = cycles.values().flatten().collect();
    scale_warning(&all)
        .into_iter()
        .chain(mirror_warning(&all))
        .chain(tool_fit_warnings(&all, least_target_sigma_m(cycles)))
        .collect()
}

/// A cycle's misfit of its measured targets to the description's: `sqrt(SS / (3n - 6))` \[m\]
/// from its fit's RMS, and `3n - 6` (module doc); `None` without a residual degree of freedom.
fn tool_misfit(cycle: &Cycle) -> Option<(f64, usize)> {
    let n = cycle.targets.len();
    let dof = (3 * n).checked_sub(6).filter(|&d| d > 0)?;
    Some((cycle.tool_fit_rms_m * (n as f64 / dof as f64).sqrt(), dof))
}

/// The experiments whose cycles' tool misfits are beyond the module doc's fence, in words:
/// one warning per experiment, with its cycles and lines.
fn tool_fit_warnings(cycles: &[&Cycle], least_sigma_m: f64) -> Vec<String> {
    let fits: Vec<(&Cycle, f64, usize)> = cycles
        .iter()
        .filter_map(|c| tool_misfit(c).map(|(m, dof)| (*c, m, dof)))
        .collect();
    let Some(dof) = fits.iter().map(|f| f.2).min() else {
        return Vec::new();
    };
    if fits.len() < MIN_CYCLES_JUDGED {
        return Vec::new();
    }
    let misfits: Vec<f64> = fits.iter().map(|f| f.1).collect();
    let median_m = quantile(&misfits, 0.5, QuantileMethod::Linear);
    let fence_m = (chi_far_out_over_median(dof as f64) * median_m).max(FAR_OUT * least_sigma_m);
    let mut warnings: Vec<String> = misplaced_targets_warning(cycles[0], median_m).into_iter().collect();
    let mut by_experiment: BTreeMap<&str, Vec<(&Cycle, f64)>> = BTreeMap::new();
    for (c, m, _) in fits.iter().filter(|f| f.1 > fence_m) {
        by_experiment.entry(&c.experiment).or_default().push((c, *m));
    }
    warnings.extend(by_experiment.into_iter().map(|(experiment, off)| {
            let of_experiment = cycles.iter().filter(|c| c.experiment == experiment).count();
            let worst = off.iter().map(|o| o.1).fold(0.0, f64::max);
            let places: Vec<String> = off.iter().take(5).map(|(c, _)| place(c)).collect();
            format!(
                "experiment {experiment}: {} of its {of_experiment} cycles' measured targets do not fit the description's tool targets (`tool.targets_mm`): a misfit of up to {:.3} mm against {:.3} mm, the median over all {} cycles (fence {:.3} mm), at {}{}: a target measured in another unit, two targets' numbers swapped, or a target moved on the tool; those cycles' figures are not the robot's",
                off.len(),
                worst * 1e3,
                median_m * 1e3,
                fits.len(),
                fence_m * 1e3,
                places.join(", "),
                if off.len() > places.len() { ", ..." } else { "" }
            )
        }));
    warnings
}

/// The median misfit `median_m` beyond [`ABSURD_SHARE`] of the spread of the tool targets of
/// `cycle` (the description's), in words.
fn misplaced_targets_warning(cycle: &Cycle, median_m: f64) -> Option<String> {
    let tool: Vec<Point3<f64>> = cycle.targets.iter().map(|t| t.0).collect();
    let spread_m = rms_spread(&tool);
    (median_m > ABSURD_SHARE * spread_m).then(|| {
        format!(
            "the measured targets miss the description's tool targets (`tool.targets_mm`) by a misfit of {:.3} mm in the median cycle, beyond {ABSURD_SHARE} of the targets' {:.3} mm RMS spread: a target is not where the description places it on the tool (or two targets' numbers are swapped) in every cycle; the orientation figures are not the robot's",
            median_m * 1e3,
            spread_m * 1e3
        )
    })
}

/// A cycle's place in words: its step, and its line when known.
fn place(cycle: &Cycle) -> String {
    match cycle.line {
        Some(line) => format!("step {} (line {line})", cycle.step),
        None => format!("step {}", cycle.step),
    }
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
