//! `axiscal study`: the calibrator's efficiency against the Cramer-Rao bound and the
//! calibration of its reported uncertainty, over many simulated campaigns.

use super::options::THREADS;
use super::options::{InRange, NOISE_MM};
use super::output::Outputs;
use super::printer::Printer;
use anyhow::Result;
use axiscal::harness::studies::EfficiencyStudy;
use axiscal::harness::studies::StudyError;
use axiscal::json_file::{self, Schema};
use std::path::PathBuf;

/// Arguments of `axiscal study`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Number of simulated campaigns (at least 2: a standard error needs two).
    #[arg(long, default_value_t = 200, value_parser = InRange::closed(2usize, 100_000_000, ""))]
    trials: usize,
    /// Study seed.
    #[arg(long, value_parser = super::options::SEED, default_value_t = 1)]
    seed: u64,
    /// Measurement noise, 3-D RMS (mm).
    #[arg(long, default_value_t = Args::DEFAULT_NOISE_MM, value_parser = NOISE_MM)]
    noise_mm: f64,
    /// Keep the truth robot's repeatability jitter (the bound then includes it as angle noise).
    #[arg(long)]
    repeatability_jitter: bool,
    /// Tell the calibrator the robot's repeatability (the nominal description's
    /// `repeatability_sigma` per joint); without it the calibrator models measurement noise only.
    #[arg(long)]
    model_repeatability: bool,
    /// Output folder (`efficiency.json`, `efficiency.md`).
    #[arg(long, default_value = "results/study")]
    out: PathBuf,
    /// Worker threads (default: one per core; 1..=1024); the result does not depend on it.
    #[arg(long, value_parser = THREADS)]
    threads: Option<usize>,
    /// Replace existing output files.
    #[arg(long)]
    force: bool,
}

impl Args {
    /// The default `--noise-mm`: a laser tracker's or the paper's theodolites' noise.
    const DEFAULT_NOISE_MM: f64 = 0.19;
}

/// Runs `axiscal study`.
pub fn run(args: Args, printer: Printer) -> Result<()> {
    let study = EfficiencyStudy {
        trials: args.trials,
        seed: args.seed,
        noise_rms_3d_mm: args.noise_mm,
        repeatability_jitter: args.repeatability_jitter,
        model_repeatability: args.model_repeatability,
    };
    let names = ["efficiency.json", "efficiency.md"];
    let outputs = Outputs::new(args.force);
    outputs.check_in(&args.out, &names)?;
    let progress = super::progress::Progress::stage("efficiency study", printer);
    let report = super::options::thread_pool(args.threads)?
        .install(|| study.run_with(&progress))
        .map_err(|e| failed_trial(e, args.noise_mm))?;
    drop(progress);
    let md = report.markdown();
    let mut staged = outputs.staged_in(&args.out)?;
    staged.write(names[0], json_file::to_string(Schema::STUDY, &report)?)?;
    staged.write(names[1], &md)?;
    staged.commit(&[])?;
    print!("{md}");
    Ok(())
}

/// A study's failure in words: a simulated trial its calibrator cannot fit is the noise's doing
/// when the noise is above the default's (the campaign resolves its sweeps at that noise).
fn failed_trial(e: StudyError, noise_mm: f64) -> anyhow::Error {
    let default = Args::DEFAULT_NOISE_MM;
    match e {
        StudyError::Fit { .. } | StudyError::Procedure { .. } if noise_mm > default => anyhow::anyhow!(
            "{e}: this trial's simulated points scatter with --noise-mm {noise_mm}, {:.0} times the default \
             {default} mm, beyond what the study campaign's sweeps resolve (its calibrator cannot place their axes); \
             a study compares the calibrator with its bound at an instrument's noise: pass a smaller --noise-mm",
            noise_mm / default
        ),
        other => other.into(),
    }
}
