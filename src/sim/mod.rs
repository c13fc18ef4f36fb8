//! The simulated real robot: the answer key of every simulated experiment.
//!
//! Everything that knows a true value lives here: the robot as it really is (a
//! [`RobotModel`](crate::robot::RobotModel) drawn around the nominal one, [`perturb`], or the
//! paper's calibrated robot, [`paper_robot`]), the unmodelled effects it carries
//! ([`Effects`], forms in [`crate::physics`]), how it turns commands into joint values
//! ([`JointDriver`]: fig. 3 controller, transmissions, backlash, couplings, repeatability
//! jitter), two executors of a pose ([`AnalyticArm`]: closed-form kinematics with first-order
//! compliance; [`rapier`]: the rigid-body arm with the four-bar as bodies, servos, gravity and
//! line of sight), and [`simulate_campaign`], which measures a plan on either.
//!
//! The boundary: `calibration`, `compensation` and `diagnosis` never import this module (a
//! test in `tests/it/architecture.rs` fails if they do); only the harnesses (`crate::harness`),
//! the viewer and the command line may, so no result can leak from the answer key.

mod analytic_arm;
mod campaign;
mod effects;
mod joint_driver;
mod paper;
mod perturb;
pub mod rapier;
mod repeatability;

pub use analytic_arm::AnalyticArm;
pub use campaign::{
    ArmExecutor, CampaignError, CampaignOptions, CampaignOutput, ExecuteError, PosePlan, simulate_campaign,
    simulate_campaign_with, simulate_poses,
};
pub use effects::{Effects, EffectsError, LinkMassEntry};
pub use joint_driver::{DrivenJoints, InversionTable, JointDriver, UNMOVED_ACTUATOR_RAD};
pub use paper::{PAPER_ROBOT_FILE, paper_robot};
pub use perturb::{
    CouplingHarmonicSpread, DEPARTURE_FALSE_ALARM, Departure, FourBarSpread, PerturbationSpec, PlacementSpread,
    RowSpread, Spread, TransmissionSpread, largest_departure, perturb, row_departure_rms,
};
pub use rapier::{
    ArmBody, ArmOptions, BAR_RADIUS_M, CRANK_MASS_KG, Compliance, CoupledTargets, FourBarBodies, LinkInertia,
    LinkPoint, LinkShape, ROD_MASS_KG, RapierArm, RapierArmOptions, ServoGains, SettleOptions, SettleReport,
    SettleTally, SimArm, SimError, SpanSearch, is_visible_from_all, visible_span_deg, visible_sweep_span,
};
pub use repeatability::{
    ObservedThrough, RepeatabilityStats, RepeatabilityTarget, calibrate_repeatability_sigmas, calibrate_uniform_sigma,
    repeatability_stats, workspace_poses,
};
