//! Test poses: an ISO 9283-style five-point set and a seeded random set, each inside the
//! calibrated spans (Table 1) or over the workspace, all reproducible.
//!
//! A test pose is a REQUIRED tool pose. It is generated from a joint configuration of the
//! nominal model (`world_from_tool = nominal FK(q_nominal)`), so `q_nominal` is also what the
//! unchanged controller sends for it without calibration (its nominal IK on that branch).

use crate::kinematics::{PhiModel, nominal_closed_form};
use crate::plan::CalibrationPlan;
use crate::robot::RobotDescription;
use crate::robot::commands_to_internal;
use nalgebra::Isometry3;
use rand::{RngExt, SeedableRng, rngs::ChaCha12Rng};
use serde::{Deserialize, Serialize};

/// Where a test pose lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Region {
    /// Every joint inside the span its axis was calibrated over (Table 1).
    InsideSpans,
    /// Anywhere in the validation workspace (the arm in front of the theodolites).
    Workspace,
}

impl Region {
    /// `inside_spans` or `workspace`.
    pub fn name(self) -> &'static str {
        match self {
            Region::InsideSpans => "inside_spans",
            Region::Workspace => "workspace",
        }
    }
}

/// One required tool pose.
#[derive(Clone, Debug, PartialEq)]
pub struct TestPose {
    /// `iso-inside-P1`, `rand-workspace-017`, ...
    pub id: String,
    /// Where it lies.
    pub region: Region,
    /// `iso9283` or `random`.
    pub family: &'static str,
    /// The nominal joint configuration \[rad or m\] whose nominal FK is the required pose.
    pub q_nominal: Vec<f64>,
    /// The required tool pose, instrument frame \[m\].
    pub world_from_tool: Isometry3<f64>,
}

/// Per-joint command ranges `[lo, hi]` \[rad or m\] of a region.
#[derive(Clone, Debug, PartialEq)]
pub struct JointRanges(pub Vec<[f64; 2]>);

impl JointRanges {
    /// The swept range of every joint in `plan` (the calibrated spans), internal units.
    pub fn calibrated_spans(desc: &RobotDescription, plan: &CalibrationPlan) -> Self {
        let reference = commands_to_internal(desc, &plan.reference);
        let mut r: Vec<[f64; 2]> = reference.iter().map(|&c| [c, c]).collect();
        for s in &plan.sweeps {
            let ends = [s.offset_at(0), s.offset_at(s.intervals)].map(|o| {
                let mut c = plan.reference.clone();
                c[s.joint - 1] += o;
                commands_to_internal(desc, &c)[s.joint - 1]
            });
            r[s.joint - 1] = [ends[0].min(ends[1]), ends[0].max(ends[1])];
        }
        JointRanges(r)
    }

    /// `+-half_range_file` (deg or mm) around zero, clipped to the description's limits.
    pub fn around_zero(desc: &RobotDescription, half_range_file: &[f64]) -> Self {
        let half = commands_to_internal(desc, half_range_file);
        JointRanges(
            (0..desc.dof())
                .map(|k| {
                    let [lo, hi] = desc.limits_internal(k);
                    [(-half[k].abs()).max(lo), half[k].abs().min(hi)]
                })
                .collect(),
        )
    }

    /// Whether `q` lies inside every range (with `slack` on each side).
    pub fn contains(&self, q: &[f64], slack: f64) -> bool {
        q.iter()
            .zip(&self.0)
            .all(|(v, [lo, hi])| *v >= lo - slack && *v <= hi + slack)
    }

    /// The middle of every range.
    pub fn centre(&self) -> Vec<f64> {
        self.0.iter().map(|[lo, hi]| 0.5 * (lo + hi)).collect()
    }
}

/// `n` configurations uniform in `ranges`, from `seed`.
pub fn random_poses(model: &PhiModel, ranges: &JointRanges, region: Region, n: usize, seed: u64) -> Vec<TestPose> {
    let mut rng = ChaCha12Rng::seed_from_u64(seed);
    (0..n)
        .map(|i| {
            let q: Vec<f64> = ranges
                .0
                .iter()
                .map(|&[lo, hi]| if hi > lo { rng.random_range(lo..=hi) } else { lo })
                .collect();
            TestPose {
                id: format!("rand-{}-{i:03}", region.name()),
                region,
                family: "random",
                world_from_tool: model.world_from_tool(&q),
                q_nominal: q,
            }
        })
        .collect()
}

/// The five ISO 9283 test points in a cube of edge `edge_m` centred on the tool position of
/// the configuration `q_centre`, axis-aligned with the robot base frame, with the tool
/// orientation of `q_centre` throughout: `P1` the centre, `P2..P5` on the diagonal plane
/// `C1-C2-C7-C8` at 10 % of that plane's diagonal from the corners (`P = P1 + 0.8 (C - P1)`),
/// ISO 9283:1998 sec. 6.8. Each point's configuration is the nominal closed-form branch
/// nearest `q_centre`. `None` if a point has no branch inside `ranges`.
pub fn iso9283_poses(
    model: &PhiModel,
    q_centre: &[f64],
    edge_m: f64,
    ranges: &JointRanges,
    region: Region,
) -> Option<Vec<TestPose>> {
    let centre = model.world_from_tool(q_centre);
    let points = crate::iso9283::cube_points(&centre, &model.world_from_base, edge_m);
    let mut out = Vec::new();
    for (i, target) in points.into_iter().enumerate() {
        let branches = nominal_closed_form(model, &target).ok()?;
        let distance = |q: &[f64]| q.iter().zip(q_centre).map(|(a, b)| (a - b).powi(2)).sum::<f64>();
        let q = branches
            .into_iter()
            .map(|b| b.q)
            .filter(|q| ranges.contains(q, 1e-9))
            .min_by(|a, b| distance(a).total_cmp(&distance(b)))?;
        out.push(TestPose {
            id: format!("iso-{}-P{}", region.name(), i + 1),
            region,
            family: "iso9283",
            q_nominal: q,
            world_from_tool: target,
        });
    }
    Some(out)
}

/// The largest cube edge (to 1 mm, at most `max_edge_m`) whose five ISO points are reachable
/// inside `ranges` from `q_centre`, and those points.
pub fn largest_iso9283_cube(
    model: &PhiModel,
    q_centre: &[f64],
    max_edge_m: f64,
    ranges: &JointRanges,
    region: Region,
) -> Option<(f64, Vec<TestPose>)> {
    let mut edge = (max_edge_m * 1e3).floor() as usize;
    while edge > 0 {
        let e = edge as f64 * 1e-3;
        if let Some(p) = iso9283_poses(model, q_centre, e, ranges, region) {
            return Some((e, p));
        }
        edge = edge.saturating_sub(10.max(edge / 20));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn iso_points_are_reachable_inside_the_spans() {
        let desc = RobotDescription::asea_irb6l();
        let model = desc.nominal_model();
        let spans = JointRanges::calibrated_spans(&desc, &CalibrationPlan::table1(6));
        assert!((spans.0[0][1] - 24f64.to_radians()).abs() < 1e-12);
        let (edge, poses) =
            largest_iso9283_cube(&model, &spans.centre(), 1.0, &spans, Region::InsideSpans).expect("a cube fits");
        assert!(edge > 0.1, "edge {edge}");
        assert_eq!(poses.len(), 5);
        for p in &poses {
            assert!(spans.contains(&p.q_nominal, 1e-9));
            let e =
                (model.world_from_tool(&p.q_nominal).translation.vector - p.world_from_tool.translation.vector).norm();
            assert!(e < 1e-9);
        }
    }
}
