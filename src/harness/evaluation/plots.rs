//! Plots like the paper's figs. 9 and 10 (error per test pose, nominal vs calibrated) and a
//! histogram of the calibrated position errors, each as PNG and SVG (plotters).
//!
//! PNG text is rendered with the DejaVu Sans font shipped in `assets/fonts/` (license beside
//! it) through plotters' `ab_glyph` feature, so no system font is needed; SVG text names the
//! `sans-serif` family and is rendered by the viewer.

use super::paper::PaperReport;
use super::poses::Region;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

pub use crate::plotting::PlotError;
use crate::plotting::{DrawError, DrawFn};

/// How a series' points are drawn.
#[derive(Clone, Copy)]
enum Marker {
    /// A filled dot.
    Dot,
    /// A cross, which leaves a dot drawn at the same place visible.
    Cross,
}

/// One series of per-pose values.
struct Series<'a> {
    label: &'a str,
    color: RGBColor,
    marker: Marker,
    values: Vec<f64>,
}

/// A run of consecutive poses of one region (the poses come grouped by region).
struct RegionBand {
    label: &'static str,
    poses: std::ops::Range<usize>,
}

/// The regions of `report`'s poses, in order: inside the calibrated spans, then the workspace.
fn region_bands(report: &PaperReport) -> Vec<RegionBand> {
    let mut bands: Vec<RegionBand> = Vec::new();
    for (i, p) in report.poses.iter().enumerate() {
        let label = match p.region {
            Region::InsideSpans => "inside the calibrated spans",
            Region::Workspace => "workspace",
        };
        match bands.last_mut() {
            Some(b) if b.label == label => b.poses.end = i + 1,
            _ => bands.push(RegionBand { label, poses: i..i + 1 }),
        }
    }
    bands
}

/// `series`' legend text: its label and its RMS over each band, e.g. `calibrated + compensated:
/// RMS 0.21 inside the calibrated spans, 1.03 workspace [mm]`.
fn legend_text(s: &Series, bands: &[RegionBand], unit: &str, precision: usize) -> String {
    let parts: Vec<String> = bands
        .iter()
        .map(|b| {
            let v: Vec<f64> = s.values[b.poses.clone()]
                .iter()
                .copied()
                .filter(|v| v.is_finite())
                .collect();
            let rms = (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt();
            format!("{rms:.precision$} {}", b.label)
        })
        .collect();
    format!("{}: RMS {} [{unit}]", s.label, parts.join(", "))
}

/// Figs. 9 and 10: one column per test pose, the region bands shaded and named, the calibrated
/// dots drawn last so neither other series hides them.
fn per_pose_chart<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    (y_desc, unit, precision): (&str, &str, usize),
    series: &[Series],
    bands: &[RegionBand],
) -> Result<(), DrawError> {
    root.fill(&WHITE)?;
    let n = series.iter().map(|s| s.values.len()).max().unwrap_or(0);
    let all = series
        .iter()
        .flat_map(|s| s.values.iter().copied())
        .filter(|v| *v > 0.0);
    let (lo, hi) = all.fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    let (lo, hi) = if lo.is_finite() {
        (lo / 2.0, hi * 8.0)
    } else {
        (1e-3, 1.0)
    };
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(-0.5..(n.max(1) as f64 - 0.5), (lo..hi).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("test pose")
        .y_desc(y_desc)
        .x_label_formatter(&|x| format!("{x:.0}"))
        .draw()?;
    for (k, b) in bands.iter().enumerate() {
        let (x0, x1) = (b.poses.start as f64 - 0.5, b.poses.end as f64 - 0.5);
        let shade = if k % 2 == 0 { RGBColor(235, 235, 235) } else { WHITE };
        chart.draw_series([Rectangle::new([(x0, lo), (x1, hi)], shade.filled())])?;
        let text = format!("{} ({} poses)", b.label, b.poses.len());
        chart.draw_series([Text::new(text, (x0 + 0.3, hi / 1.25), ("sans-serif", 15))])?;
    }
    for s in series {
        let (color, marker) = (s.color, s.marker);
        let points = s.values.iter().enumerate().map(|(i, v)| (i as f64, *v));
        let drawn = match marker {
            Marker::Dot => chart.draw_series(points.map(|c| Circle::new(c, 3, color.filled()))),
            Marker::Cross => chart.draw_series(points.map(|c| Cross::new(c, 4, color.stroke_width(2)))),
        }?;
        drawn
            .label(legend_text(s, bands, unit, precision))
            .legend(move |(x, y)| match marker {
                Marker::Dot => Circle::new((x + 10, y), 4, color.filled()).into_dyn(),
                Marker::Cross => Cross::new((x + 10, y), 4, color.stroke_width(2)).into_dyn(),
            });
    }
    crate::plotting::draw_legend(&mut chart, SeriesLabelPosition::LowerRight)?;
    Ok(root.present()?)
}

fn histogram<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    calibrated: &[f64],
    floor: &[f64],
) -> Result<(), DrawError> {
    root.fill(&WHITE)?;
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
        .build_cartesian_2d(0.0..hi, 0u32..top)?;
    chart
        .configure_mesh()
        .x_desc("position error [mm]")
        .y_desc("poses")
        .draw()?;
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
        .draw_series(bars(&cc, BLUE, true))?
        .label("calibrated + compensated")
        .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 15, y + 5)], BLUE.mix(0.6).filled()));
    chart
        .draw_series(bars(&cf, RED, false))?
        .label("noise floor")
        .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 15, y + 5)], RED.stroke_width(2)));
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    Ok(root.present()?)
}

/// The size of figs. 9 and 10 \[px\].
const SIZE: (u32, u32) = (1100, 600);

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
                marker: Marker::Dot,
                values: pick(f, 0),
            },
            Series {
                label: "noise floor",
                color: RGBColor(0, 150, 0),
                marker: Marker::Cross,
                values: pick(f, 2),
            },
            Series {
                label: "calibrated + compensated",
                color: BLUE,
                marker: Marker::Dot,
                values: pick(f, 1),
            },
        ]
    };
    let bands = region_bands(report);
    let position = series(|e| e.position_mm);
    let orientation = series(|e| e.orientation_rad * 1e3);
    let jobs: [(&str, &DrawFn); 3] = [
        ("fig9_position", &|p: &Path, png: bool| {
            let t = "Fig. 9: tool position error per test pose";
            let y = ("position error [mm]", "mm", 3);
            if png {
                per_pose_chart(BitMapBackend::new(p, SIZE).into_drawing_area(), t, y, &position, &bands)
            } else {
                per_pose_chart(SVGBackend::new(p, SIZE).into_drawing_area(), t, y, &position, &bands)
            }
        }),
        ("fig10_orientation", &|p: &Path, png: bool| {
            let t = "Fig. 10: tool orientation error per test pose";
            let y = ("orientation error [mrad]", "mrad", 3);
            if png {
                per_pose_chart(
                    BitMapBackend::new(p, SIZE).into_drawing_area(),
                    t,
                    y,
                    &orientation,
                    &bands,
                )
            } else {
                per_pose_chart(SVGBackend::new(p, SIZE).into_drawing_area(), t, y, &orientation, &bands)
            }
        }),
        ("histogram_position", &|p: &Path, png: bool| {
            let keep = |v: &[f64]| v.iter().copied().filter(|x| x.is_finite()).collect::<Vec<_>>();
            let (c, f) = (keep(&position[2].values), keep(&position[1].values));
            if png {
                histogram(BitMapBackend::new(p, (900, 520)).into_drawing_area(), &c, &f)
            } else {
                histogram(SVGBackend::new(p, (900, 520)).into_drawing_area(), &c, &f)
            }
        }),
    ];
    crate::plotting::write_png_and_svg(dir, &jobs)
}
