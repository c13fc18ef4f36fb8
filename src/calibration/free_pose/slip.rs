//! Column slips a free-pose calibration would absorb or be refused for, and tool target ids
//! in a mirrored order.
//!
//! The free-pose fit moves every row of the geometry: a command column negated turns into an
//! axis fitted the other way round, in gradians into fitted rows that follow the wrong
//! angles; the fit then succeeds and the model is wrong, or it fails and blames the
//! description. The nominal model placed on the poses (base and targets fitted, the
//! geometry the description's, [`nominal_misfits`]) has no such freedom: a slip leaves it
//! missing the points by far more than the robot's own errors do. Each slip of
//! [`crate::measurement::column_slips`] is undone on the poses in turn; the one that makes the
//! nominal model fit significantly better on the poses' paired misfits (`significantly_better`
//! at [`SLIP_FALSE_ALARM`] shared by the slips tried) with the least misfit is said. Clean data
//! make every rewrite fit worse.
//!
//! Target ids: three targets whose distances are symmetric (two equal sides) have two labellings
//! no distance tells apart, one the mirror image of the other. The fitted targets then sit in
//! the description's tool frame turned about half a turn ([`mirrored_targets`]).

use super::fit::{self, Problem};
use super::{FreePoseError, FreePoseOptions, FreePoseSummary, FreePoses, frame_parameter, layout, registered_start};
use crate::kinematics::rigid_fit;
use crate::measurement::column_slips::{ColumnSlip, column_slips, slip};
use crate::measurement::{Measurement, MeasurementSet};
use crate::numerics::stats::{ABSURD_SHARE, chi_square_quantile, ln_gamma};
use crate::robot::{Controller, RobotDescription, RobotModel};
use nalgebra::Point3;

/// The two-sided false-alarm rate of the slip search on a clean file, shared by every slip
/// tried (Bonferroni): once in ten thousand files, as calibrate's test of its own validation
/// poses.
pub const SLIP_FALSE_ALARM: f64 = 1e-4;

/// A column slip that explains the free poses better than the file as written.
#[derive(Clone, Debug, PartialEq)]
pub struct ExplainingSlip {
    /// The column (or columns): `cmd_2`, `x_mm,y_mm`.
    pub field: String,
    /// What the column holds: "`cmd_2` is negated ...".
    pub claim: String,
    /// RMS \[mm\] of the nominal model placed on the poses as written.
    pub written_rms_mm: f64,
    /// The same with the slip undone.
    pub undone_rms_mm: f64,
}

/// The free poses of `set` (at most `max_poses`, evenly spaced) and the residual \[m\] of the
/// nominal model of `desc` placed on them (base and targets fitted), 3 rows a point.
fn nominal_placement(
    set: &MeasurementSet,
    desc: &RobotDescription,
    all_rows: bool,
    max_poses: usize,
) -> Result<(FreePoses, nalgebra::DVector<f64>), FreePoseError> {
    let poses = FreePoses::from_set_at_most(set, desc, all_rows, max_poses)?;
    let controller = Controller::from_description(desc);
    let nominal = RobotModel::ideal(desc);
    let which: Vec<usize> = (0..poses.poses.len()).collect();
    let layout = layout(
        &nominal,
        &poses.target_ids,
        0,
        &poses.spans(&which),
        poses.setup_names.len(),
    );
    let problem = Problem {
        controller: &controller,
        poses: &poses,
        layout: &layout,
        description_targets_m: desc.tool_targets_m(),
    };
    let start = registered_start(&problem, &nominal, &which)?;
    let frame_columns: Vec<usize> = (0..layout.len()).filter(|&c| frame_parameter(&layout[c])).collect();
    let residual = fit::fit(&problem, &start, &which, &frame_columns)?.residual;
    Ok((poses, residual))
}

/// Each pose's RMS misfit \[m\] of the nominal model of `desc` placed on the free poses of
/// `set` (base and targets fitted; at most `max_poses` poses, evenly spaced), and the points'
/// RMS spread about their centroid \[m\].
pub fn nominal_misfits(
    set: &MeasurementSet,
    desc: &RobotDescription,
    all_rows: bool,
    max_poses: usize,
) -> Result<(Vec<f64>, f64), FreePoseError> {
    let (poses, residual) = nominal_placement(set, desc, all_rows, max_poses)?;
    let which: Vec<usize> = (0..poses.poses.len()).collect();
    let points: Vec<Point3<f64>> = poses
        .poses
        .iter()
        .flat_map(|p| p.points_m.iter().map(|(_, q)| *q))
        .collect();
    Ok((
        fit::pose_rms(&residual, &poses, &which),
        crate::numerics::stats::rms_spread(&points),
    ))
}

/// Whether the per-pose misfits `undone` beat `written` beyond chance, at [`SLIP_FALSE_ALARM`]
/// / (2 `tried`) one-sided: the paired differences of their squares sum to more than `z`
/// standard errors of that sum (`z` the normal quantile), or so many poses fit better that a
/// fair coin would give as many as rarely (the sign test: a slip that moves some poses by far
/// more than others, as a joint's zero does, leaves differences too unequal for the first).
fn significantly_better(undone: &[f64], written: &[f64], tried: usize) -> bool {
    let d: Vec<f64> = written.iter().zip(undone).map(|(w, u)| w * w - u * u).collect();
    let n = d.len() as f64;
    if d.len() < 2 {
        return false;
    }
    let alpha = SLIP_FALSE_ALARM / (2 * tried.max(1)) as f64;
    let sum: f64 = d.iter().sum();
    let mean = sum / n;
    let variance = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    let z = chi_square_quantile(1.0 - 2.0 * alpha, 1.0).sqrt();
    let better = d.iter().filter(|&&x| x > 0.0).count();
    sum.is_finite() && (sum > z * (n * variance).sqrt() || sign_test_tail(d.len(), better) < alpha)
}

/// The chance that `k` or more of `n` fair coins fall heads (the upper tail of the binomial
/// distribution with p = 1/2).
fn sign_test_tail(n: usize, k: usize) -> f64 {
    let ln_choose = |j: usize| ln_gamma(n as f64 + 1.0) - ln_gamma(j as f64 + 1.0) - ln_gamma((n - j) as f64 + 1.0);
    (k..=n)
        .map(|j| (ln_choose(j) - n as f64 * std::f64::consts::LN_2).exp())
        .sum()
}

/// `set` with `undo` applied to every row (`None` when the rewrite is no measurement set).
fn undone(set: &MeasurementSet, undo: &dyn Fn(&mut Measurement), dof: usize) -> Option<MeasurementSet> {
    let rows: Vec<Measurement> = set
        .rows()
        .iter()
        .map(|m| {
            let mut m = m.clone();
            undo(&mut m);
            m
        })
        .collect();
    MeasurementSet::new(dof, rows).ok()
}

/// Free poses the slip search places the nominal model on at most, evenly spaced: a few hundred
/// poses resolve a slip that moves points by millimetres, and each of the search's some 60
/// rewrites costs one placement of them.
pub const SLIP_SEARCH_POSES: usize = 400;

/// Standard errors of an RMS by which the calibration with a slip undone may fit worse than
/// the calibration as written and still explain the data: the RMS of `dof` residuals has a
/// relative standard error of `1 / sqrt(2 dof)`.
const RMS_STANDARD_ERRORS: f64 = 3.0;

/// The column slip (module docs) whose undoing makes the nominal model fit the free poses of
/// `set` significantly better, with the least misfit, the nominal model then within the share
/// of the points' spread a calibration accepts ([`ABSURD_SHARE`]: a slip that leaves the nominal
/// model missing by more explains only part of the miss), confirmed by the free-pose calibration of
/// the rows with it undone (with `options`): that calibration must succeed, and fit within
/// `RMS_STANDARD_ERRORS` of `written`'s RMS where the rows as written calibrated. A slip that
/// explains only part of a miss (another slip, or the description, behind it) is not said.
/// `None` when no slip does, or the poses as written cannot be placed.
pub fn explaining_slip(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &FreePoseOptions,
    written: Option<&FreePoseSummary>,
) -> Option<ExplainingSlip> {
    let poses = options.max_poses.min(SLIP_SEARCH_POSES);
    let (placed, residual) = nominal_placement(set, desc, options.all_rows, poses).ok()?;
    let everyone: Vec<usize> = (0..placed.poses.len()).collect();
    let as_written = fit::pose_rms(&residual, &placed, &everyone);
    let kinds: Vec<_> = desc.joints.iter().map(|j| j.kind).collect();
    let mut slips = column_slips(&kinds);
    let mut tried = slips.len();
    if let Some((shift, breaks)) = block_shift(set, &placed, &residual) {
        slips.push(shift);
        tried += breaks;
    }
    let rms = |m: &[f64]| (m.iter().map(|r| r * r).sum::<f64>() / m.len().max(1) as f64).sqrt() * 1e3;
    let (slip, rewritten, misfits) = slips
        .into_iter()
        .filter_map(|s| {
            let rewritten = undone(set, &*s.undo, desc.dof())?;
            let (misfits, spread_m) = nominal_misfits(&rewritten, desc, options.all_rows, poses).ok()?;
            let plausible = rms(&misfits) <= ABSURD_SHARE * spread_m * 1e3;
            (plausible && misfits.len() == as_written.len() && significantly_better(&misfits, &as_written, tried))
                .then_some((s, rewritten, misfits))
        })
        .min_by(|a, b| rms(&a.2).total_cmp(&rms(&b.2)))?;
    let calibrated = super::calibrate_free_poses(&rewritten, desc, options).ok()?;
    if slip.field != "setup" && !explains_most(rms(&as_written), rms(&misfits), calibrated.summary.calibrated_rms_mm) {
        return None;
    }
    if let Some(w) = written {
        let dof = (3 * w.points).saturating_sub(w.parameters.len()).max(1) as f64;
        let margin = RMS_STANDARD_ERRORS / (2.0 * dof).sqrt();
        // A block's shift is no geometry the fit can take (the robot's model moves every pose
        // alike): undone, the calibration must fit significantly better, or the nominal model's
        // pose-ordered misfit (a real robot's geometry errors) was read as a shift.
        let allowed = match slip.field.as_str() {
            "setup" => w.calibrated_rms_mm * (1.0 - margin),
            _ => w.calibrated_rms_mm * (1.0 + margin),
        };
        // A slip the fit absorbs into effects (a sag taking a column's scale) can fit the rows
        // as written closer than the rows undone; the effects' cross-validated RMS, which
        // charges the absorbed freedom, then judges.
        let absorbed = slip.field != "setup"
            && matches!((cross_validated_rms_mm(&calibrated.summary), cross_validated_rms_mm(w)),
                (Some(undone), Some(written)) if undone < written);
        if calibrated.summary.calibrated_rms_mm > allowed && !absorbed {
            return None;
        }
    }
    let (field, claim) = match slip.mirror {
        true => ("x_mm,y_mm,z_mm".to_owned(), MIRRORED.to_owned()),
        false => (slip.field, slip.claim),
    };
    Some(ExplainingSlip {
        field,
        claim,
        written_rms_mm: rms(&as_written),
        undone_rms_mm: rms(&misfits),
    })
}

/// Whether undoing a column slip explains most of the nominal model's miss: of the mean square
/// by which the nominal model placed on the poses as written (`written_mm`) misses them beyond
/// what the calibration of the rows with the slip undone leaves (`calibrated_mm`: the noise and
/// what no geometry takes), the slip undone (`undone_mm`) removes more than everything else
/// together, [`EXPLAINED_SHARE`]. A slip that only beats the rows as written (run 9 NU2: a real
/// positioner's `cmd_2` scaled 1.2 % read as "`cmd_1` is negated", 14.1 mm as written and 12.1 mm
/// undone where the calibration leaves 4.7 mm) is not the cause; a real sign flip or a column in
/// other units moves the points by the joint's travel and leaves the robot's own geometry
/// errors, removing nearly all of it. A block shift has its own test (the calibration with it
/// undone must fit better).
fn explains_most(written_mm: f64, undone_mm: f64, calibrated_mm: f64) -> bool {
    let beyond = written_mm.powi(2) - calibrated_mm.powi(2);
    beyond > 0.0 && written_mm.powi(2) - undone_mm.powi(2) > EXPLAINED_SHARE * beyond
}

/// The share of the nominal model's mean square miss (beyond the calibration's) a slip must
/// remove to be named: more than everything else together.
const EXPLAINED_SHARE: f64 = 0.5;

/// The cross-validated RMS \[mm\] of the effects a free-pose calibration kept (`None` without
/// `--effects auto`'s trials).
fn cross_validated_rms_mm(summary: &FreePoseSummary) -> Option<f64> {
    summary
        .effects_tried
        .iter()
        .find(|t| t.chosen)
        .map(|t| t.cross_validated_rms_mm)
}

/// Poses on either side of a break at least, for a block's mean residual to be one.
pub const MIN_BLOCK_POSES: usize = 3;

/// The poses from one on shifted as a block (the instrument or the robot moved between two
/// poses, by a bump or a re-setup): the break in file order whose later block's mean residual
/// of the nominal placement `residual` differs most from the earlier one's (the two-sample
/// statistic `|d|^2 k (n - k) / n`), as a slip that moves the later block back by that
/// difference; with the breaks tried.
fn block_shift(
    set: &MeasurementSet,
    poses: &FreePoses,
    residual: &nalgebra::DVector<f64>,
) -> Option<(ColumnSlip, usize)> {
    let n = poses.poses.len();
    if n < 2 * MIN_BLOCK_POSES {
        return None;
    }
    let mut means = Vec::with_capacity(n);
    let mut row = 0;
    for p in &poses.poses {
        let points = p.points_m.len();
        let mut sum = nalgebra::Vector3::zeros();
        for k in 0..points {
            sum += residual.fixed_rows::<3>(row + 3 * k);
        }
        row += 3 * points;
        means.push(sum / points.max(1) as f64);
    }
    let mean = |r: &[nalgebra::Vector3<f64>]| r.iter().sum::<nalgebra::Vector3<f64>>() / r.len() as f64;
    let (k, offset) = (MIN_BLOCK_POSES..=n - MIN_BLOCK_POSES)
        .map(|k| (k, mean(&means[k..]) - mean(&means[..k])))
        .max_by(|a, b| {
            let score = |(k, d): &(usize, nalgebra::Vector3<f64>)| d.norm_squared() * (*k * (n - *k)) as f64;
            score(a).total_cmp(&score(b))
        })?;
    let later: std::collections::HashSet<(String, usize)> = poses.poses[k..]
        .iter()
        .map(|p| (p.experiment.clone(), p.step))
        .collect();
    let first = &poses.poses[k];
    let line = set
        .rows()
        .iter()
        .position(|m| m.experiment == first.experiment && m.step == first.step)
        .and_then(|i| set.line_of(i));
    let mm = offset * 1e3;
    let claim = format!(
        "the poses from {} on ({} of {}) sit about ({:.1}, {:.1}, {:.1}) mm off the ones before: the instrument or the robot \
         moved between them (a bump, a re-setup)",
        line.map_or_else(
            || format!("experiment {} step {}", first.experiment, first.step),
            |l| format!("line {l}")
        ),
        n - k,
        n,
        mm.x,
        mm.y,
        mm.z
    );
    let claim = claim + &stepping_joints_words(&poses.poses[..k], &poses.poses[k..]);
    let reading = "with the later poses moved back".to_string();
    let shift = slip("setup".into(), [claim, reading], move |m: &mut Measurement| {
        if later.contains(&(m.experiment.clone(), m.step)) {
            for c in 0..3 {
                m.position_mm[c] -= mm[c];
            }
        }
    });
    Some((shift, n + 1 - 2 * MIN_BLOCK_POSES))
}

/// The joints whose file commands (`cmd_file`) over the poses `after` a break all lie beyond
/// their range over the poses `before` it, in words (empty without one): such a joint's
/// command column read with another zero or scale for the later poses turns them about its
/// axis, which moves them much as a block would (a `cmd_1` scaled 0.98 on the real FANUC,
/// whose joint 1 sits at 45 deg for 210 poses and at 26-29 deg for the last 30).
fn stepping_joints_words(before: &[super::FreePose], after: &[super::FreePose]) -> String {
    let range = |poses: &[super::FreePose], j: usize| {
        poses
            .iter()
            .map(|p| p.cmd_file[j])
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
    };
    let dof = before.first().map_or(0, |p| p.cmd_file.len());
    let words: Vec<String> = (0..dof)
        .filter_map(|j| {
            let (b, a) = (range(before, j), range(after, j));
            (a.0 > b.1 || a.1 < b.0).then(|| {
                let span = |(lo, hi): (f64, f64)| match hi - lo {
                    d if d.abs() < 1e-9 * hi.abs().max(1.0) => format!("{lo:.4}"),
                    _ => format!("{lo:.4} to {hi:.4}"),
                };
                format!("`cmd_{}` {} before, {} from there on", j + 1, span(b), span(a))
            })
        })
        .collect();
    if words.is_empty() {
        return String::new();
    }
    format!(
        " (or a command column read with another zero or scale for them: {} (file units); a joint's command \
         that changes at the break as a whole turns the later poses about its axis, much as a move of the block \
         would: check it against the controller's reading at a pose of each side)",
        words.join("; ")
    )
}

/// The claim of a mirror slip ([`crate::measurement::column_slips::ColumnSlip::mirror`]).
const MIRRORED: &str = "the coordinates are mirrored: one of `x_mm`, `y_mm`, `z_mm` is negated or two of them are \
                        swapped (a rigid placement of the robot cannot tell which; a left-handed instrument frame, or \
                        columns exported in another order)";

/// Tool targets whose ids the data give in a mirrored order: the order, and the angles \[deg\]
/// by which the tool frame fitted to the description's targets turns with the ids as written
/// and in that order.
#[derive(Clone, Debug, PartialEq)]
pub struct MirroredTargets {
    /// `order[k]`: the description's target the data's id `ids[k]` is.
    pub order: Vec<usize>,
    /// The data's target ids.
    pub ids: Vec<usize>,
    /// The tool frame's turn with the ids as written \[deg\].
    pub written_deg: f64,
    /// Its turn with the ids in `order` \[deg\].
    pub reordered_deg: f64,
}

/// The other orders of `ids` under which the description's targets `described` keep their
/// mutual distances (within `tolerance_m`): the labellings distances cannot tell apart.
fn symmetric_orders(ids: &[usize], described: &[Point3<f64>], tolerance_m: f64) -> Vec<Vec<usize>> {
    let n = ids.len();
    let mut out = Vec::new();
    let mut order: Vec<usize> = ids.to_vec();
    permutations(&mut order, 0, &mut |o: &[usize]| {
        let same = (0..n).all(|a| {
            (a + 1..n).all(|b| {
                let written = (described[ids[a]] - described[ids[b]]).norm();
                let other = (described[o[a]] - described[o[b]]).norm();
                (written - other).abs() <= tolerance_m
            })
        });
        if same && o != ids {
            out.push(o.to_vec());
        }
    });
    out
}

/// Calls `f` with every permutation of `v[from..]` (Heap-free recursion; `v` at most a few
/// ids long).
fn permutations(v: &mut Vec<usize>, from: usize, f: &mut dyn FnMut(&[usize])) {
    if from == v.len() {
        f(v);
        return;
    }
    for i in from..v.len() {
        v.swap(from, i);
        permutations(v, from + 1, f);
        v.swap(from, i);
    }
}

/// Tool targets at most tried in every order (24 orders).
const MAX_ORDERED_TARGETS: usize = 4;

/// The angle \[deg\] by which the tool frame fitted to the description's targets turns from
/// the description's, with the data's target id `k` (the `k`-th of `summary`'s targets) read as
/// the description's target `order[k]`: the rigid fit of those described positions onto the
/// fitted ones. `None` without three such targets.
pub fn tool_turn_deg(summary: &FreePoseSummary, desc: &RobotDescription, order: &[usize]) -> Option<f64> {
    let described = desc.tool_targets_m();
    let src: Vec<Point3<f64>> = order
        .iter()
        .map(|&k| described.get(k).copied())
        .collect::<Option<_>>()?;
    let fitted: Vec<Point3<f64>> = summary
        .targets
        .iter()
        .map(|t| Point3::from(t.position_mm.map(|c| c * 1e-3)))
        .collect();
    let (fit, _) = rigid_fit(&src, &fitted)?;
    Some(fit.rotation.angle().to_degrees())
}

/// The mirrored order of the fitted tool targets of `summary` (module docs): among the orders
/// of the data's ids that keep the description's distances (within three sigmas of the fitted
/// targets), the one whose rigid fit onto the fitted targets turns the tool frame least
/// ([`tool_turn_deg`]), when it turns less than the order as written. Tool frames turn by a few
/// degrees at most; the labellings of a symmetric target set lie 60 degrees or more apart.
pub fn mirrored_targets(summary: &FreePoseSummary, desc: &RobotDescription) -> Option<MirroredTargets> {
    let described = desc.tool_targets_m();
    let ids: Vec<usize> = summary.targets.iter().map(|t| t.id).collect();
    if ids.len() < 3 || ids.len() > MAX_ORDERED_TARGETS || ids.iter().any(|&id| id >= described.len()) {
        return None;
    }
    let sigma_m = summary
        .targets
        .iter()
        .flat_map(|t| t.sigma_mm.iter().flatten())
        .fold(0.0_f64, |a, &s| a.max(s * 1e-3));
    let written_deg = tool_turn_deg(summary, desc, &ids)?;
    symmetric_orders(&ids, &described, 3.0 * sigma_m)
        .into_iter()
        .filter_map(|o| Some((tool_turn_deg(summary, desc, &o)?, o)))
        .filter(|(deg, _)| *deg < written_deg)
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(reordered_deg, order)| MirroredTargets {
            order,
            ids,
            written_deg,
            reordered_deg,
        })
}
