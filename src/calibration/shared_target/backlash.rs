//! A held joint's backlash in the reference-pose test (run 11: clean sweep files whose joints
//! carry a 1-1.5 mrad band). A joint with backlash lags half its band behind the direction it
//! last moved in; a sweep's first point, taken before its joint moved, sits where the previous
//! motion left the joint in its band, ahead along the sweep's motion of the path of the others
//! by up to the band (`Turning::lead_rad`). A joint held at the reference pose through another
//! joint's sweep sits where its last move left it, which differs between the sweeps by up to
//! its band: the sweep's target then turns about that joint's axis, by the band times the
//! target's distance from the axis (0.9 mm for 1 mrad at 0.9 m). A sweep out of place by
//! what the held joints, each turned within the band the first points show about the axis its
//! own sweep measures, explain is named for the backlash, not a moved block
//! ([`explained`]). The data against themselves: every axis is a sweep's fitted circle, every
//! band a sweep's first point.

use super::sighting::{SHARED_TARGET_FALSE_ALARM, Sighting, Turning, noise_bound, variance};
use crate::measurement::column_slips::GROSS_MISS_FACTOR;
use crate::numerics::stats::chi_square_quantile;
use nalgebra::Vector3;

/// The band each held joint's sweep shows (`(joint, band)`), its first point's lead beyond the
/// noise test's bound at the noise `sigma2` of a coordinate.
fn bands(sightings: &[Sighting], sigma2: f64) -> Vec<(usize, f64, &Turning)> {
    let bound = chi_square_quantile(1.0 - SHARED_TARGET_FALSE_ALARM, 1.0).sqrt() * sigma2.sqrt();
    let mut out: Vec<(usize, f64, &Turning)> = Vec::new();
    for s in sightings {
        let Some(t) = &s.turning else { continue };
        let Some(lead) = t.lead_rad.filter(|_| t.lead_mm > bound) else {
            continue;
        };
        match out.iter_mut().find(|b| b.0 == s.joint) {
            Some(b) if b.1 < lead => *b = (s.joint, lead, t),
            Some(_) => {}
            None => out.push((s.joint, lead, t)),
        }
    }
    out
}

/// The held joints' turns (`(joint, turn rad)`) that explain sighting `k`'s `offset` across its
/// motion from the others' consensus `centre` \[mm\]: each joint held through its sweep whose
/// own sweep's first point shows a band ([`bands`]), turned within that band about its own
/// sweep's axis, leaving an offset within the test's bound ([`super::odd_one_out`]'s rule);
/// `None` when no band is shown or the turns it takes are beyond the bands.
pub(super) fn explained(
    sightings: &[Sighting],
    k: usize,
    centre: Vector3<f64>,
    offset: Vector3<f64>,
    sigma2: f64,
) -> Option<Vec<(usize, f64)>> {
    let s = &sightings[k];
    let held: Vec<(usize, f64, &Turning)> = bands(sightings, sigma2)
        .into_iter()
        .filter(|b| b.0 != s.joint)
        .collect();
    if held.is_empty() {
        return None;
    }
    let moves: Vec<Vector3<f64>> = held
        .iter()
        .map(|(_, _, t)| s.across * t.axis.cross(&(centre - t.centre)))
        .collect();
    let bounds: Vec<f64> = held.iter().map(|h| h.1).collect();
    let turns = bounded_least_squares(&moves, &bounds, offset);
    let left = offset - moves.iter().zip(&turns).map(|(m, t)| m * *t).sum::<Vector3<f64>>();
    let passes = left.norm() / variance(s, sigma2).sqrt() <= GROSS_MISS_FACTOR * noise_bound(s);
    passes.then(|| held.iter().zip(&turns).map(|((j, _, _), t)| (*j, *t)).collect())
}

/// Sweeps of [`bounded_least_squares`]'s coordinate descent: each solves one turn exactly given
/// the others, and a few held joints converge in a few tens.
const DESCENT_SWEEPS: usize = 200;

/// The turns `t` (each within `-bounds[j]..=bounds[j]`) whose moves `sum t_j moves[j]` come
/// nearest `offset`: a convex quadratic in a box, solved by coordinate descent.
fn bounded_least_squares(moves: &[Vector3<f64>], bounds: &[f64], offset: Vector3<f64>) -> Vec<f64> {
    let mut turns = vec![0.0; moves.len()];
    let mut left = offset;
    for _ in 0..DESCENT_SWEEPS {
        for (j, m) in moves.iter().enumerate() {
            let norm2 = m.norm_squared();
            if norm2 == 0.0 {
                continue;
            }
            let t = (turns[j] + m.dot(&left) / norm2).clamp(-bounds[j], bounds[j]);
            left -= m * (t - turns[j]);
            turns[j] = t;
        }
    }
    turns
}
