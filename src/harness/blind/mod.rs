//! Blind check of the diagnoser (`axiscal blind`): draws cases (an effect, its joint and
//! magnitude, a seed; no-effect cases; an out-of-set "unknown" effect), simulates each on the
//! paper robot (analytic or rapier arm, [`Simulator`]), writes the CSV and hides the truth in a separate key,
//! runs [`diagnose`](crate::diagnosis::diagnose) on the CSV alone and scores the answers
//! ([`score`]). This module sees the truth; the diagnoser never does.

mod draw;
mod score;

pub use score::{BlindScore, CaseResult, ConfusionMatrix, ShapeRow, case_table, diagnosed_label, score};

use draw::{
    draw_backlash, draw_compliance, draw_gear_harmonic, draw_instrument_scale, draw_masses, draw_thermal, draw_wobble,
    draw_zero_drift, log_uniform,
};

use crate::measurement::{Measurement, MeasurementModel, MeasurementSet};
use crate::plan::{CalibrationPlan, PoseConditions, ValidationPlan};
use crate::robot::commands_to_internal;
use crate::robot::{Controller, RobotDescription, RobotModel};
use crate::sim::{AnalyticArm, ArmExecutor, CampaignOptions, Effects, simulate_campaign_with};
use rand::{Rng, RngExt, SeedableRng, rngs::ChaCha12Rng};
use serde::{Deserialize, Serialize};

/// Effect names a case can carry (`docs/formats.md#diagnosis-json`), plus `unknown`: an effect outside the
/// candidate set, which the diagnoser should call `unexplained` (alternately a joint zero that
/// drifts with temperature, [`JointZeroDrift`], and a curvature of the instrument's field,
/// [`InstrumentSag`]).
pub const CASE_EFFECTS: [&str; 9] = [
    "none",
    "joint_compliance",
    "backlash",
    "thermal_expansion",
    "gear_harmonic",
    "axis_wobble",
    "instrument_scale",
    "unknown",
    TWO_EFFECTS,
];

/// The two-effect case: a joint compliance and a backlash at once (both from the upper part of
/// their ranges), expected as `backlash+joint_compliance` (the names of the diagnosis'
/// `effects`, sorted) with both on their joints.
pub const TWO_EFFECTS: &str = "backlash+joint_compliance";

/// The second effect of a two-effect case.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct SecondEffect {
    /// Effect name.
    pub effect: String,
    /// Its joint, if any.
    pub joint: Option<usize>,
    /// Magnitude in `magnitude_unit`.
    pub magnitude: f64,
    /// Unit of `magnitude`.
    pub magnitude_unit: String,
}

/// The hidden truth of one case (`key.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CaseKey {
    /// Case index.
    pub case: usize,
    /// Effect drawn (one of [`CASE_EFFECTS`]).
    pub effect: String,
    /// What a perfect diagnoser answers: the effect, `unexplained` for `unknown`.
    pub expected: String,
    /// Joint of the effect, if any.
    pub joint: Option<usize>,
    /// Magnitude in the effect's unit (`magnitude_unit`).
    pub magnitude: f64,
    /// Unit of `magnitude`.
    pub magnitude_unit: String,
    /// Seed of the simulation (pose draw, noise, jitter).
    pub seed: u64,
    /// The effects given to the simulator.
    pub effects: Effects,
    /// An out-of-set instrument error, if any.
    #[serde(default)]
    pub sag: Option<InstrumentSag>,
    /// An out-of-set joint zero drift, if any.
    #[serde(default)]
    pub drift: Option<JointZeroDrift>,
    /// The second effect of a two-effect case.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub second: Option<SecondEffect>,
    /// The drawn member of the effect's family (e.g. `order_1_fixed`), `-` without one.
    #[serde(default)]
    pub shape: String,
}

/// An out-of-set joint error: the zero of `joint`'s encoder drifts with the ambient
/// temperature, so at `T` the actuator stands `rad_per_k (T - 20)` away from where the same
/// command put it at 20 deg C (the axis experiments' temperature); the passive couplings
/// follow the actuator. The thermal-expansion candidate scales lengths, never turns a joint.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct JointZeroDrift {
    /// 1-based joint.
    pub joint: usize,
    /// \[rad/K\] of the joint's own displacement.
    pub rad_per_k: f64,
}

/// An out-of-set instrument error: a paraboloid sag of the measured field, every measured
/// point moved down by `curvature_per_m |p_xy|^2` (`p_xy` its horizontal distance from the
/// instrument origin).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct InstrumentSag {
    /// \[1/m\]: the sag in metres per square metre of horizontal distance.
    pub curvature_per_m: f64,
}

impl InstrumentSag {
    /// Applies the sag to a measured position \[mm\].
    fn apply_mm(&self, p: &mut [f64; 3]) {
        let r2_m2 = (p[0] * p[0] + p[1] * p[1]) * 1e-6;
        p[2] -= self.curvature_per_m * r2_m2 * 1e3;
    }
}

/// The paper robot's rated payload \[kg\] (the ASEA IRB 6 handles 6 kg), the largest
/// validation payload of a blind case.
pub const PAYLOAD_MAX_KG: f64 = 6.0;

/// Settings of the generator.
#[derive(Clone, Debug, PartialEq)]
pub struct BlindOptions {
    /// Validation poses per case (>= 100 for the suite).
    pub validation_poses: usize,
    /// Measurement noise, 3-D RMS \[mm\] (isotropic instrument).
    pub noise_rms_3d_mm: f64,
    /// Validation temperatures are drawn uniformly in `20 +- temperature_half_range_c`.
    pub temperature_half_range_c: f64,
    /// Validation payloads \[kg\] are drawn uniformly in `[0, payload_max_kg]`, the mass
    /// centred on the tool frame's origin (the axis experiments carry none). Without a
    /// payload change a joint-2 sag is a function of joint 2's angle alone (the four-bar takes
    /// link 3's moment to actuator 3), which the calibration fits into joint 2's transmission:
    /// it is visible only when the arm nearly buckles under its own weight.
    pub payload_max_kg: f64,
    /// The simulated robot.
    pub simulator: Simulator,
    /// Whether the truth re-positions with its repeatability jitter (the paper robot's
    /// `repeatability_sigma`, which the description gives the diagnoser and `calibrate`
    /// models). Off only for the noise-free trace of [`detectable_size`].
    pub repeatability: bool,
    /// The robot and what is measured.
    pub campaign: BlindCampaign,
}

/// The campaign of a blind suite: which robot, measured how.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BlindCampaign {
    /// The paper robot (description `asea-irb6l`, truth `asea-irb6l-paper-truth`): the Table-1
    /// axis experiments and the tool observation at 20 deg C without payload, then the
    /// validation poses.
    #[default]
    Sweeps,
    /// The six-axis DH arm (description `arm6-dh`, truth `arm6-dh-truth`, no passive
    /// coupling): the validation poses alone, which the diagnoser splits into training poses
    /// (its free-pose calibration) and held-out ones. Needs [`Simulator::Analytic`].
    FreePoses,
}

/// The fewest validation poses of a [`BlindCampaign::FreePoses`] case: the diagnoser calibrates
/// from its training half (every other pose, `diagnosis::split`), which needs
/// [`MIN_POSES`](crate::calibration::free_pose::MIN_POSES) poses.
pub const MIN_FREE_POSES: usize = 2 * crate::calibration::free_pose::MIN_POSES - 1;

impl BlindCampaign {
    /// The shipped description the diagnoser is given.
    pub fn description(self) -> RobotDescription {
        let (text, path) = shipped(self.names().0);
        RobotDescription::from_toml_str(text, std::path::Path::new(path))
            .expect("the shipped blind-suite descriptions are valid (checked by tests)")
    }

    /// The shipped truth the simulator runs.
    pub fn truth(self) -> RobotModel {
        let (text, path) = shipped(self.names().1);
        RobotModel::from_toml_str(text, std::path::Path::new(path))
            .expect("the shipped blind-suite truths are valid (checked by tests)")
    }

    /// The names of its shipped description and truth.
    pub fn names(self) -> (&'static str, &'static str) {
        match self {
            BlindCampaign::Sweeps => ("asea-irb6l", "asea-irb6l-paper-truth"),
            BlindCampaign::FreePoses => ("arm6-dh", "arm6-dh-truth"),
        }
    }
}

/// The text and source path of the shipped file `name`.
fn shipped(name: &str) -> (&'static str, &'static str) {
    let p = crate::presets::PRESETS
        .iter()
        .find(|p| p.name == name)
        .expect("the blind suites' robots are shipped");
    (p.text, p.source_path)
}

/// The simulated robot of a blind suite.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Simulator {
    /// [`AnalyticArm`]: the truth's kinematics with the effects to first order (compliance
    /// by `coupled_first_order_deflection`).
    #[default]
    Analytic,
    /// [`crate::sim::RapierArm`]: rapier bodies, the four-bar as bodies, compliance by the
    /// servos' static equilibrium.
    Rapier,
}

impl Default for BlindOptions {
    fn default() -> Self {
        BlindOptions {
            validation_poses: 100,
            noise_rms_3d_mm: 0.19,
            temperature_half_range_c: 10.0,
            payload_max_kg: PAYLOAD_MAX_KG,
            simulator: Simulator::Analytic,
            repeatability: true,
            campaign: BlindCampaign::Sweeps,
        }
    }
}

/// Draws case `case` of a suite seeded `seed`: effects cycle through [`CASE_EFFECTS`]
/// (so every effect appears), joints and magnitudes are random.
pub fn draw_case(seed: u64, case: usize, desc: &RobotDescription) -> CaseKey {
    let case_seed = crate::harness::scenario::trial_seed(seed, case);
    let mut rng = ChaCha12Rng::seed_from_u64(case_seed ^ 0x5eed_b11d);
    let effect = CASE_EFFECTS[case % CASE_EFFECTS.len()];
    draw_effect(effect, case, case_seed, desc, &mut rng)
}

/// A case with a given effect (magnitudes drawn from `rng`).
pub fn draw_effect<R: Rng + ?Sized>(
    effect: &str,
    case: usize,
    seed: u64,
    desc: &RobotDescription,
    rng: &mut R,
) -> CaseKey {
    // Magnitudes are log-uniform over ranges spanning each effect's detectable size on this
    // campaign (from about a third of it to ten times it; `docs/diagnosis.md`, "Blind check").
    let dof = desc.dof();
    let mut e = Effects::default();
    let mut sag = None;
    let mut drift = None;
    let mut second = None;
    let phase = rng.random_range(0.0..std::f64::consts::TAU);
    // Every case's truth has its own link masses and payload centre (they load only a
    // compliant joint).
    draw_masses(rng, desc, &mut e);
    let (joint, magnitude, unit) = match effect {
        "joint_compliance" => draw_compliance(rng, desc, false, &mut e),
        "backlash" => draw_backlash(rng, dof, false, &mut e),
        TWO_EFFECTS => {
            let first = draw_compliance(rng, desc, true, &mut e);
            let (joint, magnitude, unit) = draw_backlash(rng, dof, true, &mut e);
            second = Some(SecondEffect {
                effect: "backlash".into(),
                joint,
                magnitude,
                magnitude_unit: unit.into(),
            });
            first
        }
        "thermal_expansion" => draw_thermal(rng, dof, &mut e),
        "gear_harmonic" => draw_gear_harmonic(rng, desc, phase, &mut e),
        "axis_wobble" => {
            let w = draw_wobble(rng, dof, [4.0e-4, 1.0e-2], phase);
            e.wobble.push(w);
            (Some(w.joint), w.amplitude_rad, "rad")
        }
        "unknown" if (case / CASE_EFFECTS.len()) % 2 == 1 => {
            let c = log_uniform(rng, 2.0e-4, 2.0e-3);
            sag = Some(InstrumentSag { curvature_per_m: c });
            (None, c, "1/m (instrument sag)")
        }
        "unknown" => draw_zero_drift(rng, dof, &mut drift),
        "instrument_scale" => draw_instrument_scale(rng, &mut e),
        _ => (None, 0.0, "-"),
    };
    CaseKey {
        case,
        shape: shape_of(&e),
        effect: effect.to_owned(),
        expected: if effect == "unknown" {
            "unexplained".into()
        } else {
            effect.to_owned()
        },
        joint,
        magnitude,
        magnitude_unit: unit.into(),
        seed,
        effects: e,
        sag,
        drift,
        second,
    }
}

/// The family member an effect set's shapes belong to (`docs/diagnosis.md`, "Blind check").
fn shape_of(e: &Effects) -> String {
    let mut parts = Vec::new();
    if let Some(w) = e.wobble.first() {
        let kind = if w.fixed_direction_rad.is_some() {
            "fixed"
        } else {
            "rotating"
        };
        parts.push(format!("order_{}_{kind}", w.order));
    }
    if let Some(h) = e.gear_harmonics.first() {
        let period = match h.period {
            crate::physics::HarmonicPeriod::Transmission => "transmission",
            crate::physics::HarmonicPeriod::Joint => "joint",
        };
        parts.push(format!("order_{}_{period}", h.order));
    }
    if let Some(t) = &e.thermal {
        parts.push(
            if t.alpha_per_k_rows.is_empty() {
                "uniform"
            } else {
                "per_link"
            }
            .into(),
        );
    }
    if let Some(b) = &e.backlash {
        parts.push(match b.direction {
            crate::physics::ApproachSource::Command => "command_direction".into(),
            crate::physics::ApproachSource::Actuator => "actuator_direction".into(),
        });
    }
    if let Some(c) = &e.compliance {
        let stiff = c.stiffness_nm_per_rad.iter().position(|k| *k < 1e12);
        if stiff == Some(1) {
            // The drawn fractions are exactly 1, exactly 0, or in 0.2-0.8.
            let f = c.reflected_fraction;
            let path = if f >= 1.0 {
                "mechanism_load"
            } else if f <= 0.0 {
                "serial_load"
            } else {
                "mixed_load"
            };
            parts.push(path.into());
        }
        if c.balancer_fraction.iter().any(|f| *f > 0.0) {
            parts.push("balancer".into());
        }
        parts.push("other_masses".into());
    }
    if parts.is_empty() { "-".into() } else { parts.join("+") }
}

/// Why a blind case could not be simulated or sized.
#[derive(Debug, thiserror::Error)]
pub enum BlindError {
    /// The axis experiments' simulation failed.
    #[error("{0}")]
    Campaign(crate::sim::CampaignError),
    /// A validation pose could not be executed.
    #[error("{0}")]
    Execute(crate::sim::ExecuteError),
    /// A target could not be measured.
    #[error("{0}")]
    Measure(crate::measurement::TriangulationError),
    /// The simulated rows do not make a measurement set.
    #[error("{0}")]
    Set(crate::measurement::MeasurementSetError),
    /// The noise-free baseline refit failed.
    #[error("{0}")]
    Diagnosis(crate::diagnosis::DiagnosisError),
}

/// Simulates a case: the Table-1 axis experiments and the tool observation at 20 deg C without
/// payload, then `validation_poses` workspace poses at random temperatures and payloads
/// ([`BlindOptions`]), on the paper robot through the options' [`Simulator`] with the case's
/// effects and its repeatability jitter (unless `options.repeatability` is off; a
/// [`JointZeroDrift`] offsets the executed command), measured with isotropic noise (and the
/// instrument scale error or sag, if any).
pub fn simulate_case(
    key: &CaseKey,
    desc: &RobotDescription,
    options: &BlindOptions,
) -> Result<MeasurementSet, BlindError> {
    let mut truth = options.campaign.truth();
    if !options.repeatability {
        for j in &mut truth.joints {
            j.repeatability_sigma = 0.0;
        }
    }
    // The validation payloads sit where the key puts them (default: the tool frame's origin;
    // they load only compliant joints).
    let effects = Effects {
        payload: Some(key.effects.payload.unwrap_or_default()),
        ..key.effects.clone()
    };
    match options.simulator {
        Simulator::Analytic => {
            let mut arm = AnalyticArm::new(truth, Controller::from_description(desc)).with_effects(effects, desc);
            simulate_on(&mut arm, key, desc, options)
        }
        Simulator::Rapier => {
            let options_rapier = crate::sim::RapierArmOptions::new(desc.dof());
            let mut arm = crate::sim::RapierArm::new(truth, desc, effects, options_rapier);
            simulate_on(&mut arm, key, desc, options)
        }
    }
}

fn simulate_on<A: ArmExecutor>(
    arm: &mut A,
    key: &CaseKey,
    desc: &RobotDescription,
    options: &BlindOptions,
) -> Result<MeasurementSet, BlindError> {
    let instrument = MeasurementModel::Isotropic(crate::measurement::IsotropicNoise {
        net_radial_rms_mm: options.noise_rms_3d_mm,
    });
    let plan = match options.campaign {
        BlindCampaign::Sweeps => CalibrationPlan::table1(desc.dof()),
        BlindCampaign::FreePoses => CalibrationPlan::default_for(desc),
    };
    let mut rng = ChaCha12Rng::seed_from_u64(key.seed);
    let mut rows = match options.campaign {
        BlindCampaign::Sweeps => {
            let none = ValidationPlan {
                poses: 0,
                ..ValidationPlan::workspace_default(desc.dof())
            };
            let campaign = CampaignOptions {
                conditions: PoseConditions::default(),
                instrument_scale: key.effects.instrument_scale,
            };
            simulate_campaign_with(desc, &plan, &none, arm, &instrument, &campaign, &mut rng)
                .map_err(BlindError::Campaign)?
                .rows
        }
        BlindCampaign::FreePoses => Vec::new(),
    };
    let validation = ValidationPlan {
        poses: options.validation_poses,
        seed: key.seed ^ 0x7a11,
        ..ValidationPlan::workspace_default(desc.dof())
    };
    let scale = 1.0 + key.effects.instrument_scale.map_or(0.0, |s| s.ppm * 1e-6);
    for (step, cmd) in validation.commands(desc, &plan.reference).into_iter().enumerate() {
        let conditions = PoseConditions {
            temperature_c: 20.0 + rng.random_range(-1.0..=1.0) * options.temperature_half_range_c,
            payload_kg: rng.random_range(0.0..=1.0) * options.payload_max_kg,
        };
        let mut executed = commands_to_internal(desc, &cmd);
        if let Some(d) = &key.drift {
            executed[d.joint - 1] += d.rad_per_k * (conditions.temperature_c - PoseConditions::default().temperature_c);
        }
        let links = arm
            .execute(&executed, &conditions, &mut rng)
            .map_err(BlindError::Execute)?;
        let tool = links[desc.dof() - 1] * arm.last_link_from_tool();
        for (id, t) in desc.tool_targets_m().iter().enumerate() {
            let p = instrument.measure(&(tool * t), &mut rng).map_err(BlindError::Measure)?;
            rows.push(Measurement {
                experiment: "validation".into(),
                moved_joint: 0,
                step,
                target: id,
                position_mm: [p.x * 1e3 * scale, p.y * 1e3 * scale, p.z * 1e3 * scale],
                cmd: cmd.clone(),
                payload_kg: conditions.payload_kg,
                temperature_c: conditions.temperature_c,
            });
        }
    }
    if let Some(sag) = &key.sag {
        for m in &mut rows {
            sag.apply_mm(&mut m.position_mm);
        }
    }
    MeasurementSet::new(desc.dof(), rows).map_err(BlindError::Set)
}

/// An effect whose noise-free trace after the baseline refit is below this fraction of the
/// detectable gap is absorbed by the refit, not small: [`detectable_size`] reports it as
/// unobservable. Rounding argument: the refit's arc fits stop within about `sqrt(1e-10)` =
/// 1e-5 standard deviations of their optimum (`calibration::arc_ml`'s negligible decrease),
/// which moves the predictions by at most ~1e-5 of the noise per coordinate, and the
/// detectable gap is of the noise's order (0.08-0.10 mm for 0.11 mm per coordinate); a trace
/// below 1e-5 of it is the fit's own stopping tolerance. A uniform instrument scale traces
/// ~1e-11 mm (every length of the refit scales with it), the smallest drawn in-set effect
/// (a third of its detectable size) ~3e-2 mm: nine orders of magnitude either side.
pub const ABSORBED_TRACE_FRACTION: f64 = 1e-5;

/// How large a case's effect is against what the diagnoser can see: its trace after the
/// baseline refit (held-out RMS of the baseline on the case simulated WITHOUT noise and
/// without repeatability jitter) over the
/// smallest gap the diagnoser's gap test flags (`detectable_gap_mm`, from its diagnosis of
/// the noisy case), and the magnitude at which that ratio is 1 (the trace is linear in the
/// effect: in its magnitude, or in the compliance `1 / stiffness`). `None` without an effect.
/// An effect the refit absorbs (trace below [`ABSORBED_TRACE_FRACTION`] of the detectable
/// gap, e.g. a uniform instrument scale when every length is fitted) has ratio 0 and no
/// detectable magnitude (`None`): no magnitude makes it visible on this campaign.
pub fn detectable_size(
    key: &CaseKey,
    desc: &RobotDescription,
    options: &BlindOptions,
    diagnosis: &crate::diagnosis::DiagnosisOptions,
    detectable_gap_mm: f64,
) -> Result<Option<(f64, Option<f64>)>, BlindError> {
    if key.effect == "none" {
        return Ok(None);
    }
    let clean = BlindOptions {
        noise_rms_3d_mm: 0.0,
        repeatability: false,
        ..options.clone()
    };
    let set = simulate_case(key, desc, &clean)?;
    let trace_mm = crate::diagnosis::baseline_heldout_rms_mm(&set, desc, diagnosis).map_err(BlindError::Diagnosis)?;
    if trace_mm < ABSORBED_TRACE_FRACTION * detectable_gap_mm {
        return Ok(Some((0.0, None)));
    }
    let ratio = trace_mm / detectable_gap_mm;
    let magnitude = if key.effect == "joint_compliance" {
        key.magnitude * ratio
    } else {
        key.magnitude / ratio
    };
    Ok(Some((ratio, Some(magnitude))))
}
