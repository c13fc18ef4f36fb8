//! The model a free-pose calibration fits: the nominal robot's phi-model (Table-2 rows `a, b,
//! alpha, beta`, paper eq. A3), the joints' zero offsets, the base placement in the instrument
//! frame and the targets' positions in the tool frame; its prediction of every measured point
//! and the analytic Jacobian of that prediction (each parameter a screw motion of the frame it
//! sits in: Murray, Li & Sastry, *A Mathematical Introduction to Robotic Manipulation*, 1994,
//! sec. 3.2, the product of exponentials differentiated factor by factor).

use super::poses::FreePoses;
use crate::calibration::refine::RefitParameter;
use crate::kinematics::{ChainPoses, JointKind, PhiModel, link_from_phi};
use crate::robot::{
    BacklashTerm, Controller, CouplingFunction, LoadTerm, ModelEffects, RobotModel, SagTerm, Transmission,
    sag_regressor,
};
use nalgebra::{DMatrix, DVector, Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

/// The free-pose model's parameters (the base once per setup of the instrument), in the fit's
/// layout and in the order exactly redundant
/// ones are preferred ([`crate::numerics::subset`]): the base (6) and each target's `x, y, z`
/// in the tool frame (what the registration places, so that a parameter left out keeps the
/// description's value, never the registration's), each joint's zero offset, per Table-2 row
/// `a, b, alpha, beta`,
/// then each revolute joint's transmission harmonics (eq. 8) up to `harmonic_order` (sine and
/// cosine of each order).
///
/// A harmonic of order `n` of joint `k` enters only when the joint's values span at least an
/// eighth of its period, `45 / n` deg (`spans_rad[k]`, the range the data cover): over less,
/// its sine and cosine depart from a straight line by under 8 % of their amplitude (`1 -
/// cos 22.5 deg` over the half span), so they are nearly a zero offset and a scale error, fit
/// those and extrapolate wildly beyond the data.
pub fn layout(
    robot: &RobotModel,
    target_ids: &[usize],
    harmonic_order: usize,
    spans_rad: &[f64],
    setups: usize,
) -> Vec<RefitParameter> {
    let mut p: Vec<RefitParameter> = (0..6).map(RefitParameter::Base).collect();
    for setup in 1..setups {
        p.extend((0..6).map(|axis| RefitParameter::SetupBase { setup, axis }));
    }
    for &target in target_ids {
        p.extend((0..3).map(|axis| RefitParameter::Target { target, axis }));
    }
    for (k, j) in robot.joints.iter().enumerate() {
        p.push(RefitParameter::ZeroOffset {
            joint: k + 1,
            sliding: j.kind == JointKind::Prismatic,
        });
    }
    for r in 1..robot.dof() {
        p.extend([
            RefitParameter::RowA(r),
            RefitParameter::RowB(r),
            RefitParameter::RowAlpha(r),
            RefitParameter::RowBeta(r),
        ]);
    }
    let resolved = |k: usize, order: usize, per_joint_turn: f64| {
        order as f64 * per_joint_turn.abs() * spans_rad.get(k).copied().unwrap_or(0.0) >= std::f64::consts::FRAC_PI_4
    };
    for (k, j) in robot.joints.iter().enumerate() {
        if j.kind == JointKind::Revolute {
            // A gear's harmonics turn with the gear angle, `theta / N`.
            let per_joint_turn = match &j.transmission {
                Transmission::Gear { ratio, .. } => 1.0 / ratio,
                _ => 1.0,
            };
            for order in (1..=harmonic_order).filter(|&o| resolved(k, o, per_joint_turn)) {
                for cosine in [false, true] {
                    p.push(RefitParameter::Harmonic {
                        joint: k + 1,
                        order,
                        cosine,
                    });
                }
            }
        }
    }
    p.extend(coupling_harmonics(robot, harmonic_order, &resolved));
    p
}

/// The harmonics of each passive coupling of gear form (`g = N t + sum_k (s_k sin k N t + c_k
/// cos k N t)`, paper eq. 15; the bevel gear 4->5 of the IRB/L6, whose errors move the wrist by
/// millimetres): as the transmissions', up to `harmonic_order` where the driving joint's span
/// resolves them (`resolved(driving joint, order, N)`).
fn coupling_harmonics(
    robot: &RobotModel,
    harmonic_order: usize,
    resolved: &dyn Fn(usize, usize, f64) -> bool,
) -> Vec<RefitParameter> {
    let mut p = Vec::new();
    for (k, j) in robot.joints.iter().enumerate().skip(1) {
        let Some(CouplingFunction::Gear { ratio, .. }) = &j.coupling_in else {
            continue;
        };
        if robot.joints[k - 1].kind != JointKind::Revolute {
            continue;
        }
        for order in (1..=harmonic_order).filter(|&o| resolved(k - 1, o, *ratio)) {
            for cosine in [false, true] {
                p.push(RefitParameter::Coupling {
                    joint: k + 1,
                    coefficient: format!("{}{order}", if cosine { "cos" } else { "sin" }),
                });
            }
        }
    }
    p
}

/// The harmonic order of a transmission's or a coupling's harmonic (`None` for every other
/// parameter): the model selection's order ([`super::CV_FOLDS`]-fold cross-validation).
pub fn harmonic_order(p: &RefitParameter) -> Option<usize> {
    match p {
        RefitParameter::Harmonic { order, .. } => Some(*order),
        RefitParameter::Coupling { coefficient, .. } => coupling_term(coefficient).map(|(order, _)| order),
        _ => None,
    }
}

/// `(order, cosine)` of a coupling coefficient named `sin<k>` or `cos<k>`.
fn coupling_term(coefficient: &str) -> Option<(usize, bool)> {
    let (cosine, order) = match coefficient.split_at_checked(3)? {
        ("sin", k) => (false, k),
        ("cos", k) => (true, k),
        _ => return None,
    };
    Some((order.parse().ok()?, cosine))
}

/// The nominal model with the transmission and coupling forms the description asks the
/// calibrator to fit where they change what the free-pose model can carry: a gear
/// transmission (`transmission_fit` gear: harmonics in the gear angle, the IRB/L6's joint 5)
/// and, for every coupling, its nominal slope as a gear (already [`RobotModel::ideal`]'s
/// form). Predictions are the nominal's: a gear without harmonics is the identity.
pub fn with_fit_forms(mut robot: RobotModel, desc: &crate::robot::RobotDescription) -> RobotModel {
    for (joint, entry) in robot.joints.iter_mut().zip(&desc.joints) {
        if let Some(crate::robot::TransmissionFitForm::Gear { ratio, .. }) = entry.transmission_fit {
            joint.transmission = Transmission::Gear {
                ratio,
                sin: vec![],
                cos: vec![],
            };
        }
    }
    robot
}

/// Adds `d` to the harmonic coefficient of `order` (sine or cosine) of a harmonic
/// transmission, growing both coefficient lists as needed: a series has one sine and one
/// cosine per order (a coefficient the fit leaves out stays 0), as `calibration.json` holds it.
fn add_harmonic(t: &mut Transmission, order: usize, cosine: bool, d: f64) {
    if let Transmission::Harmonic { sin, cos } | Transmission::Gear { sin, cos, .. } = t {
        for list in [&mut *sin, &mut *cos] {
            if list.len() < order {
                list.resize(order, 0.0);
            }
        }
        let list = if cosine { cos } else { sin };
        list[order - 1] += d;
    }
}

/// Adds `d` to the coefficient `coefficient` (`sin<k>`, `cos<k>`) of a gear coupling, growing
/// both coefficient lists as [`add_harmonic`] does.
fn add_coupling_harmonic(g: &mut Option<CouplingFunction>, coefficient: &str, d: f64) {
    if let (Some(CouplingFunction::Gear { sin, cos, .. }), Some((order, cosine))) = (g, coupling_term(coefficient)) {
        for list in [&mut *sin, &mut *cos] {
            if list.len() < order {
                list.resize(order, 0.0);
            }
        }
        let list = if cosine { cos } else { sin };
        list[order - 1] += d;
    }
}

/// Adds `d` to the sag coefficient of `joint`, `link`, `load`, inserting it in the order of
/// joint, link and load term.
fn add_sag(effects: &mut ModelEffects, joint: usize, link: usize, load: LoadTerm, d: f64) {
    let key = |t: &SagTerm| (t.joint, t.link, t.load);
    match effects.sag.binary_search_by_key(&(joint, link, load), key) {
        Ok(k) => effects.sag[k].coefficient += d,
        Err(k) => effects.sag.insert(
            k,
            SagTerm {
                joint,
                link,
                load,
                coefficient: d,
            },
        ),
    }
}

/// Adds `d` to `joint`'s backlash half band, inserting it in joint order.
fn add_backlash(effects: &mut ModelEffects, joint: usize, d: f64) {
    match effects.backlash.binary_search_by_key(&joint, |b| b.joint) {
        Ok(k) => effects.backlash[k].half_band += d,
        Err(k) => effects.backlash.insert(k, BacklashTerm { joint, half_band: d }),
    }
}

/// One state of the fitted model (an immutable value: [`FreePoseModel::moved`] makes the next).
#[derive(Clone, Debug)]
pub struct FreePoseModel {
    /// The robot: its joints' zero offsets (`transducer_offset`), transmissions and couplings
    /// turn commands into joint values; its rows and placement are mirrored by `phi`.
    pub robot: RobotModel,
    /// The geometry in internal units (rows, base placement, tool frame).
    pub phi: PhiModel,
    /// The targets' ids, ascending ([`FreePoses::target_ids`]).
    pub target_ids: Vec<usize>,
    /// Each target's position in the tool frame \[m\], in the order of `target_ids`.
    pub targets_in_tool_m: Vec<Point3<f64>>,
    /// The base in the instrument frame of setups 1, 2, ... (setup 0's is
    /// `phi.world_from_base`).
    pub other_bases: Vec<Isometry3<f64>>,
}

/// A command the model cannot execute (a transmission not invertible there).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Unexecutable {
    /// The pose (index into [`FreePoses::poses`]).
    pub pose: usize,
}

impl Unexecutable {
    /// The calibration's error for it, naming the pose of `poses`.
    pub fn error(self, poses: &FreePoses) -> super::FreePoseError {
        super::FreePoseError::Unexecutable {
            pose: poses.poses[self.pose].label(),
        }
    }
}

impl FreePoseModel {
    /// The model of `robot` with its placement replaced by `world_from_base` and the targets
    /// `target_ids` at `targets_in_tool_m`.
    pub fn new(
        robot: &RobotModel,
        world_from_base: Isometry3<f64>,
        target_ids: Vec<usize>,
        targets_in_tool_m: Vec<Point3<f64>>,
    ) -> Self {
        let mut phi = robot.phi_model();
        phi.world_from_base = world_from_base;
        let mut robot = robot.clone();
        robot.placement = crate::robot::Placement::from_isometry(&world_from_base);
        FreePoseModel {
            robot,
            phi,
            target_ids,
            targets_in_tool_m,
            other_bases: Vec::new(),
        }
    }

    /// The base in the instrument frame of `setup`.
    pub fn world_from_base(&self, setup: usize) -> Isometry3<f64> {
        match setup {
            0 => self.phi.world_from_base,
            s => self.other_bases[s - 1],
        }
    }

    /// `world_of_setup_from_world_of_setup_0`: maps a point predicted in setup 0's instrument
    /// frame into `setup`'s.
    fn setup_from_first(&self, setup: usize) -> Option<Isometry3<f64>> {
        (setup > 0).then(|| self.other_bases[setup - 1] * self.phi.world_from_base.inverse())
    }

    /// The robot model with the fitted geometry written back (file units).
    pub fn to_robot(&self) -> RobotModel {
        let mut robot = self.robot.clone();
        robot.placement = crate::robot::Placement::from_isometry(&self.phi.world_from_base);
        for (entry, row) in robot.rows.iter_mut().zip(&self.phi.rows) {
            *entry = crate::robot::RowEntry::from_row(row);
        }
        robot
    }

    /// The model moved by `delta` along the parameters `which` (layout of [`layout`]): rows,
    /// offsets, harmonics and targets additively, the base by a rotation about its own origin
    /// and axes (`rz` turns about axis 1, as joint 1's zero offset does) and a translation
    /// along the instrument's axes.
    pub fn moved(&self, layout: &[RefitParameter], which: &[usize], delta: &DVector<f64>) -> Self {
        let mut next = self.clone();
        let (mut shift, mut turn) = (Vector3::zeros(), Vector3::zeros());
        let mut setup_moves = vec![(Vector3::zeros(), Vector3::zeros()); self.other_bases.len()];
        for (&c, &d) in which.iter().zip(delta.iter()) {
            match &layout[c] {
                RefitParameter::Base(a) if *a < 3 => shift[*a] += d,
                RefitParameter::Base(a) => turn[*a - 3] += d,
                RefitParameter::SetupBase { setup, axis } if *axis < 3 => setup_moves[setup - 1].0[*axis] += d,
                RefitParameter::SetupBase { setup, axis } => setup_moves[setup - 1].1[*axis - 3] += d,
                RefitParameter::RowA(r) => next.phi.rows[r - 1].a_m += d,
                RefitParameter::RowB(r) => next.phi.rows[r - 1].b_m += d,
                RefitParameter::RowAlpha(r) => next.phi.rows[r - 1].alpha_rad += d,
                RefitParameter::RowBeta(r) => next.phi.rows[r - 1].beta_rad += d,
                RefitParameter::ZeroOffset { joint, .. } => next.robot.joints[joint - 1].transducer_offset += d,
                RefitParameter::Harmonic { joint, order, cosine } => {
                    add_harmonic(&mut next.robot.joints[joint - 1].transmission, *order, *cosine, d)
                }
                RefitParameter::Target { target, axis } => {
                    let slot = self.slot(*target);
                    next.targets_in_tool_m[slot][*axis] += d
                }
                RefitParameter::Coupling { joint, coefficient } => {
                    add_coupling_harmonic(&mut next.robot.joints[joint - 1].coupling_in, coefficient, d)
                }
                RefitParameter::Sag { joint, link, load } => add_sag(&mut next.robot.effects, *joint, *link, *load, d),
                RefitParameter::Backlash { joint, .. } => add_backlash(&mut next.robot.effects, *joint, d),
                other => unreachable!("{} is not in the free-pose layout", other.name()),
            }
        }
        next.phi.world_from_base = moved_base(&self.phi.world_from_base, shift, turn);
        for (base, (shift, turn)) in next.other_bases.iter_mut().zip(setup_moves) {
            *base = moved_base(base, shift, turn);
        }
        next
    }

    /// The slot of target `id` in `targets_in_tool_m`.
    fn slot(&self, id: usize) -> usize {
        self.target_ids
            .binary_search(&id)
            .unwrap_or_else(|_| unreachable!("target {id} is in the layout, not in the model"))
    }

    /// The joint values of every pose, or the first pose the model cannot execute.
    pub fn joint_values(&self, controller: &Controller, poses: &FreePoses) -> Result<Vec<Vec<f64>>, Unexecutable> {
        poses
            .poses
            .iter()
            .enumerate()
            .map(|(i, p)| {
                controller
                    .decouple(&p.cmd)
                    .and_then(|u| self.robot.joint_values_from_actuators(&u))
                    .map_err(|_| Unexecutable { pose: i })
            })
            .collect()
    }

    /// The residual `measured - predicted` \[m\] of every point of the poses `which` (3 rows a
    /// point, in the order of the poses and their points).
    pub fn residuals(
        &self,
        controller: &Controller,
        poses: &FreePoses,
        which: &[usize],
    ) -> Result<DVector<f64>, Unexecutable> {
        let fixed = self.phi.fixed_frames();
        let mut r = Vec::with_capacity(3 * which.len() * poses.targets_per_pose_max());
        for &i in which {
            let pose = &poses.poses[i];
            let q = self.pose_joint_values(controller, poses, i)?;
            let world_from_tool = match self.setup_from_first(pose.setup) {
                Some(m) => m * fixed.world_from_tool(&q),
                None => fixed.world_from_tool(&q),
            };
            for (slot, measured) in &pose.points_m {
                let e = measured - world_from_tool * self.targets_in_tool_m[*slot];
                r.extend_from_slice(e.as_slice());
            }
        }
        Ok(DVector::from_vec(r))
    }

    /// The residual of [`Self::residuals`] and its Jacobian by the parameters `columns` of
    /// `layout` (`d residual / d parameter`, the analytic screw columns of the module docs).
    pub fn residuals_and_jacobian(
        &self,
        controller: &Controller,
        poses: &FreePoses,
        which: &[usize],
        layout: &[RefitParameter],
        columns: &[usize],
    ) -> Result<(DVector<f64>, DMatrix<f64>), Unexecutable> {
        let rows: usize = which.iter().map(|&i| 3 * poses.poses[i].points_m.len()).sum();
        let mut r = DVector::zeros(rows);
        let mut jac = DMatrix::zeros(rows, columns.len());
        let fixed = self.phi.fixed_frames();
        let mut row = 0;
        for &i in which {
            let (before_sag, q) = self.pose_joint_values_before_and_after_sag(controller, poses, i)?;
            let (dq_du, theta_a) = self.joint_sensitivity(controller, poses, i, &q)?;
            let frames = fixed.poses(&q);
            let sag_frames = (!self.robot.effects.sag.is_empty()).then(|| fixed.poses(&before_sag));
            let row_axes: Vec<RowAxes> = (0..self.phi.rows.len()).map(|k| self.row_axes(&frames, k)).collect();
            let setup = poses.poses[i].setup;
            let to_setup = self.setup_from_first(setup);
            for (slot, measured) in &poses.poses[i].points_m {
                // Everything is derived in setup 0's instrument frame, then carried into the
                // pose's own (a rigid map: points and their derivatives alike).
                let p = frames.world_from_tool * self.targets_in_tool_m[*slot];
                let p_here = to_setup.map_or(p, |m| m * p);
                r.fixed_rows_mut::<3>(row).copy_from(&(measured - p_here));
                let point = PointContext {
                    p,
                    slot: *slot,
                    frames: &frames,
                    row_axes: &row_axes,
                    dq_du: &dq_du,
                    theta_a: &theta_a,
                    sag_frames: sag_frames.as_ref().unwrap_or(&frames),
                    approach: &poses.poses[i].approach,
                    payload_kg: poses.poses[i].payload_kg,
                };
                for (c, &param) in columns.iter().enumerate() {
                    let dp = match self.base_derivative(&layout[param], setup, &p_here) {
                        Some(dp) => dp,
                        None => {
                            let dp = self.point_derivative(&point, &layout[param]);
                            to_setup.map_or(dp, |m| m.rotation * dp)
                        }
                    };
                    jac.fixed_view_mut::<3, 1>(row, c).copy_from(&(-dp));
                }
                row += 3;
            }
        }
        Ok((r, jac))
    }

    /// Joint values of pose `i`.
    fn pose_joint_values(
        &self,
        controller: &Controller,
        poses: &FreePoses,
        i: usize,
    ) -> Result<Vec<f64>, Unexecutable> {
        Ok(self.pose_joint_values_before_and_after_sag(controller, poses, i)?.1)
    }

    /// Each joint's sag at pose `i` \[rad or m\] (0 for a joint without one).
    pub fn sag_at(&self, controller: &Controller, poses: &FreePoses, i: usize) -> Result<Vec<f64>, Unexecutable> {
        let (before, after) = self.pose_joint_values_before_and_after_sag(controller, poses, i)?;
        Ok(after.iter().zip(&before).map(|(a, b)| a - b).collect())
    }

    /// Joint values of pose `i` before the sag and after it.
    fn pose_joint_values_before_and_after_sag(
        &self,
        controller: &Controller,
        poses: &FreePoses,
        i: usize,
    ) -> Result<(Vec<f64>, Vec<f64>), Unexecutable> {
        let pose = &poses.poses[i];
        controller
            .decouple(&pose.cmd)
            .and_then(|u| self.robot.joint_values_before_and_after_sag(&self.phi, u, &pose.load()))
            .map_err(|_| Unexecutable { pose: i })
    }

    /// `dq_j / du_k` at pose `i` (row `j`, column `k`; a zero offset enters as
    /// `u_k - offset_k`) and the active displacements `theta_a` (eq. 8 inverted). With
    /// `q_k = theta_k + g_k(theta_(k-1))` and `f_k(theta_k) = u_k`: `dq_k / du_k = 1 / f_k'` and
    /// `dq_(k+1) / du_k = g_(k+1)' / f_k'`, every other entry 0.
    fn joint_sensitivity(
        &self,
        controller: &Controller,
        poses: &FreePoses,
        i: usize,
        q: &[f64],
    ) -> Result<(DMatrix<f64>, Vec<f64>), Unexecutable> {
        let unexecutable = |_| Unexecutable { pose: i };
        let mut u = controller.decouple(&poses.poses[i].cmd).map_err(unexecutable)?;
        self.robot.effects.shift_actuators(&mut u, &poses.poses[i].load());
        let theta_a = self.robot.active_displacements(&u).map_err(unexecutable)?;
        let n = q.len();
        let mut d = DMatrix::zeros(n, n);
        for (k, joint) in self.robot.joints.iter().enumerate() {
            let du_dtheta = joint.transmission.slope(theta_a[k]);
            d[(k, k)] = 1.0 / du_dtheta;
            if let Some(g) = self.robot.joints.get(k + 1).and_then(|next| next.coupling_in.as_ref()) {
                let slope = g.try_slope(theta_a[k]).map_err(|_| Unexecutable { pose: i })?;
                d[(k + 1, k)] = slope / du_dtheta;
            }
        }
        Ok((d, theta_a))
    }

    /// `d p / d parameter` of a base parameter (of any setup) for a point `p` measured from
    /// `setup` (in its instrument frame): a translation along the instrument's axes or a
    /// rotation about the base's own axes through its origin; 0 for another setup's base.
    /// `None` for every other parameter.
    fn base_derivative(&self, param: &RefitParameter, setup: usize, p: &Point3<f64>) -> Option<Vector3<f64>> {
        let (of, axis) = match param {
            RefitParameter::Base(a) => (0, *a),
            RefitParameter::SetupBase { setup, axis } => (*setup, *axis),
            _ => return None,
        };
        if of != setup {
            return Some(Vector3::zeros());
        }
        let base = self.world_from_base(setup);
        Some(match axis {
            a if a < 3 => Vector3::ith(a, 1.0),
            a => (base.rotation * Vector3::ith(a - 3, 1.0)).cross(&(p.coords - base.translation.vector)),
        })
    }

    /// `d p / d parameter` of a point on the last link \[m per parameter unit\].
    fn point_derivative(&self, point: &PointContext<'_>, param: &RefitParameter) -> Vector3<f64> {
        let p = point.p;
        match param {
            RefitParameter::Base(a) if *a < 3 => Vector3::ith(*a, 1.0),
            RefitParameter::Base(a) => {
                let base = &self.phi.world_from_base;
                (base.rotation * Vector3::ith(*a - 3, 1.0)).cross(&(p.coords - base.translation.vector))
            }
            RefitParameter::RowA(r)
            | RefitParameter::RowB(r)
            | RefitParameter::RowAlpha(r)
            | RefitParameter::RowBeta(r) => self.row_derivative(point, *r - 1, param),
            // q = q(u - offset): dp/d offset_k = -sum_j dp/dq_j dq_j/du_k.
            RefitParameter::ZeroOffset { joint, .. } => -self.actuator_derivative(point, joint - 1),
            // f(theta_a) + c h(theta_a) = u moves theta_a by -h(theta_a) dc / f'(theta_a): as
            // the command moved by -h(theta_a) dc.
            // A gear's `f = theta_a + N c h(k theta_a / N)`: the same with `N h`.
            RefitParameter::Harmonic { joint, order, cosine } => {
                let n = match &self.robot.joints[joint - 1].transmission {
                    Transmission::Gear { ratio, .. } => *ratio,
                    _ => 1.0,
                };
                let angle = *order as f64 * point.theta_a[joint - 1] / n;
                let h = if *cosine { angle.cos() } else { angle.sin() };
                -n * h * self.actuator_derivative(point, joint - 1)
            }
            // q_j = theta_j + g(theta_(j-1)), g's term c h(k N theta_(j-1)): joint j moves by h.
            RefitParameter::Coupling { joint, coefficient } => {
                let ratio = match &self.robot.joints[joint - 1].coupling_in {
                    Some(CouplingFunction::Gear { ratio, .. }) => *ratio,
                    _ => unreachable!("a coupling harmonic is laid out for gear couplings only"),
                };
                let (order, cosine) = coupling_term(coefficient).unwrap_or_else(|| {
                    unreachable!("coupling coefficient {coefficient} is laid out as sin<k> or cos<k>")
                });
                let angle = order as f64 * ratio * point.theta_a[joint - 2];
                let h = if cosine { angle.cos() } else { angle.sin() };
                h * joint_column(self.phi.joints[joint - 1].kind, point.frames, joint - 1, &p)
            }
            RefitParameter::Target { target, axis } if *target == self.target_ids[point.slot] => {
                point.frames.world_from_tool.rotation * Vector3::ith(*axis, 1.0)
            }
            RefitParameter::Target { .. } => Vector3::zeros(),
            // dq_j = c r(q): the point moves as joint j does, by r per unit c (the regressor at
            // the pose's frames, module docs of `crate::robot::ModelEffects` for its order).
            RefitParameter::Sag { joint, link, load } => {
                let r = sag_regressor(&self.phi, point.sag_frames, *joint, *link, *load, point.payload_kg);
                r * joint_column(self.phi.joints[joint - 1].kind, point.frames, joint - 1, &p)
            }
            // u_k acts as u_k - s_k h_k: as the zero offset, times s_k.
            RefitParameter::Backlash { joint, .. } => {
                -point.approach[joint - 1] * self.actuator_derivative(point, joint - 1)
            }
            other => unreachable!("{} is not in the free-pose layout", other.name()),
        }
    }

    /// `d p / d u_k`: the point's motion per unit actuator command of joint `k` (0-based).
    fn actuator_derivative(&self, point: &PointContext<'_>, k: usize) -> Vector3<f64> {
        let mut dp = Vector3::zeros();
        for j in 0..self.phi.dof() {
            let w = point.dq_du[(j, k)];
            if w != 0.0 {
                dp += w * joint_column(self.phi.joints[j].kind, point.frames, j, &point.p);
            }
        }
        dp
    }

    /// The screw axes of Table-2 row `k` (0-based) at a pose, eq. (A3)
    /// `Trans(0,0,a) Rot(z,beta) Trans(b,0,0) Rot(x,alpha)` in the `phi_k` frame of link `k`.
    fn row_axes(&self, frames: &ChainPoses, k: usize) -> RowAxes {
        let row = &self.phi.rows[k];
        let world_from_phi = frames.world_from_link[k] * link_from_phi(self.phi.joints[k].phi_rad);
        let z = world_from_phi.rotation * Vector3::z();
        let o1 = world_from_phi.translation.vector + row.a_m * z;
        let x = world_from_phi.rotation
            * (UnitQuaternion::from_axis_angle(&Vector3::z_axis(), row.beta_rad) * Vector3::x());
        RowAxes {
            z,
            o1,
            x,
            o2: o1 + row.b_m * x,
        }
    }

    /// The derivative by one parameter of Table-2 row `k` (0-based): a translation along or a
    /// rotation about one of its screw axes ([`Self::row_axes`]).
    fn row_derivative(&self, point: &PointContext<'_>, k: usize, param: &RefitParameter) -> Vector3<f64> {
        let RowAxes { z, o1, x, o2 } = point.row_axes[k];
        let p = point.p.coords;
        match param {
            RefitParameter::RowA(_) => z,
            RefitParameter::RowBeta(_) => z.cross(&(p - o1)),
            RefitParameter::RowB(_) => x,
            _ => x.cross(&(p - o2)),
        }
    }
}

/// A Table-2 row's screw axes in the world at one pose: `a` translates along `z`, `beta` turns
/// about `z` through `o1`, `b` translates along `x`, `alpha` turns about `x` through `o2`.
#[derive(Clone, Copy)]
struct RowAxes {
    z: Vector3<f64>,
    o1: Vector3<f64>,
    x: Vector3<f64>,
    o2: Vector3<f64>,
}

/// What the derivatives of one measured point need.
struct PointContext<'a> {
    /// The predicted point \[m\].
    p: Point3<f64>,
    /// Its target's slot.
    slot: usize,
    /// The chain's frames at the pose.
    frames: &'a ChainPoses,
    /// Each Table-2 row's screw axes at the pose.
    row_axes: &'a [RowAxes],
    /// `dq / du` at the pose.
    dq_du: &'a DMatrix<f64>,
    /// The active displacements at the pose \[rad or m\].
    theta_a: &'a [f64],
    /// The chain's frames before the sag, where its regressors are evaluated.
    sag_frames: &'a ChainPoses,
    /// The pose's approach directions.
    approach: &'a [f64],
    /// The pose's payload \[kg\].
    payload_kg: f64,
}

/// `d p / d q_j` of a point `p` beyond joint `j` (0-based): `z x (p - o)` (revolute) or `z`.
fn joint_column(kind: JointKind, frames: &ChainPoses, j: usize, p: &Point3<f64>) -> Vector3<f64> {
    let axis = frames.axis(j);
    match kind {
        JointKind::Revolute => axis.direction.cross(&(p - axis.origin_m)),
        JointKind::Prismatic => axis.direction.into_inner(),
    }
}

/// `base` turned by `turn` about its own origin and axes, then shifted by `shift` along the
/// instrument's axes.
fn moved_base(base: &Isometry3<f64>, shift: Vector3<f64>, turn: Vector3<f64>) -> Isometry3<f64> {
    let rotation = base.rotation * UnitQuaternion::from_scaled_axis(turn);
    Isometry3::from_parts(Translation3::from(base.translation.vector + shift), rotation)
}
