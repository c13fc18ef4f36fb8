//! What a campaign measures, decided before any measurement: the axis experiments of the
//! independent-axis method (paper Table 1: which joint is swept, over what span, in what
//! order) with the hold-still commands of a coupled joint (paper section 3.1,
//! `docs/formats.md#controller-semantics`), the validation poses, and the conditions each pose
//! is measured under. Nothing here knows the robot beyond its nominal description.

mod axis;
pub mod optimize;
pub mod predict;
mod sheet;
pub mod sight;
mod stations;
mod validation;

pub use axis::{AxisSweep, CalibrationPlan, MAX_HELD_JITTER, MAX_INTERVALS, PlanError};
pub use optimize::{OptimizeOptions, Optimized, optimize, with_point_budget};
pub use predict::{PlanObjective, PlanPrediction, PredictError};
pub use sheet::{
    PlanPose, PlannedPoint, SightOptions, VALIDATION_EXPERIMENT, planned_points, points_of_poses, tool_targets,
    write_plan_csv,
};
pub use stations::{
    LINK_RADIUS_M, STATION_HEADINGS, instrument_stations_m, placement_among_stations, stations_origin,
    theodolite_stations_problem,
};
pub use validation::{MAX_POSES as MAX_VALIDATION_POSES, ValidationPlan};

pub use crate::measurement::TOOL_EXPERIMENT;

/// Conditions of one pose that unmodelled effects depend on (`docs/formats.md#measurement-csv`, optional columns).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseConditions {
    /// Payload at the tool \[kg\].
    pub payload_kg: f64,
    /// Ambient temperature \[deg C\].
    pub temperature_c: f64,
}

impl Default for PoseConditions {
    fn default() -> Self {
        PoseConditions {
            payload_kg: 0.0,
            temperature_c: 20.0,
        }
    }
}
