//! The phi-model transforms of the paper's appendix, eqs. (A1)-(A4).
//!
//! Frame `i` has its Z axis on joint axis `i`. The intermediate `phi_i` frame has its Z axis
//! in a plane parallel to `X_i Y_i` at height `d_i`, at the angle `phi_i + theta_i` from `X_i`
//! (A2); frame `i+1` is placed from the `phi_i` frame in DH fashion with `a, b, alpha, beta`,
//! plus `gamma, h` for arbitrarily placed frames (A3). Unlike DH, nothing here is singular
//! when successive axes are parallel.

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// The kind of a joint: the variable it moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum JointKind {
    /// Rotation `theta` \[rad\] about Z_i.
    Revolute,
    /// Translation `d` \[m\] along Z_i.
    Prismatic,
}

impl JointKind {
    /// A joint value in internal units (rad or m) in file units (deg or mm), as users write
    /// and read them (`docs/formats.md#units`).
    pub fn to_file_units(self, value: f64) -> f64 {
        match self {
            JointKind::Revolute => value.to_degrees(),
            JointKind::Prismatic => value * 1e3,
        }
    }

    /// The unit of file values: `deg` (revolute) or `mm` (prismatic).
    pub fn file_unit(self) -> &'static str {
        match self {
            JointKind::Revolute => "deg",
            JointKind::Prismatic => "mm",
        }
    }
}

/// One row of Table 2: the parameters of eq. (A3) relating frame `i+1` to the `phi_i` frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct PhiRow {
    /// Translation along Z_phi \[m\].
    pub a_m: f64,
    /// Translation along the rotated X \[m\].
    pub b_m: f64,
    /// Rotation about the rotated X \[rad\].
    pub alpha_rad: f64,
    /// Rotation about Z_phi \[rad\].
    pub beta_rad: f64,
    /// Extra rotation about Z_{i+1} \[rad\] (arbitrarily placed frames only).
    pub gamma_rad: f64,
    /// Extra translation along Z_{i+1} \[m\] (arbitrarily placed frames only).
    pub h_m: f64,
}

impl PhiRow {
    /// A row with `gamma = h = 0`, as every joint-to-joint row of Table 2.
    pub fn new(a_m: f64, b_m: f64, alpha_rad: f64, beta_rad: f64) -> Self {
        Self {
            a_m,
            b_m,
            alpha_rad,
            beta_rad,
            gamma_rad: 0.0,
            h_m: 0.0,
        }
    }

    /// A row from Table 2's units: metres and degrees.
    pub fn from_table_deg(a_m: f64, b_m: f64, alpha_deg: f64, beta_deg: f64) -> Self {
        Self::new(a_m, b_m, alpha_deg.to_radians(), beta_deg.to_radians())
    }

    /// The six parameters as an array `[a, b, alpha, beta, gamma, h]`.
    pub fn to_array(&self) -> [f64; 6] {
        [
            self.a_m,
            self.b_m,
            self.alpha_rad,
            self.beta_rad,
            self.gamma_rad,
            self.h_m,
        ]
    }

    /// The inverse of [`PhiRow::to_array`].
    pub fn from_array(p: [f64; 6]) -> Self {
        Self {
            a_m: p[0],
            b_m: p[1],
            alpha_rad: p[2],
            beta_rad: p[3],
            gamma_rad: p[4],
            h_m: p[5],
        }
    }

    /// `phi_T_{i+1}`, eq. (A3):
    /// `Trans(0,0,a) Rot(z,beta) Trans(b,0,0) Rot(x,alpha) Rot(z,gamma) Trans(0,0,h)`.
    ///
    /// The returned isometry maps coordinates in frame `i+1` to the `phi_i` frame
    /// (`phi_from_next`). The expanded form (A4) has a typo in the seed (second row of the
    /// `Rot(z, gamma)` block); this composition is the correct one.
    pub fn phi_from_next(&self) -> Isometry3<f64> {
        let z = Vector3::z_axis();
        let x = Vector3::x_axis();
        Isometry3::from_parts(
            Translation3::new(0.0, 0.0, self.a_m),
            UnitQuaternion::from_axis_angle(&z, self.beta_rad),
        ) * Isometry3::from_parts(
            Translation3::new(self.b_m, 0.0, 0.0),
            UnitQuaternion::from_axis_angle(&x, self.alpha_rad),
        ) * Isometry3::from_parts(
            Translation3::new(0.0, 0.0, self.h_m),
            UnitQuaternion::from_axis_angle(&z, self.gamma_rad),
        )
    }
}

/// The fixed rotation of eq. (A2) at `phi + theta = 0`: columns `x_phi = Y_i`,
/// `y_phi = Z_i`, `z_phi = X_i`.
fn phi_axes_at_zero() -> UnitQuaternion<f64> {
    let m = Matrix3::new(0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0);
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m))
}

/// `i_T_phi`, eq. (A2): the `phi_i` frame in frame `i` for joint displacement
/// `theta_rad` (rotary) and `d_m` (sliding).
///
/// `[[-s, 0, c, 0], [c, 0, s, 0], [0, 1, 0, d]]` with `c = cos(phi + theta)`,
/// `s = sin(phi + theta)`; equal to `Trans(0,0,d) Rot(z, phi + theta) R0` with `R0` the
/// fixed axis permutation (columns `Y_i`, `Z_i`, `X_i`).
pub fn frame_from_phi(phi_rad: f64, theta_rad: f64, d_m: f64) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(0.0, 0.0, d_m),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), phi_rad + theta_rad) * phi_axes_at_zero(),
    )
}

/// The motion of joint `i` expressed in frame `i`: `Trans(0,0,d) Rot(z,theta)`.
/// Everything carried by link `i` moves with this transform.
pub fn joint_motion(kind: JointKind, q: f64) -> Isometry3<f64> {
    match kind {
        JointKind::Revolute => Isometry3::rotation(Vector3::z() * q),
        JointKind::Prismatic => Isometry3::translation(0.0, 0.0, q),
    }
}

/// The constant part of eq. (A2) after the joint motion: `Rot(z, phi) R0`.
pub fn link_from_phi(phi_rad: f64) -> Isometry3<f64> {
    frame_from_phi(phi_rad, 0.0, 0.0)
}

/// Within this of +-90 deg pitch \[rad\], [`roll_pitch_yaw`] takes the angles its own way.
pub const NEAR_LOCK_RAD: f64 = 1e-3;

/// Roll, pitch and yaw \[rad\] of `rotation = Rz(yaw) Ry(pitch) Rx(roll)` (nalgebra's
/// `from_euler_angles`, URDF's `rpy`), to round-off at every pitch.
///
/// nalgebra's `euler_angles` takes the pitch as `asin(-R20)`, which near +-90 deg loses half
/// the digits (an error of `sqrt(2 eps)`, 2e-8 rad: 0.04 um over a 2 m arm). The pitch is
/// taken here from `atan2` of its sine and cosine, the yaw from the first column, and the roll
/// from what is left once they are taken out: near +-90 deg the yaw is ill-determined, but any
/// error in it is a turn about the same axis as the roll there, which the roll takes up, so
/// the three angles rebuild `rotation` to round-off. Farther than [`NEAR_LOCK_RAD`] from the
/// lock, where `asin` keeps every digit but a few (its error, `eps / cos(pitch)`, stays below
/// 3e-13 rad), the angles are `euler_angles`' bit for bit: what axiscal wrote, and hashed into
/// a description's identity, before.
pub fn roll_pitch_yaw(rotation: &UnitQuaternion<f64>) -> [f64; 3] {
    let (roll, pitch, yaw) = rotation.euler_angles();
    if std::f64::consts::FRAC_PI_2 - pitch.abs() > NEAR_LOCK_RAD {
        return [roll, pitch, yaw];
    }
    let r = rotation.to_rotation_matrix();
    let (r00, r10, r20) = (r[(0, 0)], r[(1, 0)], r[(2, 0)]);
    let pitch = (-r20).atan2(r00.hypot(r10));
    let yaw = r10.atan2(r00);
    let rest = (UnitQuaternion::from_euler_angles(0.0, pitch, yaw).inverse() * rotation).to_rotation_matrix();
    let roll = rest[(2, 1)].atan2(rest[(2, 2)]);
    [roll, pitch, yaw]
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::{Matrix4, Point3};

    /// Eq. (A2) written out element by element, as printed in the paper.
    fn a2_matrix(phi: f64, theta: f64, d: f64) -> Matrix4<f64> {
        let (s, c) = (phi + theta).sin_cos();
        Matrix4::new(-s, 0.0, c, 0.0, c, 0.0, s, 0.0, 0.0, 1.0, 0.0, d, 0.0, 0.0, 0.0, 1.0)
    }

    /// Eq. (A4) with the typo fixed: `(sin g, cos g, 0, 0)` in the second row of the gamma block.
    fn a4_matrix(r: &PhiRow) -> Matrix4<f64> {
        let (sa, ca) = r.alpha_rad.sin_cos();
        let (sb, cb) = r.beta_rad.sin_cos();
        let (sg, cg) = r.gamma_rad.sin_cos();
        let left = Matrix4::new(
            cb,
            -sb * ca,
            sb * sa,
            r.b_m * cb,
            sb,
            cb * ca,
            -cb * sa,
            r.b_m * sb,
            0.0,
            sa,
            ca,
            r.a_m,
            0.0,
            0.0,
            0.0,
            1.0,
        );
        let right = Matrix4::new(
            cg, -sg, 0.0, 0.0, sg, cg, 0.0, 0.0, 0.0, 0.0, 1.0, r.h_m, 0.0, 0.0, 0.0, 1.0,
        );
        left * right
    }

    #[test]
    fn a2_matches_the_printed_matrix() {
        for &(phi, theta, d) in &[
            (0.0, 0.0, 0.0),
            (std::f64::consts::FRAC_PI_2, 0.3, 0.0),
            (-0.7, 2.1, 0.25),
        ] {
            assert_relative_eq!(
                frame_from_phi(phi, theta, d).to_homogeneous(),
                a2_matrix(phi, theta, d),
                epsilon = 1e-15
            );
        }
    }

    #[test]
    fn a3_matches_the_corrected_a4() {
        let row = PhiRow {
            a_m: -0.69,
            b_m: 0.0049,
            alpha_rad: 1.56,
            beta_rad: -3.13,
            gamma_rad: 0.4,
            h_m: 0.15,
        };
        assert_relative_eq!(row.phi_from_next().to_homogeneous(), a4_matrix(&row), epsilon = 1e-14);
    }

    #[test]
    fn a2_is_joint_motion_then_fixed_part() {
        let t = joint_motion(JointKind::Revolute, 0.8) * link_from_phi(0.3);
        assert_relative_eq!(
            t.to_homogeneous(),
            frame_from_phi(0.3, 0.8, 0.0).to_homogeneous(),
            epsilon = 1e-15
        );
        let p = joint_motion(JointKind::Prismatic, 0.2) * link_from_phi(0.3);
        assert_relative_eq!(p * Point3::origin(), Point3::new(0.0, 0.0, 0.2), epsilon = 1e-15);
    }

    /// Roll, pitch and yaw rebuild the rotation to round-off at every pitch, also at and within
    /// 1e-7 of +-90 deg, where nalgebra's `euler_angles` is off by up to 2e-8 rad (the FANUC
    /// tool frame of `describe` was); away from the lock they are nalgebra's, bit for bit.
    #[test]
    fn roll_pitch_yaw_rebuild_the_rotation_near_the_lock_too() {
        let half_pi = std::f64::consts::FRAC_PI_2;
        let pitches = [
            0.3,
            -1.2,
            half_pi,
            -half_pi,
            half_pi - 1e-9,
            -half_pi + 3e-8,
            half_pi + 1e-7,
        ];
        let mut nalgebra_worst: f64 = 0.0;
        for pitch in pitches {
            for (roll, yaw) in [(0.0, 0.0), (2.356, 0.785), (-3.0, 1.0), (0.4, -2.9), (0.1, 0.2)] {
                let r = UnitQuaternion::from_euler_angles(roll, pitch, yaw);
                let [a, b, c] = roll_pitch_yaw(&r);
                let back = UnitQuaternion::from_euler_angles(a, b, c);
                // Away from the lock the angles are nalgebra's: its asin turns an error of one
                // unit in the last place of `R20` into `eps / cos(pitch)` of pitch.
                let tolerance = match half_pi - pitch.abs() > NEAR_LOCK_RAD {
                    true => 4.0 * f64::EPSILON * (1.0 + 1.0 / pitch.cos()),
                    false => 1e-15,
                };
                assert!(back.angle_to(&r) < tolerance, "pitch {pitch}: {}", back.angle_to(&r));
                assert!(b.abs() <= half_pi, "{b}");
                let (a, b, c) = r.euler_angles();
                if half_pi - pitch.abs() > NEAR_LOCK_RAD {
                    assert_eq!(roll_pitch_yaw(&r).map(f64::to_bits), [a, b, c].map(f64::to_bits));
                }
                nalgebra_worst = nalgebra_worst.max(UnitQuaternion::from_euler_angles(a, b, c).angle_to(&r));
            }
        }
        assert!(nalgebra_worst > 1e-9, "the grid misses the lock: {nalgebra_worst}");
    }
}
