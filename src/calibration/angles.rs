//! Observed joint displacements, eqs. (6)-(7): project each point (in the axis frame) onto
//! the plane normal to `Z_i` (eq. 6, `v = p_x x_i + p_y y_i`) and take the signed angle from
//! one projection to the next (eq. 7) with `atan2`. Positive = right-handed about `+Z_i`
//! (the printed eq. 7 crosses `v^j x v^(j-1)`, which would give the opposite sign).

use nalgebra::Point3;

use super::CalibrationError;

const FIT: &str = "observed angles (eqs. 6-7)";

/// Increments `theta^j` from point `j-1` to point `j` \[rad\] (length `n - 1`), eq. (7):
/// `atan2((v^(j-1) x v^j) . z, v^(j-1) . v^j)`.
pub fn angle_increments(points_in_axis_frame: &[Point3<f64>]) -> Result<Vec<f64>, CalibrationError> {
    if points_in_axis_frame.len() < 2 {
        return Err(CalibrationError::TooFewPoints {
            fit: FIT,
            got: points_in_axis_frame.len(),
            needed: 2,
        });
    }
    if points_in_axis_frame.iter().any(|p| p.x == 0.0 && p.y == 0.0) {
        return Err(CalibrationError::InvalidInput {
            fit: FIT,
            what: "a point lies on the axis",
        });
    }
    Ok(points_in_axis_frame
        .windows(2)
        .map(|w| {
            let (a, b) = (w[0], w[1]);
            (a.x * b.y - a.y * b.x).atan2(a.x * b.x + a.y * b.y)
        })
        .collect())
}

/// Cumulative displacements from step 0 \[rad\] (length `n`, first element 0).
pub fn displacements_from_start(points_in_axis_frame: &[Point3<f64>]) -> Result<Vec<f64>, CalibrationError> {
    let inc = angle_increments(points_in_axis_frame)?;
    let mut out = Vec::with_capacity(inc.len() + 1);
    out.push(0.0);
    let mut acc = 0.0;
    for d in inc {
        acc += d;
        out.push(acc);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn positive_about_plus_z_on_a_synthetic_arc() {
        let steps = [0.1, 0.25, -0.05, 0.4];
        let mut t: f64 = 0.3;
        let mut pts = vec![Point3::new(0.7 * t.cos(), 0.7 * t.sin(), 0.2)];
        for s in steps {
            t += s;
            pts.push(Point3::new(0.7 * t.cos(), 0.7 * t.sin(), 0.2));
        }
        let inc = angle_increments(&pts).unwrap();
        for (a, b) in inc.iter().zip(steps) {
            assert_relative_eq!(*a, b, epsilon = 1e-14);
        }
        let cum = displacements_from_start(&pts).unwrap();
        assert_relative_eq!(cum[4], 0.7, epsilon = 1e-14);
        assert!(angle_increments(&pts[..1]).is_err());
    }
}
