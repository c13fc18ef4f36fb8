//! Gross errors among the sweeps' points are found, named by file line and left out of the
//! calibration (`calibration::procedure::screen_sweeps`): a corrupted reading, a corrupted
//! coordinate, two swapped points, a point in metres, on the paper robot and on a sliding
//! table, one at a time and in several sweeps at once. A clean campaign loses no point.
//! Results no robot of the description gives (a mirrored or scaled instrument frame, a sweep
//! partly shifted) are said (`calibration::procedure::implausible`).

use crate::common::{self, axiscal, stderr};
use axiscal::calibration::procedure::{CalibrationOptions, Implausible, calibrate, implausible, screen_sweeps};
use axiscal::measurement::{IsotropicNoise, Measurement, MeasurementModel, MeasurementSet};
use axiscal::plan::{CalibrationPlan, ValidationPlan};
use axiscal::robot::{Controller, RobotDescription};
use axiscal::sim::{AnalyticArm, PerturbationSpec, perturb, simulate_campaign};
use rand::SeedableRng;
use rand::rngs::ChaCha12Rng;
use std::path::Path;

/// The row index of (experiment, step, target) in `set`.
fn row(set: &MeasurementSet, experiment: &str, step: usize, target: usize) -> usize {
    set.rows()
        .iter()
        .position(|m| m.experiment == experiment && m.step == step && m.target == target)
        .expect("the row exists")
}

/// `set` with `change` applied to its rows `rows`.
fn edited(set: &MeasurementSet, rows: &[usize], change: impl Fn(&mut Measurement)) -> MeasurementSet {
    let mut all = set.clone().into_rows();
    for &r in rows {
        change(&mut all[r]);
    }
    MeasurementSet::new(set.joint_count(), all).expect("still a valid set")
}

/// The (experiment, step) of every point the test flags on `set`, dropped.
fn flagged(set: &MeasurementSet, desc: &RobotDescription) -> Vec<(String, usize)> {
    let s = screen_sweeps(set, desc, &CalibrationOptions::default(), false).expect("the test runs");
    assert!(s.outliers.iter().all(|o| o.dropped && o.normalised_residual > o.fence));
    s.outliers.into_iter().map(|o| (o.experiment, o.step)).collect()
}

#[test]
fn clean_campaigns_lose_no_point() {
    let desc = RobotDescription::asea_irb6l();
    for seed in 1..=6 {
        let set = common::axes_only_campaign(seed);
        assert_eq!(flagged(&set, &desc), Vec::<(String, usize)>::new(), "seed {seed}");
    }
}

#[test]
fn a_corrupted_reading_of_any_joint_is_dropped_and_the_rest_calibrates_as_without_it() {
    let desc = RobotDescription::asea_irb6l();
    let clean = common::axes_only_campaign(11);
    for joint in 1..=6 {
        let experiment = format!("axis{joint}");
        // The pose's reading, written on each of its targets' rows.
        let pose: Vec<usize> = (0..2)
            .filter_map(|t| {
                clean
                    .rows()
                    .iter()
                    .position(|m| m.experiment == experiment && m.step == 7 && m.target == t)
            })
            .collect();
        // The reading `-0` of the snippet: 3 to 45 degrees off, depending on the joint.
        let bad = edited(&clean, &pose, |m| m.cmd[joint - 1] = 0.0);
        assert_ne!(
            bad.rows()[pose[0]].cmd,
            clean.rows()[pose[0]].cmd,
            "joint {joint}: the reading was changed"
        );
        if joint == 2 || joint == 4 {
            // Joint 3's (5's) command follows joint 2's (4's) while it is held (the four-bar's
            // and the bevel gear's hold-still formula): that cross-check names the pose first.
            let e = screen_sweeps(&bad, &desc, &CalibrationOptions::default(), false).unwrap_err();
            assert!(
                e.to_string().contains(&experiment) && e.to_string().contains("step 7"),
                "{e}"
            );
            continue;
        }
        assert_eq!(flagged(&bad, &desc), vec![(experiment.clone(), 7)], "joint {joint}");
        let screened = screen_sweeps(&bad, &desc, &CalibrationOptions::default(), false).unwrap();
        // The whole pose is left out: a wrong reading is wrong for every target of it.
        let without = clean.without_rows(&pose);
        assert_eq!(
            screened.set.as_ref(),
            Some(&without),
            "joint {joint}: exactly that row is left out"
        );
        let a = calibrate(screened.set.as_ref().unwrap(), &desc, &CalibrationOptions::default()).unwrap();
        let b = calibrate(&without, &desc, &CalibrationOptions::default()).unwrap();
        assert_eq!(a.robot, b.robot, "joint {joint}");
    }
}

#[test]
fn swapped_points_a_point_in_metres_and_errors_in_several_sweeps_are_all_found() {
    let desc = RobotDescription::asea_irb6l();
    let clean = common::axes_only_campaign(12);
    let (a, b) = (row(&clean, "axis2", 3, 0), row(&clean, "axis2", 12, 0));
    let (pa, pb) = (clean.rows()[a].position_mm, clean.rows()[b].position_mm);
    let swapped = edited(&clean, &[a, b], |m| {
        m.position_mm = if m.step == 3 { pb } else { pa };
    });
    let mut found = flagged(&swapped, &desc);
    found.sort();
    assert_eq!(found, vec![("axis2".to_string(), 3), ("axis2".to_string(), 12)]);
    // One point in metres, one coordinate off by 5 mm, one reading off by 2 degrees: three
    // sweeps at once, so that the sweeps they pull hold a third of the points.
    let rows = [
        row(&clean, "axis1", 5, 0),
        row(&clean, "axis3", 9, 0),
        row(&clean, "axis5", 2, 0),
    ];
    let several = edited(&clean, &rows, |m| match m.experiment.as_str() {
        "axis1" => m.position_mm = m.position_mm.map(|c| c * 1e-3),
        "axis3" => m.position_mm[2] += 5.0,
        _ => m.cmd[4] += 2.0,
    });
    let mut found = flagged(&several, &desc);
    found.sort();
    assert_eq!(
        found,
        vec![
            ("axis1".to_string(), 5),
            ("axis3".to_string(), 9),
            ("axis5".to_string(), 2)
        ]
    );
}

/// The generalised Table 1 of the shipped robot `name` drawn around its description
/// (tests/data/test-robot-spec.toml, stream `seed`), measured with 0.1 mm noise.
fn simulated(name: &str, seed: u64) -> (RobotDescription, MeasurementSet) {
    let desc = RobotDescription::from_file(Path::new(&format!("scenarios/robots/{name}.toml"))).unwrap();
    let spec = PerturbationSpec::from_toml_str(include_str!("../data/test-robot-spec.toml"), "spec").unwrap();
    let truth = perturb(&desc, &spec, &mut ChaCha12Rng::seed_from_u64(seed)).unwrap();
    let mut arm = AnalyticArm::new(truth, Controller::from_description(&desc));
    let validation = ValidationPlan {
        poses: 0,
        ..ValidationPlan::workspace_default(desc.dof())
    };
    let instrument = MeasurementModel::Isotropic(IsotropicNoise { net_radial_rms_mm: 0.1 });
    let out = simulate_campaign(
        &desc,
        &CalibrationPlan::for_robot(&desc),
        &validation,
        &mut arm,
        &instrument,
        &mut ChaCha12Rng::seed_from_u64(seed + 1),
    )
    .unwrap();
    let set = MeasurementSet::new(desc.dof(), out.rows).unwrap();
    (desc, set)
}

#[test]
fn a_corrupted_coordinate_of_a_sliding_table_is_found() {
    let (desc, clean) = simulated("table-prpp", 3);
    assert_eq!(flagged(&clean, &desc), Vec::<(String, usize)>::new());
    for e in clean.experiments().into_iter().filter(|e| e.moved_joint > 0) {
        let steps: Vec<usize> = e.rows.iter().filter(|m| m.target == 0).map(|m| m.step).collect();
        let step = steps[steps.len() / 2];
        let r = row(&clean, e.name, step, 0);
        let bad = edited(&clean, &[r], |m| m.position_mm[1] += 3.0);
        assert_eq!(flagged(&bad, &desc), vec![(e.name.to_string(), step)], "{}", e.name);
    }
}

#[test]
fn keep_outliers_flags_without_dropping() {
    let desc = RobotDescription::asea_irb6l();
    let clean = common::axes_only_campaign(13);
    let r = row(&clean, "axis4", 6, 0);
    let bad = edited(&clean, &[r], |m| m.position_mm[0] += 4.0);
    let kept = screen_sweeps(&bad, &desc, &CalibrationOptions::default(), true).unwrap();
    assert!(kept.set.is_none());
    assert_eq!(kept.outliers.len(), 1);
    assert!(!kept.outliers[0].dropped && kept.outliers[0].step == 6);
}

/// A map of positions \[mm\].
type Map = fn([f64; 3]) -> [f64; 3];

/// `set` with every position mapped by `f`.
fn positions(set: &MeasurementSet, f: impl Fn([f64; 3]) -> [f64; 3]) -> MeasurementSet {
    let rows: Vec<usize> = (0..set.rows().len()).collect();
    edited(set, &rows, |m| m.position_mm = f(m.position_mm))
}

#[test]
fn mirrored_and_scaled_frames_and_a_shifted_half_sweep_are_said() {
    let paper = (RobotDescription::asea_irb6l(), common::axes_only_campaign(14));
    let mut units_named = 0;
    for (name, (desc, clean)) in [
        ("paper", paper),
        ("table-prpp", simulated("table-prpp", 5)),
        ("scara-rrpr", simulated("scara-rrpr", 6)),
    ] {
        let said =
            |set: &MeasurementSet| implausible(&calibrate(set, &desc, &CalibrationOptions::default()).unwrap(), &desc);
        // Or the procedure refuses the fit (`ProcedureError::Absurd`): said as loudly.
        let refused = |set: &MeasurementSet| calibrate(set, &desc, &CalibrationOptions::default()).is_err();
        assert_eq!(said(&clean), vec![], "{name}: clean");
        // Only the six-axis arm's mirror image flips its lengths: the SCARA's and the table's
        // are not told from robots of their descriptions yet (docs/method.md, "Checks of the
        // result").
        let mirrors: &[(&str, Map)] = if name == "paper" {
            &[
                ("x mirrored", |p| [-p[0], p[1], p[2]]),
                ("y mirrored", |p| [p[0], -p[1], p[2]]),
            ]
        } else {
            &[]
        };
        for (what, f) in mirrors {
            let found = said(&positions(&clean, f));
            assert!(
                matches!(found[..], [Implausible::Mirrored { .. }]),
                "{name}, {what}: {found:?}"
            );
            assert!(found[0].to_string().contains("mirror image"), "{name}");
        }
        for scale in [2.0, 0.5, 25.4] {
            let scaled = positions(&clean, |p| p.map(|c| c * scale));
            if refused(&scaled) {
                continue;
            }
            let found = said(&scaled);
            assert!(
                // Said, in the right direction: what the fit holds fixed (the described tool
                // frame) keeps the factor within a few per cent of the scale, not at it.
                matches!(found[..], [Implausible::Size { factor, .. }] if (factor / scale - 1.0).abs() < 0.1),
                "{name}, x{scale}: {found:?}"
            );
            assert!(
                !found[0].to_string().contains("look like"),
                "{name}, x{scale}: {}",
                found[0]
            );
        }
        // Inches and centimetres read as mm: a size said, and the unit named where the factor
        // is within the size tolerance of the unit's (the paper robot's; the described tool
        // frame, held fixed, dominates a small positioner's lengths at a 25th of its size).
        for (scale, unit) in [(1.0 / 25.4, "inches"), (0.1, "centimetres")] {
            let scaled = positions(&clean, |p| p.map(|c| c * scale));
            if refused(&scaled) {
                continue;
            }
            let found = said(&scaled);
            let Implausible::Size { factor, .. } = found[0] else {
                panic!("{name}, x{scale}: {found:?}");
            };
            let near = (factor / scale - 1.0).abs() < axiscal::calibration::procedure::SIZE_TOLERANCE;
            assert!(near || name != "paper", "{name}, x{scale}: {factor}");
            let named = found[0]
                .to_string()
                .contains(&format!("look like {unit} read as millimetres"));
            assert_eq!(named, near, "{name}, x{scale}: {}", found[0]);
            units_named += usize::from(named);
        }
    }
    assert!(
        units_named >= 2,
        "no scale of inches or centimetres was calibrated and named ({units_named})"
    );
    // Half of axis 3's points moved 20 mm: no single point stands out of its sweep, the sweep
    // stands out of the others.
    let clean = common::axes_only_campaign(15);
    let desc = RobotDescription::asea_irb6l();
    let rows: Vec<usize> = (0..8).map(|s| row(&clean, "axis3", s, 0)).collect();
    let shifted = edited(&clean, &rows, |m| m.position_mm[2] += 20.0);
    let found = implausible(
        &calibrate(&shifted, &desc, &CalibrationOptions::default()).unwrap(),
        &desc,
    );
    assert!(matches!(found[..], [Implausible::Misfit { joint: 3, .. }]), "{found:?}");
}

#[test]
fn calibrate_names_the_file_line_of_a_corrupted_cell_and_records_it() {
    let (dir, data) = common::simulated_campaign_csv(1);
    let text = std::fs::read_to_string(&data).unwrap();
    // The snippet: `awk -F, -v OFS=, 'NR==6{$13="-0"}1'`.
    let bad: String = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i == 5 {
                let mut cells: Vec<&str> = l.split(',').collect();
                cells[12] = "-0";
                cells.join(",") + "\n"
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    let bad_path = dir.path().join("bad.csv");
    std::fs::write(&bad_path, bad).unwrap();
    let out = dir.path().join("cal");
    let a = axiscal()
        .arg("calibrate")
        .arg(&bad_path)
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    let err = stderr(&a);
    assert!(
        err.contains("bad.csv:6: outlier: experiment axis6 step 3 target 0"),
        "{err}"
    );
    let cal = common::read_calibration(&out);
    assert_eq!(cal.outliers.len(), 1);
    assert_eq!(cal.outliers[0].line, Some(6));
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        report.contains("## Outliers (1)") && report.contains("| 6 | axis6 | 3 | 0 |"),
        "{report}"
    );
    // Kept, the point spoils its sweep's fit: the procedure refuses it, with the flag said first.
    let a = axiscal()
        .arg("calibrate")
        .arg(&bad_path)
        .args(["--keep-outliers", "--out"])
        .arg(dir.path().join("kept"))
        .assert()
        .code(2);
    let err = stderr(&a);
    assert!(
        err.contains("kept (--keep-outliers)") && err.contains("misses its points"),
        "{err}"
    );
}

/// The false-alarm rate on clean campaigns of the paper robot (its jitter, the paper's
/// instrument). On seeds 1000-1199, used while choosing the sweep scale, 6 of 19,600 sweep
/// points passed the fence, each by less than half of it. These seeds (2000-2199) were run once
/// after: the count is bounded by that rate plus 3 Poisson standard deviations (6 + 3 sqrt 6).
/// `cargo test --release --test it -- --ignored outliers::false_alarms --nocapture`
#[test]
#[ignore = "200 campaigns; run with --release"]
fn false_alarms_on_clean_campaigns_are_rare_and_small() {
    let desc = RobotDescription::asea_irb6l();
    let mut flagged_points = 0;
    for seed in 2000..2200 {
        let s = screen_sweeps(
            &common::axes_only_campaign(seed),
            &desc,
            &CalibrationOptions::default(),
            false,
        )
        .unwrap();
        for o in &s.outliers {
            println!(
                "seed {seed}: {} step {}: {:.3} mm, {:.2} times the noise against the fence {:.2}",
                o.experiment, o.step, o.residual_mm, o.normalised_residual, o.fence
            );
        }
        flagged_points += s.outliers.len();
    }
    println!("flagged points over 200 clean campaigns: {flagged_points}");
    let bound = 6.0 + 3.0 * 6f64.sqrt();
    assert!(flagged_points as f64 <= bound, "{flagged_points} > {bound:.1}");
}

/// The diagnosis's validation points (`diagnosis::validation_outliers`), through `diagnose`:
/// a target 50 mm off and two swapped target ids are named by file line on stderr, listed in
/// `diagnosis.json` and left out, and the diagnosis is then, byte for byte, that of the file
/// with those rows deleted by hand (a second path: the rows removed by the test, not by the
/// program); `--keep-outliers` lists them without dropping them. An effect that moves whole
/// poses (a 1 mrad backlash of joint 3 beside a joint-2 compliance: residuals of several mm on
/// some poses) loses no point.
#[test]
fn diagnose_leaves_out_validation_outliers_and_not_an_effect() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    common::simulate_analytic(d, 40, 21, "clean.csv");
    let text = std::fs::read_to_string(d.join("clean.csv")).unwrap();
    let key = |l: &str| -> (String, usize, usize) {
        let c: Vec<&str> = l.split(',').collect();
        (c[0].to_string(), c[2].parse().unwrap(), c[3].parse().unwrap())
    };
    let is = |l: &str, step: usize, target: usize| {
        !l.starts_with('#') && !l.starts_with("experiment,") && key(l) == ("validation".into(), step, target)
    };
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut bad_lines = Vec::new();
    for (i, l) in lines.iter_mut().enumerate() {
        if is(l, 7, 1) {
            let mut c: Vec<String> = l.split(',').map(String::from).collect();
            c[4] = (c[4].parse::<f64>().unwrap() + 50.0).to_string();
            *l = c.join(",");
            bad_lines.push(i + 1);
        }
    }
    // Targets 0 and 2 of step 12 swapped (their ids exchanged).
    for (i, l) in lines.iter_mut().enumerate() {
        for (from, to) in [(0, 2), (2, 0)] {
            if is(l, 12, from) {
                let mut c: Vec<String> = l.split(',').map(String::from).collect();
                c[3] = to.to_string();
                *l = c.join(",");
                bad_lines.push(i + 1);
                break;
            }
        }
    }
    std::fs::write(d.join("bad.csv"), lines.join("\n") + "\n").unwrap();
    let by_hand: Vec<&str> = text
        .lines()
        .filter(|l| !is(l, 7, 1) && !is(l, 12, 0) && !is(l, 12, 2))
        .collect();
    std::fs::write(d.join("by-hand.csv"), by_hand.join("\n") + "\n").unwrap();
    let diagnose = |file: &str, out: &str, keep: bool| {
        let mut c = axiscal();
        c.current_dir(d).args([
            "diagnose",
            file,
            "--noise-trials",
            "4",
            "--noise-draws",
            "4",
            "--out",
            out,
        ]);
        if keep {
            c.arg("--keep-outliers");
        }
        let a = c.assert().success();
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join(out).join("diagnosis.json")).unwrap()).unwrap();
        (stderr(&a), json)
    };
    let (err, mut bad) = diagnose("bad.csv", "bad", false);
    bad_lines.sort();
    for line in &bad_lines {
        assert!(err.contains(&format!("bad.csv:{line}: outlier")), "line {line}: {err}");
    }
    let listed: Vec<u64> = bad["outliers"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| o["line"].as_u64().unwrap())
        .collect();
    assert_eq!(listed, bad_lines.iter().map(|&l| l as u64).collect::<Vec<_>>());
    assert!(bad["outliers"].as_array().unwrap().iter().all(|o| o["dropped"] == true));
    let (err, hand) = diagnose("by-hand.csv", "hand", false);
    assert!(!err.contains("outlier"), "{err}");
    bad.as_object_mut().unwrap().remove("outliers");
    assert_eq!(
        bad, hand,
        "the diagnosis without the outliers is that of the file without their rows"
    );
    let (_, kept) = diagnose("bad.csv", "kept", true);
    assert_eq!(kept["outliers"].as_array().unwrap().len(), 3);
    assert!(
        kept["outliers"]
            .as_array()
            .unwrap()
            .iter()
            .all(|o| o["dropped"] == false)
    );
    assert_ne!(kept["poses"], serde_json::Value::Null);

    std::fs::write(
        d.join("effects.toml"),
        "[compliance]\nstiffness_nm_per_rad = [1e9, 3e3, 1e9, 1e9, 1e9, 1e9]\n[backlash]\nband_rad = [0.0, 0.0, 1e-3, 0.0, 0.0, 0.0]\n",
    )
    .unwrap();
    axiscal()
        .current_dir(d)
        .args([
            "simulate",
            "--sim",
            "analytic",
            "--seed",
            "12",
            "--validation-poses",
            "100",
        ])
        .args(["--effects", "effects.toml", "--out", "effect.csv"])
        .assert()
        .success();
    let (err, effect) = diagnose("effect.csv", "effect", false);
    assert!(!err.contains("outlier"), "{err}");
    assert!(effect.get("outliers").is_none());
    assert_ne!(effect["effect"], "none", "the effect is seen");
}
