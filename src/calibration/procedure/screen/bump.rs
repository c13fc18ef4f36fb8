//! A sweep's points shifted part-way through it (the instrument or the target bumped, an
//! instrument re-set up during the sweep): a change-point test on the residuals of the sweep's
//! own fit, in the order the sweep lists its points.
//!
//! A sweep's fit (the ML arc through the transmission, eqs. 1-8 and 14; the ML line, eqs.
//! 9-13) cannot follow a step in its points: it takes part of it into its centre, axis and
//! transmission (a step along the motion reads as a scale of the joint's command) and leaves a
//! step between the residuals before and after it. The test ([`crate::numerics::change_point`],
//! blocks that run to the sweep's end: an instrument moved stays moved) finds the most
//! significant change point of each sweep; its p-value times the blocks tried over every sweep
//! of the file is held against [`SWEEP_BUMP_FALSE_ALARM`]. A smooth misfit (an unmodelled
//! effect along the sweep) correlates neighbouring residuals, which the serial test's long-run
//! covariance takes in. The size: the sweep fitted again with the block moved back by the step
//! found so far, the step left then added ([`BUMP_ROUNDS`] fits), and said only when that fit's
//! sum of squares beats the sweep's as written by an `F` likelihood-ratio test (its degrees of
//! freedom those of the directions the residuals spread over, Satterthwaite) at
//! the same family-wise rate (a second, differently computed test: the whole fit's sum of
//! squares, not the residuals' means), and when the sweep so moved back fits within the noise
//! of the file's noisiest other sweep ([`explains`]): a scrambled sweep is not a bumped one.
//! Where no change point passes both and the sweep as written misfits beyond that noise, a
//! second change point is sought with the best first block moved back ([`second_start`]: the
//! instrument or the target moved twice); the two blocks' six shift components are tested
//! together the same way, over the pairs tried (the file's change points times that search's),
//! and both are said where the sweep with both blocks moved back fits within that noise.

use crate::measurement::MeasurementSet;
use crate::numerics::stats::{f_upper_quantile, f_upper_tail};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

/// The family-wise false-alarm rate of the test over a whole file's sweeps.
pub const SWEEP_BUMP_FALSE_ALARM: f64 = 1e-4;

/// Points at least on each side of a change point.
pub const MIN_BUMP_POINTS: usize = 3;

/// Points of a sweep's end tested as a block of their own ([`best_end`]): fewer than
/// [`MIN_BUMP_POINTS`], more than one (a single point is the outlier test's).
pub const END_BUMP_POINTS: usize = 2;

/// Change points tried at most in one sweep ([`best_start`]).
pub const MAX_BUMP_STARTS: usize = 24;

/// Gauss-Newton steps of the block's shift ([`fitted_shift`]).
pub const BUMP_ROUNDS: usize = 2;

/// A sweep whose points from one step on sit off its earlier ones (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct SweepBump {
    /// The experiment.
    pub experiment: String,
    /// Its swept joint.
    pub joint: usize,
    /// The step of the block's first point.
    pub step: usize,
    /// Its line in the data file, when known.
    pub line: Option<u64>,
    /// Points in the block (from `step` to the sweep's end).
    pub points: usize,
    /// The sweep's points tested.
    pub tested: usize,
    /// The block's shift from the earlier points \[mm\] (instrument axes).
    pub shift_mm: [f64; 3],
    /// Its sigma per axis \[mm\] (the Gauss-Newton covariance, with the residuals' variance
    /// of the sweep's fit with the block moved back).
    pub shift_sigma_mm: [f64; 3],
    /// The change point's p-value, before the multiple-test correction.
    pub p_value: f64,
    /// Blocks tried over every sweep of the file.
    pub blocks_tried: usize,
    /// The sweep's fit RMS per coordinate \[mm\] as written, and with the block moved back.
    pub rms_mm: (f64, f64),
    /// The step of the other block's first point where the sweep's points shift twice
    /// (`bump::second_start`; each block's shift is from the points before it).
    pub beside: Option<usize>,
    /// Whether it is the sweep's first or last 2 points that sit off its others (`best_end`),
    /// tested over the ends tried (`blocks_tried`), rather than a change point with 3 points at
    /// least on each side.
    pub end: Option<SweepEnd>,
}

/// The points of a sweep's end that sit off its other points ([`SweepBump::end`]): two moved
/// points at an end cannot be told from two wrong readings by the step test, so they are named
/// by their lines.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepEnd {
    /// Whether they are the sweep's first points (else its last).
    pub first: bool,
    /// Their steps and lines in the data file, when known, in sweep order.
    pub points: Vec<(usize, Option<u64>)>,
}

/// The change point of a sweep whose block, moved back by its fitted shift
/// ([`fitted_shift`]), leaves the sweep's fit the least sum of squares: its first point (an
/// index into the points kept), shift \[m\] and sum of squares \[m^2\], with the starts tried.
pub fn best_start(x: &[Vector3<f64>], refit: Refit<'_>) -> Option<(Bumped, usize)> {
    let n = x.len();
    let every: Vec<usize> = (MIN_BUMP_POINTS..=n.checked_sub(MIN_BUMP_POINTS)?).collect();
    // A long sweep (a tracker streaming thousands of points) is searched at evenly spaced
    // starts: each is several fits of the whole sweep.
    let starts: Vec<usize> = match every.len() <= MAX_BUMP_STARTS {
        true => every,
        false => (0..MAX_BUMP_STARTS)
            .map(|k| every[k * (every.len() - 1) / (MAX_BUMP_STARTS - 1)])
            .collect(),
    };
    let tried = starts.len();
    let best = starts
        .into_iter()
        .filter_map(|start| fitted_shift(x, start, refit))
        .min_by(|a, b| a.sum_sq.total_cmp(&b.sum_sq))?;
    Some((best, tried))
}

/// The block of a sweep's end points ([`END_BUMP_POINTS`] of them, first or last) whose
/// moving back ([`fitted_shift`]) leaves the sweep's fit the least sum of squares, with the ends
/// tried: the same search as [`best_start`] at the starts it leaves out (fewer than
/// [`MIN_BUMP_POINTS`] on one side), tested over the ends of the file's sweeps on their own.
/// `None` when the sweep has fewer than [`END_BUMP_POINTS`] plus twice [`MIN_BUMP_POINTS`]
/// points (the other points then fit too loosely to set two apart).
pub fn best_end(x: &[Vector3<f64>], refit: Refit<'_>) -> Option<(Bumped, usize)> {
    let n = x.len();
    if n < END_BUMP_POINTS + 2 * MIN_BUMP_POINTS {
        return None;
    }
    let best = [END_BUMP_POINTS, n - END_BUMP_POINTS]
        .into_iter()
        .filter_map(|start| fitted_shift(x, start, refit))
        .min_by(|a, b| a.sum_sq.total_cmp(&b.sum_sq))?;
    Some((best, 2))
}

/// A second change point of a sweep (residuals `x`) whose first (`first`, from
/// [`best_start`]) does not explain its misfit (the instrument or the target moved twice): the
/// best start with the first block moved back, then both blocks' shifts fitted together
/// ([`fitted_shifts`]). Returned: the two blocks in the order found (each shift from the
/// points before its start; `sum_sq` with both moved back) and the starts tried; `None` where
/// the best second start is the first's.
pub fn second_start(x: &[Vector3<f64>], first: &Bumped, refit: Refits<'_>) -> Option<([Bumped; 2], usize)> {
    let moved_first = refit(&[(first.start, first.shift)])?;
    let (second, tried) = best_start(&moved_first, &|start, shift| {
        refit(&[(first.start, first.shift), (start, *shift)])
    })?;
    if second.start == first.start {
        return None;
    }
    let both = fitted_shifts(x, &[first.start, second.start], refit)?;
    Some(([both[0], both[1]], tried))
}

/// A change point with its fitted shift.
#[derive(Clone, Copy, Debug)]
pub struct Bumped {
    /// The block's first point (an index into the points kept).
    pub start: usize,
    /// The shift \[m\] that, taken off the block, fits the sweep best.
    pub shift: Vector3<f64>,
    /// The sweep fit's sum of squares with the block moved back \[m^2\].
    pub sum_sq: f64,
    /// The shift's sigma per axis for a unit variance of the residuals: the square roots of
    /// the diagonal of the Gauss-Newton covariance `(J^T J)^-1`.
    pub unit_sigma: Vector3<f64>,
    /// The directions its residuals spread over (1 to 3): `tr(S)^2 / tr(S^2)` of their scatter
    /// matrix `S` (Satterthwaite's effective degrees of freedom, as the outlier test's).
    pub spread: f64,
}

/// `tr(S)^2 / tr(S^2)` of the scatter matrix `S` of the 3-D residuals `r` (flattened), in
/// 1..=3.
fn spread(r: &DVector<f64>) -> f64 {
    let scatter: Matrix3<f64> = r
        .as_slice()
        .chunks_exact(3)
        .map(|v| Vector3::new(v[0], v[1], v[2]))
        .map(|v| v * v.transpose())
        .sum();
    (scatter.trace().powi(2) / scatter.norm_squared()).clamp(1.0, 3.0)
}

/// A sweep's refit with its points from a start on moved back by a shift ([`best_start`]):
/// the residuals of the points kept.
pub type Refit<'a> = &'a dyn Fn(usize, &Vector3<f64>) -> Option<Vec<Vector3<f64>>>;

/// A sweep's refit with its points from each start on moved back by that start's shift
/// ([`second_start`]; the shifts of blocks that overlap add): the residuals of the points kept.
pub type Refits<'a> = &'a dyn Fn(&[(usize, Vector3<f64>)]) -> Option<Vec<Vector3<f64>>>;

/// The shift \[m\] of the points `start..` of residuals `x` that minimises the sweep fit's sum
/// of squares ([`fitted_shifts`] of one block).
fn fitted_shift(x: &[Vector3<f64>], start: usize, refit: Refit<'_>) -> Option<Bumped> {
    let one = fitted_shifts(x, &[start], &|blocks| refit(blocks[0].0, &blocks[0].1))?;
    Some(one[0])
}

/// The shifts \[m\] of the points from each of `starts` on (residuals `x`, every block in
/// place) that together minimise the sweep fit's sum of squares: Gauss-Newton on the refit's
/// residuals, their Jacobian in the shifts by forward differences of [`DIFFERENCE_M`] (the
/// fit's residuals are near linear in a shift of millimetres), [`BUMP_ROUNDS`] steps with that
/// Jacobian. Each block's `unit_sigma` is from the joint covariance; `sum_sq` and `spread` are
/// the fit's with every block moved back.
fn fitted_shifts(x: &[Vector3<f64>], starts: &[usize], refit: Refits<'_>) -> Option<Vec<Bumped>> {
    let flat = |r: &[Vector3<f64>]| DVector::from_iterator(3 * r.len(), r.iter().flat_map(|v| v.iter().copied()));
    let shift_of = |s: &DVector<f64>, b: usize| Vector3::new(s[3 * b], s[3 * b + 1], s[3 * b + 2]);
    let blocks = |s: &DVector<f64>| -> Vec<(usize, Vector3<f64>)> {
        starts
            .iter()
            .enumerate()
            .map(|(b, &start)| (start, shift_of(s, b)))
            .collect()
    };
    let n = 3 * starts.len();
    let r0 = flat(x);
    let mut jacobian = DMatrix::zeros(r0.len(), n);
    for c in 0..n {
        let moved = flat(&refit(&blocks(&DVector::from_fn(n, |i, _| {
            if i == c { DIFFERENCE_M } else { 0.0 }
        })))?);
        jacobian.set_column(c, &((moved - &r0) / DIFFERENCE_M));
    }
    let solver = (jacobian.transpose() * &jacobian).cholesky()?;
    let inverse = solver.inverse();
    let (mut shift, mut sum_sq, mut spread_of) = (DVector::zeros(n), r0.norm_squared(), spread(&r0));
    let mut r = r0;
    for _ in 0..BUMP_ROUNDS {
        let next = &shift - solver.solve(&(jacobian.transpose() * &r));
        let Some(left) = refit(&blocks(&next)) else {
            break;
        };
        r = flat(&left);
        if r.norm_squared() >= sum_sq {
            break;
        }
        (shift, sum_sq, spread_of) = (next, r.norm_squared(), spread(&r));
    }
    let bumped = |(b, &start): (usize, &usize)| Bumped {
        start,
        shift: shift_of(&shift, b),
        sum_sq,
        unit_sigma: Vector3::from_fn(|c, _| inverse[(3 * b + c, 3 * b + c)].sqrt()),
        spread: spread_of,
    };
    Some(starts.iter().enumerate().map(bumped).collect())
}

/// The forward difference of the shift's Jacobian \[m\].
const DIFFERENCE_M: f64 = 1e-3;

/// Whether the change points of residuals `x` (`blocks` of them: 1, or 2 where a sweep shifts
/// twice; `found` the last, its `sum_sq` with every block moved back) pass the
/// likelihood-ratio test over `tried` change points (or pairs) of the file (module docs): its
/// p-value, before the correction, when they do. `dof` is the sweep fit's degrees of freedom.
pub fn confirmed(x: &[Vector3<f64>], found: &Bumped, (dof, blocks): (f64, usize), tried: usize) -> Option<f64> {
    let written: f64 = x.iter().map(|v| v.norm_squared()).sum();
    let shifts = 3.0 * blocks as f64;
    let nu = dof - shifts;
    if !(nu >= 1.0 && found.sum_sq > 0.0 && found.sum_sq < written) {
        return None;
    }
    // With the noise spread over `m` directions the ratio is about `F(m b, m nu / 3)` for `b`
    // blocks (Satterthwaite): `m = 3` isotropic, `m = 1` all along one direction, the heaviest
    // tail.
    let m = found.spread;
    let ratio = (written - found.sum_sq) / shifts / (found.sum_sq / nu);
    let p = f_upper_tail(ratio, m * blocks as f64, m * nu / 3.0);
    (p * (tried as f64) < SWEEP_BUMP_FALSE_ALARM).then_some(p)
}

/// Whether the sweep with its blocks moved back (`found`, its `sum_sq` with every block moved
/// back; `blocks` of them; the fit's `dof`) fits within the noise of the file's noisiest other
/// sweep (`noisiest_other`: its residual variance \[m^2\] and degrees of freedom): its
/// variance ratio to that sweep's within the `F` quantile at [`SWEEP_BUMP_FALSE_ALARM`] over
/// the `tried` change points. A sweep whose points are scrambled, in other units or of another
/// robot has a step that fits better than none, but misses its points by far more than any
/// sweep's noise even so: the step does not explain it. True without another sweep to compare
/// with. With no block (`blocks` 0) it tells whether the sweep as written fits so.
pub fn explains(found: &Bumped, (dof, blocks): (f64, usize), noisiest_other: Option<(f64, f64)>, tried: usize) -> bool {
    let Some((variance, other_dof)) = noisiest_other else {
        return true;
    };
    let nu = dof - 3.0 * blocks as f64;
    let ratio = found.sum_sq / nu / variance;
    !(variance > 0.0 && nu >= 1.0 && other_dof >= 1.0)
        || ratio <= f_upper_quantile(SWEEP_BUMP_FALSE_ALARM / tried.max(1) as f64, nu, other_dof)
}

/// `set` with the block of each of `bumps` moved back by its shift: every row of its
/// experiment from its step on (each target: an instrument moved moves them alike) less
/// [`SweepBump::shift_mm`] (less both where a sweep shifts twice), as the sweep screen's refit moved it to confirm the bump; `None`
/// when there is none. The checks that read a sweep's fit as the joint's (its transmission's
/// scale, an instrument axis' scale, a held joint's offset) run on it, so that they do not
/// name the bump's own signature as a second cause.
pub fn bumps_undone(set: &MeasurementSet, bumps: &[SweepBump]) -> Option<MeasurementSet> {
    if bumps.is_empty() {
        return None;
    }
    let moves: Vec<(usize, [f64; 3])> = set
        .rows()
        .iter()
        .enumerate()
        .filter_map(|(i, m)| {
            let mut moved = bumps
                .iter()
                .filter(|b| b.experiment == m.experiment && m.step >= b.step)
                .peekable();
            moved.peek()?;
            let shift = moved.fold([0.0; 3], |a, b| std::array::from_fn(|c| a[c] - b.shift_mm[c]));
            Some((i, shift))
        })
        .collect();
    Some(set.with_rows_moved(&moves))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    /// 16 residuals of a fixed-seed generator, 3-D, scale `sigma`.
    fn noise(seed: u64, sigma: f64) -> Vec<Vector3<f64>> {
        let mut rng = rand::rngs::ChaCha12Rng::seed_from_u64(seed);
        (0..16)
            .map(|_| {
                Vector3::from_fn(|_, _| {
                    let z: f64 = StandardNormal.sample(&mut rng);
                    sigma * z
                })
            })
            .collect()
    }

    /// A refit that takes nothing of the step (the residuals of the block less the shift):
    /// Gauss-Newton is exact on it, so the shift found is the block's mean step, found at its
    /// start, and significant; pure noise passes on 20 seeds (the F test's own rate).
    #[test]
    fn a_step_is_found_where_the_fit_takes_none_of_it() {
        let step = Vector3::new(0.0, 6.0, 1.0);
        let mut x = noise(1, 1.0);
        x[10..].iter_mut().for_each(|v| *v += step);
        let refit_of = |x: Vec<Vector3<f64>>| {
            move |start: usize, shift: &Vector3<f64>| -> Option<Vec<Vector3<f64>>> {
                Some(
                    (0..x.len())
                        .map(|i| if i >= start { x[i] - shift } else { x[i] })
                        .collect(),
                )
            }
        };
        let (found, tried) = best_start(&x, &refit_of(x.clone())).unwrap();
        assert_eq!((found.start, tried), (10, 11));
        let expected = x[10..].iter().sum::<Vector3<f64>>() / 6.0;
        assert!(
            (found.shift - expected).norm() < 1e-9,
            "{} against {expected}",
            found.shift
        );
        assert!(confirmed(&x, &found, (48.0, 1), tried).is_some());
        for seed in 0..20 {
            let x = noise(100 + seed, 1.0);
            let (found, tried) = best_start(&x, &refit_of(x.clone())).unwrap();
            assert!(confirmed(&x, &found, (48.0, 1), tried).is_none(), "seed {seed}");
        }
    }

    /// Two steps where the refit takes nothing of them: the second search, with the first block
    /// moved back, finds the other start; the joint fit's shifts are the means written out (a
    /// second path), the pair passes the test of six shift components, and noise alone passes
    /// it on 20 seeds.
    #[test]
    fn two_steps_are_found_each_with_its_own_shift() {
        let (a, b) = (Vector3::new(0.0, 4.0, 0.0), Vector3::new(3.0, 0.0, -3.0));
        let mut x = noise(2, 1.0);
        x[5..].iter_mut().for_each(|v| *v += a);
        x[11..].iter_mut().for_each(|v| *v += b);
        let refits_of = |x: Vec<Vector3<f64>>| {
            move |blocks: &[(usize, Vector3<f64>)]| -> Option<Vec<Vector3<f64>>> {
                Some(
                    (0..x.len())
                        .map(|i| {
                            x[i] - blocks
                                .iter()
                                .filter(|(s, _)| i >= *s)
                                .map(|(_, v)| v)
                                .sum::<Vector3<f64>>()
                        })
                        .collect(),
                )
            }
        };
        let refits = refits_of(x.clone());
        let (first, tried) = best_start(&x, &|s, v| refits(&[(s, *v)])).unwrap();
        let ([first, second], more) = second_start(&x, &first, &refits).unwrap();
        let mut found = [(first.start, first.shift), (second.start, second.shift)];
        found.sort_by_key(|f| f.0);
        // Gauss-Newton is exact on this refit: the points before the first start are fitted by
        // nothing, so the first shift is the mean of the points between the starts and the
        // second the mean after less it.
        let mean = |r: std::ops::Range<usize>| x[r.clone()].iter().sum::<Vector3<f64>>() / r.len() as f64;
        assert_eq!((found[0].0, found[1].0), (5, 11));
        assert!((found[0].1 - mean(5..11)).norm() < 1e-9, "{found:?}");
        assert!((found[1].1 - (mean(11..16) - mean(5..11))).norm() < 1e-9, "{found:?}");
        assert!(confirmed(&x, &second, (48.0, 2), tried * more).is_some());
        for seed in 0..20 {
            let x = noise(200 + seed, 1.0);
            let refits = refits_of(x.clone());
            let (first, tried) = best_start(&x, &|s, v| refits(&[(s, *v)])).unwrap();
            let Some(([_, second], more)) = second_start(&x, &first, &refits) else {
                continue;
            };
            assert!(confirmed(&x, &second, (48.0, 2), tried * more).is_none(), "seed {seed}");
        }
    }
}
