//! `validate` (issue 16 item 3): the predictions checked by a second path (the simulator's own
//! arm and controller), the chi-square statistics and their degrees of freedom checked by
//! Monte-Carlo of noise-only data, a known injected error recovered, and the command end to end.

use crate::common;

use crate::common::{axiscal, paper_robot_without_jitter, stdout};
use axiscal::calibration::procedure::{Calibration, CalibrationOptions, calibrate};
use axiscal::diagnosis::{CleanCampaign, NoiseModel, PointKind, Validation, ValidationOptions, replica, validate};
use axiscal::measurement::MeasurementSet;
use axiscal::robot::RobotDescription;
use rand::{SeedableRng, rngs::ChaCha12Rng};

/// A campaign of the jitter-free paper robot: Table 1 and `poses` validation poses, measured
/// with isotropic noise of 3-D RMS `noise_mm`.
fn campaign(noise_mm: f64, poses: usize, seed: u64) -> MeasurementSet {
    common::jitter_free_campaign(noise_mm, poses, seed)
}

/// A calibration of the paper robot from a noisy campaign (its own seed).
fn calibration(desc: &RobotDescription) -> Calibration {
    let options = CalibrationOptions {
        noise_rms_3d_mm: 0.19,
        ..CalibrationOptions::default()
    };
    calibrate(&campaign(0.19, 0, 3), desc, &options).expect("the campaign calibrates")
}

fn options(noise_mm: f64) -> ValidationOptions {
    ValidationOptions {
        noise_rms_3d_mm: noise_mm,
        noise_source: "given".into(),
        false_alarm: 0.01,
    }
}

/// The calibration holding the truth itself predicts the simulator's noise-free measurements
/// to rounding: the prediction (calibrated controller and chain) against the simulator's
/// arm and joint driver, a separately written path.
#[test]
fn the_truth_as_calibration_predicts_noise_free_data_exactly() {
    let desc = RobotDescription::asea_irb6l();
    let mut cal = calibration(&desc);
    cal.robot = paper_robot_without_jitter();
    let set = campaign(0.0, 20, 11);
    let v = validate(&set, &cal, &desc, &options(0.19)).unwrap();
    // Rounding: positions of a few metres carried through ~20 floating-point transforms.
    let rounding_mm = 1e-9;
    for s in [&v.validation, &v.tool, &v.axis] {
        let s = s.as_ref().expect("every kind of point is in the campaign");
        assert!(s.max_mm < rounding_mm, "{s:?}");
    }
    let o = v
        .orientation
        .as_ref()
        .expect("validation poses carry three tool targets");
    assert_eq!(o.poses, 20 + 1, "20 validation poses and the tool observation");
    // The same rounding over a tool-target lever of at least 1 mm: 1e-9 rad.
    let rounding_mrad = rounding_mm / 1.0 * 1e3;
    assert!(o.max_mrad < rounding_mrad, "{o:?}");
    assert_eq!(
        v.residuals.iter().filter(|r| r.kind == PointKind::Validation).count(),
        60
    );

    // A known error on the validation points is reported as it is.
    let shift_mm = [0.3, -0.4, 1.2];
    let norm_mm = shift_mm.iter().map(|c| c * c).sum::<f64>().sqrt();
    let rows = set
        .rows()
        .iter()
        .map(|m| {
            let mut m = m.clone();
            if m.moved_joint == 0 && m.experiment != "tool" {
                for (c, d) in m.position_mm.iter_mut().zip(shift_mm) {
                    *c += d;
                }
            }
            m
        })
        .collect();
    let shifted = MeasurementSet::new(6, rows).unwrap();
    let v = validate(&shifted, &cal, &desc, &options(0.19)).unwrap();
    let s = v.validation.as_ref().unwrap();
    assert!(
        (s.rms_mm - norm_mm).abs() < rounding_mm && (s.max_mm - norm_mm).abs() < rounding_mm,
        "{s:?}"
    );
    assert_eq!(s.chi_square.as_ref().unwrap().verdict, "exceeds_noise");
    assert!(v.verdict.starts_with("the calibrated model misses"), "{}", v.verdict);
}

/// The chi-square statistics over Monte-Carlo replicas of noise-only data (points where the
/// calibration puts them plus isotropic noise, drawn by the diagnosis' replica code): the mean
/// of `chi2 / dof` is 1 within 4 of its standard errors, for positions (validation poses, and
/// axis experiments whose target positions are estimated: 3 dof each) and orientations.
#[test]
fn chi_square_per_dof_is_one_on_noise_only_data() {
    let desc = RobotDescription::asea_irb6l();
    let cal = calibration(&desc);
    let template = campaign(0.19, 30, 17);
    let clean = CleanCampaign::new(&template, &cal, &desc, &desc.tool_targets_m()).unwrap();
    let noise_mm = 0.19;
    // The campaign's robot has no repeatability jitter (`calibration`): instrument noise only.
    let noise = NoiseModel {
        noise_rms_3d_m: noise_mm * 1e-3,
        repeatability_rad: vec![0.0; desc.dof()],
    };
    let mut rng = ChaCha12Rng::seed_from_u64(20_161);
    let trials = 40;
    let runs: Vec<Validation> = (0..trials)
        .map(|_| {
            let set = replica(&template, &clean, &noise, true, &mut rng).unwrap();
            validate(&set, &cal, &desc, &options(noise_mm)).unwrap()
        })
        .collect();
    let check = |name: &str, per_dof: Vec<f64>, dof: usize| {
        let mean = per_dof.iter().sum::<f64>() / per_dof.len() as f64;
        // chi2/dof has variance 2/dof; the mean of `trials` of them 2/(dof trials).
        let standard_error = (2.0 / (dof as f64 * trials as f64)).sqrt();
        assert!(
            (mean - 1.0).abs() < 4.0 * standard_error,
            "{name}: mean chi2/dof {mean} (standard error {standard_error})"
        );
    };
    let position = |r: &Validation, axis: bool| {
        let s = if axis { &r.axis } else { &r.validation };
        s.as_ref().unwrap().chi_square.clone().unwrap()
    };
    check(
        "validation",
        runs.iter().map(|r| position(r, false).per_dof).collect(),
        position(&runs[0], false).dof,
    );
    check(
        "axis",
        runs.iter().map(|r| position(r, true).per_dof).collect(),
        position(&runs[0], true).dof,
    );
    let axis = runs[0].axis.as_ref().unwrap();
    assert_eq!(
        axis.chi_square.as_ref().unwrap().dof,
        3 * axis.points - 3 * axis.estimated_targets
    );
    let o = |r: &Validation| r.orientation.as_ref().unwrap().chi_square.clone().unwrap();
    check(
        "orientation",
        runs.iter().map(|r| o(r).per_dof).collect(),
        o(&runs[0]).dof,
    );
    // The predicted orientation RMS against the scatter of the measured angles.
    let rms: f64 = (runs
        .iter()
        .map(|r| r.orientation.as_ref().unwrap().rms_mrad.powi(2))
        .sum::<f64>()
        / trials as f64)
        .sqrt();
    let predicted = runs[0].orientation.as_ref().unwrap().predicted_rms_mrad;
    let n_angles = (trials * runs[0].orientation.as_ref().unwrap().poses) as f64;
    // The RMS of n squared angles (each ~ 3 dof) has relative standard error ~ 1/sqrt(6 n)
    // (half that of a sum of 3 n squares); 4 of them.
    assert!(
        (rms / predicted - 1.0).abs() < 4.0 / (6.0 * n_angles).sqrt(),
        "{rms} vs {predicted}"
    );
}

/// `axiscal validate` end to end: calibrate one simulated campaign, validate on another; the
/// outputs are written, carry their schema, and are protected.
#[test]
fn validate_command_writes_protected_outputs() {
    let (dir, data) = common::simulated_campaign_csv(5);
    let (_dir2, test_data) = common::simulated_campaign_csv(6);
    let cal_dir = dir.path().join("cal");
    axiscal()
        .arg("calibrate")
        .arg(&data)
        .arg("--out")
        .arg(&cal_dir)
        .assert()
        .success();
    let out = dir.path().join("val");
    let run = || {
        let mut c = axiscal();
        c.arg("validate")
            .arg("--calibration")
            .arg(cal_dir.join("calibration.json"))
            .arg(&test_data)
            .arg("--out")
            .arg(&out);
        c
    };
    let a = run().assert().success();
    assert!(stdout(&a).contains("validation"), "{}", stdout(&a));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["schema"], "axiscal.validation/1");
    assert!(summary["validation"]["rms_mm"].as_f64().is_some_and(|r| r > 0.0));
    let csv = std::fs::read_to_string(out.join("residuals.csv")).unwrap();
    let data_rows = std::fs::read_to_string(&test_data)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#'))
        .count();
    assert_eq!(
        csv.lines().count(),
        data_rows,
        "one residual per measured point, one header each"
    );
    run().assert().code(2);
    run().arg("--force").assert().success();
    // A calibration file that is not one: one error naming it, exit 2.
    let a = axiscal()
        .arg("validate")
        .arg("--calibration")
        .arg(&test_data)
        .arg(&test_data)
        .arg("--out")
        .arg(dir.path().join("bad"))
        .assert()
        .code(2);
    assert!(
        common::stderr(&a).contains("not a calibration JSON"),
        "{}",
        common::stderr(&a)
    );
}
