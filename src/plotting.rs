//! Shared plotting set-up: plotters renders text with the `ab_glyph` feature, which needs a
//! registered font. The DejaVu Sans font ships in `assets/fonts/` (license beside it), so no
//! system font is needed on a fresh machine.

use plotters::style::FontStyle;
use std::sync::Once;

static FONT: Once = Once::new();

/// Registers the shipped font as `sans-serif` (once per process).
pub(crate) fn register_font() {
    FONT.call_once(|| {
        // The shipped font is a valid TrueType file; a failure would only lose the text.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            include_bytes!("../assets/fonts/DejaVuSans.ttf"),
        );
    });
}

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor;
use std::path::{Path, PathBuf};

/// Why a plot could not be drawn or written.
#[derive(Debug, thiserror::Error)]
#[error("plot {path}: {cause}")]
pub struct PlotError {
    /// The file.
    pub path: PathBuf,
    /// What went wrong while drawing it.
    pub cause: DrawError,
}

/// What plotters said when a drawing step failed. Its error types are generic over the
/// backend (bitmap or SVG), so its message is what one plot's steps have in common.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct DrawError(String);

impl<E: std::error::Error + Send + Sync> From<DrawingAreaErrorKind<E>> for DrawError {
    fn from(e: DrawingAreaErrorKind<E>) -> Self {
        DrawError(e.to_string())
    }
}

/// Draws one plot to a path, PNG (`true`) or SVG.
pub(crate) type DrawFn<'a> = dyn Fn(&Path, bool) -> Result<(), DrawError> + 'a;

/// Draws every `(name, draw)` job to `dir/name.png` and `dir/name.svg`; returns the files.
pub(crate) fn write_png_and_svg(dir: &Path, jobs: &[(&str, &DrawFn)]) -> Result<Vec<PathBuf>, PlotError> {
    register_font();
    let mut written = Vec::new();
    for (name, draw) in jobs {
        for (ext, png) in [("png", true), ("svg", false)] {
            let path = dir.join(format!("{name}.{ext}"));
            draw(&path, png).map_err(|cause| PlotError {
                path: path.clone(),
                cause,
            })?;
            written.push(path);
        }
    }
    Ok(written)
}

/// Draws `chart`'s legend (its labelled series) at `position`, in the program's one legend
/// style: a white, slightly translucent box with a black frame.
pub(crate) fn draw_legend<'a, DB: DrawingBackend + 'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> Result<(), DrawError> {
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// One bar of a [`bar_chart`].
pub(crate) struct Bar {
    /// Text beside the bar.
    pub label: String,
    /// Length.
    pub value: f64,
    /// Fill.
    pub color: RGBColor,
}

/// A vertical reference line of a [`bar_chart`] (with its legend entry).
pub(crate) struct Reference {
    /// Legend text.
    pub label: String,
    /// Position on the value axis.
    pub value: f64,
    /// Line colour.
    pub color: RGBColor,
}

/// What a bar colour means, for the legend.
pub(crate) struct Category {
    /// Legend text.
    pub label: String,
    /// The bars' fill.
    pub color: RGBColor,
}

/// Horizontal bars, the first at the top, from `from` (the value axis' start) to their values,
/// with vertical reference lines; the legend (bar colours, then the lines) sits in room kept
/// free right of the longest bar.
pub(crate) fn bar_chart<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    x_desc: &str,
    from: f64,
    bars: &[Bar],
    categories: &[Category],
    references: &[Reference],
) -> Result<(), DrawError> {
    root.fill(&WHITE)?;
    let n = bars.len().max(1);
    let hi = bars
        .iter()
        .map(|b| b.value)
        .chain(references.iter().map(|r| r.value))
        .filter(|v| v.is_finite())
        .fold(from, f64::max);
    let label_width = bars.iter().map(|b| b.label.len()).max().unwrap_or(4) as u32 * 7 + 16;
    // The legend's width (about 7 px a character of its longest entry, its swatch and frame)
    // as a share of the plotting area's: the value axis reaches that far beyond the longest
    // bar or line, so the legend in the lower right covers none of them.
    let legend_chars = categories
        .iter()
        .map(|c| c.label.len())
        .chain(references.iter().map(|r| r.label.len()))
        .max();
    let plot_px = f64::from(root.dim_in_pixel().0.saturating_sub(label_width.min(360) + 24).max(100));
    let legend_share = legend_chars.map_or(0.0, |c| ((c * 7 + 50) as f64 / plot_px).min(0.7));
    let hi = from + (hi - from).max(1e-9) / (1.0 - legend_share) * 1.04;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(label_width.min(360))
        .build_cartesian_2d(from..hi, 0.0..n as f64)?;
    let row = |i: usize| (n - 1 - i) as f64;
    chart
        .configure_mesh()
        .disable_y_mesh()
        .y_labels(0)
        .x_desc(x_desc)
        .draw()?;
    chart.draw_series(bars.iter().enumerate().map(|(i, b)| {
        let y = row(i);
        Rectangle::new(
            [(from, y + 0.15), (b.value.clamp(from, hi), y + 0.85)],
            b.color.mix(0.75).filled(),
        )
    }))?;
    // Bar labels in the y label area, right-aligned against the axis.
    let (area_x, _) = chart.plotting_area().get_pixel_range();
    let style = TextStyle::from(("sans-serif", 13).into_font()).pos(text_anchor::Pos::new(
        text_anchor::HPos::Right,
        text_anchor::VPos::Center,
    ));
    for (i, b) in bars.iter().enumerate() {
        let (_, py) = chart.backend_coord(&(from, row(i) + 0.5));
        root.draw_text(&b.label, &style, (area_x.start - 6, py))?;
    }
    for c in categories {
        let color = c.color;
        chart
            .draw_series(std::iter::empty::<Rectangle<(f64, f64)>>())?
            .label(c.label.clone())
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 18, y + 5)], color.mix(0.75).filled()));
    }
    for r in references {
        let color = r.color;
        chart
            .draw_series(LineSeries::new(
                [(r.value, 0.0), (r.value, n as f64)],
                color.stroke_width(2),
            ))?
            .label(r.label.clone())
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], color.stroke_width(2)));
    }
    if !references.is_empty() || !categories.is_empty() {
        draw_legend(&mut chart, SeriesLabelPosition::LowerRight)?;
    }
    Ok(root.present()?)
}
