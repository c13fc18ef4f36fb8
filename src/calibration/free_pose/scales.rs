//! The column scales tested before any pose is screened as an outlier: a command column
//! scaled on export (`cmd_k` in another ratio) or one instrument axis reading long (`x_mm`,
//! `y_mm`, `z_mm`) moves many poses' points by a pattern the geometry cannot take, and a pose
//! screen run first drops the poses it moves most and leaves the rest to be read as some other
//! cause. So the geometric fit on every pose is tested first against each candidate scale, and
//! the outlier screen then runs on the model that includes a scale the data name.
//!
//! Each candidate is one more column of the fit's design: the derivative of the residuals by
//! the column's scale `s` (a command column multiplied by `1 + s`, by central differences of
//! the model's prediction; a coordinate column scaled by `1 + s` about the points' centroid,
//! `(p_c - centroid_c)` along axis `c`). Its part the fitted parameters cannot take,
//! `u = (I - P_J) d` (`P_J` the projection on the design's columns), gives the scale's least
//! squares estimate `s = -u^T e / u^T u` (`e` the residual) and the reduction of the sum of
//! squares it brings (the augmented regression of the added-variable plot: Cook & Weisberg,
//! *Residuals and Influence in Regression*, 1982, sec. 2.3.2).
//!
//! The estimate is tested by its cluster-robust standard error (Liang & Zeger, *Biometrika* 73,
//! 1986; the small-sample form of Cameron & Miller, *J. Human Resources* 50, 2015, sec. VI:
//! the factor `G / (G - 1)` and Student's `t` with `G - 1` degrees of freedom over `G`
//! clusters), the clusters being the configurations (repeated visits of one configuration share
//! the model's error at it, so their residuals are not independent, as on a real robot's
//! repeated poses), and the variance being the scatter of the clusters' scores
//! `u_g^T (e_g + u_g s)`: a scale that explains many configurations' residuals has a small
//! scatter, while one pose's gross error makes its own cluster's score the whole estimate and
//! its scatter as large, so it never passes as a scale (`|t|` about 1). A command column's
//! estimate is tested against that sigma and a drive's departure combined
//! ([`DRIVE_DEPARTURE_TURN`], [`DRIVE_DEPARTURE_LEAD`]): a gear's once-per-turn error reads as
//! a scale over a partial turn. The rate is shared by the candidates (Bonferroni):
//! [`SCREEN_FALSE_ALARM`] over all of them.
//!
//! Each candidate is tested twice, and must pass both: on the geometric fit, and on the fit of
//! every parameter the poses identify (the effects, the transmissions' harmonics, the
//! description's gear forms), whose part of the direction and estimate is the one reported.
//! The residual of the geometric fit alone is not the noise where the robot's drives carry
//! periodic errors the model fits: the IRB/L6's joint-5 bevel gear and joint-6 once-per-turn
//! error leave 2.6 mm RMS there (0.2 mm with the harmonics), which a scale of `cmd_5` or
//! `cmd_6` takes up in part (`t` 12 and 9 on clean files). On the full fit a command scale the
//! joint's harmonics follow over a partial turn has little direction left and passes no test:
//! on free poses it cannot be told from the drive's periodic error (the transmission test's
//! note, `procedure/sanity/scale.rs`, says both). On a robot with a sliding joint a scale of
//! every coordinate about the centroid ([`Candidate::Length`]) is a candidate too, which,
//! passing as the best or alike, names nothing: the coordinate-scale profile says it.
//!
//! The candidate that passes with the largest `|s| / sigma` (the share of the residual its
//! direction explains; the drive's departure is a bar to pass, not a measure of the fit: a
//! slide's command scale along an instrument axis would lose to that axis by it) is named;
//! every other that passes on its
//! own while the named one, given it (its direction and the residual orthogonal to the
//! other's), does not, explains the residuals alike on these data (a command scale and an
//! instrument axis whose directions are nearly parallel over the poses): both are said. A
//! second scale is then sought the same way on the fits refitted with the first undone (up to
//! [`MAX_NAMED`]); before it, the columns named are tested alone on that refit, and one that
//! passes again is the remainder of its linearised estimate (a scale of a few per cent on a
//! precise file), composed into it, not a second scale (Gauss-Newton steps, up to
//! [`MAX_ROUNDS`] rounds in all).
//!
//! Where the fit of every identified parameter fails on the poses as read (a scale of several
//! per cent pulls a transmission's harmonics where the robot cannot go: the 7-axis arm's
//! `x_mm` x1.025, the real FANUC's `cmd_4` x1.03), it is made on the poses with the geometric
//! screen's finding undone, and the poses as read are tested at that fit, their residual less
//! the part its columns take (one Gauss-Newton step from there: the same augmented regression,
//! linearised at a nearby point).

use super::fit::{Fitted, Problem};
use super::model::FreePoseModel;
use super::poses::FreePoses;
use crate::numerics::finite_diff::try_central_difference;
use crate::numerics::stats::f_upper_tail;
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// The family-wise false-alarm rate of the screen over its candidates: the one-axis scale
/// test's ([`crate::measurement::unit_check::axis_scale::AXIS_SCALE_FALSE_ALARM`]), one clean
/// file in ten thousand told a column is scaled.
pub const SCREEN_FALSE_ALARM: f64 = crate::measurement::unit_check::axis_scale::AXIS_SCALE_FALSE_ALARM;

/// The sigma of a turning joint's mean travel per command about its description's, as a
/// model of what a drive gives (0.12 %, the transmission test's `PLAUSIBLE_TURN_DEVIATION` in
/// `procedure/sanity/scale.rs`, where it is measured): over a partial turn a gear's
/// once-per-turn error reads as a scale of its command column, which a geometric fit without
/// the transmission's harmonics takes for one (the simulator's drives depart by up to 0.5 %).
/// A command column's estimate is tested against its sigma and this combined.
const DRIVE_DEPARTURE_TURN: f64 = 0.0012;

/// The same for a sliding joint's lead (0.1 %, the transmission test's
/// `PLAUSIBLE_LEAD_DEVIATION`).
const DRIVE_DEPARTURE_LEAD: f64 = 0.001;

/// Scales named at most (each on the refit with the ones before undone).
const MAX_NAMED: usize = 2;

/// Rounds of the screen at most: each named scale's search and the refinements of the ones
/// named (the remainder of a linearised estimate of a few per cent passes the test on a
/// precise file: the KR's `y_mm` x1.025 read 1.02497, then 1.00003 more).
const MAX_ROUNDS: usize = 6;

/// The relative step of the command columns' central differences.
const COMMAND_STEP: f64 = 1e-5;

/// A candidate's direction counts only where the fitted parameters leave this share of its
/// length (`|u| / |d|`): below it the geometry takes the scale (a joint whose commands barely
/// move), and the estimate is the noise over nearly nothing.
const MIN_FREE_SHARE: f64 = 1e-3;

/// A column whose scale is a candidate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Candidate {
    /// A joint's command column (0-based joint).
    Command(usize),
    /// A coordinate column: 0 `x_mm`, 1 `y_mm`, 2 `z_mm`.
    Coordinate(usize),
    /// The three coordinate columns alike (a length scale about the points' centroid): never
    /// named by the screen, which leaves it to the coordinate-scale profile (the instrument's
    /// length standard), but tested so that a length scale is not named as the one column
    /// whose pattern is nearest to it (a slide's command).
    Length,
}

impl Candidate {
    /// The column's name.
    pub fn column(self) -> String {
        match self {
            Candidate::Command(k) => format!("cmd_{}", k + 1),
            Candidate::Coordinate(c) => crate::measurement::unit_check::axis_scale::COLUMNS[c].to_owned(),
            Candidate::Length => "x_mm, y_mm, z_mm".to_owned(),
        }
    }
}

/// A column read a factor off, as the screen estimates it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ColumnScale {
    /// The column (`cmd_2`, `y_mm`).
    pub column: String,
    /// The factor the file's column holds of what the model fits (the column divided by it
    /// fits best; a coordinate column about the points' centroid).
    pub factor: f64,
    /// Its cluster-robust 1-sigma.
    pub sigma: f64,
}

/// A scale the screen names (`calibration.json`'s `free_poses.scales`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct NamedScale {
    /// The column whose scale explains most, and its factor.
    pub scale: ColumnScale,
    /// `|t|`: the estimate over its cluster-robust sigma (for a command column, combined with
    /// what a drive departs by).
    pub t: f64,
    /// The configurations (clusters) the test counted.
    pub configurations: usize,
    /// The family-wise p-value (the two-sided tail of `t` with `configurations - 1` degrees of
    /// freedom, times the candidates).
    pub p_value: f64,
    /// Other columns whose scale explains the residuals alike on these data (each passes on its
    /// own, and the named one given it does not), with their factors.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub alike: Vec<ColumnScale>,
    /// The RMS per coordinate of the geometric fit on every pose as read, and with the scales
    /// named up to this one taken out \[mm\].
    pub rms_mm: [f64; 2],
}

/// One candidate's test: its estimate (`s`, the column read as `1 / (1 + s)`), sigma, `|t|` and
/// family-wise p-value.
#[derive(Clone, Copy, Debug)]
struct Tested {
    candidate: Candidate,
    s: f64,
    sigma: f64,
    t: f64,
    p: f64,
}

impl Tested {
    fn scale(&self) -> ColumnScale {
        ColumnScale {
            column: self.candidate.column(),
            factor: 1.0 / (1.0 + self.s),
            sigma: self.sigma / (1.0 + self.s).powi(2),
        }
    }
}

/// A named scale with its estimate, for undoing it.
#[derive(Clone, Debug)]
pub(super) struct Found {
    pub named: NamedScale,
    candidate: Candidate,
    s: f64,
}

impl Found {
    /// This scale with `more` of the same column found on the poses with it undone (the
    /// remainder of its linearised estimate: one more Gauss-Newton step): the two compose,
    /// `(1 + s) (1 + s_more)`, and the fit with both undone is the one reported undone; its
    /// test, sigma and the columns alike stay the first's.
    fn refine(&mut self, more: &Found) {
        self.s = (1.0 + self.s) * (1.0 + more.s) - 1.0;
        self.named.scale.factor = 1.0 / (1.0 + self.s);
        self.named.rms_mm[1] = more.named.rms_mm[1];
    }
}

/// The fit of every parameter the poses identify (the geometry, the effects, the
/// transmissions' harmonics and the description's gear forms) of a problem's poses from a
/// model: with the weakest parameters dropped while it does not converge, as the calibration's
/// own fit (`converging` in the module above), so that a scale is tested where the calibration
/// fits.
pub(super) type FullFit<'a> = dyn Fn(&Problem<'_>, &FreePoseModel) -> Result<Fitted, super::FreePoseError> + 'a;

/// The scales the poses `which` name (module doc), each found on the fit `full` (every
/// parameter the poses identify, whose residual is the noise; `None` where those are the
/// geometry's) among the
/// candidates that pass on the fit of `geometry` alone too (those columns absorb part of a
/// command column's scale), from
/// `start`, of the poses with the ones before undone, so that a second is tested on the refit,
/// not on the first's linearisation; and the poses with every one undone (`None` without any).
pub(super) fn named_scales(
    problem: &Problem<'_>,
    start: &FreePoseModel,
    which: &[usize],
    (geometry, full): (&[usize], Option<&FullFit<'_>>),
) -> (Vec<Found>, Option<FreePoses>) {
    let mut found: Vec<Found> = Vec::new();
    let mut undone: Option<FreePoses> = None;
    let mut start = start.clone();
    // After a scale is named, the next round tests the columns named only (their estimates'
    // remainder: the estimate is linearised), then, when none passes, every column again.
    let mut refining = false;
    for _ in 0..MAX_ROUNDS {
        if found.len() >= MAX_NAMED && !refining {
            break;
        }
        let here = Problem {
            poses: undone.as_ref().unwrap_or(problem.poses),
            description_targets_m: problem.description_targets_m.clone(),
            ..*problem
        };
        let Ok(fitted) = super::fit::fit(&here, &start, which, geometry) else {
            break;
        };
        let named: Vec<Candidate> = found.iter().map(|f| f.candidate).collect();
        let only = refining.then_some(named.as_slice());
        let (mut next, passing) = screen(&here, &fitted, which, only);
        if let Some(full) = full {
            // A large scale can pull the full fit's harmonics beyond what the description's
            // robot does (its fit fails): the poses are then read at the full fit of the poses
            // with the geometry's finding undone.
            let Some(with_effects) = full(&here, &fitted.model)
                .ok()
                .or_else(|| read_at_undone(&here, next.as_ref()?, which, (full, &fitted.model)))
            else {
                break;
            };
            let allowed: Vec<Candidate> = passing
                .into_iter()
                .filter(|c| only.is_none_or(|o| o.contains(c)))
                .collect();
            next = screen(&here, &with_effects, which, Some(&allowed)).0;
        }
        match (next, refining) {
            (None, true) => refining = false,
            (None, false) => break,
            (Some(next), _) => {
                undone = Some(undo(here.poses, &next, which));
                start = fitted.model;
                match found.iter_mut().find(|f| f.candidate == next.candidate) {
                    Some(same) => same.refine(&next),
                    None => found.push(next),
                }
                refining = true;
            }
        }
    }
    (found, undone)
}

/// The fit `full` (from `start`) of the poses of `here` with `found` (the geometric screen's
/// finding) undone, and as its residual that of the poses as read at its model less the part
/// its fitted columns take: one Gauss-Newton step of the full fit of the poses as read from
/// there, so that the screen's augmented regression (module doc) is linearised at the undone
/// fit (a first-order expansion about a nearby point; Cook & Weisberg 1982, sec. 2.3.2);
/// `None` where that fit fails too.
fn read_at_undone(
    here: &Problem<'_>,
    found: &Found,
    which: &[usize],
    (full, start): (&FullFit<'_>, &FreePoseModel),
) -> Option<Fitted> {
    let trial = undo(here.poses, found, which);
    let problem = Problem {
        poses: &trial,
        description_targets_m: here.description_targets_m.clone(),
        ..*here
    };
    let fitted = full(&problem, start).ok()?;
    let read = fitted.model.residuals(here.controller, here.poses, which).ok()?;
    let basis = orthonormal(&fitted.jacobian);
    let residual = &read - &basis * basis.tr_mul(&read);
    Some(Fitted { residual, ..fitted })
}

/// The screen of the module doc on the fit `fitted` of the poses `which` (its residual and
/// design in that order): the scale that explains most among the candidates `allowed` (all
/// with `None`), where one passes; and every candidate that passes.
fn screen(
    problem: &Problem<'_>,
    fitted: &Fitted,
    which: &[usize],
    allowed: Option<&[Candidate]>,
) -> (Option<Found>, Vec<Candidate>) {
    let candidates = directions(problem, fitted, which);
    let m = candidates.len();
    let rows = fitted.residual.len();
    let clusters = clusters(problem.poses, which);
    let g = clusters.iter().copied().max().map_or(0, |c| c + 1);
    let Some(dof) = rows.checked_sub(fitted.jacobian.ncols() + 1) else {
        return (None, vec![]);
    };
    if m == 0 || dof == 0 || g < 3 {
        return (None, vec![]);
    }
    let basis = orthonormal(&fitted.jacobian);
    let e = &fitted.residual;
    let drive = |c: Candidate| match c {
        Candidate::Command(k) if sliding(problem, k) => DRIVE_DEPARTURE_LEAD,
        Candidate::Command(_) => DRIVE_DEPARTURE_TURN,
        Candidate::Coordinate(_) | Candidate::Length => 0.0,
    };
    let test = |c: Candidate, u: &DVector<f64>, e: &DVector<f64>| tested((c, drive(c)), u, e, &clusters, (g, m));
    let all: Vec<(Tested, DVector<f64>)> = candidates
        .into_iter()
        .filter_map(|(c, d)| {
            let u = &d - &basis * basis.tr_mul(&d);
            (u.norm() > MIN_FREE_SHARE * d.norm()).then(|| Some((test(c, &u, e)?, u)))?
        })
        .collect();
    let passing: Vec<Candidate> = all
        .iter()
        .filter(|(t, _)| t.p < SCREEN_FALSE_ALARM)
        .map(|(t, _)| t.candidate)
        .collect();
    let Some((best, u_best)) = all
        .iter()
        .filter(|(t, _)| t.p < SCREEN_FALSE_ALARM && allowed.is_none_or(|a| a.contains(&t.candidate)))
        .max_by(|a, b| (a.0.s / a.0.sigma).abs().total_cmp(&(b.0.s / b.0.sigma).abs()))
    else {
        return (None, passing);
    };
    let alike = alike(&all, (best, u_best), e, &test);
    let length = Candidate::Length.column();
    if best.candidate == Candidate::Length || alike.iter().any(|c| c.column == length) {
        return (None, passing);
    }
    let unit = u_best / u_best.norm();
    let left = e - &unit * unit.dot(e);
    let rms = |r: &DVector<f64>, dof: usize| (r.norm_squared() / dof as f64).sqrt() * 1e3;
    let found = Found {
        named: NamedScale {
            scale: best.scale(),
            t: best.t,
            configurations: g,
            p_value: best.p,
            alike,
            rms_mm: [rms(e, dof + 1), rms(&left, dof)],
        },
        candidate: best.candidate,
        s: best.s,
    };
    (Some(found), passing)
}

/// One candidate's test against a residual, given its direction: [`tested`] with the file's
/// clusters and the candidate's drive.
type CandidateTest<'a> = dyn Fn(Candidate, &DVector<f64>, &DVector<f64>) -> Option<Tested> + 'a;

/// The candidates of `all` (each with its direction given the scales named) that pass on their
/// own while `best` (its direction `u_best`), given each, does not: they explain the residual
/// `e` alike on these data.
fn alike(
    all: &[(Tested, DVector<f64>)],
    (best, u_best): (&Tested, &DVector<f64>),
    e: &DVector<f64>,
    test: &CandidateTest<'_>,
) -> Vec<ColumnScale> {
    all.iter()
        .filter(|(t, _)| t.candidate != best.candidate && t.p < SCREEN_FALSE_ALARM)
        .filter(|(_, u)| {
            let unit = u / u.norm();
            let rest = u_best - &unit * unit.dot(u_best);
            let e_other = e - &unit * unit.dot(e);
            rest.norm() <= MIN_FREE_SHARE * u_best.norm()
                || test(best.candidate, &rest, &e_other).is_none_or(|b| b.p >= SCREEN_FALSE_ALARM)
        })
        .map(|(t, _)| t.scale())
        .collect()
}

/// The test of the direction `u` (orthogonal to the fitted columns and the scales named)
/// against the residual `e` over the clusters (module doc); `None` without scatter.
fn tested(
    (candidate, drive): (Candidate, f64),
    u: &DVector<f64>,
    e: &DVector<f64>,
    clusters: &[usize],
    (g, m): (usize, usize),
) -> Option<Tested> {
    let uu = u.norm_squared();
    let s = -u.dot(e) / uu;
    let mut scores = vec![0.0; g];
    let mut row = 0;
    for &c in clusters {
        for k in row..row + 3 {
            scores[c] += u[k] * (e[k] + u[k] * s);
        }
        row += 3;
    }
    let gf = g as f64;
    let variance = gf / (gf - 1.0) * scores.iter().map(|x| x * x).sum::<f64>() / (uu * uu);
    if !(variance > 0.0 && variance.is_finite()) {
        return None;
    }
    let sigma = variance.sqrt();
    let t = s.abs() / sigma.hypot(drive);
    let p = (f_upper_tail(t * t, 1.0, gf - 1.0) * m as f64).min(1.0);
    Some(Tested {
        candidate,
        s,
        sigma,
        t,
        p,
    })
}

/// Whether joint `k` (0-based) slides (its zero offset in the layout says).
fn sliding(problem: &Problem<'_>, k: usize) -> bool {
    problem.layout.iter().any(|p| {
        matches!(p, crate::calibration::refine::RefitParameter::ZeroOffset { joint, sliding: true } if *joint == k + 1)
    })
}

/// Each point's cluster (its pose's configuration, renumbered from 0 over `which`), one entry
/// per point in the residual's order.
fn clusters(poses: &FreePoses, which: &[usize]) -> Vec<usize> {
    let configurations = poses.configurations();
    let mut seen: std::collections::HashMap<usize, usize> = std::collections::HashMap::new();
    which
        .iter()
        .flat_map(|&i| {
            let next = seen.len();
            let c = *seen.entry(configurations[i]).or_insert(next);
            std::iter::repeat_n(c, poses.poses[i].points_m.len())
        })
        .collect()
}

/// An orthonormal basis of the columns of `j` (thin QR of the column-scaled design).
fn orthonormal(j: &DMatrix<f64>) -> DMatrix<f64> {
    let scale = crate::numerics::lsq::column_scales(j);
    let scaled = DMatrix::from_fn(j.nrows(), j.ncols(), |r, c| j[(r, c)] / scale[c]);
    scaled.qr().q()
}

/// Each candidate's direction `d residual / d s` at the fit (module doc), the command columns
/// of joints whose commands move over `which`.
fn directions(problem: &Problem<'_>, fitted: &Fitted, which: &[usize]) -> Vec<(Candidate, DVector<f64>)> {
    let poses = problem.poses;
    let rows = fitted.residual.len();
    let spans = poses.spans(which);
    let mut out = Vec::new();
    for (k, span) in spans.iter().enumerate() {
        if *span <= 0.0 {
            continue;
        }
        let at = |f: f64| {
            let moved = with_command_scaled(poses, k, f);
            fitted.model.residuals(problem.controller, &moved, which).ok()
        };
        if let Some(direction) = try_central_difference(|t| at(1.0 + t), COMMAND_STEP)
            && direction.len() == rows
        {
            out.push((Candidate::Command(k), direction));
        }
    }
    let centroid = centroid_m(poses, which);
    for c in 0..3 {
        let mut d = DVector::zeros(rows);
        let mut row = 0;
        for &i in which {
            for (_, p) in &poses.poses[i].points_m {
                d[row + c] = p[c] - centroid[c];
                row += 3;
            }
        }
        out.push((Candidate::Coordinate(c), d));
    }
    // A length scale is the links' on a robot that only turns (they take it whole); a
    // sliding joint's travel does not take it (as the coordinate-scale profile's `Every`).
    if !problem.layout.iter().any(|p| {
        matches!(
            p,
            crate::calibration::refine::RefitParameter::ZeroOffset { sliding: true, .. }
        )
    }) {
        return out;
    }
    let length = out
        .iter()
        .filter(|(c, _)| matches!(c, Candidate::Coordinate(_)))
        .fold(DVector::zeros(rows), |sum, (_, d)| sum + d);
    out.push((Candidate::Length, length));
    out
}

/// The centroid of the points of the poses `which` \[m\].
fn centroid_m(poses: &FreePoses, which: &[usize]) -> [f64; 3] {
    let points: Vec<&nalgebra::Point3<f64>> = which
        .iter()
        .flat_map(|&i| poses.poses[i].points_m.iter().map(|(_, p)| p))
        .collect();
    let n = points.len().max(1) as f64;
    std::array::from_fn(|c| points.iter().map(|p| p[c]).sum::<f64>() / n)
}

/// `poses` with joint `k`'s commands (internal units) multiplied by `factor`; the recorded
/// commands (and so the configurations) kept.
fn with_command_scaled(poses: &FreePoses, k: usize, factor: f64) -> FreePoses {
    let mut moved = poses.clone();
    for p in &mut moved.poses {
        p.cmd[k] *= factor;
    }
    moved
}

/// `poses` with the scale `found` undone (its column multiplied by `1 + s`, a coordinate about
/// the centroid of the poses `which`).
fn undo(poses: &FreePoses, found: &Found, which: &[usize]) -> FreePoses {
    match found.candidate {
        Candidate::Command(k) => with_command_scaled(poses, k, 1.0 + found.s),
        Candidate::Coordinate(_) | Candidate::Length => {
            let axes = match found.candidate {
                Candidate::Coordinate(c) => c..c + 1,
                _ => 0..3,
            };
            let centroid = centroid_m(poses, which);
            let mut out = poses.clone();
            for p in &mut out.poses {
                for (_, point) in &mut p.points_m {
                    for c in axes.clone() {
                        point[c] = centroid[c] + (point[c] - centroid[c]) * (1.0 + found.s);
                    }
                }
            }
            out
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cluster whose score carries the whole estimate gives `|t|` near 1, however large.
    #[test]
    fn one_cluster_alone_is_no_scale() {
        let n = 30;
        let u = DVector::from_fn(3 * n, |r, _| (r as f64 * 0.37).sin());
        let mut e = DVector::from_fn(3 * n, |r, _| 1e-6 * ((r as f64) * 1.7).cos());
        for r in 0..3 {
            e[r] += 1e-2 * u[r].signum();
        }
        let clusters: Vec<usize> = (0..n).collect();
        let t = tested((Candidate::Coordinate(0), 0.0), &u, &e, &clusters, (n, 1)).unwrap();
        assert!(t.t < 1.5, "t = {}", t.t);
    }
}
