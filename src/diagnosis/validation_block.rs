//! A block of validation poses shifted in file order (the instrument bumped, or set up again,
//! part-way through the validation): the change-point test the free-pose calibration makes on
//! its residuals ([`crate::calibration::free_pose::block`]), here on the validation's.
//!
//! The test: each validation pose's mean residual, less the calibration's error that every
//! pose estimates together ([`residuals_less_calibration_error`]: what the calibration itself
//! moves comes back to the noise, a block's step mostly stays), in file order; the most
//! significant block of consecutive poses by [`most_significant_block`] (three poses at least
//! inside and outside), its p-value times the blocks tried held against
//! [`SLIP_FALSE_ALARM`]. Only a validation that misses its prediction is searched: a block too
//! small to fail the validation changes none of its verdicts. Files beyond the slip search's
//! [`MAX_SEARCH_ROWS`] are not searched (each round validates a moved copy of the file). A block that alone explains the
//! miss is refused before, by the slip search ([`super::combined_slips`]); this names one beside
//! a miss no slip undoes (an effect the calibration lacks), as a warning.
//!
//! The size, and a second test: the validation repeated with the block's rows moved back by
//! the step found, twice (each round takes the step the one before left). Named only when the
//! validation poses' chi-square (against the noise and the calibration's shared error, the
//! validation's own test) then falls by more than a block's 3 free coordinates give by
//! chance: the family-wise quantile of `chi2(3)` over the blocks tried, widened by the serial
//! correlation's inflation. The validation's RMS alone would not do: where the calibration's
//! own error dominates it, a block of 1 mm fails the chi-square (no shared error moves a block
//! of poses alike) but hardly moves the RMS.

use super::DiagnosisError;
use super::combined_slips::MAX_SEARCH_ROWS;
use super::validate::{PointKind, Validation, ValidationOptions, Verdict, residuals_less_calibration_error, validate};
use crate::calibration::free_pose::slip::{MIN_BLOCK_POSES, SLIP_FALSE_ALARM};
use crate::calibration::procedure::Calibration;
use crate::measurement::{Measurement, MeasurementSet};
use crate::numerics::change_point::{Blocks, most_significant_block, step_of};
use crate::numerics::stats::chi_square_quantile;
use crate::robot::RobotDescription;
use nalgebra::Vector3;
use std::collections::{BTreeSet, HashSet};

/// Validations with the block moved back that size its shift.
const BLOCK_ROUNDS: usize = 2;

/// A block of consecutive validation poses off the others (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct ValidationBlock {
    /// File line of the block's first row and of its last (`None` for rows without lines).
    pub lines: (Option<u64>, Option<u64>),
    /// The block's first and last steps.
    pub steps: (usize, usize),
    /// Poses in the block.
    pub poses: usize,
    /// Validation poses tested.
    pub tested: usize,
    /// The block's shift from the other poses \[mm\] (instrument axes).
    pub shift_mm: [f64; 3],
    /// The p-value of the most significant block, before the multiple-test correction.
    pub p_value: f64,
    /// Blocks tried.
    pub blocks_tried: usize,
    /// The validation poses' RMS \[mm\] as written.
    pub written_rms_mm: f64,
    /// The same with the block moved back \[mm\].
    pub undone_rms_mm: f64,
    /// The validation poses' chi-square per degree of freedom as written.
    pub written_chi2_per_dof: f64,
    /// The same with the block moved back.
    pub undone_chi2_per_dof: f64,
}

/// The validation poses of `set` (`moved_joint` 0, not the tool observation), as (experiment,
/// step) in file order of their first row, with their rows.
fn validation_poses(set: &MeasurementSet, v: &Validation) -> Vec<((String, usize), Vec<usize>)> {
    let mut out: Vec<((String, usize), Vec<usize>)> = Vec::new();
    for (i, r) in v.residuals.iter().enumerate() {
        if r.kind != PointKind::Validation {
            continue;
        }
        let m = &set.rows()[i];
        match out.iter_mut().rev().find(|(k, _)| k.0 == m.experiment && k.1 == m.step) {
            Some((_, rows)) => rows.push(i),
            None => out.push(((m.experiment.clone(), m.step), vec![i])),
        }
    }
    out
}

/// Each pose's mean of `residuals` (indexed by row).
fn pose_means(poses: &[((String, usize), Vec<usize>)], residuals: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    poses
        .iter()
        .map(|(_, rows)| rows.iter().map(|&i| residuals[i]).sum::<Vector3<f64>>() / rows.len() as f64)
        .collect()
}

/// `set` with the rows `rows` moved by `-shift_mm`.
fn moved_back(set: &MeasurementSet, rows: &HashSet<usize>, shift_mm: &Vector3<f64>) -> Option<MeasurementSet> {
    let moved: Vec<Measurement> = set
        .rows()
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let mut m = m.clone();
            if rows.contains(&i) {
                (0..3).for_each(|c| m.position_mm[c] -= shift_mm[c]);
            }
            m
        })
        .collect();
    MeasurementSet::new(set.joint_count(), moved).ok()
}

/// The block of consecutive validation poses of `set` that sits off the others in the
/// validation `v` of `cal` (module docs); `None` when the validation poses meet their
/// prediction, none is significant, or the validation with the block moved back is not better.
pub fn shifted_validation_block(
    set: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
    v: &Validation,
) -> Result<Option<ValidationBlock>, DiagnosisError> {
    // Each round validates a moved copy of the file: held to the slip search's size, whose
    // note says what is not searched beyond it.
    if set.rows().len() > MAX_SEARCH_ROWS {
        return Ok(None);
    }
    let Some(summary) = v.validation.as_ref() else {
        return Ok(None);
    };
    let Some(written) = summary.chi_square.as_ref().filter(|c| c.verdict == Verdict::Exceeds) else {
        return Ok(None);
    };
    let poses = validation_poses(set, v);
    let explained = residuals_less_calibration_error(set, cal, desc, v, &BTreeSet::new())?;
    let means = pose_means(&poses, &explained);
    let Some(found) = most_significant_block(&means, MIN_BLOCK_POSES, Blocks::Any) else {
        return Ok(None);
    };
    if found.p_value * found.tried as f64 >= SLIP_FALSE_ALARM {
        return Ok(None);
    }
    let block = &poses[found.start..found.end];
    let rows: HashSet<usize> = block.iter().flat_map(|(_, r)| r.iter().copied()).collect();
    let options = ValidationOptions::of_validation(v);
    let mut shift = step_of(&means, found.start, found.end);
    let mut undone = (f64::NAN, None);
    for _ in 0..BLOCK_ROUNDS {
        let Some(moved) = moved_back(set, &rows, &shift) else {
            return Ok(None);
        };
        let again = validate(&moved, cal, desc, &options)?;
        let Some(s) = again.validation.as_ref() else {
            return Ok(None);
        };
        undone = (s.rms_mm, s.chi_square.clone());
        let left = residuals_less_calibration_error(&moved, cal, desc, &again, &BTreeSet::new())?;
        shift += step_of(&pose_means(&poses, &left), found.start, found.end);
    }
    let (undone_rms_mm, Some(undone_chi)) = undone else {
        return Ok(None);
    };
    let chance = found.inflation * chi_square_quantile(1.0 - SLIP_FALSE_ALARM / found.tried as f64, 3.0);
    if written.value - undone_chi.value <= chance {
        return Ok(None);
    }
    let lines: Vec<u64> = rows.iter().filter_map(|&i| set.line_of(i)).collect();
    Ok(Some(ValidationBlock {
        lines: (lines.iter().min().copied(), lines.iter().max().copied()),
        steps: (block[0].0.1, block[block.len() - 1].0.1),
        poses: block.len(),
        tested: poses.len(),
        shift_mm: [shift.x, shift.y, shift.z],
        p_value: found.p_value,
        blocks_tried: found.tried,
        written_rms_mm: summary.rms_mm,
        undone_rms_mm,
        written_chi2_per_dof: written.per_dof,
        undone_chi2_per_dof: undone_chi.per_dof,
    }))
}
