//! `axiscal simulate`: a full Table-1 campaign plus validation poses on a simulated robot,
//! written as a measurement CSV (`docs/formats.md#measurement-csv`).

use super::options::InRange;
use super::output::Outputs;
use super::printer::Printer;
use anyhow::{Context, Result, bail};
use axiscal::kinematics::JointKind;
use axiscal::measurement::{MeasurementModel, MeasurementSet, write_measurements_to};
use axiscal::plan::{CalibrationPlan, PoseConditions, ValidationPlan};
use axiscal::robot::{Controller, RobotDescription, RobotModel};
use axiscal::sim::{AnalyticArm, ArmExecutor, CampaignOptions, CampaignOutput, Effects, simulate_campaign_with};
use axiscal::sim::{RapierArm, RapierArmOptions, SpanSearch, visible_sweep_span};
use nalgebra::Point3;
use rand::{SeedableRng, rngs::ChaCha12Rng};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The shipped default manufacturing errors (`scenarios/robots/default-perturbation.toml`).
fn default_perturbation() -> Result<axiscal::sim::PerturbationSpec> {
    let spec_path = super::options::shipped_or_file("default-perturbation", super::options::PERTURBATION_FILE.0)
        .map_err(anyhow::Error::msg)?;
    Ok(axiscal::sim::PerturbationSpec::from_toml_str(
        &axiscal::presets::read_text(&spec_path)?,
        "default-perturbation.toml",
    )?)
}

/// The shipped description of the paper's robot (`asea-irb6l.toml`).
fn paper_description() -> Result<RobotDescription> {
    Ok(RobotDescription::from_file(
        &super::options::shipped_or_file("asea-irb6l", super::options::ROBOT_FILE.0).map_err(anyhow::Error::msg)?,
    )?)
}

/// The truth without `--truth`: the paper's robot for the ASEA IRB/L6's description, else the
/// description perturbed by the shipped `default-perturbation.toml`, drawn from its own stream of `seed`
/// (the noise's stream is untouched).
fn default_truth(desc: &RobotDescription, seed: u64, printer: Printer) -> Result<RobotModel> {
    let irb6l = paper_description()?;
    if desc.geometry_hash() == irb6l.geometry_hash() {
        return Ok(axiscal::sim::paper_robot());
    }
    let spec = default_perturbation()?;
    let mut rng = ChaCha12Rng::seed_from_u64(seed);
    rng.set_stream(TRUTH_STREAM);
    let truth = axiscal::sim::perturb(desc, &spec, &mut rng)?;
    say!(
        printer,
        "truth: {} perturbed by the default manufacturing errors (scenarios/robots/default-perturbation.toml, seed {seed}); --truth names another",
        desc.name
    );
    Ok(truth)
}

/// The truth `--truth` names: a robot model file, or a robot description, whose nominal model
/// (no manufacturing error) is then the truth (said on the console).
fn truth_file(path: &std::path::Path, printer: Printer) -> Result<RobotModel> {
    match RobotModel::from_file(path) {
        Ok(model) => Ok(model),
        Err(model_error) => match RobotDescription::from_file(path) {
            Ok(desc) => {
                say!(
                    printer,
                    "truth: {}'s nominal model (a robot description: no manufacturing errors; without --truth the description is perturbed by the default errors)",
                    path.display()
                );
                Ok(RobotModel::ideal(&desc))
            }
            Err(_) => Err(model_error.into()),
        },
    }
}

/// Refuses a truth (`--truth`, `path`; `None`: the default one) of another joint count than
/// the description's, and a `--truth` of another robot ([`truth_is_this_robots`]).
fn truth_of_this_robot(truth: &RobotModel, path: Option<&Path>, desc: &RobotDescription, robot: &Path) -> Result<()> {
    if truth.joints.len() != desc.dof() {
        anyhow::bail!(
            "--truth {} has {} joints, the description {} has {}: the truth must be this robot's",
            path.unwrap_or(Path::new("(default)")).display(),
            truth.joints.len(),
            robot.display(),
            desc.dof()
        );
    }
    path.map_or(Ok(()), |path| truth_is_this_robots(truth, path, desc, robot))
}

/// Refuses a `--truth` (`path`) of the description's joint count that is another robot's: a
/// joint of another kind, or a row beyond the manufacturing errors a robot has (counted in
/// those of the paper's measured robot, the shipped `asea-irb6l-paper-truth.toml` against
/// `asea-irb6l.toml`: [`axiscal::sim::largest_departure`]), which the simulated file would
/// carry under the description's name.
fn truth_is_this_robots(truth: &RobotModel, path: &Path, desc: &RobotDescription, robot: &Path) -> Result<()> {
    let kinds = |k: JointKind| match k {
        JointKind::Revolute => "revolute",
        JointKind::Prismatic => "prismatic",
    };
    if let Some(k) = (0..desc.dof()).find(|&k| truth.joints[k].kind != desc.joints[k].kind) {
        anyhow::bail!(
            "--truth {}: joint {} is {}, in the description {} it is {}: the truth must be this robot's (its joint kinds \
             are the description's; a truth file of another robot?)",
            path.display(),
            k + 1,
            kinds(truth.joints[k].kind),
            robot.display(),
            kinds(desc.joints[k].kind)
        );
    }
    let irb6l = paper_description()?;
    let spread = axiscal::sim::row_departure_rms(&axiscal::sim::paper_robot(), &RobotModel::ideal(&irb6l));
    if let Some(d) = axiscal::sim::largest_departure(truth, &RobotModel::ideal(desc), spread) {
        anyhow::bail!(
            "--truth {}: its {} departs from the description {}'s nominal model by {:.3} {}, {:.0} times the RMS \
             manufacturing error of a real robot (the paper's IRB/L6 against its description: {:.2} mm, {:.3} deg; \
             beyond {:.1} times happens once in {:.0} robots): the truth must be this robot's (a truth file of \
             another robot?)",
            path.display(),
            d.field,
            robot.display(),
            d.by,
            d.unit,
            d.spreads,
            spread.0,
            spread.1,
            d.bound,
            1.0 / axiscal::sim::DEPARTURE_FALSE_ALARM
        );
    }
    Ok(())
}

/// Warns of each turning joint whose sweep's described target 0 lies on its own axis
/// ([`super::plan::on_axis_warnings`] at the simulated instrument's noise).
fn warn_of_targets_on_axes(desc: &RobotDescription, set: &MeasurementSet) {
    let rows: Vec<super::plan::Target0Row> = set
        .rows()
        .iter()
        .filter(|m| m.target == 0 && m.moved_joint >= 1)
        .map(|m| super::plan::Target0Row {
            experiment: &m.experiment,
            joint: m.moved_joint,
            step: m.step,
            cmd: &m.cmd,
        })
        .collect();
    let on_axis = super::plan::on_axis_warnings(desc, &rows, axiscal::measurement::PAPER_NET_RADIAL_RMS_MM);
    super::checks::print_warnings(&on_axis.into_iter().map(|(_, w)| w).collect::<Vec<_>>());
}

/// The stream of the default truth's draws (the noise uses stream 0 of the same seed).
const TRUTH_STREAM: u64 = 1;

/// Arguments of `axiscal simulate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Nominal robot description (TOML); the controller and the plan use it.
    #[arg(long, default_value = "asea-irb6l", value_parser = super::options::ROBOT_FILE)]
    robot: PathBuf,
    /// Truth model of the simulated robot (TOML); default: the paper robot (Table 2 actual
    /// rows and the section-4 functions) for the IRB/L6, else the description perturbed by the
    /// shipped default manufacturing errors (`default-perturbation`, drawn with --seed).
    #[arg(long, value_parser = super::options::TRUTH_FILE)]
    truth: Option<PathBuf>,
    /// Measurement noise: two theodolites calibrated to 0.19 mm net radial error at the
    /// description's stations (`plan` counts line of sight from the same), or isotropic
    /// Gaussian noise of the same 3-D RMS.
    #[arg(long, value_enum, default_value_t = Instrument::Theodolite)]
    instrument: Instrument,
    /// A theodolite station `X,Y,Z` in the instrument frame (mm): give both, left then right.
    /// Default: the description's `[instrument] stations_mm`, else two chosen for the robot
    /// (`docs/formats.md#robot-description`); `plan` prints them.
    #[arg(long, value_name = "X,Y,Z", value_parser = super::plan::station_mm, allow_hyphen_values = true)]
    station: Vec<[f64; 3]>,
    /// The campaign plan (TOML: `reference`, `[[sweeps]]`, `held_jitter`;
    /// `docs/formats.md#plan-file`). Default: paper Table 1 for a six-joint revolute arm, its
    /// generalisation for any other robot (each joint swept within its limits).
    #[arg(long, value_parser = super::options::PLAN_FILE)]
    plan: Option<PathBuf>,
    /// Number of validation poses (three tool targets each). Default: 60, none for a robot
    /// without tool targets.
    #[arg(long, value_parser = InRange::closed(0usize, axiscal::plan::MAX_VALIDATION_POSES, ""))]
    validation_poses: Option<usize>,
    /// Seed of the measurement and repeatability noise.
    #[arg(long, value_parser = super::options::SEED, default_value_t = 1)]
    seed: u64,
    /// The simulated robot: the rapier rigid-body arm (line of sight, compliance) or the
    /// analytic truth model.
    #[arg(long, value_enum, default_value_t = Sim::Rapier)]
    sim: Sim,
    /// Unmodelled effects of the simulated robot and instrument (TOML:
    /// `docs/formats.md#effects-file`).
    #[arg(long)]
    effects: Option<PathBuf>,
    /// Print the largest visible span of each axis experiment's targets (rapier arm, the
    /// instrument's stations), centred on the plan's reference pose.
    #[arg(long)]
    report_spans: bool,
    /// Output CSV.
    #[arg(long)]
    out: PathBuf,
    /// Replace `--out` if it exists (otherwise an existing file is an error).
    #[arg(long)]
    force: bool,
    /// Also write a rerun recording of the campaign (robot per pose on the `step` timeline,
    /// measured targets, arc fits, validation errors of the nominal model); view it with
    /// `axiscal view FILE.rrd`. Needs a build with `--features viz`.
    #[arg(long, value_name = "FILE.rrd")]
    record: Option<PathBuf>,
    /// Skip the unit sanity check of the description's lengths and limits and of the
    /// --truth model's rows.
    #[arg(long)]
    skip_unit_check: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Sim {
    Rapier,
    Analytic,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum Instrument {
    Theodolite,
    Isotropic,
}

/// Runs `axiscal simulate`.
pub fn run(args: Args, printer: Printer) -> Result<()> {
    let outputs = [
        ("--truth", &args.truth),
        ("--effects", &args.effects),
        ("--plan", &args.plan),
    ]
    .into_iter()
    .fold(
        Outputs::new(args.force).input("--robot", &args.robot),
        |o, (what, path)| match path {
            Some(p) => o.input(what, p),
            None => o,
        },
    );
    outputs.check(&args.out)?;
    super::record::ensure_recordable(args.record.as_deref(), &outputs)?;
    if let Some(record) = &args.record {
        Outputs::new(true).input("--out", &args.out).check_not_input(record)?;
    }
    let desc = RobotDescription::from_file(&args.robot)?;
    super::checks::description_units(&desc, &args.robot, args.skip_unit_check)?;
    let poses = super::plan::validation_poses(args.validation_poses, &desc, &args.robot)?;
    let plan = super::plan::campaign_plan(&desc, &args.robot, args.plan.as_deref())?;
    let truth = match &args.truth {
        Some(path) => {
            let truth = truth_file(path, printer)?;
            super::checks::truth_units(&truth, path, args.skip_unit_check)?;
            truth
        }
        None => default_truth(&desc, args.seed, printer)?,
    };
    truth_of_this_robot(&truth, args.truth.as_deref(), &desc, &args.robot)?;
    let instrument = instrument_model(args.instrument, &args.station, &desc, &args.robot, printer)?;
    let validation = ValidationPlan {
        poses,
        ..ValidationPlan::workspace_default(desc.dof())
    };
    let effects = match &args.effects {
        Some(path) => Effects::from_file(path, desc.dof())?,
        None => Effects::default(),
    };
    let options = CampaignOptions {
        instrument_scale: effects.instrument_scale,
        ..CampaignOptions::default()
    };
    let rapier_options = RapierArmOptions {
        stations_m: instrument.stations_m(),
        ..RapierArmOptions::new(desc.dof())
    };
    if args.report_spans {
        report_spans(&desc, &truth, &effects, &plan, &rapier_options)?;
    }
    let name = truth.name.clone();
    #[cfg(feature = "viz")]
    let recorded_truth = truth.clone();
    let mut rng = ChaCha12Rng::seed_from_u64(args.seed);
    let out = match args.sim {
        Sim::Analytic => {
            let mut arm = AnalyticArm::new(truth, Controller::from_description(&desc)).with_effects(effects, &desc);
            run_campaign(&desc, &plan, &validation, &mut arm, &instrument, &options, &mut rng)
        }
        Sim::Rapier => {
            let mut arm = RapierArm::new(truth, &desc, effects, rapier_options);
            run_campaign(&desc, &plan, &validation, &mut arm, &instrument, &options, &mut rng)
        }
    }
    .with_context(|| format!("simulating the campaign on {name}"))?;
    let set = MeasurementSet::new(desc.dof(), out.rows).context("assembling the measurement set")?;
    let mut file = outputs.create(&args.out)?;
    file.write_all(super::checks::identity_comment(&desc).as_bytes())
        .and_then(|()| write_measurements_to(&mut file, &set))
        .with_context(|| format!("writing {}", args.out.display()))?;
    file.commit()?;
    println!(
        "wrote {} ({} rows) simulated on {}",
        args.out.display(),
        set.rows().len(),
        name
    );
    print_experiments(&set, &out.occluded);
    warn_of_targets_on_axes(&desc, &set);
    #[cfg(feature = "viz")]
    if let Some(path) = &args.record {
        let campaign = super::record::simulated::Campaign {
            desc: &desc,
            truth: &recorded_truth,
            plan: &plan,
            set: &set,
            instrument: &instrument,
        };
        super::record::save(path, &outputs, || super::record::simulated::write(&campaign))?;
    }
    Ok(())
}

/// The measurement model of `kind` for `desc`: two theodolites at `stations_mm` (none given:
/// the description's, `plan::instrument_stations_m`) calibrated around its base (their
/// calibration printed to stderr with `--verbose`), or isotropic noise.
fn instrument_model(
    kind: Instrument,
    stations_mm: &[[f64; 3]],
    desc: &RobotDescription,
    robot: &Path,
    printer: Printer,
) -> Result<MeasurementModel> {
    let stations_m: Vec<Point3<f64>> = match stations_mm {
        [] => axiscal::plan::instrument_stations_m(desc).context("placing the theodolites")?,
        given => given.iter().map(|s| Point3::from(*s) * 1e-3).collect(),
    };
    Ok(match (kind, stations_m.as_slice()) {
        (Instrument::Theodolite, &[left_m, right_m]) => {
            let (model, calibration) =
                MeasurementModel::theodolites_around([left_m, right_m], &desc.placement.origin_m()).map_err(|e| {
                    let placement = axiscal::plan::placement_among_stations(desc, &[left_m, right_m]);
                    match (stations_mm, placement) {
                        ([], Some(why)) if desc.instrument.is_some() => {
                            anyhow::anyhow!("{}: field `placement.translation_mm`: {why}", robot.display())
                        }
                        ([], _) => anyhow::anyhow!(
                            "{}: {}",
                            axiscal::plan::stations_origin(desc, robot),
                            axiscal::plan::theodolite_stations_problem(&[left_m, right_m], &e)
                        ),
                        _ => anyhow::anyhow!(
                            "--station: {}",
                            axiscal::plan::theodolite_stations_problem(&[left_m, right_m], &e)
                        ),
                    }
                })?;
            if printer.verbose {
                eprintln!("{calibration}");
            }
            model
        }
        (Instrument::Theodolite, other) if !stations_mm.is_empty() => bail!(
            "--station given {} times: the theodolites need two stations; give exactly two (--station X,Y,Z --station X,Y,Z), or --instrument isotropic",
            other.len()
        ),
        (Instrument::Theodolite, other) => bail!(
            "{}: field `instrument.stations_mm`: the theodolites need two stations, {} has {}: give two there, or with --station X,Y,Z --station X,Y,Z, or --instrument isotropic",
            robot.display(),
            desc.name,
            other.len()
        ),
        (Instrument::Isotropic, _) if !stations_mm.is_empty() => {
            bail!("--station: isotropic noise has no stations (every target is seen)")
        }
        (Instrument::Isotropic, _) => MeasurementModel::paper_isotropic(),
    })
}

/// One line per experiment (poses and targets), then the occluded target observations per
/// experiment (`occluded`).
fn print_experiments(set: &MeasurementSet, occluded: &[(String, usize)]) {
    for e in set.experiments() {
        let steps = e.by_step().len();
        let targets: std::collections::BTreeSet<usize> = e.rows.iter().map(|r| r.target).collect();
        println!(
            "  {:<12} moved_joint {}  {:>3} poses x {} target(s)",
            e.name,
            e.moved_joint,
            steps,
            targets.len()
        );
    }
    let total: usize = occluded.iter().map(|(_, n)| n).sum();
    println!("  occluded target observations: {total}");
    for (experiment, n) in occluded {
        println!("  {experiment}: {n} target observation(s) occluded");
    }
}

fn run_campaign<A: ArmExecutor>(
    desc: &RobotDescription,
    plan: &CalibrationPlan,
    validation: &ValidationPlan,
    arm: &mut A,
    instrument: &MeasurementModel,
    options: &CampaignOptions,
    rng: &mut ChaCha12Rng,
) -> Result<CampaignOutput> {
    Ok(simulate_campaign_with(
        desc, plan, validation, arm, instrument, options, rng,
    )?)
}

/// One line per axis experiment: the largest span, centred like the planned sweep, for which
/// every target of the experiment is visible from every station at every step (how the paper
/// chose its Table 1 spans), next to the planned span ([`visible_sweep_span`]). The experiment
/// is executed on the same rapier arm as the campaign (four-bar bodies, effects), without
/// repeatability jitter; 1 deg steps up to the nearer joint limit, the edge bisected.
fn report_spans(
    desc: &RobotDescription,
    truth: &RobotModel,
    effects: &Effects,
    plan: &CalibrationPlan,
    rapier_options: &RapierArmOptions,
) -> Result<()> {
    let mut still = truth.clone();
    for joint in &mut still.joints {
        joint.repeatability_sigma = 0.0;
    }
    let mut arm = RapierArm::new(still, desc, effects.clone(), rapier_options.clone());
    let mut rng = ChaCha12Rng::seed_from_u64(0);
    for sweep in &plan.sweeps {
        let k = sweep.joint - 1;
        let [lo, hi] = desc.limits_internal(k);
        let centre_cmd = plan.reference[k] + sweep.offset_at(0) + sweep.span / 2.0;
        let centre = axiscal::robot::commands_to_internal(desc, &{
            let mut cmd = plan.reference.clone();
            cmd[k] = centre_cmd;
            cmd
        })[k];
        let search = SpanSearch {
            max_half_span_deg: (centre - lo).min(hi - centre).to_degrees().max(0.0),
            ..SpanSearch::default()
        };
        let span_deg = visible_sweep_span(
            &mut arm,
            desc,
            plan,
            sweep,
            &PoseConditions::default(),
            &search,
            &mut rng,
        )
        .with_context(|| format!("searching the visible span of axis {}", sweep.joint))?;
        println!(
            "  span axis{}: largest visible {:.1} deg (planned {:.1} deg)",
            sweep.joint, span_deg, sweep.span
        );
    }
    Ok(())
}
