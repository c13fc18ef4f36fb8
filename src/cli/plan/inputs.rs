//! The inputs of a campaign checked against the robot description before `simulate` or `plan`
//! runs it: a plan file that is TOML (not a plan sheet CSV), axis targets for every swept
//! joint, tool targets for validation poses, and sweeps long enough for `calibrate`.

use anyhow::{Result, bail};
use axiscal::kinematics::JointKind;
use axiscal::measurement::format_f64;
use axiscal::plan::{CalibrationPlan, PlannedPoint};
use axiscal::robot::RobotDescription;
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

/// One warning per sweep of a joint in `spans` (`--span J=SPAN`) too short for `calibrate` to
/// locate its axis at the noise `noise_mm`, judged on the nominal arm (`points`, target 0): a
/// rotary sweep by its arc's bow ([`short_arc_warning`]), a sliding one by its points' spread
/// ([`short_line_warning`]).
pub fn short_span_warnings(
    desc: &RobotDescription,
    spans: &[(usize, f64)],
    points: &[PlannedPoint],
    noise_mm: f64,
) -> Vec<String> {
    spans
        .iter()
        .filter_map(|&(joint, span)| {
            let sweep: Vec<&PlannedPoint> = points
                .iter()
                .filter(|p| p.moved_joint == joint && p.target == 0)
                .collect();
            match desc.joints.get(joint - 1)?.kind {
                JointKind::Revolute => short_arc_warning(joint, span, &sweep, noise_mm),
                JointKind::Prismatic => short_line_warning(joint, span, &sweep, noise_mm),
            }
        })
        .collect()
}

/// The warning of a rotary sweep (`sweep`, its target-0 points) of `span` degrees whose arc
/// bows from its chord by less than
/// [`axiscal::numerics::stats::SHORT_ARC_SAGITTA_OVER_NOISE`] times the noise: the rule by
/// which `calibrate` refuses a sweep as too short to locate its axis.
fn short_arc_warning(joint: usize, span: f64, sweep: &[&PlannedPoint], noise_mm: f64) -> Option<String> {
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
    let bow = factor * noise_mm / radius_mm;
    let needed = if bow < 2.0 {
        format!(" to at least {:.3} deg", 2.0 * (1.0 - bow).acos().to_degrees())
    } else {
        String::new()
    };
    let radians = if span <= std::f64::consts::TAU {
        format!(
            " (--span is in degrees: {} rad would be {:.1} deg)",
            format_f64(span),
            span.to_degrees()
        )
    } else {
        String::new()
    };
    Some(format!(
        "--span {joint}={}: joint {joint}'s sweep of {} deg bows its target's arc (radius {radius_mm:.1} mm) \
         {sagitta_mm:.4} mm from its chord, within {factor} times the noise of a point ({noise_mm} mm, \
         --noise-mm): `calibrate` refuses it as too short to locate the axis; widen it{needed}{radians}",
        format_f64(span),
        format_f64(span)
    ))
}

/// The warning of a sliding sweep (`sweep`, its target-0 points) of `span` mm whose points
/// spread about their centroid by less than
/// [`axiscal::numerics::stats::UNRESOLVED_SPREAD_OVER_NOISE`] times the noise (the widest of
/// its experiments): the rule by which `calibrate` names a sweep too short for the instrument
/// to locate the axis. Points evenly along a line of length `L` spread `L / sqrt(12)`.
fn short_line_warning(joint: usize, span: f64, sweep: &[&PlannedPoint], noise_mm: f64) -> Option<String> {
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
            " (--span is in mm: {} m would be {} mm)",
            format_f64(span),
            format_f64(span * 1e3)
        )
    } else {
        String::new()
    };
    Some(format!(
        "--span {joint}={}: joint {joint}'s sweep of {} mm spreads its target's points {spread_mm:.4} mm RMS about \
         their centroid, within {factor} times the noise of a point ({noise_mm} mm, --noise-mm): `calibrate` \
         refuses it as too short for the instrument to locate the axis; widen it to at least {needed_mm:.3} mm{metres}",
        format_f64(span),
        format_f64(span)
    ))
}
