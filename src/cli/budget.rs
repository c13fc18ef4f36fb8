//! `axiscal budget`: the paper's gap budget. For each candidate unmodelled
//! effect, the magnitude that raises the simulated calibrated position error of the paper
//! robot inside the spans to the paper's 1.40 mm; writes `budget.json` and `budget.md`.

use super::OneOf;
use super::options::{InRange, THREADS, thread_pool};
use super::output::Outputs;
use super::printer::Printer;
use anyhow::{Context, Result};
use axiscal::harness::evaluation::{BudgetEffect, BudgetLine, BudgetSettings, PaperScenario, gap_budget_with};
use axiscal::json_file::{self, Schema};
use axiscal::measurement::MeasurementModel;
use std::fmt::Write as _;
use std::path::PathBuf;

/// The budgeted effects by their command-line names.
const EFFECTS: &[(&str, BudgetEffect)] = &[
    ("compliance", BudgetEffect::Compliance),
    ("backlash", BudgetEffect::Backlash),
    ("thermal", BudgetEffect::Thermal),
    ("gear-harmonic", BudgetEffect::GearHarmonic),
    ("wobble", BudgetEffect::Wobble),
    ("instrument-scale", BudgetEffect::InstrumentScale),
];

/// Arguments of `axiscal budget`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// First campaign seed; seeds `seed .. seed + seeds` are pooled per magnitude.
    #[arg(long, value_parser = super::options::SEED, default_value_t = 1)]
    seed: u64,
    /// Campaigns pooled per magnitude.
    #[arg(long, default_value_t = 8, value_parser = InRange::closed(1u64, 100_000, ""))]
    seeds: u64,
    /// Seed of the test poses and of the evaluation's jitter and noise.
    #[arg(long, value_parser = super::options::SEED, default_value_t = 9283)]
    evaluation_seed: u64,
    /// Random test poses inside the spans per campaign.
    #[arg(long, default_value_t = 30, value_parser = InRange::closed(1usize, 1_000_000, ""))]
    random_poses: usize,
    /// Effects to budget (default: all).
    #[arg(long, value_parser = OneOf(EFFECTS), value_delimiter = ',')]
    effects: Vec<BudgetEffect>,
    /// Worker threads (default: one per core); the result does not depend on it.
    #[arg(long, value_parser = THREADS)]
    threads: Option<usize>,
    /// Output directory.
    #[arg(long, default_value = "results/budget")]
    out: PathBuf,
    /// Replace existing outputs.
    #[arg(long)]
    force: bool,
}

/// A magnitude in the units a reader compares with data sheets.
fn readable(line: &BudgetLine, magnitude: f64) -> String {
    match line.effect {
        BudgetEffect::Compliance => format!("stiffness {:.3e} N m/rad on every joint", 1.0 / magnitude),
        BudgetEffect::Backlash => format!("band {:.3} mrad on every joint", magnitude * 1e3),
        BudgetEffect::Thermal => format!("{magnitude:.2} K warmer in use than in calibration (steel)"),
        BudgetEffect::GearHarmonic => format!("order-2 term {:.3} mrad on every transmission", magnitude * 1e3),
        BudgetEffect::Wobble => format!("order-2 tilt {:.3} mrad on every axis", magnitude * 1e3),
        BudgetEffect::InstrumentScale => format!("{magnitude:.1} ppm"),
    }
}

fn markdown(settings: &BudgetSettings, lines: &[BudgetLine]) -> String {
    let mut md = String::from("# The paper's gap budget\n\n");
    let base = lines.first().map(|l| l.without_effect);
    let _ = writeln!(
        md,
        "Paper robot, Table-1 campaign, 0.19 mm theodolites, seeds {}..{}, {} test poses inside the spans per \
         campaign. Without any effect the calibrated mean error is {:.3} mm (RMS {:.3} mm); the paper measured \
         {:.2} mm. Each row: the magnitude of one effect, the same on every joint, that brings the mean to {:.2} mm.\n",
        settings.scenario.seed,
        settings.scenario.seed + settings.seeds - 1,
        base.map_or(0, |b| b.n as u64 / settings.seeds.max(1)),
        base.map_or(f64::NAN, |b| b.mean),
        base.map_or(f64::NAN, |b| b.rms),
        settings.target_mean_mm,
        settings.target_mean_mm,
    );
    md.push_str("| effect | magnitude for the paper's gap | mean error there (mm) |\n|---|---|---:|\n");
    for l in lines {
        let what = match l.magnitude {
            Some(m) => readable(l, m),
            None => format!("not reached up to {}", readable(l, l.largest_tried)),
        };
        let _ = writeln!(md, "| {} | {what} | {:.3} |", l.effect.name(), l.mean_mm);
    }
    md
}

/// Runs `axiscal budget`.
pub fn run(args: Args, printer: Printer) -> Result<()> {
    let names = ["budget.json", "budget.md"];
    let outputs = Outputs::new(args.force);
    outputs.check_in(&args.out, &names)?;
    let (instrument, _) = MeasurementModel::paper_theodolites().context("calibrating the theodolites")?;
    let scenario = PaperScenario::paper(args.seed, args.evaluation_seed, args.random_poses, instrument);
    let settings = BudgetSettings::paper(scenario, args.seeds);
    let effects = if args.effects.is_empty() {
        BudgetEffect::ALL.to_vec()
    } else {
        args.effects
    };
    let pool = thread_pool(args.threads)?;
    let progress = super::progress::Progress::stage("gap budget", printer);
    let lines = pool.install(|| gap_budget_with(&settings, &effects, &progress))?;
    drop(progress);
    let md = markdown(&settings, &lines);
    print!("{md}");
    // Both files or neither (a failure half-way leaves the folder as it was).
    let mut staged = outputs.staged_in(&args.out)?;
    staged.write(
        names[0],
        json_file::to_string(
            Schema::BUDGET,
            &axiscal::harness::evaluation::BudgetReport {
                settings: settings.clone(),
                lines: lines.clone(),
            },
        )?,
    )?;
    staged.write(names[1], &md)?;
    staged.commit(&[])?;
    println!("wrote {}", args.out.display());
    Ok(())
}
