//! Classical Denavit-Hartenberg parameters of a phi-model geometry, and why they break down
//! on parallel successive axes (the reason for the paper's phi-model, appendix).
//!
//! Classical DH places frame `k` on the common normal of axes `k` and `k + 1`: `a_k` is its
//! length, `alpha_k` the twist from `z_k` to `z_{k+1}` about it, `d_k` the distance along
//! axis `k` from the previous normal's foot to this one's, and `theta_k` the angle between
//! the two normals about `z_k` (Denavit & Hartenberg 1955; Craig, *Introduction to
//! Robotics*, sec. 3.4 for the construction from axis lines).
//!
//! The common normal of two lines with directions `z1`, `z2` and points `o1`, `o2` has its
//! feet at `o1 + s z1` and `o2 + t z2` with, for `c = z1 . z2`, `w = o1 - o2`:
//! `s = (c (z2.w) - z1.w) / (1 - c^2)`, `t = (z2.w - c (z1.w)) / (1 - c^2)`. When the axes
//! are parallel, `1 - c^2 = 0` and the feet are anywhere; when they are tilted by a small
//! angle `eps` in their common plane, the lines meet at a distance `L / tan(eps)` (`L` their
//! separation) and the DH offsets `d` jump there: a 0.01 deg tilt of the IRB/L6's
//! 0.69 m upper arm moves the foot by about 4 km. The phi-model rows stay at millimetres.

use super::chain::{AxisLine, PhiModel};
use nalgebra::{Point3, Rotation3, Unit, Vector3};

/// Axes closer than this to parallel \[rad\] are reported as parallel: the DH offset would
/// exceed `L / 1e-9`, i.e. 1e8 m for a 0.1 m link, which no calibration can mean.
pub const PARALLEL_TOLERANCE_RAD: f64 = 1e-9;

/// The common normal of two axis lines.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CommonNormal {
    /// Its foot on the first axis \[m\].
    pub foot_on_first_m: Point3<f64>,
    /// Its foot on the second axis \[m\].
    pub foot_on_second_m: Point3<f64>,
    /// Its direction `z_first x z_second`, normalised (the DH `x` axis).
    pub direction: Unit<Vector3<f64>>,
    /// Signed length along `direction` (DH `a`) \[m\].
    pub length_m: f64,
    /// Twist from the first to the second axis about `direction` (DH `alpha`), in `(0, pi)` \[rad\].
    pub twist_rad: f64,
}

/// The common normal of `first` and `second`, or `None` when they are parallel to within
/// [`PARALLEL_TOLERANCE_RAD`].
pub fn common_normal(first: &AxisLine, second: &AxisLine) -> Option<CommonNormal> {
    let (z1, z2) = (first.direction.into_inner(), second.direction.into_inner());
    let cross = z1.cross(&z2);
    let sin = cross.norm();
    if sin < PARALLEL_TOLERANCE_RAD {
        return None;
    }
    let c = z1.dot(&z2);
    let w = first.origin_m - second.origin_m;
    let (d1, d2) = (z1.dot(&w), z2.dot(&w));
    let denom = sin * sin;
    let s = (c * d2 - d1) / denom;
    let t = (d2 - c * d1) / denom;
    let foot_on_first_m = first.origin_m + z1 * s;
    let foot_on_second_m = second.origin_m + z2 * t;
    let direction = Unit::new_normalize(cross);
    Some(CommonNormal {
        foot_on_first_m,
        foot_on_second_m,
        direction,
        length_m: (foot_on_second_m - foot_on_first_m).dot(&direction),
        twist_rad: sin.atan2(c),
    })
}

/// One classical DH row: joint `joint` (1-based), from the previous normal to the normal
/// between axes `joint` and `joint + 1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DhRow {
    /// The joint (1-based).
    pub joint: usize,
    /// Offset along the joint axis between the two normals \[m\].
    pub d_m: f64,
    /// Angle between the two normals about the joint axis, at `q = 0` \[rad\].
    pub theta_offset_rad: f64,
    /// Length of the normal to the next axis \[m\].
    pub a_m: f64,
    /// Twist from this axis to the next \[rad\].
    pub alpha_rad: f64,
}

/// The DH rows of joints `1..N-1` (the last joint's `d`, `theta` would only place the tool).
/// Joint 1 is measured from frame 1 (origin and X axis of the robot base frame).
#[derive(Clone, Debug, PartialEq)]
pub struct DhTable {
    /// One row per joint but the last.
    pub rows: Vec<DhRow>,
}

/// Two successive axes without a unique common normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParallelPair {
    /// The first joint of the pair (1-based); the second is `first_joint + 1`.
    pub first_joint: usize,
    /// The angle between the axes \[rad\] (below [`PARALLEL_TOLERANCE_RAD`]).
    pub angle_rad: f64,
}

/// Why no DH table exists.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DhError {
    /// Successive axes are parallel: their common normal, hence the DH `d`, is not unique.
    #[error("DH is undefined: successive axes parallel at joints {}", describe(.pairs))]
    ParallelAxes {
        /// Every parallel pair.
        pairs: Vec<ParallelPair>,
    },
}

fn describe(pairs: &[ParallelPair]) -> String {
    let v: Vec<String> = pairs
        .iter()
        .map(|p| format!("{}-{}", p.first_joint, p.first_joint + 1))
        .collect();
    v.join(", ")
}

/// The classical DH table of `model` at `q = 0`, from the common normals of its axis lines
/// (module docs); [`DhError::ParallelAxes`] when any successive pair is parallel.
pub fn dh_from_phi(model: &PhiModel) -> Result<DhTable, DhError> {
    let n = model.dof();
    let poses = model.poses(&vec![0.0; n]);
    let axes: Vec<AxisLine> = (0..n).map(|k| poses.axis(k)).collect();
    let mut normals = Vec::with_capacity(n.saturating_sub(1));
    let mut pairs = Vec::new();
    for k in 0..n.saturating_sub(1) {
        match common_normal(&axes[k], &axes[k + 1]) {
            Some(c) => normals.push(c),
            None => pairs.push(ParallelPair {
                first_joint: k + 1,
                angle_rad: axes[k].direction.cross(&axes[k + 1].direction).norm().asin(),
            }),
        }
    }
    if !pairs.is_empty() {
        return Err(DhError::ParallelAxes { pairs });
    }
    let base = model.world_from_base;
    let mut prev_foot = base * Point3::origin();
    let mut prev_x = base * Vector3::x();
    let mut rows = Vec::with_capacity(normals.len());
    for (k, c) in normals.iter().enumerate() {
        let z = axes[k].direction.into_inner();
        rows.push(DhRow {
            joint: k + 1,
            d_m: (c.foot_on_first_m - prev_foot).dot(&z),
            theta_offset_rad: prev_x.cross(&c.direction).dot(&z).atan2(prev_x.dot(&c.direction)),
            a_m: c.length_m,
            alpha_rad: c.twist_rad,
        });
        prev_foot = c.foot_on_second_m;
        prev_x = c.direction.into_inner();
    }
    Ok(DhTable { rows })
}

/// What a small tilt does to the DH offset of two parallel axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TiltSensitivity {
    /// Distance between the (parallel) axes \[m\].
    pub separation_m: f64,
    /// The tilt applied to the second axis, in the plane of both \[rad\].
    pub tilt_rad: f64,
    /// Where the common normal's foot lands on the first axis after the tilt, measured from
    /// the foot of the perpendicular from the second axis' origin \[m\]: `-L / tan(tilt)`.
    pub foot_offset_m: f64,
    /// `d(foot offset)/d(tilt) = L / sin^2(tilt)` \[m/rad\].
    pub offset_per_rad_m: f64,
}

/// For two parallel axes, tilt `second` by `tilt_rad` about its origin in the plane holding
/// both axes and return where the DH common normal lands on `first` (module docs): the DH
/// offset explodes like `L / tilt`. `None` if the axes coincide or the tilted pair is still
/// parallel to within [`PARALLEL_TOLERANCE_RAD`].
pub fn parallel_tilt_sensitivity(first: &AxisLine, second: &AxisLine, tilt_rad: f64) -> Option<TiltSensitivity> {
    let z1 = first.direction.into_inner();
    let w = second.origin_m - first.origin_m;
    let along = z1.dot(&w);
    let sep = w - z1 * along;
    let separation_m = sep.norm();
    if separation_m < PARALLEL_TOLERANCE_RAD {
        return None;
    }
    // Rotating about (z1 x sep) keeps the tilted axis in the plane of both: they now meet.
    let pivot = Unit::new_normalize(z1.cross(&sep));
    let tilted = AxisLine {
        origin_m: second.origin_m,
        direction: Rotation3::from_axis_angle(&pivot, tilt_rad) * second.direction,
    };
    let c = common_normal(first, &tilted)?;
    Some(TiltSensitivity {
        separation_m,
        tilt_rad,
        foot_offset_m: (c.foot_on_first_m - first.origin_m).dot(&z1) - along,
        offset_per_rad_m: separation_m / tilt_rad.sin().powi(2),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::PhiRow;
    use crate::robot::RobotDescription;
    use approx::assert_relative_eq;

    /// Table 2, actual columns (NOTES-paper.md): metres and degrees.
    #[allow(clippy::approx_constant)] // -0.6931 m is Table 2's a_2, not -ln 2
    const ACTUAL_ROWS: [[f64; 4]; 5] = [
        [0.00232, 0.0, 90.0, -90.378],
        [-0.6931, 0.00487, 89.828, -179.54],
        [-0.6727, 0.00162, 90.4213, -179.99],
        [-0.0007, 0.00297, 89.8033, -89.921],
        [-0.0039, -0.2331, 89.4829, -90.137],
    ];

    fn actual_model() -> PhiModel {
        let mut m = RobotDescription::asea_irb6l().nominal_model();
        m.rows = ACTUAL_ROWS
            .iter()
            .map(|r| PhiRow::from_table_deg(r[0], r[1], r[2], r[3]))
            .collect();
        m
    }

    #[test]
    fn nominal_rows_report_the_parallel_pairs() {
        let nominal = RobotDescription::asea_irb6l().nominal_model();
        let err = dh_from_phi(&nominal).unwrap_err();
        let DhError::ParallelAxes { pairs } = &err;
        let joints: Vec<usize> = pairs.iter().map(|p| p.first_joint).collect();
        assert_eq!(joints, vec![2, 3]);
        assert!(err.to_string().contains("2-3, 3-4"));
    }

    #[test]
    fn actual_rows_give_metre_dh_offsets_where_phi_rows_stay_at_mm() {
        let actual = actual_model();
        let nominal = RobotDescription::asea_irb6l().nominal_model();
        let table = dh_from_phi(&actual).expect("tilted axes have common normals");
        // phi-model: actual minus nominal is at most a few mm.
        let max_row_change_m = actual
            .rows
            .iter()
            .zip(&nominal.rows)
            .map(|(a, n)| (a.a_m - n.a_m).abs().max((a.b_m - n.b_m).abs()))
            .fold(0.0, f64::max);
        assert!(max_row_change_m < 0.01, "{max_row_change_m}");
        // DH: the offsets along axes 2, 3, 4 (the nearly parallel ones, tilted by ~0.4 deg) are
        // tens of metres (27.8, -119.2, 91.4 m here), not the nominal 0.
        for r in &table.rows[1..4] {
            assert!(r.d_m.abs() > 1.0, "joint {}: d = {} m", r.joint, r.d_m);
        }
        assert!(table.rows[2].d_m.abs() > 100.0);
    }

    #[test]
    fn a_hundredth_of_a_degree_moves_the_dh_foot_by_kilometres() {
        let poses = RobotDescription::asea_irb6l().nominal_model().poses(&[0.0; 6]);
        let tilt_rad = 0.01_f64.to_radians();
        let s = parallel_tilt_sensitivity(&poses.axis(1), &poses.axis(2), tilt_rad).expect("axes 2, 3 are distinct");
        assert_relative_eq!(s.separation_m, 0.69, epsilon = 1e-12);
        assert_relative_eq!(s.foot_offset_m.abs(), 0.69 / tilt_rad.tan(), max_relative = 1e-9);
        assert!(s.foot_offset_m.abs() > 3900.0);
    }
}
