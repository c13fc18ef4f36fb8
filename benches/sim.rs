//! Cost of the simulated arm: kinematic mode per pose, one dynamics step, and a full
//! static-equilibrium settle, each next to the phi-model forward kinematics of the same pose
//! (`PhiModel::poses`) as an in-run baseline, so the numbers read as ratios.

use axiscal::robot::RobotDescription;
use axiscal::sim::{ArmOptions, Compliance, ServoGains, SettleOptions, SimArm};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;

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
    group.bench_function("one_step_1ms_16_iterations", |b| {
        arm.static_equilibrium(&Q, &servo, &[], &options).expect("settles");
        arm.world_mut().integration_parameters.num_solver_iterations = 16;
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
    group.finish();
    let report = arm.static_equilibrium(&Q, &servo, &[], &options).expect("settles");
    println!(
        "settle at the bench pose: {} steps, final speed {:e} m/s",
        report.steps, report.max_speed_m_s
    );
}

/// The campaign's executor: commands through the truth's controller and transmissions to
/// link poses, kinematic (with line of sight from the two stations) and compliant (static
/// equilibrium under gravity with the compliance scenario's stiffnesses).
fn rapier_arm(c: &mut Criterion) {
    use axiscal::campaign::{ArmExecutor, ComplianceEffect, Effects, PoseConditions};
    use axiscal::measurement::MeasurementModel;
    use axiscal::robot::TruthRobot;
    use axiscal::sim::{RapierArm, RapierArmOptions};
    use rand::{SeedableRng, rngs::StdRng};
    let d = RobotDescription::asea_irb6l();
    let (instrument, _) = MeasurementModel::paper_theodolites().expect("theodolites");
    let options = RapierArmOptions {
        stations_m: instrument.stations_m(),
        ..RapierArmOptions::new(6)
    };
    let mut kinematic = RapierArm::new(TruthRobot::paper_robot(), &d, Effects::default(), options.clone());
    let compliance = Effects {
        compliance: Some(ComplianceEffect {
            stiffness_nm_per_rad: vec![5e5, 3e5, 3e5, 5e4, 5e4, 2e4],
            gravity_m_s2: [0.0, 0.0, -9.81],
        }),
        ..Effects::default()
    };
    let mut compliant = RapierArm::new(TruthRobot::paper_robot(), &d, compliance, options);
    let model = d.nominal_model();
    let mut rng = StdRng::seed_from_u64(1);
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
    group.bench_function("compliant_static_equilibrium", |b| {
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

criterion_group!(benches, kinematic, dynamic, rapier_arm);
criterion_main!(benches);
