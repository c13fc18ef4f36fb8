//! A block of free poses shifted in file order (the instrument bumped, a re-setup part-way
//! through the file): a change-point test on the calibrated residuals.
//!
//! The slip search of [`super::slip`] places the NOMINAL model on the poses and moves a block
//! back; on a robot whose geometry misses its description by millimetres (the IRB/L6 paper
//! robot: 4.7 mm) the nominal model's own misfit, a few millimetres different at every pose,
//! swamps a 2 mm block in its paired test. The calibrated residuals (`measured - calibrated`)
//! leave the noise and what the fit could not take of the shift: its base takes the shift's
//! mean over the poses, the geometry what happens to correlate with the block's
//! configurations, and a step between the block and the other poses stays.
//!
//! The test: the change-point test of [`crate::numerics::change_point`] over every block of
//! consecutive poses in file order (from a pose to the end, or between two poses; three poses
//! at least inside and outside) on the poses' mean residuals, its p-value times the blocks
//! tried (Bonferroni over the candidate change points) held against [`SLIP_FALSE_ALARM`]. The
//! fit's leverage (a few per cent of each residual's variance over tens of poses a parameter)
//! shrinks the step and the scatter alike to first order; the part of the shift the fit took
//! makes the test conservative.
//!
//! The size: the calibration repeated with the block moved back by the step found so far, the
//! step left then added (two calibrations). Named only when that calibration fits
//! better than the poses as written by the same family-wise quantile of the RMS's relative
//! standard error `1 / sqrt(2 dof)`, the dof divided by the serial correlation's inflation (a
//! second, differently computed test: the sum of squares of the whole fit, not the residual
//! means). The real FANUC's poses drift by 0.07 mm over its second half: significant by the
//! first test, too small for the second (0.128 -> 0.120 mm).

use super::slip::{MIN_BLOCK_POSES, SLIP_FALSE_ALARM};
use super::{FreePoseCalibration, FreePoseOptions, FreePoses, calibrate_free_poses, split};
use crate::measurement::{Measurement, MeasurementSet};
use crate::numerics::change_point::{Blocks, most_significant_block, step_of};
use crate::numerics::stats::chi_square_quantile;
use crate::robot::{Controller, RobotDescription};
use nalgebra::Vector3;
use std::collections::HashSet;

/// Calibrations with the block moved back that size its shift (each takes the step the one
/// before left).
const BLOCK_ROUNDS: usize = 2;

/// A block of consecutive free poses off the others (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct BlockShift {
    /// File line of the block's first row and of its last (`None` for rows without lines).
    pub lines: (Option<u64>, Option<u64>),
    /// Whether the block runs to the file's last fitted pose.
    pub to_end: bool,
    /// Poses in the block.
    pub poses: usize,
    /// Poses tested.
    pub tested: usize,
    /// The block's shift from the other poses \[mm\] (instrument axes).
    pub shift_mm: [f64; 3],
    /// The p-value of the most significant block, before the multiple-test correction.
    pub p_value: f64,
    /// Blocks tried.
    pub blocks_tried: usize,
    /// The calibrated RMS \[mm\] of the poses as written.
    pub written_rms_mm: f64,
    /// The calibrated RMS \[mm\] with the block moved back.
    pub undone_rms_mm: f64,
}

/// Each pose's mean residual `measured - calibrated` \[m\] of `cal`, for the poses `which`
/// in their order (`None` when the model cannot execute one).
fn pose_means(
    cal: &FreePoseCalibration,
    controller: &Controller,
    poses: &FreePoses,
    which: &[usize],
) -> Option<Vec<Vector3<f64>>> {
    let r = cal.model.residuals(controller, poses, which).ok()?;
    let mut row = 0;
    let mut out = Vec::with_capacity(which.len());
    for &i in which {
        let points = poses.poses[i].points_m.len();
        let mut sum = Vector3::zeros();
        for k in 0..points {
            sum += r.fixed_rows::<3>(row + 3 * k);
        }
        row += 3 * points;
        out.push(sum / points.max(1) as f64);
    }
    Some(out)
}

/// `set` with the rows of the poses `block` (experiment, step) moved by `-shift_m`.
fn moved_back(
    set: &MeasurementSet,
    block: &HashSet<(String, usize)>,
    shift_m: &Vector3<f64>,
) -> Option<MeasurementSet> {
    let rows: Vec<Measurement> = set
        .rows()
        .iter()
        .map(|m| {
            let mut m = m.clone();
            if block.contains(&(m.experiment.clone(), m.step)) {
                (0..3).for_each(|c| m.position_mm[c] -= shift_m[c] * 1e3);
            }
            m
        })
        .collect();
    MeasurementSet::new(set.joint_count(), rows).ok()
}

/// The block of consecutive free poses of `set` that sits off the others in the calibration
/// `cal` (made with `options`), when significant (module docs); `None` when none is, or the
/// calibration with the block moved back does not fit better.
pub fn block_shift(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &FreePoseOptions,
    cal: &FreePoseCalibration,
) -> Option<BlockShift> {
    let poses = FreePoses::from_set_at_most(set, desc, options.all_rows, options.max_poses).ok()?;
    let controller = Controller::from_description(desc);
    let dropped: HashSet<(&str, usize)> = cal
        .summary
        .outliers
        .iter()
        .filter(|o| o.dropped)
        .map(|o| (o.experiment.as_str(), o.step))
        .collect();
    let which: Vec<usize> = split(&poses, options.holdout)
        .0
        .into_iter()
        .filter(|&i| !dropped.contains(&(poses.poses[i].experiment.as_str(), poses.poses[i].step)))
        .collect();
    let means = pose_means(cal, &controller, &poses, &which)?;
    let found = most_significant_block(&means, MIN_BLOCK_POSES, Blocks::Any)?;
    if found.p_value * found.tried as f64 >= SLIP_FALSE_ALARM {
        return None;
    }
    let block: HashSet<(String, usize)> = which[found.start..found.end]
        .iter()
        .map(|&i| (poses.poses[i].experiment.clone(), poses.poses[i].step))
        .collect();
    let mut shift = step_of(&means, found.start, found.end);
    let mut undone_rms_mm = f64::NAN;
    for _ in 0..BLOCK_ROUNDS {
        let moved = moved_back(set, &block, &shift)?;
        let again = calibrate_free_poses(&moved, desc, options).ok()?;
        undone_rms_mm = again.summary.calibrated_rms_mm;
        let moved_poses = FreePoses::from_set_at_most(&moved, desc, options.all_rows, options.max_poses).ok()?;
        let left = pose_means(&again, &controller, &moved_poses, &which)?;
        shift += step_of(&left, found.start, found.end);
    }
    // The block was chosen for its step among `tried`: the calibration with it moved back must
    // fit better by the family-wise quantile, the dof shrunk by the serial correlation.
    let w = &cal.summary;
    let dof = (3 * w.points).saturating_sub(w.parameters.len()).max(1) as f64 / found.inflation;
    let z = chi_square_quantile(1.0 - 2.0 * SLIP_FALSE_ALARM / found.tried as f64, 1.0).sqrt();
    if undone_rms_mm >= w.calibrated_rms_mm * (1.0 - z / (2.0 * dof).sqrt()) {
        return None;
    }
    let lines: Vec<u64> = (0..set.rows().len())
        .filter(|&i| {
            let m = &set.rows()[i];
            block.contains(&(m.experiment.clone(), m.step))
        })
        .filter_map(|i| set.line_of(i))
        .collect();
    Some(BlockShift {
        lines: (lines.iter().min().copied(), lines.iter().max().copied()),
        to_end: found.end == which.len(),
        poses: found.end - found.start,
        tested: which.len(),
        shift_mm: [shift.x * 1e3, shift.y * 1e3, shift.z * 1e3],
        p_value: found.p_value,
        blocks_tried: found.tried,
        written_rms_mm: w.calibrated_rms_mm,
        undone_rms_mm,
    })
}
