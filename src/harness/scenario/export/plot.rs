//! Histogram of the main metric, one panel per case, as SVG (plotters' SVG backend writes
//! text as `<text>` elements, so no font files are needed). Every panel has the same value
//! axis, so cases compare by eye, and each threshold on the metric is drawn with its legend.

use super::ExportError;
use crate::harness::scenario::metrics::TrialRecord;
use crate::harness::scenario::resolve::ResolvedScenario;
use crate::harness::scenario::threshold::Threshold;
use crate::plotting::DrawError;
use plotters::prelude::*;
use std::path::Path;

/// The bin width for trials spread over `[min, max]`, `n` per case: Sturges' rule
/// `ceil(log2 n) + 1` bins (at least 5) over the trials' own spread, so an axis stretched out
/// to reach a threshold does not coarsen them; `axis_width` over as many when the trials do not
/// spread.
fn bin_width((min, max): (f64, f64), n: usize, axis_width: f64) -> f64 {
    let bins = ((n.max(1) as f64).log2().ceil() as usize + 1).max(5) as f64;
    if max > min {
        (max - min) / bins
    } else {
        axis_width / bins
    }
}

/// The colours thresholds are drawn in, one per threshold on the metric (cycled).
const THRESHOLD_COLORS: [RGBColor; 4] = [RED, RGBColor(230, 120, 0), MAGENTA, BLACK];

/// Writes `path`: for each case, the histogram of metric `metric` (column `index`).
pub fn histogram_svg(
    path: &Path,
    scenario: &ResolvedScenario,
    metric: &str,
    index: usize,
    records: &[TrialRecord],
) -> Result<(), ExportError> {
    draw_histograms(path, scenario, metric, index, records).map_err(|cause| ExportError::Plot {
        path: path.to_owned(),
        cause,
    })
}

fn draw_histograms(
    path: &Path,
    scenario: &ResolvedScenario,
    metric: &str,
    index: usize,
    records: &[TrialRecord],
) -> Result<(), DrawError> {
    let panels = scenario.cases.len().max(1);
    crate::plotting::register_font();
    let root = SVGBackend::new(path, (720, 260 * panels as u32)).into_drawing_area();
    root.fill(&WHITE)?;
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
    let trials: Vec<f64> = (0..scenario.cases.len()).flat_map(values_of).collect();
    let spread = trials
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    let (lo, hi) = if everything.is_empty() {
        (0.0, 1.0)
    } else if hi > lo {
        (lo - 0.02 * (hi - lo), hi + 0.02 * (hi - lo))
    } else {
        (lo - 0.5, hi + 0.5)
    };
    let most = (0..scenario.cases.len()).map(|c| values_of(c).len()).max().unwrap_or(0);
    let width = bin_width(spread, most, hi - lo);
    // At most 1000 bins, whatever a threshold far from the trials stretches the axis to.
    let nb = (((hi - lo) / width).ceil() as usize).clamp(1, 1000);
    let width = (hi - lo) / nb as f64;
    for (c, (case, area)) in scenario.cases.iter().zip(&areas).enumerate() {
        let values = values_of(c);
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
            .build_cartesian_2d(lo..hi, 0usize..top + 1)?;
        chart.configure_mesh().x_desc(metric).y_desc("trials").draw()?;
        chart
            .draw_series(counts.iter().enumerate().map(|(i, &n)| {
                let x0 = lo + i as f64 * width;
                Rectangle::new([(x0, 0), (x0 + width, n)], BLUE.mix(0.6).filled())
            }))?
            .label(format!("trials ({})", values.len()))
            .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 18, y + 5)], BLUE.mix(0.6).filled()));
        let applies = |t: &&&Threshold| t.case.as_ref().is_none_or(|n| *n == case.name);
        for (k, t) in thresholds.iter().enumerate().filter(|(_, t)| applies(t)) {
            let color = THRESHOLD_COLORS[k % THRESHOLD_COLORS.len()];
            chart
                .draw_series(LineSeries::new(
                    [(t.value, 0), (t.value, top + 1)],
                    color.stroke_width(2),
                ))?
                .label(format!("threshold {}", t.describe()))
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], color.stroke_width(2)));
        }
        crate::plotting::draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    }
    Ok(root.present()?)
}
