//! The robot controller of paper fig. 3, with the semantics fixed in `docs/formats.md#controller-semantics`.
//!
//! The controller is never modified by calibration (paper fig. 5): it always decouples with
//! the *nominal* passive-motion models of the robot description. Pose commands (nominal
//! inverse kinematics, the first box of fig. 3) are not part of this type: they are built by
//! the kinematics helpers from the nominal model and then fed here as joint commands.

use super::description::RobotDescription;
use super::model_error::ModelError;

/// The fig. 3 controller: joint commands -> actuator commands through the nominal couplings.
#[derive(Clone, Debug, PartialEq)]
pub struct Controller {
    /// `slope_into[k]`: nominal passive motion of joint `k + 1` (1-based) per unit actuator
    /// command of the joint below it; 0 where the joints are not coupled.
    slope_into: Vec<f64>,
}

impl Controller {
    /// The controller of a robot: its nominal couplings (`couplings` of the description).
    pub fn from_description(desc: &RobotDescription) -> Self {
        let slope_into = (1..=desc.dof())
            .map(|to| desc.nominal_coupling_into(to).unwrap_or(0.0))
            .collect();
        Self { slope_into }
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.slope_into.len()
    }

    /// `nominal_passive_{joint-1,joint}(u_from)`: the passive motion the controller expects at
    /// joint `joint` (1-based) for actuator command `u_from` of joint `joint - 1` (linear).
    pub fn nominal_passive_into(&self, joint: usize, u_from: f64) -> f64 {
        self.slope_into.get(joint.wrapping_sub(1)).copied().unwrap_or(0.0) * u_from
    }

    fn check_len(&self, what: &'static str, v: &[f64]) -> Result<(), ModelError> {
        if v.len() == self.dof() {
            Ok(())
        } else {
            Err(ModelError::WrongLength {
                what,
                expected: self.dof(),
                found: v.len(),
            })
        }
    }

    /// Decoupling (`docs/formats.md#controller-semantics`, fig. 3): `u_1 = cmd_1`,
    /// `u_{k+1} = cmd_{k+1} - nominal_passive_{k,k+1}(u_k)`; commands in internal units.
    pub fn decouple(&self, cmd: &[f64]) -> Result<Vec<f64>, ModelError> {
        self.check_len("commands", cmd)?;
        let mut u: Vec<f64> = Vec::with_capacity(cmd.len());
        for (k, &c) in cmd.iter().enumerate() {
            let passive = match k {
                0 => 0.0,
                _ => self.nominal_passive_into(k + 1, u[k - 1]),
            };
            u.push(c - passive);
        }
        Ok(u)
    }

    /// Commands that move actuator `joint` (1-based) alone to the new command `new_cmd` while
    /// holding actuator `joint + 1` still (paper section 3.1, `docs/formats.md#controller-semantics`):
    /// `cmd_{k+1} = cmd_{k+1}(0) + nominal_passive(u_k) - nominal_passive(u_k(0))`, every other
    /// command as in `cmd_ref`. The last joint has no successor: only its own command changes.
    pub fn hold_still_commands(&self, joint: usize, cmd_ref: &[f64], new_cmd: f64) -> Result<Vec<f64>, ModelError> {
        self.check_len("reference commands", cmd_ref)?;
        if joint == 0 || joint > self.dof() {
            return Err(ModelError::BadJoint { joint, dof: self.dof() });
        }
        let k = joint - 1;
        let u_ref = self.decouple(cmd_ref)?;
        // Joints below k are unchanged, so u_k moves exactly as cmd_k does.
        let u_new = u_ref[k] + (new_cmd - cmd_ref[k]);
        let mut cmd = cmd_ref.to_vec();
        cmd[k] = new_cmd;
        if k + 1 < self.dof() {
            cmd[k + 1] += self.nominal_passive_into(joint + 1, u_new) - self.nominal_passive_into(joint + 1, u_ref[k]);
        }
        Ok(cmd)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn decouple_recursion_on_the_irb6() {
        let c = Controller::from_description(&RobotDescription::asea_irb6l());
        let cmd = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6];
        let u = c.decouple(&cmd).unwrap();
        let n = 32.0 / 19.0;
        let u3 = 0.3 + 0.2;
        let u4 = 0.4 - u3;
        let u5 = 0.5 - n * u4;
        let expected = [0.1, 0.2, u3, u4, u5, 0.6];
        for (a, b) in u.iter().zip(expected) {
            assert_relative_eq!(*a, b, epsilon = 1e-15);
        }
        assert!(matches!(c.decouple(&cmd[..5]), Err(ModelError::WrongLength { .. })));
    }

    #[test]
    fn hold_still_uses_the_linear_slope() {
        let c = Controller::from_description(&RobotDescription::asea_irb6l());
        let cmd0 = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6];
        let cmd = c.hold_still_commands(4, &cmd0, 0.9).unwrap();
        assert_relative_eq!(cmd[3], 0.9);
        assert_relative_eq!(cmd[4], 0.5 + 32.0 / 19.0 * 0.5, epsilon = 1e-15);
        assert_relative_eq!(cmd[5], 0.6);
        assert!(matches!(
            c.hold_still_commands(7, &cmd0, 0.0),
            Err(ModelError::BadJoint { .. })
        ));
    }
}
