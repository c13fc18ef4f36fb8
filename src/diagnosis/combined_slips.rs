//! Slips in a block of rows, and two slips at once (`validate`): what the one-at-a-time
//! searches ([`super::slips`], [`super::sweep_slips`], [`super::file_scale`]) leave as the
//! model's error. A file can carry a command column scaled and its coordinates scaled
//! together, or a block of consecutive free poses shifted, scaled or with one command offset
//! (the instrument bumped, a joint re-mastered part-way through the session); no single
//! rewrite of the whole file or of one experiment then passes the tests.
//!
//! The search is greedy, with refit: a rewrite is a uniform change of one quantity over one
//! block of rows: the coordinates shifted (3 parameters) or scaled about the instrument's
//! origin, a command column scaled or offset (1 parameter). The blocks: the whole file, each
//! axis experiment, and every run of at least [`MIN_BLOCK_POSES`] consecutive poses of a
//! free-pose experiment. Each (rewrite, block) pair is screened by the drop of the residuals'
//! sum of squares its least-squares parameter gives (weighted with the predicted RMS of the
//! rows' kind: linear, cheap); the [`TESTED_CANDIDATES`] largest are fitted on the model and
//! scored by the drop of the validation's own statistic ([`validate`], every position test).
//! The best is kept when that drop is significant: beyond the chi-square quantile of its
//! parameters at the false-alarm rate divided by the number of pairs screened (a Bonferroni
//! bound: on clean data the largest drop of many pairs is large by chance). At most
//! [`MAX_SLIPS`] rewrites are kept, each found with the previous ones undone; when the
//! largest drop's slip leaves no second one that passes, the other significant ones are
//! tried in turn (a joint's command scale and the coordinates' scale together: the largest
//! drop can be a rewrite that takes part of both, which no second slip completes). The slips are
//! said only when the file with them undone passes every test of the validation (positions
//! and orientations): a model that is wrong (another robot, an effect the model lacks) misses
//! its data in a way no one or two uniform rewrites of blocks undo, and stays the model's.
//! Nor are they said when none of them moves its block's points beyond what the calibration's
//! own predicted error and the noise could ([`beyond_prediction`]): a calibration's shared
//! error (its tool frame kept nominal, a poorly measured axis) moves a block as a slip does,
//! and whether its pattern is in the predicted covariance or not, a move within its predicted
//! size is no evidence of a slip.
//!
//! A whole file's command offset below [`MIN_FITTED_OFFSET`] is not said: it is a zero error
//! of the joint, which the calibration fits, not a slip of the data. Runs only when a position
//! test exceeds, so clean data pay nothing.

use super::slips::{MAX_FITTED_OFFSET, MIN_FITTED_OFFSET, residuals_with};
use super::validate::{PointKind, PositionSummary, Validation, ValidationOptions, Verdict, validate};
use super::{ExplainedMiss, explained_file_scale, explained_misses, explained_sweep_misses};
use crate::calibration::procedure::Calibration;
use crate::measurement::{Measurement, MeasurementSet, format_f64};
use crate::numerics::finite_diff::try_central_difference;
use crate::numerics::stats::chi_square_quantile;
use crate::robot::RobotDescription;
use nalgebra::{DMatrix, DVector, Vector3};
use std::collections::BTreeMap;
use std::sync::Arc;

/// At most this many slips are undone together: two slips at once are what a session's
/// bookkeeping plausibly carries; more uniform rewrites of blocks could absorb a model's error.
pub const MAX_SLIPS: usize = 2;

/// A block of free poses has at least this many poses: fewer give too few points for a
/// fitted shift (3 parameters) not to absorb their noise, and are outliers' business
/// (`validate`'s outlier poses).
pub const MIN_BLOCK_POSES: usize = 3;

/// The most rows the search runs on ([`combined_slips_searched`]): each candidate is fitted on
/// the model with every row predicted again, some hundreds of times over a search. At 100 000
/// rows that took 257 s and 552 MB (quick-release build), at a million more than 2 GB and many
/// minutes; and beyond about 340 poses the runs start on evenly spaced poses only
/// (the runs' boundaries), so a slip starting between them is not found anyway.
pub const MAX_SEARCH_ROWS: usize = 20_000;

/// Whether [`explained_combined_slips`] searches `set`: at most [`MAX_SEARCH_ROWS`] rows.
pub fn combined_slips_searched(set: &MeasurementSet) -> bool {
    set.rows().len() <= MAX_SEARCH_ROWS
}

/// The (rewrite, block) pairs with the largest screening drop that are fitted and scored on
/// the validation's statistic: the screening weighs rows as independent, which the
/// calibration's shared error is not, so the best few are scored on the real statistic.
const TESTED_CANDIDATES: usize = 4;

/// Central differences of the rewrites' parameters (mm, scale, deg or mm of a command).
const SHIFT_STEP_MM: f64 = 1e-3;
const SCALE_STEP: f64 = 1e-6;
const OFFSET_STEP: f64 = 1e-3;

/// What a rewrite changes.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Quantity {
    /// The coordinates shifted (3 parameters).
    Shift,
    /// Every coordinate scaled about the instrument's origin.
    CoordinateScale,
    /// Command column `k` (0-based) scaled.
    CommandScale(usize),
    /// Command column `k` offset.
    CommandOffset(usize),
}

impl Quantity {
    /// The rewrite of a row by the parameters `p` (one, or three for a shift).
    fn apply(self, m: &mut Measurement, p: &[f64; 3]) {
        match self {
            Quantity::Shift => (0..3).for_each(|c| m.position_mm[c] += p[c]),
            Quantity::CoordinateScale => m.position_mm.iter_mut().for_each(|c| *c *= 1.0 + p[0]),
            Quantity::CommandScale(k) => m.cmd[k] *= 1.0 + p[0],
            Quantity::CommandOffset(k) => m.cmd[k] += p[0],
        }
    }

    /// The unit parameter vectors of its directions and their difference step.
    fn directions(self) -> Vec<([f64; 3], f64)> {
        match self {
            Quantity::Shift => (0..3)
                .map(|c| {
                    let mut e = [0.0; 3];
                    e[c] = 1.0;
                    (e, SHIFT_STEP_MM)
                })
                .collect(),
            Quantity::CoordinateScale | Quantity::CommandScale(_) => vec![([1.0, 0.0, 0.0], SCALE_STEP)],
            Quantity::CommandOffset(_) => vec![([1.0, 0.0, 0.0], OFFSET_STEP)],
        }
    }
}

/// A block of rows: its row indices and how it is named.
#[derive(Clone, Debug)]
struct Block {
    rows: Vec<usize>,
    whole_file: bool,
    name: String,
}

/// One rewrite undone: the quantity, the block, the fitted parameters and the directions of
/// parameter space the block measures ([`linear_fit`]; a shift's along a sweep's own axis not).
#[derive(Clone)]
struct Slip {
    quantity: Quantity,
    block: Arc<Block>,
    p: [f64; 3],
    measured: Vec<[f64; 3]>,
}

impl Slip {
    /// The row `i` (`m`) with this slip undone.
    fn undo(&self, i: usize, m: &mut Measurement) {
        if self.block.rows.binary_search(&i).is_ok() {
            self.quantity.apply(m, &self.p);
        }
    }
}

/// `rows` with every slip of `slips` undone (by row index).
fn undone(rows: &[Measurement], slips: &[Slip]) -> Vec<Measurement> {
    rows.iter()
        .enumerate()
        .map(|(i, m)| {
            let mut m = m.clone();
            slips.iter().for_each(|s| s.undo(i, &mut m));
            m
        })
        .collect()
}

/// The position summaries of `v`.
fn summaries(v: &Validation) -> impl Iterator<Item = &PositionSummary> {
    [&v.validation, &v.tool, &v.axis].into_iter().flatten()
}

/// The sum of `v`'s position statistics (infinite without one).
fn total_statistic(v: &Validation) -> f64 {
    let total: f64 = summaries(v)
        .filter_map(|s| s.chi_square.as_ref().map(|c| c.value))
        .sum();
    if total.is_finite() { total } else { f64::INFINITY }
}

/// The blocks of `set` (module docs).
fn blocks(set: &MeasurementSet) -> Vec<Arc<Block>> {
    let rows = set.rows();
    let line = |i: usize| set.line_of(i).map_or(String::new(), |l| l.to_string());
    let mut out = vec![Arc::new(Block {
        rows: (0..rows.len()).collect(),
        whole_file: true,
        name: "every row of the file".into(),
    })];
    let mut experiments: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
    rows.iter()
        .enumerate()
        .for_each(|(i, m)| experiments.entry(m.experiment.as_str()).or_default().push(i));
    for (name, indices) in experiments.iter().filter(|(_, ix)| ix.len() < rows.len()) {
        if rows[indices[0]].moved_joint > 0 {
            let lines = format!("lines {}-{}", line(indices[0]), line(*indices.last().unwrap_or(&0)));
            out.push(Arc::new(Block {
                rows: indices.clone(),
                whole_file: false,
                name: format!("experiment {name}'s {} points ({lines})", indices.len()),
            }));
        }
    }
    for (name, indices) in experiments.iter().filter(|(_, ix)| rows[ix[0]].moved_joint == 0) {
        out.extend(pose_runs(set, name, indices).into_iter().map(Arc::new));
    }
    out
}

/// The most row indices the free poses' runs of one experiment hold together ([`pose_runs`]):
/// every run of `P` poses of `r` rows each holds about `r P^3 / 6`, 20 million (160 MB) at
/// about 340 poses of three targets.
const MAX_RUN_ROWS: usize = 20_000_000;

/// Every run of at least [`MIN_BLOCK_POSES`] consecutive poses (in file order) of the
/// free-pose experiment `name` with rows `indices`, but the whole experiment when it is the file.
/// Where every run would hold more than [`MAX_RUN_ROWS`] rows, the runs start and end on
/// evenly spaced poses instead ([`run_boundaries`]): memory and time stay bounded, and a slip
/// that starts between two of them is not undone by any block (the miss stays the model's).
fn pose_runs(set: &MeasurementSet, name: &str, indices: &[usize]) -> Vec<Block> {
    let rows = set.rows();
    let mut poses: Vec<Vec<usize>> = Vec::new();
    let mut step_of: BTreeMap<usize, usize> = BTreeMap::new();
    for &i in indices {
        let at = *step_of.entry(rows[i].step).or_insert_with(|| {
            poses.push(Vec::new());
            poses.len() - 1
        });
        poses[at].push(i);
    }
    let line = |i: usize| set.line_of(i).map_or(String::new(), |l| l.to_string());
    let bounds = run_boundaries(poses.len(), indices.len());
    let mut out = Vec::new();
    for (x, &a) in bounds.iter().enumerate() {
        for &b in bounds[x + 1..].iter().filter(|&&b| b >= a + MIN_BLOCK_POSES) {
            if b - a == poses.len() && indices.len() == rows.len() {
                continue;
            }
            let mut block: Vec<usize> = poses[a..b].iter().flatten().copied().collect();
            block.sort_unstable();
            let (first, last) = (block[0], *block.last().unwrap_or(&0));
            out.push(Block {
                name: format!(
                    "experiment {name}'s {} poses of steps {}-{} (lines {}-{})",
                    b - a,
                    rows[poses[a][0]].step,
                    rows[poses[b - 1][0]].step,
                    line(first),
                    line(last)
                ),
                rows: block,
                whole_file: false,
            });
        }
    }
    out
}

/// The poses where [`pose_runs`] start and end runs, of `poses` poses holding `rows` rows:
/// every one from 0 to `poses`, or, where the runs would hold more than [`MAX_RUN_ROWS`] rows,
/// the `g + 1` evenly spaced ones (`g` segments) whose runs hold at most that many. The runs
/// between `g + 1` boundaries of `rows / g` rows a segment hold
/// `rows / g * sum_d d (g + 1 - d) = rows (g + 1) (g + 2) / 6` rows, and each of the
/// `g (g + 1) / 2` runs at most one pose more where the segments are rounded to whole poses.
fn run_boundaries(poses: usize, rows: usize) -> Vec<usize> {
    let (r, per_pose) = (rows as f64, rows as f64 / poses.max(1) as f64);
    let held = |g: usize| {
        let g = g as f64;
        r * (g + 1.0) * (g + 2.0) / 6.0 + per_pose * g * (g + 1.0) / 2.0
    };
    if r * (poses as f64 + 1.0) * (poses as f64 + 2.0) / 6.0 <= MAX_RUN_ROWS as f64 {
        return (0..=poses).collect();
    }
    let mut g = ((6.0 * MAX_RUN_ROWS as f64 / rows.max(1) as f64).sqrt() as usize).min(poses);
    while g > 1 && held(g) > MAX_RUN_ROWS as f64 {
        g -= 1;
    }
    let mut bounds: Vec<usize> = (0..=g.max(1)).map(|j| j * poses / g.max(1)).collect();
    bounds.dedup();
    bounds
}

/// The residuals of the rows, their weights and every quantity's whole-file directions:
/// what the screening of the pairs needs.
struct Screen {
    residuals: Vec<f64>,
    weights: Vec<f64>,
    directions: Vec<(Quantity, Vec<Vec<f64>>)>,
}

/// The rows' residual coordinates \[mm\] (`rows` with `slips` undone), each row weighted with
/// `3 / predicted^2` of its kind's test in `v`, and the whole-file directions of every
/// quantity (central differences); `None` when the rows cannot be predicted.
fn screen(rows: &[Measurement], (cal, desc): (&Calibration, &RobotDescription), v: &Validation) -> Option<Screen> {
    let residuals = residuals_with(rows, &|_: &mut Measurement| {}, cal, desc)?;
    let predicted = |kind: PointKind| {
        let s = match kind {
            PointKind::Validation => &v.validation,
            PointKind::Tool => &v.tool,
            PointKind::Axis => &v.axis,
        };
        s.as_ref().map_or(v.noise_rms_3d_mm, |s| s.predicted_mm.total)
    };
    let weights = v.residuals.iter().map(|r| 3.0 / predicted(r.kind).powi(2)).collect();
    let mut quantities = vec![Quantity::Shift, Quantity::CoordinateScale];
    for k in 0..desc.dof() {
        quantities.extend([Quantity::CommandScale(k), Quantity::CommandOffset(k)]);
    }
    let mut directions = Vec::new();
    for q in quantities {
        let mut of_q = Vec::new();
        for (e, h) in q.directions() {
            let at = |t: f64| {
                let p = e.map(|x| x * t);
                residuals_with(rows, &move |m: &mut Measurement| q.apply(m, &p), cal, desc).map(DVector::from_vec)
            };
            let derivative: DVector<f64> = try_central_difference(at, h)?;
            of_q.push(derivative.data.into());
        }
        directions.push((q, of_q));
    }
    Some(Screen {
        residuals,
        weights,
        directions,
    })
}

/// A pair screened: the quantity, the block, its linear parameters, the drop of the weighted
/// sum of squares they give and the directions the block measures.
struct Candidate {
    quantity: Quantity,
    block: Arc<Block>,
    p: [f64; 3],
    drop: f64,
    measured: Vec<[f64; 3]>,
}

/// The linear least-squares parameters of a quantity (its directions `d`) over `block`, the
/// rows' residuals `residuals` weighted with `weights`, the drop of the weighted sum of squares
/// and the directions of parameter space fitted: the eigenvectors of the directions' weighted
/// normal matrix over the block whose eigenvalue is above [`measured_floor`] (a shift along a
/// sweep's own axis moves no residual: the estimated target places absorb it, and a fitted
/// value there would be rounding, hundreds of millimetres).
fn linear_fit(residuals: &[f64], weights: &[f64], d: &[Vec<f64>], block: &Block) -> ([f64; 3], f64, Vec<[f64; 3]>) {
    let k = d.len();
    let (mut normal, mut right): (DMatrix<f64>, DVector<f64>) = (DMatrix::zeros(k, k), DVector::zeros(k));
    for &i in &block.rows {
        for c in 0..3 {
            let (w, r) = (weights[i], residuals[3 * i + c]);
            for a in 0..k {
                right[a] += w * d[a][3 * i + c] * r;
                for b in 0..k {
                    normal[(a, b)] += w * d[a][3 * i + c] * d[b][3 * i + c];
                }
            }
        }
    }
    let (mut p, mut drop, mut measured) = ([0.0; 3], 0.0, Vec::new());
    if !normal.iter().chain(right.iter()).all(|x| x.is_finite()) {
        return (p, drop, measured);
    }
    let floor = measured_floor(k, &normal, block, weights);
    let eigen = normal.symmetric_eigen();
    for (j, &lambda) in eigen.eigenvalues.iter().enumerate().filter(|(_, l)| **l > floor) {
        let v = eigen.eigenvectors.column(j);
        let g = v.dot(&right);
        let mut e = [0.0; 3];
        for a in 0..k {
            e[a] = v[a];
            p[a] -= v[a] * g / lambda;
        }
        drop += g * g / lambda;
        measured.push(e);
    }
    (p, drop, measured)
}

/// The least eigenvalue of a rewrite's weighted normal matrix `normal` (`k` directions) over
/// `block` that is fitted ([`linear_fit`]): for a shift (3 directions, in mm), the largest
/// weight of a row of the block, so that a direction is fitted when the block's points fix it
/// at least as well as one point fixes its own coordinate; for a one-parameter rewrite (its
/// unit the quantity's), [`RELATIVE_RANK_TOLERANCE`] of its diagonal.
fn measured_floor(k: usize, normal: &DMatrix<f64>, block: &Block, weights: &[f64]) -> f64 {
    if k == 3 {
        block.rows.iter().map(|&i| weights[i]).fold(0.0, f64::max)
    } else {
        RELATIVE_RANK_TOLERANCE * normal.diagonal().max()
    }
}

impl Screen {
    /// Every pair's screening, largest drop first, and the count of pairs screened.
    fn candidates(&self, blocks: &[Arc<Block>]) -> (Vec<Candidate>, usize) {
        let mut out = Vec::new();
        for block in blocks {
            for (quantity, d) in &self.directions {
                let (p, drop, measured) = linear_fit(&self.residuals, &self.weights, d, block);
                out.push(Candidate {
                    quantity: *quantity,
                    block: block.clone(),
                    p,
                    drop,
                    measured,
                });
            }
        }
        let screened = out.len();
        out.retain(|c| c.drop.is_finite() && c.drop > 0.0);
        out.sort_by(|a, b| b.drop.total_cmp(&a.drop));
        (out, screened)
    }
}

/// A one-parameter rewrite whose weighted square norm over its block is below this fraction of
/// its diagonal, and a direction of the slips' refit below this fraction of the normal
/// matrix's norm, is not fitted: rounding, not a measured parameter.
const RELATIVE_RANK_TOLERANCE: f64 = 1e-9;

/// Gauss-Newton steps of the slips' parameters, all together, from their linear starts: the
/// rewrites are linear in the coordinates, smooth in the commands.
const REFINE_STEPS: usize = 3;

/// Whether `slip`'s parameters are a slip a file carries: a command offset within
/// [`MAX_FITTED_OFFSET`], a command scale within 5 times either way (a larger one is a unit
/// the finite slips name), a coordinate scale within 10 % (a larger one is a unit).
fn plausible(slip: &Slip) -> bool {
    let p = slip.p[0];
    slip.p.iter().all(|x| x.is_finite())
        && match slip.quantity {
            Quantity::Shift => true,
            Quantity::CoordinateScale => p.abs() <= 0.1,
            Quantity::CommandScale(_) => (0.2..=5.0).contains(&(1.0 + p)),
            Quantity::CommandOffset(_) => p.abs() <= MAX_FITTED_OFFSET,
        }
}

/// The parameters of every slip of `slips` refitted together on `rows` (Gauss-Newton, the
/// residuals weighted with `weights`, central differences of each slip's rewrite over its
/// block); `None` when the rows cannot be predicted or a slip leaves [`plausible`].
fn refitted(
    rows: &[Measurement],
    mut slips: Vec<Slip>,
    weights: &[f64],
    (cal, desc): (&Calibration, &RobotDescription),
) -> Option<Vec<Slip>> {
    // Each slip along the directions its block measures ([`linear_fit`]), with its step.
    let parameters: Vec<(usize, [f64; 3], f64)> = slips
        .iter()
        .enumerate()
        .flat_map(|(s, slip)| {
            let h = slip.quantity.directions()[0].1;
            slip.measured.iter().map(move |&e| (s, e, h))
        })
        .collect();
    let w = DVector::from_iterator(3 * rows.len(), weights.iter().flat_map(|w| [*w; 3]));
    let residuals = |slips: &[Slip]| residuals_with(&undone(rows, slips), &|_: &mut Measurement| {}, cal, desc);
    for _ in 0..REFINE_STEPS {
        let r = DVector::from_vec(residuals(&slips)?);
        let mut jacobian = DMatrix::zeros(r.len(), parameters.len());
        for (col, &(s, e, h)) in parameters.iter().enumerate() {
            let at = |t: f64| {
                let mut moved = slips.clone();
                (0..3).for_each(|a| moved[s].p[a] += t * e[a]);
                residuals(&moved).map(DVector::from_vec)
            };
            jacobian.set_column(col, &try_central_difference(at, h)?);
        }
        // The rows scaled by their weights: a dense diagonal of the 3N rows was 3N x 3N.
        let mut weighted = jacobian.clone();
        weighted.row_iter_mut().zip(w.iter()).for_each(|(mut row, w)| row *= *w);
        let normal = jacobian.transpose() * &weighted;
        let tolerance = RELATIVE_RANK_TOLERANCE * normal.norm();
        let step = normal.pseudo_inverse(tolerance).ok()? * (weighted.transpose() * -r);
        for (col, &(s, e, _)) in parameters.iter().enumerate() {
            (0..3).for_each(|a| slips[s].p[a] += step[col] * e[a]);
        }
        if !slips.iter().all(plausible) {
            return None;
        }
    }
    Some(slips)
}

/// A slip kept: the rewrite, the drop of the validation's statistic it gives and the bound
/// that drop had to pass.
#[derive(Clone)]
struct Kept {
    slip: Slip,
    drop: f64,
    bound: f64,
}

/// The validation of `rows` (`None` when they are no set or cannot be predicted).
fn validation_of(
    rows: Vec<Measurement>,
    (cal, desc): (&Calibration, &RobotDescription),
    options: &ValidationOptions,
) -> Option<Validation> {
    let set = MeasurementSet::new(desc.dof(), rows).ok()?;
    validate(&set, cal, desc, options).ok()
}

/// The next slips of the search (module docs) on `rows` with `kept` undone, whose
/// validation's statistic is `base`: every tested pair with a significant drop, largest drop
/// first, each with the slips refitted and the validation of the rows with them undone.
fn next_slips(
    rows: &[Measurement],
    kept: &[Kept],
    blocks: &[Arc<Block>],
    model: (&Calibration, &RobotDescription),
    (v, options, base): (&Validation, &ValidationOptions, f64),
) -> Option<Vec<(Vec<Slip>, Kept, Validation)>> {
    let slips: Vec<Slip> = kept.iter().map(|k| k.slip.clone()).collect();
    let current = undone(rows, &slips);
    let screen = screen(&current, model, v)?;
    let (candidates, screened) = screen.candidates(blocks);
    let mut best_of: Vec<Candidate> = Vec::new();
    for c in candidates {
        if !best_of.iter().any(|b| b.quantity == c.quantity) {
            best_of.push(c);
        }
    }
    let rate = options.false_alarm / screened.max(1) as f64;
    let found = best_of
        .iter()
        .take(TESTED_CANDIDATES)
        .filter_map(|c| {
            let mut all = slips.clone();
            all.push(Slip {
                quantity: c.quantity,
                block: c.block.clone(),
                p: c.p,
                measured: c.measured.clone(),
            });
            let all = refitted(rows, all, &screen.weights, model)?;
            let slip = all.last()?.clone();
            let zero_error = matches!(slip.quantity, Quantity::CommandOffset(_)) && slip.block.whole_file;
            if zero_error && slip.p[0].abs() < MIN_FITTED_OFFSET {
                return None;
            }
            let after = validation_of(undone(rows, &all), model, options)?;
            let drop = base - total_statistic(&after);
            let bound = chi_square_quantile(1.0 - rate, slip.measured.len() as f64);
            (drop > bound).then_some((all, Kept { slip, drop, bound }, after))
        })
        .collect::<Vec<_>>();
    let mut found = found;
    found.sort_by(|a, b| b.1.drop.total_cmp(&a.1.drop));
    Some(found)
}

/// The slips (at most 2, `MAX_SLIPS`) whose undoing makes `set` pass every test of the
/// validation `v` of `set` against `cal` (module docs), as one miss naming their columns and
/// rows; `None` when no position test exceeds, no such slips are found or `set` has more rows
/// than the search runs on ([`combined_slips_searched`]). `desc` is the description `v` was made with.
pub fn explained_combined_slips(
    set: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
    v: &Validation,
) -> Option<ExplainedMiss> {
    if !v.exceeds(true) || !combined_slips_searched(set) {
        return None;
    }
    let options = ValidationOptions::of_validation(v);
    let blocks = blocks(set);
    let search = Search {
        rows: set.rows(),
        blocks: &blocks,
        model: (cal, desc),
        v,
        options: &options,
    };
    let (kept, after) = search.from(&[], total_statistic(v))?;
    let beyond = beyond_prediction(set.rows(), &kept, (cal, desc), v, options.false_alarm)?;
    beyond.then(|| explained(set, desc, v, (&kept, &after)))
}

/// Whether one slip of `kept` moves its block's points beyond what the calibration's own
/// predicted error and the noise move them by: the RMS of its displacement over the block's
/// points (the residuals with every slip undone against those with it left in) above `k`
/// times the RMS of the rows' predicted error (each row's kind's total in `v`: noise,
/// repeatability and the calibration's predicted error), `k^2 = chi2_3(1 - false_alarm) / 3`
/// (a 3-D Gaussian error of that RMS lies beyond `k` times it at the false-alarm rate). A
/// shared error of the calibration below that (a tool frame kept nominal, a poorly measured
/// axis) moves a block of poses as a slip does and is no slip of the data (hostile run 13 A2:
/// a clean SCARA file refused as `cmd_3` offset by 1.5 mm where 1.9 mm was predicted).
/// `None` when the rows cannot be predicted.
fn beyond_prediction(
    rows: &[Measurement],
    kept: &[Kept],
    model: (&Calibration, &RobotDescription),
    v: &Validation,
    false_alarm: f64,
) -> Option<bool> {
    let predicted2 = |kind: PointKind| {
        let s = match kind {
            PointKind::Validation => &v.validation,
            PointKind::Tool => &v.tool,
            PointKind::Axis => &v.axis,
        };
        s.as_ref().map_or(v.noise_rms_3d_mm, |s| s.predicted_mm.total).powi(2)
    };
    let k2 = chi_square_quantile(1.0 - false_alarm, 3.0) / 3.0;
    let slips: Vec<Slip> = kept.iter().map(|k| k.slip.clone()).collect();
    let none = |_: &mut Measurement| {};
    let all = residuals_with(&undone(rows, &slips), &none, model.0, model.1)?;
    for (s, slip) in slips.iter().enumerate() {
        let others: Vec<Slip> = slips
            .iter()
            .enumerate()
            .filter(|(o, _)| *o != s)
            .map(|(_, x)| x.clone())
            .collect();
        let without = residuals_with(&undone(rows, &others), &none, model.0, model.1)?;
        let (mut moved2, mut predicted) = (0.0, 0.0);
        for &i in &slip.block.rows {
            moved2 += (0..3)
                .map(|c| (all[3 * i + c] - without[3 * i + c]).powi(2))
                .sum::<f64>();
            predicted += predicted2(v.residuals.get(i)?.kind);
        }
        if moved2 > k2 * predicted {
            return Some(true);
        }
    }
    Some(false)
}

/// What the search of the slips (module docs) runs on: the rows, their blocks, the model and
/// the validation `v` of the rows as read, with its options.
struct Search<'a> {
    rows: &'a [Measurement],
    blocks: &'a [Arc<Block>],
    model: (&'a Calibration, &'a RobotDescription),
    v: &'a Validation,
    options: &'a ValidationOptions,
}

impl Search<'_> {
    /// The slips, `kept` first, whose undoing makes the rows pass every test, with the
    /// validation of the rows with them undone; `None` when no such slips are found. Greedy,
    /// largest significant drop first; when the largest leaves no second slip that passes,
    /// the next significant ones are tried in turn (two slips at once: the largest drop can
    /// be a rewrite that absorbs part of both, which no second slip then completes).
    fn from(&self, kept: &[Kept], base: f64) -> Option<(Vec<Kept>, Validation)> {
        let next = next_slips(self.rows, kept, self.blocks, self.model, (self.v, self.options, base))?;
        for (refit, slip, after) in next {
            let mut all: Vec<Kept> = kept.to_vec();
            all.iter_mut().zip(refit).for_each(|(k, s)| k.slip = s);
            all.push(slip);
            if !after.exceeds(false) {
                return Some((all, after));
            }
            if all.len() < MAX_SLIPS
                && let Some(found) = self.from(&all, total_statistic(&after))
            {
                return Some(found);
            }
        }
        None
    }
}

/// The misses of `v` (the validation of `set` against `cal`, `desc` the description it was
/// made with) that a slip of the data explains, as `validate` names them: the free poses'
/// slips ([`explained_misses`]) and the sweeps' ([`explained_sweep_misses`]); without
/// either, one coordinate column scaled over the file ([`explained_file_scale`]); without
/// that, up to two slips at once ([`explained_combined_slips`]). Empty when none does.
pub fn explained_validation_misses(
    set: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
    v: &Validation,
) -> Vec<ExplainedMiss> {
    let mut misses = explained_misses(set, cal, desc, v);
    misses.extend(explained_sweep_misses(set, cal, desc, v));
    if misses.is_empty() {
        misses.extend(explained_file_scale(set, cal, desc, v));
    }
    if misses.is_empty() {
        misses.extend(explained_combined_slips(set, cal, desc, v));
    }
    misses
}

/// The miss `v` of `set` and the slips `kept` that explain it, `after` the validation with
/// them undone, in words.
fn explained(
    set: &MeasurementSet,
    desc: &RobotDescription,
    v: &Validation,
    (kept, after): (&[Kept], &Validation),
) -> ExplainedMiss {
    let labelled = [
        ("validation poses'", &v.validation),
        ("tool observation's", &v.tool),
        ("axis experiments'", &v.axis),
    ];
    let gross = labelled
        .into_iter()
        .filter_map(|(label, s)| Some((label, s.as_ref()?)))
        .filter(|(_, s)| s.chi_square.as_ref().is_some_and(|c| c.verdict == Verdict::Exceeds))
        .max_by(|a, b| a.1.rms_mm.total_cmp(&b.1.rms_mm));
    let miss = gross.map_or(String::new(), |(label, g)| {
        format!(
            " (the {label} {} by {:.4} mm RMS where {:.4} mm is predicted)",
            match g.points {
                1 => "1 point".to_string(),
                n => format!("{n} points"),
            },
            g.rms_mm,
            g.predicted_mm.total
        )
    });
    let passes: Vec<String> = summaries(after)
        .map(|u| format!("{:.4} mm RMS where {:.4} mm", u.rms_mm, u.predicted_mm.total))
        .collect();
    let claims: Vec<String> = kept
        .iter()
        .map(|k| {
            format!(
                "{} (chi-square down {:.0}, chance at most {:.1})",
                claim(&k.slip, desc),
                k.drop,
                k.bound
            )
        })
        .collect();
    let first = &kept[0].slip.block;
    let mut fields: Vec<String> = kept.iter().map(|k| field(k.slip.quantity)).collect();
    fields.dedup();
    let slips = if kept.len() == 1 {
        "one slip".to_string()
    } else {
        format!("{} slips", kept.len())
    };
    ExplainedMiss {
        experiment: set.rows()[first.rows[0]].experiment.clone(),
        line: set.line_of(first.rows[0]),
        field: fields.join("; "),
        message: format!(
            "the calibrated model misses these data{miss}, and every test passes with {slips} undone ({} predicted): {}: \
             correct these rows (or measure them again)",
            passes.join(", "),
            claims.join("; and ")
        ),
    }
}

/// The columns a rewrite of `q` names.
fn field(q: Quantity) -> String {
    match q {
        Quantity::Shift | Quantity::CoordinateScale => "x_mm,y_mm,z_mm".into(),
        Quantity::CommandScale(k) | Quantity::CommandOffset(k) => format!("cmd_{}", k + 1),
    }
}

/// What the data are under `slip`, in words.
fn claim(slip: &Slip, desc: &RobotDescription) -> String {
    let b = &slip.block.name;
    let p = slip.p;
    let shown = |v: f64, scale: f64| format_f64((v * scale).round() / scale + 0.0);
    match slip.quantity {
        Quantity::Shift => format!(
            "the coordinates of {b} sit shifted by ({}, {}, {}) mm{}, the same for all: the instrument (or robot) \
             bumped or set up again, or a constant added to the columns",
            shown(-p[0], 1e2),
            shown(-p[1], 1e2),
            shown(-p[2], 1e2),
            unmeasured(&slip.measured)
        ),
        Quantity::CoordinateScale => format!(
            "the coordinates of {b} read {:.5} times what the calibration gives, about the instrument's origin: the \
             instrument's scale (a laser tracker's wavelength or air compensation, a scale bar) or the export's \
             scaling",
            1.0 / (1.0 + p[0])
        ),
        Quantity::CommandScale(k) => format!(
            "`cmd_{}` of {b} holds {:.4} times the values the calibration's transmission gives: the column scaled \
             (another unit, a gear ratio applied twice), or the joint's transmission changed since the calibration",
            k + 1,
            1.0 / (1.0 + p[0])
        ),
        Quantity::CommandOffset(k) => format!(
            "`cmd_{}` of {b} is offset by {} {} from the calibration: the joint's zero moved (re-mastered part-way?) \
             or the column was shifted",
            k + 1,
            shown(-p[0], 1e3),
            desc.joints[k].kind.file_unit()
        ),
    }
}

/// The words for a shift's directions its block does not measure (`measured` the ones it does,
/// [`linear_fit`]): none when it measures all three.
fn unmeasured(measured: &[[f64; 3]]) -> String {
    let shown = |v: Vector3<f64>| {
        let v = if v[v.iamax()] >= 0.0 { v } else { -v };
        let r = |c: f64| (c * 100.0).round() / 100.0 + 0.0;
        format!("({:.2}, {:.2}, {:.2})", r(v.x), r(v.y), r(v.z))
    };
    let why = "is not determined by these points: it moves the targets' places on their link";
    match measured {
        [a, b] => format!(
            " across the direction {} (a shift along it {why}, as a shift along a sweep's own turning axis does)",
            shown(Vector3::from(*a).cross(&Vector3::from(*b)).normalize())
        ),
        [a] => format!(
            " along the direction {} (a shift across it {why}, as a shift of a sliding joint's line does)",
            shown(Vector3::from(*a))
        ),
        _ => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The row indices the runs between `bounds` hold, poses of `per_pose` rows, counted one
    /// run at a time (a second path to [`run_boundaries`]' closed form), up to the first start
    /// whose runs take the count beyond [`MAX_RUN_ROWS`]: beyond it is all the test asks of such
    /// a count (every pose of 333,334 as a boundary is 10^10 pairs, minutes in a debug build).
    fn held(bounds: &[usize], per_pose: usize) -> usize {
        let mut total = 0;
        for (x, &a) in bounds.iter().enumerate() {
            total += bounds[x + 1..].iter().map(|&b| (b - a) * per_pose).sum::<usize>();
            if total > MAX_RUN_ROWS {
                break;
            }
        }
        total
    }

    /// Every pose is a boundary while the runs fit, and otherwise the evenly spaced ones hold
    /// at most [`MAX_RUN_ROWS`] rows, from the first pose to the last, increasing.
    #[test]
    fn the_runs_hold_at_most_the_bound() {
        for per_pose in [1, 3, 4] {
            for poses in [3, 10, 60, 300, 340, 400, 2000, 333_334] {
                let bounds = run_boundaries(poses, poses * per_pose);
                assert_eq!((bounds[0], *bounds.last().unwrap()), (0, poses));
                assert!(bounds.windows(2).all(|w| w[0] < w[1]));
                let all = (0..=poses).collect::<Vec<_>>();
                if bounds != all {
                    assert!(held(&all, per_pose) > MAX_RUN_ROWS, "{poses} x {per_pose}");
                }
                assert!(held(&bounds, per_pose) <= MAX_RUN_ROWS, "{poses} x {per_pose}");
            }
        }
    }
}
