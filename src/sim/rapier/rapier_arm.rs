//! The rapier arm as the campaign's simulated robot ([`ArmExecutor`]).
//!
//! Per command: the [`JointDriver`] (fig. 3 controller, the truth's transmissions with any
//! extra gear harmonics, backlash, passive couplings, repeatability) gives the joint values
//! `q` and the actuators' active displacements; the phi-model at the pose's temperature
//! (thermal effect) is built as a [`SimArm`] (rebuilt only when temperature or payload
//! change) with the truth's four-bars as bodies ([`FourBarBodies`]); the arm is placed at
//! `q` and each four-bar's crank solved to close its loop there ([`FourBarBodies::place`]).
//!
//! - Kinematic mode (no `compliance` effect): that placement is the answer.
//! - Dynamic mode: servos of the effect's stiffness (implicit springs, [`SimArm::set_servo`])
//!   hold every joint at `q` except a four-bar's driven joint, which has no servo: actuator
//!   `b`'s servo holds the crank at the angle just solved, so the mechanism carries link `b`'s
//!   load and `theta_23` comes out of the loop (for a truth whose 2->3 coupling is not the
//!   four-bar itself, e.g. the paper's fractional form, the crank angle absorbs the difference
//!   between the two laws, so at infinite stiffness the arm still reaches `q` exactly and only
//!   the compliance is the mechanism's). The other passive couplings (the bevel gear 4->5 with
//!   its error function, 3->4) are emulated by coupled servo targets updated before every step
//!   ([`CoupledTargets`]). The arm is stepped to its static equilibrium under gravity and the
//!   payload. Where a four-bar cannot close at the commanded pose (the truth's law reaches
//!   poses the mechanism cannot) its loop is opened for that pose and its joint keeps its own
//!   servo ([`FourBarBodies::set_loop_closed`]).
//!
//! Axis wobble is applied to the link poses afterwards ([`Effects::apply_wobble`]), and line
//! of sight uses the same wobbled poses for the link capsules, plus the crank and rod of
//! each four-bar as capsules.

use super::SimError;
use super::arm::{ArmBody, ArmOptions, LinkInertia, SimArm};
use super::four_bar::FourBarBodies;
use super::gear::CoupledTargets;
use super::servo::{ServoGains, SettleOptions, SettleReport, SettleTally};
use super::visibility::is_visible_from_all;
use crate::kinematics::PhiModel;
use crate::physics::{ComplianceEffect, LinkMass, PassiveSlope, coupled_static_deflection, with_simulated_load};
use crate::plan::PoseConditions;
use crate::robot::{Controller, RobotDescription, RobotModel};
use crate::sim::{ArmExecutor, DrivenJoints, Effects, ExecuteError, JointDriver};
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
    /// Build the truth's four-bars as bodies: placed in kinematic mode, driving their joint in
    /// dynamic mode (off: every joint has its own servo and every coupling is emulated).
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
    truth: RobotModel,
    built: Option<Built>,
    placed_shapes: Vec<(Isometry3<f64>, SharedShape)>,
    last_settle: Option<SettleReport>,
    settles: SettleTally,
}

struct Built {
    temperature_c: f64,
    payload_kg: f64,
    arm: SimArm,
    four_bars: Vec<FourBarBodies>,
}

impl RapierArm {
    /// The truth robot behind the controller of `desc`, with `effects` (link masses from
    /// [`Effects::truth_link_masses`]: the effects' own, else `desc`'s).
    pub fn new(truth: RobotModel, desc: &RobotDescription, effects: Effects, options: RapierArmOptions) -> Self {
        let inertias = effects
            .truth_link_masses(desc)
            .iter()
            .map(|m| LinkInertia {
                mass_kg: m.mass_kg,
                com_in_link_m: Point3::from(m.com_mm) * 1e-3,
            })
            .collect();
        RapierArm {
            model: truth.phi_model(),
            inertias,
            driver: JointDriver::new(&truth, Controller::from_description(desc), &effects),
            effects,
            options,
            truth,
            built: None,
            placed_shapes: Vec::new(),
            last_settle: None,
            settles: SettleTally::default(),
        }
    }

    /// The truth model.
    pub fn truth(&self) -> &RobotModel {
        &self.truth
    }

    /// The rapier arm of the last executed pose, if any.
    pub fn sim_arm(&self) -> Option<&SimArm> {
        self.built.as_ref().map(|b| &b.arm)
    }

    /// The static-equilibrium solve of the last executed pose (dynamic mode only).
    pub fn last_settle(&self) -> Option<&SettleReport> {
        self.last_settle.as_ref()
    }

    /// Every static-equilibrium solve since the arm was made (dynamic mode; empty in
    /// kinematic mode).
    pub fn settles(&self) -> &SettleTally {
        &self.settles
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
        if self.options.four_bar_bodies {
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

    fn run(&mut self, conditions: &PoseConditions, driven: &DrivenJoints) -> Result<Vec<Isometry3<f64>>, SimError> {
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
        let q = &driven.q;
        arm.set_joint_positions(q)?;
        let joint_positions = match &self.effects.compliance {
            None => {
                for fb in &mut built.four_bars {
                    // Kinematic placement: a linkage that cannot close here is left where it
                    // was (the link poses do not depend on it).
                    let _ = fb.place(arm);
                }
                arm.joint_positions()
            }
            Some(c) => {
                // A loop that cannot close at this pose is opened (see
                // `FourBarBodies::set_loop_closed`) and its joint keeps its servo.
                let crank_targets: Vec<Option<f64>> = built.four_bars.iter_mut().map(|fb| fb.place(arm).ok()).collect();
                let gains = ServoGains::with_damping_ratio(arm, q, &c.stiffness_nm_per_rad, self.options.damping_ratio);
                arm.set_servo(q, &gains)?;
                for (fb, crank) in built.four_bars.iter().zip(&crank_targets) {
                    fb.set_loop_closed(arm, crank.is_some())?;
                    let b = fb.driven_joint();
                    let (k, d) = (gains.stiffness_nm_per_rad[b], gains.damping_nms_per_rad[b]);
                    match crank {
                        Some(crank) => fb.drive(arm, *crank, k, d)?,
                        None => fb.hold_crank(arm, k, d)?,
                    }
                }
                if self.options.settle.warm_start {
                    let prediction = Prediction {
                        truth: &self.truth,
                        inertias: &self.inertias,
                        effects: &self.effects,
                        four_bar_bodies: self.options.four_bar_bodies,
                    };
                    let start = prediction.equilibrium(conditions, arm.model(), driven, c);
                    if let Some(start) = start {
                        arm.set_joint_positions(&start)?;
                        for fb in &mut built.four_bars {
                            // The loop is re-closed geometrically at the predicted pose; the
                            // crank's servo keeps its target at the command.
                            let _ = fb.place(arm);
                        }
                    }
                }
                let mut coupled = CoupledTargets::new(&self.truth, &built.four_bars, &crank_targets, q, &driven.active);
                let four_bars = &built.four_bars;
                let report = arm.settle_with(&[], &self.options.settle, |arm| coupled.update(arm, four_bars))?;
                let q_rest = report.joint_positions.clone();
                self.settles.add(&report);
                self.last_settle = Some(report);
                q_rest
            }
        };
        let n = self.model.dof();
        let mut links: Vec<Isometry3<f64>> = (0..n).map(|k| arm.world_from_link(k)).collect();
        let model = arm.model().clone();
        let unwobbled = links.clone();
        self.effects.apply_wobble(&model, &joint_positions, &mut links);
        self.placed_shapes = placed_shapes(arm, &built.four_bars, &unwobbled, &links);
        Ok(links)
    }
}

/// What the analytic prediction of the arm's static equilibrium needs.
struct Prediction<'a> {
    truth: &'a RobotModel,
    inertias: &'a [LinkInertia],
    effects: &'a Effects,
    /// Whether the truth's four-bars are bodies (they carry the driven joint's load back to
    /// the actuator below) or emulated couplings (kinematic only).
    four_bar_bodies: bool,
}

impl Prediction<'_> {
    /// The static equilibrium the analytic compliance model predicts for the driven joint
    /// values (`physics::coupled_static_deflection` on `model`, the arm as built: thermal
    /// state, payload): the warm start of [`SettleOptions::warm_start`]. It leaves out the
    /// four-bar bars' own weight. `None` when the model finds no equilibrium (the settle then
    /// starts from the command, as without a warm start).
    fn equilibrium(
        &self,
        conditions: &PoseConditions,
        model: &PhiModel,
        driven: &DrivenJoints,
        compliance: &ComplianceEffect,
    ) -> Option<Vec<f64>> {
        let masses: Vec<LinkMass> = self
            .inertias
            .iter()
            .map(|i| LinkMass::at(i.mass_kg, i.com_in_link_m))
            .collect();
        let couplings = PassiveSlope::of_robot(self.truth, &driven.active, |k, _| {
            self.four_bar_bodies && self.truth.four_bars.iter().any(|l| l.from == k)
        });
        let payload = self
            .effects
            .payload_in_last_link(&model.last_link_from_tool, conditions);
        let dq = with_simulated_load(&masses, payload, compliance, &couplings, |load| {
            coupled_static_deflection(model, &driven.q, load)
        })
        .ok()?;
        Some(driven.q.iter().zip(dq).map(|(q, d)| q + d).collect())
    }
}

/// The collision shapes at the executed pose: each link's shapes moved with the link's wobble
/// correction (`wobbled * unwobbled^-1`), and each four-bar's crank and rod as capsules moved
/// with the wobble of the link carrying the crank's axis.
fn placed_shapes(
    arm: &SimArm,
    four_bars: &[FourBarBodies],
    unwobbled: &[Isometry3<f64>],
    wobbled: &[Isometry3<f64>],
) -> Vec<(Isometry3<f64>, SharedShape)> {
    let correction = |body: ArmBody| match body {
        ArmBody::Base => Isometry3::identity(),
        ArmBody::Link(k) => wobbled[k] * unwobbled[k].inverse(),
    };
    let mut shapes: Vec<(Isometry3<f64>, SharedShape)> = arm
        .shapes()
        .iter()
        .map(|s| {
            (
                correction(s.body) * arm.world_from_body(s.body) * s.body_from_shape,
                s.shape.clone(),
            )
        })
        .collect();
    for fb in four_bars {
        let carrier = fb.driven_joint().checked_sub(2).map_or(ArmBody::Base, ArmBody::Link);
        for (pose, shape) in fb.placed_shapes(arm) {
            shapes.push((correction(carrier) * pose, shape));
        }
    }
    shapes
}

impl ArmExecutor for RapierArm {
    fn execute<R: Rng + ?Sized>(
        &mut self,
        cmd: &[f64],
        conditions: &PoseConditions,
        rng: &mut R,
    ) -> Result<Vec<Isometry3<f64>>, ExecuteError> {
        let driven = self
            .driver
            .drive(cmd, rng)
            .map_err(|e| ExecuteError::new(&self.model, cmd, e.to_string()))?;
        self.run(conditions, &driven)
            .map_err(|e| ExecuteError::new(&self.model, cmd, e.to_string()))
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

    fn settles(&self) -> Option<SettleTally> {
        self.effects.compliance.as_ref().map(|_| self.settles)
    }
}
