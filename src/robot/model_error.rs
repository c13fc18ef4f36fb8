//! Errors of the truth model, its controller and its perturbation.

use super::four_bar::FourBarError;

/// Why the truth model (or the controller in front of it) cannot produce joint values.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// A vector has the wrong number of entries.
    #[error("{what}: expected {expected} values, found {found}")]
    WrongLength {
        /// What the vector is, e.g. `commands`.
        what: &'static str,
        /// The robot's number of joints (or the required length).
        expected: usize,
        /// The length given.
        found: usize,
    },
    /// A joint number outside `1..=dof` (or without a successor where one is needed).
    #[error("joint {joint} is not valid here (the robot has {dof} joints)")]
    BadJoint {
        /// The 1-based joint number given.
        joint: usize,
        /// Number of joints.
        dof: usize,
    },
    /// A transmission function is not monotonic near the requested command.
    #[error(
        "joint {joint}: the transmission cannot be inverted at the actuator command {command_file} {unit} (after \
         its zero offset): the function is not monotonic there"
    )]
    NotInvertible {
        /// 1-based joint.
        joint: usize,
        /// The actuator command after offset removal, in file units (deg or mm).
        command_file: f64,
        /// `deg` or `mm`.
        unit: &'static str,
    },
    /// A four-bar coupling cannot be assembled.
    #[error("coupling into joint {joint}: {cause}")]
    Coupling {
        /// 1-based driven joint.
        joint: usize,
        /// The linkage problem.
        cause: FourBarError,
    },
    /// A compliance carried in the model finds no static equilibrium at a pose.
    #[error("the compliance of joint {joint} in the model finds no equilibrium at this pose (the arm would buckle)")]
    Buckles {
        /// 1-based joint.
        joint: usize,
    },
    /// The file could not be read or parsed.
    #[error(transparent)]
    File(#[from] crate::toml_file::TomlFileError),
    /// A value is out of range or inconsistent.
    #[error("field `{field}`: {message}")]
    Invalid {
        /// The offending key, e.g. `joints[2].repeatability_sigma`.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// [`ModelError::Invalid`] in a file.
    #[error("{path}: field `{field}`: {message}")]
    InvalidIn {
        /// The robot model file.
        path: std::path::PathBuf,
        /// The offending key.
        field: String,
        /// What is wrong.
        message: String,
    },
}
