//! A held joint's recorded command off where the robot stood through one sweep, sought by
//! recalibrating against the file's own validation poses (`calibrate`, when the calibrated
//! model misses them). On some robots (a table, a two-axis positioner, the IRB/L6) a held
//! joint's offset through one sweep turns the swept arc rigidly about the held joint's axis;
//! the sweep's own axis fit absorbs it and the reference-pose comparison
//! (`calibration::shared_target`) has nothing to see, but the validation poses, which the
//! calibration predicts with the sweep's axis placed by the recorded value, miss.
//!
//! Each hypothesis "the held `cmd_k` of experiment E is off by `d`" is tested by recalibrating
//! with E's recorded `cmd_k` corrected by `c = -d`: the validation chi-square (`validate`'s,
//! against the original calibration's noise) is a quadratic in `c` where the model is linear
//! in it (a rotation by a few degrees), so three calibrations (at 0 and at plus and minus a
//! trial step) give its least and the `c` there; the best few are refined by narrower parabolas
//! about it (Newton's method) and confirmed by a calibration at the refined correction; the
//! offset's 1-sigma is the chi-square's curvature there, scaled by the chi-square per degree
//! of freedom left where that is beyond 1. The hypothesis is named when (1) its improvement over the file as recorded, over the
//! confirmed chi-square per degree of freedom left, is an F ratio `F(1, dof - 1)` beyond its
//! quantile at [`OWN_HELD_FALSE_ALARM`] shared among the hypotheses tried (Bonferroni, as the
//! slip searches share theirs), and (2) the corrected calibration passes `validate`'s test of
//! the poses: the correction explains the miss, not only part of it (Seber & Wild, *Nonlinear
//! Regression*, 1989, sec. 5.3: the extra-sum-of-squares F test of a nested model). Its gain
//! must also exceed the chi-square's excess left beyond its degrees of freedom: that excess is
//! the model's own error, which the poses share (not independent, as the F test counts them),
//! and a one-parameter fit moves by as much where the poses miss for another reason (a clean
//! file of five-point sweeps, its poses missed at chi2/dof 3.28, 3.03 with a held `cmd_4` moved
//! 15 deg). Other hypotheses that pass all three are named beside it, as alternatives the data
//! do not tell apart; where none passes the poses' test, the best that passes the other two is
//! said as a part of the miss.
//! The sweeps are taken as the calibration fitted them (the points the screen drops left out);
//! a sweep whose points shift part-way (`screen::bump`, a bump the fit takes in) and one the
//! reference-pose test names as a moved block (`shared_target::moved_sweeps`) are not tried:
//! their cause is said already.

use axiscal::calibration::procedure::{
    AxisExperiment, Calibration, axis_experiments_with, calibrate, screen_sweeps, wandering_sweep_bumps,
};
use axiscal::calibration::shared_target::moved_sweeps;
use axiscal::diagnosis::{ValidationOptions, Verdict, validate, validate_free_tool};
use axiscal::kinematics::JointKind;
use axiscal::measurement::MeasurementSet;
use axiscal::numerics::stats::f_upper_quantile;
use axiscal::robot::RobotDescription;

/// The family-wise false-alarm rate of the search: the own-poses test's.
pub(super) const OWN_HELD_FALSE_ALARM: f64 = 1e-4;

/// The trial change of a held command (file units: 1 deg or 1 mm), about the size of the slips
/// sought (0.5 to 2 deg) so that the quadratic is read where they lie.
const TRIAL_STEP: f64 = 1.0;

/// Hypotheses refined and confirmed by a calibration at their fitted correction, best
/// predicted first.
const CONFIRMED: usize = 3;

/// The half-width of a refining parabola (file units): within it a rotation's chi-square is
/// quadratic to well below its noise.
const REFINE_STEP: f64 = 0.25;

/// Refining parabolas ([`refined`]).
const REFINE_PASSES: usize = 2;

/// A held joint's recorded command in one sweep that, corrected, lets the calibration fit the
/// file's own validation poses.
#[derive(Clone, Debug)]
pub(super) struct OwnHeld {
    /// The experiment.
    pub experiment: String,
    /// Its first and last lines.
    pub lines: Option<(u64, u64)>,
    /// The held joint (1-based).
    pub joint: usize,
    /// The recorded value minus where the robot stood (file units).
    pub offset: f64,
    /// Its 1-sigma (file units).
    pub sigma: f64,
    /// `deg` or `mm`.
    pub unit: &'static str,
    /// The validation chi-square per degree of freedom as recorded and corrected.
    pub per_dof: (f64, f64),
    /// The validation RMS as recorded and corrected \[mm\].
    pub rms_mm: (f64, f64),
    /// Other (experiment, joint, offset) that pass as well.
    pub alternatives: Vec<(String, usize, f64)>,
    /// Whether the corrected calibration passes the poses' test; `false`: the correction
    /// explains a part of the miss beyond chance, another cause the rest.
    pub passes: bool,
    /// The held commands tried.
    pub tried: usize,
}

/// One validation of a calibration of the file with a held command changed.
#[derive(Clone, Copy, Debug)]
struct Score {
    chi2: f64,
    dof: usize,
    rms_mm: f64,
    passes: bool,
}

/// A hypothesis: the experiment (its index), the held joint (0-based).
type Hypothesis = (usize, usize);

/// `experiments` less the sweeps of `set` the reference-pose test ([`moved_sweeps`]) names as
/// a moved block (or as one of two that disagree) or with a held offset: that cause is named
/// already, and no held offset is sought in them.
fn retain_unnamed(
    experiments: &mut Vec<AxisExperiment>,
    set: &MeasurementSet,
    desc: &RobotDescription,
    cal: &Calibration,
) {
    let noise = cal
        .noise
        .as_ref()
        .map_or(cal.options.noise_rms_3d_mm, |n| n.used_rms_3d_mm);
    for moved in moved_sweeps(set, desc, noise) {
        if moved.held.is_empty() && moved.backlash.is_empty() {
            let others = if moved.ambiguous {
                moved.others.clone()
            } else {
                Vec::new()
            };
            experiments.retain(|e| e.name != moved.experiment && !others.contains(&e.name));
        } else if !moved.held.is_empty() {
            experiments.retain(|e| e.name != moved.experiment);
        }
    }
}

/// The held joint of one sweep whose recorded command, corrected, explains the miss of the
/// validation poses `poses` (module docs); where none makes them pass, the one whose correction
/// explains a part of the miss beyond chance (the F test alone; [`OwnHeld::passes`] false);
/// `None` when none does.
pub(super) fn own_held_offset(
    cal: &Calibration,
    desc: &RobotDescription,
    set: &MeasurementSet,
    poses: &MeasurementSet,
) -> Option<OwnHeld> {
    // The sweeps as the calibration fitted them: without the points its screen dropped; a sweep
    // whose points shift part-way (a bump, which the fit takes in) is no held offset's.
    let screening = screen_sweeps(set, desc, &cal.options, false).ok()?;
    let set = screening.set.as_ref().unwrap_or(set);
    let (mut experiments, _) = axis_experiments_with(set, desc, cal.options.held_tolerance).ok()?;
    // Sweeps whose held joints wander are tested for bumps once the model is fitted.
    let wandering = wandering_sweep_bumps(set, desc, &cal.options, cal);
    experiments.retain(|e| !screening.bumps.iter().chain(&wandering).any(|b| b.experiment == e.name));
    retain_unnamed(&mut experiments, set, desc, cal);
    let options = ValidationOptions::of_calibration(cal, OWN_HELD_FALSE_ALARM);
    let score = |h: Option<(Hypothesis, f64)>| -> Option<Score> {
        let changed = match h {
            None => set.clone(),
            Some(((e, k), c)) => set.with_command_offset_in(&experiments[e].name, k, c),
        };
        score_of(&changed, cal, desc, (poses, &options))
    };
    let recorded = score(None)?;
    if recorded.passes {
        return None;
    }
    let hypotheses: Vec<Hypothesis> = experiments
        .iter()
        .enumerate()
        .flat_map(|(e, x)| held_joints(x, desc).into_iter().map(move |k| (e, k)))
        .collect();
    let mut fitted: Vec<(Hypothesis, f64, f64)> = hypotheses
        .iter()
        .filter_map(|&h| {
            let plus = score(Some((h, TRIAL_STEP)))?;
            let minus = score(Some((h, -TRIAL_STEP)))?;
            let (c, least) = parabola_least(minus.chi2, recorded.chi2, plus.chi2, TRIAL_STEP)?;
            Some((h, c, least))
        })
        .collect();
    fitted.sort_by(|a, b| a.2.total_cmp(&b.2));
    let tried = hypotheses.len().max(1) as f64;
    let quantile = |dof: usize| f_upper_quantile(OWN_HELD_FALSE_ALARM / tried, 1.0, dof as f64 - 1.0);
    let mut named: Vec<(Hypothesis, f64, f64, Score)> = fitted
        .iter()
        .take(CONFIRMED)
        .filter_map(|&(h, c, _)| {
            let (c, q, s) = refined(&score, h, c)?;
            let left = s.chi2 / (s.dof as f64 - 1.0);
            let gain = recorded.chi2 - s.chi2;
            // The excess left beyond the noise is the model's own error, shared by the poses: a
            // correction that explains less than it leaves is within what that error does.
            let most = gain > s.chi2 - s.dof as f64;
            (s.dof > 1 && gain / left > quantile(s.dof) && most).then_some((h, c, left.max(1.0) / q, s))
        })
        .collect();
    named.sort_by(|a, b| a.3.chi2.total_cmp(&b.3.chi2));
    // Those whose correction makes the poses pass; else the best, as a part of the miss.
    let passes = named.iter().any(|n| n.3.passes);
    named.retain(|n| n.3.passes == passes);
    let &((e, k), c, variance, best) = named.first()?;
    let x = &experiments[e];
    let alternatives = match passes {
        true => named[1..]
            .iter()
            .map(|&((e, k), c, _, _)| (experiments[e].name.clone(), k + 1, -c))
            .collect(),
        false => Vec::new(),
    };
    Some(OwnHeld {
        experiment: x.name.clone(),
        lines: x.lines,
        joint: k + 1,
        offset: -c,
        sigma: variance.sqrt(),
        unit: desc.joints[k].kind.file_unit(),
        per_dof: (recorded.chi2 / recorded.dof as f64, best.chi2 / best.dof as f64),
        rms_mm: (recorded.rms_mm, best.rms_mm),
        alternatives,
        passes,
        tried: hypotheses.len(),
    })
}

/// The correction of hypothesis `h` refined from `c` by [`REFINE_PASSES`] parabolas through
/// it and [`REFINE_STEP`] either side (Newton's method on the chi-square, its derivatives by
/// central differences: the model is a rotation, not quite linear over the 1-deg trial step),
/// with the last parabola's curvature `q` (`chi2(c) = least + q (c - c*)^2`) and the score at
/// the refined correction; `None` where a calibration fails, a parabola opens downwards or the
/// last step leaves the last parabola's span (not converged).
fn refined(
    score: &dyn Fn(Option<(Hypothesis, f64)>) -> Option<Score>,
    h: Hypothesis,
    mut c: f64,
) -> Option<(f64, f64, Score)> {
    let (mut q, mut step) = (0.0, 0.0);
    for _ in 0..REFINE_PASSES {
        let at = |x: f64| score(Some((h, x))).map(|s| s.chi2);
        let (minus, zero, plus) = (at(c - REFINE_STEP)?, at(c)?, at(c + REFINE_STEP)?);
        q = (plus + minus - 2.0 * zero) / (2.0 * REFINE_STEP * REFINE_STEP);
        step = parabola_least(minus, zero, plus, REFINE_STEP)?.0;
        c += step;
    }
    // Newton's last step beyond the parabola's own span: not converged, no least found.
    if step.abs() > REFINE_STEP {
        return None;
    }
    Some((c, q, score(Some((h, c)))?))
}

/// The joints (0-based) experiment `e` holds at one command, turning ones only where the
/// description's joint turns (a held slide's offset moves a sweep as a moved block does, which
/// the reference-pose test names).
fn held_joints(e: &AxisExperiment, desc: &RobotDescription) -> Vec<usize> {
    (0..desc.dof())
        .filter(|&k| e.holds_constant(k) && desc.joints[k].kind == JointKind::Revolute)
        .collect()
}

/// The least of the parabola through `(-step, minus)`, `(0, zero)`, `(step, plus)`: where it
/// is and its value; `None` when it opens downwards.
fn parabola_least(minus: f64, zero: f64, plus: f64, step: f64) -> Option<(f64, f64)> {
    let q = (plus + minus - 2.0 * zero) / (2.0 * step * step);
    let b = (plus - minus) / (2.0 * step);
    if q.is_nan() || q <= 0.0 {
        return None;
    }
    let c = -b / (2.0 * q);
    Some((c, zero - b * b / (4.0 * q)))
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

impl OwnHeld {
    /// The clause for the miss's cause where the correction explains a part of it
    /// ([`OwnHeld::passes`] false), for the file `data` (its name).
    pub(super) fn part_words(&self, data: &str) -> String {
        let lines = self
            .lines
            .map_or(String::new(), |(a, b)| format!(" ({data} lines {a}-{b})"));
        let j = self.joint;
        format!(
            "the held `cmd_{j}` of experiment {}{lines} looks offset by {:+.3} {} (1-sigma {:.3}) from where the robot \
             stood: recalibrated with `cmd_{j}` in these rows moved by {:+.3} {} the model misses the poses by {:.3} mm \
             RMS (chi2/dof {:.2}), a gain beyond chance among the {} held commands tried (an F test at {OWN_HELD_FALSE_ALARM:e}) \
             though not within their test: check `cmd_{j}` in these rows against the controller, and another cause \
             besides: ",
            self.experiment,
            self.offset,
            self.unit,
            self.sigma,
            -self.offset,
            self.unit,
            self.rms_mm.1,
            self.per_dof.1,
            self.tried,
        )
    }

    /// The warning, for the file `data` (its name).
    pub(super) fn words(&self, data: &str, poses: usize) -> String {
        let place = self.lines.map_or(data.to_string(), |(l, _)| format!("{data}:{l}"));
        let lines = self.lines.map_or(String::new(), |(a, b)| format!(" (lines {a}-{b})"));
        let j = self.joint;
        let or: Vec<String> = self
            .alternatives
            .iter()
            .map(|(e, k, d)| format!(", or the held `cmd_{k}` of experiment {e} by {d:+.3} {}", self.unit))
            .collect();
        format!(
            "{place}: experiment {}{lines}: the held `cmd_{j}` looks offset by {:+.3} {} (1-sigma {:.3}) from where the \
             robot stood{}: the calibrated model misses this file's own {poses} validation poses (not fitted) by {:.3} mm \
             RMS (chi2/dof {:.2}), and recalibrated with `cmd_{j}` in these rows moved by {:+.3} {} it fits them (RMS \
             {:.3} mm, chi2/dof {:.2}); the sweep's own axis fit takes such an offset in as a turn of its axis about joint \
             {j}'s, which the sweeps alone do not show: a value typed wrong for this experiment, or the joint re-mastered \
             between the sweeps (or the sweep's block moved between the sweeps, the instrument or the robot bumped, which \
             moves its points much alike where joint {j}'s axis is far from them); calibration.json is wrong for the robot: check `cmd_{j}` in these rows against the \
             controller, or measure the sweep again",
            self.experiment,
            self.offset,
            self.unit,
            self.sigma,
            or.concat(),
            self.rms_mm.0,
            self.per_dof.0,
            -self.offset,
            self.unit,
            self.rms_mm.1,
            self.per_dof.1,
        )
    }
}
