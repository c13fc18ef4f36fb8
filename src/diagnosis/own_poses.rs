//! The axis-experiment calibration tested on the file's own validation poses, which it did not
//! fit ([`validate`]'s test at [`OWN_POSES_FALSE_ALARM`]; with the tool frame estimated from the
//! poses where the file measured none, [`validate_free_tool`]). A miss beyond the prediction is
//! what a slip the unit checks cannot see leaves (one experiment's commands scaled within a
//! transmission's range, a wrong placement or description), a sweep's cause the poses show (a
//! held command off, a drift, a moved block: [`sweep_cause_of_misses`]), or an effect the model
//! lacks; the miss is then searched for the slips `validate` names
//! ([`explained_validation_misses`]). The result is a value ([`OwnPoses`]); `calibrate` and
//! `diagnose` say it.

use super::combined_slips::{combined_slips_searched, explained_validation_misses};
use super::outliers::{free_pose_outliers, without_outliers};
use super::slips::ExplainedMiss;
use super::sweep_causes::{SweepCause, SweepFault, SweepSearchTooLarge, sweep_cause_of_misses};
use super::validate::{FittedToolMove, Validation, ValidationOptions, Verdict, validate, validate_free_tool};
use crate::calibration::procedure::{
    AxisEstimator, Calibration, Implausible, OutlierPoint, PLAUSIBLE_AXIS_TILT_RAD, SIZE_TOLERANCE, longest_length_m,
};
use crate::measurement::{Measurement, MeasurementSet, bounded};
use crate::plan::TOOL_EXPERIMENT;
use crate::robot::RobotDescription;
use std::cell::OnceCell;
use std::collections::HashSet;

/// The false-alarm rate of the test of the file's own validation poses: a miss said on data the
/// model fits once in ten thousand files.
pub const OWN_POSES_FALSE_ALARM: f64 = 1e-4;

/// Validation poses [`own_validation_poses`] takes at most, evenly spaced through the file (as
/// the URDF and zero-offset checks take them).
pub const OWN_POSES_CHECKED: usize = 500;

/// The file's own validation poses (free poses other than the tool's, at most
/// [`OWN_POSES_CHECKED`] evenly spaced through the file) as a set of their rows with their file
/// lines, and how many poses; `None` without any.
pub fn own_validation_poses(set: &MeasurementSet, desc: &RobotDescription) -> Option<(MeasurementSet, usize)> {
    let is_pose = |m: &&Measurement| m.moved_joint == 0 && m.experiment != TOOL_EXPERIMENT;
    let mut poses: Vec<(&str, usize)> = set
        .rows()
        .iter()
        .filter(is_pose)
        .map(|m| (m.experiment.as_str(), m.step))
        .collect();
    poses.dedup();
    let kept: HashSet<(&str, usize)> = bounded::evenly_spaced(poses, OWN_POSES_CHECKED).into_iter().collect();
    let chosen: Vec<usize> = (0..set.rows().len())
        .filter(|&i| {
            let m = &set.rows()[i];
            is_pose(&m) && kept.contains(&(m.experiment.as_str(), m.step))
        })
        .collect();
    let rows: Vec<_> = chosen.iter().map(|&i| set.rows()[i].clone()).collect();
    let lines: Vec<u64> = chosen.iter().filter_map(|&i| set.line_of(i)).collect();
    let poses_set = MeasurementSet::new(desc.dof(), rows).ok()?.with_lines(lines);
    Some((poses_set, kept.len()))
}

/// How the validation poses were predicted and how far they are missed.
#[derive(Clone, Debug)]
pub struct OwnPosesFit {
    /// Validation poses tested.
    pub poses: usize,
    /// Their position residuals' RMS \[mm\].
    pub rms_mm: f64,
    /// The RMS the prediction expects \[mm\].
    pub predicted_mm: f64,
    /// Whether the tool frame, which no pose measured, was fitted to these poses.
    pub tool_fitted: bool,
}

/// A move of the nominal tool frame that fits the validation poses beyond a description's error:
/// more than [`SIZE_TOLERANCE`] of the description's longest length, or a turn beyond
/// [`PLAUSIBLE_AXIS_TILT_RAD`] (the sanity checks' bounds on how far a description may be off).
#[derive(Clone, Copy, Debug)]
pub struct ToolMoveBeyond {
    /// The tool frame's move \[mm\].
    pub moved_mm: f64,
    /// Its turn \[rad\].
    pub turned_rad: f64,
    /// The bound on the move \[mm\].
    pub bound_mm: f64,
}

/// What the slip search `validate` runs says of the misses.
#[derive(Clone, Debug)]
pub enum OwnPosesSlips {
    /// Not run: the tool frame was fitted to the poses, whose error would read as a slip.
    ToolFitted,
    /// No single slip names it, and the search of runs and of two slips at once did not run
    /// (beyond [`super::MAX_SEARCH_ROWS`] rows).
    Unsearched {
        /// The poses' rows.
        rows: usize,
    },
    /// No slip makes the poses pass.
    NoneNamed,
    /// The slips whose undoing makes every test pass.
    Named(Vec<ExplainedMiss>),
}

/// What the poses' miss is put down to.
#[derive(Clone, Debug)]
pub enum OwnPosesCause {
    /// A sweep's cause whose correction makes the poses pass: said alone.
    Sweep(SweepCause),
    /// No such cause: the part a held command explains (if any) and the slip search's answer.
    Unnamed {
        /// A held command's offset that explains a part of the miss.
        partial: Option<SweepCause>,
        /// The sweep search not run, as too costly.
        too_large: Option<SweepSearchTooLarge>,
        /// The slip search's answer.
        slips: OwnPosesSlips,
    },
}

/// A miss of the file's own validation poses.
#[derive(Clone, Debug)]
pub struct OwnPosesMiss {
    /// The fit of the poses.
    pub fit: OwnPosesFit,
    /// chi2/dof of the prediction's test.
    pub per_dof: f64,
    /// Whether the test fails (else only the tool frame's move is beyond a description's error).
    pub exceeds: bool,
    /// The tool frame's move, where it is beyond a description's error.
    pub tool_move: Option<ToolMoveBeyond>,
    /// What the miss is put down to.
    pub cause: OwnPosesCause,
}

/// The test of a file's own validation poses ([`test_own_validation_poses`]).
#[derive(Clone, Debug)]
pub enum OwnPoses {
    /// The paper's estimator predicts no error of its calibration: the miss is given, not tested.
    NotTested(OwnPosesFit),
    /// The poses miss beyond the prediction, or only a tool frame moved beyond a description's
    /// error fits them.
    Misses(Box<OwnPosesMiss>),
}

/// Whether [`test_own_validation_poses`] seeks a sweep's cause of a miss
/// ([`sweep_cause_of_misses`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SweepSearch {
    /// It does.
    Run,
    /// It does not: a slip of the instrument's coordinates was named (an axis or all three
    /// read scaled, the robot's size or handedness off), which moves every sweep and the poses
    /// alike, so that no one sweep's cause is to be sought (each hypothesis the search tries
    /// costs a calibration per trial, half a minute on a paper campaign).
    Skipped,
}

impl SweepSearch {
    /// The search after the calibration's checks `found` these: skipped where one is a slip of
    /// the coordinates ([`Implausible::is_coordinate_slip`]).
    pub fn after(found: &[Implausible]) -> SweepSearch {
        match found.iter().any(Implausible::is_coordinate_slip) {
            true => SweepSearch::Skipped,
            false => SweepSearch::Run,
        }
    }
}

/// The axis-experiment calibration `cal` of `set` tested on the file's own validation poses
/// (module docs), seeking a sweep's cause of a miss as `search` says: the poses' gross errors
/// (where they fail the test: [`free_pose_outliers`], flagged as dropped unless `keep`; a point
/// 500 mm off fails the test of every pose and hides the cause of a real miss), and the test
/// without those dropped, `None` without validation poses, when they cannot be validated, or
/// when they are consistent with the prediction.
pub fn test_own_validation_poses(
    cal: &Calibration,
    desc: &RobotDescription,
    set: &MeasurementSet,
    (search, keep): (SweepSearch, bool),
) -> (Vec<OutlierPoint>, Option<OwnPoses>) {
    let Some((poses_set, n)) = own_validation_poses(set, desc) else {
        return (Vec::new(), None);
    };
    let Some(first) = validated(&poses_set, cal, desc) else {
        return (Vec::new(), None);
    };
    let fails = |v: &Validation| {
        v.validation
            .as_ref()
            .and_then(|p| p.chi_square.as_ref())
            .is_some_and(|t| t.verdict == Verdict::Exceeds)
    };
    let outliers = match fails(&first.0) {
        true => free_pose_outliers(&first.0, &poses_set, (cal, desc), keep).unwrap_or_default(),
        false => Vec::new(),
    };
    let dropped: Vec<OutlierPoint> = outliers.iter().filter(|o| o.dropped).cloned().collect();
    if dropped.is_empty() {
        return (outliers, tested(cal, desc, set, (&poses_set, n), first, search));
    }
    let kept = without_outliers(&poses_set, &dropped);
    let Some(second) = validated(&kept, cal, desc) else {
        return (outliers, None);
    };
    (outliers, tested(cal, desc, set, (&kept, n), second, search))
}

/// The validation of the poses `poses_set` against `cal` at [`OWN_POSES_FALSE_ALARM`], with the
/// tool frame's move where the file measured none. A tool frame left nominal is off by an
/// error no covariance holds: estimated from the poses, so that only what no tool frame
/// explains is judged, and a move beyond what a description may be off by is said.
fn validated(
    poses_set: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
) -> Option<(Validation, Option<FittedToolMove>)> {
    let options = ValidationOptions::of_calibration(cal, OWN_POSES_FALSE_ALARM);
    match cal.tool {
        None => {
            let (v, fitted) = validate_free_tool(poses_set, cal, desc, &options).ok()?;
            Some((v, Some(fitted)))
        }
        Some(_) => Some((validate(poses_set, cal, desc, &options).ok()?, None)),
    }
}

/// [`test_own_validation_poses`] of the poses `poses_set` (`n` poses), validated as `(v,
/// tool_move)`.
fn tested(
    cal: &Calibration,
    desc: &RobotDescription,
    set: &MeasurementSet,
    (poses_set, n): (&MeasurementSet, usize),
    (v, tool_move): (Validation, Option<FittedToolMove>),
    search: SweepSearch,
) -> Option<OwnPoses> {
    let part = v.validation.as_ref()?;
    let fit = OwnPosesFit {
        poses: n,
        rms_mm: part.rms_mm,
        predicted_mm: part.predicted_mm.total,
        tool_fitted: tool_move.is_some(),
    };
    if cal.options.estimator == AxisEstimator::Paper {
        // No covariance: the prediction holds the noise and repeatability only, and a miss
        // beyond them is the calibration's own error, which this estimator does not predict.
        return Some(OwnPoses::NotTested(fit));
    }
    let test = part.chi_square.as_ref()?;
    let beyond = tool_move.and_then(|m| tool_move_beyond(&m, desc));
    let exceeds = test.verdict == Verdict::Exceeds;
    // The slip search runs at most once: the sweep's guard and the answer share it.
    let named = OnceCell::new();
    let slips_named = || named.get_or_init(|| explained_validation_misses(poses_set, cal, desc, &v));
    let (sweep, too_large) =
        match (exceeds && search == SweepSearch::Run).then(|| sweep_cause_of_misses(cal, desc, set, poses_set)) {
            Some(Ok(sweep)) => (sweep, None),
            Some(Err(too_large)) => (None, Some(too_large)),
            None => (None, None),
        };
    let sweep = sweep.filter(|s| said_beside_slips(s, fit.tool_fitted, || slips_named().is_empty()));
    let cause = match sweep {
        Some(s) if s.passes => OwnPosesCause::Sweep(s),
        _ if !exceeds && beyond.is_none() => return None,
        partial => OwnPosesCause::Unnamed {
            partial,
            too_large,
            slips: slips_of(poses_set, fit.tool_fitted, slips_named),
        },
    };
    Some(OwnPoses::Misses(Box::new(OwnPosesMiss {
        fit,
        per_dof: test.per_dof,
        exceeds,
        tool_move: beyond,
        cause,
    })))
}

/// Whether a sweep's cause found against the file's own validation poses is said: a held
/// command's offset and the whole file's drift (which moves the poses too) always; a sweep's
/// drift or moved block (three parameters, which take in much of a miss of another cause) only
/// where the slip search `validate` runs names no slip of the poses themselves (`unnamed`; a
/// column scaled on the validation rows alone reads as a move of the sweep whose joint it
/// turns). With the tool frame fitted to the poses, that search does not run.
fn said_beside_slips(sweep: &SweepCause, tool_fitted: bool, unnamed: impl FnOnce() -> bool) -> bool {
    matches!(sweep.fault, SweepFault::HeldOffset { .. }) || sweep.experiment.is_none() || tool_fitted || unnamed()
}

/// The slip search's answer on the poses `poses` (`named`, run once), or that it did not run.
fn slips_of<'a>(
    poses: &MeasurementSet,
    tool_fitted: bool,
    named: impl FnOnce() -> &'a Vec<ExplainedMiss>,
) -> OwnPosesSlips {
    if tool_fitted {
        return OwnPosesSlips::ToolFitted;
    }
    let named = named();
    match (named.is_empty(), combined_slips_searched(poses)) {
        (true, false) => OwnPosesSlips::Unsearched {
            rows: poses.rows().len(),
        },
        (true, true) => OwnPosesSlips::NoneNamed,
        (false, _) => OwnPosesSlips::Named(named.clone()),
    }
}

/// The move `m` of the nominal tool frame, where it is beyond a description's error
/// ([`ToolMoveBeyond`]); `None` within.
fn tool_move_beyond(m: &FittedToolMove, desc: &RobotDescription) -> Option<ToolMoveBeyond> {
    let bound_mm = SIZE_TOLERANCE * longest_length_m(desc) * 1e3;
    let (moved_mm, turned_rad) = (m.translation_mm.norm(), m.rotation_rad.norm());
    (moved_mm > bound_mm || turned_rad > PLAUSIBLE_AXIS_TILT_RAD).then_some(ToolMoveBeyond {
        moved_mm,
        turned_rad,
        bound_mm,
    })
}
