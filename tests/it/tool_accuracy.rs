//! The predicted tool accuracy (`calibration::tool_accuracy`) against a Monte-Carlo of
//! calibrations of the paper robot (`harness::studies::ToolAccuracyStudy`). The small test
//! holds the prediction to the Monte-Carlo's own sampling error; `make tool-accuracy` runs the
//! full check (2000 trials) and holds it to the 10 %.

use axiscal::harness::studies::{ToolAccuracyCheck, ToolAccuracyStudy};

fn print(checks: &[ToolAccuracyCheck]) {
    println!("poses      predicted mm  MC mm (+- se)         ratio   predicted mrad  MC mrad (+- se)      ratio");
    for c in checks {
        let [rp, rr] = c.ratios();
        println!(
            "{:<9}  {:>12.4}  {:>8.4} (+- {:.4})  {:>7.3}  {:>14.4}  {:>8.4} (+- {:.4})  {:>6.3}",
            c.poses,
            c.predicted_position_rms_mm,
            c.monte_carlo_position_rms_mm,
            c.monte_carlo_position_standard_error_mm,
            rp,
            c.predicted_orientation_rms_mrad,
            c.monte_carlo_orientation_rms_mrad,
            c.monte_carlo_orientation_standard_error_mrad,
            rr
        );
    }
}

/// Few trials: the predicted RMS within 3 standard errors of the Monte-Carlo RMS plus the
/// first-order prediction's own spread (it is one calibration's covariance: its
/// sigmas scatter with the model by ~ sigma / lever, far below 1 %, taken as 3 %).
#[test]
fn predicted_tool_rms_agrees_with_a_small_monte_carlo() {
    let trials = std::env::var("TOOL_ACCURACY_TRIALS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(100);
    let checks = ToolAccuracyStudy {
        trials,
        seed: 11,
        noise_rms_3d_mm: 0.19,
        poses: 40,
    }
    .run()
    .unwrap();
    print(&checks);
    for c in &checks {
        let pos = (c.predicted_position_rms_mm - c.monte_carlo_position_rms_mm).abs();
        let rot = (c.predicted_orientation_rms_mrad - c.monte_carlo_orientation_rms_mrad).abs();
        assert!(
            pos <= 3.0 * c.monte_carlo_position_standard_error_mm + 0.03 * c.monte_carlo_position_rms_mm,
            "{c:?}"
        );
        assert!(
            rot <= 3.0 * c.monte_carlo_orientation_standard_error_mrad + 0.03 * c.monte_carlo_orientation_rms_mrad,
            "{c:?}"
        );
    }
}

/// The full check (`make tool-accuracy`): 2000 trials, 200 poses per set, seed 2 (run once,
/// not tuned on); the predicted RMS within 10 % of the Monte-Carlo RMS, inside the spans and
/// over the workspace, position and orientation, and the Monte-Carlo's standard error small
/// enough (< 3 %) for that to mean something.
#[test]
#[ignore = "2000 calibrations: make tool-accuracy"]
fn predicted_tool_rms_within_ten_percent_of_the_monte_carlo() {
    let trials = std::env::var("TOOL_ACCURACY_TRIALS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2000);
    let checks = ToolAccuracyStudy {
        trials,
        seed: 2,
        noise_rms_3d_mm: 0.19,
        poses: 200,
    }
    .run()
    .unwrap();
    println!("{trials} trials, seed 2, 0.19 mm noise, 200 poses per set");
    print(&checks);
    for c in &checks {
        for r in c.ratios() {
            assert!((r - 1.0).abs() <= 0.10, "{c:?}");
        }
        assert!(
            c.monte_carlo_position_standard_error_mm < 0.03 * c.monte_carlo_position_rms_mm,
            "{c:?}"
        );
    }
}
