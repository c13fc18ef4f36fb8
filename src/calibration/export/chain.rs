//! The calibrated model as a chain of URDF joint origins, the form every kinematics export
//! writes: joint `k`'s origin in its parent link, then the joint's motion along +Z (a rotation
//! by the joint variable, or a translation). A chain's joint variables are either:
//! - the phi-model joint values `q` ([`OriginChain::of_phi_model`], as `calibrated.urdf`); the
//!   controller's readings go through the joint map first;
//! - or the controller's readings ([`reading_chain`]), each joint's zero offset turned into
//!   its origin (`origin_k Rz(q_k) = origin_k Rz(offset_k) Rz(u_k)` when `q_k = u_k + offset_k`);
//!   exact only where the reading maps to the joint value by a constant shift
//!   ([`Unrepresented`] lists the rest).

use crate::calibration::procedure::Calibration;
use crate::kinematics::{JointKind, PhiModel, joint_motion};
use crate::robot::{RobotDescription, RobotModel, Transmission};
use nalgebra::Isometry3;

/// One joint of an [`OriginChain`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChainJoint {
    /// Revolute or prismatic (motion about or along +Z of the joint frame).
    pub kind: JointKind,
    /// The joint frame at joint value 0 in its parent link (link `k - 1`; the root for joint 1).
    pub parent_from_joint: Isometry3<f64>,
}

/// A serial chain of joint origins from a root link to a tool frame.
#[derive(Clone, Debug, PartialEq)]
pub struct OriginChain {
    /// The joints, root first.
    pub joints: Vec<ChainJoint>,
    /// The tool frame in the last link.
    pub last_link_from_tool: Isometry3<f64>,
    /// The root link in the instrument frame.
    pub world_from_root: Isometry3<f64>,
}

impl OriginChain {
    /// The chain of a phi-model: root its base frame (frame 1), each joint's origin the fixed
    /// frame `k` in link `k - 1` (eqs. A1-A3), joint variables `q`.
    pub fn of_phi_model(model: &PhiModel) -> Self {
        let joints = (0..model.dof())
            .map(|k| ChainJoint {
                kind: model.joints[k].kind,
                parent_from_joint: if k == 0 {
                    Isometry3::identity()
                } else {
                    model.link_from_next_frame(k - 1)
                },
            })
            .collect();
        Self {
            joints,
            last_link_from_tool: model.last_link_from_tool,
            world_from_root: model.world_from_base,
        }
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// Link `k` (1-based; 0 the root) in the root frame at joint variables `values` (rad or m).
    pub fn root_from_link(&self, values: &[f64], k: usize) -> Isometry3<f64> {
        self.joints
            .iter()
            .zip(values)
            .take(k)
            .fold(Isometry3::identity(), |t, (j, &v)| {
                t * j.parent_from_joint * joint_motion(j.kind, v)
            })
    }

    /// The tool frame in the root frame at joint variables `values` (rad or m).
    pub fn root_from_tool(&self, values: &[f64]) -> Isometry3<f64> {
        self.root_from_link(values, self.dof()) * self.last_link_from_tool
    }
}

/// Something of the calibrated model a kinematic chain does not hold.
#[derive(Clone, Debug, PartialEq)]
pub struct Unrepresented {
    /// The joint (1-based), if it is one joint's.
    pub joint: Option<usize>,
    /// What it is, as a sentence fragment ("joint 3's reading is coupled to joint 2's ...").
    pub what: String,
    /// What the user can do instead.
    pub remedy: &'static str,
}

const USE_JOINT_MAP: &str = "use calibrated.urdf with the readings converted by joint_map.csv or `axiscal joints`";
const OFFSET_ONLY: &str = "calibrate with `transmission_fit = { form = \"harmonic\", order = 0 }` (rotary) or `{ form = \"polynomial\", order = 1 }` (sliding) on the joint in the description";
const KEEP_EFFECTS: &str = "the effects stay in calibration.json, which `compensate` and `validate` use";

/// The effects of `robot` no kinematic chain holds.
fn effects_left_out(robot: &RobotModel) -> Vec<Unrepresented> {
    let effects = &robot.effects;
    let mut out = Vec::new();
    if !effects.compliance.is_empty() {
        out.push(Unrepresented {
            joint: None,
            what: "the joint compliance carried from a diagnosis (a load-dependent sag)".into(),
            remedy: KEEP_EFFECTS,
        });
    }
    if !effects.backlash.is_empty() {
        out.push(Unrepresented {
            joint: None,
            what: "the backlash carried from a diagnosis (it depends on the approach direction)".into(),
            remedy: KEEP_EFFECTS,
        });
    }
    out
}

/// A joint value as a linear function of the reading, `q = u / reduction + offset` (ros_control's
/// simple transmission: joint position = actuator position / reduction + offset).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearReading {
    /// `reduction` (1 for a transmission without scale error).
    pub reduction: f64,
    /// `offset` \[rad or m\].
    pub offset: f64,
}

impl LinearReading {
    /// The joint value of reading `u` \[rad or m\].
    pub fn joint_value(&self, u: f64) -> f64 {
        u / self.reduction + self.offset
    }
}

/// Joint `k`'s (0-based) reading-to-value map when it is linear: `q = (u - o - c0) / (1 + c1)`
/// (a transmission without harmonics or gear errors, a sliding joint's scale error `c1`), else
/// why not.
fn linear_reading(robot: &RobotModel, k: usize) -> Result<LinearReading, String> {
    let joint = &robot.joints[k];
    let zero = |c: &[f64]| c.iter().all(|v| *v == 0.0);
    let (shift, scale) = match &joint.transmission {
        Transmission::Harmonic { sin, cos } if zero(sin) && zero(cos) => (0.0, 1.0),
        Transmission::Gear { sin, cos, .. } if zero(sin) && zero(cos) => (0.0, 1.0),
        Transmission::Polynomial { c0, c } if c.is_empty() || zero(&c[1..]) => {
            (*c0, 1.0 + c.first().copied().unwrap_or(0.0))
        }
        Transmission::Harmonic { .. } => return Err("a harmonic transmission (eq. 8)".into()),
        Transmission::Gear { .. } => return Err("a gear transmission with periodic errors (eq. 8)".into()),
        Transmission::Polynomial { .. } => return Err("a nonlinear sliding transmission (eq. 13)".into()),
    };
    Ok(LinearReading {
        reduction: scale,
        offset: -(joint.transducer_offset + shift) / scale,
    })
}

/// Every joint's [`LinearReading`] and what the calibrated model has beyond them: a reading
/// coupled to another joint's (the controller's nominal decoupling or a calibrated passive
/// coupling), a transmission that is not linear (its harmonics are left out; the map kept is
/// the mean shift over the joint's limits), and the load-dependent effects.
pub fn linear_readings(cal: &Calibration, desc: &RobotDescription) -> (Vec<LinearReading>, Vec<Unrepresented>) {
    let robot = &cal.robot;
    let mut left_out = Vec::new();
    let mut maps = Vec::with_capacity(robot.dof());
    for k in 0..robot.dof() {
        let joint = k + 1;
        if let Some(slope) = desc.nominal_coupling_into(joint) {
            left_out.push(Unrepresented {
                joint: Some(joint),
                what: format!(
                    "joint {joint}'s reading is decoupled from joint {k}'s by the controller (slope {slope}): no reading alone gives its joint value"
                ),
               remedy: USE_JOINT_MAP,
            });
        }
        if robot.joints[k].coupling_in.is_some() {
            left_out.push(Unrepresented {
                joint: Some(joint),
                what: format!("joint {joint} moves passively with joint {k} (a calibrated coupling, eq. 15)"),
                remedy: USE_JOINT_MAP,
            });
        }
        maps.push(linear_reading(robot, k).unwrap_or_else(|why| {
            left_out.push(Unrepresented {
                joint: Some(joint),
                what: format!("joint {joint}'s transmission is {why}, not a linear map of the reading"),
                remedy: OFFSET_ONLY,
            });
            LinearReading {
                reduction: 1.0,
                offset: -mean_shift(robot, desc, k),
            }
        }));
    }
    left_out.extend(effects_left_out(robot));
    (maps, left_out)
}

/// The calibrated chain with the controller's readings as joint variables, each joint's
/// offset in its origin (`origin_k M(q_k) = origin_k M(offset_k) M(u_k)`), and what it cannot
/// hold: what [`linear_readings`] lists, and a sliding joint's scale error (no origin holds
/// one; ros_control's transmission `mechanical_reduction` does). Exact when that list is
/// empty.
pub fn reading_chain(cal: &Calibration, desc: &RobotDescription) -> (OriginChain, Vec<Unrepresented>) {
    let mut chain = OriginChain::of_phi_model(&cal.robot.phi_model());
    let (maps, mut left_out) = linear_readings(cal, desc);
    for (k, (joint, map)) in chain.joints.iter_mut().zip(&maps).enumerate() {
        // Exactly: any scale error, however small, is not in the file (and is reported).
        if map.reduction - 1.0 != 0.0 {
            left_out.push(Unrepresented {
                joint: Some(k + 1),
                what: format!(
                    "joint {}'s scale error ({:e}) has no place in an origin (ros_control's `mechanical_reduction` holds it)",
                    k + 1,
                    map.reduction - 1.0
                ),
                remedy: "`axiscal export xacro-yaml --offsets transmission` writes it as `mechanical_reduction`",
            });
        }
        joint.parent_from_joint *= joint_motion(joint.kind, map.offset);
    }
    (chain, left_out)
}

/// The mean of `u - active_k(u)` over 1001 readings spread evenly through joint `k`'s limits
/// (0-based): the constant shift closest (least squares) to a transmission that is not one.
fn mean_shift(robot: &RobotModel, desc: &RobotDescription, k: usize) -> f64 {
    let [lo, hi] = desc.limits_internal(k);
    let n = 1001;
    let shifts: Vec<f64> = (0..n)
        .filter_map(|i| {
            let u = lo + (hi - lo) * i as f64 / (n - 1) as f64;
            robot.active_displacement(k, u).ok().map(|a| u - a)
        })
        .collect();
    // A transmission that inverts nowhere in the limits fails the calibration's own checks;
    // 0 is then the nominal shift.
    shifts.iter().sum::<f64>() / shifts.len().max(1) as f64
}
