//! The test cube of ISO 9283:1998 (6.2, 6.8) and the commands that reach its five points: a
//! cube of edge `L`, axis-aligned with the robot base frame, centred on the tool position of a
//! centre configuration; `P1` its centre, `P2` .. `P5` on the diagonal plane `C1-C2-C7-C8` at
//! 10 % of that plane's diagonal from the corners (`P = P1 + 0.8 (C - P1)`), all with the
//! centre's tool orientation.

use crate::compensation::Compensator;
use crate::robot::{RobotDescription, commands_to_file, commands_to_internal};
use nalgebra::{Isometry3, Point3, Translation3, Vector3};

/// The five points `P1` .. `P5` of a cube of edge `edge_m` centred on `centre` (world frame),
/// axes those of `world_from_base`, orientation `centre`'s.
pub fn cube_points(centre: &Isometry3<f64>, world_from_base: &Isometry3<f64>, edge_m: f64) -> [Isometry3<f64>; 5] {
    let h = 0.5 * edge_m;
    // Corners C1, C2, C7, C8 of the diagonal plane, in base-frame axes.
    let corners = [
        Vector3::new(-h, -h, -h),
        Vector3::new(h, -h, -h),
        Vector3::new(h, h, h),
        Vector3::new(-h, h, h),
    ];
    std::array::from_fn(|i| {
        let d = if i == 0 { Vector3::zeros() } else { 0.8 * corners[i - 1] };
        let p: Point3<f64> = Point3::from(centre.translation.vector) + world_from_base.rotation * d;
        Isometry3::from_parts(Translation3::from(p.coords), centre.rotation)
    })
}

/// The joints (1-based) whose commands `cmd` (internal units) are outside the description's
/// limits.
fn outside_limits(desc: &RobotDescription, cmd: &[f64]) -> Vec<usize> {
    (0..desc.dof())
        .filter(|&k| {
            let [lo, hi] = desc.limits_internal(k);
            cmd[k] < lo || cmd[k] > hi
        })
        .map(|k| k + 1)
        .collect()
}

/// Why a cube cannot be planned.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum CubeError {
    /// The centre commands do not reach a pose.
    #[error("the centre commands: {0}")]
    Centre(String),
    /// A point has no commands inside the limits.
    #[error("P{point} of a {edge_mm:.0} mm cube: {problem}")]
    Unreachable {
        /// 1-based point.
        point: usize,
        /// The edge \[mm\].
        edge_mm: f64,
        /// Why.
        problem: String,
    },
    /// The robot's tool does not reach 3-D positions: no centre has a cube.
    #[error(
        "an ISO 9283 cube needs a robot whose tool reaches positions in three dimensions (P1 .. P5 span the cube's tilted diagonal plane), at least {MIN_CUBE_JOINTS} joints; {robot} has {joints}: the ISO 9283 test does not apply to it"
    )]
    TooFewJoints {
        /// The robot's name.
        robot: String,
        /// Its joints.
        joints: usize,
    },
    /// A cube of the edge asked for reaches a point out of reach or beyond the joint limits.
    #[error(
        "P{point} of a {edge_mm:.0} mm cube is out of reach or beyond the joint limits ({problem}): {}",
        largest_words(*largest_mm)
    )]
    TooLarge {
        /// The point (1-5).
        point: usize,
        /// The edge asked for \[mm\].
        edge_mm: f64,
        /// Why the point is not reached.
        problem: String,
        /// The largest edge, in whole centimetres, whose five points are reached \[mm\];
        /// `None` when no cube of 10 mm is.
        largest_mm: Option<f64>,
    },
    /// Not even the smallest cube fits.
    #[error(
        "no cube of 10 mm or more around the centre has all five points inside the joint limits (a centre at a singular configuration, such as a stretched arm, has none): choose another centre"
    )]
    NoCube,
}

/// The fewest joints that move a tool through three dimensions of position: each joint adds
/// at most one, and `P1` .. `P5` span three (their plane is tilted against every base axis).
pub const MIN_CUBE_JOINTS: usize = 3;

/// Refuses a robot with fewer than [`MIN_CUBE_JOINTS`] joints, whatever its centre
/// ([`CubeError::TooFewJoints`]).
pub fn check_cube_robot(desc: &RobotDescription) -> Result<(), CubeError> {
    if desc.dof() < MIN_CUBE_JOINTS {
        return Err(CubeError::TooFewJoints {
            robot: desc.name.clone(),
            joints: desc.dof(),
        });
    }
    Ok(())
}

/// A planned cube: its edge, its points and the commands that reach them.
#[derive(Clone, Debug, PartialEq)]
pub struct Cube {
    /// The edge \[m\].
    pub edge_m: f64,
    /// `P1` .. `P5`, world frame.
    pub points: [Isometry3<f64>; 5],
    /// The commands of `P1` .. `P5`, file units (deg or mm).
    pub commands: Vec<Vec<f64>>,
}

/// The cube of edge `edge_m` around the tool pose of `centre_cmd` (file units): `P1`'s
/// commands are `centre_cmd`, the others' come through `compensator` (fig. 5, seeded from the
/// centre: the same branch), inside the description's limits.
pub fn plan_cube(
    compensator: &Compensator,
    desc: &RobotDescription,
    centre_cmd: &[f64],
    edge_m: f64,
) -> Result<Cube, CubeError> {
    check_cube_robot(desc)?;
    let centre_internal = commands_to_internal(desc, centre_cmd);
    if let Some(k) = outside_limits(desc, &centre_internal).first() {
        return Err(CubeError::Centre(format!(
            "cmd_{k} = {} is outside the joint's limits {:?}",
            centre_cmd[k - 1],
            desc.joints[k - 1].limits
        )));
    }
    let centre_q = compensator
        .calibrated_joint_values(&centre_internal)
        .map_err(|e| CubeError::Centre(e.to_string()))?;
    let model = compensator.calibrated_model();
    let points = cube_points(&model.world_from_tool(&centre_q), &model.world_from_base, edge_m);
    let mut commands = Vec::with_capacity(5);
    for (i, p) in points.iter().enumerate() {
        let unreachable = |problem: String| CubeError::Unreachable {
            point: i + 1,
            edge_mm: edge_m * 1e3,
            problem,
        };
        if i == 0 {
            // P1 is the centre's own pose: its commands, exactly.
            commands.push(centre_cmd.to_vec());
            continue;
        }
        let c = compensator
            .compensate_from(p, &centre_q)
            .map_err(|e| unreachable(e.to_string()))?;
        let outside = outside_limits(desc, &c.cmd);
        if !outside.is_empty() {
            return Err(unreachable(format!("joint(s) {outside:?} outside their limits")));
        }
        commands.push(commands_to_file(desc, &c.cmd));
    }
    Ok(Cube {
        edge_m,
        points,
        commands,
    })
}

/// The largest cube (edge to 10 mm, at most `max_edge_m`) whose five points [`plan_cube`]
/// reaches.
pub fn largest_cube(
    compensator: &Compensator,
    desc: &RobotDescription,
    centre_cmd: &[f64],
    max_edge_m: f64,
) -> Result<Cube, CubeError> {
    check_cube_robot(desc)?;
    let mut edge_cm = (max_edge_m * 1e2).floor() as usize;
    while edge_cm >= 1 {
        match plan_cube(compensator, desc, centre_cmd, edge_cm as f64 * 1e-2) {
            Ok(c) => return Ok(c),
            Err(CubeError::Centre(e)) => return Err(CubeError::Centre(e)),
            Err(_) => edge_cm -= 1,
        }
    }
    Err(CubeError::NoCube)
}

/// The cube of edge `edge_m` ([`plan_cube`]); when one of its points is not reached,
/// [`CubeError::TooLarge`] with the largest edge that is ([`largest_cube`]).
pub fn cube_of_edge(
    compensator: &Compensator,
    desc: &RobotDescription,
    centre_cmd: &[f64],
    edge_m: f64,
) -> Result<Cube, CubeError> {
    match plan_cube(compensator, desc, centre_cmd, edge_m) {
        Err(CubeError::Unreachable {
            point,
            edge_mm,
            problem,
        }) => Err(CubeError::TooLarge {
            point,
            edge_mm,
            problem,
            largest_mm: largest_cube(compensator, desc, centre_cmd, edge_m)
                .ok()
                .map(|c| c.edge_m * 1e3),
        }),
        planned => planned,
    }
}

/// What [`CubeError::TooLarge`] says of the largest cube.
fn largest_words(largest_mm: Option<f64>) -> String {
    match largest_mm {
        Some(mm) => format!(
            "the largest cube around this centre whose five points are reached inside the joint limits has an edge of {mm:.0} mm: plan an edge of {mm:.0} mm or less (--edge-mm)"
        ),
        None => "no cube of 10 mm or more around this centre has its five points inside the joint limits (a centre at a singular configuration, such as a stretched arm, has none): choose another centre".into(),
    }
}

/// The commands that approach each of `cube`'s points from `distance_m` along base axis
/// `axis` (0, 1, 2: x, y, z), on its negative side (ISO 9283 7.2.3: the multi-directional
/// test approaches each pose from three directions parallel to the base axes), through
/// `compensator` seeded from the centre; each inside the limits.
pub fn approach_commands(
    compensator: &Compensator,
    desc: &RobotDescription,
    cube: &Cube,
    axis: usize,
    distance_m: f64,
) -> Result<Vec<Vec<f64>>, CubeError> {
    let model = compensator.calibrated_model();
    let centre_q = compensator
        .calibrated_joint_values(&commands_to_internal(desc, &cube.commands[0]))
        .map_err(|e| CubeError::Centre(e.to_string()))?;
    let offset = model.world_from_base.rotation * Vector3::ith(axis, -distance_m);
    cube.points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let unreachable = |problem: String| CubeError::Unreachable {
                point: i + 1,
                edge_mm: cube.edge_m * 1e3,
                problem: format!("its approach along base {}: {problem}", ["x", "y", "z"][axis]),
            };
            let target = Isometry3::from_parts(Translation3::from(p.translation.vector + offset), p.rotation);
            let c = compensator
                .compensate_from(&target, &centre_q)
                .map_err(|e| unreachable(e.to_string()))?;
            let outside = outside_limits(desc, &c.cmd);
            if !outside.is_empty() {
                return Err(unreachable(format!("joint(s) {outside:?} outside their limits")));
            }
            Ok(commands_to_file(desc, &c.cmd))
        })
        .collect()
}
