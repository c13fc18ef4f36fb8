//! `axiscal merge DIR... --out DIR`: combine shard results (`axiscal run --shard K/N`) into the
//! same results a single run gives, bit for bit.

use super::output::Outputs;
use super::printer::Printer;
use anyhow::{Context, Result, bail};
use axiscal::harness::scenario::export::{self, RESOLVED_FILE, RUN_FILES, RunLock, SHARD_FILE, TRIALS_FILE};
use axiscal::harness::scenario::{CampaignTrial, ResolvedScenario, Shard, Summary, Trial, TrialRecord, complete_run};
use std::path::{Path, PathBuf};

/// Where a record was read: the index of its shard folder and its 1-based line in that
/// folder's trials file.
type Origin = (usize, u64);

/// The first line of `dir`'s `shard.txt` as a shard, when it has one.
fn shard_of(dir: &Path) -> Option<Shard> {
    let text = std::fs::read_to_string(dir.join(SHARD_FILE)).ok()?;
    text.lines().next().and_then(|l| l.trim().parse::<Shard>().ok())
}

/// Refuses shard records (`records`, each read at `origin` of `dirs`) that do not make one
/// run, naming the files and lines: a trial twice (both rows), a trial missing (the shard
/// folder whose `shard.txt` range holds it, or that no folder given holds it).
fn check_coverage(
    scenario: &ResolvedScenario,
    dirs: &[PathBuf],
    records: &[TrialRecord],
    origin: &[Origin],
) -> Result<()> {
    let (n, total) = (scenario.trials, scenario.units());
    let at = |k: usize| format!("{}:{}", dirs[origin[k].0].join(TRIALS_FILE).display(), origin[k].1);
    let mut seen: Vec<Option<usize>> = vec![None; total];
    for (i, r) in records.iter().enumerate() {
        let Some(slot) = seen.get_mut(r.unit(n)) else { continue };
        if let Some(first) = *slot {
            bail!(
                "merging the shards: trial {} of case {} appears more than once: {} and {} (a row repeated, or a shard's \
                 rows copied into another): remove one of the two rows",
                r.trial,
                scenario.cases[r.case].name,
                at(first),
                at(i)
            );
        }
        *slot = Some(i);
    }
    let missing: Vec<usize> = (0..total).filter(|&u| seen[u].is_none()).collect();
    let Some(&first) = missing.first() else { return Ok(()) };
    let holder = dirs
        .iter()
        .find_map(|d| shard_of(d).filter(|s| s.units(total).contains(&first)).map(|s| (d, s)));
    let whose = match holder {
        Some((dir, s)) => format!(
            "shard {} of {} ({}) should hold it, and its {TRIALS_FILE} lacks it: that shard's run did not finish or rows \
             were removed; finish it (`axiscal run ... --shard {s} --out {} --resume`) and merge again",
            s.index,
            s.count,
            dir.display(),
            dir.display()
        ),
        None => "no shard folder given holds it (by their shard.txt): give every shard of the split".to_string(),
    };
    bail!(
        "merging the shards: {} of {total} trials are missing (first: trial {} of case {}): {whose}",
        missing.len(),
        first % n,
        scenario.cases[first / n].name
    )
}

/// Arguments of `axiscal merge`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Shard results folders (each with `scenario.resolved.toml` and `trials.csv`).
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Where to write the merged results.
    #[arg(long)]
    out: PathBuf,
    /// Replace the results in `--out` if it already holds some.
    #[arg(long)]
    force: bool,
    /// Print the merged `summary.json` on stdout (the human-readable lines go to stderr).
    #[arg(long)]
    json: bool,
}

/// Refuses shards of different splits (`--shard K/N` with another `N`: their trial ranges
/// overlap) and one shard given twice, by the first line of each folder's `shard.txt` (a folder
/// without one, or with another first line, is left to the trial count check).
fn check_splits(dirs: &[PathBuf]) -> Result<()> {
    let mut seen: Vec<(&PathBuf, Shard)> = Vec::new();
    for dir in dirs {
        let Ok(text) = std::fs::read_to_string(dir.join(SHARD_FILE)) else {
            continue;
        };
        let Some(shard) = text.lines().next().and_then(|l| l.trim().parse::<Shard>().ok()) else {
            continue;
        };
        if let Some((other, s)) = seen.iter().find(|(_, s)| s.count != shard.count) {
            bail!(
                "{} is shard {} of {}, {} is shard {} of {}: shards of different splits (`run --shard K/N` with another N) overlap; merge the N shards of one split",
                other.display(),
                s.index,
                s.count,
                dir.display(),
                shard.index,
                shard.count
            );
        }
        if let Some((other, _)) = seen.iter().find(|(_, s)| *s == shard) {
            bail!(
                "{} and {} are both shard {shard}: give each shard of the split once",
                other.display(),
                dir.display()
            );
        }
        seen.push((dir, shard));
    }
    Ok(())
}

/// Refuses a shard that is not a folder of `run`'s results (a file, a missing folder, a folder
/// without `scenario.resolved.toml`), naming it.
fn check_shard_folders(dirs: &[PathBuf]) -> Result<()> {
    for dir in dirs {
        if dir.is_file() {
            bail!(
                "{} is a file; merge takes the results folders of `run --shard K/N` (each with {RESOLVED_FILE} and {TRIALS_FILE})",
                dir.display()
            );
        }
        if !dir.is_dir() {
            bail!(
                "{}: no such folder (a results folder of `run --shard K/N`)",
                dir.display()
            );
        }
        if !dir.join(RESOLVED_FILE).is_file() {
            bail!(
                "{} holds no {RESOLVED_FILE}: not a results folder of `run` (merge takes the folders of `run --shard K/N`)",
                dir.display()
            );
        }
    }
    Ok(())
}

/// Writes the merged set into `out` as calibrate writes its folder ([`Outputs::staged_in`]):
/// every file under a temporary name first, then put in place by renames only, the earlier
/// run's files the set does not replace removed. An interrupt (even SIGKILL) while the files
/// are written leaves the whole old set, and the temporaries a SIGKILL leaves are removed by
/// the next command writing into the folder.
fn write_set(
    outputs: &Outputs,
    out: &Path,
    resolved_text: &str,
    scenario: &ResolvedScenario,
    names: &[String],
    records: &[TrialRecord],
) -> Result<Summary> {
    let (files, summary) = export::render_final(out, scenario, names, records)?;
    let mut set = outputs.staged_in(out)?;
    set.write(RESOLVED_FILE, resolved_text)?;
    for (name, bytes) in &files {
        set.write(name, bytes)?;
    }
    if let Some(histogram) = export::histogram_name(scenario, names) {
        set.draw(&[histogram.as_str()], |dir| {
            export::draw_histogram(dir, scenario, names, records)
        })?;
    }
    let stale = export::run_outputs_in(out);
    set.commit(&stale.iter().map(String::as_str).collect::<Vec<_>>())?;
    Ok(summary)
}

/// Runs `axiscal merge`.
pub fn run(args: Args, printer: Printer) -> Result<()> {
    let printer = printer.with_json(args.json);
    check_shard_folders(&args.dirs)?;
    let first = args.dirs[0].join(RESOLVED_FILE);
    let resolved_text = axiscal::presets::read_text(&first).with_context(|| format!("reading {}", first.display()))?;
    let scenario = ResolvedScenario::from_resolved_file(&first)?;
    check_splits(&args.dirs)?;
    let names = CampaignTrial::new(&scenario).metric_names();
    scenario.check_metrics(&names, &first)?;
    let (mut records, mut origin) = (Vec::new(), Vec::new());
    for (d, dir) in args.dirs.iter().enumerate() {
        let path = dir.join(RESOLVED_FILE);
        let text = axiscal::presets::read_text(&path).with_context(|| format!("reading {}", path.display()))?;
        if text != resolved_text {
            bail!(
                "{} differs from {}: shards of different scenarios (or trials/seed overrides) cannot be merged",
                path.display(),
                first.display()
            );
        }
        let (r, lines) = export::csv::read_trials_located(&dir.join(TRIALS_FILE), &scenario, &names)?;
        origin.extend(lines.into_iter().map(|l| (d, l)));
        records.extend(r);
    }
    check_coverage(&scenario, &args.dirs, &records, &origin)?;
    let records = complete_run(&scenario, records).context("merging the shards")?;
    let outputs = Outputs::new(args.force).inputs_in("a shard", &args.dirs, &[RESOLVED_FILE, TRIALS_FILE]);
    Outputs::check_folder(&args.out)?;
    for name in RUN_FILES {
        outputs.check_not_input(&args.out.join(name))?;
    }
    let _lock = RunLock::acquire(&args.out)?;
    export::check_replace(&args.out, args.force)?;
    let summary = write_set(&outputs, &args.out, &resolved_text, &scenario, &names, &records)?;
    printer.emit_json(&args.out.join(export::SUMMARY_JSON))?;
    super::run::report(&summary, &args.out, printer)
}
