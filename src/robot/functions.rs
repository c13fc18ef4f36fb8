//! Transmission and passive-coupling function forms (paper eqs. 8 and 15, section 4).
//!
//! These are pure maths shared by the truth model (which evaluates them) and the calibrator
//! (which fits their coefficients): a form carries no knowledge of any true value.

use super::description::MAX_GEAR_RATIO;
use super::four_bar::{FourBarError, FourBarGeometry};
use serde::{Deserialize, Serialize};

/// A transmission function `theta_c = f(theta_a)`: the command \[rad\] a joint needs to reach
/// the actual active displacement `theta_a` \[rad\] (eq. 8).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "form", rename_all = "snake_case", deny_unknown_fields)]
pub enum Transmission {
    /// `theta_c = theta_a + sum_k (sin\[k-1\] sin(k theta_a) + cos\[k-1\] cos(k theta_a))`;
    /// the paper's form for joints 1, 2, 3 and 6 is order 1.
    Harmonic {
        /// Sine coefficients, order 1 first \[rad\].
        sin: Vec<f64>,
        /// Cosine coefficients, order 1 first \[rad\].
        cos: Vec<f64>,
    },
    /// A gear of ratio `N` with errors periodic in the gear angle (the paper's joint 5):
    /// `theta_G = theta_a / N + sum_k (sin\[k-1\] sin(k theta_a / N) + cos\[k-1\] cos(k theta_a / N))`
    /// and, in joint units, `theta_c = N theta_G`.
    Gear {
        /// Gear ratio `N` (joint turns per gear turn).
        ratio: f64,
        /// Sine coefficients in gear units \[rad\].
        sin: Vec<f64>,
        /// Cosine coefficients in gear units \[rad\].
        cos: Vec<f64>,
    },
    /// A sliding joint's transmission (eq. 13): `s_c = s_a + c0 + sum_k c\[k-1\] s_a^k` in
    /// metres; `c\[0\]` is the scale error (dimensionless), `c\[1\]..` the nonlinearity
    /// (`c_k` in m^(1-k)), `c0` a constant (m, 0 unless the model was shifted to a new zero).
    Polynomial {
        /// Constant term \[m\].
        #[serde(default)]
        c0: f64,
        /// `c_1, c_2, ..`: scale error, then the higher orders.
        c: Vec<f64>,
    },
}

/// `(sum_k c_k s^k, d/ds of it, d2/ds2 of it)` for `k = 1..`.
fn polynomial(s: f64, c: &[f64]) -> (f64, f64, f64) {
    let (mut v, mut dv, mut ddv) = (0.0, 0.0, 0.0);
    let mut power = 1.0; // s^(k-1)
    let mut power_minus = 0.0; // s^(k-2), 0 for k = 1
    for (i, ck) in c.iter().enumerate() {
        let k = (i + 1) as f64;
        v += ck * power * s;
        dv += ck * k * power;
        ddv += ck * k * (k - 1.0) * power_minus;
        power_minus = power;
        power *= s;
    }
    (v, dv, ddv)
}

/// The largest amplitude of one harmonic of a transmission or a coupling a calibration may
/// hold \[rad\] (about 6 deg, in the transmission's own angle: the gear's for a gear): a gear's
/// transmission error is a few mrad, and ripple of this size is a broken joint, not an error to
/// compensate. The diagnosis's plausible gear-harmonic amplitude
/// (`crate::diagnosis::MAX_ANGLE_RAD`) is this bound.
pub const MAX_HARMONIC_AMPLITUDE_RAD: f64 = 0.1;

/// Why a list of numbers of a function is unusable: `None` when every value is finite.
fn non_finite(values: &[f64]) -> Option<String> {
    values
        .iter()
        .any(|v| !v.is_finite())
        .then(|| "every coefficient must be finite".to_string())
}

/// Why harmonics could make a transmission turn backwards: its slope is `1 + sum_k k (s_k
/// cos kx - c_k sin kx)` (in the gear angle for a gear), which stays above 0 wherever
/// `sum_k k sqrt(s_k^2 + c_k^2) < 1` (exactly so for one harmonic). A transmission that turns
/// back gives one command two joint values and cannot be inverted (fig. 3).
fn turns_back(sin: &[f64], cos: &[f64]) -> Option<String> {
    let coefficient = |list: &[f64], k: usize| list.get(k).copied().unwrap_or(0.0);
    let slopes: f64 = (0..sin.len().max(cos.len()))
        .map(|k| (k + 1) as f64 * coefficient(sin, k).hypot(coefficient(cos, k)))
        .sum();
    (slopes >= 1.0).then(|| {
        format!(
            "the harmonics' slopes add up to {} (the sum of k sqrt(sin_k^2 + cos_k^2) must stay below 1): the \
             transmission would turn backwards, so a command would have no single joint value; a real \
             transmission's coefficients are a few mrad",
            crate::measurement::format_f64(slopes)
        )
    })
}

/// Why a gear ratio is unusable: `None` when it is finite and not 0.
fn bad_ratio(ratio: f64) -> Option<String> {
    (!ratio.is_finite() || ratio == 0.0 || ratio.abs() > MAX_GEAR_RATIO).then(|| {
        format!(
            "the gear ratio must be finite, not 0 and at most {MAX_GEAR_RATIO} in size (as a description's), found {}",
            crate::measurement::format_f64(ratio)
        )
    })
}

/// Why a transmission's gear ratio is none ([`bad_ratio`], and at least `1 / MAX_GEAR_RATIO` in
/// size: joint turns per gear turn, as a description's `transmission_fit`), if so.
fn bad_transmission_ratio(ratio: f64) -> Option<String> {
    bad_ratio(ratio).or_else(|| {
        (ratio.abs() < 1.0 / MAX_GEAR_RATIO).then(|| {
            format!(
                "the gear ratio must be from {} to {MAX_GEAR_RATIO} in size (joint turns per gear turn, as a description's), found {}",
                1.0 / MAX_GEAR_RATIO,
                crate::measurement::format_f64(ratio)
            )
        })
    })
}

impl Transmission {
    /// Why the transmission cannot be evaluated (a ratio of 0, a coefficient not finite), if so.
    pub fn problem(&self) -> Option<String> {
        match self {
            Transmission::Harmonic { sin, cos } => non_finite(sin)
                .or_else(|| non_finite(cos))
                .or_else(|| turns_back(sin, cos)),
            Transmission::Gear { ratio, sin, cos } => bad_transmission_ratio(*ratio)
                .or_else(|| non_finite(sin))
                .or_else(|| non_finite(cos))
                .or_else(|| turns_back(sin, cos)),
            Transmission::Polynomial { c0, c } => non_finite(&[*c0]).or_else(|| non_finite(c)),
        }
    }

    /// The ideal transmission `theta_c = theta_a`.
    pub fn identity() -> Self {
        Transmission::Harmonic {
            sin: vec![],
            cos: vec![],
        }
    }

    /// `theta_c = f(theta_a)`.
    pub fn command_from_actual(&self, theta_a: f64) -> f64 {
        self.value_and_slope(theta_a).0
    }

    /// `d theta_c / d theta_a`.
    pub fn slope(&self, theta_a: f64) -> f64 {
        self.value_and_slope(theta_a).1
    }

    /// `(f(theta_a), f'(theta_a))` from one evaluation of the harmonics (one `sin_cos` per
    /// harmonic) or of the polynomial: what each Newton step of the inversion needs.
    pub fn value_and_slope(&self, theta_a: f64) -> (f64, f64) {
        match self {
            Transmission::Harmonic { sin, cos } => {
                let (v, dv) = harmonics(theta_a, sin, cos);
                (theta_a + v, 1.0 + dv)
            }
            Transmission::Gear { ratio, sin, cos } => {
                let (v, dv) = harmonics(theta_a / ratio, sin, cos);
                (theta_a + ratio * v, 1.0 + dv)
            }
            Transmission::Polynomial { c0, c } => {
                let (v, dv, _) = polynomial(theta_a, c);
                (theta_a + c0 + v, 1.0 + dv)
            }
        }
    }

    /// The coefficients in the order the calibrator fits them: `[sin.., cos..]`, or `[c_1..]`
    /// for a polynomial (its constant, a zero convention, left out).
    pub fn coefficients(&self) -> Vec<f64> {
        match self {
            Transmission::Harmonic { sin, cos } | Transmission::Gear { sin, cos, .. } => {
                sin.iter().chain(cos).copied().collect()
            }
            Transmission::Polynomial { c, .. } => c.clone(),
        }
    }

    /// The identity of a joint kind: no harmonics (revolute) or no scale error (prismatic).
    pub fn identity_for(kind: crate::kinematics::JointKind) -> Self {
        match kind {
            crate::kinematics::JointKind::Revolute => Self::identity(),
            crate::kinematics::JointKind::Prismatic => Transmission::Polynomial { c0: 0.0, c: vec![] },
        }
    }

    /// The same transmission seen from an actual angle shifted by `shift_rad`:
    /// `f(theta - C) = f'(theta) - C` exactly, with each harmonic pair rotated by `k C`
    /// (`k C / N` for a gear). Returns `f'`; a model `theta_a = f^-1(u) + C` is then
    /// `theta_a = f'^-1(u + C)`, i.e. `f'` with a transducer offset of `-C`.
    pub fn shifted(&self, shift_rad: f64) -> Transmission {
        let rotate = |sin: &[f64], cos: &[f64], step: f64| -> (Vec<f64>, Vec<f64>) {
            let k_max = sin.len().max(cos.len());
            let (mut s2, mut c2) = (vec![0.0; k_max], vec![0.0; k_max]);
            for k in 0..k_max {
                let (s, c) = (sin.get(k).copied().unwrap_or(0.0), cos.get(k).copied().unwrap_or(0.0));
                let (sk, ck) = ((k + 1) as f64 * step).sin_cos();
                s2[k] = s * ck + c * sk;
                c2[k] = c * ck - s * sk;
            }
            (s2, c2)
        };
        match self {
            Transmission::Harmonic { sin, cos } => {
                let (sin, cos) = rotate(sin, cos, shift_rad);
                Transmission::Harmonic { sin, cos }
            }
            Transmission::Gear { ratio, sin, cos } => {
                let (sin, cos) = rotate(sin, cos, shift_rad / ratio);
                Transmission::Gear {
                    ratio: *ratio,
                    sin,
                    cos,
                }
            }
            Transmission::Polynomial { c0, c } => shifted_polynomial(*c0, c, shift_rad),
        }
    }

    /// `theta_a = f^-1(theta_c)` by safeguarded Newton iteration; `None` if `f` is not
    /// monotonic near the solution (coefficients too large for a real transmission).
    pub fn actual_from_command(&self, theta_c: f64) -> Option<f64> {
        invert_monotonic(
            |t| {
                let (value, slope) = self.value_and_slope(t);
                (value - theta_c, slope)
            },
            theta_c,
        )
    }
}

/// `f'(s) = f(s - C) + C` for `f(s) = s + c0 + sum_k c_k s^k`, expanded by the binomial
/// theorem: `f'(s) = s + c0' + sum_i c_i' s^i` with `c_i' = sum_{k >= i} c_k binom(k, i) (-C)^(k-i)`.
fn shifted_polynomial(c0: f64, c: &[f64], shift: f64) -> Transmission {
    let n = c.len();
    let mut out = vec![0.0; n + 1]; // index i: coefficient of s^i
    out[0] = c0;
    for (idx, ck) in c.iter().enumerate() {
        let k = idx + 1;
        let mut binom = 1.0;
        for (i, o) in out.iter_mut().enumerate().take(k + 1) {
            if i > 0 {
                binom = binom * (k - i + 1) as f64 / i as f64;
            }
            *o += ck * binom * (-shift).powi((k - i) as i32);
        }
    }
    Transmission::Polynomial {
        c0: out[0],
        c: out[1..].to_vec(),
    }
}

/// A passive coupling `theta_p = g(theta_a)`: the passive displacement of joint `i+1` \[rad\]
/// driven by the active displacement `theta_a` of joint `i` \[rad\] (eq. 15).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "form", rename_all = "snake_case", deny_unknown_fields)]
pub enum CouplingFunction {
    /// `g = N t + sum_k (sin\[k-1\] sin(k N t) + cos\[k-1\] cos(k N t))`: a gear of ratio `N`
    /// (bevel gear 4->5: `N = 32/19`; identity 3->4: `N = 1`, no harmonics).
    Gear {
        /// Ratio `N`.
        ratio: f64,
        /// Sine coefficients \[rad\].
        sin: Vec<f64>,
        /// Cosine coefficients \[rad\].
        cos: Vec<f64>,
    },
    /// The paper's fractional four-bar form (section 4, joint 2->3):
    /// `g = atan((n0 sin t + n1 cos t + n2) / (cos t + d0 sin t + d1))`, continuous branch
    /// through `t = 0`.
    Fractional {
        /// `[n0, n1, n2]`.
        num: [f64; 3],
        /// `[d0, d1]`.
        den: [f64; 2],
    },
    /// The geometric four-bar of paper fig. 6, solved by loop closure (see
    /// [`FourBarGeometry`]); written `form = "four_bar"` with the geometry's keys inline.
    FourBar(FourBarGeometry),
}

impl CouplingFunction {
    /// Why the coupling cannot be evaluated (a ratio of 0, a coefficient not finite), if so;
    /// a four-bar's geometry is checked by [`FourBarGeometry::validate`].
    pub fn problem(&self) -> Option<String> {
        match self {
            CouplingFunction::Gear { ratio, sin, cos } => bad_ratio(*ratio)
                .or_else(|| non_finite(sin))
                .or_else(|| non_finite(cos)),
            CouplingFunction::Fractional { num, den } => non_finite(num).or_else(|| non_finite(den)),
            CouplingFunction::FourBar(_) => None,
        }
    }

    /// A linear coupling `g = slope * t` (the controller's nominal model).
    pub fn linear(slope: f64) -> Self {
        CouplingFunction::Gear {
            ratio: slope,
            sin: vec![],
            cos: vec![],
        }
    }

    /// `theta_p = g(theta_a)`; NaN where a [`CouplingFunction::FourBar`] cannot close (use
    /// [`CouplingFunction::try_passive`] to get the reason).
    pub fn passive(&self, t: f64) -> f64 {
        self.try_passive(t).unwrap_or(f64::NAN)
    }

    /// `theta_p = g(theta_a)`, or why a four-bar cannot be assembled at `t`.
    pub fn try_passive(&self, t: f64) -> Result<f64, FourBarError> {
        Ok(match self {
            CouplingFunction::FourBar(g) => g.passive(t)?,
            other => other.closed_form_passive(t),
        })
    }

    /// `d g / d t`, or why a four-bar cannot be assembled at `t`.
    pub fn try_slope(&self, t: f64) -> Result<f64, FourBarError> {
        Ok(match self {
            CouplingFunction::FourBar(g) => g.solve(t)?.slope,
            other => other.closed_form_slope(t),
        })
    }

    /// `d g / d t`; NaN where a four-bar cannot close.
    pub fn slope(&self, t: f64) -> f64 {
        self.try_slope(t).unwrap_or(f64::NAN)
    }

    fn closed_form_passive(&self, t: f64) -> f64 {
        match self {
            CouplingFunction::Gear { ratio, sin, cos } => ratio * t + harmonics(ratio * t, sin, cos).0,
            CouplingFunction::Fractional { num, den } => {
                let (s, c) = t.sin_cos();
                let y = num[0] * s + num[1] * c + num[2];
                let x = c + den[0] * s + den[1];
                // atan of the ratio, kept on the branch through t = 0 (x > 0 there).
                y.atan2(x)
            }
            CouplingFunction::FourBar(_) => f64::NAN,
        }
    }

    fn closed_form_slope(&self, t: f64) -> f64 {
        match self {
            CouplingFunction::Gear { ratio, sin, cos } => ratio * (1.0 + harmonics(ratio * t, sin, cos).1),
            CouplingFunction::Fractional { num, den } => {
                let (s, c) = t.sin_cos();
                let y = num[0] * s + num[1] * c + num[2];
                let x = c + den[0] * s + den[1];
                let dy = num[0] * c - num[1] * s;
                let dx = -s + den[0] * c;
                (x * dy - y * dx) / (x * x + y * y)
            }
            CouplingFunction::FourBar(_) => f64::NAN,
        }
    }
}

/// `(sum_k s_k sin(k x) + c_k cos(k x), d/dx of it)`, the sine terms summed before the cosine
/// terms; one `sin_cos` per harmonic (the first eight kept for the cosine terms).
fn harmonics(x: f64, sin: &[f64], cos: &[f64]) -> (f64, f64) {
    // Order 0 and 1 (the paper's forms, evaluated in every transmission inversion): the same
    // operations in the same order as the loops below, without their table.
    match (sin, cos) {
        ([], []) => return (0.0, 0.0),
        ([_] | [], [_] | []) => {
            let (sk, ck) = x.sin_cos();
            let (mut v, mut dv) = (0.0, 0.0);
            if let Some(s) = sin.first() {
                v += s * sk;
                dv += s * 1.0 * ck;
            }
            if let Some(c) = cos.first() {
                v += c * ck;
                dv -= c * 1.0 * sk;
            }
            return (v, dv);
        }
        _ => {}
    }
    let mut kept = [(0.0, 0.0); 8];
    let n_kept = sin.len().max(cos.len()).min(kept.len());
    for (k, sc) in kept.iter_mut().enumerate().take(n_kept) {
        *sc = ((k + 1) as f64 * x).sin_cos();
    }
    let sin_cos = |k: usize| {
        if k < n_kept {
            kept[k]
        } else {
            ((k + 1) as f64 * x).sin_cos()
        }
    };
    let (mut v, mut dv) = (0.0, 0.0);
    for (k, s) in sin.iter().enumerate() {
        let kf = (k + 1) as f64;
        let (sk, ck) = sin_cos(k);
        v += s * sk;
        dv += s * kf * ck;
    }
    for (k, c) in cos.iter().enumerate() {
        let kf = (k + 1) as f64;
        let (sk, ck) = sin_cos(k);
        v += c * ck;
        dv -= c * kf * sk;
    }
    (v, dv)
}

/// Root of a monotonically increasing `h` by Newton from `start`: `h_and_slope(t)` returns
/// `(h(t), h'(t))` from one evaluation.
pub(crate) fn invert_monotonic(h_and_slope: impl Fn(f64) -> (f64, f64), start: f64) -> Option<f64> {
    let mut t = start;
    for _ in 0..50 {
        let (r, d) = h_and_slope(t);
        if r.abs() < 1e-15 {
            return Some(t);
        }
        if d <= 0.0 || !d.is_finite() {
            return None;
        }
        let step = r / d;
        t -= step;
        if step.abs() < 1e-15 * (1.0 + t.abs()) {
            return Some(t);
        }
    }
    (h_and_slope(t).0.abs() < 1e-12).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn shifted_is_exact() {
        let forms = [
            Transmission::Harmonic {
                sin: vec![0.017334, 0.002],
                cos: vec![0.002677, -0.001],
            },
            Transmission::Gear {
                ratio: 32.0 / 19.0,
                sin: vec![0.041227],
                cos: vec![-0.000013],
            },
            Transmission::Polynomial {
                c0: 0.001,
                c: vec![2e-4, -0.03, 0.5],
            },
        ];
        for f in forms {
            let c = 0.37;
            let g = f.shifted(c);
            for i in -10..=10 {
                let t = i as f64 * 0.13;
                assert_relative_eq!(
                    f.command_from_actual(t - c),
                    g.command_from_actual(t) - c,
                    epsilon = 1e-14
                );
            }
        }
    }

    /// Harmonics whose slopes add up to 1 or more are refused (the transmission could turn
    /// back), for a gear too; just below, they are not.
    #[test]
    fn harmonics_that_could_turn_back_are_a_problem() {
        let harmonic = |sin: Vec<f64>, cos: Vec<f64>| Transmission::Harmonic { sin, cos };
        assert!(harmonic(vec![0.6], vec![0.79]).problem().is_none());
        assert!(
            harmonic(vec![0.6], vec![0.8])
                .problem()
                .unwrap()
                .contains("add up to 1")
        );
        assert!(harmonic(vec![0.0, 0.3], vec![0.0, 0.2]).problem().is_none());
        assert!(harmonic(vec![0.0, 0.4], vec![0.0, 0.3]).problem().is_some());
        let gear = Transmission::Gear {
            ratio: 32.0 / 19.0,
            sin: vec![2.0],
            cos: vec![],
        };
        assert!(gear.problem().is_some());
    }

    #[test]
    fn paper_joint6_inverts() {
        let f = Transmission::Harmonic {
            sin: vec![0.017334],
            cos: vec![0.002677],
        };
        for i in -20..=20 {
            let a = i as f64 * 0.1;
            let c = f.command_from_actual(a);
            assert_relative_eq!(f.actual_from_command(c).unwrap(), a, epsilon = 1e-13);
        }
    }

    #[test]
    fn slopes_match_central_differences() {
        let t = Transmission::Gear {
            ratio: 32.0 / 19.0,
            sin: vec![0.041227, 0.001],
            cos: vec![-0.000013],
        };
        let g = CouplingFunction::Fractional {
            num: [-0.998132, 0.213253, -0.212863],
            den: [0.096654, -0.0006941],
        };
        let b = CouplingFunction::Gear {
            ratio: 32.0 / 19.0,
            sin: vec![-0.040562],
            cos: vec![0.000018],
        };
        let h = 1e-6;
        for i in -10..=10 {
            let x = i as f64 * 0.07;
            let fd = |f: &dyn Fn(f64) -> f64| (f(x + h) - f(x - h)) / (2.0 * h);
            assert_relative_eq!(t.slope(x), fd(&|v| t.command_from_actual(v)), epsilon = 1e-8);
            assert_relative_eq!(g.slope(x), fd(&|v| g.passive(v)), epsilon = 1e-8);
            assert_relative_eq!(b.slope(x), fd(&|v| b.passive(v)), epsilon = 1e-8);
        }
    }

    #[test]
    fn paper_four_bar_is_nearly_minus_identity() {
        let g = CouplingFunction::Fractional {
            num: [-0.998132, 0.213253, -0.212863],
            den: [0.096654, -0.0006941],
        };
        assert!(g.passive(0.0).abs() < 1e-3);
        assert_relative_eq!(g.slope(0.0), -1.0, epsilon = 0.05);
    }
}
