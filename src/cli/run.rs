//! `axiscal run SCENARIO`: resolve the scenario, run its trials in parallel, write
//! `results/<name>/` and judge the thresholds (exit 1 when one fails).
//!
//! A trial that fails is recorded with its error and counted (the scenario's
//! `max_failure_rate`); SIGINT or SIGTERM stops starting trials, saves the finished ones with a
//! summary marked partial and exits 130 or 143; `--resume` continues such a folder; a lock
//! file refuses a second run into the same folder.

use super::options::{InRange, THREADS, duration_words, thread_pool};
use super::output::Outputs;
use super::printer::Printer;
use super::{Interrupted, ThresholdsFailed, signals};
use anyhow::{Context, Result, bail};
use axiscal::harness::scenario::export::{self, PartialTrials, RUN_FILES, RunLock, SHARD_FILE, TRIALS_FILE};
use axiscal::harness::scenario::resolve::{MAX_UNITS, default_results_dir};
use axiscal::harness::scenario::{
    CampaignTrial, Overrides, ResolvedScenario, Shard, Summary, Trial, TrialRecord, complete_run, run_units_until,
};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

/// Arguments of `axiscal run`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scenario file (TOML), e.g. `scenarios/paper.toml`, or a shipped scenario's name (`paper`).
    #[arg(value_parser = super::options::SCENARIO_FILE)]
    scenario: PathBuf,
    /// Print `summary.json` on stdout (the human-readable lines go to stderr). Not with
    /// `--shard`: a shard has no summary until `axiscal merge` (which takes `--json`) combines them.
    #[arg(long, conflicts_with = "shard")]
    json: bool,
    /// Worker threads (default: one per core; 1..=1024).
    #[arg(long, value_parser = THREADS)]
    threads: Option<usize>,
    /// Run only the K-th of N disjoint trial ranges (1-based), for `axiscal merge`.
    #[arg(long, value_name = "K/N")]
    shard: Option<Shard>,
    /// Results folder; default `results/<name>` (a shard: `results/<name>/shard-K-of-N`).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Replace the results in `--out` if it already holds some (the old run's files are
    /// deleted first).
    #[arg(long, conflicts_with = "resume")]
    force: bool,
    /// Continue an interrupted run in `--out`: the same scenario (and `--trials`, `--seed`,
    /// `--shard`) must resolve to the folder's `scenario.resolved.toml`; only the missing trials
    /// run.
    #[arg(long)]
    resume: bool,
    /// Override the scenario's number of trials per case.
    #[arg(long, value_parser = InRange::closed(1usize, MAX_UNITS, ""))]
    trials: Option<usize>,
    /// Override the scenario's seed.
    #[arg(long, value_parser = super::options::SEED)]
    seed: Option<u64>,
    /// Skip the unit sanity checks of the scenario (its noise in m, its validation half-ranges
    /// in rad, its truth model's rows in mm) and of its robot description.
    #[arg(long)]
    skip_unit_check: bool,
}

/// What a run works on, once resolved.
struct Plan {
    scenario: ResolvedScenario,
    resolved_text: String,
    trial: CampaignTrial,
    names: Vec<String>,
    shard: Shard,
    out: PathBuf,
}

/// Runs `axiscal run`.
pub fn run(args: Args, printer: Printer) -> Result<()> {
    let printer = printer.with_json(args.json);
    let plan = resolve(&args)?;
    super::checks::description_units(&plan.scenario.robot, &args.scenario, args.skip_unit_check)?;
    let outputs = Outputs::new(args.force).input("SCENARIO", &args.scenario);
    Outputs::check_folder(&plan.out)?;
    // The files the run writes, and those of an earlier run it removes with --force.
    let replaced = export::run_outputs_in(&plan.out);
    for name in RUN_FILES.iter().copied().chain(replaced.iter().map(String::as_str)) {
        outputs.check_not_input(&plan.out.join(name))?;
    }
    let _lock = RunLock::acquire(&plan.out)?;
    let done = if args.resume {
        export::resume::previous_trials(&plan.out, &plan.scenario, &plan.resolved_text, &plan.names, plan.shard)?
    } else {
        export::prepare_dir(&plan.out, args.force)?;
        export::write_resolved(&plan.out, &plan.resolved_text)?;
        Vec::new()
    };
    let pool = thread_pool(args.threads)?;
    signals::install();
    let records = run_missing(&plan, done, args.resume, &pool, printer)?;
    if let Some(signal) = signals::received() {
        // A signal after the last trial finished stops nothing: the run is whole.
        if records.len() < plan.shard.units(plan.scenario.units()).len() {
            return Err(interrupted(&plan, &args, records, signal));
        }
        eprintln!(
            "note: {} arrived after the last trial finished: the run is complete",
            signals::name(signal)
        );
    }
    finish(&plan, records, printer)
}

/// The scenario, its trial and where the results go.
fn resolve(args: &Args) -> Result<Plan> {
    let overrides = Overrides {
        trials: args.trials,
        seed: args.seed,
    };
    let (scenario, slips) = ResolvedScenario::from_file_with_slips(&args.scenario, overrides)?;
    super::checks::scenario_units(&slips, &args.scenario, args.skip_unit_check)?;
    let trial = CampaignTrial::new(&scenario);
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
    let resolved_text = scenario.to_toml().context("serialising the resolved scenario")?;
    Ok(Plan {
        scenario,
        resolved_text,
        trial,
        names,
        shard,
        out,
    })
}

/// Runs the units of the shard not in `done` (appending each to `trials.csv` as it finishes)
/// until done or a signal; returns every finished record, sorted by unit.
fn run_missing(
    plan: &Plan,
    done: Vec<TrialRecord>,
    resume: bool,
    pool: &rayon::ThreadPool,
    printer: Printer,
) -> Result<Vec<TrialRecord>> {
    let (scenario, n) = (&plan.scenario, plan.scenario.trials);
    let path = plan.out.join(TRIALS_FILE);
    let partial = if resume && path.exists() {
        PartialTrials::resume(&path, &plan.names)?
    } else {
        PartialTrials::create(&path, &plan.names)?
    };
    let have: std::collections::BTreeSet<usize> = done.iter().map(|r| r.unit(n)).collect();
    let units = plan.shard.units(scenario.units());
    let todo: Vec<usize> = units.clone().filter(|u| !have.contains(u)).collect();
    say!(
        printer,
        "{}: {} case(s) x {} trial(s); units {}..{} (shard {}): {} to run{} into {}",
        scenario.name,
        scenario.cases.len(),
        n,
        units.start,
        units.end,
        plan.shard,
        todo.len(),
        if done.is_empty() {
            String::new()
        } else {
            format!(", {} already done", done.len())
        },
        plan.out.display()
    );
    let bar = super::progress::Progress::counted(todo.len(), "trials", printer);
    let write_error = Mutex::new(None);
    let estimate = EtaWarning::new(todo.len(), pool.current_num_threads());
    let on_done = |r: &TrialRecord| {
        if let Err(e) = partial.append(scenario, r) {
            write_error.lock().unwrap_or_else(|p| p.into_inner()).get_or_insert(e);
        }
        estimate.finished();
        bar.inc();
    };
    let new = pool.install(|| run_units_until(scenario, &plan.trial, todo, &on_done, &signals::STOP));
    drop(bar);
    if let Some(e) = write_error.into_inner().unwrap_or_else(|p| p.into_inner()) {
        return Err(e.into());
    }
    let mut records = done;
    records.extend(new);
    records.sort_by_key(|r| r.unit(n));
    Ok(records)
}

/// Warns once, after the first trials, when the whole run would take more than an hour.
struct EtaWarning {
    start: Instant,
    total: usize,
    threads: usize,
    finished: std::sync::atomic::AtomicUsize,
}

impl EtaWarning {
    /// Estimated time beyond which the run warns (s).
    const LONG_S: f64 = 3600.0;

    fn new(total: usize, threads: usize) -> Self {
        EtaWarning {
            start: Instant::now(),
            total,
            threads: threads.max(1),
            finished: Default::default(),
        }
    }

    /// Counts one finished trial; after as many as threads (at least 4) estimates the total.
    fn finished(&self) {
        let k = self.finished.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        if k != (2 * self.threads).max(4) || k >= self.total {
            return;
        }
        let elapsed = self.start.elapsed().as_secs_f64();
        let remaining = elapsed / k as f64 * (self.total - k) as f64;
        if remaining > Self::LONG_S {
            eprintln!(
                "warning: {} trials at {:.1} ms each on {} thread(s) will take about {}; Ctrl-C stops cleanly \
                 (finished trials are kept, `--resume` continues)",
                self.total,
                elapsed / k as f64 * self.threads as f64 * 1e3,
                self.threads,
                duration_words(remaining)
            );
        }
    }
}

/// Saves an interrupted run: sorted `trials.csv`, and for a whole run a summary marked partial;
/// the error says what was saved and how to continue.
fn interrupted(plan: &Plan, args: &Args, records: Vec<TrialRecord>, signal: i32) -> anyhow::Error {
    let units = plan.shard.units(plan.scenario.units()).len();
    let saved = if plan.shard == Shard::ALL {
        export::write_final(&plan.out, &plan.scenario, &plan.names, &records).map(|_| "summary.json marked partial")
    } else {
        export::csv::write_trials_file(&plan.out.join(TRIALS_FILE), &plan.scenario, &plan.names, &records)
            .map(|()| "no summary for a shard")
    };
    let mut again = format!(
        "axiscal run {} --out {} --resume",
        args.scenario.display(),
        plan.out.display()
    );
    for (flag, value) in [
        ("--trials", args.trials.map(|t| t.to_string())),
        ("--seed", args.seed.map(|s| s.to_string())),
    ] {
        if let Some(v) = value {
            again += &format!(" {flag} {v}");
        }
    }
    if let Some(shard) = args.shard {
        again += &format!(" --shard {shard}");
    }
    let message = match saved {
        Ok(what) => format!(
            "interrupted by {}: {} of {units} trial(s) saved in {} ({what}); continue with `{again}`",
            signals::name(signal),
            records.len(),
            plan.out.display()
        ),
        Err(e) => format!(
            "interrupted by {}; saving the finished trials failed: {e}",
            signals::name(signal)
        ),
    };
    Interrupted { signal, message }.into()
}

/// Writes the results of a finished run (a shard: its trials and `shard.txt`).
fn finish(plan: &Plan, records: Vec<TrialRecord>, printer: Printer) -> Result<()> {
    let (scenario, out) = (&plan.scenario, &plan.out);
    if plan.shard != Shard::ALL {
        let units = plan.shard.units(scenario.units());
        export::csv::write_trials_file(&out.join(TRIALS_FILE), scenario, &plan.names, &records)?;
        let path = out.join(SHARD_FILE);
        std::fs::write(&path, format!("{}\nunits {}..{}\n", plan.shard, units.start, units.end))
            .with_context(|| format!("writing {}", path.display()))?;
        let failed = records.iter().filter(|r| !r.succeeded()).count();
        say!(
            printer,
            "shard {}: {} trial(s) ({failed} failed) written to {}; combine the shards with `axiscal merge`",
            plan.shard,
            records.len(),
            out.display()
        );
        return Ok(());
    }
    let records = complete_run(scenario, records)?;
    let summary = export::write_final(out, scenario, &plan.names, &records)?;
    printer.emit_json(&out.join(export::SUMMARY_JSON))?;
    report(&summary, out, printer)
}

/// Prints the verdicts; an error naming every failed threshold when one fails.
pub fn report(summary: &Summary, out: &Path, printer: Printer) -> Result<()> {
    say!(printer, "results in {}", out.display());
    for c in &summary.cases {
        say!(printer, "case {} ({} trials, {} failed)", c.case, c.trials, c.failed);
        if let Some(f) = &c.first_error {
            eprintln!(
                "warning: case {}: trial {} failed: {} ({} of the {} failed trials alike; every error is in {}/trials.csv)",
                c.case,
                f.trial,
                f.error,
                f.same,
                c.failed,
                out.display()
            );
        }
        if c.trials > 0 && c.failed == c.trials {
            say!(printer, "  no trial succeeded: no statistics");
            continue;
        }
        for m in &c.metrics {
            say!(
                printer,
                "  {:<22} mean {:>12.6}  median {:>12.6}  p95 {:>12.6}  max {:>12.6}",
                m.metric,
                m.stats.mean,
                m.stats.median,
                m.stats.p95,
                m.stats.max
            );
        }
    }
    for v in &summary.verdicts {
        say!(printer, "{v}");
    }
    let failed = summary.failures();
    if failed.is_empty() {
        return Ok(());
    }
    let lines: Vec<String> = failed
        .iter()
        .map(|v| match v.observed.is_nan() {
            true => format!("[{}] {} no value", v.case, v.threshold.describe()),
            false => format!(
                "[{}] {} observed {} (over the bound by {})",
                v.case,
                v.threshold.describe(),
                v.observed,
                v.excess
            ),
        })
        .collect();
    bail!(ThresholdsFailed(format!(
        "{} threshold(s) failed: {}",
        failed.len(),
        lines.join("; ")
    )))
}
