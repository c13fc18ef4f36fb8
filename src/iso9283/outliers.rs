//! Gross errors among the cycles of an ISO test, found before the figures: a cycle measured in
//! other units, with two target ids swapped, or of another point, alone makes its pose's `AP`
//! and `RP` (one cycle in metres of thirty gives an `RP_l` of metres).
//!
//! Per pose and approach direction, each cycle's attained pose is six coordinates: the position
//! `x, y, z` in the base frame of the pose's targets' centroid on the tool (the point whose
//! position the fit knows apart from its orientation) and its rotation vector `rx, ry, rz` from
//! the pose's median orientation. The outlier cycles are those of Rosner's generalized extreme studentised
//! deviate test ([`generalized_esd`]): each coordinate against the other cycles' own scatter
//! along it (the robot's repeatability and the instrument's noise, far from isotropic: a joint's
//! jitter moves the tool along its Jacobian's column), never one pose's scatter against
//! another's. Its fence is the Student t quantile for the cycles left, so that it holds its
//! false-alarm rate for 8 cycles as for 300: [`ISO_CYCLES_FALSE_ALARM`] over every pose and
//! coordinate a file's test screens. A cycle in metres or with swapped targets lies thousands
//! of standard deviations out. A pose with fewer than [`MIN_CYCLES`] cycles is not screened, and no
//! coordinate's standard deviation is taken below its resolution (below); more than
//! [`OUTLIER_SHARE_MAX`] of a pose's cycles, or more than [`OUTLIER_ROUNDS_MAX`], beyond the
//! fence is an error: the pose, not single cycles, is wrong; so is a pose with more cycles than
//! that beyond the first round's fence from its median in robust standard deviations, which
//! the rounds would not reach (more bad cycles than rounds mask each other in every round).
//! The test runs one round more than it may set aside, so that a pose of 20,000 cycles is not
//! screened in 4,000 rounds.
//!
//! The resolution: a target's coordinates are known no better than the step the file's
//! cycles are written rounded to ([`written_step_mm`]: 0.01 mm for two decimals), nor than an
//! instrument resolves ([`INSTRUMENT_RESOLUTION_MM`]), whichever is coarser; that step is a
//! standard deviation, not the `1 / sqrt(12)` of a step of rounding noise, because cycles at
//! one true position round alike and one step between two of them is ordinary. Carried through
//! the rigid fit of the cycle's targets, it is the least standard deviation of each of the six
//! coordinates (`least_sigmas`). Without it, cycles rounded alike but one, or noise-free
//! cycles, are judged against the last bits of the fit's arithmetic.

use super::IsoError;
use super::evaluate::Cycle;
use crate::calibration::procedure::{OUTLIER_ROUNDS_MAX, OUTLIER_SHARE_MAX};
use crate::kinematics::centroid;
use crate::measurement::resolution::{INSTRUMENT_RESOLUTION_MM, written_step_mm};
use crate::numerics::stats::{generalized_esd, median, robustly_beyond, student_t_two_sided};
use nalgebra::{Isometry3, Matrix3, Point3, Quaternion, UnitQuaternion, Vector3};
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
    /// Its coordinate farthest out (`x`, `y`, `z` of its targets' centroid \[base frame\], `rx`,
    /// `ry`, `rz` \[rotation vector from the pose's median orientation\]).
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

/// A cycle's six coordinates (module doc): where its attained pose puts `point_m` (on the tool)
/// \[m, base frame\] and its attained orientation's rotation vector from `centre` \[rad\].
fn coordinates_of(attained: &Isometry3<f64>, point_m: &Point3<f64>, centre: &UnitQuaternion<f64>) -> [f64; 6] {
    let p = attained * point_m;
    let r = (centre.inverse() * attained.rotation).scaled_axis();
    [p.x, p.y, p.z, r.x, r.y, r.z]
}

/// The six coordinates of each of a pose's cycles (module doc), at the centroid of the tool
/// targets they measured, and the least standard deviation of each coordinate
/// ([`least_sigmas`] of each cycle's targets, the largest), each target coordinate known to
/// `target_sigma_m`.
fn pose_coordinates(cycles: &[&Cycle], target_sigma_m: f64) -> (Vec<[f64; 6]>, [f64; 6]) {
    let tool = |c: &Cycle| c.targets.iter().map(|t| t.0).collect::<Vec<_>>();
    let point_m = centroid(&cycles.iter().flat_map(|c| tool(c)).collect::<Vec<_>>());
    let rotation = median_rotation(&cycles.iter().map(|c| &c.attained).collect::<Vec<_>>());
    let coordinates = cycles
        .iter()
        .map(|c| coordinates_of(&c.attained, &point_m, &rotation))
        .collect();
    let least = cycles
        .iter()
        .map(|c| least_sigmas(&tool(c), &point_m, target_sigma_m))
        .fold([0.0f64; 6], |a, b| std::array::from_fn(|k| a[k].max(b[k])));
    (coordinates, least)
}

/// The least standard deviations of the six coordinates (at `point_m` on the tool) of a pose
/// fitted to targets at `tool_m` (on the tool, at least three not in a line), each measured
/// with standard deviation `sigma_m` along each axis (module doc). Linearised, the fit's
/// rotation has the covariance `sigma^2 A^-1` with `A = sum_i |c_i|^2 I - c_i c_i^T` (`c_i` the
/// targets about their centroid `c`): at most `sigma^2 / lambda_min(A)` along any axis. The
/// measured centroid has `sigma^2 / n` along each axis, independent of the rotation; the point
/// is the centroid moved by the turned `point - c`: at most
/// `sigma^2 / n + sigma_rot^2 |point - c|^2` along any axis. Infinite for targets in a line.
fn least_sigmas(tool_m: &[Point3<f64>], point_m: &Point3<f64>, sigma_m: f64) -> [f64; 6] {
    let n = tool_m.len() as f64;
    let c = centroid(tool_m);
    let a: Matrix3<f64> = tool_m
        .iter()
        .map(|t| t - c)
        .map(|c| Matrix3::identity() * c.norm_squared() - c * c.transpose())
        .sum();
    let lambda_min = a.symmetric_eigenvalues().min();
    let rotation = if lambda_min > 0.0 {
        sigma_m / lambda_min.sqrt()
    } else {
        f64::INFINITY
    };
    let position = (sigma_m.powi(2) / n + (rotation * (point_m - c).norm()).powi(2)).sqrt();
    [position, position, position, rotation, rotation, rotation]
}

/// The cycles of one pose (at least [`MIN_CYCLES`]) the test flags at false-alarm rate
/// `alpha` (module doc), each target coordinate known to `target_sigma_m`, with `keep` flagged
/// as kept; and, when more cycles than the test has rounds lie beyond the first round's fence
/// from the pose's median in robust standard deviations ([`robustly_beyond`]), their count: so
/// many bad cycles mask each other in every round. (Up to as many as the rounds are found by
/// them; asking for more keeps a clean pose of 8 cycles, whose median absolute deviation is
/// too uncertain, from being refused.)
fn screen_pose(cycles: &[&Cycle], target_sigma_m: f64, alpha: f64, keep: bool) -> (Vec<OutlierCycle>, Option<usize>) {
    let (coordinates, least) = pose_coordinates(cycles, target_sigma_m);
    let origins: Vec<Vector3<f64>> = cycles.iter().map(|c| c.attained.translation.vector).collect();
    let median_origin = Vector3::from_fn(|i, _| median(&origins.iter().map(|p| p[i]).collect::<Vec<_>>()));
    let most = ((OUTLIER_SHARE_MAX * cycles.len() as f64).floor() as usize).min(OUTLIER_ROUNDS_MAX) + 1;
    let n = cycles.len() as f64;
    let first_fence = student_t_two_sided(alpha / (most as f64 * n * COORDINATES.len() as f64), n - 2.0);
    let beyond = robustly_beyond(&coordinates, &least, first_fence);
    let flagged = generalized_esd(&coordinates, &least, alpha, most)
        .into_iter()
        .map(|o| {
            let (c, x) = (cycles[o.sample], coordinates[o.sample]);
            let position_m = c.attained.translation.vector - median_origin;
            OutlierCycle {
                experiment: c.experiment.clone(),
                step: c.step,
                line: c.line,
                position_mm: position_m.norm() * 1e3,
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

/// The least standard deviation \[m\] of a measured target coordinate of `cycles`: the step
/// they are written rounded to ([`written_step_mm`]), or an instrument's resolution
/// ([`INSTRUMENT_RESOLUTION_MM`]), whichever is coarser (module doc).
pub(super) fn least_target_sigma_m(cycles: &BTreeMap<usize, Vec<Cycle>>) -> f64 {
    let measured_mm = cycles
        .values()
        .flatten()
        .flat_map(|c| c.targets.iter().flat_map(|t| t.1.coords.iter().map(|v| v * 1e3)));
    written_step_mm(measured_mm).map_or(INSTRUMENT_RESOLUTION_MM, |q| q.max(INSTRUMENT_RESOLUTION_MM)) * 1e-3
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
    let target_sigma_m = least_target_sigma_m(cycles);
    let mut out = Vec::new();
    for group in screened {
        let (flagged, beyond) = screen_pose(group, target_sigma_m, alpha, keep);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::rigid_fit;
    use crate::numerics::finite_diff::central_jacobian;
    use nalgebra::DMatrix;

    /// [`least_sigmas`] against the fit's own covariance, by another path: the Jacobian of the
    /// six coordinates with respect to the measured targets by central differences through
    /// [`rigid_fit`] (Horn's quaternion, not the linearised normal equations), `sigma^2 J J^T`.
    /// The rotation's largest standard deviation over directions is the bound itself; at the
    /// targets' centroid the position's is `sigma / sqrt(n)` along every axis; elsewhere on the
    /// tool each coordinate's stays within the bound and above `sigma / sqrt(n)`.
    #[test]
    fn least_sigmas_are_the_fits_own_worst_standard_deviations() {
        let tool = [
            Point3::new(0.10, 0.02, 0.05),
            Point3::new(0.03, -0.07, 0.06),
            Point3::new(-0.05, 0.01, 0.11),
            Point3::new(0.0, 0.04, 0.2),
        ];
        let pose = Isometry3::new(Vector3::new(0.8, -0.3, 1.1), Vector3::new(0.4, -1.2, 0.7));
        let measured: Vec<f64> = tool.iter().flat_map(|t| (pose * t).coords.data.0[0]).collect();
        let sigma: f64 = 1e-5;
        let largest = |c: DMatrix<f64>| c.symmetric_eigenvalues().max().sqrt();
        for point in [centroid(&tool), Point3::origin()] {
            let coordinates = |x: &[f64]| {
                let dst: Vec<Point3<f64>> = x.chunks(3).map(|c| Point3::new(c[0], c[1], c[2])).collect();
                let (fit, _) = rigid_fit(&tool, &dst)?;
                Some(coordinates_of(&fit, &point, &pose.rotation).to_vec())
            };
            let j = central_jacobian(coordinates, &measured, &vec![1e-5; measured.len()]).unwrap();
            let covariance = &j * j.transpose() * sigma.powi(2);
            let least = least_sigmas(&tool, &point, sigma);
            let rotation = largest(covariance.view((3, 3), (3, 3)).into_owned());
            assert!((rotation / least[3] - 1.0).abs() < 1e-6, "{rotation} {least:?}");
            let at_centroid = sigma / (tool.len() as f64).sqrt();
            for k in 0..3 {
                let sd = covariance[(k, k)].sqrt();
                assert!(
                    sd <= least[k] * (1.0 + 1e-6) && sd >= at_centroid * (1.0 - 1e-6),
                    "{k}: {sd} {least:?}"
                );
            }
            if point == centroid(&tool) {
                let position = largest(covariance.view((0, 0), (3, 3)).into_owned());
                assert!((position / at_centroid - 1.0).abs() < 1e-6, "{position} {at_centroid}");
                assert!((least[0] / at_centroid - 1.0).abs() < 1e-12, "{least:?}");
            }
        }
        let line = [Point3::origin(), Point3::new(0.1, 0.0, 0.0), Point3::new(0.2, 0.0, 0.0)];
        assert!(least_sigmas(&line, &Point3::origin(), sigma)[3].is_infinite());
    }
}
