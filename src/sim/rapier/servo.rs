//! Dynamic mode: position servos with finite stiffness holding the arm against gravity, and
//! the static-equilibrium solve.
//!
//! Each servo is a rapier *implicit joint spring* (`MultibodyJoint::set_spring`, rest position
//! = the commanded value) plus the multibody's implicit per-DoF damping: the generalised force
//! is `tau_k = -K_k (q_k - q_cmd_k) - D_k dq_k/dt` with `K` in N m/rad (N/m for prismatic
//! joints), and both terms are integrated backward-Euler inside the multibody's mass matrix
//! (`dt^2 K + dt D` on its diagonal). At rest the equilibrium satisfies `K dq = Q_gravity(q)`,
//! the usual joint-stiffness model of servo compliance.
//!
//! Why springs and not rapier joint motors: a position motor is a soft velocity constraint
//! solved by the PGS loop next to any loop-closing impulse joint, and with stiff gains the two
//! fight: measured on rapier 0.36.1 (dt 1 ms, 16 solver iterations, 1e8 N m/rad) the four-bar
//! closure of [`FourBarBodies`](super::FourBarBodies) held only 1.6-1.8 micrometres (0.45 with
//! 4 PGS iterations per substep) and joint 3 was off by 9-13 microradians (4), whereas with
//! implicit springs the closure is the only constraint, its effective mass already contains
//! the servos, and it holds to 2e-12 to 1.3e-10 m. (A rapier motor with zero stiffness and
//! damping is not "off" either: its zero-softness constraint locks the joint velocity, which
//! is what opened the loop by centimetres when joint 3 was "released" that way; a passive
//! joint here has no spring, no damping and no motor.)

use super::SimArm;
use super::SimError;
use super::arm::{LinkPoint, check_len, check_positive};
use nalgebra::{Point3, Vector3};
use rapier3d_f64::prelude::{JointAxis, MultibodyJointHandle, PhysicsWorld};

/// Servo stiffness and damping per joint.
#[derive(Clone, Debug, PartialEq)]
pub struct ServoGains {
    /// Position gain of each joint's servo \[N m/rad\] (or \[N/m\]).
    pub stiffness_nm_per_rad: Vec<f64>,
    /// Velocity gain of each joint's servo \[N m s/rad\] (or \[N s/m\]).
    pub damping_nms_per_rad: Vec<f64>,
}

impl ServoGains {
    /// Gains with damping `D_k = 2 zeta sqrt(K_k I_k)`, `I_k` the inertia about joint `k` at
    /// `q` estimated from point masses at the centres of mass of the links beyond it (the
    /// payload is left out) and the links' own cylinder axial inertia `m r^2 / 2` with
    /// `r = 0.05 m` as a floor. `zeta = 1` gives roughly critical damping of each joint alone.
    pub fn with_damping_ratio(arm: &SimArm, q: &[f64], stiffness_nm_per_rad: &[f64], zeta: f64) -> Self {
        let model = arm.model();
        let poses = model.poses(q);
        let coms: Vec<(f64, Point3<f64>)> = arm
            .inertias()
            .iter()
            .enumerate()
            .map(|(i, li)| (li.mass_kg, poses.world_from_link[i] * li.com_in_link_m))
            .collect();
        let damping = stiffness_nm_per_rad
            .iter()
            .enumerate()
            .map(|(k, &stiff)| {
                let axis = poses.axis(k);
                let inertia: f64 = coms[k..]
                    .iter()
                    .map(|(m, c)| m * (axis.direction.cross(&(c - axis.origin_m)).norm_squared() + 0.05 * 0.05 / 2.0))
                    .sum();
                2.0 * zeta * (stiff * inertia).sqrt()
            })
            .collect();
        Self {
            stiffness_nm_per_rad: stiffness_nm_per_rad.to_vec(),
            damping_nms_per_rad: damping,
        }
    }
}

/// How the joints hold their commanded values.
#[derive(Clone, Debug, PartialEq)]
pub enum Compliance {
    /// Infinitely stiff servos: the arm sits exactly at the command (kinematic mode).
    Rigid,
    /// Finite servo stiffness under gravity: the arm sags to its static equilibrium.
    Servo(ServoGains),
}

/// Time step, solver and stopping rule of the static-equilibrium solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SettleOptions {
    /// Time step \[s\].
    pub dt_s: f64,
    /// rapier solver iterations per step.
    pub solver_iterations: usize,
    /// Give up after this many steps.
    pub max_steps: usize,
    /// At rest when every watched point moves slower than this \[m/s\] ...
    pub speed_tolerance_m_s: f64,
    /// ... for this many consecutive steps, or (the decay rule, [`SettleOptions::decay_steps`])
    /// earlier, when the motion left is known to be smaller than
    /// [`SettleOptions::distance_left_m`].
    pub quiet_steps: usize,
    /// The decay rule: the stepping also ends when, for this many consecutive quiet steps,
    /// every watched point kept moving the same way by less each step and the geometric tail
    /// of its steps is below [`SettleOptions::distance_left_m`] (0: off, only the
    /// `quiet_steps` rule; see [`SimArm::settle_with`]).
    pub decay_steps: usize,
    /// Bound on the distance every watched point has left to go when the decay rule ends the
    /// stepping \[m\].
    pub distance_left_m: f64,
    /// Start the compliant arm from the static equilibrium the analytic model predicts
    /// (`physics::coupled_static_deflection`: the joints' springs against gravity and payload,
    /// sags carried through the couplings) instead of the undeflected command, so the time
    /// stepping only confirms it (what the prediction leaves out, e.g. the four-bar bars' own
    /// weight, settles in a few steps).
    pub warm_start: bool,
    /// Before the settle proper, approach the equilibrium with this many steps at most of
    /// length [`SettleOptions::approach_dt_s`] (0: no approach). See [`SimArm::settle_with`].
    pub approach_max_steps: usize,
    /// Length of an approach step \[s\]: much longer than the servos' time constants, so
    /// rapier's backward-Euler step of the implicit springs and damping lands near the static
    /// equilibrium in each step instead of following the motion.
    pub approach_dt_s: f64,
    /// Leaps of the approach, at most, to the rest its decaying steps predict (0: none); see
    /// [`SimArm::settle_with`].
    pub approach_leaps: usize,
    /// A leap needs every watched point's last two step ratios to agree within this share of
    /// `r (1 - r)`: the geometric tail's relative error, to first order.
    pub leap_ratio_spread: f64,
    /// Share `f` of the predicted tail a leap covers; the velocity keeps `1 - f`.
    pub leap_fraction: f64,
}

impl Default for SettleOptions {
    /// 1 ms steps, 8 solver iterations, 1 micrometre per second for 20 steps, at most 20 s,
    /// warm start on, an approach of at most 50 steps of 10 ms; the decay rule over 2 steps
    /// with 20 nm left, the distance the 20 quiet steps let a point creep (20 steps of less
    /// than `1 um/s * 1 ms`).
    ///
    /// The solver iterations are rapier's substeps (each rebuilds the multibody's mass
    /// matrix, most of a step's cost). 8 instead of the former 16 halve a step: the rest they
    /// find lies as close to that of pure 1 ms stepping with 16 from the undeflected command as
    /// the rest with 16 does (`tests/it/rapier_arm.rs`, 36 settles of three stiffness sets,
    /// payloads, poses, four-bar bodies and emulated: largest tool difference 3.5e-8 m with 8,
    /// 3.8e-8 m with 16); with 4 it was 8.4e-8 m, a shift of the four-bar's rest (the loop
    /// closure's constraint stabilisation depends on the substep length).
    ///
    /// The approach's step: on the paper arm of the `compliance` scenario (stiffnesses 2e4-5e5
    /// N m/rad, 10 kg payload, four-bar bodies and gear, 8 poses) the approach took 13-17
    /// steps of 10 ms and the settle proper then the bare 20 quiet steps (36 in all, against
    /// 130-138 from the warm start alone); steps of 5 ms took 24-30 approach steps, steps of
    /// 20 ms left a rest that the 1 ms steps moved away from again (20-36 steps after 10
    /// approach steps; the loop closure's constraint stabilisation depends on the step
    /// length), and steps of 200 ms 90-120.
    ///
    /// The leaps (at most 4, ratios steady to 0.05 of `r (1 - r)`, 0.9 of the tail): on the
    /// first 40 cases of `blind --seed 2 --sim rapier`, the five joint-compliance cases (the
    /// approach's 10 ms steps decaying by a steady ratio of about 0.75, an overdamped slow
    /// mode) took 22.6 steps a pose instead of 37.4 (approach 17.1 instead of 27.9); the four
    /// with backlash too 31.7 instead of 33.9. Leaping the whole tail and stopping the arm
    /// (`f = 1`) took 25.8: from rest the slow mode builds up again for 2-3 steps, which the
    /// velocity's remaining tenth avoids; a looser steadiness (0.1, 0.2) leapt on ratios still
    /// falling towards the slow mode's (the tail overestimated) and took 23.8 and 26.2. The
    /// `compliance` scenario's arm (10 kg payload: its lightly damped modes reverse the steps)
    /// never leaps.
    fn default() -> Self {
        Self {
            dt_s: 1e-3,
            solver_iterations: 8,
            max_steps: 20_000,
            speed_tolerance_m_s: 1e-6,
            quiet_steps: 20,
            decay_steps: 2,
            distance_left_m: 2e-8,
            warm_start: true,
            approach_max_steps: 50,
            approach_dt_s: 0.01,
            approach_leaps: 4,
            leap_ratio_spread: 0.05,
            leap_fraction: 0.9,
        }
    }
}

/// A stopping rule of [`SimArm::step_until_quiet`].
struct Quiet {
    max_steps: usize,
    /// A step moving every watched point by less than this \[m\] is quiet.
    distance_m: f64,
    /// Consecutive quiet steps that end the stepping.
    steps: usize,
    /// The decay rule (`None`: off): consecutive decaying quiet steps and the bound on the
    /// geometric tail \[m\] that end the stepping.
    decay: Option<(usize, f64)>,
    /// Leaps to the predicted rest allowed ([`SettleOptions::approach_leaps`]).
    leaps: usize,
    /// [`SettleOptions::leap_ratio_spread`].
    leap_ratio_spread: f64,
    /// [`SettleOptions::leap_fraction`].
    leap_fraction: f64,
}

/// How the stepping ended.
struct Stop {
    /// Steps taken.
    steps: usize,
    /// Largest move of a watched point in the last step \[m\].
    last_move_m: f64,
    /// Whether a rule ended it (not the step cap).
    quiet: bool,
    /// The decay rule's bound on the distance left, when that rule ended it \[m\].
    distance_left_m: Option<f64>,
}

/// One watched point's last two step displacements (the decay rule of
/// [`SimArm::settle_with`]).
struct Track {
    at: Point3<f64>,
    last: Vector3<f64>,
    ratios: [f64; 2],
}

impl Track {
    fn new(at: Point3<f64>) -> Self {
        Self {
            at,
            last: Vector3::zeros(),
            ratios: [f64::INFINITY; 2],
        }
    }

    /// Moves to `now`: the length of the step \[m\].
    fn advance(&mut self, now: Point3<f64>) -> f64 {
        let d = now - self.at;
        let ratio = if d.dot(&self.last) > 0.0 {
            d.norm() / self.last.norm()
        } else {
            f64::INFINITY
        };
        self.ratios = [self.ratios[1], ratio];
        self.at = now;
        self.last = d;
        d.norm()
    }

    /// The geometric tail as a displacement, `d r / (1 - r)` with `r` the last ratio, if the
    /// last two steps decayed (the approach's leap, [`SettleOptions::approach_leaps`]) \[m\].
    /// None unless the ratio is steady: `|r_n - r_{n-1}| <= spread r (1 - r)`, the tail's
    /// relative error (`dr / (r (1 - r))` to first order) below `spread`.
    fn tail_ahead_m(&self, spread: f64) -> Option<Vector3<f64>> {
        let r = self.ratios[1];
        let steady = (r - self.ratios[0]).abs() <= spread * r * (1.0 - r);
        (self.ratios[0] < 1.0 && r < 1.0 && steady).then(|| self.last * (r / (1.0 - r)))
    }

    /// The geometric tail `|d| r / (1 - r)` with `r` the larger of the last two ratios, if
    /// the last step decayed (same direction, shorter) \[m\].
    fn tail_m(&self) -> Option<f64> {
        let r = self.ratios[1];
        (r < 1.0).then(|| {
            let r = r.max(self.ratios[0]).min(1.0);
            self.last.norm() * r / (1.0 - r)
        })
    }
}

/// The outcome of a settle.
#[derive(Clone, Debug, PartialEq)]
pub struct SettleReport {
    /// Steps of length [`SettleOptions::dt_s`] taken (the settle proper).
    pub steps: usize,
    /// Approach steps taken before them ([`SettleOptions::approach_max_steps`]).
    pub approach_steps: usize,
    /// Speed of the fastest watched point at the last step \[m/s\].
    pub max_speed_m_s: f64,
    /// When the decay rule ended the settle: its bound on the distance any watched point had
    /// left to go \[m\] (`None`: the `quiet_steps` rule ended it, or no settle was needed).
    pub distance_left_m: Option<f64>,
    /// The joint values at rest (rad or m).
    pub joint_positions: Vec<f64>,
}

/// The settles of a series of poses, summed up: what a dynamic-mode campaign cost and how
/// still it ended (a trial's `settle_*` metrics).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SettleTally {
    /// Poses settled.
    pub poses: usize,
    /// Steps of all of them, approach steps included.
    pub steps: usize,
    /// The most steps one pose took, approach steps included.
    pub max_steps: usize,
    /// The largest speed of a watched point at the end of a settle \[m/s\].
    pub max_speed_m_s: f64,
}

impl SettleReport {
    /// Every step the settle took: the approach's and the settle proper's.
    pub fn total_steps(&self) -> usize {
        self.steps + self.approach_steps
    }
}

impl SettleTally {
    /// Adds one pose's settle.
    pub fn add(&mut self, report: &SettleReport) {
        let steps = report.total_steps();
        self.poses += 1;
        self.steps += steps;
        self.max_steps = self.max_steps.max(steps);
        self.max_speed_m_s = self.max_speed_m_s.max(report.max_speed_m_s);
    }

    /// Mean steps per pose (0 with no pose).
    pub fn mean_steps(&self) -> f64 {
        if self.poses == 0 {
            0.0
        } else {
            self.steps as f64 / self.poses as f64
        }
    }
}

impl SimArm {
    /// Puts every joint's servo (implicit spring and damping, module docs) on `q_cmd` with the
    /// given gains.
    pub fn set_servo(&mut self, q_cmd: &[f64], gains: &ServoGains) -> Result<(), SimError> {
        let n = self.model.dof();
        check_len("commanded joint values", n, q_cmd.len())?;
        check_len("servo stiffness", n, gains.stiffness_nm_per_rad.len())?;
        check_len("servo damping", n, gains.damping_nms_per_rad.len())?;
        for (k, (&stiffness, &damping)) in gains
            .stiffness_nm_per_rad
            .iter()
            .zip(&gains.damping_nms_per_rad)
            .enumerate()
        {
            check_positive("servo stiffness", k, stiffness)?;
            if !(damping.is_finite() && damping >= 0.0) {
                return Err(SimError::NotPositive {
                    what: "servo damping",
                    joint: k,
                    value: damping,
                });
            }
        }
        for (k, ((&target, &stiffness), &damping)) in q_cmd
            .iter()
            .zip(&gains.stiffness_nm_per_rad)
            .zip(&gains.damping_nms_per_rad)
            .enumerate()
        {
            self.set_joint_servo(k, target, stiffness, damping)?;
        }
        Ok(())
    }

    /// Sets one joint's (0-based) servo: implicit spring of stiffness `K` \[N m/rad\] towards
    /// `target` and damping `D` \[N m s/rad\]; `K = D = 0` makes the joint passive (e.g. driven
    /// by a four-bar).
    pub fn set_joint_servo(
        &mut self,
        k: usize,
        target: f64,
        stiffness_nm_per_rad: f64,
        damping_nms_per_rad: f64,
    ) -> Result<(), SimError> {
        let axis = match self.model.joints.get(k).map(|j| j.kind) {
            Some(crate::kinematics::JointKind::Revolute) => JointAxis::AngX,
            Some(crate::kinematics::JointKind::Prismatic) => JointAxis::LinX,
            None => return Err(SimError::JointRejected { joint: k }),
        };
        let handle = self.joints[k];
        set_joint_spring(
            &mut self.world,
            handle,
            axis,
            target,
            stiffness_nm_per_rad,
            damping_nms_per_rad,
        )
        .ok_or(SimError::JointRejected { joint: k })
    }

    /// Moves joint `k`'s servo target, keeping its gains (a per-step coupling such as the
    /// bevel gear sets it every step).
    pub fn set_joint_servo_target(&mut self, k: usize, target: f64) -> Result<(), SimError> {
        let axis = match self.model.joints.get(k).map(|j| j.kind) {
            Some(crate::kinematics::JointKind::Revolute) => 3,
            Some(crate::kinematics::JointKind::Prismatic) => 0,
            None => return Err(SimError::JointRejected { joint: k }),
        };
        let (mb, id) = self
            .world
            .multibody_joints
            .get_mut(self.joints[k])
            .ok_or(SimError::JointRejected { joint: k })?;
        let link = mb.link_mut(id).ok_or(SimError::JointRejected { joint: k })?;
        let (stiffness, _) = link.joint.spring(axis);
        link.joint.set_spring(axis, stiffness, target);
        Ok(())
    }

    /// Steps the dynamics until every watched point (the tool-frame origin and `watch`) moves
    /// slower than `options.speed_tolerance_m_s` for `options.quiet_steps` steps in a row.
    pub fn settle(&mut self, watch: &[LinkPoint], options: &SettleOptions) -> Result<SettleReport, SimError> {
        self.settle_with(watch, options, |_| Ok(()))
    }

    /// [`SimArm::settle`] calling `before_step` before every step (e.g. to move a servo target
    /// that depends on the current joint values, as the bevel gear does).
    ///
    /// With an approach ([`SettleOptions::approach_max_steps`] > 0) the arm first takes steps
    /// of [`SettleOptions::approach_dt_s`] until one moves every watched point by less than
    /// the settle's own stopping distance (`speed_tolerance_m_s * dt_s`), or, with the decay
    /// rule on, until its steps move less than `speed_tolerance_m_s * approach_dt_s` and decay
    /// (below). rapier integrates the servo springs and damping
    /// backward-Euler, which is L-stable: a step much longer than the servos' time constants
    /// maps the arm close to the static equilibrium of the springs, gravity and the
    /// constraints (a joint of time constant `tau` keeps about `tau / dt` of its distance per
    /// step), rather than following its motion. The approach only chooses where the settle
    /// proper starts: that is the same stepping at `dt_s` (and `solver_iterations`) as
    /// without it, so the rest it reports is rapier's at the settle's time step, and what the
    /// approach left (a velocity, a constraint error of the long steps) settles there. The
    /// settle proper ends after `quiet_steps` quiet steps or, earlier, by the decay rule, with
    /// its bound on the distance left in [`SettleReport::distance_left_m`].
    ///
    /// The decay rule: near rest the stepping is linear, `s_{n+1} = A s_n`, and once its
    /// slowest mode dominates (a real eigenvalue `0 < r < 1`: the servos are critically
    /// damped or more, and backward Euler keeps such modes real) every point's step
    /// displacement is `d_{n+1} = r d_n`, so the distance it has left is the geometric tail
    /// `|d_n| r / (1 - r)`. A step *decays* for a point when its displacement keeps the
    /// direction of the previous one (`d_n . d_{n-1} > 0`) and shrinks (`r_n = |d_n| /
    /// |d_{n-1}| < 1`); the rule ends the stepping after [`SettleOptions::decay_steps`]
    /// consecutive quiet steps that decay for every watched point with
    /// `|d_n| r / (1 - r) <` [`SettleOptions::distance_left_m`], `r` the larger of the point's
    /// last two ratios. A turning point (the velocity through zero, the displacement
    /// reversing) or a growing mode breaks the run: quiet steps alone do not prove rest there.
    ///
    /// The approach's leaps ([`SettleOptions::approach_leaps`]): when the approach's steps
    /// decay by a steady ratio the same geometric tail predicts the rest, and the arm is moved
    /// most of the way there along its current motion (`SimArm::leap`, Aitken's
    /// extrapolation), then stepped on: a leap only chooses where the following steps start,
    /// and the settle proper confirms the rest as without it.
    ///
    /// Why the approach keeps the settle's solver iterations (rapier's substeps): the rest
    /// of the arm with the four-bar's bodies depends on the substep length (the loop
    /// closure's constraint stabilisation), so an approach of fewer, longer substeps lands
    /// where the 1 ms steps move away from again (measured: 10 ms approach steps of 4 substeps
    /// instead of 16 cost more substeps in all, the settle proper taking up to 303 steps
    /// instead of 63); likewise a quasi-static approach (velocities zeroed before every long
    /// step, a Newton-like iteration that converged in 3-5 steps) found a rest 88-956 steps of
    /// 1 ms away from rapier's.
    pub fn settle_with(
        &mut self,
        watch: &[LinkPoint],
        options: &SettleOptions,
        mut before_step: impl FnMut(&mut SimArm) -> Result<(), SimError>,
    ) -> Result<SettleReport, SimError> {
        let mut points: Vec<LinkPoint> = watch.to_vec();
        let last = self.model.dof() - 1;
        points.push(LinkPoint {
            link: last,
            position_in_link_m: self.model.last_link_from_tool * Point3::origin(),
        });
        self.world.integration_parameters.num_solver_iterations = options.solver_iterations;
        let stop_distance_m = options.speed_tolerance_m_s * options.dt_s;
        let decay = (options.decay_steps > 0).then_some((options.decay_steps, options.distance_left_m));
        let mut approach_steps = 0;
        if options.approach_max_steps > 0 {
            self.world.integration_parameters.dt = options.approach_dt_s;
            let approach = match decay {
                // The approach hands over to the settle proper once its own steps decay.
                Some(_) => Quiet {
                    max_steps: options.approach_max_steps,
                    distance_m: options.speed_tolerance_m_s * options.approach_dt_s,
                    steps: usize::MAX,
                    decay,
                    leaps: options.approach_leaps,
                    leap_ratio_spread: options.leap_ratio_spread,
                    leap_fraction: options.leap_fraction,
                },
                None => Quiet {
                    max_steps: options.approach_max_steps,
                    distance_m: stop_distance_m,
                    steps: 1,
                    decay: None,
                    leaps: options.approach_leaps,
                    leap_ratio_spread: options.leap_ratio_spread,
                    leap_fraction: options.leap_fraction,
                },
            };
            approach_steps = self.step_until_quiet(&points, &approach, &mut before_step)?.steps;
        }
        self.world.integration_parameters.dt = options.dt_s;
        let settle = Quiet {
            max_steps: options.max_steps,
            distance_m: stop_distance_m,
            steps: options.quiet_steps,
            decay,
            leaps: 0,
            leap_ratio_spread: options.leap_ratio_spread,
            leap_fraction: options.leap_fraction,
        };
        let stop = self.step_until_quiet(&points, &settle, &mut before_step)?;
        let max_speed_m_s = stop.last_move_m / options.dt_s;
        if !stop.quiet {
            return Err(SimError::NotSettled {
                steps: options.max_steps,
                max_speed_m_s,
            });
        }
        Ok(SettleReport {
            steps: stop.steps,
            approach_steps,
            max_speed_m_s,
            distance_left_m: stop.distance_left_m,
            joint_positions: self.joint_positions(),
        })
    }

    /// Steps (`before_step` before each) until the watched `points` have moved less than
    /// `rule.distance_m` in `rule.steps` consecutive steps, or the decay rule of
    /// [`SimArm::settle_with`] holds (`rule.decay = (k, bound)`), or `rule.max_steps` were
    /// taken.
    fn step_until_quiet(
        &mut self,
        points: &[LinkPoint],
        rule: &Quiet,
        before_step: &mut impl FnMut(&mut SimArm) -> Result<(), SimError>,
    ) -> Result<Stop, SimError> {
        let mut tracks: Vec<Track> = points.iter().map(|p| Track::new(self.point_in_world(p))).collect();
        let (mut quiet, mut decaying, mut leaps) = (0, 0, 0);
        let mut last_move_m = f64::INFINITY;
        for step in 1..=rule.max_steps {
            before_step(self)?;
            self.world.step();
            last_move_m = 0.0;
            let mut decays = true;
            let mut left_m: f64 = 0.0;
            for (p, track) in points.iter().zip(tracks.iter_mut()) {
                let moved = track.advance(self.point_in_world(p));
                last_move_m = last_move_m.max(moved);
                match track.tail_m() {
                    Some(tail) => left_m = left_m.max(tail),
                    None => decays = false,
                }
            }
            let is_quiet = last_move_m < rule.distance_m;
            quiet = if is_quiet { quiet + 1 } else { 0 };
            decaying = if is_quiet && decays { decaying + 1 } else { 0 };
            if quiet >= rule.steps {
                return Ok(Stop {
                    steps: step,
                    last_move_m,
                    quiet: true,
                    distance_left_m: None,
                });
            }
            if let Some((k, bound_m)) = rule.decay
                && decaying >= k
                && left_m < bound_m
            {
                return Ok(Stop {
                    steps: step,
                    last_move_m,
                    quiet: true,
                    distance_left_m: Some(left_m),
                });
            }
            if leaps < rule.leaps && self.leap(points, &tracks, rule)? {
                leaps += 1;
                tracks = points.iter().map(|p| Track::new(self.point_in_world(p))).collect();
                (quiet, decaying) = (0, 0);
            }
        }
        Ok(Stop {
            steps: rule.max_steps,
            last_move_m,
            quiet: false,
            distance_left_m: None,
        })
    }

    /// The approach's leap: once every watched point's last two steps decayed by a steady
    /// ratio, the arm is moved along its current motion towards where the geometric tails of
    /// those steps put its rest (Aitken's extrapolation of a geometric sequence: a point's
    /// remaining displacement is `d r / (1 - r)`, [`SimArm::settle_with`]). The move is the
    /// generalised velocity times `f t`, `t` the duration that best maps the points' velocities
    /// `v_i` onto their tails `e_i` (least squares, `t = sum v_i . e_i / sum |v_i|^2`) and `f`
    /// [`SettleOptions::leap_fraction`]; the velocity keeps its share `1 - f`, so the state
    /// stays on the line of the slow mode it extrapolates. Returns whether it leapt (not when a
    /// point's ratio is not steady or the motion does not lead towards the tails, `t <= 0`).
    fn leap(&mut self, points: &[LinkPoint], tracks: &[Track], rule: &Quiet) -> Result<bool, SimError> {
        let (mut along, mut norm) = (0.0, 0.0);
        for (p, track) in points.iter().zip(tracks) {
            let Some(tail) = track.tail_ahead_m(rule.leap_ratio_spread) else {
                return Ok(false);
            };
            let v = self.point_velocity(p);
            along += v.dot(&tail);
            norm += v.norm_squared();
        }
        let duration_s = along / norm;
        if !(duration_s > 0.0 && duration_s.is_finite()) {
            return Ok(false);
        }
        self.coast(rule.leap_fraction * duration_s, 1.0 - rule.leap_fraction)?;
        Ok(true)
    }

    /// The static equilibrium at command `q_cmd`: with [`Compliance::Rigid`] the arm is placed
    /// at `q_cmd` (kinematic mode); with [`Compliance::Servo`] it starts at rest at `q_cmd`, the
    /// servos hold it against gravity, and it is stepped until it settles.
    pub fn static_equilibrium(
        &mut self,
        q_cmd: &[f64],
        compliance: &Compliance,
        watch: &[LinkPoint],
        options: &SettleOptions,
    ) -> Result<SettleReport, SimError> {
        self.set_joint_positions(q_cmd)?;
        match compliance {
            Compliance::Rigid => Ok(SettleReport {
                steps: 0,
                approach_steps: 0,
                max_speed_m_s: 0.0,
                distance_left_m: None,
                joint_positions: self.joint_positions(),
            }),
            Compliance::Servo(gains) => {
                self.set_servo(q_cmd, gains)?;
                self.settle(watch, options)
            }
        }
    }
}

/// Puts an implicit spring (`stiffness` towards `target`) and implicit damping on the free
/// `axis` of a multibody joint, and takes the axis out of rapier's motor mask (module docs).
/// `None` if the handle is not in the world.
pub(super) fn set_joint_spring(
    world: &mut PhysicsWorld,
    handle: MultibodyJointHandle,
    axis: JointAxis,
    target: f64,
    stiffness: f64,
    damping: f64,
) -> Option<()> {
    let (mb, id) = world.multibody_joints.get_mut(handle)?;
    let link = mb.link_mut(id)?;
    let dof = link.assembly_id();
    let index = axis as usize;
    link.joint.data.motor_axes.remove(axis.into());
    link.joint.set_spring(index, stiffness, target);
    *mb.damping_mut().get_mut(dof)? = damping;
    Some(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::RobotDescription;
    use crate::sim::ArmOptions;
    use nalgebra::Vector3;

    /// First-order static sag of the tool-frame origin: `dq = K^-1 Q(q)` with the gravity
    /// generalised force `Q_j = sum_{i >= j} m_i g . (z_j x (c_i - o_j))`, then
    /// `dp = sum_j dq_j z_j x (p - o_j)`.
    fn analytic_tool_sag_m(arm: &SimArm, q: &[f64], stiffness: &[f64], payload_kg: f64) -> Vector3<f64> {
        let model = arm.model();
        let poses = model.poses(q);
        let g = Vector3::new(0.0, 0.0, -9.81);
        let tool = poses.world_from_tool * Point3::origin();
        let mut masses: Vec<(usize, f64, Point3<f64>)> = arm
            .inertias()
            .iter()
            .enumerate()
            .map(|(i, li)| (i, li.mass_kg, poses.world_from_link[i] * li.com_in_link_m))
            .collect();
        masses.push((model.dof() - 1, payload_kg, tool));
        (0..model.dof())
            .map(|j| {
                let axis = poses.axis(j);
                let z = axis.direction.into_inner();
                let q_j: f64 = masses
                    .iter()
                    .filter(|(i, _, _)| *i >= j)
                    .map(|(_, m, c)| (g * *m).dot(&z.cross(&(c - axis.origin_m))))
                    .sum();
                (q_j / stiffness[j]) * z.cross(&(tool - axis.origin_m))
            })
            .sum()
    }

    fn sag_error(compliant_joint: usize, payload_kg: f64) -> (f64, f64) {
        let d = RobotDescription::asea_irb6l();
        let options = ArmOptions {
            payload_kg,
            ..ArmOptions::new(6)
        };
        let mut arm = SimArm::from_description(&d.nominal_model(), &d, &options).expect("valid arm");
        let q = [0.0; 6];
        let mut stiffness = [1e8; 6];
        stiffness[compliant_joint] = 2e5;
        let gains = ServoGains::with_damping_ratio(&arm, &q, &stiffness, 1.0);
        let rigid_tool = arm.model().world_from_tool(&q) * Point3::origin();
        let report = arm
            .static_equilibrium(&q, &Compliance::Servo(gains), &[], &SettleOptions::default())
            .expect("settles");
        assert!(report.steps < 5000, "{report:?}");
        let sim = arm.world_from_tool() * Point3::origin() - rigid_tool;
        let analytic = analytic_tool_sag_m(&arm, &q, &stiffness, payload_kg);
        ((sim - analytic).norm() / analytic.norm(), analytic.norm())
    }

    /// Link 3 horizontal along +y at q = 0: the sag from a compliant joint 3 (or 2) matches
    /// the first-order estimate within 2 % (its own error is about the sag angle, 5e-4).
    #[test]
    fn static_sag_matches_the_joint_stiffness_estimate() {
        for (joint, payload_kg) in [(2, 0.0), (1, 0.0), (2, 5.0)] {
            let (relative, sag_m) = sag_error(joint, payload_kg);
            eprintln!(
                "joint {} payload {payload_kg}: sag {:.4} mm, relative error {relative:.2e}",
                joint + 1,
                sag_m * 1e3
            );
            assert!(relative < 0.02, "joint {}: relative error {relative}", joint + 1);
        }
    }

    #[test]
    fn rigid_compliance_is_kinematic_mode() {
        let d = RobotDescription::asea_irb6l();
        let mut arm = SimArm::from_description(&d.nominal_model(), &d, &ArmOptions::new(6)).expect("valid arm");
        let q = [0.1, -0.2, 0.3, 0.4, -0.5, 0.6];
        let report = arm
            .static_equilibrium(&q, &Compliance::Rigid, &[], &SettleOptions::default())
            .expect("rigid");
        assert_eq!(report.steps, 0);
        let p = arm.world_from_tool().translation.vector - arm.model().world_from_tool(&q).translation.vector;
        assert!(p.norm() < 1e-12);
    }

    #[test]
    fn a_too_short_settle_reports_not_settled() {
        let d = RobotDescription::asea_irb6l();
        let mut arm = SimArm::from_description(&d.nominal_model(), &d, &ArmOptions::new(6)).expect("valid arm");
        let q = [0.0; 6];
        let gains = ServoGains::with_damping_ratio(&arm, &q, &[2e5; 6], 1.0);
        // Two steps: too few for either rule (the decay rule needs two decaying steps after a
        // first one, the quiet rule 20 quiet steps).
        let options = SettleOptions {
            max_steps: 2,
            ..SettleOptions::default()
        };
        let err = arm.static_equilibrium(&q, &Compliance::Servo(gains), &[], &options);
        assert!(matches!(err, Err(SimError::NotSettled { steps: 2, .. })), "{err:?}");
    }

    /// Same inputs, same machine: bit-identical equilibrium (rapier is deterministic).
    #[test]
    fn settling_twice_is_bit_identical() {
        let run = || {
            let d = RobotDescription::asea_irb6l();
            let mut arm = SimArm::from_description(&d.nominal_model(), &d, &ArmOptions::new(6)).expect("valid arm");
            let q = [0.2, 0.1, -0.3, 0.5, 0.4, -0.2];
            let gains = ServoGains::with_damping_ratio(&arm, &q, &[3e5; 6], 1.0);
            arm.static_equilibrium(&q, &Compliance::Servo(gains), &[], &SettleOptions::default())
                .expect("settles")
        };
        let (a, b) = (run(), run());
        assert_eq!(a.steps, b.steps);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&a.joint_positions), bits(&b.joint_positions));
    }
}
