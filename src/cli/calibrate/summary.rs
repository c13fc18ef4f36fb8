//! The console summary of an axis-experiment calibration: the axes table, the noise, what
//! was not calibrated, the predicted tool accuracy.

use crate::cli::printer::Printer;
use axiscal::calibration::procedure::{AxisEstimator, Calibration, RawReadingDeviation};
use axiscal::calibration::tool_accuracy::ToolAccuracy;
use axiscal::robot::RobotDescription;

/// The console summary of an independent-axis calibration and its predicted tool accuracy.
pub(super) fn print_axes(
    (cal, accuracy): (&Calibration, Option<&ToolAccuracy>),
    desc: &RobotDescription,
    source: &str,
    printer: Printer,
) {
    say!(
        printer,
        "calibrated {} from {} ({} axes)",
        desc.name,
        source,
        cal.axes.len()
    );
    print_scope(cal, desc, printer);
    say!(
        printer,
        "  joint  points  span (deg|mm)  residual RMS (mm)  direction 1-sigma (mrad)"
    );
    for a in &cal.axes {
        let unit = a.span.unit();
        let sigma = a.direction_sigma.major_rad * 1e3;
        // The paper's estimator gives its line no covariance: said, not printed as NaN.
        let sigma = if sigma.is_finite() {
            format!("{sigma:.4}")
        } else {
            "none (paper)".to_owned()
        };
        say!(
            printer,
            "  {:>5}  {:>6}  {:>9.1} {:<3}  {:>17.4}  {:>24}",
            a.joint,
            a.points,
            a.span.value(),
            unit,
            a.residual_rms_mm,
            sigma
        );
    }
    print_tool_accuracy(accuracy, printer);
    if cal.options.estimator == AxisEstimator::Paper {
        say!(
            printer,
            "  no sigmas: the paper's estimator (eqs. 1-8) gives its axes no covariance, so no row, zero-offset or tool \
             sigma and no predicted tool accuracy is computed (null or absent in calibration.json); `--estimator ml` gives them"
        );
    }
}

/// The predicted tool 1-sigma line, when there is one.
pub(in crate::cli) fn print_tool_accuracy(accuracy: Option<&ToolAccuracy>, printer: Printer) {
    if let Some(a) = accuracy {
        say!(
            printer,
            "  predicted tool 1-sigma: inside the spans RMS {:.3} mm / {:.3} mrad (max {:.3} mm), workspace RMS {:.3} mm / {:.3} mrad (max {:.3} mm)",
            a.spans.position_rms_mm,
            a.spans.orientation_rms_mrad,
            a.spans.position_max_mm,
            a.workspace.position_rms_mm,
            a.workspace.orientation_rms_mrad,
            a.workspace.position_max_mm
        );
    }
}

/// A note where the sweeps of the joints fitted from several miss one another beyond the noise
/// their own fits show ([`axiscal::calibration::procedure::sweeps_agreement`] below
/// [`axiscal::calibration::noise::NOISE_TEST_LEVEL`]): the noise estimate
/// then holds the held joints' correction's model error.
pub(super) fn print_sweeps_disagree(cal: &axiscal::calibration::procedure::Calibration) {
    use axiscal::calibration::noise::NOISE_TEST_LEVEL;
    use axiscal::calibration::procedure::sweeps_agreement;
    let Some(a) = sweeps_agreement(cal).filter(|a| a.p_value < NOISE_TEST_LEVEL) else {
        return;
    };
    let joints: Vec<String> = a.joints.iter().map(ToString::to_string).collect();
    eprintln!(
        "note: the sweeps of joint{} {} miss one another, once the held joints' correction has moved them to one pose, by \
         more than the noise each sweep's own fit shows: the joint fits' residuals are {:.4} mm RMS per coordinate \
         against {:.4} mm in the sweeps' own fits (F = {:.2} on {} and {} dof, p = {:.1e}); the calibrated model that \
         corrects them is that uncertain (longer sweeps locate its axes better), and the noise estimate, every \
         sigma and the coordinate-scale test count that model error as noise",
        if joints.len() == 1 { "" } else { "s" },
        joints.join(", "),
        a.rms_mm[1],
        a.rms_mm[0],
        a.variance_ratio,
        a.dof.0,
        a.dof.1,
        a.p_value
    );
}

/// The noise (estimated, used, contradicted), joints not calibrated, the base-frame rule.
pub(super) fn print_scope(
    cal: &axiscal::calibration::procedure::Calibration,
    desc: &RobotDescription,
    printer: Printer,
) {
    if let Some(n) = &cal.noise {
        if let Some(e) = &n.estimate {
            say!(
                printer,
                "  noise from the residuals: {:.4} mm 3-D RMS ({:.0} % interval {:.4}-{:.4} mm, {} dof); fits weighted with {:.4} mm ({})",
                e.rms_3d_mm,
                e.confidence * 100.0,
                e.interval.low_mm,
                e.interval.high_mm,
                e.dof,
                n.used_rms_3d_mm,
                n.source
            );
            print_sweeps_disagree(cal);
        }
        if n.source == "default" && n.estimate.is_some() {
            let (joint, sigma) = desc
                .joints
                .iter()
                .enumerate()
                .map(|(k, j)| (k + 1, j.repeatability_sigma))
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap_or((0, 0.0));
            eprintln!(
                "warning: the residuals give no noise estimate above 0: the joints' repeatability (the description's repeatability_sigma, joint {joint}: {sigma} rad or m) explains all of their scatter; the fits keep the default {:.4} mm and every sigma follows the repeatability: check repeatability_sigma (radians for a turning joint, metres for a sliding one) or give --repeatability-rad",
                n.used_rms_3d_mm
            );
        }
        if n.given_contradicted {
            say!(
                printer,
                "  WARNING: the residuals contradict --noise-mm {:.4} (chi-square p = {:.2e}); see report.md",
                n.used_rms_3d_mm,
                n.given_p_value.unwrap_or(f64::NAN)
            );
        }
    }
    if !cal.not_calibrated.is_empty() {
        eprintln!(
            "warning: joints {:?} not calibrated (no axis experiment: kept nominal): their errors are in no predicted uncertainty; sweep them, or `axiscal validate` tests the model",
            cal.not_calibrated
        );
    }
    if let Some(b) = &cal.base_rule {
        say!(printer, "  base frame: {}", b.text);
    }
    if cal.tool.is_none() && !desc.tool.targets_mm.is_empty() {
        say!(
            printer,
            "  tool frame: nominal (no pose at the reference commands sees all three tool targets): its error is in no predicted uncertainty; `axiscal validate` tests it"
        );
    }
}

/// The URDF-fed-raw-readings line printed after the axes table.
pub(super) fn deviation_line(d: &RawReadingDeviation) -> String {
    format!(
        "  URDF fed raw controller readings: tool off by up to {:.3} mm, {:.3} mrad over {} poses (use joint_map.csv / `axiscal joints`)",
        d.max_position_mm, d.max_orientation_mrad, d.poses
    )
}
