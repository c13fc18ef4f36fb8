//! The unit check of a scenario file (`axiscal run`, silenced by `--skip-unit-check` as the
//! description's is): values within their keys' ranges that are another unit's all the same.
//!
//! - An instrument's noise (`measurement.net_radial_rms_mm`, `[sweep] net_radial_rms_mm`)
//!   below [`MIN_NET_RADIAL_RMS_MM`]: metres where millimetres are expected.
//! - Validation half-ranges (`[validation] half_range`) whose revolute values are all at most
//!   [`RADIANS_HALF_RANGE_DEG`]: radians where degrees are expected.
//! - A truth model file's rows (`[truth] path`) in millimetres where metres are expected: the
//!   description's row check ([`crate::measurement::unit_check::row_slips`]).

use super::file::ScenarioFile;
use super::resolve::{ResolvedScenario, ResolvedTruth};
use crate::kinematics::JointKind;
use crate::measurement::unit_check::{UnitSlip, row_slips};
use crate::measurement::{format_f64, format_f64_converted};

/// The finest noise \[mm, a 3-D RMS\] of an instrument that measures a robot's tool: a laser
/// tracker is good to about 0.01 mm, the paper's theodolites to 0.19 mm. A value below it is
/// metres written where millimetres belong (0.19 mm as 0.00019); the key's range
/// (above 0, at most [`crate::calibration::procedure::MAX_NOISE_RMS_3D_MM`]) is `--noise-mm`'s.
pub const MIN_NET_RADIAL_RMS_MM: f64 = 1e-3;

/// Revolute validation half-ranges all at most this \[deg\] are radians read as degrees: a
/// joint turns at most a turn either way, 2 pi in radians. Validation poses within a few
/// degrees of the reference measure the accuracy there, not over the workspace.
pub const RADIANS_HALF_RANGE_DEG: f64 = std::f64::consts::TAU;

/// Why an instrument's noise of `mm` (3-D RMS) is metres written as millimetres: below
/// [`MIN_NET_RADIAL_RMS_MM`]. The scenario's noise keys and every `--noise-mm` are checked by it.
pub fn noise_slip(mm: f64) -> Option<String> {
    (mm < MIN_NET_RADIAL_RMS_MM).then(|| {
        format!(
            "{} mm is finer than any instrument that measures a robot (at least {MIN_NET_RADIAL_RMS_MM} mm; a \
             laser tracker: about 0.01 mm): the noise is in mm; it looks like metres ({} mm?)",
            format_f64(mm),
            format_f64_converted(mm * 1e3)
        )
    })
}

/// The likely unit slips of `file`, resolved as `scenario`.
pub fn scenario_slips(file: &ScenarioFile, scenario: &ResolvedScenario) -> Vec<UnitSlip> {
    let mut noises = vec![(
        "measurement.net_radial_rms_mm".to_owned(),
        file.measurement.net_radial_rms_mm,
    )];
    if let Some(values) = file.sweep.as_ref().and_then(|s| s.net_radial_rms_mm.as_ref()) {
        noises.extend(
            values
                .iter()
                .enumerate()
                .map(|(i, v)| (format!("sweep.net_radial_rms_mm[{i}]"), *v)),
        );
    }
    let mut slips: Vec<UnitSlip> = noises
        .into_iter()
        .filter_map(|(field, mm)| {
            Some(UnitSlip {
                field,
                message: noise_slip(mm)?,
            })
        })
        .collect();
    if file.validation.is_some() {
        slips.extend(radians_half_range(scenario));
    }
    if let ResolvedTruth::Fixed { robot } = &scenario.truth {
        slips.extend(row_slips(&robot.rows).into_iter().map(|s| UnitSlip {
            field: format!("truth: {}", s.field),
            ..s
        }));
    }
    slips
}

/// The validation half-ranges when every revolute one (and one at least above 0) is at most
/// [`RADIANS_HALF_RANGE_DEG`].
fn radians_half_range(scenario: &ResolvedScenario) -> Option<UnitSlip> {
    let half = &scenario.validation.half_range;
    let revolute: Vec<f64> = scenario
        .robot
        .joints
        .iter()
        .zip(half)
        .filter(|(j, _)| j.kind == JointKind::Revolute)
        .map(|(_, h)| *h)
        .collect();
    let widest = revolute.iter().fold(0.0_f64, |m, h| m.max(*h));
    (widest > 0.0 && widest <= RADIANS_HALF_RANGE_DEG).then(|| {
        let shown: Vec<String> = half.iter().map(|h| format_f64(*h)).collect();
        UnitSlip {
            field: "validation.half_range".into(),
            message: format!(
                "[{}]: every revolute joint's half-range is at most {} deg, so every validation pose sits within {} \
                 deg of the reference and measures the accuracy there, not over the workspace: the half-ranges are in \
                 deg (or mm); they look like radians ({} rad is {:.1} deg)",
                shown.join(", "),
                format_f64((RADIANS_HALF_RANGE_DEG * 100.0).round() / 100.0),
                format_f64(widest),
                format_f64(widest),
                widest.to_degrees()
            ),
        }
    })
}
