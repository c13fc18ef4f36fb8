//! `axiscal study`: the calibrator's efficiency against the Cramer-Rao bound and the
//! calibration of its reported uncertainty, over many simulated campaigns.

use super::calibrate::write_output;
use anyhow::{Context, Result};
use axiscal::harness::studies::EfficiencyStudy;
use axiscal::json_file::{self, Schema};
use std::path::PathBuf;

/// Arguments of `axiscal study`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Number of simulated campaigns.
    #[arg(long, default_value_t = 200)]
    trials: usize,
    /// Study seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Measurement noise, 3-D RMS \[mm\].
    #[arg(long, default_value_t = 0.19)]
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
    /// Replace existing output files.
    #[arg(long)]
    force: bool,
}

/// Runs `axiscal study`.
pub fn run(args: Args) -> Result<()> {
    let study = EfficiencyStudy {
        trials: args.trials,
        seed: args.seed,
        noise_rms_3d_mm: args.noise_mm,
        repeatability_jitter: args.repeatability_jitter,
        model_repeatability: args.model_repeatability,
    };
    let report = study.run()?;
    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let md = report.markdown();
    write_output(
        &args.out,
        "efficiency.json",
        &json_file::to_string(Schema::STUDY, &report)?,
        args.force,
    )?;
    write_output(&args.out, "efficiency.md", &md, args.force)?;
    print!("{md}");
    Ok(())
}
