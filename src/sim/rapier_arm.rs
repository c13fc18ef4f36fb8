//! The rapier arm as the campaign's simulated robot ([`ArmExecutor`]).
//!
//! Per command: the [`JointDriver`] (fig. 3 controller, the truth's transmissions with any
//! extra gear harmonics, backlash, passive couplings, repeatability) gives the joint values;
//! the phi-model at the pose's temperature (thermal effect) is built as a [`SimArm`] (rebuilt
//! only when temperature or payload change); with no `compliance` effect the arm is placed
//! in kinematic mode, otherwise servos of the given stiffness hold it against gravity and the
//! payload and it is settled to its static equilibrium. The 2->3 four-bar of the truth (if
//! any) is placed as bodies ([`FourBarBodies::place`], crank solved analytically). Axis
//! wobble is applied to the link poses afterwards ([`Effects::apply_wobble`]); line of sight
//! uses the link capsules without it (a sub-milliradian tilt does not change occlusion).
//!
//! The bevel gear 4->5 (`N = 32/19` with its error function) is part of the joint values the
//! driver computes (kinematic mode, and the servo targets of compliant mode): rapier has no
//! gear joint, and in compliant mode each joint's servo holds its own target, so the gear
//! acts as two coupled position motors whose targets satisfy
//! `q_5 = theta_act_5 + g_45(theta_act_4)` exactly; the sag of joint 4 under load is not fed
//! back into joint 5 (a stiff-gear approximation, documented as such).

use super::SimError;
use super::arm::{ArmOptions, LinkInertia, SimArm};
use super::four_bar::FourBarBodies;
use super::servo::{Compliance, ServoGains, SettleOptions};
use super::visibility::is_visible_from_all;
use crate::campaign::{ArmExecutor, Effects, ExecuteError, JointDriver, PoseConditions};
use crate::kinematics::PhiModel;
use crate::robot::{Controller, RobotDescription, TruthRobot};
use nalgebra::{Isometry3, Point3, Vector3};
use parry3d_f64::shape::SharedShape;
use rand::Rng;

/// How the rapier arm is built and settled.
#[derive(Clone, Debug, PartialEq)]
pub struct RapierArmOptions {
    /// Link capsule radii \[m\] (see [`ArmOptions::link_radius_m`]).
    pub link_radius_m: Vec<f64>,
    /// Stations lines of sight start from (e.g. `MeasurementModel::stations_m()`); empty:
    /// every target is visible.
    pub stations_m: Vec<Point3<f64>>,
    /// Rays stop this short of the target \[m\] (see [`is_visible_from_all`]).
    pub stop_short_m: f64,
    /// Damping ratio of the compliant servos.
    pub damping_ratio: f64,
    /// Settling of the compliant mode.
    pub settle: SettleOptions,
    /// Build the truth's four-bars as bodies.
    pub four_bar_bodies: bool,
}

impl RapierArmOptions {
    /// 50 mm capsules, no stations, rays stopped 2 mm short, critical damping, default
    /// settling, four-bar bodies on.
    pub fn new(dof: usize) -> Self {
        Self {
            link_radius_m: vec![0.05; dof],
            stations_m: Vec::new(),
            stop_short_m: 2e-3,
            damping_ratio: 1.0,
            settle: SettleOptions::default(),
            four_bar_bodies: true,
        }
    }
}

/// The simulated real robot in rapier (module docs).
pub struct RapierArm {
    model: PhiModel,
    inertias: Vec<LinkInertia>,
    driver: JointDriver,
    effects: Effects,
    options: RapierArmOptions,
    truth: TruthRobot,
    built: Option<Built>,
    placed_shapes: Vec<(Isometry3<f64>, SharedShape)>,
}

struct Built {
    temperature_c: f64,
    payload_kg: f64,
    arm: SimArm,
    four_bars: Vec<FourBarBodies>,
}

impl RapierArm {
    /// The truth robot behind the controller of `desc` (masses from `desc`), with `effects`.
    pub fn new(truth: TruthRobot, desc: &RobotDescription, effects: Effects, options: RapierArmOptions) -> Self {
        let inertias = desc
            .joints
            .iter()
            .map(|j| LinkInertia {
                mass_kg: j.mass_kg,
                com_in_link_m: Point3::from(j.com_mm) * 1e-3,
            })
            .collect();
        RapierArm {
            model: truth.model(),
            inertias,
            driver: JointDriver::new(&truth, Controller::from_description(desc), &effects),
            effects,
            options,
            truth,
            built: None,
            placed_shapes: Vec::new(),
        }
    }

    /// The truth model.
    pub fn truth(&self) -> &TruthRobot {
        &self.truth
    }

    /// The rapier arm of the last executed pose, if any.
    pub fn sim_arm(&self) -> Option<&SimArm> {
        self.built.as_ref().map(|b| &b.arm)
    }

    /// The four-bar bodies of the last executed pose.
    pub fn four_bars(&self) -> &[FourBarBodies] {
        self.built.as_ref().map_or(&[], |b| &b.four_bars)
    }

    fn build(&self, conditions: &PoseConditions) -> Result<Built, SimError> {
        let model = self.effects.thermal_model(&self.model, conditions.temperature_c);
        let payload = self
            .effects
            .payload_in_last_link(&model.last_link_from_tool, conditions);
        let gravity = self
            .effects
            .compliance
            .as_ref()
            .map_or(Vector3::new(0.0, 0.0, -9.81), |c| Vector3::from(c.gravity_m_s2));
        let options = ArmOptions {
            link_radius_m: self.options.link_radius_m.clone(),
            payload_kg: payload.map_or(0.0, |p| p.0),
            payload_in_last_link_m: payload.map(|p| p.1),
            gravity_m_s2: gravity,
        };
        let mut arm = SimArm::new(&model, &self.inertias, &options)?;
        let mut four_bars = Vec::new();
        // In compliant mode the bodies are left out: the impulse closure does not hold
        // against the stiff servos (see `four_bar`), and the arm's servos carry the load.
        if self.options.four_bar_bodies && self.effects.compliance.is_none() {
            for l in &self.truth.four_bars {
                four_bars.push(FourBarBodies::attach(&mut arm, l)?);
            }
        }
        Ok(Built {
            temperature_c: conditions.temperature_c,
            payload_kg: conditions.payload_kg,
            arm,
            four_bars,
        })
    }

    fn run(&mut self, conditions: &PoseConditions, q: &[f64]) -> Result<Vec<Isometry3<f64>>, SimError> {
        let stale = self.built.as_ref().is_none_or(|b| {
            b.temperature_c.to_bits() != conditions.temperature_c.to_bits()
                || b.payload_kg.to_bits() != conditions.payload_kg.to_bits()
        });
        if stale {
            self.built = Some(self.build(conditions)?);
        }
        let Some(built) = self.built.as_mut() else {
            unreachable!("built above")
        };
        let arm = &mut built.arm;
        let compliance = match &self.effects.compliance {
            None => Compliance::Rigid,
            Some(c) => Compliance::Servo(ServoGains::with_damping_ratio(
                arm,
                q,
                &c.stiffness_nm_per_rad,
                self.options.damping_ratio,
            )),
        };
        let report = arm.static_equilibrium(q, &compliance, &[], &self.options.settle)?;
        for fb in &mut built.four_bars {
            // Kinematic placement: a linkage that cannot close here is left where it was.
            let _ = fb.place(arm);
        }
        let n = self.model.dof();
        let mut links: Vec<Isometry3<f64>> = (0..n).map(|k| arm.world_from_link(k)).collect();
        self.placed_shapes = arm.placed_shapes();
        let model = arm.model().clone();
        self.effects.apply_wobble(&model, &report.joint_positions, &mut links);
        Ok(links)
    }
}

impl ArmExecutor for RapierArm {
    fn execute<R: Rng + ?Sized>(
        &mut self,
        cmd: &[f64],
        conditions: &PoseConditions,
        rng: &mut R,
    ) -> Result<Vec<Isometry3<f64>>, ExecuteError> {
        let fail = |reason: String| ExecuteError {
            cmd_deg: cmd.iter().map(|c| c.to_degrees()).collect(),
            reason,
        };
        let q = self.driver.drive(cmd, rng).map_err(|e| fail(e.to_string()))?.q;
        self.run(conditions, &q).map_err(|e| fail(e.to_string()))
    }

    fn visible(&self, point_m: &Point3<f64>) -> bool {
        is_visible_from_all(
            &self.placed_shapes,
            &self.options.stations_m,
            point_m,
            self.options.stop_short_m,
        )
    }

    fn last_link_from_tool(&self) -> Isometry3<f64> {
        self.model.last_link_from_tool
    }
}
