//! `summary.md`: a short human summary.

use crate::harness::scenario::resolve::ResolvedScenario;
use crate::harness::scenario::summary::Summary;
use std::fmt::Write;

/// The markdown summary: scenario, one statistics table per case, the verdicts.
pub fn render(scenario: &ResolvedScenario, summary: &Summary) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Scenario {}\n", crate::markdown::code(&scenario.name));
    if !scenario.description.is_empty() {
        let _ = writeln!(s, "{}\n", scenario.description);
    }
    let _ = writeln!(
        s,
        "{} trial(s) per case, seed {}, simulator {:?}, {} case(s).\n",
        scenario.trials,
        scenario.seed,
        scenario.sim,
        scenario.cases.len()
    );
    if summary.partial {
        let done: usize = summary.cases.iter().map(|c| c.trials).sum();
        let _ = writeln!(
            s,
            "**PARTIAL RUN: interrupted after {done} of {} trials.** The statistics and verdicts below are over \
             the finished trials only; `axiscal run --resume` completes the run.\n",
            scenario.units()
        );
    }
    for c in &summary.cases {
        let _ = writeln!(
            s,
            "## Case {} ({} trials, {} failed)\n",
            crate::markdown::code(&c.case),
            c.trials,
            c.failed
        );
        let _ = writeln!(s, "| metric | mean | median | p95 | max |\n|---|---:|---:|---:|---:|");
        for m in &c.metrics {
            let st = &m.stats;
            let _ = writeln!(
                s,
                "| {} | {:.4} | {:.4} | {:.4} | {:.4} |",
                m.metric, st.mean, st.median, st.p95, st.max
            );
        }
        s.push('\n');
    }
    let _ = writeln!(s, "## Thresholds\n");
    if summary.verdicts.is_empty() {
        let _ = writeln!(s, "none");
    }
    for v in &summary.verdicts {
        let _ = writeln!(s, "- {v}");
    }
    let _ = writeln!(
        s,
        "\n**{}**",
        if summary.all_hold {
            "All thresholds hold."
        } else if summary.partial {
            "Partial run: not judged complete."
        } else {
            "Some thresholds FAIL."
        }
    );
    s
}
