//! Monte-Carlo harness at the library level: thread-count determinism, shipped scenarios
//! resolve, the resolved dump round-trips.

use axiscal::harness::scenario::export::csv::write_trials;
use axiscal::harness::scenario::{CampaignTrial, ISO_METRICS, Overrides, ResolvedScenario, SimMode, Trial, run_units};
use std::path::Path;

fn smoke(trials: usize) -> ResolvedScenario {
    ResolvedScenario::from_file(
        Path::new("scenarios/ci-smoke.toml"),
        Overrides {
            trials: Some(trials),
            seed: None,
        },
    )
    .unwrap()
}

fn trials_csv_with_threads(scenario: &ResolvedScenario, threads: usize) -> Vec<u8> {
    let trial = CampaignTrial::new(scenario);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    let records = pool.install(|| run_units(scenario, &trial, 0..scenario.units(), &|_| {}));
    assert!(records.iter().all(|r| r.succeeded()), "{records:?}");
    let mut out = Vec::new();
    write_trials(&mut out, scenario, &trial.metric_names(), &records).unwrap();
    out
}

#[test]
fn trials_are_bit_identical_for_one_and_two_threads() {
    let scenario = smoke(6);
    let one = trials_csv_with_threads(&scenario, 1);
    let two = trials_csv_with_threads(&scenario, 2);
    assert_eq!(String::from_utf8(one).unwrap(), String::from_utf8(two).unwrap());
}

#[test]
fn shipped_scenarios_resolve_and_their_dump_round_trips() {
    for name in [
        "ci-smoke",
        "paper",
        "perturbed-fleet",
        "noise-sweep",
        "span-study",
        "compliance",
        "plan-optimize",
        "iso9283",
        "scara-rrpr",
        "table-prpp",
    ] {
        let path = format!("scenarios/{name}.toml");
        let s = ResolvedScenario::from_file(Path::new(&path), Overrides::default())
            .unwrap_or_else(|e| panic!("{path}: {e}"));
        assert_eq!(s.name, name);
        let text = s.to_toml().unwrap();
        let back: ResolvedScenario = toml::from_str(&text).unwrap_or_else(|e| panic!("{path} dump: {e}"));
        assert_eq!(back, s, "{path}: resolved dump does not round-trip");
        if s.sim == SimMode::Analytic {
            let trial = CampaignTrial::new(&s);
            s.check_metrics(&trial.metric_names(), Path::new(&path)).unwrap();
        }
    }
    let sweep = ResolvedScenario::from_file(Path::new("scenarios/noise-sweep.toml"), Overrides::default()).unwrap();
    assert_eq!(sweep.cases.len(), 5);
    assert_eq!(sweep.cases[0].name, "net_radial_rms_mm=0.05");
}

#[test]
fn a_fleet_draws_a_different_robot_per_trial() {
    let s = ResolvedScenario::from_file(
        Path::new("scenarios/perturbed-fleet.toml"),
        Overrides {
            trials: Some(3),
            seed: None,
        },
    )
    .unwrap();
    let trial = CampaignTrial::new(&s);
    let records = run_units(&s, &trial, 0..3, &|_| {});
    assert_ne!(records[0].values[0].to_bits(), records[1].values[0].to_bits());
    assert_eq!(records.iter().map(|r| r.trial).collect::<Vec<_>>(), [0, 1, 2]);
}

#[test]
fn sweep_and_plan_errors_name_their_key() {
    let resolve = |text: &str| {
        let file: axiscal::harness::scenario::ScenarioFile = toml::from_str(text).unwrap();
        ResolvedScenario::resolve(file, Path::new("scenarios/x.toml"), Overrides::default())
            .unwrap_err()
            .to_string()
    };
    let both = resolve("trials = 1\n[sweep]\nspan_scale = [1.0]\nnet_radial_rms_mm = [0.1]\n");
    assert!(
        both.contains("scenarios/x.toml") && both.contains("key `sweep`"),
        "{both}"
    );
    let wide = resolve("trials = 1\n[sweep]\nspan_scale = [1.0, 3.0]\n");
    assert!(
        wide.contains("key `sweep.span_scale`") && wide.contains("limits"),
        "{wide}"
    );
    let short = resolve("trials = 1\n[sweep]\nspans = [[10.0]]\n");
    assert!(short.contains("key `sweep.spans`"), "{short}");
    // A stiffness list of the wrong length names the key.
    let effects = resolve("trials = 1\n[effects.compliance]\nstiffness_nm_per_rad = [1e5, 1e5]\n");
    assert!(effects.contains("key `effects`"), "{effects}");
    let case = resolve(
        "trials = 1\n[[thresholds]]\nmetric = \"occluded\"\nstat = \"max\"\nop = \"<=\"\nvalue = 0\ncase = \"nope\"\n",
    );
    assert!(case.contains("key `thresholds[0].case`"), "{case}");
}

/// A scenario with `[iso9283]` (the table robot, isotropic noise, 2 trials, a 100 mm cube)
/// adds the ISO metrics after the campaign's, bit-identical on one and two threads; each ratio
/// is the measured figure over the predicted one; a section out of range names its key.
#[test]
fn an_iso_section_adds_measured_and_predicted_figures() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("iso.toml");
    let robot = std::fs::canonicalize("scenarios/robots/table-prpp.toml").unwrap();
    let text = format!(
        "trials = 2\nseed = 4\nrobot = {:?}\n[truth]\nkind = \"perturbed\"\n[truth.perturbation]\ntransducer_offset_deg = {{ normal = {{ sigma = 0.1 }} }}\n[measurement]\ninstrument = \"isotropic\"\nnet_radial_rms_mm = 0.1\n[iso9283]\ncycles = 5\nedge_mm = 100.0\nprediction_trials = 4\n",
        robot.display().to_string()
    );
    std::fs::write(&path, &text).unwrap();
    let s = ResolvedScenario::from_file(&path, Overrides::default()).unwrap();
    let trial = CampaignTrial::new(&s);
    let names = trial.metric_names();
    assert_eq!(names[names.len() - ISO_METRICS.len()..], ISO_METRICS.map(String::from));
    let one = trials_csv_with_threads(&s, 1);
    assert_eq!(one, trials_csv_with_threads(&s, 2));
    let records = run_units(&s, &trial, 0..s.units(), &|_| {});
    let at = |name: &str| names.iter().position(|n| n == name).unwrap();
    for r in &records {
        assert_eq!(r.values[at("iso_edge_mm")], 100.0);
        let (ap, predicted) = (r.values[at("iso_ap_p_mm")], r.values[at("iso_ap_p_predicted_mm")]);
        assert!(ap > 0.0 && predicted > 0.0, "{r:?}");
        assert_eq!(r.values[at("iso_ap_p_ratio")], ap / predicted);
    }
    std::fs::write(&path, text.replace("cycles = 5", "cycles = 1")).unwrap();
    let err = ResolvedScenario::from_file(&path, Overrides::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("iso9283.cycles"), "{err}");
    // A cube beyond reach is refused when the file is read, with the largest edge that is
    // reached, not failed in every trial after its calibration.
    std::fs::write(&path, text.replace("edge_mm = 100.0", "edge_mm = 3000.0")).unwrap();
    let err = ResolvedScenario::from_file(&path, Overrides::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("iso9283.edge_mm") && err.contains("3000 mm cube"), "{err}");
    assert!(
        err.contains("plan an edge of") && err.contains("(iso9283.edge_mm)"),
        "{err}"
    );
}
