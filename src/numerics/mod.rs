//! Numerical tools shared by the maths: dense least squares (one Levenberg-Marquardt /
//! Gauss-Newton loop, covariances, condition numbers), the thin SVD of tall designs, and
//! sample statistics with named quantile definitions.

pub mod lsq;
pub mod stats;
pub mod subset;
pub mod svd;
