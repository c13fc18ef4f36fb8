//! Diagnosis of a Table-1 campaign with 100 validation poses (target: < 5 s on 2 cores; the
//! default 16 recalibrated noise-only replicas x 32 validation-noise draws), against an
//! in-run baseline: one standard calibration of the same campaign (the diagnosis runs 17 of
//! them plus the refits and the candidates).

use axiscal::calibration::procedure::{CalibrationOptions, calibrate};
use axiscal::diagnosis::{DiagnosisOptions, diagnose};
use axiscal::harness::blind::{BlindOptions, draw_effect, simulate_case};
use axiscal::robot::RobotDescription;
use criterion::{Criterion, criterion_group, criterion_main};
use rand::{SeedableRng, rngs::ChaCha12Rng};
use std::hint::black_box;

mod common;

fn bench(c: &mut Criterion) {
    // `cargo test --all-targets` (`make test`) runs benchmarks once in a debug build, where a
    // diagnosis takes ~30 s; `tests/it/diagnosis.rs` covers it there. Only `cargo bench` runs it.
    if !common::is_cargo_bench() {
        println!("diagnosis bench: skipped outside `cargo bench`");
        return;
    }
    let desc = RobotDescription::asea_irb6l();
    // A joint-3 compliance case (about 3 times its detectable stiffness), so the named
    // candidate's nonlinear refinement runs too.
    let mut key = draw_effect("joint_compliance", 0, 11, &desc, &mut ChaCha12Rng::seed_from_u64(11));
    if let Some(c) = key.effects.compliance.as_mut() {
        c.stiffness_nm_per_rad = vec![1e12; desc.dof()];
        c.stiffness_nm_per_rad[2] = 6e4;
    }
    let set = simulate_case(&key, &desc, &BlindOptions::default()).expect("the case simulates");
    let calibration = CalibrationOptions::default();
    let options = DiagnosisOptions::default();
    let mut g = c.benchmark_group("diagnosis");
    g.sample_size(10);
    g.bench_function("baseline/table1_calibration", |b| {
        b.iter(|| black_box(calibrate(black_box(&set), &desc, &calibration).expect("calibrates")))
    });
    g.bench_function("table1_100_validation_poses", |b| {
        b.iter(|| black_box(diagnose(black_box(&set), &desc, &options).expect("diagnoses")))
    });
    g.finish();

    // The ratio to the in-run baseline, which a loaded machine changes far less than the
    // times: medians of interleaved runs.
    let (b, f) = common::interleaved_medians(
        RUNS,
        (BASELINE_BATCH, &|| {
            black_box(calibrate(black_box(&set), &desc, &calibration).expect("calibrates"));
        }),
        (1, &|| {
            black_box(diagnose(black_box(&set), &desc, &options).expect("diagnoses"));
        }),
    );
    println!(
        "diagnosis/table1_100_validation_poses: {:.3} s = {:.1} x baseline/table1_calibration ({:.2} ms)",
        f,
        f / b,
        b * 1e3
    );
}

/// Interleaved runs per median, and baseline calls per timed run.
const RUNS: usize = 5;
const BASELINE_BATCH: usize = 10;

criterion_group!(benches, bench);
criterion_main!(benches);
