//! Measurement campaigns: the plan of axis experiments (Table 1) and validation poses.

mod analytic_arm;
mod plan;
mod simulate;
mod validation;

pub use analytic_arm::AnalyticArm;
pub use plan::{AxisSweep, CalibrationPlan, PlanError, commands_to_internal};
pub use simulate::{ArmExecutor, CampaignError, CampaignOutput, ExecuteError, PoseConditions, simulate_campaign};
pub use validation::ValidationPlan;
