//! Closed-form inverse kinematics of the NOMINAL IRB/L6 geometry class.
//!
//! The class (checked on the model at `q = 0`, in base-frame coordinates, frame 1 having its Z
//! on axis 1): axes 2, 3, 4 parallel to one direction `u0` perpendicular to axis 1; axis 5
//! perpendicular to axis 4 and meeting it at the wrist point `W`; axis 6 perpendicular to
//! axis 5; the frame-6 origin on axis 5, at the signed distance `b5` from `W` along `z5`
//! (Table 2: `b5 = 0.2325 m`). Every joint is revolute.
//!
//! Equations, with `p6`, `z6` the origin and Z axis of frame 6 required by the target:
//! 1. **Arm plane, theta1.** Rotations about axes parallel to `u` keep points in the plane
//!    `u . x = s0` (`s0 = u0 . o5`), which holds axis 5, hence `p6`. With
//!    `u(theta1) = Rz(theta1) u0` at horizontal angle `psi0 + theta1` and `p6` at horizontal
//!    radius `rho` and angle `phi`: `rho cos(psi0 + theta1 - phi) = s0`, so
//!    `theta1 = phi - psi0 +- acos(s0 / rho)` (two shoulder branches).
//! 2. **Wrist point.** `z5` is perpendicular to `u` (axis 4) and to `z6`:
//!    `z5 = sigma (u x z6) / |u x z6|`, `sigma = +-1` (two wrist branches; singular when
//!    `z6 || u`). Then `W = p6 - b5 z5`.
//! 3. **theta2, theta3** (planar 2R). In plane coordinates (`e1 = z1`, `e2 = u0 x e1`, angles
//!    counter-clockwise about `u0`), `W - c2 = R(g2) (v2 + R(g3) v3)` with `c2` the trace of
//!    axis 2, `v2 = c3 - c2`, `v3 = w0 - c3` (zero-pose traces of axis 3 and of `W`), and
//!    `g_k = s_k theta_k`, `s_k = sign(z_k . u0)`. The law of cosines gives
//!    `cos(g3 + ang v3 - ang v2) = (|W - c2|^2 - |v2|^2 - |v3|^2) / (2 |v2| |v3|)` (two elbow
//!    branches), then `g2 = ang(W - c2) - ang(v2 + R(g3) v3)`.
//! 4. **theta4.** `z5` lies in the plane: `ang z5 = ang z5(0) + g2 + g3 + s4 theta4`.
//! 5. **theta5, theta6.** With frame 5 known, `frame5^-1 * frame6_target` has rotation
//!    `Rz(theta5) R56 Rz(theta6)` (`R56` fixed): `theta5` turns `R56 z` onto the target's
//!    `z6` about `z5`, and `theta6` is the remaining rotation about `z6`.
//!
//! The up-to-8 branches are each verified by forward kinematics.

use super::super::chain::PhiModel;
use super::super::phi::JointKind;
use super::{pose_error, wrap_angle};
use nalgebra::{Isometry3, Point3, Rotation3, Vector2, Vector3};

/// Geometric tolerance of the class test \[m or rad\]: far above the ~1e-16 rounding of an
/// exactly nominal model, far below any real calibration deviation (~1e-4).
const CLASS_TOLERANCE: f64 = 1e-9;
/// A branch is kept when forward kinematics reproduces the target to this \[m or rad\].
const VERIFY_TOLERANCE: f64 = 1e-9;

/// Why the nominal closed form does not apply.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ClosedFormError {
    /// The model is not of the IRB/L6 class (module docs).
    #[error("model is not of the IRB/L6 class: {condition} (deviation {deviation:.3e})")]
    NotInClass {
        /// The violated condition.
        condition: &'static str,
        /// By how much \[m or rad, or a count\].
        deviation: f64,
    },
    /// No branch reaches the target (out of reach or singular).
    #[error("no closed-form branch reaches the target")]
    NoBranch,
}

/// One verified closed-form branch.
#[derive(Clone, Debug, PartialEq)]
pub struct ClosedFormSolution {
    /// Joint values \[rad\], wrapped into `(-pi, pi]`.
    pub q: Vec<f64>,
    /// Branch signs `[shoulder, elbow, wrist]`, each `+1` or `-1`.
    pub branch: [i8; 3],
    /// Forward-kinematics check: tool position error \[m\].
    pub position_error_m: f64,
    /// Forward-kinematics check: tool orientation error \[rad\].
    pub orientation_error_rad: f64,
}

/// The class constants, read off the model at `q = 0` in base-frame coordinates.
struct ArmClass {
    u0: Vector3<f64>,
    s0: f64,
    signs: [f64; 3],
    e1: Vector3<f64>,
    e2: Vector3<f64>,
    c2: Vector2<f64>,
    v2: Vector2<f64>,
    v3: Vector2<f64>,
    z5_angle: f64,
    b5_m: f64,
}

fn require(ok_deviation: f64, condition: &'static str) -> Result<(), ClosedFormError> {
    if ok_deviation.abs() <= CLASS_TOLERANCE {
        Ok(())
    } else {
        Err(ClosedFormError::NotInClass {
            condition,
            deviation: ok_deviation,
        })
    }
}

fn angle(v: &Vector2<f64>) -> f64 {
    v.y.atan2(v.x)
}

fn rot2(theta: f64, v: &Vector2<f64>) -> Vector2<f64> {
    let (s, c) = theta.sin_cos();
    Vector2::new(c * v.x - s * v.y, s * v.x + c * v.y)
}

impl ArmClass {
    fn of(model: &PhiModel) -> Result<Self, ClosedFormError> {
        if model.dof() != 6 || !model.is_consistent() {
            return Err(ClosedFormError::NotInClass {
                condition: "six joints",
                deviation: model.dof() as f64,
            });
        }
        if model.joints.iter().any(|j| j.kind != JointKind::Revolute) {
            return Err(ClosedFormError::NotInClass {
                condition: "all joints revolute",
                deviation: 1.0,
            });
        }
        let poses = model.poses(&[0.0; 6]);
        let base_inv = model.world_from_base.inverse();
        let o: Vec<Point3<f64>> = (0..6).map(|k| base_inv * poses.axis(k).origin_m).collect();
        let z: Vec<Vector3<f64>> = (0..6).map(|k| base_inv * *poses.axis(k).direction).collect();
        let u0 = z[1];
        require(u0.dot(&z[0]), "axis 2 perpendicular to axis 1")?;
        require(z[2].cross(&u0).norm(), "axis 3 parallel to axis 2")?;
        require(z[3].cross(&u0).norm(), "axis 4 parallel to axis 2")?;
        require(z[4].dot(&u0), "axis 5 perpendicular to axis 4")?;
        let n45 = z[3].cross(&z[4]).normalize();
        require((o[4] - o[3]).dot(&n45), "axis 5 meets axis 4")?;
        require(z[5].dot(&z[4]), "axis 6 perpendicular to axis 5")?;
        require((o[5] - o[4]).cross(&z[4]).norm(), "frame-6 origin on axis 5")?;
        let s0 = u0.dot(&o[4].coords);
        let w0 = o[3] + z[3] * ((s0 - u0.dot(&o[3].coords)) / z[3].dot(&u0));
        let e1 = z[0];
        let e2 = u0.cross(&e1);
        let pl = |p: &Point3<f64>| Vector2::new(p.coords.dot(&e1), p.coords.dot(&e2));
        let c2 = pl(&o[1]);
        let c3 = pl(&o[2]);
        let signs = [1.0, z[2].dot(&u0).signum(), z[3].dot(&u0).signum()];
        Ok(Self {
            u0,
            s0,
            signs,
            e1,
            e2,
            c2,
            v2: c3 - c2,
            v3: pl(&w0) - c3,
            z5_angle: z[4].dot(&e2).atan2(z[4].dot(&e1)),
            b5_m: (o[5] - w0).dot(&z[4]),
        })
    }

    /// Steps 2-4 for one shoulder angle: `(theta2, theta3, theta4, [elbow, wrist])` branches.
    fn arm_branches(&self, p6: &Vector3<f64>, z6: &Vector3<f64>) -> Vec<([f64; 3], [i8; 2])> {
        let mut out = Vec::new();
        let n = self.u0.cross(z6);
        if n.norm() < CLASS_TOLERANCE {
            return out; // wrist singularity: z6 along axis 4
        }
        let (l2, l3) = (self.v2.norm(), self.v3.norm());
        for sigma in [1.0, -1.0] {
            let z5 = n.normalize() * sigma;
            let w = p6 - z5 * self.b5_m;
            let d = Vector2::new(w.dot(&self.e1), w.dot(&self.e2)) - self.c2;
            let kappa = (d.norm_squared() - l2 * l2 - l3 * l3) / (2.0 * l2 * l3);
            if kappa.abs() > 1.0 + CLASS_TOLERANCE {
                continue; // wrist point out of the 2R reach
            }
            for eps in [1.0, -1.0] {
                let g3 = eps * kappa.clamp(-1.0, 1.0).acos() - (angle(&self.v3) - angle(&self.v2));
                let g2 = angle(&d) - angle(&(self.v2 + rot2(g3, &self.v3)));
                let z5_angle = z5.dot(&self.e2).atan2(z5.dot(&self.e1));
                let g4 = z5_angle - self.z5_angle - g2 - g3;
                let q = [g2 * self.signs[0], g3 * self.signs[1], g4 * self.signs[2]];
                out.push((q, [eps as i8, sigma as i8]));
            }
        }
        out
    }
}

/// Step 5: theta5 and theta6 from frame 5 (at `q1..q4`) and the target frame 6.
fn wrist_angles(model: &PhiModel, q: &mut [f64; 6], world_from_frame6: &Isometry3<f64>) {
    q[4] = 0.0;
    q[5] = 0.0;
    let frame5 = model.poses(q).world_from_frame[4];
    let m: Rotation3<f64> = (frame5.rotation.inverse() * world_from_frame6.rotation).to_rotation_matrix();
    let r56 = model.link_from_next_frame(4).rotation.to_rotation_matrix();
    let a = r56 * Vector3::z();
    let b = m * Vector3::z();
    q[4] = b.y.atan2(b.x) - a.y.atan2(a.x);
    let r6 = r56.inverse() * Rotation3::from_axis_angle(&Vector3::z_axis(), -q[4]) * m;
    q[5] = r6[(1, 0)].atan2(r6[(0, 0)]);
}

/// All verified closed-form IK branches of a model of the IRB/L6 class (module docs) for the
/// tool pose `world_from_tool_target`. Meant for the NOMINAL model; on a calibrated model it
/// reports [`ClosedFormError::NotInClass`], and its branches seed the general solver instead.
pub fn nominal_closed_form(
    model: &PhiModel,
    world_from_tool_target: &Isometry3<f64>,
) -> Result<Vec<ClosedFormSolution>, ClosedFormError> {
    let class = ArmClass::of(model)?;
    let world_from_frame6 = world_from_tool_target * model.last_link_from_tool.inverse();
    let base_from_frame6 = model.world_from_base.inverse() * world_from_frame6;
    let p6 = base_from_frame6.translation.vector;
    let z6 = base_from_frame6.rotation * Vector3::z();
    let rho = p6.x.hypot(p6.y);
    if rho < class.s0.abs() || rho < CLASS_TOLERANCE {
        return Err(ClosedFormError::NoBranch); // out of reach, or on axis 1 (singular)
    }
    let (phi, psi0) = (p6.y.atan2(p6.x), class.u0.y.atan2(class.u0.x));
    let mut out: Vec<ClosedFormSolution> = Vec::new();
    for shoulder in [1.0, -1.0] {
        let q1 = phi - psi0 + shoulder * (class.s0 / rho).clamp(-1.0, 1.0).acos();
        let undo_q1 = Rotation3::from_axis_angle(&Vector3::z_axis(), -q1);
        for (arm, [elbow, wrist]) in class.arm_branches(&(undo_q1 * p6), &(undo_q1 * z6)) {
            let mut q = [q1, arm[0], arm[1], arm[2], 0.0, 0.0];
            wrist_angles(model, &mut q, &world_from_frame6);
            let q: Vec<f64> = q.iter().map(|v| wrap_angle(*v)).collect();
            let e = pose_error(world_from_tool_target, &model.world_from_tool(&q));
            let (pos, ori) = (e.fixed_rows::<3>(0).norm(), e.fixed_rows::<3>(3).norm());
            let duplicate = out
                .iter()
                .any(|s| s.q.iter().zip(&q).all(|(a, b)| (a - b).abs() < VERIFY_TOLERANCE));
            if pos < VERIFY_TOLERANCE && ori < VERIFY_TOLERANCE && !duplicate {
                out.push(ClosedFormSolution {
                    q,
                    branch: [shoulder as i8, elbow, wrist],
                    position_error_m: pos,
                    orientation_error_rad: ori,
                });
            }
        }
    }
    if out.is_empty() {
        Err(ClosedFormError::NoBranch)
    } else {
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::RobotDescription;

    #[test]
    fn tilted_axes_are_not_in_the_class() {
        let mut m = RobotDescription::asea_irb6l().nominal_model();
        m.rows[1].alpha_rad += 0.003;
        let err = nominal_closed_form(&m, &m.world_from_tool(&[0.1; 6])).unwrap_err();
        assert!(matches!(
            err,
            ClosedFormError::NotInClass {
                condition: "axis 3 parallel to axis 2",
                ..
            }
        ));
    }

    #[test]
    fn far_targets_have_no_branch() {
        let m = RobotDescription::asea_irb6l().nominal_model();
        let far = Isometry3::translation(5.0, 0.0, 0.0) * m.world_from_tool(&[0.1; 6]);
        assert_eq!(nominal_closed_form(&m, &far), Err(ClosedFormError::NoBranch));
    }
}
