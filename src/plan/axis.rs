//! The calibration plan: which joint is swept, over what span, in what order (paper Table 1),
//! the commands each step sends (`docs/formats.md#controller-semantics`), and the validation poses.

use crate::robot::RobotDescription;
use serde::{Deserialize, Serialize};

/// One axis experiment: joint `joint` swept from `start_deg` (relative to the reference pose)
/// over `span_deg` in `intervals` equal steps (`intervals + 1` poses), Table 1.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AxisSweep {
    /// The swept joint (1-based).
    pub joint: usize,
    /// Total displacement \[deg\] (revolute) or \[mm\] (prismatic).
    pub span: f64,
    /// Number of intervals; the experiment observes `intervals + 1` poses.
    pub intervals: usize,
    /// Observe the second target (passive coupling into `joint + 1`, eq. 14); the commands then
    /// hold actuator `joint + 1` still.
    #[serde(default)]
    pub second_target: bool,
    /// Where the sweep starts, relative to the reference pose \[deg or mm\]; default `-span/2`
    /// (a sweep centred on the reference pose).
    #[serde(default)]
    pub start: Option<f64>,
    /// The other joints' offsets from the reference pose during this sweep (file units, one
    /// per joint; the swept joint's entry is ignored): a sweep at another pose, e.g. a joint
    /// swept again at another position of the joint below. Default: at the reference.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub held_at: Option<Vec<f64>>,
}

impl AxisSweep {
    /// The command of the swept joint at `step`, relative to the reference \[deg or mm\].
    pub fn offset_at(&self, step: usize) -> f64 {
        self.start.unwrap_or(-self.span / 2.0) + self.span * step as f64 / self.intervals as f64
    }

    /// Number of poses, `intervals + 1`.
    pub fn poses(&self) -> usize {
        self.intervals + 1
    }
}

/// Most intervals a sweep may have (`plan --intervals`, a plan file's `intervals`): 100,001
/// poses of one joint, far beyond any campaign; a larger count is a slip that would only stall
/// the plan.
pub const MAX_INTERVALS: usize = 100_000;

/// A problem with a plan.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PlanError {
    /// A sweep names a joint the robot does not have.
    #[error("sweep {index}: joint {joint} is not in 1..={dof}")]
    NoSuchJoint {
        /// Index of the sweep in the plan.
        index: usize,
        /// The joint named.
        joint: usize,
        /// Number of joints.
        dof: usize,
    },
    /// A sweep has a zero, negative or infinite span, or too few or too many intervals.
    #[error(
        "sweep {index} (joint {joint}): span must be finite and > 0 and intervals in 2..={MAX_INTERVALS} (got span {span}, intervals {intervals})"
    )]
    Degenerate {
        /// Index of the sweep.
        index: usize,
        /// The joint.
        joint: usize,
        /// Its span.
        span: f64,
        /// Its intervals.
        intervals: usize,
    },
    /// A second target is asked for where there is no coupling or no target.
    #[error("sweep {index} (joint {joint}): {reason}")]
    SecondTarget {
        /// Index of the sweep.
        index: usize,
        /// The joint.
        joint: usize,
        /// What is missing.
        reason: String,
    },
    /// The robot description gives no targets for a swept joint.
    #[error(
        "sweep {index} moves joint {joint}, but the robot description has no `axis_targets` entry for joint {joint}: \
         add one (docs/formats.md#robot-description), or leave the joint out of the plan"
    )]
    NoTargets {
        /// Index of the sweep.
        index: usize,
        /// The joint.
        joint: usize,
    },
    /// The sweep leaves the joint limits.
    #[error(
        "sweep {index} (joint {joint}): commands {}..{} leave the joint limits {limit_low:.3}..{limit_high:.3}",
        crate::measurement::format_f64(*low),
        crate::measurement::format_f64(*high)
    )]
    OutOfLimits {
        /// Index of the sweep.
        index: usize,
        /// The joint.
        joint: usize,
        /// Lowest command.
        low: f64,
        /// Highest command.
        high: f64,
        /// Lower limit.
        limit_low: f64,
        /// Upper limit.
        limit_high: f64,
    },
    /// A planned pose the nominal robot cannot take (e.g. a target on no link).
    #[error("{message}")]
    Invalid {
        /// What is wrong.
        message: String,
    },
    /// A joint's value of the reference pose is outside its limits.
    #[error(
        "key `reference`: joint {joint}'s command {} leaves its limits {limit_low:.3}..{limit_high:.3} (the reference \
         pose is measured as the tool observation and every sweep starts from it): give a `reference` within the limits",
        crate::measurement::format_f64(*value)
    )]
    ReferenceOutOfLimits {
        /// The joint (1-based).
        joint: usize,
        /// Its reference command.
        value: f64,
        /// Lower limit.
        limit_low: f64,
        /// Upper limit.
        limit_high: f64,
    },
    /// The reference pose has the wrong length.
    #[error("reference pose has {found} values, the robot has {dof} joints")]
    ReferenceLength {
        /// Values found.
        found: usize,
        /// Joints.
        dof: usize,
    },
    /// A sweep's `held_at` has another length than the robot's joint count.
    #[error(
        "`sweeps[{index}].held_at`: {found} values, the robot has {dof} joints: one offset per joint (deg or mm; \
         the swept joint's is ignored)"
    )]
    HeldAtLength {
        /// Index of the sweep.
        index: usize,
        /// Values found.
        found: usize,
        /// Joints.
        dof: usize,
    },
    /// `held_jitter` is not a range `[min, max]` of plausible wander.
    #[error(
        "`held_jitter`: [{min}, {max}]: the range [min, max] of a held joint's wander (deg or mm) needs 0 <= min <= \
         max <= {MAX_HELD_JITTER}"
    )]
    HeldJitter {
        /// The lower end.
        min: f64,
        /// The upper end.
        max: f64,
    },
}

/// The largest wander `held_jitter` may give a held joint's recorded value (deg or mm): far
/// beyond an encoder's, and beyond it the joint is no longer held
/// ([`crate::calibration::procedure::DEFAULT_HELD_TOLERANCE`] is 0.5).
pub const MAX_HELD_JITTER: f64 = 10.0;

/// The axis experiments in the order they are run, around a common reference pose.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CalibrationPlan {
    /// Commands of the common reference pose, in file units (deg or mm), one per joint.
    pub reference: Vec<f64>,
    /// The sweeps, in the order they are run.
    pub sweeps: Vec<AxisSweep>,
    /// Simulation only: the held joints' recorded values wander, each step and joint by a
    /// uniform `|x|` in `[min, max]` with a random sign (file units), as encoder readings of a
    /// real controller do (`docs/formats.md#held-joints`); the robot stands at the recorded
    /// value. Default: none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub held_jitter: Option<[f64; 2]>,
}

impl CalibrationPlan {
    /// Paper Table 1, descending order 6..1: spans 50, 60, 90, 45, 45, 48 deg; intervals 16,
    /// 15, 15, 15, 15, 15; a second target for joints 4 and 2. Reference pose: all zero.
    pub fn table1(dof: usize) -> Self {
        let rows = [
            (6, 50.0, 16, false),
            (5, 60.0, 15, false),
            (4, 90.0, 15, true),
            (3, 45.0, 15, false),
            (2, 45.0, 15, true),
            (1, 48.0, 15, false),
        ];
        CalibrationPlan {
            reference: vec![0.0; dof],
            sweeps: rows
                .iter()
                .map(|&(joint, span, intervals, second_target)| AxisSweep {
                    joint,
                    span,
                    intervals,
                    second_target,
                    start: None,
                    held_at: None,
                })
                .collect(),
            held_jitter: None,
        }
    }

    /// The plan used where none is given: paper Table 1 for a six-joint revolute arm whose
    /// description measures the couplings Table 1 measures (a fitted coupling and a second
    /// target for each of its two-target sweeps), [`CalibrationPlan::for_robot`] for any other
    /// robot (a six-axis arm without couplings, say).
    pub fn default_for(desc: &RobotDescription) -> Self {
        let six_revolute = desc.dof() == 6
            && desc
                .joints
                .iter()
                .all(|j| j.kind == crate::kinematics::JointKind::Revolute);
        let table1 = Self::table1(6);
        let measures_its_couplings = table1.sweeps.iter().filter(|s| s.second_target).all(|s| {
            desc.couplings.iter().any(|c| c.from == s.joint && c.fit.is_some())
                && desc.axis_targets_of(s.joint).is_some_and(|t| t.target1.is_some())
        });
        if six_revolute && measures_its_couplings {
            table1
        } else {
            Self::for_robot(desc)
        }
    }

    /// Table 1 generalised to any joint mix: every joint swept once, last joint first, 15
    /// intervals, around a reference at 0 (or the middle of the limits when 0 is outside):
    /// a revolute joint over 90 deg, a prismatic one over half its range (each within its
    /// limits); the second target
    /// wherever the description fits a coupling (`couplings[].fit`) and gives a `target1`.
    pub fn for_robot(desc: &RobotDescription) -> Self {
        let reference: Vec<f64> = desc
            .joints
            .iter()
            .map(|j| {
                if j.limits[0] < 0.0 && j.limits[1] > 0.0 {
                    0.0
                } else {
                    0.5 * (j.limits[0] + j.limits[1])
                }
            })
            .collect();
        let sweeps = (1..=desc.dof())
            .rev()
            .map(|joint| {
                let j = &desc.joints[joint - 1];
                let room = 2.0 * (reference[joint - 1] - j.limits[0]).min(j.limits[1] - reference[joint - 1]);
                let span = match j.kind {
                    crate::kinematics::JointKind::Revolute => 90f64.min(0.9 * room),
                    crate::kinematics::JointKind::Prismatic => 0.5 * (j.limits[1] - j.limits[0]).min(room),
                };
                let fitted = desc.couplings.iter().any(|c| c.from == joint && c.fit.is_some());
                let second_target = fitted && desc.axis_targets_of(joint).is_some_and(|t| t.target1.is_some());
                AxisSweep {
                    joint,
                    span,
                    intervals: 15,
                    second_target,
                    start: None,
                    held_at: None,
                }
            })
            .collect();
        CalibrationPlan {
            reference,
            sweeps,
            held_jitter: None,
        }
    }

    /// The first sweep (its index and joint) of a joint whose coupling into the next joint the
    /// description fits (`couplings[].fit`) when no sweep of that joint has `second_target`:
    /// `calibrate` fits the coupling from target 1 of such a sweep (eq. 14) and refuses data
    /// without one.
    pub fn unmeasured_coupling(&self, desc: &RobotDescription) -> Option<(usize, usize)> {
        self.sweeps
            .iter()
            .enumerate()
            .find(|(_, s)| {
                desc.couplings.iter().any(|c| c.from == s.joint && c.fit.is_some())
                    && !self.sweeps.iter().any(|t| t.joint == s.joint && t.second_target)
            })
            .map(|(i, s)| (i, s.joint))
    }

    /// The experiment id of each sweep: `axis<k>`, and `axis<k>-2`, `axis<k>-3`, .. for a
    /// joint swept again.
    pub fn experiment_names(&self) -> Vec<String> {
        let mut seen = std::collections::HashMap::new();
        self.sweeps
            .iter()
            .map(|s| {
                let n = seen.entry(s.joint).or_insert(0usize);
                *n += 1;
                if *n == 1 {
                    format!("axis{}", s.joint)
                } else {
                    format!("axis{}-{}", s.joint, n)
                }
            })
            .collect()
    }

    /// Checks the plan against a robot: joints exist, spans are real, `held_at` has one value
    /// per joint, `held_jitter` is a plausible range, targets are given, second targets only
    /// where a nominal coupling leaves the swept joint, limits respected.
    pub fn validate(&self, desc: &RobotDescription) -> Result<(), PlanError> {
        let dof = desc.dof();
        if self.reference.len() != dof {
            return Err(PlanError::ReferenceLength {
                found: self.reference.len(),
                dof,
            });
        }
        for (j, (&value, joint)) in self.reference.iter().zip(&desc.joints).enumerate() {
            let [limit_low, limit_high] = joint.limits;
            if !(limit_low..=limit_high).contains(&value) {
                return Err(PlanError::ReferenceOutOfLimits {
                    joint: j + 1,
                    value,
                    limit_low,
                    limit_high,
                });
            }
        }
        if let Some([min, max]) = self.held_jitter
            && !(0.0 <= min && min <= max && max <= MAX_HELD_JITTER)
        {
            return Err(PlanError::HeldJitter { min, max });
        }
        for (index, s) in self.sweeps.iter().enumerate() {
            let joint = s.joint;
            if joint == 0 || joint > dof {
                return Err(PlanError::NoSuchJoint { index, joint, dof });
            }
            if let Some(at) = &s.held_at
                && at.len() != dof
            {
                return Err(PlanError::HeldAtLength {
                    index,
                    found: at.len(),
                    dof,
                });
            }
            if !(s.span.is_finite() && s.span > 0.0 && (2..=MAX_INTERVALS).contains(&s.intervals)) {
                return Err(PlanError::Degenerate {
                    index,
                    joint,
                    span: s.span,
                    intervals: s.intervals,
                });
            }
            let targets = desc
                .axis_targets_of(joint)
                .ok_or(PlanError::NoTargets { index, joint })?;
            if s.second_target {
                if desc.nominal_coupling_from(joint).is_none() {
                    return Err(PlanError::SecondTarget {
                        index,
                        joint,
                        reason: format!("no nominal coupling {joint}->{} to measure", joint + 1),
                    });
                }
                if targets.target1.is_none() {
                    return Err(PlanError::SecondTarget {
                        index,
                        joint,
                        reason: "the robot description gives no target1 for this joint".into(),
                    });
                }
            }
            let (first, last) = (self.commands(desc, s, 0), self.commands(desc, s, s.intervals));
            for (j, (a, b)) in first.iter().zip(&last).enumerate() {
                let [limit_low, limit_high] = desc.joints[j].limits;
                let (low, high) = (a.min(*b), a.max(*b));
                if low < limit_low || high > limit_high {
                    return Err(PlanError::OutOfLimits {
                        index,
                        joint: j + 1,
                        low,
                        high,
                        limit_low,
                        limit_high,
                    });
                }
            }
        }
        Ok(())
    }

    /// The commands (file units, one per joint) of `sweep` at `step`.
    ///
    /// The swept joint moves; with `second_target`, joint `k+1` is commanded with the
    /// nominal passive displacement so that its actuator holds still (`docs/formats.md#controller-semantics`:
    /// `cmd_{k+1}(s) = cmd_{k+1}(0) + slope (cmd_k(s) - cmd_k(0))`); every other command stays
    /// at the reference, so the controller's nominal decoupling keeps those joints' values.
    pub fn commands(&self, desc: &RobotDescription, sweep: &AxisSweep, step: usize) -> Vec<f64> {
        let k = sweep.joint - 1;
        let mut cmd = self.reference.clone();
        if let Some(at) = &sweep.held_at {
            for (c, a) in cmd.iter_mut().zip(at) {
                *c += a;
            }
        }
        cmd[k] = self.reference[k] + sweep.offset_at(step);
        if sweep.second_target
            && let Some(slope) = desc.nominal_coupling_from(sweep.joint)
        {
            cmd[k + 1] += slope * (sweep.offset_at(step) - sweep.offset_at(0));
        }
        cmd
    }
}
