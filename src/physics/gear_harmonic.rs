//! Extra harmonic terms of a joint's transmission (eq. 8): gear errors of orders the
//! calibrated transmission form does not carry, periodic in the transmission's own angle or in
//! the joint's.

use crate::robot::{RobotModel, Transmission};
use serde::{Deserialize, Serialize};

/// Which angle a [`GearHarmonic`] is periodic in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum HarmonicPeriod {
    /// The transmission's own angle (eq. 8): the joint's active displacement for a harmonic
    /// transmission, the gear angle `theta_a / N` for a [`Transmission::Gear`]; the term is
    /// added to the transmission's coefficients.
    #[default]
    Transmission,
    /// The joint's active displacement `theta_a` itself, whatever the transmission (for a
    /// geared joint: an error of its output stage, periodic in the joint's turn rather than
    /// the gear's): the actual displacement is `theta_a + s sin(n theta_a) + c cos(n theta_a)`,
    /// `theta_a` the displacement the transmission gives ([`joint_period_error_rad`]).
    Joint,
}

/// One extra harmonic term of a joint's transmission `theta_c = f(theta_a)` (eq. 8), or of its
/// actual displacement ([`HarmonicPeriod::Joint`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GearHarmonic {
    /// The joint (1-based).
    pub joint: usize,
    /// Harmonic order `n >= 1` in the angle of `period`.
    pub order: usize,
    /// Added sine coefficient \[rad\] (gear units for a gear's transmission period).
    #[serde(default)]
    pub sin_rad: f64,
    /// Added cosine coefficient \[rad\].
    #[serde(default)]
    pub cos_rad: f64,
    /// The angle the term is periodic in; default the transmission's.
    #[serde(default, skip_serializing_if = "is_transmission")]
    pub period: HarmonicPeriod,
}

fn is_transmission(p: &HarmonicPeriod) -> bool {
    *p == HarmonicPeriod::Transmission
}

/// `model` with the extra transmission-period `harmonics` added to its joints' transmissions (a
/// harmonic of a joint the model does not have, or of a sliding joint, is ignored; joint-period
/// ones are applied to the displacement, [`joint_period_error_rad`]).
pub fn with_gear_harmonics(model: &RobotModel, harmonics: &[GearHarmonic]) -> RobotModel {
    let mut m = model.clone();
    for h in harmonics.iter().filter(|h| h.period == HarmonicPeriod::Transmission) {
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

/// The error the joint-period `harmonics` of `joint` (1-based) add to its active displacement
/// `theta_a` \[rad\]: `sum (s sin(n theta_a) + c cos(n theta_a))` ([`HarmonicPeriod::Joint`]).
pub fn joint_period_error_rad(harmonics: &[GearHarmonic], joint: usize, theta_a: f64) -> f64 {
    harmonics
        .iter()
        .filter(|h| h.joint == joint && h.period == HarmonicPeriod::Joint)
        .map(|h| {
            let (s, c) = (h.order as f64 * theta_a).sin_cos();
            h.sin_rad * s + h.cos_rad * c
        })
        .sum()
}

/// Adds the joint-period `harmonics` to the active displacements `active` (index `k` = joint
/// `k + 1`) in place ([`joint_period_error_rad`]).
pub fn add_joint_period_errors(harmonics: &[GearHarmonic], active: &mut [f64]) {
    for (k, a) in active.iter_mut().enumerate() {
        *a += joint_period_error_rad(harmonics, k + 1, *a);
    }
}
