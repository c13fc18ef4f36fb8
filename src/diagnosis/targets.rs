//! The tool targets refined from the validation poses before scoring.
//!
//! A real campaign's tool targets are a guess (a drawing, a ruler): the description's are
//! nominal. The calibration's tool frame is the rigid fit of those nominal targets to the
//! points measured at the reference pose, so a wrong guess tilts the calibrated tool frame,
//! and the baseline refit, linear in its parameters, leaves the second-order part of that
//! tilt in the held-out residual, where a candidate bends itself to imitate it. So the
//! diagnosis first fits the baseline refit (geometry, identified shapes, tool-target
//! positions, base and tool frames) to the training poses by Gauss-Newton beyond its
//! linearisation ([`Prepared::refine`](super::Prepared)), takes the targets it finds and runs
//! everything else (calibration included) with them. The refit keeps the target positions
//! among its parameters, so the refinement only moves the point the refit is linearised at:
//! the tests and their noise-only thresholds are those of the same model.
//!
//! The targets' placement in the tool frame trades off against the tool frame itself (a rigid
//! motion of all targets is not identifiable); their shape is: the distances between them.
//! Each distance is compared with the nominal one in sigmas of the refined estimate (first-
//! order propagation of the refit's covariance, `J N J^T s^2`, `N` the normal matrix's
//! pseudo-inverse, `s^2` the larger of the noise variance and the training residual
//! variance; a rigid motion leaves a distance unchanged to first order, so the unidentifiable
//! directions do not enter). A distance beyond [`FAR_SIGMAS`] makes the guess "far off".

use super::{LinearFit, sensitivity};
use crate::robot::RobotDescription;
use nalgebra::{DVector, Point3};
use serde::{Deserialize, Serialize};

/// A nominal distance between tool targets this many sigmas (of the refined estimate) from
/// the refined one is "far off": a two-sided Gaussian tail of 6e-5 per distance, so a right
/// guess is flagged about once in 5000 diagnoses of a three-target tool.
pub const FAR_SIGMAS: f64 = 4.0;

/// One distance between two tool targets, nominal and refined.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct TargetDistance {
    /// The first target of the pair (its CSV `target` id).
    pub first_target: usize,
    /// The second target of the pair (its CSV `target` id).
    pub second_target: usize,
    /// The description's distance \[mm\].
    pub nominal_mm: f64,
    /// Refined from the training poses \[mm\].
    pub refined_mm: f64,
    /// 1-sigma of `refined_mm` \[mm\].
    pub sigma_mm: f64,
    /// `(nominal - refined) / sigma`.
    pub sigmas_off: f64,
}

/// The tool targets the diagnosis used: refined from the training validation poses (module
/// docs of `diagnosis::targets`), against the description's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ToolTargets {
    /// The description's tool targets, tool frame \[mm\].
    pub nominal_mm: Vec<[f64; 3]>,
    /// The refined tool targets the diagnosis scored with, tool frame \[mm\] (their placement
    /// in the frame is the refit's minimum-norm choice; their shape is what the data say).
    pub refined_mm: Vec<[f64; 3]>,
    /// Every distance between two targets.
    pub distances: Vec<TargetDistance>,
    /// The largest `|sigmas_off|` (0 with fewer than two targets).
    pub largest_sigmas_off: f64,
    /// `largest_sigmas_off > FAR_SIGMAS`: the nominal guess is far off (a warning).
    pub far: bool,
}

impl ToolTargets {
    /// The warning to print when the nominal guess is far off.
    pub fn warning(&self) -> Option<String> {
        let worst = self
            .distances
            .iter()
            .max_by(|a, b| a.sigmas_off.abs().total_cmp(&b.sigmas_off.abs()))?;
        self.far.then(|| {
            format!(
                "the description's tool targets are far off: targets {} and {} are {:.3} mm apart in the \
                 description, {:.3} +- {:.3} mm from the validation poses ({:.1} sigma); the diagnosis \
                 used the refined targets {}",
                worst.first_target,
                worst.second_target,
                worst.nominal_mm,
                worst.refined_mm,
                worst.sigma_mm,
                worst.sigmas_off.abs(),
                format_targets(&self.refined_mm)
            )
        })
    }

    /// `desc` with the refined tool targets.
    pub fn description(&self, desc: &RobotDescription) -> RobotDescription {
        let mut refined = desc.clone();
        refined.tool.targets_mm = self.refined_mm.clone();
        refined
    }
}

fn format_targets(targets_mm: &[[f64; 3]]) -> String {
    let each: Vec<String> = targets_mm
        .iter()
        .map(|t| format!("[{:.2}, {:.2}, {:.2}]", t[0], t[1], t[2]))
        .collect();
    format!("{} mm", each.join(", "))
}

fn distances_m(targets: &[Point3<f64>]) -> Vec<f64> {
    let mut out = Vec::new();
    for i in 0..targets.len() {
        for j in i + 1..targets.len() {
            out.push((targets[i] - targets[j]).norm());
        }
    }
    out
}

/// The comparison of the `nominal` targets with the refined ones `refined(params)` at the
/// refit's parameters `params`, `fit` linearised there, `variance` the per-coordinate
/// residual variance \[m^2\]. `None` when the refined targets cannot be evaluated.
pub(super) fn compare<F>(
    nominal: &[Point3<f64>],
    refined: F,
    params: &DVector<f64>,
    fit: &LinearFit,
    variance: f64,
) -> Option<ToolTargets>
where
    F: Fn(&[f64]) -> Vec<Point3<f64>> + Sync,
{
    let at = refined(params.as_slice());
    let d = |p: &[f64]| Some(distances_m(&refined(p)));
    let steps = vec![1e-6; params.len()];
    let jac = sensitivity(d, params.as_slice(), &steps)?;
    let cov = &jac * &fit.normal_inverse * jac.transpose() * variance;
    let nominal_d = distances_m(nominal);
    let refined_d = distances_m(&at);
    let pairs = (0..nominal.len()).flat_map(|i| (i + 1..nominal.len()).map(move |j| [i, j]));
    let distances: Vec<TargetDistance> = pairs
        .zip(nominal_d.iter().zip(&refined_d))
        .enumerate()
        .map(|(k, (targets, (n, r)))| {
            let sigma = cov[(k, k)].max(0.0).sqrt();
            TargetDistance {
                first_target: targets[0],
                second_target: targets[1],
                nominal_mm: n * 1e3,
                refined_mm: r * 1e3,
                sigma_mm: sigma * 1e3,
                sigmas_off: if sigma > 0.0 { (n - r) / sigma } else { 0.0 },
            }
        })
        .collect();
    let largest = distances.iter().map(|d| d.sigmas_off.abs()).fold(0.0, f64::max);
    let to_mm = |t: &Point3<f64>| [t.x * 1e3, t.y * 1e3, t.z * 1e3];
    Some(ToolTargets {
        nominal_mm: nominal.iter().map(to_mm).collect(),
        refined_mm: at.iter().map(to_mm).collect(),
        distances,
        largest_sigmas_off: largest,
        far: largest > FAR_SIGMAS,
    })
}
