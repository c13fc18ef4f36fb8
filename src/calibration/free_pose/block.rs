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
//! The test: for every block of consecutive poses in file order (from a pose to the end, or
//! between two poses; three poses at least inside and outside), the two-sample
//! Hotelling `T^2` of the poses' mean residuals inside against outside, with the within-group
//! pooled covariance (Mardia, Kent & Bibby, *Multivariate Analysis*, 1979, sec. 3.6.1),
//! finds the block; that block is then tested with the long-run (serially correlated)
//! covariance of the within-group residuals (`serial_test`, `T^2` read as Hotelling's, an
//! `F(3, n - 4)` multiple, without a shift), its p-value times the blocks tried (Bonferroni over the candidate change points)
//! held against [`SLIP_FALSE_ALARM`]. The fit's leverage (a few per cent of each residual's
//! variance over tens of poses a parameter) shrinks the step and the scatter alike to first
//! order; the part of the shift the fit took makes the test conservative.
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
use crate::numerics::stats::{chi_square_quantile, f_upper_tail};
use crate::robot::{Controller, RobotDescription};
use nalgebra::{Matrix3, Vector3};
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

/// The most significant block of poses `start..end` (indices into the tested sequence), its
/// residual step \[m\], p-value and the blocks tried.
struct Found {
    start: usize,
    end: usize,
    p_value: f64,
    tried: usize,
    /// How much the serial correlation widens the block's test (the plain `T^2` over the
    /// serial one, at least 1).
    inflation: f64,
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

/// The block of `x` (file order) whose mean differs most significantly from the others'
/// (module docs: Hotelling's two-sample `T^2`, within-group covariance), over every block
/// `a..b` with `0 < a` (a block from the first pose is the complement of one to the end).
fn most_significant_block(x: &[Vector3<f64>]) -> Option<Found> {
    let n = x.len();
    if n < 2 * MIN_BLOCK_POSES || n < 6 {
        return None;
    }
    let centre = x.iter().sum::<Vector3<f64>>() / n as f64;
    let x: Vec<Vector3<f64>> = x.iter().map(|v| v - centre).collect();
    let mut prefix = vec![Vector3::zeros(); n + 1];
    let mut total = Matrix3::zeros();
    for (i, v) in x.iter().enumerate() {
        prefix[i + 1] = prefix[i] + v;
        total += v * v.transpose();
    }
    let nf = n as f64;
    let (mut best, mut tried) = (None::<(f64, usize, usize)>, 0);
    for a in 1..n {
        for b in a + MIN_BLOCK_POSES..=n {
            let (inside, outside) = ((b - a) as f64, (n - (b - a)) as f64);
            if n - (b - a) < MIN_BLOCK_POSES {
                break;
            }
            tried += 1;
            let sum_in = prefix[b] - prefix[a];
            let (m1, m0) = (sum_in / inside, (prefix[n] - sum_in) / outside);
            let within = (total - m1 * m1.transpose() * inside - m0 * m0.transpose() * outside) / (nf - 2.0);
            let d = m1 - m0;
            let Some(ch) = within.cholesky() else { continue };
            let t2 = inside * outside / nf * d.dot(&ch.solve(&d));
            if best.is_none_or(|(t, _, _)| t2 > t) {
                best = Some((t2, a, b));
            }
        }
    }
    let (t2, start, end) = best?;
    let (t2_serial, p_value) = serial_test(&x, start, end)?;
    Some(Found {
        start,
        end,
        p_value,
        tried,
        inflation: (t2 / t2_serial).max(1.0),
    })
}

/// The block `start..end` of `x` (centred) tested with the long-run covariance of the
/// within-group residuals instead of their plain covariance: Bartlett weights over
/// `floor(4 (n / 100)^(2/9))` lags (Newey & West, *Rev. Econ. Stud.* 61, 1994, eq. 3.8;
/// Andrews, *Econometrica* 61, 1993, for the change-point test with it), `T^2` then about
/// `chi^2(3)` without a shift. The poses of a real file in file order share unmodelled errors
/// with their neighbours (the real FANUC's: lag-1 correlation 0.7 in z), which the plain
/// covariance takes for independent scatter. Returns `T^2` and its p-value (Hotelling's `F`).
fn serial_test(x: &[Vector3<f64>], start: usize, end: usize) -> Option<(f64, f64)> {
    let n = x.len();
    let inside = |i: usize| (start..end).contains(&i);
    let mean_of = |want: bool| {
        let v: Vec<&Vector3<f64>> = (0..n).filter(|&i| inside(i) == want).map(|i| &x[i]).collect();
        v.iter().copied().sum::<Vector3<f64>>() / v.len() as f64
    };
    let (m1, m0) = (mean_of(true), mean_of(false));
    let e: Vec<Vector3<f64>> = (0..n).map(|i| x[i] - if inside(i) { m1 } else { m0 }).collect();
    let lags = (4.0 * (n as f64 / 100.0).powf(2.0 / 9.0)).floor() as usize;
    let autocovariance =
        |l: usize| -> Matrix3<f64> { (l..n).map(|i| e[i] * e[i - l].transpose()).sum::<Matrix3<f64>>() / n as f64 };
    let mut long_run = autocovariance(0);
    for l in 1..=lags.min(n - 1) {
        let g = autocovariance(l);
        long_run += (g + g.transpose()) * (1.0 - l as f64 / (lags + 1) as f64);
    }
    let (n1, n0) = ((end - start) as f64, (n - (end - start)) as f64);
    let d = m1 - m0;
    let t2 = n1 * n0 / n as f64 * d.dot(&long_run.cholesky()?.solve(&d));
    // Hotelling's two-sample `T^2` on `nu = n - 2` degrees of freedom of the covariance is
    // `nu p / (nu - p + 1)` times an `F(p, nu - p + 1)` (Mardia, Kent & Bibby, eq. 3.6.4,
    // `p = 3`); its tail, far heavier than `chi^2(3)`'s at the Bonferroni level over thousands
    // of blocks, keeps the family-wise rate on white noise.
    let nu = n as f64 - 2.0;
    Some((t2, f_upper_tail(t2 * (nu - 2.0) / (3.0 * nu), 3.0, nu - 2.0)))
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

/// The mean of `x[start..end]` less the mean of the others.
fn step_of(x: &[Vector3<f64>], start: usize, end: usize) -> Vector3<f64> {
    let inside: Vector3<f64> = x[start..end].iter().sum();
    let all: Vector3<f64> = x.iter().sum();
    inside / (end - start) as f64 - (all - inside) / (x.len() - (end - start)) as f64
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
    let found = most_significant_block(&means)?;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Independent draws of a fixed-seed generator, 3-D, scale 1.
    fn noise(n: usize, seed: u64) -> Vec<Vector3<f64>> {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand::rngs::ChaCha12Rng::seed_from_u64(seed);
        (0..n)
            .map(|_| Vector3::from_fn(|_, _| StandardNormal.sample(&mut rng)))
            .collect()
    }

    /// A step of 3 sigma in z over the poses 40..70 of 100 is found there (a change point's
    /// place is off by more than one pose with odds of about `Phi(-3 / sqrt 2)^2` per side);
    /// clean noise's smallest p-value times the blocks tried stays above the false-alarm rate
    /// on 20 seeds.
    #[test]
    fn a_middle_block_is_found_and_noise_is_quiet() {
        let mut x = noise(100, 7);
        x[40..70].iter_mut().for_each(|v| v.z += 3.0);
        let f = most_significant_block(&x).unwrap();
        assert!(
            f.start.abs_diff(40) <= 1 && f.end.abs_diff(70) <= 1,
            "{}..{}",
            f.start,
            f.end
        );
        assert!(f.p_value * (f.tried as f64) < SLIP_FALSE_ALARM);
        for seed in 0..20 {
            let f = most_significant_block(&noise(100, seed)).unwrap();
            assert!(
                f.p_value * (f.tried as f64) > SLIP_FALSE_ALARM,
                "seed {seed}: {}",
                f.p_value
            );
        }
    }
}
