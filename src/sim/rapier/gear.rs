//! Passive couplings without bodies (the bevel gear 4 -> 5, N = 32/19 with its error function,
//! and any other `coupling_in` of the truth not built as a four-bar) emulated by coupled servo
//! targets, updated before every dynamics step.
//!
//! rapier has no gear joint. In the truth model the passive motion of joint `k` is driven by
//! the *active* rotation of joint `k - 1` (`docs/formats.md#controller-semantics`):
//! `q_k = theta_act_k + g(theta_act_{k-1})`. In dynamic mode joint `k - 1` sags by
//! `s_{k-1} = q_{k-1} - T_{k-1}` (its position minus its servo's current target; for a joint
//! driven by a four-bar, the crank's deviation from its target), so the actual rotation of
//! its actuator is `theta_act_{k-1} + s_{k-1}` and each step joint `k`'s servo target becomes
//!
//! `T_k = q_cmd_k - g(theta_act_{k-1}) + g(theta_act_{k-1} + s_{k-1})`
//!
//! (`q_cmd_k` the driver's joint value, jitter included), with the gear's full error function
//! `g`, not its slope. Joints are processed base first, so `T_{k-1}` is already this step's.
//!
//! The emulation is kinematic: it reproduces the gear law exactly at rest (the targets follow
//! joint `k - 1`'s last position, a one-step lag that vanishes at equilibrium), but a gear
//! also reflects joint `k`'s load torque onto joint `k - 1` (by virtual work, `g' Q_k` with
//! `g' = dg/dtheta`, 1.68 for the bevel gear), and that reaction is missing: joint `k - 1`
//! sags by `Q_{k-1} / K_{k-1}` instead of `(Q_{k-1} + g' Q_k) / K_{k-1}`, an error of
//! `|g' Q_k| / K_{k-1}` on joint `k - 1` and `g'^2 |Q_k| / K_{k-1}` on joint `k`. The
//! analytic arm's first-order compliance (`campaign::coupled_first_order_deflection`) uses
//! the same kinematic coupling, so the two agree.
//!
//! Measured (`tests/it/rapier_arm.rs`, joint 4 at 2e4 N m/rad under a 10 kg payload 80 mm off
//! axis 4, joint 5 at 1e8): joint 4 sags 1.89e-3 rad, joint 5 sits 2.7e-9 rad from the gear
//! law above (the error function's nonlinearity alone is 1.6e-7 rad there); the missing
//! reaction (`Q_5` = 4.2 N m) would have turned joint 4 by a further 3.4e-4 rad. A reaction
//! torque applied each step as an external torque was not tried: it would put the stiffness
//! `g'^2 K_5` on joint 4 explicitly, and explicit integration is stable only while
//! `dt sqrt(g'^2 K_5 / I_4) < 2` (estimate: with `I_4` of order 0.1 kg m^2 at 1 ms, `K_5`
//! below about 1e5 N m/rad), not for the stiff servos used elsewhere.

use super::SimError;
use super::arm::SimArm;
use super::four_bar::FourBarBodies;
use crate::robot::{CouplingFunction, RobotModel};

/// Coupled servo targets of one static-equilibrium solve (module docs).
#[derive(Clone, Debug)]
pub struct CoupledTargets {
    /// `(k, g)`: joint `k` (0-based) is driven by joint `k - 1` through `g`.
    couplings: Vec<(usize, CouplingFunction)>,
    q_cmd: Vec<f64>,
    active: Vec<f64>,
    targets: Vec<f64>,
    /// `(b, i, crank target)`: joint `b` is driven by four-bar `i`, whose crank holds this angle.
    cranks: Vec<(usize, usize, f64)>,
}

impl CoupledTargets {
    /// The couplings of `truth` into every joint not driven by one of `four_bars`, for the
    /// driver's joint values `q_cmd` and active displacements `active`; `crank_targets` are
    /// the four-bars' crank targets \[rad\] (same order as `four_bars`), `None` for a four-bar
    /// whose loop is open at this pose (its joint is then servo-driven and coupled here).
    pub fn new(
        truth: &RobotModel,
        four_bars: &[FourBarBodies],
        crank_targets: &[Option<f64>],
        q_cmd: &[f64],
        active: &[f64],
    ) -> Self {
        let cranks: Vec<(usize, usize, f64)> = four_bars
            .iter()
            .zip(crank_targets)
            .enumerate()
            .filter_map(|(i, (fb, c))| c.map(|c| (fb.driven_joint(), i, c)))
            .collect();
        let couplings = truth
            .joints
            .iter()
            .enumerate()
            .skip(1)
            .filter(|(k, _)| !cranks.iter().any(|(b, _, _)| b == k))
            .filter_map(|(k, j)| j.coupling_in.clone().map(|g| (k, g)))
            .collect();
        Self {
            couplings,
            q_cmd: q_cmd.to_vec(),
            active: active.to_vec(),
            targets: q_cmd.to_vec(),
            cranks,
        }
    }

    /// The joints whose targets move (0-based).
    pub fn coupled_joints(&self) -> Vec<usize> {
        self.couplings.iter().map(|(k, _)| *k).collect()
    }

    /// The current servo target of joint `k` \[rad\].
    pub fn target(&self, k: usize) -> f64 {
        self.targets[k]
    }

    /// Sets every coupled joint's servo target from the current sag of the joint below.
    pub fn update(&mut self, arm: &mut SimArm, four_bars: &[FourBarBodies]) -> Result<(), SimError> {
        for (k, g) in &self.couplings {
            let below = k - 1;
            let sag = match self.cranks.iter().find(|(b, _, _)| *b == below) {
                Some(&(_, i, crank)) => four_bars[i].crank_angle(arm) - crank,
                None => arm.joint_position(below) - self.targets[below],
            };
            let a = self.active[below];
            let passive = |t: f64| {
                g.try_passive(t).map_err(|source| SimError::Coupling {
                    joint: *k,
                    cause: source,
                })
            };
            let target = self.q_cmd[*k] - passive(a)? + passive(a + sag)?;
            arm.set_joint_servo_target(*k, target)?;
            self.targets[*k] = target;
        }
        Ok(())
    }
}
