//! Gross errors among the cycles of an ISO test, found before the figures: a cycle measured in
//! other units, with two target ids swapped, or of another point, alone makes its pose's `AP`
//! and `RP` (one cycle in metres of thirty gives an `RP_l` of metres).
//!
//! Per pose and approach direction, each cycle's attained pose is six coordinates: its position
//! `x, y, z` in the base frame and its rotation vector `rx, ry, rz` from the pose's median
//! orientation. The outlier cycles are those of Rosner's generalized extreme studentised
//! deviate test ([`generalized_esd`]): each coordinate against the other cycles' own scatter
//! along it (the robot's repeatability and the instrument's noise, far from isotropic: a joint's
//! jitter moves the tool along its Jacobian's column), never one pose's scatter against
//! another's. Its fence is the Student t quantile for the cycles left, so that it holds its
//! false-alarm rate for 8 cycles as for 300: [`ISO_CYCLES_FALSE_ALARM`] over every pose and
//! coordinate a file's test screens. A cycle in metres or with swapped targets lies thousands
//! of standard deviations out. A pose with fewer than [`MIN_CYCLES`] cycles is not screened,
//! nor a coordinate its other cycles share exactly (no scatter: noise-free data); more than
//! [`OUTLIER_SHARE_MAX`] of a pose's cycles, or more than [`OUTLIER_ROUNDS_MAX`], beyond the
//! fence is an error: the pose, not single cycles, is wrong; so is a pose with more cycles than
//! that beyond the first round's fence from its median in robust standard deviations, which
//! the rounds would not reach (more bad cycles than rounds mask each other in every round).
//! The test runs one round more than it may set aside, so that a pose of 20,000 cycles is not
//! screened in 4,000 rounds.

use super::IsoError;
use super::evaluate::Cycle;
use crate::calibration::procedure::{OUTLIER_ROUNDS_MAX, OUTLIER_SHARE_MAX};
use crate::numerics::stats::{generalized_esd, median, robustly_beyond, student_t_two_sided};
use nalgebra::{Isometry3, Quaternion, UnitQuaternion, Vector3};
use std::collections::BTreeMap;

/// A pose with fewer cycles than this is not screened: the other cycles' scatter is too
/// uncertain to find any but the grossest error (as the validation points' screen needs 8
/// points).
pub const MIN_CYCLES: usize = 8;

/// The family-wise false-alarm rate of the screen over a whole file: on clean cycles about this
/// share of files has a cycle flagged (the sweep points' rate,
/// [`crate::calibration::procedure::SWEEP_POINTS_FALSE_ALARM`]).
pub const ISO_CYCLES_FALSE_ALARM: f64 = crate::calibration::procedure::SWEEP_POINTS_FALSE_ALARM;

/// The names of a cycle's six coordinates.
const COORDINATES: [&str; 6] = ["x", "y", "z", "rx", "ry", "rz"];

/// A cycle the screen flagged.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct OutlierCycle {
    /// The experiment (`iso-P<k>` or `iso-P<k>-d<h>`).
    pub experiment: String,
    /// Its step: the cycle.
    pub step: usize,
    /// The data file's line of the cycle's first row, when known.
    pub line: Option<u64>,
    /// Distance of its attained position from its pose's median \[mm\].
    pub position_mm: f64,
    /// Angle of its attained orientation from its pose's median \[mrad\].
    pub angle_mrad: f64,
    /// Its coordinate farthest out (`x`, `y`, `z` \[base frame\], `rx`, `ry`, `rz` \[rotation
    /// vector from the pose's median orientation\]).
    pub coordinate: String,
    /// Its externally studentised deviation along that coordinate: its distance from the mean
    /// of the pose's other cycles kept, in their standard deviations (module doc).
    pub studentised: f64,
    /// The fence it exceeds: the Student t quantile for the pose's cycles kept, at the file's
    /// false-alarm rate.
    pub fence: f64,
    /// Whether the figures were computed without it (`false`: kept on request).
    pub dropped: bool,
}

impl OutlierCycle {
    /// The cycle, where it is in the file, how far out, and what to check, in words.
    pub fn describe(&self) -> String {
        format!(
            "{}outlier cycle: experiment {} cycle (step) {} attained {:.3} mm and {:.3} mrad from its pose's median; its {} lies {:.1} standard deviations of the pose's other cycles from their mean (the fence for this pose is {:.1}): {}; check this cycle's rows (coordinates and their units, target ids)",
            self.line.map_or(String::new(), |l| format!("line {l}: ")),
            self.experiment,
            self.step,
            self.position_mm,
            self.angle_mrad,
            self.coordinate,
            self.studentised,
            self.fence,
            if self.dropped {
                "the figures are computed without it (--keep-outliers keeps it)"
            } else {
                "kept (--keep-outliers)"
            }
        )
    }
}

/// The orientation at the middle of `poses`: the per-component median of their rotation
/// vectors about their mean quaternion (each sign-aligned to the first), which a few far
/// cycles barely move.
fn median_rotation(poses: &[&Isometry3<f64>]) -> UnitQuaternion<f64> {
    let first = poses[0].rotation.into_inner();
    let sum: Quaternion<f64> = poses
        .iter()
        .map(|p| p.rotation.into_inner())
        .map(|q| if q.dot(&first) < 0.0 { -q } else { q })
        .fold(Quaternion::default(), |a, q| a + q);
    let mean = UnitQuaternion::from_quaternion(sum);
    let vectors: Vec<Vector3<f64>> = poses
        .iter()
        .map(|p| (mean.inverse() * p.rotation).scaled_axis())
        .collect();
    let centre = Vector3::from_fn(|i, _| median(&vectors.iter().map(|v| v[i]).collect::<Vec<_>>()));
    mean * UnitQuaternion::from_scaled_axis(centre)
}

/// The cycles of one pose (at least [`MIN_CYCLES`]) the test flags at false-alarm rate
/// `alpha` (module doc), with `keep` flagged as kept; and, when more cycles than the test has
/// rounds lie beyond the first round's fence from the pose's median in robust standard
/// deviations ([`robustly_beyond`]), their count: so many bad cycles mask each other in every
/// round. (Up to as many as the rounds are found by them; asking for more keeps a clean pose
/// of 8 cycles, whose median absolute deviation is too uncertain, from being refused.)
fn screen_pose(cycles: &[&Cycle], alpha: f64, keep: bool) -> (Vec<OutlierCycle>, Option<usize>) {
    let rotation = median_rotation(&cycles.iter().map(|c| &c.attained).collect::<Vec<_>>());
    let coordinates: Vec<[f64; 6]> = cycles
        .iter()
        .map(|c| {
            let p = c.attained.translation.vector;
            let r = (rotation.inverse() * c.attained.rotation).scaled_axis();
            [p.x, p.y, p.z, r.x, r.y, r.z]
        })
        .collect();
    let median_position = Vector3::from_fn(|i, _| median(&coordinates.iter().map(|c| c[i]).collect::<Vec<_>>()));
    let most = ((OUTLIER_SHARE_MAX * cycles.len() as f64).floor() as usize).min(OUTLIER_ROUNDS_MAX) + 1;
    let n = cycles.len() as f64;
    let first_fence = student_t_two_sided(alpha / (most as f64 * n * COORDINATES.len() as f64), n - 2.0);
    let beyond = robustly_beyond(&coordinates, first_fence);
    let flagged = generalized_esd(&coordinates, alpha, most)
        .into_iter()
        .map(|o| {
            let (c, x) = (cycles[o.sample], coordinates[o.sample]);
            OutlierCycle {
                experiment: c.experiment.clone(),
                step: c.step,
                line: c.line,
                position_mm: (Vector3::new(x[0], x[1], x[2]) - median_position).norm() * 1e3,
                angle_mrad: Vector3::new(x[3], x[4], x[5]).norm() * 1e3,
                coordinate: COORDINATES[o.coordinate].to_string(),
                studentised: o.studentised,
                fence: o.fence,
                dropped: !keep,
            }
        })
        .collect();
    (flagged, (beyond > most).then_some(beyond))
}

/// The outlier cycles of `cycles` (module doc), in file order; with `keep` flagged as kept.
pub(super) fn screen_cycles(cycles: &BTreeMap<usize, Vec<Cycle>>, keep: bool) -> Result<Vec<OutlierCycle>, IsoError> {
    let mut groups: BTreeMap<(usize, usize), Vec<&Cycle>> = BTreeMap::new();
    for (&pose, list) in cycles {
        for c in list {
            groups.entry((pose, c.direction)).or_default().push(c);
        }
    }
    let screened: Vec<&Vec<&Cycle>> = groups.values().filter(|g| g.len() >= MIN_CYCLES).collect();
    let alpha = ISO_CYCLES_FALSE_ALARM / screened.len().max(1) as f64;
    let mut out = Vec::new();
    for group in screened {
        let (flagged, beyond) = screen_pose(group, alpha, keep);
        let bad = beyond.unwrap_or(flagged.len());
        if bad > OUTLIER_ROUNDS_MAX || bad as f64 > OUTLIER_SHARE_MAX * group.len() as f64 {
            return Err(IsoError::TooManyOutliers {
                experiment: group[0].experiment.clone(),
                flagged: bad,
                cycles: group.len(),
            });
        }
        out.extend(flagged);
    }
    out.sort_by(|a, b| (a.line, &a.experiment, a.step).cmp(&(b.line, &b.experiment, b.step)));
    Ok(out)
}
