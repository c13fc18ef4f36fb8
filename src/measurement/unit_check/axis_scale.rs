//! One axis of the instrument reading long or short (`calibrate`): a laser tracker's or a
//! coordinate measuring machine's x scale off by per mille, or an exporter that scaled one
//! coordinate column. A calibration absorbs a scale of every coordinate into the links'
//! lengths, and each arc or pose alone absorbs a scale of one coordinate as a tilt or a
//! slightly different radius, but the robot's arcs and poses together cannot: the fit of the
//! whole file is worse than with the column undone.
//!
//! A profile test: the calibration ([`Fit`], supplied by the caller, so this module knows
//! nothing of it) is re-run with one column rescaled about the data's centroid by `1 +- h`
//! (`PROFILE_STEP`); a scale about any other point is this one plus a shift, which the base
//! frame absorbs, so only the factor is identifiable. The three residual sums of squares give
//! the parabola of the sum against the factor, its minimum (the factor the column reads), the
//! reduction of the sum there, and the factor's sigma (the noise over the parabola's
//! curvature). The reduction is tested with the F ratio against the residuals' own noise
//! estimate at [`AXIS_SCALE_FALSE_ALARM`] shared by the three columns, and the factor is
//! confirmed by a fourth run with the column undone, whose own reduction must pass the same
//! test and whose every free pose the model fits within its outlier fence, and whose joints'
//! sweeps at several poses agree on their axes within the noise their own fits show (a pose
//! the model cannot fit, or sweeps its held joints' correction cannot bring together, say the
//! residuals are the model's limits, not noise, and any extra parameter reduces them; the
//! linearisation checked against the re-run; when it does not, one more parabola about the
//! factor found and its re-run decide). A uniform scale of all
//! three columns is one of the links' lengths, so "x reads long" and "y and z read short" are
//! one finding: the column named is the one whose undoing explains most.
//!
//! On a robot with sliding joints two more readings move the points alike and are profiled the
//! same way: a slide's command column scaled (its lead or the controller's scale: the slide's
//! travel along one instrument axis is that axis' scale on such data), and the three columns
//! scaled together (the slides' readings are a length standard the links cannot absorb, so an
//! isotropic scale of the instrument shows against them). The most significant is named and
//! every other within the test's reach of it said beside it. Where nothing is named, the scale
//! each column lets pass (the test's threshold in sigmas of its factor) is kept for a note.

use super::super::MeasurementSet;
use crate::numerics::stats::{f_upper_quantile, f_upper_tail};

/// The false-alarm rate of the test, shared by the three columns: one clean file in ten
/// thousand is told an axis reads long.
pub const AXIS_SCALE_FALSE_ALARM: f64 = 1e-4;

/// The relative step of the profile: a thousandth moves a point a metre from the centroid by
/// a millimetre, several times a tracker's or a theodolite pair's noise, and keeps the sum of
/// squares within its parabola for the per-mille scales an instrument reads.
const PROFILE_STEP: f64 = 1e-3;

/// How far from its samples the parabola is trusted, in steps: the sums of squares follow a
/// parabola near the factor the fits are run at, not 300 steps away (a minimum that far out,
/// such as 4/3 on a coaxial SCARA's clean file, says the profile is flat, not that an axis
/// reads a third long); a column 2 % off is a unit or exporter slip for the unit checks.
const PROFILE_REACH_STEPS: f64 = 20.0;

/// Above this many rows the profile fits a subsample of evenly spaced rows of each
/// experiment: the test needs the robot's arcs and poses, not every point, and each of its
/// four runs is a whole calibration.
pub const PROFILE_MAX_ROWS: usize = 20_000;

/// The same bound for a free-pose file (about 500 poses of three targets): each run of a
/// free-pose calibration fits every pose it is given (up to `--max-poses`), so the profile's
/// runs on a large file would otherwise take minutes each; 500 poses resolve a per-mille
/// scale of a metre-sized robot's poses many times over.
pub const PROFILE_MAX_FREE_POSE_ROWS: usize = 1_500;

/// The residuals of one calibration of a file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fit {
    /// The sum of the squared residual coordinates \[mm^2\].
    pub sum_squares_mm2: f64,
    /// Its degrees of freedom (coordinates less fitted parameters).
    pub dof: usize,
    /// What the model cannot fit within the noise: the free poses beyond the fit's outlier
    /// fence, or (sweeps) 1 where the sweeps of the joints fitted from several miss one
    /// another beyond the noise their own fits show
    /// ([`crate::calibration::procedure::sweeps_agreement`]). Either says the residuals are not
    /// the noise the F test assumes.
    pub misfits: usize,
}

/// What a profile scales: one coordinate column, the three together, or a sliding joint's
/// commands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scaled {
    /// One coordinate column: 0 `x_mm`, 1 `y_mm`, 2 `z_mm` (about the data's centroid).
    Column(usize),
    /// The three coordinate columns alike (about the centroid): the links take such a scale,
    /// a sliding joint's travel does not, so it is tried only on robots with one.
    Every,
    /// A sliding joint's command column, by 0-based joint index (`cmd_1` is 0): its travel
    /// along one instrument axis and that axis' scale move the points alike.
    Command(usize),
}

impl Scaled {
    /// `set` as it would read with this scale `factor` undone (divided by it), coordinates
    /// about `centroid`.
    fn undone(self, set: &MeasurementSet, factor: f64, centroid: [f64; 3]) -> MeasurementSet {
        match self {
            Scaled::Column(c) => set.with_coordinate_scaled_about(c, 1.0 / factor, centroid[c]),
            Scaled::Every => (0..3).fold(set.clone(), |s, c| {
                s.with_coordinate_scaled_about(c, 1.0 / factor, centroid[c])
            }),
            Scaled::Command(j) => set.with_command_scaled(j, 1.0 / factor),
        }
    }

    /// The columns' names, in backticks.
    pub fn columns(self) -> String {
        match self {
            Scaled::Column(c) => format!("`{}`", COLUMNS[c]),
            Scaled::Every => "`x_mm`, `y_mm`, `z_mm`".into(),
            Scaled::Command(j) => format!("`cmd_{}`", j + 1),
        }
    }

    /// What reads `factor` times, in words: "`y_mm` reads 1.003 times", or with `long` "`y_mm`:
    /// the instrument's y axis reads 1.003 times".
    fn reads(self, factor: f64, long: bool) -> String {
        match self {
            Scaled::Column(c) if !long => format!("`{}` reads {factor:.5} times", COLUMNS[c]),
            Scaled::Column(c) => format!(
                "`{}`: the instrument's {} axis reads {factor:.5} times",
                COLUMNS[c],
                &COLUMNS[c][..1]
            ),
            Scaled::Every => format!("every coordinate reads {factor:.5} times"),
            Scaled::Command(j) => format!("`cmd_{}` (joint {} slides) holds {factor:.5} times", j + 1, j + 1),
        }
    }
}

/// A coordinate column's scale the data determine.
#[derive(Clone, Debug, PartialEq)]
pub struct AxisScale {
    /// What is scaled: a coordinate column, or what reads alike on a robot with a slide.
    pub scaled: Scaled,
    /// The factor the column reads against the others (about the data's centroid).
    pub factor: f64,
    /// Its 1-sigma.
    pub sigma: f64,
    /// The F test's upper tail probability of the reduction (per column).
    pub p_value: f64,
    /// The residual RMS per coordinate \[mm\] as read and with the column undone.
    pub rms_mm: [f64; 2],
    /// Whether the test names it (beyond the false-alarm rate, and confirmed).
    pub significant: bool,
    /// Others whose scale explains the residuals as well, within the test's reach, and the
    /// factor each reads: a robot whose links absorb a scale of two columns together (a
    /// SCARA's arm in x and y) cannot tell x long from y short, nor a slide's lead from the
    /// scale of the axis it travels along.
    pub alike: Vec<(Scaled, f64)>,
    /// By coordinate column, the scale the test lets pass (its threshold in sigmas of the
    /// column's factor), `None` where the profile is flat (the data do not resolve it within
    /// [`PROFILE_REACH`]).
    pub reach: [Option<f64>; 3],
    /// Whether the profile found it beyond the test's threshold but the fit with it undone did
    /// not confirm it (its reduction passes, but a free pose the model cannot fit, or a
    /// joint's sweeps that miss one another beyond their noise, remain; or the re-run fails):
    /// the test names nothing on such a file, at any size.
    pub unconfirmed: bool,
}

/// The column names, by column.
pub const COLUMNS: [&str; 3] = ["x_mm", "y_mm", "z_mm"];

/// How far from 1 the profile is trusted (module docs): a column 2 % off is a unit or
/// exporter slip for the unit checks.
pub const PROFILE_REACH: f64 = PROFILE_REACH_STEPS * PROFILE_STEP;

/// The one-axis scale the test is meant to name wherever the data resolve it (0.3 %): it
/// moves a metre-sized robot's points by 3 mm along one axis, 15 to 30 times a tracker's
/// noise, and a calibration that absorbed it missed its unedited file by 1.4 to 45 times the
/// predicted error in our hostile runs. A file that lets more pass says so
/// ([`AxisScale::reach_note`]).
pub const AXIS_SCALE_REACH_CLAIM: f64 = 0.003;

/// The centroid of `set`'s coordinates \[mm\].
fn centroid(set: &MeasurementSet) -> [f64; 3] {
    let rows = set.rows();
    let n = rows.len().max(1) as f64;
    std::array::from_fn(|c| rows.iter().map(|m| m.position_mm[c]).sum::<f64>() / n)
}

/// The profile of one scale about the factor `at` (module docs; `base` the fit with it
/// divided by `at`): the factor it reads, before confirmation. A minimum beyond
/// [`PROFILE_REACH_STEPS`] steps is walked toward ([`walked`]); one still beyond them keeps the
/// factor `at` and a p-value of 1 (not a finding) beside the sigma the curvature gives.
fn profile(
    set: &MeasurementSet,
    (scaled, at): (Scaled, f64),
    base: Fit,
    fit: &dyn Fn(&MeasurementSet) -> Option<Fit>,
) -> Option<AxisScale> {
    let h = PROFILE_STEP;
    let (there, near, parabola) = walked(set, (scaled, at), base, fit)?;
    let dof = base.dof as f64;
    let Parabola { slope, curvature } = parabola;
    let shift = slope / (2.0 * curvature);
    let trusted = shift.abs() <= PROFILE_REACH_STEPS * h;
    let reduction = if trusted {
        (base.sum_squares_mm2 - near.sum_squares_mm2) + slope * slope / (4.0 * curvature)
    } else {
        0.0
    };
    let left = (base.sum_squares_mm2 - reduction).max(0.0);
    let variance = left / (dof - 1.0);
    Some(AxisScale {
        scaled,
        factor: if trusted { there * (1.0 - shift) } else { at },
        sigma: there * (variance / curvature).sqrt(),
        p_value: if trusted {
            f_upper_tail(reduction / variance, 1.0, dof - 1.0)
        } else {
            1.0
        },
        rms_mm: [(base.sum_squares_mm2 / dof).sqrt(), (left / dof).sqrt()],
        significant: false,
        alike: vec![],
        reach: [None; 3],
        unconfirmed: false,
    })
}

/// The sums of squares against the relative factor about a point of the profile: their
/// slope and curvature per unit factor.
#[derive(Clone, Copy, Debug)]
struct Parabola {
    slope: f64,
    curvature: f64,
}

/// The parabola about the factor `at` (`base` the fit there), from the fits at `at (1 +- h)`.
fn parabola(
    set: &MeasurementSet,
    (scaled, at): (Scaled, f64),
    base: Fit,
    fit: &dyn Fn(&MeasurementSet) -> Option<Fit>,
) -> Option<Parabola> {
    let c = centroid(set);
    let h = PROFILE_STEP;
    let plus = fit(&scaled.undone(set, at * (1.0 + h), c))?;
    let minus = fit(&scaled.undone(set, at * (1.0 - h), c))?;
    if plus.dof != base.dof || minus.dof != base.dof || base.dof < 2 {
        return None;
    }
    let slope = (plus.sum_squares_mm2 - minus.sum_squares_mm2) / (2.0 * h);
    let curvature = (plus.sum_squares_mm2 + minus.sum_squares_mm2 - 2.0 * base.sum_squares_mm2) / (2.0 * h * h);
    (curvature > 0.0 && slope.is_finite()).then_some(Parabola { slope, curvature })
}

/// Rounds at most of the walk toward a minimum beyond the parabola's reach ([`walked`]).
const WALK_ROUNDS: usize = 4;

/// How far one round of the walk moves the factor at most (relative).
const WALK_STEP: f64 = 0.05;

/// How far from the profile's first factor the walk goes at most (relative): a column 10 %
/// off moves a metre-sized robot's points by 100 mm, a unit or exporter slip for the unit
/// checks.
const WALK_REACH: f64 = 0.1;

/// The factor the profile ends at, its fit and its parabola: from `at` (`base` the fit there),
/// while the parabola's minimum lies beyond [`PROFILE_REACH_STEPS`] steps, the profile moves
/// to that minimum (at most [`WALK_STEP`] a round, [`WALK_REACH`] in all, [`WALK_ROUNDS`]
/// rounds) where the fit there is better (Newton's method on the sums of squares). A scale of
/// a few per cent lies far beyond the per-mille parabola about 1, whose minimum then points
/// the way but misplaces it (a UR5e's `y_mm` x1.025 read as `x_mm` x0.992).
fn walked(
    set: &MeasurementSet,
    (scaled, at): (Scaled, f64),
    base: Fit,
    fit: &dyn Fn(&MeasurementSet) -> Option<Fit>,
) -> Option<(f64, Fit, Parabola)> {
    let c = centroid(set);
    let (mut there, mut near) = (at, base);
    for round in 0.. {
        let p = parabola(set, (scaled, there), near, fit)?;
        let shift = p.slope / (2.0 * p.curvature);
        let next = there * (1.0 - shift.clamp(-WALK_STEP, WALK_STEP));
        if shift.abs() <= PROFILE_REACH_STEPS * PROFILE_STEP
            || round == WALK_ROUNDS
            || (next / at - 1.0).abs() > WALK_REACH
        {
            return Some((there, near, p));
        }
        match fit(&scaled.undone(set, next, c)) {
            Some(f) if f.dof == near.dof && f.sum_squares_mm2 < near.sum_squares_mm2 => (there, near) = (next, f),
            _ => return Some((there, near, p)),
        }
    }
    None
}

/// The F test's upper tail probability of the reduction of the sum of squares from `base` to
/// `at` (one parameter more; the fewer degrees of freedom of the two when the fits kept
/// different parameters), `None` without two degrees of freedom.
fn reduction_p(base: Fit, at: Fit) -> Option<f64> {
    let dof = base.dof.min(at.dof) as f64 - 1.0;
    let variance = at.sum_squares_mm2 / dof;
    (dof >= 1.0).then(|| f_upper_tail((base.sum_squares_mm2 - at.sum_squares_mm2) / variance, 1.0, dof))
}

/// `found` confirmed by the fit with its column undone: the re-run's own reduction must pass
/// the test; when it does not, one more profile about the factor found (the parabola about 1
/// extrapolated too far) and its re-run decide.
fn confirmed(
    set: &MeasurementSet,
    found: AxisScale,
    base: Fit,
    fit: &dyn Fn(&MeasurementSet) -> Option<Fit>,
) -> Option<AxisScale> {
    let c = centroid(set);
    let rate = AXIS_SCALE_FALSE_ALARM / 3.0;
    let at = fit(&found.scaled.undone(set, found.factor, c))?;
    if reduction_p(base, at)? < rate && at.misfits == 0 {
        return Some(AxisScale {
            significant: true,
            ..found
        });
    }
    let again = profile(set, (found.scaled, found.factor), at, fit)?;
    let at = fit(&found.scaled.undone(set, again.factor, c))?;
    let reduced = reduction_p(base, at)? < rate;
    Some(AxisScale {
        significant: reduced && at.misfits == 0,
        // The reduction passes, but a pose the model cannot fit remains with it undone.
        unconfirmed: reduced && at.misfits > 0,
        rms_mm: [found.rms_mm[0], (at.sum_squares_mm2 / base.dof as f64).sqrt()],
        ..again
    })
}

/// `set` thinned to at most about `max_rows` rows: every `k`-th step of each experiment, all
/// of a step's targets kept.
fn thinned(set: &MeasurementSet, max_rows: usize) -> Option<MeasurementSet> {
    let n = set.rows().len();
    if n <= max_rows {
        return None;
    }
    let k = n.div_ceil(max_rows);
    let dropped: Vec<usize> = (0..n).filter(|&i| !set.rows()[i].step.is_multiple_of(k)).collect();
    Some(set.without_rows(&dropped))
}

/// The column scale that best explains `set`'s residuals under the calibration `fit`
/// (module docs), significant or not (`significant` says; `unconfirmed` where the profile found
/// it but the re-run with it undone left a pose the model cannot fit, or failed), or `None` when the fit of the file as
/// read fails or no profile is a parabola (the fit changed its course between the runs). `slides` are the
/// sliding joints (0-based): each one's command scale, and the three columns' together, are
/// tried beside the columns, as what moves the points alike with a column's scale.
/// Above `max_rows` rows ([`PROFILE_MAX_ROWS`], [`PROFILE_MAX_FREE_POSE_ROWS`]) the profile
/// runs on every `k`-th step.
pub fn axis_scale(
    set: &MeasurementSet,
    fit: &dyn Fn(&MeasurementSet) -> Option<Fit>,
    max_rows: usize,
    slides: &[usize],
) -> Option<AxisScale> {
    let thin = thinned(set, max_rows);
    let set = thin.as_ref().unwrap_or(set);
    let base = fit(set)?;
    let candidates = (0..3)
        .map(Scaled::Column)
        .chain(slides.first().map(|_| Scaled::Every))
        .chain(slides.iter().map(|&j| Scaled::Command(j)));
    let profiles: Vec<AxisScale> = candidates.filter_map(|c| profile(set, (c, 1.0), base, fit)).collect();
    let best = profiles.iter().min_by(|a, b| a.p_value.total_cmp(&b.p_value))?.clone();
    let rate = AXIS_SCALE_FALSE_ALARM / 3.0;
    let dof = base.dof as f64;
    let threshold = f_upper_quantile(rate, 1.0, dof - 1.0).sqrt();
    let reach = std::array::from_fn(|c| {
        let column = profiles.iter().find(|a| a.scaled == Scaled::Column(c))?;
        let r = threshold * column.sigma;
        (r <= PROFILE_REACH).then_some(r)
    });
    if best.p_value >= rate {
        return Some(AxisScale { reach, ..best });
    }
    let reduction = |a: &AxisScale| base.sum_squares_mm2 - a.rms_mm[1].powi(2) * dof;
    let variance = best.rms_mm[1].powi(2) * dof / (dof - 1.0);
    let apart = variance * threshold * threshold;
    let alike = profiles
        .iter()
        .filter(|a| a.scaled != best.scaled && a.p_value < rate && reduction(&best) - reduction(a) < apart)
        .map(|a| (a.scaled, a.factor))
        .collect();
    // A re-run that fails leaves the finding as profiled, unconfirmed.
    let checked = confirmed(set, best.clone(), base, fit).unwrap_or(AxisScale {
        unconfirmed: true,
        ..best
    });
    Some(AxisScale {
        alike,
        reach,
        ..checked
    })
}

impl AxisScale {
    /// How large a one-axis scale the test lets pass on this file, in words, where it is
    /// beyond [`AXIS_SCALE_REACH_CLAIM`] for some column and nothing was named; `None`
    /// otherwise.
    pub fn reach_note(&self) -> Option<String> {
        if self.unconfirmed {
            return Some(format!(
                "one-axis instrument scales this file cannot show: any, at any size ({} reads {:.5} times (+- {:.5}), \
                 but with it undone a pose the model cannot fit, or sweeps of a joint that miss one another beyond \
                 their noise, remain, or the re-run fails, so it is not named; report.md, \"Detection limits\")",
                self.scaled.columns(),
                self.factor,
                self.sigma
            ));
        }
        let short = |r: &Option<f64>| r.is_none_or(|r| r > AXIS_SCALE_REACH_CLAIM);
        if self.significant || !self.reach.iter().any(short) {
            return None;
        }
        let parts: Vec<String> = (0..3)
            .filter(|&c| short(&self.reach[c]))
            .map(|c| match self.reach[c] {
                Some(r) => format!("`{}` below {:.2} %", COLUMNS[c], r * 100.0),
                None => format!("`{}` at any size within {:.0} %", COLUMNS[c], PROFILE_REACH * 100.0),
            })
            .collect();
        Some(format!(
            "one-axis instrument scales this file cannot show: {} (report.md, \"Detection limits\")",
            parts.join(", ")
        ))
    }
}

/// What the profile reads on files that hold no scale: files simulated from the file's own
/// calibration at its commands (a robot that holds together exactly, with the file's noise),
/// each calibrated and profiled as the file was. Where the file's sweeps enter through the
/// held joints' correction, its model error (the calibration's own uncertainty, carried into
/// every corrected point) reads as a scale the noise alone does not explain: on a UR5e swept
/// 30 degrees at three poses per joint the profile read `x_mm` and `y_mm` from 1 by 3.7 of its
/// noise sigmas RMS over 61 clean files, and files simulated from one of them read `y_mm`
/// 1.0068 +- 0.0040 where the file read 1.0060. The simulated files carry that error as the
/// file does, so the finding is tested against their spread about their centre (a parametric
/// bootstrap, Efron & Tibshirani 1993, "An Introduction to the Bootstrap"): the normal-theory
/// prediction interval for one more draw, `centre +- t sigma sqrt(1 + 1/n)`, Student's t with
/// `n - 1` degrees of freedom for `n` files.
#[derive(Clone, Debug, PartialEq)]
pub struct NullSpread {
    /// The simulated files whose profile resolved a factor (a flat profile resolves none).
    pub files: usize,
    /// Their factors' mean.
    pub centre: f64,
    /// Their factors' standard deviation.
    pub sigma: f64,
    /// The two-sided tail probability of the finding's departure from `centre` over
    /// `sigma * sqrt(1 + 1 / files)` (the F ratio `(1, files - 1)` of its square).
    pub p_value: f64,
}

impl NullSpread {
    /// Whether the finding stands beyond the spread at the test's false-alarm rate per
    /// column ([`AXIS_SCALE_FALSE_ALARM`] over the three columns).
    pub fn passes(&self) -> bool {
        self.p_value < AXIS_SCALE_FALSE_ALARM / 3.0
    }
}

/// The factor the profile of `scaled` reads on `set` (calibrated with `fit`, thinned above
/// `max_rows` rows as [`axis_scale`] thins): `Some(None)` where the profile is flat (the factor
/// left at 1, a p-value of 1: it resolves nothing), `None` where a calibration fails.
pub fn factor_read(
    set: &MeasurementSet,
    scaled: Scaled,
    fit: &dyn Fn(&MeasurementSet) -> Option<Fit>,
    max_rows: usize,
) -> Option<Option<f64>> {
    let thin = thinned(set, max_rows);
    let set = thin.as_ref().unwrap_or(set);
    let read = profile(set, (scaled, 1.0), fit(set)?, fit)?;
    Some((read.p_value < 1.0).then_some(read.factor))
}

/// `found` against the factors `reads` of files that hold no scale ([`factor_read`] of each;
/// [`NullSpread`]); `None` where fewer than half of them (and than three) resolve a factor.
pub fn null_spread(found: &AxisScale, reads: &[Option<f64>]) -> Option<NullSpread> {
    let factors: Vec<f64> = reads.iter().flatten().copied().collect();
    let files = factors.len();
    if files < 3 || 2 * files < reads.len() {
        return None;
    }
    let n = files as f64;
    let centre = factors.iter().sum::<f64>() / n;
    let sigma = (factors.iter().map(|f| (f - centre).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let t = (found.factor - centre) / (sigma * (1.0 + 1.0 / n).sqrt());
    Some(NullSpread {
        files,
        centre,
        sigma,
        p_value: f_upper_tail(t * t, 1.0, n - 1.0),
    })
}

/// The profile ([`axis_scale`]) of `set` with coordinate `column` (0 `x_mm`, 1 `y_mm`, 2
/// `z_mm`) divided by `factor` about the data's centroid: what the profile reads once a named
/// column scale is undone (a second axis behind it, or nothing where the named one explains
/// the rest).
pub fn axis_scale_with_column_undone(
    set: &MeasurementSet,
    (column, factor): (usize, f64),
    fit: &dyn Fn(&MeasurementSet) -> Option<Fit>,
    max_rows: usize,
    slides: &[usize],
) -> Option<AxisScale> {
    let undone = set.with_coordinate_scaled_about(column, 1.0 / factor, centroid(set)[column]);
    axis_scale(&undone, fit, max_rows, slides)
}

/// The words of [`AxisScale::reach_note`] for report.md: why a file lets a one-axis scale pass
/// and what closes it.
pub fn axis_reach_words() -> String {
    format!(
        "Where `calibrate` notes one-axis instrument scales this file cannot show (`x_mm` below 0.44 %, say), one \
         instrument axis read that much long or short would pass the coordinate-scale test: each arc or pose alone \
         takes such a scale as a tilt or a slightly different radius, and these data's arcs and poses together pin it \
         no closer (the test names {:.1} % where they do). A length standard along that axis, or free poses spread \
         over the workspace (fitted with the sweeps, or checked by `validate`), close it.",
        AXIS_SCALE_REACH_CLAIM * 100.0
    )
}

impl AxisScale {
    /// The others read alike (` (or, alike for these data, ...)`), empty without any.
    fn alike_words(&self) -> String {
        if self.alike.is_empty() {
            return String::new();
        }
        let reads: Vec<String> = self.alike.iter().map(|&(s, f)| s.reads(f, false)).collect();
        let slide = !matches!(self.scaled, Scaled::Column(_))
            || self.alike.iter().any(|(s, _)| !matches!(s, Scaled::Column(_)));
        let why = if slide {
            "a slide's travel along one instrument axis and that axis' scale move the points alike"
        } else {
            "the robot's links take a scale of both together"
        };
        format!(" (or, alike for these data, {}: {why})", reads.join("; or "))
    }
}

impl std::fmt::Display for AxisScale {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let AxisScale {
            scaled,
            factor,
            sigma,
            rms_mm: [before, after],
            ..
        } = self;
        let against = match scaled {
            Scaled::Column(_) => "the other axes",
            Scaled::Every => "the sliding joints' travel",
            Scaled::Command(_) => "the travel the points show",
        };
        let alike = self.alike_words();
        write!(
            f,
            "{} (+- {sigma:.5}, {:.0} sigma from 1) {against}{alike}: the calibration misses the points by {before:.4} mm \
             RMS per coordinate as read and by {after:.4} mm with {} divided by {factor:.5}",
            scaled.reads(*factor, true),
            (factor - 1.0).abs() / sigma,
            scaled.columns(),
        )?;
        match scaled {
            Scaled::Column(c) => {
                let axis = &COLUMNS[*c][..1];
                write!(
                    f,
                    " about the data's centroid; each arc or pose alone takes such a scale as a tilt, the robot's arcs \
                     and poses together do not, and calibration.json has absorbed it into the geometry: check the \
                     instrument's scale along {axis} (its axis scale or compensation, a photogrammetry scale bar along \
                     it) and the exporter (a column scaled or converted alone)"
                )?;
                if self.alike.iter().any(|(s, _)| matches!(s, Scaled::Command(_))) {
                    write!(f, ", or the slide's lead or the controller's scale of its command")?;
                }
                write!(f, ", then calibrate the corrected file again")
            }
            Scaled::Every => write!(
                f,
                " about the data's centroid: the slides' readings are this file's length standard, and every point \
                 reads {factor:.5} times the length they give; an isotropic scale is the instrument's length scale or \
                 units (a laser tracker's wavelength or air compensation, a photogrammetry scale bar, the export's \
                 scaling), or every slide's lead alike: check them, then calibrate the corrected file again"
            ),
            Scaled::Command(j) => write!(
                f,
                ": the joint's readings are not its travel in millimetres; check the slide's lead or screw pitch and \
                 the controller's or the exporter's scale of `cmd_{}`, then calibrate the corrected file again",
                j + 1
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `y_mm` finding of `factor` as the profile would give it.
    fn found(factor: f64) -> AxisScale {
        AxisScale {
            scaled: Scaled::Column(1),
            factor,
            sigma: 1e-3,
            p_value: 0.0,
            rms_mm: [0.1, 0.1],
            significant: true,
            alike: vec![],
            reach: [None; 3],
            unconfirmed: false,
        }
    }

    /// Twenty files reading 1.001 +- 0.002 (ten each side): the spread is their sample
    /// standard deviation, and the prediction interval's p-value is Student's t with 19
    /// degrees of freedom, checked against the t density integrated numerically (a second
    /// path to `f_upper_tail`): a finding at the centre has p = 1, one 3 of their deviations
    /// out p ~ 7.8e-3 (inside the interval at the test's rate), one 8 out passes it.
    #[test]
    fn a_finding_is_tested_against_the_simulated_files_spread_about_their_centre() {
        let reads: Vec<Option<f64>> = (0..20)
            .map(|i| Some(1.001 + if i % 2 == 0 { 0.002 } else { -0.002 }))
            .collect();
        let at = |f: f64| null_spread(&found(f), &reads).unwrap();
        let centred = at(1.001);
        assert!((centred.centre - 1.001).abs() < 1e-12);
        let sd = 0.002 * (20.0f64 / 19.0).sqrt();
        assert!((centred.sigma - sd).abs() < 1e-12, "{}", centred.sigma);
        assert!((centred.p_value - 1.0).abs() < 1e-12 && !centred.passes());
        let width = sd * (1.0f64 + 1.0 / 20.0).sqrt();
        let t_tail = |t: f64| {
            // Two-sided tail of Student's t with 19 dof: the density integrated on x = t / u,
            // its constant Gamma(10) / (sqrt(19 pi) Gamma(9.5)), Gamma(9.5) = sqrt(pi) 0.5 1.5 .. 8.5.
            let nu = 19.0f64;
            let pi = std::f64::consts::PI;
            let gamma_half: f64 = pi.sqrt() * (0..9).map(|k| k as f64 + 0.5).product::<f64>();
            let c = 362_880.0 / ((nu * pi).sqrt() * gamma_half);
            let n = 200_000;
            let sum: f64 = (0..n)
                .map(|i| {
                    let u = (i as f64 + 0.5) / n as f64;
                    let x = t / u;
                    c * (1.0 + x * x / nu).powf(-(nu + 1.0) / 2.0) * t / (u * u)
                })
                .sum();
            2.0 * sum / n as f64
        };
        let three = at(1.001 + 3.0 * width);
        assert!(
            (three.p_value / t_tail(3.0) - 1.0).abs() < 1e-4,
            "{} vs {}",
            three.p_value,
            t_tail(3.0)
        );
        assert!(!three.passes());
        let eight = at(1.001 - 8.0 * width);
        assert!(
            (eight.p_value / t_tail(8.0) - 1.0).abs() < 1e-4,
            "{} vs {}",
            eight.p_value,
            t_tail(8.0)
        );
        assert!(eight.passes());
    }

    /// Files whose profile is flat resolve nothing: with fewer than half resolving a factor
    /// there is no verdict.
    #[test]
    fn too_few_files_resolving_a_factor_give_no_verdict() {
        let mut reads: Vec<Option<f64>> = vec![None; 11];
        reads.extend((0..9).map(|i| Some(1.0 + 1e-3 * i as f64)));
        assert!(null_spread(&found(1.01), &reads).is_none());
        reads[0] = Some(1.0);
        assert_eq!(null_spread(&found(1.01), &reads).unwrap().files, 10);
    }
}
