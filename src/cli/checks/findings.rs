//! What the fits found in the data, as warnings naming the file's lines: outlier points and
//! poses, misses a slip explains, a sweep's bump or drifting end.

use super::print_warnings;
use anyhow::{Result, bail};
use axiscal::calibration::procedure::{CalibrationOptions, calibrate};
use axiscal::measurement::MeasurementSet;
use axiscal::robot::RobotDescription;
use std::path::Path;

/// One warning line per free pose an outlier test flagged in `set` (read from `data`), with
/// the line of its first row; `done` is what the command did without it (`calibrated`,
/// `refined`).
pub fn print_pose_outliers(
    outliers: &[axiscal::calibration::free_pose::OutlierPose],
    set: &MeasurementSet,
    data: &Path,
    done: &str,
) {
    for o in outliers {
        let row = set
            .rows()
            .iter()
            .position(|m| m.experiment == o.experiment && m.step == o.step);
        let place = row
            .and_then(|r| set.line_of(r))
            .map_or_else(|| data.display().to_string(), |l| format!("{}:{l}", data.display()));
        let what = if o.dropped {
            format!("{done} without it (--keep-outliers keeps it)")
        } else {
            "kept (--keep-outliers)".to_string()
        };
        let check = match (o.spacing_departure_mm, o.spacing_fence_mm) {
            (Some(off), Some(fence)) if off <= fence => format!(
                "its targets agree with each other (their spacings within {off:.3} mm of every pose's, inside the {fence:.3} mm their noise reaches), so the tool as a whole sits off: the robot did not reach this pose as the others (its repeatability, an effect the model lacks) or its commands slipped; check its commands, else measure it again"
            ),
            (Some(off), Some(fence)) => format!(
                "its targets' spacings differ from every other pose's by {off:.3} mm (their noise reaches {fence:.3} mm): a target id swapped, one target's point off or the pose in other units; check its rows' target ids, coordinates and units"
            ),
            _ => "check its rows' target ids, coordinates, commands and units".to_string(),
        };
        let fence = match o.false_alarm {
            Some(rate) => format!(
                "its leverage in the fit and the noise of the poses near it allow, a clean file's poses passing with {:.0} % probability",
                100.0 * (1.0 - rate)
            ),
            None => "Q3 + 3 IQR of the poses' RMS".to_string(),
        };
        eprintln!(
            "warning: {place}: outlier pose: experiment {} step {}: RMS {:.4} mm beyond the fence {:.4} mm ({fence}): {what}; {check}",
            o.experiment, o.step, o.rms_mm, o.fence_mm
        );
    }
}

/// One warning line per point an outlier test flagged in `data` (a sweep's, or a validation
/// point, `joint` 0); `done` is what the command did without it (`calibrated`, `diagnosed`).
pub fn print_outliers(outliers: &[axiscal::calibration::procedure::OutlierPoint], data: &Path, done: &str) {
    print_warnings(&outlier_warnings(outliers, data, done));
    print_approach_notes(outliers, data, done);
}

/// One note per sweep's first point the outlier test found off only by its joint's backlash
/// (`approach`, [`axiscal::calibration::procedure::OutlierPoint`]): not a wrong row, so not a
/// warning; `done` as in [`print_outliers`].
pub fn print_approach_notes(outliers: &[axiscal::calibration::procedure::OutlierPoint], data: &Path, done: &str) {
    for o in outliers {
        let Some(turn) = o.approach else { continue };
        let (place, what) = outlier_place(o, data, done);
        // A turning joint's turn in mrad, a sliding one's travel in mm: both 1e3 times the value.
        eprintln!(
            "note: {place}: experiment {} step {}, the sweep's first point, taken before joint {} moved: {:.3} mm ahead \
             along the sweep's motion of the fit of its other points ({:.1} times their noise), as {:.2} mrad more of \
             the joint's turn (mm of a sliding joint's travel) would put it, and on it across the motion: the joint's backlash \
             (or a reversal's lost motion), taken up on the other side before the sweep's first move, not a wrong row: \
             {what}. Approach every sweep's first point in the direction the sweep then moves to keep it",
            o.experiment,
            o.step,
            o.joint,
            o.residual_mm,
            o.normalised_residual,
            turn * 1e3
        );
    }
}

/// A flagged point's place (`FILE:LINE`) and what the command did with it.
pub(in crate::cli) fn outlier_place(
    o: &axiscal::calibration::procedure::OutlierPoint,
    data: &Path,
    done: &str,
) -> (String, String) {
    let place = o
        .line
        .map_or_else(|| data.display().to_string(), |l| format!("{}:{l}", data.display()));
    let what = if o.dropped {
        format!("{done} without it (--keep-outliers keeps it)")
    } else {
        "kept (--keep-outliers)".to_string()
    };
    (place, what)
}

/// [`print_outliers`]'s lines, without `warning: `.
pub fn outlier_warnings(
    outliers: &[axiscal::calibration::procedure::OutlierPoint],
    data: &Path,
    done: &str,
) -> Vec<String> {
    let mut lines = Vec::new();
    for o in outliers.iter().filter(|o| o.approach.is_none()) {
        let (place, what) = outlier_place(o, data, done);
        let clean_pass = format!(
            "a clean file's sweeps pass it with {:.0} % probability",
            100.0 * (1.0 - axiscal::calibration::procedure::SWEEP_POINTS_FALSE_ALARM)
        );
        let (from, noise, fence_of, check) = match (o.joint, o.target) {
            (0, _) => (
                "the calibrated model",
                "the noise",
                "Q3 + 3 IQR of every validation point's, at least what the noise reaches once in a hundred clean files), and far from its pose's other targets (an effect moves them alike",
                "coordinates and target id",
            ),
            // A sweep's second target, judged by its passive angle (eqs. 14-15).
            (_, 1) => (
                "the curve of its neighbours' passive angles",
                "their scatter",
                "Q3 + 3 IQR of every sweep point's",
                "coordinates and target id (a reading swapped with another step's)",
            ),
            _ => (
                "the fit of its sweep's other points",
                "the noise of the sweep's other points",
                clean_pass.as_str(),
                "coordinates and commands",
            ),
        };
        lines.push(format!(
            "{place}: outlier: experiment {} step {} target {}: {:.3} mm from {from}, {:.1} times {noise}, beyond the fence {:.1} ({fence_of}): {what}; check this row's {check}",
            o.experiment, o.step, o.target, o.residual_mm, o.normalised_residual, o.fence
        ));
    }
    lines
}

/// Why a calibration (or a validation, a diagnosis) with `--noise-mm given_mm` failed when the
/// data scatter far more than that: the calibration of `set`'s axis experiments weighted with
/// the noise their residuals estimate succeeds, and `given_mm` lies below that estimate's 95 %
/// interval. Names the failed joint `failed_joint` (else the one whose residuals are the
/// largest) and its residual RMS against `given_mm`; `None` when `given_mm` is within the
/// estimate or `set` has no axis experiment to estimate it from. `failing` names what failed
/// (`the fits`), `without` what they are weighted with when `--noise-mm` is not given (`it`:
/// the estimate).
pub fn noise_far_below(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &CalibrationOptions,
    given_mm: f64,
    failed_joint: Option<usize>,
    [failing, without]: [&str; 2],
) -> Option<String> {
    // As without --noise-mm: a first pass at the default noise, then the estimate's.
    let estimating = CalibrationOptions {
        estimate_noise: true,
        noise_rms_3d_mm: CalibrationOptions::default().noise_rms_3d_mm,
        ..options.clone()
    };
    let cal = calibrate(set, desc, &estimating).ok()?;
    let estimate = cal.noise.as_ref()?.estimate.as_ref()?;
    if given_mm >= estimate.interval.low_mm {
        return None;
    }
    let largest = || {
        cal.axes
            .iter()
            .max_by(|a, b| a.residual_rms_mm.total_cmp(&b.residual_rms_mm))
    };
    let axis = failed_joint
        .and_then(|j| cal.axes.iter().find(|a| a.joint == j))
        .or_else(largest)?;
    Some(format!(
        "experiment {} (joint {}): the residuals ({:.4} mm RMS) are {:.0} times --noise-mm {}; --noise-mm is too \
         small or the data are bad: {failing} weighted with it fail, while the residuals estimate a noise of {:.4} mm \
         (95 % interval {:.4}-{:.4} mm; without --noise-mm {failing} are weighted with {without})",
        axis.experiment,
        axis.joint,
        axis.residual_rms_mm,
        axis.residual_rms_mm / given_mm,
        axiscal::measurement::format_f64(given_mm),
        estimate.rms_3d_mm,
        estimate.interval.low_mm,
        estimate.interval.high_mm
    ))
}

/// A slip found in `data` ([`axiscal::diagnosis::ExplainedMiss`]) in words: the file and line
/// of its first row, its columns and what it is.
pub fn explained_miss_words(m: &axiscal::diagnosis::ExplainedMiss, data: &Path) -> String {
    let place = m
        .line
        .map_or_else(|| data.display().to_string(), |l| format!("{}:{l}", data.display()));
    format!("{place}: `{}`: {}", m.field, m.message)
}

/// The free-pose misses a slip in `data` explains ([`axiscal::diagnosis::explained_misses`]) as
/// one error naming the file, the first row's line and the column, unless `skip`
/// (`--skip-unit-check`): the model is not blamed for a column in other units.
pub fn refuse_explained_misses(misses: &[axiscal::diagnosis::ExplainedMiss], data: &Path, skip: bool) -> Result<()> {
    if skip || misses.is_empty() {
        return Ok(());
    }
    let all: Vec<String> = misses.iter().map(|m| explained_miss_words(m, data)).collect();
    bail!(
        "{}; if the units are right after all, pass --skip-unit-check",
        all.join("; ")
    )
}

/// The warning of a sweep whose first or last points sit off its others (`end`): the points
/// named by their lines, since two moved points at an end cannot be told from two wrong
/// readings; the offset is the end points' from the others.
pub(super) fn print_sweep_end(
    b: &axiscal::calibration::procedure::SweepBump,
    end: &axiscal::calibration::procedure::SweepEnd,
    data: &Path,
) {
    let file = data.display();
    let place = end.points[0]
        .1
        .map_or_else(|| file.to_string(), |l| format!("{file}:{l}"));
    let lines: Vec<String> = end.points.iter().filter_map(|p| p.1.map(|l| l.to_string())).collect();
    let steps: Vec<String> = end.points.iter().map(|p| p.0.to_string()).collect();
    let rows = match lines.len() == end.points.len() {
        true => format!("lines {}, steps {}", lines.join(", "), steps.join(", ")),
        false => format!("steps {}", steps.join(", ")),
    };
    let sign = if end.first { -1.0 } else { 1.0 };
    let [x, y, z] = b.shift_mm.map(|v| sign * v);
    let [sx, sy, sz] = b.shift_sigma_mm;
    let (which, others, moved) = match end.first {
        true => (
            "first",
            "later",
            "after them (every later row of the file is then in its new place too)",
        ),
        false => ("last", "earlier", "before them"),
    };
    eprintln!(
        "warning: {place}: experiment {}'s {which} {} of {} points ({rows}) sit ({x:.2}, {y:.2}, {z:.2}) \
         (+- {sx:.2}, {sy:.2}, {sz:.2}) mm off its {others} points (p = {:.1e} over the {} sweep ends tried in the \
         file; the sweep's fit RMS {:.3} mm as written, {:.3} mm with them moved back): the instrument or the target \
         moved {moved}, or these rows are wrong readings (two points at a sweep's end look alike either way). The fits \
         take them into joint {}'s axis and transmission, so a calibration from this file is wrong for that joint: \
         check these rows, measure them again or drop them",
        b.experiment,
        end.points.len(),
        b.tested,
        b.p_value,
        b.blocks_tried,
        b.rms_mm.0,
        b.rms_mm.1,
        b.joint,
    );
}

/// That the search of slips in runs of rows and of two slips at once did not run on `rows` rows
/// (read from `data`): more than [`axiscal::diagnosis::MAX_SEARCH_ROWS`].
pub fn unsearched_words(rows: usize, data: &Path) -> String {
    format!(
        "the search for slips in runs of rows and for two slips at once runs on up to {} rows, and these are {} rows of {}: \
         it was not run",
        axiscal::diagnosis::MAX_SEARCH_ROWS,
        rows,
        data.display()
    )
}

/// One warning per sweep whose points from one step on sit off its earlier ones (two where
/// they shift twice; [`axiscal::calibration::procedure::SweepBump`]): the instrument or the
/// target moved during the sweep.
pub fn print_sweep_bumps(bumps: &[axiscal::calibration::procedure::SweepBump], data: &Path) {
    for b in bumps {
        if let Some(end) = &b.end {
            print_sweep_end(b, end, data);
            continue;
        }
        let place = b
            .line
            .map_or_else(|| data.display().to_string(), |l| format!("{}:{l}", data.display()));
        let [x, y, z] = b.shift_mm;
        let [sx, sy, sz] = b.shift_sigma_mm;
        let (twice, tried, moved) = match b.beside {
            Some(other) => (
                format!(
                    " (one of two steps in this sweep, the other from step {other} on: each block's shift is from \
                     the points before it)"
                ),
                "pairs of change points",
                "both blocks",
            ),
            None => (String::new(), "change points", "them"),
        };
        eprintln!(
            "warning: {place}: experiment {}'s last {} of {} points, from step {} on, sit ({x:.2}, {y:.2}, {z:.2}) \
             (+- {sx:.2}, {sy:.2}, {sz:.2}) mm off its earlier points{twice} (p = {:.1e} over the {} {tried} tried in the \
             file's sweeps; the sweep's fit RMS {:.3} mm as written, {:.3} mm with {moved} moved back): the \
             instrument or the target moved during the sweep (bumped, re-set up, the target re-seated). The fits take \
             the step into joint {}'s axis and transmission, so a calibration from this file is wrong for that joint; \
             if the instrument moved, every later row is in its new place too: measure the sweep again, or split the \
             file at that line",
            b.experiment, b.points, b.tested, b.step, b.p_value, b.blocks_tried, b.rms_mm.0, b.rms_mm.1, b.joint,
        );
    }
}
