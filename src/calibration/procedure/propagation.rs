//! Uncertainty of what the procedure derives from the fitted axes: the passive couplings
//! (eqs. 14-15), the joint zero offsets and the tool frame. Each is a function of the axis
//! fits (axis line and transmission of every swept joint), of the second targets the
//! couplings are fitted from and of the tool targets; first-order propagation
//!
//! `C_out = sum_k J_k C_k J_k^T + sigma^2 J_t J_t^T`,
//!
//! `C_k` the covariance of fit `k`'s local parameters (the fits are independent, each from its
//! own sweep), `sigma` the measurement noise per coordinate and `J` by one-sided differences
//! of the whole assembly ([`super::Context::derived`]) from the unmoved one computed the same
//! way ([`Propagation::add`]), whose couplings are refitted by one
//! Newton step with the exact Hessian at the fitted optimum (`coupling_fit::CouplingResponse`). An arc fit's
//! covariance is carried to its axis line's four coordinates and its transmission's
//! coefficients first ([`add_axis_fit`]), so the assembly is differentiated along what it
//! depends on; a column that moves neither the axes nor a coupling's inputs reuses the
//! fitted frames and that coupling's refit (the same arithmetic, done once). The second
//! targets move the derived quantities only through their coupling's parameters `x`: their
//! term is `J_x C_x J_x^T`, `C_x` from the targets' noise through the passive angles'
//! analytic gradients and the fit's exact Hessian (`Context::second_target_sigma`) and `J_x` by
//! one-sided differences of the assembly with the coupling set to moved parameters; the tool targets
//! move only the tool frame. A coupling fit's own a-posteriori sigma
//! counts only the second target's noise: the active angles it is fitted against come from
//! the driving joint's fitted transmission and the frame it is measured in from the fitted
//! axes, whose errors are common to every point of the sweep and do not average out.
//!
//! The swept joint's repeatability turns each second target about the driving axis, one
//! independent angle per step. Not counted: the held joints' repeatability bias (as for the
//! rows), the joints' repeatability at the tool observation and, on campaigns whose held
//! joints needed correction passes, the dependence of the corrected points on the model.

use crate::calibration::arc_model::ArcParams;
use crate::calibration::line_ml::LineParams;
use crate::calibration::model_parameters::{ModelCovariance, ModelOrigin, model_parameter_names};
use crate::kinematics::AxisLine;
use crate::numerics::finite_diff::central_difference;
use crate::robot::TransmissionFitForm;
use crate::robot::{RobotModel, Transmission};
use nalgebra::{DMatrix, Isometry3, Point3, Unit, Vector3, Vector4};
use serde::{Deserialize, Serialize};

/// An ML axis fit's parameters at the optimum and their covariance, to rebuild the axis and
/// the transmission at perturbed parameters.
#[derive(Clone, Debug)]
pub(super) enum LocalFit {
    /// A rotary joint's arc fit ([`crate::calibration::fit_arc`]).
    Arc {
        /// Parameters at the optimum.
        params: ArcParams,
        /// The reference point the axis point is taken nearest to \[m\].
        reference: Point3<f64>,
        /// The transmission form.
        form: TransmissionFitForm,
        /// Covariance of the local parameters.
        covariance: DMatrix<f64>,
    },
    /// A sliding joint's line fit ([`crate::calibration::line_ml::fit_line`]).
    Line {
        /// Parameters at the optimum.
        params: LineParams,
        /// The transmission form.
        form: TransmissionFitForm,
        /// Covariance of the local parameters.
        covariance: DMatrix<f64>,
    },
}

impl LocalFit {
    /// Whether local parameter `i` moves the axis or the transmission at all: an arc's radius
    /// and phase (`arc_model`'s `delta[5]`, `delta[6]`) do not, so their Jacobian columns are
    /// exactly zero and need no evaluation.
    pub(super) fn moves_model(&self, i: usize) -> bool {
        !matches!(self, LocalFit::Arc { .. }) || !(i == 5 || i == 6)
    }

    /// Whether local parameter `i` moves the axis line (the geometric ones; the rest are the
    /// transmission's coefficients).
    pub(super) fn moves_axis(&self, i: usize) -> bool {
        match self {
            LocalFit::Arc { .. } => i < crate::calibration::arc_model::N_GEOMETRY,
            LocalFit::Line { .. } => i < crate::calibration::line_ml::N_GEOMETRY,
        }
    }

    /// Covariance of the local parameters.
    pub(super) fn covariance(&self) -> &DMatrix<f64> {
        match self {
            LocalFit::Arc { covariance, .. } | LocalFit::Line { covariance, .. } => covariance,
        }
    }

    /// The axis and the transmission (in the fit's own zero) at the parameters moved by the
    /// local perturbation `delta`, as the fit builds them at its optimum.
    pub(super) fn rebuilt(&self, delta: &[f64]) -> (AxisLine, Transmission) {
        match self {
            LocalFit::Arc {
                params,
                reference,
                form,
                ..
            } => {
                let p = params.perturbed(delta);
                let axis = AxisLine {
                    origin_m: p.axis_point_near(reference),
                    direction: p.normal(),
                };
                (axis, form.build(&p.coefficients))
            }
            LocalFit::Line { params, form, .. } => {
                let p = params.perturbed(delta);
                let axis = AxisLine {
                    origin_m: p.start,
                    direction: Unit::new_normalize(p.axis(2)),
                };
                (axis, form.build(&p.coefficients))
            }
        }
    }
}

/// Coordinates of lines near an axis line `(o, d)`: `[tilt_u, tilt_v, shift_u, shift_v]`, the
/// line through `o + shift_u u + shift_v v` along `d + tilt_u u + tilt_v v` (`u`, `v` across
/// `d`). A line's four degrees of freedom: what the assembly depends on, where an arc fit has
/// five geometric parameters (the centre's component along the axis only slides the line
/// along itself).
pub(super) struct LineCoordinates {
    axis: AxisLine,
    u: Vector3<f64>,
    v: Vector3<f64>,
}

impl LineCoordinates {
    /// Around `axis`.
    pub(super) fn new(axis: AxisLine) -> Self {
        let d = axis.direction.into_inner();
        let pick = if d.x.abs() < 0.6 { Vector3::x() } else { Vector3::y() };
        let u = d.cross(&pick).normalize();
        let v = d.cross(&u);
        LineCoordinates { axis, u, v }
    }

    /// The line at coordinates `q`.
    pub(super) fn line(&self, q: &[f64; 4]) -> AxisLine {
        let (o, d) = (self.axis.origin_m, self.axis.direction.into_inner());
        AxisLine {
            origin_m: o + self.u * q[2] + self.v * q[3],
            direction: Unit::new_normalize(d + self.u * q[0] + self.v * q[1]),
        }
    }

    /// The coordinates of `line` (not perpendicular to the axis): its direction scaled to a
    /// unit component along `d`, its point in the plane through `o` across `d`.
    pub(super) fn coordinates(&self, line: &AxisLine) -> [f64; 4] {
        let (o, d) = (self.axis.origin_m, self.axis.direction.into_inner());
        let along = line.direction.dot(&d);
        let t = line.direction.into_inner() / along;
        let p = line.origin_m + t * (o - line.origin_m).dot(&d);
        [
            t.dot(&self.u),
            t.dot(&self.v),
            (p - o).dot(&self.u),
            (p - o).dot(&self.v),
        ]
    }
}

/// Adds the propagation of one axis fit's covariance: `eval(axis, transmission)` is the
/// derived vector with the fit's axis and transmission moved (`None`: as fitted). An arc
/// fit's covariance is first carried to its axis line's coordinates ([`LineCoordinates`])
/// and transmission coefficients, `C_q = L C L^T` with `L` by central differences of the
/// rebuilt axis (steps `1e-3` of each sigma: no assembly is evaluated): four assembly columns
/// for the line instead of five for the arc's geometry, and none for its radius and phase.
/// A line fit's (sliding joint: the direction only) goes column by column.
pub(super) fn add_axis_fit<E>(
    prop: &mut Propagation,
    local: &LocalFit,
    axis: &AxisLine,
    base: &Derived,
    mut eval: impl FnMut(Option<AxisLine>, Option<Transmission>) -> Result<Derived, E>,
) -> Result<(), E> {
    let c = local.covariance();
    let n = c.nrows();
    let moved = |i: usize, h: f64| {
        let mut delta = vec![0.0; n];
        delta[i] = h;
        local.rebuilt(&delta)
    };
    if matches!(local, LocalFit::Line { .. }) {
        return prop.add_where(
            c,
            |i| local.moves_model(i),
            base,
            |i, h| {
                let (a, t) = moved(i, h);
                eval(local.moves_axis(i).then_some(a), Some(t))
            },
        );
    }
    let coordinates = LineCoordinates::new(*axis);
    let geometric = crate::calibration::arc_model::N_GEOMETRY;
    let m = n - geometric;
    let mut l = DMatrix::<f64>::zeros(4 + m, n);
    for j in (0..geometric).filter(|&j| local.moves_model(j) && c[(j, j)] > 0.0) {
        let h = 1e-3 * c[(j, j)].sqrt();
        let at = |t: f64| Vector4::from(coordinates.coordinates(&moved(j, t).0));
        let column: Vector4<f64> = central_difference(at, h);
        l.fixed_view_mut::<4, 1>(0, j).copy_from(&column);
    }
    for i in 0..m {
        l[(4 + i, geometric + i)] = 1.0;
    }
    let c_q = &l * c * l.transpose();
    prop.add(&c_q, base, |i, h| {
        if i < 4 {
            let mut q = [0.0; 4];
            q[i] = h;
            eval(Some(coordinates.line(&q)), None)
        } else {
            eval(None, Some(moved(geometric + i - 4, h).1))
        }
    })
}

/// The 1-sigma of a position and of an orientation, per axis of a frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct FrameSigma {
    /// Along x \[mm\].
    pub x_mm: f64,
    /// Along y \[mm\].
    pub y_mm: f64,
    /// Along z \[mm\].
    pub z_mm: f64,
    /// About x \[mrad\].
    pub rx_mrad: f64,
    /// About y \[mrad\].
    pub ry_mrad: f64,
    /// About z \[mrad\].
    pub rz_mrad: f64,
}

/// The 1-sigma of a joint's zero offset (`transducer_offset`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ZeroOffsetSigma {
    /// Joint (1-based).
    pub joint: usize,
    /// 1-sigma of a rotary joint's offset \[rad\] (null for a sliding joint).
    pub sigma_rad: Option<f64>,
    /// 1-sigma of a sliding joint's offset \[mm\] (null for a rotary joint).
    pub sigma_mm: Option<f64>,
}

/// The propagated 1-sigma of the derived quantities.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct DerivedSigma {
    /// Per fitted coupling (in the order of the couplings' reports): each parameter's 1-sigma.
    pub couplings: Vec<Vec<f64>>,
    /// Per joint (base first): the zero offset's 1-sigma (rad or m).
    pub zero_offsets: Vec<f64>,
    /// The tool frame's (in the tool frame), when measured.
    pub tool: Option<FrameSigma>,
}

/// The derived quantities as one vector (couplings' parameters, zero offsets, tool frame
/// translation \[m\] and rotation \[rad\]) with the layout to read it back.
#[derive(Clone, Debug)]
pub(super) struct Derived {
    /// Couplings' parameters, then zero offsets.
    pub(super) values: Vec<f64>,
    /// Number of parameters of each coupling.
    pub(super) coupling_sizes: Vec<usize>,
    /// The tool frame in the last link.
    pub(super) tool: Option<Isometry3<f64>>,
    /// The whole calibrated model, for its parameters' covariance
    /// ([`crate::calibration::tool_accuracy`]; the report path only).
    pub(super) robot: Option<RobotModel>,
}

/// A derived vector as the origin of differences, its model's parameters read once.
pub(super) struct Origin<'a> {
    derived: &'a Derived,
    model: Option<ModelOrigin>,
}

impl Derived {
    /// `self` as the origin of [`Derived::difference`]s.
    pub(super) fn origin(&self) -> Origin<'_> {
        Origin {
            derived: self,
            model: self.robot.as_ref().map(ModelOrigin::new),
        }
    }

    /// `(self - other) / step` as a column: the values, then the tool frame's translation
    /// and rotation vector, both in the tool frame of `other`, then the model's parameters
    /// ([`crate::calibration::model_parameters::model_difference`]).
    pub(super) fn difference(mut self, origin: &Origin, step: f64) -> Vec<f64> {
        let other = origin.derived;
        let mut d: Vec<f64> = Vec::with_capacity(self.values.len() + 6);
        d.extend(self.values.iter().zip(&other.values).map(|(a, b)| (a - b) / step));
        if let (Some(a), Some(b)) = (self.tool, other.tool) {
            let rel = b.inverse() * a;
            d.extend(rel.translation.vector.iter().map(|x| x / step));
            d.extend(rel.rotation.scaled_axis().iter().map(|x| x / step));
        }
        if let (Some(a), Some(b)) = (&mut self.robot, &origin.model) {
            d.extend(b.difference(a, step));
        }
        d
    }

    /// How many numbers [`Derived::difference`] gives.
    pub(super) fn len(&self) -> usize {
        let tool = if self.tool.is_some() { 6 } else { 0 };
        self.values.len() + tool + self.robot.as_ref().map_or(0, |r| model_parameter_names(r).len())
    }

    /// The covariance of the model's parameters: the trailing block of `c`.
    pub(super) fn model_covariance(&self, c: &DMatrix<f64>) -> Option<ModelCovariance> {
        let names = model_parameter_names(self.robot.as_ref()?);
        let at = c.nrows() - names.len();
        let block = at..c.nrows();
        Some(ModelCovariance {
            names,
            covariance: block
                .clone()
                .map(|i| block.clone().map(|j| c[(i, j)]).collect())
                .collect(),
        })
    }

    /// The 1-sigma of every derived quantity from the diagonal of their covariance `c`.
    pub(super) fn sigma(&self, c: &DMatrix<f64>) -> DerivedSigma {
        let s = |i: usize| c[(i, i)].max(0.0).sqrt();
        let mut at = 0;
        let mut couplings = Vec::new();
        for &n in &self.coupling_sizes {
            couplings.push((at..at + n).map(s).collect());
            at += n;
        }
        let zero_offsets = (at..self.values.len()).map(s).collect();
        let t = self.values.len();
        let tool = self.tool.map(|_| FrameSigma {
            x_mm: s(t) * 1e3,
            y_mm: s(t + 1) * 1e3,
            z_mm: s(t + 2) * 1e3,
            rx_mrad: s(t + 3) * 1e3,
            ry_mrad: s(t + 4) * 1e3,
            rz_mrad: s(t + 5) * 1e3,
        });
        DerivedSigma {
            couplings,
            zero_offsets,
            tool,
        }
    }
}

/// Accumulates `J C J^T` from one-sided differences: `eval(k, h)` is the derived vector at
/// inputs moved by `h` along input direction `k`.
pub(super) struct Propagation {
    /// The running covariance.
    pub(super) covariance: DMatrix<f64>,
}

impl Propagation {
    /// An empty sum for `n` derived quantities.
    pub(super) fn new(n: usize) -> Self {
        Propagation {
            covariance: DMatrix::zeros(n, n),
        }
    }

    /// Adds `J C J^T` for inputs with covariance `c`: column `k` of `J` the one-sided
    /// difference `(eval(k, h_k) - base) / h_k`, `base` the derived vector at the unmoved
    /// inputs computed by the same arithmetic as `eval` (the caller's: one evaluation for all
    /// columns instead of one per column), `h_k = 1e-3 sqrt(c_kk)`: the parameters move by a
    /// thousandth of their sigma, so the truncation error, `h_k f'' / 2` against `f'`, is a
    /// thousandth of the relative change of the slope over one sigma, which makes a variance
    /// `1e-3 sigma |f''/f'|` relative (the sigmas move by <= 6.2e-5 against central
    /// differences on the paper arm, `docs/validation.md`, "One-sided differences"). Not smaller:
    /// rounding at the metre and radian scale of the derived quantities, ~1e-16 over the
    /// step, gives a parameter fixed by convention (`b1 = 0`) a 1-sigma of ~1e-16 sigma / h
    /// per column, ~4e-13 here, which must stay below the 1e-12 that marks a parameter as
    /// estimated (`harness::studies::efficiency`); at 1e-4 sigma it reached 4e-12.
    pub(super) fn add<E>(
        &mut self,
        c: &DMatrix<f64>,
        base: &Derived,
        eval: impl FnMut(usize, f64) -> Result<Derived, E>,
    ) -> Result<(), E> {
        self.add_where(c, |_| true, base, eval)
    }

    /// [`Propagation::add`] with the columns of the inputs `k` where `moves(k)` is false
    /// known to be zero (not evaluated).
    pub(super) fn add_where<E>(
        &mut self,
        c: &DMatrix<f64>,
        moves: impl Fn(usize) -> bool,
        base: &Derived,
        mut eval: impl FnMut(usize, f64) -> Result<Derived, E>,
    ) -> Result<(), E> {
        let n = self.covariance.nrows();
        let mut jac = DMatrix::<f64>::zeros(n, c.nrows());
        let origin = base.origin();
        for k in 0..c.nrows() {
            if c[(k, k)] <= 0.0 || !moves(k) {
                continue;
            }
            let h = 1e-3 * c[(k, k)].sqrt();
            for (r, v) in eval(k, h)?.difference(&origin, h).into_iter().enumerate().take(n) {
                jac[(r, k)] = v;
            }
        }
        // Only the derived quantities these inputs move (a joint's zero offset does not move
        // the joints below it, the tool targets move only the tool frame): the rows of `J`
        // that are exactly zero add nothing.
        let moved: Vec<usize> = (0..n).filter(|&r| jac.row(r).iter().any(|v| *v != 0.0)).collect();
        let j = jac.select_rows(&moved);
        let part = &j * c * j.transpose();
        for (a, &ra) in moved.iter().enumerate() {
            for (b, &rb) in moved.iter().enumerate() {
                self.covariance[(ra, rb)] += part[(a, b)];
            }
        }
        Ok(())
    }

    /// Adds `sigma^2 J J^T` for `count` independent inputs of 1-sigma `sigma`.
    pub(super) fn add_independent<E>(
        &mut self,
        count: usize,
        sigma: f64,
        base: &Derived,
        eval: impl FnMut(usize, f64) -> Result<Derived, E>,
    ) -> Result<(), E> {
        if count == 0 || sigma <= 0.0 {
            return Ok(());
        }
        self.add(&DMatrix::from_diagonal_element(count, count, sigma * sigma), base, eval)
    }
}

/// `points` with coordinate `k % 3` of point `at[k / 3]` (list, index) moved by `h`.
pub(super) fn moved_point(
    points: &[Vec<Point3<f64>>],
    at: &[(usize, usize)],
    k: usize,
    h: f64,
) -> Vec<Vec<Point3<f64>>> {
    let mut out = points.to_vec();
    let (list, i) = at[k / 3];
    out[list][i] += Vector3::ith(k % 3, h);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A derived vector that is a known function of two inputs `x`: values
    /// `[x0 + 2 x1, x0 x1]`, no tool.
    fn derived_of(x: [f64; 2]) -> Derived {
        Derived {
            values: vec![x[0] + 2.0 * x[1], x[0] * x[1]],
            coupling_sizes: vec![2],
            tool: None,
            robot: None,
        }
    }

    /// The one-sided differences of `add` against the analytic `J C J^T` (J = [[1, 2], [x1,
    /// x0]]): agreement to rounding of the steps (the first row is linear, the second
    /// linear in each input alone: one-sided differences are exact up to rounding, ~1e-16 /
    /// 1e-3 relative).
    #[test]
    fn propagation_matches_the_analytic_jacobian() {
        let x = [0.3, -1.7];
        let c = DMatrix::from_row_slice(2, 2, &[4e-6, 1e-6, 1e-6, 9e-6]);
        let mut p = Propagation::new(2);
        p.add(&c, &derived_of(x), |k, h| {
            let mut y = x;
            y[k] += h;
            Ok::<_, ()>(derived_of(y))
        })
        .unwrap();
        let j = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, x[1], x[0]]);
        let expected = &j * &c * j.transpose();
        assert!((&p.covariance - &expected).abs().max() <= 1e-9 * expected.abs().max());
        let s = derived_of(x).sigma(&p.covariance);
        assert_eq!(s.couplings.len(), 1);
        assert!((s.couplings[0][0] - expected[(0, 0)].sqrt()).abs() < 1e-12);
    }

    /// A curved derived vector, `[exp(x0), sin(x0 + x1)]` with 1-sigma of 1e-2 and 3e-2
    /// (curvature on the unit scale, larger sigmas than any fit's): the one-sided columns
    /// differ from the analytic Jacobian by the truncation `h f'' / 2`, `h = 1e-3 sigma`, so
    /// a variance by `1e-3 sigma |f''/f'|` relative (twice the column's): 1e-5 for the
    /// exponential, 2.8e-5 for the sine (`tan(x0 + x1) = 1`, its variance mostly from `x1`);
    /// checked at 5e-5. With a step ten times larger it fails (the truncation is what is
    /// checked).
    #[test]
    fn one_sided_truncation_is_a_thousandth_of_the_curvature_over_one_sigma() {
        let x = [0.2, std::f64::consts::FRAC_PI_4 - 0.2];
        let curved = |y: [f64; 2]| Derived {
            values: vec![y[0].exp(), (y[0] + y[1]).sin()],
            coupling_sizes: vec![2],
            tool: None,
            robot: None,
        };
        let c = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![1e-4, 9e-4]));
        let j = DMatrix::from_row_slice(2, 2, &[x[0].exp(), 0.0, (x[0] + x[1]).cos(), (x[0] + x[1]).cos()]);
        let expected = &j * &c * j.transpose();
        let relative = |scale: f64| {
            let mut p = Propagation::new(2);
            p.add(&c, &curved(x), |k, h| {
                let mut y = x;
                y[k] += scale * h;
                let mut d = curved(y);
                d.values
                    .iter_mut()
                    .zip(&curved(x).values)
                    .for_each(|(v, v0)| *v = v0 + (*v - v0) / scale);
                Ok::<_, ()>(d)
            })
            .unwrap();
            (0..2)
                .map(|i| (p.covariance[(i, i)] / expected[(i, i)] - 1.0).abs())
                .fold(0.0, f64::max)
        };
        assert!(relative(1.0) <= 5e-5, "{}", relative(1.0));
        assert!(relative(10.0) > 5e-5, "{}", relative(10.0));
    }

    /// An arc fit with a first-order harmonic transmission and local covariance `c`.
    fn arc_fit(covariance: DMatrix<f64>) -> LocalFit {
        LocalFit::Arc {
            params: ArcParams {
                centre: Point3::new(0.1, -0.2, 0.7),
                frame: nalgebra::Rotation3::new(Vector3::new(0.3, -0.2, 0.5)),
                radius: 0.4,
                phase_rad: 0.2,
                coefficients: vec![1e-3, -2e-3],
            },
            reference: Point3::new(0.5, 0.5, 0.5),
            form: TransmissionFitForm::Harmonic { order: 1 },
            covariance,
        }
    }

    /// The columns `add_where` skips are those that move neither the axis nor the
    /// transmission: an arc's radius and phase rebuild exactly the unperturbed axis and
    /// transmission; every other local parameter moves one of them, and the transmission's
    /// coefficients move only the transmission (the axis to rounding: the frame is
    /// re-orthonormalised).
    #[test]
    fn skipped_columns_move_nothing() {
        let n = 2 + crate::calibration::arc_model::N_GEOMETRY;
        let fit = arc_fit(DMatrix::identity(n, n));
        let (axis0, t0) = fit.rebuilt(&vec![0.0; n]);
        for i in 0..n {
            let mut delta = vec![0.0; n];
            delta[i] = 1e-4;
            let (axis, t) = fit.rebuilt(&delta);
            let axis_moved = (axis.origin_m - axis0.origin_m).norm()
                + (axis.direction.into_inner() - axis0.direction.into_inner()).norm();
            assert_eq!(fit.moves_model(i), axis_moved > 0.0 || t != t0, "parameter {i}");
            if fit.moves_model(i) {
                assert_eq!(fit.moves_axis(i), axis_moved > 1e-12, "parameter {i}: {axis_moved}");
            }
        }
    }

    /// The line coordinates invert: `coordinates(line(q)) = q`.
    #[test]
    fn line_coordinates_round_trip() {
        let axis = AxisLine {
            origin_m: Point3::new(0.2, -0.1, 0.4),
            direction: Unit::new_normalize(Vector3::new(0.9, 0.3, -0.2)),
        };
        let c = LineCoordinates::new(axis);
        let q = [2e-3, -1e-3, 5e-4, -7e-4];
        let back = c.coordinates(&c.line(&q));
        for (a, b) in back.iter().zip(&q) {
            assert!((a - b).abs() < 1e-15, "{back:?} {q:?}");
        }
    }

    /// `add_axis_fit` through the line coordinates against the arc's local parameters column
    /// by column (a second path: central differences of the rebuilt axis), for a derived
    /// vector that depends on the line only (the foot of the perpendicular from a fixed
    /// point, the direction) and on the transmission's coefficients: the two covariances
    /// agree to the one-sided differences' truncation, `1e-3 sigma |f''/f'|` relative
    /// ([`Propagation::add`]), here with sigmas up to ~1e-2 and curvature on the unit scale
    /// (the foot of the perpendicular from a point ~1 m away): ~1e-5, checked at 5e-5 of the
    /// largest entry (measured 1.1e-5; at steps of 1e-4 sigma 1.1e-6).
    #[test]
    fn line_coordinates_propagate_as_the_local_parameters() {
        let n = 2 + crate::calibration::arc_model::N_GEOMETRY;
        let a = DMatrix::from_fn(n, n, |i, j| {
            ((i * 7 + j * 3) % 5) as f64 * 1e-3 + if i == j { 4e-3 } else { 0.0 }
        });
        let fit = arc_fit(&a * a.transpose());
        let (axis0, t0) = fit.rebuilt(&vec![0.0; n]);
        let p = Point3::new(-0.3, 0.8, 0.1);
        let derived = |axis: &AxisLine, t: &Transmission| {
            let d = axis.direction.into_inner();
            let foot = axis.origin_m + d * (p - axis.origin_m).dot(&d);
            let Transmission::Harmonic { sin, cos } = t else {
                panic!("harmonic")
            };
            Derived {
                values: vec![foot.x, foot.y, foot.z, d.x, d.y, d.z, sin[0], cos[0]],
                coupling_sizes: vec![],
                tool: None,
                robot: None,
            }
        };
        let mut chained = Propagation::new(8);
        let base = derived(&axis0, &t0);
        add_axis_fit(&mut chained, &fit, &axis0, &base, |axis, t| {
            Ok::<_, ()>(derived(&axis.unwrap_or(axis0), &t.unwrap_or_else(|| t0.clone())))
        })
        .unwrap();
        let mut direct = Propagation::new(8);
        direct
            .add(fit.covariance(), &base, |i, h| {
                let mut delta = vec![0.0; n];
                delta[i] = h;
                let (axis, t) = fit.rebuilt(&delta);
                Ok::<_, ()>(derived(&axis, &t))
            })
            .unwrap();
        let scale = direct.covariance.abs().max();
        let diff = (&chained.covariance - &direct.covariance).abs().max();
        assert!(diff <= 5e-5 * scale, "{diff} of {scale}");
        assert!(chained.covariance[(0, 0)] > 0.0 && chained.covariance[(6, 6)] > 0.0);
    }

    /// Independent inputs: `sigma^2 J J^T`; a tool frame moved along x and about z gives
    /// exactly those columns.
    #[test]
    fn independent_inputs_and_tool_columns() {
        let tool = |h: f64, which: usize| Derived {
            values: vec![],
            coupling_sizes: vec![],
            robot: None,
            tool: Some(if which == 0 {
                Isometry3::translation(h, 0.0, 0.0)
            } else {
                Isometry3::rotation(Vector3::z() * h)
            }),
        };
        let mut p = Propagation::new(6);
        p.add_independent(2, 0.01, &tool(0.0, 0), |k, h| Ok::<_, ()>(tool(h, k)))
            .unwrap();
        let s = tool(0.0, 0).sigma(&p.covariance).tool.unwrap();
        assert!((s.x_mm - 10.0).abs() < 1e-9 && (s.rz_mrad - 10.0).abs() < 1e-9, "{s:?}");
        assert!(s.y_mm.abs() < 1e-9 && s.rx_mrad.abs() < 1e-9, "{s:?}");
        let moved = moved_point(&[vec![Point3::origin(); 2]], &[(0, 1)], 2, 0.5);
        assert_eq!(moved[0][1], Point3::new(0.0, 0.0, 0.5));
    }
}
