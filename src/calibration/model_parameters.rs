//! The calibrated model's parameter vector `p` and its covariance: the base placement
//! (translation \[m\] and rotation vector \[rad\], both relative to the calibrated placement,
//! `world_from_base = B exp(d)`), every Table-2 row (`a`, `b` \[m\], `alpha`, `beta`, `gamma`
//! \[rad\], `h` \[m\]), every joint (`phi` \[rad\], zero offset \[rad or m\], transmission
//! coefficients, coupling coefficients) and the tool frame (relative, as the base), with the
//! moves and differences along it that the propagation, the tool accuracy and the refinement
//! take their finite differences with.

use crate::robot::{CouplingFunction, RobotModel, Transmission};
use nalgebra::{DMatrix, Isometry3, Translation3, UnitQuaternion, Vector3, Vector6};
use serde::{Deserialize, Serialize};

/// The covariance of the calibrated model's parameter vector ([`model_parameter_names`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ModelCovariance {
    /// Parameter names with their unit, in vector order.
    pub names: Vec<String>,
    /// The covariance, row by row (units of the names, squared).
    pub covariance: Vec<Vec<f64>>,
}

impl ModelCovariance {
    /// From a matrix in the order of `names`.
    pub fn new(names: Vec<String>, c: &DMatrix<f64>) -> Self {
        ModelCovariance {
            names,
            covariance: c.row_iter().map(|r| r.iter().copied().collect()).collect(),
        }
    }

    /// As a matrix.
    pub fn matrix(&self) -> DMatrix<f64> {
        let n = self.covariance.len();
        DMatrix::from_fn(n, n, |r, c| self.covariance[r][c])
    }
}

/// How a scalar of the model is stored.
#[derive(Clone, Copy)]
enum Stored {
    /// In the vector's unit (m, rad or dimensionless).
    Si,
    /// In degrees (the vector holds radians).
    Deg,
}

/// A visitor of the model's scalars: `(name, made only when called; value; how stored)`.
type ScalarVisitor<'a> = dyn FnMut(&dyn Fn() -> String, &mut f64, Stored) + 'a;

/// Calls `f(name, value, how stored)` (the name made only when asked) on every scalar of
/// `robot` the vector holds between the two placements, in vector order.
fn visit_scalars(robot: &mut RobotModel, f: &mut ScalarVisitor<'_>) {
    for (i, r) in robot.rows.iter_mut().enumerate() {
        let row = i + 1;
        f(&|| format!("row {row} a [m]"), &mut r.a_m, Stored::Si);
        f(&|| format!("row {row} b [m]"), &mut r.b_m, Stored::Si);
        f(&|| format!("row {row} alpha [rad]"), &mut r.alpha_deg, Stored::Deg);
        f(&|| format!("row {row} beta [rad]"), &mut r.beta_deg, Stored::Deg);
        f(&|| format!("row {row} gamma [rad]"), &mut r.gamma_deg, Stored::Deg);
        f(&|| format!("row {row} h [m]"), &mut r.h_m, Stored::Si);
    }
    for (i, j) in robot.joints.iter_mut().enumerate() {
        let joint = i + 1;
        f(&|| format!("joint {joint} phi [rad]"), &mut j.phi_deg, Stored::Deg);
        f(
            &|| format!("joint {joint} zero offset [rad or m]"),
            &mut j.transducer_offset,
            Stored::Si,
        );
        match &mut j.transmission {
            Transmission::Harmonic { sin, cos } | Transmission::Gear { sin, cos, .. } => {
                visit_harmonics(f, &|| format!("joint {joint} transmission"), sin, cos);
            }
            Transmission::Polynomial { c, .. } => {
                for (k, v) in c.iter_mut().enumerate() {
                    f(&|| format!("joint {joint} transmission c{}", k + 1), v, Stored::Si);
                }
            }
        }
        let from = || format!("coupling {}->{joint}", joint - 1);
        match &mut j.coupling_in {
            Some(CouplingFunction::Gear { ratio, sin, cos }) => {
                f(&|| format!("{} ratio", from()), ratio, Stored::Si);
                visit_harmonics(f, &from, sin, cos);
            }
            Some(CouplingFunction::Fractional { num, den }) => {
                for (k, v) in num.iter_mut().enumerate() {
                    f(&|| format!("{} n{k}", from()), v, Stored::Si);
                }
                for (k, v) in den.iter_mut().enumerate() {
                    f(&|| format!("{} d{k}", from()), v, Stored::Si);
                }
            }
            Some(CouplingFunction::FourBar(_)) | None => {}
        }
    }
}

/// Calls `f` on harmonic coefficients `sin..` then `cos..` \[rad\].
fn visit_harmonics(f: &mut ScalarVisitor<'_>, prefix: &dyn Fn() -> String, sin: &mut [f64], cos: &mut [f64]) {
    for (k, s) in sin.iter_mut().enumerate() {
        f(&|| format!("{} sin{} [rad]", prefix(), k + 1), s, Stored::Si);
    }
    for (k, c) in cos.iter_mut().enumerate() {
        f(&|| format!("{} cos{} [rad]", prefix(), k + 1), c, Stored::Si);
    }
}

/// Names of the six components of a placement.
fn placement_names(what: &str) -> [String; 6] {
    ["x [m]", "y [m]", "z [m]", "rx [rad]", "ry [rad]", "rz [rad]"].map(|c| format!("{what} {c}"))
}

/// The names (with units) of `robot`'s parameter vector: base placement, scalars, tool frame.
pub fn model_parameter_names(robot: &RobotModel) -> Vec<String> {
    let mut names: Vec<String> = placement_names("base").into();
    visit_scalars(&mut robot.clone(), &mut |name, _, _| names.push(name()));
    names.extend(placement_names("tool"));
    names
}

/// The values of `robot`'s parameter vector ([`model_parameter_names`] order, the vector's
/// units): 0 for the base and tool placements (the vector holds them relative to the model's
/// own), the scalars as they are.
pub fn model_parameter_values(robot: &RobotModel) -> Vec<f64> {
    let mut values = vec![0.0; 6];
    values.extend(ModelOrigin::new(robot).values);
    values.extend([0.0; 6]);
    values
}

/// `b^-1 a` as translation and rotation vector.
fn relative(a: &Isometry3<f64>, b: &Isometry3<f64>) -> Vector6<f64> {
    let rel = b.inverse() * a;
    let (t, r) = (rel.translation.vector, rel.rotation.scaled_axis());
    Vector6::new(t.x, t.y, t.z, r.x, r.y, r.z)
}

/// `(p(a) - p(b)) / step` for two models of the same structure, the placements relative to
/// `b`'s.
pub fn model_difference(a: &RobotModel, b: &RobotModel, step: f64) -> Vec<f64> {
    ModelOrigin::new(b).difference(&mut a.clone(), step)
}

/// A model `b` as the origin of [`model_difference`]s, its parameters read once for many
/// differences.
#[derive(Clone, Debug)]
pub struct ModelOrigin {
    placement: Isometry3<f64>,
    tool: Isometry3<f64>,
    values: Vec<f64>,
}

impl ModelOrigin {
    /// The origin at `b`.
    pub fn new(b: &RobotModel) -> Self {
        let mut values = Vec::new();
        visit_scalars(&mut b.clone(), &mut |_, v, stored| values.push(in_vector(*v, stored)));
        ModelOrigin {
            placement: b.placement.to_isometry(),
            tool: b.tool_frame.to_isometry(),
            values,
        }
    }

    /// [`model_difference`]`(a, b, step)`; `a` is read, not changed (the visitor of its
    /// scalars is the one [`model_moved`] writes through).
    pub fn difference(&self, a: &mut RobotModel, step: f64) -> Vec<f64> {
        let mut out: Vec<f64> = Vec::with_capacity(self.values.len() + 12);
        out.extend(relative(&a.placement.to_isometry(), &self.placement).iter());
        let mut i = 0;
        visit_scalars(a, &mut |_, v, stored| {
            out.push(in_vector(*v, stored) - self.values[i]);
            i += 1;
        });
        out.extend(relative(&a.tool_frame.to_isometry(), &self.tool).iter());
        out.iter_mut().for_each(|x| *x /= step);
        out
    }
}

fn in_vector(v: f64, stored: Stored) -> f64 {
    match stored {
        Stored::Si => v,
        Stored::Deg => v.to_radians(),
    }
}

/// `iso exp(d)`: component `k` of a placement's relative perturbation set to `h`.
fn moved_placement(iso: &Isometry3<f64>, k: usize, h: f64) -> crate::robot::Placement {
    let delta = if k < 3 {
        Isometry3::from_parts(Translation3::from(Vector3::ith(k, h)), UnitQuaternion::identity())
    } else {
        Isometry3::rotation(Vector3::ith(k - 3, h))
    };
    crate::robot::Placement::from_isometry(&(iso * delta))
}

/// `robot` with parameter `k` of its vector moved by `h` (in the vector's unit).
pub fn model_moved(robot: &RobotModel, k: usize, h: f64) -> RobotModel {
    let mut out = robot.clone();
    if k < 6 {
        out.placement = moved_placement(&robot.placement.to_isometry(), k, h);
        return out;
    }
    let mut i = 6;
    visit_scalars(&mut out, &mut |_, v, stored| {
        if i == k {
            *v += match stored {
                Stored::Si => h,
                Stored::Deg => h.to_degrees(),
            };
        }
        i += 1;
    });
    if k >= i {
        out.tool_frame = moved_placement(&robot.tool_frame.to_isometry(), k - i, h);
    }
    out
}

/// `robot` with its whole parameter vector moved by `delta` (in the vector's units, length
/// [`model_parameter_names`]`(robot).len()`): the base and tool placements by `exp(d)` on the
/// right (as [`ModelOrigin::difference`] measures them), every scalar by its component. The
/// robot a calibration with parameter error `delta` was made on.
pub fn model_displaced(robot: &RobotModel, delta: &[f64]) -> RobotModel {
    let displaced = |iso: &Isometry3<f64>, d: &[f64]| {
        let rel = Isometry3::from_parts(
            Translation3::new(d[0], d[1], d[2]),
            UnitQuaternion::from_scaled_axis(Vector3::new(d[3], d[4], d[5])),
        );
        crate::robot::Placement::from_isometry(&(iso * rel))
    };
    let mut out = robot.clone();
    out.placement = displaced(&robot.placement.to_isometry(), &delta[..6]);
    let mut i = 6;
    visit_scalars(&mut out, &mut |_, v, stored| {
        *v += match stored {
            Stored::Si => delta[i],
            Stored::Deg => delta[i].to_degrees(),
        };
        i += 1;
    });
    out.tool_frame = displaced(&robot.tool_frame.to_isometry(), &delta[i..i + 6]);
    out
}
