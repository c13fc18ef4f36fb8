//! Plots like the paper's figs. 9 and 10 (error per test pose, nominal vs calibrated) and a
//! histogram of the calibrated position errors, each as PNG and SVG (plotters).
//!
//! PNG text is rendered with the DejaVu Sans font shipped in `assets/fonts/` (license beside
//! it) through plotters' `ab_glyph` feature, so no system font is needed; SVG text names the
//! `sans-serif` family and is rendered by the viewer.

use super::paper::PaperReport;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

use crate::plotting::DrawFn;
pub use crate::plotting::PlotError;

/// One series of per-pose values.
struct Series<'a> {
    label: &'a str,
    color: RGBColor,
    values: Vec<f64>,
}

fn per_pose_chart<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    y_desc: &str,
    series: &[Series],
) -> Result<(), String> {
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let n = series.iter().map(|s| s.values.len()).max().unwrap_or(0);
    let all = series
        .iter()
        .flat_map(|s| s.values.iter().copied())
        .filter(|v| *v > 0.0);
    let (lo, hi) = all.fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    let (lo, hi) = if lo.is_finite() {
        (lo / 2.0, hi * 2.0)
    } else {
        (1e-3, 1.0)
    };
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(0..n.max(1), (lo..hi).log_scale())
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc("test pose")
        .y_desc(y_desc)
        .draw()
        .map_err(|e| e.to_string())?;
    for s in series {
        let color = s.color;
        chart
            .draw_series(PointSeries::of_element(
                s.values.iter().enumerate().map(|(i, v)| (i, *v)),
                3,
                color.filled(),
                &|c, size, style| EmptyElement::at(c) + Circle::new((0, 0), size, style),
            ))
            .map_err(|e| e.to_string())?
            .label(s.label)
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, color.filled()));
    }
    crate::plotting::draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    root.present().map_err(|e| e.to_string())
}

fn histogram<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    calibrated: &[f64],
    floor: &[f64],
) -> Result<(), String> {
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let hi = calibrated.iter().chain(floor).copied().fold(0.0f64, f64::max).max(1e-6) * 1.05;
    let bins = 20;
    let width = hi / bins as f64;
    let count = |v: &[f64]| {
        let mut c = vec![0u32; bins];
        for x in v {
            c[((x / width) as usize).min(bins - 1)] += 1;
        }
        c
    };
    let (cc, cf) = (count(calibrated), count(floor));
    let top = cc.iter().chain(&cf).copied().max().unwrap_or(1) + 1;
    let mut chart = ChartBuilder::on(&root)
        .caption("Calibrated position error (all test poses)", ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(0.0..hi, 0u32..top)
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc("position error [mm]")
        .y_desc("poses")
        .draw()
        .map_err(|e| e.to_string())?;
    let bars = |c: &[u32], color: RGBColor, filled: bool| {
        let style = if filled {
            color.mix(0.6).filled()
        } else {
            color.stroke_width(2)
        };
        c.iter()
            .enumerate()
            .map(|(i, &n)| Rectangle::new([(i as f64 * width, 0), ((i + 1) as f64 * width, n)], style))
            .collect::<Vec<_>>()
    };
    chart
        .draw_series(bars(&cc, BLUE, true))
        .map_err(|e| e.to_string())?
        .label("calibrated + compensated")
        .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 15, y + 5)], BLUE.mix(0.6).filled()));
    chart
        .draw_series(bars(&cf, RED, false))
        .map_err(|e| e.to_string())?
        .label("noise floor")
        .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 15, y + 5)], RED.stroke_width(2)));
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| e.to_string())?;
    root.present().map_err(|e| e.to_string())
}

/// The files [`write_plots`] writes into its directory.
pub const PLOT_FILES: [&str; 6] = [
    "fig9_position.png",
    "fig9_position.svg",
    "fig10_orientation.png",
    "fig10_orientation.svg",
    "histogram_position.png",
    "histogram_position.svg",
];

/// Writes figs. 9 and 10 and the position histogram ([`PLOT_FILES`]) into `dir`; returns the
/// files written.
pub fn write_plots(report: &PaperReport, dir: &Path) -> Result<Vec<PathBuf>, PlotError> {
    let pick = |f: fn(&super::ToolError) -> f64, which: usize| -> Vec<f64> {
        report
            .poses
            .iter()
            .map(|p| {
                let e = match which {
                    0 => Some(&p.uncalibrated),
                    1 => p.calibrated.as_ref(),
                    _ => p.floor.as_ref(),
                };
                e.map_or(f64::NAN, f)
            })
            .collect()
    };
    let series = |f: fn(&super::ToolError) -> f64| {
        vec![
            Series {
                label: "nominal commands",
                color: RED,
                values: pick(f, 0),
            },
            Series {
                label: "calibrated + compensated",
                color: BLUE,
                values: pick(f, 1),
            },
            Series {
                label: "noise floor",
                color: RGBColor(0, 150, 0),
                values: pick(f, 2),
            },
        ]
    };
    let position = series(|e| e.position_mm);
    let orientation = series(|e| e.orientation_rad);
    let jobs: [(&str, &DrawFn); 3] = [
        ("fig9_position", &|p: &Path, png: bool| {
            let t = "Fig. 9: tool position error per test pose";
            let y = "position error [mm]";
            if png {
                per_pose_chart(BitMapBackend::new(p, (1000, 560)).into_drawing_area(), t, y, &position)
            } else {
                per_pose_chart(SVGBackend::new(p, (1000, 560)).into_drawing_area(), t, y, &position)
            }
        }),
        ("fig10_orientation", &|p: &Path, png: bool| {
            let t = "Fig. 10: tool orientation error per test pose";
            let y = "orientation error [rad]";
            if png {
                per_pose_chart(
                    BitMapBackend::new(p, (1000, 560)).into_drawing_area(),
                    t,
                    y,
                    &orientation,
                )
            } else {
                per_pose_chart(SVGBackend::new(p, (1000, 560)).into_drawing_area(), t, y, &orientation)
            }
        }),
        ("histogram_position", &|p: &Path, png: bool| {
            let keep = |v: &[f64]| v.iter().copied().filter(|x| x.is_finite()).collect::<Vec<_>>();
            let (c, f) = (keep(&position[1].values), keep(&position[2].values));
            if png {
                histogram(BitMapBackend::new(p, (900, 520)).into_drawing_area(), &c, &f)
            } else {
                histogram(SVGBackend::new(p, (900, 520)).into_drawing_area(), &c, &f)
            }
        }),
    ];
    crate::plotting::write_png_and_svg(dir, &jobs)
}
