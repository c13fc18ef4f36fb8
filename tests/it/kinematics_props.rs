//! Property tests of the kinematics on random non-ideal geometry around the ASEA IRB/L6
//! nominal (Table 2 rows perturbed like a real calibration: a, b by up to 3 mm, alpha, beta
//! by up to 0.5 deg): analytic Jacobians against central differences of forward kinematics,
//! FK -> IK round trips seeded by the nominal closed form, and errors (not panics) for
//! unreachable targets.

use axiscal::kinematics::{
    IkError, IkOptions, PhiModel, geometric_jacobian, nominal_closed_form, point_jacobian, pose_error, rotation_vector,
    solve_seeded_by_nominal,
};
use axiscal::robot::RobotDescription;
use nalgebra::{Isometry3, Point3, Translation3, Vector3};
use proptest::prelude::*;

/// Largest perturbation of the row lengths a, b [m] and angles alpha, beta [rad].
const LENGTH_PERTURBATION_M: f64 = 0.003;
const ANGLE_PERTURBATION_RAD: f64 = 0.5 * std::f64::consts::PI / 180.0;

/// Central-difference step [rad].
const H: f64 = 1e-6;
/// Tolerance of a central difference with step `H`: the truncation error `h^2 |f'''| / 6` is
/// ~1.6 m * 1e-12 / 6 ~ 3e-13 (reach 1.6 m), the rounding error `eps |f| / h` is
/// 2.2e-16 * 6 m / 1e-6 ~ 1.3e-9 (the tool is ~6 m from the instrument origin), amplified
/// by the ~10 rounded products of the chain: about 1e-8; we allow a further factor 10.
const FD_TOLERANCE: f64 = 1e-7;

/// The round-trip requirement of the issue: FK -> IK pose error below 1e-9 m and 1e-9 rad.
const ROUND_TRIP_TOLERANCE: f64 = 1e-9;

fn nominal() -> PhiModel {
    RobotDescription::asea_irb6l().nominal_model()
}

/// The nominal model with each row's a, b, alpha, beta shifted by `unit[..] * scale`.
fn perturbed(unit: &[f64; 20]) -> PhiModel {
    let mut m = nominal();
    for (k, row) in m.rows.iter_mut().enumerate() {
        row.a_m += unit[4 * k] * LENGTH_PERTURBATION_M;
        row.b_m += unit[4 * k + 1] * LENGTH_PERTURBATION_M;
        row.alpha_rad += unit[4 * k + 2] * ANGLE_PERTURBATION_RAD;
        row.beta_rad += unit[4 * k + 3] * ANGLE_PERTURBATION_RAD;
    }
    m
}

/// Joint values at fractions `unit` (in [-1, 1]) of the joint limits.
fn within_limits(unit: &[f64; 6]) -> Vec<f64> {
    let d = RobotDescription::asea_irb6l();
    (0..6)
        .map(|k| {
            let [lo, hi] = d.limits_internal(k);
            0.5 * (lo + hi) + 0.5 * (hi - lo) * unit[k]
        })
        .collect()
}

/// Joint values inside the workspace and away from its singularities: limits of the
/// description, except joint 5 kept within 0.15..1.2 rad of 0 in magnitude (axis 6 aligns
/// with axis 4 at +-pi/2, a wrist singularity where the joint values are not unique).
fn inside_workspace(unit: &[f64; 6]) -> Vec<f64> {
    let mut q = within_limits(unit);
    q[4] = unit[4].signum() * (0.15 + 1.05 * unit[4].abs());
    q
}

fn unit_array<const N: usize>() -> impl Strategy<Value = [f64; N]> {
    proptest::array::uniform(-1.0f64..1.0)
}

fn options() -> IkOptions {
    let d = RobotDescription::asea_irb6l();
    IkOptions {
        limits: Some((0..6).map(|k| d.limits_internal(k)).collect()),
        ..IkOptions::default()
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn geometric_jacobian_matches_central_differences(g in unit_array::<20>(), u in unit_array::<6>()) {
        let model = perturbed(&g);
        let q = within_limits(&u);
        let j = geometric_jacobian(&model, &q);
        for k in 0..6 {
            let (mut qp, mut qm) = (q.clone(), q.clone());
            qp[k] += H;
            qm[k] -= H;
            let (tp, tm) = (model.world_from_tool(&qp), model.world_from_tool(&qm));
            let v = (tp.translation.vector - tm.translation.vector) / (2.0 * H);
            let w = rotation_vector(&(tp.rotation * tm.rotation.inverse())) / (2.0 * H);
            let col = j.column(k);
            prop_assert!((v - col.fixed_rows::<3>(0)).norm() < FD_TOLERANCE, "joint {k}: linear");
            prop_assert!((w - col.fixed_rows::<3>(3)).norm() < FD_TOLERANCE, "joint {k}: angular");
        }
    }

    #[test]
    fn point_jacobian_matches_central_differences(
        g in unit_array::<20>(),
        u in unit_array::<6>(),
        link in 0usize..6,
        p in unit_array::<3>(),
    ) {
        let model = perturbed(&g);
        let q = within_limits(&u);
        let point_m = Point3::from(Vector3::from(p) * 0.3);
        let j = point_jacobian(&model, &q, link, &point_m);
        for k in 0..6 {
            let (mut qp, mut qm) = (q.clone(), q.clone());
            qp[k] += H;
            qm[k] -= H;
            let fd = (model.point_on_link(&qp, link, &point_m) - model.point_on_link(&qm, link, &point_m)) / (2.0 * H);
            prop_assert!((fd - j.column(k)).norm() < FD_TOLERANCE, "joint {k}");
        }
    }

    #[test]
    fn nominal_closed_form_reproduces_the_target(u in unit_array::<6>()) {
        let model = nominal();
        let q = inside_workspace(&u);
        let target = model.world_from_tool(&q);
        let branches = nominal_closed_form(&model, &target).expect("reachable pose");
        prop_assert!(!branches.is_empty());
        for b in &branches {
            let e = pose_error(&target, &model.world_from_tool(&b.q));
            prop_assert!(e.fixed_rows::<3>(0).norm() < ROUND_TRIP_TOLERANCE);
            prop_assert!(e.fixed_rows::<3>(3).norm() < ROUND_TRIP_TOLERANCE);
        }
        // The generating joint values are one of the branches (angles modulo 2 pi).
        let same = |a: &[f64]| a.iter().zip(&q).all(|(x, y)| {
            let d = (x - y).rem_euclid(std::f64::consts::TAU);
            d.min(std::f64::consts::TAU - d) < 1e-8
        });
        prop_assert!(branches.iter().any(|b| same(&b.q)), "{:?} not among {:?}", q, branches);
    }

    #[test]
    fn fk_ik_round_trip_on_random_geometry(g in unit_array::<20>(), u in unit_array::<6>()) {
        let actual = perturbed(&g);
        let q = inside_workspace(&u);
        let target = actual.world_from_tool(&q);
        let s = solve_seeded_by_nominal(&actual, &nominal(), &target, &options())
            .map_err(|e| TestCaseError::fail(format!("{e}")))?;
        let e = pose_error(&target, &actual.world_from_tool(&s.q));
        prop_assert!(e.fixed_rows::<3>(0).norm() < ROUND_TRIP_TOLERANCE, "{:?}", s.report);
        prop_assert!(e.fixed_rows::<3>(3).norm() < ROUND_TRIP_TOLERANCE, "{:?}", s.report);
        prop_assert!(s.report.converged);
    }

    #[test]
    fn unreachable_target_is_an_error(g in unit_array::<20>(), u in unit_array::<6>()) {
        let actual = perturbed(&g);
        let reachable = actual.world_from_tool(&inside_workspace(&u));
        let away = Isometry3::from_parts(Translation3::new(5.0, 0.0, 0.0), Default::default()) * reachable;
        let r = solve_seeded_by_nominal(&actual, &nominal(), &away, &options());
        let is_not_converged = matches!(r, Err(IkError::NotConverged { position_error_m, .. }) if position_error_m > 1.0);
        prop_assert!(is_not_converged, "{:?}", r);
    }
}
