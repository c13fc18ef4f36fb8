//! Line of sight from the theodolite stations to a target through the arm's collision shapes,
//! and the widest symmetric sweep over which a target stays in sight (how the paper chose its
//! Table 1 spans).

use super::SimError;
use super::arm::{LinkPoint, SimArm, check_len};
use super::convert::{point_to_glam, pose_to_glam, vector_to_glam};
use crate::plan::{AxisSweep, CalibrationPlan, PoseConditions};
use crate::robot::RobotDescription;
use crate::robot::commands_to_internal;
use crate::sim::{ArmExecutor, ExecuteError};
use nalgebra::{Isometry3, Point3};
use parry3d_f64::query::Ray;
use parry3d_f64::shape::SharedShape;
use rand::Rng;

/// Whether `target_m` is seen from every station: for each station, the segment from the
/// station towards the target, stopped `stop_short_m` before the target (so a target sitting
/// on a link's surface is not hidden by that surface), meets none of the shapes (solid).
///
/// A station within `stop_short_m` of the target sees it trivially.
pub fn is_visible_from_all(
    shapes: &[(Isometry3<f64>, SharedShape)],
    stations_m: &[Point3<f64>],
    target_m: &Point3<f64>,
    stop_short_m: f64,
) -> bool {
    stations_m.iter().all(|station| {
        let to_target = target_m - station;
        let distance_m = to_target.norm();
        if distance_m <= stop_short_m {
            return true;
        }
        let ray = Ray::new(point_to_glam(station), vector_to_glam(&(to_target / distance_m)));
        let max_m = distance_m - stop_short_m;
        !shapes
            .iter()
            .any(|(pose, shape)| shape.cast_ray(&pose_to_glam(pose), &ray, max_m, true).is_some())
    })
}

/// How [`visible_span_deg`] searches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpanSearch {
    /// Coarse step of the half span \[deg\]; an occlusion narrower than this can be missed.
    pub step_deg: f64,
    /// The search stops here (e.g. the distance from the centre to the nearest joint limit)
    /// \[deg\].
    pub max_half_span_deg: f64,
    /// Bisection steps refining the edge after the coarse search.
    pub refinements: usize,
    /// See [`is_visible_from_all`] \[m\].
    pub stop_short_m: f64,
}

impl Default for SpanSearch {
    /// 1 deg steps up to 180 deg, refined to about 0.001 deg, rays stopped 2 mm short.
    fn default() -> Self {
        Self {
            step_deg: 1.0,
            max_half_span_deg: 180.0,
            refinements: 10,
            stop_short_m: 2e-3,
        }
    }
}

/// The largest span \[deg\], symmetric about `q_centre\[joint\]` with the other joints fixed, over
/// which `target` stays visible from every station (sampled: every coarse step, then the edge
/// bisected). Zero if the target is hidden at the centre. The arm is left at `q_centre`.
pub fn visible_span_deg(
    arm: &mut SimArm,
    q_centre: &[f64],
    joint: usize,
    target: &LinkPoint,
    stations_m: &[Point3<f64>],
    search: &SpanSearch,
) -> Result<f64, SimError> {
    check_len("centre joint values", arm.model().dof(), q_centre.len())?;
    let result = largest_visible_span_deg(search, |half_deg| {
        let mut q = q_centre.to_vec();
        for sign in [1.0, -1.0] {
            q[joint] = q_centre[joint] + sign * half_deg.to_radians();
            arm.set_joint_positions(&q)?;
            let p = arm.point_in_world(target);
            if !is_visible_from_all(&arm.placed_shapes(), stations_m, &p, search.stop_short_m) {
                return Ok(false);
            }
        }
        Ok(true)
    });
    arm.set_joint_positions(q_centre)?;
    result
}

/// The largest span of an axis experiment \[deg or mm\], centred like the planned sweep and
/// with its number of intervals, for which every target the experiment observes is visible from
/// every station of `arm` at every step, the experiment executed as the campaign executes it:
/// the plan's commands ([`CalibrationPlan::commands`]; with a second target the next actuator
/// holds still where the sweep starts, so the passive joint turns through the whole sweep)
/// through the controller, the passive couplings and the arm's effects (for
/// [`RapierArm`](super::RapierArm): the four-bar crank and rod, wobble, sag). Repeatability
/// jitter, if the arm has any, is drawn from `rng`: give it a truth without jitter for a
/// reproducible edge.
pub fn visible_sweep_span<A: ArmExecutor, R: Rng + ?Sized>(
    arm: &mut A,
    desc: &RobotDescription,
    plan: &CalibrationPlan,
    sweep: &AxisSweep,
    conditions: &PoseConditions,
    search: &SpanSearch,
    rng: &mut R,
) -> Result<f64, ExecuteError> {
    let targets: Vec<LinkPoint> = desc
        .axis_targets_of(sweep.joint)
        .map(|t| {
            std::iter::once(t.target0)
                .chain(t.target1.filter(|_| sweep.second_target))
                .map(|t| LinkPoint::from_target(&t))
                .collect()
        })
        .unwrap_or_default();
    largest_visible_span_deg(search, |half| {
        let centre = sweep.offset_at(0) + sweep.span / 2.0;
        let widened = AxisSweep {
            span: 2.0 * half,
            start: Some(centre - half),
            ..sweep.clone()
        };
        for step in 0..widened.poses() {
            let cmd = commands_to_internal(desc, &plan.commands(desc, &widened, step));
            let world_from_link = arm.execute(&cmd, conditions, rng)?;
            if !targets
                .iter()
                .all(|t| arm.visible(&(world_from_link[t.link] * t.position_in_link_m)))
            {
                return Ok(false);
            }
        }
        Ok(true)
    })
}

/// The search of [`SpanSearch`]: the largest half span `h <= max_half_span_deg` with
/// `visible_at(h)`, stepping by `step_deg` and bisecting the first failing step; returns the
/// full span `2 h` (0 if hidden at the centre).
fn largest_visible_span_deg<E>(
    search: &SpanSearch,
    mut visible_at: impl FnMut(f64) -> Result<bool, E>,
) -> Result<f64, E> {
    if !visible_at(0.0)? {
        return Ok(0.0);
    }
    let mut ok_deg = 0.0;
    let mut bad_deg = None;
    while ok_deg < search.max_half_span_deg {
        let next = (ok_deg + search.step_deg).min(search.max_half_span_deg);
        if visible_at(next)? {
            ok_deg = next;
        } else {
            bad_deg = Some(next);
            break;
        }
    }
    if let Some(bad) = bad_deg {
        let stop = crate::numerics::roots::Bisection::steps(search.refinements);
        [ok_deg, _] = crate::numerics::roots::bisect(ok_deg, bad, stop, &mut visible_at)?;
    }
    Ok(2.0 * ok_deg)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::RobotDescription;
    use crate::sim::ArmOptions;

    /// The measurement set-up: left theodolite at the origin, right one 6.2846 m to its left.
    fn stations() -> [Point3<f64>; 2] {
        [Point3::origin(), Point3::new(-6.2846, 0.0, 0.0)]
    }

    /// A target 450 mm up the upper arm, 60 mm out along link 2's Z (the world +X at q = 0),
    /// i.e. 10 mm off the 50 mm capsule. Joint 1 turns that offset about the vertical: at
    /// -90 deg it faces the stations, at +90 deg it hides behind the upper arm.
    fn arm_and_target() -> (SimArm, LinkPoint) {
        let d = RobotDescription::asea_irb6l();
        let arm = SimArm::from_description(&d.nominal_model(), &d, &ArmOptions::new(6)).expect("valid arm");
        let target = LinkPoint {
            link: 1,
            position_in_link_m: Point3::new(-0.45, 0.0, 0.06),
        };
        (arm, target)
    }

    fn visible(arm: &mut SimArm, q1_deg: f64, target: &LinkPoint) -> bool {
        let q = [q1_deg.to_radians(), 0.0, 0.0, 0.0, 0.0, 0.0];
        arm.set_joint_positions(&q).expect("six values");
        is_visible_from_all(&arm.placed_shapes(), &stations(), &arm.point_in_world(target), 2e-3)
    }

    #[test]
    fn a_target_behind_the_upper_arm_is_hidden_and_in_front_is_visible() {
        let (mut arm, target) = arm_and_target();
        assert!(visible(&mut arm, -90.0, &target));
        assert!(!visible(&mut arm, 90.0, &target));
    }

    /// In plan view the upper arm is a disc of radius R = 50 mm and the target sits r = 60 mm
    /// from its centre: a station is hidden when its direction is within asin(R / r) of the
    /// direction from the target to the axis. The stations lie at atan(3.1423 / 4.4394) either
    /// side of -y as seen from the robot, so centred on the -y-facing pose the half span is
    /// `180 - asin(R / r) - atan(3.1423 / 4.4394)`. The bound covers the 60 mm parallax of the
    /// target and the 1 deg-wide rays of the 2 mm stop-short.
    #[test]
    fn the_visible_span_matches_the_plan_view_estimate() {
        let (mut arm, target) = arm_and_target();
        let q = [-90f64.to_radians(), 0.0, 0.0, 0.0, 0.0, 0.0];
        let span_deg =
            visible_span_deg(&mut arm, &q, 0, &target, &stations(), &SpanSearch::default()).expect("six values");
        let half_deg = 180.0 - (0.05f64 / 0.06).asin().to_degrees() - (3.1423f64 / 4.4394).atan().to_degrees();
        assert!(
            (span_deg - 2.0 * half_deg).abs() < 2.0,
            "span {span_deg} deg, plan view {}",
            2.0 * half_deg
        );
        assert!(
            !visible(&mut arm, -90.0 + span_deg / 2.0 + 0.5, &target)
                || !visible(&mut arm, -90.0 - span_deg / 2.0 - 0.5, &target)
        );
        let hidden = [90f64.to_radians(), 0.0, 0.0, 0.0, 0.0, 0.0];
        let none =
            visible_span_deg(&mut arm, &hidden, 0, &target, &stations(), &SpanSearch::default()).expect("six values");
        approx::assert_abs_diff_eq!(none, 0.0);
    }
}
