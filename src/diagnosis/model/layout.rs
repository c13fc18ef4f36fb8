//! The refit's parameters named ([`RefitParameter`]) and applied to a robot model: what
//! `calibrate --refine` refines and writes back into `calibration.json`.

use super::{Predictor, RefitScope, coupling_parameters};
use crate::calibration::refine::RefitParameter;
use crate::kinematics::JointKind;
use crate::robot::{CouplingFunction, Placement, RobotModel};

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
