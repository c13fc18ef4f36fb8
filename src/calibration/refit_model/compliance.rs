//! The compliance candidates' sag: the gravity load of each mass model in product units
//! (compliance times mass and first moment) as a [`ComplianceTerm`], whose static equilibrium
//! at unit stiffness is the sag (the same term a model carries, `calibrate --carry`).

use super::Predictor;
use super::candidate::{Candidate, LoadPath, MassModel, serial_load_count};
use super::effect_set::EffectSet;
use super::poses::Pose;
use crate::kinematics::PhiModel;
use crate::physics::{LinkMass, coupled_first_order_deflection_at};
use crate::robot::{ComplianceTerm, LoadProduct, RobotModel, SpringLoad};
use nalgebra::{DMatrix, Vector3};

/// Step \[rad\] of the joint offsets in [`Predictor::joint_sensitivity`]: moves the targets by
/// about 1e-6 m, where the central difference's rounding (about `eps x 1 m / 1e-6 m`, 2e-10
/// relative) and its truncation (`(1e-6)^2 / 6` of the next derivative) are both negligible.
pub(super) const JOINT_STEP_RAD: f64 = 1e-6;

impl Predictor {
    /// One gravity load of a compliance member as link masses times the compliance (unit
    /// stiffness then gives the sag), `e` its parameters ([`super::candidate`]'s
    /// `load_names`): the description's masses scaled, with a payload at the tool frame's
    /// origin offset by the fitted offset (tool frame) where the member fits one; or lumped
    /// from link `first_link` (1-based) on; the payload's per kg.
    fn spring_load(&self, model: &PhiModel, masses: MassModel, first_link: usize, e: &[f64]) -> SpringLoad {
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
                let mut v = vec![LinkMass::default(); n];
                for (o, link) in (first_link - 1..n).enumerate() {
                    v[link] = LinkMass {
                        mass_kg: e[4 * o],
                        first_moment_kg_m: Vector3::new(e[4 * o + 1], e[4 * o + 2], e[4 * o + 3]),
                    };
                }
                let p = 4 * (n + 1 - first_link);
                (v, e[p], Vector3::new(e[p + 1], e[p + 2], e[p + 3]))
            }
        };
        let tool = &model.last_link_from_tool;
        let payload = LinkMass {
            mass_kg: c_payload,
            first_moment_kg_m: tool.translation.vector * c_payload + tool.rotation * c_offset,
        };
        loads.truncate(n);
        SpringLoad {
            links: loads.iter().map(LoadProduct::of).collect(),
            payload: LoadProduct::of(&payload),
        }
    }

    /// Compliance member `c` with parameters `e` as the term a model carries; `None` for
    /// another candidate.
    pub fn compliance_term(&self, model: &PhiModel, c: Candidate, e: &[f64]) -> Option<ComplianceTerm> {
        let Candidate::JointCompliance {
            joint,
            spring,
            masses,
            load,
        } = c
        else {
            return None;
        };
        let serial = serial_load_count(masses, joint, self.dof());
        Some(ComplianceTerm {
            joint,
            spring,
            reflects_load: load != LoadPath::Serial,
            carried: self.spring_load(model, masses, joint, &e[..serial]),
            reflected: (load == LoadPath::Mixed).then(|| self.spring_load(model, masses, joint + 1, &e[serial..])),
        })
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
            if e.iter().all(|x| *x == 0.0) {
                continue;
            }
            let Some(term) = self.compliance_term(model, *c, e) else {
                continue;
            };
            let dq = term.deflection(robot, model, q, active, payload_kg)?;
            for (t, d) in total.iter_mut().zip(dq) {
                *t += d;
            }
        }
        Some(total)
    }

    /// The sensitivity `d prediction / d q` of the residual rows of `poses` (as
    /// [`Predictor::residuals`] at `params`) to a joint offset common to every pose: the rows
    /// of one pose depend on its own joint values only, so they are that pose's Jacobian. By
    /// central differences ([`crate::calibration::refine::sensitivity`], the one tool), the
    /// joint values before the offset computed once.
    pub fn joint_sensitivity(&self, params: &[f64], poses: &[&Pose]) -> Option<DMatrix<f64>> {
        let n = self.dof();
        let memo = self.joint_memo(params, poses);
        crate::calibration::refine::sensitivity(
            |offset| self.residuals_offset(params, poses, offset, memo.as_ref()),
            &vec![0.0; n],
            &vec![JOINT_STEP_RAD; n],
        )
    }

    /// The sensitivity `X = d prediction / d e` of compliance candidate `candidate` at `e = 0`
    /// (the refit at zero) on the residual rows of `poses`, from the joints' sensitivity
    /// `joint_x` ([`Predictor::joint_sensitivity`] at zero): chain rule `X = J_q (d sag / d e)`.
    /// The sag is the fixed point `dq = C(q + dq; e)` of [`coupled_static_deflection`](crate::physics::coupled_static_deflection), whose
    /// map `C` is linear in the loads and the loads linear in `e`
    /// (`compliance_masses`); at `e = 0` the sag is zero, so `d sag / d e_i` is
    /// the first-order map of the unit load `e_i` at the undeflected pose,
    /// [`coupled_first_order_deflection`](crate::physics::coupled_first_order_deflection), exactly. `None` for another candidate or a command
    /// the model cannot execute.
    pub fn compliance_sensitivity(
        &self,
        candidate: Candidate,
        joint_x: &DMatrix<f64>,
        poses: &[&Pose],
    ) -> Option<DMatrix<f64>> {
        let count = candidate.parameter_names(&self.shape).len();
        let zeros = vec![0.0; self.geometric_count() + self.effect_count()];
        let (robot, effects) = self.robot_and_effects(&zeros);
        let model = self.model(&robot, &zeros);
        let shape = self.compliance_term(&model, candidate, &vec![0.0; count])?;
        let compliance = shape.unit_compliance(self.dof());
        let mut x = DMatrix::zeros(joint_x.nrows(), count);
        let mut row = 0;
        for pose in poses {
            let (q, active) = self.joint_values(&robot, &effects, pose)?;
            let model_t = effects.model_at(&model, pose.temperature_c);
            let couplings = shape.couplings(&robot, &active);
            let rows = 3 * pose.targets.len();
            let j_q = joint_x.rows(row, rows);
            // Every unit load of the pose sees the same frames: computed once.
            let frames = model_t.poses(&q);
            let mut unit = vec![0.0; count];
            for i in 0..count {
                unit[i] = 1.0;
                let term = self.compliance_term(&model_t, candidate, &unit)?;
                unit[i] = 0.0;
                let dq = term.with_load(pose.payload_kg, &compliance, &couplings, |load| {
                    coupled_first_order_deflection_at(&model_t, &frames, load)
                });
                x.view_mut((row, i), (rows, 1))
                    .copy_from(&(j_q * nalgebra::DVector::from_vec(dq)));
            }
            row += rows;
        }
        (row == joint_x.nrows()).then_some(x)
    }
}
