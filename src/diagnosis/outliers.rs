//! Gross errors among the validation points, found before the diagnosis: each point's 3-D
//! residual after the baseline refit (the training points fitted, the held-out ones predicted)
//! over the noise per axis, `z`, against Tukey's far-out fence of every point's (the rule of the
//! sweeps' screening, [`crate::calibration::procedure::screen_sweeps`], and of the free-pose
//! fit, [`far_out_fence`]), and never below the level the noise reaches at a family-wise rate
//! ([`VALIDATION_POINTS_FALSE_ALARM`] over the file's points, as the sweeps' fence).
//!
//! An effect moves the tool, so every target of a pose nearly alike (their residuals differ by
//! the tool's rotation error times the targets' spacing); a corrupted reading, two swapped
//! target ids or a point in other units moves one or two. So a point is an outlier when both
//! its `z` and its distance from the nearest residual of another target of its pose (over the
//! noise of a difference, `sigma sqrt 2`) are beyond their far-out fences: an effect's pose, its
//! targets far off alike, stays for the diagnosis to explain. A pose with one target is not
//! tested.

use super::validate::{Validation, residuals_less_calibration_error};
use super::{DiagnosisError, DiagnosisOptions, ordered, prepare, with_free_pose_targets};
use crate::calibration::procedure::Calibration;
use crate::calibration::procedure::SWEEP_POINTS_FALSE_ALARM;
use crate::calibration::procedure::{OutlierPoint, OutlierTest};
use crate::measurement::MeasurementSet;
use crate::numerics::stats::{chi_square_quantile, far_out_fence};
use crate::robot::RobotDescription;
use nalgebra::{DMatrix, Vector3};
use std::collections::HashMap;

/// Fewer points than this are not tested (their quartiles are no fence).
const MIN_POINTS: usize = 8;

/// The validation points of `set` beyond both fences (module docs), in file order; with `keep`
/// they are flagged as they would be dropped (`dropped` false), as
/// [`screen_sweeps`](crate::calibration::procedure::screen_sweeps) does.
pub fn validation_outliers(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &DiagnosisOptions,
    keep: bool,
) -> Result<Vec<OutlierPoint>, DiagnosisError> {
    let fitted = with_free_pose_targets(set, desc, options)?;
    let prep = prepare(set, fitted.as_ref().unwrap_or(desc), options, false)?;
    let observed = DMatrix::from_column_slice(prep.residuals.len(), 1, prep.residuals.as_slice());
    let (train, held) = prep.rows(&observed);
    let (train, held) = prep.baseline_fit().residualise(&train, &held);
    let r: Vec<f64> = train.iter().chain(held.iter()).copied().collect();
    let sigma_m = options.noise_rms_3d_mm * 1e-3 / 3f64.sqrt();
    // Per pose (training then held-out, as the rows), per target: (target, r [m]).
    let mut row = 0;
    let mut poses = Vec::new();
    for p in ordered(&prep.poses) {
        let points: Vec<(usize, Vector3<f64>)> = p
            .targets
            .iter()
            .map(|&(target, _)| {
                row += 3;
                (target, Vector3::new(r[row - 3], r[row - 2], r[row - 1]))
            })
            .collect();
        poses.push(((p.experiment.as_str(), p.step), points));
    }
    Ok(pose_point_outliers(set, &poses, sigma_m, keep))
}

/// The residual vectors \[m\] of the targets of one free pose, keyed by its experiment and step.
pub type PoseResiduals<'a> = ((&'a str, usize), Vec<(usize, Vector3<f64>)>);

/// The points of `poses` (each pose's targets' residuals) beyond both fences (module docs),
/// `sigma_m` the noise per axis, in the file order of `set`; with `keep` flagged as they would
/// be dropped (`dropped` false). What [`validation_outliers`] finds after the baseline refit,
/// and `validate` in a given calibration's residuals.
pub fn pose_point_outliers(
    set: &MeasurementSet,
    poses: &[PoseResiduals<'_>],
    sigma_m: f64,
    keep: bool,
) -> Vec<OutlierPoint> {
    // Per point of a pose with two targets or more: (pose, target, |r|, z, d).
    let mut tested = Vec::new();
    for (p, points) in poses {
        for (k, (target, rk)) in points.iter().enumerate() {
            let nearest = points
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != k)
                .map(|(_, (_, rj))| (rk - rj).norm())
                .fold(f64::INFINITY, f64::min);
            if nearest.is_finite() {
                let d = nearest / (sigma_m * 2f64.sqrt());
                tested.push((*p, *target, rk.norm(), rk.norm() / sigma_m, d));
            }
        }
    }
    if tested.len() < MIN_POINTS {
        return Vec::new();
    }
    let residuals: Vec<Vector3<f64>> = poses
        .iter()
        .flat_map(|(_, points)| points.iter().map(|(_, r)| *r))
        .collect();
    let fence =
        far_out_fence(&tested.iter().map(|t| t.3).collect::<Vec<_>>()).max(noise_fence(&residuals, tested.len()));
    let fence_apart = far_out_fence(&tested.iter().map(|t| t.4).collect::<Vec<_>>());
    let mut flagged: Vec<OutlierPoint> = tested
        .iter()
        .filter(|t| t.3 > fence && t.4 > fence_apart)
        .map(|&((experiment, step), target, norm, z, _)| OutlierPoint {
            experiment: experiment.to_owned(),
            joint: 0,
            step,
            target,
            line: None,
            residual_mm: norm * 1e3,
            normalised_residual: z,
            fence,
            dropped: !keep,
            approach: None,
            test: OutlierTest::Screen,
        })
        .collect();
    let rows: HashMap<(&str, usize, usize), usize> = set
        .rows()
        .iter()
        .enumerate()
        .map(|(i, m)| ((m.experiment.as_str(), m.step, m.target), i))
        .collect();
    for o in &mut flagged {
        o.line = rows
            .get(&(o.experiment.as_str(), o.step, o.target))
            .and_then(|&i| set.line_of(i));
    }
    flagged.sort_by_key(|o| (o.line, o.step, o.target));
    flagged
}

/// The free-pose points (`moved_joint` 0: validation and tool poses) of `set` whose residuals
/// in `v` are gross errors, as `diagnose` finds them ([`pose_point_outliers`]: beyond the
/// far-out fences of every point's residual and of its distance from its pose's other targets'
/// residuals; an error of the model moves a pose's targets alike), dropped unless `keep`. A
/// point is flagged only if it is also beyond them once the calibration's own error, which
/// the residuals of every pose but the flagged points' estimate together, is taken out
/// ([`residuals_less_calibration_error`]); what `validate` drops and `calibrate` leaves out of
/// its test of the file's own validation poses: where that error dominates the prediction, a clean
/// point may sit tens of noise sigmas off, and it is the calibration's error, not a gross one.
pub fn free_pose_outliers(
    v: &Validation,
    set: &MeasurementSet,
    (cal, desc): (&Calibration, &RobotDescription),
    keep: bool,
) -> Result<Vec<OutlierPoint>, DiagnosisError> {
    let raw: Vec<Vector3<f64>> = v
        .residuals
        .iter()
        .map(|r| Vector3::from(r.measured_mm) - Vector3::from(r.predicted_mm))
        .collect();
    let sigma_m = v.noise_rms_3d_mm * 1e-3 / 3f64.sqrt();
    let flagged = pose_point_outliers(set, &free_pose_residuals(set, &raw), sigma_m, keep);
    if flagged.is_empty() {
        return Ok(flagged);
    }
    let suspects: std::collections::BTreeSet<(&str, usize)> =
        flagged.iter().map(|o| (o.experiment.as_str(), o.step)).collect();
    let explained = residuals_less_calibration_error(set, cal, desc, v, &suspects)?;
    let still = pose_point_outliers(set, &free_pose_residuals(set, &explained), sigma_m, keep);
    let key = |o: &OutlierPoint| (o.experiment.clone(), o.step, o.target);
    let still: std::collections::HashSet<_> = still.iter().map(key).collect();
    Ok(flagged.into_iter().filter(|o| still.contains(&key(o))).collect())
}

/// Each free pose's targets' residuals (`residuals_mm` per row of `set`), in metres, the poses
/// in order of first appearance.
fn free_pose_residuals<'a>(set: &'a MeasurementSet, residuals_mm: &[Vector3<f64>]) -> Vec<PoseResiduals<'a>> {
    let mut poses: Vec<PoseResiduals<'_>> = Vec::new();
    // Each pose's place in `poses`: linear in the rows.
    let mut index: std::collections::HashMap<(&str, usize), usize> = std::collections::HashMap::new();
    for (m, r) in set.rows().iter().zip(residuals_mm).filter(|(m, _)| m.moved_joint == 0) {
        let key = (m.experiment.as_str(), m.step);
        let at = *index.entry(key).or_insert_with(|| {
            poses.push((key, Vec::new()));
            poses.len() - 1
        });
        poses[at].1.push((m.target, r * 1e-3));
    }
    poses
}

/// The family-wise false-alarm rate of the validation points' test over a whole file: the
/// sweeps' ([`SWEEP_POINTS_FALSE_ALARM`]), so that a clean file's points pass both tests alike.
pub const VALIDATION_POINTS_FALSE_ALARM: f64 = SWEEP_POINTS_FALSE_ALARM;

/// The normalised residual `|r| / sigma` a point of the noise passes with probability
/// `1 - VALIDATION_POINTS_FALSE_ALARM / tested`: with the residuals `residuals` spread over `m`
/// directions (1 to 3, Satterthwaite's `tr(S)^2 / tr(S^2)` of their scatter matrix `S`; a
/// theodolite pair's depth error puts most of it along one), `z^2` is about `3 / m` times a
/// chi-square with `m` degrees of freedom. Tukey's far-out fence alone is no rate: over the
/// 120 points of a clean 40-pose file it set aside one at 4.7 sigma (hostile run 9 FA4),
/// inside what 120 draws of the noise reach one time in a hundred.
fn noise_fence(residuals: &[Vector3<f64>], tested: usize) -> f64 {
    let scatter: nalgebra::Matrix3<f64> = residuals.iter().map(|r| r * r.transpose()).sum();
    let spread = (scatter.trace().powi(2) / scatter.norm_squared()).clamp(1.0, 3.0);
    if !spread.is_finite() {
        return 0.0;
    }
    let tail = VALIDATION_POINTS_FALSE_ALARM / tested.max(1) as f64;
    (3.0 / spread * chi_square_quantile(1.0 - tail, spread)).sqrt()
}

/// `set` without the points `outliers`.
pub fn without_outliers(set: &MeasurementSet, outliers: &[OutlierPoint]) -> MeasurementSet {
    let drop: std::collections::HashSet<(&str, usize, usize)> = outliers
        .iter()
        .map(|o| (o.experiment.as_str(), o.step, o.target))
        .collect();
    let rows: Vec<usize> = (0..set.rows().len())
        .filter(|&i| {
            let m = &set.rows()[i];
            drop.contains(&(m.experiment.as_str(), m.step, m.target))
        })
        .collect();
    set.without_rows(&rows)
}
