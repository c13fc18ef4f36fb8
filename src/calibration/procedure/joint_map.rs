//! From controller readings to the calibrated joint values, for tools that only know a
//! kinematic chain (URDF, a ROS `joint_states` publisher): the calibrated semantics of fig. 3
//! (`docs/formats.md#controller-semantics`) evaluated exactly ([`calibrated_joint_values`]),
//! tabulated per joint ([`joint_map`]: the actuator's transmission inverted, eq. 8, and the
//! passive coupling from the joint below, eq. 15), and the zero offsets a controller that
//! takes nothing else can use ([`controller_zero_offsets`]).
//!
//! `q_k = active_k(u_k) + passive_k(active_{k-1})`, with `u` the controller's decoupling of the
//! commands by the nominal couplings (`u_1 = cmd_1`, `u_k = cmd_k - slope_{k-1,k} u_{k-1}`),
//! `active_k(u) = f_k^-1(u - offset_k)` and `passive_k` the calibrated coupling into joint `k`.

use super::Calibration;
use crate::kinematics::JointKind;
use crate::robot::{Controller, ModelError, RobotDescription, commands_to_internal};
use serde::{Deserialize, Serialize};

/// The calibrated joint values \[rad or m\] of commands `cmd_file` (file units: deg or mm).
pub fn calibrated_joint_values(
    cal: &Calibration,
    desc: &RobotDescription,
    cmd_file: &[f64],
) -> Result<Vec<f64>, ModelError> {
    cal.robot.joint_values(
        &Controller::from_description(desc),
        &commands_to_internal(desc, cmd_file),
    )
}

/// Which function a [`MapRow`] tabulates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum MapTable {
    /// `active_k(u)`: input the actuator command `u_k`, output the joint's active
    /// displacement.
    Active,
    /// `passive_k(a)`: input the active displacement of joint `k - 1`, output the passive
    /// motion it adds to joint `k`.
    Passive,
}

/// One row of the joint map: `output = table_joint(input)`, in file units (deg or mm).
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct MapRow {
    /// The function.
    pub table: MapTable,
    /// 1-based joint.
    pub joint: usize,
    /// Input \[deg or mm\].
    pub input: f64,
    /// Output \[deg or mm\].
    pub output: f64,
    /// Unit of `input`: `deg` or `mm`.
    pub input_unit: &'static str,
    /// Unit of `output`: `deg` or `mm`.
    pub output_unit: &'static str,
}

/// The tabulated joint map and how well linear interpolation in it reproduces the exact
/// functions.
#[derive(Clone, Debug, PartialEq)]
pub struct JointMap {
    /// The rows, joint by joint, active then passive, inputs ascending.
    pub rows: Vec<MapRow>,
    /// The nominal decoupling slopes `slope_{k-1,k}` (index `k - 1`; 0 where not coupled).
    pub decoupling_slopes: Vec<f64>,
    /// Largest difference between linear interpolation in the table and the exact function,
    /// at the midpoints of the grid \[deg or mm\].
    pub max_interpolation_error: f64,
}

/// File units per internal unit of joint `k` (0-based).
fn file_scale(desc: &RobotDescription, k: usize) -> (f64, &'static str) {
    match desc.joints[k].kind {
        JointKind::Revolute => (1f64.to_degrees(), "deg"),
        JointKind::Prismatic => (1e3, "mm"),
    }
}

/// The range of actuator commands `u_k` \[rad or m\] that commands within the limits produce
/// (interval arithmetic through the nominal decoupling).
fn actuator_ranges(desc: &RobotDescription, slopes: &[f64]) -> Vec<[f64; 2]> {
    let mut out: Vec<[f64; 2]> = Vec::with_capacity(desc.dof());
    for (k, &slope) in slopes.iter().enumerate().take(desc.dof()) {
        let [lo, hi] = desc.limits_internal(k);
        let range = match out.last() {
            Some(&[a, b]) if slope != 0.0 => {
                let (p, q) = (slope * a, slope * b);
                [lo - p.max(q), hi - p.min(q)]
            }
            _ => [lo, hi],
        };
        out.push(range);
    }
    out
}

/// `n + 1` evenly spaced points from `lo` to `hi`, and the midpoints between them.
fn grid(lo: f64, hi: f64, step: f64) -> (Vec<f64>, Vec<f64>) {
    let n = (((hi - lo) / step).ceil() as usize).max(1);
    let at = |i: f64| lo + (hi - lo) * i / n as f64;
    (
        (0..=n).map(|i| at(i as f64)).collect(),
        (0..n).map(|i| at(i as f64 + 0.5)).collect(),
    )
}

/// The joint map of `cal` (module docs), tabulated every `step` (file units: deg or mm) over
/// the inputs that commands within the description's limits produce. Inputs where a function
/// cannot be evaluated (a transmission that does not invert) are left out.
pub fn joint_map(cal: &Calibration, desc: &RobotDescription, step: f64) -> JointMap {
    let slopes: Vec<f64> = (0..desc.dof())
        .map(|k| desc.nominal_coupling_into(k + 1).unwrap_or(0.0))
        .collect();
    let ranges = actuator_ranges(desc, &slopes);
    let mut rows = Vec::new();
    let mut max_error: f64 = 0.0;
    let mut tabulate = |table: MapTable, k: usize, range: [f64; 2], f: &dyn Fn(f64) -> Option<f64>| {
        // The passive table's input is the joint below's active displacement.
        let (scale, input_unit) = file_scale(desc, k.saturating_sub(usize::from(table == MapTable::Passive)));
        let (out_scale, output_unit) = file_scale(desc, k);
        let (points, mids) = grid(range[0], range[1], step / scale);
        let values: Vec<Option<f64>> = points.iter().map(|&x| f(x)).collect();
        for (w, m) in values.windows(2).zip(&mids) {
            if let (Some(a), Some(b), Some(exact)) = (w[0], w[1], f(*m)) {
                max_error = max_error.max(((a + b) / 2.0 - exact).abs() * out_scale);
            }
        }
        for (x, y) in points.iter().zip(values) {
            if let Some(y) = y {
                rows.push(MapRow {
                    table,
                    joint: k + 1,
                    input: x * scale,
                    output: y * out_scale,
                    input_unit,
                    output_unit,
                });
            }
        }
    };
    let active_ranges: Vec<[f64; 2]> = (0..desc.dof())
        .map(|k| {
            let j = &cal.robot.joints[k];
            let a = |u: f64| j.transmission.actual_from_command(u - j.transducer_offset);
            match (a(ranges[k][0]), a(ranges[k][1])) {
                (Some(x), Some(y)) => [x.min(y), x.max(y)],
                _ => ranges[k],
            }
        })
        .collect();
    for (k, (j, &range)) in cal.robot.joints.iter().zip(&ranges).enumerate() {
        tabulate(MapTable::Active, k, range, &|u| {
            j.transmission.actual_from_command(u - j.transducer_offset)
        });
        if let (Some(g), Some(below)) = (&j.coupling_in, k.checked_sub(1)) {
            tabulate(MapTable::Passive, k, active_ranges[below], &|a| g.try_passive(a).ok());
        }
    }
    JointMap {
        rows,
        decoupling_slopes: slopes,
        max_interpolation_error: max_error,
    }
}

/// The per-joint zero offsets that bring the NOMINAL kinematics closest to the calibrated
/// robot (for a controller that takes nothing but zero offsets): `delta` minimising
/// `sum |base^-1 FK_nominal(cmd + delta) t - base_cal^-1 FK_calibrated(q(cmd)) t|^2` over the
/// poses and the tool targets `t`, each robot in its own base frame (the numerics' one
/// Levenberg-Marquardt loop, Jacobian [`crate::kinematics::point_jacobian`]). A joint whose
/// turn moves no tool target at any pose (the targets on its axis: a description without
/// targets, whose tool point lies on the last joint's axis) has no offset the fit can see: its
/// Jacobian column is rounding noise, whose spurious gradient kept the loop from ever meeting
/// its stopping rules; it is kept at 0 and named in [`ZeroOffsetFit::undetermined`].
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct ZeroOffsetFit {
    /// Per joint, the offset to ADD to a controller reading (equivalently, to subtract from a
    /// command) so the nominal kinematics reproduce the calibrated robot best \[deg or mm\].
    pub offsets: Vec<f64>,
    /// Their units (`deg` or `mm`).
    pub units: Vec<&'static str>,
    /// Poses fitted.
    pub poses: usize,
    /// Tool-target RMS distance nominal vs calibrated without offsets \[mm\].
    pub rms_before_mm: f64,
    /// ... and with them: what the offsets alone cannot take \[mm\].
    pub rms_after_mm: f64,
    /// Joints (1-based) whose turn moves no tool target at any pose: offset 0, not fitted.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub undetermined: Vec<usize>,
}

/// A Jacobian column at most this fraction of the largest column's norm is rounding noise
/// (about `sqrt(eps)`: a joint whose turn moves a target by a micrometre over a metre's reach
/// still counts).
const NEGLIGIBLE_COLUMN: f64 = 1e-8;

/// [`ZeroOffsetFit`] of `cal` over `commands` (file units); commands the calibrated model
/// cannot execute are skipped. Fails when the fit does not converge.
pub fn controller_zero_offsets(
    cal: &Calibration,
    desc: &RobotDescription,
    commands: &[Vec<f64>],
) -> Result<ZeroOffsetFit, crate::numerics::lsq::LsqError> {
    use crate::numerics::lsq::{LmOptions, levenberg_marquardt};
    use nalgebra::{DMatrix, DVector, Point3};
    let nominal = desc.nominal_model();
    let calibrated = cal.robot.phi_model();
    let controller = Controller::from_description(desc);
    let targets: Vec<Point3<f64>> = match desc.tool_targets_m() {
        t if t.is_empty() => vec![Point3::origin()],
        t => t,
    };
    let n = desc.dof();
    // (raw joint values, calibrated tool targets in the calibrated base frame [m])
    let data: Vec<(Vec<f64>, Vec<Point3<f64>>)> = commands
        .iter()
        .filter_map(|cmd| {
            let raw = commands_to_internal(desc, cmd);
            let q = cal.robot.joint_values(&controller, &raw).ok()?;
            let tool = calibrated.world_from_base.inverse() * calibrated.world_from_tool(&q);
            Some((raw, targets.iter().map(|t| tool * t).collect()))
        })
        .collect();
    let base_inv = nominal.world_from_base.inverse();
    let eval = |delta: &DVector<f64>| -> Result<(DVector<f64>, DMatrix<f64>), crate::numerics::lsq::LsqError> {
        let rows = data.len() * targets.len() * 3;
        let (mut r, mut j) = (DVector::zeros(rows), DMatrix::zeros(rows, n));
        for (i, (raw, wanted)) in data.iter().enumerate() {
            let q: Vec<f64> = raw.iter().zip(delta.iter()).map(|(a, d)| a + d).collect();
            let tool = nominal.world_from_tool(&q);
            for (t, (target, want)) in targets.iter().zip(wanted).enumerate() {
                let row = 3 * (i * targets.len() + t);
                let p = base_inv * (tool * target);
                r.rows_mut(row, 3).copy_from(&((p - want) * 1e3));
                let in_link = nominal.last_link_from_tool * target;
                let jac = base_inv.rotation.to_rotation_matrix()
                    * crate::kinematics::point_jacobian(&nominal, &q, n - 1, &in_link);
                j.view_mut((row, 0), (3, n)).copy_from(&(jac * 1e3));
            }
        }
        Ok((r, j))
    };
    let (before, j0) = eval(&DVector::zeros(n))?;
    let norms: Vec<f64> = (0..n).map(|k| j0.column(k).norm()).collect();
    let largest = norms.iter().copied().fold(0.0, f64::max);
    let fitted: Vec<usize> = (0..n).filter(|&k| norms[k] > NEGLIGIBLE_COLUMN * largest).collect();
    let full = |d: &DVector<f64>| {
        let mut all = DVector::zeros(n);
        fitted.iter().zip(d.iter()).for_each(|(&k, v)| all[k] = *v);
        all
    };
    let outcome = levenberg_marquardt(
        DVector::zeros(fitted.len()),
        &LmOptions::marquardt("controller zero offsets", 100),
        |d: &DVector<f64>| eval(&full(d)).map(|(r, j)| (r, j.select_columns(&fitted))),
        |d, step| Ok(d + step),
    )?
    .converged("controller zero offsets", None)?;
    let rms = |r: &DVector<f64>| (r.norm_squared() / (r.len() / 3).max(1) as f64).sqrt();
    let (offsets, units): (Vec<f64>, Vec<&'static str>) = full(&outcome.state)
        .iter()
        .enumerate()
        .map(|(k, d)| {
            let (scale, unit) = file_scale(desc, k);
            (d * scale, unit)
        })
        .unzip();
    Ok(ZeroOffsetFit {
        offsets,
        units,
        poses: data.len(),
        rms_before_mm: rms(&before),
        rms_after_mm: rms(&outcome.residual),
        undetermined: (1..=n).filter(|j| !fitted.contains(&(j - 1))).collect(),
    })
}
