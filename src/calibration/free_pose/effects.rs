//! The non-geometric effects a free-pose model may carry (`crate::robot::ModelEffects`): their
//! parameters in the layout and the choice, by cross-validation, of the set the data support
//! (`docs/method.md`, "Effects in the model").

use super::fit::{self, Fitted, Problem};
use super::identify::{Identification, is_effect};
use super::poses::FreePoses;
use super::summary::EffectTrial;
use super::{FreePoseError, cv_errors, significantly_better};
use crate::calibration::refine::RefitParameter;
use crate::kinematics::JointKind;
use crate::numerics::lsq::LsqError;
use crate::robot::{LoadTerm, RobotModel};

/// The effects' parameters for the poses `train`, after the geometry's (identification keeps
/// what the poses resolve, [`super::identify::EFFECT_IDENTIFIABLE_PART`]):
/// - each joint's backlash, where its approach direction takes both signs;
/// - each revolute joint's sag (from joint 2): the four load terms of every link from the one
///   before it to the last, and the payload's four, where the payload varies.
pub fn effect_layout(robot: &RobotModel, poses: &FreePoses, train: &[usize]) -> Vec<RefitParameter> {
    let n = robot.dof();
    let mut p = Vec::new();
    for (k, joint) in robot.joints.iter().enumerate() {
        let signs = |s: f64| train.iter().any(|&i| poses.poses[i].approach[k] * s > 0.0);
        if signs(1.0) && signs(-1.0) {
            p.push(RefitParameter::Backlash {
                joint: k + 1,
                sliding: joint.kind == JointKind::Prismatic,
            });
        }
    }
    let payloads = train.iter().map(|&i| poses.poses[i].payload_kg);
    let (lo, hi) = payloads.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    let payload_varies = hi > lo;
    for (k, joint) in robot.joints.iter().enumerate().skip(1) {
        if joint.kind != JointKind::Revolute {
            continue;
        }
        for link in k..=n {
            for load in LoadTerm::LINK {
                p.push(RefitParameter::Sag {
                    joint: k + 1,
                    link,
                    load,
                });
            }
        }
        if payload_varies {
            for load in LoadTerm::PAYLOAD {
                p.push(RefitParameter::Sag {
                    joint: k + 1,
                    link: n,
                    load,
                });
            }
        }
    }
    p
}

/// The sets of effects tried, by name: which effect parameters each takes.
const TRIALS: [(&str, bool, bool); 4] = [
    ("none", false, false),
    ("backlash", false, true),
    ("sag", true, false),
    ("sag+backlash", true, true),
];

/// The set of effects that predicts held-out configurations best ([`super::CV_FOLDS`]-fold
/// cross-validation over the folds of the harmonic order's, each fold's fit the Gauss-Newton
/// step from the fit on every pose, refitted in full where a fold leaves a parameter
/// undetermined: [`cv_errors`]), taken in the order of [`TRIALS`] and
/// replacing the set before only when [`significantly_better`]: its fit on the poses `kept`,
/// the effect columns left out, and every trial. A set whose fit does not converge is more
/// than the data resolve and is not chosen.
pub(super) fn select_effects(
    problem: &Problem<'_>,
    geometry: Fitted,
    kept: &[usize],
    identification: &Identification,
) -> Result<(Fitted, Vec<usize>, Vec<EffectTrial>), FreePoseError> {
    let layout = problem.layout;
    let effect_columns: Vec<usize> = identification
        .fitted
        .iter()
        .copied()
        .filter(|&c| is_effect(&layout[c]))
        .collect();
    if effect_columns.is_empty() {
        return Ok((geometry, vec![], vec![]));
    }
    let takes = |c: usize, sag: bool, backlash: bool| match layout[c] {
        RefitParameter::Sag { .. } => sag,
        RefitParameter::Backlash { .. } => backlash,
        _ => true,
    };
    let configurations = problem.poses.configurations();
    let points = |which: &[usize]| -> usize { which.iter().map(|&i| problem.poses.poses[i].points_m.len()).sum() };
    let mut trials = Vec::new();
    let mut best: Option<(Vec<f64>, usize, Fitted, Vec<usize>)> = None;
    for (name, sag, backlash) in TRIALS {
        let columns: Vec<usize> = identification
            .fitted
            .iter()
            .copied()
            .filter(|&c| takes(c, sag, backlash))
            .collect();
        let parameters = columns.iter().filter(|&&c| is_effect(&layout[c])).count();
        // Two effects together are tried only when one of them alone predicts better than
        // none: each of two effects the data show does so on its own.
        let single_kept = trials.iter().any(|t: &EffectTrial| t.effects != "none" && t.chosen);
        if (name != "none" && parameters == 0) || (sag && backlash && !single_kept) {
            continue;
        }
        let attempt = || -> Result<(Fitted, Vec<f64>), FreePoseError> {
            let fitted = if name == "none" {
                geometry.clone()
            } else {
                fit::fit(problem, &geometry.model, kept, &columns)?
            };
            let errors = cv_errors(problem, &fitted, kept, &configurations, &columns)?;
            Ok((fitted, errors))
        };
        let (fitted, errors) = match attempt() {
            Ok(v) => v,
            Err(FreePoseError::Fit(LsqError::NotConverged { .. }) | FreePoseError::Unexecutable { .. })
                if name != "none" =>
            {
                continue;
            }
            Err(e) => return Err(e),
        };
        let sse: f64 = errors.iter().sum();
        trials.push(EffectTrial {
            effects: name.into(),
            parameters,
            cross_validated_rms_mm: (sse / points(kept) as f64).sqrt() * 1e3,
            chosen: false,
        });
        if best.as_ref().is_none_or(|(b, ..)| significantly_better(&errors, b)) {
            if let Some((_, before, ..)) = &best {
                trials[*before].chosen = false;
            }
            trials.last_mut().unwrap_or_else(|| unreachable!("pushed above")).chosen = true;
            best = Some((errors, trials.len() - 1, fitted, columns));
        }
    }
    let (_, _, fitted, columns) = best.unwrap_or_else(|| unreachable!("the trial without effects stands"));
    let left_out = effect_columns.into_iter().filter(|c| !columns.contains(c)).collect();
    Ok((fitted, left_out, trials))
}
