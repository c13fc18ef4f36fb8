//! The inputs of a campaign checked against the robot description before `simulate` or `plan`
//! runs it: a plan file that is TOML (not a plan sheet CSV), axis targets for every swept
//! joint, tool targets for validation poses, and sweeps long enough for `calibrate`.

use anyhow::{Result, bail};
use axiscal::calibration::procedure::target_on_axis;
use axiscal::kinematics::JointKind;
use axiscal::measurement::{format_f64, format_f64_converted};
use axiscal::plan::{CalibrationPlan, PlannedPoint};
use axiscal::robot::{Controller, RobotDescription};
use std::path::Path;

/// Validation poses by default when the robot has tool targets (`--validation-poses`).
pub const DEFAULT_VALIDATION_POSES: usize = 60;

/// Reads the plan file `path` given to `option` (TOML, `docs/formats.md#plan-file`); a CSV is
/// refused with what it is (a plan sheet is `plan`'s output and `import points`' input).
pub fn read_plan_file(path: &Path, option: &str) -> Result<CalibrationPlan> {
    let text = axiscal::toml_file::read(path)?;
    let is_csv =
        path.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv")) || axiscal::toml_file::looks_like_csv(&text);
    if is_csv {
        bail!(
            "{}: {option} takes a TOML plan file (`reference`, `[[sweeps]]`: docs/formats.md#plan-file), but this is a \
             CSV table: a plan sheet of points (what `axiscal plan --out` and `iso9283 plan` write) goes to the \
             controller and to `axiscal import points`; give the TOML plan (`plan --optimize` writes one with \
             --plan-out) or leave {option} out for the default plan",
            path.display()
        );
    }
    Ok(axiscal::toml_file::parse_own::<CalibrationPlan>(
        &text,
        path,
        axiscal::toml_file::OwnToml::Plan,
    )?)
}

/// Refuses a plan (`plan_file`, or the default plan) that sweeps a joint for which the
/// description `robot` gives no `[[axis_targets]]`: its experiment has nothing to measure.
pub fn axis_targets_for(
    desc: &RobotDescription,
    robot: &Path,
    plan: &CalibrationPlan,
    plan_file: Option<&Path>,
) -> Result<()> {
    let Some(joint) = plan
        .sweeps
        .iter()
        .map(|s| s.joint)
        .find(|&j| j >= 1 && j <= desc.dof() && desc.axis_targets_of(j).is_none())
    else {
        return Ok(());
    };
    let plan_name = plan_file.map_or_else(|| "the default plan".to_owned(), |p| p.display().to_string());
    bail!(
        "{}: field `axis_targets`: no entry for joint {joint}, which {plan_name} sweeps: its axis experiment measures \
         the targets the joint moves; add `[[axis_targets]]` with `joint = {joint}` and `target0 = {{ link = \
         {joint}, position_mm = [x, y, z] }}` (docs/formats.md#robot-description)",
        robot.display()
    )
}

/// The validation poses to simulate or plan: `given` (`--validation-poses`); by default
/// [`DEFAULT_VALIDATION_POSES`], none for a robot without tool targets. Poses asked of a
/// robot without tool targets are refused: a validation pose measures them.
pub fn validation_poses(given: Option<usize>, desc: &RobotDescription, robot: &Path) -> Result<usize> {
    let has_targets = !desc.tool.targets_mm.is_empty();
    match given {
        Some(n) if n > 0 && !has_targets => bail!(
            "--validation-poses {n}: {} has no tool targets (`tool.targets_mm` is empty), and a validation pose \
             measures the three tool targets: give `[tool] targets_mm` (three points in the tool frame, mm) or \
             --validation-poses 0",
            robot.display()
        ),
        Some(n) => Ok(n),
        None if has_targets => Ok(DEFAULT_VALIDATION_POSES),
        None => Ok(0),
    }
}

/// Where a sweep's span was given: `--span J=SPAN`, or a plan file's `span` key.
#[derive(Clone, Copy, Debug)]
pub enum SpanGiven<'a> {
    /// `--span`.
    Option,
    /// A plan file (`--plan`).
    PlanFile(&'a std::path::Path),
}

impl SpanGiven<'_> {
    /// The warning's opening: the option as given, or the file and the sweep's key.
    fn opening(self, joint: usize, span: f64) -> String {
        match self {
            SpanGiven::Option => format!("--span {joint}={}", format_f64(span)),
            SpanGiven::PlanFile(file) => format!(
                "{}: the sweep of joint {joint}, `span = {}`",
                file.display(),
                format_f64(span)
            ),
        }
    }

    /// The name of the value in a unit hint.
    fn key(self) -> &'static str {
        match self {
            SpanGiven::Option => "--span",
            SpanGiven::PlanFile(_) => "`span`",
        }
    }
}

/// A row of target 0 of an axis experiment, planned or simulated: its experiment, moved joint
/// (1-based), step and commands (the file's units).
pub struct Target0Row<'a> {
    /// The experiment's id.
    pub experiment: &'a str,
    /// The moved joint (1-based).
    pub joint: usize,
    /// The step along the sweep.
    pub step: usize,
    /// The commands, in the file's units.
    pub cmd: &'a [f64],
}

/// One warning per turning joint whose first sweep (in `rows`, target 0 of every axis
/// experiment) has its target 0 placed by the description on the joint's own axis
/// ([`target_on_axis`] at the sweep's first commands and over its commanded span, at the noise
/// `noise_mm`), with the joint: `calibrate` would refuse the sweep, so the target is to be moved
/// before the campaign is measured.
pub fn on_axis_warnings(desc: &RobotDescription, rows: &[Target0Row<'_>], noise_mm: f64) -> Vec<(usize, String)> {
    let controller = Controller::from_description(desc);
    let mut joints: Vec<usize> = rows.iter().map(|r| r.joint).filter(|&j| j >= 1).collect();
    joints.sort_unstable();
    joints.dedup();
    joints
        .into_iter()
        .filter_map(|joint| {
            let experiment = rows.iter().find(|r| r.joint == joint)?.experiment;
            let sweep: Vec<&Target0Row> = rows.iter().filter(|r| r.experiment == experiment).collect();
            let first = sweep.iter().min_by_key(|r| r.step)?;
            let commanded = sweep.iter().filter_map(|r| r.cmd.get(joint - 1).copied());
            let (low, high) = commanded.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), c| (a.min(c), b.max(c)));
            let t = target_on_axis(desc, &controller, joint, first.cmd, (high - low).to_radians(), noise_mm)?;
            let [x, y, z] = t.position_mm.map(format_f64);
            Some((
                joint,
                format!(
                    "joint {joint}: the description places its sweep's target 0 (`axis_targets` of joint {joint}: link {}, \
                     position_mm = [{x}, {y}, {z}]) {:.3} mm from the joint's own axis, where turning the joint barely moves \
                     it: `calibrate` refuses such a sweep at the noise of a point ({noise_mm} mm); put the target at least \
                     {:.1} mm off the axis (tens of mm locate the axis well) and give its place in `axis_targets` before \
                     measuring",
                    t.link, t.off_axis_mm, t.needed_mm
                ),
            ))
        })
        .collect()
}

/// One warning per sweep of a joint in `spans` (each as given: `--span J=SPAN`, or a sweep
/// of a plan file) too short for `calibrate` to locate its axis at the noise `noise_mm`,
/// judged on the nominal arm (`points`, target 0): a rotary sweep by its arc's bow
/// ([`short_arc_warning`]), a sliding one by its points' spread ([`short_line_warning`]).
/// A joint swept twice is judged once.
pub fn short_span_warnings(
    desc: &RobotDescription,
    spans: &[(usize, f64, SpanGiven<'_>)],
    points: &[PlannedPoint],
    noise_mm: f64,
) -> Vec<String> {
    spans
        .iter()
        .enumerate()
        .filter(|&(k, (joint, ..))| !spans[..k].iter().any(|(j, ..)| j == joint))
        .filter_map(|(_, &(joint, span, given))| {
            let sweep: Vec<&PlannedPoint> = points
                .iter()
                .filter(|p| p.moved_joint == joint && p.target == 0)
                .collect();
            match desc.joints.get(joint - 1)?.kind {
                JointKind::Revolute => short_arc_warning((joint, span, given), &sweep, noise_mm),
                JointKind::Prismatic => short_line_warning((joint, span, given), &sweep, noise_mm),
            }
        })
        .collect()
}

/// The warning of a rotary sweep (`sweep`, its target-0 points) of `span` degrees whose arc
/// bows from its chord by less than
/// [`axiscal::numerics::stats::SHORT_ARC_SAGITTA_OVER_NOISE`] times the noise: the rule by
/// which `calibrate` refuses a sweep as too short to locate its axis.
fn short_arc_warning(
    (joint, span, given): (usize, f64, SpanGiven<'_>),
    sweep: &[&PlannedPoint],
    noise_mm: f64,
) -> Option<String> {
    let factor = axiscal::numerics::stats::SHORT_ARC_SAGITTA_OVER_NOISE;
    let first = sweep.iter().min_by_key(|p| p.step)?;
    let last = sweep.iter().max_by_key(|p| p.step)?;
    let half_rad = (span / 2.0).to_radians();
    if half_rad >= std::f64::consts::FRAC_PI_2 {
        return None;
    }
    let radius_mm = (last.nominal_m - first.nominal_m).norm() * 1e3 / (2.0 * half_rad.sin());
    let sagitta_mm = radius_mm * (1.0 - half_rad.cos());
    if sagitta_mm >= factor * noise_mm {
        return None;
    }
    // Below a micro-radian the points coincide to the planner's precision: no radius to read.
    if !(radius_mm.is_finite() && half_rad > 1e-6) {
        return Some(format!(
            "{}: joint {joint}'s sweep of {} deg moves its target by nothing the instrument resolves: `calibrate` \
             refuses it as too short to locate the axis; give a span of degrees (tens of them)",
            given.opening(joint, span),
            format_f64(span)
        ));
    }
    let bow = factor * noise_mm / radius_mm;
    let least_deg = (bow < 2.0).then(|| 2.0 * (1.0 - bow).acos().to_degrees());
    let needed = least_deg.map_or_else(String::new, |d| format!(" to at least {d:.3} deg"));
    // The hint of radians only where the value read as radians would be wide enough.
    let radians = if span <= std::f64::consts::TAU && least_deg.is_some_and(|d| span.to_degrees() >= d) {
        format!(
            " ({} is in degrees: {} rad would be {:.1} deg)",
            given.key(),
            format_f64(span),
            span.to_degrees()
        )
    } else {
        String::new()
    };
    Some(format!(
        "{}: joint {joint}'s sweep of {} deg bows its target's arc (radius {radius_mm:.1} mm) \
         {sagitta_mm:.4} mm from its chord, within {factor} times the noise of a point ({noise_mm} mm, \
         --noise-mm): `calibrate` refuses it as too short to locate the axis; widen it{needed}{radians}",
        given.opening(joint, span),
        format_f64(span)
    ))
}

/// The warning of a sliding sweep (`sweep`, its target-0 points) of `span` mm whose points
/// spread about their centroid by less than
/// [`axiscal::numerics::stats::UNRESOLVED_SPREAD_OVER_NOISE`] times the noise (the widest of
/// its experiments): the rule by which `calibrate` names a sweep too short for the instrument
/// to locate the axis. Points evenly along a line of length `L` spread `L / sqrt(12)`.
fn short_line_warning(
    (joint, span, given): (usize, f64, SpanGiven<'_>),
    sweep: &[&PlannedPoint],
    noise_mm: f64,
) -> Option<String> {
    let factor = axiscal::numerics::stats::UNRESOLVED_SPREAD_OVER_NOISE;
    let mut experiments: Vec<&str> = sweep.iter().map(|p| p.experiment.as_str()).collect();
    experiments.dedup();
    let spread_mm = experiments
        .iter()
        .map(|e| {
            let points: Vec<_> = sweep
                .iter()
                .filter(|p| p.experiment == *e)
                .map(|p| p.nominal_m)
                .collect();
            axiscal::numerics::stats::rms_spread(&points) * 1e3
        })
        .max_by(f64::total_cmp)?;
    if spread_mm >= factor * noise_mm {
        return None;
    }
    let needed_mm = 12f64.sqrt() * factor * noise_mm;
    let metres = if span * 1e3 >= needed_mm {
        format!(
            " ({} is in mm: {} m would be {} mm)",
            given.key(),
            format_f64(span),
            format_f64_converted(span * 1e3)
        )
    } else {
        String::new()
    };
    Some(format!(
        "{}: joint {joint}'s sweep of {} mm spreads its target's points {spread_mm:.4} mm RMS about \
         their centroid, within {factor} times the noise of a point ({noise_mm} mm, --noise-mm): `calibrate` \
         refuses it as too short for the instrument to locate the axis; widen it to at least {needed_mm:.3} mm{metres}",
        given.opening(joint, span),
        format_f64(span)
    ))
}
