//! The plots are for readers (checked on their SVG text): every chart has its axis titles and a
//! legend naming each colour and line, and no two bars share a label.

use crate::common::{axiscal, simulate_analytic};
use std::path::Path;

/// The text elements of an SVG file, unescaped enough to compare (`&amp;` etc. kept).
fn texts(svg: &Path) -> Vec<String> {
    let body = std::fs::read_to_string(svg).unwrap_or_else(|e| panic!("{}: {e}", svg.display()));
    body.split("<text")
        .skip(1)
        .filter_map(|t| {
            t.split_once('>')
                .and_then(|(_, rest)| rest.split_once("</text>"))
                .map(|(s, _)| s.to_owned())
        })
        .collect()
}

fn has(texts: &[String], needle: &str, svg: &str) {
    assert!(
        texts.iter().any(|t| t.contains(needle)),
        "{svg}: no text with {needle:?} in {texts:?}"
    );
}

#[test]
fn every_plot_has_axis_titles_a_legend_and_unique_labels() {
    let dir = tempfile::tempdir().unwrap();
    simulate_analytic(dir.path(), 30, 12, "data.csv");
    for args in [
        &["calibrate", "data.csv", "--out", "cal"][..],
        &["diagnose", "data.csv", "--out", "diag"][..],
    ] {
        axiscal().current_dir(dir.path()).args(args).assert().success();
    }
    let map = texts(&dir.path().join("cal/tool_sigma_map.svg"));
    for needle in [
        "reach from the base z axis [mm]",
        "height above the base [mm]",
        "white: no pose",
        "inside the calibrated spans (1-sigma RMS",
        "mm",
    ] {
        has(&map, needle, "tool_sigma_map.svg");
    }
    let where_ = texts(&dir.path().join("diag/where.svg"));
    for needle in [
        "excess ratio",
        "noise only (ratio 1)",
        "the gap test flags above",
        "an axis experiment",
    ] {
        has(&where_, needle, "where.svg");
    }
    let candidates = texts(&dir.path().join("diag/candidates.svg"));
    for needle in [
        "held-out position RMS [mm]",
        "baseline (refit), held out",
        "noise only:",
    ] {
        has(&candidates, needle, "candidates.svg");
    }
    let diagnosis: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("diag/diagnosis.json")).unwrap()).unwrap();
    let mut labels: Vec<&String> = candidates.iter().filter(|t| t.contains(" (")).collect();
    let shown = labels.len();
    labels.sort();
    labels.dedup();
    assert_eq!(labels.len(), shown, "repeated candidate labels: {labels:?}");
    assert!(
        shown >= diagnosis["candidates"].as_array().unwrap().len().min(20) - 2,
        "{shown} labels"
    );
}

/// The Monte-Carlo histogram: a panel per case, each with the thresholds on its metric drawn
/// and named in its legend.
#[test]
fn the_monte_carlo_histogram_draws_its_thresholds() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = dir.path().join("grades.toml");
    std::fs::write(
        &scenario,
        "trials = 3\nseed = 3\nmain_metric = \"cal_pos_rms_mm\"\n\n[sweep]\nnet_radial_rms_mm = [0.05, 0.5]\n\n\
         [[thresholds]]\nmetric = \"cal_pos_rms_mm\"\nstat = \"p95\"\nop = \"<=\"\nvalue = 5.0\n",
    )
    .unwrap();
    let ran = axiscal()
        .current_dir(dir.path())
        .args(["run", "grades.toml", "--out", "run"])
        .output()
        .unwrap();
    // 0, or 1 when the threshold fails: the run completed either way.
    assert!(matches!(ran.status.code(), Some(0 | 1)), "{ran:?}");
    let hist = texts(&dir.path().join("run/hist-cal_pos_rms_mm.svg"));
    let count = |needle: &str| hist.iter().filter(|t| t.contains(needle)).count();
    assert_eq!(count("threshold p95(cal_pos_rms_mm) &lt;= 5"), 2, "{hist:?}");
    assert_eq!(count("trials (3)"), 2, "{hist:?}");
}

/// Figs. 9 and 10 separate the poses inside the calibrated spans from the workspace poses: each
/// region is named with its pose count, and each series' legend gives its RMS per region, equal
/// (to the printed digits) to the report's region summaries, a separately computed path.
#[test]
fn figs_9_and_10_name_the_regions_and_their_rms() {
    let dir = tempfile::tempdir().unwrap();
    axiscal()
        .current_dir(dir.path())
        .args(["evaluate", "--seed", "2", "--random-poses", "5", "--out", "ev"])
        .assert()
        .success();
    let report: axiscal::harness::evaluation::PaperReport =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("ev/evaluation.json")).unwrap()).unwrap();
    let fig9 = texts(&dir.path().join("ev/fig9_position.svg"));
    let fig10 = texts(&dir.path().join("ev/fig10_orientation.svg"));
    for (texts, name, y) in [
        (&fig9, "fig9", "position error [mm]"),
        (&fig10, "fig10", "orientation error [mrad]"),
    ] {
        has(texts, y, name);
        has(texts, "test pose", name);
    }
    for r in &report.regions {
        let label = match r.region {
            axiscal::harness::evaluation::Region::InsideSpans => "inside the calibrated spans",
            axiscal::harness::evaluation::Region::Workspace => "workspace",
        };
        let count = report.poses.iter().filter(|p| p.region == r.region).count();
        has(&fig9, &format!("{label} ({count} poses)"), "fig9");
        for (series, stats) in [
            ("nominal commands", r.position_mm.uncalibrated),
            ("noise floor", r.position_mm.floor),
            ("calibrated + compensated", r.position_mm.calibrated),
        ] {
            let legend = fig9.iter().find(|t| t.trim().starts_with(series)).expect(series);
            assert!(
                legend.contains(&format!("{:.3} {label}", stats.rms)),
                "{legend} vs {stats:?}"
            );
        }
        let legend = fig10.iter().find(|t| t.trim().starts_with("calibrated")).unwrap();
        let mrad = r.orientation_rad.calibrated.rms * 1e3;
        assert!(legend.contains(&format!("{mrad:.3} {label}")), "{legend} vs {mrad}");
    }
}
