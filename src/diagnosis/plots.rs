//! The diagnosis report's plots, each as PNG and SVG (plotters, the shipped font): WHERE the
//! residuals exceed noise (`where`) and WHICH candidate closes the held-out gap
//! (`candidates`).

use super::{AxesDiagnosis, Diagnosis, WhereEntry};
use crate::plotting::{Bar, Category, DrawError, DrawFn, PlotError, Reference, bar_chart, write_png_and_svg};
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// The files [`write_plots`] writes into its directory.
pub const PLOT_FILES: [&str; 4] = ["where.png", "where.svg", "candidates.png", "candidates.svg"];

/// The files [`write_axes_plots`] writes into its directory.
pub const AXES_PLOT_FILES: [&str; 2] = ["where.png", "where.svg"];

/// Most bars per chart (the rest are in `diagnosis.json`).
const MAX_BARS: usize = 20;

const SIZE: (u32, u32) = (1000, 620);

/// A chart's text and bars.
struct Chart<'a> {
    title: &'a str,
    x_desc: &'a str,
    /// Start of the value axis.
    from: f64,
    bars: &'a [Bar],
    categories: &'a [Category],
    references: &'a [Reference],
}

/// Draws a [`bar_chart`] to a PNG or SVG file.
fn draw(path: &Path, png: bool, c: &Chart) -> Result<(), DrawError> {
    if png {
        let root = BitMapBackend::new(path, SIZE).into_drawing_area();
        bar_chart(root, c.title, c.x_desc, c.from, c.bars, c.categories, c.references)
    } else {
        let root = SVGBackend::new(path, SIZE).into_drawing_area();
        bar_chart(root, c.title, c.x_desc, c.from, c.bars, c.categories, c.references)
    }
}

/// The colours of the `where` bars: a workspace feature's bin, the validation poses, an axis
/// experiment.
const FEATURE: RGBColor = RGBColor(0, 140, 70);
const VALIDATION: RGBColor = RGBColor(200, 110, 0);
const AXIS: RGBColor = BLUE;

fn where_bars(entries: &[WhereEntry]) -> Vec<Bar> {
    entries
        .iter()
        .take(MAX_BARS)
        .map(|w| Bar {
            label: match w.joint {
                Some(j) if !w.experiment.contains(&j.to_string()) => format!("{} (joint {j})", w.experiment),
                _ => w.experiment.clone(),
            },
            value: w.excess_ratio,
            color: if w.experiment.starts_with("feature:") {
                FEATURE
            } else if w.experiment.starts_with("validation") {
                VALIDATION
            } else {
                AXIS
            },
        })
        .collect()
}

/// The legend of the `where` bars' colours present in `bars`.
fn where_categories(bars: &[Bar]) -> Vec<Category> {
    [
        (FEATURE, "held-out poses of one workspace-feature bin"),
        (VALIDATION, "validation poses"),
        (AXIS, "an axis experiment"),
    ]
    .into_iter()
    .filter(|(c, _)| bars.iter().any(|b| b.color == *c))
    .map(|(color, label)| Category {
        label: label.into(),
        color,
    })
    .collect()
}

fn noise_line() -> Reference {
    Reference {
        label: "noise only (ratio 1)".into(),
        value: 1.0,
        color: BLACK,
    }
}

/// Writes `where` (residual over noise-only RMS per experiment and workspace feature, the
/// largest first) and `candidates` (held-out RMS with each candidate, best first, against the
/// baseline's and noise's) into `dir` ([`PLOT_FILES`]); returns the files.
pub fn write_plots(d: &Diagnosis, dir: &Path) -> Result<Vec<PathBuf>, PlotError> {
    let where_ = where_bars(&d.where_);
    let candidates: Vec<Bar> = d
        .candidates
        .iter()
        .take(MAX_BARS)
        .map(|c| Bar {
            label: format!(
                "{} ({}){}{}",
                c.effect,
                c.member,
                c.joint.map_or(String::new(), |j| format!(" joint {j}")),
                if c.significant { " *" } else { "" }
            ),
            value: c.heldout_rms_mm,
            color: if c.significant { BLUE } else { RGBColor(150, 150, 150) },
        })
        .collect();
    let rms_refs = [
        Reference {
            label: format!("baseline (refit), held out: {:.3} mm", d.heldout_rms_before_mm),
            value: d.heldout_rms_before_mm,
            color: RED,
        },
        Reference {
            label: format!("noise only: {:.3} mm", d.noise_only_rms_mm),
            value: d.noise_only_rms_mm,
            color: BLACK,
        },
    ];
    let verdict = format!(
        "Which: held-out RMS per candidate (* beats noise); verdict {}{}",
        d.outcome.effect,
        d.outcome.joint.map_or(String::new(), |j| format!(" joint {j}"))
    );
    // The candidates differ by a fraction of the noise: the axis starts below the smallest.
    let from = 0.9 * candidates.iter().map(|b| b.value).fold(d.noise_only_rms_mm, f64::min);
    // The gap test flags a held-out RMS of sqrt(noise^2 + detectable gap^2): that ratio, for
    // all held-out poses pooled (a bin of fewer poses scatters more).
    let flagged = d.noise_only_rms_mm.hypot(d.detectable_gap_mm) / d.noise_only_rms_mm;
    let where_refs = [
        noise_line(),
        Reference {
            label: format!(
                "the gap test flags above {flagged:.2} (all held-out poses, false alarm {})",
                d.false_alarm
            ),
            value: flagged,
            color: RED,
        },
    ];
    let where_legend = where_categories(&where_);
    let charts = [
        Chart {
            title: &format!(
                "Where: residual RMS over its noise-only RMS (verdict {})",
                d.outcome.effect
            ),
            x_desc: "excess ratio (residual RMS / noise-only RMS)",
            from: 0.0,
            bars: &where_,
            categories: &where_legend,
            references: &where_refs,
        },
        Chart {
            title: &verdict,
            x_desc: "held-out position RMS [mm] (axis starts at 90 % of the smallest)",
            from,
            bars: &candidates,
            categories: &[],
            references: &rms_refs,
        },
    ];
    let jobs: [(&str, &DrawFn); 2] = [
        ("where", &|p: &Path, png: bool| draw(p, png, &charts[0])),
        ("candidates", &|p: &Path, png: bool| draw(p, png, &charts[1])),
    ];
    write_png_and_svg(dir, &jobs)
}

/// Writes `where` for the axis-experiments-only mode (arc residual over its noise-only RMS
/// per axis, with the family-wise threshold) into `dir` ([`AXES_PLOT_FILES`]).
pub fn write_axes_plots(d: &AxesDiagnosis, dir: &Path) -> Result<Vec<PathBuf>, PlotError> {
    let bars = where_bars(&d.where_);
    let refs = [
        noise_line(),
        Reference {
            label: format!(
                "family-wise threshold {:.2} (false alarm {})",
                d.ratio_threshold, d.false_alarm
            ),
            value: d.ratio_threshold,
            color: RED,
        },
    ];
    let legend = where_categories(&bars);
    let chart = Chart {
        title: "Where: arc residual RMS over its noise-only RMS",
        x_desc: "excess ratio (residual RMS / noise-only RMS)",
        from: 0.0,
        bars: &bars,
        categories: &legend,
        references: &refs,
    };
    let jobs: [(&str, &DrawFn); 1] = [("where", &|p: &Path, png: bool| draw(p, png, &chart))];
    write_png_and_svg(dir, &jobs)
}
