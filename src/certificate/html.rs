//! The certificate as one self-contained HTML page: inline CSS (with print rules) and inline
//! SVG, no script, no network. Every number cell carries its full value in `data-value`
//! (Rust's shortest round-trip form), so a reader program gets the numbers the page rounds.

use super::svg::{correlation_heat_map, escape, residual_plot};
use super::{Certificate, FrameUncertainty, ParameterLine};
use crate::iso9283::IsoFigures;
use crate::robot::Placement;
use std::fmt::Write as _;

const STYLE: &str = "body{font-family:'DejaVu Sans',Helvetica,Arial,sans-serif;font-size:11pt;color:#111;max-width:1100px;margin:2em auto;padding:0 1em}\
h1{font-size:20pt;margin-bottom:0.2em}h2{font-size:14pt;border-bottom:1px solid #999;margin-top:1.6em}\
table{border-collapse:collapse;margin:0.6em 0;font-size:9.5pt}th,td{border:1px solid #bbb;padding:2px 6px;text-align:left;vertical-align:top}\
td.n{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}th{background:#eee}\
p.note{font-size:9.5pt;color:#333}p.warning{border:2px solid #b2182b;padding:0.5em;background:#fdf0f0}.plots svg{margin:0 1em 1em 0}\
@media print{body{margin:0;max-width:none}h2{break-after:avoid}table,svg,figure{break-inside:avoid}@page{size:A4;margin:15mm}}";

/// A number cell: `value` rounded to `decimals` for the eye, in full in `data-value`.
fn num(value: f64, decimals: usize) -> String {
    if !value.is_finite() {
        return "<td class=\"n\">-</td>".into();
    }
    format!("<td class=\"n\" data-value=\"{value:e}\">{value:.decimals$}</td>")
}

/// A cell with an optional number.
fn opt_num(value: Option<f64>, decimals: usize) -> String {
    value.map_or_else(|| "<td class=\"n\">-</td>".into(), |v| num(v, decimals))
}

/// A text cell.
fn text(value: &str) -> String {
    format!("<td>{}</td>", escape(value))
}

/// The page of `c`.
pub fn render(c: &Certificate) -> String {
    let mut s = String::new();
    let title = format!("Calibration certificate: {}", c.robot.name);
    let _ = write!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title><style>{STYLE}</style></head><body>\n<h1>{}</h1>\n",
        escape(&title),
        escape(&title)
    );
    for w in &c.warnings {
        let _ = writeln!(s, "<p class=\"warning\"><strong>Warning:</strong> {}</p>", escape(w));
    }
    identity(&mut s, c);
    data(&mut s, c);
    noise(&mut s, c);
    parameters(&mut s, c);
    frames(&mut s, c);
    correlation(&mut s, c);
    axes(&mut s, c);
    residuals(&mut s, c);
    held_out(&mut s, c);
    if let Some(iso) = &c.iso9283 {
        iso9283(&mut s, iso);
    }
    s.push_str("<h2 id=\"not-calibrated\">What was not calibrated</h2><ul>");
    for line in &c.not_calibrated {
        let _ = write!(s, "<li>{}</li>", escape(line));
    }
    s.push_str("</ul>\n</body></html>\n");
    s
}

fn identity(s: &mut String, c: &Certificate) {
    s.push_str("<h2 id=\"identity\">Robot, calibration and instrument</h2><table id=\"identity-table\">");
    let rows = [
        ("Robot", c.robot.name.clone()),
        (
            "Description geometry hash",
            c.robot.geometry_hash.clone().unwrap_or_else(|| "not recorded".into()),
        ),
        ("Joints", c.robot.joints.to_string()),
        ("Calibration file", c.calibration.file.clone()),
        (
            "Certificate written by",
            format!("axiscal {}", c.calibration.axiscal_version),
        ),
        ("Method", c.calibration.method.clone()),
        (
            "Base frame",
            c.calibration.base_rule.clone().unwrap_or_else(|| "not recorded".into()),
        ),
        (
            "Instrument",
            c.instrument.description.clone().unwrap_or_else(|| "not stated".into()),
        ),
    ];
    for (k, v) in rows {
        let _ = write!(s, "<tr><th>{}</th>{}</tr>", escape(k), text(&v));
    }
    s.push_str("</table>\n");
}

fn data(s: &mut String, c: &Certificate) {
    let Some(d) = &c.data else {
        return;
    };
    let _ = write!(
        s,
        "<h2 id=\"data\">Data</h2><p>{}: {} measured points.</p><table id=\"data-table\"><tr><th>experiment</th><th>moved joint</th><th>poses</th><th>points</th></tr>",
        escape(&d.file),
        d.rows
    );
    for e in &d.experiments {
        let _ = write!(
            s,
            "<tr>{}<td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td></tr>",
            text(&e.name),
            e.moved_joint,
            e.poses,
            e.rows
        );
    }
    s.push_str("</table>\n");
}

fn noise(s: &mut String, c: &Certificate) {
    let i = &c.instrument;
    s.push_str("<h2 id=\"noise\">Measurement noise</h2><table id=\"noise-table\">");
    let _ = write!(
        s,
        "<tr><th>noise the fits were weighted with, 3-D RMS (mm)</th>{}</tr><tr><th>source</th>{}</tr>",
        opt_num(i.noise_used_rms_3d_mm, 4),
        text(i.noise_source.as_deref().unwrap_or("not recorded"))
    );
    if let Some(e) = &i.noise_estimate {
        let _ = write!(
            s,
            "<tr><th>estimate from the residuals, 3-D RMS (mm)</th>{}</tr><tr><th>{:.0} % interval (mm)</th><td class=\"n\">{:.4} to {:.4}</td></tr><tr><th>degrees of freedom</th><td class=\"n\">{}</td></tr>",
            num(e.rms_3d_mm, 4),
            e.confidence * 100.0,
            e.low_mm,
            e.high_mm,
            e.dof
        );
    }
    if let Some(p) = i.given_p_value {
        let _ = write!(
            s,
            "<tr><th>chi-square test of the given noise (two-sided p)</th>{}</tr><tr><th>verdict</th>{}</tr>",
            num(p, 4),
            text(if i.given_contradicted {
                "the residuals contradict the given noise (p < 0.01)"
            } else {
                "consistent with the given noise"
            })
        );
    }
    s.push_str("</table>\n");
}

fn parameter_row(p: &ParameterLine) -> String {
    format!(
        "<tr>{}{}{}{}{}{}{}</tr>",
        text(&p.name),
        text(&p.unit),
        opt_num(p.nominal, 4),
        num(p.identified, 4),
        num(p.standard_uncertainty, 4),
        num(p.expanded_uncertainty, 4),
        text(&p.evaluation)
    )
}

fn parameters(s: &mut String, c: &Certificate) {
    let _ = write!(
        s,
        "<h2 id=\"parameters\">Identified parameters</h2><p class=\"note\">{}</p><table id=\"parameters-table\"><tr><th>parameter</th><th>unit</th><th>nominal</th><th>identified</th><th>u</th><th>U (k = {})</th><th>evaluation</th></tr>",
        escape(&c.uncertainty_statement),
        c.coverage_factor
    );
    for p in &c.parameters {
        s.push_str(&parameter_row(p));
    }
    s.push_str("</table>\n");
}

fn placement_cells(p: &Placement) -> String {
    let mut out = String::new();
    for v in p.translation_mm.iter().chain(&p.rpy_deg) {
        out.push_str(&num(*v, 4));
    }
    out
}

fn uncertainty_cells(u: &FrameUncertainty) -> String {
    [u.x_mm, u.y_mm, u.z_mm, u.rx_mrad, u.ry_mrad, u.rz_mrad]
        .iter()
        .map(|v| num(*v, 4))
        .collect()
}

fn frames(s: &mut String, c: &Certificate) {
    s.push_str("<h2 id=\"frames\">Base and tool frames</h2><p class=\"note\">Placements as x, y, z (mm) and roll, pitch, yaw (deg, R = Rz Ry Rx); uncertainties along and about the frame's own axes (mm, mrad).</p><table id=\"frames-table\"><tr><th>frame</th><th>value</th><th>x</th><th>y</th><th>z</th><th>roll / rx</th><th>pitch / ry</th><th>yaw / rz</th></tr>");
    for f in &c.frames {
        let _ = write!(
            s,
            "<tr>{}{}{}</tr><tr>{}{}{}</tr><tr>{}{}{}</tr><tr>{}{}{}</tr>",
            text(&f.frame),
            text("nominal"),
            placement_cells(&f.nominal),
            text(&f.frame),
            text("identified"),
            placement_cells(&f.identified),
            text(&f.frame),
            text("u"),
            uncertainty_cells(&f.standard_uncertainty),
            text(&f.frame),
            text(&format!("U (k = {})", c.coverage_factor)),
            uncertainty_cells(&f.expanded_uncertainty)
        );
    }
    s.push_str("</table>\n");
}

fn correlation(s: &mut String, c: &Certificate) {
    let _ = write!(
        s,
        "<h2 id=\"correlation\">Parameter correlations and identifiability</h2><p class=\"note\">Correlation of the {} parameters with an uncertainty; red positive, blue negative. Strongly correlated pairs (|&#961;| &#8805; {}) are what the data barely separate.</p><figure>{}</figure>",
        c.correlation.names.len(),
        super::STRONG_CORRELATION,
        correlation_heat_map(&c.correlation)
    );
    s.push_str("<table id=\"strong-pairs-table\"><tr><th>parameter</th><th>parameter</th><th>&#961;</th></tr>");
    for p in &c.correlation.strong_pairs {
        let _ = write!(s, "<tr>{}{}{}</tr>", text(&p.a), text(&p.b), num(p.rho, 4));
    }
    if c.correlation.strong_pairs.is_empty() {
        s.push_str("<tr><td colspan=\"3\">none</td></tr>");
    }
    s.push_str("</table>\n");
}

fn axes(s: &mut String, c: &Certificate) {
    if c.axes.is_empty() {
        return;
    }
    s.push_str("<h2 id=\"axes\">Axis fits</h2><table id=\"axes-table\"><tr><th>joint</th><th>experiment</th><th>points</th><th>span (deg or mm)</th><th>residual RMS (mm)</th><th>condition number</th><th>what the data cannot pin down</th></tr>");
    for a in &c.axes {
        let _ = write!(
            s,
            "<tr><td class=\"n\">{}</td>{}<td class=\"n\">{}</td>{}{}{}{}</tr>",
            a.joint,
            text(&a.experiment),
            a.points,
            num(a.span_deg_or_mm, 1),
            num(a.residual_rms_mm, 4),
            num(a.condition_number, 1),
            text(&a.identifiability.join("; "))
        );
    }
    s.push_str("</table>\n");
}

fn residuals(s: &mut String, c: &Certificate) {
    if c.residuals.is_empty() {
        return;
    }
    s.push_str("<h2 id=\"residuals\">Residuals of the axis fits</h2><p class=\"note\">Each measured point minus its fitted position, in the axis's own directions; dashed: twice the noise's standard deviation per coordinate.</p><div class=\"plots\">");
    for j in &c.residuals {
        s.push_str(&residual_plot(j, c.instrument.noise_used_rms_3d_mm));
    }
    s.push_str("</div>\n");
}

fn held_out(s: &mut String, c: &Certificate) {
    let Some(h) = &c.held_out else {
        return;
    };
    let _ = writeln!(
        s,
        "<h2 id=\"held-out\">Before and after calibration on held-out poses</h2><p class=\"note\">{}: {} points the calibration did not use. Before: the nominal model, its base frame registered to these points. After: the calibrated model. The noise alone predicts an RMS of {:.4} mm{}.</p><table id=\"held-out-table\"><tr><th>model</th><th>RMS (mm)</th><th>largest (mm)</th></tr><tr>{}{}{}</tr><tr>{}{}{}</tr></table><p>{}</p>",
        escape(&h.file),
        h.points,
        h.noise_predicted_rms_mm,
        match (h.predicted_tool_spans_rms_mm, h.predicted_tool_workspace_rms_mm) {
            (Some(a), Some(b)) => format!(
                "; the calibration's own uncertainty predicts a tool position error of {a:.4} mm RMS inside the calibrated spans and {b:.4} mm over the workspace (held-out poses beyond the spans are expected to miss by more than the noise)"
            ),
            _ => String::new(),
        },
        text("nominal (before)"),
        num(h.before.rms_mm, 4),
        num(h.before.max_mm, 4),
        text("calibrated (after)"),
        num(h.after.rms_mm, 4),
        num(h.after.max_mm, 4),
        escape(&h.verdict)
    );
}

fn iso9283(s: &mut String, iso: &IsoFigures) {
    s.push_str("<h2 id=\"iso9283\">ISO 9283 pose characteristics</h2><table id=\"iso9283-table\"><tr><th>pose</th><th>cycles</th><th>AP_P (mm)</th><th>RP_l (mm)</th><th>vAP_P (mm)</th></tr>");
    for p in &iso.poses {
        let _ = write!(
            s,
            "<tr>{}<td class=\"n\">{}</td>{}{}{}</tr>",
            text(&format!("P{}", p.pose)),
            p.cycles,
            num(p.accuracy.ap_p_mm, 4),
            opt_num(p.repeatability.map(|r| r.rp_l_mm), 4),
            opt_num(p.directional.map(|d| d.vap_p_mm), 4)
        );
    }
    s.push_str("</table>");
    if let Some(d) = &iso.distance_p2_p4 {
        let _ = write!(
            s,
            "<p>Distance P2-P4 (commanded {:.3} mm): AD_P {:.4} mm, RD_P &#177;{:.4} mm.</p>",
            d.commanded_mm, d.ad_p_mm, d.rd_p_mm
        );
    }
    s.push('\n');
}
