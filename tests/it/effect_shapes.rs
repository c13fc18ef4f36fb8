//! The shapes the blind generator draws besides each effect's first form: a backlash signed by
//! the actuator's direction, a harmonic periodic in a geared joint's own angle, a per-link
//! thermal expansion and the real links' masses unlike the description's. Each is checked
//! against an independent evaluation of its definition.

use crate::common;

use axiscal::physics::{ApproachSource, BacklashEffect, ComplianceEffect, GearHarmonic, HarmonicPeriod, ThermalEffect};
use axiscal::plan::PoseConditions;
use axiscal::robot::{Controller, RobotDescription, RobotModel};
use axiscal::sim::{AnalyticArm, ArmExecutor, Effects, JointDriver, LinkMassEntry, RapierArm, RapierArmOptions};
use nalgebra::Point3;
use rand::SeedableRng;
use rand::rngs::ChaCha12Rng;

fn truth() -> (RobotDescription, RobotModel) {
    (RobotDescription::asea_irb6l(), common::paper_robot_without_jitter())
}

/// The active displacements of `cmds` executed in turn by a driver with `effects`.
fn active_after(effects: &Effects, cmds: &[[f64; 6]]) -> Vec<f64> {
    let (desc, t) = truth();
    let mut driver = JointDriver::new(&t, Controller::from_description(&desc), effects);
    let mut rng = ChaCha12Rng::seed_from_u64(1);
    let mut last = Vec::new();
    for c in cmds {
        last = driver.drive(c, &mut rng).expect("drives").active;
    }
    last
}

/// Joint 3 is driven passively by joint 2 (nominal slope -1), so its actuator command is
/// `u_3 = cmd_3 + u_2`: raising `cmd_2` by 0.2 rad while lowering `cmd_3` by 0.05 turns actuator 3
/// forwards (`+0.15`) while its command goes backwards. A backlash signed by the command puts the
/// joint half a band ahead of the band-free joint, one signed by the actuator half a band behind.
#[test]
fn backlash_signed_by_the_actuator_differs_from_the_command_on_a_coupled_joint() {
    let band = 2e-3;
    let cmds = [[0.1, 0.0, 0.0, 0.2, -0.3, 0.5], [0.1, 0.2, -0.05, 0.2, -0.3, 0.5]];
    let free = active_after(&Effects::default(), &cmds);
    for (direction, sign) in [(ApproachSource::Command, 1.0), (ApproachSource::Actuator, -1.0)] {
        let mut band_rad = vec![0.0; 6];
        band_rad[2] = band;
        let effects = Effects {
            backlash: Some(BacklashEffect { band_rad, direction }),
            ..Effects::default()
        };
        let lagged = active_after(&effects, &cmds);
        // Half a band: the lag is exact (one subtraction).
        assert!(
            (lagged[2] - free[2] - sign * band / 2.0).abs() < 1e-15,
            "{direction:?}: {} vs {}",
            lagged[2] - free[2],
            sign * band / 2.0
        );
        for k in [0, 1, 3, 4, 5] {
            assert_eq!(lagged[k], free[k], "joint {} moved", k + 1);
        }
    }
}

/// A joint-period harmonic on the geared joint 5 adds `s sin(n t) + c cos(n t)` to its active
/// displacement `t` (not periodic in the gear angle `t / N`, as a transmission-period term).
#[test]
fn a_joint_period_harmonic_adds_to_the_geared_joints_displacement() {
    let (s, c, n) = (2e-3, -1e-3, 2);
    let cmds = [[0.1, 0.0, 0.0, 0.2, -0.7, 0.5]];
    let free = active_after(&Effects::default(), &cmds);
    let effects = Effects {
        gear_harmonics: vec![GearHarmonic {
            joint: 5,
            order: n,
            sin_rad: s,
            cos_rad: c,
            period: HarmonicPeriod::Joint,
        }],
        ..Effects::default()
    };
    let with = active_after(&effects, &cmds);
    let t = free[4];
    let expected = s * (n as f64 * t).sin() + c * (n as f64 * t).cos();
    assert!((with[4] - t - expected).abs() < 1e-15, "{} vs {expected}", with[4] - t);
}

/// A per-link thermal coefficient scales only its row's `a` and `b`, by `1 + (alpha + alpha_r) dT`.
#[test]
fn per_link_thermal_expansion_scales_each_row_by_its_own_coefficient() {
    let (_, t) = truth();
    let model = t.phi_model();
    let rows = vec![0.0, 3e-5, 0.0, 0.0, -1e-5];
    let effects = Effects {
        thermal: Some(ThermalEffect {
            alpha_per_k_rows: rows.clone(),
            ..ThermalEffect::uniform(1e-5, 20.0)
        }),
        ..Effects::default()
    };
    effects.validate(6).expect("valid");
    let hot = effects.thermal_model(&model, 30.0);
    for (r, (a, b)) in hot.rows.iter().zip(&model.rows).enumerate() {
        let s = 1.0 + (1e-5 + rows[r]) * 10.0;
        assert_eq!(a.a_m, b.a_m * s, "row {r}");
        assert_eq!(a.b_m, b.b_m * s, "row {r}");
    }
    let short = Effects {
        thermal: Some(ThermalEffect {
            alpha_per_k_rows: vec![1e-5],
            ..ThermalEffect::uniform(1e-5, 20.0)
        }),
        ..Effects::default()
    };
    let e = short.validate(6).expect_err("one value for five rows");
    assert!(e.to_string().contains("thermal.alpha_per_k_rows"), "{e}");
}

/// The real links' masses, when given, load the compliant joints instead of the description's:
/// doubling every mass doubles the analytic arm's sag (to first order: linear in the masses), and
/// the rapier arm built with them sags like the analytic one within the 2 % of
/// `tests/it/effects.rs` (the four-bar bodies' own weight, which neither mass set contains).
#[test]
fn the_real_link_masses_replace_the_descriptions_in_the_sag() {
    let (desc, t) = truth();
    let cmd = [0.3, -0.2, 0.25, 0.4, -0.6, 0.8];
    let mut stiffness = vec![1e8; 6];
    stiffness[1] = 2e5;
    let compliance = ComplianceEffect::new(stiffness, [0.0, 0.0, -9.81]);
    let doubled: Vec<LinkMassEntry> = desc
        .joints
        .iter()
        .map(|j| LinkMassEntry {
            mass_kg: 2.0 * j.mass_kg,
            com_mm: j.com_mm,
        })
        .collect();
    let tool = Point3::new(0.0, 0.0, 0.15);
    let conditions = PoseConditions::default();
    let mut rng = ChaCha12Rng::seed_from_u64(1);
    let mut analytic = |effects: Effects| {
        let mut arm = AnalyticArm::new(t.clone(), Controller::from_description(&desc)).with_effects(effects, &desc);
        arm.execute(&cmd, &conditions, &mut rng).expect("executes")[5] * tool
    };
    let rigid = analytic(Effects::default());
    let nominal = analytic(Effects {
        compliance: Some(compliance.clone()),
        ..Effects::default()
    }) - rigid;
    let heavy_effects = Effects {
        compliance: Some(compliance),
        link_masses: doubled,
        ..Effects::default()
    };
    heavy_effects.validate(6).expect("valid");
    let heavy = analytic(heavy_effects.clone()) - rigid;
    // The arm solves the static equilibrium `K dq = tau(q + dq)`, linear in the masses only to
    // first order: the second-order part is relative of the order of the sag angle, the
    // tool's sag over its lever about joint 2 (at least 0.5 m on the paper arm).
    let sag_angle_rad = heavy.norm() / 0.5;
    assert!(
        (heavy - nominal * 2.0).norm() < sag_angle_rad * heavy.norm(),
        "{heavy:?} vs 2 x {nominal:?}"
    );
    let mut rapier = RapierArm::new(t.clone(), &desc, heavy_effects, RapierArmOptions::new(6));
    let r = rapier.execute(&cmd, &conditions, &mut rng).expect("settles")[5] * tool - rigid;
    let relative = (r - heavy).norm() / heavy.norm();
    eprintln!(
        "doubled masses: analytic sag {:.4} mm, rapier {:.4} mm, relative difference {relative:.2e}",
        heavy.norm() * 1e3,
        r.norm() * 1e3
    );
    assert!(relative < 0.02, "analytic {heavy:?} rapier {r:?}");
}
