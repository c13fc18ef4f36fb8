//! Subcommands. Each has `Args` (clap derive) and `run(args) -> anyhow::Result<()>`.

mod blind;
mod budget;
mod calibrate;
mod compensate;
mod describe;
mod diagnose;
mod evaluate;
mod import;
mod merge;
#[cfg(feature = "viz")]
mod record;
mod run;
mod simulate;
mod study;
mod view;

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{Parser, Subcommand};
use std::ffi::OsStr;
use std::process::ExitCode;

/// A value parser for one of a library enum's values by name: the library's types carry no
/// clap derive, the command line spells their values here (and `--help` lists them).
#[derive(Clone, Copy)]
pub(crate) struct OneOf<T: 'static>(pub &'static [(&'static str, T)]);

impl<T: Clone + Send + Sync + 'static> TypedValueParser for OneOf<T> {
    type Value = T;

    fn parse_ref(&self, cmd: &clap::Command, arg: Option<&clap::Arg>, value: &OsStr) -> Result<T, clap::Error> {
        if let Some((_, v)) = self.0.iter().find(|(name, _)| OsStr::new(name) == value) {
            return Ok(v.clone());
        }
        // clap's own message for a value outside the list.
        let names = PossibleValuesParser::new(self.0.iter().map(|(name, _)| *name));
        Err(names
            .parse_ref(cmd, arg, value)
            .err()
            .unwrap_or_else(|| clap::Error::new(clap::error::ErrorKind::InvalidValue).with_cmd(cmd)))
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(self.0.iter().map(|(name, _)| PossibleValue::new(*name))))
    }
}

/// Independent-axis robot calibration (Sultan & Wager) with a simulation-backed harness.
#[derive(Debug, Parser)]
#[command(name = "axiscal", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Calibrate a robot from a measurement CSV (axes, transmissions, couplings, offsets).
    Calibrate(calibrate::Args),
    /// The phi-model of a robot description (rows, phi angles, axes); for a DH table or a URDF,
    /// its forward kinematics checked against the source at random poses.
    Describe(describe::Args),
    /// Monte-Carlo study of the calibrator: efficiency against the Cramer-Rao bound (ML and the
    /// paper's estimator) and the calibration of the reported uncertainties.
    Study(study::Args),
    /// Convert measurement data from another group's format to the measurement CSV.
    Import(import::Args),
    /// Simulate a measurement campaign (Table-1 axis experiments + validation poses) to CSV.
    Simulate(simulate::Args),
    /// Run a Monte-Carlo scenario (`scenarios/*.toml`): trials in parallel, results under
    /// `results/<name>/`, exit 1 when a threshold fails.
    Run(run::Args),
    /// Merge shard results of `run --shard K/N` into one run's results.
    Merge(merge::Args),
    /// Fig. 5 compensation: commands for required tool poses from a calibration.
    Compensate(compensate::Args),
    /// The paper scenario end to end: simulate, calibrate, compensate, evaluate (figs. 9-10).
    Evaluate(evaluate::Args),
    /// The paper's gap budget: per unmodelled effect, the magnitude that raises the simulated
    /// calibrated error of the paper robot to the paper's 1.40 mm.
    Budget(budget::Args),
    /// Sim-to-real gap diagnosis: where the calibrated model misses, which effect explains it,
    /// how far the gap shrinks (diagnosis.json, `docs/formats.md#diagnosis-json`).
    Diagnose(diagnose::Args),
    /// Blind check of `diagnose`: simulated cases with hidden keys, scored (confusion matrix).
    Blind(blind::Args),
    /// Open a rerun recording (`.rrd`) in the matching rerun viewer, or print how to install it.
    View(view::Args),
}

/// A run that completed but whose thresholds did not hold: exit code 1.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct ThresholdsFailed(pub String);

/// Parses the command line, runs the subcommand and maps its outcome to an exit code.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Calibrate(args) => calibrate::run(args),
        Command::Describe(args) => describe::run(args),
        Command::Import(args) => import::run(args),
        Command::Simulate(args) => simulate::run(args),
        Command::Study(args) => study::run(args),
        Command::Run(args) => run::run(args),
        Command::Merge(args) => merge::run(args),
        Command::Compensate(args) => compensate::run(args),
        Command::Evaluate(args) => evaluate::run(args),
        Command::Budget(args) => budget::run(args),
        Command::Diagnose(args) => diagnose::run(args),
        Command::Blind(args) => blind::run(args),
        Command::View(args) => view::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            if e.downcast_ref::<ThresholdsFailed>().is_some() {
                ExitCode::from(1)
            } else {
                ExitCode::from(2)
            }
        }
    }
}
