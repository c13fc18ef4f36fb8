//! Physics of the effects the independent-axis model leaves out (paper sections 3-4): gravity
//! loads and joint compliance, backlash, thermal expansion, extra gear harmonics, axis wobble
//! and instrument scale, each as a parametric form with its parameters.
//!
//! This module is neutral ground: the simulated robot ([`crate::sim`]) instantiates these
//! forms with its hidden true parameters, and the diagnosis ([`crate::diagnosis`]) fits them
//! as candidates. Nothing here knows a true value.

mod backlash;
mod compliance;
mod gear_harmonic;
mod gravity;
mod instrument_scale;
mod thermal;
mod wobble;

pub use backlash::{
    ApproachSource, ApproachTracker, BacklashEffect, PoseApproach, UNMOVED_ACTUATOR_RAD, actuator_approach_by_pose,
    pose_approaches,
};
pub use compliance::{
    ComplianceEffect, CompliantLoad, DeflectionError, PassiveSlope, PayloadEffect, STATIC_DEFLECTION_MAX_STEPS,
    STATIC_DEFLECTION_ROUNDING_RAD, coupled_first_order_deflection, coupled_first_order_deflection_at,
    coupled_static_deflection, first_order_deflection, reflected_masses, with_simulated_load,
};
pub use gear_harmonic::{
    GearHarmonic, HarmonicPeriod, add_joint_period_errors, joint_period_error_rad, with_gear_harmonics,
};
pub use gravity::{LinkMass, STANDARD_GRAVITY_M_S2, gravity_torques_at_nm, gravity_torques_nm};
pub use instrument_scale::InstrumentScale;
pub use thermal::ThermalEffect;
pub use wobble::{AxisTiltSeries, AxisWobble, apply_axis_tilts, apply_wobble};
