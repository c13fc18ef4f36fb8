//! A whole file's coordinates scaled (`validate`): with a calibration held fixed the robot's
//! size is known, so a uniform scale of every measured point about the instrument's origin is
//! measurable, where a calibration of the same file would absorb it into the links' lengths. A
//! scale error of the instrument (a laser tracker's wavelength or air compensation, a
//! photogrammetry scale bar), an export that scaled the coordinates, or a robot whose size
//! changed since the calibration misses every experiment alike, which the per-experiment
//! searches ([`super::slips`], [`super::sweep_slips`]) leave as the model's error. The one
//! factor that best explains every point (Gauss-Newton, [`fitted_parameter`]) is said when it
//! lies beyond the false-alarm rate's normal quantile of its sigma from 1 and the file with it
//! undone passes every test of the validation. When no uniform scale does, each coordinate
//! column alone is tried the same way: one axis of the instrument reading long or short (its
//! axis scale, a scale bar along it) or an exporter that scaled one column, which the
//! calibration's own file would have hidden as tilts of its arcs. Tried only when a test misses by more than
//! [`GROSS_MISS_FACTOR`] times its acceptance and no other slip explains the miss, so clean
//! data pay nothing.

use super::slips::{ExplainedMiss, GROSS_MISS_FACTOR, acceptance, fitted_parameter, residuals_with, rewritten};
use super::validate::{PositionSummary, Validation, ValidationOptions, Verdict, validate};
use crate::calibration::procedure::Calibration;
use crate::measurement::{Measurement, MeasurementSet};
use crate::numerics::stats::chi_square_quantile;
use crate::robot::RobotDescription;

/// The fitted factor is searched within this ratio of 1 either way: the length units the unit
/// checks name ([`crate::measurement::unit_check::LENGTH_SLIPS`]: inches, centimetres, ...) differ from millimetres by 2.5
/// times or more; a scale within 10 % is an instrument's or an export's, not a unit.
const MAX_SCALE_RATIO: f64 = 1.1;

/// The summaries of `v`'s position tests (free poses, tool, axis experiments).
fn summaries(v: &Validation) -> impl Iterator<Item = &PositionSummary> {
    [&v.validation, &v.tool, &v.axis].into_iter().flatten()
}

/// Whether `s`'s test exceeds.
fn exceeds(s: &PositionSummary) -> bool {
    s.chi_square.as_ref().is_some_and(|c| c.verdict == Verdict::Exceeds)
}

/// The coordinate columns a scale is tried on: every one (a uniform scale) first, then each
/// alone (one axis of the instrument reading long or short), with the columns' names.
const SCALED_COLUMNS: [(&[usize], &str); 4] = [
    (&[0, 1, 2], "x_mm,y_mm,z_mm"),
    (&[0], "x_mm"),
    (&[1], "y_mm"),
    (&[2], "z_mm"),
];

/// A scale of some coordinate columns that explains a validation's misses: the factor the
/// file reads (the columns' values over what the calibration gives), its sigma, and the
/// validation with it undone.
struct FoundScale {
    factor: f64,
    sigma: f64,
    undone: Validation,
}

/// The scale of `set`'s `columns` (about the instrument's origin) that explains `v`'s misses,
/// fitted as in the module docs; `None` when it is within its noise of 1 or the file with it
/// undone still fails a test.
fn scale_of(
    set: &MeasurementSet,
    (cal, desc): (&Calibration, &RobotDescription),
    v: &Validation,
    columns: &'static [usize],
) -> Option<FoundScale> {
    let rows = set.rows();
    let scaled = |s: f64| move |m: &mut Measurement| columns.iter().for_each(|&c| m.position_mm[c] *= s);
    let at = |s: f64| residuals_with(rows, &scaled(s), cal, desc);
    let within = |s: f64| (1.0 / MAX_SCALE_RATIO..=MAX_SCALE_RATIO).contains(&s);
    let (s, jj) = fitted_parameter(&at, 1.0, [1e-6, 1e-9], &within)?;
    let sigma_s = v.noise_rms_3d_mm / 3f64.sqrt() / jj.sqrt();
    let z = chi_square_quantile(1.0 - v.false_alarm, 1.0).sqrt();
    if (s - 1.0).abs() <= z * sigma_s {
        return None;
    }
    let options = ValidationOptions::of_validation(v);
    let undone = validate(&rewritten(rows, &scaled(s), desc)?, cal, desc, &options).ok()?;
    if summaries(&undone).any(exceeds) {
        return None;
    }
    Some(FoundScale {
        factor: 1.0 / s,
        sigma: sigma_s / (s * s),
        undone,
    })
}

/// The uniform scale of every coordinate of `set` (module docs), or else the scale of one
/// coordinate column alone (an instrument axis reading long), that explains `v`'s misses, as
/// one miss naming the columns; `None` when no test misses grossly, the fitted factor is
/// within its noise of 1, or the file with it undone still fails a test. `desc` is the
/// description `v` was made with.
pub fn explained_file_scale(
    set: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
    v: &Validation,
) -> Option<ExplainedMiss> {
    let gross = summaries(v)
        .filter(|s| {
            exceeds(s) && s.rms_mm > GROSS_MISS_FACTOR * acceptance(s.predicted_mm.total, s.points, v.false_alarm)
        })
        .max_by(|a, b| a.rms_mm.total_cmp(&b.rms_mm))?;
    let (found, field) = SCALED_COLUMNS
        .iter()
        .find_map(|&(columns, field)| Some((scale_of(set, (cal, desc), v, columns)?, field)))?;
    let FoundScale { factor, sigma, undone } = found;
    let after: Vec<String> = summaries(&undone)
        .map(|u| {
            format!(
                "{} points {:.4} mm RMS where {:.4} mm is predicted",
                u.points, u.rms_mm, u.predicted_mm.total
            )
        })
        .collect();
    let missed = format!(
        "the calibrated model misses these data ({} points by {:.4} mm RMS where {:.4} mm is predicted)",
        gross.points, gross.rms_mm, gross.predicted_mm.total
    );
    let from_one = (factor - 1.0).abs() / sigma;
    let message = if field.contains(',') {
        format!(
            "{missed}, and every \
             test passes with every coordinate divided by {factor:.5} ({}): every coordinate of the file reads \
             {factor:.5} times (+- {sigma:.5}, {from_one:.0} sigma from 1) what the calibration gives, about the instrument's \
             origin: check the instrument's scale (a laser tracker's wavelength or air compensation, a photogrammetry \
             scale bar), the coordinates' units and the export's scaling, or whether the robot's size changed since \
             the calibration",
            after.join(", "),
        )
    } else {
        format!(
            "{missed}, and every test passes with the `{field}` column alone divided by {factor:.5} ({}): the \
             instrument's {} axis reads {factor:.5} times (+- {sigma:.5}, {from_one:.0} sigma from 1) what the \
             calibration gives, the other axes as it gives, about the instrument's origin: check the instrument's \
             scale along that axis (its axis or encoder scale, a photogrammetry scale bar along it) and the exporter \
             (a column scaled or converted alone)",
            after.join(", "),
            &field[..1],
        )
    };
    Some(ExplainedMiss {
        experiment: "all".into(),
        line: set.line_of(0),
        field: field.into(),
        message,
    })
}
