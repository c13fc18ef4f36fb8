//! Subcommands. Each has `Args` (clap derive) and `run(args) -> anyhow::Result<()>`.

/// A human-readable line through the command's [`printer::Printer`]:
/// `say!(printer, printer, "format", args...)`.
macro_rules! say {
    ($printer:expr, $($t:tt)*) => {
        $printer.say(format_args!($($t)*))
    };
}

mod blind;
mod budget;
mod calibrate;
mod checks;
mod compensate;
mod describe;
mod diagnose;
mod evaluate;
mod export;
mod import;
mod iso9283;
mod joints;
mod merge;
mod options;
mod output;
mod plan;
mod printer;
mod progress;
mod record;
mod referenced;
mod report;
mod run;
mod signals;
mod simulate;
mod study;
mod sweep_cause;
mod validate;
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
    /// Also print details (e.g. the instrument's calibration) on stderr.
    #[arg(long, short, global = true)]
    verbose: bool,
    /// No progress display (it is also hidden when stderr is not a terminal); with `--json`,
    /// no human-readable lines either.
    #[arg(long, short, global = true)]
    quiet: bool,
    #[command(subcommand)]
    command: Command,
}

/// The error as one line: its context and causes joined by `: `, line breaks folded into `; `.
/// Each error is handled once: the library's errors show their cause and do not also chain it,
/// so no cause is repeated (checked in debug builds: a plain `cargo test` runs the commands so).
pub fn one_line(e: &anyhow::Error) -> String {
    debug_assert!(
        !e.chain().skip(1).any(|cause| {
            let text = cause.to_string();
            let shown: Vec<String> = e
                .chain()
                .take_while(|c| !std::ptr::addr_eq(*c, cause))
                .map(|c| c.to_string())
                .collect();
            !text.trim().is_empty() && shown.iter().any(|s| s.contains(text.trim()))
        }),
        "an error shows a cause it also chains: {e:?}"
    );
    let causes: Vec<String> = e
        .chain()
        .map(|c| c.to_string().trim().to_owned())
        .filter(|t| !t.is_empty())
        .collect();
    fold_lines(&causes.join(": "))
}

/// `text` on one line: lines trimmed, the empty ones dropped, the rest joined by `; ` (by a
/// space after a line that ends with `:`, which introduces what follows).
fn fold_lines(text: &str) -> String {
    let mut out = String::new();
    for line in text.lines().map(str::trim).filter(|l| !l.is_empty()) {
        if !out.is_empty() {
            out.push_str(if out.ends_with(':') { " " } else { "; " });
        }
        out.push_str(line);
    }
    out
}

/// A command-line error of clap as one line (its usage and "for more information" lines are
/// left out; `axiscal COMMAND --help` lists every option).
fn clap_one_line(e: &clap::Error) -> String {
    let text = e.render().to_string();
    let lines: Vec<&str> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with("Usage:") && !l.starts_with("For more information"))
        .collect();
    // A line ending in `:` introduces the next ("not provided:" then the arguments).
    let mut joined = String::new();
    for line in lines {
        if !joined.is_empty() {
            joined.push_str(if joined.ends_with(':') { " " } else { "; " });
        }
        joined.push_str(line);
    }
    // clap's tip to pass a value after `--` makes it the command's file argument here: wrong
    // advice for an option the command does not have.
    let joined = match joined.find("; tip: to pass '") {
        Some(at) if joined[at..].contains("as a value, use '-- ") => joined[..at].to_owned(),
        _ => joined,
    };
    joined.strip_prefix("error: ").unwrap_or(&joined).to_owned()
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
    /// The measurement plan for a real robot: every point to measure, with every joint's
    /// command, the target and whether each station should see it (`docs/formats.md#measurement-plan`).
    Plan(plan::Args),
    /// Simulate a measurement campaign (Table-1 axis experiments + validation poses) to CSV.
    Simulate(simulate::Args),
    /// Run a Monte-Carlo scenario (`scenarios/*.toml`): trials in parallel, results under
    /// `results/<name>/`, exit 1 when a threshold fails.
    Run(run::Args),
    /// Merge shard results of `run --shard K/N` into one run's results.
    Merge(merge::Args),
    /// Fig. 5 compensation: commands for required tool poses from a calibration.
    Compensate(compensate::Args),
    /// The calibrated joint values of controller commands: what a URDF or a ROS
    /// `joint_states` publisher must be fed instead of the raw readings.
    Joints(joints::Args),
    /// A calibration in the files a robot's software loads (UR `kinematics.yaml`, per-joint URDF
    /// origins for a xacro), each read back and checked against the calibrated model.
    Export(export::Args),
    /// ISO 9283 performance figures (pose accuracy and repeatability, multi-directional
    /// variation, distance accuracy and repeatability) of measured cycles.
    #[command(name = "iso9283")]
    Iso9283(iso9283::Args),
    /// The calibration certificate: every parameter with its GUM uncertainty (u, U with
    /// k = 2), correlations, residual plots, held-out poses, ISO 9283 figures, as one HTML page
    /// and its JSON (`docs/formats.md#certificate`).
    Report(report::Args),
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
    /// Print a shell completion script (`axiscal completions bash > ~/.local/share/bash-completion/completions/axiscal`).
    Completions {
        /// The shell.
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
    /// Validate a calibration on measured data: every point predicted, `residuals.csv` and
    /// `summary.json` (RMS against the instrument's noise, the robot's repeatability and the
    /// calibration's own predicted error; chi-square or F verdicts).
    Validate(validate::Args),
    /// Open a rerun recording (`.rrd`) in the matching rerun viewer, or print how to install it.
    View(view::Args),
}

/// A run that completed but whose thresholds did not hold: exit code 1.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct ThresholdsFailed(pub String);

/// A run stopped by SIGINT or SIGTERM after saving what it had: exit code 128 + the signal
/// (130, 143), as shells report a process killed by it.
#[derive(Debug, thiserror::Error)]
#[error("{message}")]
pub struct Interrupted {
    /// The signal number.
    pub signal: i32,
    /// What was saved and how to continue.
    pub message: String,
}

impl Interrupted {
    fn exit_code(&self) -> u8 {
        u8::try_from(128 + self.signal).unwrap_or(130)
    }
}

/// A failed write to stdout or stderr (`| head -1`, `> /dev/full`) ends the run with exit 2
/// and one line on stderr where it can still be written, instead of a panic's 101: the reader
/// went away or the device is full, which is the user's to fix, not a crash.
fn exit_2_when_output_fails() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info.payload();
        let message = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or("");
        if message.starts_with("failed printing to std") {
            use std::io::Write;
            let _ = writeln!(std::io::stderr(), "error: {message}");
            std::process::exit(2);
        }
        default(info);
    }));
}

/// `axiscal completions SHELL`: the script, written to stdout as a whole (a failed write is an
/// error, not clap_complete's panic).
fn completions(shell: clap_complete::Shell) -> anyhow::Result<()> {
    use anyhow::Context;
    use clap::CommandFactory;
    use std::io::Write;
    let mut script = Vec::new();
    clap_complete::generate(shell, &mut Cli::command(), "axiscal", &mut script);
    let mut stdout = std::io::stdout().lock();
    stdout
        .write_all(&script)
        .and_then(|()| stdout.flush())
        .context("writing the completion script to stdout")
}

/// The command line read with every option value allowed to be a negative number, so that
/// `--payload-kg -5` meets the option's own range check instead of clap's "unexpected argument".
fn parse_command_line() -> Result<Cli, clap::Error> {
    use clap::{CommandFactory, FromArgMatches};
    let matches = negative_values_allowed(Cli::command()).try_get_matches()?;
    Cli::from_arg_matches(&matches)
}

/// `cmd` and its subcommands, recursively, with `allow_negative_numbers` on every argument that
/// takes a value.
fn negative_values_allowed(cmd: clap::Command) -> clap::Command {
    cmd.mut_args(|arg| {
        if arg.get_action().takes_values() {
            arg.allow_negative_numbers(true)
        } else {
            arg
        }
    })
    .mut_subcommands(negative_values_allowed)
}

/// Parses the command line, runs the subcommand and maps its outcome to an exit code.
pub fn main() -> ExitCode {
    exit_2_when_output_fails();
    options::cap_rayon_threads_from_environment();
    signals::install_cleanup();
    let cli = match parse_command_line() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => {
            // --help, --version: printed to stdout, exit 0 (2 when stdout fails).
            return match e.print().and_then(|()| std::io::Write::flush(&mut std::io::stdout())) {
                Ok(()) => ExitCode::SUCCESS,
                Err(error) => {
                    eprintln!("error: writing to stdout: {error}");
                    ExitCode::from(2)
                }
            };
        }
        Err(e) => {
            eprintln!("error: {} (see `axiscal help`)", clap_one_line(&e));
            return ExitCode::from(2);
        }
    };
    let printer = printer::Printer {
        verbose: cli.verbose,
        quiet: cli.quiet,
        json: false,
    };
    let result = match cli.command {
        Command::Calibrate(args) => calibrate::run(args, printer),
        Command::Describe(args) => describe::run(args),
        Command::Import(args) => import::run(args),
        Command::Plan(args) => plan::run(args),
        Command::Simulate(args) => simulate::run(args, printer),
        Command::Study(args) => study::run(args, printer),
        Command::Run(args) => run::run(args, printer),
        Command::Merge(args) => merge::run(args, printer),
        Command::Compensate(args) => compensate::run(args),
        Command::Joints(args) => joints::run(args),
        Command::Export(args) => export::run(args, printer),
        Command::Iso9283(args) => iso9283::run(args, printer),
        Command::Report(args) => report::run(args, printer),
        Command::Evaluate(args) => evaluate::run(args, printer),
        Command::Budget(args) => budget::run(args, printer),
        Command::Diagnose(args) => diagnose::run(args, printer),
        Command::Blind(args) => blind::run(args, printer),
        Command::Validate(args) => validate::run(args),
        Command::View(args) => view::run(args),
        Command::Completions { shell } => completions(shell),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", one_line(&e));
            if let Some(interrupted) = e.downcast_ref::<Interrupted>() {
                ExitCode::from(interrupted.exit_code())
            } else if e.downcast_ref::<ThresholdsFailed>().is_some() {
                ExitCode::from(1)
            } else {
                ExitCode::from(2)
            }
        }
    }
}
