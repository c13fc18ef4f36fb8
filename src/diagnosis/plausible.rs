//! Physical ranges of the candidates' fitted parameters (`docs/diagnosis.md`, "Plausibility"):
//! a fit that beats noise with a value no real robot has (a 33 rad tilt) is not that effect,
//! and is not named.

use super::Candidate;
use crate::diagnosis::Parameter;

/// Largest plausible tilt of a joint axis, gear-harmonic amplitude, or joint sag under
/// gravity \[rad\] (about 6 deg): the candidates are small-angle forms, and a bearing runout,
/// transmission ripple or sag of this size is a broken or unloaded-to-buckling joint, not an
/// effect to compensate. The same bound as a calibration file's harmonics
/// ([`crate::robot::MAX_HARMONIC_AMPLITUDE_RAD`]).
pub const MAX_ANGLE_RAD: f64 = crate::robot::MAX_HARMONIC_AMPLITUDE_RAD;
/// Largest plausible backlash half band \[rad\] (a 40 mrad band; industrial gearboxes have
/// 0.1-3 mrad).
pub const MAX_HALF_BAND_RAD: f64 = 0.02;
/// Largest plausible thermal expansion coefficient \[1/K\] (steel 1.2e-5, aluminium 2.3e-5,
/// engineering plastics up to 2e-4).
pub const MAX_ALPHA_PER_K: f64 = 3e-4;
/// Most negative plausible thermal expansion coefficient of a link \[1/K\]: structural
/// materials expand when heated; the most negative coefficient of one used in arms is carbon
/// fibre composite's along the fibre, about -1e-6 (invar +1e-6, steel 1.2e-5). A fit more
/// negative than this by more than `SIGN_K_SIGMA` of its sigma imitates something else (a
/// joint zero drifting with temperature bends per-link coefficients of both signs).
pub const MIN_ALPHA_PER_K: f64 = -2e-6;
/// Largest plausible instrument scale error \[ppm\] (1 %; trackers are within 10 ppm).
pub const MAX_SCALE_PPM: f64 = 1e4;
/// Largest plausible distance of a payload's centre of mass from the tool frame's origin \[m\].
pub const MAX_PAYLOAD_OFFSET_M: f64 = 1.0;
/// Coverage factor of the sign checks: a backlash band or a compliance may not be negative by
/// more than this many of its standard deviations.
pub const SIGN_K_SIGMA: f64 = 3.0;

fn value(params: &[Parameter], name: &str) -> Option<(f64, f64)> {
    params.iter().find(|p| p.name == name).map(|p| (p.value, p.sigma))
}

fn norm(params: &[Parameter], names: &[&str]) -> f64 {
    names
        .iter()
        .filter_map(|n| value(params, n))
        .map(|(v, _)| v * v)
        .sum::<f64>()
        .sqrt()
}

fn not_negative(params: &[Parameter], name: &str, what: &str) -> Option<String> {
    let (v, s) = value(params, name)?;
    (v < -SIGN_K_SIGMA * s).then(|| format!("{what} {v:.3e} is negative by more than {SIGN_K_SIGMA} sigma ({s:.1e})"))
}

fn at_most(v: f64, limit: f64, what: &str) -> Option<String> {
    // A NaN is out of range too.
    let within = v.abs() <= limit;
    (!within).then(|| format!("{what} {v:.3e} is beyond the plausible {limit:.1e}"))
}

/// Why `candidate`'s fitted `params` are physically implausible, or `None` when they are in
/// range. `largest_sag_rad` is a compliance member's largest sag of its joint over the poses
/// ([`super::Predictor::largest_sag_rad`]).
pub fn implausible(candidate: Candidate, params: &[Parameter], largest_sag_rad: Option<f64>) -> Option<String> {
    match candidate {
        Candidate::AxisWobble { .. } => at_most(
            norm(
                params,
                &[
                    "tilt_x_rad",
                    "tilt_y_rad",
                    "tilt_cos_x_rad",
                    "tilt_cos_y_rad",
                    "tilt_sin_x_rad",
                    "tilt_sin_y_rad",
                ],
            ),
            MAX_ANGLE_RAD,
            "tilt amplitude [rad]",
        ),
        Candidate::GearHarmonic { .. } => at_most(
            norm(params, &["sin_rad", "cos_rad"]),
            MAX_ANGLE_RAD,
            "harmonic amplitude [rad]",
        ),
        Candidate::Backlash { .. } => not_negative(params, "half_band_rad", "half band [rad]")
            .or_else(|| at_most(value(params, "half_band_rad")?.0, MAX_HALF_BAND_RAD, "half band [rad]")),
        Candidate::ThermalExpansion { .. } => params.iter().find_map(|p| {
            let what = format!("{} [1/K]", p.name);
            let contracts = p.value < MIN_ALPHA_PER_K - SIGN_K_SIGMA * p.sigma;
            contracts
                .then(|| {
                    format!(
                        "{what} {:.3e} is below {MIN_ALPHA_PER_K:.0e} by more than {SIGN_K_SIGMA} sigma ({:.1e}): links do \
                         not shrink when heated",
                        p.value, p.sigma
                    )
                })
                .or_else(|| at_most(p.value, MAX_ALPHA_PER_K, &what))
        }),
        Candidate::InstrumentScale => at_most(value(params, "scale_ppm")?.0, MAX_SCALE_PPM, "scale [ppm]"),
        Candidate::JointCompliance { .. } => compliance(params, largest_sag_rad),
    }
}

fn compliance(params: &[Parameter], largest_sag_rad: Option<f64>) -> Option<String> {
    // A spring does not lift a load, and a mechanism carries a part of its load, not a
    // negative one.
    let sign = [
        ("compliance_rad_per_nm", "compliance [rad/(N m)]"),
        ("compliance_payload_rad_per_nm", "payload compliance [rad/(N m)]"),
        (
            "compliance_reflected_rad_per_nm",
            "reflected load's compliance [rad/(N m)]",
        ),
        (
            "compliance_reflected_payload_rad_per_nm",
            "reflected payload's compliance [rad/(N m)]",
        ),
    ]
    .iter()
    .find_map(|(name, what)| not_negative(params, name, what));
    if sign.is_some() {
        return sign;
    }
    if let Some(s) = largest_sag_rad
        && let Some(why) = at_most(s, MAX_ANGLE_RAD, "largest sag [rad]")
    {
        return Some(why);
    }
    // The payload offset's products over the payload's compliance.
    let c = value(params, "compliance_rad_per_nm")
        .or_else(|| value(params, "compliance_payload_rad_per_nm"))
        .map(|(v, _)| v)?;
    let offset = norm(
        params,
        &[
            "compliance_payload_offset_x_m_rad_per_nm",
            "compliance_payload_offset_y_m_rad_per_nm",
            "compliance_payload_offset_z_m_rad_per_nm",
        ],
    );
    (c > 0.0)
        .then(|| at_most(offset / c, MAX_PAYLOAD_OFFSET_M, "payload offset [m]"))
        .flatten()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnosis::TiltShape;

    fn p(name: &str, value: f64, sigma: f64) -> Parameter {
        Parameter {
            name: name.into(),
            value,
            sigma,
        }
    }

    #[test]
    fn a_33_rad_tilt_is_not_a_wobble_and_a_2_mrad_one_is() {
        let w = Candidate::AxisWobble {
            joint: 1,
            order: 1,
            shape: TiltShape::General,
        };
        let big = [p("tilt_cos_x_rad", 33.0, 1.0), p("tilt_sin_y_rad", 0.1, 1.0)];
        assert!(implausible(w, &big, None).is_some());
        let small = [p("tilt_cos_x_rad", 2e-3, 1e-4), p("tilt_sin_y_rad", -1e-3, 1e-4)];
        assert_eq!(implausible(w, &small, None), None);
    }

    #[test]
    fn a_negative_band_or_compliance_beyond_its_sigma_is_implausible() {
        let b = Candidate::Backlash {
            joint: 2,
            direction: crate::physics::ApproachSource::Command,
        };
        assert!(implausible(b, &[p("half_band_rad", -1e-3, 1e-4)], None).is_some());
        // Within its noise of zero: in range.
        assert_eq!(implausible(b, &[p("half_band_rad", -1e-4, 1e-4)], None), None);
        let c = Candidate::JointCompliance {
            joint: 2,
            spring: crate::diagnosis::SpringSite::Actuator,
            masses: crate::diagnosis::MassModel::Description,
            load: crate::diagnosis::LoadPath::Mechanism,
        };
        assert!(implausible(c, &[p("compliance_rad_per_nm", -1e-5, 1e-6)], Some(0.01)).is_some());
        assert!(implausible(c, &[p("compliance_rad_per_nm", 1e-4, 1e-6)], Some(0.3)).is_some());
        assert_eq!(
            implausible(c, &[p("compliance_rad_per_nm", 1e-4, 1e-6)], Some(0.03)),
            None
        );
    }

    #[test]
    fn a_link_that_shrinks_when_heated_beyond_its_sigma_is_implausible() {
        let t = Candidate::ThermalExpansion {
            links: crate::diagnosis::ThermalLinks::PerLink,
        };
        let steel = [p("alpha_row1_per_k", 1.2e-5, 1e-6), p("alpha_row2_per_k", 1.1e-5, 1e-6)];
        assert_eq!(implausible(t, &steel, None), None);
        // Carbon fibre, and a negative value within its noise of the bound: in range.
        assert_eq!(implausible(t, &[p("alpha_row1_per_k", -1e-6, 1e-6)], None), None);
        assert_eq!(implausible(t, &[p("alpha_row1_per_k", -6e-6, 2e-6)], None), None);
        let shrinking = [p("alpha_row1_per_k", 1.2e-5, 1e-6), p("alpha_row2_per_k", -3e-5, 2e-6)];
        assert!(implausible(t, &shrinking, None).is_some());
    }
}
