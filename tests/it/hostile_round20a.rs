//! A gross error in a sweep whose held joints wander (a controller's encoder log: the sweep's
//! points lie on no one arc, so the sweep screen cannot test them): the axis fit that fails on
//! it names the point, and `calibrate` drops its pose and calibrates again, as the screen does
//! with the outliers it finds; `--keep-outliers` keeps the point and fails, naming the row.

use crate::common::{self, altered_csv, axiscal};

/// `(experiment, step, mm added to y_mm)` of the gross errors tried, on one target-0 row each.
const CASES: [(&str, &str, f64); 2] = [("axis6", "5", 5.0), ("axis3", "9", -30.0)];

#[test]
fn an_outlier_in_a_wandering_sweep_is_dropped_as_the_file_without_its_pose() {
    let dir = tempfile::tempdir().unwrap();
    let clean = dir.path().join("clean.csv");
    axiscal()
        .args([
            "simulate",
            "--robot",
            "arm6-dh",
            "--truth",
            "arm6-dh-truth",
            "--plan",
            "arm6-jitter-plan",
        ])
        .args([
            "--sim",
            "analytic",
            "--instrument",
            "isotropic",
            "--seed",
            "21",
            "--out",
        ])
        .arg(&clean)
        .assert()
        .success();
    for (experiment, step, add_mm) in CASES {
        let hit = |f: &[String]| f[0] == experiment && f[2] == step && f[3] == "0";
        let bad = altered_csv(
            &clean,
            &format!("bad-{experiment}.csv"),
            |_| true,
            |f| {
                if hit(f) {
                    f[5] = (f[5].parse::<f64>().unwrap() + add_mm).to_string();
                }
            },
        );
        // The second path: the pose's rows deleted by hand.
        let pose = |f: &[String]| f[0] == experiment && f[2] == step;
        let without = altered_csv(&clean, &format!("without-{experiment}.csv"), |f| !pose(f), |_| {});
        let out = dir.path().join(format!("bad-{experiment}"));
        let run = axiscal()
            .args(["calibrate", "--robot", "arm6-dh"])
            .arg(&bad)
            .arg("--out")
            .arg(&out)
            .assert()
            .success();
        let e = common::stderr(&run);
        let line = std::fs::read_to_string(&bad)
            .unwrap()
            .lines()
            .position(|l| {
                let f: Vec<String> = l.split(',').map(String::from).collect();
                f.len() > 3 && hit(&f)
            })
            .unwrap()
            + 1;
        let named = format!(
            "{}:{line}: outlier: experiment {experiment} step {step} target 0:",
            bad.display()
        );
        assert!(
            e.lines()
                .any(|l| l.contains(&named) && l.contains("the sweep screen cannot test")),
            "{experiment}: {e}"
        );
        let record = common::read_record(&out);
        let flagged: Vec<_> = record.calibration.outliers.iter().filter(|o| o.dropped).collect();
        assert_eq!(flagged.len(), 1, "{experiment}: {:?}", record.calibration.outliers);
        assert_eq!(flagged[0].test, axiscal::calibration::procedure::OutlierTest::AxisFit);
        assert_eq!(
            (flagged[0].experiment.as_str(), flagged[0].line),
            (experiment, Some(line as u64))
        );
        let out_without = dir.path().join(format!("without-{experiment}"));
        axiscal()
            .args(["calibrate", "--robot", "arm6-dh"])
            .arg(&without)
            .arg("--out")
            .arg(&out_without)
            .assert()
            .success();
        let by_hand = common::read_record(&out_without).calibration;
        assert_eq!(record.calibration.robot, by_hand.robot, "{experiment}");
        assert_eq!(record.calibration.axes, by_hand.axes, "{experiment}");
        // Kept, the point fails the fit, and the error names its row.
        let kept = axiscal()
            .args(["calibrate", "--robot", "arm6-dh", "--keep-outliers"])
            .arg(&bad)
            .arg("--out")
            .arg(dir.path().join(format!("kept-{experiment}")))
            .assert()
            .code(2);
        let e = common::stderr(&kept);
        assert!(e.contains(&format!("line {line} (step {step},")), "{experiment}: {e}");
    }
}
