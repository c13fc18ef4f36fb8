//! The map of the predicted tool 1-sigma over reach and height (PNG and SVG, plotters, the
//! shipped font): the workspace poses of [`super::tool_accuracy::predict`] binned by where
//! their tool point is (distance from the base's z axis, height above its xy plane), each
//! cell coloured by the RMS position 1-sigma norm of its poses on the viridis scale
//! (perceptually uniform, readable in grey and by colour-blind readers); cells no pose reaches
//! stay white, and the tool points of the poses inside the calibrated spans are marked.

use super::tool_accuracy::MapPoint;
use crate::plotting::{DrawError, DrawFn, PlotError, write_png_and_svg};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// The files [`write_tool_map`] writes.
pub const TOOL_MAP_FILES: [&str; 2] = ["tool_sigma_map.png", "tool_sigma_map.svg"];

/// Cells across reach and height.
const CELLS: (usize, usize) = (12, 9);

const SIZE: (u32, u32) = (900, 640);

/// One occupied cell: reach range \[m\], height range \[m\], RMS position 1-sigma \[mm\].
type Cell = ([f64; 2], [f64; 2], f64);

/// The occupied cells and the plotted extent `[reach lo, hi, height lo, hi]` \[m\].
fn cells(points: &[&MapPoint]) -> (Vec<Cell>, [f64; 4]) {
    let lim = |f: &dyn Fn(&MapPoint) -> f64| {
        points
            .iter()
            .map(|p| f(p))
            .fold([f64::INFINITY, f64::NEG_INFINITY], |[a, b], v| [a.min(v), b.max(v)])
    };
    let ([r0, r1], [h0, h1]) = (lim(&|p| p.reach_m), lim(&|p| p.height_m));
    let (dr, dh) = (
        ((r1 - r0) / CELLS.0 as f64).max(1e-9),
        ((h1 - h0) / CELLS.1 as f64).max(1e-9),
    );
    let mut sums = vec![(0.0, 0usize); CELLS.0 * CELLS.1];
    for p in points {
        let i = (((p.reach_m - r0) / dr) as usize).min(CELLS.0 - 1);
        let j = (((p.height_m - h0) / dh) as usize).min(CELLS.1 - 1);
        let cell = &mut sums[j * CELLS.0 + i];
        cell.0 += p.sigma.position_norm_mm.powi(2);
        cell.1 += 1;
    }
    let out = sums
        .iter()
        .enumerate()
        .filter(|(_, (_, n))| *n > 0)
        .map(|(k, (s, n))| {
            let (i, j) = ((k % CELLS.0) as f64, (k / CELLS.0) as f64);
            (
                [r0 + i * dr, r0 + (i + 1.0) * dr],
                [h0 + j * dh, h0 + (j + 1.0) * dh],
                (s / *n as f64).sqrt(),
            )
        })
        .collect();
    (out, [r0, r1 + dr * 1e-6, h0, h1 + dh * 1e-6])
}

/// Viridis (matplotlib's, van der Walt and Smith 2015) at ten even stops, `t = 0` dark purple
/// (low) to `t = 1` yellow (high), linear between them.
fn colour(t: f64) -> RGBColor {
    const VIRIDIS: [(u8, u8, u8); 10] = [
        (0x44, 0x01, 0x54),
        (0x48, 0x28, 0x78),
        (0x3e, 0x49, 0x89),
        (0x31, 0x68, 0x8e),
        (0x26, 0x82, 0x8e),
        (0x1f, 0x9e, 0x89),
        (0x35, 0xb7, 0x79),
        (0x6e, 0xce, 0x58),
        (0xb5, 0xde, 0x2b),
        (0xfd, 0xe7, 0x25),
    ];
    let x = t.clamp(0.0, 1.0) * (VIRIDIS.len() - 1) as f64;
    let (i, f) = (
        (x as usize).min(VIRIDIS.len() - 2),
        x - (x as usize).min(VIRIDIS.len() - 2) as f64,
    );
    let mix = |a: u8, b: u8| (f64::from(a) + f * (f64::from(b) - f64::from(a))).round() as u8;
    let ((r0, g0, b0), (r1, g1, b1)) = (VIRIDIS[i], VIRIDIS[i + 1]);
    RGBColor(mix(r0, r1), mix(g0, g1), mix(b0, b1))
}

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, points: &[MapPoint]) -> Result<(), DrawError> {
    root.fill(&WHITE)?;
    let workspace: Vec<&MapPoint> = points.iter().filter(|p| !p.inside_spans).collect();
    let (cells, [r0, r1, h0, h1]) = cells(&workspace);
    let (lo, hi) = cells
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), c| (a.min(c.2), b.max(c.2)));
    let (main, bar) = root.split_horizontally(SIZE.0 - 110);
    let mut chart = ChartBuilder::on(&main)
        .caption(
            "Predicted tool position 1-sigma over the workspace [mm] (white: no pose)",
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(r0 * 1e3..r1 * 1e3, h0 * 1e3..h1 * 1e3)?;
    chart
        .configure_mesh()
        .x_desc("reach from the base z axis [mm]")
        .y_desc("height above the base [mm]")
        .draw()?;
    let t = |v: f64| if hi > lo { (v - lo) / (hi - lo) } else { 0.5 };
    chart.draw_series(
        cells.iter().map(|([a, b], [c, d], v)| {
            Rectangle::new([(a * 1e3, c * 1e3), (b * 1e3, d * 1e3)], colour(t(*v)).filled())
        }),
    )?;
    let inside: Vec<&MapPoint> = points.iter().filter(|p| p.inside_spans).collect();
    let inside_rms_mm =
        (inside.iter().map(|p| p.sigma.position_norm_mm.powi(2)).sum::<f64>() / inside.len().max(1) as f64).sqrt();
    let in_view = |p: &&&MapPoint| (r0..=r1).contains(&p.reach_m) && (h0..=h1).contains(&p.height_m);
    chart
        .draw_series(
            inside
                .iter()
                .filter(in_view)
                .map(|p| Circle::new((p.reach_m * 1e3, p.height_m * 1e3), 2, RED.filled())),
        )?
        .label(format!(
            "tool point of a pose inside the calibrated spans (1-sigma RMS {inside_rms_mm:.3} mm)"
        ))
        .legend(|(x, y)| Circle::new((x + 8, y), 3, RED.filled()));
    crate::plotting::draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
    let steps: i32 = 50;
    for k in 0..steps {
        let y0 = 60 + (steps - 1 - k) * 8;
        bar.draw(&Rectangle::new(
            [(20, y0), (45, y0 + 8)],
            colour(f64::from(k) / f64::from(steps - 1)).filled(),
        ))?;
    }
    let font = ("sans-serif", 14).into_font();
    bar.draw(&Text::new(format!("{hi:.3}"), (50, 58), font.clone()))?;
    bar.draw(&Text::new(format!("{lo:.3}"), (50, 60 + steps * 8 - 12), font.clone()))?;
    bar.draw(&Text::new("mm", (20, 40), font))?;
    Ok(root.present()?)
}

/// Writes the map of `points` into `dir` ([`TOOL_MAP_FILES`]).
pub fn write_tool_map(points: &[MapPoint], dir: &Path) -> Result<Vec<PathBuf>, PlotError> {
    let job = |path: &Path, png: bool| {
        if png {
            draw(BitMapBackend::new(path, SIZE).into_drawing_area(), points)
        } else {
            draw(SVGBackend::new(path, SIZE).into_drawing_area(), points)
        }
    };
    let jobs: [(&str, &DrawFn); 1] = [("tool_sigma_map", &job)];
    write_png_and_svg(dir, &jobs)
}
