//! Measurement campaigns: the plan of axis experiments (Table 1) and validation poses.

mod analytic_arm;
mod effects;
mod plan;
mod simulate;
mod validation;

pub use analytic_arm::AnalyticArm;
pub use effects::{
    AxisWobble, BacklashEffect, ComplianceEffect, CompliantLoad, DeflectionError, DrivenJoints, Effects, EffectsError,
    GearHarmonic, InstrumentScale, JointDriver, LinkMass, PassiveSlope, PayloadEffect, STATIC_DEFLECTION_MAX_STEPS,
    STATIC_DEFLECTION_ROUNDING_RAD, ThermalEffect, UNMOVED_ACTUATOR_RAD, coupled_first_order_deflection,
    coupled_static_deflection, first_order_deflection,
};
pub use plan::{AxisSweep, CalibrationPlan, PlanError, commands_to_internal};
pub use simulate::{
    ArmExecutor, CampaignError, CampaignOptions, CampaignOutput, ExecuteError, PoseConditions, TOOL_EXPERIMENT,
    simulate_campaign, simulate_campaign_with,
};
pub use validation::ValidationPlan;
