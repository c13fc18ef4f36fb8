//! One full 6-axis calibration of a Table-1 campaign, and the lean path of the Monte-Carlo
//! trials (`calibrate_model`: the model only; target <= 50x the baseline), against an in-run
//! baseline: one circle fit per axis (the least any per-axis method must do).

use axiscal::calibration::fit_circle;
use axiscal::calibration::procedure::{CalibrationOptions, Detail, calibrate, calibrate_model};
use axiscal::measurement::{MeasurementModel, MeasurementSet};
use axiscal::plan::{CalibrationPlan, ValidationPlan};
use axiscal::robot::{Controller, RobotDescription};
use axiscal::sim::{AnalyticArm, simulate_campaign};
use criterion::{Criterion, criterion_group, criterion_main};
use rand::{SeedableRng, rngs::ChaCha12Rng};
use std::hint::black_box;

mod common;

fn campaign() -> (RobotDescription, MeasurementSet) {
    let desc = RobotDescription::asea_irb6l();
    let mut arm = AnalyticArm::new(axiscal::sim::paper_robot(), Controller::from_description(&desc));
    let validation = ValidationPlan {
        poses: 0,
        ..ValidationPlan::workspace_default(6)
    };
    let out = simulate_campaign(
        &desc,
        &CalibrationPlan::table1(6),
        &validation,
        &mut arm,
        &MeasurementModel::paper_isotropic(),
        &mut ChaCha12Rng::seed_from_u64(1),
    )
    .expect("the paper campaign simulates");
    let set = MeasurementSet::new(6, out.rows).expect("consistent rows");
    (desc, set)
}

fn bench(c: &mut Criterion) {
    let (desc, set) = campaign();
    let sweeps: Vec<Vec<nalgebra::Point3<f64>>> = set
        .experiments()
        .iter()
        .filter(|e| e.moved_joint > 0)
        .map(|e| {
            e.rows
                .iter()
                .filter(|r| r.target == 0)
                .map(|r| r.position_m())
                .collect()
        })
        .collect();
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
