//! Table 1 plan and the hold-still commands of `docs/formats.md#controller-semantics`.

use approx::assert_relative_eq;
use axiscal::plan::{CalibrationPlan, PlanError, ValidationPlan};
use axiscal::robot::RobotDescription;

#[test]
fn table1_point_counts_and_order() {
    let desc = RobotDescription::asea_irb6l();
    let plan = CalibrationPlan::table1(6);
    plan.validate(&desc).expect("Table 1 fits the IRB/L6 limits");
    let order: Vec<usize> = plan.sweeps.iter().map(|s| s.joint).collect();
    assert_eq!(order, vec![6, 5, 4, 3, 2, 1]);
    let points: Vec<usize> = plan.sweeps.iter().map(|s| s.poses()).collect();
    assert_eq!(points, vec![17, 16, 16, 16, 16, 16]);
    let spans: Vec<f64> = plan.sweeps.iter().map(|s| s.span).collect();
    assert_eq!(spans, vec![50.0, 60.0, 90.0, 45.0, 45.0, 48.0]);
}

#[test]
fn hold_still_commands_follow_the_nominal_slope() {
    let desc = RobotDescription::asea_irb6l();
    let plan = CalibrationPlan::table1(6);
    let j4 = plan.sweeps.iter().find(|s| s.joint == 4).unwrap();
    let n = 32.0 / 19.0;
    for step in 0..j4.poses() {
        let c = plan.commands(&desc, j4, step);
        let c0 = plan.commands(&desc, j4, 0);
        assert_relative_eq!(c[4] - c0[4], n * (c[3] - c0[3]), epsilon = 1e-12);
        assert_eq!([c[0], c[1], c[2], c[5]], [0.0; 4]);
    }
    let j2 = plan.sweeps.iter().find(|s| s.joint == 2).unwrap();
    let (c, c0) = (plan.commands(&desc, j2, 7), plan.commands(&desc, j2, 0));
    assert_relative_eq!(c[2] - c0[2], -(c[1] - c0[1]), epsilon = 1e-12);
    // A sweep without a second target leaves every other command at the reference.
    let j3 = plan.sweeps.iter().find(|s| s.joint == 3).unwrap();
    let c = plan.commands(&desc, j3, 9);
    assert_eq!([c[0], c[1], c[3], c[4], c[5]], [0.0; 5]);
}

#[test]
fn bad_plans_are_named() {
    let desc = RobotDescription::asea_irb6l();
    let mut plan = CalibrationPlan::table1(6);
    plan.sweeps[0].span = 0.0;
    assert!(matches!(
        plan.validate(&desc),
        Err(PlanError::Degenerate { joint: 6, .. })
    ));
    let mut plan = CalibrationPlan::table1(6);
    plan.sweeps[3].second_target = true; // joint 3: coupling 3->4 exists, but no target1 given
    assert!(matches!(
        plan.validate(&desc),
        Err(PlanError::SecondTarget { joint: 3, .. })
    ));
    let mut plan = CalibrationPlan::table1(6);
    plan.sweeps[4].span = 200.0;
    assert!(matches!(
        plan.validate(&desc),
        Err(PlanError::OutOfLimits { joint: 2, .. })
    ));
}

#[test]
fn validation_poses_are_reproducible_and_inside_limits() {
    let desc = RobotDescription::asea_irb6l();
    let v = ValidationPlan::workspace_default(6);
    let a = v.commands(&desc, &[0.0; 6]);
    assert_eq!(a, v.commands(&desc, &[0.0; 6]));
    assert_eq!(a.len(), 60);
    for c in &a {
        for (k, j) in desc.joints.iter().enumerate() {
            assert!(c[k] >= j.limits[0] && c[k] <= j.limits[1]);
        }
    }
}
