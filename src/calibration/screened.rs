//! The independent-axis calibration of a file as `axiscal calibrate` runs it: the sweep screen
//! ([`screen_sweeps`]: outliers, bumps), the procedure on the rows it kept, the sweeps whose held
//! joints wander (tested on the model fitted), and the checks that read the calibration with
//! the named bumps moved back: the instrument axis whose scale explains the joints'
//! departures ([`instrument_axis_source`]) and the coordinate-scale profile
//! ([`coordinate_scale`]). Each finding is a value; the words are the caller's.
//!
//! A sweep whose held joints wander is not on one arc, so the screen cannot test its points;
//! where the procedure's fit of such a sweep then fails on a few points off the path the others
//! draw (or off their commands along it: [`SweepMisfit`]), those poses are dropped and the
//! procedure runs again, unless the outliers are kept: they are the screen's outliers found by
//! the fit that failed. Once the procedure has fitted the model, the points of such sweeps
//! moved to the design pose by it are screened as a still sweep's are
//! ([`screen_wandering_sweeps`]): a gross error the fit took in without failing is dropped with
//! its pose, and the procedure runs again, at most [`WANDERING_ROUNDS_MAX`] times. Where the
//! procedure fails on a joint fitted from several sweeps, the one sweep without which it passes
//! is named ([`failing_sweep`]).

use crate::calibration::procedure::{
    Calibration, CalibrationOptions, ColumnSource, OUTLIER_ROUNDS_MAX, OUTLIER_SHARE_MAX, OutlierPoint, ProcedureError,
    SweepBump, SweepMisfit, calibrate, screen_sweeps, screen_wandering_sweeps, without_poses,
};
use crate::calibration::recalibrated::{
    CoordinateScale, axes_profile_fit, beyond_correction_error, calibrated_with_bumps_undone, command_slopes,
    coordinate_scale, instrument_axis_source, with_commands_scaled,
};
use crate::measurement::MeasurementSet;
use crate::measurement::unit_check::axis_scale::PROFILE_MAX_ROWS;
use crate::robot::RobotDescription;

/// The data with the sweep screen's named bumps moved back and the calibration of its rows
/// the screen kept: the checks that read a sweep's fit as its joint's judge these, so that a
/// bump named is not blamed on a scale or a held joint too.
#[derive(Clone, Debug)]
pub struct BumpsUndone {
    /// The rows the screen kept, the bumps' blocks moved back.
    pub set: MeasurementSet,
    /// The calibration of the rows kept, so moved.
    pub cal: Calibration,
}

/// A screened calibration ([`calibrate_screened`]) and what its checks found.
#[derive(Clone, Debug)]
pub struct ScreenedCalibration {
    /// The calibration of the rows the screens kept, with the points they flagged
    /// ([`Calibration::outliers`]): the sweep screen's, then those the procedure's failed fit
    /// named off their sweep's path in a sweep the screen could not test (module docs;
    /// [`OutlierTest::AxisFit`](crate::calibration::procedure::OutlierTest::AxisFit)), then
    /// those the screen of such sweeps' points moved by the model flagged
    /// ([`OutlierTest::Moved`](crate::calibration::procedure::OutlierTest::Moved): dropped with
    /// their poses unless the outliers are kept or the calibration without them failed).
    pub cal: Calibration,
    /// The rows the screens kept; `None` when they dropped none.
    pub screened: Option<MeasurementSet>,
    /// The sweeps whose points from one step on sit off their earlier ones, then those whose
    /// held joints wander ([`screen_wandering_sweeps`]).
    pub bumps: Vec<SweepBump>,
    /// The data with those bumps moved back, calibrated; `None` when none was named or that
    /// calibration failed.
    pub bumps_undone: Option<BumpsUndone>,
    /// The instrument axis whose scale explains the joints' transmission departures, judged with
    /// the bumps moved back.
    pub column_source: Option<ColumnSource>,
    /// The coordinate-scale profile, so judged, weighed against that axis.
    pub coordinate_scale: CoordinateScale,
}

/// Why [`calibrate_screened`] failed.
#[derive(Debug)]
pub enum ScreenFailure {
    /// The screen itself refused the sweeps (a sweep with too many points beyond the fence).
    Screen(ProcedureError),
    /// The procedure failed on the rows the screen kept.
    Calibration(Box<CalibrationFailed>),
}

/// The procedure's failure on the rows the sweep screen kept ([`ScreenFailure::Calibration`]).
#[derive(Debug)]
pub struct CalibrationFailed {
    /// The procedure's error.
    pub error: ProcedureError,
    /// The points the screen flagged.
    pub outliers: Vec<OutlierPoint>,
    /// The rows it kept; `None` when it dropped none.
    pub screened: Option<MeasurementSet>,
    /// The one sweep of the failing joint without which the procedure passes, where the error
    /// names a joint fitted from several sweeps ([`failing_sweep`]).
    pub sweep: Option<FailingSweep>,
}

/// The sweep that carries a joint's failure in the procedure ([`failing_sweep`]).
#[derive(Clone, Debug, PartialEq)]
pub struct FailingSweep {
    /// The experiment.
    pub experiment: String,
    /// Its joint.
    pub joint: usize,
    /// Its first and last file lines, when the data know them.
    pub lines: Option<(u64, u64)>,
}

/// Where the procedure failed on a joint (`error` names one: its axis fit misses its points, or
/// the held joints' correction diverged on it) fitted from several sweeps: the one sweep
/// without which the procedure on `set` passes, where without each other sweep of the joint it
/// still fails, as [`crate::calibration::procedure::MisfitSweep`] locates a misfit in a
/// calibration that passes. `None` when none or more than one does.
pub fn failing_sweep(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &CalibrationOptions,
    error: &ProcedureError,
) -> Option<FailingSweep> {
    let joint = error.joint()?;
    let sweeps: Vec<String> = (set.experiments().iter())
        .filter(|e| e.moved_joint == joint)
        .map(|e| e.name.to_string())
        .collect();
    if sweeps.len() < 2 {
        return None;
    }
    let rows_of = |name: &str| -> Vec<usize> {
        (set.rows().iter().enumerate())
            .filter(|(_, m)| m.experiment == name)
            .map(|(i, _)| i)
            .collect()
    };
    let passing: Vec<&String> = (sweeps.iter())
        .filter(|name| calibrate(&set.without_rows(&rows_of(name)), desc, options).is_ok())
        .collect();
    let [experiment] = passing[..] else {
        return None;
    };
    let lines: Vec<u64> = rows_of(experiment).into_iter().filter_map(|i| set.line_of(i)).collect();
    Some(FailingSweep {
        experiment: experiment.clone(),
        joint,
        lines: lines.first().zip(lines.last()).map(|(a, b)| (*a, *b)),
    })
}

/// The independent-axis calibration of `set` with `options` as `calibrate` runs it (module
/// docs): the points beyond the screen's fence dropped unless `keep_outliers`.
pub fn calibrate_screened(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &CalibrationOptions,
    keep_outliers: bool,
) -> Result<ScreenedCalibration, ScreenFailure> {
    let mut screening = screen_sweeps(set, desc, options, keep_outliers).map_err(ScreenFailure::Screen)?;
    let kept = screening.set.as_ref().unwrap_or(set);
    let (cal, off_path) = match calibrate(kept, desc, options) {
        Ok(cal) => (cal, Vec::new()),
        Err(error) => match without_off_path(kept, desc, options, (&error, keep_outliers)) {
            Some((without, cal, off_path)) => {
                screening.set = Some(without);
                (cal, off_path)
            }
            None => {
                let sweep = failing_sweep(kept, desc, options, &error);
                return Err(ScreenFailure::Calibration(Box::new(CalibrationFailed {
                    error,
                    outliers: screening.outliers,
                    screened: screening.set,
                    sweep,
                })));
            }
        },
    };
    let kept = screening.set.as_ref().unwrap_or(set);
    let wandering = without_wandering_outliers((kept, cal), desc, options, keep_outliers);
    let mut cal = wandering.cal;
    if wandering.set.is_some() {
        screening.set = wandering.set;
    }
    let kept = screening.set.as_ref().unwrap_or(set);
    screening.bumps.extend(wandering.bumps);
    cal.outliers = std::mem::take(&mut screening.outliers);
    cal.outliers.extend(off_path);
    cal.outliers.extend(wandering.outliers);
    let undone = calibrated_with_bumps_undone(kept, &screening.bumps, desc, options);
    let (judged, judged_cal) = undone.as_ref().map_or((kept, &cal), |(s, c)| (s, c));
    let fit = |s: &MeasurementSet| axes_profile_fit(s, desc, options);
    let slopes = command_slopes(judged_cal, desc);
    let column_source = instrument_axis_source(&slopes, (judged, desc), options);
    // A joint's slope off its description's that no instrument axis explains is its command
    // column's: the fits carry it, and the coordinate-scale profile would read part of it as
    // an axis' scale (`cmd_2` x1.02 on the UR5e read as `z_mm` x1.0055), so it runs with those
    // columns undone by their slopes, as on free poses.
    let commands_undone =
        (column_source.is_none() && !slopes.is_empty()).then(|| with_commands_scaled(judged, &slopes));
    let profiled = commands_undone.as_ref().unwrap_or(judged);
    let coordinate_scale = beyond_correction_error(
        coordinate_scale(
            (profiled, desc),
            (&fit, column_source.as_ref()),
            (PROFILE_MAX_ROWS, false),
        ),
        (profiled, desc),
        (judged_cal, &fit),
        PROFILE_MAX_ROWS,
    );
    let bumps_undone = undone.map(|(set, cal)| BumpsUndone { set, cal });
    Ok(ScreenedCalibration {
        cal,
        screened: screening.set,
        bumps: screening.bumps,
        bumps_undone,
        column_source,
        coordinate_scale,
    })
}

/// The screen of the sweeps whose held joints wander runs at most this many times: again on
/// the model calibrated without the points it dropped (which a gross error had bent), once.
pub const WANDERING_ROUNDS_MAX: usize = 2;

/// What the screen of the sweeps whose held joints wander found ([`without_wandering_outliers`]).
struct Wandering {
    /// The calibration of the rows kept.
    cal: Calibration,
    /// The rows kept, where the screen dropped some.
    set: Option<MeasurementSet>,
    /// The points flagged, every round's.
    outliers: Vec<OutlierPoint>,
    /// The bumps of the last round.
    bumps: Vec<SweepBump>,
}

/// The calibration `cal` of `set` without the points the screen of its sweeps whose held
/// joints wander drops ([`screen_wandering_sweeps`], on `cal`'s model): their poses dropped and
/// the procedure run again, then the screen again on that model, while it drops points, at
/// most [`WANDERING_ROUNDS_MAX`] times. Where the procedure fails without them, the points are
/// flagged as kept, with the calibration of the rows before.
fn without_wandering_outliers(
    (set, cal): (&MeasurementSet, Calibration),
    desc: &RobotDescription,
    options: &CalibrationOptions,
    keep_outliers: bool,
) -> Wandering {
    let mut found = Wandering {
        cal,
        set: None,
        outliers: Vec::new(),
        bumps: Vec::new(),
    };
    for _ in 0..WANDERING_ROUNDS_MAX {
        let on = found.set.as_ref().unwrap_or(set);
        let screening = screen_wandering_sweeps(on, desc, options, &found.cal, keep_outliers);
        found.bumps = screening.bumps;
        let Some(without) = screening.set else {
            found.outliers.extend(screening.outliers);
            break;
        };
        match calibrate(&without, desc, options) {
            Ok(cal) => {
                found.outliers.extend(screening.outliers);
                found.cal = cal;
                found.set = Some(without);
            }
            Err(_) => {
                let kept = screening
                    .outliers
                    .into_iter()
                    .map(|o| OutlierPoint { dropped: false, ..o });
                found.outliers.extend(kept);
                break;
            }
        }
    }
    found
}

/// `set` without the poses of the points the procedure's failed fits name off their sweep's
/// path (or off their commands along it: [`SweepMisfit::OffPath`], [`SweepMisfit::OffCommand`]),
/// calibrated again, with those points flagged as dropped: one point a round, the farthest the
/// failed fit names (a sweep whose held joints wander puts its good points off the arc too, by
/// less), as the screen peels its outliers; `None` with `keep_outliers`, where a failure names
/// no such point or another cause, or where more would be dropped than the screen sets aside
/// of a sweep ([`OUTLIER_SHARE_MAX`] of its points, at most [`OUTLIER_ROUNDS_MAX`]: then the
/// sweep, not its points, is wrong).
fn without_off_path(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &CalibrationOptions,
    (error, keep_outliers): (&ProcedureError, bool),
) -> Option<(MeasurementSet, Calibration, Vec<OutlierPoint>)> {
    if keep_outliers {
        return None;
    }
    let swept = |e: &str| set.rows().iter().filter(|m| m.experiment == e && m.target == 0).count();
    let mut dropped: Vec<OutlierPoint> = Vec::new();
    let mut failure = farthest_off_path(error)?;
    loop {
        let off = dropped.iter().filter(|o| o.experiment == failure.experiment).count() + 1;
        if off > OUTLIER_ROUNDS_MAX || off as f64 > OUTLIER_SHARE_MAX * swept(&failure.experiment) as f64 {
            return None;
        }
        dropped.push(OutlierPoint {
            dropped: true,
            ..failure
        });
        let without = without_poses(set, &dropped)?;
        match calibrate(&without, desc, options) {
            Ok(cal) => return Some((without, cal, dropped)),
            Err(e) => failure = farthest_off_path(&e)?,
        }
    }
}

/// The point farthest off its sweep's path that `error`'s fit names ([`without_off_path`]);
/// `None` for any other failure.
fn farthest_off_path(error: &ProcedureError) -> Option<OutlierPoint> {
    let ProcedureError::Misfit { finding, .. } = error.misfit()? else {
        return None;
    };
    let (SweepMisfit::OffPath { points, .. } | SweepMisfit::OffCommand { points, .. }) = finding else {
        return None;
    };
    points
        .iter()
        .max_by(|a, b| a.residual_mm.total_cmp(&b.residual_mm))
        .cloned()
}
