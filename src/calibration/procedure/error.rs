//! Why a campaign could not be calibrated ([`ProcedureError`]), each cause in the words a
//! metrology engineer checks the data with: the experiment, its lines, what to check.

use super::frames::FramesError;
use super::misfit::SweepMisfit;
use super::options::InvalidOption;
use super::second_targets::SecondTargetData;
use crate::calibration::CalibrationError;
use crate::kinematics::JointKind;
use crate::measurement::MeasurementSet;

/// Why a campaign could not be calibrated.
#[derive(Debug, thiserror::Error)]
pub enum ProcedureError {
    /// Too many of one sweep's points fail the outlier test ([`screen_sweeps`](super::screen_sweeps)).
    #[error(
        "experiment {experiment}: {flagged} of its {points} points lie beyond the outlier fence ({fence:.2} times the sweep's noise){which}"
    )]
    TooManyOutliers {
        /// The experiment.
        experiment: String,
        /// Points beyond the fence.
        flagged: usize,
        /// Its points.
        points: usize,
        /// The fence (normalised residual).
        fence: f64,
        /// Which points, and what that says (single rows named by line, or a run of the sweep).
        which: String,
    },
    /// The set has no axis experiment at all.
    #[error("no axis experiment (no row with moved_joint > 0): nothing to calibrate")]
    NoAxisExperiment,
    /// Two experiments hold the same measured points: one is a copy of the other.
    #[error(
        "experiments {first} ({first_lines}) and {second} ({second_lines}) both sweep joint {joint} with the same {points} measured points, to the last digit: one is a copy of the other (fitted twice, its points would count double and every sigma shrink by 1.4); delete one"
    )]
    DuplicateExperiment {
        /// The first experiment.
        first: String,
        /// Its file lines, as `lines A-B` (or `no file lines`).
        first_lines: String,
        /// The copy.
        second: String,
        /// Its file lines.
        second_lines: String,
        /// The joint both sweep.
        joint: usize,
        /// Their target-0 points.
        points: usize,
    },
    /// The fit-and-correct passes for the held joints' recorded values did not settle.
    #[error(
        "the correction for the held joints' recorded values did not converge in {passes} passes (last change {change_mm:.3e} mm)"
    )]
    HeldNotConverged {
        /// Passes made.
        passes: usize,
        /// Largest change of a corrected point in the last pass \[mm\].
        change_mm: f64,
    },
    /// An axis fit misses its points by a good part of their own spread: no calibration.
    #[error(
        "experiment {experiment} (joint {joint}): the fitted axis misses its points by {rms_mm:.3} mm RMS, {share:.1} % of their spread about their centroid ({spread_mm:.1} mm): the points are not on one arc or line of this joint (check the joint order and kinds of the robot file, the target ids, the units, and whether the noise is far above the instrument's: {rms_mm:.3} mm)"
    )]
    Absurd {
        /// The experiments of the joint.
        experiment: String,
        /// The joint.
        joint: usize,
        /// The fit's RMS \[mm\].
        rms_mm: f64,
        /// The points' RMS spread \[mm\].
        spread_mm: f64,
        /// `100 rms / spread`.
        share: f64,
    },
    /// A joint's sweeps move their target less than the noise: no axis can be fitted.
    #[error(
        "experiment {experiment} (joint {joint}): its points spread {spread_mm:.4} mm RMS about their centroid, within {factor} times the noise of a point ({noise_mm:.3} mm): the sweep ({} as written) is too short for the instrument to locate the axis; widen its span{} (or check that the joint moved and the commands' units)",
        span.written(),
        span.needed()
    )]
    Unresolved {
        /// The experiments of the joint.
        experiment: String,
        /// The joint.
        joint: usize,
        /// The points' RMS spread \[mm\].
        spread_mm: f64,
        /// The noise of a point, 3-D RMS \[mm\].
        noise_mm: f64,
        /// [`crate::numerics::stats::UNRESOLVED_SPREAD_OVER_NOISE`].
        factor: f64,
        /// Its span as written and the least the fit needs.
        span: ShortSpan,
    },
    /// A turning joint's sweep moves its target less than the noise because the description
    /// places that target on (or next to) the joint's own axis.
    #[error(
        "experiment {experiment} (joint {joint}): its points spread {spread_mm:.4} mm RMS about their centroid, within {factor} times the noise of a point ({noise_mm:.3} mm): the description places the sweep's target 0 (`axis_targets` of joint {joint}: link {link}, position_mm = [{}, {}, {}]) {off_axis_mm:.3} mm from joint {joint}'s own axis, where turning the joint barely moves it; put the target at least {needed_mm:.1} mm off the axis (tens of mm locate the axis well), measure it there and give its place in `axis_targets`",
        position_mm[0],
        position_mm[1],
        position_mm[2]
    )]
    TargetOnAxis {
        /// The experiments of the joint.
        experiment: String,
        /// The joint.
        joint: usize,
        /// The points' RMS spread \[mm\].
        spread_mm: f64,
        /// The noise of a point, 3-D RMS \[mm\].
        noise_mm: f64,
        /// [`crate::numerics::stats::UNRESOLVED_SPREAD_OVER_NOISE`].
        factor: f64,
        /// The link the description puts the target on.
        link: usize,
        /// Its position in that link's frame \[mm\].
        position_mm: [f64; 3],
        /// Its distance from the joint's axis on the nominal robot at the sweep's first
        /// commands \[mm\].
        off_axis_mm: f64,
        /// The least distance off the axis to put it at \[mm\]: where the sweep's span would
        /// move it `factor` times the noise, and no less than the margin the check holds it to.
        needed_mm: f64,
    },
    /// A rotary joint's points lie on a straight line: no arc to fit.
    #[error(
        "experiment {experiment} (joint {joint}): its points are collinear: they lie on a straight line ({off_line_mm:.4} mm RMS from it, within {} times the noise of a point, {noise_mm:.3} mm) though the joint turns {} as written: a turning joint moves its target on an arc; check that the sweep's target 0 sits on the swept link, that the coordinates are the target's, and the joint's kind in the description",
        crate::numerics::stats::UNRESOLVED_SPREAD_OVER_NOISE,
        span.written()
    )]
    Straight {
        /// The experiments of the joint.
        experiment: String,
        /// The joint.
        joint: usize,
        /// The points' RMS distance from their line \[mm\].
        off_line_mm: f64,
        /// The noise of a point, 3-D RMS \[mm\].
        noise_mm: f64,
        /// Its span as written.
        span: ShortSpan,
    },
    /// A rotary joint's arc bows from its chord by too little for its fit: the sweep is short.
    #[error(
        "experiment {experiment} (joint {joint}): the sweep spans {} as written, too short to locate the axis: its arc bows {sagitta_mm:.4} mm from its chord (radius {radius_mm:.1} mm), within {} times the noise of a point ({noise_mm:.3} mm); widen its span{} (or check the commands' units)",
        span.written(),
        crate::numerics::stats::SHORT_ARC_SAGITTA_OVER_NOISE,
        span.needed()
    )]
    ShortArc {
        /// The experiments of the joint.
        experiment: String,
        /// The joint.
        joint: usize,
        /// The arc's sagitta \[mm\].
        sagitta_mm: f64,
        /// Its radius, from its chord and its span \[mm\].
        radius_mm: f64,
        /// The noise of a point, 3-D RMS \[mm\].
        noise_mm: f64,
        /// Its span as written and the least the fit needs.
        span: ShortSpan,
    },
    /// A fit-and-correct pass for the held joints' recorded values failed: the correction
    /// moved the points away from any arc (it diverges), or the joint's sweeps fitted together
    /// show what no correction mends (too short, no motion, a straight line), said as such.
    #[error("{}", held_failure_words(*pass, cause))]
    HeldDiverged {
        /// The pass that failed (the first correction is pass 2).
        pass: usize,
        /// Its error.
        cause: Box<ProcedureError>,
    },
    /// The recorded values could not be evaluated on the calibrated model.
    #[error("modelling the held joints' recorded values: {0}")]
    Held(crate::robot::ModelError),
    /// The swept joint's command does not move.
    #[error("experiment {experiment}{}: the command of joint {joint} has zero span{cause}", lines_text(*lines))]
    ZeroSpan {
        /// Experiment.
        experiment: String,
        /// Joint.
        joint: usize,
        /// The file lines of the experiment's first and last row, when known.
        lines: Option<(u64, u64)>,
        /// Why, in words (starting with `; `).
        cause: String,
    },
    /// Commands contradict the experiment design (`docs/formats.md#controller-semantics`).
    #[error("experiment {experiment}, step {step}, column cmd_{joint}: {reason}")]
    InconsistentCommands {
        /// Experiment.
        experiment: String,
        /// Step.
        step: usize,
        /// Joint.
        joint: usize,
        /// What is inconsistent.
        reason: String,
    },
    /// A coupling needs a second target the experiment does not have.
    #[error(
        "experiment {experiment}: joint {joint} drives a coupling into joint {} that must be measured, but target 1 is seen at only {seen} step(s) (3 needed)",
        joint + 1
    )]
    SecondTargetMissing {
        /// Experiment.
        experiment: String,
        /// Joint.
        joint: usize,
        /// Steps where target 1 was seen.
        seen: usize,
    },
    /// A fit failed.
    #[error("experiment {experiment} (joint {joint}): {}", fit_words(error))]
    Fit {
        /// Experiment.
        experiment: String,
        /// Joint.
        joint: usize,
        /// The fit's error (not a `source`: the message says it in words, once).
        error: CalibrationError,
    },
    /// A joint's sweeps fit no arc or line of it, for a cause their points show
    /// ([`SweepMisfit`]).
    #[error("experiment {experiment} (joint {joint}): {failure}: {finding}")]
    Misfit {
        /// The experiments of the joint.
        experiment: String,
        /// The joint.
        joint: usize,
        /// How the fit failed, in words.
        failure: String,
        /// What the points show.
        finding: SweepMisfit,
    },
    /// A joint's sweeps have too few points for the transmission order its description's
    /// `transmission_fit` asks for.
    #[error(
        "experiment {experiment} (joint {joint}): {source}: the description's `joints[{}].transmission_fit.order` = \
         {order} asks for more coefficients than the sweeps' points resolve; lower the order (the paper fits 1) or \
         sweep the joint over more points",
        joint - 1
    )]
    FitOrder {
        /// Experiment.
        experiment: String,
        /// Joint.
        joint: usize,
        /// The order the description asks for.
        order: usize,
        /// The fit's error.
        source: Box<CalibrationError>,
    },
    /// A coupling fit (eqs. 14-15) failed; with its second target's reading farthest from the
    /// curve of its neighbours (a reading swapped or off, the likely cause).
    #[error("experiment {experiment} (joint {joint}): {cause}{}", data.worst().map_or(String::new(), |w| w.to_string()))]
    CouplingFit {
        /// Experiment.
        experiment: String,
        /// The driving joint.
        joint: usize,
        /// The fit's error.
        cause: CalibrationError,
        /// What the fit was fitted to (the outlier test reads it; the message names its point
        /// farthest from its neighbours' curve, [`SecondTargetData::worst`](super::SecondTargetData::worst)).
        data: Box<SecondTargetData>,
    },
    /// The axes do not make a phi-model.
    #[error(transparent)]
    Frames(#[from] FramesError),
    /// An option out of range.
    #[error(transparent)]
    InvalidOption(#[from] InvalidOption),
}

/// A failed axis fit in words: what it means for the sweep's points and what to check.
fn fit_words(e: &CalibrationError) -> String {
    match e {
        CalibrationError::IllConditioned { fit, .. } => format!(
            "{fit}: its points leave the joint's axis undetermined (moving the axis some way changes none of the \
             misfits): the points barely move, lie on a line, or sit where their commands do not put them; check \
             the sweep's rows (each point against its commands) and its span"
        ),
        CalibrationError::NotConverged { fit, .. } => format!(
            "{fit}: the fit of the joint's axis does not settle: the sweep's points do not lie on one path of the \
             joint at their commands; check the sweep's rows for a point off the others' path, or a command that \
             does not match its point"
        ),
        other => other.to_string(),
    }
}

/// How an axis fit failed, in a few words, before what its points show ([`SweepMisfit`]).
pub(super) fn failure_words(e: &ProcedureError) -> String {
    match e {
        ProcedureError::Fit {
            error: CalibrationError::IllConditioned { .. },
            ..
        } => "its points leave the joint's axis undetermined".into(),
        ProcedureError::Fit { .. } => "the fit of the joint's axis does not settle".into(),
        ProcedureError::Absurd { rms_mm, share, .. } => {
            format!("the fitted axis misses its points by {rms_mm:.3} mm RMS, {share:.1} % of their spread")
        }
        other => other.to_string(),
    }
}

impl ProcedureError {
    /// The error with the file lines of the points it names, read from `set`.
    pub fn with_lines(self, set: &MeasurementSet) -> Self {
        match self {
            Self::Misfit {
                experiment,
                joint,
                failure,
                finding,
            } => Self::Misfit {
                experiment,
                joint,
                failure,
                finding: finding.with_lines(set),
            },
            Self::HeldDiverged { pass, cause } => Self::HeldDiverged {
                pass,
                cause: Box::new(cause.with_lines(set)),
            },
            other => other,
        }
    }

    /// The sweep misfit this error is, or holds ([`Self::HeldDiverged`]'s): rows of the data named
    /// as the cause.
    pub fn misfit(&self) -> Option<&ProcedureError> {
        match self {
            Self::Misfit { .. } => Some(self),
            Self::HeldDiverged { cause, .. } => cause.misfit(),
            _ => None,
        }
    }

    /// The joint the error is about, when it names one (an axis fit's, a sweep's).
    pub fn joint(&self) -> Option<usize> {
        match self {
            Self::Absurd { joint, .. }
            | Self::Unresolved { joint, .. }
            | Self::ShortArc { joint, .. }
            | Self::ZeroSpan { joint, .. }
            | Self::InconsistentCommands { joint, .. }
            | Self::SecondTargetMissing { joint, .. }
            | Self::Fit { joint, .. }
            | Self::Misfit { joint, .. }
            | Self::FitOrder { joint, .. }
            | Self::CouplingFit { joint, .. } => Some(*joint),
            Self::HeldDiverged { cause, .. } => cause.joint(),
            _ => None,
        }
    }
}

/// A sweep's span as written (file units) and the least its fit needs, when known.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShortSpan {
    /// The widest sweep's span of the joint's command (deg or mm).
    pub written: f64,
    /// The span whose points the fit would resolve (same unit), when it can be said.
    pub needed: Option<f64>,
    /// The joint's kind: the unit (deg or mm).
    pub kind: JointKind,
}

impl ShortSpan {
    fn unit(&self) -> &'static str {
        match self.kind {
            JointKind::Revolute => "deg",
            JointKind::Prismatic => "mm",
        }
    }

    fn written(&self) -> String {
        format!("{:.4} {}", self.written, self.unit())
    }

    fn needed(&self) -> String {
        self.needed.map_or(String::new(), |n| {
            format!(" to at least {n:.3} {} at this noise", self.unit())
        })
    }
}

/// [`ProcedureError::HeldDiverged`]'s words: a cause the sweeps' shape explains first (the
/// correction did not make the sweep short), any other as the correction's divergence.
fn held_failure_words(pass: usize, cause: &ProcedureError) -> String {
    match cause {
        ProcedureError::ShortArc { .. } | ProcedureError::Unresolved { .. } | ProcedureError::Straight { .. } => {
            format!(
                "{cause} (found in pass {pass} of the correction for the held joints' recorded values, which fits each \
             joint's sweeps together)"
            )
        }
        _ => format!("the correction for the held joints' recorded values diverged in pass {pass}: {cause}"),
    }
}

/// ` (lines A-B)` of an experiment read from a file, or nothing.
fn lines_text(lines: Option<(u64, u64)>) -> String {
    match lines {
        Some((a, b)) if a == b => format!(" (line {a})"),
        Some((a, b)) => format!(" (lines {a}-{b})"),
        None => String::new(),
    }
}

impl From<crate::robot::ModelError> for ProcedureError {
    fn from(e: crate::robot::ModelError) -> Self {
        Self::Held(e)
    }
}
