//! A driver for `valgrind --tool=callgrind` (instruction counts, which a loaded machine does
//! not change): `cargo build --release --example profile_speed`, then
//! `valgrind --tool=callgrind target/release/examples/profile_speed WHAT N` with WHAT one of
//! `circles`, `full`, `lean`, `trial` (the benchmarks' work: six circle fits, the full and the
//! lean Table-1 calibration, one analytic paper trial), called N times after one warm-up call.
//! Instructions per call = (total of N calls - total of 0 calls) / N.

use axiscal::calibration::fit_circle;
use axiscal::calibration::procedure::{CalibrationOptions, Detail, calibrate, calibrate_model};
use axiscal::harness::scenario::{CampaignTrial, Overrides, ResolvedScenario, Trial, trial_seed};
use axiscal::measurement::{MeasurementModel, MeasurementSet};
use axiscal::plan::{CalibrationPlan, ValidationPlan};
use axiscal::robot::{Controller, RobotDescription};
use axiscal::sim::{AnalyticArm, simulate_campaign};
use rand::{SeedableRng, rngs::ChaCha12Rng};
use std::hint::black_box;
use std::path::Path;

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

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let what = args.get(1).map(String::as_str).unwrap_or("lean");
    let n: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(10);
    let (desc, set) = campaign();
    let options = CalibrationOptions::default();
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
    let scenario = ResolvedScenario::from_file(
        Path::new("scenarios/paper.toml"),
        Overrides {
            trials: Some(1),
            seed: None,
        },
    )
    .expect("the paper scenario resolves");
    let trial = CampaignTrial::new(&scenario).expect("analytic");
    let call = |i: usize| match what {
        "circles" => {
            for s in &sweeps {
                black_box(fit_circle(black_box(s)).expect("arc"));
            }
        }
        "full" => {
            black_box(calibrate(black_box(&set), &desc, &options).expect("calibrates"));
        }
        "lean" => {
            black_box(calibrate_model(black_box(&set), &desc, &options, Detail::Model).expect("calibrates"));
        }
        "trial" => {
            black_box(
                trial
                    .run(&scenario.cases[0], trial_seed(scenario.seed, i))
                    .expect("trial runs"),
            );
        }
        other => panic!("unknown {other}: circles, full, lean or trial"),
    };
    for i in 0..=n {
        call(i);
    }
}
