//! The actual phi-model from joint axes observed at a common reference pose (paper section 4),
//! for any joint mix and any subset of observed axes.
//!
//! **Base frame** ([`BaseRule`], stated in the report): the calibrated base frame is the
//! nominal one (the description's `placement`) moved rigidly onto the observed axes, fixed
//! step by step:
//!
//! 1. *Section 4* (axes 1 and 2 observed, both rotary, skew or intersecting): Z on axis 1; the
//!    common normal from axis 1 to axis 2 gives the Y direction (the nominal model's angle of
//!    it in link 1 carried over) and, where it meets axis 1, the origin (the nominal offset
//!    along axis 1 carried over) ("A robot base coordinate system ... has been established
//!    with its Z-axis directed along the calibrated axis of the first joint. The common
//!    normal directed from the axis of the first joint to the second joint-axis coincides with
//!    the Y-axis of the base system."). Every degree of freedom is observed.
//!    Which axes are parallel is decided on the nominal model (the design): observed axes of a
//!    parallel pair are never exactly parallel, and their small tilt must fix nothing.
//! 2. Otherwise (axis 1 slides, axes 1 and 2 parallel, or axis 1 or 2 not swept), the rigid
//!    motion is fixed in order: the first observed axis turns the nominal one onto its
//!    direction (smallest rotation) and, if rotary, moves it onto its line; the first later
//!    observed axis not parallel to it fixes the rotation about it (the component of its
//!    direction across the first), else a parallel rotary one at a distance (the direction of
//!    the perpendicular between them); the first later rotary axis not parallel fixes the
//!    position along it (common-normal feet; for a sliding first axis, the first two rotary
//!    axes fix the position). Whatever no observed axis fixes keeps the nominal placement;
//!    the rule names those degrees of freedom. The position along parallel axes (a SCARA's
//!    height) is then fixed by a tool target seen at the reference pose when the tool frame is
//!    not measured ([`BaseRule::with_along_fixed`], `procedure/height.rs`).
//!
//! **Rows**, joint by joint: the `phi_i` frame at the reference displacement (eq. A2) and the
//! row `(a, b, alpha, beta)` that puts `Z_{i+1}` on the observed axis `i+1` in DH fashion
//! (eq. A3, [`row_to_line`]). A sliding axis has only a direction (eq. 9): its row takes
//! `alpha`, `beta` from the observed direction and keeps the nominal `a`, `b` (the line's
//! position, a convention). An axis not swept keeps its nominal row (its place on the link
//! below).

use crate::kinematics::{AxisLine, JointKind, PhiModel, PhiRow, frame_from_phi, row_to_line};
use nalgebra::{Isometry3, Point3, Rotation3, Translation3, Unit, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// Why the axes do not define a phi-model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FramesError {
    /// Wrong number of axes or reference values.
    #[error("{axes} axes and {reference} reference values given for a {dof}-joint model")]
    Count {
        /// Axes given.
        axes: usize,
        /// Reference values given.
        reference: usize,
        /// Joints of the model.
        dof: usize,
    },
    /// Z_phi of joint `joint` is parallel to the next axis, so the row is singular; a
    /// different phi angle is needed (appendix: phi is chosen to avoid this).
    #[error("joint {joint}: Z_phi is parallel to axis {next} (angle {angle_rad:.3e} rad); choose another phi angle")]
    PhiParallel {
        /// The joint (1-based).
        joint: usize,
        /// The next joint.
        next: usize,
        /// The angle between Z_phi and the next axis.
        angle_rad: f64,
    },
}

/// Which rule placed the calibrated base frame (module docs), and what it leaves nominal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BaseRule {
    /// `section4` or `sequential`.
    pub rule: String,
    /// The observed axes (1-based) that fixed it.
    pub anchors: Vec<usize>,
    /// Degrees of freedom no observed axis fixes (kept from the description's placement).
    pub unobserved: Vec<String>,
    /// The rule in words.
    pub text: String,
}

/// How [`BaseRule::unobserved`] names the position along an axis that no observed axis fixes
/// (every rotary axis parallel to it), followed by the axis (1-based).
const ALONG_AXIS: &str = "position along axis ";

impl BaseRule {
    /// The axis (0-based) along which the rule kept the description's position (every observed
    /// rotary axis parallel to it: a SCARA's height), if any.
    pub fn unobserved_along(&self) -> Option<usize> {
        self.unobserved
            .iter()
            .find_map(|u| u.strip_prefix(ALONG_AXIS)?.parse::<usize>().ok())
            .and_then(|a| a.checked_sub(1))
    }

    /// The rule with the position along axis `axis` (0-based) fixed by `how` instead of kept
    /// from the description's placement.
    pub fn with_along_fixed(mut self, axis: usize, how: &str) -> BaseRule {
        let name = format!("{ALONG_AXIS}{}", axis + 1);
        self.unobserved.retain(|u| *u != name);
        let kept = "; kept from the description's placement: ";
        if let Some(at) = self.text.find(kept) {
            self.text.truncate(at);
            self.text.push(')');
        }
        if !self.unobserved.is_empty() {
            self.text.pop();
            self.text.push_str(&format!("{kept}{})", self.unobserved.join(", ")));
        }
        self.text.push_str(&format!("; {name}: {how}"));
        self
    }
}

/// The closest points of two lines: `(on a, on b)`, or `None` when they are parallel.
pub fn common_normal_feet(a: &AxisLine, b: &AxisLine) -> Option<(Point3<f64>, Point3<f64>)> {
    let (da, db) = (a.direction.into_inner(), b.direction.into_inner());
    let w = a.origin_m - b.origin_m;
    let (aa, ab, bb) = (1.0, da.dot(&db), 1.0);
    let (d, e) = (da.dot(&w), db.dot(&w));
    let den = aa * bb - ab * ab;
    if den < 1e-14 {
        return None;
    }
    let s = (ab * e - bb * d) / den;
    let t = (aa * e - ab * d) / den;
    Some((a.origin_m + da * s, b.origin_m + db * t))
}

/// Directions closer than this to parallel \[sin of the angle\] count as parallel for the base
/// rule: the common normal's foot would move by more than 1e7 times the axes' distance.
const PARALLEL_SIN: f64 = 1e-7;

fn parallel(a: &Vector3<f64>, b: &Vector3<f64>) -> bool {
    a.cross(b).norm() < PARALLEL_SIN
}

/// The rigid motion of the world turning `line`'s point by `rot` about `about`.
fn turn_about(rot: UnitQuaternion<f64>, about: &Point3<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(Translation3::from(about.coords), rot) * Isometry3::translation(-about.x, -about.y, -about.z)
}

/// The rigid motion `T` (world to world) that moves the nominal model's axes at the reference
/// (`nominal`) onto the observed ones (`observed`, `None` = not swept), by the rules of the
/// module docs, with the rule used.
fn base_motion(kinds: &[JointKind], nominal: &[AxisLine], observed: &[Option<AxisLine>]) -> (Isometry3<f64>, BaseRule) {
    let seen: Vec<usize> = (0..observed.len()).filter(|&k| observed[k].is_some()).collect();
    let Some(&f) = seen.first() else {
        return (
            Isometry3::identity(),
            BaseRule {
                rule: "nominal".into(),
                anchors: vec![],
                unobserved: vec!["all".into()],
                text: "no axis observed: the nominal placement".into(),
            },
        );
    };
    let mut motion = BaseMotion {
        kinds,
        nominal,
        observed,
        seen,
        t: Isometry3::identity(),
        anchors: vec![f + 1],
        unobserved: vec![],
    };
    motion.align_first(f);
    motion.turn_about_first(f);
    if motion.rotary(f) {
        motion.place_along(f);
    } else {
        motion.place_sliding_first();
    }
    motion.into_rule()
}

/// The sequential base rule's state: the motion so far, the axes it rests on and what it
/// could not fix.
struct BaseMotion<'a> {
    kinds: &'a [JointKind],
    nominal: &'a [AxisLine],
    observed: &'a [Option<AxisLine>],
    /// The observed joints (0-based), in order.
    seen: Vec<usize>,
    /// The motion so far.
    t: Isometry3<f64>,
    /// The axes (1-based) the motion rests on.
    anchors: Vec<usize>,
    /// What stays at the description's placement.
    unobserved: Vec<String>,
}

impl BaseMotion<'_> {
    fn line(&self, k: usize) -> AxisLine {
        self.observed[k].expect("observed")
    }

    fn rotary(&self, k: usize) -> bool {
        self.kinds[k] == JointKind::Revolute
    }

    /// Which axes are parallel is the design's business: nearly parallel observed axes (a
    /// parallel pair measured with noise) must not fix anything by their tiny tilt.
    fn design_parallel(&self, a: usize, b: usize) -> bool {
        parallel(&self.nominal[a].direction, &self.nominal[b].direction)
    }

    /// Moves the motion by the translation `v`.
    fn translate(&mut self, v: Vector3<f64>) {
        self.t = Isometry3::translation(v.x, v.y, v.z) * self.t;
    }

    /// Step 1: direction (and line, for a rotary axis) of the first observed axis `f`.
    fn align_first(&mut self, f: usize) {
        let (nf, of) = (self.nominal[f], self.line(f));
        let r1 =
            UnitQuaternion::rotation_between(&nf.direction, &of.direction).unwrap_or_else(UnitQuaternion::identity);
        self.t = turn_about(r1, &nf.origin_m);
        if self.rotary(f) {
            let w = of.origin_m - self.t * nf.origin_m;
            self.translate(w - of.direction.into_inner() * w.dot(&of.direction));
        } else {
            self.unobserved
                .push(format!("position across axis {} (sliding)", f + 1));
        }
    }

    /// Step 2: rotation about the first observed axis `f`: from the direction of the next axis not
    /// parallel to it by design, else from the offset of the next rotary axis.
    fn turn_about_first(&mut self, f: usize) {
        let of = self.line(f);
        let z = of.direction.into_inner();
        let pivot = self.t * self.nominal[f].origin_m;
        let across = |v: Vector3<f64>| v - z * v.dot(&z);
        let signed_angle = |a: Vector3<f64>, b: Vector3<f64>| a.cross(&b).dot(&z).atan2(a.dot(&b));
        let later: Vec<usize> = self.seen.iter().skip(1).copied().collect();
        let by_direction = later.iter().copied().find(|&k| !self.design_parallel(f, k));
        let by_offset = || {
            later.iter().copied().find(|&k| {
                self.rotary(f) && self.rotary(k) && across(self.line(k).origin_m - of.origin_m).norm() > 1e-9
            })
        };
        let angle = if let Some(k) = by_direction {
            self.anchors.push(k + 1);
            let a = across(self.t * self.nominal[k].direction.into_inner());
            Some(signed_angle(a, across(self.line(k).direction.into_inner())))
        } else if let Some(k) = by_offset() {
            self.anchors.push(k + 1);
            let a = across(self.t * self.nominal[k].origin_m - pivot);
            Some(signed_angle(a, across(self.line(k).origin_m - of.origin_m)))
        } else {
            self.unobserved.push(format!("rotation about axis {}", f + 1));
            None
        };
        if let Some(a) = angle {
            self.t = turn_about(UnitQuaternion::from_axis_angle(&of.direction, a), &pivot) * self.t;
        }
    }

    /// The shift along observed axis `a` that puts the common normal of the moved nominal axes
    /// `a`, `b` where the observed one is.
    fn shift_along(&self, a: usize, b: usize) -> Option<Vector3<f64>> {
        let moved = |k: usize| AxisLine {
            origin_m: self.t * self.nominal[k].origin_m,
            direction: Unit::new_normalize(self.t * self.nominal[k].direction.into_inner()),
        };
        let (fo, _) = common_normal_feet(&self.line(a), &self.line(b))?;
        let (fn_, _) = common_normal_feet(&moved(a), &moved(b))?;
        let d = self.line(a).direction.into_inner();
        Some(d * (fo - fn_).dot(&d))
    }

    /// Step 3: position along the rotary axis `a` from its common normal with the next observed
    /// rotary axis not parallel to it by design.
    fn place_along(&mut self, a: usize) {
        let partner = self
            .seen
            .iter()
            .copied()
            .find(|&k| self.rotary(k) && k != a && !self.design_parallel(a, k));
        match partner {
            Some(k) => {
                self.anchors.push(k + 1);
                if let Some(s) = self.shift_along(a, k) {
                    self.translate(s);
                }
            }
            None => self.unobserved.push(format!("{ALONG_AXIS}{}", a + 1)),
        }
    }

    /// Step 3 for a sliding first axis: the position across the first observed rotary axis `a` from
    /// its line, along it from its common normal with the next one.
    fn place_sliding_first(&mut self) {
        let Some(a) = self.seen.iter().copied().find(|&k| self.rotary(k)) else {
            self.unobserved.push("position (no rotary axis observed)".into());
            return;
        };
        self.anchors.push(a + 1);
        let oa = self.line(a);
        let w = oa.origin_m - self.t * self.nominal[a].origin_m;
        self.translate(w - oa.direction.into_inner() * w.dot(&oa.direction));
        self.place_along(a);
    }

    /// The motion with the rule's record.
    fn into_rule(mut self) -> (Isometry3<f64>, BaseRule) {
        self.anchors.sort_unstable();
        self.anchors.dedup();
        let text = format!(
            "the nominal base frame moved rigidly onto the observed axes {} (sequential rule{})",
            self.anchors
                .iter()
                .map(|a| a.to_string())
                .collect::<Vec<_>>()
                .join(", "),
            if self.unobserved.is_empty() {
                String::new()
            } else {
                format!(
                    "; kept from the description's placement: {}",
                    self.unobserved.join(", ")
                )
            }
        );
        (
            self.t,
            BaseRule {
                rule: "sequential".into(),
                anchors: self.anchors,
                unobserved: self.unobserved,
                text,
            },
        )
    }
}

/// The base convention of a nominal model, carried over to the calibrated one: the direction
/// of `z1 x z2` as an angle in link 1's XY plane, and the signed distance along axis 1 from
/// the common-normal foot to frame 1's origin (both 0 for the IRB/L6); `None` with one joint.
fn base_convention(nominal: &PhiModel) -> Option<(f64, f64)> {
    if nominal.dof() < 2 {
        return None;
    }
    let poses = nominal.poses(&vec![0.0; nominal.dof()]);
    let (a1, a2) = (poses.axis(0), poses.axis(1));
    let link1 = poses.world_from_link[0];
    let n = link1.inverse_transform_vector(&a1.direction.cross(&a2.direction));
    let (foot, _) = common_normal_feet(&a1, &a2)?;
    Some((n.y.atan2(n.x), (a1.origin_m - foot).dot(&a1.direction)))
}

/// Section 4's base frame (module docs): link 1 at the reference, from observed axes 1 and 2,
/// with the nominal base convention `(psi, d)` ([`base_convention`]).
fn section4_link1((psi, d): (f64, f64), a1: &AxisLine, a2: &AxisLine) -> Option<Isometry3<f64>> {
    let (foot, _) = common_normal_feet(a1, a2)?;
    let z1 = a1.direction.into_inner();
    let normal = Unit::new_normalize(z1.cross(&a2.direction));
    // Link 1 at the reference: the common-normal direction sits at angle psi in its XY plane.
    let x1 = Rotation3::from_axis_angle(&a1.direction, -psi) * normal.into_inner();
    let y1 = z1.cross(&x1);
    let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_basis_unchecked(&[x1, y1, z1]));
    Some(Isometry3::from_parts(Translation3::from(foot.coords + z1 * d), rot))
}

/// The calibrated base frame (frame 1 in the world) and the rule used.
fn base_frame(nominal: &NominalGeometry, axes: &[Option<AxisLine>]) -> (Isometry3<f64>, BaseRule) {
    let (model, q_ref, nominal_axes) = (&nominal.model, &nominal.q_ref, &nominal.axes);
    let kinds: Vec<JointKind> = model.joints.iter().map(|j| j.kind).collect();
    let motion = |q| crate::kinematics::joint_motion(kinds[0], q);
    if kinds.len() > 1
        && kinds[0] == JointKind::Revolute
        && kinds[1] == JointKind::Revolute
        && let (Some(a1), Some(a2)) = (axes[0], axes[1])
        && !parallel(&nominal_axes[0].direction, &nominal_axes[1].direction)
        && let Some(convention) = nominal.convention
        && let Some(link1) = section4_link1(convention, &a1, &a2)
    {
        let rule = BaseRule {
            rule: "section4".into(),
            anchors: vec![1, 2],
            unobserved: vec![],
            text:
                "section 4: Z on axis 1, Y along the common normal from axis 1 to axis 2, origin where it meets axis 1"
                    .into(),
        };
        return (link1 * motion(q_ref[0]).inverse(), rule);
    }
    let (t, rule) = base_motion(&kinds, nominal_axes, axes);
    (t * model.world_from_base, rule)
}

/// What [`model_from_axes`] takes from the nominal model, computed once for the many models of
/// one calibration (its propagation rebuilds the model for every perturbed axis): the nominal
/// model, the reference joint values, the nominal axes there and the base convention.
#[derive(Clone, Debug)]
pub struct NominalGeometry {
    model: PhiModel,
    q_ref: Vec<f64>,
    axes: Vec<AxisLine>,
    convention: Option<(f64, f64)>,
}

impl NominalGeometry {
    /// The nominal `model` at joint values `q_ref` (an error if their counts differ).
    pub fn new(model: PhiModel, q_ref: &[f64]) -> Result<Self, FramesError> {
        let n = model.dof();
        if q_ref.len() != n {
            return Err(FramesError::Count {
                axes: n,
                reference: q_ref.len(),
                dof: n,
            });
        }
        let poses = model.poses(q_ref);
        let axes = (0..n).map(|k| poses.axis(k)).collect();
        let convention = base_convention(&model);
        Ok(NominalGeometry {
            model,
            q_ref: q_ref.to_vec(),
            axes,
            convention,
        })
    }

    /// [`model_from_axes`] of this nominal model and reference.
    pub fn model_from_axes(&self, axes: &[Option<AxisLine>]) -> Result<(PhiModel, BaseRule), FramesError> {
        let (nominal, q_ref) = (&self.model, &self.q_ref[..]);
        let n = nominal.dof();
        if axes.len() != n {
            return Err(FramesError::Count {
                axes: axes.len(),
                reference: q_ref.len(),
                dof: n,
            });
        }
        let mut model = nominal.clone();
        let (world_from_base, rule) = base_frame(self, axes);
        model.world_from_base = world_from_base;
        let mut world_from_frame = model.world_from_base;
        for k in 0..n - 1 {
            let j = nominal.joints[k];
            let (theta, dist) = match j.kind {
                JointKind::Revolute => (q_ref[k], 0.0),
                JointKind::Prismatic => (0.0, q_ref[k]),
            };
            let world_from_phi = world_from_frame * frame_from_phi(j.phi_rad, theta, dist);
            if let Some(next) = &axes[k + 1] {
                let mut local = AxisLine {
                    origin_m: world_from_phi.inverse_transform_point(&next.origin_m),
                    direction: Unit::new_normalize(world_from_phi.inverse_transform_vector(&next.direction)),
                };
                let nominal_row = nominal.rows[k];
                if nominal.joints[k + 1].kind == JointKind::Prismatic {
                    // Only the direction is observed: any line; the nominal frame origin's.
                    local.origin_m = nominal_row.phi_from_next() * Point3::origin();
                }
                let row = row_to_line(&local, nominal_row.beta_rad).ok_or(FramesError::PhiParallel {
                    joint: k + 1,
                    next: k + 2,
                    angle_rad: local
                        .direction
                        .z
                        .abs()
                        .acos()
                        .min(std::f64::consts::PI - local.direction.z.abs().acos()),
                })?;
                model.rows[k] = if nominal.joints[k + 1].kind == JointKind::Prismatic {
                    // Only the direction is observed (eq. 9): `a`, `b` (and `gamma`, `h`) stay
                    // nominal; the direction `Rot(z, beta) Rot(x, alpha) z` is the observed one.
                    PhiRow {
                        alpha_rad: row.alpha_rad,
                        beta_rad: row.beta_rad,
                        ..nominal_row
                    }
                } else {
                    row
                };
            }
            world_from_frame = world_from_phi * model.rows[k].phi_from_next();
        }
        Ok((model, rule))
    }
}

/// The actual phi-model whose axes, at joint values `q_ref`, are the observed `axes` (world
/// frame; `None` for an axis not swept; a sliding axis's origin is ignored), with the nominal
/// model's joint kinds, phi angles, base convention and tool (module docs).
///
/// The calibrated joint values at the reference pose are `q_ref` by definition: the constant
/// difference from the robot's own zero goes into the transducer offsets.
pub fn model_from_axes(
    nominal: &PhiModel,
    axes: &[Option<AxisLine>],
    q_ref: &[f64],
) -> Result<(PhiModel, BaseRule), FramesError> {
    let n = nominal.dof();
    if axes.len() != n || q_ref.len() != n {
        return Err(FramesError::Count {
            axes: axes.len(),
            reference: q_ref.len(),
            dof: n,
        });
    }
    NominalGeometry::new(nominal.clone(), q_ref)?.model_from_axes(axes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::RobotDescription;
    use approx::assert_relative_eq;

    fn some(v: Vec<AxisLine>) -> Vec<Option<AxisLine>> {
        v.into_iter().map(Some).collect()
    }

    fn axes_of(model: &PhiModel, q: &[f64]) -> Vec<AxisLine> {
        let p = model.poses(q);
        (0..model.dof()).map(|k| p.axis(k)).collect()
    }

    #[test]
    fn nominal_rows_are_recovered_exactly() {
        let nominal = RobotDescription::asea_irb6l().nominal_model();
        let q_ref = [0.0; 6];
        let m = model_from_axes(&nominal, &some(axes_of(&nominal, &q_ref)), &q_ref)
            .unwrap()
            .0;
        for (a, b) in m.rows.iter().zip(&nominal.rows) {
            assert_relative_eq!(a.a_m, b.a_m, epsilon = 1e-12);
            assert_relative_eq!(a.b_m, b.b_m, epsilon = 1e-12);
            assert_relative_eq!(a.alpha_rad, b.alpha_rad, epsilon = 1e-12);
            assert_relative_eq!(a.beta_rad, b.beta_rad, epsilon = 1e-12);
        }
        assert_relative_eq!(
            m.world_from_base.to_homogeneous(),
            nominal.world_from_base.to_homogeneous(),
            epsilon = 1e-12
        );
    }

    /// The paper robot's axes rebuild a model with the same axes at the reference and the
    /// same link motion up to a constant zero shift per joint.
    #[test]
    fn paper_robot_axes_rebuild_an_equivalent_model() {
        let nominal = RobotDescription::asea_irb6l().nominal_model();
        let actual = crate::sim::paper_robot().phi_model();
        let q_ref = [0.1, -0.2, 0.15, 0.3, -0.25, 0.4];
        let m = model_from_axes(&nominal, &some(axes_of(&actual, &q_ref)), &q_ref)
            .unwrap()
            .0;
        let (am, aa) = (axes_of(&m, &q_ref), axes_of(&actual, &q_ref));
        for (x, y) in am.iter().zip(&aa) {
            assert_relative_eq!(*x.direction, *y.direction, epsilon = 1e-12);
            // Same line: the offset between origins is along the direction.
            assert!((x.origin_m - y.origin_m).cross(&y.direction).norm() < 1e-12);
        }
        // Table 2 form: within millimetres and tenths of a degree of Table 2's actual rows
        // (the joint zeros differ by convention).
        for (r, t) in m.rows.iter().zip(&actual.rows) {
            assert!(
                (r.a_m - t.a_m).abs() < 0.01 && (r.b_m - t.b_m).abs() < 0.01,
                "{r:?} vs {t:?}"
            );
            assert!(
                (r.alpha_rad - t.alpha_rad).abs() < 0.01 && (r.beta_rad - t.beta_rad).abs() < 0.02,
                "{r:?} vs {t:?}"
            );
        }
    }

    /// Parallel axes 1 and 2: the sequential rule fixes all but the position along axis 1,
    /// which stays nominal, and the model has the observed axes.
    #[test]
    fn parallel_base_axes_use_the_sequential_rule() {
        use crate::kinematics::{DhConvention, DhParams, SourceChain, phi_model_of};
        let dh = |d: f64, a: f64, alpha_deg: f64| DhParams {
            d_m: d,
            theta_rad: 0.0,
            a_m: a,
            alpha_rad: alpha_deg.to_radians(),
        };
        let scara = SourceChain::Dh {
            convention: DhConvention::Classic,
            kinds: vec![
                JointKind::Revolute,
                JointKind::Revolute,
                JointKind::Prismatic,
                JointKind::Revolute,
            ],
            rows: vec![
                dh(0.4, 0.35, 0.0),
                dh(0.0, 0.3, 180.0),
                dh(0.0, 0.0, 0.0),
                dh(0.1, 0.0, 0.0),
            ],
            flange_from_tool: Isometry3::identity(),
        };
        let nominal = phi_model_of(&scara, &Isometry3::translation(1.0, 2.0, 0.0)).unwrap();
        let q = [0.1, -0.2, 0.05, 0.3];
        // The observed robot: turned by 2 mrad about a horizontal axis, 3 mm away, and its
        // second axis 1 mm further out.
        let actual = {
            let mut m = nominal.clone();
            m.world_from_base = Isometry3::new(
                nalgebra::Vector3::new(0.003, 0.0, 0.001),
                nalgebra::Vector3::new(0.002, 0.0, 0.0),
            ) * m.world_from_base;
            m.rows[0].a_m += 0.001;
            m
        };
        let mut axes: Vec<Option<AxisLine>> = some(axes_of(&actual, &q));
        // The sliding axis's line is not observed: any point on another line.
        if let Some(a) = &mut axes[2] {
            a.origin_m += nalgebra::Vector3::new(0.05, 0.02, 0.0);
        }
        let (m, rule) = model_from_axes(&nominal, &axes, &q).unwrap();
        let axes: Vec<AxisLine> = axes_of(&actual, &q);
        assert_eq!(rule.rule, "sequential");
        assert!(rule.unobserved.iter().any(|u| u.contains("along axis 1")), "{rule:?}");
        let got = axes_of(&m, &q);
        for (k, (x, y)) in got.iter().zip(&axes).enumerate() {
            assert!((x.direction.into_inner() - y.direction.into_inner()).norm() < 1e-9);
            if k != 2 {
                assert!(
                    (x.origin_m - y.origin_m).cross(&y.direction).norm() < 1e-9,
                    "axis {}",
                    k + 1
                );
            }
        }
    }
}
