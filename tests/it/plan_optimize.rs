//! `plan --optimize` (issue 16, item 5): the optimised plan predicts a lower tool error over the
//! workspace than Table 1 at the same number of points and stays within the joint limits; the
//! prediction's `trace(C M)` equals the per-pose propagation of `calibration::tool_accuracy`.

use axiscal::calibration::procedure::{CalibrationOptions, calibrate};
use axiscal::calibration::tool_accuracy::ToolSensitivity;
use axiscal::plan::optimize::axis_points;
use axiscal::plan::predict::noise_free_campaign;
use axiscal::plan::{
    CalibrationPlan, OptimizeOptions, PlanObjective, SightOptions, ValidationPlan, optimize, with_point_budget,
};
use axiscal::robot::{Controller, RobotDescription, commands_to_internal};
use nalgebra::Point3;

fn setting() -> (RobotDescription, SightOptions, ValidationPlan, CalibrationOptions) {
    let desc = RobotDescription::asea_irb6l();
    let sight = SightOptions {
        stations_m: vec![
            Point3::origin(),
            Point3::from(axiscal::measurement::PAPER_RIGHT_STATION_MM) * 1e-3,
        ],
        link_radius_m: 0.05,
        stop_short_m: 2e-3,
    };
    let workspace = ValidationPlan {
        poses: 40,
        ..ValidationPlan::workspace_default(desc.dof())
    };
    (desc, sight, workspace, CalibrationOptions::default())
}

#[test]
fn one_round_beats_table1_at_the_same_points_within_the_limits() {
    let (desc, sight, workspace, options) = setting();
    let table1 = CalibrationPlan::table1(6);
    let objective = PlanObjective::new(&desc, &table1, &workspace, &sight, &options).unwrap();
    let search = OptimizeOptions {
        max_rounds: 1,
        ..OptimizeOptions::default()
    };
    let found = optimize(&objective, &desc, &table1, search).unwrap();
    println!(
        "Table 1 {:.4} mm, optimised {:.4} mm ({} candidates)",
        found.seed.position_rms_mm, found.prediction.position_rms_mm, found.candidates
    );
    assert!(found.prediction.position_rms_mm < found.seed.position_rms_mm);
    assert_eq!(axis_points(&found.plan), axis_points(&table1));
    assert_eq!(found.prediction.axis_points, axis_points(&table1));
    // The limits, checked on the commands themselves (not through `validate`).
    for sweep in &found.plan.sweeps {
        assert!(sweep.intervals >= search.min_intervals.min(15));
        for step in [0, sweep.intervals] {
            for (c, j) in found.plan.commands(&desc, sweep, step).iter().zip(&desc.joints) {
                assert!(
                    (j.limits[0]..=j.limits[1]).contains(c),
                    "joint {} sweep: {c}",
                    sweep.joint
                );
            }
        }
    }
}

#[test]
fn trace_form_equals_the_per_pose_propagation() {
    let (desc, sight, workspace, options) = setting();
    let plan = CalibrationPlan::table1(6);
    let predicted = PlanObjective::new(&desc, &plan, &workspace, &sight, &options)
        .unwrap()
        .predict(&plan)
        .unwrap();
    // Second path: the calibration's own covariance through `ToolSensitivity::sigma_at`
    // (its own steps, 1e-3 sigma) at each pose, RMS of the norms.
    let (set, _) = noise_free_campaign(&desc, &plan, &sight).unwrap();
    let cal = calibrate(&set, &desc, &options).unwrap();
    let controller = Controller::from_description(&desc);
    let cov = cal.model_covariance.unwrap().matrix();
    let sensitivity = ToolSensitivity::new(&cal.robot, &controller, &cov);
    let poses = workspace.commands(&desc, &plan.reference);
    let mean_square = poses
        .iter()
        .map(|c| {
            sensitivity
                .sigma_at(&commands_to_internal(&desc, c))
                .unwrap()
                .position_norm_mm
                .powi(2)
        })
        .sum::<f64>()
        / poses.len() as f64;
    let direct = mean_square.sqrt();
    // Both are central differences of the same smooth map; their truncation errors are
    // O((h / 0.1)^2) with h <= 1e-3 sigma ~ 1e-5 (m or rad): far below 1e-6 relative.
    // 1e-6 leaves room for rounding in the two sums.
    assert!(
        (predicted.position_rms_mm - direct).abs() <= 1e-6 * direct,
        "{} vs {direct}",
        predicted.position_rms_mm
    );
    let shares: f64 = predicted.breakdown_mm2.iter().map(|(_, v)| v).sum();
    assert!((shares - direct * direct).abs() <= 1e-6 * direct * direct);
}

#[test]
fn a_point_budget_is_met_exactly_or_refused() {
    let table1 = CalibrationPlan::table1(6);
    for points in [60, 129, 200, 301] {
        let plan = with_point_budget(&table1, points).unwrap();
        assert_eq!(axis_points(&plan), points);
    }
}
