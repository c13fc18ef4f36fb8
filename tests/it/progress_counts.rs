//! The long library computations behind `study`, `budget`, `evaluate` and `diagnose` count
//! their work through `axiscal::progress::Progress` (what the command line's bar shows as
//! "n/N"): each announces its total once and reports exactly that many units, and the result
//! is the one of the uncounted call.

use crate::common;

use axiscal::harness::evaluation::{
    BudgetEffect, BudgetSettings, PaperScenario, gap_budget, gap_budget_with, run_paper_scenario,
    run_paper_scenario_with,
};
use axiscal::harness::studies::EfficiencyStudy;
use axiscal::measurement::MeasurementModel;
use axiscal::progress::Progress;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Records every `start` and counts the units since the last one.
#[derive(Default)]
struct Counter {
    starts: Mutex<Vec<(usize, String)>>,
    done: AtomicUsize,
}

impl Progress for Counter {
    fn start(&self, total: usize, unit: &str) {
        self.starts.lock().unwrap().push((total, unit.to_owned()));
        self.done.store(0, Ordering::SeqCst);
    }
    fn inc(&self) {
        self.done.fetch_add(1, Ordering::SeqCst);
    }
}

impl Counter {
    /// The one `(total, unit)` announced; panics unless exactly one and all of it was done.
    fn finished(&self) -> (usize, String) {
        let starts = self.starts.lock().unwrap();
        assert_eq!(starts.len(), 1, "{starts:?}");
        let (total, unit) = starts[0].clone();
        assert_eq!(self.done.load(Ordering::SeqCst), total, "{unit}");
        (total, unit)
    }
}

#[test]
fn study_counts_its_trials() {
    let study = EfficiencyStudy {
        trials: 3,
        seed: 7,
        noise_rms_3d_mm: 0.19,
        repeatability_jitter: false,
        model_repeatability: false,
    };
    let c = Counter::default();
    let counted = study.run_with(&c).unwrap();
    assert_eq!(c.finished(), (3, "trials".to_owned()));
    assert_eq!(counted, study.run().unwrap());
}

#[test]
fn evaluation_counts_its_test_poses_and_budget_its_effects() {
    let scenario = PaperScenario::paper(3, 9283, 4, MeasurementModel::paper_isotropic());
    let c = Counter::default();
    let counted = run_paper_scenario_with(&scenario, &c).unwrap().report;
    let (total, unit) = c.finished();
    assert_eq!((total, unit.as_str()), (counted.poses.len(), "test poses"));
    assert_eq!(counted, run_paper_scenario(&scenario).unwrap().report);

    let mut settings = BudgetSettings::paper(scenario, 1);
    settings.bisection_steps = 1;
    let effects = [BudgetEffect::ALL[0], BudgetEffect::ALL[1]];
    let c = Counter::default();
    let lines = gap_budget_with(&settings, &effects, &c).unwrap();
    assert_eq!(c.finished(), (2, "effects".to_owned()));
    // (As JSON: pooled medians are NaN, which `==` never equals.)
    let json = |l| serde_json::to_string(&l).unwrap();
    assert_eq!(json(lines), json(gap_budget(&settings, &effects).unwrap()));
}

#[test]
fn diagnosis_counts_its_noise_only_replicas() {
    let desc = axiscal::robot::RobotDescription::asea_irb6l();
    let set = common::axes_only_campaign(11);
    let options = axiscal::diagnosis::DiagnosisOptions {
        axis_replicas: 5,
        ..Default::default()
    };
    let c = Counter::default();
    let counted = axiscal::diagnosis::diagnose_axes_with(&set, &desc, &options, &c).unwrap();
    assert_eq!(c.finished(), (5, "noise-only replicas".to_owned()));
    assert_eq!(
        counted,
        axiscal::diagnosis::diagnose_axes(&set, &desc, &options).unwrap()
    );
}
