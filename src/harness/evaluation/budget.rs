//! The paper's gap budget: for each candidate unmodelled effect, the
//! magnitude that raises the simulated calibrated position error of the paper robot inside the
//! spans from its noise-limited value to the 1.40 mm the paper measured after calibration.
//!
//! Each effect is scaled by one magnitude, the same on every joint it applies to, and put into
//! the real robot of the paper scenario (campaign *and* test poses; [`PaperScenario::effects`]):
//!
//! | effect | magnitude | what changes |
//! |---|---|---|
//! | compliance | compliance `1/K` \[rad/(N m)\], reported as the stiffness `K` | every joint sags by `Q_gravity / K` |
//! | backlash | dead band \[rad\] | every joint lags half a band behind its approach direction |
//! | thermal | temperature rise between calibration and use \[K\] (steel, 1.2e-5/K) | link lengths |
//! | gear harmonic | amplitude of an order-2 sine term of every transmission \[rad\] (the calibrator fits order 1) | joint angles |
//! | wobble | order-2 tilt amplitude of every axis \[rad\] | link poses |
//! | instrument scale | \[ppm\] | every measured coordinate (calibration *and* test) |
//!
//! The error is the mean observed tool-point error over the test poses inside the spans and
//! over `seeds` campaigns (common random numbers: the same seeds and test poses at every
//! magnitude, so the curve is smooth in the magnitude). The magnitude is found by bracketing
//! (doubling from a first guess) and bisection on that curve; an effect that does not reach
//! the target within its search cap is reported as such (e.g. an instrument scale error, which
//! the same instrument hides again in the test).

use super::accuracy::Stats;
use super::paper::{PAPER_POSITION_ERROR_MM, PaperScenario, ScenarioError, calibrated_position_error_inside_spans};
use crate::physics::{AxisWobble, BacklashEffect, ComplianceEffect, GearHarmonic, InstrumentScale, ThermalEffect};
use crate::plan::PoseConditions;
use crate::sim::Effects;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Steel's linear expansion coefficient \[1/K\].
pub const STEEL_ALPHA_PER_K: f64 = 1.2e-5;

/// The candidate effects of the budget (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum BudgetEffect {
    /// Joint compliance under gravity.
    Compliance,
    /// Backlash.
    Backlash,
    /// Thermal growth between calibration and use.
    Thermal,
    /// Order-2 transmission harmonic.
    GearHarmonic,
    /// Order-2 axis wobble.
    Wobble,
    /// Instrument scale error.
    InstrumentScale,
}

impl BudgetEffect {
    /// Every candidate, in report order.
    pub const ALL: [BudgetEffect; 6] = [
        BudgetEffect::Compliance,
        BudgetEffect::Backlash,
        BudgetEffect::Thermal,
        BudgetEffect::GearHarmonic,
        BudgetEffect::Wobble,
        BudgetEffect::InstrumentScale,
    ];

    /// Name as in the effects files.
    pub fn name(self) -> &'static str {
        match self {
            BudgetEffect::Compliance => "compliance",
            BudgetEffect::Backlash => "backlash",
            BudgetEffect::Thermal => "thermal",
            BudgetEffect::GearHarmonic => "gear_harmonic",
            BudgetEffect::Wobble => "wobble",
            BudgetEffect::InstrumentScale => "instrument_scale",
        }
    }

    /// Unit of the searched magnitude.
    pub fn unit(self) -> &'static str {
        match self {
            BudgetEffect::Compliance => "rad/(N m)",
            BudgetEffect::Backlash | BudgetEffect::GearHarmonic | BudgetEffect::Wobble => "rad",
            BudgetEffect::Thermal => "K",
            BudgetEffect::InstrumentScale => "ppm",
        }
    }

    /// First guess of the bracket and the cap of the search (magnitude units): each cap is
    /// beyond anything physical for a working robot and instrument (a 1 kN m/rad joint, a 3 deg
    /// band, 200 K, 3 deg gear or tilt terms, 1 mm per metre of scale), so "not reached" means
    /// the effect cannot explain the gap.
    fn search(self) -> (f64, f64) {
        match self {
            BudgetEffect::Compliance => (1e-7, 1e-3),
            BudgetEffect::Backlash => (1e-4, 0.05),
            BudgetEffect::Thermal => (1.0, 200.0),
            BudgetEffect::GearHarmonic => (1e-4, 0.05),
            BudgetEffect::Wobble => (1e-5, 0.05),
            BudgetEffect::InstrumentScale => (10.0, 1000.0),
        }
    }

    /// The scenario's effects and test-pose temperature at `magnitude`, for a robot of `dof`
    /// joints.
    pub fn apply(self, magnitude: f64, dof: usize, scenario: &mut PaperScenario) {
        let every = |v: f64| vec![v; dof];
        let mut effects = Effects::default();
        let mut temperature_c = PoseConditions::default().temperature_c;
        match self {
            BudgetEffect::Compliance => {
                effects.compliance = Some(ComplianceEffect::new(
                    every(1.0 / magnitude.max(f64::MIN_POSITIVE)),
                    [0.0, 0.0, -9.81],
                ))
            }
            BudgetEffect::Backlash => {
                effects.backlash = Some(BacklashEffect {
                    band_rad: every(magnitude),
                    direction: Default::default(),
                })
            }
            BudgetEffect::Thermal => {
                effects.thermal = Some(ThermalEffect::uniform(STEEL_ALPHA_PER_K, temperature_c));
                temperature_c += magnitude;
            }
            BudgetEffect::GearHarmonic => {
                effects.gear_harmonics = (1..=dof)
                    .map(|joint| GearHarmonic {
                        joint,
                        order: 2,
                        sin_rad: magnitude,
                        cos_rad: 0.0,
                        period: Default::default(),
                    })
                    .collect()
            }
            BudgetEffect::Wobble => {
                effects.wobble = (1..=dof)
                    .map(|joint| AxisWobble {
                        joint,
                        amplitude_rad: magnitude,
                        phase_rad: 0.0,
                        order: 2,
                        fixed_direction_rad: None,
                    })
                    .collect()
            }
            BudgetEffect::InstrumentScale => effects.instrument_scale = Some(InstrumentScale { ppm: magnitude }),
        }
        scenario.effects = effects;
        scenario.evaluation_temperature_c = temperature_c;
    }
}

/// Settings of [`gap_budget`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BudgetSettings {
    /// The scenario every magnitude is run on (its effects are replaced); seeds
    /// `scenario.seed .. scenario.seed + seeds` are pooled.
    pub scenario: PaperScenario,
    /// Campaigns pooled per magnitude.
    pub seeds: u64,
    /// The mean error to reach \[mm\]; the paper's 1.40 by default.
    pub target_mean_mm: f64,
    /// Bisection steps after bracketing.
    pub bisection_steps: usize,
}

impl BudgetSettings {
    /// The paper's target (1.40 mm) on `scenario`, `seeds` campaigns, 10 bisection steps
    /// (magnitude to 0.1 % of the bracket).
    pub fn paper(scenario: PaperScenario, seeds: u64) -> Self {
        BudgetSettings {
            scenario,
            seeds,
            target_mean_mm: PAPER_POSITION_ERROR_MM[1],
            bisection_steps: 10,
        }
    }
}

/// `budget.json`: the settings and one line per effect.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BudgetReport {
    /// The settings.
    pub settings: BudgetSettings,
    /// One line per effect.
    pub lines: Vec<BudgetLine>,
}

/// One line of the budget.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BudgetLine {
    /// The effect.
    pub effect: BudgetEffect,
    /// Unit of `magnitude`.
    pub unit: String,
    /// The magnitude reaching the target, if one below the search cap does.
    pub magnitude: Option<f64>,
    /// Largest magnitude tried.
    pub largest_tried: f64,
    /// Mean error \[mm\] at the magnitude found (or at the largest tried).
    pub mean_mm: f64,
    /// Pooled error statistics without the effect \[mm\].
    pub without_effect: Stats,
}

/// Pooled statistics of the observed position error inside the spans over the settings'
/// seeds, with `effect` at `magnitude` (rayon over seeds; the pooling is in seed order, so the
/// result does not depend on the thread count).
pub fn pooled_error(settings: &BudgetSettings, effect: Option<(BudgetEffect, f64)>) -> Result<Stats, ScenarioError> {
    let per_seed: Vec<Stats> = (0..settings.seeds)
        .into_par_iter()
        .map(|i| {
            let mut s = settings.scenario.clone();
            s.seed = settings.scenario.seed.wrapping_add(i);
            match effect {
                Some((e, m)) => e.apply(m, 6, &mut s),
                None => s.effects = Effects::default(),
            }
            calibrated_position_error_inside_spans(&s)
        })
        .collect::<Result<_, _>>()?;
    Ok(Stats::pooled(&per_seed))
}

/// The magnitude of `effect` that brings the pooled mean error to the target (module docs).
pub fn budget_line(settings: &BudgetSettings, effect: BudgetEffect) -> Result<BudgetLine, ScenarioError> {
    let without_effect = pooled_error(settings, None)?;
    let mean_at = |m: f64| pooled_error(settings, Some((effect, m))).map(|s| s.mean);
    let (guess, cap) = effect.search();
    let target = settings.target_mean_mm;
    let line = |magnitude, largest_tried, mean_mm| BudgetLine {
        effect,
        unit: effect.unit().to_owned(),
        magnitude,
        largest_tried,
        mean_mm,
        without_effect,
    };
    if without_effect.mean >= target {
        return Ok(line(Some(0.0), 0.0, without_effect.mean));
    }
    let (mut lo, mut hi) = (0.0, guess);
    let mut at_hi = mean_at(hi)?;
    while at_hi < target {
        if hi >= cap {
            return Ok(line(None, hi, at_hi));
        }
        lo = hi;
        hi = (hi * 2.0).min(cap);
        at_hi = mean_at(hi)?;
    }
    let stop = crate::numerics::roots::Bisection::steps(settings.bisection_steps);
    // `at_hi` follows `hi`: the mean where the bracket's upper end last moved.
    [_, hi] = crate::numerics::roots::bisect(lo, hi, stop, |mid| {
        let at_mid = mean_at(mid)?;
        if at_mid >= target {
            at_hi = at_mid;
        }
        Ok::<_, ScenarioError>(at_mid < target)
    })?;
    Ok(line(Some(hi), hi, at_hi))
}

/// The whole budget: one line per effect of `effects`.
pub fn gap_budget(settings: &BudgetSettings, effects: &[BudgetEffect]) -> Result<Vec<BudgetLine>, ScenarioError> {
    gap_budget_with(settings, effects, &crate::progress::Silent)
}

/// [`gap_budget`], counting the effects done on `progress`.
pub fn gap_budget_with(
    settings: &BudgetSettings,
    effects: &[BudgetEffect],
    progress: &dyn crate::progress::Progress,
) -> Result<Vec<BudgetLine>, ScenarioError> {
    progress.start(effects.len(), "effects");
    effects
        .iter()
        .map(|e| {
            let line = budget_line(settings, *e);
            progress.inc();
            line
        })
        .collect()
}
