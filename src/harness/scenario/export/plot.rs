//! Histogram of the main metric, one panel per case, as SVG (plotters' SVG backend writes
//! text as `<text>` elements, so no font files are needed). Every panel has the same value
//! axis, so cases compare by eye, and each threshold on the metric is drawn with its legend.

use super::ExportError;
use crate::harness::scenario::metrics::TrialRecord;
use crate::harness::scenario::resolve::ResolvedScenario;
use crate::harness::scenario::threshold::Threshold;
use plotters::prelude::*;
use std::path::Path;

/// Number of bins over the common value axis of `panels` cases of `n` trials each: Sturges'
/// rule `ceil(log2 n) + 1` per panel's share of the axis, at least 5, at most 60.
fn bins(n: usize, panels: usize) -> usize {
    (((n.max(1) as f64).log2().ceil() as usize + 1) * panels.max(1)).clamp(5, 60)
}

/// Writes `path`: for each case, the histogram of metric `metric` (column `index`).
pub fn histogram_svg(
    path: &Path,
    scenario: &ResolvedScenario,
    metric: &str,
    index: usize,
    records: &[TrialRecord],
) -> Result<(), ExportError> {
    let err = |e: String| ExportError::Plot {
        path: path.to_owned(),
        message: e,
    };
    let panels = scenario.cases.len().max(1);
    crate::plotting::register_font();
    let root = SVGBackend::new(path, (720, 260 * panels as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
    let areas = root.split_evenly((panels, 1));
    let values_of = |c: usize| -> Vec<f64> {
        records
            .iter()
            .filter(|r| r.case == c && r.succeeded())
            .map(|r| r.values[index])
            .filter(|v| v.is_finite())
            .collect()
    };
    let thresholds: Vec<_> = scenario.thresholds.iter().filter(|t| t.metric == metric).collect();
    // One value axis for every panel: the trials of every case and the thresholds.
    let everything: Vec<f64> = (0..scenario.cases.len())
        .flat_map(values_of)
        .chain(thresholds.iter().map(|t| t.value))
        .collect();
    let lo = everything.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = everything.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (lo, hi) = if everything.is_empty() {
        (0.0, 1.0)
    } else if hi > lo {
        (lo - 0.02 * (hi - lo), hi + 0.02 * (hi - lo))
    } else {
        (lo - 0.5, hi + 0.5)
    };
    for (c, (case, area)) in scenario.cases.iter().zip(&areas).enumerate() {
        let values = values_of(c);
        let nb = bins(values.len(), panels);
        let width = (hi - lo) / nb as f64;
        let mut counts = vec![0usize; nb];
        for v in &values {
            counts[(((v - lo) / width) as usize).min(nb - 1)] += 1;
        }
        let top = counts.iter().copied().max().unwrap_or(0).max(1);
        let mut chart = ChartBuilder::on(area)
            .caption(format!("{metric} — case {}", case.name), ("sans-serif", 16))
            .margin(10)
            .x_label_area_size(30)
            .y_label_area_size(40)
            .build_cartesian_2d(lo..hi, 0usize..top + 1)
            .map_err(|e| err(e.to_string()))?;
        chart
            .configure_mesh()
            .x_desc(metric)
            .y_desc("trials")
            .draw()
            .map_err(|e| err(e.to_string()))?;
        chart
            .draw_series(counts.iter().enumerate().map(|(i, &n)| {
                let x0 = lo + i as f64 * width;
                Rectangle::new([(x0, 0), (x0 + width, n)], BLUE.mix(0.6).filled())
            }))
            .map_err(|e| err(e.to_string()))?
            .label(format!("trials ({})", values.len()))
            .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 18, y + 5)], BLUE.mix(0.6).filled()));
        let applies = |t: &&&Threshold| t.case.as_ref().is_none_or(|n| *n == case.name);
        for t in thresholds.iter().filter(applies) {
            chart
                .draw_series(LineSeries::new([(t.value, 0), (t.value, top + 1)], RED.stroke_width(2)))
                .map_err(|e| err(e.to_string()))?
                .label(format!("threshold {}", t.describe()))
                .legend(|(x, y)| PathElement::new([(x, y), (x + 18, y)], RED.stroke_width(2)));
        }
        crate::plotting::draw_legend(&mut chart, SeriesLabelPosition::UpperRight).map_err(err)?;
    }
    root.present().map_err(|e| err(e.to_string()))
}
