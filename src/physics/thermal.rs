//! Thermal expansion of the links about the base frame's origin.

use crate::kinematics::PhiModel;
use serde::{Deserialize, Serialize};

fn default_reference_c() -> f64 {
    20.0
}

/// Thermal expansion of the links.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ThermalEffect {
    /// Linear expansion coefficient \[1/K\] (steel about 1.2e-5, aluminium 2.3e-5).
    pub alpha_per_k: f64,
    /// Temperature at which the truth's lengths hold \[deg C\]; default 20.
    #[serde(default = "default_reference_c")]
    pub reference_c: f64,
}

impl ThermalEffect {
    /// The phi-model at temperature `temperature_c`: every row's `a` and `b` scaled by
    /// `1 + alpha (T - T_ref)`.
    pub fn expanded(&self, model: &PhiModel, temperature_c: f64) -> PhiModel {
        let mut m = model.clone();
        let s = 1.0 + self.alpha_per_k * (temperature_c - self.reference_c);
        for row in &mut m.rows {
            row.a_m *= s;
            row.b_m *= s;
        }
        m
    }
}
