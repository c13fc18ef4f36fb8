//! The axis-experiment calibration tested on the file's own validation poses, which it did not
//! fit, in words: the miss, a sweep's cause, the slip search's answer.

use super::Args;
use crate::cli::checks;
use axiscal::calibration::procedure::{Calibration, Implausible, PLAUSIBLE_AXIS_TILT_RAD, SIZE_TOLERANCE};
use axiscal::diagnosis::{
    MAX_SWEEP_SEARCH_CALIBRATIONS, OwnPoses, OwnPosesCause, OwnPosesMiss, OwnPosesSlips, SweepSearch,
    SweepSearchTooLarge, ToolMoveBeyond, test_own_validation_poses,
};
use axiscal::measurement::{MeasurementSet, format_f64};
use axiscal::robot::RobotDescription;
use std::path::Path;

/// The warning of a miss of the file's own validation poses by `cal` (calibrated from `kept`;
/// [`misses_own_validation_poses`]; not with `--refine`, which fits them), seeking a sweep's
/// cause unless the checks `found` a slip of the coordinates ([`SweepSearch::after`]).
pub(super) fn own_poses_miss(
    cal: &Calibration,
    (desc, kept): (&RobotDescription, &MeasurementSet),
    args: &Args,
    found: &[Implausible],
) -> Option<OwnPosesWarning> {
    if args.refine {
        return None;
    }
    let stated = args.repeatability_rad.as_deref();
    misses_own_validation_poses(
        cal,
        (desc, kept, &args.data),
        (stated, SweepSearch::after(found), args.keep_outliers),
    )
}

/// A miss of the file's own validation poses, in words ([`misses_own_validation_poses`]).
pub(in crate::cli) struct OwnPosesWarning {
    /// The warning.
    pub text: String,
    /// The experiment whose reading by the reference-pose test (a moved block, a held offset)
    /// it replaces: a drift through that sweep, which the test reads so at the reference pose,
    /// and which fits the validation poses.
    pub replaces: Option<String>,
}

/// The axis-experiment calibration tested on the file's own validation poses, which it did not
/// fit ([`test_own_validation_poses`], seeking a sweep's cause as `search` says), in words: a
/// sweep's cause that makes them pass alone, else the miss with what the slip search `validate`
/// runs names; the paper's estimator's untested miss as a note. The poses' gross errors are
/// warned of as they are found (left out of the test unless `keep`). `None` without validation
/// poses or when they are consistent.
pub(in crate::cli) fn misses_own_validation_poses(
    cal: &Calibration,
    (desc, set, data): (&RobotDescription, &MeasurementSet, &Path),
    (stated_repeatability, search, keep): (Option<&[f64]>, SweepSearch, bool),
) -> Option<OwnPosesWarning> {
    let place = data.display().to_string();
    let (outliers, tested) = test_own_validation_poses(cal, desc, set, (search, keep));
    checks::print_warnings(&checks::outlier_warnings(
        &outliers,
        data,
        "its own validation poses tested",
    ));
    let miss = match tested? {
        OwnPoses::NotTested(fit) => {
            eprintln!(
                "note: {place}: the calibrated model misses this file's own {} validation poses (not fitted) by {:.3} mm RMS{}; \
                 not tested: the paper's estimator predicts no error of its calibration (the noise and repeatability alone \
                 give {:.3} mm; `--estimator ml` predicts and tests it)",
                fit.poses,
                fit.rms_mm,
                if fit.tool_fitted {
                    ", with the tool frame fitted to them"
                } else {
                    ""
                },
                fit.predicted_mm
            );
            return None;
        }
        OwnPoses::Misses(miss) => miss,
    };
    let (partial, slips) = match &miss.cause {
        OwnPosesCause::Sweep(sweep) => {
            return Some(OwnPosesWarning {
                text: crate::cli::sweep_cause::words(sweep, &place, miss.fit.poses),
                replaces: sweep.shadows.as_ref().and(sweep.experiment.clone()),
            });
        }
        OwnPosesCause::Unnamed {
            partial,
            too_large,
            slips,
        } => (partial, (too_large, slips)),
    };
    let (too_large, slips) = slips;
    let sweep_part = partial
        .as_ref()
        .map(|h| crate::cli::sweep_cause::part_words(h, &place))
        .unwrap_or_default();
    let first = understated_repeatability(desc, stated_repeatability);
    let cause = own_poses_slips(slips, data);
    let beyond = miss.tool_move.map(tool_move_words).unwrap_or_default();
    let unsearched = too_large.as_ref().map(sweep_search_too_large_words).unwrap_or_default();
    Some(OwnPosesWarning {
        text: format!(
            "{}{beyond}: {first}{sweep_part}{cause}{unsearched}",
            own_miss_words(&miss)
        ),
        replaces: None,
    })
}

/// Why no sweep's cause of a miss was sought ([`SweepSearchTooLarge`]).
pub(super) fn sweep_search_too_large_words(t: &SweepSearchTooLarge) -> String {
    format!(
        "; no sweep's held command, drift or moved block was tried as its cause (its {} hypotheses would cost {} calibrations, \
         beyond the {MAX_SWEEP_SEARCH_CALIBRATIONS} the search runs; they grow as the square of the joints): check each sweep's \
         held commands against the controller and the reference-pose warnings above",
        t.hypotheses, t.calibrations
    )
}

/// The first clause of a miss of the file's own validation poses: by how much, against what.
pub(super) fn own_miss_words(miss: &OwnPosesMiss) -> String {
    let (n, rms, predicted) = (miss.fit.poses, miss.fit.rms_mm, miss.fit.predicted_mm);
    let tool = if miss.fit.tool_fitted {
        ", with the tool frame, which no pose measured, fitted to these poses"
    } else {
        ""
    };
    if !miss.exceeds || rms > predicted {
        format!(
            "the calibrated model misses this file's own {n} validation poses (not fitted) by {rms:.3} mm RMS against {predicted:.3} mm predicted (chi2/dof {:.2}{tool})",
            miss.per_dof
        )
    } else {
        format!(
            "the calibrated model's misses of this file's own {n} validation poses (not fitted) fail the prediction's chi-square test (chi2/dof {:.2}{tool}) though their RMS, {rms:.3} mm, is within the {predicted:.3} mm predicted: their pattern, not their size, contradicts it (some poses or directions missed well beyond their own predicted error, where the prediction is tight)",
            miss.per_dof
        )
    }
}

/// What the slip search `validate` runs says of the misses of the file's own validation poses
/// (read from `data`): the slips whose undoing makes every test pass, in
/// `validate`'s words, or, when none does, the causes left: a slip of the whole file the
/// calibration has taken into its geometry from the axis experiments too, the description, or
/// an effect the model lacks (a joint's compliance: `diagnose` models it); with the tool frame fitted
/// to the poses (the search not run), what to check.
pub(super) fn own_poses_slips(slips: &OwnPosesSlips, data: &Path) -> String {
    match slips {
        OwnPosesSlips::Unsearched { rows } => {
            let words = checks::unsearched_words(*rows, data);
            format!("{words} (`axiscal validate` on a part of the file runs it)")
        }
        OwnPosesSlips::Named(named) => {
            let said: Vec<String> = named.iter().map(|m| checks::explained_miss_words(m, data)).collect();
            format!("`axiscal validate`'s slip search names it: {}", said.join("; "))
        }
        // The nominal tool frame's error would be read as a slip of the coordinates.
        OwnPosesSlips::ToolFitted => "check one experiment's commands or coordinates for a scale or offset the unit checks cannot tell (e.g. gradians), the description's \
             placement and lengths, or an effect the model lacks (`axiscal validate`, `axiscal diagnose` on this file)"
            .to_string(),
        OwnPosesSlips::NoneNamed => "no slip `axiscal validate` tests (a command column scaled or offset, one coordinate column or all three scaled, the \
                coordinates shifted; over these poses or a run of them, one or two at once) makes them pass against this calibration: \
                a slip the axis experiments carry as well, which the calibration has taken into its geometry (see the warnings above, or \
                check each column for a scale or offset throughout the file, e.g. gradians), the description's placement and lengths, or \
                an effect the model lacks, such as joints yielding under the load (`axiscal diagnose` on this file models it)"
            .to_string(),
    }
}

/// What a move of the nominal tool frame that fits the validation poses beyond a description's
/// error says ([`axiscal::diagnosis::ToolMoveBeyond`]): the poses then miss by more than the
/// unmeasured tool frame's error, e.g. along an axis the sweeps cannot place (a SCARA's height).
pub(super) fn tool_move_words(m: ToolMoveBeyond) -> String {
    format!(
        "; the tool frame would have to move {:.1} mm and turn {:.2} deg from the description's to fit them, beyond a description's error \
         ({:.1} mm, {:.0} % of its longest length; {:.0} deg): the poses are off by more than the unmeasured tool frame explains",
        m.moved_mm,
        m.turned_rad.to_degrees(),
        m.bound_mm,
        SIZE_TOLERANCE * 100.0,
        PLAUSIBLE_AXIS_TILT_RAD.to_degrees()
    )
}

/// The first cause of a miss of the validation poses when `--repeatability-rad` (`stated`) is
/// 0 or below the description's `repeatability_sigma` for some joint: the prediction then
/// leaves out the joints' own scatter. Empty otherwise.
pub(super) fn understated_repeatability(desc: &RobotDescription, stated: Option<&[f64]>) -> String {
    let Some(stated) = stated else { return String::new() };
    let of_joint = |k: usize| if stated.len() == 1 { stated[0] } else { stated[k] };
    // `--repeatability-rad` holds 1 or one value per joint (checked before calibrating).
    let joints = if stated.len() == 1 {
        desc.dof()
    } else {
        stated.len().min(desc.dof())
    };
    let low = (0..joints).find(|&k| of_joint(k) <= 0.0 || of_joint(k) < desc.joints[k].repeatability_sigma);
    let Some(k) = low else { return String::new() };
    let unit = if desc.joints[k].kind == axiscal::kinematics::JointKind::Revolute {
        "rad"
    } else {
        "m"
    };
    let values: Vec<String> = stated.iter().map(|v| format_f64(*v)).collect();
    format!(
        "the stated repeatability (--repeatability-rad {}: joint {} at {} {unit}, the description's repeatability_sigma \
         {} {unit}) leaves the joints' own scatter out of the prediction: drop --repeatability-rad or give the \
         joints' real repeatability; else ",
        values.join(","),
        k + 1,
        format_f64(of_joint(k)),
        format_f64(desc.joints[k].repeatability_sigma)
    )
}
