//! Gravity loads of a serial arm: link masses and the gravity generalised force about each
//! joint, the load that joint compliance turns into sag.

use crate::kinematics::{ChainPoses, JointKind, PhiModel};
use crate::robot::RobotDescription;
use nalgebra::{Point3, Vector3};

/// Gravity in the instrument frame used where nothing else is said \[m/s^2\].
pub const STANDARD_GRAVITY_M_S2: [f64; 3] = [0.0, 0.0, -9.81];

/// The mass of a link and its first mass moment about the link's moving-frame origin (mass
/// times centre of mass, in that frame): all gravity needs to know of a link. Keeping the
/// moment rather than the centre of mass lets a fit treat both as free linear parameters
/// (the diagnosis's lumped compliance), zero mass included.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LinkMass {
    /// \[kg\]
    pub mass_kg: f64,
    /// `mass_kg` times the centre of mass in the link's moving frame \[kg m\].
    pub first_moment_kg_m: Vector3<f64>,
}

impl LinkMass {
    /// A mass `mass_kg` with its centre of mass at `com_in_link_m` (link frame).
    pub fn at(mass_kg: f64, com_in_link_m: Point3<f64>) -> Self {
        LinkMass {
            mass_kg,
            first_moment_kg_m: com_in_link_m.coords * mass_kg,
        }
    }

    /// The masses of a robot description's links.
    pub fn from_description(desc: &RobotDescription) -> Vec<Self> {
        desc.joints
            .iter()
            .map(|j| LinkMass::at(j.mass_kg, Point3::from(j.com_mm) * 1e-3))
            .collect()
    }
}

/// Gravity generalised force about every joint \[N m\] (N for prismatic joints):
/// `Q_j = sum_{i >= j} g . (z_j x (m_i (o_i - o_j) + R_i mu_i))` for revolute joints
/// (`sum_{i >= j} m_i g . z_j` for prismatic ones), `o_i`, `R_i` link `i`'s frame at joint
/// values `q`, `m_i`, `mu_i` its mass and first moment ([`LinkMass`]; the payload
/// `(mass, position in the last link's frame)` adds to the last link), `o_j`, `z_j` axis `j`.
pub fn gravity_torques_nm(
    model: &PhiModel,
    q: &[f64],
    masses: &[LinkMass],
    payload: Option<(f64, Point3<f64>)>,
    gravity_m_s2: [f64; 3],
) -> Vec<f64> {
    gravity_torques_at_nm(model, &model.poses(q), masses, payload, gravity_m_s2)
}

/// [`gravity_torques_nm`] with `model`'s frames at the joint values already computed
/// (`poses = model.poses(q)`), for several loads of one pose: the same numbers bit for bit.
pub fn gravity_torques_at_nm(
    model: &PhiModel,
    poses: &ChainPoses,
    masses: &[LinkMass],
    payload: Option<(f64, Point3<f64>)>,
    gravity_m_s2: [f64; 3],
) -> Vec<f64> {
    let g = Vector3::from(gravity_m_s2);
    let n = model.dof();
    // Per link: its mass and its first moment in the world frame about the link's origin.
    let mut loads: Vec<(usize, f64, Point3<f64>, Vector3<f64>)> = masses
        .iter()
        .enumerate()
        .take(n)
        .map(|(i, m)| {
            let f = &poses.world_from_link[i];
            (i, m.mass_kg, f * Point3::origin(), f * m.first_moment_kg_m)
        })
        .collect();
    if let Some((mass, p)) = payload {
        let f = &poses.world_from_link[n - 1];
        loads.push((n - 1, mass, f * Point3::origin(), f * (p.coords * mass)));
    }
    (0..n)
        .map(|j| {
            let axis = poses.axis(j);
            let z = axis.direction.into_inner();
            loads
                .iter()
                .filter(|(i, ..)| *i >= j)
                .map(|(_, m, o, mu)| match model.joints[j].kind {
                    JointKind::Revolute => g.dot(&z.cross(&((o - axis.origin_m) * *m + mu))),
                    JointKind::Prismatic => (g * *m).dot(&z),
                })
                .sum()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// The moment form equals the point-mass formula `m g . (z x (c - o))` summed link by
    /// link (an independent evaluation with each centre of mass placed in the world).
    #[test]
    fn first_moments_give_the_point_mass_torques() {
        let desc = RobotDescription::asea_irb6l();
        let model = desc.nominal_model();
        let masses = LinkMass::from_description(&desc);
        let q = [0.3, -0.4, 0.5, 1.1, -0.7, 0.2];
        let payload = Some((4.0, Point3::new(0.01, -0.02, 0.15)));
        let torques = gravity_torques_nm(&model, &q, &masses, payload, STANDARD_GRAVITY_M_S2);
        let poses = model.poses(&q);
        let g = Vector3::from(STANDARD_GRAVITY_M_S2);
        for (j, t) in torques.iter().enumerate() {
            let axis = poses.axis(j);
            let z = axis.direction.into_inner();
            let mut expected: f64 = desc.joints[j..]
                .iter()
                .enumerate()
                .map(|(o, jd)| {
                    let c = poses.world_from_link[j + o] * (Point3::from(jd.com_mm) * 1e-3);
                    (g * jd.mass_kg).dot(&z.cross(&(c - axis.origin_m)))
                })
                .sum();
            let pc = poses.world_from_link[5] * Point3::new(0.01, -0.02, 0.15);
            expected += (g * 4.0).dot(&z.cross(&(pc - axis.origin_m)));
            assert_relative_eq!(*t, expected, epsilon = 1e-12);
        }
    }
}
