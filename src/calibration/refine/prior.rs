//! The unrefined estimate's 1-sigma of every refit parameter, from the calibration's
//! propagated sigmas (`docs/method.md`, "Uncertainty").

use super::RefitParameter;
use crate::calibration::procedure::Calibration;

/// The 1-sigma of `p` in `cal` (internal units: m, rad, coefficient); `None` where `cal`
/// reports none (the base placement, a coupling coefficient the fit held fixed, a tool frame
/// not observed) or a non-positive one.
pub fn unrefined_sigma(cal: &Calibration, p: &RefitParameter) -> Option<f64> {
    let s = match p {
        RefitParameter::RowA(r) => cal.row_sigma.get(r - 1).map(|s| s.a_mm * 1e-3),
        RefitParameter::RowB(r) => cal.row_sigma.get(r - 1).map(|s| s.b_mm * 1e-3),
        RefitParameter::RowAlpha(r) => cal.row_sigma.get(r - 1).map(|s| s.alpha_deg.to_radians()),
        RefitParameter::RowBeta(r) => cal.row_sigma.get(r - 1).map(|s| s.beta_deg.to_radians()),
        RefitParameter::ZeroOffset { joint, .. } => cal
            .zero_offset_sigma
            .iter()
            .find(|z| z.joint == *joint)
            .and_then(|z| z.sigma_rad.or(z.sigma_mm.map(|mm| mm * 1e-3))),
        RefitParameter::Coupling { joint, coefficient } => {
            cal.couplings.iter().find(|c| c.to == *joint).and_then(|c| {
                let i = c.parameter_names.iter().position(|n| n == coefficient)?;
                c.sigma.get(i).copied()
            })
        }
        RefitParameter::Harmonic { joint, order, cosine } => {
            let name = format!("{}{order}", if *cosine { "cos" } else { "sin" });
            cal.axes.iter().find(|a| a.joint == *joint).and_then(|a| {
                let i = a.coefficient_names.iter().position(|n| *n == name)?;
                a.coefficient_sigma.get(i).copied()
            })
        }
        RefitParameter::Target { .. }
        | RefitParameter::Base(_)
        | RefitParameter::SetupBase { .. }
        | RefitParameter::Sag { .. }
        | RefitParameter::Backlash { .. }
        | RefitParameter::Effect { .. } => None,
        RefitParameter::Tool(axis) => cal
            .tool
            .as_ref()
            .and_then(|t| t.sigma)
            .map(|f| [f.x_mm, f.y_mm, f.z_mm, f.rx_mrad, f.ry_mrad, f.rz_mrad][*axis] * 1e-3),
    };
    s.filter(|v| v.is_finite() && *v > 0.0)
}
