//! The diagnostic report, like the paper's section-4 bullets: what the identified parameters
//! mean physically, each with its uncertainty and whether the data resolve it (> 3 sigma).

use super::outlier_point::OutlierTest;
use super::result::{Calibration, PointResidual, RowSigma};
use super::uncertainty::SIGNIFICANT_SIGMAS;
use crate::calibration::record::CalibrationRecord;
use crate::calibration::tool_accuracy::ToolAccuracy;
use crate::kinematics::JointKind;
use crate::markdown;
use crate::robot::{RobotDescription, Transmission};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;

/// One statement of the report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Finding {
    /// What it is about, e.g. `row 2: b` or `joint 6 transmission`.
    pub subject: String,
    /// The deviation from the design (or the fitted amplitude).
    pub value: f64,
    /// Its 1-sigma (NaN when the estimator reports none).
    pub sigma: f64,
    /// Unit of `value` and `sigma`.
    pub unit: String,
    /// Whether `|value| > 3 sigma`; never without a finite positive sigma (a value whose
    /// uncertainty is not known is not resolved by the data, it is untested).
    pub significant: bool,
    /// The sentence.
    pub text: String,
}

fn finding(subject: String, value: f64, sigma: f64, unit: &str, text: String) -> Finding {
    let significant = has_sigma(sigma) && value.abs() > SIGNIFICANT_SIGMAS * sigma;
    Finding {
        subject,
        value,
        sigma,
        unit: unit.into(),
        significant,
        text,
    }
}

/// ` +- sigma` at `digits` decimals, or ` (no sigma)` where none is computed (NaN: the paper's
/// estimator).
fn pm(sigma: f64, digits: usize) -> String {
    if sigma.is_finite() {
        format!(" +- {sigma:.digits$}")
    } else {
        " (no sigma)".to_owned()
    }
}

/// Each row's 1-sigma: the propagated ones; without them, from the model covariance where
/// there is one ([`covariance_row_sigmas`], a free-pose calibration); else NaN for every row
/// (the paper's estimator).
fn row_sigmas(cal: &Calibration) -> impl Iterator<Item = RowSigma> + '_ {
    let none = RowSigma {
        a_mm: f64::NAN,
        b_mm: f64::NAN,
        alpha_deg: f64::NAN,
        beta_deg: f64::NAN,
    };
    let rows = match cal.row_sigma.is_empty() {
        true => covariance_row_sigmas(cal).unwrap_or_default(),
        false => cal.row_sigma.clone(),
    };
    rows.into_iter().chain(std::iter::repeat(none))
}

/// Each row's 1-sigma from the diagonal of the model covariance
/// ([`crate::calibration::model_parameters::ModelCovariance`], `row K a [m]`, `row K alpha
/// [rad]`, ...): the free-pose fit's covariance of its parameters propagated to the model's
/// scalars (`free_pose::summary`). 0 for a scalar the fit kept at its design value (not
/// identified); NaN for one the covariance does not name. `None` without a covariance.
fn covariance_row_sigmas(cal: &Calibration) -> Option<Vec<RowSigma>> {
    let mc = cal.model_covariance.as_ref()?;
    let sigma = |name: String| {
        mc.names
            .iter()
            .position(|n| *n == name)
            .and_then(|i| mc.covariance.get(i).and_then(|r| r.get(i)))
            .map_or(f64::NAN, |v| v.max(0.0).sqrt())
    };
    Some(
        (1..=cal.robot.rows.len())
            .map(|k| RowSigma {
                a_mm: sigma(format!("row {k} a [m]")) * 1e3,
                b_mm: sigma(format!("row {k} b [m]")) * 1e3,
                alpha_deg: sigma(format!("row {k} alpha [rad]")).to_degrees(),
                beta_deg: sigma(format!("row {k} beta [rad]")).to_degrees(),
            })
            .collect(),
    )
}

/// Whether `sigma` is a real 1-sigma (finite and positive).
fn has_sigma(sigma: f64) -> bool {
    sigma.is_finite() && sigma > 0.0
}

/// Deviations of the Table-2 rows from the design, offsets, transmissions and couplings.
pub fn findings(cal: &Calibration, desc: &RobotDescription) -> Vec<Finding> {
    let mut out = Vec::new();
    row_findings(cal, desc, &mut out);
    zero_offset_findings(cal, &mut out);
    transmission_findings(cal, &mut out);
    coupling_findings(cal, &mut out);
    out
}

/// The deviations of each row's `a`, `b`, `alpha` and `beta` from the design, appended to
/// `out`. A free-pose calibration's rows (sigmas from its model covariance) leave out the scalars its
/// fit kept at their design values (sigma 0: nothing to report).
fn row_findings(cal: &Calibration, desc: &RobotDescription, out: &mut Vec<Finding>) {
    let from_covariance = cal.row_sigma.is_empty() && cal.model_covariance.is_some();
    let first = out.len();
    row_findings_all(cal, desc, out);
    if from_covariance {
        let mut k = 0;
        out.retain(|f| {
            k += 1;
            k <= first || f.sigma != 0.0
        });
    }
}

/// [`row_findings`], every scalar of every row.
fn row_findings_all(cal: &Calibration, desc: &RobotDescription, out: &mut Vec<Finding>) {
    for (k, ((r, n), s)) in cal.robot.rows.iter().zip(&desc.rows).zip(row_sigmas(cal)).enumerate() {
        let (i, j) = (k + 1, k + 2);
        let da = (r.a_m - n.a_m) * 1e3;
        out.push(finding(
            format!("row {i}: a"),
            da,
            s.a_mm,
            "mm",
            format!(
                "frame {j} (on axis {j}) sits {:.2}{} mm from its design position along Z_phi{i}, the direction from axis {i} towards axis {j}",
                da,
                pm(s.a_mm, 2)
            ),
        ));
        let db = (r.b_m - n.b_m) * 1e3;
        out.push(finding(
            format!("row {i}: b"),
            db,
            s.b_mm,
            "mm",
            format!(
                "the common normal from Z_phi{i} to axis {j} is {:.2}{} mm {} than designed",
                db.abs(),
                pm(s.b_mm, 2),
                if db >= 0.0 { "longer" } else { "shorter" }
            ),
        ));
        let dalpha = r.alpha_deg - n.alpha_deg;
        out.push(finding(
            format!("row {i}: alpha"),
            dalpha,
            s.alpha_deg,
            "deg",
            format!(
                "axis {j} is tilted {:.3}{} deg from its designed angle about the common normal",
                dalpha,
                pm(s.alpha_deg, 3)
            ),
        ));
        let dbeta = r.beta_deg - n.beta_deg;
        out.push(finding(
            format!("row {i}: beta"),
            dbeta,
            s.beta_deg,
            "deg",
            format!(
                "axis {j} is turned {:.3}{} deg about Z_phi{i} from its designed direction (joint-{i} zero and axis misalignment)",
                dbeta,
                pm(s.beta_deg, 3)
            ),
        ));
    }
}

/// Each calibrated joint's zero offset at the reference pose, appended to `out`.
fn zero_offset_findings(cal: &Calibration, out: &mut Vec<Finding>) {
    for (k, j) in cal.robot.joints.iter().enumerate() {
        let sigma = cal
            .zero_offset_sigma
            .iter()
            .find(|s| s.joint == k + 1)
            .and_then(|s| s.sigma_rad.map(f64::to_degrees).or(s.sigma_mm));
        // A joint without an axis experiment keeps its nominal zero: nothing was measured.
        if !cal.axes.iter().any(|a| a.joint == k + 1) {
            continue;
        }
        let (off, unit) = match j.kind {
            JointKind::Revolute => (j.transducer_offset.to_degrees(), "deg"),
            JointKind::Prismatic => (j.transducer_offset * 1e3, "mm"),
        };
        out.push(finding(
            format!("joint {}: zero offset", k + 1),
            off,
            sigma.unwrap_or(f64::NAN),
            unit,
            format!(
                "joint {} reads {:.3}{} {unit} off its calibrated zero at the reference pose",
                k + 1,
                off,
                pm(sigma.unwrap_or(f64::NAN), 3)
            ),
        ));
    }
}

/// The amplitude of every harmonic of each joint's transmission (eq. 8) and each sliding
/// joint's scale error and nonlinearity (eq. 13), appended to `out`.
fn transmission_findings(cal: &Calibration, out: &mut Vec<Finding>) {
    for a in &cal.axes {
        let (sin, cos, to_joint) = match &a.transmission {
            Transmission::Polynomial { c, .. } => {
                polynomial_findings(a.joint, c, &a.coefficient_sigma, out);
                continue;
            }
            Transmission::Harmonic { sin, cos } => (sin, cos, 1.0),
            // A gear's coefficients are in gear units: N times them in joint units.
            Transmission::Gear { ratio, sin, cos } => (sin, cos, *ratio),
        };
        for (h, (s, c)) in sin.iter().zip(cos).enumerate() {
            // Amplitude and its 1-sigma along the (sin, cos) direction, from the coefficients'
            // covariance (`HarmonicReport`); a report without them (older files) says none.
            let (amp, sig) = a.harmonics.get(h).map_or((to_joint * s.hypot(*c), f64::NAN), |r| {
                (r.amplitude_rad, r.amplitude_sigma_rad)
            });
            let per = match &a.transmission {
                Transmission::Gear { ratio, .. } => format!("per {:.3} joint turns", ratio / (h + 1) as f64),
                _ => format!("{} times per turn", h + 1),
            };
            out.push(finding(
                format!("joint {} transmission harmonic {}", a.joint, h + 1),
                amp * 1e3,
                sig * 1e3,
                "mrad",
                format!(
                    "joint {} lags or leads its command by up to {:.2} +- {:.2} mrad, {} (sin {:+.6}, cos {:+.6} rad)",
                    a.joint,
                    amp * 1e3,
                    sig * 1e3,
                    per,
                    s,
                    c
                ),
            ));
        }
    }
}

/// A sliding joint's scale error (ppm) and higher-order terms (um at 100 mm), eq. (13).
fn polynomial_findings(joint: usize, c: &[f64], sigma: &[f64], out: &mut Vec<Finding>) {
    for (i, ck) in c.iter().enumerate() {
        let s = sigma.get(i).copied().unwrap_or(f64::NAN);
        if i == 0 {
            out.push(finding(
                format!("joint {joint} scale error"),
                ck * 1e6,
                s * 1e6,
                "ppm",
                format!(
                    "sliding joint {joint} travels {:.1} +- {:.1} ppm {} than commanded (scale error, eq. 13)",
                    (ck * 1e6).abs(),
                    s * 1e6,
                    if *ck > 0.0 { "less" } else { "more" }
                ),
            ));
        } else {
            // The term's size at 100 mm of travel, in micrometres.
            let at = 0.1f64.powi(i as i32 + 1) * 1e6;
            out.push(finding(
                format!("joint {joint} nonlinearity order {}", i + 1),
                ck * at,
                s * at,
                "um at 100 mm",
                format!(
                    "sliding joint {joint}: the order-{} term of its transmission is {:.2} +- {:.2} um at 100 mm of travel",
                    i + 1,
                    ck * at,
                    s * at
                ),
            ));
        }
    }
}

/// Each fitted coupling's parameters and residual, appended to `out`.
fn coupling_findings(cal: &Calibration, out: &mut Vec<Finding>) {
    for c in &cal.couplings {
        let rms = c.residual_rms_rad * 1e3;
        let params: Vec<String> = c
            .parameter_names
            .iter()
            .zip(c.parameters.iter().zip(&c.sigma))
            .map(|(n, (p, s))| format!("{n} = {p:+.6} +- {s:.6}"))
            .collect();
        out.push(finding(
            format!("coupling {}->{}", c.from, c.to),
            rms,
            f64::NAN,
            "mrad",
            format!(
                "passive motion {}->{} fitted as {}; residual {:.3} mrad RMS",
                c.from,
                c.to,
                params.join(", "),
                rms
            ),
        ));
    }
}

/// The report of `record` as Markdown.
pub fn markdown(record: &CalibrationRecord, desc: &RobotDescription, source: &str) -> String {
    let (cal, reports) = (&record.calibration, &record.reports);
    let mut s = String::new();
    let _ = writeln!(s, "# Calibration of {}\n", markdown::text(&desc.name));
    let _ = writeln!(
        s,
        "Data: {}. Estimator: `{}` (`--estimator`).\n",
        markdown::code(source),
        cal.options.estimator.name()
    );
    s.push_str(&warnings_section(&reports.warnings));
    write_noise(&mut s, cal);
    write_outliers(&mut s, cal);
    write_scope(&mut s, cal);
    write_axes_table(&mut s, cal);
    write_sweeps(&mut s, cal, desc);
    write_rows_table(&mut s, cal, desc);
    write_tool(&mut s, cal);
    write_tool_accuracy(&mut s, reports.tool_accuracy.as_ref());
    write_findings(&mut s, cal, desc);
    write_identifiability(&mut s, cal);
    if let Some(r) = &reports.refinement {
        s += &crate::calibration::refine::markdown(r);
    }
    s
}

/// A report's section of the warnings `calibrate` gave on its results
/// ([`crate::calibration::record::Reports::warnings`]), empty without any.
pub fn warnings_section(warnings: &[String]) -> String {
    if warnings.is_empty() {
        return String::new();
    }
    let mut s = String::from("## Warnings\n\n");
    for w in warnings {
        let _ = writeln!(s, "- **{w}**");
    }
    s.push('\n');
    s
}

/// The sweep points the outlier test flagged (`docs/method.md`, "Outliers"), when any was.
fn write_outliers(s: &mut String, cal: &Calibration) {
    if cal.outliers.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "## Outliers ({})\n\nSweep points beyond the outlier fence (`docs/method.md`, \"Outliers\": a point's residual over the noise of its sweep's other points, against a fence a clean file passes with 99 % probability); \"dropped\": the calibration was made without them and the other targets of their poses (`--keep-outliers` keeps them). Check each row's coordinates and commands.\n\n| file line | experiment | step | target | residual (mm) | over the noise | fence | dropped |\n|---|---|---|---|---:|---:|---:|---|",
        cal.outliers.len()
    );
    for o in &cal.outliers {
        let line = o.line.map_or_else(|| "-".to_string(), |l| l.to_string());
        let _ = writeln!(
            s,
            "| {line} | {} | {} | {} | {:.3} | {:.1} | {:.1} | {} |",
            markdown::text(&o.experiment),
            o.step,
            o.target,
            o.residual_mm,
            o.normalised_residual,
            o.fence,
            o.dropped
        );
    }
    s.push('\n');
    let of_test = |test: OutlierTest| -> Vec<String> {
        let lines = cal.outliers.iter().filter(|o| o.test == test);
        lines
            .map(|o| {
                o.line.map_or_else(
                    || format!("{} step {}", markdown::text(&o.experiment), o.step),
                    |l| l.to_string(),
                )
            })
            .collect()
    };
    let moved = of_test(OutlierTest::Moved);
    if !moved.is_empty() {
        let _ = writeln!(
            s,
            "In a sweep whose held joints wander (as measured its points lie on no one arc or line), tested on its points moved to the design pose by the calibrated model, then calibrated again without them unless kept: lines {}.\n",
            moved.join(", ")
        );
    }
    let axis_fit = of_test(OutlierTest::AxisFit);
    if !axis_fit.is_empty() {
        let _ = writeln!(
            s,
            "Named by the axis fit of a sweep whose held joints wander, which failed with them: their distance off the path the sweep's other points draw, over the noise, beyond Tukey's far-out fence of those distances (`Q3 + 3 IQR`), not the screen's: lines {}.\n",
            axis_fit.join(", ")
        );
    }
}

/// The predicted tool 1-sigma inside the spans and over the workspace, when predicted.
fn write_tool_accuracy(s: &mut String, accuracy: Option<&ToolAccuracy>) {
    let Some(a) = accuracy else { return };
    let _ = writeln!(
        s,
        "## Predicted tool accuracy
"
    );
    let _ = writeln!(
        s,
        "The calibrated model's parameter covariance through the tool Jacobian (`docs/method.md`, \"Predicted tool accuracy\"): 1-sigma of the compensated tool point and orientation at {} poses inside the spans and {} over the workspace, drawn uniformly (seed {}).\n",
        a.spans.poses, a.workspace.poses, a.seed
    );
    let _ = writeln!(
        s,
        "| poses | position RMS (mm) | position max (mm) | orientation RMS (mrad) | orientation max (mrad) |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|");
    for (name, t) in [
        ("inside the calibrated spans", &a.spans),
        ("workspace (joint limits)", &a.workspace),
    ] {
        let _ = writeln!(
            s,
            "| {name} | {:.4} | {:.4} | {:.4} | {:.4} |",
            t.position_rms_mm, t.position_max_mm, t.orientation_rms_mrad, t.orientation_max_mrad
        );
    }
    let _ = writeln!(s, "\nMap over reach and height: `tool_sigma_map.png` / `.svg`.\n");
}

/// The noise estimated from the residuals, the noise used, and a contradiction if any.
fn write_noise(s: &mut String, cal: &Calibration) {
    let Some(n) = &cal.noise else { return };
    let _ = writeln!(s, "## Noise\n");
    match &n.estimate {
        Some(e) => {
            let _ = writeln!(
                s,
                "Estimated from the residuals of {} axis fits ({} degrees of freedom): {:.4} mm 3-D RMS, {:.0} % interval {:.4} - {:.4} mm{}.",
                e.fits,
                e.dof,
                e.rms_3d_mm,
                e.confidence * 100.0,
                e.interval.low_mm,
                e.interval.high_mm,
                if e.jitter_share > 0.0 {
                    format!(
                        " (the assumed joint repeatability explains {:.0} % of the squared residuals, subtracted)",
                        e.jitter_share * 100.0
                    )
                } else {
                    String::new()
                }
            );
        }
        None => {
            let _ = writeln!(s, "Not estimated (the paper's estimator reports no residual moments).");
        }
    }
    let _ = writeln!(
        s,
        "\nThe fits are weighted with {:.4} mm ({}).",
        n.used_rms_3d_mm, n.source
    );
    if n.given_contradicted {
        let _ = writeln!(
            s,
            "\n**The residuals contradict the given noise of {:.4} mm** (chi-square test, p = {:.2e}): the reported uncertainties are too {}; calibrate without `--noise-mm` to use the estimate.",
            n.used_rms_3d_mm,
            n.given_p_value.unwrap_or(f64::NAN),
            if n.estimate.as_ref().is_some_and(|e| e.rms_3d_mm > n.used_rms_3d_mm) {
                "small"
            } else {
                "large"
            }
        );
    }
    let _ = writeln!(s);
}

/// The base-frame rule, joints not calibrated, the held-joint passes.
fn write_scope(s: &mut String, cal: &Calibration) {
    if let Some(b) = &cal.base_rule {
        let _ = writeln!(s, "Base frame: {}.\n", b.text);
    }
    if !cal.not_calibrated.is_empty() {
        let list: Vec<String> = cal.not_calibrated.iter().map(|j| j.to_string()).collect();
        let _ = writeln!(
            s,
            "Not calibrated (no axis experiment): joint(s) {}; their rows, transmissions and couplings are the nominal ones.\n",
            list.join(", ")
        );
    }
    if cal.held_passes > 1 {
        let _ = writeln!(
            s,
            "Held joints as recorded: the recorded values of the held joints (and sweeps at other poses) were modelled in {} fit-and-correct passes.\n",
            cal.held_passes
        );
    }
}

/// Per jointly fitted axis with several sweeps (or recorded wander): what differs.
fn write_sweeps(s: &mut String, cal: &Calibration, desc: &RobotDescription) {
    let rows: Vec<(usize, &super::SweepReport)> = cal
        .axes
        .iter()
        .flat_map(|a| a.sweeps.iter().map(move |w| (a.joint, w)))
        .filter(|(j, w)| {
            cal.axes.iter().filter(|a| a.joint == *j).count() > 0
                && (w.held_wander > 0.0 || w.own_axis_angle_mrad.is_some())
        })
        .collect();
    if rows.is_empty() {
        return;
    }
    let _ = writeln!(s, "\n## Sweeps\n");
    let _ = writeln!(
        s,
        "| joint | experiment | points | residual RMS (mm) | held joints (file units) | held wander | own axis vs joint axis |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|");
    for (j, w) in rows {
        let held: Vec<String> = w
            .held_offsets
            .iter()
            .map(|h| format!("{}: {:.4}", h.joint, h.offset_deg_or_mm))
            .collect();
        let own = match (w.own_axis_angle_mrad, w.own_axis_offset_mm) {
            (Some(a), Some(o)) => format!("{a:.3} mrad, {o:.3} mm"),
            (Some(a), None) => format!("{a:.3} mrad"),
            _ => "-".into(),
        };
        let unit = if desc
            .joints
            .iter()
            .any(|x| x.kind == crate::kinematics::JointKind::Prismatic)
        {
            "deg/mm"
        } else {
            "deg"
        };
        let _ = writeln!(
            s,
            "| {j} | {} | {} | {:.4} | {} | {:.4} {unit} | {own} |",
            markdown::text(&w.experiment),
            w.points,
            w.residual_rms_mm,
            held.join(", "),
            w.held_wander
        );
    }
}

/// `residuals.csv`: one row per observed point of the axis fits (`docs/formats.md#residuals-csv`).
pub fn residuals_csv(cal: &Calibration) -> String {
    let rows = cal.residuals.iter().map(|r| {
        let [a, b, c] = r.components_mm.map(|v| format!("{v:.6}"));
        let mut row = vec![
            r.experiment.clone(),
            r.joint.to_string(),
            r.step.to_string(),
            r.target.to_string(),
        ];
        if r.sliding {
            row.extend(["sliding".into(), String::new(), String::new(), String::new(), a, b, c]);
        } else {
            row.extend(["rotary".into(), a, b, c, String::new(), String::new(), String::new()]);
        }
        row
    });
    crate::csv_lines::table_text(&RESIDUALS_COLUMNS, rows)
}

/// The columns of `residuals.csv`, in order.
const RESIDUALS_COLUMNS: [&str; 11] = [
    "experiment",
    "moved_joint",
    "step",
    "target",
    "kind",
    "radial_mm",
    "tangential_mm",
    "axial_mm",
    "across_u_mm",
    "across_v_mm",
    "along_mm",
];

/// Reads `residuals.csv` as [`residuals_csv`] writes it; an error names the 1-based line and
/// the column.
pub fn read_residuals_csv(text: &str) -> Result<Vec<PointResidual>, String> {
    let mut reader = csv::ReaderBuilder::new().has_headers(true).from_reader(text.as_bytes());
    let header = reader.headers().map_err(|e| format!("line 1: {e}"))?.clone();
    let column = |name: &str| {
        header.iter().position(|h| h == name).ok_or_else(|| {
            // `axiscal validate` writes a residuals.csv of its own layout (predicted points).
            let foreign = header.iter().any(|h| h == "predicted_x_mm");
            let whose = if foreign {
                ": this residuals.csv has the layout `axiscal validate` writes (its predicted points), not the \
                     axis fits' residuals `axiscal calibrate` writes beside calibration.json; calibrate again into \
                     this folder to restore it (and give validate another --out)"
            } else {
                ": not the axis fits' residuals `axiscal calibrate` writes beside calibration.json"
            };
            format!("line 1: no column `{name}`{whose}")
        })
    };
    let at: Vec<usize> = RESIDUALS_COLUMNS.iter().map(|n| column(n)).collect::<Result<_, _>>()?;
    let mut out = Vec::new();
    for (i, record) in reader.records().enumerate() {
        let line = i + 2;
        let record = record.map_err(|e| format!("line {line}: {e}"))?;
        let cell = |k: usize| record.get(at[k]).unwrap_or("");
        let parse = |k: usize| -> Result<f64, String> {
            let v: f64 = cell(k).parse().map_err(|_| {
                format!(
                    "line {line}: column `{}`: {:?} is not a number",
                    RESIDUALS_COLUMNS[k],
                    cell(k)
                )
            })?;
            if v.is_finite() {
                Ok(v)
            } else {
                Err(format!("line {line}: column `{}`: not finite", RESIDUALS_COLUMNS[k]))
            }
        };
        let integer = |k: usize| -> Result<usize, String> {
            cell(k).parse().map_err(|_| {
                format!(
                    "line {line}: column `{}`: {:?} is not a count",
                    RESIDUALS_COLUMNS[k],
                    cell(k)
                )
            })
        };
        let sliding = match cell(4) {
            "rotary" => false,
            "sliding" => true,
            other => {
                return Err(format!(
                    "line {line}: column `kind`: {other:?} is neither `rotary` nor `sliding`"
                ));
            }
        };
        let first = if sliding { 8 } else { 5 };
        out.push(PointResidual {
            experiment: cell(0).to_string(),
            joint: integer(1)?,
            step: integer(2)?,
            target: integer(3)?,
            components_mm: [parse(first)?, parse(first + 1)?, parse(first + 2)?],
            sliding,
        });
    }
    Ok(out)
}

/// The table of the fitted axes (instrument frame).
fn write_axes_table(s: &mut String, cal: &Calibration) {
    let _ = writeln!(s, "## Axes (instrument frame)\n");
    let _ = writeln!(
        s,
        "| joint | experiment | points | span (deg or mm) | point (mm) | direction | dir 1-sigma (mrad) | pos 1-sigma (mm) | residual RMS (mm) |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|");
    for a in &cal.axes {
        // A sliding axis has a direction only (eq. 9): no position, so no position sigma.
        let unit = a.span.unit();
        let position_sigma = match a.kind {
            JointKind::Prismatic => "- (sliding)".to_owned(),
            JointKind::Revolute if a.position_sigma.major_mm.is_nan() => "- (none)".to_owned(),
            JointKind::Revolute => format!("{:.3}", a.position_sigma.major_mm),
        };
        // The paper's estimator gives the line no covariance.
        let direction_sigma = match a.direction_sigma.major_rad * 1e3 {
            x if x.is_nan() => "- (none)".to_owned(),
            x => format!("{x:.3}"),
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.1} {unit} | ({:.2}, {:.2}, {:.2}) | ({:.6}, {:.6}, {:.6}) | {direction_sigma} | {position_sigma} | {:.3} |",
            a.joint,
            markdown::text(&a.experiment),
            a.points,
            a.span.value(),
            a.point_mm[0],
            a.point_mm[1],
            a.point_mm[2],
            a.direction[0],
            a.direction[1],
            a.direction[2],
            a.residual_rms_mm
        );
    }
}

/// The table of the calibrated phi-model rows (Table 2 form) with the nominal ones.
fn write_rows_table(s: &mut String, cal: &Calibration, desc: &RobotDescription) {
    let _ = writeln!(s, "\n## Phi-model parameters (Table 2 form)\n");
    let _ = writeln!(
        s,
        "| row | nominal a, b (m); alpha, beta (deg) | calibrated a (m) | b (m) | alpha (deg) | beta (deg) |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for (k, ((r, n), sg)) in cal.robot.rows.iter().zip(&desc.rows).zip(row_sigmas(cal)).enumerate() {
        let _ = writeln!(
            s,
            "| {} | {:.6}, {:.6}; {:.4}, {:.4} | {:.5}{} | {:.5}{} | {:.4}{} | {:.4}{} |",
            k + 1,
            n.a_m,
            n.b_m,
            n.alpha_deg,
            n.beta_deg,
            r.a_m,
            pm(sg.a_mm * 1e-3, 5),
            r.b_m,
            pm(sg.b_mm * 1e-3, 5),
            r.alpha_deg,
            pm(sg.alpha_deg, 4),
            r.beta_deg,
            pm(sg.beta_deg, 4)
        );
    }
}

/// Where the tool frame comes from.
fn write_tool(s: &mut String, cal: &Calibration) {
    if let Some(t) = &cal.tool {
        let _ = writeln!(
            s,
            "\nTool frame from the three tool targets of {} step {} (fit RMS {:.3} mm).",
            markdown::code(&t.experiment),
            t.step,
            t.fit_rms_mm
        );
        if let Some(g) = &t.sigma {
            let _ = writeln!(
                s,
                "Its 1-sigma in its own axes (propagated; includes the last joint's zero offset, which it absorbs): x {:.3}, y {:.3}, z {:.3} mm; about x {:.3}, y {:.3}, z {:.3} mrad.",
                g.x_mm, g.y_mm, g.z_mm, g.rx_mrad, g.ry_mrad, g.rz_mrad
            );
        }
    } else {
        let _ = writeln!(
            s,
            "\nNo tool observation at the reference pose (or no tool targets in the description): the tool frame is the nominal one, and so is the tool's place along any axis direction the axes do not fix."
        );
    }
}

/// The findings, resolved by the data or not.
fn write_findings(s: &mut String, cal: &Calibration, desc: &RobotDescription) {
    let all = findings(cal, desc);
    let sections: [(String, Vec<&Finding>); 3] = [
        (
            format!("Findings (resolved by the data: > {SIGNIFICANT_SIGMAS} sigma)"),
            all.iter().filter(|f| f.significant).collect(),
        ),
        (
            format!("Not resolved by the data (< {SIGNIFICANT_SIGMAS} sigma)"),
            all.iter().filter(|f| !f.significant && has_sigma(f.sigma)).collect(),
        ),
        (
            "No uncertainty reported (not tested against the data)".to_owned(),
            all.iter().filter(|f| !has_sigma(f.sigma)).collect(),
        ),
    ];
    for (title, items) in sections {
        let _ = writeln!(s, "\n## {title}\n");
        if items.is_empty() {
            let _ = writeln!(s, "None.");
        }
        for f in items {
            let _ = writeln!(s, "- {}", f.text);
        }
    }
}

/// Each axis fit's condition number and identifiability notes.
fn write_identifiability(s: &mut String, cal: &Calibration) {
    let _ = writeln!(s, "\n## Identifiability\n");
    for a in &cal.axes {
        if a.condition_number.is_nan() {
            let _ = writeln!(
                s,
                "- joint {}: condition number not computed (the paper's estimator)",
                a.joint
            );
        } else {
            let _ = writeln!(s, "- joint {}: condition number {:.3e}", a.joint, a.condition_number);
        }
        for note in &a.identifiability {
            let _ = writeln!(s, "  - {note}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn significant_only_from_a_real_sigma() {
        let f = |value: f64, sigma: f64| finding("x".into(), value, sigma, "mm", String::new()).significant;
        let threshold = SIGNIFICANT_SIGMAS;
        assert!(f(1.01 * threshold, 1.0));
        assert!(!f(0.99 * threshold, 1.0));
        // No sigma, or a degenerate one: never significant, however large the value.
        assert!(!f(1e6, f64::NAN));
        assert!(!f(1e6, 0.0));
        assert!(!f(1e6, f64::INFINITY));
    }

    /// What the writer writes the reader reads (to the written 6 decimals), a quoted
    /// experiment name included; a bad cell is named by line and column.
    #[test]
    fn residuals_csv_reads_back() {
        let residuals = vec![
            PointResidual {
                experiment: "axis,1".into(),
                joint: 1,
                step: 3,
                target: 0,
                components_mm: [0.123456, -0.5, 1e-3],
                sliding: false,
            },
            PointResidual {
                experiment: "slide".into(),
                joint: 3,
                step: 0,
                target: 1,
                components_mm: [-0.25, 0.0, 2.5],
                sliding: true,
            },
        ];
        let mut text = String::from(
            "experiment,moved_joint,step,target,kind,radial_mm,tangential_mm,axial_mm,across_u_mm,across_v_mm,along_mm\n",
        );
        text.push_str("\"axis,1\",1,3,0,rotary,0.123456,-0.500000,0.001000,,,\nslide,3,0,1,sliding,,,,-0.250000,0.000000,2.500000\n");
        assert_eq!(read_residuals_csv(&text).unwrap(), residuals);
        let bad = text.replace("-0.500000", "x");
        assert_eq!(
            read_residuals_csv(&bad).unwrap_err(),
            "line 2: column `tangential_mm`: \"x\" is not a number"
        );
    }
}
