//! Where the instrument stands for a robot: the stations `simulate` measures from and `plan`
//! counts line of sight from, the same for both.

use super::sheet::{SightOptions, planned_points};
use super::sight::STOP_SHORT_M;
use super::{CalibrationPlan, PlanError, ValidationPlan};
use crate::robot::RobotDescription;
use nalgebra::Point3;
use std::cmp::Reverse;

/// Headings tried around the robot for its theodolites (every 15 deg).
pub const STATION_HEADINGS: usize = 24;

/// Radius of the links' capsules the default stations are chosen against \[m\] (the rapier
/// arm's and `plan`'s default).
pub const LINK_RADIUS_M: f64 = 0.05;

/// The instrument's stations for `desc` \[m\]: `[instrument] stations_mm` when the description
/// gives them; else the pair of [`RobotDescription::stations_at_heading_m`] whose lines of
/// sight, on the nominal arm, reach the most points of the robot's default axis and tool
/// experiments ([`CalibrationPlan::default_for`]) from both stations, over
/// [`STATION_HEADINGS`] headings (a tie goes to the smallest heading).
pub fn instrument_stations_m(desc: &RobotDescription) -> Result<Vec<Point3<f64>>, PlanError> {
    if let Some(given) = desc.given_stations_m() {
        return Ok(given);
    }
    let turn_rad = std::f64::consts::TAU / STATION_HEADINGS as f64;
    let pairs: Vec<[Point3<f64>; 2]> = (0..STATION_HEADINGS)
        .map(|h| desc.stations_at_heading_m(h as f64 * turn_rad))
        .collect();
    let sight = SightOptions {
        stations_m: pairs.iter().flatten().copied().collect(),
        link_radius_m: LINK_RADIUS_M,
        stop_short_m: STOP_SHORT_M,
    };
    let no_validation = ValidationPlan {
        poses: 0,
        ..ValidationPlan::workspace_default(desc.dof())
    };
    let points = planned_points(desc, &CalibrationPlan::default_for(desc), &no_validation, &sight)?;
    let seen_by_both = |h: usize| {
        points
            .iter()
            .filter(|p| p.visible[2 * h] && p.visible[2 * h + 1])
            .count()
    };
    let best = (0..STATION_HEADINGS)
        .max_by_key(|&h| (seen_by_both(h), Reverse(h)))
        .unwrap_or(0);
    Ok(pairs[best].to_vec())
}
