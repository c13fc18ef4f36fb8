//! The robot: its description file, and the analytic truth model (transmissions, passive
//! couplings, transducer offsets, the fig. 3 controller, repeatability, perturbation for
//! Monte-Carlo).

mod controller;
mod description;
mod four_bar;
mod four_bar_fit;
mod functions;
mod perturb;
mod repeatability;
mod truth;
mod truth_error;

pub use controller::Controller;
pub use description::{
    AxisTargets, CouplingFitForm, DescriptionError, JointEntry, LinkTarget, NominalCoupling, Placement,
    RobotDescription, RowEntry, ToolEntry, TransmissionFitForm,
};
pub use four_bar::{FourBarError, FourBarGeometry, FourBarState};
pub use four_bar_fit::{FourBarFit, fit_four_bar};
pub use functions::{CouplingFunction, Transmission};
pub use perturb::{
    CouplingHarmonicSpread, FourBarSpread, PerturbationSpec, PlacementSpread, RowSpread, Spread, TransmissionSpread,
    perturb,
};
pub use repeatability::{
    ObservedThrough, RepeatabilityStats, RepeatabilityTarget, calibrate_repeatability_sigmas, calibrate_uniform_sigma,
    repeatability_stats, workspace_poses,
};
pub use truth::{FourBarLinkage, TruthJoint, TruthRobot};
pub use truth_error::TruthError;
