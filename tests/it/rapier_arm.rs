//! The rapier arm as the campaign's real robot: kinematic mode agrees with the analytic truth,
//! occluded targets are left out of the campaign.

use axiscal::measurement::MeasurementModel;
use axiscal::plan::{AxisSweep, CalibrationPlan, PoseConditions, ValidationPlan};
use axiscal::robot::{Controller, RobotDescription};
use axiscal::sim::{AnalyticArm, ArmExecutor, Effects, simulate_campaign};
use axiscal::sim::{RapierArm, RapierArmOptions};
use nalgebra::Point3;
use rand::rngs::ChaCha12Rng;
use rand::{RngExt, SeedableRng};

/// Every axis target and tool target of the description, as (link 0-based, point in link).
fn all_targets(desc: &RobotDescription, arm: &impl ArmExecutor) -> Vec<(usize, Point3<f64>)> {
    let mut t: Vec<(usize, Point3<f64>)> = desc
        .axis_targets
        .iter()
        .flat_map(|a| std::iter::once(a.target0).chain(a.target1))
        .map(|lt| (lt.link - 1, lt.position_m()))
        .collect();
    let last = desc.dof() - 1;
    t.extend(
        desc.tool_targets_m()
            .iter()
            .map(|p| (last, arm.last_link_from_tool() * p)),
    );
    t
}

/// Same truth (paper robot, with its repeatability jitter drawn from equal seeds), same
/// commands: the rapier multibody's forward kinematics reproduces the phi-model to rounding
/// (a few 1e-13 m over the 5 m lever, see `sim::arm`), far below the 1 micrometre asked.
#[test]
fn kinematic_rapier_arm_agrees_with_the_analytic_arm_to_a_micrometre() {
    let desc = RobotDescription::asea_irb6l();
    let truth = axiscal::sim::paper_robot();
    let mut analytic = AnalyticArm::new(truth.clone(), Controller::from_description(&desc));
    let mut rapier = RapierArm::new(truth, &desc, Effects::default(), RapierArmOptions::new(desc.dof()));
    let targets = all_targets(&desc, &analytic);
    let mut draw = ChaCha12Rng::seed_from_u64(11);
    let (mut rng_a, mut rng_r) = (ChaCha12Rng::seed_from_u64(5), ChaCha12Rng::seed_from_u64(5));
    let conditions = PoseConditions::default();
    let mut worst_m = 0.0_f64;
    for _ in 0..1000 {
        let cmd: Vec<f64> = (0..desc.dof())
            .map(|k| {
                let [lo, hi] = desc.limits_internal(k);
                draw.random_range(lo..hi)
            })
            .collect();
        let a = analytic.execute(&cmd, &conditions, &mut rng_a).expect("analytic");
        let r = rapier.execute(&cmd, &conditions, &mut rng_r).expect("rapier");
        for (link, p) in &targets {
            worst_m = worst_m.max((a[*link] * p - r[*link] * p).norm());
        }
    }
    assert!(worst_m < 1e-6, "worst target disagreement {worst_m:e} m");
}

/// The joint-2 target sits on the upper arm's face towards the stations (-y) at q1 = 0; with
/// joint 1 at 170 deg it faces away from both theodolites, behind the 50 mm capsule (see
/// `sim::visibility`): a joint-2 sweep there sees nothing (no row in the measurement CSV
/// written and read back), the analytic arm sees everything.
#[test]
fn an_occluded_target_is_left_out_of_the_campaign() {
    let desc = RobotDescription::asea_irb6l();
    let truth = axiscal::sim::paper_robot();
    let (instrument, _) = MeasurementModel::paper_theodolites().expect("theodolites");
    let plan = CalibrationPlan {
        reference: vec![170.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        sweeps: vec![AxisSweep {
            joint: 2,
            span: 10.0,
            intervals: 2,
            second_target: false,
            start: None,
            held_at: None,
        }],
        held_jitter: None,
    };
    let validation = ValidationPlan {
        poses: 0,
        ..ValidationPlan::workspace_default(desc.dof())
    };
    let options = RapierArmOptions {
        stations_m: instrument.stations_m(),
        ..RapierArmOptions::new(desc.dof())
    };
    let mut rapier = RapierArm::new(truth.clone(), &desc, Effects::default(), options);
    let mut rng = ChaCha12Rng::seed_from_u64(1);
    let out = simulate_campaign(&desc, &plan, &validation, &mut rapier, &instrument, &mut rng).expect("runs");
    let axis2 = |rows: &[axiscal::measurement::Measurement]| rows.iter().filter(|r| r.experiment == "axis2").count();
    assert_eq!(axis2(&out.rows), 0, "{} rows measured", axis2(&out.rows));
    assert_eq!(out.occluded, vec![("axis2".to_owned(), 3)]);
    assert_eq!(csv_rows_of(&out.rows, "axis2"), 0);
    let mut analytic = AnalyticArm::new(truth, Controller::from_description(&desc));
    let out = simulate_campaign(&desc, &plan, &validation, &mut analytic, &instrument, &mut rng).expect("runs");
    assert_eq!(axis2(&out.rows), 3);
    assert!(out.occluded.is_empty());
    assert_eq!(csv_rows_of(&out.rows, "axis2"), 3);
}

/// `visible_sweep_span` is the campaign's own notion of visibility: the paper's axis-4
/// experiment (second target on link 5, actuator 5 held still) run by the campaign loses no
/// target at the span the search reports, and loses one just beyond it (one coarse step of the
/// search wider); the analytic arm sees everything up to the joint limit.
#[test]
fn the_visible_span_is_where_the_campaign_starts_losing_targets() {
    use axiscal::sim::{SpanSearch, visible_sweep_span};
    let desc = RobotDescription::asea_irb6l();
    let mut truth = axiscal::sim::paper_robot();
    for joint in &mut truth.joints {
        joint.repeatability_sigma = 0.0;
    }
    let (instrument, _) = MeasurementModel::paper_theodolites().expect("theodolites");
    let table1 = CalibrationPlan::table1(desc.dof());
    let axis4 = table1
        .sweeps
        .iter()
        .find(|s| s.joint == 4)
        .expect("Table 1 sweeps joint 4")
        .clone();
    let options = RapierArmOptions {
        stations_m: instrument.stations_m(),
        ..RapierArmOptions::new(desc.dof())
    };
    let mut rapier = RapierArm::new(truth.clone(), &desc, Effects::default(), options);
    let search = SpanSearch {
        max_half_span_deg: 90.0,
        ..SpanSearch::default()
    };
    let mut rng = ChaCha12Rng::seed_from_u64(3);
    let conditions = PoseConditions::default();
    let span = visible_sweep_span(&mut rapier, &desc, &table1, &axis4, &conditions, &search, &mut rng).expect("runs");
    assert!(span > 0.0 && span < axis4.span, "span {span} deg");
    let validation = ValidationPlan {
        poses: 0,
        ..ValidationPlan::workspace_default(desc.dof())
    };
    let centre = axis4.offset_at(0) + axis4.span / 2.0;
    let occluded_at = |span_deg: f64, rapier: &mut RapierArm, rng: &mut ChaCha12Rng| {
        let plan = CalibrationPlan {
            sweeps: vec![AxisSweep {
                span: span_deg,
                start: Some(centre - span_deg / 2.0),
                ..axis4.clone()
            }],
            ..table1.clone()
        };
        let out = simulate_campaign(&desc, &plan, &validation, rapier, &instrument, rng).expect("runs");
        out.occluded.iter().map(|(_, n)| n).sum::<usize>()
    };
    assert_eq!(occluded_at(span, &mut rapier, &mut rng), 0);
    assert!(occluded_at(span + 2.0 * search.step_deg, &mut rapier, &mut rng) > 0);
    let mut analytic = AnalyticArm::new(truth, Controller::from_description(&desc));
    let all = visible_sweep_span(&mut analytic, &desc, &table1, &axis4, &conditions, &search, &mut rng).expect("runs");
    assert_eq!(all, 2.0 * search.max_half_span_deg);
}

/// The measurement CSV (`docs/formats.md#measurement-csv`) written from `rows` and read back: how many
/// rows it holds for `experiment`.
fn csv_rows_of(rows: &[axiscal::measurement::Measurement], experiment: &str) -> usize {
    use axiscal::measurement::{MeasurementSet, read_measurements_from, write_measurements_to};
    let set = MeasurementSet::new(6, rows.to_vec()).expect("valid rows");
    let mut csv = Vec::new();
    write_measurements_to(&mut csv, &set).expect("writes");
    let back = read_measurements_from(csv.as_slice(), std::path::Path::new("campaign.csv"), Some(6)).expect("reads");
    back.rows().iter().filter(|r| r.experiment == experiment).count()
}

mod dynamic {
    use axiscal::physics::{ComplianceEffect, LinkMass, PayloadEffect, first_order_deflection};
    use axiscal::plan::PoseConditions;
    use axiscal::robot::{Controller, FourBarGeometry, RobotDescription, RobotModel};
    use axiscal::sim::{ArmExecutor, DrivenJoints, Effects, JointDriver};
    use axiscal::sim::{CRANK_MASS_KG, ROD_MASS_KG, RapierArm, RapierArmOptions};
    use rand::SeedableRng;
    use rand::rngs::ChaCha12Rng;

    const CMD: [f64; 6] = [0.3, -0.2, 0.25, 0.4, -0.6, 0.8];

    /// The ideal (nominal) truth without jitter: axes 2 and 3 exactly parallel, so the planar
    /// four-bar law is exact for the spatial mechanism.
    fn ideal_truth(desc: &RobotDescription) -> RobotModel {
        RobotModel::ideal(desc)
    }

    fn compliance(stiffness: [f64; 6]) -> ComplianceEffect {
        ComplianceEffect::new(stiffness.to_vec(), [0.0, 0.0, -9.81])
    }

    /// Executes `CMD` on the rapier arm and returns it with the driver's joint values.
    fn execute(
        truth: &RobotModel,
        desc: &RobotDescription,
        effects: &Effects,
        conditions: &PoseConditions,
    ) -> (RapierArm, DrivenJoints) {
        let mut driver = JointDriver::new(truth, Controller::from_description(desc), effects);
        let mut rng = ChaCha12Rng::seed_from_u64(1);
        let driven = driver.drive(&CMD, &mut rng).expect("drives");
        let mut arm = RapierArm::new(truth.clone(), desc, effects.clone(), RapierArmOptions::new(6));
        arm.execute(&CMD, conditions, &mut ChaCha12Rng::seed_from_u64(1))
            .expect("settles");
        (arm, driven)
    }

    /// Gravity torque about each axis at joint values `q` (no payload).
    fn gravity_torque(truth: &RobotModel, desc: &RobotDescription, q: &[f64]) -> Vec<f64> {
        first_order_deflection(
            &truth.phi_model(),
            q,
            &LinkMass::from_description(desc),
            None,
            &compliance([1.0; 6]),
        )
    }

    fn linkage(desc: &RobotDescription) -> axiscal::robot::FourBarLinkage {
        let mut l = axiscal::sim::paper_robot().four_bars[0];
        l.geometry.arm_m = desc.rows[1].a_m.abs();
        l
    }

    /// `g''` of the planar law by central differences of its analytic slope.
    fn curvature(g: &FourBarGeometry, t: f64) -> f64 {
        let h = 1e-4;
        (g.solve(t + h).unwrap().slope - g.solve(t - h).unwrap().slope) / (2.0 * h)
    }

    /// In compliant mode the four-bar's bodies drive joint 3 (it has no servo of its own) and
    /// the loop stays closed to < 1 micrometre.
    ///
    /// The mechanism gives `theta_23 = g(theta_2 - c)` (planar law, exact on the nominal arm),
    /// so joint 3 moves by `g' (dq_2 - dc)`; by virtual work the crank (actuator 3, stiffness
    /// `K_3`) carries `-g' Q_3` and turns by `dc = -g' Q_3 / K_3`: `dq_3 = g' dq_2 + g'^2 Q_3 /
    /// K_3`. Bound: the crank's and rod's own weight on the crank, at most `tau_bars = 9.81
    /// (m_c r_c / 2 + m_r (r_c + |g'| r_l) / 2)`, turns joint 3 by `|g'| tau_bars / K_3`, and
    /// the second-order term `|g''| dq_2^2 / 2`. Case (i): joint 2 compliant (2e5 N m/rad),
    /// the crank stiff: link 3 is held level by the near-parallelogram (`g' ~ -1`) while
    /// joint 2 sags. Case (ii): the crank compliant (2e5), joint 2 stiff.
    #[test]
    fn compliant_rapier_arm_drives_joint3_through_the_four_bar() {
        let desc = RobotDescription::asea_irb6l();
        let mut truth = ideal_truth(&desc);
        let l = linkage(&desc);
        let g = l.geometry;
        truth.four_bars = vec![l];
        for (joint, k) in [(1, 2e5), (2, 2e5)] {
            let mut stiffness = [1e8; 6];
            stiffness[joint] = k;
            let effects = Effects {
                compliance: Some(compliance(stiffness)),
                ..Effects::default()
            };
            let (arm, driven) = execute(&truth, &desc, &effects, &PoseConditions::default());
            let sim = arm.sim_arm().expect("built");
            let fb = &arm.four_bars()[0];
            let gap = fb.closure_error_m(sim);
            let q = sim.joint_positions();
            let dq2 = q[1] - driven.q[1];
            let dq3 = q[2] - driven.q[2];
            // The mechanism's input is theta_2 - c; the crank sits near the angle that gives
            // the commanded theta_23.
            let c = fb.crank_angle(sim);
            let slope = g.solve(q[1] - c).unwrap().slope;
            let q3_torque = gravity_torque(&truth, &desc, &q)[2];
            let tau_bars =
                9.81 * (CRANK_MASS_KG * g.crank_m / 2.0 + ROD_MASS_KG * (g.crank_m + slope.abs() * g.lever_m) / 2.0);
            let predicted = slope * dq2 + slope * slope * q3_torque / stiffness[2];
            let bound = slope.abs() * tau_bars / stiffness[2] + curvature(&g, q[1] - c).abs() * dq2 * dq2 / 2.0;
            eprintln!(
                "joint {} compliant: dq2 {dq2:.4e}, dq3 {dq3:.4e} rad, predicted {predicted:.4e} +- {bound:.2e}, \
                 loop gap {gap:.2e} m",
                joint + 1
            );
            assert!(gap < 1e-6, "loop gap {gap} m");
            assert!((dq3 - predicted).abs() < bound, "dq3 {dq3} vs {predicted} +- {bound}");
        }
    }

    /// The bevel gear 4 -> 5 emulated by coupled servo targets (`sim::CoupledTargets`): at
    /// equilibrium joint 5 follows joint 4's sag `s_4` through the gear's full error function,
    /// `q_5 = q_cmd_5 - g(theta_act_4) + g(theta_act_4 + s_4) + Q_5 / K_5` (paper truth's
    /// `g = N t - 0.040562 sin(N t) + 0.000018 cos(N t)`, N = 32/19). Joint 4 soft (2e4 N m/rad)
    /// under a 10 kg payload 80 mm off axis 4; the 3 -> 4 coupling is taken out so that joint
    /// 4's target is the command. Tolerance: joint 5's spring (1e8) sags by `Q_5 / K_5`,
    /// evaluated here at the settled pose; what is left is the settling itself: the arm is
    /// called at rest when the tool moves slower than `v = 1e-6 m/s`, i.e. joint 4 turns slower
    /// than `v / r` (`r` the tool's distance from axis 4), so the one-step lag of the target
    /// and the remaining creep over the spring's time constant `tau = D_4 / K_4` bound the error
    /// by `|g'| (v / r) (dt + tau)`.
    #[test]
    fn the_bevel_gear_follows_joint4s_sag_through_its_error_function() {
        let desc = RobotDescription::asea_irb6l();
        let paper = axiscal::sim::paper_robot();
        let mut truth = ideal_truth(&desc);
        truth.joints[4].coupling_in = paper.joints[4].coupling_in.clone();
        truth.joints[3].coupling_in = None;
        let gear = truth.joints[4].coupling_in.clone().expect("bevel gear");
        let mut stiffness = [1e8; 6];
        stiffness[3] = 2e4;
        let effects = Effects {
            compliance: Some(compliance(stiffness)),
            payload: Some(PayloadEffect {
                com_in_tool_mm: [0.0, 80.0, 150.0],
            }),
            ..Effects::default()
        };
        let conditions = PoseConditions {
            payload_kg: 10.0,
            ..PoseConditions::default()
        };
        let (arm, driven) = execute(&truth, &desc, &effects, &conditions);
        let sim = arm.sim_arm().expect("built");
        let q = sim.joint_positions();
        let s4 = q[3] - driven.q[3];
        let a4 = driven.active[3];
        let model = truth.phi_model();
        let payload = effects.payload_in_last_link(&model.last_link_from_tool, &conditions);
        let q5_torque = first_order_deflection(
            &model,
            &q,
            &LinkMass::from_description(&desc),
            payload,
            &compliance([1.0; 6]),
        )[4];
        let law = driven.q[4] - gear.passive(a4) + gear.passive(a4 + s4) + q5_torque / stiffness[4];
        let linear = driven.q[4] + gear.slope(a4) * s4;
        let poses = model.poses(&q);
        let axis4 = poses.axis(3);
        let tool = poses.world_from_tool * nalgebra::Point3::origin();
        let r = axis4.direction.cross(&(tool - axis4.origin_m)).norm();
        let options = RapierArmOptions::new(6).settle;
        let gains = axiscal::sim::ServoGains::with_damping_ratio(sim, &q, &stiffness, 1.0);
        let tau = gains.damping_nms_per_rad[3] / stiffness[3];
        let bound = gear.slope(a4 + s4).abs() * options.speed_tolerance_m_s / r * (options.dt_s + tau);
        eprintln!(
            "joint 4 sag {s4:.4e} rad; q5 - gear law {:.3e} rad (bound {bound:.2e}); gear law - its \
             linearisation {:.3e} rad",
            q[4] - law,
            law - linear
        );
        eprintln!(
            "Q_5 {q5_torque:.3} N m: the gear reaction the emulation leaves out would turn joint 4 by \
             {:.3e} rad",
            gear.slope(a4) * q5_torque / stiffness[3]
        );
        assert!(s4.abs() > 1e-4, "joint 4 sag {s4} too small to test the gear");
        // The test can tell the gear's error function from its slope.
        assert!((law - linear).abs() > bound);
        assert!((q[4] - law).abs() < bound, "q5 {} vs gear law {law}", q[4]);
    }

    /// Where the four-bar cannot close at the commanded pose (here a rod too short to reach
    /// the lever anywhere) the dynamic mode opens the loop: joint 3 keeps its own servo and
    /// the arm settles as if it had no four-bar, as the analytic first-order deflection
    /// without the four-bar predicts (within 2 % of the sag, as `tests/it/effects.rs`).
    #[test]
    fn a_four_bar_that_cannot_close_leaves_joint3_to_its_servo() {
        let desc = RobotDescription::asea_irb6l();
        let mut truth = ideal_truth(&desc);
        let mut l = linkage(&desc);
        l.geometry.rod_m = 0.3;
        truth.four_bars = vec![l];
        let mut stiffness = [1e8; 6];
        stiffness[2] = 2e5;
        let effects = Effects {
            compliance: Some(compliance(stiffness)),
            ..Effects::default()
        };
        let (arm, driven) = execute(&truth, &desc, &effects, &PoseConditions::default());
        let q = arm.sim_arm().expect("built").joint_positions();
        let mut without = truth.clone();
        without.four_bars.clear();
        let masses = LinkMass::from_description(&desc);
        let couplings = axiscal::physics::PassiveSlope::of_linkages(&without, &driven.active);
        let load = axiscal::physics::CompliantLoad {
            masses: &masses,
            payload: None,
            compliance: &compliance(stiffness),
            couplings: &couplings,
            reflected_masses: None,
        };
        let dq_analytic = axiscal::physics::coupled_first_order_deflection(&without.phi_model(), &driven.q, &load);
        let dq3 = q[2] - driven.q[2];
        eprintln!("open loop: dq3 {dq3:.4e} rad, analytic {:.4e}", dq_analytic[2]);
        assert!(arm.four_bars()[0].closure_error_m(arm.sim_arm().expect("built")) > 0.01);
        assert!((dq3 - dq_analytic[2]).abs() < 0.02 * dq_analytic[2].abs());
    }

    /// How a compliant pose is settled: from the undeflected command (cold: pure time
    /// stepping at 1 ms of 16 substeps to 20 quiet steps), from the analytic static
    /// equilibrium (warm), from there with the long-step approach first (main's previous
    /// default), and the default (the same with the decay rule ending both the approach and
    /// the settle proper, 8 substeps a step), the same without the approach's leaps (main's
    /// default before them).
    #[derive(Clone, Copy, Debug)]
    enum Start {
        Cold,
        Warm,
        Approach,
        NoLeap,
        Fast,
    }

    /// The rapier substeps of a step before the fast settle (the fast settle's own are
    /// `SettleOptions::default().solver_iterations`).
    const OLD_SOLVER_ITERATIONS: usize = 16;

    /// The compliance scenario's stiffnesses, a softer set, and one soft at the base and stiff
    /// at the wrist (the slow mode moves to the heavy links).
    const STIFFNESS_SETS: [[f64; 6]; 3] = [
        [5e5, 3e5, 3e5, 5e4, 5e4, 2e4],
        [2e5, 3e4, 1e5, 5e4, 5e4, 2e4],
        [4e4, 6e4, 8e4, 3e5, 3e5, 2e5],
    ];

    /// No payload, 5 kg 150 mm below the flange, 10 kg 80 mm off the tool axis.
    fn payload(i: usize) -> (f64, [f64; 3]) {
        [
            (0.0, [0.0, 0.0, 0.0]),
            (5.0, [0.0, 0.0, 150.0]),
            (10.0, [0.0, 80.0, 150.0]),
        ][i % 3]
    }

    /// One settle of `cmd` started as `start`: the tool position \[m\] and the report.
    fn settle_as(
        start: Start,
        effects: &Effects,
        conditions: &PoseConditions,
        four_bar_bodies: bool,
        cmd: &[f64; 6],
    ) -> (nalgebra::Vector3<f64>, axiscal::sim::SettleReport) {
        let desc = RobotDescription::asea_irb6l();
        let mut truth = axiscal::sim::paper_robot();
        for j in &mut truth.joints {
            j.repeatability_sigma = 0.0;
        }
        let mut options = RapierArmOptions::new(6);
        options.four_bar_bodies = four_bar_bodies;
        options.settle.warm_start = !matches!(start, Start::Cold);
        if matches!(start, Start::Cold | Start::Warm) {
            options.settle.approach_max_steps = 0;
        }
        if !matches!(start, Start::Fast) {
            options.settle.approach_leaps = 0;
        }
        if !matches!(start, Start::Fast | Start::NoLeap) {
            options.settle.decay_steps = 0;
            options.settle.solver_iterations = OLD_SOLVER_ITERATIONS;
        }
        let mut arm = RapierArm::new(truth, &desc, effects.clone(), options);
        let links = arm
            .execute(cmd, conditions, &mut ChaCha12Rng::seed_from_u64(3))
            .expect("settles");
        let report = arm.last_settle().expect("dynamic mode").clone();
        (
            (links[5] * desc.nominal_model().last_link_from_tool).translation.vector,
            report,
        )
    }

    /// The fast settle (warm start, long-step approach, then the 1 ms settle, both ended by
    /// the decay rule) lands where the old stepping did: from the undeflected command (cold,
    /// pure time stepping: the rest is rapier's whatever the prediction says), from the
    /// prediction alone, and from the approach with the 20 quiet steps (main's previous
    /// default). A settle stopped at speed `v_tol` still has about `v_tol tau` to go, `tau` the
    /// slowest mode's time constant, and `tau` is shorter than the cold settle's duration
    /// `steps dt` (in which every mode decayed by orders of magnitude): so two settles agree
    /// within `v_tol dt steps_cold`; the decay rule's own bound on what it left (20 nm) is
    /// checked as reported. The cost is counted in substeps (steps times solver iterations:
    /// each rebuilds the multibody's mass matrix). Shapes varied: the paper truth (bevel gear 4->5 emulated) with
    /// the four-bar as bodies and emulated, three poses across the range, three stiffness
    /// sets, payloads of 0, 5 kg below the flange and 10 kg off the tool axis.
    #[test]
    fn the_fast_settle_lands_where_the_old_stepping_does_in_fewer_steps() {
        let poses: [[f64; 6]; 3] = [
            CMD,
            [-0.4, 0.3, -0.2, -1.0, 0.7, -0.5],
            [1.0, -0.5, 0.6, 1.5, -1.2, 2.0],
        ];
        let options = RapierArmOptions::new(6).settle;
        let (mut fast_substeps, mut previous_substeps, mut no_leap_substeps) = (0, 0, 0);
        for (s, stiffness) in STIFFNESS_SETS.iter().enumerate() {
            for (p, cmd) in poses.iter().enumerate() {
                let (payload_kg, com_in_tool_mm) = payload(s + p);
                let effects = Effects {
                    compliance: Some(compliance(*stiffness)),
                    payload: (payload_kg > 0.0).then_some(PayloadEffect { com_in_tool_mm }),
                    ..Effects::default()
                };
                let conditions = PoseConditions {
                    payload_kg,
                    ..PoseConditions::default()
                };
                for four_bar_bodies in [true, false] {
                    let settle = |start| settle_as(start, &effects, &conditions, four_bar_bodies, cmd);
                    let (cold, cold_report) = settle(Start::Cold);
                    let (warm, warm_report) = settle(Start::Warm);
                    let (previous, previous_report) = settle(Start::Approach);
                    let (no_leap, no_leap_report) = settle(Start::NoLeap);
                    let (fast, fast_report) = settle(Start::Fast);
                    let bound_m = options.speed_tolerance_m_s * options.dt_s * cold_report.steps as f64;
                    let d = [cold, warm, previous, no_leap].map(|other| (fast - other).norm());
                    eprintln!(
                        "K {stiffness:?} payload {payload_kg} kg four-bar bodies {four_bar_bodies} cmd {}: steps cold {} \
                         warm {} approach {} + {} no leap {} + {} fast {} + {} (residual {:.2e} m/s, left {:.1e} m); \
                         tool from cold {:.2e} m, warm {:.2e} m, approach {:.2e} m, no leap {:.2e} m, bound {bound_m:.2e} m",
                        cmd[0],
                        cold_report.steps,
                        warm_report.steps,
                        previous_report.approach_steps,
                        previous_report.steps,
                        no_leap_report.approach_steps,
                        no_leap_report.steps,
                        fast_report.approach_steps,
                        fast_report.steps,
                        fast_report.max_speed_m_s,
                        fast_report.distance_left_m.unwrap_or(f64::NAN),
                        d[0],
                        d[1],
                        d[2],
                        d[3]
                    );
                    assert!(d.iter().all(|&d| d < bound_m), "{d:?} against {bound_m}");
                    // It really settled at rapier's 1 ms steps: the decaying steps were
                    // taken there and the arm was at rest in them.
                    assert!(fast_report.steps > options.decay_steps);
                    assert!(fast_report.max_speed_m_s < options.speed_tolerance_m_s);
                    assert!(
                        fast_report
                            .distance_left_m
                            .is_none_or(|left| left < options.distance_left_m)
                    );
                    assert!(fast_report.approach_steps > 0);
                    assert!(warm_report.steps < cold_report.steps);
                    fast_substeps += fast_report.total_steps() * options.solver_iterations;
                    previous_substeps += previous_report.total_steps() * OLD_SOLVER_ITERATIONS;
                    no_leap_substeps += no_leap_report.total_steps() * options.solver_iterations;
                }
            }
        }
        eprintln!(
            "substeps of all poses: fast {fast_substeps}, without leaps {no_leap_substeps}, approach with 20 quiet \
             steps {previous_substeps}"
        );
        assert!(fast_substeps < no_leap_substeps);
        assert!(no_leap_substeps < previous_substeps);
    }

    /// The dynamic mode (four-bar, coupled targets, paper truth) is deterministic: two fresh
    /// arms give bit-identical link poses.
    #[test]
    fn the_dynamic_mode_is_bit_identical_run_twice() {
        let desc = RobotDescription::asea_irb6l();
        let truth = axiscal::sim::paper_robot();
        let effects = Effects {
            compliance: Some(compliance([5e5, 3e5, 3e5, 5e4, 5e4, 2e4])),
            ..Effects::default()
        };
        let run = || {
            let mut arm = RapierArm::new(truth.clone(), &desc, effects.clone(), RapierArmOptions::new(6));
            let links = arm
                .execute(&CMD, &PoseConditions::default(), &mut ChaCha12Rng::seed_from_u64(3))
                .expect("settles");
            links
                .iter()
                .flat_map(|l| l.to_homogeneous().iter().map(|x| x.to_bits()).collect::<Vec<_>>())
                .collect::<Vec<u64>>()
        };
        assert_eq!(run(), run());
    }
}

mod line_of_sight {
    use axiscal::physics::AxisWobble;
    use axiscal::plan::PoseConditions;
    use axiscal::robot::{RobotDescription, RobotModel};
    use axiscal::sim::{ArmExecutor, Effects};
    use axiscal::sim::{RapierArm, RapierArmOptions};
    use nalgebra::{Isometry3, Point3, Vector3};
    use rand::SeedableRng;
    use rand::rngs::ChaCha12Rng;

    const CMD: [f64; 6] = [0.3, -0.2, 0.25, 0.4, -0.6, 0.8];

    fn executed(
        truth: &RobotModel,
        effects: Effects,
        stations_m: Vec<Point3<f64>>,
        four_bar_bodies: bool,
    ) -> (RapierArm, Vec<Isometry3<f64>>) {
        let desc = RobotDescription::asea_irb6l();
        let options = RapierArmOptions {
            stations_m,
            four_bar_bodies,
            ..RapierArmOptions::new(6)
        };
        let mut arm = RapierArm::new(truth.clone(), &desc, effects, options);
        let links = arm
            .execute(&CMD, &PoseConditions::default(), &mut ChaCha12Rng::seed_from_u64(1))
            .expect("executes");
        (arm, links)
    }

    /// A station looking at a target across the middle of the coupler rod, along axis 2 (the
    /// rod lies in the plane normal to it, 0.2 m from the upper arm, so that line passes 0.2 m
    /// from every link capsule): hidden with the four-bar's bodies, seen without them.
    #[test]
    fn a_ray_blocked_only_by_the_rod_is_occluded() {
        let mut truth = axiscal::sim::paper_robot();
        for j in &mut truth.joints {
            j.repeatability_sigma = 0.0;
        }
        let (probe, links) = executed(&truth, Effects::default(), vec![], true);
        let sim = probe.sim_arm().expect("built");
        let rod_m = truth.four_bars[0].geometry.rod_m;
        let (rod_pose, _) = probe.four_bars()[0].placed_shapes(sim)[1].clone();
        let middle = rod_pose * Point3::new(rod_m / 2.0, 0.0, 0.0);
        let axis2 = links[1] * Vector3::z();
        let station = middle - axis2 * 3.0;
        let target = middle + axis2 * 0.5;
        let (with_bodies, _) = executed(&truth, Effects::default(), vec![station], true);
        let (without, _) = executed(&truth, Effects::default(), vec![station], false);
        assert!(!with_bodies.visible(&target), "the rod should hide the target");
        assert!(without.visible(&target), "only the rod is in the way");
    }

    /// Axis wobble moves the link capsules too: joint 1 tilted by 0.1 rad moves a point
    /// 0.6 of the way up the upper arm by `d` (42 mm); a ray perpendicular to both the upper
    /// arm and `d`, passing 30 mm from the wobbled arm's axis on the side it moved to, passes
    /// about `|d| + 30 mm` (more than 60 mm) from the unwobbled axis: hidden by the 50 mm
    /// capsule only when the wobble is applied to the shapes.
    #[test]
    fn line_of_sight_uses_the_wobbled_link_poses() {
        let mut truth = axiscal::sim::paper_robot();
        for j in &mut truth.joints {
            j.repeatability_sigma = 0.0;
        }
        let wobble = Effects {
            wobble: vec![AxisWobble {
                joint: 1,
                amplitude_rad: 0.1,
                phase_rad: 0.0,
                order: 1,
                fixed_direction_rad: None,
            }],
            ..Effects::default()
        };
        let (_, straight) = executed(&truth, Effects::default(), vec![], false);
        let (_, tilted) = executed(&truth, wobble.clone(), vec![], false);
        let along = truth.phi_model().link_from_next_frame(1) * Point3::origin();
        let on_axis = |links: &[Isometry3<f64>]| links[1] * (along * 0.6);
        let d = on_axis(&tilted) - on_axis(&straight);
        let u = d.normalize();
        let arm_dir = (tilted[1] * along - tilted[1] * Point3::origin()).normalize();
        let w = u.cross(&arm_dir).normalize();
        let x = on_axis(&tilted) + u * 0.03;
        let station = x - w * 3.0;
        let target = x + w * 0.5;
        assert!(d.norm() > 0.03, "wobble displacement {} m", d.norm());
        let (tilted_arm, _) = executed(&truth, wobble, vec![station], false);
        let (straight_arm, _) = executed(&truth, Effects::default(), vec![station], false);
        assert!(!tilted_arm.visible(&target), "the wobbled upper arm is in the way");
        assert!(straight_arm.visible(&target), "the unwobbled upper arm is not");
    }
}
