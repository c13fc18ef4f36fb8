//! The certificate's inline SVG plots: the correlation heat map and the residuals of each axis
//! fit. Written by hand (no fonts to embed: the page's own sans-serif renders the text).

use super::{Correlation, JointResiduals};
use std::fmt::Write as _;

/// `text` with `&`, `<`, `>`, `"` and `'` escaped for HTML and SVG.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// The diverging colour of `rho` in [-1, 1]: ColorBrewer RdBu's ends (blue `#2166ac` at -1,
/// red `#b2182b` at +1) through its neutral `#f7f7f7` at 0, interpolated in sRGB.
fn diverging(rho: f64) -> String {
    let (neutral, end) = if rho < 0.0 {
        ([247.0, 247.0, 247.0], [33.0, 102.0, 172.0])
    } else {
        ([247.0, 247.0, 247.0], [178.0, 24.0, 43.0])
    };
    let t = rho.abs().min(1.0);
    let c: Vec<u8> = (0..3)
        .map(|i| (neutral[i] + t * (end[i] - neutral[i])).round() as u8)
        .collect();
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

/// The heat map of `c`: one cell per pair, the names on the left and on top, a colour bar.
pub fn correlation_heat_map(c: &Correlation) -> String {
    let n = c.names.len();
    let cell = if n > 40 { 8.0 } else { 14.0 };
    let label = 190.0;
    let size = n as f64 * cell;
    let (width, height) = (label + size + 90.0, label + size + 20.0);
    let mut s = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" class="heat-map" width="{width}" height="{height}" viewBox="0 0 {width} {height}" role="img" aria-label="parameter correlation heat map"><title>Correlation of the identified parameters</title>"#
    );
    let font = if n > 40 { 6.5 } else { 9.0 };
    for (i, name) in c.names.iter().enumerate() {
        let y = label + (i as f64 + 0.75) * cell;
        let x = label + (i as f64 + 0.75) * cell;
        let _ = write!(
            s,
            r#"<text x="{:.1}" y="{y:.1}" font-size="{font}" text-anchor="end">{}</text><text transform="translate({x:.1},{:.1}) rotate(-90)" font-size="{font}">{}</text>"#,
            label - 4.0,
            escape(name),
            label - 4.0,
            escape(name)
        );
        for (j, rho) in c.correlation[i].iter().enumerate() {
            let _ = write!(
                s,
                r#"<rect x="{:.1}" y="{:.1}" width="{cell}" height="{cell}" fill="{}"><title>{} / {}: {rho:.3}</title></rect>"#,
                label + j as f64 * cell,
                label + i as f64 * cell,
                diverging(*rho),
                escape(name),
                escape(&c.names[j])
            );
        }
    }
    // The colour bar: -1 at the bottom, +1 at the top.
    let (bar_x, steps) = (label + size + 20.0, 20);
    for k in 0..steps {
        let rho = 1.0 - 2.0 * (k as f64 + 0.5) / steps as f64;
        let _ = write!(
            s,
            r#"<rect x="{bar_x:.1}" y="{:.1}" width="14" height="{:.2}" fill="{}"/>"#,
            label + k as f64 * size / steps as f64,
            size / steps as f64,
            diverging(rho)
        );
    }
    for (rho, y) in [
        ("+1", label + 8.0),
        ("0", label + size / 2.0 + 3.0),
        ("-1", label + size),
    ] {
        let _ = write!(
            s,
            r#"<text x="{:.1}" y="{y:.1}" font-size="10">{rho}</text>"#,
            bar_x + 18.0
        );
    }
    let _ = write!(
        s,
        r#"<text transform="translate({:.1},{:.1}) rotate(-90)" font-size="10" text-anchor="middle">correlation &#961;</text></svg>"#,
        bar_x + 48.0,
        label + size / 2.0
    );
    s
}

/// The residual plot of one joint's axis fit: its three components against the point's place
/// in the sweep, the noise's +-2 sigma per coordinate dashed (`sigma = noise / sqrt 3`).
pub fn residual_plot(j: &JointResiduals, noise_rms_3d_mm: Option<f64>) -> String {
    let (w, h, left, bottom, top, right) = (360.0, 210.0, 52.0, 36.0, 32.0, 110.0);
    let (pw, ph) = (w - left - right, h - top - bottom);
    let two_sigma = noise_rms_3d_mm.map(|n| 2.0 * n / 3f64.sqrt());
    let largest = j
        .points
        .iter()
        .flat_map(|p| [p.first_mm, p.second_mm, p.third_mm])
        .fold(two_sigma.unwrap_or(0.0), |m, v| m.max(v.abs()));
    let y_max = if largest > 0.0 { 1.15 * largest } else { 1.0 };
    let n = j.points.len().max(1) as f64;
    let x = |i: usize| left + (i as f64 + 0.5) / n * pw;
    let y = |v: f64| top + (1.0 - (v + y_max) / (2.0 * y_max)) * ph;
    let names = if j.sliding {
        ["across u", "across v", "along"]
    } else {
        ["radial", "tangential", "axial"]
    };
    let colours = COLOURS;
    let mut s = format!(
        r##"<svg xmlns="http://www.w3.org/2000/svg" class="residual-plot" width="{w}" height="{h}" viewBox="0 0 {w} {h}" role="img" aria-label="joint {} residuals"><title>Joint {} axis fit residuals</title><rect x="{left}" y="{top}" width="{pw}" height="{ph}" fill="none" stroke="#444"/>"##,
        j.joint, j.joint
    );
    let experiments: Vec<&str> = j.points.iter().fold(Vec::new(), |mut v, p| {
        if !v.contains(&p.experiment.as_str()) {
            v.push(&p.experiment);
        }
        v
    });
    let _ = write!(
        s,
        r#"<text x="{:.1}" y="12" font-size="11" font-weight="bold" text-anchor="middle">joint {} ({})</text>"#,
        left + pw / 2.0,
        j.joint,
        escape(&experiments.join(", "))
    );
    let _ = write!(
        s,
        r##"<line x1="{left}" x2="{:.1}" y1="{:.1}" y2="{:.1}" stroke="#999"/>"##,
        left + pw,
        y(0.0),
        y(0.0)
    );
    if let Some(t) = two_sigma {
        for v in [t, -t] {
            let _ = write!(
                s,
                r##"<line x1="{left}" x2="{:.1}" y1="{:.1}" y2="{:.1}" stroke="#666" stroke-dasharray="4 3"/>"##,
                left + pw,
                y(v),
                y(v)
            );
        }
    }
    for (i, p) in j.points.iter().enumerate() {
        let (cx, [a, b, c]) = (x(i), [p.first_mm, p.second_mm, p.third_mm]);
        let _ = write!(
            s,
            r#"<circle cx="{cx:.1}" cy="{:.1}" r="2.2" fill="{}"/><path d="M{:.1},{:.1}l2.4,4.2h-4.8z" fill="{}"/><rect x="{:.1}" y="{:.1}" width="3.6" height="3.6" fill="{}"/>"#,
            y(a),
            colours[0],
            cx,
            y(b) - 2.8,
            colours[1],
            cx - 1.8,
            y(c) - 1.8,
            colours[2]
        );
    }
    let _ = write!(
        s,
        r#"<text x="{left}" y="{:.1}" font-size="10">{:+.3}</text><text x="{left}" y="{:.1}" font-size="10">{:+.3}</text>"#,
        top - 4.0,
        y_max,
        top + ph + 12.0,
        -y_max
    );
    let _ = write!(
        s,
        r#"<text x="{:.1}" y="{:.1}" font-size="10" text-anchor="middle">point, in sweep order ({} points)</text><text transform="translate(14,{:.1}) rotate(-90)" font-size="10" text-anchor="middle">residual [mm]</text>"#,
        left + pw / 2.0,
        h - 6.0,
        j.points.len(),
        top + ph / 2.0
    );
    legend(&mut s, &names, left + pw + 10.0, top, two_sigma.is_some());
    s.push_str("</svg>");
    s
}

/// Okabe-Ito colours of the three residual components, distinct for colour-blind readers
/// (with three marker shapes: circle, triangle, square).
const COLOURS: [&str; 3] = ["#0072b2", "#e69f00", "#009e73"];

/// The residual plot's legend at `lx`: the three components' markers and, with `noise`, the
/// dashed noise line.
fn legend(s: &mut String, names: &[&str; 3], lx: f64, top: f64, noise: bool) {
    let colours = COLOURS;
    for (k, name) in names.iter().enumerate() {
        let ly = top + 12.0 + 16.0 * k as f64;
        let (mx, my, colour) = (lx + 4.0, ly - 3.0, colours[k]);
        let marker = match k {
            0 => format!(r#"<circle cx="{mx:.1}" cy="{my:.1}" r="2.2" fill="{colour}"/>"#),
            1 => format!(r#"<path d="M{mx:.1},{:.1}l2.4,4.2h-4.8z" fill="{colour}"/>"#, my - 2.8),
            _ => format!(
                r#"<rect x="{:.1}" y="{:.1}" width="3.6" height="3.6" fill="{colour}"/>"#,
                mx - 1.8,
                my - 1.8
            ),
        };
        let _ = write!(
            s,
            r#"{marker}<text x="{:.1}" y="{ly:.1}" font-size="10">{name}</text>"#,
            lx + 12.0
        );
    }
    if noise {
        let ly = top + 12.0 + 48.0;
        let _ = write!(
            s,
            r##"<line x1="{lx:.1}" x2="{:.1}" y1="{:.1}" y2="{:.1}" stroke="#666" stroke-dasharray="4 3"/><text x="{:.1}" y="{ly:.1}" font-size="10">noise 2&#963;</text>"##,
            lx + 9.0,
            ly - 3.0,
            ly - 3.0,
            lx + 12.0
        );
    }
}
