//! `axiscal evaluate`: the paper scenario end to end (simulate the paper robot under the
//! 0.19 mm theodolites -> calibrate -> compensate -> accuracy and repeatability tests), next
//! to the paper's figures and the noise floor measured in the same run; writes
//! `evaluation.json`, `poses.csv`, `calibration.json`, `floor_calibration.json` and the plots.

use super::options::{InRange, THREADS, thread_pool};
use super::output::Outputs;
use super::printer::Printer;
use anyhow::{Context, Result};
use axiscal::harness::evaluation::{
    FloorCheck, PAPER_ORIENTATION_ERROR_RAD, PAPER_POSITION_ERROR_MM, PAPER_REPEATABILITY, PLOT_FILES, PaperReport,
    PaperScenario, Region, RepeatabilitySummary, floor_check_with, run_paper_scenario_with, write_plots,
};
use axiscal::json_file::{self, Schema};
use axiscal::measurement::MeasurementModel;
use std::path::PathBuf;

/// The largest calibrated/floor RMS ratio accepted inside the spans (the 1.1x).
const FLOOR_RATIO_LIMIT: f64 = 1.1;

/// Arguments of `axiscal evaluate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Seed of the campaign's noise.
    #[arg(long, value_parser = super::options::SEED, default_value_t = 1)]
    seed: u64,
    /// Seed of the test poses and of the evaluation's jitter and noise.
    #[arg(long, value_parser = super::options::SEED, default_value_t = 9283)]
    evaluation_seed: u64,
    /// Random test poses per region (inside the spans, workspace).
    #[arg(long, default_value_t = 30, value_parser = InRange::closed(1usize, 1_000_000, ""))]
    random_poses: usize,
    /// Also pool the floor check over this many campaign seeds (`seed ..`), written to
    /// `floor_check.json`; 1: the single run only.
    #[arg(long, default_value_t = 1, value_parser = InRange::closed(1u64, 100_000, ""))]
    floor_seeds: u64,
    /// Output directory.
    #[arg(long, default_value = "results/paper")]
    out: PathBuf,
    /// Print `evaluation.json` on stdout (the human-readable lines go to stderr, or nowhere
    /// with `--quiet`).
    #[arg(long)]
    json: bool,
    /// Worker threads (default: one per core; 1..=1024); the result does not depend on it.
    #[arg(long, value_parser = THREADS)]
    threads: Option<usize>,
    /// Replace existing outputs.
    #[arg(long)]
    force: bool,
}

/// Runs `axiscal evaluate`.
pub fn run(args: Args, printer: Printer) -> Result<()> {
    let printer = printer.with_json(args.json);
    let pool = thread_pool(args.threads)?;
    pool.install(|| evaluate(&args, printer))
}

/// `axiscal evaluate` on the current thread pool.
fn evaluate(args: &Args, printer: Printer) -> Result<()> {
    let (instrument, noise) = MeasurementModel::paper_theodolites().context("calibrating the theodolites")?;
    if printer.verbose {
        eprintln!("{noise}");
    }
    let scenario = PaperScenario::paper(args.seed, args.evaluation_seed, args.random_poses, instrument);
    let mut outputs = vec![
        "evaluation.json",
        "calibration.json",
        "floor_calibration.json",
        "poses.csv",
        "floor_check.json",
    ];
    outputs.extend(PLOT_FILES);
    let guard = Outputs::new(args.force);
    guard.check_in(&args.out, &outputs)?;
    let progress = super::progress::Progress::stage("paper scenario", printer);
    let out = run_paper_scenario_with(&scenario, &progress)?;
    drop(progress);
    let check = match args.floor_seeds > 1 {
        true => {
            let progress = super::progress::Progress::stage("floor check", printer);
            Some(floor_check_with(&scenario, args.floor_seeds, &progress)?)
        }
        false => None,
    };
    let r = &out.report;
    // Every file, plots included, or none (a failure half-way leaves the folder as it was); a
    // floor check of an earlier run goes when this one has none.
    let mut staged = guard.staged_in(&args.out)?;
    staged.write("evaluation.json", json_file::to_string(Schema::EVALUATION, r)?)?;
    staged.write(
        "calibration.json",
        json_file::to_string(Schema::CALIBRATION, &out.calibration)?,
    )?;
    staged.write(
        "floor_calibration.json",
        json_file::to_string(Schema::CALIBRATION, &out.floor_calibration)?,
    )?;
    staged.write("poses.csv", poses_csv(r)?)?;
    if let Some(check) = &check {
        staged.write("floor_check.json", json_file::to_string(Schema::FLOOR_CHECK, check)?)?;
    }
    let mut plots = 0;
    staged.draw(&PLOT_FILES, |dir| {
        write_plots(r, dir).inspect(|drawn| plots = drawn.len())
    })?;
    staged.commit(&["floor_check.json"])?;

    say!(
        printer,
        "paper scenario: seed {}, evaluation seed {}",
        args.seed,
        args.evaluation_seed
    );
    say!(
        printer,
        "ISO 9283 cube edges: {:.0} mm inside the spans, {:.0} mm in the workspace",
        r.iso_cube_edge.inside_spans_m * 1e3,
        r.iso_cube_edge.workspace_m * 1e3
    );
    let inside_ratio = print_regions(r, printer);
    print_repeatability(&r.repeatability, printer);
    say!(
        printer,
        "floor check inside the spans: calibrated/floor position RMS = {inside_ratio:.2} ({} {FLOOR_RATIO_LIMIT}x; see docs/validation.md)",
        if inside_ratio <= FLOOR_RATIO_LIMIT {
            "within"
        } else {
            "ABOVE"
        }
    );
    if let Some(check) = &check {
        print_floor_check(check, printer);
    }
    say!(printer, "wrote {} and {plots} plots", args.out.display());
    printer.emit_json(&args.out.join("evaluation.json"))?;
    Ok(())
}

/// Every test pose's errors (`poses.csv`).
fn poses_csv(r: &PaperReport) -> Result<Vec<u8>> {
    let mut w = axiscal::csv_lines::writer(Vec::new());
    w.write_record([
        "id",
        "region",
        "family",
        "uncal_position_mm",
        "uncal_orientation_rad",
        "cal_position_mm",
        "cal_orientation_rad",
        "floor_position_mm",
        "floor_orientation_rad",
        "cal_model_position_mm",
        "floor_model_position_mm",
        "failure",
    ])?;
    let f = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:.6}"));
    for p in &r.poses {
        w.write_record([
            p.id.clone(),
            p.region.name().into(),
            p.family.clone(),
            f(Some(p.uncalibrated.position_mm)),
            f(Some(p.uncalibrated.orientation_rad)),
            f(p.calibrated.map(|e| e.position_mm)),
            f(p.calibrated.map(|e| e.orientation_rad)),
            f(p.floor.map(|e| e.position_mm)),
            f(p.floor.map(|e| e.orientation_rad)),
            f(p.calibrated.map(|e| e.model_position_mm)),
            f(p.floor.map(|e| e.model_position_mm)),
            p.failure.clone().unwrap_or_default(),
        ])?;
    }
    w.into_inner().map_err(|e| anyhow::anyhow!("poses.csv: {}", e.error()))
}

/// Prints each region's accuracy next to the paper's and the floor; returns the calibrated/floor
/// position RMS ratio inside the spans (NaN when that region is absent).
fn print_regions(r: &PaperReport, printer: Printer) -> f64 {
    let mut inside_ratio = f64::NAN;
    for s in &r.regions {
        say!(
            printer,
            "{} ({} poses, {} failed):",
            s.region.name(),
            s.position_mm.uncalibrated.n,
            s.failures
        );
        let rows = [
            (
                "position    [mm] ",
                &s.position_mm,
                PAPER_POSITION_ERROR_MM,
                s.ratio_to_floor.position,
                3,
            ),
            (
                "orientation [rad]",
                &s.orientation_rad,
                PAPER_ORIENTATION_ERROR_RAD,
                s.ratio_to_floor.orientation,
                4,
            ),
        ];
        for (label, st, paper, ratio, p) in rows {
            say!(
                printer,
                "  {label} uncalibrated mean {:7.p$} rms {:7.p$}   (paper {:.2} mean)",
                st.uncalibrated.mean,
                st.uncalibrated.rms,
                paper[0]
            );
            say!(
                printer,
                "                    calibrated   mean {:7.p$} rms {:7.p$}   (paper {:.2})  floor rms {:.p$}  ratio {ratio:.2}",
                st.calibrated.mean,
                st.calibrated.rms,
                paper[1],
                st.floor.rms
            );
        }
        say!(
            printer,
            "  model only (no jitter, no noise): position rms {:.3} mm (floor {:.3}, ratio {:.2})",
            s.model_position_mm.calibrated.rms,
            s.model_position_mm.floor.rms,
            s.model_ratio_to_floor.position
        );
        if s.region == Region::InsideSpans {
            inside_ratio = s.ratio_to_floor.position;
        }
    }
    inside_ratio
}

/// Prints the repeatability test next to the paper's.
fn print_repeatability(rep: &RepeatabilitySummary, printer: Printer) {
    say!(
        printer,
        "repeatability ({} poses, mean of 2 executions): observed {:.3} mm / {:.4} rad (paper {:.2} mm / {:.4} rad, \
         through theodolites); robot alone {:.3} mm / {:.4} rad",
        rep.poses,
        rep.observed_radial_mm,
        rep.observed_orientation_rad,
        PAPER_REPEATABILITY[0],
        PAPER_REPEATABILITY[1],
        rep.robot_radial_mm,
        rep.robot_orientation_rad
    );
}

/// Prints the floor check pooled over the campaign seeds (`floor_check.json`).
fn print_floor_check(check: &FloorCheck, printer: Printer) {
    say!(
        printer,
        "floor check pooled over seeds {}..{}: calibrated/floor RMS position {:.3} ({:.3} / {:.3} mm), \
             orientation {:.3} ({} {FLOOR_RATIO_LIMIT}x)",
        check.first_seed,
        check.first_seed + check.seeds - 1,
        check.ratio.position,
        check.position_rms.calibrated_mm,
        check.position_rms.floor_mm,
        check.ratio.orientation,
        if check.ratio.position <= FLOOR_RATIO_LIMIT && check.ratio.orientation <= FLOOR_RATIO_LIMIT {
            "within"
        } else {
            "ABOVE"
        }
    );
}
