//! ISO 9283 figures of a measured campaign: the cycles of poses `P1` .. `P5` (experiments
//! named `iso-P<k>`, or `iso-P<k>-d<h>` for approach direction `h`; `step` the cycle; the tool
//! targets measured at each), each attained pose fitted to the description's tool targets
//! (absolute orientation, [`crate::kinematics::rigid_fit`]), each commanded pose the model's
//! forward kinematics of the cycle's commands, both in the model's robot base frame.
//!
//! Before the figures: an experiment named like an ISO pose that is not one is refused
//! ([`IsoError::NotAPose`]), cycles far from their pose's others are set aside
//! ([`super::outliers`]), and the instrument frame is checked against the description
//! ([`super::frame`]); what is found is said in [`IsoFigures::warnings`].

use super::figures::{
    DirectionalVariation, DistanceFigures, PoseAccuracy, PoseRepeatability, abc, directional_variation,
    distance_figures, pose_accuracy, pose_repeatability,
};
use super::frame::frame_warnings;
use super::outliers::{OutlierCycle, screen_cycles};
use super::predict::CYCLE_ORDER;
use crate::kinematics::{PhiModel, rigid_fit};
use crate::measurement::{Experiment, Measurement, MeasurementSet};
use crate::robot::{Controller, DescriptionIdentity, Placement, RobotDescription, RobotModel, commands_to_internal};
use nalgebra::{Isometry3, Point3};
use std::collections::{BTreeMap, HashMap};

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
    /// An experiment named like an ISO pose (`iso-P` and a digit) whose name does not parse:
    /// its cycles would be left out without a word.
    #[error(
        "experiment `{experiment}`{}: {problem}; an ISO pose is named `iso-P<k>` (k = 1 .. 5) or `iso-P<k>-d<h>` (approach direction h = 1, 2, ...): rename it",
        line.map_or(String::new(), |l| format!(" (line {l})"))
    )]
    NotAPose {
        /// The experiment.
        experiment: String,
        /// The line of its first row, when known.
        line: Option<u64>,
        /// What does not parse.
        problem: String,
    },
    /// An ISO pose's rows marked as an axis experiment: its cycles are free poses, all at one
    /// command.
    #[error(
        "experiment `{experiment}`{}: moved_joint {moved_joint}, but an ISO pose's cycles are free poses at one command (moved_joint 0): set moved_joint to 0 on its rows, or rename the experiment if it is an axis experiment",
        line.map_or(String::new(), |l| format!(" (line {l})"))
    )]
    MovedJoint {
        /// The experiment.
        experiment: String,
        /// The line of its first row, when known.
        line: Option<u64>,
        /// Its `moved_joint`.
        moved_joint: usize,
    },
    /// Two experiments name one pose and approach direction (`iso-P1` and `iso-P1-d1`): their
    /// cycles would count twice.
    #[error(
        "experiments `{first}`{} and `{second}`{} both name pose P{pose}, approach direction {direction} (`iso-P<k>` is `iso-P<k>-d1`): their cycles would count as one pose's twice; delete the repeated rows, or rename one experiment (`iso-P{pose}-d<h>` for another approach direction)",
        first_line.map_or(String::new(), |l| format!(" (line {l})")),
        second_line.map_or(String::new(), |l| format!(" (line {l})"))
    )]
    SamePose {
        /// The experiment seen first.
        first: String,
        /// The line of its first row, when known.
        first_line: Option<u64>,
        /// The other experiment.
        second: String,
        /// The line of its first row, when known.
        second_line: Option<u64>,
        /// Pose `k`.
        pose: usize,
        /// Approach direction `h`.
        direction: usize,
    },
    /// So many cycles of a pose are outliers that the pose, not single cycles, is wrong.
    #[error(
        "experiment `{experiment}`: at least {flagged} of its {cycles} cycles are outliers (each a coordinate beyond the generalized ESD test's fence against the other cycles), more than the test sets aside ({share:.0} % of a pose's cycles, and at most {rounds}): the pose, not single cycles, is wrong; check its rows (commands, coordinates and their units, target ids)",
        share = crate::calibration::procedure::OUTLIER_SHARE_MAX * 100.0,
        rounds = crate::calibration::procedure::OUTLIER_ROUNDS_MAX
    )]
    TooManyOutliers {
        /// The experiment.
        experiment: String,
        /// Cycles beyond the fences.
        flagged: usize,
        /// Its cycles.
        cycles: usize,
    },
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

/// What an experiment's name says.
#[derive(Debug, PartialEq)]
enum Label {
    /// Pose `k`, approach direction `h`.
    Pose(usize, usize),
    /// Not an ISO pose (an approach pose `iso-approach-...`, an axis experiment, ...).
    Other,
    /// Named like an ISO pose (`iso-P` and a digit, in any case) but not one: why.
    Malformed(String),
}

/// The [`Label`] of an experiment named `name`.
fn label(name: &str) -> Label {
    // Bytes, not a `str` slice: a name may have a multi-byte character anywhere.
    let bytes = name.as_bytes();
    let looks_iso = bytes.get(..5).is_some_and(|b| b.eq_ignore_ascii_case(b"iso-p"))
        && bytes.get(5).is_some_and(u8::is_ascii_digit);
    if !looks_iso {
        return Label::Other;
    }
    let Some(rest) = name.strip_prefix("iso-P") else {
        return Label::Malformed("names are case-sensitive".into());
    };
    let (pose, direction) = rest.split_once("-d").unwrap_or((rest, "1"));
    let poses = CYCLE_ORDER.len();
    match (pose.parse::<usize>(), direction.parse::<usize>()) {
        (Err(_), _) => Label::Malformed(format!("`{pose}` is not a pose number")),
        (Ok(k), _) if !(1..=poses).contains(&k) => Label::Malformed(format!(
            "P{k} is not one of the cube's points P1 .. P{poses} (ISO 9283 6.2)"
        )),
        (_, Err(_)) => Label::Malformed(format!("`d{direction}` is not an approach direction")),
        (_, Ok(0)) => Label::Malformed("approach directions count from 1 (`-d1`)".into()),
        (Ok(k), Ok(h)) => Label::Pose(k, h),
    }
}

/// Pose `k` and approach direction `h` of an experiment named `iso-P<k>` or `iso-P<k>-d<h>`.
pub fn pose_label(experiment: &str) -> Option<(usize, usize)> {
    match label(experiment) {
        Label::Pose(k, h) => Some((k, h)),
        _ => None,
    }
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
    /// The cycles the outlier screen flagged ([`super::outliers`]), each with whether the
    /// figures were computed without it; empty when none was.
    #[serde(default)]
    pub outliers: Vec<OutlierCycle>,
    /// What to check before trusting the figures (an outlier cycle, a scale or handedness of
    /// the instrument frame the description contradicts), in words; empty when nothing.
    #[serde(default)]
    pub warnings: Vec<String>,
    /// The robot description the cycles were read with (absent from files of an older
    /// axiscal).
    #[serde(default)]
    pub robot: Option<DescriptionIdentity>,
    /// [`RobotModel::digest`] of the model that commanded the poses: a calibration's (its
    /// `model_digest`) or, before calibration, the nominal model's (absent from files of an
    /// older axiscal).
    #[serde(default)]
    pub model_digest: Option<String>,
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

/// A measured cycle: its commanded and attained tool poses in the base frame, and its targets.
pub(super) struct Cycle {
    pub(super) experiment: String,
    pub(super) direction: usize,
    pub(super) step: usize,
    /// The data file's line of its first row, when known.
    pub(super) line: Option<u64>,
    /// Its commands (file units: deg or mm).
    pub(super) cmd: Vec<f64>,
    pub(super) commanded: Isometry3<f64>,
    pub(super) attained: Isometry3<f64>,
    /// Per measured target: its position on the tool (the description's) and where it was
    /// measured (instrument frame) \[m\].
    pub(super) targets: Vec<(Point3<f64>, Point3<f64>)>,
    /// The RMS residual of the fit of the description's targets to the measured ones \[m\].
    pub(super) tool_fit_rms_m: f64,
}

/// The commanded and attained poses and the targets of one step's rows.
struct Fitted {
    commanded: Isometry3<f64>,
    attained: Isometry3<f64>,
    targets: Vec<(Point3<f64>, Point3<f64>)>,
    tool_fit_rms_m: f64,
}

/// The attained and commanded poses of one step's rows.
fn cycle(
    rows: &[&Measurement],
    targets_m: &[Point3<f64>],
    model: &RobotModel,
    phi: &PhiModel,
    controller: &Controller,
    desc: &RobotDescription,
) -> Result<Fitted, String> {
    let mut targets = Vec::new();
    for r in rows {
        let t = targets_m.get(r.target).ok_or_else(|| {
            format!(
                "target {} is not one of the description's {} tool targets",
                r.target,
                targets_m.len()
            )
        })?;
        targets.push((*t, r.position_m()));
    }
    let (src, dst): (Vec<_>, Vec<_>) = targets.iter().copied().unzip();
    let (world_from_tool, tool_fit_rms_m) = rigid_fit(&src, &dst)
        .ok_or("fewer than three targets measured, or they are in a line: no attained orientation")?;
    let cmd = &rows[0].cmd;
    if rows.iter().any(|r| &r.cmd != cmd) {
        return Err("its rows command different joint values".into());
    }
    let q = model
        .joint_values(controller, &commands_to_internal(desc, cmd))
        .map_err(|e| e.to_string())?;
    let base_from_world = phi.world_from_base.inverse();
    Ok(Fitted {
        commanded: base_from_world * phi.world_from_tool(&q),
        attained: base_from_world * world_from_tool,
        targets,
        tool_fit_rms_m,
    })
}

/// The ISO poses of `set` by label, every experiment named like one checked
/// ([`IsoError::NotAPose`]).
fn iso_experiments<'a>(set: &'a MeasurementSet) -> Result<Vec<(Experiment<'a>, usize, usize)>, IsoError> {
    let mut out: Vec<(Experiment<'a>, usize, usize)> = Vec::new();
    for experiment in set.experiments() {
        match label(experiment.name) {
            Label::Pose(_, _) if experiment.moved_joint != 0 => {
                return Err(IsoError::MovedJoint {
                    experiment: experiment.name.to_string(),
                    line: experiment.lines.map(|(first, _)| first),
                    moved_joint: experiment.moved_joint,
                });
            }
            Label::Pose(k, h) => {
                if let Some((first, ..)) = out.iter().find(|(_, pose, direction)| (*pose, *direction) == (k, h)) {
                    return Err(IsoError::SamePose {
                        first: first.name.to_string(),
                        first_line: first.lines.map(|(line, _)| line),
                        second: experiment.name.to_string(),
                        second_line: experiment.lines.map(|(line, _)| line),
                        pose: k,
                        direction: h,
                    });
                }
                out.push((experiment, k, h));
            }
            Label::Other => {}
            Label::Malformed(problem) => {
                let line = set
                    .rows()
                    .iter()
                    .position(|m| m.experiment == experiment.name)
                    .and_then(|i| set.line_of(i));
                return Err(IsoError::NotAPose {
                    experiment: experiment.name.to_string(),
                    line,
                    problem,
                });
            }
        }
    }
    Ok(out)
}

/// The cycles of every ISO pose of `set`, by pose.
fn cycles(
    set: &MeasurementSet,
    model: &RobotModel,
    desc: &RobotDescription,
) -> Result<BTreeMap<usize, Vec<Cycle>>, IsoError> {
    let experiments = iso_experiments(set)?;
    let targets_m = desc.tool_targets_m();
    if targets_m.len() < 3 && !experiments.is_empty() {
        return Err(IsoError::TooFewToolTargets(targets_m.len()));
    }
    let controller = Controller::from_description(desc);
    let phi = model.phi_model();
    // The line of each (experiment, step)'s first row.
    let mut lines: HashMap<(&str, usize), u64> = HashMap::new();
    for (i, m) in set.rows().iter().enumerate() {
        if let Some(line) = set.line_of(i) {
            lines.entry((m.experiment.as_str(), m.step)).or_insert(line);
        }
    }
    let mut out: BTreeMap<usize, Vec<Cycle>> = BTreeMap::new();
    for (experiment, pose, direction) in experiments {
        super::commands::one_command(&experiment, desc, &lines)?;
        for (step, rows) in experiment.by_step() {
            let fitted =
                cycle(&rows, &targets_m, model, &phi, &controller, desc).map_err(|problem| IsoError::Cycle {
                    experiment: experiment.name.to_string(),
                    step,
                    problem,
                })?;
            out.entry(pose).or_default().push(Cycle {
                experiment: experiment.name.to_string(),
                direction,
                step,
                line: lines.get(&(experiment.name, step)).copied(),
                cmd: rows[0].cmd.clone(),
                commanded: fitted.commanded,
                attained: fitted.attained,
                targets: fitted.targets,
                tool_fit_rms_m: fitted.tool_fit_rms_m,
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

/// How [`evaluate`] treats its data.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EvaluateOptions {
    /// The model was not measured (a nominal one): its base frame is fitted to the data first
    /// ([`IsoFigures::registration_rms_mm`]).
    pub register_base: bool,
    /// Flag the outlier cycles ([`super::outliers`]) but keep them in the figures.
    pub keep_outliers: bool,
    /// Screen the cycles for gross errors ([`super::outliers`]): a measured file's. Simulated
    /// cycles (a scenario's test, the prediction's draws) have none to find, and their
    /// scatter need not be Gaussian (a joint's backlash or settling puts a pose's cycles in
    /// two clusters): screened, a share of them would be refused as a wrong pose.
    pub screen: bool,
    /// Check that no pose's commands are in radians (`super::commands::radian_pose`): a
    /// measured file's (`--skip-unit-check` skips it); simulated cycles are commanded in degrees.
    pub unit_check: bool,
}

/// The ISO 9283 figures of the `iso-P<k>` experiments of `set`, commanded poses from `model`
/// driven as `desc`'s controller drives it: a calibrated robot as it is, a nominal one with
/// `options.register_base`. Outlier cycles are left out unless `options.keep_outliers`.
pub fn evaluate(
    set: &MeasurementSet,
    model: &RobotModel,
    desc: &RobotDescription,
    options: EvaluateOptions,
) -> Result<IsoFigures, IsoError> {
    let mut cycles = cycles(set, model, desc)?;
    if options.unit_check {
        super::commands::radian_pose(&cycles, model, desc, options.register_base)?;
    }
    let outliers = if options.screen {
        screen_cycles(&cycles, options.keep_outliers)?
    } else {
        Vec::new()
    };
    if !options.keep_outliers {
        for c in cycles.values_mut() {
            c.retain(|c| {
                !outliers
                    .iter()
                    .any(|o| o.experiment == c.experiment && o.step == c.step)
            });
        }
    }
    let registration_rms_mm = if options.register_base {
        Some(register(&mut cycles)?)
    } else {
        None
    };
    let mut warnings: Vec<String> = outliers.iter().map(OutlierCycle::describe).collect();
    warnings.extend(frame_warnings(&cycles));
    let poses: Vec<PoseFigures> = cycles
        .iter()
        .filter(|(_, c)| !c.is_empty())
        .map(|(&k, c)| pose_figures(k, c))
        .collect();
    let distance_p2_p4 = distance(&cycles);
    Ok(IsoFigures {
        registration_rms_mm,
        worst_ap_p_mm: poses.iter().map(|p| p.accuracy.ap_p_mm).fold(0.0, f64::max),
        worst_rp_l_mm: poses
            .iter()
            .filter_map(|p| p.repeatability.map(|r| r.rp_l_mm))
            .fold(0.0, f64::max),
        poses,
        distance_p2_p4,
        outliers,
        warnings,
        robot: Some(desc.identity()),
        model_digest: Some(model.digest()),
    })
}

/// Distance accuracy and repeatability between `P2` and `P4`, direction 1, cycle by cycle.
fn distance(cycles: &BTreeMap<usize, Vec<Cycle>>) -> Option<DistanceFigures> {
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
    match (p2.values().next(), p4.values().next()) {
        (Some(a), Some(b)) => distance_figures((&a.commanded, &b.commanded), &pairs),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn iso_names_parse_and_near_misses_say_why() {
        assert_eq!(label("iso-P3"), Label::Pose(3, 1));
        assert_eq!(label("iso-P2-d3"), Label::Pose(2, 3));
        for other in [
            "axis1",
            "tool",
            "iso-approach-P2-d1",
            "iso-position",
            "validation",
            "isö-P1",
            "iso-ö1",
            "iso-",
        ] {
            assert_eq!(label(other), Label::Other, "{other}");
        }
        let why = |name: &str| match label(name) {
            Label::Malformed(w) => w,
            l => panic!("{name}: {l:?}"),
        };
        assert!(why("iso-P2-d0").contains("count from 1"));
        assert!(why("iso-P6").contains("P1 .. P5"));
        assert!(why("ISO-P1").contains("case-sensitive"));
        assert!(why("iso-P2-dx").contains("`dx`"));
        assert!(why("iso-P2x").contains("`2x`"));
    }
}
