//! Which parameters the free poses identify: the column subset of the design at the registered
//! nominal model ([`crate::numerics::subset`]), each parameter left out named with the
//! combination of fitted ones it is made of and, where the geometry says why, the reason.

use crate::calibration::refine::{DirectionWeight, RefitParameter};
use crate::kinematics::{JointKind, PhiModel};
use crate::numerics::subset::{ColumnSubset, select_columns_with};
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

/// A parameter is identified when the part of its column (scaled to unit length) outside the
/// span of the parameters before it reaches this. Below it the parameter's sigma would be
/// 1e5 times what its column alone gives (over 100 mrad for 0.05 mm noise, 0.5 m lever arms
/// and 100 poses): nothing a user could use. Structural redundancies (parallel axes, an
/// offset and a base rotation about one axis) leave parts at the design's rounding, about
/// 1e-9 (the joint map's central difference), 1e4 times below; the weakest genuinely
/// identified parameters of real campaigns sit near 1e-3.
pub const IDENTIFIABLE_PART: f64 = 1e-5;

/// An effect's parameter is kept when this part of its column (scaled to unit length) is
/// independent of the parameters before it: its sigma is then at most 100 times what its column
/// alone gives. A sag's basis terms are products of masses and compliance whose regressors
/// overlap heavily on any workspace; a term less independent than this adds under 1 % of new
/// shape at 1e4 times its own variance.
pub const EFFECT_IDENTIFIABLE_PART: f64 = 1e-2;

/// Whether `p` is an effect's parameter (sag or backlash).
pub fn is_effect(p: &RefitParameter) -> bool {
    matches!(p, RefitParameter::Sag { .. } | RefitParameter::Backlash { .. })
}

/// Terms of a combination reported at most.
const LEADING_TERMS: usize = 4;

/// Two axes closer to parallel than this angle \[rad\] are parallel for the reasons given.
const PARALLEL_RAD: f64 = 1e-6;

/// A parameter the data do not identify: kept at its nominal (registered) value.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Unidentified {
    /// Parameter name (`row2.a`, `joint1.zero_offset`, ...).
    pub name: String,
    /// Why, in words.
    pub reason: String,
    /// Its effect on the points as a combination of fitted parameters (coefficients in the
    /// parameters' internal units: m, rad), largest first, at most four terms; empty when it
    /// has no effect at all.
    pub same_as: Vec<DirectionWeight>,
}

/// The identification: the fitted columns of the layout and the others.
#[derive(Clone, Debug, PartialEq)]
pub struct Identification {
    /// Fitted parameters (indices into the layout), ascending.
    pub fitted: Vec<usize>,
    /// The parameters left out.
    pub unidentified: Vec<Unidentified>,
}

impl Identification {
    /// Moves the fitted columns `columns` to the unidentified ones: harmonics whose order the
    /// model selection did not keep.
    pub fn drop_insignificant(&mut self, columns: &[usize], layout: &[RefitParameter]) {
        self.fitted.retain(|c| !columns.contains(c));
        self.unidentified.extend(columns.iter().map(|&c| Unidentified {
            name: layout[c].name(),
            reason: "its harmonic order does not predict held-out configurations better (cross-validation)".into(),
            same_as: vec![],
        }));
    }

    /// Moves the fitted parameter the design `jacobian` determines worst to the unidentified
    /// ones: the one whose column (scaled to unit length) has the smallest part outside the
    /// span of every other fitted column, `1 / sqrt((X^T X)^-1_cc)` of the scaled fitted
    /// columns `X`. For a fit that does not converge: along such a direction the cost's
    /// curvature is the data's information (that part squared) plus the residuals' own
    /// curvature, which the Gauss-Newton model leaves out; where the second rivals the first
    /// the steps crawl. Returns the parameter's name, or `None` when nothing is fitted.
    pub fn drop_weakest(&mut self, jacobian: &DMatrix<f64>, layout: &[RefitParameter]) -> Option<String> {
        let columns: Vec<_> = self
            .fitted
            .iter()
            .map(|&c| {
                let col = jacobian.column(c);
                let norm = col.norm();
                if norm > 0.0 { col / norm } else { col.into_owned() }
            })
            .collect();
        if columns.is_empty() {
            return None;
        }
        let x = DMatrix::from_columns(&columns);
        let inverse = crate::numerics::lsq::inverse_normal(&x, "identification").ok()?;
        let (slot, part) = (0..self.fitted.len())
            .map(|i| (i, 1.0 / inverse[(i, i)].max(f64::MIN_POSITIVE).sqrt()))
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        let column = self.fitted.remove(slot);
        let name = layout[column].name();
        self.unidentified.push(Unidentified {
            name: name.clone(),
            reason: format!(
                "the data determine it too weakly for the fit to converge with it (part {part:.1e} of its effect independent of the other parameters)"
            ),
            same_as: vec![],
        });
        Some(name)
    }
}

/// The identification of the layout's parameters from the design `jacobian` (every column of
/// the layout) at the registered nominal `phi`.
/// (in the layout's order of preference: the geometry before the transmission harmonics).
///
/// An effect's parameters (sag and backlash, [`is_effect`]) are a basis for a shape, not
/// physical quantities each: they are kept only when [`EFFECT_IDENTIFIABLE_PART`] of them is
/// independent of everything before them, and the others are dropped unreported (the summary
/// counts the kept ones).
pub fn identify(jacobian: &DMatrix<f64>, layout: &[RefitParameter], phi: &PhiModel) -> Identification {
    let tolerance = |c: usize| {
        if is_effect(&layout[c]) {
            EFFECT_IDENTIFIABLE_PART
        } else {
            IDENTIFIABLE_PART
        }
    };
    let ColumnSubset { chosen, rejected } = select_columns_with(jacobian, tolerance);
    let parallel = parallel_pairs(phi);
    let unidentified = rejected
        .into_iter()
        .filter(|r| !is_effect(&layout[r.column]))
        .map(|r| {
            let same_as: Vec<DirectionWeight> = r
                .combination
                .iter()
                .take(LEADING_TERMS)
                .map(|&(k, weight)| DirectionWeight {
                    name: layout[k].name(),
                    weight,
                })
                .collect();
            Unidentified {
                name: layout[r.column].name(),
                reason: reason(&layout[r.column], same_as.is_empty(), &parallel, phi),
                same_as,
            }
        })
        .collect();
    Identification {
        fitted: chosen,
        unidentified,
    }
}

/// Rows (1-based) whose two axes are parallel in the nominal geometry.
fn parallel_pairs(phi: &PhiModel) -> Vec<usize> {
    let frames = phi.poses(&vec![0.0; phi.dof()]);
    (1..phi.dof())
        .filter(|&r| {
            let (a, b) = (frames.axis(r - 1).direction, frames.axis(r).direction);
            a.cross(&b).norm() < PARALLEL_RAD
        })
        .collect()
}

/// Why `p` is not identified.
fn reason(p: &RefitParameter, no_effect: bool, parallel: &[usize], phi: &PhiModel) -> String {
    if no_effect {
        return "the measured points do not depend on it (no pose moves it)".into();
    }
    let row = match p {
        RefitParameter::RowA(r)
        | RefitParameter::RowB(r)
        | RefitParameter::RowAlpha(r)
        | RefitParameter::RowBeta(r) => Some(*r),
        _ => None,
    };
    match (row, p) {
        (Some(r), _) if parallel.contains(&r) => format!(
            "axes {r} and {} are parallel: its effect equals a combination of other parameters",
            r + 1
        ),
        (_, RefitParameter::ZeroOffset { joint: 1, .. }) => {
            "joint 1's zero turns everything about axis 1, as the base frame's rotation does".into()
        }
        (_, RefitParameter::ZeroOffset { joint, .. })
            if *joint == phi.dof() && phi.joints[joint - 1].kind == JointKind::Revolute =>
        {
            format!("joint {joint}'s zero turns every target about axis {joint}, as the targets' positions do")
        }
        _ => "its effect on the points equals a combination of other parameters".into(),
    }
}
