//! A measured point an outlier test flagged ([`OutlierPoint`]): what `calibration.json`'s
//! `outliers` lists, and the row of the data it came from.

use crate::measurement::MeasurementSet;
use serde::{Deserialize, Serialize};

/// A measured point an outlier test flagged: a sweep's point (this module's test) or a
/// validation point of the diagnosis (`diagnosis::validation_outliers`, `joint` 0).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct OutlierPoint {
    /// The experiment.
    pub experiment: String,
    /// Its swept joint (0: a validation point).
    pub joint: usize,
    /// The point's step.
    pub step: usize,
    /// The target (0: the sweep's first target).
    pub target: usize,
    /// The line of the data file it was read from, when known.
    pub line: Option<u64>,
    /// Its 3-D distance from the fit of its sweep's points kept (a validation point: from the
    /// calibrated model after the diagnosis's baseline refit) \[mm\].
    pub residual_mm: f64,
    /// That residual over the noise per axis (its sweep's; a validation point: the
    /// diagnosis's), about `sqrt(3)` for a point of the noise.
    pub normalised_residual: f64,
    /// The fence it exceeds (Tukey's far-out fence of every sweep point's, or every
    /// validation point's, normalised residual).
    pub fence: f64,
    /// Whether the calibration (the diagnosis) was made without it, and for a sweep point
    /// without the other targets of its pose (`false` with `--keep-outliers`).
    pub dropped: bool,
    /// A sweep's first point, taken before its joint moved, off its fit only along the sweep's
    /// motion, ahead toward its second point: the swept joint's turn \[rad\] (a sliding joint's
    /// travel \[m\]) that puts it there, its backlash taken up on the other side before the
    /// sweep's first move (`screen`'s approach test); `None` for any other point.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub approach: Option<f64>,
    /// The test that flagged it; absent for the sweep screen's (and the validation poses').
    #[serde(default, skip_serializing_if = "OutlierTest::is_screen")]
    pub test: OutlierTest,
}

/// The test that flagged an [`OutlierPoint`] (`docs/method.md`, "Outliers").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum OutlierTest {
    /// The sweep screen: the point's residual from the fit of its sweep's other points over
    /// their noise, against a fence a clean file passes with 99 % probability (the validation
    /// poses' screen in a diagnosis).
    #[default]
    Screen,
    /// The procedure's axis fit of a sweep whose held joints wander, which failed with it: its
    /// distance from the path the sweep's other points draw, beyond Tukey's far-out fence of
    /// their distances (`procedure/misfit.rs`).
    AxisFit,
    /// The screen of a sweep whose held joints wander, its points moved to the design pose by
    /// the calibrated model (`screen_wandering_sweeps`): the sweep screen's test and fence.
    Moved,
}

impl OutlierTest {
    /// Whether it is the sweep screen's ([`OutlierTest::Screen`]).
    pub fn is_screen(&self) -> bool {
        *self == OutlierTest::Screen
    }
}

/// The set's row of a flagged point.
pub(super) fn row_of(set: &MeasurementSet, o: &OutlierPoint) -> Option<usize> {
    set.rows()
        .iter()
        .position(|m| m.experiment == o.experiment && m.step == o.step && m.target == o.target)
}
