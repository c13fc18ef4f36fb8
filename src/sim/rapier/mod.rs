//! The simulated robot as a rigid-body multibody in rapier (reduced coordinates), and line of
//! sight with parry.
//!
//! - [`SimArm`] builds any [`PhiModel`](crate::kinematics::PhiModel) as a rapier multibody:
//!   a fixed base body at `world_from_base`, one dynamic body per link whose body frame *is*
//!   the phi-model's moving link frame, and one multibody joint per phi-model joint. In
//!   kinematic mode the joint values are written straight into the multibody and its forward
//!   kinematics places the bodies; in dynamic mode position servos with finite stiffness
//!   (implicit joint springs and damping) hold the arm against gravity and
//!   [`SimArm::settle`] finds the static equilibrium.
//! - [`FourBarBodies`]: the 2->3 four-bar as crank, rod and loop-closing joint; in dynamic
//!   mode it drives joint 3. [`CoupledTargets`]: the passive couplings without bodies (the
//!   bevel gear 4->5) as servo targets that follow the joint below each step.
//! - [`RapierArm`]: the campaign's executor on top of both modes.
//! - [`visibility`](self::is_visible_from_all) casts rays from the theodolite stations to a
//!   target through the link collision shapes.
//!
//! rapier's math types are glam; every conversion to and from nalgebra lives in the private
//! `convert` module.

mod arm;
mod convert;
mod four_bar;
mod gear;
mod rapier_arm;
mod servo;
mod visibility;
pub use visibility::{SpanSearch, is_visible_from_all, visible_span_deg, visible_sweep_span};

pub use arm::{ArmBody, ArmOptions, LinkInertia, LinkPoint, LinkShape, SimArm};
pub use four_bar::{BAR_RADIUS_M, CRANK_MASS_KG, FourBarBodies, ROD_MASS_KG};
pub use gear::CoupledTargets;
pub use rapier_arm::{RapierArm, RapierArmOptions};
pub use servo::{Compliance, ServoGains, SettleOptions, SettleReport, SettleTally};

/// A problem building or running the simulated arm.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A per-joint input has the wrong length.
    #[error("{what}: expected {expected} values (one per joint), found {found}")]
    WrongLength {
        /// Which input.
        what: &'static str,
        /// The number of joints.
        expected: usize,
        /// The length given.
        found: usize,
    },
    /// The phi-model does not have `N` joints and `N - 1` rows.
    #[error("inconsistent phi-model: {joints} joints but {rows} rows")]
    InconsistentModel {
        /// Number of joints.
        joints: usize,
        /// Number of rows.
        rows: usize,
    },
    /// A value that must be finite and positive is not.
    #[error("{what} of joint {} must be finite and positive, found {value}", joint + 1)]
    NotPositive {
        /// Which quantity.
        what: &'static str,
        /// The joint (0-based).
        joint: usize,
        /// The value given.
        value: f64,
    },
    /// rapier refused a joint (it would have closed a loop in the multibody).
    #[error("rapier refused multibody joint {joint}")]
    JointRejected {
        /// The joint (0-based).
        joint: usize,
    },
    /// A passive coupling cannot be evaluated (a four-bar coupling that cannot close).
    #[error("coupling into joint {} cannot be evaluated: {cause}", joint + 1)]
    Coupling {
        /// The driven joint (0-based).
        joint: usize,
        /// Why.
        cause: crate::robot::FourBarError,
    },
    /// The dynamic simulation did not come to rest within the step cap.
    #[error("the arm did not settle in {steps} steps: fastest watched point still moves at {max_speed_m_s} m/s")]
    NotSettled {
        /// Steps taken.
        steps: usize,
        /// Speed of the fastest watched point at the last step \[m/s\].
        max_speed_m_s: f64,
    },
}
