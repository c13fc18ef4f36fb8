//! The magnitude draws of a blind case's effect: log-uniform over ranges spanning each
//! effect's detectable size on the paper campaign (`docs/diagnosis.md`, "Blind check").

use super::JointZeroDrift;
use crate::physics::{
    ApproachSource, AxisWobble, BacklashEffect, ComplianceEffect, GearHarmonic, HarmonicPeriod, InstrumentScale,
    PayloadEffect, ThermalEffect,
};
use crate::robot::RobotDescription;
use crate::sim::{Effects, LinkMassEntry};
use rand::{Rng, RngExt};

/// Log-uniform draw in `[lo, hi)`.
pub(super) fn log_uniform<R: Rng + ?Sized>(rng: &mut R, lo: f64, hi: f64) -> f64 {
    (rng.random_range(lo.ln()..hi.ln())).exp()
}

/// A wobble of a random joint with a log-uniform amplitude in `amplitude_rad`, its shape drawn
/// from the family: order 1 about a fixed direction (a swash, `A sin(theta + phase)` about a
/// direction fixed in the joint's frame; a rotating order-1 tilt is a constant axis error the
/// calibration absorbs), or order 2 rotating or about a fixed direction.
pub(super) fn draw_wobble<R: Rng + ?Sized>(
    rng: &mut R,
    dof: usize,
    amplitude_rad: [f64; 2],
    phase_rad: f64,
) -> AxisWobble {
    let joint = rng.random_range(1..=dof);
    let amplitude_rad = log_uniform(rng, amplitude_rad[0], amplitude_rad[1]);
    let order = if rng.random_bool(0.5) { 1 } else { 2 };
    let fixed = order == 1 || rng.random_bool(0.5);
    let direction = rng.random_range(0.0..std::f64::consts::TAU);
    AxisWobble {
        joint,
        amplitude_rad,
        phase_rad,
        order,
        fixed_direction_rad: fixed.then_some(direction),
    }
}

/// The real links' masses, each the description's scaled by a log-uniform factor in 0.6-1.6
/// with its centre of mass moved by up to 50 mm per axis, and a payload whose centre of mass
/// sits up to 100 mm off the tool axis and 0-200 mm along it, into `e`: the truth's mass model
/// is not the description's.
pub(super) fn draw_masses<R: Rng + ?Sized>(rng: &mut R, desc: &RobotDescription, e: &mut Effects) {
    e.link_masses = desc
        .joints
        .iter()
        .map(|j| LinkMassEntry {
            mass_kg: j.mass_kg * log_uniform(rng, 0.6, 1.6),
            com_mm: j.com_mm.map(|c| c + rng.random_range(-50.0..=50.0)),
        })
        .collect();
    e.payload = Some(PayloadEffect {
        com_in_tool_mm: [
            rng.random_range(-100.0..=100.0),
            rng.random_range(-100.0..=100.0),
            rng.random_range(0.0..=200.0),
        ],
    });
}

/// The joint (if any), magnitude and unit of a drawn effect.
pub(super) type DrawnMagnitude = (Option<usize>, f64, &'static str);

/// A compliant joint 2 or 3 (the others stiff) with a log-uniform stiffness, into `e`.
///
/// `strong` (the two-effect cases): only the compliant third of each range, from about the
/// detectable stiffness down.
pub(super) fn draw_compliance<R: Rng + ?Sized>(
    rng: &mut R,
    desc: &RobotDescription,
    strong: bool,
    e: &mut Effects,
) -> DrawnMagnitude {
    let dof = desc.dof();
    // Joints 2 and 3 carry the gravity load of the arm.
    let joint = rng.random_range(2..=3);
    // The refit absorbs the part of a sag that follows the joint angles alone; the
    // validation payloads (`BlindOptions::payload_max_kg`) leave the rest. On this
    // campaign joint 2's detectable stiffness is about 3e4 N m/rad, joint 3's about
    // 2e5 (development suite, seed 7): draws from about a third of it to ten times.
    let k = match (joint, strong) {
        (2, false) => log_uniform(rng, 8.0e3, 1.0e5),
        (2, true) => log_uniform(rng, 8.0e3, 3.0e4),
        (_, false) => log_uniform(rng, 2.0e4, 6.0e5),
        (_, true) => log_uniform(rng, 2.0e4, 2.0e5),
    };
    let mut stiffness = vec![1e12; dof];
    stiffness[joint - 1] = k;
    let mut compliance = ComplianceEffect::new(stiffness, crate::diagnosis::GRAVITY_M_S2);
    draw_load_path(rng, desc, joint, &mut compliance);
    e.compliance = Some(compliance);
    (Some(joint), k, "N m/rad")
}

/// How the load reaches a compliant joint 2, into `compliance`: where it drives a mechanism
/// (the paper arm's four-bar, [`crate::diagnosis::drives_mechanism`]) through it (a third of
/// the cases), serially (the actuator carries the forearm's own moment, a third) or mixed
/// (the mechanism carries 20-80 %), else serially (no load reflected); and in half the cases
/// a spring balancer taking 50-90 % of the upper arm's own torque.
fn draw_load_path<R: Rng + ?Sized>(
    rng: &mut R,
    desc: &RobotDescription,
    joint: usize,
    compliance: &mut ComplianceEffect,
) {
    if joint != 2 {
        return;
    }
    compliance.reflected_fraction = if crate::diagnosis::drives_mechanism(desc, joint) {
        match rng.random_range(0..3) {
            0 => 1.0,
            1 => 0.0,
            _ => rng.random_range(0.2..=0.8),
        }
    } else {
        0.0
    };
    if rng.random_bool(0.5) {
        let mut f = vec![0.0; compliance.stiffness_nm_per_rad.len()];
        f[joint - 1] = rng.random_range(0.5..=0.9);
        compliance.balancer_fraction = f;
    }
}

/// A backlash band of a random joint, into `e`; `strong` (the two-effect cases): only bands
/// above about the detectable one (1-3 mrad).
pub(super) fn draw_backlash<R: Rng + ?Sized>(rng: &mut R, dof: usize, strong: bool, e: &mut Effects) -> DrawnMagnitude {
    let joint = rng.random_range(1..=dof);
    let band = log_uniform(rng, if strong { 1.0e-3 } else { 1.0e-4 }, 3.0e-3);
    let mut b = vec![0.0; dof];
    b[joint - 1] = band;
    // Signed by the command's or by the actuator's direction (they differ on coupled joints).
    let direction = if rng.random_bool(0.5) {
        ApproachSource::Command
    } else {
        ApproachSource::Actuator
    };
    e.backlash = Some(BacklashEffect { band_rad: b, direction });
    (Some(joint), band, "rad (band)")
}

/// A thermal expansion coefficient (reference 20 deg C), uniform or (half the cases) per link,
/// each row's coefficient the drawn one times a factor in 0.3-1.7, into `e`.
pub(super) fn draw_thermal<R: Rng + ?Sized>(rng: &mut R, dof: usize, e: &mut Effects) -> DrawnMagnitude {
    let alpha = log_uniform(rng, 4.0e-6, 1.0e-4);
    let mut t = ThermalEffect::uniform(alpha, 20.0);
    if rng.random_bool(0.5) {
        t.alpha_per_k_rows = (1..dof).map(|_| alpha * rng.random_range(-0.7..=0.7)).collect();
    }
    e.thermal = Some(t);
    (None, alpha, "1/K")
}

/// A gear harmonic of a random joint at an order its transmission fit does not model, with
/// phase `phase` (rad), into `e`.
pub(super) fn draw_gear_harmonic<R: Rng + ?Sized>(
    rng: &mut R,
    desc: &RobotDescription,
    phase: f64,
    e: &mut Effects,
) -> DrawnMagnitude {
    let dof = desc.dof();
    let joint = rng.random_range(1..=dof);
    // An order the calibrator does not fit, up to the diagnoser's default maximum, in the
    // transmission's angle; on a geared joint half the cases in the joint's own period.
    let first = crate::diagnosis::unmodelled_harmonic_order(desc, joint);
    let top = crate::diagnosis::DEFAULT_MAX_HARMONIC_ORDER.max(first);
    let (order, period) = if crate::diagnosis::is_geared(desc, joint) && rng.random_bool(0.5) {
        (rng.random_range(1..=top), HarmonicPeriod::Joint)
    } else {
        (rng.random_range(first..=top), HarmonicPeriod::Transmission)
    };
    // A gear's error spectrum falls with the order: up to 10 mrad at orders 1-2, then
    // `20 mrad / order` (at 5-9 mrad an order-5 or -6 harmonic is a 3-7 mm error that breaks
    // the axis fits themselves, not an unmodelled effect left after them).
    let a = log_uniform(rng, 3.0e-4, 1.0e-2 * (2.0 / order as f64).min(1.0));
    e.gear_harmonics.push(GearHarmonic {
        joint,
        order,
        sin_rad: a * phase.sin(),
        cos_rad: a * phase.cos(),
        period,
    });
    (Some(joint), a, "rad")
}

/// An out-of-set joint zero drift with temperature of a random joint, of random sign, into
/// `drift`.
pub(super) fn draw_zero_drift<R: Rng + ?Sized>(
    rng: &mut R,
    dof: usize,
    drift: &mut Option<JointZeroDrift>,
) -> DrawnMagnitude {
    // 0.1-3 mrad over the validation's +-10 K; detectable from about 2e-5 rad/K at
    // joint 3 to 2.4e-4 at joint 6 (development suite, seed 7).
    let joint = rng.random_range(1..=dof);
    let rate = log_uniform(rng, 1.0e-5, 3.0e-4) * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
    *drift = Some(JointZeroDrift { joint, rad_per_k: rate });
    (Some(joint), rate, "rad/K (joint zero drift)")
}

/// An instrument scale error of random sign, into `e`.
pub(super) fn draw_instrument_scale<R: Rng + ?Sized>(rng: &mut R, e: &mut Effects) -> DrawnMagnitude {
    let ppm = log_uniform(rng, 200.0, 6000.0) * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
    e.instrument_scale = Some(InstrumentScale { ppm });
    (None, ppm, "ppm")
}
