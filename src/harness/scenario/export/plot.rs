//! Histogram of the main metric, one panel per case, as SVG (plotters' SVG backend writes
//! text as `<text>` elements, so no font files are needed).

use super::ExportError;
use crate::harness::scenario::metrics::TrialRecord;
use crate::harness::scenario::resolve::ResolvedScenario;
use plotters::prelude::*;
use std::path::Path;

/// Number of bins: Sturges' rule `ceil(log2 n) + 1`, at least 5.
fn bins(n: usize) -> usize {
    ((n.max(1) as f64).log2().ceil() as usize + 1).max(5)
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
    for (c, (case, area)) in scenario.cases.iter().zip(&areas).enumerate() {
        let values: Vec<f64> = records
            .iter()
            .filter(|r| r.case == c && r.succeeded())
            .map(|r| r.values[index])
            .filter(|v| v.is_finite())
            .collect();
        let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let (lo, hi) = if values.is_empty() {
            (0.0, 1.0)
        } else if hi > lo {
            (lo, hi)
        } else {
            (lo - 0.5, hi + 0.5)
        };
        let nb = bins(values.len());
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
            .map_err(|e| err(e.to_string()))?;
    }
    root.present().map_err(|e| err(e.to_string()))
}
