//! The effects of a predictor's candidates at given parameters, gathered by where they act:
//! transmissions, active displacements, axis tilts, the phi-model at a temperature, the
//! instrument, the gravity sag.

use super::candidate::{Candidate, ModelShape, ThermalLinks, TiltShape};
use crate::kinematics::PhiModel;
use crate::physics::{ApproachSource, AxisTiltSeries, GearHarmonic, ThermalEffect};

/// The candidates' effects (the refit's transmission harmonics live in the robot).
#[derive(Clone, Debug)]
pub(super) struct EffectSet {
    /// Extra harmonics: transmission-period ones go into the robot's transmissions,
    /// joint-period ones onto the active displacements.
    pub(super) harmonics: Vec<GearHarmonic>,
    /// Backlash lags: (0-based joint, whose direction, half band \[rad\]).
    pub(super) backlash: Vec<(usize, ApproachSource, f64)>,
    /// Axis tilts.
    pub(super) tilts: Vec<AxisTiltSeries>,
    /// Thermal expansion.
    pub(super) thermal: Option<ThermalEffect>,
    /// Measured coordinates over true ones.
    pub(super) scale: f64,
    /// Compliance candidates and their parameters.
    pub(super) compliance: Vec<(Candidate, Vec<f64>)>,
    reference_c: f64,
}

impl EffectSet {
    /// No effect; thermal expansion about `reference_c`.
    pub(super) fn new(reference_c: f64) -> Self {
        EffectSet {
            harmonics: Vec::new(),
            backlash: Vec::new(),
            tilts: Vec::new(),
            thermal: None,
            scale: 1.0,
            compliance: Vec::new(),
            reference_c,
        }
    }

    /// Adds candidate `c` with its parameters `e`.
    pub(super) fn add(&mut self, c: Candidate, e: &[f64], shape: &ModelShape) {
        match c {
            Candidate::GearHarmonic { joint, order, period } => self.harmonics.push(GearHarmonic {
                joint,
                order,
                sin_rad: e[0],
                cos_rad: e[1],
                period,
            }),
            Candidate::Backlash { joint, direction } => self.backlash.push((joint - 1, direction, e[0])),
            Candidate::AxisWobble { joint, order, shape } => {
                let (cos_rad, sin_rad) = match shape {
                    // A tilt (x, y) turning at n q: cos(n q) (x, y) + sin(n q) (-y, x).
                    TiltShape::Rotating => ([e[0], e[1]], [-e[1], e[0]]),
                    TiltShape::General => ([e[0], e[1]], [e[2], e[3]]),
                };
                self.tilts.push(AxisTiltSeries {
                    joint,
                    order,
                    cos_rad,
                    sin_rad,
                });
            }
            Candidate::ThermalExpansion { links } => {
                let t = self
                    .thermal
                    .get_or_insert_with(|| ThermalEffect::uniform(0.0, self.reference_c));
                match links {
                    ThermalLinks::Uniform => t.alpha_per_k += e[0],
                    ThermalLinks::PerLink => {
                        if t.alpha_per_k_rows.is_empty() {
                            t.alpha_per_k_rows = vec![0.0; shape.dof.saturating_sub(1)];
                        }
                        for (&r, a) in shape.thermal_rows.iter().zip(e) {
                            t.alpha_per_k_rows[r] += a;
                        }
                    }
                }
            }
            Candidate::InstrumentScale => self.scale *= 1.0 + e[0] * 1e-6,
            Candidate::JointCompliance { .. } => self.compliance.push((c, e.to_vec())),
        }
    }

    /// The phi-model at temperature `temperature_c`.
    pub(super) fn model_at(&self, model: &PhiModel, temperature_c: f64) -> PhiModel {
        self.expanded_at(model, temperature_c).unwrap_or_else(|| model.clone())
    }

    /// [`EffectSet::model_at`] when it differs from `model` (a thermal effect in the set).
    pub(super) fn expanded_at(&self, model: &PhiModel, temperature_c: f64) -> Option<PhiModel> {
        self.thermal.as_ref().map(|t| t.expanded(model, temperature_c))
    }
}
