//! Extra harmonic terms of a joint's transmission (eq. 8): gear errors of orders the
//! calibrated transmission form does not carry.

use crate::robot::{RobotModel, Transmission};
use serde::{Deserialize, Serialize};

/// One extra harmonic term of a joint's transmission `theta_c = f(theta_a)` (eq. 8).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GearHarmonic {
    /// The joint (1-based).
    pub joint: usize,
    /// Harmonic order `n >= 1`, in the transmission's own angle (the gear angle for a
    /// [`Transmission::Gear`]).
    pub order: usize,
    /// Added sine coefficient \[rad\] (gear units for a gear).
    #[serde(default)]
    pub sin_rad: f64,
    /// Added cosine coefficient \[rad\].
    #[serde(default)]
    pub cos_rad: f64,
}

/// `model` with the extra `harmonics` added to its joints' transmissions (a harmonic of a
/// joint the model does not have, or of a sliding joint, is ignored).
pub fn with_gear_harmonics(model: &RobotModel, harmonics: &[GearHarmonic]) -> RobotModel {
    let mut m = model.clone();
    for h in harmonics {
        let Some(joint) = m.joints.get_mut(h.joint.wrapping_sub(1)) else {
            continue;
        };
        let (sin, cos) = match &mut joint.transmission {
            Transmission::Harmonic { sin, cos } | Transmission::Gear { sin, cos, .. } => (sin, cos),
            // A sliding joint's screw has no angle to carry a harmonic.
            Transmission::Polynomial { .. } => continue,
        };
        for v in [&mut *sin, &mut *cos] {
            if v.len() < h.order {
                v.resize(h.order, 0.0);
            }
        }
        sin[h.order - 1] += h.sin_rad;
        cos[h.order - 1] += h.cos_rad;
    }
    m
}
