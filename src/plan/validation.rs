//! Validation poses: free joint configurations spread over the workspace, visited after the
//! axis experiments (`docs/formats.md#measurement-csv`, `moved_joint = 0`).

use crate::robot::RobotDescription;
use rand::{RngExt, SeedableRng, rngs::ChaCha12Rng};
use serde::{Deserialize, Serialize};

/// A seeded set of validation poses drawn uniformly inside per-joint command ranges.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ValidationPlan {
    /// Number of distinct poses (the paper's figs. 9-10 use a few dozen; the diagnosis wants >= 50
    /// for a simulated campaign).
    pub poses: usize,
    /// Per joint, the half-range of commands around the reference \[deg or mm\]; clipped to
    /// the joint limits.
    pub half_range: Vec<f64>,
    /// Seed of the pose draw (independent of the measurement noise seed).
    pub seed: u64,
}

/// The most validation poses a campaign draws (`simulate --validation-poses`, a scenario's
/// `[validation] poses`): three million rows, beyond which a file is no longer a campaign.
pub const MAX_POSES: usize = 1_000_000;

impl ValidationPlan {
    /// Checks the plan for a robot of `dof` joints: 1 to [`MAX_POSES`] poses, one finite,
    /// non-negative half-range per joint. The error names the key.
    pub fn check(&self, dof: usize) -> Result<(), (&'static str, String)> {
        if !(1..=MAX_POSES).contains(&self.poses) {
            return Err((
                "validation.poses",
                format!("{} poses: must be 1 to {MAX_POSES}", self.poses),
            ));
        }
        if self.half_range.len() != dof {
            return Err((
                "validation.half_range",
                format!("{} values for {dof} joints: one per joint", self.half_range.len()),
            ));
        }
        match self.half_range.iter().position(|h| !(h.is_finite() && *h >= 0.0)) {
            Some(k) => Err((
                "validation.half_range",
                format!(
                    "joint {}: {} must be finite and >= 0 (deg or mm)",
                    k + 1,
                    self.half_range[k]
                ),
            )),
            None => Ok(()),
        }
    }

    /// Checks a written `half_range` against `desc`'s joints: none wider than its joint's
    /// whole range (upper minus lower limit), which reaches beyond both limits from any
    /// reference and is clipped to them; a wider one is a slip (mm for deg, a dummy value).
    pub fn check_limits(&self, desc: &RobotDescription) -> Result<(), (&'static str, String)> {
        let too_wide = self
            .half_range
            .iter()
            .zip(&desc.joints)
            .enumerate()
            .find(|(_, (h, j))| {
                let [lo, hi] = j.limits;
                **h > hi - lo
            });
        match too_wide {
            Some((k, (h, j))) => {
                let [lo, hi] = j.limits;
                let unit = j.kind.file_unit();
                Err((
                    "validation.half_range",
                    format!(
                        "joint {}: {} {unit} is wider than the joint's whole range, its limits [{}, {}] {unit} ({} \
                         {unit}): the poses are clipped to the limits, so give at most that (deg or mm, as the \
                         description's `limits`)",
                        k + 1,
                        crate::measurement::format_f64(*h),
                        crate::measurement::format_f64(lo),
                        crate::measurement::format_f64(hi),
                        crate::measurement::format_f64(hi - lo)
                    ),
                ))
            }
            None => Ok(()),
        }
    }

    /// The default workspace set for the IRB/L6: 60 poses, joints 1-3 within +-40/30/35 deg
    /// (the arm in front of the theodolites), wrist joints 4-6 within +-60/90/90 deg.
    pub fn workspace_default(dof: usize) -> Self {
        let ranges = [40.0, 30.0, 35.0, 60.0, 90.0, 90.0];
        ValidationPlan {
            poses: 60,
            half_range: (0..dof).map(|k| ranges.get(k).copied().unwrap_or(30.0)).collect(),
            seed: 9283,
        }
    }

    /// The command vectors (file units), reproducible for a given seed.
    pub fn commands(&self, desc: &RobotDescription, reference: &[f64]) -> Vec<Vec<f64>> {
        let mut rng = ChaCha12Rng::seed_from_u64(self.seed);
        (0..self.poses)
            .map(|_| {
                desc.joints
                    .iter()
                    .enumerate()
                    .map(|(k, j)| {
                        let half = self.half_range.get(k).copied().unwrap_or(0.0).abs();
                        let lo = (reference[k] - half).max(j.limits[0]);
                        let hi = (reference[k] + half).min(j.limits[1]);
                        if hi > lo {
                            rng.random_range(lo..=hi)
                        } else {
                            reference[k]
                        }
                    })
                    .collect()
            })
            .collect()
    }
}
