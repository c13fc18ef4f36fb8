//! ISO 9283 figures of a measured campaign: the cycles of poses `P1` .. `P5` (experiments
//! named `iso-P<k>`, or `iso-P<k>-d<h>` for approach direction `h`; `step` the cycle; the tool
//! targets measured at each), each attained pose fitted to the description's tool targets
//! (absolute orientation, [`crate::kinematics::rigid_fit`]), each commanded pose the model's
//! forward kinematics of the cycle's commands, both in the model's robot base frame.

use super::figures::{
    DirectionalVariation, DistanceFigures, PoseAccuracy, PoseRepeatability, abc, directional_variation,
    distance_figures, pose_accuracy, pose_repeatability,
};
use crate::kinematics::{PhiModel, rigid_fit};
use crate::measurement::{Measurement, MeasurementSet};
use crate::robot::{Controller, Placement, RobotDescription, RobotModel, commands_to_internal};
use nalgebra::{Isometry3, Point3};
use std::collections::BTreeMap;

/// What stops an evaluation.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum IsoError {
    /// No experiment of the file is an ISO pose.
    #[error(
        "no experiment is named `iso-P<k>` (or `iso-P<k>-d<h>` for approach direction h): no ISO 9283 cycles in the file"
    )]
    NoPoses,
    /// The description has fewer than three tool targets: no attained orientation.
    #[error("the robot description gives {0} tool target(s); an attained pose needs three (`tool.targets_mm`)")]
    TooFewToolTargets(usize),
    /// The poses are too few or in a line to register a base frame to.
    #[error("the commanded positions are fewer than three or in a line: no base frame can be registered to them")]
    Registration,
    /// A cycle's pose could not be fitted.
    #[error("experiment `{experiment}`, cycle (step) {step}: {problem}")]
    Cycle {
        /// The experiment.
        experiment: String,
        /// The step.
        step: usize,
        /// What is wrong.
        problem: String,
    },
}

/// Pose `k` and approach direction `h` of an experiment named `iso-P<k>` or `iso-P<k>-d<h>`.
pub fn pose_label(experiment: &str) -> Option<(usize, usize)> {
    let rest = experiment.strip_prefix("iso-P")?;
    let (pose, direction) = match rest.split_once("-d") {
        Some((p, d)) => (p.parse().ok()?, d.parse().ok()?),
        None => (rest.parse().ok()?, 1),
    };
    (pose >= 1 && direction >= 1).then_some((pose, direction))
}

/// One ISO pose's figures.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct PoseFigures {
    /// `k` of `P<k>`.
    pub pose: usize,
    /// Cycles measured (all directions).
    pub cycles: usize,
    /// The commanded tool pose in the base frame (`rpy_deg` = `a, b, c`).
    pub commanded: Placement,
    /// Pose accuracy (the cycles of the first approach direction measured).
    pub accuracy: PoseAccuracy,
    /// Pose repeatability (the same cycles); absent with one cycle.
    pub repeatability: Option<PoseRepeatability>,
    /// Multi-directional variation; absent with one direction.
    pub directional: Option<DirectionalVariation>,
}

/// The figures of a campaign.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct IsoFigures {
    /// Per pose, `P1` first.
    pub poses: Vec<PoseFigures>,
    /// Distance accuracy and repeatability between `P2` and `P4` (direction 1, cycle by
    /// cycle), when both are measured in two or more cycles.
    pub distance_p2_p4: Option<DistanceFigures>,
    /// With a registered base frame: the RMS distance of the registered commanded positions
    /// from the attained ones over all cycles \[mm\].
    pub registration_rms_mm: Option<f64>,
    /// Largest `AP_P` over the poses \[mm\].
    pub worst_ap_p_mm: f64,
    /// Largest `RP_l` over the poses \[mm\].
    pub worst_rp_l_mm: f64,
}

impl IsoFigures {
    /// The mean of `AP_P` over the poses \[mm\].
    pub fn mean_ap_p_mm(&self) -> f64 {
        self.poses.iter().map(|p| p.accuracy.ap_p_mm).sum::<f64>() / self.poses.len() as f64
    }

    /// The mean of `RP_l` over the poses \[mm\]; `None` when a pose has a single cycle.
    pub fn mean_rp_l_mm(&self) -> Option<f64> {
        let r: Option<Vec<f64>> = self.poses.iter().map(|p| p.repeatability.map(|r| r.rp_l_mm)).collect();
        r.map(|r| r.iter().sum::<f64>() / r.len() as f64)
    }
}

/// A measured cycle: its commanded and attained tool poses in the base frame.
struct Cycle {
    direction: usize,
    step: usize,
    commanded: Isometry3<f64>,
    attained: Isometry3<f64>,
}

/// The attained and commanded poses of one step's rows.
fn cycle(
    rows: &[&Measurement],
    targets_m: &[Point3<f64>],
    model: &RobotModel,
    phi: &PhiModel,
    controller: &Controller,
    desc: &RobotDescription,
) -> Result<(Isometry3<f64>, Isometry3<f64>), String> {
    let (mut src, mut dst) = (Vec::new(), Vec::new());
    for r in rows {
        let t = targets_m.get(r.target).ok_or_else(|| {
            format!(
                "target {} is not one of the description's {} tool targets",
                r.target,
                targets_m.len()
            )
        })?;
        src.push(*t);
        dst.push(r.position_m());
    }
    let (world_from_tool, _) = rigid_fit(&src, &dst)
        .ok_or("fewer than three targets measured, or they are in a line: no attained orientation")?;
    let cmd = &rows[0].cmd;
    if rows.iter().any(|r| &r.cmd != cmd) {
        return Err("its rows command different joint values".into());
    }
    let q = model
        .joint_values(controller, &commands_to_internal(desc, cmd))
        .map_err(|e| e.to_string())?;
    let base_from_world = phi.world_from_base.inverse();
    Ok((
        base_from_world * phi.world_from_tool(&q),
        base_from_world * world_from_tool,
    ))
}

/// The cycles of every ISO pose of `set`, by pose.
fn cycles(
    set: &MeasurementSet,
    model: &RobotModel,
    desc: &RobotDescription,
) -> Result<BTreeMap<usize, Vec<Cycle>>, IsoError> {
    let targets_m = desc.tool_targets_m();
    if targets_m.len() < 3 {
        return Err(IsoError::TooFewToolTargets(targets_m.len()));
    }
    let controller = Controller::from_description(desc);
    let phi = model.phi_model();
    let mut out: BTreeMap<usize, Vec<Cycle>> = BTreeMap::new();
    for experiment in set.experiments() {
        let Some((pose, direction)) = pose_label(experiment.name) else {
            continue;
        };
        for (step, rows) in experiment.by_step() {
            let (commanded, attained) =
                cycle(&rows, &targets_m, model, &phi, &controller, desc).map_err(|problem| IsoError::Cycle {
                    experiment: experiment.name.to_string(),
                    step,
                    problem,
                })?;
            out.entry(pose).or_default().push(Cycle {
                direction,
                step,
                commanded,
                attained,
            });
        }
    }
    if out.is_empty() {
        Err(IsoError::NoPoses)
    } else {
        Ok(out)
    }
}

/// The figures of one pose's cycles (at least one): accuracy and repeatability over the
/// first approach direction measured, the variation over all.
fn pose_figures(pose: usize, cycles: &[Cycle]) -> PoseFigures {
    let mut by_direction: BTreeMap<usize, Vec<Isometry3<f64>>> = BTreeMap::new();
    for c in cycles {
        by_direction.entry(c.direction).or_default().push(c.attained);
    }
    let first = by_direction.values().next().cloned().unwrap_or_default();
    let commanded = cycles[0].commanded;
    let v = commanded.translation.vector * 1e3;
    PoseFigures {
        pose,
        cycles: cycles.len(),
        commanded: Placement {
            translation_mm: [v.x, v.y, v.z],
            rpy_deg: abc(&commanded).map(f64::to_degrees),
        },
        accuracy: pose_accuracy(&commanded, &first).expect("a pose has a cycle"),
        repeatability: pose_repeatability(&first),
        directional: directional_variation(&by_direction.into_values().collect::<Vec<_>>()),
    }
}

/// The rigid transform that best maps the commanded positions onto the attained ones (every
/// cycle a pair), applied to every commanded pose: the base frame of a model that was not
/// measured (a nominal one) registered to the data. Returns the RMS residual \[mm\].
fn register(cycles: &mut BTreeMap<usize, Vec<Cycle>>) -> Result<f64, IsoError> {
    let pairs: Vec<(Point3<f64>, Point3<f64>)> = cycles
        .values()
        .flatten()
        .map(|c| {
            (
                Point3::from(c.commanded.translation.vector),
                Point3::from(c.attained.translation.vector),
            )
        })
        .collect();
    let (src, dst): (Vec<_>, Vec<_>) = pairs.into_iter().unzip();
    let (t, rms_m) = rigid_fit(&src, &dst).ok_or(IsoError::Registration)?;
    for c in cycles.values_mut().flatten() {
        c.commanded = t * c.commanded;
    }
    Ok(rms_m * 1e3)
}

/// The ISO 9283 figures of the `iso-P<k>` experiments of `set`, commanded poses from `model`
/// driven as `desc`'s controller drives it: a calibrated robot as it is, a nominal one with
/// `register_base` (its base frame fitted to the data first, [`IsoFigures::registration_rms_mm`]).
pub fn evaluate(
    set: &MeasurementSet,
    model: &RobotModel,
    desc: &RobotDescription,
    register_base: bool,
) -> Result<IsoFigures, IsoError> {
    let mut cycles = cycles(set, model, desc)?;
    let registration_rms_mm = if register_base {
        Some(register(&mut cycles)?)
    } else {
        None
    };
    let poses: Vec<PoseFigures> = cycles.iter().map(|(&k, c)| pose_figures(k, c)).collect();
    let steps = |k: usize| -> BTreeMap<usize, &Cycle> {
        cycles
            .get(&k)
            .map(|c| c.iter().filter(|c| c.direction == 1).map(|c| (c.step, c)).collect())
            .unwrap_or_default()
    };
    let (p2, p4) = (steps(2), steps(4));
    let pairs: Vec<(Isometry3<f64>, Isometry3<f64>)> = p2
        .iter()
        .filter_map(|(s, a)| p4.get(s).map(|b| (a.attained, b.attained)))
        .collect();
    let distance_p2_p4 = match (p2.values().next(), p4.values().next()) {
        (Some(a), Some(b)) => distance_figures((&a.commanded, &b.commanded), &pairs),
        _ => None,
    };
    Ok(IsoFigures {
        registration_rms_mm,
        worst_ap_p_mm: poses.iter().map(|p| p.accuracy.ap_p_mm).fold(0.0, f64::max),
        worst_rp_l_mm: poses
            .iter()
            .filter_map(|p| p.repeatability.map(|r| r.rp_l_mm))
            .fold(0.0, f64::max),
        poses,
        distance_p2_p4,
    })
}
