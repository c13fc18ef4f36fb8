//! `axiscal plan --robot R --out PLAN.csv`: the measurement plan for a real robot
//! (`docs/formats.md#measurement-plan`): every point to measure with every joint's command,
//! the target, its nominal position and whether each station should see it. The choice of
//! poses (`--plan`, `--span`, `--intervals`, `--order`, `--validation-poses`) is made here;
//! the writer (`axiscal::plan::write_plan_csv`) takes any list of points.

mod inputs;
mod optimize;

pub use inputs::{Target0Row, axis_targets_for, on_axis_warnings, validation_poses};

use super::options::{InRange, NOISE_MM};
use super::output::Outputs;
use anyhow::{Context, Result, bail};
use axiscal::plan::{
    CalibrationPlan, SightOptions, ValidationPlan, instrument_stations_m, planned_points, write_plan_csv,
};
use axiscal::robot::RobotDescription;
use nalgebra::Point3;
use std::path::{Path, PathBuf};

/// Arguments of `axiscal plan`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Nominal robot description (TOML), or a shipped one's name.
    #[arg(long, default_value = "asea-irb6l", value_parser = super::options::ROBOT_FILE)]
    robot: PathBuf,
    /// The axis experiments (TOML: `reference`, `[[sweeps]]`; `docs/formats.md#plan-file`), or
    /// a shipped plan's name. Default: paper Table 1 for a six-joint revolute arm, its
    /// generalisation for any other robot (as `simulate`).
    #[arg(long, value_parser = super::options::PLAN_FILE)]
    plan: Option<PathBuf>,
    /// The span of joint J's sweeps, `J=SPAN` (deg or mm); repeatable.
    #[arg(long, value_name = "J=SPAN", value_parser = joint_value)]
    span: Vec<(usize, f64)>,
    /// Intervals of every sweep (each sweep measures `intervals + 1` poses).
    #[arg(long, value_parser = InRange::closed(2usize, axiscal::plan::MAX_INTERVALS, ""))]
    intervals: Option<usize>,
    /// The order the joints are swept in, e.g. `6,5,4,3,2,1` (every swept joint once).
    #[arg(long, value_delimiter = ',')]
    order: Vec<usize>,
    /// Validation poses (three tool targets each) after the axis experiments. Default: 60, none
    /// for a robot without tool targets.
    #[arg(long, value_parser = InRange::closed(0usize, axiscal::plan::MAX_VALIDATION_POSES, ""))]
    validation_poses: Option<usize>,
    /// Seed of the validation poses' draw.
    #[arg(long, value_parser = super::options::SEED)]
    validation_seed: Option<u64>,
    #[command(flatten)]
    sight: SightArgs,
    /// Choose the spans and the points per sweep that minimise the predicted tool error over
    /// the workspace (`docs/method.md#plans-that-buy-accuracy`), seeded by `--plan` (default
    /// Table 1) at the same number of points; also writes the plan TOML (`--plan-out`).
    #[arg(long)]
    optimize: bool,
    /// With `--optimize`: the axis experiments' total of points (each target at each pose).
    /// Default: the seed plan's (Table 1: 129).
    #[arg(long, value_parser = InRange::closed(8usize, 1_000_000, ""))]
    points: Option<usize>,
    /// With `--optimize`: the workspace, per joint the half-range of commands around the
    /// reference (deg or mm, comma-separated, clipped to the limits). Default: the validation
    /// poses' (IRB/L6: 40,30,35,60,90,90).
    #[arg(long, value_delimiter = ',', value_parser = InRange::above(0.0, 1e6, "deg or mm"))]
    workspace_half_range: Vec<f64>,
    /// With `--optimize`: workspace poses the predicted RMS is taken over (drawn with
    /// `--validation-seed`).
    #[arg(long, default_value_t = 200, value_parser = InRange::closed(1usize, 100_000, ""))]
    workspace_poses: usize,
    /// The instrument's noise, 3-D RMS of a point (mm) (the paper's 0.19): what `--optimize`
    /// predicts with, and what a `--span` too short for `calibrate` is warned against.
    #[arg(long, default_value_t = axiscal::measurement::PAPER_NET_RADIAL_RMS_MM, value_parser = NOISE_MM)]
    noise_mm: f64,
    /// With `--optimize`: the robot's repeatability (rad) the calibration models, one value or
    /// one per joint. Default: the description's `repeatability_sigma`.
    #[arg(long, value_delimiter = ',', value_parser = super::options::REPEATABILITY_RAD)]
    repeatability_rad: Option<Vec<f64>>,
    /// With `--optimize`: the fewest intervals a sweep keeps (its fits need points); at most
    /// what `--points` gives every sweep at once. Default: 8.
    #[arg(long, value_parser = InRange::closed(2usize, 100_000, ""))]
    min_intervals: Option<usize>,
    /// With `--optimize`: the most rounds of the search; 0 predicts the seed plan (`--plan`
    /// at `--points`) without changing it.
    #[arg(long, default_value_t = axiscal::plan::OptimizeOptions::default().max_rounds, value_parser = InRange::closed(0usize, 1000, ""))]
    max_rounds: usize,
    /// With `--optimize`: where to write the optimised plan TOML (`docs/formats.md#plan-file`).
    /// Default: `--out` with the extension `toml`.
    #[arg(long)]
    plan_out: Option<PathBuf>,
    /// Output plan CSV.
    #[arg(long)]
    out: PathBuf,
    /// Replace `--out` if it exists.
    #[arg(long)]
    force: bool,
    /// Skip the unit sanity check of the description's lengths (as `simulate` and `calibrate`
    /// run it).
    #[arg(long)]
    skip_unit_check: bool,
}

fn joint_value(text: &str) -> Result<(usize, f64), String> {
    let (j, v) = text
        .split_once('=')
        .ok_or_else(|| format!("`{text}`: expected J=SPAN, e.g. 2=40"))?;
    let joint = j.trim().parse().map_err(|_| format!("`{j}` is not a joint number"))?;
    let value: f64 = v.trim().parse().map_err(|_| format!("`{v}` is not a number"))?;
    if !(value.is_finite() && value > 0.0) {
        return Err(format!("span {value} must be above 0"));
    }
    Ok((joint, value))
}

/// The line of sight of a measurement plan: what `plan` and `iso9283 plan` share.
#[derive(Debug, clap::Args)]
pub struct SightArgs {
    /// An instrument station `X,Y,Z` in the instrument frame (mm); repeatable. Default: the
    /// description's `[instrument] stations_mm`, else two chosen for the robot, as `simulate`
    /// places them (`docs/formats.md#robot-description`).
    #[arg(long, value_name = "X,Y,Z", value_parser = station_mm, allow_hyphen_values = true)]
    station: Vec<[f64; 3]>,
    /// Leave out the line-of-sight columns.
    #[arg(long)]
    no_sight: bool,
    /// Radius of the links' capsules for the line of sight (mm).
    #[arg(long, default_value_t = axiscal::plan::LINK_RADIUS_M * 1e3, value_parser = InRange::above(0.0, 10_000.0, "mm"))]
    link_radius_mm: f64,
}

impl SightArgs {
    /// The stations (mm): none with `--no-sight`, `--station`s as given, by default the
    /// description's (`plan::instrument_stations_m`, those `simulate` measures from).
    pub fn stations_mm(&self, desc: &RobotDescription) -> Result<Vec<[f64; 3]>> {
        Ok(if self.no_sight {
            vec![]
        } else if self.station.is_empty() {
            instrument_stations_m(desc)
                .context("placing the instrument's stations")?
                .iter()
                .map(|s_m| (s_m.coords * 1e3).map(|c| (c * 10.0).round() / 10.0 + 0.0).into())
                .collect()
        } else {
            if let Some((k, why)) = axiscal::robot::station_problem(&self.station) {
                anyhow::bail!("--station: station {k} (counting from 0) at {why}");
            }
            self.station.clone()
        })
    }

    /// The options of the line-of-sight columns for `desc`.
    pub fn options(&self, desc: &RobotDescription) -> Result<SightOptions> {
        Ok(SightOptions {
            stations_m: self
                .stations_mm(desc)?
                .iter()
                .map(|s| Point3::from(*s) * 1e-3)
                .collect(),
            link_radius_m: self.link_radius_mm * 1e-3,
            stop_short_m: axiscal::plan::sight::STOP_SHORT_M,
        })
    }

    /// The plan's first comment lines: the robot's identity, what the file is, the stations.
    pub fn header_comment(&self, desc: &RobotDescription) -> Result<String> {
        Ok(header_comment(desc, &self.stations_mm(desc)?, self.link_radius_mm))
    }
}

pub(super) fn station_mm(text: &str) -> Result<[f64; 3], String> {
    let v: Vec<f64> = text
        .split(',')
        .map(|c| c.trim().parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect::<Option<_>>()
        .ok_or_else(|| format!("`{text}`: expected X,Y,Z in mm"))?;
    <[f64; 3]>::try_from(v).map_err(|_| format!("`{text}`: expected three numbers X,Y,Z in mm"))
}

/// The plan `simulate` and `plan` use without `--plan`: paper Table 1 for a six-joint revolute
/// arm, [`CalibrationPlan::for_robot`] for any other robot; or the plan file at `path`.
/// The description `robot` must give axis targets for every joint the plan sweeps.
pub fn campaign_plan(desc: &RobotDescription, robot: &Path, path: Option<&Path>) -> Result<CalibrationPlan> {
    let plan = match path {
        Some(path) => inputs::read_plan_file(path, "--plan")?,
        None => CalibrationPlan::default_for(desc),
    };
    axis_targets_for(desc, robot, &plan, path)?;
    if let Some(path) = path {
        plan.validate(desc)
            .with_context(|| format!("{} for {}", path.display(), desc.name))?;
    }
    Ok(plan)
}

/// Refuses a `--span` whose sweep leaves the joint limits, naming the option (the plan's own
/// sweeps are checked where the plan is made).
fn span_within_limits(plan: &CalibrationPlan, args: &Args, desc: &RobotDescription) -> Result<()> {
    if let Err(axiscal::plan::PlanError::OutOfLimits {
        index,
        joint,
        low,
        high,
        limit_low,
        limit_high,
    }) = plan.validate(desc)
        && let Some(&(swept, span)) = args.span.iter().find(|(j, _)| *j == plan.sweeps[index].joint)
    {
        let shown = axiscal::measurement::format_f64;
        bail!(
            "--span {swept}={}: joint {swept}'s sweep of {} {} about the reference pose's {} takes joint {joint}'s commands to \
             {}..{}, beyond its limits {limit_low:.3}..{limit_high:.3}: give a shorter span",
            shown(span),
            shown(span),
            desc.joints[swept - 1].kind.file_unit(),
            shown(plan.reference[swept - 1]),
            shown(low),
            shown(high)
        );
    }
    Ok(())
}

/// The spans of `plan`'s sweeps a user gave, each with where: `--span`'s, and a plan file's
/// (`--plan`) where no `--span` overrides them; a default plan's are not judged.
fn spans_given<'a>(plan: &CalibrationPlan, args: &'a Args) -> Vec<(usize, f64, inputs::SpanGiven<'a>)> {
    let by_option = |j: usize| args.span.iter().any(|&(k, _)| k == j);
    plan.sweeps
        .iter()
        .filter_map(|s| match (&args.plan, by_option(s.joint)) {
            (_, true) => Some((s.joint, s.span, inputs::SpanGiven::Option)),
            (Some(file), false) => Some((s.joint, s.span, inputs::SpanGiven::PlanFile(file))),
            (None, false) => None,
        })
        .collect()
}

/// `plan` with the command line's `--span`, `--intervals` and `--order` applied.
fn adjusted(mut plan: CalibrationPlan, args: &Args, desc: &RobotDescription) -> Result<CalibrationPlan> {
    for (k, &(joint, span)) in args.span.iter().enumerate() {
        if let Some(&(_, earlier)) = args.span[..k].iter().find(|(j, _)| *j == joint) {
            bail!(
                "--span {joint}={span}: joint {joint} given twice (also --span {joint}={earlier}); give each joint once"
            );
        }
        let mut found = false;
        for s in plan.sweeps.iter_mut().filter(|s| s.joint == joint) {
            s.span = span;
            found = true;
        }
        if !found {
            bail!("--span {joint}={span}: the plan sweeps no joint {joint}");
        }
    }
    span_within_limits(&plan, args, desc)?;
    if let Some(n) = args.intervals {
        plan.sweeps.iter_mut().for_each(|s| s.intervals = n);
    }
    if !args.order.is_empty() {
        let mut swept: Vec<usize> = plan.sweeps.iter().map(|s| s.joint).collect();
        swept.dedup();
        let (mut a, mut b) = (swept.clone(), args.order.clone());
        a.sort_unstable();
        b.sort_unstable();
        if a != b {
            bail!("--order {:?}: must name each swept joint {:?} once", args.order, swept);
        }
        let mut sweeps = Vec::new();
        for j in &args.order {
            sweeps.extend(plan.sweeps.iter().filter(|s| s.joint == *j).cloned());
        }
        plan.sweeps = sweeps;
    }
    Ok(plan)
}

/// Runs `axiscal plan`.
pub fn run(args: Args) -> Result<()> {
    let mut outputs = Outputs::new(args.force).input("--robot", &args.robot);
    if let Some(p) = &args.plan {
        outputs = outputs.input("--plan", p);
    }
    outputs.check(&args.out)?;
    let plan_out = args.plan_out.clone().unwrap_or_else(|| args.out.with_extension("toml"));
    if args.optimize {
        if plan_out == args.out {
            bail!(
                "--plan-out {} is the plan CSV --out; choose another path",
                plan_out.display()
            );
        }
        outputs.check(&plan_out)?;
    } else if args.points.is_some() || args.plan_out.is_some() || !args.workspace_half_range.is_empty() {
        bail!("--points, --plan-out and --workspace-half-range need --optimize");
    }
    let desc = RobotDescription::from_file(&args.robot)?;
    super::checks::description_units(&desc, &args.robot, args.skip_unit_check)?;
    let mut plan = adjusted(campaign_plan(&desc, &args.robot, args.plan.as_deref())?, &args, &desc)?;
    let default_validation = ValidationPlan::workspace_default(desc.dof());
    let validation = ValidationPlan {
        poses: validation_poses(args.validation_poses, &desc, &args.robot)?,
        seed: args.validation_seed.unwrap_or(default_validation.seed),
        ..default_validation
    };
    let sight = args.sight.options(&desc)?;
    let mut plan_toml = None;
    if args.optimize {
        plan = optimize::run(&args, &desc, &plan, &validation, &sight)?;
        let text = toml::to_string(&plan).context("writing the optimised plan as TOML")?;
        plan_toml = Some(format!("{}{text}", optimize::toml_comment(&args, &desc)));
    }
    let points = planned_points(&desc, &plan, &validation, &sight).with_context(|| match &args.plan {
        Some(file) => format!(
            "planning the campaign of {} with {}",
            args.robot.display(),
            file.display()
        ),
        None => format!("planning the campaign of {}", args.robot.display()),
    })?;
    let rows: Vec<inputs::Target0Row> = points
        .iter()
        .filter(|p| p.target == 0 && p.moved_joint >= 1)
        .map(|p| inputs::Target0Row {
            experiment: &p.experiment,
            joint: p.moved_joint,
            step: p.step,
            cmd: &p.cmd,
        })
        .collect();
    let on_axis = inputs::on_axis_warnings(&desc, &rows, args.noise_mm);
    // A joint whose target is on its axis is warned of that, not of its span.
    let spans: Vec<_> = spans_given(&plan, &args)
        .into_iter()
        .filter(|(j, ..)| !on_axis.iter().any(|(k, _)| k == j))
        .collect();
    let mut warnings: Vec<String> = on_axis.into_iter().map(|(_, w)| w).collect();
    warnings.extend(inputs::short_span_warnings(&desc, &spans, &points, args.noise_mm));
    super::checks::print_warnings(&warnings);
    let comment = args.sight.header_comment(&desc)?;
    let mut file = outputs.create(&args.out)?;
    write_plan_csv(&mut file, &comment, &points).with_context(|| format!("writing {}", args.out.display()))?;
    // The optimised plan and its CSV are placed together: a signal waits for both.
    super::signals::deferred(|| -> Result<()> {
        if let Some(text) = &plan_toml {
            outputs.write(&plan_out, text)?;
            println!("wrote {}", plan_out.display());
        }
        file.commit()
    })?;
    summarise(&args.out, &points, sight.stations_m.len());
    Ok(())
}

fn header_comment(desc: &RobotDescription, stations_mm: &[[f64; 3]], radius_mm: f64) -> String {
    let stations: Vec<String> = stations_mm
        .iter()
        .enumerate()
        .map(|(k, s)| format!("visible_{} = station ({}, {}, {}) mm", k + 1, s[0], s[1], s[2]))
        .collect();
    let mut text = super::checks::identity_comment(desc);
    text.push_str(&format!(
        "# axiscal measurement plan of {}: one row per point to measure, in order; rows of one pose share it\n",
        desc.name
    ));
    if !stations.is_empty() {
        text.push_str(&format!(
            "# line of sight on the nominal arm (link capsules {radius_mm} mm): {}\n",
            stations.join(", ")
        ));
    }
    text
}

/// Prints what was written: points, poses, and how many are hidden from a station.
pub fn summarise(out: &Path, points: &[axiscal::plan::PlannedPoint], stations: usize) {
    let poses = points.last().map_or(0, |p| p.pose);
    let hidden = points.iter().filter(|p| p.visible.iter().any(|v| !v)).count();
    println!("wrote {} ({} points at {} poses)", out.display(), points.len(), poses);
    if stations > 0 {
        println!("  {hidden} point(s) hidden from at least one station on the nominal arm");
    }
}
