//! Free-pose misses a slip in the data explains (`validate`, `report --held-out`, `diagnose`):
//! when the calibrated model misses a free-pose experiment's points (validation poses, the
//! tool observation) by more than [`GROSS_MISS_FACTOR`] times its test's acceptance, the usual
//! slips of a measurement file are tried on that experiment's rows, one at a time: the column
//! slips the free-pose calibration tries ([`crate::measurement::column_slips`], one list: a
//! command column in radians (metres for a sliding joint) or gradians, negated, halved or
//! doubled; two command columns swapped; a coordinate column in metres, micrometres, inches or
//! centimetres ([`crate::measurement::unit_check::LENGTH_SLIPS`], the factors the sweeps' unit
//! checks know) or negated; two coordinate columns swapped); the tool target ids in another order. The one
//! that brings the rows within the test's acceptance ([`acceptance`]: the RMS the noise, the
//! robot's repeatability and the calibration's own error predict, times the chi-square
//! quantile of the validation's own test) with the least RMS is the slip said, with its column.
//! When none does, a constant offset of one command column is fitted (a zero that moved, or a
//! column shifted, [`MIN_FITTED_OFFSET`] to [`MAX_FITTED_OFFSET`]). A miss no slip explains
//! stays the model's.
//!
//! The search is finite and cheap: about 60 rewrites of the experiment's rows, each predicted
//! once, and one offset fit. It runs only on experiments the model misses grossly, so valid data
//! never pay it.

use super::DiagnosisError;
use super::noise::CleanCampaign;
use super::validate::{PointKind, PositionSummary, Validation, ValidationOptions, Verdict, validate};
use crate::calibration::procedure::Calibration;
use crate::kinematics::JointKind;
use crate::measurement::column_slips;
pub(super) use crate::measurement::column_slips::{ColumnSlip as Hypothesis, slip as hypothesis};
use crate::measurement::{Measurement, MeasurementSet, format_f64};
use crate::numerics::finite_diff::try_central_difference;
use crate::numerics::roots::{Bisection, bisect_infallible};
use crate::numerics::stats::chi_square_quantile;
use crate::plan::TOOL_EXPERIMENT;
use crate::robot::RobotDescription;
use nalgebra::DVector;
use std::collections::BTreeMap;

/// A fitted command offset beyond this \[deg or mm\] is not said: half a turn is no zero
/// shift a robot keeps, and the fit's start (no offset) is too far from it to trust.
pub const MAX_FITTED_OFFSET: f64 = 180.0;

/// A fitted command offset below this \[deg or mm\] is not said either: a smaller shift is a
/// zero error of the joint (what a calibration fits, or an effect the diagnosis looks for),
/// not a column shifted by hand; a degree moves a target 1 m from its axis by 17 mm, far beyond
/// any calibration's predicted error.
pub const MIN_FITTED_OFFSET: f64 = 1.0;

pub use crate::measurement::column_slips::GROSS_MISS_FACTOR;

/// Experiments with fewer poses than this are not searched: one or two poses (the tool
/// observation) give too few points for about 60 rewrites and a fitted offset not to explain
/// some of them by chance.
pub const MIN_SEARCHED_POSES: usize = 3;

/// The offset the least squares find is refined within this \[deg or mm\] either way on the
/// validation's own statistic ([`refined_offset`]): the calibration's
/// error, shared by every pose, moves the least-squares offset by tenths of a degree from the
/// one its test accepts.
const OFFSET_REFINE_HALF_WIDTH: f64 = 1.0;

/// Gauss-Newton steps of a one-parameter fit (a command's offset or scale): the residuals are smooth in the offset (sines and
/// cosines of the joint angles), and a step below [`OFFSET_STEP_DONE`] ends the fit earlier.
const OFFSET_ITERATIONS: usize = 20;

/// An offset step below this \[deg or mm\] ends its fit: a thousandth of a degree moves a
/// point 3 m from its axis by 0.05 mm, below any instrument's noise.
const OFFSET_STEP_DONE: f64 = 1e-3;

/// The command columns' slips ([`column_slips::command_slips`]: the one list the free-pose
/// calibration tries too): in radians (a revolute joint) or metres (a sliding one), in
/// gradians, negated, twice or half the file's unit; every pair of columns swapped.
pub(super) fn command_hypotheses(desc: &RobotDescription) -> Vec<Hypothesis> {
    let kinds: Vec<JointKind> = desc.joints.iter().map(|j| j.kind).collect();
    column_slips::command_slips(&kinds)
}

/// Every other order of the tool targets' ids (`targets` of them, at most 3: 5 orders).
fn target_hypotheses(targets: usize) -> Vec<Hypothesis> {
    let orders: Vec<Vec<usize>> = match targets {
        2 => vec![vec![1, 0]],
        3 => vec![
            vec![1, 0, 2],
            vec![2, 1, 0],
            vec![0, 2, 1],
            vec![1, 2, 0],
            vec![2, 0, 1],
        ],
        _ => Vec::new(),
    };
    orders
        .into_iter()
        .map(|order| {
            let moved: Vec<String> = order
                .iter()
                .enumerate()
                .filter(|(a, b)| a != *b)
                .map(|(a, b)| format!("{a} is {b}"))
                .collect();
            let words = [
                format!("the target ids are mixed up ({})", moved.join(", ")),
                format!("with the target ids renumbered ({})", moved.join(", ")),
            ];
            hypothesis("target".into(), words, move |m| {
                if let Some(&t) = order.get(m.target) {
                    m.target = t;
                }
            })
        })
        .collect()
}

/// The RMS \[mm\] by which `cal` misses `rows` (each rewritten by `apply`), or `None` when
/// the rewritten rows cannot be predicted (a command beyond a coupling's range).
pub(super) fn rms_with(
    rows: &[Measurement],
    apply: &dyn Fn(&mut Measurement),
    cal: &Calibration,
    desc: &RobotDescription,
) -> Option<f64> {
    let residuals = residuals_with(rows, apply, cal, desc)?;
    Some((residuals.iter().map(|r| r * r).sum::<f64>() / rows.len() as f64).sqrt())
}

/// `rows` rewritten by `apply`, as a measurement set (`None` when the rewrite is not one).
pub(super) fn rewritten(
    rows: &[Measurement],
    apply: &dyn Fn(&mut Measurement),
    desc: &RobotDescription,
) -> Option<MeasurementSet> {
    let rows: Vec<Measurement> = rows
        .iter()
        .map(|m| {
            let mut m = m.clone();
            apply(&mut m);
            m
        })
        .collect();
    MeasurementSet::new(desc.dof(), rows).ok()
}

/// The residual coordinates \[mm\] of `rows` rewritten by `apply` against `cal`'s prediction.
pub(super) fn residuals_with(
    rows: &[Measurement],
    apply: &dyn Fn(&mut Measurement),
    cal: &Calibration,
    desc: &RobotDescription,
) -> Option<Vec<f64>> {
    let set = rewritten(rows, apply, desc)?;
    let predicted = CleanCampaign::new(&set, cal, desc, &desc.tool_targets_m())
        .ok()?
        .positions();
    let out: Vec<f64> = set
        .rows()
        .iter()
        .zip(&predicted)
        .flat_map(|(m, p)| (0..3).map(move |c| m.position_mm[c] - p[c] * 1e3))
        .collect();
    out.iter().all(|v| v.is_finite()).then_some(out)
}

/// One Gauss-Newton step of the parameter `d` of a rewrite whose residual coordinates \[mm\]
/// `at(d)` gives, central differences of `h`, and the squared norm of the residuals' derivative
/// (`J^T J`); `None` when the rows cannot be predicted or do not move with the parameter.
fn parameter_step(at: &dyn Fn(f64) -> Option<Vec<f64>>, d: f64, h: f64) -> Option<(f64, f64)> {
    let r = at(d)?;
    let jacobian: DVector<f64> = try_central_difference(|t| at(d + t).map(DVector::from_vec), h)?;
    let jj: f64 = jacobian.iter().map(|j| j * j).sum();
    (jj > 0.0).then(|| (-jacobian.iter().zip(&r).map(|(j, r)| j * r).sum::<f64>() / jj, jj))
}

/// One parameter of a rewrite fitted by Gauss-Newton from `start` ([`parameter_step`],
/// differences of `h`, done at a step below `done`): the value and its `J^T J` \[mm^2 per unit^2\]
/// (the parameter's variance is a coordinate's over it); `None` when the fit leaves `within`
/// or the rows cannot be predicted.
pub(super) fn fitted_parameter(
    at: &dyn Fn(f64) -> Option<Vec<f64>>,
    start: f64,
    [h, done]: [f64; 2],
    within: &dyn Fn(f64) -> bool,
) -> Option<(f64, f64)> {
    let mut d = start;
    for _ in 0..OFFSET_ITERATIONS {
        let (step, jj) = parameter_step(at, d, h)?;
        d += step;
        if !(d.is_finite() && within(d)) {
            return None;
        }
        if step.abs() < done {
            return Some((d, jj));
        }
    }
    Some((d, parameter_step(at, d, h)?.1))
}

/// The offset of command column `k` (0-based) that brings `rows` nearest `cal`'s prediction,
/// fitted by Gauss-Newton from no offset ([`fitted_parameter`], differences of 1e-3 deg or mm);
/// `None` when the fit leaves [`MAX_FITTED_OFFSET`] or the rows cannot be predicted.
fn fitted_offset(rows: &[Measurement], k: usize, cal: &Calibration, desc: &RobotDescription) -> Option<f64> {
    let at = |d: f64| residuals_with(rows, &move |m: &mut Measurement| m.cmd[k] += d, cal, desc);
    let within = |d: f64| d.abs() <= MAX_FITTED_OFFSET;
    fitted_parameter(&at, 0.0, [1e-3, OFFSET_STEP_DONE], &within).map(|(d, _)| d)
}

/// The largest RMS \[mm\] of `points` points that still passes a test with prediction
/// `predicted_mm`: `predicted * sqrt(q / (3 n))`, `q` the chi-square quantile at the upper
/// `false_alarm / 2` with `3 n` degrees of freedom (the validation's own two-sided test).
pub fn acceptance(predicted_mm: f64, points: usize, false_alarm: f64) -> f64 {
    let dof = 3.0 * points as f64;
    predicted_mm * (chi_square_quantile(1.0 - 0.5 * false_alarm, dof) / dof).sqrt()
}

/// The summary of `kind` in `v`, when its test says the model misses its points.
fn missed(v: &Validation, kind: PointKind) -> Option<&PositionSummary> {
    let s = match kind {
        PointKind::Validation => v.validation.as_ref(),
        PointKind::Tool => v.tool.as_ref(),
        PointKind::Axis => None,
    }?;
    s.chi_square
        .as_ref()
        .is_some_and(|c| c.verdict == Verdict::Exceeds)
        .then_some(s)
}

/// A free-pose experiment the calibrated model misses, and the slip of its rows that explains
/// the miss ([`explained_misses`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ExplainedMiss {
    /// The experiment (`validation`, `tool`).
    pub experiment: String,
    /// The file line of its first row, when known.
    pub line: Option<u64>,
    /// The column (or columns) the slip names: `cmd_2`, `x_mm,y_mm`, `target`.
    pub field: String,
    /// The miss, the RMS with the slip undone and what the column looks like.
    pub message: String,
}

/// The slips that explain `v`'s misses of `set`'s free-pose experiments (module docs), one per
/// experiment explained. `desc` is the description `v` was made with.
pub fn explained_misses(
    set: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
    v: &Validation,
) -> Vec<ExplainedMiss> {
    let mut experiments: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
    for (i, m) in set.rows().iter().enumerate().filter(|(_, m)| m.moved_joint == 0) {
        experiments.entry(m.experiment.as_str()).or_default().push(i);
    }
    let options = ValidationOptions::of_validation(v);
    let mut out = Vec::new();
    for (name, indices) in experiments {
        let kind = if name == TOOL_EXPERIMENT {
            PointKind::Tool
        } else {
            PointKind::Validation
        };
        let Some(summary) = missed(v, kind) else {
            continue;
        };
        let rows: Vec<Measurement> = indices.iter().map(|&i| set.rows()[i].clone()).collect();
        if rows
            .iter()
            .map(|m| m.step)
            .collect::<std::collections::BTreeSet<_>>()
            .len()
            < MIN_SEARCHED_POSES
        {
            continue;
        }
        let bound = acceptance(summary.predicted_mm.total, rows.len(), v.false_alarm);
        let rms = (indices.iter().map(|&i| v.residuals[i].error_mm.powi(2)).sum::<f64>() / rows.len() as f64).sqrt();
        if !(rms.is_finite() && rms > GROSS_MISS_FACTOR * bound) {
            continue;
        }
        if let Some(e) = best_explanation(&rows, (cal, desc), &options, bound) {
            out.push(ExplainedMiss {
                experiment: name.to_string(),
                line: set.line_of(indices[0]),
                field: e.hypothesis.field,
                message: format!(
                    "the calibrated model misses experiment {name}'s {} points by {:.4} mm RMS where {:.4} mm is \
                     predicted, and by {:.4} mm (chi2/dof {:.3}: within the prediction) {}: in these rows {}",
                    rows.len(),
                    rms,
                    summary.predicted_mm.total,
                    e.rms_mm,
                    e.per_dof,
                    e.hypothesis.reading,
                    e.hypothesis.claim
                ),
            });
        }
    }
    out
}

/// At most this many rewrites, those with the least RMS, are tested with the validation's own
/// test ([`confirmed`]): the ones behind them miss by more, and each test costs a validation of
/// the rows.
const TESTED_REWRITES: usize = 3;

/// A rewrite that explains the rows: the hypothesis, its RMS \[mm\], its test's chi-square
/// per degree of freedom and the statistic itself.
pub(super) struct Explanation {
    pub(super) hypothesis: Hypothesis,
    pub(super) rms_mm: f64,
    pub(super) per_dof: f64,
    pub(super) statistic: f64,
}

/// The rows the model no longer misses grossly under each of `hypotheses` (their RMS at most
/// [`GROSS_MISS_FACTOR`] times `bound_mm`), least RMS first, the first of them the
/// validation's own test accepts ([`confirmed`]) with its RMS and statistic.
pub(super) fn first_confirmed(
    hypotheses: Vec<Hypothesis>,
    rows: &[Measurement],
    (cal, desc): (&Calibration, &RobotDescription),
    options: &ValidationOptions,
    bound_mm: f64,
) -> Option<Explanation> {
    let mut near: Vec<(Hypothesis, f64)> = hypotheses
        .into_iter()
        .filter_map(|h| {
            let rms = rms_with(rows, &h.undo, cal, desc)?;
            (rms <= GROSS_MISS_FACTOR * bound_mm).then_some((h, rms))
        })
        .collect();
    near.sort_by(|a, b| a.1.total_cmp(&b.1));
    near.into_iter().take(TESTED_REWRITES).find_map(|(hypothesis, rms_mm)| {
        let (per_dof, statistic) = confirmed(rows, &hypothesis.undo, cal, desc, options)?;
        Some(Explanation {
            hypothesis,
            rms_mm,
            per_dof,
            statistic,
        })
    })
}

/// The chi-square per degree of freedom and the statistic of `rows` rewritten by `apply` when
/// the validation's own test ([`validate`] with `options`) accepts them (not `exceeds`);
/// `None` when it does not or they cannot be predicted.
fn confirmed(
    rows: &[Measurement],
    apply: &dyn Fn(&mut Measurement),
    cal: &Calibration,
    desc: &RobotDescription,
    options: &ValidationOptions,
) -> Option<(f64, f64)> {
    let set = rewritten(rows, apply, desc)?;
    let v = validate(&set, cal, desc, options).ok()?;
    let test = v
        .validation
        .as_ref()
        .or(v.tool.as_ref())
        .or(v.axis.as_ref())?
        .chi_square
        .as_ref()?;
    (test.verdict != Verdict::Exceeds).then_some((test.per_dof, test.value))
}

/// The hypothesis (module docs) under which the validation's own test accepts `rows`, with the
/// least RMS, if any: the finite set first, then one command column's fitted offset.
fn best_explanation(
    rows: &[Measurement],
    (cal, desc): (&Calibration, &RobotDescription),
    options: &ValidationOptions,
    bound_mm: f64,
) -> Option<Explanation> {
    let targets = rows.iter().map(|m| m.target + 1).max().unwrap_or(0);
    let mut all = command_hypotheses(desc);
    all.extend(column_slips::coordinate_slips());
    all.extend(target_hypotheses(targets.min(desc.tool_targets_m().len())));
    first_confirmed(all, rows, (cal, desc), options, bound_mm)
        .or_else(|| {
            let offset = offset_hypothesis(rows, (cal, desc), options)?;
            first_confirmed(vec![offset], rows, (cal, desc), options, bound_mm)
        })
        .or_else(|| {
            let scales = (0..desc.dof()).filter_map(|k| super::sweep_slips::swept_scale(rows, k, (cal, desc), options));
            first_confirmed(scales.collect(), rows, (cal, desc), options, bound_mm)
        })
        .or_else(|| {
            let shift = translation_hypothesis(rows, (cal, desc), options, bound_mm)?;
            first_confirmed(vec![shift], rows, (cal, desc), options, bound_mm)
        })
}

/// The constant translation of every point of `rows` that brings them nearest `cal`'s
/// prediction, as a hypothesis: a constant added to a coordinate column, or the instrument
/// moved since the calibration. Its columns are those whose mean residual (the least-squares
/// shift) exceeds `bound_mm` (the rows' acceptance: a smaller part is within the test's reach),
/// each shifted alone by the value within `bound_mm` of that mean that minimises the
/// validation's own statistic ([`minimum_near`]: the calibration's error, shared by every
/// pose, moves the mean from the shift its test accepts); `None` when no column's is that large.
fn translation_hypothesis(
    rows: &[Measurement],
    (cal, desc): (&Calibration, &RobotDescription),
    options: &ValidationOptions,
    bound_mm: f64,
) -> Option<Hypothesis> {
    const NAMES: [&str; 3] = ["x_mm", "y_mm", "z_mm"];
    let residuals = residuals_with(rows, &|_: &mut Measurement| {}, cal, desc)?;
    let mut shift: [f64; 3] = [0, 1, 2].map(|c| residuals.iter().skip(c).step_by(3).sum::<f64>() / rows.len() as f64);
    let named: Vec<usize> = (0..3).filter(|&c| shift[c].abs() > bound_mm).collect();
    (0..3).filter(|c| !named.contains(c)).for_each(|c| shift[c] = 0.0);
    for &c in named.iter() {
        let at = |d: f64| {
            let mut trial = shift;
            trial[c] = d;
            statistic_with(
                rows,
                &move |m: &mut Measurement| (0..3).for_each(|i| m.position_mm[i] -= trial[i]),
                (cal, desc),
                options,
            )
        };
        shift[c] = minimum_near(&at, shift[c], bound_mm);
    }
    named.first()?;
    let shown = |v: f64| format_f64((v * 1e2).round() / 1e2);
    let columns: Vec<String> = named
        .iter()
        .map(|&c| {
            format!(
                "`{}` {}{} mm",
                NAMES[c],
                if shift[c] >= 0.0 { "+" } else { "" },
                shown(shift[c])
            )
        })
        .collect();
    let words = [
        format!(
            "every point sits {} from the calibrated model's prediction, the same for all: a constant added to the \
             column{}, or the instrument (or the robot) moved since the calibration",
            columns.join(", "),
            if named.len() > 1 { "s" } else { "" }
        ),
        format!("with {} taken off", columns.join(", ")),
    ];
    let field = named.iter().map(|&c| NAMES[c]).collect::<Vec<_>>().join(",");
    Some(hypothesis(field, words, move |m| {
        (0..3).for_each(|c| m.position_mm[c] -= shift[c])
    }))
}

/// The statistic of the validation's own test ([`validate`] with `options`) of `rows` rewritten
/// by `apply` (infinite when they cannot be predicted).
fn statistic_with(
    rows: &[Measurement],
    apply: &dyn Fn(&mut Measurement),
    (cal, desc): (&Calibration, &RobotDescription),
    options: &ValidationOptions,
) -> f64 {
    let value = rewritten(rows, apply, desc)
        .and_then(|set| validate(&set, cal, desc, options).ok())
        .and_then(|v| Some(v.validation.or(v.tool).or(v.axis)?.chi_square?.value));
    value.filter(|v| v.is_finite()).unwrap_or(f64::INFINITY)
}

/// The offset of command column `k` (0-based) within [`OFFSET_REFINE_HALF_WIDTH`] of `d` that
/// minimises the validation's own statistic ([`statistic_with`], [`minimum_near`]).
fn refined_offset(
    rows: &[Measurement],
    k: usize,
    d: f64,
    model: (&Calibration, &RobotDescription),
    options: &ValidationOptions,
) -> f64 {
    let at = |d: f64| statistic_with(rows, &move |m: &mut Measurement| m.cmd[k] += d, model, options);
    minimum_near(&at, d, OFFSET_REFINE_HALF_WIDTH)
}

/// The minimum of `at` within `half_width` of `d`, to [`OFFSET_STEP_DONE`]: the one bisection
/// ([`bisect_infallible`]) on the sign of its slope (central differences a tenth of that
/// width apart); the statistic is smooth in the shift and has one minimum that near.
fn minimum_near(at: &dyn Fn(f64) -> f64, d: f64, half_width: f64) -> f64 {
    let h = 0.05 * OFFSET_STEP_DONE;
    let stop = Bisection::to_width(OFFSET_STEP_DONE);
    let [lo, hi] = bisect_infallible(d - half_width, d + half_width, stop, |x| at(x + h) < at(x - h));
    0.5 * (lo + hi)
}

/// The fitted offset of the command column ([`fitted_offset`]) that leaves the least RMS,
/// refined on the validation's statistic ([`refined_offset`]), as a hypothesis, when it is at
/// least [`MIN_FITTED_OFFSET`].
fn offset_hypothesis(
    rows: &[Measurement],
    (cal, desc): (&Calibration, &RobotDescription),
    options: &ValidationOptions,
) -> Option<Hypothesis> {
    let (k, d, _) = (0..desc.dof())
        .filter_map(|k| {
            let d = fitted_offset(rows, k, cal, desc)?;
            Some((
                k,
                d,
                rms_with(rows, &move |m: &mut Measurement| m.cmd[k] += d, cal, desc)?,
            ))
        })
        .min_by(|a, b| a.2.total_cmp(&b.2))
        .filter(|(_, d, _)| d.abs() >= MIN_FITTED_OFFSET)?;
    let d = refined_offset(rows, k, d, (cal, desc), options);
    let unit = desc.joints[k].kind.file_unit();
    let shown = |v: f64| format_f64((v * 1e3).round() / 1e3);
    let words = [
        format!(
            "`cmd_{}` is offset by {} {unit} from the calibration: the joint's zero moved since the calibration \
             (re-mastered?), the column was shifted, or the calibration's zero of the joint was edited",
            k + 1,
            shown(-d)
        ),
        format!("with {} {unit} added to `cmd_{}`", shown(d), k + 1),
    ];
    Some(hypothesis(format!("cmd_{}", k + 1), words, move |m| m.cmd[k] += d))
}

/// [`explained_misses`] of the free poses of `set` (validation and tool poses, the axis
/// experiments left out), validated with the noise `cal` was weighted with at two-sided
/// false-alarm rate `false_alarm`: for the commands that do not validate the whole file
/// (`report --held-out`, `diagnose`). Empty without free poses.
pub fn free_pose_misses(
    set: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
    false_alarm: f64,
) -> Result<Vec<ExplainedMiss>, DiagnosisError> {
    let others: Vec<usize> = (0..set.rows().len())
        .filter(|&i| set.rows()[i].moved_joint > 0)
        .collect();
    if others.len() == set.rows().len() {
        return Ok(Vec::new());
    }
    let subset = set.without_rows(&others);
    let v = validate(&subset, cal, desc, &ValidationOptions::of_calibration(cal, false_alarm))?;
    Ok(explained_misses(&subset, cal, desc, &v))
}
