//! Where the instrument stands in the cell: the stations simulated measurements and planned
//! lines of sight start from.

use super::RobotDescription;
use crate::measurement::paper_stations_around_m;
use nalgebra::Point3;
use serde::{Deserialize, Serialize};

/// The instrument's stations as written (`[instrument]`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct InstrumentEntry {
    /// Station centres in the instrument frame \[mm\] (two for the theodolites; one for a
    /// laser tracker's line-of-sight plan).
    pub stations_mm: Vec<[f64; 3]>,
}

impl RobotDescription {
    /// The stations of `[instrument] stations_mm` in the instrument frame \[m\], if written.
    pub fn given_stations_m(&self) -> Option<Vec<Point3<f64>>> {
        (self.instrument.as_ref()).map(|entry| entry.stations_mm.iter().map(|s| Point3::from(*s) * 1e-3).collect())
    }

    /// Two theodolite stations around this robot facing it from `heading_rad` (about the
    /// vertical, on top of the placement's yaw): the horizontal offsets the paper's stations had
    /// from the IRB/L6's base ([`paper_stations_around_m`]), turned, at the height of the
    /// nominal tool origin with every joint at 0 (clamped into its limits) so the lines of
    /// sight run level with the work; rounded to 0.1 mm.
    pub fn stations_at_heading_m(&self, heading_rad: f64) -> [Point3<f64>; 2] {
        let tool_height_m = self.nominal_model().world_from_tool(&self.home_q()).translation.z;
        paper_stations_around_m(&self.placement.origin_m(), self.placement.yaw_rad() + heading_rad)
            .map(|s| Point3::new(s.x, s.y, tool_height_m).map(round_to_tenth_mm))
    }

    /// Joint values 0, each clamped into its limits \[rad or m\].
    fn home_q(&self) -> Vec<f64> {
        (0..self.dof())
            .map(|k| {
                let [low, high] = self.limits_internal(k);
                0.0f64.clamp(low, high)
            })
            .collect()
    }
}

/// `x_m` rounded to 0.1 mm.
fn round_to_tenth_mm(x_m: f64) -> f64 {
    (x_m * 1e4).round() / 1e4 + 0.0
}
