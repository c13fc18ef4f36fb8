//! Each candidate member, at the true parameters of the effect the simulator draws in the same
//! shape, reproduces the simulated measurements to rounding: the simulator's code path
//! (`sim::JointDriver`, `sim::AnalyticArm`, `physics`) and the predictor's are written apart.

use super::*;
use crate::measurement::{IsotropicNoise, MeasurementModel, MeasurementSet};
use crate::physics::{ApproachSource, ComplianceEffect, LinkMass};
use crate::physics::{AxisWobble, BacklashEffect, HarmonicPeriod, PassiveSlope, coupled_static_deflection};
use crate::plan::{CalibrationPlan, PoseConditions, ValidationPlan};
use crate::robot::commands_to_internal;
use crate::robot::{Controller, RobotDescription, RobotModel};
use crate::sim::{AnalyticArm, Effects, JointDriver, simulate_campaign};
use nalgebra::Vector3;
use rand::{SeedableRng, rngs::ChaCha12Rng};

fn truth() -> (RobotDescription, RobotModel) {
    let desc = RobotDescription::asea_irb6l();
    let mut truth = crate::sim::paper_robot();
    for j in &mut truth.joints {
        j.repeatability_sigma = 0.0;
    }
    (desc, truth)
}

/// The validation poses of a noise-free Table-1 campaign (analytic arm) with `effects`.
fn simulated_poses(effects: &Effects) -> Vec<Pose> {
    let (desc, truth) = truth();
    let mut arm = AnalyticArm::new(truth, Controller::from_description(&desc)).with_effects(effects.clone(), &desc);
    let exact = MeasurementModel::Isotropic(IsotropicNoise { net_radial_rms_mm: 0.0 });
    let validation = ValidationPlan {
        poses: 16,
        ..ValidationPlan::workspace_default(desc.dof())
    };
    let out = simulate_campaign(
        &desc,
        &CalibrationPlan::table1(desc.dof()),
        &validation,
        &mut arm,
        &exact,
        &mut ChaCha12Rng::seed_from_u64(3),
    )
    .expect("simulates");
    let set = MeasurementSet::new(desc.dof(), out.rows).expect("valid");
    validation_poses(set.rows(), &desc)
}

/// RMS \[m\] of the predictor's residuals on `poses` with `candidate` at `effect_params`
/// (refit at zero), and without it.
fn rms_with_and_without(candidate: Candidate, effect_params: &[f64], poses: &[Pose]) -> (f64, f64) {
    let (desc, truth) = truth();
    let p = Predictor::new(
        &truth,
        &desc,
        PoseConditions::default().temperature_c,
        RefitScope::Geometry,
    );
    let every: Vec<&Pose> = poses.iter().collect();
    let rms = |p: &Predictor, params: &[f64]| {
        let r = p.residuals(params, &every).expect("predicts");
        (r.iter().map(|x| x * x).sum::<f64>() / r.len() as f64).sqrt()
    };
    let without = rms(&p, &vec![0.0; p.geometric_count()]);
    let with_c = p.with_candidates(&[candidate]);
    let mut params = vec![0.0; with_c.geometric_count()];
    params.extend_from_slice(effect_params);
    (rms(&with_c, &params), without)
}

/// The members that reproduce the simulator's shapes exactly: a fixed-direction wobble of
/// order 1 (general tilt member), a joint-period harmonic of the geared joint 5, a backlash
/// of joint 3 signed by its actuator (joint 3 is driven through the 2->3 coupling, so its
/// actuator's direction differs from its command's).
#[test]
fn tilt_harmonic_and_backlash_members_reproduce_the_simulators_shapes() {
    let swash = AxisWobble {
        joint: 4,
        amplitude_rad: 3e-3,
        phase_rad: 0.4,
        order: 1,
        fixed_direction_rad: Some(-0.9),
    };
    let s = swash.series();
    let harmonic = crate::physics::GearHarmonic {
        joint: 5,
        order: 2,
        sin_rad: 2e-3,
        cos_rad: -1e-3,
        period: HarmonicPeriod::Joint,
    };
    let mut band_rad = vec![0.0; 6];
    band_rad[2] = 3e-3;
    let cases = [
        (
            Effects {
                wobble: vec![swash],
                ..Effects::default()
            },
            Candidate::AxisWobble {
                joint: 4,
                order: 1,
                shape: TiltShape::General,
            },
            vec![s.cos_rad[0], s.cos_rad[1], s.sin_rad[0], s.sin_rad[1]],
        ),
        (
            Effects {
                gear_harmonics: vec![harmonic],
                ..Effects::default()
            },
            Candidate::GearHarmonic {
                joint: 5,
                order: 2,
                period: HarmonicPeriod::Joint,
            },
            vec![2e-3, -1e-3],
        ),
        (
            Effects {
                backlash: Some(BacklashEffect {
                    band_rad,
                    direction: ApproachSource::Actuator,
                }),
                ..Effects::default()
            },
            Candidate::Backlash {
                joint: 3,
                direction: ApproachSource::Actuator,
            },
            vec![1.5e-3],
        ),
    ];
    for (effects, candidate, params) in cases {
        let poses = simulated_poses(&effects);
        let (with, without) = rms_with_and_without(candidate, &params, &poses);
        assert!(without > 1e-5, "{candidate:?}: the effect is visible ({without} m)");
        // Rounding of the forward kinematics over a 2 m reach.
        assert!(with < 1e-12, "{candidate:?} leaves {with} m of {without} m");
    }
}

/// The compliance candidate with the description's masses on the truth robot itself reproduces
/// the coupled static equilibrium (joint 2's sag drives joint 3 through the four-bar) to
/// rounding; the lumped member at the description's products (compliance times each link's
/// mass and first moment, the payload's compliance) and the payload-offset member at a zero
/// offset give the same residuals.
/// Validation poses of the truth with joint 2 compliant at `stiffness_nm_per_rad`, the
/// four-bar reflecting `reflected_fraction` of joint 3's load (the exact static equilibrium,
/// [`coupled_static_deflection`]), the description's masses, no payload.
fn sagged_poses(stiffness_nm_per_rad: f64, reflected_fraction: f64) -> Vec<Pose> {
    let (desc, truth) = truth();
    let mut stiffness = vec![f64::INFINITY; desc.dof()];
    stiffness[1] = stiffness_nm_per_rad;
    let compliance = ComplianceEffect {
        reflected_fraction,
        ..ComplianceEffect::new(stiffness, GRAVITY_M_S2)
    };
    let masses = LinkMass::from_description(&desc);
    let mut driver = JointDriver::new(&truth, Controller::from_description(&desc), &Effects::default());
    let model = truth.phi_model();
    let mut sagged = |cmd: &[f64]| {
        let d = driver.drive(cmd, &mut ChaCha12Rng::seed_from_u64(1)).unwrap();
        let couplings = PassiveSlope::of_linkages(&truth, &d.active);
        let dq = crate::physics::with_simulated_load(&masses, None, &compliance, &couplings, |load| {
            coupled_static_deflection(&model, &d.q, load)
        })
        .unwrap();
        let q: Vec<f64> = d.q.iter().zip(&dq).map(|(a, b)| a + b).collect();
        model.poses(&q).world_from_link[desc.dof() - 1] * model.last_link_from_tool
    };
    let plan = ValidationPlan {
        poses: 12,
        ..ValidationPlan::workspace_default(desc.dof())
    };
    let reference = CalibrationPlan::table1(desc.dof()).reference;
    plan.commands(&desc, &reference)
        .into_iter()
        .enumerate()
        .map(|(step, c)| {
            let cmd = commands_to_internal(&desc, &c);
            let tool = sagged(&cmd);
            Pose {
                experiment: "validation".into(),
                step,
                cmd,
                approach: vec![0.0; desc.dof()],
                actuator_approach: vec![0.0; desc.dof()],
                temperature_c: PoseConditions::default().temperature_c,
                payload_kg: 0.0,
                targets: desc.tool_targets_m().iter().map(|t| tool * t).enumerate().collect(),
            }
        })
        .collect()
}

/// The lumped parameters of `masses` from link `first_link` (1-based) on at compliance `c`,
/// then the payload's `c` and zero offset.
fn lumped(masses: &[LinkMass], first_link: usize, c: f64) -> Vec<f64> {
    let mut out = Vec::new();
    for m in &masses[first_link - 1..] {
        out.push(c * m.mass_kg);
        out.extend((m.first_moment_kg_m * c).iter());
    }
    out.extend([c, 0.0, 0.0, 0.0]);
    out
}

/// Each load path's members reproduce the sag of the physics they stand for, to the
/// equilibrium's rounding (1e-13 rad times the reach): the rigid four-bar's (mechanism), the
/// serial chain's (nothing reflected) and a four-bar that carries 40 % of joint 3's load
/// (mixed: the reflected load is 0.4 times the carried one); a member on another path misses it.
#[test]
fn compliance_members_reproduce_the_coupled_sag() {
    let (desc, _) = truth();
    let masses = LinkMass::from_description(&desc);
    let stiffness_nm_per_rad = 2.0e4;
    let c = 1.0 / stiffness_nm_per_rad;
    let member = |load, masses| Candidate::JointCompliance {
        joint: 2,
        spring: SpringSite::Actuator,
        masses,
        load,
    };
    let lumped_mixed = |f: f64| {
        let mut v = lumped(&masses, 2, c);
        v.extend(lumped(&masses, 3, f * c));
        v
    };
    for (fraction, load) in [
        (1.0, LoadPath::Mechanism),
        (0.0, LoadPath::Serial),
        (0.4, LoadPath::Mixed),
    ] {
        let poses = sagged_poses(stiffness_nm_per_rad, fraction);
        let (description, lumped_params) = match load {
            LoadPath::Mixed => (vec![c, fraction * c], lumped_mixed(fraction)),
            _ => (vec![c], lumped(&masses, 2, c)),
        };
        let (with, without) = rms_with_and_without(member(load, MassModel::Description), &description, &poses);
        assert!(without > 1e-4, "{load:?}: the sag is visible: {without} m");
        assert!(with < 1e-11, "{load:?}: candidate leaves {with} m of {without} m");
        if load != LoadPath::Mixed {
            let offset = member(load, MassModel::PayloadOffset);
            assert!(rms_with_and_without(offset, &[c, 0.0, 0.0, 0.0], &poses).0 < 1e-11);
        }
        let with = rms_with_and_without(member(load, MassModel::Lumped), &lumped_params, &poses).0;
        assert!(with < 1e-11, "{load:?} lumped leaves {with} m");
        // The mixed member at the other paths' fractions is each of them.
        let (mixed, _) = rms_with_and_without(
            member(LoadPath::Mixed, MassModel::Description),
            &[c, fraction * c],
            &poses,
        );
        assert!(mixed < 1e-11, "{load:?}: mixed at fraction {fraction} leaves {mixed} m");
    }
    // Another path's member at the true compliance misses the serial sag by far more.
    let serial = sagged_poses(stiffness_nm_per_rad, 0.0);
    let (wrong, without) = rms_with_and_without(member(LoadPath::Mechanism, MassModel::Description), &[c], &serial);
    assert!(
        wrong > 0.1 * without,
        "the mechanism path leaves {wrong} m of {without} m"
    );
}

/// Every compliance member's analytic sensitivity (the chain rule through its sag,
/// [`Predictor::compliance_sensitivity`]) against central differences of the whole predictor
/// ([`crate::calibration::refine::sensitivity`], the project's one finite-difference tool), on
/// the poses of a Table-1 campaign with a payload varying (so the payload members are in the
/// library). Tolerance from the difference's rounding: the predictions are below 3 m, so
/// `plus - minus` carries at most about `4 eps x 3 m` of rounding, divided by the `2 h` of the
/// member's step `h`; a factor 10 over that, plus 1e-7 of the column's largest entry for the
/// joint Jacobian's own central differences (rounding 2e-10 relative at its 1e-6 rad step).
#[test]
fn compliance_sensitivities_match_central_differences() {
    let (desc, truth) = truth();
    let mut poses = simulated_poses(&Effects::default());
    for (k, p) in poses.iter_mut().enumerate() {
        p.payload_kg = [0.0, 5.0, 12.0][k % 3];
    }
    let every: Vec<&Pose> = poses.iter().collect();
    let p = Predictor::new(
        &truth,
        &desc,
        PoseConditions::default().temperature_c,
        RefitScope::Identified,
    );
    let zeros = vec![0.0; p.geometric_count()];
    let joint_x = p.joint_sensitivity(&zeros, &every).expect("predicts");
    let library = Candidate::library(&desc, &poses, DEFAULT_MAX_HARMONIC_ORDER);
    let compliance: Vec<Candidate> = library
        .into_iter()
        .filter(|c| matches!(c, Candidate::JointCompliance { .. }))
        .collect();
    assert!(
        compliance.iter().any(|c| matches!(
            c,
            Candidate::JointCompliance {
                masses: MassModel::Lumped,
                ..
            }
        )) && compliance.len() >= 6,
        "{compliance:?}"
    );
    for c in compliance {
        let pred = p.with_candidates(&[c]);
        let g = pred.geometric_count();
        let steps = pred.steps();
        let analytic = pred
            .compliance_sensitivity(c, &joint_x, &every)
            .expect("a compliance member");
        let numeric = crate::calibration::refine::sensitivity(
            |e| {
                let mut params = vec![0.0; g];
                params.extend_from_slice(e);
                pred.residuals(&params, &every)
            },
            &vec![0.0; pred.effect_count()],
            &steps[g..],
        )
        .expect("predicts");
        assert_eq!(analytic.shape(), numeric.shape());
        for i in 0..analytic.ncols() {
            let (a, n) = (analytic.column(i), numeric.column(i));
            let largest = n.amax();
            let tolerance = 10.0 * 4.0 * f64::EPSILON * 3.0 / (2.0 * steps[g + i]) + 1e-7 * largest;
            let off = (a - n).amax();
            assert!(
                off <= tolerance,
                "{c:?} parameter {i}: {off:e} off (column up to {largest:e}, tolerance {tolerance:e})"
            );
        }
    }
}

/// The predictor's sensitivity ([`Predictor::sensitivity`], the joint values kept across the
/// columns that do not move them) is the project's one finite-difference tool applied to
/// [`Predictor::residuals`] bit for bit, at a point away from zero (every parameter moved),
/// for every parameter of the refit and of candidates of every family (harmonics in both
/// periods and a backlash move the joints, the rest act after them), and for a sub-range of
/// the columns; so is the joint sensitivity at that point against the offset's differences
/// without the kept values (here: the same function with the joint values recomputed).
#[test]
fn the_predictors_sensitivity_is_the_central_differences_bit_for_bit() {
    let (desc, truth) = truth();
    let mut poses = simulated_poses(&Effects::default());
    for (k, p) in poses.iter_mut().enumerate() {
        p.payload_kg = [0.0, 5.0, 12.0][k % 3];
        p.temperature_c = 18.0 + k as f64 * 0.7;
    }
    let every: Vec<&Pose> = poses.iter().collect();
    let candidates = [
        Candidate::GearHarmonic {
            joint: 5,
            order: 2,
            period: HarmonicPeriod::Joint,
        },
        Candidate::GearHarmonic {
            joint: 2,
            order: 3,
            period: HarmonicPeriod::Transmission,
        },
        Candidate::Backlash {
            joint: 3,
            direction: ApproachSource::Actuator,
        },
        Candidate::AxisWobble {
            joint: 4,
            order: 1,
            shape: TiltShape::General,
        },
        Candidate::ThermalExpansion {
            links: ThermalLinks::PerLink,
        },
        Candidate::InstrumentScale,
        Candidate::JointCompliance {
            joint: 2,
            spring: SpringSite::Actuator,
            masses: MassModel::Lumped,
            load: LoadPath::Mixed,
        },
    ];
    // All candidates at once (every pose's frames its own: the thermal rows, the tilt), and
    // all but the thermal and the wobble ones (the columns that leave the chain below alone
    // continue from the memo's links).
    let chain_kept: Vec<Candidate> = candidates
        .iter()
        .copied()
        .filter(|c| !matches!(c, Candidate::ThermalExpansion { .. } | Candidate::AxisWobble { .. }))
        .collect();
    for set in [&candidates[..], &chain_kept] {
        sensitivity_is_the_central_differences(&desc, &truth, set, &every);
    }
}

/// [`Predictor::sensitivity`] and [`Predictor::joint_sensitivity`] with `candidates` against
/// the plain differences, bit for bit (the test above).
fn sensitivity_is_the_central_differences(
    desc: &RobotDescription,
    truth: &RobotModel,
    candidates: &[Candidate],
    every: &[&Pose],
) {
    let every = every.to_vec();
    let pred = Predictor::new(
        truth,
        desc,
        PoseConditions::default().temperature_c,
        RefitScope::Identified,
    )
    .with_candidates(candidates);
    let n = pred.geometric_count() + pred.effect_count();
    let steps = pred.steps();
    // Small enough that every command still executes, different in every parameter.
    let params: Vec<f64> = (0..n).map(|i| steps[i] * (((i * 7919) % 13) as f64 - 6.0)).collect();
    let plain = |columns: std::ops::Range<usize>| {
        crate::calibration::refine::sensitivity(
            |e| {
                let mut p = params.clone();
                p[columns.clone()].copy_from_slice(e);
                pred.residuals(&p, &every)
            },
            &params[columns.clone()],
            &steps[columns.clone()],
        )
        .expect("predicts")
    };
    let bits = |m: &DMatrix<f64>| m.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    for columns in [0..n, pred.geometric_count()..n, 3..17] {
        let kept = pred
            .sensitivity(&params, columns.clone(), &every, &steps)
            .expect("predicts");
        assert_eq!(kept.ncols(), columns.len());
        assert_eq!(bits(&kept), bits(&plain(columns.clone())), "columns {columns:?}");
    }
    let joint = pred.joint_sensitivity(&params, &every).expect("predicts");
    let fresh = crate::calibration::refine::sensitivity(
        |offset| pred.residuals_offset(&params, &every, offset, None),
        &vec![0.0; pred.dof()],
        &vec![super::compliance::JOINT_STEP_RAD; pred.dof()],
    )
    .expect("predicts");
    assert_eq!(bits(&joint), bits(&fresh));
}

/// A model carrying the candidates (`Predictor::carried_robot`) predicts through its own path
/// (`RobotModel::loaded_joint_values`, the backlash on the actuator command, the compliance
/// term at the joint values before it) what the predictor predicts at the same parameters: a
/// joint-2 compliance on the mixed load path with payloads and both loads lumped, a backlash of
/// joint 3 signed by its actuator (driven through the 2->3 coupling), an order-3 transmission
/// harmonic of joint 1, and a refit moved off zero. The truth's transmissions are the identity
/// there, so that the two backlash sites (the actuator command, the active displacement) are
/// one; the bound is rounding (1e-12 m over a 1 m reach).
#[test]
fn a_carried_model_predicts_what_the_predictor_predicts() {
    let (desc, mut truth) = truth();
    for j in &mut truth.joints {
        j.transmission = crate::robot::Transmission::identity();
    }
    let mut poses = sagged_poses(3.0e4, 1.0);
    for (i, p) in poses.iter_mut().enumerate() {
        p.payload_kg = 1.5 * (i % 4) as f64;
        p.actuator_approach = (0..desc.dof())
            .map(|k| if (i + k) % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
    }
    let compliance = Candidate::JointCompliance {
        joint: 2,
        spring: SpringSite::Actuator,
        masses: MassModel::Lumped,
        load: LoadPath::Mixed,
    };
    let backlash = Candidate::Backlash {
        joint: 3,
        direction: ApproachSource::Actuator,
    };
    let harmonic = Candidate::GearHarmonic {
        joint: 1,
        order: 3,
        period: HarmonicPeriod::Transmission,
    };
    let p =
        Predictor::new(&truth, &desc, 20.0, RefitScope::Identified).with_candidates(&[compliance, backlash, harmonic]);
    let masses = LinkMass::from_description(&desc);
    let mut params = vec![0.0; p.geometric_count()];
    params[0] = 2e-4; // row 1 a
    params[4 * desc.rows.len()] = 1e-3; // joint 1 zero offset
    let g = params.len();
    params[g - 9] = 3e-4; // base translation z
    params.extend(lumped(&masses, 2, 3e-5));
    params.extend(lumped(&masses, 3, 1e-5));
    params.extend([1.5e-3, 4e-4, -2e-4]);
    assert_eq!(params.len(), g + p.effect_count());
    let every: Vec<&Pose> = poses.iter().collect();
    let residuals = p.residuals(&params, &every).expect("predicts");
    let robot = p.carried_robot(&params);
    assert_eq!((robot.effects.compliance.len(), robot.effects.backlash.len()), (1, 1));
    let phi = robot.phi_model();
    let controller = Controller::from_description(&desc);
    let mut worst: f64 = 0.0;
    let mut row = 0;
    for pose in &poses {
        let load = crate::robot::PoseLoad {
            approach: &pose.actuator_approach,
            payload_kg: pose.payload_kg,
        };
        let q = robot
            .loaded_joint_values(&controller, &phi, &pose.cmd, &load)
            .expect("executes");
        let tool = phi.poses(&q).world_from_link[desc.dof() - 1] * phi.last_link_from_tool;
        for (id, measured) in &pose.targets {
            let predicted = tool * desc.tool_targets_m()[*id];
            let by_predictor = measured - Vector3::from_column_slice(&residuals[row..row + 3]);
            worst = worst.max((predicted - by_predictor).norm());
            row += 3;
        }
    }
    assert!(worst < 1e-12, "carried model and predictor differ by {worst} m");
}
