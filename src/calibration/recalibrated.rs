//! The checks that calibrate a file again on its data altered: the fits the coordinate-scale
//! profile compares ([`axes_profile_fit`], [`free_pose_profile_fit`]), the instrument axis whose
//! scale explains the joints the transmission test names ([`instrument_axis_source`], a
//! calibration per trial scale), and the data with the sweep screen's named bumps moved back,
//! calibrated ([`calibrated_with_bumps_undone`]). Each calibration is the procedure's own
//! (`procedure::calibrate`, or the free-pose fit); the checks' words are the callers'.

use crate::calibration::free_pose::{FreePoseOptions, calibrate_free_poses};
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
