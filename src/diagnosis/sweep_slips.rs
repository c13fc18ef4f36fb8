//! Axis-experiment misses a slip in the data explains (`validate`, and `diagnose` against the
//! file's own free poses, [`own_sweep_misses`]): when the calibrated model
//! misses one axis experiment's points by more than [`GROSS_MISS_FACTOR`] times its test's
//! acceptance ([`acceptance`], with the axis experiments' predicted RMS), the slips `calibrate`
//! finds in a sweep are tried on that experiment's rows before the model is blamed, in this
//! order:
//!
//! 1. a frozen sweep: its points spread within [`UNRESOLVED_SPREAD_OVER_NOISE`] times the noise
//!    of a point (as `calibrate` refuses it) while the model moves them;
//! 2. the free poses' command slips ([`super::slips`]): a command column in radians, negated
//!    (the sign `calibrate` finds as an axis pointing opposite to its nominal), halved or
//!    doubled, two command columns swapped, after a held joint's command recorded off through the
//!    rows (`held_offsets`, tried first) (a coordinate column's unit in one experiment is the
//!    unit checks' `experiments` finding, and with the target's place on its link estimated
//!    from the points, a column flattened or negated is nearly absorbed);
//! 3. the coordinates in another order than the steps: the permutation of the points that
//!    puts each on the model's arc at another step's command ([`step_order`]);
//! 4. the swept joint's command scaled: the one factor that best explains the points
//!    (Gauss-Newton), said when it is beyond the false-alarm rate's normal quantile of its
//!    sigma from 1, and named gradians when 400/360 is within that quantile of it;
//! 5. the block moved rigidly (turned and shifted, an instrument bumped or re-set up between
//!    sweeps, [`rigid_move`]).
//!
//! The rewrites (2 to 5) are tried only on an experiment missed grossly alone, while the free
//! poses (validation, tool) pass their tests: a wrong model (another robot, a stale calibration)
//! misses the free poses and several sweeps alike, and a flexible rewrite of one sweep (a
//! scale, a rigid move) could absorb its share of that error. Each rewrite must bring the experiment within the validation's own test of its points (the
//! axis experiments' statistic, [`super::validate`]) to be said; a miss no slip explains stays
//! the model's. Experiments the model does not miss grossly are never searched, so clean data
//! pay nothing.

use super::noise::CleanCampaign;
use super::slips::{
    ExplainedMiss, Explanation, GROSS_MISS_FACTOR, Hypothesis, acceptance, command_hypotheses, first_confirmed,
    fitted_parameter, hypothesis, residuals_with,
};
use super::validate::{Validation, ValidationOptions, Verdict};
use crate::calibration::free_pose::{FreePoseOptions, calibrate_free_poses, with_fitted_targets};
use crate::calibration::procedure::Calibration;
use crate::kinematics::JointKind;
use crate::measurement::{Measurement, MeasurementSet};
use crate::numerics::finite_diff::central_jacobian;
use crate::numerics::stats::{UNRESOLVED_SPREAD_OVER_NOISE, chi_square_quantile, rms_spread};
use crate::robot::RobotDescription;
use nalgebra::{DVector, Point3, Vector3};
use std::collections::{BTreeMap, BTreeSet};

/// Gauss-Newton steps of the rigid move's fit ([`rigid_move`]) at most: the residuals are
/// smooth in the move, and a step below [`RIGID_DONE`] ends the fit earlier.
const RIGID_ITERATIONS: usize = 20;

/// The rigid move's fit stops at a step below this (rad and m together: a microradian moves a
/// point 1 m away by a micrometre, far below any instrument's noise).
const RIGID_DONE: f64 = 1e-6;

/// The rigid move's central differences \[rad or m\]: far below the chain's curvature scale and
/// above the residuals' rounding.
const RIGID_STEP: f64 = 1e-6;

/// One axis experiment of the set: its name, lines, moved joint and row indices.
struct Sweep<'a> {
    name: &'a str,
    joint: usize,
    lines: Option<(u64, u64)>,
    indices: Vec<usize>,
}

/// The slips that explain `v`'s misses of `set`'s axis experiments (module docs), one per
/// experiment explained; empty when `v`'s axis test does not exceed. `desc` is the
/// description `v` was made with.
pub fn explained_sweep_misses(
    set: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
    v: &Validation,
) -> Vec<ExplainedMiss> {
    let Some(axis) = v
        .axis
        .as_ref()
        .filter(|s| s.chi_square.as_ref().is_some_and(|c| c.verdict == Verdict::Exceeds))
    else {
        return Vec::new();
    };
    let options = ValidationOptions::of_validation(v);
    let predicted = axis.predicted_mm.total;
    let gross: Vec<(Sweep, f64, f64)> = sweeps(set)
        .into_iter()
        .filter_map(|s| {
            let n = s.indices.len();
            let rms = (s.indices.iter().map(|&i| v.residuals[i].error_mm.powi(2)).sum::<f64>() / n as f64).sqrt();
            let bound = acceptance(predicted, n, v.false_alarm);
            (n >= 3 && rms.is_finite() && rms > GROSS_MISS_FACTOR * bound).then_some((s, rms, bound))
        })
        .collect();
    // A model that is wrong (another robot, a stale calibration) misses the free poses and
    // several sweeps alike, and a flexible rewrite of one sweep could pass its test by
    // absorbing that error: the rewrites are tried only on a sweep missed alone.
    let free_consistent = [&v.validation, &v.tool]
        .into_iter()
        .flatten()
        .all(|s| s.chi_square.as_ref().is_none_or(|c| c.verdict != Verdict::Exceeds));
    let alone = gross.len() == 1 && free_consistent;
    gross
        .iter()
        .filter_map(|(s, rms, bound)| {
            let rows: Vec<Measurement> = s.indices.iter().map(|&i| set.rows()[i].clone()).collect();
            let lines = s.lines.map_or(String::new(), |(a, b)| format!(" (lines {a}-{b})"));
            let miss = format!(
                "the calibrated model misses experiment {}'s {} points{lines} by {rms:.4} mm RMS where {predicted:.4} mm \
                 is predicted",
                s.name,
                rows.len()
            );
            let (field, message) = match frozen(&rows, s, v, (&options, desc)) {
                Some(found) => found,
                None if alone => {
                    let e = explanation(&rows, s.joint, (cal, desc), &options, *bound)?;
                    let h = e.hypothesis;
                    let within = format!("{:.4} mm (chi2/dof {:.3}: within the prediction)", e.rms_mm, e.per_dof);
                    (h.field, format!("and by {within} {}: in these rows {}", h.reading, h.claim))
                }
                None => return None,
            };
            Some(ExplainedMiss {
                experiment: s.name.to_string(),
                line: s.indices.first().and_then(|&i| set.line_of(i)),
                field,
                message: format!("{miss}, {message}"),
            })
        })
        .collect()
}

/// The axis experiments of `set` in order of first appearance, with their rows' indices.
fn sweeps(set: &MeasurementSet) -> Vec<Sweep<'_>> {
    let mut index: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
    for (i, m) in set.rows().iter().enumerate().filter(|(_, m)| m.moved_joint > 0) {
        index.entry(m.experiment.as_str()).or_default().push(i);
    }
    set.experiments()
        .into_iter()
        .filter(|e| e.moved_joint > 0)
        .filter_map(|e| {
            Some(Sweep {
                name: e.name,
                joint: e.moved_joint,
                lines: e.lines,
                indices: index.remove(e.name)?,
            })
        })
        .collect()
}

/// The frozen sweep of the module docs: the column and the message, when the points of `rows`
/// spread within [`UNRESOLVED_SPREAD_OVER_NOISE`] times the noise of a point while the
/// calibrated model moves them by more than the test accepts.
fn frozen(
    rows: &[Measurement],
    s: &Sweep,
    v: &Validation,
    (options, desc): (&ValidationOptions, &RobotDescription),
) -> Option<(String, String)> {
    let measured: Vec<Point3<f64>> = rows.iter().map(|m| Point3::from(m.position_mm)).collect();
    let predicted: Vec<Point3<f64>> = s
        .indices
        .iter()
        .map(|&i| Point3::from(v.residuals[i].predicted_mm))
        .collect();
    let (spread, moved) = (rms_spread(&measured), rms_spread(&predicted));
    let limit = UNRESOLVED_SPREAD_OVER_NOISE * options.noise_rms_3d_mm;
    let column = |m: &Measurement| m.cmd[s.joint - 1];
    let span = rows.iter().map(column).fold(f64::NEG_INFINITY, f64::max)
        - rows.iter().map(column).fold(f64::INFINITY, f64::min);
    (spread <= limit && moved > limit).then(|| {
        (
            "x_mm,y_mm,z_mm".to_string(),
            format!(
                "and its points spread {spread:.4} mm RMS about their centroid, within {UNRESOLVED_SPREAD_OVER_NOISE} \
                 times the noise of a point ({:.4} mm), while `cmd_{}` moves by {} {} and the model moves the target \
                 {moved:.4} mm RMS: the coordinates did not follow the joint (one reading repeated, the instrument lost \
                 the target, the column filled by hand), or the joint did not move; `calibrate` refuses such a sweep",
                options.noise_rms_3d_mm,
                s.joint,
                crate::measurement::format_f64((span * 1e4).round() / 1e4),
                desc.joints[s.joint - 1].kind.file_unit()
            ),
        )
    })
}

/// The rewrite of the module docs (2 to 5) under which the validation's own test accepts
/// `rows` (an experiment sweeping joint `joint`, 1-based), with `bound_mm` its acceptance: the
/// first finite slip (2) that passes, else the fitted rewrites (3 to 5) that pass weighed by
/// [`simplest_sufficient`].
fn explanation(
    rows: &[Measurement],
    joint: usize,
    model: (&Calibration, &RobotDescription),
    options: &ValidationOptions,
    bound_mm: f64,
) -> Option<Explanation> {
    let fitted: [(usize, &dyn Fn() -> Option<Hypothesis>); 3] = [
        (0, &|| step_order(rows, model)),
        (1, &|| swept_scale(rows, joint - 1, model, options)),
        (RIGID_PARAMETERS, &|| rigid_move(rows, model)),
    ];
    // A held command recorded off (`calibrate`'s "the held `cmd_k` looks offset") is tried
    // before the column slips: one wrong value of a held column, where a swap of it with a
    // column the rows leave at the reference moves the offset to that joint, and passes too
    // when that joint barely moves the target. A swap involving the swept column, or two held
    // columns at other values, is not undone by moving one column back: it passes alone.
    first_confirmed(held_offsets(rows, joint, model), rows, model, options, bound_mm)
        .or_else(|| first_confirmed(command_hypotheses(model.1), rows, model, options, bound_mm))
        .or_else(|| {
            let passing = fitted
                .iter()
                .filter_map(|(p, h)| Some((*p, first_confirmed(vec![h()?], rows, model, options, bound_mm)?)))
                .collect();
            simplest_sufficient(passing, options.false_alarm)
        })
}

/// A held joint's command recorded off through `rows` (an experiment sweeping `joint`,
/// 1-based): for each other joint whose median command in the rows differs from the
/// calibration's reference pose, the rewrite that moves its commands back by that difference
/// (its wander kept). A sweep held at another pose on purpose is missed by the rewrite, not
/// explained: only a command that should have been the reference's passes.
fn held_offsets(rows: &[Measurement], joint: usize, (cal, desc): (&Calibration, &RobotDescription)) -> Vec<Hypothesis> {
    use crate::numerics::stats::{QuantileMethod, quantile};
    let mut out = Vec::new();
    for (j, reference) in cal.reference_cmd.iter().copied().enumerate() {
        if j + 1 == joint || rows.is_empty() {
            continue;
        }
        let values: Vec<f64> = rows.iter().map(|m| m.cmd[j]).collect();
        let offset = quantile(&values, 0.5, QuantileMethod::Linear) - reference;
        if offset == 0.0 {
            continue;
        }
        let unit = match desc.joints[j].kind {
            JointKind::Revolute => "deg",
            JointKind::Prismatic => "mm",
        };
        let c = format!("`cmd_{}`", j + 1);
        out.push(hypothesis(
            format!("cmd_{}", j + 1),
            [
                format!(
                    "the held {c} is recorded {offset:+.3} {unit} off where the robot stood (the reference pose's {reference} {unit}): a value typed wrong for these rows, or the joint re-mastered between the sweeps"
                ),
                format!("with the held {c} moved back by {offset:+.3} {unit}"),
            ],
            move |m| m.cmd[j] -= offset,
        ));
    }
    out
}

/// The rigid move's parameters: a turn (3) and a shift (3).
const RIGID_PARAMETERS: usize = 6;

/// Of the explanations `passing` (each with its count of fitted parameters) the one with the
/// fewest parameters, unless one with more fits significantly better: its statistic lower by
/// more than the chi-square quantile at `1 - false_alarm` with the extra parameters as degrees
/// of freedom (the likelihood-ratio test: a free parameter lowers the statistic by about 1 on
/// clean data). A rewrite with more parameters that fits better but not significantly so ties
/// with it: both are said, the simpler first.
fn simplest_sufficient(mut passing: Vec<(usize, Explanation)>, false_alarm: f64) -> Option<Explanation> {
    passing.sort_by_key(|(p, _)| *p);
    let mut it = passing.into_iter();
    let (mut params, mut best) = it.next()?;
    let mut tied: Vec<Explanation> = Vec::new();
    for (p, e) in it {
        let gain = best.statistic - e.statistic;
        if p > params && gain > chi_square_quantile(1.0 - false_alarm, (p - params) as f64) {
            (params, best) = (p, e);
            tied.clear();
        } else if gain > 0.0 {
            tied.push(e);
        }
    }
    for t in tied {
        best.hypothesis.claim = format!(
            "{}; or, as well within the prediction ({:.4} mm, chi2/dof {:.3}) {}: {}",
            best.hypothesis.claim, t.rms_mm, t.per_dof, t.hypothesis.reading, t.hypothesis.claim
        );
    }
    Some(best)
}

/// The points of `rows` reordered among their steps (per target) so that each sits where the
/// calibrated model puts the target at its new step's command: with the target on its link
/// placed by the first point at each step in turn, every point goes to the step whose predicted
/// position is nearest; the placement whose assignment is one-to-one with the least sum of
/// squares wins. A hypothesis only when some point moves.
fn step_order(rows: &[Measurement], (cal, desc): (&Calibration, &RobotDescription)) -> Option<Hypothesis> {
    let set = MeasurementSet::new(desc.dof(), rows.to_vec()).ok()?;
    let frames = CleanCampaign::new(&set, cal, desc, &desc.tool_targets_m())
        .ok()?
        .link_frames();
    let mut moved: BTreeMap<(usize, usize), [f64; 3]> = BTreeMap::new();
    let targets: BTreeSet<usize> = rows.iter().map(|m| m.target).collect();
    for target in targets {
        let idx: Vec<usize> = (0..rows.len()).filter(|&i| rows[i].target == target).collect();
        let points: Vec<Point3<f64>> = idx.iter().map(|&i| rows[i].position_m()).collect();
        let Some(assigned) = best_assignment(&idx, &points, &frames) else {
            continue;
        };
        for (j, &k) in assigned.iter().enumerate().filter(|(j, k)| j != *k) {
            moved.insert((rows[idx[k]].step, target), rows[idx[j]].position_mm);
        }
    }
    if moved.is_empty() {
        return None;
    }
    let count = moved.len();
    let words = [
        format!(
            "the coordinates are not in step order: {count} of the sweep's points sit where the joint was at another \
             step's command (rows sorted or pasted in another order than the commands)"
        ),
        format!("with {count} points put back at the steps whose commands place them"),
    ];
    Some(hypothesis("x_mm,y_mm,z_mm".into(), words, move |m| {
        if let Some(p) = moved.get(&(m.step, m.target)) {
            m.position_mm = *p;
        }
    }))
}

/// For the points `points` of rows `idx` (one target) and every row's link frame `frames`: the
/// row each point is assigned to (by index into `idx`), one-to-one, with the least sum of
/// squares over the placements of the target by the first point (module docs of
/// [`step_order`]).
fn best_assignment(idx: &[usize], points: &[Point3<f64>], frames: &[nalgebra::Isometry3<f64>]) -> Option<Vec<usize>> {
    let first = points.first()?;
    (0..idx.len())
        .filter_map(|k0| {
            let on_link = frames[idx[k0]].inverse() * first;
            let predicted: Vec<Point3<f64>> = idx.iter().map(|&i| frames[i] * on_link).collect();
            let mut sum = 0.0;
            let assigned: Vec<usize> = points
                .iter()
                .map(|p| {
                    let (k, d) = predicted
                        .iter()
                        .map(|q| (p - q).norm_squared())
                        .enumerate()
                        .min_by(|a, b| a.1.total_cmp(&b.1))
                        .unwrap_or((0, f64::INFINITY));
                    sum += d;
                    k
                })
                .collect();
            let distinct: BTreeSet<usize> = assigned.iter().copied().collect();
            (distinct.len() == assigned.len()).then_some((sum, assigned))
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, assigned)| assigned)
}

/// The factor of the swept joint's command column `k` (0-based) in `rows` that best explains
/// their points against the calibration (module docs, item 4) as a hypothesis, when it is beyond
/// the normal quantile of the false-alarm rate times its sigma from 1.
pub(super) fn swept_scale(
    rows: &[Measurement],
    k: usize,
    (cal, desc): (&Calibration, &RobotDescription),
    options: &ValidationOptions,
) -> Option<Hypothesis> {
    let at = |s: f64| residuals_with(rows, &move |m: &mut Measurement| m.cmd[k] *= s, cal, desc);
    // The file's values over the true ones within a factor of 5 (a larger one is a unit the
    // finite slips and the unit checks name).
    let within = |s: f64| (0.2..=5.0).contains(&s);
    let (s, jj) = fitted_parameter(&at, 1.0, [1e-5, 1e-9], &within)?;
    let sigma_s = options.noise_rms_3d_mm / 3f64.sqrt() / jj.sqrt();
    let z = chi_square_quantile(1.0 - options.false_alarm, 1.0).sqrt();
    if (s - 1.0).abs() <= z * sigma_s {
        return None;
    }
    let (factor, sigma) = (1.0 / s, sigma_s / (s * s));
    let gradians = 400.0 / 360.0;
    let revolute = desc.joints[k].kind == JointKind::Revolute;
    let cause = if revolute && (factor - gradians).abs() <= z * sigma {
        "gradians (400/360 = 1.1111 times the degrees)?".to_string()
    } else if revolute && (factor - 1.0 / gradians).abs() <= z * sigma {
        format!(
            "0.9 = 360/400: the calibration's own sweep of joint {} was in gradians (its transmission took the \
             factor), or these rows' column holds the degrees times 0.9",
            k + 1
        )
    } else {
        "the column scaled (another unit, a gear ratio applied twice), or the joint's transmission changed since \
         the calibration"
            .to_string()
    };
    let c = format!("`cmd_{}`", k + 1);
    let words = [
        format!(
            "{c} holds {factor:.4} times (+- {sigma:.4}, {:.0} sigma from 1) the values the calibration's transmission \
             gives for these points: {cause}",
            (factor - 1.0).abs() / sigma
        ),
        format!("with {c} divided by {factor:.4}"),
    ];
    Some(hypothesis(format!("cmd_{}", k + 1), words, move |m| m.cmd[k] *= s))
}

/// `m`'s point moved rigidly by `params` (a rotation vector \[rad\], then a translation \[m\])
/// about `centre` \[m\].
fn moved_by(m: &mut Measurement, params: &[f64; 6], centre: &Point3<f64>) {
    let rotation = nalgebra::Rotation3::new(Vector3::new(params[0], params[1], params[2]));
    let p = centre + rotation * (m.position_m() - centre) + Vector3::new(params[3], params[4], params[5]);
    m.position_mm = (p.coords * 1e3).into();
}

/// The rigid move of the whole block `rows` that brings it nearest the calibration's prediction
/// (module docs, item 5): a rotation about the block's centroid and a translation, fitted by
/// Gauss-Newton (central differences, the normal equations solved by a pseudo-inverse: a turn
/// about the swept axis only moves the targets on the link, which are re-estimated from the
/// moved points); as a hypothesis with its angle and shift.
fn rigid_move(rows: &[Measurement], (cal, desc): (&Calibration, &RobotDescription)) -> Option<Hypothesis> {
    let n = rows.len() as f64;
    let centre = Point3::from(rows.iter().map(|m| m.position_m().coords).sum::<Vector3<f64>>() / n);
    let at = |x: &[f64; 6]| residuals_with(rows, &|m: &mut Measurement| moved_by(m, x, &centre), cal, desc);
    let mut x = [0.0; 6];
    for _ in 0..RIGID_ITERATIONS {
        let r = DVector::from_vec(at(&x)?);
        let jacobian = central_jacobian(|p: &[f64]| at(p.try_into().ok()?), &x, &[RIGID_STEP; 6])?;
        let normal = jacobian.transpose() * &jacobian;
        let tolerance = 1e-9 * normal.norm();
        let step = normal.pseudo_inverse(tolerance).ok()? * (jacobian.transpose() * -r);
        x.iter_mut().zip(step.iter()).for_each(|(a, d)| *a += d);
        if step.norm() < RIGID_DONE {
            break;
        }
    }
    let angle_deg = Vector3::new(x[0], x[1], x[2]).norm().to_degrees();
    let shift_mm = Vector3::new(x[3], x[4], x[5]) * 1e3;
    let words = [
        format!(
            "the block is out of place among the other experiments: it sits turned {angle_deg:.2} deg and shifted \
             ({:.1}, {:.1}, {:.1}) mm (its centroid) from where the model puts it, as one rigid body: the instrument \
             (or the robot) was bumped or set up again between the sweeps, or the block comes from another setup",
            -shift_mm.x, -shift_mm.y, -shift_mm.z
        ),
        format!(
            "with the block moved back ({angle_deg:.2} deg, {:.1} mm)",
            shift_mm.norm()
        ),
    ];
    Some(hypothesis("x_mm,y_mm,z_mm".into(), words, move |m| {
        moved_by(m, &x, &centre)
    }))
}

/// The slips of `set`'s axis experiments found against its own free poses (`diagnose`, which
/// has no other calibration to hold the sweeps against): when `cal`, the calibration of the
/// file's axis experiments, misses its free poses grossly (by more than 3 times their test's
/// acceptance at `false_alarm`, `GROSS_MISS_FACTOR`), the robot is calibrated again from the free
/// poses alone ([`calibrate_free_poses`], its outlier poses left out) and every sweep is tested
/// against that model as `validate` tests a file's sweeps against a calibration
/// ([`explained_sweep_misses`]). A slip in one sweep (a sign, gradians or another scale, two
/// columns swapped, its points frozen or out of step order, the block moved) is absorbed by the
/// sweeps' own calibration (a transmission scaled, an axis reversed), so only the free poses
/// show it; against their model it stands out in that sweep alone. Empty when the free poses
/// are met, cannot be calibrated alone, or no one sweep's slip explains the miss.
pub fn own_sweep_misses(
    set: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
    false_alarm: f64,
) -> Vec<ExplainedMiss> {
    own_sweep_misses_of(set, cal, desc, false_alarm).unwrap_or_default()
}

fn own_sweep_misses_of(
    set: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
    false_alarm: f64,
) -> Option<Vec<ExplainedMiss>> {
    let sweep_rows: Vec<usize> = (0..set.rows().len())
        .filter(|&i| set.rows()[i].moved_joint > 0)
        .collect();
    if sweep_rows.is_empty() || sweep_rows.len() == set.rows().len() {
        return None;
    }
    let poses = set.without_rows(&sweep_rows);
    let miss = gross_free_pose_miss(&poses, cal, desc, false_alarm)?;
    let free = calibrate_free_poses(&poses, desc, &FreePoseOptions::default()).ok()?;
    let dropped: BTreeSet<(String, usize)> = free
        .summary
        .outliers
        .iter()
        .filter(|o| o.dropped)
        .map(|o| (o.experiment.clone(), o.step))
        .collect();
    let fitted_poses = free.summary.poses;
    let (reference, summary) = free.into_calibration(desc);
    let fitted = with_fitted_targets(desc, Some(&summary));
    let outlier_rows: Vec<usize> = (0..set.rows().len())
        .filter(|&i| dropped.contains(&(set.rows()[i].experiment.clone(), set.rows()[i].step)))
        .collect();
    let kept = set.without_rows(&outlier_rows);
    let options = ValidationOptions::of_calibration(&reference, false_alarm);
    let v = super::validate::validate(&kept, &reference, &fitted, &options).ok()?;
    let model = format!(
        "the model calibrated from this file's own {fitted_poses} free poses (the calibration of its axis experiments \
         misses them by {miss}) misses"
    );
    let found = explained_sweep_misses(&kept, &reference, &fitted, &v)
        .into_iter()
        .map(|m| ExplainedMiss {
            message: m.message.replacen("the calibrated model misses", &model, 1),
            ..m
        })
        .collect();
    Some(found)
}

/// `... mm RMS where ... mm is predicted` when `cal` misses the free poses `poses` by more than
/// [`GROSS_MISS_FACTOR`] times their test's acceptance ([`acceptance`] at `false_alarm`).
fn gross_free_pose_miss(
    poses: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
    false_alarm: f64,
) -> Option<String> {
    let options = ValidationOptions::of_calibration(cal, false_alarm);
    let v = super::validate::validate(poses, cal, desc, &options).ok()?;
    let s = v.validation.as_ref()?;
    let exceeds = s.chi_square.as_ref().is_some_and(|c| c.verdict == Verdict::Exceeds);
    let bound = acceptance(s.predicted_mm.total, s.points, false_alarm);
    (exceeds && s.rms_mm > GROSS_MISS_FACTOR * bound).then(|| {
        format!(
            "{:.4} mm RMS where {:.4} mm is predicted",
            s.rms_mm, s.predicted_mm.total
        )
    })
}
