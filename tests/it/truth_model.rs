//! The analytic truth model: controller semantics (`docs/formats.md#controller-semantics`), the paper preset
//! (section 4, Table 2), the four-bar, repeatability and Monte-Carlo perturbation.

use approx::assert_relative_eq;
use axiscal::measurement::MeasurementModel;
use axiscal::robot::*;
use axiscal::sim::{
    Effects, JointDriver, ObservedThrough, PerturbationSpec, RepeatabilityTarget, calibrate_uniform_sigma, perturb,
    repeatability_stats, workspace_poses,
};
use rand::rngs::ChaCha12Rng;
use rand::{RngExt, SeedableRng};
use std::path::Path;

fn paper_fractional() -> CouplingFunction {
    CouplingFunction::Fractional {
        num: [-0.998132, 0.213253, -0.212863],
        den: [0.096654, -0.0006941],
    }
}

fn random_commands(desc: &RobotDescription, rng: &mut ChaCha12Rng) -> Vec<f64> {
    (0..desc.dof())
        .map(|k| {
            let [lo, hi] = desc.limits_internal(k);
            rng.random_range(0.8 * lo..0.8 * hi)
        })
        .collect()
}

#[test]
fn ideal_robot_reaches_exactly_the_commanded_joint_values() {
    let desc = RobotDescription::asea_irb6l();
    let ctrl = Controller::from_description(&desc);
    let ideal = RobotModel::ideal(&desc);
    let mut geometric = ideal.clone();
    // The same robot with the geometric parallelogram as its 2->3 coupling.
    geometric.joints[2].coupling_in = Some(CouplingFunction::FourBar(FourBarGeometry::parallelogram(
        0.69, 0.2, 1.6,
    )));
    let mut rng = ChaCha12Rng::seed_from_u64(1);
    for _ in 0..200 {
        let cmd = random_commands(&desc, &mut rng);
        for robot in [&ideal, &geometric] {
            let q = robot.joint_values(&ctrl, &cmd).unwrap();
            for (a, b) in q.iter().zip(&cmd) {
                // Rounding only: u_{k+1} + slope u_k re-adds what decoupling subtracted.
                assert!((a - b).abs() < 1e-14, "{a} vs {b}");
            }
            let mut jitter_rng = ChaCha12Rng::seed_from_u64(2);
            let mut driver = JointDriver::new(robot, ctrl.clone(), &Effects::default());
            assert_eq!(driver.drive(&cmd, &mut jitter_rng).unwrap().q, q);
        }
    }
    assert!(matches!(
        ideal.joint_values(&ctrl, &[0.0; 5]),
        Err(ModelError::WrongLength { .. })
    ));
    // A linkage that cannot close is reported with the joint it drives.
    let mut jammed = geometric;
    let mut g = FourBarGeometry::parallelogram(0.69, 0.2, 1.6);
    g.rod_m = 0.3;
    jammed.joints[2].coupling_in = Some(CouplingFunction::FourBar(g));
    assert!(matches!(
        jammed.joint_values(&ctrl, &[0.0; 6]),
        Err(ModelError::Coupling { joint: 3, .. })
    ));
}

/// Moving actuator `joint` alone with the hold-still commands: the other actuator commands are
/// unchanged, and joint `joint + 1` moves only by the actual passive function.
fn check_hold_still(joint: usize) {
    let desc = RobotDescription::asea_irb6l();
    let ctrl = Controller::from_description(&desc);
    let truth = axiscal::sim::paper_robot();
    let g = truth.joints[joint].coupling_in.clone().unwrap();
    let cmd0 = vec![0.1, -0.2, 0.15, 0.3, -0.25, 0.4];
    let u0 = ctrl.decouple(&cmd0).unwrap();
    let theta0 = truth.active_displacements(&u0).unwrap();
    for s in -6..=6 {
        let new_cmd = cmd0[joint - 1] + 0.05 * s as f64;
        let cmd = ctrl.hold_still_commands(joint, &cmd0, new_cmd).unwrap();
        let u = ctrl.decouple(&cmd).unwrap();
        for j in (0..6).filter(|&j| j != joint - 1) {
            assert!((u[j] - u0[j]).abs() < 1e-15, "actuator {} moved", j + 1);
        }
        let theta = truth.active_displacements(&u).unwrap();
        let q = truth.joint_values(&ctrl, &cmd).unwrap();
        let expected = theta0[joint] + g.passive(theta[joint - 1]);
        assert_relative_eq!(q[joint], expected, epsilon = 1e-14);
    }
}

#[test]
fn hold_still_moves_actuator_2_alone_and_joint_3_passively() {
    check_hold_still(2);
}

#[test]
fn hold_still_moves_actuator_4_alone_and_joint_5_passively() {
    check_hold_still(4);
}

#[test]
#[allow(clippy::approx_constant)] // -0.6931 m is Table 2's a_2, not ln 2
fn paper_preset_reproduces_the_paper_functions() {
    let t = axiscal::sim::paper_robot();
    assert_eq!(t.dof(), 6);
    let n = 32.0 / 19.0;
    let f = |k: usize, a: f64| t.joints[k].transmission.command_from_actual(a);
    let g = |k: usize, a: f64| t.joints[k].coupling_in.as_ref().unwrap().passive(a);
    for i in -10..=10 {
        let a = 0.1 * i as f64;
        let (s, c) = a.sin_cos();
        assert_relative_eq!(f(0, a), a + 0.000771 * s - 0.000007 * c, epsilon = 1e-15);
        assert_relative_eq!(f(1, a), a + 0.001094 * s + 0.001317 * c, epsilon = 1e-15);
        assert_relative_eq!(f(2, a), a + 0.003462 * s - 0.000867 * c, epsilon = 1e-15);
        assert_relative_eq!(f(3, a), a, epsilon = 1e-15);
        let theta_g = a / n + 0.041227 * (a / n).sin() - 0.000013 * (a / n).cos();
        assert_relative_eq!(f(4, a), n * theta_g, epsilon = 1e-14);
        assert_relative_eq!(f(5, a), a + 0.017334 * s + 0.002677 * c, epsilon = 1e-15);
        let frac = ((-0.998132 * s + 0.213253 * c - 0.212863) / (c + 0.096654 * s - 0.0006941)).atan();
        assert_relative_eq!(g(2, a), frac, epsilon = 1e-15);
        assert_relative_eq!(g(3, a), a, epsilon = 1e-15);
        let na = n * a;
        assert_relative_eq!(g(4, a), na - 0.040562 * na.sin() + 0.000018 * na.cos(), epsilon = 1e-14);
    }
    let table2 = [
        (0.00232, 0.0, 90.0, -90.378),
        (-0.6931, 0.00487, 89.828, -179.54),
        (-0.6727, 0.00162, 90.4213, -179.99),
        (-0.0007, 0.00297, 89.8033, -89.921),
        (-0.0039, -0.2331, 89.4829, -90.137),
    ];
    for (r, (a, b, al, be)) in t.rows.iter().zip(table2) {
        assert_eq!((r.a_m, r.b_m, r.alpha_deg, r.beta_deg), (a, b, al, be));
    }
    assert!(t.joints.iter().all(|j| j.transducer_offset == 0.0));
    // The placement turns the base z axis onto the paper's measured axis 1.
    let z1 = t.phi_model().poses(&[0.0; 6]).axis(0).direction.into_inner();
    let z1_paper = nalgebra::Vector3::new(0.001445, 0.002876, 0.999995).normalize();
    assert!((z1 - z1_paper).norm() < 1e-6, "{z1:?}");
}

#[test]
fn truth_files_round_trip_and_reject_unknown_keys() {
    let t = axiscal::sim::paper_robot();
    let text = toml::to_string(&t).unwrap();
    let back = RobotModel::from_toml_str(&text, Path::new("<round trip>")).unwrap();
    assert_eq!(back, t);
    let mut geometric = t.clone();
    geometric.joints[2].coupling_in = Some(CouplingFunction::FourBar(t.four_bars[0].geometry));
    let text = toml::to_string(&geometric).unwrap();
    assert!(text.contains("form = \"four_bar\""), "{text}");
    assert_eq!(RobotModel::from_toml_str(&text, Path::new("x")).unwrap(), geometric);
    let typo = text.replacen("transducer_offset", "transducer_ofset", 1);
    assert!(matches!(
        RobotModel::from_toml_str(&typo, Path::new("x")),
        Err(ModelError::File(axiscal::toml_file::TomlFileError::Parse { .. }))
    ));
}

/// The shipped four-bar is the least-squares four-bar for the paper's fractional form.
#[test]
fn paper_four_bar_matches_the_fractional_form_as_closely_as_a_four_bar_can() {
    let shipped = axiscal::sim::paper_robot().four_bars[0];
    assert_eq!(shipped.from, 2);
    let frac = paper_fractional();
    let target = |t: f64| frac.passive(t);
    let span = 45f64.to_radians();
    let start = FourBarGeometry::parallelogram(shipped.geometry.arm_m, shipped.geometry.crank_m, 90f64.to_radians());
    let fit = fit_four_bar(&target, span, 91, start).unwrap();
    let max_err = (0..=90)
        .map(|i| {
            let t = -span + i as f64 * span / 45.0;
            (shipped.geometry.passive(t).unwrap() - target(t)).abs()
        })
        .fold(0.0, f64::max);
    // The shipped dimensions are the fit rounded to 1 um / 1 urad: the curve moves by less
    // than ~10 urad under such rounding (slope of g wrt a length ~ 1/crank ~ 5 rad/m).
    assert!((max_err - fit.max_abs_error_rad).abs() < 1e-5, "{max_err} vs {fit:?}");
    assert!(fit.max_abs_error_rad < 2.2e-3 && fit.rms_error_rad < 0.7e-3, "{fit:?}");
    for (a, b) in [
        (shipped.geometry.rod_m, fit.geometry.rod_m),
        (shipped.geometry.lever_m, fit.geometry.lever_m),
        (shipped.geometry.crank_angle_rad, fit.geometry.crank_angle_rad),
        (shipped.geometry.lever_angle_rad, fit.geometry.lever_angle_rad),
    ] {
        assert!((a - b).abs() < 2e-6, "{a} vs {b}");
    }
}

#[test]
fn paper_repeatability_sigmas_reproduce_the_paper() {
    let desc = RobotDescription::asea_irb6l();
    let truth = axiscal::sim::paper_robot();
    let model = truth.phi_model();
    let limits: Vec<[f64; 2]> = (0..6).map(|k| desc.limits_internal(k)).collect();
    // The paper observed its repeatability through the theodolites: the distance between two
    // measurements of the tool point.
    let (instrument, _) = MeasurementModel::paper_theodolites().unwrap();
    let tool_point = desc.tool_targets_m()[0];
    let covariance = |p: &nalgebra::Point3<f64>| instrument.covariance_m2(p).ok();
    let observed = ObservedThrough {
        point_in_tool_m: tool_point,
        covariance_m2: &covariance,
    };
    // The shipped sigma is this calibration (seed, 64 poses, 200 draws per pose), rounded to
    // 5 significant digits, and shared by all six joints (see calibrate_uniform_sigma).
    let mut rng = ChaCha12Rng::seed_from_u64(20240611);
    let poses = workspace_poses(&limits, 64, &mut rng);
    let target = RepeatabilityTarget::PAPER;
    let sigma = calibrate_uniform_sigma(&model, &poses, target.mean_radial_mm, &observed, 200, &mut rng).unwrap();
    println!("calibrated sigma {sigma:.5e} rad");
    for a in truth.repeatability_sigmas() {
        assert_relative_eq!(a, sigma, max_relative = 1e-4);
    }
    // Independent check with the full nonlinear kinematics and the real instrument on fresh
    // poses, one pair each, so the pairs are i.i.d. and the standard error is sd / sqrt(n).
    let mut rng = ChaCha12Rng::seed_from_u64(7);
    let fresh = workspace_poses(&limits, 1500, &mut rng);
    let point_in_last_link = model.last_link_from_tool * tool_point;
    let sigmas = truth.repeatability_sigmas();
    let mut distances_mm = Vec::new();
    for q in &fresh {
        let measure = |rng: &mut ChaCha12Rng| {
            let jittered: Vec<f64> = q
                .iter()
                .zip(&sigmas)
                .map(|(qk, s)| qk + s * rng.sample::<f64, _>(rand_distr::StandardNormal))
                .collect();
            instrument.measure(&model.point_on_link(&jittered, 5, &point_in_last_link), rng)
        };
        if let (Ok(a), Ok(b)) = (measure(&mut rng), measure(&mut rng)) {
            distances_mm.push((a - b).norm() * 1e3);
        }
    }
    let n = distances_mm.len() as f64;
    let mean = distances_mm.iter().sum::<f64>() / n;
    let se = (distances_mm.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
    // 10 % tolerance; it must be at least 4 standard errors wide so that a correct model
    // fails with probability < 1e-4.
    let tol_r = 0.1 * target.mean_radial_mm;
    assert!(4.0 * se < tol_r, "mean {mean} se {se}");
    assert!((mean - target.mean_radial_mm).abs() < tol_r, "mean {mean} se {se}");
    // The robot's own orientation jitter stays well below the paper's 0.0033 rad, which was
    // observed through the theodolites (instrument noise alone gives about that much).
    let st = repeatability_stats(&model, &fresh, &sigmas, 1, &mut rng);
    assert!(
        st.mean_orientation_rad + 4.0 * st.orientation_standard_error_rad < target.mean_orientation_rad,
        "{st:?}"
    );
}

fn monte_carlo_spec() -> PerturbationSpec {
    PerturbationSpec::from_toml_str(
        include_str!("../data/perturbation-spec.toml"),
        "tests/data/perturbation-spec.toml",
    )
    .unwrap()
}

#[test]
fn perturbation_is_deterministic_per_seed() {
    let desc = RobotDescription::asea_irb6l();
    let spec = monte_carlo_spec();
    let a = perturb(&desc, &spec, &mut ChaCha12Rng::seed_from_u64(11)).unwrap();
    let b = perturb(&desc, &spec, &mut ChaCha12Rng::seed_from_u64(11)).unwrap();
    let c = perturb(&desc, &spec, &mut ChaCha12Rng::seed_from_u64(12)).unwrap();
    assert_eq!(a, b);
    assert_ne!(a, c);
    // The perturbed robot runs, its four-bar closes, and it is close to the nominal robot.
    let ctrl = Controller::from_description(&desc);
    let cmd = [0.1, 0.3, -0.2, 0.4, 0.5, -0.6];
    let q = a.joint_values(&ctrl, &cmd).unwrap();
    assert!(q.iter().zip(cmd).all(|(q, c)| (q - c).abs() < 0.05), "{q:?}");
    assert!(matches!(a.joints[2].coupling_in, Some(CouplingFunction::FourBar(_))));
    let bad = PerturbationSpec::from_toml_str("[rows]\na_m = { normal = { sigma = 0.5 } }", "<typo>");
    assert!(matches!(
        bad,
        Err(ModelError::File(axiscal::toml_file::TomlFileError::Parse { .. }))
    ));
}

#[test]
fn perturbation_empirical_sigmas_match_the_spec() {
    let desc = RobotDescription::asea_irb6l();
    let spec = monte_carlo_spec();
    let mut rng = ChaCha12Rng::seed_from_u64(3);
    let n = 3000;
    let (mut da, mut dalpha, mut doff) = (vec![], vec![], vec![]);
    for _ in 0..n {
        let t = perturb(&desc, &spec, &mut rng).unwrap();
        da.push((t.rows[1].a_m - desc.rows[1].a_m) * 1e3);
        dalpha.push(t.rows[2].alpha_deg - desc.rows[2].alpha_deg);
        doff.push(t.joints[3].transducer_offset.to_degrees());
    }
    let std = |v: &[f64]| {
        let m = v.iter().sum::<f64>() / v.len() as f64;
        (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
    };
    let cases = [
        (&da, spec.rows.a_mm.unwrap()),
        (&dalpha, spec.rows.alpha_deg.unwrap()),
        (&doff, spec.transducer_offset_deg.unwrap()),
    ];
    for (v, spread) in cases {
        let sigma = spread.std_dev();
        // Standard error of a sample sd is sigma sqrt((kurtosis - 1) / (4 n)) <= sigma /
        // sqrt(2 n) for these (kurtosis <= 3); allow 5 of them.
        let tol = 5.0 * sigma / (2.0 * n as f64).sqrt();
        assert!((std(v) - sigma).abs() < tol, "{spread:?}: {} vs {sigma}", std(v));
    }
    assert!(doff.iter().all(|x| x.abs() <= 0.15));
    assert!(dalpha.iter().all(|x| x.abs() <= 0.05));
}
