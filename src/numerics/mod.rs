//! Numerical tools shared by the maths: dense least squares (one Levenberg-Marquardt /
//! Gauss-Newton loop, covariances, condition numbers), the thin SVD of tall designs, sample
//! statistics with named quantile definitions, a change-point test, bisection, central differences
//! (a derivative, a Jacobian, a quadratic's least), and the selection of a design's identifiable
//! columns.

pub mod change_point;
pub mod finite_diff;
pub mod lsq;
pub mod outlier_rounds;
pub mod roots;
pub mod stats;
pub mod subset;
pub mod svd;
