//! A free-pose calibration of 1,000 poses x 3 targets of a six-axis arm (target: well under
//! 1 s on one core; FIGAROH and pybotics take 19-20 s on such data), against an in-run
//! baseline: one standard calibration of a Table-1 campaign of the paper robot. The printed
//! ratio is the number to compare across machines.

use axiscal::calibration::free_pose::{FreePoseOptions, calibrate_free_poses};
use axiscal::calibration::procedure::{CalibrationOptions, calibrate};
use axiscal::measurement::{IsotropicNoise, Measurement, MeasurementModel, MeasurementSet};
use axiscal::plan::{CalibrationPlan, ValidationPlan};
use axiscal::robot::{Controller, RobotDescription, RobotModel, commands_to_file};
use axiscal::sim::{AnalyticArm, simulate_campaign};
use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Point3, Vector3};
use rand::{RngExt, SeedableRng, rngs::ChaCha12Rng};
use rand_distr::{Distribution, Normal};
use std::hint::black_box;
use std::path::Path;

mod common;

/// Poses and targets of the free-pose campaign.
const POSES: usize = 1000;
const TARGETS: [[f64; 3]; 3] = [[0.03, 0.02, 0.10], [0.11, 0.02, 0.09], [0.03, 0.10, 0.11]];

/// The six-axis DH arm with 0.5 mm / 0.5 mrad errors in every row and offset, measured at
/// random commands with 0.05 mm noise per coordinate.
fn free_poses(desc: &RobotDescription, count: usize) -> MeasurementSet {
    let mut rng = ChaCha12Rng::seed_from_u64(1000);
    let mut truth = RobotModel::ideal(desc);
    for row in &mut truth.rows {
        row.a_m += 5e-4 * (2.0 * rng.random::<f64>() - 1.0);
        row.b_m += 5e-4 * (2.0 * rng.random::<f64>() - 1.0);
        row.alpha_deg += 0.03 * (2.0 * rng.random::<f64>() - 1.0);
    }
    for j in &mut truth.joints {
        j.transducer_offset = 5e-4 * (2.0 * rng.random::<f64>() - 1.0);
    }
    let controller = Controller::from_description(desc);
    let phi = truth.phi_model();
    let noise = Normal::new(0.0, 5e-5).expect("noise");
    let mut rows = Vec::new();
    for step in 0..count {
        let cmd: Vec<f64> = (0..desc.dof())
            .map(|k| {
                let [lo, hi] = desc.limits_internal(k);
                lo + 0.1 * (hi - lo) + 0.8 * (hi - lo) * rng.random::<f64>()
            })
            .collect();
        let tool = phi.world_from_tool(&truth.joint_values(&controller, &cmd).expect("executable"));
        for (target, y) in TARGETS.iter().enumerate() {
            let p = tool * Point3::from(*y) + Vector3::from_fn(|_, _| noise.sample(&mut rng));
            rows.push(Measurement {
                experiment: "poses".into(),
                moved_joint: 0,
                step,
                target,
                position_mm: [p.x * 1e3, p.y * 1e3, p.z * 1e3],
                cmd: commands_to_file(desc, &cmd),
                payload_kg: 0.0,
                temperature_c: 20.0,
            });
        }
    }
    MeasurementSet::new(desc.dof(), rows).expect("a valid set")
}

/// The baseline's campaign: Table 1 on the paper robot without jitter.
fn table1(desc: &RobotDescription) -> MeasurementSet {
    let mut truth = axiscal::sim::paper_robot();
    for j in &mut truth.joints {
        j.repeatability_sigma = 0.0;
    }
    let mut arm = AnalyticArm::new(truth, Controller::from_description(desc));
    let instrument = MeasurementModel::Isotropic(IsotropicNoise {
        net_radial_rms_mm: 0.19,
    });
    let out = simulate_campaign(
        desc,
        &CalibrationPlan::table1(6),
        &ValidationPlan {
            poses: 0,
            ..ValidationPlan::workspace_default(6)
        },
        &mut arm,
        &instrument,
        &mut ChaCha12Rng::seed_from_u64(60),
    )
    .expect("the campaign runs");
    MeasurementSet::new(desc.dof(), out.rows).expect("a valid set")
}

fn bench(c: &mut Criterion) {
    let arm = RobotDescription::from_file(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/robots/arm6-dh.toml"))
        .expect("the shipped arm");
    // Outside `cargo bench` (a debug build in `make test`) a smoke test on 50 poses.
    let poses = free_poses(&arm, if common::is_cargo_bench() { POSES } else { 50 });
    let paper = RobotDescription::asea_irb6l();
    let campaign = table1(&paper);
    let calibration = CalibrationOptions::default();
    let options = FreePoseOptions::default();
    let free = || black_box(calibrate_free_poses(black_box(&poses), &arm, &options).expect("calibrates"));
    let baseline = || black_box(calibrate(black_box(&campaign), &paper, &calibration).expect("calibrates"));
    let mut g = c.benchmark_group("free_pose");
    g.sample_size(10);
    g.bench_function("baseline/table1_calibration", |b| b.iter(baseline));
    g.bench_function("1000_poses_3_targets", |b| b.iter(free));
    g.finish();
    let (b, f) = common::interleaved_medians(
        RUNS,
        (BATCH, &|| {
            baseline();
        }),
        (1, &|| {
            free();
        }),
    );
    println!(
        "free_pose/1000_poses_3_targets: {:.1} ms = {:.1} x baseline/table1_calibration ({:.2} ms); target well under 1 s on one core",
        f * 1e3,
        f / b,
        b * 1e3
    );
}

/// Interleaved runs per median, and calls per timed run of the baseline.
const RUNS: usize = 5;
const BATCH: usize = 3;

criterion_group!(benches, bench);
criterion_main!(benches);
