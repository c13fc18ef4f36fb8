//! The refit's parameters named ([`RefitParameter`]) and applied to a robot model: what
//! `calibrate --refine` refines and writes back into `calibration.json`.

use super::{Candidate, Predictor, RefitScope, coupling_parameters};
use crate::calibration::refine::RefitParameter;
use crate::kinematics::JointKind;
use crate::robot::{BacklashTerm, CouplingFunction, Placement, RobotModel};

/// The names of a coupling's refit coefficients, in [`coupling_parameters`] order.
fn coupling_names(g: Option<&CouplingFunction>) -> Vec<String> {
    match g {
        Some(CouplingFunction::Gear { sin, cos, .. }) => std::iter::once("ratio".to_owned())
            .chain((1..=sin.len()).map(|i| format!("sin{i}")))
            .chain((1..=cos.len()).map(|i| format!("cos{i}")))
            .collect(),
        Some(CouplingFunction::Fractional { .. }) => ["n0", "n1", "n2", "d0", "d1"].map(String::from).to_vec(),
        Some(CouplingFunction::FourBar(_)) | None => Vec::new(),
    }
}

impl Predictor {
    /// The baseline refit's parameters in their order ([`Predictor::geometric_count`]).
    pub fn refit_layout(&self) -> Vec<RefitParameter> {
        let mut out = Vec::with_capacity(self.geometric_count());
        for r in 1..=self.base.rows.len() {
            out.extend([
                RefitParameter::RowA(r),
                RefitParameter::RowB(r),
                RefitParameter::RowAlpha(r),
                RefitParameter::RowBeta(r),
            ]);
        }
        for (k, j) in self.base.joints.iter().enumerate() {
            out.push(RefitParameter::ZeroOffset {
                joint: k + 1,
                sliding: j.kind == JointKind::Prismatic,
            });
        }
        if self.scope == RefitScope::Identified {
            for (k, j) in self.base.joints.iter().enumerate() {
                let names = coupling_names(j.coupling_in.as_ref());
                debug_assert_eq!(names.len(), coupling_parameters(j.coupling_in.as_ref()));
                out.extend(names.into_iter().map(|coefficient| RefitParameter::Coupling {
                    joint: k + 1,
                    coefficient,
                }));
            }
            for (k, &orders) in self.harmonic_orders.iter().enumerate() {
                for order in 1..=orders {
                    for cosine in [false, true] {
                        out.push(RefitParameter::Harmonic {
                            joint: k + 1,
                            order,
                            cosine,
                        });
                    }
                }
            }
        }
        for target in 0..self.tool_targets_m.len() {
            out.extend((0..3).map(|axis| RefitParameter::Target { target, axis }));
        }
        out.extend((0..6).map(RefitParameter::Base));
        out.extend((0..6).map(RefitParameter::Tool));
        out
    }

    /// The candidates' parameters in their order after the refit's, named
    /// `joint<J>.<effect>.<parameter>` (`<effect>.<parameter>` without a joint).
    pub fn effect_layout(&self) -> Vec<RefitParameter> {
        self.candidates
            .iter()
            .flat_map(|c| {
                let prefix = match c.joint() {
                    Some(j) => format!("joint{j}.{}", c.effect_name()),
                    None => c.effect_name().to_owned(),
                };
                c.parameter_names(&self.shape)
                    .into_iter()
                    .map(move |p| RefitParameter::Effect {
                        name: format!("{prefix}.{p}"),
                    })
            })
            .collect()
    }

    /// [`Predictor::refit_robot`] with the candidates (each [`crate::diagnosis::carriable`])
    /// at `params` carried: a transmission-period harmonic in its transmission, a compliance
    /// as `effects.compliance`, a backlash as `effects.backlash` (the model's backlash lags the
    /// actuator command, the candidate's the active displacement: they differ by the half band
    /// times the transmission's slope error, 1e-3 of it at most).
    pub fn carried_robot(&self, params: &[f64]) -> RobotModel {
        let (mut robot, _) = self.robot_and_effects(params);
        let model = self.model(&robot, params);
        robot.placement = Placement::from_isometry(&model.world_from_base);
        robot.tool_frame = Placement::from_isometry(&model.last_link_from_tool);
        let phi = robot.phi_model();
        let mut at = self.geometric_count();
        for c in &self.candidates {
            let count = c.parameter_names(&self.shape).len();
            let e = &params[at..at + count];
            at += count;
            match *c {
                Candidate::JointCompliance { .. } => robot.effects.compliance.extend(self.compliance_term(&phi, *c, e)),
                Candidate::Backlash { joint, .. } => {
                    robot.effects.backlash.push(BacklashTerm { joint, half_band: e[0] })
                }
                _ => {}
            }
        }
        robot
    }

    /// The calibrated robot with the refit corrections `params` applied (rows, zero offsets,
    /// couplings, transmission harmonics, base placement and tool frame): it predicts what
    /// [`Predictor::residuals`] predicts at `params` with the description's tool targets (the
    /// refit's target corrections are not carried: `calibrate --refine` keeps them fixed).
    /// Without candidates.
    pub fn refit_robot(&self, params: &[f64]) -> RobotModel {
        let plain = self.with_candidates(&[]);
        let (mut robot, _) = plain.robot_and_effects(params);
        let model = plain.model(&robot, params);
        robot.placement = Placement::from_isometry(&model.world_from_base);
        robot.tool_frame = Placement::from_isometry(&model.last_link_from_tool);
        robot
    }
}
