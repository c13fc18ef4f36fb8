//! A scale error of the measuring instrument.

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

/// A scale error of the instrument.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct InstrumentScale {
    /// Measured coordinates are `(1 + ppm 1e-6)` times the true ones, about the instrument
    /// origin \[ppm\].
    pub ppm: f64,
}

impl InstrumentScale {
    /// What the scaled instrument reports for a (noisy) measurement `p` (instrument frame).
    pub fn applied_to(&self, p: &Point3<f64>) -> Point3<f64> {
        Point3::from(p.coords * (1.0 + self.ppm * 1e-6))
    }
}
