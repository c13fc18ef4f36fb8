//! Monte-Carlo throughput: one analytic trial of the paper scenario (Table 1 + 60
//! validation poses) next to its in-run baseline (the campaign's measurement rows' nominal
//! forward kinematics alone), and a batch of trials on a rayon pool of 1 and of 2 threads
//! (`elements/s` = trials per second; per core = divide by the thread count; the 2-thread
//! over 1-thread ratio is the speed-up). The same trial with `sim = "rapier"` (kinematic mode,
//! line of sight through the link capsules) against the same baseline.

use axiscal::harness::scenario::{CampaignTrial, Overrides, ResolvedScenario, SimMode, Trial, run_units, trial_seed};
use axiscal::robot::commands_to_internal;
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use std::path::Path;

const BATCH: usize = 16;

fn paper() -> ResolvedScenario {
    ResolvedScenario::from_file(
        Path::new("scenarios/paper.toml"),
        Overrides {
            trials: Some(BATCH),
            seed: None,
        },
    )
    .expect("the shipped paper scenario resolves")
}

fn one_trial(c: &mut Criterion) {
    let s = paper();
    let trial = CampaignTrial::new(&s).expect("analytic");
    let case = &s.cases[0];
    let desc = &s.robot;
    let model = desc.nominal_model();
    let mut commands: Vec<Vec<f64>> = Vec::new();
    for sweep in &case.plan.sweeps {
        for step in 0..sweep.poses() {
            commands.push(commands_to_internal(desc, &case.plan.commands(desc, sweep, step)));
        }
    }
    for cmd in s.validation.commands(desc, &case.plan.reference) {
        commands.push(commands_to_internal(desc, &cmd));
    }
    let mut group = c.benchmark_group("analytic_trial");
    group.throughput(Throughput::Elements(1));
    group.bench_function("baseline_nominal_fk_of_every_pose", |b| {
        b.iter(|| {
            for q in &commands {
                black_box(model.poses(black_box(q)));
            }
        })
    });
    let mut i = 0;
    group.bench_function("paper_trial", |b| {
        b.iter(|| {
            i += 1;
            black_box(trial.run(case, trial_seed(s.seed, i)).expect("trial runs"))
        })
    });
    let rapier = ResolvedScenario {
        sim: SimMode::Rapier,
        ..s.clone()
    };
    let rapier_trial = CampaignTrial::new(&rapier).expect("rapier");
    group.sample_size(10);
    group.bench_function("paper_trial_rapier", |b| {
        b.iter(|| {
            i += 1;
            black_box(rapier_trial.run(case, trial_seed(s.seed, i)).expect("trial runs"))
        })
    });
    group.finish();
}

fn threads(c: &mut Criterion) {
    let s = paper();
    let trial = CampaignTrial::new(&s).expect("analytic");
    let mut group = c.benchmark_group("analytic_batch");
    group.throughput(Throughput::Elements(BATCH as u64));
    group.sample_size(10);
    for n in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .expect("thread pool");
        group.bench_function(format!("{BATCH}_trials_{n}_threads"), |b| {
            b.iter(|| pool.install(|| black_box(run_units(&s, &trial, 0..BATCH, &|_| {}))))
        });
    }
    group.finish();
}

criterion_group!(benches, one_trial, threads);
criterion_main!(benches);
