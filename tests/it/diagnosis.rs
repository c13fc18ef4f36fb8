//! A small blind suite (`make test`): cases simulated with a hidden key, diagnosed from the
//! measurement CSV alone (written and read back), scored by the suite's own rules. Tolerances
//! come from the noise: an effect counts as detectable when its trace after the baseline
//! refit exceeds twice the smallest gap the diagnoser's noise-only test flags; a fitted
//! parameter must lie within `K_SIGMA` of its reported standard deviation of the truth.
//! Few validation poses and noise replicas keep it fast in a debug build.

use crate::common;

use axiscal::diagnosis::{Diagnosis, DiagnosisOptions, diagnose};
use axiscal::harness::blind::{
    BlindCampaign, BlindOptions, CASE_EFFECTS, CaseKey, CaseResult, Simulator, detectable_size, draw_effect, score,
    simulate_case,
};
use axiscal::measurement::{MeasurementSet, read_measurements, write_measurements};
use axiscal::robot::RobotDescription;
use rand::{SeedableRng, rngs::ChaCha12Rng};

/// Coverage factor of the parameter checks.
const K_SIGMA: f64 = 4.0;

fn blind_options() -> BlindOptions {
    BlindOptions {
        validation_poses: 40,
        ..BlindOptions::default()
    }
}

fn rapier_options() -> BlindOptions {
    BlindOptions {
        simulator: Simulator::Rapier,
        ..blind_options()
    }
}

fn diagnosis_options() -> DiagnosisOptions {
    DiagnosisOptions {
        noise_trials: 2,
        noise_draws: 16,
        ..DiagnosisOptions::default()
    }
}

/// Draws `effect` with `seed`, lets `set_magnitude` fix its size, diagnoses it from its CSV
/// alone, and returns the scored case.
fn run_case(effect: &str, seed: u64, set_magnitude: impl Fn(&mut CaseKey)) -> CaseResult {
    run_case_on(&blind_options(), effect, seed, set_magnitude)
}

/// [`run_case`] on the simulated robot of `options`.
fn run_case_on(options: &BlindOptions, effect: &str, seed: u64, set_magnitude: impl Fn(&mut CaseKey)) -> CaseResult {
    run_case_with_data(options, effect, seed, set_magnitude).0
}

/// [`run_case_on`], also returning the data read back from the CSV.
fn run_case_with_data(
    options: &BlindOptions,
    effect: &str,
    seed: u64,
    set_magnitude: impl Fn(&mut CaseKey),
) -> (CaseResult, MeasurementSet) {
    let desc = options.campaign.description();
    let mut key = draw_effect(effect, 0, seed, &desc, &mut ChaCha12Rng::seed_from_u64(seed));
    set_magnitude(&mut key);
    let set = simulate_case(&key, &desc, options).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("data.csv");
    write_measurements(&csv, &set, true).unwrap();
    let blind = read_measurements(&csv, Some(desc.dof())).unwrap();
    let d = diagnose(&blind, &desc, &diagnosis_options()).unwrap();
    let size = detectable_size(&key, &desc, options, &diagnosis_options(), d.detectable_gap_mm).unwrap();
    let result = CaseResult {
        key,
        diagnosis: d,
        size_ratio: size.map(|s| s.0),
        detectable_magnitude: size.and_then(|s| s.1),
    };
    (result, blind)
}

fn parameter(d: &Diagnosis, name: &str) -> (f64, f64) {
    let p = d.parameters.iter().find(|p| p.name == name).unwrap();
    (p.value, p.sigma)
}

/// An effect well above its detectable size is named, on the right joint, its gap shrinks by
/// 70 % or to below the detectable gap, and its parameters agree with the truth.
fn assert_found(r: &CaseResult) {
    let (k, d) = (&r.key, &r.diagnosis);
    let ratio = r.size_ratio.unwrap();
    assert!(ratio >= 2.0, "case too small for the test: size ratio {ratio}");
    assert_eq!(d.outcome.effect, k.expected, "{}", d.verdict);
    assert_eq!(d.outcome.joint, k.joint, "{}", d.verdict);
    assert_gap_closed(d);
}

/// The named effect's gap shrank by 70 % or to below the detectable gap.
fn assert_gap_closed(d: &Diagnosis) {
    assert!(
        d.outcome.gap_after_mm <= 0.3 * d.outcome.gap_before_mm || d.outcome.gap_after_mm < d.detectable_gap_mm,
        "gap {} -> {} mm (detectable {}): {}",
        d.outcome.gap_before_mm,
        d.outcome.gap_after_mm,
        d.detectable_gap_mm,
        d.verdict
    );
}

/// `d` names `effect` on `joint` and closes its gap.
fn assert_named(d: &Diagnosis, effect: &str, joint: usize) {
    assert_eq!(d.outcome.effect, effect, "{}", d.verdict);
    assert_eq!(d.outcome.joint, Some(joint), "{}", d.verdict);
    assert_gap_closed(d);
}

#[test]
fn no_effect_is_none_and_json_has_the_fixed_fields() {
    let (r, data) = run_case_with_data(&blind_options(), "none", 3, |_| {});
    let d = &r.diagnosis;
    assert_eq!(d.outcome.effect, "none", "{}", d.verdict);
    let right = d.tool_targets.as_ref().unwrap();
    assert!(!right.far, "right tool targets flagged far off: {:?}", right.distances);
    wrong_tool_targets_are_refined(&data, d);
    let json: serde_json::Value = serde_json::to_value(d).unwrap();
    for field in [
        "effect",
        "joint",
        "confidence",
        "gap_before_mm",
        "gap_after_mm",
        "where",
        "candidates",
    ] {
        assert!(json.get(field).is_some(), "missing {field}");
    }
    let w = &json["where"][0];
    assert!(w.get("experiment").is_some() && w.get("joint").is_some() && w.get("excess_ratio").is_some());
    let c = &json["candidates"][0];
    assert!(c.get("effect").is_some() && c.get("joint").is_some() && c.get("heldout_rms_mm").is_some());
    // WHERE per workspace feature: every varying feature has its bins, and without an effect
    // each bin's held-out RMS matches the noise-only replicas' within K_SIGMA of a bin's
    // relative RMS scatter, 1 / sqrt(2 n) for its n degrees of freedom. The repeatability
    // jitter moves a pose's three targets together, so a pose's nine coordinates carry at
    // least about 3 independent degrees of freedom (jitter dominating: one per direction); a
    // tercile bin holds at least 6 of the 20 held-out poses, an approach bin at least 3
    // (`MIN_BIN_POSES`).
    for f in [
        "reach",
        "payload",
        "temperature",
        "joint_angle_2",
        "gravity_torque_2",
        "approach_1",
    ] {
        assert!(
            d.where_
                .iter()
                .any(|w| w.experiment.starts_with(&format!("feature:{f}:"))),
            "no `where` bins for {f}"
        );
    }
    for w in d.where_.iter().filter(|w| w.experiment.starts_with("feature:")) {
        let tercile = ["low", "mid", "high"].iter().any(|b| w.experiment.ends_with(b));
        let poses: f64 = if tercile { 6.0 } else { 3.0 };
        let bound = K_SIGMA / (2.0 * 3.0 * poses).sqrt();
        assert!(
            (w.excess_ratio - 1.0).abs() < bound,
            "{}: excess {}",
            w.experiment,
            w.excess_ratio
        );
    }
    // Each feature's contrast test false-alarms at max(alpha, 1 / (samples + 1)), 1/33 with
    // this test's 32 null samples: over 21 features four or more alarms have probability
    // 0.3 % (binomial tail).
    assert!(d.features.len() >= 15, "{} features", d.features.len());
    let alarms = d.features.iter().filter(|f| f.beyond_noise).count();
    assert!(alarms < 4, "{alarms} features beyond noise without an effect");
    let dir = tempfile::tempdir().unwrap();
    let written = axiscal::diagnosis::write_plots(d, dir.path()).unwrap();
    assert_eq!(written.len(), axiscal::diagnosis::PLOT_FILES.len());
    for f in written {
        assert!(std::fs::metadata(&f).unwrap().len() > 1000, "{} is empty", f.display());
    }
    let s = score(&[r]);
    assert_eq!(s.none_accuracy, 1.0);
}

/// The description's third tool target guessed 300 mm too high (an extension the drawing
/// leaves out): the diagnosis refines the targets from the training poses, reads the verdict it reads
/// with the right ones (`right`), recovers the true distances between the targets within
/// `K_SIGMA` of their reported sigma, and warns that the guess is far off. Scored with the
/// guess as it is, the same data read otherwise (the test's shape: on this campaign with 40
/// poses a guess up to 100 mm off is absorbed by the refit even unrefined, measured with
/// `axiscal diagnose --nominal-tool-targets`, `docs/diagnosis.md`; 300 mm read `unexplained`).
fn wrong_tool_targets_are_refined(data: &MeasurementSet, right: &Diagnosis) {
    let desc = RobotDescription::asea_irb6l();
    let mut guess = desc.clone();
    guess.tool.targets_mm[2][2] += 300.0;
    let refined = diagnose(data, &guess, &diagnosis_options()).unwrap();
    assert_eq!(refined.outcome.effect, right.outcome.effect, "{}", refined.verdict);
    let t = refined.tool_targets.as_ref().unwrap();
    assert!(t.far && t.warning().is_some(), "{:?}", t.distances);
    let truth = desc.tool_targets_m();
    for d in &t.distances {
        let true_mm = (truth[d.first_target] - truth[d.second_target]).norm() * 1e3;
        assert!(
            (d.refined_mm - true_mm).abs() <= K_SIGMA * d.sigma_mm,
            "{d:?}, true {true_mm} mm"
        );
    }
    let nominal = DiagnosisOptions {
        refine_tool_targets: false,
        ..diagnosis_options()
    };
    let unrefined = diagnose(data, &guess, &nominal).unwrap();
    assert_ne!(unrefined.outcome.effect, right.outcome.effect, "{}", unrefined.verdict);
}

#[test]
fn axis_wobble_is_found_with_its_tilt() {
    let r = run_case("axis_wobble", 5, |k| {
        // The order-2 rotating member, whose two tilt components the test checks.
        k.effects.wobble[0].amplitude_rad = 6e-3;
        k.effects.wobble[0].joint = 6;
        k.effects.wobble[0].order = 2;
        k.effects.wobble[0].fixed_direction_rad = None;
        (k.magnitude, k.joint) = (6e-3, Some(6));
    });
    assert_found(&r);
    let truth = &r.key.effects.wobble[0];
    let (a, phase) = (truth.amplitude_rad, truth.phase_rad);
    for (name, t) in [("tilt_x_rad", a * phase.cos()), ("tilt_y_rad", a * phase.sin())] {
        let (v, s) = parameter(&r.diagnosis, name);
        assert!((v - t).abs() <= K_SIGMA * s, "{name}: fitted {v} +- {s}, truth {t}");
    }
}

/// A uniform instrument scale is absorbed by the refit (every length it fits scales with the
/// instrument): its detectable size is "none at any magnitude", not the ~1e13 ppm a trace at
/// the refit's rounding level gave; an effect the refit does not absorb keeps a finite one.
#[test]
fn an_instrument_scale_is_absorbed_not_detectable_at_some_huge_size() {
    let desc = RobotDescription::asea_irb6l();
    let options = blind_options();
    // The detectable gap is of the order of the noise per coordinate (0.08-0.10 mm against
    // 0.11 mm, docs/diagnosis.md); only its order matters against the absorption floor.
    let gap_mm = options.noise_rms_3d_mm / 3f64.sqrt();
    let size_of = |effect: &str| {
        let key = draw_effect(effect, 0, 5, &desc, &mut ChaCha12Rng::seed_from_u64(5));
        detectable_size(&key, &desc, &options, &diagnosis_options(), gap_mm).unwrap()
    };
    assert_eq!(size_of("instrument_scale"), Some((0.0, None)));
    let (ratio, magnitude) = size_of("thermal_expansion").unwrap();
    assert!(
        ratio > 0.0 && magnitude.is_some_and(f64::is_finite),
        "{ratio} {magnitude:?}"
    );
}

#[test]
fn out_of_set_instrument_sag_is_unexplained() {
    // A case index with odd `case / CASE_EFFECTS.len()` draws the out-of-set kind that is the
    // instrument sag.
    let desc = RobotDescription::asea_irb6l();
    let mut key = draw_effect(
        "unknown",
        CASE_EFFECTS.len(),
        7,
        &desc,
        &mut ChaCha12Rng::seed_from_u64(7),
    );
    // 4.1e-4 /m was 1.6 times its detectable size with the repeatability jitter and this
    // test's 40 poses; the trace is linear in the curvature, so 1e-3 /m (within the
    // generator's 2e-4..2e-3) is about 4 times.
    let sag = key.sag.as_mut().unwrap();
    sag.curvature_per_m = 1e-3;
    key.magnitude = sag.curvature_per_m;
    let r = run_case("unknown", 7, |k| *k = key.clone());
    let d = &r.diagnosis;
    assert!(r.size_ratio.unwrap() >= 2.0, "size ratio {:?}", r.size_ratio);
    assert_eq!(d.outcome.effect, "unexplained", "{}", d.verdict);
}

/// Joint-2 compliance of 4e3 N m/rad (30-50 mrad of sag; with the repeatability jitter the
/// detectable stiffness with this test's 40 validation poses is about 1e4, so the check of
/// `assert_found` that the case is twice its detectable size holds), simulated on the rapier
/// arm (servo springs, the four-bar as bodies), is named with
/// its compliance. The validation payloads expose it: without them the sag follows joint 2's
/// angle alone and the calibration fits it into the transmission.
#[test]
fn joint_2_compliance_is_found_on_the_rapier_arm_with_its_stiffness() {
    let stiffness_nm_per_rad = 4.0e3;
    let r = run_case_on(&rapier_options(), "joint_compliance", 2, |k| {
        let c = k.effects.compliance.as_mut().unwrap();
        c.stiffness_nm_per_rad = vec![1e12; c.stiffness_nm_per_rad.len()];
        c.stiffness_nm_per_rad[1] = stiffness_nm_per_rad;
        // The description's masses and the payload on the tool frame's origin: the member
        // whose compliance is the stiffness's inverse.
        k.effects.link_masses.clear();
        k.effects.payload = None;
        (k.magnitude, k.joint) = (stiffness_nm_per_rad, Some(2));
    });
    assert_found(&r);
    let (v, s) = parameter(&r.diagnosis, "compliance_rad_per_nm");
    let truth = 1.0 / stiffness_nm_per_rad;
    assert!(
        (v - truth).abs() <= K_SIGMA * s,
        "compliance: fitted {v} +- {s}, truth {truth}"
    );
}

/// The free-pose campaign (`axiscal blind --campaign free-poses`): the six-axis arm without a
/// mechanism measured at poses alone, calibrated by the diagnoser from its training poses. A
/// joint-2 sag whose actuator carries the serial chain's load, a balancer taking 70 % of the
/// upper arm's own torque, is named on joint 2 along the serial path and its gap closed; a
/// backlash of joint 4 is named on joint 4; the same arm without an effect reads `none`.
#[test]
fn free_pose_cases_name_a_balanced_serial_sag_and_a_backlash() {
    let options = BlindOptions {
        campaign: BlindCampaign::FreePoses,
        validation_poses: 120,
        ..BlindOptions::default()
    };
    let stiffness_nm_per_rad = 1.0e4;
    let r = run_case_on(&options, "joint_compliance", 3, |k| {
        let c = k.effects.compliance.as_mut().unwrap();
        c.stiffness_nm_per_rad = vec![1e12; c.stiffness_nm_per_rad.len()];
        c.stiffness_nm_per_rad[1] = stiffness_nm_per_rad;
        c.balancer_fraction = vec![0.0, 0.7, 0.0, 0.0, 0.0, 0.0];
        (k.magnitude, k.joint) = (stiffness_nm_per_rad, Some(2));
    });
    assert_found(&r);
    let member = r.diagnosis.member.clone().unwrap_or_default();
    assert!(
        member.contains("serial_load"),
        "member {member}: {}",
        r.diagnosis.verdict
    );
    let r = run_case_on(&options, "backlash", 3, |k| {
        let b = k.effects.backlash.as_mut().unwrap();
        b.band_rad = vec![0.0, 0.0, 0.0, 4.0e-3, 0.0, 0.0];
        (k.magnitude, k.joint) = (4.0e-3, Some(4));
    });
    assert_found(&r);
    let r = run_case_on(&options, "none", 3, |_| {});
    assert_eq!(r.diagnosis.outcome.effect, "none", "{}", r.diagnosis.verdict);
}

/// Without a given noise the diagnosis takes the calibration's estimate from the axis
/// experiments' residuals: on a clean case (repeatability jitter on, which the estimate
/// subtracts) measured with 0.3 mm of 3-D noise instead of the default 0.19 mm, the estimate
/// lies within `K_SIGMA` of its relative standard deviation `1 / sqrt(2 nu_eff)` of the truth.
#[test]
fn the_noise_is_estimated_from_the_axis_experiments() {
    let desc = RobotDescription::asea_irb6l();
    let key = draw_effect("none", 0, 11, &desc, &mut ChaCha12Rng::seed_from_u64(11));
    let truth_mm = 0.3;
    let options = BlindOptions {
        noise_rms_3d_mm: truth_mm,
        validation_poses: 4,
        ..BlindOptions::default()
    };
    let set = simulate_case(&key, &desc, &options).unwrap();
    let e = axiscal::diagnosis::estimated_noise(&set, &desc).unwrap().unwrap();
    let sd_mm = e.rms_3d_mm / (2.0 * e.effective_dof).sqrt();
    assert!(
        (e.rms_3d_mm - truth_mm).abs() <= K_SIGMA * sd_mm,
        "estimated {} mm (sd {sd_mm}), truth {truth_mm} mm",
        e.rms_3d_mm
    );
    assert!(e.jitter_share > 0.0, "the repeatability share is subtracted");
}

/// Effects computed by this test's own formulas on a clean simulated campaign (not by the
/// simulator's effect code, whose shapes the diagnosis shares): every measured point rotated
/// about joint 1's nominal axis line by a rotation that depends on joint 1's command alone,
/// `rotation_in_base(theta_1)` a rotation vector in the base frame \[rad\]. Everything the
/// campaign measures is carried by joint 1, so this is an error of joint 1's axis or angle;
/// the nominal axis (not the simulated truth's, a few mm and mrad away) only moves the
/// rotation's line by that much, a second-order change of the effect.
fn rotated_by_joint_1(
    set: &axiscal::measurement::MeasurementSet,
    desc: &RobotDescription,
    rotation_in_base: impl Fn(f64) -> nalgebra::Vector3<f64>,
) -> axiscal::measurement::MeasurementSet {
    use nalgebra::{Point3, UnitQuaternion};
    let base = desc.nominal_model().world_from_base;
    let origin_mm = Point3::from(base.translation.vector * 1e3);
    let rows = set
        .rows()
        .iter()
        .map(|m| {
            let tilt = UnitQuaternion::from_scaled_axis(base.rotation * rotation_in_base(m.cmd[0].to_radians()));
            let p = origin_mm + tilt * (Point3::from(m.position_mm) - origin_mm);
            axiscal::measurement::Measurement {
                position_mm: [p.x, p.y, p.z],
                ..m.clone()
            }
        })
        .collect();
    axiscal::measurement::MeasurementSet::new(desc.dof(), rows).unwrap()
}

/// A clean case (repeatability jitter and noise on) with one of [`rotated_by_joint_1`]'s
/// effects, diagnosed from its CSV.
fn diagnose_joint_1_effect(rotation_in_base: impl Fn(f64) -> nalgebra::Vector3<f64>) -> Diagnosis {
    let desc = RobotDescription::asea_irb6l();
    let key = draw_effect("none", 0, 3, &desc, &mut ChaCha12Rng::seed_from_u64(3));
    let clean = simulate_case(&key, &desc, &blind_options()).unwrap();
    let set = rotated_by_joint_1(&clean, &desc, rotation_in_base);
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("data.csv");
    write_measurements(&csv, &set, true).unwrap();
    let blind = read_measurements(&csv, Some(desc.dof())).unwrap();
    diagnose(&blind, &desc, &diagnosis_options()).unwrap()
}

/// A 15 mrad swash of joint 1 (a tilt about a fixed horizontal direction at 37 deg from the
/// base's x axis, varying as `A sin(theta + 1.4)`), computed by this test's own formula, is
/// named an axis wobble of joint 1 and closes the gap. Over the validation poses' +-40 deg of
/// joint 1 the tilt's part linear in the angle is an axis-direction error the calibration
/// absorbs (a 5 mrad swash at phase 0.7 left no gap at all with this test's 40 poses); what
/// shows is its curvature, about `A sin(1.4) theta^2 / 2`, 3.6 mrad at the span's ends, over
/// three times the simulator's median detectable wobble (1.1 mrad with 100 poses).
#[test]
fn independent_swash_of_joint_1_is_an_axis_wobble() {
    let (amplitude_rad, phase_rad, direction_rad) = (15e-3, 1.4, 37f64.to_radians());
    let d = diagnose_joint_1_effect(|theta| {
        nalgebra::Vector3::new(direction_rad.cos(), direction_rad.sin(), 0.0)
            * amplitude_rad
            * (theta + phase_rad).sin()
    });
    assert_named(&d, "axis_wobble", 1);
}

/// A 5 mrad order-3 harmonic of joint 1's angle at a phase of 2.2 rad (the calibrator fits
/// order 1; three times the simulator's median detectable gear harmonic of 1.7 mrad with 100
/// poses), computed by this test's own formula, is named a gear harmonic of joint 1.
#[test]
fn independent_order_3_harmonic_of_joint_1_is_a_gear_harmonic() {
    let (amplitude_rad, phase_rad) = (5e-3, 2.2);
    let d = diagnose_joint_1_effect(|theta| nalgebra::Vector3::z() * amplitude_rad * (3.0 * theta + phase_rad).sin());
    assert_named(&d, "gear_harmonic", 1);
}

/// A file of `tests/data/independent-parallelogram/` (a separately written Python generator:
/// its own DH kinematics, masses, noise and sag physics; README there).
fn parallelogram(file: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/independent-parallelogram")
        .join(file)
}

/// `axiscal diagnose --quiet` of `data` for `robot` with the options `extra`: its
/// `diagnosis.json`.
fn diagnose_file(robot: &std::path::Path, data: &std::path::Path, extra: &[&str]) -> serde_json::Value {
    let dir = tempfile::tempdir().unwrap();
    common::axiscal()
        .args(["diagnose", "--quiet"])
        .args(extra)
        .arg("--robot")
        .arg(robot)
        .arg(data)
        .arg("--out")
        .arg(dir.path())
        .assert()
        .success();
    serde_json::from_str(&std::fs::read_to_string(dir.path().join("diagnosis.json")).unwrap()).unwrap()
}

/// `axiscal diagnose` of an independent parallelogram file: its `diagnosis.json`.
fn diagnose_parallelogram(file: &str) -> serde_json::Value {
    diagnose_file(&parallelogram("pg-arm.toml"), &parallelogram(file), &[])
}

/// Joint-2 compliance of an arm unlike the paper's (a DH arm whose forearm is driven through a
/// parallelogram), written by a separate generator, along the load paths a real arm has: the
/// actuator carrying the serial chain's torque (the forearm's own moment included), the same
/// with a spring balancer taking 70 % of the upper arm's torque, the rigid parallelogram's
/// virtual-work load; and a joint-3 compliance. Each is named on its joint, the serial ones by
/// a member of the serial load path (the family's only members whose load includes the
/// forearm's own moment at actuator 2), and closes at least half the gap; the clean file of
/// the same generator reads `none`.
#[test]
fn load_paths_of_an_independent_parallelogram_arm_are_named() {
    let clean = diagnose_parallelogram("none.csv");
    assert_eq!(clean["effect"], "none", "{}", clean["verdict"]);
    for (file, joint, path) in [
        ("serial-mid.csv", 2, Some("serial_load")),
        ("balancer-f0.7.csv", 2, Some("serial_load")),
        ("mechanism-hi.csv", 2, None),
        ("joint3-hi.csv", 3, None),
    ] {
        let d = diagnose_parallelogram(file);
        assert_eq!(d["effect"], "joint_compliance", "{file}: {}", d["verdict"]);
        assert_eq!(d["joint"], joint, "{file}");
        let member = d["member"].as_str().unwrap();
        if let Some(path) = path {
            assert!(member.contains(path), "{file}: {member}");
        }
        let (before, after) = (
            d["gap_before_mm"].as_f64().unwrap(),
            d["gap_after_mm"].as_f64().unwrap(),
        );
        assert!(after < 0.5f64.sqrt() * before, "{file}: gap {before} -> {after} mm");
    }
}

/// A file of `tests/data/independent-freepose/` (free poses of a DH arm from a separately
/// written generator; README there).
fn free_pose_file(file: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/independent-freepose")
        .join(file)
}

/// Free poses only, from the independent generator (0.02 mm per coordinate: 0.02 sqrt(3) mm
/// 3-D RMS, given as the instrument's figure): the diagnosis calibrates from the even poses
/// and names the effect on the odd ones. The clean file reads `none`; gravity sag on joints 2
/// and 3 (serial load path) is a joint compliance of one of them; backlash of joints 1-3 is a
/// backlash of one of them that closes most of the gap. Without `--noise-mm` the free poses
/// cannot tell noise from model error: exit 2, saying so. Six noise-only replicas (192
/// samples of the null, enough for its 1 % quantile) keep the debug build's time down.
#[test]
fn free_poses_alone_are_diagnosed_on_held_out_poses() {
    let noise_mm = format!("{}", 0.02 * 3f64.sqrt());
    let run = |file: &str| {
        diagnose_file(
            &free_pose_file("kr-arm.toml"),
            &free_pose_file(file),
            &["--noise-trials", "6", "--noise-mm", &noise_mm],
        )
    };
    assert_eq!(run("clean.csv")["effect"], "none");
    for (file, effect, joints) in [
        ("serial.csv", "joint_compliance", [2, 3]),
        ("backlash.csv", "backlash", [1, 3]),
    ] {
        let d = run(file);
        assert_eq!(d["effect"], effect, "{file}: {}", d["verdict"]);
        let joint = d["joint"].as_u64().unwrap();
        assert!((joints[0]..=joints[1]).contains(&joint), "{file}: joint {joint}");
        let (before, after) = (
            d["gap_before_mm"].as_f64().unwrap(),
            d["gap_after_mm"].as_f64().unwrap(),
        );
        assert!(after < 0.5f64.sqrt() * before, "{file}: gap {before} -> {after} mm");
    }
    let dir = tempfile::tempdir().unwrap();
    let refused = common::axiscal()
        .args(["diagnose", "--quiet", "--robot"])
        .arg(free_pose_file("kr-arm.toml"))
        .arg(free_pose_file("clean.csv"))
        .arg("--out")
        .arg(dir.path())
        .assert()
        .code(2);
    assert!(common::stderr(&refused).contains("--noise-mm"));
}

/// Two campaigns of the paper robot with a joint-2 compliance (1.5e4 N m/rad) whose actuator
/// carries the serial chain's load, each its own validation poses, payloads, temperatures,
/// noise and jitter.
fn two_compliant_campaigns() -> (RobotDescription, MeasurementSet, MeasurementSet) {
    let options = BlindOptions {
        validation_poses: 60,
        ..BlindOptions::default()
    };
    let desc = RobotDescription::asea_irb6l();
    let mut key = draw_effect("joint_compliance", 0, 4, &desc, &mut ChaCha12Rng::seed_from_u64(4));
    let c = key.effects.compliance.as_mut().unwrap();
    c.stiffness_nm_per_rad = vec![1e12; desc.dof()];
    c.stiffness_nm_per_rad[1] = 1.5e4;
    c.reflected_fraction = 0.0;
    c.balancer_fraction = Vec::new();
    let a = simulate_case(&key, &desc, &options).unwrap();
    key.seed += 1000;
    let b = simulate_case(&key, &desc, &options).unwrap();
    (desc, a, b)
}

/// Effects carried into the model (`calibrate --refine --carry`): on the paper campaign with a
/// joint-2 compliance whose actuator carries the serial chain's load, the diagnosis names it,
/// the refinement fits it with the geometry and folds it into the model, and on a second
/// campaign of the same robot (new validation poses, payloads, temperatures, noise and
/// repeatability jitter) the carried model's validation RMS is within `K_SIGMA` standard errors
/// (`rms / sqrt(2 m)` over `m` coordinates) of what noise and jitter alone leave after a refit
/// (the diagnosis's noise-only held-out RMS), while the refinement without it is beyond them.
#[test]
fn a_named_compliance_carried_into_the_model_closes_the_gap_on_new_poses() {
    use axiscal::calibration::procedure::{CalibrationOptions, calibrate};
    use axiscal::calibration::refine::RefineOptions;
    use axiscal::calibration::refit_model::refine::{refine_calibration, refine_carrying};
    use axiscal::diagnosis::{ValidationOptions, carried_candidates, validate};
    let (desc, a, b) = two_compliant_campaigns();
    let d = diagnose(&a, &desc, &diagnosis_options()).unwrap();
    assert_eq!(
        (d.outcome.effect.as_str(), d.outcome.joint),
        ("joint_compliance", Some(2)),
        "{}",
        d.verdict
    );
    let cal = calibrate(&a, &desc, &CalibrationOptions::default()).unwrap();
    let noise_mm = cal.noise.as_ref().unwrap().used_rms_3d_mm;
    let refine = RefineOptions {
        noise_rms_3d_mm: noise_mm,
        ..RefineOptions::default()
    };
    let carried = carried_candidates(&d, &desc, &a).unwrap();
    let (refined, _) = refine_calibration(&a, &desc, &cal, &refine).unwrap();
    let (with_effect, _) = refine_carrying(&a, &desc, &cal, &refine, &carried).unwrap();
    assert!(!with_effect.robot.effects.compliance.is_empty());
    let check = ValidationOptions::given(noise_mm, 0.01);
    let on_b = |cal| validate(&b, cal, &desc, &check).unwrap().validation.unwrap();
    let (without, with) = (on_b(&refined), on_b(&with_effect));
    let bound = d.noise_only_rms_mm * (1.0 + K_SIGMA / (2.0 * 3.0 * with.points as f64).sqrt());
    assert!(
        with.rms_mm < bound && without.rms_mm > bound,
        "validation RMS on new poses: {} mm with the carried effect, {} mm without, against {bound} mm",
        with.rms_mm,
        without.rms_mm
    );
}

/// `--carry` through the command line: `diagnose` names the compliance of
/// [`two_compliant_campaigns`]' first file, `calibrate --refine --carry` writes it into
/// `calibration.json`'s `robot.effects.compliance`, and `validate` of the second file with it
/// leaves less than without it (`--refine` alone). `--carry` needs `--refine`; a diagnosis that
/// names nothing, or an axes-only one, is refused with the file named; all exit 2.
#[test]
fn carry_writes_the_named_effect_into_calibration_json() {
    let (_, a, b) = two_compliant_campaigns();
    let dir = tempfile::tempdir().unwrap();
    let (csv_a, csv_b) = (dir.path().join("a.csv"), dir.path().join("b.csv"));
    write_measurements(&csv_a, &a, true).unwrap();
    write_measurements(&csv_b, &b, true).unwrap();
    let run = |args: &[&str]| common::axiscal().arg("--quiet").args(args).assert();
    let path = |p: &std::path::Path| p.to_str().unwrap().to_owned();
    let (dg, with, without) = (
        dir.path().join("dg"),
        dir.path().join("with"),
        dir.path().join("without"),
    );
    run(&["diagnose", &path(&csv_a), "--out", &path(&dg)]).success();
    let diagnosis = dg.join("diagnosis.json");
    run(&[
        "calibrate",
        &path(&csv_a),
        "--refine",
        "--carry",
        &path(&diagnosis),
        "--out",
        &path(&with),
    ])
    .success();
    run(&["calibrate", &path(&csv_a), "--refine", "--out", &path(&without)]).success();
    let json = |p: std::path::PathBuf| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
    };
    let cal = json(with.join("calibration.json"));
    assert_eq!(cal["robot"]["effects"]["compliance"][0]["joint"], 2);
    let rms = |cal_dir: &std::path::Path| {
        let out = cal_dir.join("validation");
        let calibration = path(&cal_dir.join("calibration.json"));
        run(&[
            "validate",
            "--calibration",
            &calibration,
            &path(&csv_b),
            "--out",
            &path(&out),
        ])
        .success();
        json(out.join("summary.json"))["validation"]["rms_mm"].as_f64().unwrap()
    };
    let (rms_with, rms_without) = (rms(&with), rms(&without));
    assert!(
        rms_with < rms_without,
        "validation RMS {rms_with} mm with the carried effect, {rms_without} mm without"
    );
    let refused = run(&[
        "calibrate",
        &path(&csv_a),
        "--carry",
        &path(&diagnosis),
        "--out",
        &path(&with),
        "--force",
    ]);
    refused.code(2);
    let mut none = json(diagnosis.clone());
    none["effect"] = "none".into();
    none["member"] = serde_json::Value::Null;
    let none_file = dir.path().join("none.json");
    std::fs::write(&none_file, serde_json::to_string(&none).unwrap()).unwrap();
    let refused = run(&[
        "calibrate",
        &path(&csv_a),
        "--refine",
        "--carry",
        &path(&none_file),
        "--out",
        &path(&with),
        "--force",
    ]);
    let message = common::stderr(&refused.code(2));
    assert!(
        message.contains("none.json") && message.contains("names no effect"),
        "{message}"
    );
    let axes_only = dir.path().join("axes.json");
    std::fs::write(&axes_only, r#"{"schema": "axiscal.diagnosis/1", "mode": "axes_only"}"#).unwrap();
    let carry_axes = path(&axes_only);
    let refused = run(&[
        "calibrate",
        &path(&csv_a),
        "--refine",
        "--carry",
        &carry_axes,
        "--out",
        &path(&with),
        "--force",
    ]);
    let message = common::stderr(&refused.code(2));
    assert!(message.contains("axes-only diagnosis"), "{message}");
}
