//! Cost of the simulated arm: kinematic mode per pose, one dynamics step, and a full
//! static-equilibrium settle (plain arm, arm with the four-bar's bodies, and the campaign's
//! `RapierArm` in both modes), each next to the phi-model forward kinematics of the same pose
//! (`PhiModel::poses`) as an in-run baseline, so the numbers read as ratios.
//!
//! After criterion's groups, a summary times each case again (best of three batches) and
//! prints time per pose, steps per pose and steps per second of the dynamic cases, and every
//! time as a ratio to the baseline measured in the same run.

use axiscal::measurement::MeasurementModel;
use axiscal::physics::ComplianceEffect;
use axiscal::plan::PoseConditions;
use axiscal::robot::RobotDescription;
use axiscal::sim::{ArmExecutor, Effects};
use axiscal::sim::{
    ArmOptions, Compliance, FourBarBodies, RapierArm, RapierArmOptions, ServoGains, SettleOptions, SettleReport, SimArm,
};
use criterion::{Criterion, Throughput};
use rand::SeedableRng;
use rand::rngs::ChaCha12Rng;
use std::hint::black_box;
use std::time::Instant;

#[path = "common/allocator.rs"]
mod allocator;

const Q: [f64; 6] = [0.3, -0.2, 0.25, 0.4, -0.6, 0.8];

fn arm() -> (SimArm, RobotDescription) {
    let d = RobotDescription::asea_irb6l();
    let arm = SimArm::from_description(&d.nominal_model(), &d, &ArmOptions::new(d.dof()))
        .expect("the shipped description builds");
    (arm, d)
}

fn gains(arm: &SimArm) -> ServoGains {
    let mut stiffness = [1e8; 6];
    stiffness[2] = 2e5;
    ServoGains::with_damping_ratio(arm, &Q, &stiffness, 1.0)
}

/// The nominal arm with the paper truth's four-bar (arm length set to the nominal 0.69 m).
fn four_bar_arm() -> (SimArm, FourBarBodies, [f64; 6]) {
    let d = RobotDescription::asea_irb6l();
    let mut arm = SimArm::from_description(&d.nominal_model(), &d, &ArmOptions::new(6)).expect("builds");
    let mut linkage = axiscal::sim::paper_robot().four_bars[0];
    linkage.geometry.arm_m = d.rows[1].a_m.abs();
    let bodies = FourBarBodies::attach(&mut arm, &linkage).expect("attaches");
    let mut q = Q;
    q[2] = linkage.geometry.passive(Q[1]).expect("closes at the bench pose");
    (arm, bodies, q)
}

/// One four-bar settle: placed closed at `q`, servos of [`gains`] (the crank holds actuator
/// 3's stiffness), joint 3 driven by the mechanism.
fn settle_four_bar(arm: &mut SimArm, bodies: &mut FourBarBodies, q: &[f64; 6]) -> SettleReport {
    arm.set_joint_positions(q).expect("six values");
    let crank = bodies.place(arm).expect("closes");
    let g = gains(arm);
    arm.set_servo(q, &g).expect("valid gains");
    bodies
        .drive(arm, crank, g.stiffness_nm_per_rad[2], g.damping_nms_per_rad[2])
        .expect("drives");
    arm.settle(&[], &SettleOptions::default()).expect("settles")
}

/// The campaign's executors for the paper truth (four-bar bodies on): kinematic with line of
/// sight from the two stations, and compliant with the compliance scenario's stiffnesses.
fn rapier_arms() -> (RapierArm, RapierArm) {
    let d = RobotDescription::asea_irb6l();
    let (instrument, _) = MeasurementModel::paper_theodolites().expect("theodolites");
    let options = RapierArmOptions {
        stations_m: instrument.stations_m(),
        ..RapierArmOptions::new(6)
    };
    let kinematic = RapierArm::new(axiscal::sim::paper_robot(), &d, Effects::default(), options.clone());
    let compliance = Effects {
        compliance: Some(ComplianceEffect::new(
            vec![5e5, 3e5, 3e5, 5e4, 5e4, 2e4],
            [0.0, 0.0, -9.81],
        )),
        ..Effects::default()
    };
    (
        kinematic,
        RapierArm::new(axiscal::sim::paper_robot(), &d, compliance, options),
    )
}

fn kinematic(c: &mut Criterion) {
    let (mut arm, d) = arm();
    let model = d.nominal_model();
    let mut group = c.benchmark_group("kinematic_pose");
    group.throughput(Throughput::Elements(1));
    group.bench_function("baseline_phi_model_poses", |b| {
        b.iter(|| black_box(model.poses(black_box(&Q))))
    });
    group.bench_function("sim_set_positions_and_read_links", |b| {
        b.iter(|| {
            arm.set_joint_positions(black_box(&Q)).expect("six values");
            black_box((0..6).map(|k| arm.world_from_link(k)).collect::<Vec<_>>())
        })
    });
    group.finish();
}

fn dynamic(c: &mut Criterion) {
    let (mut arm, d) = arm();
    let model = d.nominal_model();
    let servo = Compliance::Servo(gains(&arm));
    let options = SettleOptions::default();
    let mut group = c.benchmark_group("dynamic");
    group.sample_size(10);
    group.bench_function("baseline_phi_model_poses", |b| {
        b.iter(|| black_box(model.poses(black_box(&Q))))
    });
    // The settle's own step: 1 ms of `SettleOptions::solver_iterations` substeps (8).
    group.bench_function("one_step_1ms_settle_iterations", |b| {
        arm.static_equilibrium(&Q, &servo, &[], &options).expect("settles");
        b.iter(|| arm.world_mut().step())
    });
    group.bench_function("settle_one_pose", |b| {
        b.iter(|| {
            black_box(
                arm.static_equilibrium(black_box(&Q), &servo, &[], &options)
                    .expect("settles"),
            )
        })
    });
    let (mut fb_arm, mut bodies, q) = four_bar_arm();
    group.bench_function("settle_one_pose_four_bar", |b| {
        b.iter(|| black_box(settle_four_bar(&mut fb_arm, &mut bodies, &q)))
    });
    group.finish();
}

fn rapier_arm(c: &mut Criterion) {
    let (mut kinematic, mut compliant) = rapier_arms();
    let model = RobotDescription::asea_irb6l().nominal_model();
    let mut rng = ChaCha12Rng::seed_from_u64(1);
    let conditions = PoseConditions::default();
    let target = nalgebra::Point3::new(-3.1423, 5.3, 0.0);
    let mut group = c.benchmark_group("rapier_arm_execute");
    group.throughput(Throughput::Elements(1));
    group.bench_function("baseline_phi_model_poses", |b| {
        b.iter(|| black_box(model.poses(black_box(&Q))))
    });
    group.bench_function("kinematic_pose_and_line_of_sight", |b| {
        b.iter(|| {
            let links = kinematic.execute(black_box(&Q), &conditions, &mut rng).expect("runs");
            black_box((links, kinematic.visible(&target)))
        })
    });
    group.sample_size(10);
    group.bench_function("compliant_static_equilibrium_four_bar_gear", |b| {
        b.iter(|| {
            black_box(
                compliant
                    .execute(black_box(&Q), &conditions, &mut rng)
                    .expect("settles"),
            )
        })
    });
    group.finish();
}

/// Seconds per call of `f`: the best of three batches of `n` calls.
fn seconds_per_call(n: usize, mut f: impl FnMut()) -> f64 {
    (0..3)
        .map(|_| {
            let start = Instant::now();
            for _ in 0..n {
                f();
            }
            start.elapsed().as_secs_f64() / n as f64
        })
        .fold(f64::INFINITY, f64::min)
}

/// Time per pose (and for the dynamic cases steps per pose and steps per second), each as a
/// ratio to the phi-model baseline timed in the same run.
fn summary() {
    let (mut arm, d) = arm();
    let model = d.nominal_model();
    let baseline_s = seconds_per_call(100_000, || {
        black_box(model.poses(black_box(&Q)));
    });
    println!(
        "\nsummary, time per pose (best of 3 batches; ratio = time / baseline {:.3} us):",
        baseline_s * 1e6
    );
    let line = |name: &str, seconds: f64, steps: Option<usize>| {
        let per_step = steps.map_or(String::new(), |s| {
            format!(", {s} steps/pose, {:.0} steps/s", s as f64 / seconds)
        });
        println!(
            "  {name:<48} {:>12.3} us  ratio {:>10.3}{per_step}",
            seconds * 1e6,
            seconds / baseline_s
        );
    };
    line("baseline PhiModel::poses", baseline_s, None);
    let kin_s = seconds_per_call(20_000, || {
        arm.set_joint_positions(black_box(&Q)).expect("six values");
        black_box(arm.world_from_link(5));
    });
    line("kinematic SimArm pose (set q, read links)", kin_s, None);
    let (mut kinematic, mut compliant) = rapier_arms();
    let mut rng = ChaCha12Rng::seed_from_u64(2);
    let conditions = PoseConditions::default();
    let target = nalgebra::Point3::new(-3.1423, 5.3, 0.0);
    let exec_s = seconds_per_call(2_000, || {
        let links = kinematic.execute(&Q, &conditions, &mut rng).expect("runs");
        black_box((links, kinematic.visible(&target)));
    });
    line("kinematic RapierArm pose + line of sight", exec_s, None);
    let servo = Compliance::Servo(gains(&arm));
    let options = SettleOptions::default();
    let mut steps = 0;
    let settle_s = seconds_per_call(5, || {
        let r = arm.static_equilibrium(&Q, &servo, &[], &options).expect("settles");
        steps = r.total_steps();
    });
    line("dynamic: settle one pose", settle_s, Some(steps));
    // At rest under the servos: the cost of one step alone, with the settle's solver
    // iterations (rapier substeps) and with 16, for
    // comparison.
    let step_s = seconds_per_call(2_000, || arm.world_mut().step());
    line(
        &format!(
            "dynamic: one step at rest (1 ms, {} iterations)",
            options.solver_iterations
        ),
        step_s,
        Some(1),
    );
    arm.world_mut().integration_parameters.num_solver_iterations = 16;
    let step16_s = seconds_per_call(2_000, || arm.world_mut().step());
    line("dynamic: one step at rest (1 ms, 16 iterations)", step16_s, Some(1));
    let (mut fb_arm, mut bodies, q) = four_bar_arm();
    let fb_s = seconds_per_call(5, || {
        let r = settle_four_bar(&mut fb_arm, &mut bodies, &q);
        steps = r.total_steps();
    });
    line("dynamic: settle one pose, four-bar bodies", fb_s, Some(steps));
    let rapier_s = seconds_per_call(5, || {
        compliant.execute(&Q, &conditions, &mut rng).expect("settles");
        steps = compliant.last_settle().map_or(0, |r| r.total_steps());
    });
    line("dynamic RapierArm pose (four-bar, gear, paper)", rapier_s, Some(steps));
    println!(
        "  dynamic settles in rapier steps (settle time / one step at rest {:.3} us): plain {:.1}, four-bar {:.1}, \
         RapierArm four-bar + gear {:.1}; in 16-iteration steps ({:.3} us): {:.1}, {:.1}, {:.1}",
        step_s * 1e6,
        settle_s / step_s,
        fb_s / step_s,
        rapier_s / step_s,
        step16_s * 1e6,
        settle_s / step16_s,
        fb_s / step16_s,
        rapier_s / step16_s
    );
}

fn main() {
    let mut c = Criterion::default().configure_from_args();
    kinematic(&mut c);
    dynamic(&mut c);
    rapier_arm(&mut c);
    summary();
    c.final_summary();
}
