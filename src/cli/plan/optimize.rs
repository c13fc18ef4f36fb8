//! `axiscal plan --optimize`: the search ([`axiscal::plan::optimize`]) run from the command
//! line's settings, its result printed next to the seed plan's at the same number of points.

use super::Args;
use anyhow::{Context, Result, bail};
use axiscal::calibration::CalibrationError;
use axiscal::calibration::procedure::{CalibrationOptions, ProcedureError};
use axiscal::plan::optimize::{axis_points, points_per_round};
use axiscal::plan::{
    CalibrationPlan, OptimizeOptions, PlanObjective, PlanPrediction, PredictError, SightOptions, ValidationPlan,
    optimize, with_point_budget,
};
use axiscal::robot::RobotDescription;

/// The workspace of the prediction: `--workspace-half-range` (default the validation poses'),
/// `--workspace-poses` poses drawn with the validation seed.
fn workspace(args: &Args, desc: &RobotDescription, validation: &ValidationPlan) -> Result<ValidationPlan> {
    let half_range = if args.workspace_half_range.is_empty() {
        validation.half_range.clone()
    } else if args.workspace_half_range.len() == desc.dof() {
        args.workspace_half_range.clone()
    } else {
        bail!(
            "--workspace-half-range: {} values, the robot has {} joints",
            args.workspace_half_range.len(),
            desc.dof()
        );
    };
    Ok(ValidationPlan {
        poses: args.workspace_poses,
        half_range,
        seed: validation.seed,
    })
}

/// `--min-intervals` (default [`OptimizeOptions::default`]'s), refused when given above what
/// `points` lets every sweep of `seed` keep at once (the search would leave the sweeps below it
/// as they are).
fn min_intervals(args: &Args, seed: &CalibrationPlan, points: usize) -> Result<usize> {
    let Some(wanted) = args.min_intervals else {
        return Ok(OptimizeOptions::default().min_intervals);
    };
    let per_round = points_per_round(seed).max(1);
    let most = (points / per_round).saturating_sub(1);
    if wanted > most {
        bail!(
            "--min-intervals {wanted}: {points} axis points (--points; default: the plan's) over the plan's {} sweeps let each keep at most \
             {most} intervals (a sweep of n intervals measures n + 1 poses, two points a pose with a second target); \
             pass --min-intervals {most} or less, or --points {} or more",
            seed.sweeps.len(),
            (wanted + 1) * per_round
        );
    }
    Ok(wanted)
}

/// Runs the search from `seed_plan` and prints the result; returns the optimised plan.
pub(super) fn run(
    args: &Args,
    desc: &RobotDescription,
    seed_plan: &CalibrationPlan,
    validation: &ValidationPlan,
    sight: &SightOptions,
) -> Result<CalibrationPlan> {
    let points = args.points.unwrap_or_else(|| axis_points(seed_plan));
    let seed = with_point_budget(seed_plan, points)
        .with_context(|| format!("--points {points}: the plan's sweeps cannot measure exactly {points} points"))?;
    let min_intervals = min_intervals(args, &seed, points)?;
    let workspace = workspace(args, desc, validation)?;
    let options = CalibrationOptions {
        noise_rms_3d_mm: args.noise_mm,
        repeatability_sigma_rad: args.repeatability_rad.clone(),
        ..CalibrationOptions::default()
    };
    options
        .joint_repeatability_rad(desc)
        .map_err(|e| anyhow::anyhow!("--repeatability-rad: {e}"))?;
    let objective = seed_objective(desc, seed_plan, (&seed, points), &workspace, sight, &options)?;
    let found = optimize(
        &objective,
        desc,
        &seed,
        OptimizeOptions {
            min_intervals,
            max_rounds: args.max_rounds,
        },
    )?;
    println!(
        "workspace: {} poses, joints within +-{} (deg or mm) of the reference, seed {}; noise {} mm; {} axis points",
        objective.workspace_poses(),
        join(&workspace.half_range),
        workspace.seed,
        args.noise_mm,
        points
    );
    println!(
        "searched {} candidate plans in {} rounds (coordinate descent over spans, moves of points between sweeps)",
        found.candidates, found.rounds
    );
    let name = if args.plan.is_some() { "seed plan" } else { "Table 1" };
    print_prediction(name, &found.seed);
    print_prediction("optimised", &found.prediction);
    println!(
        "  predicted tool position RMS {:.2}x lower than {name}'s at the same number of points",
        found.seed.position_rms_mm / found.prediction.position_rms_mm
    );
    for (a, b) in seed.sweeps.iter().zip(&found.plan.sweeps) {
        println!(
            "  joint {}: span {} -> {}, poses {} -> {}{}",
            a.joint,
            a.span,
            b.span,
            a.poses(),
            b.poses(),
            match (b.second_target, &b.held_at) {
                (true, Some(_)) => " (two targets, the follower joint centred)",
                (true, None) => " (two targets)",
                _ => "",
            }
        );
    }
    Ok(found.plan)
}

/// A fit the seed plan at `--points` leaves too few points: the joint, the fit, the points it
/// has and needs.
fn starved_fit(e: &PredictError) -> Option<(usize, &'static str, usize, usize)> {
    let PredictError::Calibration(
        ProcedureError::Fit {
            joint, error: source, ..
        }
        | ProcedureError::CouplingFit {
            joint, cause: source, ..
        },
    ) = e
    else {
        return None;
    };
    match source {
        CalibrationError::TooFewPoints { fit, got, needed } => Some((*joint, *fit, *got, *needed)),
        _ => None,
    }
}

/// Calibrations tried at most to find the `--points` a starved fit needs.
const POINT_TRIES: usize = 20;

/// The objective of `seed` (`seed_plan` at `points`). When a sweep is left too few points for
/// its fits, the error names `--points` and the smallest value that calibrates (the sweep's
/// poses grown by at least what the fit lacks, each candidate calibrated), if one is found
/// within [`POINT_TRIES`] calibrations.
fn seed_objective(
    desc: &RobotDescription,
    seed_plan: &CalibrationPlan,
    (seed, points): (&CalibrationPlan, usize),
    workspace: &ValidationPlan,
    sight: &SightOptions,
    options: &CalibrationOptions,
) -> Result<PlanObjective> {
    let e = match PlanObjective::new(desc, seed, workspace, sight, options) {
        Ok(objective) => return Ok(objective),
        Err(e) => e,
    };
    let Some((joint, fit, got, needed)) = starved_fit(&e) else {
        return Err(anyhow::Error::new(e).context("predicting the seed plan"));
    };
    let poses =
        |plan: &CalibrationPlan| -> usize { plan.sweeps.iter().filter(|s| s.joint == joint).map(|s| s.poses()).sum() };
    let wanted = poses(seed) + needed.saturating_sub(got);
    let enough = (points + 1..=points.saturating_mul(4))
        .filter_map(|p| Some((p, with_point_budget(seed_plan, p)?)))
        .filter(|(_, plan)| poses(plan) >= wanted)
        .take(POINT_TRIES)
        .find(|(_, plan)| PlanObjective::new(desc, plan, workspace, sight, options).is_ok());
    let raise = match enough {
        Some((p, _)) => format!("raise --points to {p} or more"),
        None => "raise --points".to_owned(),
    };
    bail!(
        "--points {points} is too few: the sweep of joint {joint} gets {got} points for its {fit}, which needs at least {needed}; {raise}"
    )
}

fn join(values: &[f64]) -> String {
    values.iter().map(|v| v.to_string()).collect::<Vec<_>>().join("/")
}

fn print_prediction(name: &str, p: &PlanPrediction) {
    let top: Vec<String> = p
        .breakdown_mm2
        .iter()
        .take(4)
        .map(|(g, v)| format!("{g} {:.0} %", 100.0 * v / p.position_rms_mm.powi(2)))
        .collect();
    println!(
        "  {name:<10} predicted tool 1-sigma over the workspace: position RMS {:.3} mm, orientation RMS {:.3} mrad ({} points, {} hidden); largest shares: {}",
        p.position_rms_mm,
        p.orientation_rms_mrad,
        p.axis_points,
        p.hidden_points,
        top.join(", ")
    );
}

/// The comment on top of the optimised plan TOML: how it was made.
pub(super) fn toml_comment(args: &Args, desc: &RobotDescription) -> String {
    format!(
        "# axiscal plan --optimize for {}: spans and points per sweep minimising the predicted tool\n\
         # error over the workspace (docs/method.md#plans-that-buy-accuracy); noise {} mm.\n\
         # Use with `axiscal simulate --plan` or `axiscal plan --plan`.\n",
        desc.name, args.noise_mm
    )
}
