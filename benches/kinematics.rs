//! Kinematics benchmarks on the ASEA IRB/L6 model.
//!
//! Speed targets are ratios against `baseline/six_isometry_products`, measured in the same
//! run: one chain of six isometry products written inline, the least work any forward
//! kinematics must do.

use axiscal::kinematics::{
    IkOptions, PhiModel, geometric_jacobian, nominal_closed_form, point_jacobian, solve_seeded_by_nominal,
};
use axiscal::robot::RobotDescription;
use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Isometry3, Point3, Vector3};
use std::hint::black_box;

#[path = "common/allocator.rs"]
mod allocator;

const Q: [f64; 6] = [0.3, 0.2, -0.4, 0.5, 0.7, -1.0];

fn model() -> PhiModel {
    RobotDescription::asea_irb6l().nominal_model()
}

/// The nominal model with the rows off by about Table 2's actual deviations, so IK must iterate.
fn actual_like() -> PhiModel {
    let mut m = model();
    m.rows[1].alpha_rad += 0.003;
    m.rows[1].b_m += 0.00487;
    m.rows[2].beta_rad += 0.007;
    m.rows[3].b_m += 0.003;
    m
}

fn baseline(c: &mut Criterion) {
    let links: Vec<Isometry3<f64>> = (0..6)
        .map(|k| {
            Isometry3::new(
                Vector3::new(0.1 * k as f64, 0.2, 0.3),
                Vector3::new(0.1, 0.2 * k as f64, 0.3),
            )
        })
        .collect();
    c.benchmark_group("baseline")
        .bench_function("six_isometry_products", |b| {
            b.iter(|| {
                let l = black_box(&links);
                l[0] * l[1] * l[2] * l[3] * l[4] * l[5]
            })
        });
}

fn forward(c: &mut Criterion) {
    let m = model();
    let mut g = c.benchmark_group("forward_kinematics");
    g.bench_function("world_from_tool", |b| b.iter(|| m.world_from_tool(black_box(&Q))));
    g.bench_function("poses", |b| b.iter(|| m.poses(black_box(&Q))));
    g.finish();
}

fn jacobians(c: &mut Criterion) {
    let m = model();
    let p = Point3::new(0.0, 0.08, 0.15);
    let mut g = c.benchmark_group("jacobian");
    g.bench_function("geometric", |b| b.iter(|| geometric_jacobian(&m, black_box(&Q))));
    g.bench_function("point_link6", |b| b.iter(|| point_jacobian(&m, black_box(&Q), 5, &p)));
    g.finish();
}

fn inverse(c: &mut Criterion) {
    let nominal = model();
    let actual = actual_like();
    let target_nominal = nominal.world_from_tool(&Q);
    let target_actual = actual.world_from_tool(&Q);
    let opts = IkOptions::default();
    let mut g = c.benchmark_group("inverse_kinematics");
    g.bench_function("nominal_closed_form_all_branches", |b| {
        b.iter(|| nominal_closed_form(&nominal, black_box(&target_nominal)))
    });
    g.bench_function("actual_lm_seeded_by_nominal", |b| {
        b.iter(|| solve_seeded_by_nominal(&actual, &nominal, black_box(&target_actual), &opts))
    });
    g.finish();
}

criterion_group!(benches, baseline, forward, jacobians, inverse);
criterion_main!(benches);
