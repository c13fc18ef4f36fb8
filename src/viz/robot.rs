//! The robot in a recording: link frames, a skeleton through the joint origins, slim boxes
//! for the links, and the four-bar loop.

use super::{Recorder, vec3};
use crate::kinematics::PhiModel;
use crate::robot::FourBarGeometry;
use nalgebra::{Isometry3, Point3, Rotation3, Unit, UnitQuaternion, Vector3};

/// Half-width of the link boxes \[m\].
const LINK_HALF_WIDTH_M: f32 = 0.025;
/// Colour of the robot of [`Recorder::log_robot`] (the simulated one).
pub const ROBOT_COLOR: [u8; 4] = [150, 150, 160, 255];
/// Length of the drawn link-frame axes \[m\].
const FRAME_AXIS_LENGTH_M: f32 = 0.12;

/// One box per segment `points[i] -> points[i+1]` of a polyline: `(centre, half sizes,
/// rotation)`, the box's local x along the segment, `half_width` across. Zero-length segments
/// are skipped.
pub fn segment_boxes(
    points_m: &[Point3<f64>],
    half_width_m: f64,
) -> Vec<(Point3<f64>, Vector3<f64>, UnitQuaternion<f64>)> {
    points_m
        .windows(2)
        .filter_map(|w| {
            let d = w[1] - w[0];
            let length = d.norm();
            if length <= f64::EPSILON {
                return None;
            }
            let rotation = UnitQuaternion::rotation_between(&Vector3::x(), &d)
                // x and d antiparallel: half a turn about z.
                .unwrap_or_else(|| UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI));
            Some((
                nalgebra::center(&w[0], &w[1]),
                Vector3::new(length / 2.0, half_width_m, half_width_m),
                rotation,
            ))
        })
        .collect()
}

/// The closed loop `O2 -> C -> P -> O3 -> O2` of the 2->3 four-bar (the planar construction
/// documented with [`FourBarGeometry`]: arm, crank, rod, lever) in the world \[m\]: the linkage's plane is the one
/// through `O2` (origin of `world_from_frame2`, the fixed frame of axis 2) normal to axis 2;
/// its planar x axis is the arm direction `O2 -> O3` (projected in the plane) turned back by
/// `theta_2_rad`, the active displacement of joint 2; `passive_rad` is `g(theta_2)`.
pub fn four_bar_loop_m(
    geometry: &FourBarGeometry,
    world_from_frame2: &Isometry3<f64>,
    axis3_point_m: &Point3<f64>,
    theta_2_rad: f64,
    passive_rad: f64,
) -> [Point3<f64>; 5] {
    let o2 = world_from_frame2 * Point3::origin();
    let n = world_from_frame2 * Vector3::z_axis();
    let to_o3 = axis3_point_m - o2;
    let in_plane = to_o3 - n.into_inner() * n.dot(&to_o3);
    let arm = Unit::try_new(in_plane, 1e-9).unwrap_or(world_from_frame2 * Vector3::x_axis());
    let ex = Rotation3::from_axis_angle(&n, -theta_2_rad) * arm.into_inner();
    let ey = n.cross(&ex);
    let at = |radius: f64, angle: f64| radius * (angle.cos() * ex + angle.sin() * ey);
    let g = geometry;
    let o3 = o2 + at(g.arm_m, theta_2_rad);
    let c = o2 + at(g.crank_m, g.crank_angle_rad);
    let p = o3 + at(g.lever_m, theta_2_rad + g.lever_angle_rad + passive_rad);
    [o2, c, p, o3, o2]
}

impl Recorder {
    /// Logs the arm of `model` at joint values `q` (rad, m) under `world/robot`, in grey (see
    /// [`Recorder::log_robot_as`]).
    ///
    /// # Panics
    /// If `q.len() != model.dof()` (a programming error, as [`PhiModel::poses`]).
    pub fn log_robot(&self, model: &PhiModel, q: &[f64]) {
        self.log_robot_as("world/robot", model, q, ROBOT_COLOR);
    }

    /// Logs the arm of `model` at joint values `q` (rad, m) under the entity `root` (e.g.
    /// `world/nominal`, `world/calibrated`, so that two robots stand side by side):
    /// `{root}/link{k}` transforms (`world_from_link`, with drawn axes), a skeleton line strip
    /// through the fixed frames' origins and the tool origin, and a slim box per segment in
    /// `color`.
    ///
    /// # Panics
    /// If `q.len() != model.dof()` (a programming error, as [`PhiModel::poses`]).
    pub fn log_robot_as(&self, root: &str, model: &PhiModel, q: &[f64], color: [u8; 4]) {
        let poses = model.poses(q);
        for (k, link) in poses.world_from_link.iter().enumerate() {
            let t = link.translation.vector;
            let r = link.rotation.coords; // (i, j, k, w)
            let transform = rerun::Transform3D::from_translation_rotation(
                [t.x as f32, t.y as f32, t.z as f32],
                rerun::Quaternion::from_xyzw([r.x as f32, r.y as f32, r.z as f32, r.w as f32]),
            );
            let entity = format!("{root}/link{}", k + 1);
            self.log(entity.as_str(), &transform);
            self.log(entity.as_str(), &rerun::TransformAxes3D::new(FRAME_AXIS_LENGTH_M));
        }
        let mut joints: Vec<Point3<f64>> = poses.world_from_frame.iter().map(|f| f * Point3::origin()).collect();
        joints.push(poses.world_from_tool * Point3::origin());
        let skeleton = rerun::LineStrips3D::new([joints.iter().map(vec3).collect::<Vec<_>>()])
            .with_radii([0.004_f32])
            .with_colors([[40_u8, 40, 40, 255]]);
        self.log(&format!("{root}/skeleton"), &skeleton);
        let boxes = segment_boxes(&joints, f64::from(LINK_HALF_WIDTH_M));
        let links = rerun::Boxes3D::from_centers_and_half_sizes(
            boxes.iter().map(|(c, _, _)| vec3(c)),
            boxes.iter().map(|(_, h, _)| [h.x as f32, h.y as f32, h.z as f32]),
        )
        .with_quaternions(boxes.iter().map(|(_, _, r)| {
            let c = r.coords;
            rerun::Quaternion::from_xyzw([c.x as f32, c.y as f32, c.z as f32, c.w as f32])
        }))
        .with_colors([color]);
        self.log(&format!("{root}/links"), &links);
    }

    /// Logs the four-bar as a closed line strip at `world/robot/four_bar` (points in the world
    /// \[m\], e.g. from [`four_bar_loop_m`]).
    pub fn log_four_bar(&self, points_m: &[Point3<f64>]) {
        let strip = rerun::LineStrips3D::new([points_m.iter().map(vec3).collect::<Vec<_>>()])
            .with_radii([0.005_f32])
            .with_colors([[200_u8, 90, 30, 255]]);
        self.log("world/robot/four_bar", &strip);
    }
}
