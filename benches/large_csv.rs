//! A 1 M-row measurement CSV, read and calibrated as `axiscal calibrate` does (target: under
//! 10 s in release), against an in-run baseline: the csv crate splitting the same file into
//! records without reading a number (the least any reader of the file must do).
//!
//! The file is the reproduction: a simulated Table-1 campaign whose validation rows are
//! repeated with new step numbers up to 1 000 000 rows (about 200 MB). Outside `cargo bench`
//! (`cargo test --all-targets`) 20 000 rows, once, as a smoke test. Peak memory is measured
//! outside the benchmark (`/usr/bin/time -v axiscal calibrate`, docs/performance.md).

use axiscal::calibration::procedure::{CalibrationOptions, calibrate};
use axiscal::measurement::{MeasurementModel, MeasurementSet, read_measurements, write_measurements_to};
use axiscal::plan::{CalibrationPlan, ValidationPlan};
use axiscal::robot::{Controller, RobotDescription};
use axiscal::sim::{AnalyticArm, simulate_campaign};
use criterion::{Criterion, criterion_group, criterion_main};
use rand::{SeedableRng, rngs::ChaCha12Rng};
use std::hint::black_box;
use std::io::Write;
use std::path::Path;

mod common;

/// Writes the campaign with its validation rows repeated to `rows` rows into `path`.
fn write_large_file(path: &Path, rows: usize) {
    let desc = RobotDescription::asea_irb6l();
    let mut arm = AnalyticArm::new(axiscal::sim::paper_robot(), Controller::from_description(&desc));
    let out = simulate_campaign(
        &desc,
        &CalibrationPlan::table1(6),
        &ValidationPlan::workspace_default(6),
        &mut arm,
        &MeasurementModel::paper_isotropic(),
        &mut ChaCha12Rng::seed_from_u64(3),
    )
    .expect("the paper campaign simulates");
    let set = MeasurementSet::new(6, out.rows).expect("consistent rows");
    let mut text = Vec::new();
    write_measurements_to(&mut text, &set).expect("in memory");
    let text = String::from_utf8(text).expect("UTF-8");
    let validation: Vec<&str> = text.lines().filter(|l| l.starts_with("validation,")).collect();
    let mut file = std::io::BufWriter::new(std::fs::File::create(path).expect("a temporary file"));
    file.write_all(text.as_bytes()).expect("written");
    let mut n = text.lines().count() - 1;
    let mut copy = 1;
    while n < rows {
        for v in &validation {
            let mut cells: Vec<&str> = v.split(',').collect();
            let step = (cells[2].parse::<usize>().expect("a step") + 1000 * copy).to_string();
            cells[2] = &step;
            writeln!(file, "{}", cells.join(",")).expect("written");
            n += 1;
            if n == rows {
                break;
            }
        }
        copy += 1;
    }
    file.flush().expect("written");
}

fn bench(c: &mut Criterion) {
    let rows = if common::is_cargo_bench() { 1_000_000 } else { 20_000 };
    let dir = tempfile::tempdir().expect("a temporary folder");
    let path = dir.path().join("large.csv");
    write_large_file(&path, rows);
    let desc = RobotDescription::asea_irb6l();
    let options = CalibrationOptions::default();
    let baseline = || {
        let mut reader = csv::Reader::from_path(&path).expect("readable");
        let mut record = csv::StringRecord::new();
        let mut n = 0usize;
        while reader.read_record(&mut record).expect("CSV") {
            n += record.len();
        }
        black_box(n);
    };
    let measured = || {
        let set = read_measurements(&path, Some(desc.dof())).expect("a valid file");
        black_box(calibrate(&set, &desc, &options).expect("calibrates"));
    };
    let mut g = c.benchmark_group("large_csv");
    g.sample_size(10);
    g.bench_function("baseline/csv_records_only", |b| b.iter(baseline));
    g.bench_function("read_and_calibrate", |b| b.iter(measured));
    g.finish();
    let (b, f) = common::interleaved_medians(3, (1, &baseline), (1, &measured));
    println!(
        "large_csv/read_and_calibrate ({rows} rows, {:.0} MB): {f:.2} s = {:.2} x baseline/csv_records_only ({b:.2} s)",
        std::fs::metadata(&path).map_or(0.0, |m| m.len() as f64 / 1e6),
        f / b
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
