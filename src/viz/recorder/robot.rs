//! The robot in a recording: link frames, a skeleton through the joint origins, slim boxes
//! for the links, and the four-bar loop.

use super::{Recorder, vec3};
use crate::kinematics::PhiModel;
use crate::viz::{ROBOT_COLOR, segment_boxes};
use nalgebra::Point3;

/// Half-width of the link boxes \[m\].
const LINK_HALF_WIDTH_M: f32 = 0.025;
/// Length of the drawn link-frame axes \[m\].
const FRAME_AXIS_LENGTH_M: f32 = 0.12;

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
    /// \[m\], e.g. from [`crate::viz::four_bar_loop_m`]).
    pub fn log_four_bar(&self, points_m: &[Point3<f64>]) {
        let strip = rerun::LineStrips3D::new([points_m.iter().map(vec3).collect::<Vec<_>>()])
            .with_radii([0.005_f32])
            .with_colors([[200_u8, 90, 30, 255]]);
        self.log("world/robot/four_bar", &strip);
    }
}
