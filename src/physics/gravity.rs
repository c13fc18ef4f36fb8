//! Gravity loads of a serial arm: link masses and the gravity generalised force about each
//! joint, the load that joint compliance turns into sag.

use crate::kinematics::{JointKind, PhiModel};
use crate::robot::RobotDescription;
use nalgebra::{Point3, Vector3};

/// Gravity in the instrument frame used where nothing else is said \[m/s^2\].
pub const STANDARD_GRAVITY_M_S2: [f64; 3] = [0.0, 0.0, -9.81];

/// Mass of a link and its centre of mass in the link's moving frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkMass {
    /// \[kg\]
    pub mass_kg: f64,
    /// \[m\]
    pub com_in_link_m: Point3<f64>,
}

impl LinkMass {
    /// The masses of a robot description's links.
    pub fn from_description(desc: &RobotDescription) -> Vec<Self> {
        desc.joints
            .iter()
            .map(|j| LinkMass {
                mass_kg: j.mass_kg,
                com_in_link_m: Point3::from(j.com_mm) * 1e-3,
            })
            .collect()
    }
}

/// Gravity generalised force about every joint \[N m\] (N for prismatic joints):
/// `Q_j = sum_{i >= j} m_i g . (z_j x (c_i - o_j))` (revolute joints; `z_j . m_i g` for
/// prismatic ones), `c_i` the centres of mass of the links at joint values `q` (and the
/// payload `(mass, position in the last link's frame)` on the last link), `o_j`, `z_j` axis `j`.
pub fn gravity_torques_nm(
    model: &PhiModel,
    q: &[f64],
    masses: &[LinkMass],
    payload: Option<(f64, Point3<f64>)>,
    gravity_m_s2: [f64; 3],
) -> Vec<f64> {
    let poses = model.poses(q);
    let g = Vector3::from(gravity_m_s2);
    let n = model.dof();
    let mut loads: Vec<(usize, f64, Point3<f64>)> = masses
        .iter()
        .enumerate()
        .take(n)
        .map(|(i, m)| (i, m.mass_kg, poses.world_from_link[i] * m.com_in_link_m))
        .collect();
    if let Some((mass, p)) = payload {
        loads.push((n - 1, mass, poses.world_from_link[n - 1] * p));
    }
    (0..n)
        .map(|j| {
            let axis = poses.axis(j);
            let z = axis.direction.into_inner();
            loads
                .iter()
                .filter(|(i, _, _)| *i >= j)
                .map(|(_, m, c)| match model.joints[j].kind {
                    JointKind::Revolute => (g * *m).dot(&z.cross(&(c - axis.origin_m))),
                    JointKind::Prismatic => (g * *m).dot(&z),
                })
                .sum()
        })
        .collect()
}
