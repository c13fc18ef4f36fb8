//! A driver for `valgrind --tool=callgrind` (instruction counts, which a loaded machine does
//! not change): `cargo build --release --example profile_speed`, then
//! `valgrind --tool=callgrind target/release/examples/profile_speed WHAT N` with WHAT one of
//! `circles`, `full`, `lean`, `trial` (the benchmarks' work: six circle fits, the full and the
//! lean Table-1 calibration, one analytic paper trial), called N times after one warm-up call.
//! Instructions per call = (total of N calls - total of 0 calls) / N.

use axiscal::calibration::fit_circle;
use axiscal::calibration::procedure::{CalibrationOptions, Detail, calibrate, calibrate_model};
use axiscal::harness::scenario::{CampaignTrial, Overrides, ResolvedScenario, Trial, trial_seed};
use std::hint::black_box;
use std::path::Path;

#[path = "../benches/common/allocator.rs"]
mod allocator;
#[path = "../benches/table1/mod.rs"]
mod table1;
use table1::{campaign, target0_sweeps};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let what = args.get(1).map(String::as_str).unwrap_or("lean");
    let n: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(10);
    let (desc, set) = campaign();
    let options = CalibrationOptions::default();
    let sweeps = target0_sweeps(&set);
    let scenario = ResolvedScenario::from_file(
        Path::new("scenarios/paper.toml"),
        Overrides {
            trials: Some(1),
            seed: None,
        },
    )
    .expect("the paper scenario resolves");
    let trial = CampaignTrial::new(&scenario);
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
