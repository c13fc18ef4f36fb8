//! Derivatives by central differences, the project's one implementation: `(f(x + h) - f(x -
//! h)) / 2h`, whose error is `h^2 f''' / 6` (Nocedal & Wright, Numerical Optimization, 2nd ed.,
//! eq. 8.7), for a value along one parameter ([`central_difference`], [`try_central_difference`]), for a vector function's
//! Jacobian ([`central_jacobian`]) and for a scalar function's gradient and Hessian, read as a
//! quadratic with its least ([`quadratic_least`], eqs. 8.7 and 8.9).

use super::lsq::pseudo_inverse_semidefinite;
use nalgebra::{DMatrix, DVector};
use std::ops::{Div, Sub};

/// The derivative at 0 of `f` along its one parameter by a central difference `h` wide:
/// `(f(h) - f(-h)) / 2h`, of any value whose difference divides by a length (a vector, a point's
/// move).
pub fn central_difference<P, V>(f: impl Fn(f64) -> P, h: f64) -> V
where
    P: Sub<Output = V>,
    V: Div<f64, Output = V>,
{
    quotient(f(h), f(-h), h)
}

/// [`central_difference`] of an `f` that may fail: `None` when either evaluation does.
pub fn try_central_difference<P, V>(f: impl Fn(f64) -> Option<P>, h: f64) -> Option<V>
where
    P: Sub<Output = V>,
    V: Div<f64, Output = V>,
{
    let plus = f(h)?;
    Some(quotient(plus, f(-h)?, h))
}

/// The central difference quotient `(plus - minus) / 2h`.
fn quotient<P, V>(plus: P, minus: P, h: f64) -> V
where
    P: Sub<Output = V>,
    V: Div<f64, Output = V>,
{
    (plus - minus) / (2.0 * h)
}

/// The Jacobian `d f / d x` at `x0` of a vector function `f` by central differences, parameter
/// `c` moved by `steps[c]` either side: `2 len(x0)` evaluations (the centre itself is not
/// evaluated); `None` when an evaluation fails or two differ in length. The columns are
/// independent evaluations: they run in parallel on the current rayon pool, each computed by
/// the same arithmetic whatever the thread count (bit for bit the serial result).
pub fn central_jacobian<F>(f: F, x0: &[f64], steps: &[f64]) -> Option<DMatrix<f64>>
where
    F: Fn(&[f64]) -> Option<Vec<f64>> + Sync,
{
    use rayon::prelude::*;
    if x0.is_empty() {
        return Some(DMatrix::zeros(f(x0)?.len(), 0));
    }
    let column = |c: usize| -> Option<Vec<f64>> {
        let mut q = x0.to_vec();
        q[c] = x0[c] + steps[c];
        let plus = f(&q)?;
        q[c] = x0[c] - steps[c];
        let minus = f(&q)?;
        (plus.len() == minus.len()).then(|| {
            plus.iter()
                .zip(&minus)
                .map(|(p, m)| (p - m) / (2.0 * steps[c]))
                .collect()
        })
    };
    let columns: Vec<Vec<f64>> = (0..x0.len()).into_par_iter().map(column).collect::<Option<_>>()?;
    let n = columns[0].len();
    if columns.iter().any(|c| c.len() != n) {
        return None;
    }
    Some(DMatrix::from_fn(n, x0.len(), |i, c| columns[c][i]))
}

/// A scalar function read as a quadratic about a point ([`quadratic_least`]).
#[derive(Clone, Debug)]
pub struct Quadratic {
    /// Where the quadratic is least (Newton's step from the centre, orthogonal to the null
    /// directions).
    pub least_at: Vec<f64>,
    /// The quadratic's least value.
    pub least: f64,
    /// The Hessian's pseudo-inverse.
    pub inverse_hessian: DMatrix<f64>,
    /// The directions the quadratic does not change along (unit vectors).
    pub null: Vec<DVector<f64>>,
}

/// The least of the quadratic through `f` about `centre` (where it is `f_centre`), from
/// central differences `step` wide along each parameter and at the sum of two steps for each
/// pair (eq. 8.9's off-diagonal terms, from the one-sided pair): where it is and its value,
/// with the Hessian's pseudo-inverse and the directions whose curvature is below `weak` times
/// the stiffest (either sign: [`pseudo_inverse_semidefinite`]); `None` where an evaluation fails
/// or the quadratic is not convex.
pub fn quadratic_least(
    f: &dyn Fn(&[f64]) -> Option<f64>,
    centre: &[f64],
    f_centre: f64,
    (step, weak): (f64, f64),
) -> Option<Quadratic> {
    let p = centre.len();
    let moved = |d: &[(usize, f64)]| {
        let mut x = centre.to_vec();
        d.iter().for_each(|&(i, by)| x[i] += by);
        f(&x)
    };
    let plus: Vec<f64> = (0..p).map(|i| moved(&[(i, step)])).collect::<Option<_>>()?;
    let minus: Vec<f64> = (0..p).map(|i| moved(&[(i, -step)])).collect::<Option<_>>()?;
    let gradient = DVector::from_fn(p, |i, _| (plus[i] - minus[i]) / (2.0 * step));
    let mut hessian = DMatrix::from_fn(p, p, |i, j| match i == j {
        true => (plus[i] + minus[i] - 2.0 * f_centre) / (step * step),
        false => 0.0,
    });
    for i in 0..p {
        for j in i + 1..p {
            let both = moved(&[(i, step), (j, step)])?;
            let h = (both - plus[i] - plus[j] + f_centre) / (step * step);
            (hessian[(i, j)], hessian[(j, i)]) = (h, h);
        }
    }
    let (inverse_hessian, null) = pseudo_inverse_semidefinite(&hessian, weak)?;
    let newton = &inverse_hessian * &gradient;
    Some(Quadratic {
        least_at: centre.iter().zip(newton.iter()).map(|(c, n)| c - n).collect(),
        least: f_centre - gradient.dot(&newton) / 2.0,
        inverse_hessian,
        null,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::{Point3, Vector3};

    /// On a cubic the central difference's error is `h^2 f''' / 6` (eq. 8.7), read against
    /// the derivative written out by hand; a point's move divides as a vector.
    #[test]
    fn a_central_difference_errs_by_the_third_derivative() {
        // f(t) = 2 + 3 t + t^3 about 0.5: f'(0.5) = 3 + 3 (0.25) = 3.75, f''' = 6.
        let f = |t: f64| Some(DVector::from_vec(vec![2.0 + 3.0 * (t + 0.5) + (t + 0.5).powi(3)]));
        let h = 0.1;
        let d: DVector<f64> = try_central_difference(f, h).unwrap();
        assert_relative_eq!(d[0], 3.75 + h * h * 6.0 / 6.0, max_relative = 1e-12);
        let point = |t: f64| Point3::new(t, 2.0 * t, t * t);
        let v: Vector3<f64> = central_difference(point, 1e-3);
        assert_relative_eq!(v, Vector3::new(1.0, 2.0, 0.0), epsilon = 1e-12);
        assert!(try_central_difference(|t: f64| (t > 0.0).then_some(DVector::from_vec(vec![t])), 0.1).is_none());
    }

    /// The Jacobian of a linear map is the map (a second path: the matrix written out).
    #[test]
    fn a_linear_maps_jacobian_is_the_map() {
        let f = |p: &[f64]| Some(vec![1.0 - 2.0 * p[0], 3.0 - p[0] - 4.0 * p[1]]);
        let j = central_jacobian(f, &[0.1, 0.2], &[1e-6, 1e-6]).unwrap();
        assert_relative_eq!(
            j,
            DMatrix::from_row_slice(2, 2, &[-2.0, 0.0, -1.0, -4.0]),
            max_relative = 1e-8
        );
        let ragged = |p: &[f64]| Some(vec![0.0; if p[0] > 0.1 { 2 } else { 3 }]);
        assert!(central_jacobian(ragged, &[0.1], &[1e-3]).is_none());
    }

    /// The parallel columns are the serial ones bit for bit, whatever the pool's size.
    #[test]
    fn a_jacobian_is_the_same_on_any_thread_count() {
        let f = |p: &[f64]| {
            Some(
                (0..40)
                    .map(|i| (p[i % 7] * (i as f64 + 0.3)).sin() * p[(i + 3) % 7])
                    .collect(),
            )
        };
        let p0: Vec<f64> = (0..7).map(|k| 0.1 + 0.07 * k as f64).collect();
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a pool");
            pool.install(|| central_jacobian(f, &p0, &[1e-6; 7]).expect("finite"))
        };
        let one = on(1);
        for threads in [2, 5] {
            let other = on(threads);
            assert!(one.iter().zip(other.iter()).all(|(a, b)| a.to_bits() == b.to_bits()));
        }
    }

    /// The quadratic's least and inverse Hessian are exact on a quadratic (a second path: the
    /// least written out by hand, the Hessian's inverse by hand).
    #[test]
    fn a_quadratics_least_and_hessian_are_read_exactly() {
        // f = 3 + (x - 1)^2 + 2 (y + 0.5)^2 + (x - 1)(y + 0.5) + 0.5 (z - 2)^2
        let f = |v: &[f64]| {
            let (x, y, z) = (v[0] - 1.0, v[1] + 0.5, v[2] - 2.0);
            Some(3.0 + x * x + 2.0 * y * y + x * y + 0.5 * z * z)
        };
        let centre = [0.3, 0.2, -0.4];
        let q = quadratic_least(&f, &centre, f(&centre).unwrap(), (0.7, 1e-3)).unwrap();
        let (at, least, h) = (q.least_at, q.least, q.inverse_hessian);
        let tight = 1e-12;
        for (a, b) in at.iter().zip([1.0, -0.5, 2.0]) {
            assert!((a - b).abs() < tight, "{at:?}");
        }
        assert!((least - 3.0).abs() < tight);
        // The Hessian [[2, 1, 0], [1, 4, 0], [0, 0, 1]] inverted by hand.
        let expected = [
            [4.0 / 7.0, -1.0 / 7.0, 0.0],
            [-1.0 / 7.0, 2.0 / 7.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        for (i, row) in expected.iter().enumerate() {
            for (j, e) in row.iter().enumerate() {
                assert!((h[(i, j)] - e).abs() < 1e-9, "{h}");
            }
        }
    }

    /// A direction the quadratic does not change along is null: no step along it, the others'
    /// least found.
    #[test]
    fn a_flat_direction_is_null_and_the_others_least_is_found() {
        // f = (x + y - 2)^2 + (z - 1)^2: flat along (1, -1, 0).
        let f = |v: &[f64]| Some((v[0] + v[1] - 2.0).powi(2) + (v[2] - 1.0).powi(2));
        let centre = [0.5, 0.25, 0.0];
        let q = quadratic_least(&f, &centre, f(&centre).unwrap(), (0.5, 1e-3)).unwrap();
        assert_eq!(q.null.len(), 1);
        let n = &q.null[0];
        assert!((n[0].abs() - 0.5f64.sqrt()).abs() < 1e-9 && (n[0] + n[1]).abs() < 1e-9 && n[2].abs() < 1e-9);
        assert!((q.least_at[0] + q.least_at[1] - 2.0).abs() < 1e-9 && (q.least_at[2] - 1.0).abs() < 1e-9);
        // The step is orthogonal to the null direction: x - y as at the centre.
        assert!((q.least_at[0] - q.least_at[1] - 0.25).abs() < 1e-9);
        assert!(q.least.abs() < 1e-9);
    }

    /// A saddle or a maximum has no least.
    #[test]
    fn a_quadratic_that_is_not_convex_has_no_least() {
        let saddle = |v: &[f64]| Some(v[0] * v[0] - v[1] * v[1]);
        assert!(quadratic_least(&saddle, &[0.1, 0.2], saddle(&[0.1, 0.2]).unwrap(), (0.5, 1e-3)).is_none());
        let max = |v: &[f64]| Some(-v[0] * v[0]);
        assert!(quadratic_least(&max, &[0.3], max(&[0.3]).unwrap(), (1.0, 1e-3)).is_none());
    }
}
