//! Subcommands. Each has `Args` (clap derive) and `run(args) -> anyhow::Result<()>`.

mod calibrate;
mod import;
mod simulate;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

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
    /// Convert measurement data from another group's format to the measurement CSV.
    Import(import::Args),
    /// Simulate a measurement campaign (Table-1 axis experiments + validation poses) to CSV.
    Simulate(simulate::Args),
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
        Command::Import(args) => import::run(args),
        Command::Simulate(args) => simulate::run(args),
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
