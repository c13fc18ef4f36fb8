//! Monte-Carlo scenarios: a scenario file (`scenarios/*.toml`) resolved into a checked plan,
//! trials run in parallel with per-trial seeds, per-case statistics, pass/fail thresholds,
//! and results written per format.
//!
//! - [`file`](mod@file): the TOML a user writes ([`ScenarioFile`], `deny_unknown_fields`, units in
//!   key names); [`resolve`]: CLI overrides + file -> [`ResolvedScenario`] (self-contained,
//!   dumped to the results folder, read back by `axiscal merge`).
//! - [`seed`]: trial seed = SplitMix64 mix of the scenario seed and the trial index.
//! - [`trial`]: the pluggable [`Trial`]; [`CampaignTrial`] simulates the campaign; [`iso`]: the
//!   ISO 9283 test a trial runs after its calibration.
//! - [`runner`]: rayon over trial units, [`Shard`]s, completeness of merged shards.
//! - [`stats`], [`threshold`], [`summary`]: pure statistics and verdicts.
//! - [`units`]: the scenario's unit check (noise in metres, half-ranges in radians).
//! - [`export`]: `trials.csv`, `summary.json`, `summary.md`, SVG histogram.

pub mod error;
pub mod export;
pub mod file;
pub mod iso;
pub mod metrics;
pub mod resolve;
pub mod runner;
pub mod seed;
pub mod stats;
pub mod summary;
pub mod threshold;
pub mod trial;
pub mod units;
pub mod validation_error;

pub use error::ScenarioError;
pub use file::{ConditionsSection, Instrument, IsoSection, ScenarioFile, SimMode};
pub use iso::ISO_METRICS;
pub use metrics::{Metrics, TrialRecord};
pub use resolve::{Case, Overrides, ResolvedScenario, ResolvedTruth};
pub use runner::{CoverageError, Shard, ShardError, complete_run, run_units, run_units_until};
pub use seed::trial_seed;
pub use stats::{Stat, Stats, stat_of};
pub use summary::Summary;
pub use threshold::{Op, Threshold, Verdict};
pub use trial::{CAMPAIGN_METRICS, CampaignTrial, SETTLE_METRICS, Trial};
