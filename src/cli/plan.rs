//! `axiscal plan --robot R --out PLAN.csv`: the measurement plan for a real robot
//! (`docs/formats.md#measurement-plan`): every point to measure with every joint's command,
//! the target, its nominal position and whether each station should see it. The choice of
//! poses (`--plan`, `--span`, `--intervals`, `--order`, `--validation-poses`) is made here;
//! the writer (`axiscal::plan::write_plan_csv`) takes any list of points.

use super::options::InRange;
use super::output::Outputs;
use anyhow::{Context, Result, bail};
use axiscal::kinematics::JointKind;
use axiscal::measurement::PAPER_RIGHT_STATION_MM;
use axiscal::plan::{CalibrationPlan, SightOptions, ValidationPlan, planned_points, write_plan_csv};
use axiscal::robot::RobotDescription;
use nalgebra::Point3;
use std::path::{Path, PathBuf};

/// Arguments of `axiscal plan`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Nominal robot description (TOML), or a shipped one's name.
    #[arg(long, default_value = "asea-irb6l", value_parser = super::options::robot_file)]
    robot: PathBuf,
    /// The axis experiments (TOML: `reference`, `[[sweeps]]`; `docs/formats.md#plan-file`), or
    /// a shipped plan's name. Default: paper Table 1 for a six-joint revolute arm, its
    /// generalisation for any other robot (as `simulate`).
    #[arg(long, value_parser = super::options::robot_file)]
    plan: Option<PathBuf>,
    /// The span of joint J's sweeps, `J=SPAN` (deg or mm); repeatable.
    #[arg(long, value_name = "J=SPAN", value_parser = joint_value)]
    span: Vec<(usize, f64)>,
    /// Intervals of every sweep (each sweep measures `intervals + 1` poses).
    #[arg(long, value_parser = InRange::closed(2usize, 100_000, ""))]
    intervals: Option<usize>,
    /// The order the joints are swept in, e.g. `6,5,4,3,2,1` (every swept joint once).
    #[arg(long, value_delimiter = ',')]
    order: Vec<usize>,
    /// Validation poses (three tool targets each) after the axis experiments.
    #[arg(long, default_value_t = 60, value_parser = InRange::closed(0usize, 1_000_000, ""))]
    validation_poses: usize,
    /// Seed of the validation poses' draw.
    #[arg(long)]
    validation_seed: Option<u64>,
    /// An instrument station `X,Y,Z` in the instrument frame \[mm\]; repeatable. Default: the
    /// paper's two theodolites (origin and `-6284.6,0,0`).
    #[arg(long, value_name = "X,Y,Z", value_parser = station_mm)]
    station: Vec<[f64; 3]>,
    /// Leave out the line-of-sight columns.
    #[arg(long)]
    no_sight: bool,
    /// Radius of the links' capsules for the line of sight \[mm\].
    #[arg(long, default_value_t = 50.0, value_parser = InRange::above(0.0, 10_000.0, "mm"))]
    link_radius_mm: f64,
    /// Output plan CSV.
    #[arg(long)]
    out: PathBuf,
    /// Replace `--out` if it exists.
    #[arg(long)]
    force: bool,
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

fn station_mm(text: &str) -> Result<[f64; 3], String> {
    let v: Vec<f64> = text
        .split(',')
        .map(|c| c.trim().parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect::<Option<_>>()
        .ok_or_else(|| format!("`{text}`: expected X,Y,Z in mm"))?;
    <[f64; 3]>::try_from(v).map_err(|_| format!("`{text}`: expected three numbers X,Y,Z in mm"))
}

/// The plan `simulate` and `plan` use without `--plan`: paper Table 1 for a six-joint revolute
/// arm, [`CalibrationPlan::for_robot`] for any other robot; or the plan file at `path`.
pub fn campaign_plan(desc: &RobotDescription, path: Option<&Path>) -> Result<CalibrationPlan> {
    Ok(match path {
        Some(path) => {
            let text = axiscal::toml_file::read(path)?;
            axiscal::toml_file::parse::<CalibrationPlan>(&text, path)?
        }
        None if desc.dof() == 6 && desc.joints.iter().all(|j| j.kind == JointKind::Revolute) => {
            CalibrationPlan::table1(6)
        }
        None => CalibrationPlan::for_robot(desc),
    })
}

/// `plan` with the command line's `--span`, `--intervals` and `--order` applied.
fn adjusted(mut plan: CalibrationPlan, args: &Args) -> Result<CalibrationPlan> {
    for &(joint, span) in &args.span {
        let mut found = false;
        for s in plan.sweeps.iter_mut().filter(|s| s.joint == joint) {
            s.span = span;
            found = true;
        }
        if !found {
            bail!("--span {joint}={span}: the plan sweeps no joint {joint}");
        }
    }
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
    let desc = RobotDescription::from_file(&args.robot)?;
    let plan = adjusted(campaign_plan(&desc, args.plan.as_deref())?, &args)?;
    let default_validation = ValidationPlan::workspace_default(desc.dof());
    let validation = ValidationPlan {
        poses: args.validation_poses,
        seed: args.validation_seed.unwrap_or(default_validation.seed),
        ..default_validation
    };
    let stations_mm = if args.no_sight {
        vec![]
    } else if args.station.is_empty() {
        vec![[0.0; 3], PAPER_RIGHT_STATION_MM]
    } else {
        args.station.clone()
    };
    let sight = SightOptions {
        stations_m: stations_mm.iter().map(|s| Point3::from(*s) * 1e-3).collect(),
        link_radius_m: args.link_radius_mm * 1e-3,
        stop_short_m: 2e-3,
    };
    let points = planned_points(&desc, &plan, &validation, &sight)
        .with_context(|| format!("planning the campaign of {}", args.robot.display()))?;
    let comment = header_comment(&desc, &stations_mm, args.link_radius_mm);
    let mut file = outputs.create(&args.out)?;
    write_plan_csv(&mut file, &comment, &points).with_context(|| format!("writing {}", args.out.display()))?;
    file.commit()?;
    summarise(&args.out, &points, stations_mm.len());
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

fn summarise(out: &Path, points: &[axiscal::plan::PlannedPoint], stations: usize) {
    let poses = points.last().map_or(0, |p| p.pose);
    let hidden = points.iter().filter(|p| p.visible.iter().any(|v| !v)).count();
    println!("wrote {} ({} points at {} poses)", out.display(), points.len(), poses);
    if stations > 0 {
        println!("  {hidden} point(s) hidden from at least one station on the nominal arm");
    }
}
