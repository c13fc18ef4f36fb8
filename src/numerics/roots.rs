//! Bisection: the one bracket-halving loop of the program, for the edge of a predicate (a span
//! still feasible or visible, a statistic still below its target) or the root of a
//! nondecreasing function, each caller stating when to stop ([`Bisection`]).

/// When [`bisect`] stops halving its bracket `[lo, hi]`: after `max_steps` halvings, when the
/// bracket is at most `width` wide or at most `relative_width` times `hi`, or when no number
/// lies between `lo` and `hi` (the last bit of the bracket), whichever comes first.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bisection {
    /// Halvings at most.
    pub max_steps: usize,
    /// The bracket's width at which it stops (units of the argument).
    pub width: f64,
    /// The bracket's width, relative to `hi`, at which it stops.
    pub relative_width: f64,
}

impl Bisection {
    /// `n` halvings (fewer only at the last bit).
    pub const fn steps(n: usize) -> Self {
        Bisection {
            max_steps: n,
            width: 0.0,
            relative_width: 0.0,
        }
    }

    /// Halvings until the bracket is at most `width` wide.
    pub const fn to_width(width: f64) -> Self {
        Bisection {
            max_steps: usize::MAX,
            width,
            relative_width: 0.0,
        }
    }

    /// Halvings until the bracket is at most `relative_width` times its upper end wide.
    pub const fn to_relative_width(relative_width: f64) -> Self {
        Bisection {
            max_steps: usize::MAX,
            width: 0.0,
            relative_width,
        }
    }
}

/// Halves the bracket `[lo, hi]` of an edge: `below(mid)` says whether the edge lies above `mid`
/// (`mid` becomes `lo`) or not (`mid` becomes `hi`); the final bracket, with `lo` on the
/// `below` side and `hi` on the other as they were given. An error of `below` ends the search.
pub fn bisect<E>(
    mut lo: f64,
    mut hi: f64,
    stop: Bisection,
    mut below: impl FnMut(f64) -> Result<bool, E>,
) -> Result<[f64; 2], E> {
    for _ in 0..stop.max_steps {
        if hi - lo <= stop.width || hi - lo <= stop.relative_width * hi {
            break;
        }
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if below(mid)? {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok([lo, hi])
}

/// [`bisect`] with a predicate that cannot fail.
pub fn bisect_infallible(lo: f64, hi: f64, stop: Bisection, mut below: impl FnMut(f64) -> bool) -> [f64; 2] {
    let found: Result<_, std::convert::Infallible> = bisect(lo, hi, stop, |x| Ok(below(x)));
    match found {
        Ok(bracket) => bracket,
        Err(never) => match never {},
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The square root of 2 as the edge of `x^2 < 2`, checked against `f64::sqrt` (a different
    /// path): to the last bit, to a width, to a relative width, and in a counted number of
    /// halvings (each halves the bracket exactly).
    #[test]
    fn each_stop_brackets_the_edge_as_stated() {
        let root = 2f64.sqrt();
        let below = |x: f64| x * x < 2.0;
        let [lo, hi] = bisect_infallible(0.0, 2.0, Bisection::steps(200), below);
        assert!(lo <= root && root <= hi && hi - lo <= f64::EPSILON * 2.0, "{lo} {hi}");
        let [lo, hi] = bisect_infallible(0.0, 2.0, Bisection::to_width(1e-3), below);
        assert!(lo < root && root < hi && hi - lo <= 1e-3 && hi - lo > 0.5e-3);
        let [lo, hi] = bisect_infallible(0.0, 2.0, Bisection::to_relative_width(1e-9), below);
        assert!(lo < root && root < hi && hi - lo <= 1e-9 * hi);
        let [lo, hi] = bisect_infallible(0.0, 2.0, Bisection::steps(10), below);
        assert_eq!((hi - lo).to_bits(), (2.0f64 / 1024.0).to_bits(), "ten exact halvings");
        assert!(lo < root && root < hi);
    }

    /// An error of the predicate ends the search and is returned; no halving after it.
    #[test]
    fn an_error_ends_the_search() {
        let mut calls = 0;
        let found = bisect(0.0, 1.0, Bisection::steps(50), |x| {
            calls += 1;
            if x < 0.3 { Err("failed") } else { Ok(false) }
        });
        assert_eq!(found, Err("failed"));
        assert_eq!(calls, 2, "0.5, then 0.25 fails");
    }
}
