//! Subcommands. Each has `Args` (clap derive) and `run(args) -> anyhow::Result<()>`.

#[cfg(feature = "viz")]
mod record;
mod simulate;
mod view;

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
    /// Simulate a measurement campaign (Table-1 axis experiments + validation poses) to CSV.
    Simulate(simulate::Args),
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
        Command::Simulate(args) => simulate::run(args),
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
