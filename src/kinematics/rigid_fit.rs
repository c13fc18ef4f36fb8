//! Least-squares rigid transform between point sets (Kabsch / Horn): the frame of a body
//! from three or more observed targets whose positions on the body are known.

use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion};

/// `dst_from_src` minimising `sum |dst_i - T src_i|^2` (Kabsch, *Acta Cryst.* A32 (1976);
/// reflection-corrected SVD of the cross-covariance), and the RMS residual \[input units\].
/// `None` with fewer than three points or collinear `src`.
pub fn rigid_fit(src: &[Point3<f64>], dst: &[Point3<f64>]) -> Option<(Isometry3<f64>, f64)> {
    let n = src.len();
    if n < 3 || dst.len() != n {
        return None;
    }
    let mean = |p: &[Point3<f64>]| Point3::from(p.iter().map(|q| q.coords).sum::<nalgebra::Vector3<f64>>() / n as f64);
    let (cs, cd) = (mean(src), mean(dst));
    let mut h = Matrix3::zeros();
    for (s, d) in src.iter().zip(dst) {
        h += (s - cs) * (d - cd).transpose();
    }
    let svd = h.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let sv = svd.singular_values;
    if sv[1] <= 1e-12 * sv[0].max(f64::MIN_POSITIVE) {
        return None;
    }
    let d = (v_t.transpose() * u.transpose()).determinant().signum();
    let r = v_t.transpose() * Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0, d)) * u.transpose();
    let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
    let t = cd.coords - rot * cs.coords;
    let iso = Isometry3::from_parts(Translation3::from(t), rot);
    let rms = (src
        .iter()
        .zip(dst)
        .map(|(s, d)| (iso * s - d).norm_squared())
        .sum::<f64>()
        / n as f64)
        .sqrt();
    Some((iso, rms))
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::Vector3;

    #[test]
    fn recovers_a_known_transform() {
        let src = [
            Point3::new(0.0, 0.0, 0.15),
            Point3::new(0.08, 0.0, 0.15),
            Point3::new(0.0, 0.08, 0.15),
        ];
        let t = Isometry3::new(Vector3::new(-3.1, 5.3, 0.2), Vector3::new(0.3, -2.0, 0.7));
        let dst: Vec<_> = src.iter().map(|p| t * p).collect();
        let (fit, rms) = rigid_fit(&src, &dst).unwrap();
        assert_relative_eq!(fit.to_homogeneous(), t.to_homogeneous(), epsilon = 1e-12);
        assert!(rms < 1e-12);
        assert!(rigid_fit(&src[..2], &dst[..2]).is_none());
        let line = [Point3::origin(), Point3::new(1.0, 0.0, 0.0), Point3::new(2.0, 0.0, 0.0)];
        assert!(rigid_fit(&line, &line).is_none());
    }
}
