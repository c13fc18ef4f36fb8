//! The paper scenario closed in the loop: simulate -> calibrate -> compensate -> evaluate.

use axiscal::harness::evaluation::{PaperScenario, Region, floor_check, run_paper_scenario};
use axiscal::measurement::MeasurementModel;

fn scenario(seed: u64) -> PaperScenario {
    PaperScenario::paper(seed, 9283, 20, MeasurementModel::paper_isotropic())
}

/// Calibration + compensation removes most of the error inside the spans; no pose fails
/// there; the run is deterministic.
#[test]
fn paper_scenario_compensation_beats_the_nominal_controller() {
    let a = run_paper_scenario(&scenario(1)).unwrap().report;
    let b = run_paper_scenario(&scenario(1)).unwrap().report;
    assert_eq!(a, b, "same settings, same report");
    let inside = a.regions.iter().find(|r| r.region == Region::InsideSpans).unwrap();
    assert_eq!(inside.failures, 0);
    // The nominal error is ~12 mm; the noise-driven calibrated model error ~1-2 mm.
    assert!(
        inside.position_mm.calibrated.rms < inside.position_mm.uncalibrated.rms / 4.0,
        "{:?}",
        inside.position_mm
    );
}

/// The gate: calibrated RMS inside the spans within 1.1x of the noise floor (same
/// campaign with repeatability off), position and orientation, aggregated over seeds 1-3 (one
/// seed's floor alone scatters by 0.6-2.5 mm: the Table-1 spans leave joint 5's and 6's
/// harmonic terms poorly determined). It fails by far (1.6x over 30 seeds) when every joint is
/// re-drawn at every step instead of only the actuators that move (`docs/validation.md`, "The paper scenario").
#[test]
fn paper_scenario_calibrated_error_is_within_1_1x_of_the_noise_floor() {
    let check = floor_check(&scenario(1), 3).unwrap();
    println!("calibrated/floor RMS over seeds 1-3: {check:?}");
    assert!(check.ratio.position <= 1.1, "position {check:?}");
    assert!(check.ratio.orientation <= 1.1, "orientation {check:?}");
}
