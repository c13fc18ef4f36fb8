//! `axiscal run SCENARIO`: resolve the scenario, run its trials in parallel, write
//! `results/<name>/` and judge the thresholds (exit 1 when one fails).

use super::ThresholdsFailed;
use anyhow::{Context, Result, bail};
use axiscal::harness::scenario::export::{self, PartialTrials, SHARD_FILE, TRIALS_FILE};
use axiscal::harness::scenario::resolve::default_results_dir;
use axiscal::harness::scenario::{
    CampaignTrial, Overrides, ResolvedScenario, Shard, Summary, Trial, complete_run, run_units,
};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};

/// Arguments of `axiscal run`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scenario file (TOML), e.g. `scenarios/paper.toml`.
    scenario: PathBuf,
    /// Worker threads (default: one per core).
    #[arg(long)]
    threads: Option<usize>,
    /// Run only the K-th of N disjoint trial ranges (1-based), for `axiscal merge`.
    #[arg(long, value_name = "K/N")]
    shard: Option<Shard>,
    /// Results folder; default `results/<name>` (a shard: `results/<name>/shard-K-of-N`).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Replace the results in `--out` if it already holds some.
    #[arg(long)]
    force: bool,
    /// Override the scenario's number of trials per case.
    #[arg(long)]
    trials: Option<usize>,
    /// Override the scenario's seed.
    #[arg(long)]
    seed: Option<u64>,
}

/// Runs `axiscal run`.
pub fn run(args: Args) -> Result<()> {
    let overrides = Overrides {
        trials: args.trials,
        seed: args.seed,
    };
    let scenario = ResolvedScenario::from_file(&args.scenario, overrides)?;
    let trial = CampaignTrial::new(&scenario).map_err(|m| anyhow::anyhow!("{}: {m}", args.scenario.display()))?;
    let names = trial.metric_names();
    scenario.check_metrics(&names, &args.scenario)?;
    let shard = args.shard.unwrap_or(Shard::ALL);
    let out = args.out.clone().unwrap_or_else(|| {
        let dir = default_results_dir(&scenario.name);
        if shard == Shard::ALL {
            dir
        } else {
            dir.join(format!("shard-{}-of-{}", shard.index, shard.count))
        }
    });
    export::prepare_dir(&out, args.force)?;
    export::write_resolved(&out, &scenario.to_toml().context("serialising the resolved scenario")?)?;
    let units = shard.units(scenario.units());
    eprintln!(
        "{}: {} case(s) x {} trial(s); running units {}..{} (shard {shard}) into {}",
        scenario.name,
        scenario.cases.len(),
        scenario.trials,
        units.start,
        units.end,
        out.display()
    );
    let partial = PartialTrials::create(&out.join(TRIALS_FILE), &names)?;
    let bar = ProgressBar::new(units.len() as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} trials  {elapsed} elapsed, ETA {eta}")
            .context("progress template")?,
    );
    let write_error = std::sync::Mutex::new(None);
    let on_done = |r: &axiscal::harness::scenario::TrialRecord| {
        if let Err(e) = partial.append(&scenario, r) {
            write_error.lock().unwrap_or_else(|p| p.into_inner()).get_or_insert(e);
        }
        bar.inc(1);
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .context("building the thread pool")?;
    let records = pool.install(|| run_units(&scenario, &trial, units.clone(), &on_done));
    bar.finish_and_clear();
    let records = records?;
    if let Some(e) = write_error.into_inner().unwrap_or_else(|p| p.into_inner()) {
        return Err(e.into());
    }
    if shard != Shard::ALL {
        export::csv::write_trials_file(&out.join(TRIALS_FILE), &scenario, &names, &records)?;
        let path = out.join(SHARD_FILE);
        std::fs::write(&path, format!("{shard}\nunits {}..{}\n", units.start, units.end))
            .with_context(|| format!("writing {}", path.display()))?;
        println!(
            "shard {shard}: {} trial(s) written to {}; combine the shards with `axiscal merge`",
            records.len(),
            out.display()
        );
        return Ok(());
    }
    let records = complete_run(&scenario, records)?;
    let summary = export::write_final(&out, &scenario, &names, &records)?;
    report(&summary, &out)
}

/// Prints the verdicts; an error naming every failed threshold when one fails.
pub fn report(summary: &Summary, out: &Path) -> Result<()> {
    println!("results in {}", out.display());
    for c in &summary.cases {
        println!("case {} ({} trials)", c.case, c.trials);
        for m in &c.metrics {
            println!(
                "  {:<22} mean {:>12.6}  median {:>12.6}  p95 {:>12.6}  max {:>12.6}",
                m.metric, m.stats.mean, m.stats.median, m.stats.p95, m.stats.max
            );
        }
    }
    for v in &summary.verdicts {
        println!("{v}");
    }
    let failed = summary.failures();
    if failed.is_empty() {
        return Ok(());
    }
    let lines: Vec<String> = failed
        .iter()
        .map(|v| {
            format!(
                "[{}] {} observed {} (over the bound by {})",
                v.case,
                v.threshold.describe(),
                v.observed,
                v.excess
            )
        })
        .collect();
    bail!(ThresholdsFailed(format!(
        "{} threshold(s) failed:\n  {}",
        failed.len(),
        lines.join("\n  ")
    )))
}
