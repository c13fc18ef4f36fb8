//! One full 6-axis calibration of a Table-1 campaign, and the lean path of the Monte-Carlo
//! trials (`calibrate_model`: the model only; target <= 50x the baseline), against an in-run
//! baseline: one circle fit per axis (the least any per-axis method must do).

use axiscal::calibration::fit_circle;
use axiscal::calibration::procedure::{CalibrationOptions, Detail, calibrate, calibrate_model};
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

mod common;
#[path = "table1/mod.rs"]
mod table1;
use table1::{campaign, target0_sweeps};

fn bench(c: &mut Criterion) {
    let (desc, set) = campaign();
    let sweeps = target0_sweeps(&set);
    let mut g = c.benchmark_group("calibration");
    g.bench_function("baseline/six_circle_fits", |b| {
        b.iter(|| {
            for s in &sweeps {
                black_box(fit_circle(black_box(s)).expect("arc"));
            }
        })
    });
    let options = CalibrationOptions::default();
    g.bench_function("full_table1_calibration", |b| {
        b.iter(|| black_box(calibrate(black_box(&set), &desc, &options).expect("calibrates")))
    });
    g.bench_function("lean_table1_calibration", |b| {
        b.iter(|| black_box(calibrate_model(black_box(&set), &desc, &options, Detail::Model).expect("calibrates")))
    });
    g.finish();

    // The ratio to the in-run baseline, which a loaded machine changes far less than the
    // times: medians of interleaved batches.
    let circles = || {
        for s in &sweeps {
            black_box(fit_circle(black_box(s)).expect("arc"));
        }
    };
    let full = || {
        black_box(calibrate(black_box(&set), &desc, &options).expect("calibrates"));
    };
    let (set_ref, desc_ref, options_ref) = (&set, &desc, &options);
    let lean = |detail| {
        move || {
            black_box(calibrate_model(black_box(set_ref), desc_ref, options_ref, detail).expect("calibrates"));
        }
    };
    let (model, with_covariance) = (lean(Detail::Model), lean(Detail::ModelAndCovariance));
    let measured: [(&str, &dyn Fn()); 3] = [
        ("full_table1_calibration", &full),
        ("lean_table1_calibration (model)", &model),
        ("lean_table1_calibration (model_and_covariance)", &with_covariance),
    ];
    for (name, f) in measured {
        let (b, t) = common::interleaved_medians(BATCHES, (BATCH, &circles), (BATCH, f));
        println!(
            "calibration/{name}: {:.1} us = {:.1} x baseline/six_circle_fits ({:.2} us)",
            t * 1e6,
            t / b,
            b * 1e6
        );
    }
}

/// Calls per timed batch and batches per median, for the ratio.
const BATCH: usize = 20;
const BATCHES: usize = 25;

criterion_group!(benches, bench);
criterion_main!(benches);
