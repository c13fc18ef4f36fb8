//! Backlash: a direction-dependent dead band of a joint.

use serde::{Deserialize, Serialize};

/// Backlash: a direction-dependent dead band per joint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BacklashEffect {
    /// Width of the dead band of each joint \[rad\] (>= 0).
    pub band_rad: Vec<f64>,
}

impl BacklashEffect {
    /// The active displacement `active` of a joint whose dead band is `band_rad`, approached
    /// in direction `approach` (+1, -1, or 0 before any motion: the middle of the band): it
    /// lags half the band behind the approach.
    pub fn lagged(active: f64, approach: f64, band_rad: f64) -> f64 {
        active - approach * band_rad / 2.0
    }
}
