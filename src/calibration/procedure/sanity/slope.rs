//! A swept joint's fitted slope against its description's, and how far it may depart: what
//! the transmission test ([`super::scale`]) and the attribution to an instrument axis
//! ([`super::scale_source`]) both read.

/// A joint's slope is said when it departs from its description's by more than this many
/// sigmas of the drive's ([`super::scale::PLAUSIBLE_TURN_DEVIATION`], [`super::scale::PLAUSIBLE_LEAD_DEVIATION`]) and the
/// fit's combined: 6, not 5, because the fit's sigma (its coefficients' correlation left out)
/// runs short on a poorly resolved wrist joint: the clean simulations reach 4.5 on the paper
/// robot's joint 6 (6.3 % +-1.4 % where 1.7 % is true).
pub const DRIVE_SIGMAS: f64 = 6.0;

/// One swept joint's fitted mean slope over its sweep against its description's (the slope
/// the transmission test reads), for the attribution of several joints' departures to one
/// instrument axis ([`super::column_source`]; `joint_slopes` reads them).
#[derive(Clone, Debug, PartialEq)]
pub struct JointSlope {
    /// The joint (1-based).
    pub joint: usize,
    /// Fitted over described mean slope (commanded per actual) \[1\].
    pub ratio: f64,
    /// Its 1-sigma (the fit's).
    pub sigma: f64,
    /// The sigma of what its drive departs by ([`super::scale::PLAUSIBLE_TURN_DEVIATION`], [`super::scale::PLAUSIBLE_LEAD_DEVIATION`]).
    pub drive: f64,
    /// Whether it slides (else it turns).
    pub sliding: bool,
    /// Its sweep's experiment.
    pub experiment: String,
}

impl JointSlope {
    /// Whether it departs from 1 beyond `DRIVE_SIGMAS` of its sigma and its drive's combined
    /// (the transmission test's warning).
    pub fn beyond(&self) -> bool {
        (self.ratio - 1.0).abs() > DRIVE_SIGMAS * self.sigma.hypot(self.drive)
    }
}
