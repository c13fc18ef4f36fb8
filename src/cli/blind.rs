//! `axiscal blind --cases N --seed S --out DIR`: the blind check of the diagnoser. Each case's
//! CSV goes to `DIR/case-NNN/data.csv`, its hidden truth to `DIR/case-NNN/key.json`; the
//! diagnoser reads the CSV back alone; `DIR/summary.{json,md}` hold the score. `--effect` and
//! `--joint` run a subset of the drawn cases (same numbers and seeds).

use super::options::{InRange, THREADS, thread_pool};
use super::output::Outputs;
use super::printer::Printer;
use anyhow::{Context, Result, bail};
use axiscal::diagnosis::{DiagnosisOptions, RefitScope, diagnose};
use axiscal::harness::blind::{
    BlindCampaign, BlindOptions, CASE_EFFECTS, CaseResult, MIN_FREE_POSES, Simulator, case_table, detectable_size,
    draw_case, score, simulate_case,
};
use axiscal::json_file::{self, Schema};
use axiscal::measurement::{read_measurements_from, write_measurements_to};
use rayon::prelude::*;
use std::path::PathBuf;

/// Arguments of `axiscal blind`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Number of cases.
    #[arg(long, default_value_t = 16, value_parser = InRange::closed(1usize, 1_000_000, ""))]
    cases: usize,
    /// Suite seed.
    #[arg(long, value_parser = super::options::SEED, default_value_t = 0)]
    seed: u64,
    /// Validation poses per case (default: 100 after the sweeps, 300 free poses).
    #[arg(long, value_parser = InRange::closed(4usize, 1_000_000, ""))]
    poses: Option<usize>,
    /// What each case measures: `sweeps` (the paper robot's Table-1 axis experiments, then
    /// validation poses) or `free-poses` (the six-axis `arm6-dh`, poses only).
    #[arg(long, default_value = "sweeps")]
    campaign: String,
    /// Baseline refit scope of the diagnoser (`identified` or `geometry`).
    #[arg(long, default_value = "identified")]
    refit: String,
    /// Run only the cases (of the `--cases` drawn) with this effect (`CASE_EFFECTS`, e.g.
    /// `joint_compliance`); their numbers and seeds stay those of the full suite.
    #[arg(long)]
    effect: Option<String>,
    /// Run only the cases (of the `--cases` drawn) whose effect sits on this joint (1-based).
    #[arg(long)]
    joint: Option<usize>,
    /// Simulated robot: `analytic` (effects without bodies, fast) or `rapier` (bodies, servos).
    #[arg(long, default_value = "analytic")]
    sim: String,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// Replace an existing non-empty output folder.
    #[arg(long)]
    force: bool,
    /// Worker threads (default: one per core; 1..=1024); the result does not depend on it.
    #[arg(long, value_parser = THREADS)]
    threads: Option<usize>,
}

/// Runs `axiscal blind`.
pub fn run(args: Args, printer: Printer) -> Result<()> {
    let campaign = match args.campaign.as_str() {
        "sweeps" => BlindCampaign::Sweeps,
        "free-poses" => BlindCampaign::FreePoses,
        other => bail!("--campaign {other}: expected `sweeps` or `free-poses`"),
    };
    let desc = campaign.description();
    if let Some(j) = args.joint.filter(|j| *j == 0 || *j > desc.dof()) {
        bail!("--joint {j}: must be in 1..={} (a joint of {})", desc.dof(), desc.name);
    }
    if let Some(n) = args
        .poses
        .filter(|&n| campaign == BlindCampaign::FreePoses && n < MIN_FREE_POSES)
    {
        bail!(
            "--poses {n} is too few for --campaign free-poses: at least {MIN_FREE_POSES} (the diagnoser calibrates from every other pose, and a free-pose calibration needs {} poses)",
            axiscal::calibration::free_pose::MIN_POSES
        );
    }
    let options = BlindOptions {
        validation_poses: args.poses.unwrap_or(match campaign {
            BlindCampaign::Sweeps => 100,
            BlindCampaign::FreePoses => 300,
        }),
        campaign,
        simulator: match args.sim.as_str() {
            "analytic" => Simulator::Analytic,
            "rapier" => Simulator::Rapier,
            other => bail!("--sim {other}: expected `analytic` or `rapier`"),
        },
        ..BlindOptions::default()
    };
    let diagnosis_options = DiagnosisOptions {
        refit: match args.refit.as_str() {
            "identified" => RefitScope::Identified,
            "geometry" => RefitScope::Geometry,
            other => bail!("--refit {other}: expected `identified` or `geometry`"),
        },
        ..DiagnosisOptions::default()
    };
    if let Some(effect) = &args.effect
        && !CASE_EFFECTS.contains(&effect.as_str())
    {
        bail!("--effect {effect}: expected one of {CASE_EFFECTS:?}");
    }
    let outputs = held_output(&args)?;
    let keys: Vec<_> = (0..args.cases)
        .map(|i| (i, draw_case(args.seed, i, &desc)))
        .filter(|(_, key)| args.effect.as_ref().is_none_or(|e| *e == key.effect))
        .filter(|(_, key)| args.joint.is_none_or(|j| key.joint == Some(j)))
        .collect();
    let progress = super::progress::Progress::counted(keys.len(), "cases", printer);
    let pool = thread_pool(args.threads)?;
    let cases: Vec<(CaseResult, CaseFiles)> = pool.install(|| {
        keys.into_par_iter()
            .map(|(i, key)| -> Result<_> {
                let case = run_case(i, key, &desc, (&options, &diagnosis_options), &args.out)?;
                progress.inc();
                Ok(case)
            })
            .collect::<Result<_>>()
    })?;
    drop(progress);
    let (results, files): (Vec<CaseResult>, Vec<CaseFiles>) = cases.into_iter().unzip();
    let s = score(&results);
    // Every file of the new set is written under a temporary name first, then all are put in
    // place at once (a signal meanwhile waits), and the old run's other cases removed: an
    // interrupted run leaves the old set whole.
    let mut staged = outputs.staged_in(&args.out)?;
    for (name, text) in files.iter().flatten() {
        staged.write(name, text)?;
    }
    staged.write("summary.json", json_file::to_string(Schema::BLIND_SUMMARY, &s)?)?;
    staged.write("summary.md", format!("{}\n{}", s.markdown(), case_table(&results)))?;
    staged.write(
        "cases.json",
        json_file::list_to_string(Schema::BLIND_CASES, "cases", &results)?,
    )?;
    let stale = stale_case_files(&args.out, &results)?;
    let stale: Vec<&str> = stale.iter().map(String::as_str).collect();
    super::signals::deferred(|| -> Result<()> {
        staged.commit(&stale)?;
        remove_emptied_cases(&args.out, &stale);
        Ok(())
    })?;
    print!("{}", s.markdown());
    Ok(())
}

/// The files of one case folder, as names under `--out` and their bytes.
type CaseFiles = Vec<(String, Vec<u8>)>;

/// Simulates case `i`, diagnoses its CSV alone and scores it: the result and the case folder's
/// files (`out` only names the CSV in messages; nothing is written here).
fn run_case(
    i: usize,
    key: axiscal::harness::blind::CaseKey,
    desc: &axiscal::robot::RobotDescription,
    (options, diagnosis_options): (&BlindOptions, &DiagnosisOptions),
    out: &std::path::Path,
) -> Result<(CaseResult, CaseFiles)> {
    let folder = format!("case-{i:03}");
    let csv = out.join(&folder).join("data.csv");
    let set = simulate_case(&key, desc, options)?;
    let mut text = super::checks::identity_comment(desc).into_bytes();
    write_measurements_to(&mut text, &set)?;
    // The diagnoser sees the CSV alone.
    let blind = read_measurements_from(&text[..], &csv, Some(desc.dof()))?;
    let d = diagnose(&blind, desc, diagnosis_options).with_context(|| format!("diagnosing {}", csv.display()))?;
    let files = vec![
        (format!("{folder}/data.csv"), text),
        (
            format!("{folder}/key.json"),
            json_file::to_string(Schema::BLIND_KEY, &key)?.into_bytes(),
        ),
        (
            format!("{folder}/diagnosis.json"),
            json_file::to_string(Schema::DIAGNOSIS, &d)?.into_bytes(),
        ),
    ];
    // Generator side (knows the truth): the effect's trace against the detectable gap.
    let size = detectable_size(&key, desc, options, diagnosis_options, d.detectable_gap_mm)?;
    let result = CaseResult {
        key,
        diagnosis: d,
        size_ratio: size.map(|s| s.0),
        detectable_magnitude: size.and_then(|s| s.1),
    };
    Ok((result, files))
}

/// The outputs of `blind`, its folder `--out` held for the whole run, so that a second run
/// into it at the same time is refused ([`Outputs::hold_folder`]); its files are placed as
/// one set at the end.
fn held_output(args: &Args) -> Result<Outputs> {
    let mut outputs = Outputs::new(args.force);
    outputs.hold_folder(&args.out)?;
    outputs.check_empty_dir(&args.out)?;
    Ok(outputs)
}

/// The files a case folder holds.
const CASE_FILES: [&str; 3] = ["data.csv", "key.json", "diagnosis.json"];

/// The files of an earlier run's (`--force`) case folders that this run does not write, as
/// names under `out`: beside this run's summary they would read as its cases. Only the files a
/// case writes are named.
fn stale_case_files(out: &std::path::Path, results: &[CaseResult]) -> Result<Vec<String>> {
    let written: std::collections::BTreeSet<String> =
        results.iter().map(|r| format!("case-{:03}", r.key.case)).collect();
    let entries = std::fs::read_dir(out).with_context(|| format!("reading {}", out.display()))?;
    let mut stale = Vec::new();
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let is_case = name
            .strip_prefix("case-")
            .is_some_and(|n| n.len() >= 3 && n.bytes().all(|b| b.is_ascii_digit()));
        if !is_case || written.contains(&name) || !entry.path().is_dir() {
            continue;
        }
        stale.extend(
            CASE_FILES
                .iter()
                .filter(|file| entry.path().join(file).is_file())
                .map(|file| format!("{name}/{file}")),
        );
    }
    Ok(stale)
}

/// Removes the stale case folders emptied by the commit (a folder holding anything else stays).
fn remove_emptied_cases(out: &std::path::Path, stale: &[&str]) {
    let folders: std::collections::BTreeSet<&str> =
        stale.iter().filter_map(|f| f.split_once('/')).map(|f| f.0).collect();
    for folder in folders {
        let _ = std::fs::remove_dir(out.join(folder));
    }
}
