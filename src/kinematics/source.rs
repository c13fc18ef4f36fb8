//! Serial chains as users describe them, converted to the phi-model (appendix, eqs. A1-A4):
//! classic Denavit-Hartenberg, modified DH (Craig) and URDF joint chains.
//!
//! Both models are products of exponentials of the same joint screws (Brockett 1984; Murray,
//! Li & Sastry, *A Mathematical Introduction to Robotic Manipulation*, eq. 3.3): a chain's
//! forward kinematics is fixed by its joint axes (lines, with their sense) and kinds at `q = 0`
//! and its tool pose at `q = 0`. The conversion therefore reads those from the source and
//! builds phi-model frames on the same axes:
//!
//! - frame 1 is the source's own frame on axis 1 (DH frame 0, MDH frame 1, or the first URDF
//!   joint's frame turned so that its Z is the joint axis);
//! - **the phi rule**: `phi_k` turns `Z_phi_k` onto the common normal `z_k x z_{k+1}` of axes
//!   `k` and `k+1`; for parallel axes onto the perpendicular from axis `k` towards axis
//!   `k+1`; for coincident axes `phi_k = 0`. So `Z_phi_k` is perpendicular to both axes, the
//!   row has `alpha = +-90 deg` and is never singular (`Z_phi` never parallel to the next axis);
//! - row `k` puts `Z_{k+1}` on the source's axis `k+1` in DH fashion from `Z_phi_k`
//!   ([`row_to_line`]: `x_{k+1}` on the common normal, `gamma = h = 0`);
//! - the tool frame is the source's tool at `q = 0` seen from the last phi link.

use super::chain::{AxisLine, PhiJoint, PhiModel};
use super::phi::{JointKind, PhiRow, frame_from_phi, joint_motion};
use nalgebra::{Isometry3, Point3, Translation3, Unit, UnitQuaternion, Vector3};

/// Rows with `Z_{i+1}` closer than this to `Z_phi` \[sin of the angle\] are singular.
const ROW_SINGULAR_SIN: f64 = 1e-9;

/// Row `(a, b, alpha, beta)` placing `Z_{i+1}` on the line `next_in_phi` (given in the `phi_i`
/// frame) in DH fashion from `Z_phi` (eq. A3 with `gamma = h = 0`): `x_{i+1}` along the common
/// normal of `Z_phi` and `Z_{i+1}`, `b` its length, `a` where it leaves `Z_phi`; `beta` wrapped
/// to within pi of `beta_near`. `None` when the line is parallel to `Z_phi` (no unique normal).
pub fn row_to_line(next_in_phi: &AxisLine, beta_near: f64) -> Option<PhiRow> {
    let d = next_in_phi.direction.into_inner();
    let sin_alpha = (d.x * d.x + d.y * d.y).sqrt();
    if sin_alpha < ROW_SINGULAR_SIN {
        return None;
    }
    let alpha = sin_alpha.atan2(d.z);
    // Z_{i+1} = Rot(z, beta) Rot(x, alpha) z = (sin b sin a, -cos b sin a, cos a), eq. (A3).
    let beta_raw = d.x.atan2(-d.y);
    let beta = beta_raw + std::f64::consts::TAU * ((beta_near - beta_raw) / std::f64::consts::TAU).round();
    // The common normal of Z_phi and Z_{i+1} runs along x_{i+1} = (cos b, sin b, 0); its foot
    // on Z_{i+1} is where the line's component along (-sin b, cos b, 0) vanishes.
    let n = Vector3::new(-beta.sin(), beta.cos(), 0.0);
    let p = next_in_phi.origin_m.coords;
    let t = p.dot(&n) / sin_alpha;
    let o = p + d * t;
    Some(PhiRow {
        a_m: o.z,
        b_m: o.x * beta.cos() + o.y * beta.sin(),
        alpha_rad: alpha,
        beta_rad: beta,
        gamma_rad: 0.0,
        h_m: 0.0,
    })
}

/// Classic or modified (Craig) Denavit-Hartenberg.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DhConvention {
    /// `T = prod Rz(theta_i + q) Tz(d_i) Tx(a_i) Rx(alpha_i)`: joint `i` turns about `z_{i-1}`.
    Classic,
    /// `T = prod Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(theta_i + q) Tz(d_i)` (Craig, sec. 3.4): joint `i`
    /// turns about `z_i`.
    Modified,
}

/// One DH row in internal units; a prismatic joint adds its `q` to `d`, a revolute one to `theta`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DhParams {
    /// \[m\]
    pub d_m: f64,
    /// \[rad\]
    pub theta_rad: f64,
    /// \[m\]
    pub a_m: f64,
    /// \[rad\]
    pub alpha_rad: f64,
}

/// One movable URDF joint, fixed joints before it merged into its origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UrdfJoint {
    /// Revolute (also URDF `continuous`) or prismatic.
    pub kind: JointKind,
    /// The joint frame in the previous joint's child link (the chain's base for the first).
    pub parent_from_joint: Isometry3<f64>,
    /// The joint axis in the joint frame.
    pub axis: Unit<Vector3<f64>>,
}

/// Each joint's frame before its motion, with its axis direction, in the base frame.
type JointFrames = Vec<(Isometry3<f64>, Unit<Vector3<f64>>)>;

/// A serial chain in the form a user has it.
#[derive(Clone, Debug, PartialEq)]
pub enum SourceChain {
    /// A DH table, one row per joint; the tool is given in the last DH frame.
    Dh {
        /// Classic or modified.
        convention: DhConvention,
        /// Joint kinds, base first.
        kinds: Vec<JointKind>,
        /// One row per joint.
        rows: Vec<DhParams>,
        /// The tool frame in the last DH frame (classic: frame N; modified: frame N).
        flange_from_tool: Isometry3<f64>,
    },
    /// A URDF joint chain; the tool is given in the last joint's child link.
    Urdf {
        /// The movable joints, base first.
        joints: Vec<UrdfJoint>,
        /// The tool frame in the last child link.
        last_link_from_tool: Isometry3<f64>,
    },
}

fn rz(t: f64) -> Isometry3<f64> {
    Isometry3::rotation(Vector3::z() * t)
}
fn rx(t: f64) -> Isometry3<f64> {
    Isometry3::rotation(Vector3::x() * t)
}
fn tz(d: f64) -> Isometry3<f64> {
    Isometry3::translation(0.0, 0.0, d)
}
fn tx(a: f64) -> Isometry3<f64> {
    Isometry3::translation(a, 0.0, 0.0)
}

/// The motion of a joint of `kind` by `q` about or along `axis`.
fn motion_about(kind: JointKind, axis: &Unit<Vector3<f64>>, q: f64) -> Isometry3<f64> {
    match kind {
        JointKind::Revolute => {
            Isometry3::from_parts(Translation3::identity(), UnitQuaternion::from_axis_angle(axis, q))
        }
        JointKind::Prismatic => {
            Isometry3::from_parts(Translation3::from(axis.into_inner() * q), UnitQuaternion::identity())
        }
    }
}

impl SourceChain {
    /// Joint kinds, base first.
    pub fn kinds(&self) -> Vec<JointKind> {
        match self {
            SourceChain::Dh { kinds, .. } => kinds.clone(),
            SourceChain::Urdf { joints, .. } => joints.iter().map(|j| j.kind).collect(),
        }
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.kinds().len()
    }

    /// Forward kinematics in the source's own base frame: the tool at joint values `q` (rad, m),
    /// and each joint's frame (Z on its axis for DH; the URDF joint frame otherwise) before its
    /// motion, with that joint's axis direction in the base frame.
    fn walk(&self, q: &[f64]) -> (Isometry3<f64>, JointFrames) {
        let mut joints = Vec::with_capacity(q.len());
        match self {
            SourceChain::Dh {
                convention,
                kinds,
                rows,
                flange_from_tool,
            } => {
                let mut t = Isometry3::identity();
                for (i, (r, kind)) in rows.iter().zip(kinds).enumerate() {
                    if *convention == DhConvention::Modified {
                        t = t * rx(r.alpha_rad) * tx(r.a_m);
                    }
                    let axis_frame = t * rz(r.theta_rad) * tz(r.d_m);
                    joints.push((axis_frame, Unit::new_unchecked(t * Vector3::z())));
                    t = axis_frame * joint_motion(*kind, q[i]);
                    if *convention == DhConvention::Classic {
                        t = t * tx(r.a_m) * rx(r.alpha_rad);
                    }
                }
                (t * flange_from_tool, joints)
            }
            SourceChain::Urdf {
                joints: chain,
                last_link_from_tool,
            } => {
                let mut t = Isometry3::identity();
                for (j, qj) in chain.iter().zip(q) {
                    let frame = t * j.parent_from_joint;
                    joints.push((frame, Unit::new_normalize(frame * j.axis.into_inner())));
                    t = frame * motion_about(j.kind, &j.axis, *qj);
                }
                (t * last_link_from_tool, joints)
            }
        }
    }

    /// The tool frame in the source's base frame at joint values `q` (rad, m).
    pub fn base_from_tool(&self, q: &[f64]) -> Isometry3<f64> {
        self.walk(q).0
    }

    /// The joint axes at `q = 0` in the source's base frame, with each axis's sense (the
    /// direction a positive `q` turns or slides about/along).
    pub fn axes_at_zero(&self) -> Vec<AxisLine> {
        let (_, joints) = self.walk(&vec![0.0; self.dof()]);
        joints
            .iter()
            .map(|(f, dir)| AxisLine {
                origin_m: f * Point3::origin(),
                direction: *dir,
            })
            .collect()
    }

    /// Frame 1 of the phi-model in the source's base frame: the source's frame on axis 1 (DH:
    /// the frame whose Z is axis 1; URDF: the first joint frame turned by the smallest rotation
    /// that takes its Z onto the joint axis).
    fn frame1(&self) -> Isometry3<f64> {
        let (_, joints) = self.walk(&vec![0.0; self.dof()]);
        let (frame, axis) = joints[0];
        let local = frame.inverse_transform_vector(&axis);
        let turn = UnitQuaternion::rotation_between(&Vector3::z(), &local)
            .unwrap_or_else(|| UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI));
        frame * Isometry3::from_parts(Translation3::identity(), turn)
    }
}

/// The phi angle of the rule (module docs) for joint `k`'s frame `world_from_frame` and the next
/// axis `next`: `Z_phi` along `z_k x z_{k+1}`, or towards a parallel next axis, else `X_k`.
pub fn phi_rule(world_from_frame: &Isometry3<f64>, next: &AxisLine) -> f64 {
    let z = world_from_frame * Vector3::z();
    let cross = z.cross(&next.direction);
    let toward = {
        let w = next.origin_m - world_from_frame * Point3::origin();
        w - z * w.dot(&z)
    };
    let d = if cross.norm() > 1e-9 {
        cross
    } else if toward.norm() > 1e-12 {
        toward
    } else {
        return 0.0;
    };
    let local = world_from_frame.inverse_transform_vector(&d);
    local.y.atan2(local.x)
}

/// The phi-model of `source` (module docs), placed in the world by `world_from_source_base`.
/// `None` only if a row would be singular, which the phi rule excludes.
pub fn phi_model_of(source: &SourceChain, world_from_source_base: &Isometry3<f64>) -> Option<PhiModel> {
    let kinds = source.kinds();
    let n = kinds.len();
    let axes: Vec<AxisLine> = source
        .axes_at_zero()
        .iter()
        .map(|a| AxisLine {
            origin_m: world_from_source_base * a.origin_m,
            direction: Unit::new_normalize(world_from_source_base * a.direction.into_inner()),
        })
        .collect();
    let world_from_base = world_from_source_base * source.frame1();
    let mut joints = Vec::with_capacity(n);
    let mut rows = Vec::with_capacity(n.saturating_sub(1));
    let mut frame = world_from_base;
    for k in 0..n {
        let phi = if k + 1 < n { phi_rule(&frame, &axes[k + 1]) } else { 0.0 };
        joints.push(PhiJoint {
            kind: kinds[k],
            phi_rad: phi,
        });
        if k + 1 < n {
            let world_from_phi = frame * frame_from_phi(phi, 0.0, 0.0);
            let next = &axes[k + 1];
            let local = AxisLine {
                origin_m: world_from_phi.inverse_transform_point(&next.origin_m),
                direction: Unit::new_normalize(world_from_phi.inverse_transform_vector(&next.direction)),
            };
            let row = row_to_line(&local, 0.0)?;
            frame = world_from_phi * row.phi_from_next();
            rows.push(row);
        }
    }
    let world_from_tool = world_from_source_base * source.base_from_tool(&vec![0.0; n]);
    Some(PhiModel {
        joints,
        rows,
        world_from_base,
        last_link_from_tool: frame.inverse() * world_from_tool,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng, rngs::ChaCha12Rng};

    fn check_equal_fk(source: &SourceChain, seed: u64) {
        let place = Isometry3::from_parts(
            Translation3::new(0.3, -1.2, 0.4),
            UnitQuaternion::from_euler_angles(0.2, -0.3, 1.1),
        );
        let model = phi_model_of(source, &place).unwrap();
        let mut rng = ChaCha12Rng::seed_from_u64(seed);
        for _ in 0..50 {
            let q: Vec<f64> = source
                .kinds()
                .iter()
                .map(|k| match k {
                    JointKind::Revolute => rng.random_range(-3.0..3.0),
                    JointKind::Prismatic => rng.random_range(-0.5..0.5),
                })
                .collect();
            let a = place * source.base_from_tool(&q);
            let b = model.world_from_tool(&q);
            // Rounding of a dozen products of unit-size transforms.
            assert!((a.translation.vector - b.translation.vector).norm() < 1e-12);
            assert!(a.rotation.angle_to(&b.rotation) < 1e-12);
        }
        for r in &model.rows {
            assert!((r.alpha_rad.abs() - std::f64::consts::FRAC_PI_2).abs() < 1e-9, "{r:?}");
        }
    }

    fn dh(d: f64, theta_deg: f64, a: f64, alpha_deg: f64) -> DhParams {
        DhParams {
            d_m: d,
            theta_rad: theta_deg.to_radians(),
            a_m: a,
            alpha_rad: alpha_deg.to_radians(),
        }
    }

    #[test]
    fn classic_and_modified_dh_and_urdf_give_the_same_forward_kinematics() {
        use JointKind::{Prismatic as P, Revolute as R};
        let tool = Isometry3::from_parts(
            Translation3::new(0.01, 0.02, 0.15),
            UnitQuaternion::from_euler_angles(0.1, 0.0, 0.3),
        );
        // A PUMA-like arm (a skew pair, parallel pairs, intersecting wrist) and a SCARA (all axes
        // parallel, one prismatic), in both DH conventions.
        let puma = vec![
            dh(0.67, 0.0, 0.0, -90.0),
            dh(0.0, 10.0, 0.43, 0.0),
            dh(0.15, 0.0, 0.02, 90.0),
            dh(0.43, 0.0, 0.0, -90.0),
            dh(0.0, 0.0, 0.0, 90.0),
            dh(0.06, 0.0, 0.0, 0.0),
        ];
        let scara = vec![
            dh(0.4, 0.0, 0.35, 0.0),
            dh(0.0, 0.0, 0.3, 180.0),
            dh(0.1, 0.0, 0.0, 0.0),
            dh(0.05, 30.0, 0.0, 0.0),
        ];
        for convention in [DhConvention::Classic, DhConvention::Modified] {
            check_equal_fk(
                &SourceChain::Dh {
                    convention,
                    kinds: vec![R; 6],
                    rows: puma.clone(),
                    flange_from_tool: tool,
                },
                1,
            );
            check_equal_fk(
                &SourceChain::Dh {
                    convention,
                    kinds: vec![R, R, P, R],
                    rows: scara.clone(),
                    flange_from_tool: tool,
                },
                2,
            );
        }
        // A P-R-P-P table as URDF joints with arbitrary axes and origins.
        let j = |kind, xyz: [f64; 3], rpy: [f64; 3], axis: [f64; 3]| UrdfJoint {
            kind,
            parent_from_joint: Isometry3::from_parts(
                Translation3::new(xyz[0], xyz[1], xyz[2]),
                UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]),
            ),
            axis: Unit::new_normalize(Vector3::from(axis)),
        };
        let urdf = SourceChain::Urdf {
            joints: vec![
                j(P, [0.1, 0.0, 0.2], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]),
                j(R, [0.0, 0.05, 0.1], [0.0, 0.1, 0.0], [0.0, 0.0, 1.0]),
                j(P, [0.0, 0.0, 0.08], [0.0, 0.0, 0.4], [0.0, 1.0, 0.0]),
                j(P, [0.02, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.3, 1.0]),
            ],
            last_link_from_tool: tool,
        };
        check_equal_fk(&urdf, 3);
    }
}
