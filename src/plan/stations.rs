//! Where the instrument stands for a robot: the stations `simulate` measures from and `plan`
//! counts line of sight from, the same for both.

use super::sheet::{SightOptions, planned_points};
use super::sight::STOP_SHORT_M;
use super::{CalibrationPlan, PlanError, ValidationPlan};
use crate::measurement::{ReferenceVolume, TriangulationError, format_f64};
use crate::robot::RobotDescription;
use nalgebra::Point3;
use std::cmp::Reverse;
use std::path::Path;

/// Headings tried around the robot for its theodolites (every 15 deg).
pub const STATION_HEADINGS: usize = 24;

/// Radius of the links' capsules the default stations are chosen against \[m\] (the rapier
/// arm's and `plan`'s default).
pub const LINK_RADIUS_M: f64 = 0.05;

/// Where the theodolites of `desc`, read from `file`, stand, naming the key for a message:
/// `[instrument] stations_mm` when the description gives them, else the pair chosen for the
/// robot ([`instrument_stations_m`]).
pub fn stations_origin(desc: &RobotDescription, file: &Path) -> String {
    match desc.instrument {
        Some(_) => format!("{}: field `instrument.stations_mm`", file.display()),
        None => format!(
            "{}: the theodolites chosen for the robot (no `[instrument]`; give `stations_mm` to place them)",
            file.display()
        ),
    }
}

/// Why two theodolites at `stations_m` (left, right \[m\]) could not be calibrated over the
/// robot's work volume (`e`), in words, with the stations in mm as `[instrument] stations_mm`
/// writes them and what to do: lines of sight that meet nearly parallel want the stations
/// further apart, on either side of the robot.
pub fn theodolite_stations_problem(stations_m: &[Point3<f64>; 2], e: &TriangulationError) -> String {
    // To 0.1 um, so that a station written in mm reads back as written.
    let mm = |p: &Point3<f64>| {
        let c: Vec<String> = p.iter().map(|x| format_f64((x * 1e7).round() / 1e4 + 0.0)).collect();
        format!("[{}]", c.join(", "))
    };
    let stations = format!("the stations {} and {} mm", mm(&stations_m[0]), mm(&stations_m[1]));
    match e {
        TriangulationError::NearParallel {
            intersection_angle_rad,
            min_intersection_angle_rad,
        } => format!(
            "{stations} see the robot's work volume (the 2 m cube about its base) along lines of sight meeting at \
             {:.2} deg, below the {:.2} deg two theodolites need (nearly parallel): place the stations further apart, \
             on either side of the robot (the paper's stood 6.3 m apart, 5.4 m from its base)",
            intersection_angle_rad.to_degrees(),
            min_intersection_angle_rad.to_degrees()
        ),
        other => format!("{stations} cannot measure the robot's work volume (the 2 m cube about its base): {other}"),
    }
}

/// Why `desc`'s placement, not its stations, is at fault when theodolites at `stations_m`
/// cannot measure the robot's work volume (the 2 m cube about its base,
/// [`ReferenceVolume::around_robot_base`]): a station stands inside that volume, as a
/// placement written in metres puts the base beside the instrument's origin. `None` otherwise.
pub fn placement_among_stations(desc: &RobotDescription, stations_m: &[Point3<f64>]) -> Option<String> {
    let base_m = desc.placement.origin_m();
    let volume = ReferenceVolume::around_robot_base(&base_m);
    let (k, station_m) = stations_m
        .iter()
        .enumerate()
        .find(|(_, s)| (*s - volume.centre_m).amax() <= volume.side_m / 2.0)?;
    let mm = |p: &Point3<f64>| {
        let c: Vec<String> = p.iter().map(|x| format_f64((x * 1e7).round() / 1e4 + 0.0)).collect();
        format!("[{}]", c.join(", "))
    };
    Some(format!(
        "the robot's base {} mm stands {:.1} mm from station {k} {} mm, inside the robot's work volume (the 2 m cube \
         about its base the theodolites are calibrated over): is the placement in metres? (`translation_mm` is in mm; \
         the paper's base stood 5.4 m from its stations)",
        mm(&base_m),
        (station_m - base_m).norm() * 1e3,
        mm(station_m)
    ))
}

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
