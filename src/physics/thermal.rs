//! Thermal expansion of the links about the base frame's origin.

use crate::kinematics::PhiModel;
use serde::{Deserialize, Serialize};

fn default_reference_c() -> f64 {
    20.0
}

/// Thermal expansion of the links: uniform, or link by link.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ThermalEffect {
    /// Linear expansion coefficient of every link \[1/K\] (steel about 1.2e-5, aluminium
    /// 2.3e-5).
    pub alpha_per_k: f64,
    /// Temperature at which the truth's lengths hold \[deg C\]; default 20.
    #[serde(default = "default_reference_c")]
    pub reference_c: f64,
    /// Per row of the phi-model (one per link between two joints), a coefficient added to
    /// `alpha_per_k` \[1/K\] (links of different materials or temperatures); empty (default):
    /// the same coefficient everywhere.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub alpha_per_k_rows: Vec<f64>,
}

impl ThermalEffect {
    /// A uniform expansion of coefficient `alpha_per_k` about `reference_c`.
    pub fn uniform(alpha_per_k: f64, reference_c: f64) -> Self {
        ThermalEffect {
            alpha_per_k,
            reference_c,
            alpha_per_k_rows: Vec::new(),
        }
    }

    /// The coefficient of row `r` \[1/K\].
    pub fn row_alpha_per_k(&self, r: usize) -> f64 {
        self.alpha_per_k + self.alpha_per_k_rows.get(r).copied().unwrap_or(0.0)
    }

    /// The phi-model at temperature `temperature_c`: row `r`'s `a` and `b` scaled by
    /// `1 + alpha_r (T - T_ref)`.
    pub fn expanded(&self, model: &PhiModel, temperature_c: f64) -> PhiModel {
        let mut m = model.clone();
        let dt = temperature_c - self.reference_c;
        for (r, row) in m.rows.iter_mut().enumerate() {
            let s = 1.0 + self.row_alpha_per_k(r) * dt;
            row.a_m *= s;
            row.b_m *= s;
        }
        m
    }
}
