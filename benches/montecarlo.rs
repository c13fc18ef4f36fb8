//! Monte-Carlo throughput: one analytic trial of the paper scenario (Table 1 + 60
//! validation poses) next to its in-run baseline (the campaign's measurement rows' nominal
//! forward kinematics alone), and a batch of trials on a rayon pool of 1 and of 2 threads
//! (`elements/s` = trials per second; per core = divide by the thread count; the 2-thread
//! over 1-thread ratio is the speed-up). The same trial with `sim = "rapier"` (kinematic mode,
//! line of sight through the link capsules) against the same baseline.
//!
//! After criterion's groups a summary prints, from interleaved timings (medians; a loaded
//! machine slows both sides alike), each trial as a ratio to its baseline, the trials per
//! second per core, the 2-thread speed-up, and the rapier arm in dynamic mode (the
//! `compliance` scenario: four-bar bodies, gear coupling, compliance, payload, line of sight)
//! with its own baseline (the nominal forward kinematics of its poses).

use axiscal::harness::scenario::{CampaignTrial, Overrides, ResolvedScenario, SimMode, Trial, run_units, trial_seed};
use axiscal::robot::commands_to_internal;
use criterion::{Criterion, Throughput};
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

mod common;
#[path = "table1/mod.rs"]
mod table1;

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

/// The joint values of every pose of `s`'s first case (calibration sweeps, validation poses):
/// the baseline's work is their nominal forward kinematics.
fn trial_commands(s: &ResolvedScenario) -> Vec<Vec<f64>> {
    let case = &s.cases[0];
    let desc = &s.robot;
    let mut commands: Vec<Vec<f64>> = Vec::new();
    for sweep in &case.plan.sweeps {
        for step in 0..sweep.poses() {
            commands.push(commands_to_internal(desc, &case.plan.commands(desc, sweep, step)));
        }
    }
    for cmd in s.validation.commands(desc, &case.plan.reference) {
        commands.push(commands_to_internal(desc, &cmd));
    }
    commands
}

fn one_trial(c: &mut Criterion) {
    let s = paper();
    let trial = CampaignTrial::new(&s);
    let case = &s.cases[0];
    let model = s.robot.nominal_model();
    let commands = trial_commands(&s);
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
    let rapier_trial = CampaignTrial::new(&rapier);
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
    let trial = CampaignTrial::new(&s);
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

/// Calls per timed batch and batches per median of the summary's ratios.
const BATCHES: usize = 15;

/// The summary: ratios to the in-run baselines (module docs).
fn summary() {
    let s = paper();
    let trial = CampaignTrial::new(&s);
    let commands = trial_commands(&s);
    let model = s.robot.nominal_model();
    let fk = || {
        for q in &commands {
            black_box(model.poses(black_box(q)));
        }
    };
    let seed = std::cell::Cell::new(0usize);
    let run = |t: &CampaignTrial, s: &ResolvedScenario| {
        seed.set(seed.get() + 1);
        black_box(t.run(&s.cases[0], trial_seed(s.seed, seed.get())).expect("trial runs"));
    };
    let (b, t) = common::interleaved_medians(BATCHES, (20, &fk), (20, &|| run(&trial, &s)));
    println!(
        "\nmontecarlo/analytic paper trial ({} poses): {:.3} ms = {:.0} x baseline (nominal FK of its poses, {:.2} us); {:.0} trials/s/core",
        commands.len(),
        t * 1e3,
        t / b,
        b * 1e6,
        1.0 / t
    );
    // The calibration benchmark's baseline, for a machine-independent trial target: issue
    // 19 pairs 0.25 ms with 50x six circle fits, so 0.5 ms a trial is about 100x.
    let sweeps = table1::target0_sweeps(&table1::campaign().1);
    let circles = || {
        for p in &sweeps {
            black_box(axiscal::calibration::fit_circle(black_box(p)).expect("arc"));
        }
    };
    let (c, t) = common::interleaved_medians(BATCHES, (20, &circles), (20, &|| run(&trial, &s)));
    println!(
        "montecarlo/analytic paper trial: {:.3} ms = {:.0} x six circle fits ({:.2} us)",
        t * 1e3,
        t / c,
        c * 1e6
    );
    let pools: Vec<rayon::ThreadPool> = [1, 2]
        .iter()
        .map(|&n| rayon::ThreadPoolBuilder::new().num_threads(n).build().expect("pool"))
        .collect();
    let batch = |p: &rayon::ThreadPool| {
        p.install(|| black_box(run_units(&s, &trial, 0..BATCH, &|_| {})));
    };
    let (one, two) = common::interleaved_medians(5, (1, &|| batch(&pools[0])), (1, &|| batch(&pools[1])));
    println!(
        "montecarlo/{} analytic trials: 1 thread {:.1} ms, 2 threads {:.1} ms: speed-up {:.2}x",
        BATCH,
        one * 1e3,
        two * 1e3,
        one / two
    );
    dynamic_summary();
}

/// The rapier arm in dynamic mode: one trial of the `compliance` scenario (timed one at a time:
/// a trial takes long enough for the clock), against the nominal FK of its poses.
fn dynamic_summary() {
    if !common::is_cargo_bench() {
        return; // a dynamic rapier trial in a debug build is too slow for the smoke test
    }
    let s = ResolvedScenario::from_file(Path::new("scenarios/compliance.toml"), Overrides::default())
        .expect("the shipped compliance scenario resolves");
    let trial = CampaignTrial::new(&s);
    let commands = trial_commands(&s);
    let model = s.robot.nominal_model();
    let fk_start = Instant::now();
    for _ in 0..100 {
        for q in &commands {
            black_box(model.poses(black_box(q)));
        }
    }
    let b = fk_start.elapsed().as_secs_f64() / 100.0;
    let mut times: Vec<f64> = (0..5usize)
        .map(|i| {
            let start = Instant::now();
            black_box(trial.run(&s.cases[0], trial_seed(s.seed, i)).expect("trial runs"));
            start.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    let t = times[times.len() / 2];
    println!(
        "montecarlo/rapier dynamic trial (compliance scenario, {} poses): {:.1} ms = {:.0} x baseline ({:.2} us); {:.1} trials/s/core",
        commands.len(),
        t * 1e3,
        t / b,
        b * 1e6,
        1.0 / t
    );
}

fn main() {
    let mut c = Criterion::default().configure_from_args();
    one_trial(&mut c);
    threads(&mut c);
    summary();
    c.final_summary();
}
