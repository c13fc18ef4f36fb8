//! Resolution: scenario file + command-line overrides -> one checked, self-contained
//! [`ResolvedScenario`] (the robot, truth and instrument inlined, the sweep expanded into
//! cases), in the manner of ripgrep's low-level -> high-level arguments. The resolved scenario
//! is what runs, what is dumped to `results/<name>/scenario.resolved.toml`, and what
//! `axiscal merge` reads back.

use super::error::ScenarioError;
use super::file::{
    ConditionsSection, Instrument, IsoSection, MeasurementSection, PlanSection, ScenarioFile, SimMode, SweepSection,
    TruthSection,
};
use super::threshold::Threshold;
use crate::measurement::{
    IsotropicNoise, MAX_PAYLOAD_KG, MeasurementModel, TEMPERATURE_RANGE_C, TheodolitePair, format_f64, format_f64_list,
};
use crate::plan::{CalibrationPlan, ValidationPlan};
use crate::robot::{RobotDescription, RobotModel};
use crate::sim::Effects;
use crate::sim::{PerturbationSpec, perturb};
use nalgebra::Point3;
use rand::{SeedableRng, rngs::ChaCha12Rng};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Command-line values that replace the file's.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Overrides {
    /// Trials per case.
    pub trials: Option<usize>,
    /// Scenario seed.
    pub seed: Option<u64>,
}

/// The simulated real robot of every trial.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ResolvedTruth {
    /// The same robot in every trial.
    Fixed {
        /// The truth model.
        robot: Box<RobotModel>,
    },
    /// A robot drawn per trial around the nominal description.
    Perturbed {
        /// The distributions.
        perturbation: Box<PerturbationSpec>,
    },
}

/// One case of a scenario: one value of the swept parameter.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Case {
    /// `base`, or `<parameter>=<value>`.
    pub name: String,
    /// The instrument.
    pub measurement: MeasurementModel,
    /// The calibration plan.
    pub plan: CalibrationPlan,
}

/// A checked, self-contained scenario (see module docs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ResolvedScenario {
    /// Name (results folder).
    pub name: String,
    /// What it studies.
    pub description: String,
    /// Trials per case.
    pub trials: usize,
    /// Scenario seed.
    pub seed: u64,
    /// Simulator.
    pub sim: SimMode,
    /// The histogram metric.
    pub main_metric: String,
    /// Unmodelled effects.
    pub effects: Effects,
    /// Pose conditions.
    pub conditions: ConditionsSection,
    /// Rapier line of sight on.
    pub occlusion: bool,
    /// Pass/fail criteria.
    pub thresholds: Vec<Threshold>,
    /// The largest fraction of a case's trials that may fail (a verdict per case).
    #[serde(default)]
    pub max_failure_rate: f64,
    /// The nominal robot (what the controller, the plan and the calibrator know).
    pub robot: RobotDescription,
    /// The real robot.
    pub truth: ResolvedTruth,
    /// Validation poses.
    pub validation: ValidationPlan,
    /// The cases, in sweep order.
    pub cases: Vec<Case>,
    /// The ISO 9283 test after each calibration, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub iso9283: Option<IsoSection>,
}

/// Metric plotted when the file names none.
pub const DEFAULT_MAIN_METRIC: &str = "uncal_pos_rms_mm";

/// A threshold beyond this, in any metric's unit, is a slip: no metric reaches it.
const MAX_THRESHOLD: f64 = 1e9;

impl ResolvedScenario {
    /// Reads `path` and resolves it with `overrides`.
    pub fn from_file(path: &Path, overrides: Overrides) -> Result<Self, ScenarioError> {
        Self::from_file_with_slips(path, overrides).map(|(scenario, _)| scenario)
    }

    /// [`Self::from_file`] with the file's likely unit slips
    /// ([`super::units::scenario_slips`]), for the caller to refuse or to skip.
    pub fn from_file_with_slips(
        path: &Path,
        overrides: Overrides,
    ) -> Result<(Self, Vec<crate::measurement::unit_check::UnitSlip>), ScenarioError> {
        let file: ScenarioFile = crate::toml_file::parse_own(
            &crate::toml_file::read(path)?,
            path,
            crate::toml_file::OwnToml::Scenario,
        )?;
        let scenario = Self::resolve(file.clone(), path, overrides)?;
        let slips = super::units::scenario_slips(&file, &scenario);
        Ok((scenario, slips))
    }

    /// Resolves a parsed file; `path` locates relative paths and labels errors.
    pub fn resolve(file: ScenarioFile, path: &Path, overrides: Overrides) -> Result<Self, ScenarioError> {
        let invalid = |key: &str, message: String| ScenarioError::Invalid {
            path: path.to_owned(),
            key: key.to_owned(),
            message,
        };
        let dir = path.parent().unwrap_or(Path::new("."));
        let robot = match &file.robot {
            Some(p) => RobotDescription::from_file(&dir.join(p)).map_err(|e| invalid("robot", e.to_string()))?,
            None => RobotDescription::asea_irb6l(),
        };
        let trials = overrides.trials.unwrap_or(file.trials);
        if trials == 0 {
            return Err(invalid("trials", "must be at least 1".into()));
        }
        file.effects
            .validate(robot.dof())
            .map_err(|e| invalid("effects", e.to_string()))?;
        check_conditions(&file.conditions).map_err(|(k, m)| invalid(k, m))?;

        let truth = resolve_truth(&file.truth, &robot, dir).map_err(|(k, m)| invalid(k, m))?;
        let validation = file
            .validation
            .clone()
            .unwrap_or_else(|| ValidationPlan::workspace_default(robot.dof()));
        validation.check(robot.dof()).map_err(|(k, m)| invalid(k, m))?;
        if file.validation.is_some() {
            validation.check_limits(&robot).map_err(|(k, m)| invalid(k, m))?;
        }
        let cases = resolve_cases(&file, &robot, dir).map_err(|(k, m)| invalid(&k, m))?;
        check_size(&file, trials, cases.len()).map_err(|(k, m)| invalid(k, m))?;
        for (i, t) in file.thresholds.iter().enumerate() {
            if !(t.value.is_finite() && t.value.abs() <= MAX_THRESHOLD) {
                return Err(invalid(
                    &format!("thresholds[{i}].value"),
                    format!(
                        "{} must be finite and within +-{MAX_THRESHOLD:e} (no metric reaches it)",
                        format_f64(t.value)
                    ),
                ));
            }
            if let Some(c) = &t.case
                && !cases.iter().any(|k| &k.name == c)
            {
                let names: Vec<&str> = cases.iter().map(|k| k.name.as_str()).collect();
                return Err(invalid(
                    &format!("thresholds[{i}].case"),
                    format!("no case {c:?} (cases: {names:?})"),
                ));
            }
        }
        if let Some(iso) = &file.iso9283 {
            check_iso(iso, &robot).map_err(|(k, m)| invalid(k, m))?;
            check_iso_cube(iso, &robot, &cases).map_err(|(k, m)| invalid(k, m))?;
        }
        let name = file.name.clone().unwrap_or_else(|| {
            path.file_stem()
                .map_or_else(|| "scenario".into(), |s| s.to_string_lossy().into_owned())
        });
        if name.is_empty()
            || name == "."
            || name == ".."
            || name.contains(['/', '\\'])
            || name.chars().any(char::is_control)
        {
            return Err(invalid(
                "name",
                format!(
                    "{name:?} is not a folder name of its own under results/ (not `.` or `..`, no `/`, `\\` or control characters)"
                ),
            ));
        }
        Ok(ResolvedScenario {
            name,
            description: file.description.clone(),
            trials,
            seed: overrides.seed.unwrap_or(file.seed),
            sim: file.sim,
            main_metric: file.main_metric.clone().unwrap_or_else(|| DEFAULT_MAIN_METRIC.into()),
            effects: file.effects.clone(),
            conditions: file.conditions,
            occlusion: file.occlusion,
            thresholds: file.thresholds.clone(),
            max_failure_rate: file.max_failure_rate,
            robot,
            truth,
            validation,
            cases,
            iso9283: file.iso9283.clone(),
        })
    }

    /// Checks that the thresholds and the main metric name metrics the trial produces.
    pub fn check_metrics(&self, names: &[String], path: &Path) -> Result<(), ScenarioError> {
        let known = |m: &str| names.iter().any(|n| n == m);
        let invalid = |key: String, m: &str| ScenarioError::Invalid {
            path: path.to_owned(),
            key,
            message: format!("unknown metric {m:?} (metrics: {})", names.join(", ")),
        };
        if !known(&self.main_metric) {
            return Err(invalid("main_metric".into(), &self.main_metric));
        }
        for (i, t) in self.thresholds.iter().enumerate() {
            if !known(&t.metric) {
                return Err(invalid(format!("thresholds[{i}].metric"), &t.metric));
            }
        }
        Ok(())
    }

    /// Total number of trial units (`cases x trials`); unit `u` is trial `u % trials` of case
    /// `u / trials`.
    pub fn units(&self) -> usize {
        self.cases.len() * self.trials
    }

    /// The resolved scenario as TOML (the dump in the results folder).
    pub fn to_toml(&self) -> Result<String, toml::ser::Error> {
        toml::to_string(self)
    }

    /// Reads a dumped resolved scenario (e.g. a shard's).
    pub fn from_resolved_file(path: &Path) -> Result<Self, ScenarioError> {
        Ok(crate::toml_file::parse(&crate::toml_file::read(path)?, path)?)
    }
}

/// The most trial units (`cases x trials`) a run may have: every finished trial's record is
/// kept in memory for the summary (about 150 bytes with the campaign's ten metrics).
pub const MAX_UNITS: usize = 100_000_000;

/// `max_failure_rate` is a fraction, and `trials x cases` fits [`MAX_UNITS`].
fn check_size(file: &ScenarioFile, trials: usize, cases: usize) -> Result<(), (&'static str, String)> {
    let rate = file.max_failure_rate;
    if !(0.0..=1.0).contains(&rate) {
        return Err((
            "max_failure_rate",
            format!("must be in 0..=1 (a fraction of the trials), got {}", format_f64(rate)),
        ));
    }
    if trials.saturating_mul(cases) > MAX_UNITS {
        return Err((
            "trials",
            format!(
                "{trials} trials x {cases} case(s) exceed the limit of {MAX_UNITS} trial runs (each kept in memory \
                 for the summary); split the study into several scenarios or seeds"
            ),
        ));
    }
    Ok(())
}

fn resolve_truth(
    truth: &TruthSection,
    robot: &RobotDescription,
    dir: &Path,
) -> Result<ResolvedTruth, (&'static str, String)> {
    Ok(match truth {
        TruthSection::Paper {} => ResolvedTruth::Fixed {
            robot: Box::new(of_this_robot(crate::sim::paper_robot(), robot, "truth")?),
        },
        TruthSection::File { path } => {
            let model = RobotModel::from_file(&dir.join(path)).map_err(|e| ("truth.path", e.to_string()))?;
            ResolvedTruth::Fixed {
                robot: Box::new(of_this_robot(model, robot, "truth.path")?),
            }
        }
        TruthSection::Perturbed { perturbation } => {
            // One throw-away draw checks the spec against the robot before any trial runs.
            perturb(robot, perturbation, &mut ChaCha12Rng::seed_from_u64(0))
                .map_err(|e| ("truth.perturbation", e.to_string()))?;
            ResolvedTruth::Perturbed {
                perturbation: perturbation.clone(),
            }
        }
    })
}

/// `truth`, refused (under `key`) when its joints are not `robot`'s: another count or another
/// kind (a truth of another robot; every trial would fail on it).
fn of_this_robot(
    truth: RobotModel,
    robot: &RobotDescription,
    key: &'static str,
) -> Result<RobotModel, (&'static str, String)> {
    if truth.dof() != robot.dof() {
        return Err((
            key,
            format!(
                "the truth has {} joints, the robot {} has {}: the truth must be this robot's",
                truth.dof(),
                robot.name,
                robot.dof()
            ),
        ));
    }
    let kind = |k: crate::kinematics::JointKind| format!("{k:?}").to_lowercase();
    match (0..robot.dof()).find(|&k| truth.joints[k].kind != robot.joints[k].kind) {
        Some(k) => Err((
            key,
            format!(
                "the truth's joint {} is {}, the robot {}'s is {}: the truth must be this robot's",
                k + 1,
                kind(truth.joints[k].kind),
                robot.name,
                kind(robot.joints[k].kind)
            ),
        )),
        None => Ok(truth),
    }
}

type KeyError = (String, String);

fn resolve_cases(file: &ScenarioFile, robot: &RobotDescription, dir: &Path) -> Result<Vec<Case>, KeyError> {
    let base_plan = base_plan(&file.plan, robot)?;
    let robot_file = file.robot.as_ref().map(|p| dir.join(p));
    let drafts = match &file.sweep {
        Some(sweep) => distinct(swept_cases(sweep, file.measurement, &base_plan, dir)?)?,
        None => vec![Draft {
            name: "base".into(),
            measurement: file.measurement,
            plan: base_plan,
            keys: ("plan", NOISE),
        }],
    };
    drafts
        .into_iter()
        .map(|d| {
            d.plan
                .validate(robot)
                .map_err(|e| (d.keys.0.to_owned(), e.to_string()))?;
            some_sweep(&d, file.plan.sweeps.is_some())?;
            coupling_measured(&d, file.plan.sweeps.is_some(), robot)?;
            Ok(Case {
                name: d.name,
                measurement: measurement_model(&d.measurement, robot, robot_file.as_deref())
                    .map_err(|(key, e)| (key.unwrap_or(d.keys.1).to_owned(), e))?,
                plan: d.plan,
            })
        })
        .collect()
}

/// Refuses two cases of a sweep with one label (a value given twice, two plan files of one
/// name): the summary's rows and a threshold's `case` could not tell them apart.
fn distinct(drafts: Vec<Draft>) -> Result<Vec<Draft>, KeyError> {
    for (i, d) in drafts.iter().enumerate() {
        if let Some(first) = drafts[..i].iter().position(|e| e.name == d.name) {
            let (parameter, value) = d.name.split_once('=').unwrap_or((d.name.as_str(), ""));
            let key = if parameter == "plan" { "plans" } else { parameter };
            return Err((
                format!("sweep.{key}"),
                format!(
                    "{value} is given twice (values {first} and {i}): each value is one case, labelled by it \
                     (`{}`); give each value once (more trials of a case: raise `trials`)",
                    d.name
                ),
            ));
        }
    }
    Ok(drafts)
}

/// Refuses a case whose plan has no sweep: a trial calibrates from the axis experiments, so
/// every trial would fail. `written` as for [`coupling_measured`].
fn some_sweep(d: &Draft, written: bool) -> Result<(), KeyError> {
    if !d.plan.sweeps.is_empty() {
        return Ok(());
    }
    let key = match d.keys.0 {
        "sweep.plans" => "sweep.plans",
        _ if written => "plan.sweeps",
        _ => d.keys.0,
    };
    Err((
        key.to_owned(),
        format!(
            "case `{}`: the plan has no sweep, and a trial calibrates from its axis experiments, so every trial \
             would fail: give `[[plan.sweeps]]` (one per joint at least), or leave `plan.sweeps` out for the \
             robot's default plan",
            d.name
        ),
    ))
}

/// Refuses a case whose plan sweeps a joint whose coupling the description fits without a
/// sweep of it that measures the second target ([`CalibrationPlan::unmeasured_coupling`]):
/// every trial's calibration would fail. `written` says whether the file gives
/// `[[plan.sweeps]]` (else the default plan is at fault, or the case's plan file).
fn coupling_measured(d: &Draft, written: bool, robot: &RobotDescription) -> Result<(), KeyError> {
    let Some((i, joint)) = d.plan.unmeasured_coupling(robot) else {
        return Ok(());
    };
    let key = match d.keys.0 {
        "sweep.plans" => "sweep.plans".to_owned(),
        _ if written => format!("plan.sweeps[{i}].second_target"),
        _ => "plan.sweeps".to_owned(),
    };
    let fix = if robot.axis_targets_of(joint).is_some_and(|t| t.target1.is_some()) {
        format!("set `second_target = true` on a sweep of joint {joint}")
    } else {
        format!(
            "give the robot's `[[axis_targets]]` of joint {joint} a `target1`, or leave the coupling's `fit` out of \
             the description"
        )
    };
    Err((
        key,
        format!(
            "case `{}`: joint {joint} drives a coupling into joint {} that the description fits (`couplings[].fit`), \
             and calibrate measures it from target 1 in a sweep of joint {joint} with `second_target = true`; no sweep \
             of joint {joint} has it, so every trial would fail: {fix}",
            d.name,
            joint + 1
        ),
    ))
}

/// The key blamed for a bad instrument when the case keeps the file's.
const NOISE: &str = "measurement.net_radial_rms_mm";

/// A case before its checks: its name, instrument and plan, with the keys blamed for a bad
/// plan and for a bad instrument.
struct Draft {
    name: String,
    measurement: MeasurementSection,
    plan: CalibrationPlan,
    keys: (&'static str, &'static str),
}

/// The cases of a `[sweep]` section: exactly one of its lists, one case per value, each a
/// variation of the file's `measurement` and `base_plan` (plan files relative to `dir`).
fn swept_cases(
    sweep: &SweepSection,
    measurement: MeasurementSection,
    base_plan: &CalibrationPlan,
    dir: &Path,
) -> Result<Vec<Draft>, KeyError> {
    let set = [
        sweep.net_radial_rms_mm.is_some(),
        sweep.span_scale.is_some(),
        sweep.spans.is_some(),
        sweep.plans.is_some(),
    ];
    let count = set.iter().filter(|s| **s).count();
    if count != 1 {
        return Err((
            "sweep".into(),
            format!("set exactly one of net_radial_rms_mm, span_scale, spans, plans (found {count})"),
        ));
    }
    let draft = |name: String, measurement, plan, keys| Draft {
        name,
        measurement,
        plan,
        keys,
    };
    if let Some(values) = &sweep.net_radial_rms_mm {
        let keys = ("plan", "sweep.net_radial_rms_mm");
        return Ok(nonempty(values, "sweep.net_radial_rms_mm")?
            .iter()
            .map(|v| {
                let m = MeasurementSection {
                    net_radial_rms_mm: *v,
                    ..measurement
                };
                draft(format!("net_radial_rms_mm={v}"), m, base_plan.clone(), keys)
            })
            .collect());
    }
    if let Some(values) = &sweep.span_scale {
        return nonempty(values, "sweep.span_scale")?
            .iter()
            .map(|v| {
                let plan = scaled(base_plan, *v).map_err(|e| ("sweep.span_scale".to_owned(), e.to_string()))?;
                Ok(draft(
                    format!("span_scale={v}"),
                    measurement,
                    plan,
                    ("sweep.span_scale", NOISE),
                ))
            })
            .collect();
    }
    if let Some(lists) = &sweep.spans {
        return nonempty(lists, "sweep.spans")?
            .iter()
            .enumerate()
            .map(|(i, spans)| {
                if spans.len() != base_plan.sweeps.len() {
                    let found = format!(
                        "list {i} has {} spans, the plan has {} sweeps",
                        spans.len(),
                        base_plan.sweeps.len()
                    );
                    return Err(("sweep.spans".into(), found));
                }
                let mut plan = base_plan.clone();
                for (s, span) in plan.sweeps.iter_mut().zip(spans) {
                    s.span = *span;
                }
                Ok(draft(format!("spans={i}"), measurement, plan, ("sweep.spans", NOISE)))
            })
            .collect();
    }
    let paths = sweep.plans.as_deref().unwrap_or_default();
    nonempty(paths, "sweep.plans")?
        .iter()
        .map(|path| {
            let path = dir.join(path);
            let key = || "sweep.plans".to_owned();
            let text = crate::toml_file::read(&path).map_err(|e| (key(), e.to_string()))?;
            let plan: CalibrationPlan = crate::toml_file::parse_own(&text, &path, crate::toml_file::OwnToml::Plan)
                .map_err(|e| (key(), e.to_string()))?;
            let stem = path
                .file_stem()
                .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
            Ok(draft(format!("plan={stem}"), measurement, plan, ("sweep.plans", NOISE)))
        })
        .collect()
}

fn nonempty<'a, T>(values: &'a [T], key: &str) -> Result<&'a [T], KeyError> {
    if values.is_empty() {
        Err((key.to_owned(), "needs at least one value".into()))
    } else {
        Ok(values)
    }
}

fn base_plan(section: &PlanSection, robot: &RobotDescription) -> Result<CalibrationPlan, KeyError> {
    let table1 = CalibrationPlan::default_for(robot);
    let plan = CalibrationPlan {
        reference: section.reference.clone().unwrap_or(table1.reference),
        sweeps: section.sweeps.clone().unwrap_or(table1.sweeps),
        held_jitter: None,
    };
    scaled(&plan, section.span_scale).map_err(|e| ("plan.span_scale".into(), e.to_string()))
}

/// A span scale that is not finite and positive.
#[derive(Debug, thiserror::Error)]
#[error("span scale {} must be finite and > 0", format_f64(*.0))]
struct NotAScale(f64);

/// `plan` with every sweep's span and start times `scale`.
fn scaled(plan: &CalibrationPlan, scale: f64) -> Result<CalibrationPlan, NotAScale> {
    if !(scale.is_finite() && scale > 0.0) {
        return Err(NotAScale(scale));
    }
    let mut plan = plan.clone();
    for s in &mut plan.sweeps {
        s.span *= scale;
        s.start = s.start.map(|x| x * scale);
    }
    Ok(plan)
}

/// The instrument of a measurement section: theodolites at the description's stations
/// calibrated over the 2 m cube around the robot's placement, or isotropic noise. An error
/// blames `robot` (the description `robot_file`, or the default robot's) when its stations are
/// at fault, else (`None`) the case's instrument key.
fn measurement_model(
    m: &MeasurementSection,
    robot: &RobotDescription,
    robot_file: Option<&Path>,
) -> Result<MeasurementModel, (Option<&'static str>, String)> {
    let rms_mm = m.net_radial_rms_mm;
    let most = crate::calibration::procedure::MAX_NOISE_RMS_3D_MM;
    if !(rms_mm.is_finite() && rms_mm > 0.0 && rms_mm <= most) {
        return Err((
            None,
            format!(
                "net radial error {} mm must be above 0 and at most {most} mm (a 3-D RMS, as --noise-mm: no \
                 instrument that measures a robot is noisier)",
                format_f64(rms_mm)
            ),
        ));
    }
    let stations_fault = |message: String| {
        let origin = robot_file.map_or_else(
            || "the default robot".to_owned(),
            |f| crate::plan::stations_origin(robot, f),
        );
        (Some("robot"), format!("{origin}: {message}"))
    };
    Ok(match m.instrument {
        Instrument::Isotropic => MeasurementModel::Isotropic(IsotropicNoise {
            net_radial_rms_mm: rms_mm,
        }),
        Instrument::Theodolite => {
            let stations_m = crate::plan::instrument_stations_m(robot)
                .map_err(|e| stations_fault(format!("placing the theodolites: {e}")))?;
            let [left_m, right_m] = <[Point3<f64>; 2]>::try_from(stations_m).map_err(|s| {
                stations_fault(format!(
                    "the theodolites need two stations, {} has {}",
                    robot.name,
                    s.len()
                ))
            })?;
            let (pair, _) =
                TheodolitePair::around_robot_base([left_m, right_m], &robot.placement.origin_m(), rms_mm * 1e-3)
                    .map_err(|e| {
                        match crate::plan::placement_among_stations(robot, &[left_m, right_m])
                            .filter(|_| robot.instrument.is_some())
                        {
                            Some(why) => (
                                Some("robot"),
                                format!(
                                    "{}: field `placement.translation_mm`: {why}",
                                    robot_file
                                        .map_or_else(|| "the default robot".to_owned(), |f| f.display().to_string())
                                ),
                            ),
                            None => stations_fault(crate::plan::theodolite_stations_problem(&[left_m, right_m], &e)),
                        }
                    })?;
            MeasurementModel::Theodolite(pair)
        }
    })
}

/// Where a scenario's results go by default: `results/<name>`.
pub fn default_results_dir(name: &str) -> PathBuf {
    Path::new("results").join(name)
}

/// The `[conditions]` within the physical ranges a measurement file's rows are held to
/// ([`MAX_PAYLOAD_KG`], [`TEMPERATURE_RANGE_C`]).
fn check_conditions(c: &ConditionsSection) -> Result<(), (&'static str, String)> {
    if !(0.0..=MAX_PAYLOAD_KG).contains(&c.payload_kg) {
        return Err((
            "conditions.payload_kg",
            format!(
                "{} kg must be in 0..={MAX_PAYLOAD_KG} kg (no robot carries more than 10 t)",
                format_f64(c.payload_kg)
            ),
        ));
    }
    let [coldest, hottest] = TEMPERATURE_RANGE_C;
    if !(coldest..=hottest).contains(&c.temperature_c) {
        return Err((
            "conditions.temperature_c",
            format!(
                "{} deg C must be in {coldest}..={hottest} deg C (the ambient a robot is measured in)",
                format_f64(c.temperature_c)
            ),
        ));
    }
    Ok(())
}

/// The `[iso9283]` cube of every case planned on the nominal model, as each trial plans it on
/// its calibrated one ([`crate::iso9283::cube_of_edge`], [`crate::iso9283::largest_cube`]): a
/// cube out of reach fails here, once, not in every trial. The key and the problem otherwise.
fn check_iso_cube(iso: &IsoSection, robot: &RobotDescription, cases: &[Case]) -> Result<(), (&'static str, String)> {
    use crate::iso9283::{check_cube_robot, cube_of_edge, largest_cube};
    check_cube_robot(robot).map_err(|e| ("iso9283", e.to_string()))?;
    let compensator = crate::compensation::Compensator::new(&RobotModel::ideal(robot), robot)
        .map_err(|e| ("iso9283", e.to_string()))?;
    let mut centres: Vec<(&[f64], &str)> = match &iso.centre_cmd {
        Some(c) => vec![(c.as_slice(), "iso9283.centre_cmd")],
        None => cases
            .iter()
            .map(|c| (c.plan.reference.as_slice(), "plan.reference"))
            .collect(),
    };
    centres.dedup_by(|a, b| a.0 == b.0);
    for (centre, source) in centres {
        let planned = match iso.edge_mm {
            Some(mm) => cube_of_edge(&compensator, robot, centre, mm * 1e-3),
            None => largest_cube(&compensator, robot, centre, 0.5),
        };
        if let Err(e) = planned {
            let key = if iso.edge_mm.is_some() {
                "iso9283.edge_mm"
            } else {
                source
            };
            return Err((
                key,
                format!(
                    "the ISO cube around the centre commands {} ({source}), planned on the nominal model: {}",
                    format_f64_list(centre),
                    e.to_string().replace("(--edge-mm)", "(iso9283.edge_mm)")
                ),
            ));
        }
    }
    Ok(())
}

/// The `[iso9283]` section's values in their ranges (the centre within `robot`'s limits): the key and
/// the problem otherwise.
fn check_iso(iso: &IsoSection, robot: &RobotDescription) -> Result<(), (&'static str, String)> {
    let dof = robot.dof();
    if !(2..=1000).contains(&iso.cycles) {
        return Err(("iso9283.cycles", format!("must be 2 to 1000, got {}", iso.cycles)));
    }
    if !(1..=10_000).contains(&iso.prediction_trials) {
        return Err((
            "iso9283.prediction_trials",
            format!("must be 1 to 10000, got {}", iso.prediction_trials),
        ));
    }
    if let Some(e) = iso.edge_mm
        && !(e.is_finite() && e > 0.0 && e <= 1e5)
    {
        return Err((
            "iso9283.edge_mm",
            format!("must be above 0 and at most 100000 mm, got {}", format_f64(e)),
        ));
    }
    if let Some(c) = &iso.centre_cmd {
        if c.len() != dof {
            return Err((
                "iso9283.centre_cmd",
                format!("gives {} values; the robot has {dof} joints", c.len()),
            ));
        }
        if c.iter().any(|v| !v.is_finite()) {
            return Err(("iso9283.centre_cmd", "values must be finite".into()));
        }
        if let Some((k, j)) = robot
            .joints
            .iter()
            .enumerate()
            .find(|(k, j)| !(j.limits[0]..=j.limits[1]).contains(&c[*k]))
        {
            return Err((
                "iso9283.centre_cmd",
                format!(
                    "joint {}'s {} {} is outside its limits {}..{}: the cube's centre must be a pose the robot reaches",
                    k + 1,
                    format_f64(c[k]),
                    j.kind.file_unit(),
                    format_f64(j.limits[0]),
                    format_f64(j.limits[1])
                ),
            ));
        }
    }
    Ok(())
}
