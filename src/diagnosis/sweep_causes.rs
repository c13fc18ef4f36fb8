//! One sweep's records off from what the robot did, sought by recalibrating against the
//! file's own validation poses (`calibrate`, when the calibrated model misses them). Four
//! corrections are tried, as hypotheses:
//! - **a held command** ([`SweepCorrection::HeldCommand`]): on some robots (a table, a two-axis
//!   positioner, the IRB/L6) a held joint's offset through one sweep turns the swept arc
//!   rigidly about the held joint's axis; the sweep's own axis fit absorbs it and the
//!   reference-pose comparison (`calibration::shared_target`) has nothing to see;
//! - **a drift** ([`SweepCorrection::Drift`]): the sweep's points moving by a fixed vector
//!   growing linearly from its first step to its last (the instrument or the robot's base
//!   creeping while it ran); the sweep's own fit takes most of a slow drift into its axis
//!   (`screen::bump`, a step, does not name it);
//! - **a drift of the whole file**: every row, the validation poses' too, moving by a fixed
//!   vector growing linearly with its file line (an instrument creeping through the campaign);
//! - **a move of the sweep's block** ([`SweepCorrection::Block`]), all its points alike (the
//!   instrument or the robot bumped between sweeps), where the reference-pose test does not
//!   name it (the sweep not compared there), and against a drift where it does.
//!
//! Either way the validation poses, which the calibration predicts with the sweep's axis as
//! fitted, miss. Each hypothesis is tested by recalibrating with the sweep's records corrected
//! by `c` (a vector of 1 or 3 parameters): the validation chi-square (`validate`'s, against the
//! original calibration's noise) is a quadratic in `c` where the model is linear in it (a
//! rotation by a few degrees, a shift of a few millimetres), so calibrations at 0, at plus and
//! minus a trial step along each parameter and at the sum of two steps for each pair give its
//! gradient and Hessian by central differences, and Newton's step its least; the best few are
//! refined by narrower quadratics about it and confirmed by a calibration at the refined
//! correction; the correction's covariance is the inverse of half the chi-square's Hessian
//! there, scaled by the chi-square per degree of freedom left where that is beyond 1. The
//! hypothesis is named when (1) its improvement over the file as recorded, per parameter and
//! over the confirmed chi-square per degree of freedom left, is an F ratio `F(p, dof - p)`
//! beyond its quantile at [`SWEEP_CAUSE_FALSE_ALARM`] shared among the hypotheses tried
//! (Bonferroni, as the slip searches share theirs), and (2) the corrected calibration passes
//! `validate`'s test of the poses: the correction explains the miss, not only part of it
//! (Seber & Wild, *Nonlinear Regression*, 1989, sec. 5.3: the extra-sum-of-squares F test of a
//! nested model). Its gain must also exceed the chi-square's excess left beyond its degrees of
//! freedom: that excess is the model's own error, which the poses share (not independent, as
//! the F test counts them), and a fit moves by as much where the poses miss for another reason
//! (a clean file of five-point sweeps, its poses missed at chi2/dof 3.28, 3.03 with a held
//! `cmd_4` moved 15 deg). Other hypotheses that pass all three are given beside it, as
//! alternatives the data do not tell apart, best first by the chi-square per degree of freedom
//! left; where none passes the poses' test, the best held command that passes the other two is
//! said as a part of the miss (a move's three parameters take in a part of most misses).
//! The sweeps are taken as the calibration fitted them (the points the screen drops left out);
//! a sweep whose points shift part-way (`screen::bump`, a bump the fit takes in) and one the
//! reference-pose test names as one of two that disagree (`shared_target::moved_sweeps`) are
//! not tried:
//! their cause is said already. In a sweep that test names with a held offset or as a moved
//! block (not one of two that disagree), only that correction, a move of its block and a drift
//! are tried, and another than the one it names is said only where it fits the poses best (the
//! one named is said already; at the reference pose a drift reads as either, and a block
//! moved as a held offset where the held joint's axis is far from the sweep's point).
//!
//! A move of a sweep's block along the axis it turns about (a drift, likewise) leaves that axis
//! where it is: the poses do not show it. A move is given across such directions (the least
//! that fits: the Hessian's pseudo-inverse's Newton step and covariance) with the directions.

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

use super::{ValidationOptions, Verdict, curvature_counts, validate, validate_free_tool};
use crate::calibration::procedure::{
    AxisExperiment, Calibration, axis_experiments_with, calibrate, screen_sweeps, wandering_sweep_bumps,
};
use crate::calibration::shared_target::moved_sweeps;
use crate::kinematics::JointKind;
use crate::measurement::MeasurementSet;
use crate::numerics::finite_diff::quadratic_least;
use crate::numerics::stats::f_upper_quantile;
use crate::robot::RobotDescription;

/// The family-wise false-alarm rate of the search: the own-poses test's.
pub const SWEEP_CAUSE_FALSE_ALARM: f64 = 1e-4;

/// Hypotheses refined and confirmed by a calibration at their fitted correction, best
/// predicted first.
const CONFIRMED: usize = 3;

/// Refining quadratics ([`refined`]).
const REFINE_PASSES: usize = 2;

/// The most calibrations the search's first pass may cost (two per held command, nine per
/// drift or block, summed over the hypotheses): a robot's sweeps times their held joints grow
/// as the square of its joints, and each trial is a calibration and a validation (an 18-joint
/// arm's 915 took a minute), so that past ten joints the search is not run and says so
/// ([`SweepSearchTooLarge`]).
pub const MAX_SWEEP_SEARCH_CALIBRATIONS: usize = 400;

/// The search not run: its first pass would cost `calibrations`, beyond
/// [`MAX_SWEEP_SEARCH_CALIBRATIONS`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SweepSearchTooLarge {
    /// The hypotheses it would try.
    pub hypotheses: usize,
    /// The calibrations their first pass would cost.
    pub calibrations: usize,
}

/// A correction of one sweep's records.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SweepCorrection {
    /// Held joint `k`'s (0-based) recorded command moved by `c` (file units).
    HeldCommand(usize),
    /// The points moved by `-t c` \[mm\], `t` running from 0 at the sweep's first step to 1 at
    /// its last: a linear drift `c` undone.
    Drift,
    /// The points moved by `-c` \[mm\]: a move of the sweep's block undone (the
    /// reference-pose test names most; this one where the sweep is not compared, or against a
    /// drift).
    Block,
}

impl SweepCorrection {
    /// Its parameters.
    fn parameters(self) -> usize {
        match self {
            Self::HeldCommand(_) => 1,
            Self::Drift | Self::Block => 3,
        }
    }

    /// The calibrations its quadratic costs ([`quadratic_least`]: two per parameter, one per
    /// pair).
    fn trials(self) -> usize {
        let p = self.parameters();
        2 * p + p * (p - 1) / 2
    }

    /// The trial change (1 deg or 1 mm of a held command; 1 mm of drift), about the size of
    /// the slips sought, so that the quadratic is read where they lie.
    fn trial_step(self) -> f64 {
        1.0
    }

    /// The half-width of a refining quadratic: within it a rotation's or a shift's chi-square
    /// is quadratic to well below its noise.
    fn refine_step(self) -> f64 {
        0.25
    }

    /// `set` with experiment `experiment` corrected by `c`.
    fn applied(self, set: &MeasurementSet, experiment: &str, c: &[f64]) -> MeasurementSet {
        match self {
            Self::HeldCommand(k) => set.with_command_offset_in(experiment, k, c[0]),
            Self::Drift => set.with_sweep_move_undone_in(experiment, [0.0; 3], [c[0], c[1], c[2]]),
            Self::Block => set.with_sweep_move_undone_in(experiment, [c[0], c[1], c[2]], [0.0; 3]),
        }
    }
}

/// What a sweep's records look off by: the correction's negative.
#[derive(Clone, Debug, PartialEq)]
pub enum SweepFault {
    /// A held joint's recorded command minus where the robot stood.
    HeldOffset {
        /// The held joint (1-based).
        joint: usize,
        /// The offset (file units).
        offset: f64,
        /// Its 1-sigma (file units).
        sigma: f64,
        /// `deg` or `mm`.
        unit: &'static str,
    },
    /// The points' drift from the sweep's first step to its last, in the instrument frame.
    Drift {
        /// The drift \[mm\]: its part across `free_along`.
        drift_mm: [f64; 3],
        /// Its 1-sigma per axis \[mm\].
        sigma_mm: [f64; 3],
        /// Unit directions along which more drift changes nothing the poses show.
        free_along: Vec<[f64; 3]>,
    },
    /// The sweep's block moved, all its points alike, in the instrument frame.
    Block {
        /// The move \[mm\]: its part across `free_along`.
        moved_mm: [f64; 3],
        /// Its 1-sigma per axis \[mm\].
        sigma_mm: [f64; 3],
        /// Unit directions along which a further move changes nothing the poses show (a
        /// sweep's block moved along the axis it turns about leaves that axis where it is).
        free_along: Vec<[f64; 3]>,
    },
}

/// What the reference-pose test (`shared_target::moved_sweeps`) names in a sweep, where a
/// drift or (against a held offset) a moved block found there fits the validation poses best:
/// at the reference pose a drift through the sweep moves its point as either does, and a moved
/// block as a held offset does where the held joint's axis is far from it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SweepShadow {
    /// The held joints (1-based) it names with an offset.
    HeldOffset(Vec<usize>),
    /// A move of the sweep's block.
    MovedBlock,
}

/// A sweep whose records, corrected, let the calibration fit the file's own validation poses.
#[derive(Clone, Debug)]
pub struct SweepCause {
    /// The experiment; `None`: the whole file (a [`SweepFault::Drift`] in file order, from its
    /// first line to its last).
    pub experiment: Option<String>,
    /// Its first and last lines.
    pub lines: Option<(u64, u64)>,
    /// What its records look off by.
    pub fault: SweepFault,
    /// The validation chi-square per degree of freedom as recorded and corrected.
    pub per_dof: (f64, f64),
    /// The validation RMS as recorded and corrected \[mm\].
    pub rms_mm: (f64, f64),
    /// Other (experiment, fault) that pass as well (empty where [`SweepCause::passes`] is
    /// false; experiment `None`: the whole file).
    pub alternatives: Vec<(Option<String>, SweepFault)>,
    /// Whether the corrected calibration passes the poses' test; `false`: the correction
    /// explains a part of the miss beyond chance, another cause the rest.
    pub passes: bool,
    /// What the reference-pose test names in this sweep, where the drift or the moved block
    /// found fits the poses best.
    pub shadows: Option<SweepShadow>,
    /// The corrections tried (held commands, drifts, moved blocks).
    pub tried: usize,
}

/// One validation of a calibration of the file with a sweep corrected.
#[derive(Clone, Copy, Debug)]
struct Score {
    chi2: f64,
    dof: usize,
    rms_mm: f64,
    passes: bool,
}

/// A hypothesis: the experiment (its index; `None`: the whole file, its validation poses
/// too, a drift in file order) and the correction.
type Hypothesis = (Option<usize>, SweepCorrection);

/// The validation of the file as recorded (`None`) or with a hypothesis's correction.
type ScoreOf<'a> = dyn Fn(Option<Hypothesis>, &[f64]) -> Option<Score> + Sync + 'a;

/// A hypothesis with its confirmed correction, that correction's covariance and its score.
struct Confirmed {
    hypothesis: Hypothesis,
    c: Vec<f64>,
    covariance: DMatrix<f64>,
    /// The parameters the poses determine: the hypothesis's less its null directions.
    rank: usize,
    /// The directions the poses do not show a correction along (unit vectors).
    null: Vec<DVector<f64>>,
    score: Score,
}

impl Confirmed {
    /// The chi-square per degree of freedom left.
    fn left(&self) -> f64 {
        self.score.chi2 / (self.score.dof as f64 - self.rank as f64)
    }
}

/// The curvature, relative to the stiffest direction's, below which a direction of the
/// chi-square's Hessian is taken as null (either sign): central differences over a
/// millimetre's step read a direction the model does not change along (a sweep's block moved
/// along its own axis, which leaves the axis line) at about -1e-4 of the stiffest, through the
/// fit's curvature, not at 0.
const WEAK_DIRECTION: f64 = 1e-3;

/// `experiments` less the sweeps of `set` the reference-pose test ([`moved_sweeps`]) names as
/// one of two that disagree: that cause is named already, and nothing is sought in them.
/// Returned: the sweeps it names with a held offset (the held joints, 0-based) or as a moved
/// block: in them only that correction, a move of the block and a drift are tried (a drift
/// through the sweep reads as either at the reference pose, a moved block as a held offset).
fn retain_unnamed(
    experiments: &mut Vec<AxisExperiment>,
    set: &MeasurementSet,
    desc: &RobotDescription,
    cal: &Calibration,
) -> Vec<(String, Named)> {
    let noise = cal
        .noise
        .as_ref()
        .map_or(cal.options.noise_rms_3d_mm, |n| n.used_rms_3d_mm);
    let mut held = Vec::new();
    for moved in moved_sweeps(set, desc, noise) {
        if moved.held.is_empty() && moved.backlash.is_empty() {
            if moved.ambiguous {
                experiments.retain(|e| e.name != moved.experiment && !moved.others.contains(&e.name));
            } else {
                held.push((moved.experiment.clone(), Named::Block));
            }
        } else if !moved.held.is_empty() {
            let joints = moved.held.iter().map(|h| h.joint - 1).collect();
            held.push((moved.experiment.clone(), Named::Held(joints)));
        }
    }
    held
}

/// What the reference-pose test names in a sweep: held joints' offsets (0-based) or a move
/// of its block.
enum Named {
    Held(Vec<usize>),
    Block,
}

/// The sweeps tried ([`sweeps_tried`]): the set they come from, the sweeps, and those the
/// reference-pose test names ([`retain_unnamed`]).
struct Tried {
    set: MeasurementSet,
    experiments: Vec<AxisExperiment>,
    named: Vec<(String, Named)>,
}

impl Tried {
    /// What the reference-pose test names in experiment `e`.
    fn named_of(&self, e: usize) -> Option<&Named> {
        let name = &self.experiments[e].name;
        self.named.iter().find(|(n, _)| n == name).map(|(_, k)| k)
    }

    /// The hypotheses: each sweep's held turning commands, its block and its drift; in a
    /// sweep the reference-pose test names, the correction it names (a held offset, or a
    /// move of its block), a move of its block and the drift.
    fn hypotheses(&self, desc: &RobotDescription) -> Vec<Hypothesis> {
        (0..self.experiments.len())
            .flat_map(|e| {
                let named: Vec<SweepCorrection> = match self.named_of(e) {
                    // At the reference pose a block moved reads as a held offset where the held
                    // joint's axis is far from the sweep's point.
                    Some(Named::Held(joints)) => joints
                        .iter()
                        .map(|&k| SweepCorrection::HeldCommand(k))
                        .chain([SweepCorrection::Block])
                        .collect(),
                    Some(Named::Block) => vec![SweepCorrection::Block],
                    None => held_joints(&self.experiments[e], desc)
                        .into_iter()
                        .map(SweepCorrection::HeldCommand)
                        .chain([SweepCorrection::Block])
                        .collect(),
                };
                named
                    .into_iter()
                    .chain([SweepCorrection::Drift])
                    .map(move |c| (Some(e), c))
            })
            .collect()
    }

    /// Whether `correction` in experiment `e` is what the reference-pose test names there
    /// (said already).
    fn names(&self, e: usize, correction: SweepCorrection) -> bool {
        match (self.named_of(e), correction) {
            (Some(Named::Held(joints)), SweepCorrection::HeldCommand(k)) => joints.contains(&k),
            (Some(Named::Block), SweepCorrection::Block) => true,
            _ => false,
        }
    }

    /// What a drift or a block found in experiment `e` stands beside: what the reference-pose
    /// test names there.
    fn shadow_of(&self, e: usize) -> Option<SweepShadow> {
        Some(match self.named_of(e)? {
            Named::Held(joints) => SweepShadow::HeldOffset(joints.iter().map(|k| k + 1).collect()),
            Named::Block => SweepShadow::MovedBlock,
        })
    }
}

/// The sweeps of `set` as the calibration `cal` fitted them (without the points its screen
/// dropped), less those whose cause is said already (a bump, which the fit takes in; a moved
/// block the reference-pose test names).
fn sweeps_tried(cal: &Calibration, desc: &RobotDescription, set: &MeasurementSet) -> Option<Tried> {
    let screening = screen_sweeps(set, desc, &cal.options, false).ok()?;
    let set = screening.set.unwrap_or_else(|| set.clone());
    let (mut experiments, _) = axis_experiments_with(&set, desc, cal.options.held_tolerance).ok()?;
    // Sweeps whose held joints wander are tested for bumps once the model is fitted.
    let wandering = wandering_sweep_bumps(&set, desc, &cal.options, cal);
    experiments.retain(|e| !screening.bumps.iter().chain(&wandering).any(|b| b.experiment == e.name));
    let named = retain_unnamed(&mut experiments, &set, desc, cal);
    Some(Tried {
        set,
        experiments,
        named,
    })
}

/// The sweep whose records, corrected, explain the miss of the validation poses `poses` by
/// the calibration `cal` of `set` (module docs); where none makes them pass, the one whose
/// correction explains a part of the miss beyond chance (the F test alone;
/// [`SweepCause::passes`] false); `Ok(None)` when none does or the poses pass as recorded;
/// [`SweepSearchTooLarge`] when the search would cost more than
/// [`MAX_SWEEP_SEARCH_CALIBRATIONS`].
pub fn sweep_cause_of_misses(
    cal: &Calibration,
    desc: &RobotDescription,
    set: &MeasurementSet,
    poses: &MeasurementSet,
) -> Result<Option<SweepCause>, SweepSearchTooLarge> {
    let Some(tried_sweeps) = sweeps_tried(cal, desc, set) else {
        return Ok(None);
    };
    let mut hypotheses = tried_sweeps.hypotheses(desc);
    if set.line_span().is_some() {
        hypotheses.push((None, SweepCorrection::Drift));
    }
    let calibrations = hypotheses.iter().map(|h| h.1.trials()).sum();
    if calibrations > MAX_SWEEP_SEARCH_CALIBRATIONS {
        return Err(SweepSearchTooLarge {
            hypotheses: hypotheses.len(),
            calibrations,
        });
    }
    Ok(sweep_cause_among(cal, desc, (set, poses), &tried_sweeps, &hypotheses))
}

/// [`sweep_cause_of_misses`] over `hypotheses` of the sweeps `tried_sweeps`.
fn sweep_cause_among(
    cal: &Calibration,
    desc: &RobotDescription,
    (set, poses): (&MeasurementSet, &MeasurementSet),
    tried_sweeps: &Tried,
    hypotheses: &[Hypothesis],
) -> Option<SweepCause> {
    let file_lines = set.line_span();
    let (set, experiments) = (&tried_sweeps.set, &tried_sweeps.experiments);
    let mut options = ValidationOptions::of_calibration(cal, SWEEP_CAUSE_FALSE_ALARM);
    // Every hypothesis is tested with the curvature judgement of the file as recorded.
    options.curvature_counts = Some(curvature_counts(poses, cal, desc, &options).ok()?);
    let score = |h: Option<Hypothesis>, c: &[f64]| -> Option<Score> {
        match h {
            None => score_of(set, cal, desc, (poses, &options)),
            Some((Some(e), correction)) => {
                let changed = correction.applied(set, &experiments[e].name, c);
                score_of(&changed, cal, desc, (poses, &options))
            }
            // The whole file's drift: the poses drifted too.
            Some((None, _)) => {
                let (drift, lines) = ([c[0], c[1], c[2]], file_lines?);
                let changed = set.with_file_drift_undone(drift, lines);
                score_of(
                    &changed,
                    cal,
                    desc,
                    (&poses.with_file_drift_undone(drift, lines), &options),
                )
            }
        }
    };
    let recorded = score(None, &[])?;
    if recorded.passes {
        return None;
    }
    let mut named = confirmed(&score, hypotheses, recorded);
    named.sort_by(|a, b| a.left().total_cmp(&b.left()));
    // Those whose correction makes the poses pass; else the best held command, as a part of the
    // miss (a move's three parameters take in a part of most misses).
    let passes = named.iter().any(|n| n.score.passes);
    named.retain(|n| n.score.passes == passes);
    if !passes {
        named.retain(|n| matches!(n.hypothesis.1, SweepCorrection::HeldCommand(_)));
    }
    let best = named.first()?;
    // What the reference-pose test names is said there.
    if let (Some(e), correction) = best.hypothesis
        && tried_sweeps.names(e, correction)
    {
        return None;
    }
    let shadows = best.hypothesis.0.and_then(|e| tried_sweeps.shadow_of(e));
    let fault = |n: &Confirmed| fault_of(n, desc);
    let name = |n: &Confirmed| n.hypothesis.0.map(|e| experiments[e].name.clone());
    let alternatives = match passes {
        true => named[1..].iter().map(|n| (name(n), fault(n))).collect(),
        false => Vec::new(),
    };
    Some(SweepCause {
        experiment: name(best),
        lines: best.hypothesis.0.map_or(file_lines, |e| experiments[e].lines),
        fault: fault(best),
        per_dof: (
            recorded.chi2 / recorded.dof as f64,
            best.score.chi2 / best.score.dof as f64,
        ),
        rms_mm: (recorded.rms_mm, best.score.rms_mm),
        alternatives,
        passes,
        shadows,
        tried: hypotheses.len(),
    })
}

/// The hypotheses whose correction, fitted and confirmed, passes the F test and explains more
/// than it leaves (module docs), against the file as `recorded`.
fn confirmed(score: &ScoreOf, hypotheses: &[Hypothesis], recorded: Score) -> Vec<Confirmed> {
    // Each hypothesis's quadratic is its own calibrations: run side by side, kept in order.
    let mut fitted: Vec<(Hypothesis, Vec<f64>, f64)> = hypotheses
        .par_iter()
        .filter_map(|&h| {
            let at = |c: &[f64]| score(Some(h), c).map(|s| s.chi2);
            let zero = vec![0.0; h.1.parameters()];
            let q = quadratic_least(&at, &zero, recorded.chi2, (h.1.trial_step(), WEAK_DIRECTION))?;
            Some((h, q.least_at, q.least))
        })
        .collect();
    fitted.sort_by(|a, b| a.2.total_cmp(&b.2));
    let tried = hypotheses.len().max(1) as f64;
    let quantile = |p: usize, dof: usize| f_upper_quantile(SWEEP_CAUSE_FALSE_ALARM / tried, p as f64, (dof - p) as f64);
    fitted
        .iter()
        .take(CONFIRMED)
        .filter_map(|(h, c, _)| refined(&|c: &[f64]| score(Some(*h), c), *h, c.clone()))
        .filter(|n| {
            let (s, p) = (n.score, n.rank);
            let gain = recorded.chi2 - s.chi2;
            // The excess left beyond the noise is the model's own error, shared by the poses: a
            // correction that explains less than it leaves is within what that error does.
            let most = gain > s.chi2 - s.dof as f64;
            s.dof > p && gain / p as f64 / n.left() > quantile(p, s.dof) && most
        })
        .collect()
}

/// The fault a confirmed correction undoes, with its 1-sigma: a held command's offset is the
/// correction's negative (undetermined where the poses do not show it), a drift the drift
/// undone. A move (a drift, a block) is given across the directions the poses do not show it
/// along, with those directions: the least move that fits, its covariance the Hessian's
/// pseudo-inverse's.
fn fault_of(n: &Confirmed, desc: &RobotDescription) -> SweepFault {
    let sigma = |i: usize| n.covariance[(i, i)].sqrt();
    let across = || {
        let c = part_across(&n.c, &n.null);
        let free_along = n.null.iter().map(pointing_up).collect();
        ([c[0], c[1], c[2]], [sigma(0), sigma(1), sigma(2)], free_along)
    };
    match n.hypothesis.1 {
        SweepCorrection::HeldCommand(k) => SweepFault::HeldOffset {
            joint: k + 1,
            offset: -n.c[0],
            sigma: if n.null.is_empty() { sigma(0) } else { f64::INFINITY },
            unit: desc.joints[k].kind.file_unit(),
        },
        SweepCorrection::Drift => {
            let (drift_mm, sigma_mm, free_along) = across();
            SweepFault::Drift {
                drift_mm,
                sigma_mm,
                free_along,
            }
        }
        SweepCorrection::Block => {
            let (moved_mm, sigma_mm, free_along) = across();
            SweepFault::Block {
                moved_mm,
                sigma_mm,
                free_along,
            }
        }
    }
}

/// `c` less its parts along the orthonormal directions `null`.
fn part_across(c: &[f64], null: &[DVector<f64>]) -> DVector<f64> {
    let mut c = DVector::from_column_slice(c);
    for u in null {
        c -= u * u.dot(&c);
    }
    c
}

/// A unit direction of three components, signed so that its largest component is positive
/// (a null direction's sign is arbitrary).
fn pointing_up(u: &DVector<f64>) -> [f64; 3] {
    let largest = u
        .iter()
        .copied()
        .fold(0.0, |a: f64, x| if x.abs() > a.abs() { x } else { a });
    let sign = if largest < 0.0 { -1.0 } else { 1.0 };
    [sign * u[0], sign * u[1], sign * u[2]]
}

/// The correction of hypothesis `h` refined from `c` by [`REFINE_PASSES`] quadratics about
/// it ([`SweepCorrection::refine_step`] either side: Newton's method on the chi-square, its
/// derivatives by central differences: the model is a rotation or a fit's shift, not quite
/// linear over the trial step), confirmed by the score at the refined correction, with the
/// covariance from the last quadratic's Hessian; `None` where a calibration fails, a
/// quadratic is not convex or the last step leaves the last quadratic's span (not converged).
fn refined(score: &dyn Fn(&[f64]) -> Option<Score>, h: Hypothesis, mut c: Vec<f64>) -> Option<Confirmed> {
    let step = h.1.refine_step();
    let at = |x: &[f64]| score(x).map(|s| s.chi2);
    let mut last = None;
    for _ in 0..REFINE_PASSES {
        let q = quadratic_least(&at, &c, at(&c)?, (step, WEAK_DIRECTION))?;
        let newton: Vec<f64> = q.least_at.iter().zip(&c).map(|(a, b)| a - b).collect();
        c = q.least_at.clone();
        last = Some((newton, q));
    }
    let (newton, q) = last?;
    // Newton's last step beyond the quadratic's own span: not converged, no least found.
    if newton.iter().any(|s| s.abs() > step) {
        return None;
    }
    let score = score(&c)?;
    let rank = c.len() - q.null.len();
    let left = score.chi2 / (score.dof as f64 - rank as f64);
    // chi2 = least + (c - c*)' (H / 2) (c - c*): the covariance is (H / 2)^-1, scaled by the
    // chi-square per degree of freedom left where that is beyond 1.
    let covariance = q.inverse_hessian * (2.0 * left.max(1.0));
    Some(Confirmed {
        hypothesis: h,
        c,
        covariance,
        rank,
        null: q.null,
        score,
    })
}

/// The joints (0-based) experiment `e` holds at one command, turning ones only where the
/// description's joint turns (a held slide's offset moves a sweep as a moved block does, which
/// the reference-pose test names).
fn held_joints(e: &AxisExperiment, desc: &RobotDescription) -> Vec<usize> {
    (0..desc.dof())
        .filter(|&k| e.holds_constant(k) && desc.joints[k].kind == JointKind::Revolute)
        .collect()
}

/// The validation of `poses` against the calibration of `set` (with its options), tested with
/// `options`; the tool frame estimated from the poses when the calibration measured none.
fn score_of(
    set: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
    (poses, options): (&MeasurementSet, &ValidationOptions),
) -> Option<Score> {
    let c = calibrate(set, desc, &cal.options).ok()?;
    let v = match c.tool {
        None => validate_free_tool(poses, &c, desc, options).ok()?.0,
        Some(_) => validate(poses, &c, desc, options).ok()?,
    };
    let part = v.validation.as_ref()?;
    let test = part.chi_square.as_ref()?;
    Some(Score {
        chi2: test.value,
        dof: test.dof,
        rms_mm: part.rms_mm,
        passes: test.verdict != Verdict::Exceeds,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use std::cell::Cell;

    /// The cost the cap counts is the evaluations [`quadratic_least`] makes (a second path:
    /// counted as it runs, on a convex quadratic of each correction's parameters).
    #[test]
    fn a_corrections_trials_are_its_quadratics_evaluations() {
        for correction in [
            SweepCorrection::HeldCommand(0),
            SweepCorrection::Drift,
            SweepCorrection::Block,
        ] {
            let calls = Cell::new(0);
            let f = |x: &[f64]| {
                calls.set(calls.get() + 1);
                Some(
                    x.iter()
                        .enumerate()
                        .map(|(i, v)| (i + 1) as f64 * (v - 0.3).powi(2))
                        .sum(),
                )
            };
            let centre = vec![0.0; correction.parameters()];
            let q = quadratic_least(&f, &centre, f(&centre).unwrap(), (1.0, WEAK_DIRECTION)).unwrap();
            calls.set(calls.get() - 1);
            assert_eq!(calls.get(), correction.trials(), "{correction:?}");
            assert!(q.least_at.iter().all(|c| (c - 0.3).abs() < 1e-12));
        }
    }

    /// A move along a null direction is left out and the rest kept (a second path: the
    /// component along the direction written out); a null direction reads the same either sign.
    #[test]
    fn a_move_is_given_across_its_null_directions() {
        let u = DVector::from_vec(vec![0.6, 0.0, -0.8]);
        let across = part_across(&[3.0, 1.0, 0.0], std::slice::from_ref(&u));
        // (3, 1, 0) . u = 1.8: less 1.8 u.
        assert_relative_eq!(across, DVector::from_vec(vec![3.0 - 1.08, 1.0, 1.44]), epsilon = 1e-12);
        assert_relative_eq!(across.dot(&u), 0.0, epsilon = 1e-12);
        assert_eq!(
            part_across(&[3.0, 1.0, 0.0], &[]),
            DVector::from_vec(vec![3.0, 1.0, 0.0])
        );
        let up = |u: &DVector<f64>| nalgebra::Vector3::from(pointing_up(u));
        assert_relative_eq!(up(&u), up(&-&u), epsilon = 1e-15);
        assert_relative_eq!(up(&u), nalgebra::Vector3::new(-0.6, 0.0, 0.8), epsilon = 1e-15);
    }
}
