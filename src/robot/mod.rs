//! The robot: its description file, and the analytic truth model (transmissions, passive
//! couplings, transducer offsets, the fig. 3 controller, perturbation for Monte-Carlo).

mod description;
mod four_bar;
mod four_bar_fit;
mod functions;

pub use description::{
    AxisTargets, DescriptionError, JointEntry, LinkTarget, NominalCoupling, Placement, RobotDescription, RowEntry,
    ToolEntry,
};
pub use four_bar::{FourBarError, FourBarGeometry, FourBarState};
pub use four_bar_fit::{FourBarFit, fit_four_bar};
pub use functions::{CouplingFunction, Transmission};
