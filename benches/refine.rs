//! `calibrate --refine` on a Table-1 campaign of the jitter-free paper robot with 60 free poses
//! (target: < 50 ms), against an in-run baseline: one standard calibration of the same
//! campaign. The printed ratio is the number to compare across machines; 50 ms is the target
//! on the reference machine (`docs/validation.md`, "Refinement on free poses").

use axiscal::calibration::procedure::{CalibrationOptions, calibrate};
use axiscal::calibration::refine::RefineOptions;
use axiscal::calibration::refit_model::refine::refine_calibration;
use axiscal::measurement::{IsotropicNoise, MeasurementModel, MeasurementSet};
use axiscal::plan::{CalibrationPlan, ValidationPlan};
use axiscal::robot::{Controller, RobotDescription};
use axiscal::sim::{AnalyticArm, simulate_campaign};
use criterion::{Criterion, criterion_group, criterion_main};
use rand::{SeedableRng, rngs::ChaCha12Rng};
use std::hint::black_box;

mod common;

fn campaign(desc: &RobotDescription) -> MeasurementSet {
    let mut truth = axiscal::sim::paper_robot();
    for j in &mut truth.joints {
        j.repeatability_sigma = 0.0;
    }
    let mut arm = AnalyticArm::new(truth, Controller::from_description(desc));
    let validation = ValidationPlan {
        poses: 60,
        ..ValidationPlan::workspace_default(6)
    };
    let instrument = MeasurementModel::Isotropic(IsotropicNoise {
        net_radial_rms_mm: 0.19,
    });
    let out = simulate_campaign(
        desc,
        &CalibrationPlan::table1(6),
        &validation,
        &mut arm,
        &instrument,
        &mut ChaCha12Rng::seed_from_u64(60),
    )
    .expect("the campaign runs");
    MeasurementSet::new(desc.dof(), out.rows).expect("a valid set")
}

fn bench(c: &mut Criterion) {
    let desc = RobotDescription::asea_irb6l();
    let set = campaign(&desc);
    let calibration = CalibrationOptions::default();
    let cal = calibrate(&set, &desc, &calibration).expect("calibrates");
    let options = RefineOptions::default();
    let refine = || black_box(refine_calibration(black_box(&set), &desc, &cal, &options).expect("refines"));
    let mut g = c.benchmark_group("refine");
    g.sample_size(10);
    g.bench_function("baseline/table1_calibration", |b| {
        b.iter(|| black_box(calibrate(black_box(&set), &desc, &calibration).expect("calibrates")))
    });
    g.bench_function("60_free_poses", |b| b.iter(refine));
    g.finish();
    let (b, f) = common::interleaved_medians(
        RUNS,
        (BATCH, &|| {
            black_box(calibrate(black_box(&set), &desc, &calibration).expect("calibrates"));
        }),
        (BATCH, &|| {
            refine();
        }),
    );
    println!(
        "refine/60_free_poses: {:.2} ms = {:.2} x baseline/table1_calibration ({:.2} ms); target 50 ms",
        f * 1e3,
        f / b,
        b * 1e3
    );
}

/// Interleaved runs per median, and calls per timed run.
const RUNS: usize = 7;
const BATCH: usize = 3;

criterion_group!(benches, bench);
criterion_main!(benches);
