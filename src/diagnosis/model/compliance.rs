//! The compliance candidates' sag: the gravity load of each mass model in product units
//! (compliance times mass and first moment) and the static equilibrium under it at unit
//! stiffness ([`coupled_static_deflection`]).

use super::candidate::{Candidate, MassModel, SpringSite};
use super::effect_set::EffectSet;
use super::{GRAVITY_M_S2, Predictor};
use crate::kinematics::PhiModel;
use crate::physics::{ComplianceEffect, CompliantLoad, LinkMass, PassiveSlope, coupled_static_deflection};
use crate::robot::{CouplingFunction, RobotModel};
use nalgebra::Vector3;

/// The calibrated couplings at the active displacements `active`, for
/// [`coupled_static_deflection`]: the slope of every `coupling_in`; the fractional (eq. 15)
/// and four-bar forms are mechanisms that also carry the driven joint's load back to the
/// actuator below, a gear is kinematic only.
fn passive_slopes(robot: &RobotModel, active: &[f64]) -> Vec<PassiveSlope> {
    PassiveSlope::of_robot(robot, active, |_, g| {
        matches!(g, CouplingFunction::Fractional { .. } | CouplingFunction::FourBar(_))
    })
}

impl Predictor {
    /// The gravity load of compliance member `masses` of `joint` (1-based) with parameters
    /// `e`, as link masses times the compliance (unit stiffness then gives the sag), the
    /// pose's `payload_kg` folded into the last link: at the tool frame's origin, offset by the
    /// fitted offset (tool frame) where the member fits one.
    fn compliance_masses(
        &self,
        model: &PhiModel,
        masses: MassModel,
        joint: usize,
        e: &[f64],
        payload_kg: f64,
    ) -> Vec<LinkMass> {
        let n = self.dof();
        let scaled = |c: f64| -> Vec<LinkMass> {
            self.masses
                .iter()
                .map(|m| LinkMass {
                    mass_kg: m.mass_kg * c,
                    first_moment_kg_m: m.first_moment_kg_m * c,
                })
                .collect()
        };
        let (mut loads, c_payload, c_offset) = match masses {
            MassModel::Description => (scaled(e[0]), e[0], Vector3::zeros()),
            MassModel::PayloadOffset => (scaled(e[0]), e[0], Vector3::new(e[1], e[2], e[3])),
            MassModel::Lumped => {
                let mut v = vec![
                    LinkMass {
                        mass_kg: 0.0,
                        first_moment_kg_m: Vector3::zeros()
                    };
                    n
                ];
                for (o, link) in (joint - 1..n).enumerate() {
                    v[link] = LinkMass {
                        mass_kg: e[4 * o],
                        first_moment_kg_m: Vector3::new(e[4 * o + 1], e[4 * o + 2], e[4 * o + 3]),
                    };
                }
                let p = 4 * (n + 1 - joint);
                (v, e[p], Vector3::new(e[p + 1], e[p + 2], e[p + 3]))
            }
        };
        let tool = &model.last_link_from_tool;
        let last = &mut loads[n - 1];
        last.mass_kg += c_payload * payload_kg;
        last.first_moment_kg_m += (tool.translation.vector * c_payload + tool.rotation * c_offset) * payload_kg;
        loads
    }

    /// The sum of the compliance candidates' sags at joint values `q` (each the static
    /// equilibrium of its own spring, at the undeflected pose: two springs interact at second
    /// order in the sag); `None` when an equilibrium is not found (the arm would buckle).
    pub(super) fn sag(
        &self,
        robot: &RobotModel,
        model: &PhiModel,
        effects: &EffectSet,
        q: &[f64],
        active: &[f64],
        payload_kg: f64,
    ) -> Option<Vec<f64>> {
        let n = q.len();
        let mut total = vec![0.0; n];
        for (c, e) in &effects.compliance {
            let Candidate::JointCompliance { joint, spring, masses } = *c else {
                continue;
            };
            if e.iter().all(|x| *x == 0.0) {
                continue;
            }
            let loads = self.compliance_masses(model, masses, joint, e, payload_kg);
            let mut stiffness_nm_per_rad = vec![f64::INFINITY; n];
            stiffness_nm_per_rad[joint - 1] = 1.0;
            let compliance = ComplianceEffect {
                stiffness_nm_per_rad,
                gravity_m_s2: GRAVITY_M_S2,
            };
            let mut couplings = passive_slopes(robot, active);
            if spring == SpringSite::Joint
                && let Some(out) = couplings.get_mut(joint)
            {
                *out = PassiveSlope::default();
            }
            let load = CompliantLoad {
                masses: &loads,
                payload: None,
                compliance: &compliance,
                couplings: &couplings,
            };
            let dq = coupled_static_deflection(model, q, &load).ok()?;
            for (t, d) in total.iter_mut().zip(dq) {
                *t += d;
            }
        }
        Some(total)
    }
}
