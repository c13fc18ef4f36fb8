//! Line of sight from the instrument's stations to a target past the nominal arm, from the
//! description's own geometry: each link is a capsule of a given radius on the segment from its
//! frame origin to the next frame origin (the last link: to the tool origin), as the rapier
//! simulation shapes it, but tested here with a closed-form segment-to-segment distance
//! (Ericson, *Real-Time Collision Detection*, sec. 5.1.9) instead of parry's ray cast, so the
//! plan does not depend on the simulator.

use crate::kinematics::PhiModel;
use nalgebra::{Point3, Vector3};

/// How far short of its target a sight line stops \[m\] (a target on a link's surface is not
/// hidden by that surface).
pub const STOP_SHORT_M: f64 = 2e-3;

/// The nominal arm's link capsules at joint values `q`, in the instrument frame \[m\].
pub fn link_segments(model: &PhiModel, q: &[f64]) -> Vec<(Point3<f64>, Point3<f64>)> {
    let poses = model.poses(q);
    let n = model.dof();
    (0..n)
        .map(|k| {
            let end = if k + 1 < n {
                model.link_from_next_frame(k) * Point3::origin()
            } else {
                model.last_link_from_tool * Point3::origin()
            };
            let world_from_link = poses.world_from_link[k];
            (world_from_link * Point3::origin(), world_from_link * end)
        })
        .collect()
}

/// Whether `station_m` sees `target_m` past capsules of `radius_m` on `segments`: the sight
/// line, stopped `stop_short_m` before the target (a target on a link's surface is not hidden
/// by that surface), keeps at least `radius_m` from every segment.
pub fn sees(
    station_m: &Point3<f64>,
    target_m: &Point3<f64>,
    segments: &[(Point3<f64>, Point3<f64>)],
    radius_m: f64,
    stop_short_m: f64,
) -> bool {
    let to_target = target_m - station_m;
    let distance_m = to_target.norm();
    if distance_m <= stop_short_m {
        return true;
    }
    let end = station_m + to_target * ((distance_m - stop_short_m) / distance_m);
    segments
        .iter()
        .all(|(a, b)| segment_distance_m(station_m, &end, a, b) >= radius_m)
}

/// The distance between segments `p1-q1` and `p2-q2` (Ericson sec. 5.1.9: the closest points'
/// parameters `s`, `t` clamped to `[0, 1]`).
pub fn segment_distance_m(p1: &Point3<f64>, q1: &Point3<f64>, p2: &Point3<f64>, q2: &Point3<f64>) -> f64 {
    let d1: Vector3<f64> = q1 - p1;
    let d2: Vector3<f64> = q2 - p2;
    let r = p1 - p2;
    let a = d1.norm_squared();
    let e = d2.norm_squared();
    let f = d2.dot(&r);
    const TINY: f64 = 1e-18;
    let (s, t) = if a <= TINY && e <= TINY {
        (0.0, 0.0)
    } else if a <= TINY {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(&r);
        if e <= TINY {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(&d2);
            let denom = a * e - b * b;
            let mut s = if denom > TINY {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    ((p1 + d1 * s) - (p2 + d2 * t)).norm()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn p(x: f64, y: f64, z: f64) -> Point3<f64> {
        Point3::new(x, y, z)
    }

    /// A brute-force distance: the minimum over a fine grid of both parameters (the
    /// independent check of the closed form).
    fn sampled_distance(p1: &Point3<f64>, q1: &Point3<f64>, p2: &Point3<f64>, q2: &Point3<f64>) -> f64 {
        const N: usize = 400;
        let mut best = f64::INFINITY;
        for i in 0..=N {
            let x = p1 + (q1 - p1) * (i as f64 / N as f64);
            for j in 0..=N {
                let y = p2 + (q2 - p2) * (j as f64 / N as f64);
                best = best.min((x - y).norm());
            }
        }
        best
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(40))]
        #[test]
        fn closed_form_matches_sampling(c in proptest::collection::vec(-1.0f64..1.0, 12)) {
            let (p1, q1) = (p(c[0], c[1], c[2]), p(c[3], c[4], c[5]));
            let (p2, q2) = (p(c[6], c[7], c[8]), p(c[9], c[10], c[11]));
            let exact = segment_distance_m(&p1, &q1, &p2, &q2);
            let sampled = sampled_distance(&p1, &q1, &p2, &q2);
            // The grid point nearest the true closest pair is at most half a grid step (of
            // segments at most 2*sqrt(3) long) away along each segment.
            let grid_step = 2.0 * 3f64.sqrt() / 400.0;
            prop_assert!(exact <= sampled + 1e-12);
            prop_assert!(sampled - exact <= grid_step, "{exact} {sampled}");
        }
    }

    #[test]
    fn a_link_between_station_and_target_hides_it_and_one_beside_does_not() {
        let station = p(0.0, 0.0, 0.0);
        let target = p(2.0, 0.0, 0.0);
        let across = [(p(1.0, -1.0, 0.0), p(1.0, 1.0, 0.0))];
        assert!(!sees(&station, &target, &across, 0.05, 2e-3));
        let beside = [(p(1.0, 0.2, -1.0), p(1.0, 0.2, 1.0))];
        assert!(sees(&station, &target, &beside, 0.05, 2e-3));
        assert!(!sees(&station, &target, &beside, 0.25, 2e-3));
        // The target's own link ends at the target: stopping short keeps it visible.
        let own = [(p(2.0, 0.0, 0.0), p(3.0, 0.0, 0.0))];
        assert!(sees(&station, &target, &own, 1e-3, 2e-3));
    }
}
