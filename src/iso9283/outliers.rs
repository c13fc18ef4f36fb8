//! Gross errors among the cycles of an ISO test, found before the figures: a cycle measured in
//! other units, with two target ids swapped, or of another point, alone makes its pose's `AP`
//! and `RP` (one cycle in metres of thirty gives an `RP_l` of metres).
//!
//! Per pose and approach direction, each cycle's attained pose is six coordinates: its position
//! `x, y, z` in the base frame and its rotation vector `rx, ry, rz` from the pose's median
//! orientation. A cycle is an outlier when any coordinate lies beyond Tukey's far-out fences
//! `Q1 - 3 IQR`, `Q3 + 3 IQR` of its pose's cycles ([`FAR_OUT`], the rule of the sweeps' and
//! the validation points' screens, [`crate::calibration::procedure::screen_sweeps`]): each
//! coordinate against the cycles' own scatter along it (the robot's repeatability and the
//! instrument's noise, far from isotropic: a joint's jitter moves the tool along its Jacobian's
//! column), never one pose's scatter against another's. A Gaussian coordinate passes a fence
//! once in about 800,000 (4.7 sigma); a cycle in metres or with swapped targets lies thousands
//! of interquartile ranges out. A pose with fewer than [`MIN_CYCLES`] cycles is not screened,
//! nor a coordinate its cycles share exactly (no scatter: noise-free data); more than
//! [`OUTLIER_SHARE_MAX`] of a pose's cycles beyond the fences is an error: the pose, not single
//! cycles, is wrong.

use super::IsoError;
use super::evaluate::Cycle;
use crate::calibration::procedure::OUTLIER_SHARE_MAX;
use crate::numerics::stats::{FAR_OUT, QuantileMethod, median, quantile};
use nalgebra::{Isometry3, Quaternion, UnitQuaternion, Vector3};
use std::collections::BTreeMap;

/// A pose with fewer cycles than this is not screened: its quartiles are no fence (as the
/// validation points' screen needs 8 points).
pub const MIN_CYCLES: usize = 8;

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
    /// How far that coordinate lies beyond its pose's quartile, in interquartile ranges
    /// (beyond the far-out fence: more than 3).
    pub beyond_iqr: f64,
    /// Whether the figures were computed without it (`false`: kept on request).
    pub dropped: bool,
}

impl OutlierCycle {
    /// The cycle, where it is in the file, how far out, and what to check, in words.
    pub fn describe(&self) -> String {
        format!(
            "{}outlier cycle: experiment {} cycle (step) {} attained {:.3} mm and {:.3} mrad from its pose's median; its {} lies {:.1} interquartile ranges beyond its pose's cycles' quartile (the far-out fence is {FAR_OUT}): {}; check this cycle's rows (coordinates and their units, target ids)",
            self.line.map_or(String::new(), |l| format!("line {l}: ")),
            self.experiment,
            self.step,
            self.position_mm,
            self.angle_mrad,
            self.coordinate,
            self.beyond_iqr,
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

/// The cycles of one pose (at least [`MIN_CYCLES`]) beyond a far-out fence (module doc), with
/// `keep` flagged as kept.
fn screen_pose(cycles: &[&Cycle], keep: bool) -> Vec<OutlierCycle> {
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
    // Per coordinate: its first and third quartiles and their distance.
    let quartiles: [(f64, f64, f64); 6] = std::array::from_fn(|k| {
        let v: Vec<f64> = coordinates.iter().map(|c| c[k]).collect();
        let (q1, q3) = (
            quantile(&v, 0.25, QuantileMethod::Linear),
            quantile(&v, 0.75, QuantileMethod::Linear),
        );
        (q1, q3, q3 - q1)
    });
    let mut out = Vec::new();
    for (c, x) in cycles.iter().zip(&coordinates) {
        let (k, beyond) = (0..6)
            .filter(|&k| quartiles[k].2 > 0.0)
            .map(|k| {
                let (q1, q3, iqr) = quartiles[k];
                (k, (q1 - x[k]).max(x[k] - q3) / iqr)
            })
            .fold((0, f64::NEG_INFINITY), |best, b| if b.1 > best.1 { b } else { best });
        if beyond > FAR_OUT {
            out.push(OutlierCycle {
                experiment: c.experiment.clone(),
                step: c.step,
                line: c.line,
                position_mm: (Vector3::new(x[0], x[1], x[2]) - median_position).norm() * 1e3,
                angle_mrad: Vector3::new(x[3], x[4], x[5]).norm() * 1e3,
                coordinate: COORDINATES[k].to_string(),
                beyond_iqr: beyond,
                dropped: !keep,
            });
        }
    }
    out
}

/// The outlier cycles of `cycles` (module doc), in file order; with `keep` flagged as kept.
pub(super) fn screen_cycles(cycles: &BTreeMap<usize, Vec<Cycle>>, keep: bool) -> Result<Vec<OutlierCycle>, IsoError> {
    let mut groups: BTreeMap<(usize, usize), Vec<&Cycle>> = BTreeMap::new();
    for (&pose, list) in cycles {
        for c in list {
            groups.entry((pose, c.direction)).or_default().push(c);
        }
    }
    let mut out = Vec::new();
    for group in groups.values().filter(|g| g.len() >= MIN_CYCLES) {
        let flagged = screen_pose(group, keep);
        if flagged.len() as f64 > OUTLIER_SHARE_MAX * group.len() as f64 {
            return Err(IsoError::TooManyOutliers {
                experiment: group[0].experiment.clone(),
                flagged: flagged.len(),
                cycles: group.len(),
            });
        }
        out.extend(flagged);
    }
    out.sort_by(|a, b| (a.line, &a.experiment, a.step).cmp(&(b.line, &b.experiment, b.step)));
    Ok(out)
}
