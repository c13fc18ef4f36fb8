//! The checks that calibrate a file again on its data altered: the fits the coordinate-scale
//! profile compares ([`axes_profile_fit`], [`free_pose_profile_fit`]), the instrument axis whose
//! scale explains the joints the transmission test names ([`instrument_axis_source`], a
//! calibration per trial scale), and the data with the sweep screen's named bumps moved back,
//! calibrated ([`calibrated_with_bumps_undone`]); for free poses, the slip or moved block behind
//! the column scales the screen named ([`shift_behind_scales`]) and the poses with those scales
//! undone, calibrated ([`calibrated_with_scales_undone`]). Each calibration is the procedure's own
//! (`procedure::calibrate`, or the free-pose fit); the checks' words are the callers'.

use crate::calibration::free_pose::block::{BlockShift, block_shift};
use crate::calibration::free_pose::slip::{ExplainingSlip, explaining_slip};
use crate::calibration::free_pose::{FreePoseOptions, FreePoseSummary, NamedScale, calibrate_free_poses};
use crate::calibration::procedure::{
    Calibration, CalibrationOptions, ColumnSource, Implausible, Refit, ScaleSlip, SweepBump, bumps_undone, calibrate,
    column_source, implausible, joint_slopes,
};
use crate::measurement::MeasurementSet;
use crate::measurement::unit_check::axis_scale::Fit;
use crate::robot::RobotDescription;

/// The axis fits' residuals of `cal` as the coordinate-scale profile reads them: the sum of
/// each axis's squared residual coordinates over the noise estimate's degrees of freedom;
/// `None` without a noise estimate.
pub fn axes_fit(cal: &Calibration) -> Option<Fit> {
    Some(Fit {
        sum_squares_mm2: cal
            .axes
            .iter()
            .map(|a| a.points as f64 * a.residual_rms_mm.powi(2))
            .sum(),
        dof: cal.noise.as_ref()?.estimate.as_ref()?.dof,
        misfit_poses: 0,
    })
}

/// The axis-experiment calibration of `set` with `options`, as the coordinate-scale profile
/// reads it ([`axes_fit`]); `None` where it fails.
pub fn axes_profile_fit(set: &MeasurementSet, desc: &RobotDescription, options: &CalibrationOptions) -> Option<Fit> {
    axes_fit(&calibrate(set, desc, options).ok()?)
}

/// The free-pose calibration of `set` with `options` (no held-out half, no effects: the
/// profile compares geometries), as the coordinate-scale profile reads it: the points' sum of
/// squares over their coordinates less the parameters, and the poses beyond the outlier fence
/// (a pose the model cannot fit stays flagged with a column undone); `None` where it fails.
pub fn free_pose_profile_fit(set: &MeasurementSet, desc: &RobotDescription, options: &FreePoseOptions) -> Option<Fit> {
    let profile = FreePoseOptions {
        holdout: false,
        effects: false,
        ..*options
    };
    let c = calibrate_free_poses(set, desc, &profile).ok()?;
    let points = c.summary.points as f64;
    Some(Fit {
        sum_squares_mm2: points * c.summary.calibrated_rms_mm.powi(2),
        dof: (3 * c.summary.points).saturating_sub(c.summary.parameters.len()),
        misfit_poses: c.summary.outliers.len(),
    })
}

/// The instrument axis whose scale explains the departures of the joints the transmission
/// test names in `cal` ([`column_source`]), the calibrations re-run on `set` with `options`;
/// `None` where the test names none.
pub fn instrument_axis_source(
    cal: &Calibration,
    (set, desc): (&MeasurementSet, &RobotDescription),
    options: &CalibrationOptions,
) -> Option<ColumnSource> {
    let named: Vec<usize> = implausible(cal, desc)
        .iter()
        .filter_map(|f| match f {
            Implausible::Scaled(ScaleSlip::Command { joint, .. }) => Some(*joint),
            _ => None,
        })
        .collect();
    if named.is_empty() {
        return None;
    }
    let refit = |s: &MeasurementSet| {
        let c = calibrate(s, desc, options).ok()?;
        Some(Refit {
            slopes: joint_slopes(&c, desc),
            fit: axes_fit(&c)?,
        })
    };
    column_source(set, &named, &refit)
}

/// `set` (screened) with the sweep screen's `bumps` moved back ([`bumps_undone`]) and its
/// calibration with `options`; `None` when no bump was named or that calibration fails (the
/// checks then read the data as written).
pub fn calibrated_with_bumps_undone(
    set: &MeasurementSet,
    bumps: &[SweepBump],
    desc: &RobotDescription,
    options: &CalibrationOptions,
) -> Option<(MeasurementSet, Calibration)> {
    let undone = bumps_undone(set, bumps)?;
    let cal = calibrate(&undone, desc, options).ok()?;
    Some((undone, cal))
}

/// A column slip or a block of free poses moved ([`explaining_slip`], [`block_shift`]).
#[derive(Clone, Debug)]
pub enum FreePoseShift {
    /// A column slip, or a block found by the nominal model's slip search.
    Slip(ExplainingSlip),
    /// A block found in the calibrated residuals.
    Block(BlockShift),
}

/// The slip ([`explaining_slip`]), else the shifted block (`block`, [`block_shift`] of the
/// calibration as read), the free poses `set` show, unless the column-scale screen named a
/// scale ([`FreePoseSummary::scales`]) that explains it: a scale moves the poses it reaches far
/// (a wrist's command at its extremes, a coordinate far from the centroid) by a pattern the
/// nominal model's slip search and the calibrated residuals' change-point test read as a step
/// in file order where those poses stand together (a KR's `cmd_5` x1.025 read as lines 474-482
/// moved; its `x_mm` x1.025 as the poses from line 780 on). The two explanations are compared
/// by their fit: the poses with the scales undone are calibrated again with the same options;
/// a block or slip whose undoing fits the poses better than the scales undone (calibrated RMS)
/// is returned (a `cmd_2`/`cmd_3` swap the screen reads as `cmd_2` x 1.31), as is a slip or
/// block that both tests still find on the undone poses (the scale may then be the shift's
/// shadow); where neither remains, the shift was the scale's and `None` is returned (the refit
/// with the first explanation undone, as the sweep side's `diagnosis/combined_slips.rs`). A
/// column slip of a column the screen named (`cmd_3` in gradians, read as `cmd_3` x 1.135 +-
/// 0.018) is returned: the two agree on the column, and the slip's exact factor names the cause.
pub fn shift_behind_scales(
    (set, desc): (&MeasurementSet, &RobotDescription),
    options: &FreePoseOptions,
    summary: &FreePoseSummary,
    block: Option<&BlockShift>,
) -> Option<FreePoseShift> {
    let as_read = explaining_slip(set, desc, options, Some(summary))
        .map(FreePoseShift::Slip)
        .or_else(|| block.cloned().map(FreePoseShift::Block))?;
    let same_column =
        matches!(&as_read, FreePoseShift::Slip(s) if summary.scales.iter().any(|n| n.scale.column == s.field));
    if summary.scales.is_empty() || same_column {
        return Some(as_read);
    }
    let undone = scales_undone(set, &summary.scales);
    let Ok(again) = calibrate_free_poses(&undone, desc, options) else {
        return Some(as_read);
    };
    // A shift that leaves less than the scales' refit does explains more than they do (a
    // column swap read as a scale that takes a twentieth of its misfit).
    let undone_rms_mm = match &as_read {
        FreePoseShift::Block(b) => b.undone_rms_mm,
        FreePoseShift::Slip(s) => s.undone_rms_mm,
    };
    if undone_rms_mm < again.summary.calibrated_rms_mm {
        return Some(as_read);
    }
    let remains = block_shift(&undone, desc, options, &again).is_some() || {
        let (_, summary_again) = again.into_calibration(desc);
        explaining_slip(&undone, desc, options, Some(&summary_again)).is_some()
    };
    remains.then_some(as_read)
}

/// `set` with the column scales `named` undone: each column divided by its factor (a
/// coordinate column about the origin: the centre a scale is read about moves only the base,
/// which the fit places).
pub fn scales_undone(set: &MeasurementSet, named: &[NamedScale]) -> MeasurementSet {
    named
        .iter()
        .fold(set.clone(), |s, n| match coordinate_index(&n.scale.column) {
            Some(c) => s.with_coordinate_scaled(c, 1.0 / n.scale.factor),
            None => {
                command_index(&n.scale.column).map_or(s.clone(), |j| s.with_command_scaled(j, 1.0 / n.scale.factor))
            }
        })
}

/// The free poses calibrated again with the column scales the screen named
/// ([`FreePoseSummary::scales`]) undone ([`scales_undone`]), with no held-out half and no
/// effects (the tests of the joints' transmissions read the geometry).
#[derive(Clone, Debug)]
pub struct ScalesUndone {
    /// The poses with the scales undone.
    pub set: MeasurementSet,
    /// Their calibration.
    pub cal: Calibration,
    /// Its free-pose summary.
    pub summary: FreePoseSummary,
}

/// [`ScalesUndone`] of `set` and the scales `named`; `None` without a named scale, or when the
/// calibration of the undone poses fails (the tests then run on the calibration as read).
pub fn calibrated_with_scales_undone(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &FreePoseOptions,
    named: &[NamedScale],
) -> Option<ScalesUndone> {
    if named.is_empty() {
        return None;
    }
    let undone = scales_undone(set, named);
    let profile = FreePoseOptions {
        holdout: false,
        effects: false,
        ..*options
    };
    let (cal, summary) = calibrate_free_poses(&undone, desc, &profile)
        .ok()?
        .into_calibration(desc);
    Some(ScalesUndone {
        set: undone,
        cal,
        summary,
    })
}

/// The 0-based coordinate of `x_mm`, `y_mm`, `z_mm`.
fn coordinate_index(column: &str) -> Option<usize> {
    ["x_mm", "y_mm", "z_mm"].iter().position(|c| *c == column)
}

/// The 0-based joint of `cmd_K`.
fn command_index(column: &str) -> Option<usize> {
    column.strip_prefix("cmd_")?.parse::<usize>().ok()?.checked_sub(1)
}
