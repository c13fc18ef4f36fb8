//! Free-pose calibration on simulated campaigns of several robots, and the Jacobian against
//! central differences.

use super::*;
use crate::measurement::Measurement;
use crate::robot::{RobotDescription, Transmission, commands_to_file};
use nalgebra::{DMatrix, DVector, Point3, Vector3};
use rand::{RngExt, SeedableRng, rngs::ChaCha12Rng};
use rand_distr::{Distribution, Normal};
use std::path::Path;

fn shipped(name: &str) -> RobotDescription {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenarios/robots/{name}.toml"));
    RobotDescription::from_file(&path).expect("shipped description")
}

fn seven_axis() -> RobotDescription {
    shipped("arm7-dh")
}

/// Per-coordinate noise of the simulated instrument \[m\].
const NOISE_M: f64 = 5e-5;

/// Targets on the last link (tool frame) \[m\]: one to three of them.
fn targets(count: usize) -> Vec<Point3<f64>> {
    [[0.03, 0.02, 0.10], [0.11, 0.02, 0.09], [0.03, 0.10, 0.11]]
        .iter()
        .take(count)
        .map(|p| Point3::from(*p))
        .collect()
}

/// Random commands within 80 % of each joint's limits (file units).
fn commands(desc: &RobotDescription, poses: usize, rng: &mut ChaCha12Rng) -> Vec<Vec<f64>> {
    (0..poses)
        .map(|_| {
            let internal: Vec<f64> = (0..desc.dof())
                .map(|k| {
                    let [lo, hi] = desc.limits_internal(k);
                    let mid = 0.5 * (lo + hi);
                    mid + 0.8 * (hi - lo) * (rng.random::<f64>() - 0.5)
                })
                .collect();
            commands_to_file(desc, &internal)
        })
        .collect()
}

/// The configurations of a simulated campaign.
#[derive(Clone, Copy, Debug)]
enum Shape<'a> {
    /// Random configurations within 80 % of each joint's limits; the fit takes them all, the
    /// z-score campaigns twice as many with every other one held out.
    Free(usize),
    /// One sweep per entry `(joint, span_deg, points)` in this order, each at its own random
    /// configuration of the other joints (within 80 % of their limits), ascending; every
    /// other point held out.
    Sweeps(&'a [Sweep]),
}

/// One sweep of a simulated campaign: `(joint, span_deg, points)`.
type Sweep = (usize, f64, usize);

impl Shape<'_> {
    /// Whether every z-score is expected below 5 (Gaussian: once in 1.7 million). Not for
    /// partial sweeps (joints never swept, one configuration per swept joint): there the
    /// weakest combinations scatter beyond their linearised sigma (seeds 1000-1049: largest
    /// |z| 7.6 on the 6R arm, 5.8 on the IRB/L6, the mean square still within its bound).
    fn tail_bounded(&self, joints: usize) -> bool {
        match self {
            Shape::Free(_) => true,
            Shape::Sweeps(sweeps) => (1..=joints).all(|k| sweeps.iter().any(|s| s.0 == k)),
        }
    }
}

/// One sweep per entry of `sweeps`, each at its own random configuration (file units).
fn sweep_commands(desc: &RobotDescription, sweeps: &[Sweep], rng: &mut ChaCha12Rng) -> Vec<Vec<f64>> {
    let mut out = Vec::new();
    for &(joint, span_deg, points) in sweeps {
        let held = commands(desc, 1, rng).remove(0);
        let k = joint - 1;
        let [lo, hi] = desc.limits_internal(k);
        let span = span_deg.to_radians().min(hi - lo);
        let internal = crate::robot::commands_to_internal(desc, &held);
        let centre = internal[k].clamp(lo + span / 2.0, hi - span / 2.0);
        for i in 0..points {
            let mut q = internal.clone();
            q[k] = centre - span / 2.0 + span * i as f64 / (points - 1) as f64;
            out.push(commands_to_file(desc, &q));
        }
    }
    out
}

/// The measurement set of `truth` at `cmds` with isotropic noise `NOISE_M`: the points made by
/// the robot model's own forward kinematics (`RobotModel::joint_values`, `PhiModel`).
fn measure(desc: &RobotDescription, truth: &FreePoseModel, cmds: &[Vec<f64>], rng: &mut ChaCha12Rng) -> MeasurementSet {
    let robot = truth.to_robot();
    let phi = robot.phi_model();
    let controller = Controller::from_description(desc);
    let normal = Normal::new(0.0, NOISE_M).expect("noise");
    let mut rows = Vec::new();
    for (step, cmd) in cmds.iter().enumerate() {
        let q = robot
            .joint_values(&controller, &crate::robot::commands_to_internal(desc, cmd))
            .expect("executable");
        let tool = phi.world_from_tool(&q);
        for (&target, y) in truth.target_ids.iter().zip(&truth.targets_in_tool_m) {
            let p = tool * y + Vector3::from_fn(|_, _| normal.sample(rng));
            rows.push(Measurement {
                experiment: "poses".into(),
                moved_joint: 0,
                step,
                target,
                position_mm: [p.x * 1e3, p.y * 1e3, p.z * 1e3],
                cmd: cmd.clone(),
                payload_kg: 0.0,
                temperature_c: 20.0,
            });
        }
    }
    MeasurementSet::new(desc.dof(), rows).expect("valid set")
}

/// A truth: the nominal robot placed in the instrument, with the targets, moved along the
/// parameters `which` by errors of 1 mm / 1 mrad scale (harmonics 1 mrad).
fn truth(desc: &RobotDescription, target_count: usize, which: &[String], rng: &mut ChaCha12Rng) -> FreePoseModel {
    let nominal = RobotModel::ideal(desc);
    let ids: Vec<usize> = (0..target_count).collect();
    let layout = layout(&nominal, &ids, 1, &vec![std::f64::consts::TAU; desc.dof()], 1);
    let start = FreePoseModel::new(
        &nominal,
        nominal.phi_model().world_from_base,
        ids,
        targets(target_count),
    );
    let columns: Vec<usize> = (0..layout.len())
        .filter(|&c| which.contains(&layout[c].name()))
        .collect();
    let delta = DVector::from_fn(columns.len(), |_, _| 1e-3 * (2.0 * rng.random::<f64>() - 1.0));
    start.moved(&layout, &columns, &delta)
}

/// The configurations of `shape`: the fit's (`twice`: the z-score campaigns', half of them
/// held out).
fn configurations(desc: &RobotDescription, shape: Shape<'_>, twice: bool, rng: &mut ChaCha12Rng) -> Vec<Vec<f64>> {
    match shape {
        Shape::Free(poses) => commands(desc, if twice { 2 * poses } else { poses }, rng),
        Shape::Sweeps(sweeps) => sweep_commands(desc, sweeps, rng),
    }
}

/// The options of a z-score fit: every other configuration held out, harmonics of order 1.
fn fit_options(holdout: bool) -> FreePoseOptions {
    FreePoseOptions {
        holdout,
        max_harmonic_order: 1,
        ..FreePoseOptions::default()
    }
}

/// The names of the parameters a campaign of the nominal robot identifies.
fn identified(desc: &RobotDescription, target_count: usize, poses: usize) -> Vec<String> {
    let mut rng = ChaCha12Rng::seed_from_u64(0);
    let nominal = truth(desc, target_count, &[], &mut rng);
    let cmds = commands(desc, poses, &mut rng);
    identified_at(desc, &nominal, &cmds, false, &mut rng)
}

/// The names of the parameters a campaign of `nominal` at the configurations `cmds`
/// identifies (with every other configuration held out: `holdout`).
fn identified_at(
    desc: &RobotDescription,
    nominal: &FreePoseModel,
    cmds: &[Vec<f64>],
    holdout: bool,
    rng: &mut ChaCha12Rng,
) -> Vec<String> {
    let set = measure(desc, nominal, cmds, rng);
    let cal = calibrate_free_poses(&set, desc, &fit_options(holdout)).expect("calibration");
    cal.summary.parameters.iter().map(|p| p.name.clone()).collect()
}

/// A campaign's truth and configurations: a truth moved along the parameters a free-pose
/// campaign of the shape identifies (`names`), or, for sweeps at random configurations,
/// along those this campaign's own configurations identify (which joints' parameters the
/// few configurations resolve depends on them).
fn campaign(
    desc: &RobotDescription,
    target_count: usize,
    shape: Shape<'_>,
    names: &[String],
    rng: &mut ChaCha12Rng,
) -> (FreePoseModel, Vec<Vec<f64>>) {
    match shape {
        Shape::Free(_) => {
            let truth = truth(desc, target_count, names, rng);
            (truth, configurations(desc, shape, true, rng))
        }
        Shape::Sweeps(_) => {
            let cmds = configurations(desc, shape, true, rng);
            let nominal = truth(desc, target_count, &[], &mut ChaCha12Rng::seed_from_u64(0));
            let own = identified_at(desc, &nominal, &cmds, true, &mut ChaCha12Rng::seed_from_u64(0));
            (truth(desc, target_count, &own, rng), cmds)
        }
    }
}

/// The z-scores `(estimate - truth) / sigma` of every fitted parameter but the base's over
/// `seeds` campaigns, the held-out RMS over the noise's 3-D RMS of each, and the sum over the
/// campaigns of `tr(R^2)`, `R` the correlation matrix of the scored parameters: the variance
/// of the sum of the squared z-scores is twice it (the z-scores of one campaign are
/// correlated Gaussians).
fn z_scores(
    desc: &RobotDescription,
    target_count: usize,
    shape: Shape<'_>,
    seeds: std::ops::Range<u64>,
) -> (Vec<f64>, Vec<f64>, f64) {
    let names = match shape {
        Shape::Free(poses) => identified(desc, target_count, poses),
        Shape::Sweeps(_) => vec![],
    };
    let (mut z, mut ratio, mut trace_r2) = (Vec::new(), Vec::new(), 0.0);
    for seed in seeds {
        let mut rng = ChaCha12Rng::seed_from_u64(seed);
        let (truth, cmds) = campaign(desc, target_count, shape, &names, &mut rng);
        let set = measure(desc, &truth, &cmds, &mut rng);
        let cal = calibrate_free_poses(&set, desc, &fit_options(true)).expect("calibration");
        let layout = layout(
            &cal.model.robot,
            &cal.model.target_ids,
            1,
            &vec![std::f64::consts::TAU; desc.dof()],
            1,
        );
        for p in cal.summary.parameters.iter().filter(|p| !p.name.starts_with("base")) {
            let param = layout.iter().find(|l| l.name() == p.name).expect("in layout");
            let true_value = summary::value_of(param, &truth).expect("value") * p.unit.per_si();
            z.push((p.value.expect("value") - true_value) / p.sigma);
        }
        let scored: Vec<usize> = (0..cal.summary.parameters.len())
            .filter(|&i| !cal.summary.parameters[i].name.starts_with("base"))
            .collect();
        let r = &cal.summary.correlation;
        trace_r2 += scored
            .iter()
            .flat_map(|&i| scored.iter().map(move |&j| r[i][j] * r[i][j]))
            .sum::<f64>();
        let h = cal.summary.holdout.expect("holdout");
        ratio.push(h.calibrated_rms_mm / (NOISE_M * 3f64.sqrt() * 1e3));
    }
    (z, ratio, trace_r2)
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

/// Every robot shape: the fitted parameters agree with the truth within their sigmas (the
/// mean squared z-score within 4 standard errors of 1; its standard error `sqrt(2 sum tr(R^2))
/// / n`, `sqrt(2 / n)` for independent scores, printed as the bound on the RMS, half of it),
/// and the held-out RMS is at the noise floor (within 4 standard errors of the ratio's own
/// spread, 30 % here).
fn check_robot(desc: &RobotDescription, target_count: usize, shape: Shape<'_>, seeds: std::ops::Range<u64>) {
    let (z, ratio, trace_r2) = z_scores(desc, target_count, shape, seeds);
    let n = z.len() as f64;
    let bound_sq = 4.0 * (2.0 * trace_r2).sqrt() / n;
    let bound = bound_sq / 2.0;
    let z_rms = rms(&z);
    assert!(
        (z_rms * z_rms - 1.0).abs() < bound_sq,
        "{}: z RMS {z_rms:.3} over {n} scores (bound {bound:.3})",
        desc.name
    );
    let worst = z.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if shape.tail_bounded(desc.dof()) {
        assert!(worst < 5.0, "{}: a z-score of {worst:.2}", desc.name);
    }
    let mean_ratio = ratio.iter().sum::<f64>() / ratio.len() as f64;
    eprintln!(
        "{}: z RMS {z_rms:.3} over {n} scores (bound {bound:.3}), largest |z| {worst:.2}, held-out RMS / noise {mean_ratio:.3}",
        desc.name
    );
    assert!(
        (0.9..1.3).contains(&mean_ratio),
        "{}: held-out RMS / noise {mean_ratio:.3}",
        desc.name
    );
}

#[test]
fn six_axis_arm_with_parallel_axes_three_targets() {
    check_robot(&shipped("arm6-dh"), 3, Shape::Free(60), 1..4);
}

/// The calibrated model's predictions at new configurations against the truth's, each point's
/// error in its predicted covariance `J C J^T` (`C` from the reported sigmas and correlations):
/// `d^2 / 3` averaged over the points of one campaign has expectation 1 when the sigmas are
/// honest. Invariant under the redundancies the parameters leave (on a SCARA, a common height
/// of the targets equals the base's: the registration picks one, the truth another, and the
/// parameters' z-scores compare different gauges). Returns one mean per seed.
fn prediction_check(
    desc: &RobotDescription,
    target_count: usize,
    poses: usize,
    seeds: std::ops::Range<u64>,
) -> Vec<f64> {
    let names = identified(desc, target_count, poses);
    let controller = Controller::from_description(desc);
    seeds
        .map(|seed| {
            let mut rng = ChaCha12Rng::seed_from_u64(seed);
            let truth = truth(desc, target_count, &names, &mut rng);
            let set = measure(desc, &truth, &commands(desc, poses, &mut rng), &mut rng);
            let options = FreePoseOptions {
                max_harmonic_order: 0,
                ..FreePoseOptions::default()
            };
            let cal = calibrate_free_poses(&set, desc, &options).expect("calibration");
            let fresh = measure_exact(desc, &truth, &commands(desc, 50, &mut rng));
            let poses = FreePoses::from_set(&fresh, desc, false).expect("poses");
            let layout = layout(&cal.model.robot, &cal.model.target_ids, 0, &[], 1);
            let columns: Vec<usize> = cal
                .summary
                .parameters
                .iter()
                .map(|p| layout.iter().position(|l| l.name() == p.name).expect("in layout"))
                .collect();
            let which: Vec<usize> = (0..poses.poses.len()).collect();
            let (r, j) = cal
                .model
                .residuals_and_jacobian(&controller, &poses, &which, &layout, &columns)
                .expect("prediction");
            let sd: Vec<f64> = cal
                .summary
                .parameters
                .iter()
                .map(|p| p.sigma / p.unit.per_si())
                .collect();
            let c = DMatrix::from_fn(sd.len(), sd.len(), |a, b| cal.summary.correlation[a][b] * sd[a] * sd[b]);
            let points = r.len() / 3;
            let d2: f64 = (0..points)
                .map(|k| {
                    let jk = j.rows(3 * k, 3);
                    let cov = jk * &c * jk.transpose();
                    let e = r.fixed_rows::<3>(3 * k).into_owned();
                    let inv = nalgebra::Matrix3::from_fn(|a, b| cov[(a, b)])
                        .try_inverse()
                        .expect("covariance");
                    (e.transpose() * inv * e)[(0, 0)]
                })
                .sum();
            d2 / (3.0 * points as f64)
        })
        .collect()
}

/// The points of `truth` at `cmds` without noise.
fn measure_exact(desc: &RobotDescription, truth: &FreePoseModel, cmds: &[Vec<f64>]) -> MeasurementSet {
    let mut rng = ChaCha12Rng::seed_from_u64(0);
    let noisy = measure(desc, truth, cmds, &mut rng);
    let robot = truth.to_robot();
    let phi = robot.phi_model();
    let controller = Controller::from_description(desc);
    let rows = noisy
        .rows()
        .iter()
        .map(|r| {
            let q = robot
                .joint_values(&controller, &crate::robot::commands_to_internal(desc, &r.cmd))
                .expect("executable");
            let slot = truth.target_ids.binary_search(&r.target).expect("target");
            let p = phi.world_from_tool(&q) * truth.targets_in_tool_m[slot];
            Measurement {
                position_mm: [p.x * 1e3, p.y * 1e3, p.z * 1e3],
                ..r.clone()
            }
        })
        .collect();
    MeasurementSet::new(desc.dof(), rows).expect("set")
}

/// The predictions' errors in their sigmas average 1 over ten campaigns, within 4 standard
/// errors of the seeds' own spread, on the SCARA and on the 6R arm.
#[test]
fn predictions_are_within_their_sigmas() {
    check_predictions(1..11);
}

fn check_predictions(seeds: std::ops::Range<u64>) {
    for (desc, targets) in [(shipped("scara-rrpr"), 3), (shipped("arm6-dh"), 1)] {
        let per_seed = prediction_check(&desc, targets, 60, seeds.clone());
        let n = per_seed.len() as f64;
        let mean = per_seed.iter().sum::<f64>() / n;
        let sd = (per_seed.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        eprintln!(
            "{}: prediction d^2/3 mean {mean:.3} over {n} campaigns (sd {sd:.3})",
            desc.name
        );
        assert!(
            (mean - 1.0).abs() < 4.0 * sd / n.sqrt(),
            "{}: mean d^2/3 {mean:.3} (per seed {per_seed:.3?})",
            desc.name
        );
    }
}

#[test]
fn seven_axis_arm_two_targets() {
    check_robot(&seven_axis(), 2, Shape::Free(80), 1..4);
}

/// Sweeps at per-sweep configurations, as real campaigns take them: a 6R arm with joints 1,
/// 2, 5 and 6 swept once each (3 and 4 never, spans 95-270 deg, 20-55 points, one target); a
/// 6R arm with every joint swept twice at two configurations; a 7R arm with every joint swept
/// once, two targets; the coupled IRB/L6 with joints 2, 3 and 5 swept, three targets.
fn sweep_campaigns() -> [(RobotDescription, usize, &'static [Sweep]); 4] {
    const ARM6_PARTIAL: &[Sweep] = &[(1, 120.0, 24), (2, 95.0, 20), (5, 200.0, 40), (6, 270.0, 55)];
    const ARM6_ONCE: [Sweep; 6] = [
        (1, 90.0, 15),
        (2, 80.0, 15),
        (3, 80.0, 15),
        (4, 120.0, 15),
        (5, 120.0, 15),
        (6, 180.0, 15),
    ];
    const ARM6_TWICE: &[Sweep] = &{
        let mut out = [(0, 0.0, 0); 12];
        let mut i = 0;
        while i < 12 {
            out[i] = ARM6_ONCE[i % 6];
            i += 1;
        }
        out
    };
    const SEVEN: &[Sweep] = &[
        (1, 120.0, 20),
        (2, 100.0, 20),
        (3, 120.0, 20),
        (4, 100.0, 20),
        (5, 120.0, 20),
        (6, 100.0, 20),
        (7, 180.0, 20),
    ];
    const IRB_PARTIAL: &[Sweep] = &[(2, 60.0, 25), (3, 50.0, 25), (5, 150.0, 25)];
    [
        (shipped("arm6-dh"), 1, ARM6_PARTIAL),
        (shipped("arm6-dh"), 3, ARM6_TWICE),
        (seven_axis(), 2, SEVEN),
        (shipped("asea-irb6l"), 3, IRB_PARTIAL),
    ]
}

#[test]
fn sweeps_at_their_own_configurations() {
    for (desc, targets, sweeps) in sweep_campaigns() {
        check_robot(&desc, targets, Shape::Sweeps(sweeps), 1..4);
    }
}

#[test]
fn coupled_arm_one_target() {
    check_robot(&shipped("asea-irb6l"), 1, Shape::Free(80), 1..4);
}

/// The 50-seed check (release build: `cargo test --release --lib free_pose -- --ignored`).
#[test]
#[ignore]
fn fifty_seeds_per_robot() {
    check_robot(&shipped("arm6-dh"), 3, Shape::Free(100), 100..150);
    check_robot(&seven_axis(), 2, Shape::Free(100), 100..150);
    check_robot(&shipped("asea-irb6l"), 1, Shape::Free(100), 100..150);
    for (desc, targets, sweeps) in sweep_campaigns() {
        check_robot(&desc, targets, Shape::Sweeps(sweeps), 1000..1050);
    }
    check_predictions(100..150);
}

/// The analytic Jacobian against central differences of the residuals through
/// [`FreePoseModel::moved`], on the coupled IRB/L6 with harmonic transmissions. The central
/// difference errs by `h^2 / 6 |r'''|` (lever arms of metres: ~1e-12 m at `h = 1e-6`) plus
/// rounding `eps |r| / h` (~1e-9 m for points metres from the origin): the tolerance is 10x
/// their sum.
#[test]
fn jacobian_matches_central_differences() {
    let desc = shipped("asea-irb6l");
    let mut rng = ChaCha12Rng::seed_from_u64(3);
    let mut robot = RobotModel::ideal(&desc);
    for j in &mut robot.joints {
        j.transmission = Transmission::Harmonic {
            sin: vec![2e-3, -1e-3],
            cos: vec![1e-3, 5e-4],
        };
        j.transducer_offset = 2e-3;
    }
    let (model, poses, layout) = six_poses_two_targets(&desc, &robot, &mut rng);
    let all: Vec<usize> = (0..layout.len()).collect();
    check_against_central_differences(&desc, &model, &poses, &layout, &all);
}

/// `robot` placed as its nominal with targets 0 and 4, measured at 6 random poses, and the
/// layout of every parameter (harmonics to order 2 over full turns): what the Jacobian tests
/// difference.
fn six_poses_two_targets(
    desc: &RobotDescription,
    robot: &RobotModel,
    rng: &mut ChaCha12Rng,
) -> (FreePoseModel, FreePoses, Vec<RefitParameter>) {
    let model = FreePoseModel::new(robot, robot.phi_model().world_from_base, vec![0, 4], targets(2));
    let set = measure(desc, &model, &commands(desc, 6, rng), rng);
    let poses = FreePoses::from_set(&set, desc, false).expect("poses");
    let layout = layout(robot, &model.target_ids, 2, &vec![std::f64::consts::TAU; desc.dof()], 1);
    (model, poses, layout)
}

/// The gear forms' columns (a gear transmission's harmonics in the gear angle, a gear
/// coupling's in `N t`) against central differences, at harmonics away from 0: the IRB/L6's
/// joint 5 as the description fits it (`with_fit_forms`).
#[test]
fn gear_forms_jacobian_matches_central_differences() {
    let desc = shipped("asea-irb6l");
    let mut rng = ChaCha12Rng::seed_from_u64(5);
    let mut robot = super::model::with_fit_forms(RobotModel::ideal(&desc), &desc);
    assert!(matches!(robot.joints[4].transmission, Transmission::Gear { .. }));
    if let Transmission::Gear { sin, cos, .. } = &mut robot.joints[4].transmission {
        *sin = vec![0.04, -2e-3];
        *cos = vec![1e-3, 5e-4];
    }
    for j in robot.joints.iter_mut().skip(1) {
        if let Some(crate::robot::CouplingFunction::Gear { sin, cos, .. }) = &mut j.coupling_in {
            *sin = vec![-0.04, 1e-3];
            *cos = vec![2e-3, -1e-3];
        }
    }
    let (model, poses, layout) = six_poses_two_targets(&desc, &robot, &mut rng);
    let gear: Vec<usize> = (0..layout.len())
        .filter(|&c| super::model::harmonic_order(&layout[c]).is_some())
        .collect();
    assert!(
        gear.iter()
            .any(|&c| matches!(layout[c], RefitParameter::Coupling { .. })),
        "no coupling harmonic laid out"
    );
    check_against_central_differences(&desc, &model, &poses, &layout, &gear);
}

/// The analytic columns `columns` of `layout` at `model` against central differences of the
/// residual (step 1e-6: truncation `h^2 / 6` of a third derivative of order 10 m, rounding
/// `eps 10 m / h`, ten times both).
fn check_against_central_differences(
    desc: &RobotDescription,
    model: &FreePoseModel,
    poses: &FreePoses,
    layout: &[RefitParameter],
    columns: &[usize],
) {
    let controller = Controller::from_description(desc);
    let which: Vec<usize> = (0..poses.poses.len()).collect();
    let (r0, jac) = model
        .residuals_and_jacobian(&controller, poses, &which, layout, columns)
        .expect("jacobian");
    let h = 1e-6;
    let tolerance = 10.0 * (h * h / 6.0 * 10.0 + f64::EPSILON * 10.0 / h);
    for (k, &c) in columns.iter().enumerate() {
        let step = |s: f64| {
            let moved = model.moved(layout, &[c], &DVector::from_element(1, s));
            moved.residuals(&controller, poses, &which).expect("residuals")
        };
        let fd = (step(h) - step(-h)) / (2.0 * h);
        let err = (fd - jac.column(k)).amax();
        assert!(
            err < tolerance,
            "{}: analytic vs central difference {err:.3e}",
            layout[c].name()
        );
    }
    assert_eq!(r0.len(), 3 * poses.points());
}

/// The effects' columns (`robot.effects`) against central differences, on a robot with
/// transmission harmonics, poses arriving from both sides and payloads varying. With a
/// backlash and no sag every column is exact; with a sag, the sag's own columns are (the
/// geometry's leave out the sag's regressors' change with the geometry, a first-order term of
/// the sag's size: `crate::robot::ModelEffects`).
#[test]
fn effect_columns_match_central_differences() {
    let desc = shipped("arm6-dh");
    let mut rng = ChaCha12Rng::seed_from_u64(8);
    let mut robot = RobotModel::ideal(&desc);
    for j in &mut robot.joints {
        j.transmission = Transmission::Harmonic {
            sin: vec![1e-3],
            cos: vec![-5e-4],
        };
    }
    let mut model = FreePoseModel::new(&robot, robot.phi_model().world_from_base, vec![0, 1], targets(2));
    let mut set = measure(&desc, &model, &commands(&desc, 12, &mut rng), &mut rng);
    let rows: Vec<Measurement> = set
        .rows()
        .iter()
        .map(|m| Measurement {
            payload_kg: (m.step % 3) as f64 * 2.5,
            ..m.clone()
        })
        .collect();
    set = MeasurementSet::new(desc.dof(), rows).expect("valid set");
    let poses = FreePoses::from_set(&set, &desc, false).expect("poses");
    let train: Vec<usize> = (0..poses.poses.len()).collect();
    let mut layout = layout(
        &robot,
        &model.target_ids,
        1,
        &vec![std::f64::consts::TAU; desc.dof()],
        1,
    );
    let geometry = layout.len();
    layout.extend(effects::effect_layout(&robot, &poses, &train));
    let backlash: Vec<usize> = (geometry..layout.len())
        .filter(|&c| matches!(layout[c], RefitParameter::Backlash { .. }))
        .collect();
    let sag: Vec<usize> = (geometry..layout.len())
        .filter(|&c| matches!(layout[c], RefitParameter::Sag { .. }))
        .collect();
    assert!(backlash.len() >= 3 && sag.len() > 40, "{backlash:?} {}", sag.len());
    let half_bands = DVector::from_fn(backlash.len(), |k, _| 2e-4 * (1.0 + k as f64));
    model = model.moved(&layout, &backlash, &half_bands);
    let all: Vec<usize> = (0..layout.len()).collect();
    check_against_central_differences(&desc, &model, &poses, &layout, &all);
    let coefficients = DVector::from_fn(sag.len(), |k, _| 1e-5 * ((k % 7) as f64 - 3.0));
    let sagging = model.moved(&layout, &sag, &coefficients);
    assert!(
        (0..poses.poses.len()).any(|i| sagging
            .residuals(&Controller::from_description(&desc), &poses, &[i])
            .unwrap()
            != model
                .residuals(&Controller::from_description(&desc), &poses, &[i])
                .unwrap()),
        "the sag moves the points"
    );
    check_against_central_differences(&desc, &sagging, &poses, &layout, &sag);
}

/// One corrupted cell (a pose's joint-6 reading 50 deg off, as a hand edit or a swapped column
/// makes it) is flagged by experiment and step and left out: the other parameters agree with
/// the truth as on clean data, and with `keep_outliers` the pose is flagged but kept.
#[test]
fn a_corrupted_pose_is_flagged_and_dropped() {
    let desc = shipped("arm6-dh");
    let names = identified(&desc, 3, 60);
    let mut rng = ChaCha12Rng::seed_from_u64(11);
    let truth = truth(&desc, 3, &names, &mut rng);
    let mut cmds = commands(&desc, 60, &mut rng);
    let clean = measure(&desc, &truth, &cmds, &mut rng);
    cmds[17][5] += 50.0;
    let rows: Vec<Measurement> = clean
        .rows()
        .iter()
        .map(|r| Measurement {
            cmd: cmds[r.step].clone(),
            ..r.clone()
        })
        .collect();
    let set = MeasurementSet::new(desc.dof(), rows).expect("set");
    let options = FreePoseOptions {
        max_harmonic_order: 0,
        ..FreePoseOptions::default()
    };
    let cal = calibrate_free_poses(&set, &desc, &options).expect("calibration");
    let flagged: Vec<(usize, bool)> = cal.summary.outliers.iter().map(|o| (o.step, o.dropped)).collect();
    assert_eq!(flagged, vec![(17, true)]);
    let layout = layout(&cal.model.robot, &cal.model.target_ids, 0, &[], 1);
    for p in cal.summary.parameters.iter().filter(|p| !p.name.starts_with("base")) {
        let param = layout.iter().find(|l| l.name() == p.name).expect("in layout");
        let z =
            (p.value.expect("value") - summary::value_of(param, &truth).expect("value") * p.unit.per_si()) / p.sigma;
        assert!(z.abs() < 5.0, "{}: z {z:.2}", p.name);
    }
    let kept = FreePoseOptions {
        keep_outliers: true,
        ..options
    };
    let cal = calibrate_free_poses(&set, &desc, &kept).expect("calibration");
    assert!(cal.summary.outliers.iter().any(|o| o.step == 17 && !o.dropped));
}

/// Two setups (the instrument moved by metres and turned between the halves of the campaign,
/// the file's `setup` column): one calibration places the base in both instrument frames and
/// recovers the robot's parameters within their sigmas, and setup `B`'s base within its own.
#[test]
fn two_setups_calibrate_together() {
    let desc = shipped("arm6-dh");
    let names = identified(&desc, 2, 40);
    let (mut z, mut base_z) = (Vec::new(), Vec::new());
    for seed in 1..4 {
        let mut rng = ChaCha12Rng::seed_from_u64(seed);
        let mut truth = truth(&desc, 2, &names, &mut rng);
        let second = nalgebra::Isometry3::new(Vector3::new(-2.0, 1.5, 0.3), Vector3::new(0.1, -0.2, 2.5))
            * truth.phi.world_from_base;
        truth.other_bases = vec![second];
        let cmds = commands(&desc, 80, &mut rng);
        let first = measure(&desc, &truth, &cmds[..40], &mut rng);
        let mut moved = truth.clone();
        moved.phi.world_from_base = second;
        let other = measure(&desc, &moved, &cmds[40..], &mut rng);
        let rows: Vec<Measurement> = first
            .rows()
            .iter()
            .cloned()
            .chain(other.rows().iter().map(|r| Measurement {
                step: r.step + 40,
                ..r.clone()
            }))
            .collect();
        let setups: Vec<usize> = rows.iter().map(|r| usize::from(r.step >= 40)).collect();
        let set = MeasurementSet::new(desc.dof(), rows)
            .expect("set")
            .with_setups(setups, vec!["A".into(), "B".into()]);
        let options = FreePoseOptions {
            max_harmonic_order: 0,
            ..FreePoseOptions::default()
        };
        let cal = calibrate_free_poses(&set, &desc, &options).expect("calibration");
        let layout = layout(&cal.model.robot, &cal.model.target_ids, 0, &[], 2);
        for p in cal.summary.parameters.iter().filter(|p| !p.name.contains("base")) {
            let param = layout.iter().find(|l| l.name() == p.name).expect("in layout");
            let true_value = summary::value_of(param, &truth).expect("value") * p.unit.per_si();
            z.push((p.value.expect("value") - true_value) / p.sigma);
        }
        let fitted = cal.model.world_from_base(1).translation.vector;
        for (axis, sigma) in ["x", "y", "z"]
            .iter()
            .map(|a| {
                let name = format!("setup1.base.{a}");
                cal.summary
                    .parameters
                    .iter()
                    .find(|p| p.name == name)
                    .map(|p| p.sigma * 1e-3)
            })
            .enumerate()
        {
            if let Some(sigma) = sigma {
                base_z.push((fitted[axis] - second.translation.vector[axis]) / sigma);
            }
        }
    }
    let bound = 4.0 / (2.0 * z.len() as f64).sqrt();
    assert!(
        (rms(&z) - 1.0).abs() < bound,
        "z RMS {:.3} over {} (bound {bound:.3})",
        rms(&z),
        z.len()
    );
    assert!(
        base_z.len() == 9 && base_z.iter().all(|v| v.abs() < 5.0),
        "setup B's base: {base_z:.2?}"
    );
}

/// The predicted tool 1-sigma of a free-pose calibration (its `model_covariance`, propagated
/// through the robot's parameter vector by central differences and then through
/// `ToolSensitivity`'s own differences) equals the direct propagation through the free-pose
/// model's analytic Jacobian of a target at the tool frame's origin, `J C J^T` with `C` from
/// the reported sigmas and correlations, to the differences' truncation (1e-3 relative).
#[test]
fn the_predicted_tool_sigma_matches_the_direct_propagation() {
    let desc = shipped("arm6-dh");
    let mut rng = ChaCha12Rng::seed_from_u64(21);
    let names = identified(&desc, 1, 60);
    let truth = truth(&desc, 1, &names, &mut rng);
    let set = measure(&desc, &truth, &commands(&desc, 60, &mut rng), &mut rng);
    let fp = calibrate_free_poses(&set, &desc, &fit_options(false)).expect("calibration");
    let controller = Controller::from_description(&desc);
    let cov = fp.model_covariance.clone().expect("model covariance").matrix();
    let sensitivity = crate::calibration::tool_accuracy::ToolSensitivity::new(&fp.robot, &controller, &cov);
    // The direct path: the fitted model with its one target moved to the tool origin.
    let mut at_tool = fp.model.clone();
    at_tool.targets_in_tool_m = vec![Point3::origin()];
    let cmds = commands(&desc, 5, &mut rng);
    let fresh = measure_exact(&desc, &at_tool, &cmds);
    let poses = FreePoses::from_set(&fresh, &desc, false).expect("poses");
    let layout = layout(
        &fp.model.robot,
        &fp.model.target_ids,
        1,
        &vec![std::f64::consts::TAU; desc.dof()],
        1,
    );
    let fitted: Vec<(usize, &ParameterEstimate)> = fp
        .summary
        .parameters
        .iter()
        .enumerate()
        .filter(|(_, p)| !p.name.starts_with("target"))
        .collect();
    let columns: Vec<usize> = fitted
        .iter()
        .map(|(_, p)| layout.iter().position(|l| l.name() == p.name).expect("in layout"))
        .collect();
    let sd: Vec<f64> = fitted.iter().map(|(_, p)| p.sigma / p.unit.per_si()).collect();
    let c = DMatrix::from_fn(sd.len(), sd.len(), |a, b| {
        fp.summary.correlation[fitted[a].0][fitted[b].0] * sd[a] * sd[b]
    });
    let which: Vec<usize> = (0..poses.poses.len()).collect();
    let (_, j) = at_tool
        .residuals_and_jacobian(&controller, &poses, &which, &layout, &columns)
        .expect("jacobian");
    for (k, cmd) in cmds.iter().enumerate() {
        let jk = j.rows(3 * k, 3);
        let direct_mm = (jk * &c * jk.transpose()).trace().sqrt() * 1e3;
        let internal = crate::robot::commands_to_internal(&desc, cmd);
        let predicted_mm = sensitivity.sigma_at(&internal).expect("sigma").position_norm_mm;
        assert!(
            (predicted_mm - direct_mm).abs() <= 1e-3 * direct_mm,
            "pose {k}: predicted {predicted_mm:.6} mm, direct {direct_mm:.6} mm"
        );
    }
}
