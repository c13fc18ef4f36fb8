//! Backlash: a direction-dependent dead band of a joint.

use serde::{Deserialize, Serialize};

/// Whose motion decides the side of the dead band a joint sits on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ApproachSource {
    /// The sign of the change of the joint's command `cmd_k` into the pose
    /// (`docs/formats.md#measurement-csv`).
    #[default]
    Command,
    /// The sign of the change of the joint's actuator command `u_k` (after the fig. 3
    /// decoupling, `u_{k+1} = cmd_{k+1} - nominal_passive(u_k)`): where the gear's teeth are.
    /// It differs from the command's on a joint driven passively by the one below when both
    /// move.
    Actuator,
}

/// Backlash: a direction-dependent dead band per joint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BacklashEffect {
    /// Width of the dead band of each joint \[rad\] (>= 0).
    pub band_rad: Vec<f64>,
    /// Whose direction of motion decides the side of the band; default the command's.
    #[serde(default, skip_serializing_if = "is_command")]
    pub direction: ApproachSource,
}

fn is_command(s: &ApproachSource) -> bool {
    *s == ApproachSource::Command
}

impl BacklashEffect {
    /// The active displacement `active` of a joint whose dead band is `band_rad`, approached
    /// in direction `approach` (+1, -1, or 0 before any motion: the middle of the band): it
    /// lags half the band behind the approach.
    pub fn lagged(active: f64, approach: f64, band_rad: f64) -> f64 {
        active - approach * band_rad / 2.0
    }
}

/// An actuator command that changed by no more than this \[rad or m\] has not moved: the
/// hold-still commands of a coupled joint reproduce its actuator command only to rounding (a
/// few 1e-16 rad through the fig. 3 decoupling), and no encoder resolves 1e-12.
pub const UNMOVED_ACTUATOR_RAD: f64 = 1e-12;

/// Approach directions of every joint, updated pose by pose: `sign(x_k(s) - x_k(s-1))` of a
/// sequence of joint quantities `x` (commands or actuator commands), the previous direction
/// when `x_k` moved by no more than `unmoved`, 0 before any motion.
#[derive(Clone, Debug, PartialEq)]
pub struct ApproachTracker {
    unmoved: f64,
    last: Option<Vec<f64>>,
    approach: Vec<f64>,
}

impl ApproachTracker {
    /// A tracker of `n` joints before any motion; a change of at most `unmoved` is no motion
    /// (0 for commands, which a file repeats exactly; [`UNMOVED_ACTUATOR_RAD`] for actuator
    /// commands).
    pub fn new(n: usize, unmoved: f64) -> Self {
        ApproachTracker {
            unmoved,
            last: None,
            approach: vec![0.0; n],
        }
    }

    /// Moves to `x` and returns the approach direction of every joint into it.
    pub fn step(&mut self, x: &[f64]) -> &[f64] {
        if let Some(last) = &self.last {
            for ((dir, c), l) in self.approach.iter_mut().zip(x).zip(last) {
                if (c - l).abs() > self.unmoved {
                    *dir = (c - l).signum();
                }
            }
        }
        match &mut self.last {
            Some(last) if last.len() == x.len() => last.copy_from_slice(x),
            last => *last = Some(x.to_vec()),
        }
        &self.approach
    }
}

/// The approach directions of one pose of a measurement file.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseApproach {
    /// Its experiment.
    pub experiment: String,
    /// Its step.
    pub step: usize,
    /// Each joint's command's ([`ApproachSource::Command`]).
    pub command: Vec<f64>,
    /// Each joint's actuator command's ([`ApproachSource::Actuator`]; the fig. 3 decoupling
    /// with the description's nominal couplings, a change of at most
    /// [`UNMOVED_ACTUATOR_RAD`] no motion).
    pub actuator: Vec<f64>,
}

/// The approach directions of every pose of `rows` (`docs/formats.md#row-order-and-approach-direction`):
/// a pose is a distinct `(experiment, step)`, in the order of its first row, across
/// experiments; one item per pose, in that order, computed as the poses are taken.
pub fn pose_approaches<'a>(
    rows: &'a [crate::measurement::Measurement],
    desc: &'a crate::robot::RobotDescription,
) -> impl Iterator<Item = PoseApproach> + 'a {
    let n = desc.dof();
    let controller = crate::robot::Controller::from_description(desc);
    let mut seen: std::collections::HashSet<(&str, usize)> = std::collections::HashSet::new();
    let mut by_command = ApproachTracker::new(n, 0.0);
    let mut by_actuator = ApproachTracker::new(n, UNMOVED_ACTUATOR_RAD);
    rows.iter().filter_map(move |m| {
        if !seen.insert((m.experiment.as_str(), m.step)) {
            return None;
        }
        let cmd = crate::robot::commands_to_internal(desc, &m.cmd);
        let command = by_command.step(&cmd).to_vec();
        // The file's command count was checked against the description on reading.
        let u = controller.decouple(&cmd).unwrap_or_else(|_| cmd.clone());
        let actuator = by_actuator.step(&u).to_vec();
        Some(PoseApproach {
            experiment: m.experiment.clone(),
            step: m.step,
            command,
            actuator,
        })
    })
}

/// [`pose_approaches`] by `(experiment, step)`: each pose's actuator approach directions, what
/// a model's backlash (`crate::robot::ModelEffects`) is signed by.
pub fn actuator_approach_by_pose(
    rows: &[crate::measurement::Measurement],
    desc: &crate::robot::RobotDescription,
) -> std::collections::HashMap<(String, usize), Vec<f64>> {
    pose_approaches(rows, desc)
        .map(|a| ((a.experiment, a.step), a.actuator))
        .collect()
}
