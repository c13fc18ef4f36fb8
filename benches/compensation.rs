//! Compensation (paper fig. 5) per pose on the paper robot's calibrated-like model.
//!
//! Target: `compensation/compensate_from_nominal_seed` < 20 us in release. In-run baseline:
//! `baseline/world_from_tool` (one forward kinematics of the calibrated model), so the
//! result reads as "compensation costs N forward kinematics" on any machine.

use axiscal::compensation::Compensator;
use axiscal::robot::RobotDescription;
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

#[path = "common/allocator.rs"]
mod allocator;

const Q: [f64; 6] = [0.3, 0.2, -0.3, 0.5, 0.7, -1.0];

fn bench(c: &mut Criterion) {
    let desc = RobotDescription::asea_irb6l();
    // The paper robot as a calibrated model: Table 2 actual rows, every section-4 function.
    let calibrated = axiscal::sim::paper_robot();
    let comp = Compensator::new(&calibrated, &desc).unwrap();
    let target = desc.nominal_model().world_from_tool(&Q);
    let model = calibrated.phi_model();
    c.benchmark_group("baseline")
        .bench_function("world_from_tool", |b| b.iter(|| model.world_from_tool(black_box(&Q))));
    let mut g = c.benchmark_group("compensation");
    g.bench_function("compensate_from_nominal_seed", |b| {
        b.iter(|| comp.compensate_from(black_box(&target), &Q).unwrap())
    });
    g.bench_function("compensate_closed_form_seeds", |b| {
        b.iter(|| comp.compensate(black_box(&target)).unwrap())
    });
    g.bench_function("joint_commands_only", |b| {
        b.iter(|| comp.joint_commands(black_box(&Q)).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
