//! The axis-experiment path of `calibrate`: the screened calibration, its failure said (or its
//! sweeps fitted as free poses), and the coordinate-scale profile's finding in words.

use super::accuracy::{predict_free_pose_accuracy, predict_tool_accuracy};
use super::args_view;
use super::refine::refine;
use super::{Args, Said};
use crate::cli::checks;
use crate::cli::printer::Printer;
use anyhow::Result;
use axiscal::calibration::free_pose;
use axiscal::calibration::procedure::{CalibrationOptions, ColumnSource, OutlierPoint, OutlierTest, ProcedureError};
use axiscal::calibration::recalibrated::CoordinateScale;
use axiscal::calibration::record::{CalibrationRecord, Reports};
use axiscal::calibration::screened::{BumpsUndone, CalibrationFailed, FailingSweep, ScreenFailure, calibrate_screened};
use axiscal::calibration::tool_accuracy::MapPoint;
use axiscal::measurement::MeasurementSet;
use axiscal::measurement::unit_check::axis_scale::NullSpread;
use axiscal::robot::RobotDescription;
use std::path::Path;

/// What the axis-experiment calibration found beside its record ([`calibrate_axes`]).
#[derive(Default)]
pub(super) struct AxesFound {
    /// The instrument axis whose scale explains the joints' transmission departures
    /// ([`axiscal::calibration::screened::ScreenedCalibration::column_source`]).
    pub(super) column_source: Option<ColumnSource>,
    /// The data with the sweep screen's named bumps moved back, where it named any.
    pub(super) bumps_undone: Option<BumpsUndone>,
    /// The rows the screens kept; `None` when they dropped none.
    pub(super) kept: Option<MeasurementSet>,
}

/// The axis-experiment calibration of `set` after its failure on the rows the screen kept
/// (`failed`): every row a free pose where the independent-axis correction for the held joints
/// does not settle (that fit tests its poses for outliers itself, on every row); else the
/// points flagged and why it failed.
pub(super) fn calibration_failed(
    args: &Args,
    (set, desc): (&MeasurementSet, &RobotDescription),
    options: &CalibrationOptions,
    failed: CalibrationFailed,
    printer: Printer,
) -> Result<(CalibrationRecord, Vec<MapPoint>, AxesFound)> {
    let sweep = failing_sweep_words(failed.sweep.as_ref());
    if let e @ (ProcedureError::HeldNotConverged { .. } | ProcedureError::HeldDiverged { .. }) = &failed.error
        && !args.refine
    {
        let mut record = sweeps_as_free_poses(args, (set, desc), (e, failed.sweep.as_ref()), printer)?;
        let (accuracy, map) = predict_free_pose_accuracy(&record.calibration, desc, set);
        record.reports.tool_accuracy = accuracy;
        return Ok((record, map, AxesFound::default()));
    }
    checks::print_outliers(&failed.outliers, &args.data, "calibrated");
    let kept = failed.screened.as_ref().unwrap_or(set);
    Err(failure_words(args, (kept, desc), options, (&failed.error, &sweep)))
}

/// The words naming the sweep that carries a joint's failure (empty without one).
pub(super) fn failing_sweep_words(sweep: Option<&FailingSweep>) -> String {
    let Some(s) = sweep else {
        return String::new();
    };
    let lines = s.lines.map_or_else(String::new, |(a, b)| format!(" (lines {a}-{b})"));
    format!(
        "; the failure is experiment {}'s{lines}: without it the calibration passes, without any other sweep of joint {} \
         it fails: check that sweep's rows (its block moved part-way, a bump of the instrument or the robot, or a held \
         joint's recorded command off through it: a value typed wrong or the joint re-mastered between the sweeps)",
        s.experiment, s.joint
    )
}

/// The outliers of the sweeps whose held joints wander, as warnings naming each row: those the
/// procedure's failed fit named off their sweep's path, dropped with their poses
/// ([`OutlierTest::AxisFit`]), and those the screen of these sweeps' points moved by the
/// calibrated model flagged ([`OutlierTest::Moved`]).
pub(super) fn print_wandering_outliers(outliers: &[OutlierPoint], desc: &RobotDescription, args: &Args) {
    let path_of = |o: &OutlierPoint| match desc.joints.get(o.joint.wrapping_sub(1)).map(|j| j.kind) {
        Some(axiscal::kinematics::JointKind::Prismatic) => "line",
        _ => "arc",
    };
    for o in outliers.iter().filter(|o| o.test == OutlierTest::AxisFit) {
        let (place, _) = checks::outlier_place(o, &args.data, "calibrated");
        let path = path_of(o);
        eprintln!(
            "warning: {place}: outlier: experiment {} step {} target {}: {:.3} mm off the {path} its sweep's other points \
             draw (or along it, off its command), {:.1} times the noise, beyond the fence {:.1} of their distances: the \
             sweep screen cannot test a sweep whose held joints wander (its points lie on no one {path}), and the axis \
             fit failed with it: calibrated without it and the other targets of its pose (--keep-outliers keeps it, and \
             the fit fails); check this row's coordinates and commands",
            o.experiment, o.step, o.target, o.residual_mm, o.normalised_residual, o.fence
        );
    }
    let moved: Vec<OutlierPoint> = (outliers.iter())
        .filter(|o| o.test == OutlierTest::Moved)
        .cloned()
        .collect();
    for o in moved.iter().filter(|o| o.approach.is_none()) {
        let (place, what) = checks::outlier_place(o, &args.data, "calibrated again");
        let what = match o.dropped || args.keep_outliers {
            true => what,
            false => "kept: the calibration without its pose failed".to_string(),
        };
        let path = path_of(o);
        eprintln!(
            "warning: {place}: outlier: experiment {} step {} target {}: {:.3} mm from the fit of its sweep's other \
             points, {:.1} times their noise, beyond the fence {:.1} (a clean file's sweeps pass it with {:.0} % \
             probability), its sweep's points moved to the design pose by the calibrated model (its held joints wander, \
             so that as measured they lie on no one {path}): {what}; check this row's coordinates and commands",
            o.experiment,
            o.step,
            o.target,
            o.residual_mm,
            o.normalised_residual,
            o.fence,
            100.0 * (1.0 - axiscal::calibration::procedure::SWEEP_POINTS_FALSE_ALARM)
        );
    }
    checks::print_approach_notes(&moved, &args.data, "calibrated again");
}

/// Why the axis-experiment calibration of `screened` failed (`e`, and the words naming the sweep
/// that carries it, [`failing_sweep_words`]), with what `--noise-mm` or
/// `--repeatability-rad` had to do with it.
pub(super) fn failure_words(
    args: &Args,
    (screened, desc): (&MeasurementSet, &RobotDescription),
    options: &CalibrationOptions,
    (e, sweep): (&ProcedureError, &str),
) -> anyhow::Error {
    if let Some(too_small) = args
        .noise_mm
        .and_then(|n| checks::noise_far_below(screened, desc, options, n, e.joint(), ["the fits", "it"]))
    {
        return anyhow::anyhow!("calibrating {}: {too_small}", args.data.display());
    }
    let hint = match (args.noise_mm, &args.repeatability_rad) {
        (Some(n), _) => format!(
            " (with --noise-mm {n:e}: a noise far below the data's makes the fits trust each point more than the joints' repeatability allows; without --noise-mm it is estimated from the residuals)"
        ),
        (None, Some(r)) => format!(
            " (with --repeatability-rad {}: a repeatability far above the joints' own weights the fits away from their points; without it the description's repeatability_sigma is used)",
            r.iter().map(f64::to_string).collect::<Vec<_>>().join(",")
        ),
        (None, None) => String::new(),
    };
    anyhow::anyhow!("calibrating {}: {e}{sweep}{hint}", args.data.display())
}

/// The independent-axis calibration of `set` (`--refine` applied) with its reports, the
/// tool-accuracy map, and what the checks found beside it ([`AxesFound`]).
pub(super) fn calibrate_axes(
    args: &Args,
    set: &MeasurementSet,
    desc: &RobotDescription,
    printer: Printer,
) -> Result<(CalibrationRecord, Vec<MapPoint>, AxesFound)> {
    if args.holdout {
        anyhow::bail!(
            "--holdout applies to free-pose files (no axis experiment); {} has axis experiments",
            args.data.display()
        );
    }
    for warning in unused_on_axes(args) {
        eprintln!("warning: {warning}");
    }
    let options = CalibrationOptions {
        estimator: args.estimator,
        noise_rms_3d_mm: args.noise_mm.unwrap_or(CalibrationOptions::default().noise_rms_3d_mm),
        estimate_noise: args.noise_mm.is_none(),
        held_tolerance: args.held_tolerance,
        repeatability_sigma_rad: args.repeatability_rad.clone(),
        ..CalibrationOptions::default()
    };
    options
        .joint_repeatability_rad(desc)
        .map_err(|e| anyhow::anyhow!("--repeatability-rad: {e}"))?;
    let screened = match calibrate_screened(set, desc, &options, args.keep_outliers) {
        Ok(screened) => screened,
        Err(ScreenFailure::Screen(e)) => anyhow::bail!("calibrating {}: {e}", args.data.display()),
        Err(ScreenFailure::Calibration(failed)) => {
            return calibration_failed(args, (set, desc), &options, *failed, printer);
        }
    };
    let screen_outliers: Vec<OutlierPoint> = (screened.cal.outliers.iter())
        .filter(|o| o.test.is_screen())
        .cloned()
        .collect();
    checks::print_outliers(&screen_outliers, &args.data, "calibrated");
    print_wandering_outliers(&screened.cal.outliers, desc, args);
    checks::print_sweep_bumps(&screened.bumps, &args.data);
    let set = screened.screened.as_ref().unwrap_or(set);
    let mut said = Said::default();
    print_coordinate_scale(&screened.coordinate_scale, set, &args.data, (printer, &mut said));
    let cal = screened.cal;
    let (tool_accuracy, map) = predict_tool_accuracy(&cal, desc, set, args.held_tolerance)?;
    // The prediction describes the axis experiments' model and its propagated covariance;
    // `--refine` reports its own covariance and held-out check beside it.
    let (calibration, refinement) = if args.refine {
        let (refined, refinement) = refine(args, set, desc, &cal, printer)?;
        (refined, Some(refinement))
    } else {
        (cal, None)
    };
    let reports = Reports {
        tool_accuracy,
        refinement,
        warnings: said.into_warnings(),
        ..Reports::default()
    };
    let found = AxesFound {
        column_source: screened.column_source,
        bumps_undone: screened.bumps_undone,
        kept: screened.screened,
    };
    Ok((CalibrationRecord { calibration, reports }, map, found))
}

/// The options given that the axis-experiment calibration does not use, as one warning each:
/// free-pose options (`--harmonics`, `--effects`), and `--max-poses` without `--refine`.
pub(super) fn unused_on_axes(args: &Args) -> Vec<String> {
    let data = args.data.display();
    let free_pose_only = [
        ("--harmonics", args.harmonics.is_some()),
        ("--effects", args.effects.is_some()),
        ("--max-poses", args.max_poses.is_some() && !args.refine),
    ];
    free_pose_only
        .iter()
        .filter(|(_, given)| *given)
        .map(|(option, _)| {
            format!(
                "{option} has no effect here: it applies to free-pose calibrations (a file without axis experiments, or --free-poses){}, and {data} has axis experiments",
                if *option == "--max-poses" { " and to --refine" } else { "" }
            )
        })
        .collect()
}

/// The free-pose calibration of every row of `set`, for sweeps the independent-axis correction
/// for their held joints does not bring to one pose (`failure`); an error when the sweeps'
/// targets cannot be free poses (on a link before the last), or when the procedure passes
/// without one sweep (`sweep`) and the free-pose fit finds a block of rows shifted off the
/// others: then that sweep is the fault, not the configurations.
pub(super) fn sweeps_as_free_poses(
    args: &Args,
    (set, desc): (&MeasurementSet, &RobotDescription),
    (failure, sweep): (&ProcedureError, Option<&FailingSweep>),
    printer: Printer,
) -> Result<CalibrationRecord> {
    let sweep_words = failing_sweep_words(sweep);
    if let Some(why_not) = free_pose::poses::why_sweeps_are_not_poses(set, desc) {
        anyhow::bail!(
            "calibrating {}: {failure}{sweep_words}; the sweeps cannot be fitted as free poses either: {why_not}",
            args.data.display()
        );
    }
    let mut view = args_view(args);
    view.all_rows = true;
    if sweep.is_some()
        && let Some(block) = super::free_poses::quietly_shifted_block(&view, set, desc)
    {
        let [x, y, z] = block.shift_mm;
        anyhow::bail!(
            "calibrating {}: {failure}{sweep_words}; fitted as free poses instead, the poses {} sit about ({x:.2}, \
             {y:.2}, {z:.2}) mm off the others",
            args.data.display(),
            super::free_poses::block_place(&block)
        );
    }
    let why = format!(
        "the independent-axis procedure cannot bring the sweeps from their configurations to one pose ({failure}{sweep_words})"
    );
    eprintln!(
        "warning: {}: {why}; every point is fitted as a free pose instead (docs/method.md, \"Calibration from free poses\")",
        args.data.display()
    );
    let mut record = match (
        super::free_poses::calibrate(&view, set, desc, printer),
        failure.misfit(),
    ) {
        (Ok(record), _) => record,
        // The rows named are the likelier cause than the configurations' spread.
        (Err(_), Some(misfit)) => anyhow::bail!(
            "calibrating {}: {misfit}{sweep_words}; fitted as free poses, the sweeps fail too",
            args.data.display()
        ),
        (Err(e), None) => return Err(e),
    };
    if let Some(summary) = record.reports.free_poses.as_mut() {
        summary.axis_rows_as_poses = Some(why);
    }
    Ok(record)
}

/// The coordinate-scale profile's finding on `set` ([`axiscal::calibration::recalibrated::coordinate_scale`]) in words: a scale
/// named as a warning, with a second axis behind it; else a note of how large a scale would
/// pass where that is beyond the test's claim, and with `--verbose` a note of the largest one
/// either way. A scale the free poses' screen named none of is a note.
pub(in crate::cli) fn print_coordinate_scale(
    found: &CoordinateScale,
    set: &MeasurementSet,
    data: &Path,
    (printer, said): (Printer, &mut Said),
) {
    match found {
        CoordinateScale::Untested => eprintln!(
            "note: {}: one-axis instrument scales this file cannot show: any column, at any size (the \
             coordinate-scale test could not run: its re-run calibrations did not keep the same poses and \
             parameters, or failed; report.md, \"Detection limits\")",
            data.display()
        ),
        CoordinateScale::SourceNamed => {}
        CoordinateScale::Within(found) => {
            if printer.verbose {
                eprintln!(
                    "note: {}: of the coordinate columns {} reads the most unlike the others: {:.5} times \
                     (+- {:.5}, {:.1} sigma from 1, within the data's reach of 1)",
                    data.display(),
                    found.scaled.columns(),
                    found.factor,
                    found.sigma,
                    (found.factor - 1.0).abs() / found.sigma
                );
            }
            if let Some(reach) = found.reach_note() {
                eprintln!("note: {}: {reach}", data.display());
            }
        }
        CoordinateScale::ScreenNamedNone(found) => eprintln!(
            "note: {}: the coordinate-scale profile reads {} {:.5} times (+- {:.5}, counting every point as \
             independent), but the column-scale screen over the configurations (repeated visits share the model's \
             error at each) names no command column or instrument axis: not named",
            data.display(),
            found.scaled.columns(),
            found.factor,
            found.sigma
        ),
        CoordinateScale::WithinCorrectionError { found, null } => eprintln!(
            "note: {}: the coordinate-scale profile reads {} {:.5} times (+- {:.5} from the noise, {:.1} sigma from \
             1), but {}: the sweeps at other poses enter through the held joints' correction, whose model error reads \
             as a scale (longer sweeps locate the axes better): not named",
            data.display(),
            found.scaled.columns(),
            found.factor,
            found.sigma,
            (found.factor - 1.0).abs() / found.sigma,
            simulated_words(null)
        ),
        CoordinateScale::Named { found, second, null } => {
            let place = match set.line_of(0) {
                Some(line) => format!("{}:{line}", data.display()),
                None => data.display().to_string(),
            };
            let beyond = null.as_ref().map_or(String::new(), |null| {
                format!(
                    " (the sweeps at other poses enter through the held joints' correction, whose model error reads as \
                     a scale; {}, so it stands beyond that)",
                    simulated_words(null)
                )
            });
            said.warn(format!("{place}: {found}{beyond}"));
            if let Some(second) = second {
                said.warn(format!(
                    "{place}: with {} divided by {:.5} about the data's centroid (the scale named above) \
                     the coordinate-scale profile was run again, and a second axis shows: {second}",
                    found.scaled.columns(),
                    found.factor
                ));
            }
        }
    }
}

/// What the files simulated without a scale read ([`NullSpread`]), in words.
pub(super) fn simulated_words(null: &NullSpread) -> String {
    format!(
        "{} files simulated from this calibration at these commands, with this noise and no scale, read it {:.5} \
         times (+- {:.5}; p = {:.1e} for this file among them)",
        null.files, null.centre, null.sigma, null.p_value
    )
}
