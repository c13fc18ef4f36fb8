//! The robot: its description file, and the analytic truth model (transmissions, passive
//! couplings, transducer offsets, the fig. 3 controller, perturbation for Monte-Carlo).

mod description;
mod functions;

pub use description::{
    AxisTargets, DescriptionError, JointEntry, LinkTarget, NominalCoupling, Placement, RobotDescription, RowEntry,
    ToolEntry,
};
pub use functions::{CouplingFunction, Transmission};
