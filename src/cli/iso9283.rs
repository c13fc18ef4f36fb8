//! `axiscal iso9283 plan|evaluate`: the measurement plan of an ISO 9283 test
//! (`docs/formats.md#iso9283-plan`), and the pose and distance characteristics of measured
//! cycles (`docs/formats.md#iso9283-evaluate`), written as `iso9283.json` and `iso9283.md`.

use super::checks;
use super::options::InRange;
use super::output::Outputs;
use super::printer::Printer;
use anyhow::{Context, Result, bail};
use axiscal::compensation::Compensator;
use axiscal::iso9283::{
    CYCLE_ORDER, Cube, EvaluateOptions, IsoFigures, IsoPrediction, PredictionInputs, approach_commands, cube_of_edge,
    evaluate, largest_cube, predict,
};
use axiscal::json_file::{self, Schema};
use axiscal::measurement::{IsotropicNoise, MeasurementModel};
use axiscal::plan::{CalibrationPlan, PlanPose, points_of_poses, tool_targets, write_plan_csv};
use axiscal::robot::{RobotDescription, RobotModel};
use std::fmt::Write as _;
use std::path::PathBuf;

/// The files `iso9283 evaluate` writes into its output folder.
const OUTPUTS: [&str; 2] = ["iso9283.json", "iso9283.md"];

/// Arguments of `axiscal iso9283`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    what: What,
}

#[derive(Debug, clap::Subcommand)]
enum What {
    /// Pose accuracy and repeatability (AP, RP), multi-directional variation (vAP) and
    /// distance accuracy and repeatability (AD, RD) of the cycles in a measurement CSV
    /// (experiments `iso-P<k>` or `iso-P<k>-d<h>`, the step the cycle).
    Evaluate(EvaluateArgs),
    /// The measurement plan of an ISO 9283 test: the cube's five points `P1` .. `P5` (ISO
    /// 9283 6.2, 6.8), each cycle visiting `P1, P5, P4, P3, P2`, the tool targets measured at
    /// each (`docs/formats.md#iso9283-plan`).
    Plan(PlanArgs),
    /// The figures an ISO 9283 test after calibration is predicted to give, before it is
    /// measured: a Monte-Carlo over the calibration's covariance, the robot's repeatability
    /// and the instrument's noise (`docs/formats.md#iso9283-predict`).
    Predict(PredictArgs),
}

/// Where the cube goes: what `plan` and `predict` share.
#[derive(Debug, clap::Args)]
struct CubeArgs {
    /// Nominal robot description (TOML), or a shipped robot's name.
    #[arg(long, default_value = "asea-irb6l", value_parser = super::options::ROBOT_FILE)]
    robot: PathBuf,
    /// The commands of the cube's centre, `cmd_1,..,cmd_N` (deg or mm): its tool position is
    /// `P1`, its tool orientation every point's. Default: the calibration plan's reference pose.
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    centre_cmd: Option<Vec<f64>>,
    /// The cube's edge (mm). Default: the largest, to 10 mm and at most 500 mm, whose five
    /// points are inside the joint limits.
    #[arg(long, value_parser = InRange::closed(1.0, 1e5, "mm"))]
    edge_mm: Option<f64>,
    /// Cycles (ISO 9283: 30).
    #[arg(long, default_value_t = 30, value_parser = clap::value_parser!(u32).range(1..=1000))]
    cycles: u32,
    /// Go on even when the calibration records another robot description than `--robot`.
    #[arg(long)]
    allow_other_robot: bool,
}

#[derive(Debug, clap::Args)]
struct PredictArgs {
    /// The calibration (`calibration.json` with its `model_covariance`): its model commands the
    /// points, its covariance is the calibration's error.
    #[arg(long)]
    calibration: PathBuf,
    #[command(flatten)]
    cube: CubeArgs,
    /// The instrument's 3-D RMS noise (mm), isotropic. Default: the noise the calibration's
    /// fits were weighted with (`noise.used_rms_3d_mm`).
    #[arg(long, value_parser = super::options::NOISE_MM)]
    noise_mm: Option<f64>,
    /// Simulated tests.
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    trials: u32,
    /// Seed of the simulated tests.
    #[arg(long, value_parser = super::options::SEED, default_value_t = 1)]
    seed: u64,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// Replace existing output files.
    #[arg(long)]
    force: bool,
}

#[derive(Debug, clap::Args)]
struct PlanArgs {
    /// The calibration whose model commands the points (after calibration, fig. 5). Without
    /// it the nominal model does (before calibration).
    #[arg(long)]
    calibration: Option<PathBuf>,
    #[command(flatten)]
    cube: CubeArgs,
    /// Approach directions (ISO 9283 7.2.3): 1, or 2 or 3 for the multi-directional test, each
    /// pose approached from `--approach-mm` along the base's x, then y, then z axis (its
    /// negative side); the poses are then `iso-P<k>-d<h>`, the approach poses
    /// `iso-approach-P<k>-d<h>` (measured or not: `import points --allow-missing`).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=3))]
    directions: u32,
    /// How far each pose is approached from, with `--directions` 2 or 3 (mm).
    #[arg(long, default_value_t = 50.0, value_parser = InRange::above(0.0, 1e4, ""))]
    approach_mm: f64,
    #[command(flatten)]
    sight: super::plan::SightArgs,
    /// The plan CSV to write.
    #[arg(long)]
    out: PathBuf,
    /// Replace `--out` if it exists.
    #[arg(long)]
    force: bool,
}

#[derive(Debug, clap::Args)]
struct EvaluateArgs {
    /// Measurement CSV with the cycles (`docs/formats.md#iso9283-evaluate`).
    data: PathBuf,
    /// Nominal robot description (TOML), or a shipped robot's name: the tool targets and the
    /// controller.
    #[arg(long, default_value = "asea-irb6l", value_parser = super::options::ROBOT_FILE)]
    robot: PathBuf,
    /// The calibration whose model commands the poses (after calibration). Without it the
    /// nominal model commands them, its base frame registered to the data (before calibration).
    #[arg(long)]
    calibration: Option<PathBuf>,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// Replace existing output files.
    #[arg(long)]
    force: bool,
    /// Flag the cycles the outlier screen rejects (a cycle far from its pose's others) but
    /// keep them in the figures.
    #[arg(long)]
    keep_outliers: bool,
    #[command(flatten)]
    checks: checks::Overrides,
}

/// Runs `axiscal iso9283`.
pub fn run(args: Args, printer: Printer) -> Result<()> {
    match args.what {
        What::Evaluate(a) => evaluate_cycles(a, printer),
        What::Plan(a) => plan(a, printer),
        What::Predict(a) => predict_figures(a, printer),
    }
}

/// The cube of `args` commanded through `model` (file units).
fn cube_of(args: &CubeArgs, desc: &RobotDescription, model: &RobotModel) -> Result<Cube> {
    axiscal::iso9283::check_cube_robot(desc).with_context(|| args.robot.display().to_string())?;
    let targets = desc.tool_targets_m().len();
    if targets < 3 {
        return Err(axiscal::iso9283::IsoError::TooFewToolTargets(targets))
            .with_context(|| format!("{}: an ISO 9283 test measures the tool's pose", args.robot.display()));
    }
    let compensator = Compensator::new(model, desc)?;
    let centre = args
        .centre_cmd
        .clone()
        .unwrap_or_else(|| CalibrationPlan::for_robot(desc).reference);
    if centre.len() != desc.dof() {
        bail!(
            "--centre-cmd gives {} values; the robot has {} joints",
            centre.len(),
            desc.dof()
        );
    }
    if let Some(k) = centre.iter().position(|c| !c.is_finite()) {
        bail!(
            "--centre-cmd: cmd_{} = {}: give each joint's command as a finite number (deg or mm)",
            k + 1,
            centre[k]
        );
    }
    let source = if args.centre_cmd.is_some() {
        "--centre-cmd"
    } else {
        "the calibration plan's reference pose; --centre-cmd gives another"
    };
    match args.edge_mm {
        Some(mm) => cube_of_edge(&compensator, desc, &centre, mm * 1e-3),
        None => largest_cube(&compensator, desc, &centre, 0.5),
    }
    .with_context(|| format!("the ISO cube around the centre commands {centre:?} ({source})"))
}

fn plan(args: PlanArgs, printer: Printer) -> Result<()> {
    let robot = &args.cube.robot;
    let mut outputs = Outputs::new(args.force).input("--robot", robot);
    if let Some(c) = &args.calibration {
        outputs = outputs.input("--calibration", c);
    }
    outputs.check(&args.out)?;
    let desc = RobotDescription::from_file(robot)?;
    let model = match &args.calibration {
        Some(path) => {
            checks::read_calibration(path, &desc, robot, args.cube.allow_other_robot)?
                .calibration
                .robot
        }
        None => RobotModel::ideal(&desc),
    };
    let cube = cube_of(&args.cube, &desc, &model)?;
    let poses = plan_poses(&args, &desc, &model, &cube)?;
    let sight = args.sight.options(&desc)?;
    let points = points_of_poses(&desc, poses, &sight)?;
    let comment = format!(
        "{}# ISO 9283 test of {}: cube edge {:.0} mm, {} cycles of P1, P5, P4, P3, P2, {} approach direction(s); commanded through {}\n",
        args.sight.header_comment(&desc)?,
        desc.name,
        cube.edge_m * 1e3,
        args.cube.cycles,
        args.directions,
        if args.calibration.is_some() {
            "the calibrated model (fig. 5)"
        } else {
            "the nominal model"
        }
    );
    let mut text = Vec::new();
    write_plan_csv(&mut text, &comment, &points)?;
    outputs.write(&args.out, text)?;
    say!(
        printer,
        "ISO 9283 cube of edge {:.0} mm, {} cycles x 5 points x {} direction(s)",
        cube.edge_m * 1e3,
        args.cube.cycles,
        args.directions
    );
    super::plan::summarise(&args.out, &points, sight.stations_m.len());
    Ok(())
}

/// The poses of the plan: per direction, per cycle, per point in `CYCLE_ORDER` (with more
/// than one direction, its approach pose first).
fn plan_poses(args: &PlanArgs, desc: &RobotDescription, model: &RobotModel, cube: &Cube) -> Result<Vec<PlanPose>> {
    let targets = tool_targets(desc);
    let pose = |experiment: String, step: usize, cmd: &[f64]| PlanPose {
        experiment,
        moved_joint: 0,
        step,
        cmd: cmd.to_vec(),
        targets: targets.clone(),
    };
    if args.directions == 1 {
        return Ok((0..args.cube.cycles as usize)
            .flat_map(|cycle| CYCLE_ORDER.map(|k| (cycle, k)))
            .map(|(cycle, k)| pose(format!("iso-P{k}"), cycle, &cube.commands[k - 1]))
            .collect());
    }
    let compensator = Compensator::new(model, desc)?;
    let mut poses = Vec::new();
    for h in 1..=args.directions as usize {
        let approach = approach_commands(&compensator, desc, cube, h - 1, args.approach_mm * 1e-3)
            .with_context(|| format!("approach direction {h} (--approach-mm {})", args.approach_mm))?;
        for cycle in 0..args.cube.cycles as usize {
            for k in CYCLE_ORDER {
                poses.push(pose(format!("iso-approach-P{k}-d{h}"), cycle, &approach[k - 1]));
                poses.push(pose(format!("iso-P{k}-d{h}"), cycle, &cube.commands[k - 1]));
            }
        }
    }
    Ok(poses)
}

fn evaluate_cycles(args: EvaluateArgs, printer: Printer) -> Result<()> {
    let mut outputs = Outputs::new(args.force)
        .input("DATA", &args.data)
        .input("--robot", &args.robot);
    if let Some(c) = &args.calibration {
        outputs = outputs.input("--calibration", c);
    }
    outputs.check_in(&args.out, &OUTPUTS)?;
    let desc = RobotDescription::from_file(&args.robot)?;
    checks::description_units(&desc, &args.robot, args.checks.skip_unit_check)?;
    let set = checks::read_data(&args.data, &desc, &args.robot, args.checks)?;
    checks::one_setup(&set, &args.data, "iso9283 evaluate")?;
    let (model, commanded_by) = match &args.calibration {
        Some(path) => (
            checks::read_calibration(path, &desc, &args.robot, args.checks.allow_other_robot)?
                .calibration
                .robot,
            format!(
                "the calibrated model of {}",
                axiscal::markdown::code(&path.display().to_string())
            ),
        ),
        None => (
            RobotModel::ideal(&desc),
            "the nominal model, its base frame registered to the data".to_string(),
        ),
    };
    let options = EvaluateOptions {
        register_base: args.calibration.is_none(),
        keep_outliers: args.keep_outliers,
        screen: true,
        unit_check: !args.checks.skip_unit_check,
    };
    let figures = evaluate(&set, &model, &desc, options)
        .with_context(|| format!("ISO 9283 figures of {}", args.data.display()))?;
    for w in &figures.warnings {
        eprintln!("warning: {}: {w}", args.data.display());
    }
    let text = markdown(
        &figures,
        &commanded_by,
        &axiscal::markdown::code(&args.data.display().to_string()),
    );
    let mut staged = outputs.staged_in(&args.out)?;
    staged.write(OUTPUTS[0], json_file::to_string(Schema::ISO9283, &figures)?)?;
    staged.write(OUTPUTS[1], &text)?;
    staged.commit(&[])?;
    say!(printer, "{}", text.trim_end());
    say!(printer, "wrote {}/{{{}}}", args.out.display(), OUTPUTS.join(","));
    Ok(())
}

/// `iso9283.md`: the figures per pose, the distance figures, how the poses were commanded.
fn markdown(f: &IsoFigures, commanded_by: &str, data: &str) -> String {
    let mut s = format!(
        "# ISO 9283 pose characteristics of {data}\n\nCommanded poses: {commanded_by}; positions in the robot base frame.\n"
    );
    if let Some(rms) = f.registration_rms_mm {
        let _ = writeln!(s, "Base frame registration: {rms:.3} mm RMS over all cycles.");
    }
    let _ = writeln!(
        s,
        "\n| pose | cycles | AP_P (mm) | AP_a, AP_b, AP_c (mrad) | RP_l (mm) | RP_a, RP_b, RP_c (mrad) | vAP_P (mm) |\n|---|---|---|---|---|---|---|"
    );
    for p in &f.poses {
        let a = &p.accuracy;
        let rp = p.repeatability.map_or("-".into(), |r| format!("{:.4}", r.rp_l_mm));
        let rpa = p.repeatability.map_or("-".into(), |r| {
            format!("{:.4}, {:.4}, {:.4}", r.rp_a_mrad, r.rp_b_mrad, r.rp_c_mrad)
        });
        let vap = p.directional.map_or("-".into(), |v| format!("{:.4}", v.vap_p_mm));
        let _ = writeln!(
            s,
            "| P{} | {} | {:.4} | {:.4}, {:.4}, {:.4} | {rp} | {rpa} | {vap} |",
            p.pose, p.cycles, a.ap_p_mm, a.ap_a_mrad, a.ap_b_mrad, a.ap_c_mrad
        );
    }
    match &f.distance_p2_p4 {
        Some(d) => {
            let _ = writeln!(
                s,
                "\nDistance P2-P4 (commanded {:.3} mm): AD_P {:.4} mm, RD_P +-{:.4} mm.",
                d.commanded_mm, d.ad_p_mm, d.rd_p_mm
            );
        }
        None => s.push_str("\nDistance P2-P4: not measured in two or more common cycles.\n"),
    }
    if !f.warnings.is_empty() {
        s.push_str("\n## Warnings\n\n");
        for w in &f.warnings {
            let _ = writeln!(s, "- {w}");
        }
    }
    s
}

/// The files `iso9283 predict` writes into its output folder.
const PREDICTION_OUTPUTS: [&str; 2] = ["iso9283-prediction.json", "iso9283-prediction.md"];

fn predict_figures(args: PredictArgs, printer: Printer) -> Result<()> {
    let robot = &args.cube.robot;
    let outputs = Outputs::new(args.force)
        .input("--robot", robot)
        .input("--calibration", &args.calibration);
    outputs.check_in(&args.out, &PREDICTION_OUTPUTS)?;
    let desc = RobotDescription::from_file(robot)?;
    let cal = checks::read_calibration(&args.calibration, &desc, robot, args.cube.allow_other_robot)?.calibration;
    let Some(covariance) = &cal.model_covariance else {
        bail!(
            "{} has no `model_covariance` (a file written before it was recorded): the calibration's error cannot be drawn; recalibrate with `axiscal calibrate`",
            args.calibration.display()
        );
    };
    let noise_mm = match (args.noise_mm, &cal.noise) {
        (Some(mm), _) => mm,
        (None, Some(n)) => n.used_rms_3d_mm,
        (None, None) => bail!(
            "{} records no measurement noise: give the instrument's with --noise-mm",
            args.calibration.display()
        ),
    };
    let repeatability = cal.options.joint_repeatability_rad(&desc)?;
    let cube = cube_of(&args.cube, &desc, &cal.robot)?;
    let instrument = MeasurementModel::Isotropic(IsotropicNoise {
        net_radial_rms_mm: noise_mm,
    });
    let inputs = PredictionInputs {
        model: &cal.robot,
        covariance: &covariance.matrix(),
        desc: &desc,
        repeatability_rad_or_m: &repeatability,
        instrument: &instrument,
    };
    let prediction = predict(
        &inputs,
        &cube.commands,
        args.cube.cycles as usize,
        args.trials as usize,
        args.seed,
    )
    .with_context(|| format!("predicting the ISO test of {}", args.calibration.display()))?;
    let text = prediction_markdown(
        &prediction,
        &cube,
        noise_mm,
        &axiscal::markdown::code(&args.calibration.display().to_string()),
    );
    let mut staged = outputs.staged_in(&args.out)?;
    staged.write(
        PREDICTION_OUTPUTS[0],
        json_file::to_string(Schema::ISO9283_PREDICTION, &prediction)?,
    )?;
    staged.write(PREDICTION_OUTPUTS[1], &text)?;
    staged.commit(&[])?;
    say!(printer, "{}", text.trim_end());
    say!(
        printer,
        "wrote {}/{{{}}}",
        args.out.display(),
        PREDICTION_OUTPUTS.join(",")
    );
    Ok(())
}

/// `iso9283-prediction.md`: per pose the predicted `AP_P` and `RP_l` (mean and 95 % quantile
/// over the simulated tests), the distance figures, what was drawn.
fn prediction_markdown(p: &IsoPrediction, cube: &Cube, noise_mm: f64, calibration: &str) -> String {
    let mut s = format!(
        "# Predicted ISO 9283 figures after the calibration {calibration}\n\nCube edge {:.0} mm; {} simulated tests (seed {}) of the calibration's error (its model covariance), the robot's repeatability and isotropic instrument noise of {noise_mm:.4} mm 3-D RMS.\n\n| pose | AP_P mean (mm) | AP_P p95 (mm) | RP_l mean (mm) | RP_l p95 (mm) |\n|---|---|---|---|---|\n",
        cube.edge_m * 1e3,
        p.trials,
        p.seed
    );
    let or_dash = |x: Option<f64>| x.map_or("-".into(), |v| format!("{v:.4}"));
    for q in &p.poses {
        let _ = writeln!(
            s,
            "| P{} | {:.4} | {:.4} | {} | {} |",
            q.pose,
            q.ap_p_mm.mean,
            q.ap_p_mm.p95,
            or_dash(q.rp_l_mm.map(|r| r.mean)),
            or_dash(q.rp_l_mm.map(|r| r.p95))
        );
    }
    let _ = writeln!(
        s,
        "\nMean over the poses: AP_P {:.4} mm (p95 {:.4}), RP_l {} mm; worst AP_P {:.4} mm (p95 {:.4}).",
        p.mean_ap_p_mm.mean,
        p.mean_ap_p_mm.p95,
        or_dash(p.mean_rp_l_mm.map(|r| r.mean)),
        p.worst_ap_p_mm.mean,
        p.worst_ap_p_mm.p95
    );
    if let (Some(ad), Some(rd)) = (p.ad_p_mm, p.rd_p_mm) {
        let _ = writeln!(
            s,
            "Distance P2-P4: AD_P {:.4} mm (RMS over the tests {:.4}), RD_P {:.4} mm.",
            ad.mean, ad.rms, rd.mean
        );
    }
    s
}
