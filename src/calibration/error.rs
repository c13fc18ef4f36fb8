//! The one error type of the calibration maths.

use thiserror::Error;

/// Why a calibration fit could not produce an answer.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CalibrationError {
    /// Fewer observations than the fit needs.
    #[error("{fit}: {got} points given, at least {needed} needed")]
    TooFewPoints {
        /// Which fit refused.
        fit: &'static str,
        /// Points given.
        got: usize,
        /// Points needed.
        needed: usize,
    },
    /// The points lie (numerically) on one line, so they define no plane or circle.
    #[error("{fit}: points are collinear (second/first singular value {ratio:.3e})")]
    Collinear {
        /// Which fit refused.
        fit: &'static str,
        /// Ratio of the second to the first singular value of the centred points.
        ratio: f64,
    },
    /// The points (or the commands) do not span any distance or angle.
    #[error("{fit}: observations have zero span")]
    ZeroSpan {
        /// Which fit refused.
        fit: &'static str,
    },
    /// Two input sequences that must match do not.
    #[error("{fit}: {what} has length {got}, expected {expected}")]
    LengthMismatch {
        /// Which fit refused.
        fit: &'static str,
        /// The offending input.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The length it should have.
        expected: usize,
    },
    /// The normal matrix of a least-squares step is singular or too ill-conditioned to solve.
    #[error("{fit}: ill-conditioned Jacobian (condition number {condition_number:.3e})")]
    IllConditioned {
        /// Which fit refused.
        fit: &'static str,
        /// 2-norm condition number of the (column-scaled) Jacobian.
        condition_number: f64,
    },
    /// An iterative fit did not converge.
    #[error("{fit}: not converged after {iterations} iterations (residual RMS {residual_rms:.3e})")]
    NotConverged {
        /// Which fit failed.
        fit: &'static str,
        /// Iterations performed.
        iterations: usize,
        /// RMS of the residual vector at the last iterate (input units).
        residual_rms: f64,
    },
    /// A fitted transmission function is not invertible (not monotonic) at some command.
    #[error(
        "{fit}: the fitted transmission turns back on itself near the command {:.3} deg (or mm): no joint \
         position gives that command, so the points cannot be placed on the axis; the sweep is too short or its \
         points too noisy to resolve the transmission's harmonics: widen the span, measure more points or with \
         less noise, or lower the description's `transmission_fit.order` for this joint",
        command_rad.to_degrees()
    )]
    NotInvertible {
        /// Which fit failed.
        fit: &'static str,
        /// The command that could not be inverted \[rad\].
        command_rad: f64,
    },
    /// An input value is not finite or out of its domain.
    #[error("{fit}: invalid input {what}")]
    InvalidInput {
        /// Which fit refused.
        fit: &'static str,
        /// What is wrong.
        what: &'static str,
    },
}

impl From<crate::numerics::lsq::LsqError> for CalibrationError {
    fn from(e: crate::numerics::lsq::LsqError) -> Self {
        use crate::numerics::lsq::LsqError;
        match e {
            LsqError::IllConditioned { fit, condition_number } => {
                CalibrationError::IllConditioned { fit, condition_number }
            }
            LsqError::NotConverged {
                fit,
                iterations,
                residual_rms,
            } => CalibrationError::NotConverged {
                fit,
                iterations,
                residual_rms,
            },
        }
    }
}
