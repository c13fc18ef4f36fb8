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
//! test and whose every free pose the model fits within its outlier fence (a pose the model
//! cannot fit even so says the residuals are the model's limits, not noise, and any extra
//! parameter reduces them; the linearisation checked against the re-run; when it does not, one more parabola
//! about the factor found and its re-run decide). A uniform scale of all
//! three columns is one of the links' lengths, so "x reads long" and "y and z read short" are
//! one finding: the column named is the one whose undoing explains most.

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
    /// Free poses the fit finds beyond its outlier fence (0 for sweeps): a pose the model
    /// cannot fit says the residuals are not the noise the F test assumes.
    pub misfit_poses: usize,
}

/// A coordinate column's scale the data determine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisScale {
    /// The column: 0 `x_mm`, 1 `y_mm`, 2 `z_mm`.
    pub column: usize,
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
    /// Another column whose scale explains the residuals as well, within the test's reach,
    /// and the factor it reads: a robot whose links absorb a scale of two columns together (a
    /// SCARA's arm in x and y) cannot tell x long from y short.
    pub alike: Option<(usize, f64)>,
}

/// The column names, by column.
pub const COLUMNS: [&str; 3] = ["x_mm", "y_mm", "z_mm"];

/// The centroid of `set`'s coordinate `column` \[mm\].
fn centroid(set: &MeasurementSet, column: usize) -> f64 {
    let rows = set.rows();
    rows.iter().map(|m| m.position_mm[column]).sum::<f64>() / rows.len().max(1) as f64
}

/// `set` with column `column` read as `factor` times what it is (about the centroid `c`)
/// undone: divided by `factor`.
fn undone(set: &MeasurementSet, column: usize, factor: f64, c: f64) -> MeasurementSet {
    set.with_coordinate_scaled_about(column, 1.0 / factor, c)
}

/// The profile of one column about the factor `at` (module docs; `base` the fit with the
/// column divided by `at`): the factor it reads, before confirmation.
fn profile(
    set: &MeasurementSet,
    (column, at): (usize, f64),
    base: Fit,
    fit: &dyn Fn(&MeasurementSet) -> Option<Fit>,
) -> Option<AxisScale> {
    let c = centroid(set, column);
    let h = PROFILE_STEP;
    let plus = fit(&undone(set, column, at * (1.0 + h), c))?;
    let minus = fit(&undone(set, column, at * (1.0 - h), c))?;
    if plus.dof != base.dof || minus.dof != base.dof || base.dof < 2 {
        return None;
    }
    let dof = base.dof as f64;
    let slope = (plus.sum_squares_mm2 - minus.sum_squares_mm2) / (2.0 * h);
    let curvature = (plus.sum_squares_mm2 + minus.sum_squares_mm2 - 2.0 * base.sum_squares_mm2) / (2.0 * h * h);
    if !(curvature > 0.0 && slope.is_finite()) {
        return None;
    }
    let shift = slope / (2.0 * curvature);
    if shift.abs() > PROFILE_REACH_STEPS * h {
        return None;
    }
    let reduction = slope * slope / (4.0 * curvature);
    let left = (base.sum_squares_mm2 - reduction).max(0.0);
    let variance = left / (dof - 1.0);
    Some(AxisScale {
        column,
        factor: at * (1.0 - shift),
        sigma: at * (variance / curvature).sqrt(),
        p_value: f_upper_tail(reduction / variance, 1.0, dof - 1.0),
        rms_mm: [(base.sum_squares_mm2 / dof).sqrt(), (left / dof).sqrt()],
        significant: false,
        alike: None,
    })
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
    let c = centroid(set, found.column);
    let rate = AXIS_SCALE_FALSE_ALARM / 3.0;
    let at = fit(&undone(set, found.column, found.factor, c))?;
    if reduction_p(base, at)? < rate && at.misfit_poses == 0 {
        return Some(AxisScale {
            significant: true,
            ..found
        });
    }
    let again = profile(set, (found.column, found.factor), at, fit)?;
    let at = fit(&undone(set, found.column, again.factor, c))?;
    let significant = reduction_p(base, at)? < rate && at.misfit_poses == 0;
    Some(AxisScale {
        significant,
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
/// (module docs), significant or not (`significant` says), or `None` when a fit fails or the
/// profile is not a parabola (the fit changed its course between the runs).
/// Above `max_rows` rows ([`PROFILE_MAX_ROWS`], [`PROFILE_MAX_FREE_POSE_ROWS`]) the profile
/// runs on every `k`-th step.
pub fn axis_scale(
    set: &MeasurementSet,
    fit: &dyn Fn(&MeasurementSet) -> Option<Fit>,
    max_rows: usize,
) -> Option<AxisScale> {
    let thin = thinned(set, max_rows);
    let set = thin.as_ref().unwrap_or(set);
    let base = fit(set)?;
    let profiles: Vec<AxisScale> = (0..3)
        .filter_map(|column| profile(set, (column, 1.0), base, fit))
        .collect();
    let best = *profiles.iter().min_by(|a, b| a.p_value.total_cmp(&b.p_value))?;
    let rate = AXIS_SCALE_FALSE_ALARM / 3.0;
    if best.p_value >= rate {
        return Some(best);
    }
    let dof = base.dof as f64;
    let reduction = |a: &AxisScale| base.sum_squares_mm2 - a.rms_mm[1].powi(2) * dof;
    let variance = best.rms_mm[1].powi(2) * dof / (dof - 1.0);
    let apart = variance * f_upper_quantile(rate, 1.0, dof - 1.0);
    let alike = profiles
        .iter()
        .filter(|a| a.column != best.column && reduction(&best) - reduction(a) < apart)
        .map(|a| (a.column, a.factor))
        .next();
    Some(AxisScale {
        alike,
        ..confirmed(set, best, base, fit)?
    })
}
