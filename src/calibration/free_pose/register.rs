//! The instrument frame and the targets on the last link, from the nominal kinematics alone, in
//! closed form (no user guess).
//!
//! A target `t` at `y_t` in the tool frame is measured at pose `i` at
//! `m_it = R (p_i + R_i y_t) + p`, with `(R_i, p_i)` the nominal tool frame in the base frame
//! and `(R, p)` the base in the instrument frame. `R R_i y_t = sum_j (y_tj R) R_i e_j` is linear
//! in the 3x9 matrix `Y_t = [y_t1 R, y_t2 R, y_t3 R]`, so with `M = R` relaxed to any 3x3
//! matrix every coordinate of `m_it` is linear in `(M, Y_1..Y_T, p)`: the linearisation of
//! the hand-eye problem `AX = YB` by Kronecker products (Andreff, Horaud & Espiau, *On-line
//! hand-eye calibration*, 3DIM 1999; Shah, *Solving the robot-world/hand-eye calibration
//! problem using the Kronecker product*, J. Mech. Robot. 5 (2013) 031007). `R` is then the
//! rotation nearest `M` (Higham's polar factor, through its SVD), `y_tj = tr(R^T Y_tj) / 3`,
//! and a few alternations of the two exact sub-problems (Horn's rigid fit for `(R, p)` given
//! the targets; the mean of `R_i^T (R^T (m_it - p) - p_i)` for the targets given `(R, p)`)
//! take the relaxed solution to a consistent one. The fit that follows refines everything.

use crate::kinematics::rigid_fit;
use crate::numerics::lsq::TruncatedSvd;
use nalgebra::{DMatrix, DVector, Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};

/// Alternations of the two exact sub-problems at most.
const ALTERNATIONS: usize = 50;

/// The alternation stops when the registration's RMS changes by less than this fraction.
const SETTLED: f64 = 1e-9;

/// Relative singular-value threshold of the linear solve (exact redundancies only: a design
/// whose poses all share an orientation leaves the targets' `Y` blocks undetermined).
const LINEAR_TOLERANCE: f64 = 1e-10;

/// One measured point for the registration.
#[derive(Clone, Copy, Debug)]
pub struct Observation {
    /// The pose (index into `base_from_tool`).
    pub pose: usize,
    /// The target's slot.
    pub slot: usize,
    /// Measured position in the instrument frame \[m\].
    pub measured_m: Point3<f64>,
}

/// The registration: the base in the instrument frame and the targets in the tool frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Registration {
    /// The robot's base frame in the instrument frame.
    pub world_from_base: Isometry3<f64>,
    /// Each target slot's position in the tool frame \[m\].
    pub targets_in_tool_m: Vec<Point3<f64>>,
    /// RMS distance of the measured points from the registered nominal model \[m\].
    pub rms_m: f64,
}

/// The registration of `observations` (targets `0..slots`) against the nominal tool frames
/// `base_from_tool` of each pose (module docs). `None` when the points do not fix a frame
/// (fewer than three non-collinear tool positions).
///
/// The alternation also starts from every target at the tool frame's origin; the better of
/// the two ends is kept (the linear solve is ill-posed when the tool turns about one direction
/// only, as a SCARA's does: its relaxed solution can be far off).
pub fn register(base_from_tool: &[Isometry3<f64>], observations: &[Observation], slots: usize) -> Option<Registration> {
    let starts = [
        linear_start(base_from_tool, observations, slots),
        flange_start(base_from_tool, observations, slots),
    ];
    starts
        .into_iter()
        .flatten()
        .filter_map(|start| alternate(base_from_tool, observations, slots, start))
        .min_by(|a, b| a.rms_m.total_cmp(&b.rms_m))
}

/// The alternation of the two exact sub-problems from `start` (module docs).
fn alternate(
    base_from_tool: &[Isometry3<f64>],
    observations: &[Observation],
    slots: usize,
    (mut world_from_base, mut targets): (Isometry3<f64>, Vec<Point3<f64>>),
) -> Option<Registration> {
    let mut rms = f64::INFINITY;
    for _ in 0..ALTERNATIONS {
        world_from_base = fit_base(base_from_tool, observations, &targets).unwrap_or(world_from_base);
        targets = fit_targets(base_from_tool, observations, slots, &world_from_base, &targets);
        let next = rms_of(base_from_tool, observations, &world_from_base, &targets);
        let settled = (rms - next).abs() <= SETTLED * next.max(f64::MIN_POSITIVE);
        rms = next;
        if settled {
            break;
        }
    }
    rms.is_finite().then_some(Registration {
        world_from_base,
        targets_in_tool_m: targets,
        rms_m: rms,
    })
}

/// The relaxed linear solution and its projection (module docs).
fn linear_start(
    base_from_tool: &[Isometry3<f64>],
    observations: &[Observation],
    slots: usize,
) -> Option<(Isometry3<f64>, Vec<Point3<f64>>)> {
    let unknowns = 4 + 9 * slots;
    if observations.len() < unknowns {
        return flange_start(base_from_tool, observations, slots);
    }
    let mut a = DMatrix::zeros(observations.len(), unknowns);
    let mut b = DMatrix::zeros(observations.len(), 3);
    for (row, o) in observations.iter().enumerate() {
        let t = &base_from_tool[o.pose];
        let r = t.rotation.to_rotation_matrix();
        for c in 0..3 {
            a[(row, c)] = t.translation.vector[c];
            for k in 0..3 {
                a[(row, 3 + 9 * o.slot + 3 * c + k)] = r[(k, c)];
            }
            b[(row, c)] = o.measured_m[c];
        }
        a[(row, unknowns - 1)] = 1.0;
    }
    let solve = TruncatedSvd::new(&a, LINEAR_TOLERANCE);
    let x: Vec<DVector<f64>> = (0..3).map(|c| solve.solve(&b.column(c).into_owned())).collect();
    let m = Matrix3::from_fn(|row, col| x[row][col]);
    let rotation = nearest_rotation(&m)?;
    let translation = Vector3::from_fn(|row, _| x[row][unknowns - 1]);
    let targets = (0..slots)
        .map(|s| {
            Point3::from(Vector3::from_fn(|j, _| {
                let y = Matrix3::from_fn(|row, k| x[row][3 + 9 * s + 3 * j + k]);
                (rotation.matrix().transpose() * y).trace() / 3.0
            }))
        })
        .collect();
    Some((
        Isometry3::from_parts(
            Translation3::from(translation),
            UnitQuaternion::from_rotation_matrix(&rotation),
        ),
        targets,
    ))
}

/// Too few points for the linear solve: every target at the tool frame's origin, the base by
/// the rigid fit of the tool origins onto the points.
fn flange_start(
    base_from_tool: &[Isometry3<f64>],
    observations: &[Observation],
    slots: usize,
) -> Option<(Isometry3<f64>, Vec<Point3<f64>>)> {
    let targets = vec![Point3::origin(); slots];
    fit_base(base_from_tool, observations, &targets).map(|base| (base, targets))
}

/// The rotation nearest `m` in the Frobenius norm (`U V^T` with the sign of the smallest
/// singular direction fixed to make it proper). `None` for a non-finite `m`.
fn nearest_rotation(m: &Matrix3<f64>) -> Option<Rotation3<f64>> {
    if !m.iter().all(|v| v.is_finite()) {
        return None;
    }
    let svd = m.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let mut d = Matrix3::identity();
    if (u * v_t).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    Some(Rotation3::from_matrix_unchecked(u * d * v_t))
}

/// The base frame given the targets: Horn's rigid fit of the predicted points in the base frame
/// onto the measured ones.
pub(super) fn fit_base(
    base_from_tool: &[Isometry3<f64>],
    observations: &[Observation],
    targets: &[Point3<f64>],
) -> Option<Isometry3<f64>> {
    let src: Vec<Point3<f64>> = observations
        .iter()
        .map(|o| base_from_tool[o.pose] * targets[o.slot])
        .collect();
    let dst: Vec<Point3<f64>> = observations.iter().map(|o| o.measured_m).collect();
    rigid_fit(&src, &dst).map(|(t, _)| t)
}

/// The targets given the base: each the mean of its points brought into the tool frame (the
/// exact least-squares solution, the tool rotations being orthogonal). A slot without points
/// keeps its previous position.
fn fit_targets(
    base_from_tool: &[Isometry3<f64>],
    observations: &[Observation],
    slots: usize,
    world_from_base: &Isometry3<f64>,
    previous: &[Point3<f64>],
) -> Vec<Point3<f64>> {
    let mut sum = vec![Vector3::zeros(); slots];
    let mut count = vec![0usize; slots];
    for o in observations {
        let in_tool = (world_from_base * base_from_tool[o.pose]).inverse_transform_point(&o.measured_m);
        sum[o.slot] += in_tool.coords;
        count[o.slot] += 1;
    }
    (0..slots)
        .map(|s| match count[s] {
            0 => previous[s],
            n => Point3::from(sum[s] / n as f64),
        })
        .collect()
}

/// RMS distance of the points from the registered model \[m\].
fn rms_of(
    base_from_tool: &[Isometry3<f64>],
    observations: &[Observation],
    world_from_base: &Isometry3<f64>,
    targets: &[Point3<f64>],
) -> f64 {
    let sum: f64 = observations
        .iter()
        .map(|o| (o.measured_m - world_from_base * (base_from_tool[o.pose] * targets[o.slot])).norm_squared())
        .sum();
    (sum / observations.len().max(1) as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng, rngs::ChaCha12Rng};

    /// Random tool frames, a hidden base and targets, exact points: the closed form recovers
    /// them to rounding (a second path: the points are made by composing isometries, not by the
    /// linear design).
    #[test]
    fn recovers_base_and_targets_from_exact_points() {
        let mut rng = ChaCha12Rng::seed_from_u64(7);
        for slots in 1..=3 {
            let tools: Vec<Isometry3<f64>> = (0..20)
                .map(|_| {
                    let t = Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0));
                    let r = Vector3::from_fn(|_, _| rng.random_range(-2.0..2.0));
                    Isometry3::new(t, r)
                })
                .collect();
            let base = Isometry3::new(Vector3::new(2.0, -1.0, 0.5), Vector3::new(0.3, -2.5, 1.0));
            let targets: Vec<Point3<f64>> = (0..slots)
                .map(|_| Point3::from(Vector3::from_fn(|_, _| rng.random_range(-0.2..0.2))))
                .collect();
            let obs: Vec<Observation> = (0..tools.len())
                .flat_map(|i| (0..slots).map(move |s| (i, s)))
                .map(|(i, s)| Observation {
                    pose: i,
                    slot: s,
                    measured_m: base * (tools[i] * targets[s]),
                })
                .collect();
            let reg = register(&tools, &obs, slots).expect("registration");
            assert!(reg.rms_m < 1e-12, "rms {}", reg.rms_m);
            assert!((reg.world_from_base.translation.vector - base.translation.vector).norm() < 1e-12);
            assert!(reg.world_from_base.rotation.angle_to(&base.rotation) < 1e-12);
            for (a, b) in reg.targets_in_tool_m.iter().zip(&targets) {
                assert!((a - b).norm() < 1e-12);
            }
        }
    }
}
