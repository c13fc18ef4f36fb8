//! Forward kinematics of a serial arm in the phi-model, eq. (A1).
//!
//! Numbering: the paper counts joints and frames from 1; in code, index `k` (0-based)
//! is joint `k + 1`. Frame `k` is the fixed frame whose Z axis is joint axis `k` (it rides on
//! link `k - 1`), and "link `k`" is the moving frame `frame_k * Trans(0,0,d_k) Rot(z,theta_k)`:
//! everything joint `k` carries is expressed in it. Tool frame: link `N` times a fixed
//! `last_link_from_tool`.

use super::phi::{JointKind, PhiRow, joint_motion, link_from_phi};
use nalgebra::{Isometry3, Point3, Unit, Vector3};
use serde::{Deserialize, Serialize};

/// One joint of the phi-model: its kind and its constant angle `phi_i` (A2).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct PhiJoint {
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// The constant angle of Z_phi from X_i \[rad\] (A2); unused by the last joint.
    pub phi_rad: f64,
}

/// The kinematic geometry of an `N`-joint serial arm in the phi-model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PhiModel {
    /// The `N` joints, base first.
    pub joints: Vec<PhiJoint>,
    /// The `N - 1` rows of Table 2: `rows\[k\]` places frame `k + 2` in the `phi_{k+1}` frame.
    pub rows: Vec<PhiRow>,
    /// Frame 1 (the robot base frame, Z on axis 1) in the world (instrument) frame.
    pub world_from_base: Isometry3<f64>,
    /// The tool frame in the last link's moving frame.
    pub last_link_from_tool: Isometry3<f64>,
}

/// A joint axis as a line in some frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisLine {
    /// A point on the axis (the origin of frame `i`) \[m\].
    pub origin_m: Point3<f64>,
    /// The axis direction Z_i.
    pub direction: Unit<Vector3<f64>>,
}

/// Every frame of the chain at one joint configuration, in the world frame.
#[derive(Clone, Debug, PartialEq)]
pub struct ChainPoses {
    /// `world_from_frame\[k\]`: fixed frame of joint `k + 1` (Z on the axis).
    pub world_from_frame: Vec<Isometry3<f64>>,
    /// `world_from_link\[k\]`: moving frame of link `k + 1`.
    pub world_from_link: Vec<Isometry3<f64>>,
    /// The tool frame.
    pub world_from_tool: Isometry3<f64>,
}

impl ChainPoses {
    /// Joint axis `k` (0-based) as a line in the world frame.
    pub fn axis(&self, k: usize) -> AxisLine {
        let f = &self.world_from_frame[k];
        AxisLine {
            origin_m: f * Point3::origin(),
            direction: Unit::new_unchecked(f * Vector3::z()),
        }
    }
}

impl PhiModel {
    /// Number of joints `N`.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// Checks the shape of the model: `N >= 1` joints and `N - 1` rows.
    pub fn is_consistent(&self) -> bool {
        !self.joints.is_empty() && self.rows.len() + 1 == self.joints.len()
    }

    /// `frame_{k+1}` in `link_k` (0-based `k`): `Rot(z, phi_k) R0 * phi_T_{k+1}` (A1, A2 at
    /// zero motion).
    pub fn link_from_next_frame(&self, k: usize) -> Isometry3<f64> {
        link_from_phi(self.joints[k].phi_rad) * self.rows[k].phi_from_next()
    }

    /// All frames at joint values `q` (rad for revolute, m for prismatic joints).
    ///
    /// # Panics
    /// If `q.len() != self.dof()`: a programming error, not a data error.
    pub fn poses(&self, q: &[f64]) -> ChainPoses {
        self.poses_by(q, |k| self.link_from_next_frame(k))
    }

    /// The tool frame in the world frame at joint values `q`.
    pub fn world_from_tool(&self, q: &[f64]) -> Isometry3<f64> {
        self.world_from_tool_by(q, |k| self.link_from_next_frame(k))
    }

    /// The model's constant frames computed once, for the forward kinematics of many poses
    /// of one model: the same numbers as [`PhiModel::poses`] and
    /// [`PhiModel::world_from_tool`], bit for bit, without recomputing eq. (A1)'s fixed
    /// factors (four of every joint's five rotations) at each pose.
    pub fn fixed_frames(&self) -> FixedFrames {
        FixedFrames::new(self.clone())
    }

    /// [`PhiModel::poses`] with `link_from_next(k)` for [`PhiModel::link_from_next_frame`].
    fn poses_by(&self, q: &[f64], link_from_next: impl Fn(usize) -> Isometry3<f64>) -> ChainPoses {
        let mut world_from_frame = Vec::with_capacity(self.dof());
        let world_from_link = self.links_by(q, link_from_next, Some(&mut world_from_frame));
        let world_from_tool = world_from_link[self.dof() - 1] * self.last_link_from_tool;
        ChainPoses {
            world_from_frame,
            world_from_link,
            world_from_tool,
        }
    }

    /// `world_from_link` of [`Self::poses_by`], with each joint's fixed frame pushed onto
    /// `world_from_frame` if given.
    fn links_by(
        &self,
        q: &[f64],
        link_from_next: impl Fn(usize) -> Isometry3<f64>,
        mut world_from_frame: Option<&mut Vec<Isometry3<f64>>>,
    ) -> Vec<Isometry3<f64>> {
        assert_eq!(
            q.len(),
            self.dof(),
            "joint vector length must equal the number of joints"
        );
        let n = self.dof();
        let mut world_from_link = Vec::with_capacity(n);
        let mut frame = self.world_from_base;
        for (k, (joint, &qk)) in self.joints.iter().zip(q).enumerate() {
            if let Some(frames) = world_from_frame.as_deref_mut() {
                frames.push(frame);
            }
            let link = frame * joint_motion(joint.kind, qk);
            world_from_link.push(link);
            if k + 1 < n {
                frame = link * link_from_next(k);
            }
        }
        world_from_link
    }

    /// [`PhiModel::world_from_tool`] with `link_from_next(k)` for
    /// [`PhiModel::link_from_next_frame`].
    fn world_from_tool_by(&self, q: &[f64], link_from_next: impl Fn(usize) -> Isometry3<f64>) -> Isometry3<f64> {
        let n = self.dof();
        let mut t = self.world_from_base;
        for (k, (joint, &qk)) in self.joints.iter().zip(q).enumerate() {
            t *= joint_motion(joint.kind, qk);
            if k + 1 < n {
                t *= link_from_next(k);
            }
        }
        t * self.last_link_from_tool
    }

    /// A point fixed on link `k` (0-based), given in that link's moving frame, in the world.
    pub fn point_on_link(&self, q: &[f64], k: usize, point_in_link_m: &Point3<f64>) -> Point3<f64> {
        self.poses(q).world_from_link[k] * point_in_link_m
    }
}

/// A model with its constant frames, `frame_{k+1}` in `link_k` for every joint
/// ([`PhiModel::link_from_next_frame`]), computed once: the forward kinematics of many poses
/// of one model without recomputing them.
#[derive(Clone, Debug, PartialEq)]
pub struct FixedFrames {
    model: PhiModel,
    link_from_next_frame: Vec<Isometry3<f64>>,
}

impl FixedFrames {
    /// The frames of `model`.
    pub fn new(model: PhiModel) -> Self {
        let link_from_next_frame = (0..model.dof().saturating_sub(1))
            .map(|k| model.link_from_next_frame(k))
            .collect();
        FixedFrames {
            model,
            link_from_next_frame,
        }
    }

    /// The frames of `model`, each taken from `near` where its joint and row are `near`'s
    /// (the same numbers as [`FixedFrames::new`], bit for bit): the frames of a model that
    /// differs from another in a few rows, e.g. a central difference's.
    pub fn new_near(model: PhiModel, near: &FixedFrames) -> Self {
        let link_from_next_frame = (0..model.dof().saturating_sub(1))
            .map(|k| {
                let same = near.link_from_next_frame.len() > k
                    && model.joints[k] == near.model.joints[k]
                    && model.rows[k] == near.model.rows[k];
                if same {
                    near.link_from_next_frame[k]
                } else {
                    model.link_from_next_frame(k)
                }
            })
            .collect();
        FixedFrames {
            model,
            link_from_next_frame,
        }
    }

    /// The model these frames are of.
    pub fn model(&self) -> &PhiModel {
        &self.model
    }

    /// The model, consuming the frames.
    pub fn into_model(self) -> PhiModel {
        self.model
    }

    /// [`PhiModel::poses`], bit for bit.
    ///
    /// # Panics
    /// If `q.len() != self.model().dof()`: a programming error, not a data error.
    pub fn poses(&self, q: &[f64]) -> ChainPoses {
        self.model.poses_by(q, |k| self.link_from_next_frame[k])
    }

    /// The last link's moving frame in the world, `poses(q).world_from_link[N - 1]` bit for bit
    /// (the same products in the same order), without building the other frames.
    ///
    /// # Panics
    /// If `q.len() != self.model().dof()`: a programming error, not a data error.
    pub fn world_from_last_link(&self, q: &[f64]) -> Isometry3<f64> {
        let n = self.model.dof();
        assert_eq!(q.len(), n, "joint vector length must equal the number of joints");
        let mut frame = self.model.world_from_base;
        for (k, (joint, &qk)) in self.model.joints.iter().zip(q).enumerate() {
            let link = frame * joint_motion(joint.kind, qk);
            if k + 1 == n {
                return link;
            }
            frame = link * self.link_from_next_frame[k];
        }
        frame
    }

    /// [`Self::world_from_last_link`] at `q`, bit for bit, starting from the links `near_links`
    /// (`near.world_from_links(near_q)`) of frames `near` as far up the chain as the base,
    /// the joint values and the fixed frames below are the same to the bit (a link's frame is
    /// a product of those alone): the forward kinematics of a central difference's column that
    /// moves one row, the tool frame or nothing of the chain, from the point it is taken
    /// around.
    ///
    /// # Panics
    /// If `q`, `near_q` or `near_links` is shorter than `self.model().dof()`: a programming
    /// error, not a data error.
    pub fn world_from_last_link_near(
        &self,
        q: &[f64],
        near: &FixedFrames,
        near_q: &[f64],
        near_links: &[Isometry3<f64>],
    ) -> Isometry3<f64> {
        let n = self.model.dof();
        let mut kept = 0;
        if same_bits(&self.model.world_from_base, &near.model.world_from_base) {
            while kept < n
                && q[kept].to_bits() == near_q[kept].to_bits()
                && near.model.joints.get(kept).map(|j| j.kind) == Some(self.model.joints[kept].kind)
                && (kept == 0
                    || same_bits(
                        &self.link_from_next_frame[kept - 1],
                        &near.link_from_next_frame[kept - 1],
                    ))
            {
                kept += 1;
            }
        }
        if kept == n && n > 0 {
            return near_links[n - 1];
        }
        let mut frame = match kept {
            0 => self.model.world_from_base,
            k => near_links[k - 1] * self.link_from_next_frame[k - 1],
        };
        for (k, &qk) in q.iter().enumerate().take(n).skip(kept) {
            let link = frame * joint_motion(self.model.joints[k].kind, qk);
            if k + 1 == n {
                return link;
            }
            frame = link * self.link_from_next_frame[k];
        }
        frame
    }

    /// The `world_from_link` of [`Self::poses`] alone (what a simulated arm reports), bit for
    /// bit, without the joints' fixed frames and the tool frame.
    pub fn world_from_links(&self, q: &[f64]) -> Vec<Isometry3<f64>> {
        self.model.links_by(q, |k| self.link_from_next_frame[k], None)
    }

    /// [`PhiModel::world_from_tool`], bit for bit.
    pub fn world_from_tool(&self, q: &[f64]) -> Isometry3<f64> {
        self.model.world_from_tool_by(q, |k| self.link_from_next_frame[k])
    }
}

/// Whether two frames are the same to the bit (their rotation's quaternion and translation).
fn same_bits(a: &Isometry3<f64>, b: &Isometry3<f64>) -> bool {
    let bits = |f: &Isometry3<f64>| {
        let (r, t) = (f.rotation.coords, f.translation.vector);
        [r[0], r[1], r[2], r[3], t[0], t[1], t[2]].map(f64::to_bits)
    };
    bits(a) == bits(b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A model of `kinds` with rows, phi angles and base placement from `x` (any values).
    fn model(kinds: &[JointKind], x: &[f64]) -> PhiModel {
        let at = |i: usize| x[i % x.len()];
        PhiModel {
            joints: kinds
                .iter()
                .enumerate()
                .map(|(k, &kind)| PhiJoint {
                    kind,
                    phi_rad: at(7 * k),
                })
                .collect(),
            rows: (0..kinds.len() - 1)
                .map(|k| PhiRow {
                    a_m: at(7 * k + 1),
                    beta_rad: at(7 * k + 2),
                    b_m: at(7 * k + 3),
                    alpha_rad: at(7 * k + 4),
                    h_m: at(7 * k + 5),
                    gamma_rad: at(7 * k + 6),
                })
                .collect(),
            world_from_base: Isometry3::new(Vector3::new(at(1), at(2), at(3)), Vector3::new(at(4), at(5), at(6))),
            last_link_from_tool: Isometry3::new(Vector3::new(at(3), at(1), at(2)), Vector3::new(at(6), at(4), at(5))),
        }
    }

    proptest! {
        /// The fixed frames give the model's own forward kinematics bit for bit, on chains
        /// of any length and joint mix (a second route: the per-pose path recomputes every
        /// rotation).
        #[test]
        fn fixed_frames_are_the_models_kinematics_bit_for_bit(
            kinds in prop::collection::vec(prop::bool::ANY, 1..8),
            x in prop::collection::vec(-3.0f64..3.0, 7..60),
            q in prop::collection::vec(-3.0f64..3.0, 8),
        ) {
            let kinds: Vec<JointKind> =
                kinds.iter().map(|&r| if r { JointKind::Revolute } else { JointKind::Prismatic }).collect();
            let m = model(&kinds, &x);
            let q = &q[..kinds.len()];
            let frames = m.fixed_frames();
            prop_assert_eq!(frames.poses(q), m.poses(q));
            prop_assert_eq!(frames.world_from_tool(q), m.world_from_tool(q));
            prop_assert_eq!(frames.world_from_tool(q), m.poses(q).world_from_tool);
            prop_assert_eq!(frames.world_from_last_link(q), m.poses(q).world_from_link[kinds.len() - 1]);
            prop_assert_eq!(frames.world_from_links(q), m.poses(q).world_from_link);
        }

        /// Frames taken from another model's where a joint and its row are the same are the
        /// model's own, bit for bit, whichever rows and angles differ.
        #[test]
        fn frames_near_another_models_are_the_models_own(
            kinds in prop::collection::vec(prop::bool::ANY, 1..8),
            x in prop::collection::vec(-3.0f64..3.0, 7..60),
            moved in prop::collection::vec(prop::bool::ANY, 8),
            q in prop::collection::vec(-3.0f64..3.0, 8),
        ) {
            let kinds: Vec<JointKind> =
                kinds.iter().map(|&r| if r { JointKind::Revolute } else { JointKind::Prismatic }).collect();
            let near = model(&kinds, &x).fixed_frames();
            let mut m = model(&kinds, &x);
            for (k, row) in m.rows.iter_mut().enumerate() {
                if moved[k] {
                    row.b_m += 1e-6;
                    m.joints[k].phi_rad -= 1e-6;
                }
            }
            let q = &q[..kinds.len()];
            let frames = FixedFrames::new_near(m.clone(), &near);
            prop_assert_eq!(&frames, &FixedFrames::new(m.clone()));
            prop_assert_eq!(frames.poses(q), m.poses(q));
        }

        /// The last link's frame continued from another model's links is the model's own, bit
        /// for bit, whichever rows, joint values and base differ (none, some, all).
        #[test]
        fn the_last_link_near_another_models_is_the_models_own(
            kinds in prop::collection::vec(prop::bool::ANY, 1..8),
            x in prop::collection::vec(-3.0f64..3.0, 7..60),
            moved in prop::collection::vec(0u8..4, 8),
            q in prop::collection::vec(-3.0f64..3.0, 8),
            base_moved in prop::bool::ANY,
        ) {
            let kinds: Vec<JointKind> =
                kinds.iter().map(|&r| if r { JointKind::Revolute } else { JointKind::Prismatic }).collect();
            let near = model(&kinds, &x).fixed_frames();
            let near_q = &q[..kinds.len()];
            let mut m = model(&kinds, &x);
            let mut q_m = near_q.to_vec();
            for (k, row) in m.rows.iter_mut().enumerate() {
                match moved[k] {
                    1 => row.b_m += 1e-6,
                    2 => q_m[k] += 1e-6,
                    _ => {}
                }
            }
            if base_moved {
                m.world_from_base.translation.vector.x += 1e-6;
            }
            let frames = FixedFrames::new_near(m.clone(), &near);
            let own = m.poses(&q_m).world_from_link[kinds.len() - 1];
            let links = near.world_from_links(near_q);
            prop_assert_eq!(frames.world_from_last_link_near(&q_m, &near, near_q, &links), own);
        }
    }
}
