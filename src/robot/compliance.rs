//! A joint's compliance in the form the diagnosis names it (`docs/diagnosis.md`, "Candidate
//! families"), carried into a model (`calibration.json`'s `robot.effects.compliance`,
//! `calibrate --carry`): the spring's site, whether the mechanism the joint drives reflects the
//! driven joint's load back to it, and the gravity load it carries as link masses and first
//! moments times its compliance (what the data identify: the product, not the mass or the
//! stiffness alone). Its sag at a pose is the static equilibrium of that spring at unit stiffness
//! under that load ([`crate::physics::coupled_static_deflection`]), gravity `-z` of the
//! instrument frame.

use super::{CouplingFunction, RobotModel};
use crate::kinematics::PhiModel;
use crate::physics::{
    ComplianceEffect, CompliantLoad, LinkMass, PassiveSlope, STANDARD_GRAVITY_M_S2, coupled_static_deflection,
};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// Where a compliant joint's spring sits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SpringSite {
    /// In the actuator (motor and gear): its sag drives the passive coupling into the next
    /// joint like any active motion, and a mechanism coupling (four-bar) carries the next
    /// joint's load back to it (the rapier arm's physics).
    Actuator,
    /// In the joint itself (the output side): the joint bends under the gravity torque about
    /// it and nothing else follows. Differs from `Actuator` only on a joint that drives a
    /// coupling.
    Joint,
}

/// One link's gravity load times a compliance: its mass and its first moment (mass times the
/// centre of mass, in the link's moving frame). For a payload's, per kg of payload, the first
/// moment in the last link's frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LoadProduct {
    /// Mass times compliance \[kg rad/(N m)\] (a payload's: \[rad/(N m)\] per kg).
    pub mass_kg_rad_per_nm: f64,
    /// First moment times compliance \[kg m rad/(N m)\] (a payload's: \[m rad/(N m)\] per kg).
    pub first_moment_kg_m_rad_per_nm: [f64; 3],
}

impl LoadProduct {
    /// As a [`LinkMass`] (at unit stiffness the sag of this load is the compliant sag).
    fn link_mass(&self) -> LinkMass {
        LinkMass {
            mass_kg: self.mass_kg_rad_per_nm,
            first_moment_kg_m: Vector3::from(self.first_moment_kg_m_rad_per_nm),
        }
    }

    /// From a [`LinkMass`] of products.
    pub fn of(m: &LinkMass) -> Self {
        LoadProduct {
            mass_kg_rad_per_nm: m.mass_kg,
            first_moment_kg_m_rad_per_nm: m.first_moment_kg_m.into(),
        }
    }
}

/// A load of the spring: every link's product and the payload's per kg.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SpringLoad {
    /// Per link, base first.
    pub links: Vec<LoadProduct>,
    /// The payload's, per kg (the pose's `payload_kg` times it joins the last link's).
    pub payload: LoadProduct,
}

impl SpringLoad {
    /// Its links' products at a pose carrying `payload_kg` (the payload folded into the last
    /// link).
    pub fn at(&self, payload_kg: f64) -> Vec<LinkMass> {
        let mut loads: Vec<LinkMass> = self.links.iter().map(LoadProduct::link_mass).collect();
        if let Some(last) = loads.last_mut() {
            let p = self.payload.link_mass();
            last.mass_kg += p.mass_kg * payload_kg;
            last.first_moment_kg_m += p.first_moment_kg_m * payload_kg;
        }
        loads
    }
}

/// A named joint compliance (module docs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ComplianceTerm {
    /// The compliant joint (1-based).
    pub joint: usize,
    /// Where its spring sits.
    pub spring: SpringSite,
    /// Whether the mechanism the joint drives (a fractional or four-bar coupling into the next
    /// joint) carries that joint's load back to the spring by virtual work: the mechanism and
    /// mixed load paths; `false`: the serial path (the actuator carries the chain beyond it).
    pub reflects_load: bool,
    /// The load the spring carries.
    pub carried: SpringLoad,
    /// The load the mechanism reflects (a mixed path's own products); absent: `carried`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reflected: Option<SpringLoad>,
}

impl ComplianceTerm {
    /// The couplings' slopes at the active displacements `active` as this spring sees them: a
    /// spring in the joint drives nothing and has nothing reflected to it; on the serial path
    /// the mechanism it drives reflects nothing; the fractional (eq. 15) and four-bar forms are
    /// mechanisms, a gear is kinematic only.
    pub fn couplings(&self, robot: &RobotModel, active: &[f64]) -> Vec<PassiveSlope> {
        let mut couplings = PassiveSlope::of_robot(robot, active, |_, g| {
            matches!(g, CouplingFunction::Fractional { .. } | CouplingFunction::FourBar(_))
        });
        if let Some(out) = couplings.get_mut(self.joint) {
            match self.spring {
                SpringSite::Joint => *out = PassiveSlope::default(),
                SpringSite::Actuator if !self.reflects_load => out.reflects_load = false,
                SpringSite::Actuator => {}
            }
        }
        couplings
    }

    /// Unit stiffness at its joint, the others rigid.
    pub fn unit_compliance(&self, n: usize) -> ComplianceEffect {
        let mut stiffness_nm_per_rad = vec![f64::INFINITY; n];
        stiffness_nm_per_rad[self.joint - 1] = 1.0;
        ComplianceEffect::new(stiffness_nm_per_rad, STANDARD_GRAVITY_M_S2)
    }

    /// The joints' sag at joint values `q` (before it; `active` their active displacements)
    /// on the chain `phi`, a pose carrying `payload_kg`; `None` when no equilibrium is found
    /// (the arm would buckle).
    pub fn deflection(
        &self,
        robot: &RobotModel,
        phi: &PhiModel,
        q: &[f64],
        active: &[f64],
        payload_kg: f64,
    ) -> Option<Vec<f64>> {
        let compliance = self.unit_compliance(q.len());
        let couplings = self.couplings(robot, active);
        self.with_load(payload_kg, &compliance, &couplings, |load| {
            coupled_static_deflection(phi, q, load).ok()
        })
    }

    /// Calls `f` with its load at a pose carrying `payload_kg` under `compliance` through
    /// `couplings` ([`Self::unit_compliance`], [`Self::couplings`]).
    pub fn with_load<R>(
        &self,
        payload_kg: f64,
        compliance: &ComplianceEffect,
        couplings: &[PassiveSlope],
        f: impl FnOnce(&CompliantLoad) -> R,
    ) -> R {
        let carried = self.carried.at(payload_kg);
        let reflected = self.reflected.as_ref().map(|r| r.at(payload_kg));
        f(&CompliantLoad {
            masses: &carried,
            payload: None,
            compliance,
            couplings,
            reflected_masses: reflected.as_deref(),
        })
    }

    /// Checks the joint and the load lists against a model of `n` joints and the values'
    /// finiteness: the offending field (`effects.compliance[0].carried.links`) and why.
    pub fn validate(&self, n: usize, field: &str) -> Result<(), (String, String)> {
        if !(1..=n).contains(&self.joint) {
            return Err((
                format!("{field}.joint"),
                format!("must be in 1..={n}, found {}", self.joint),
            ));
        }
        for (name, load) in
            std::iter::once(("carried", &self.carried)).chain(self.reflected.iter().map(|r| ("reflected", r)))
        {
            if load.links.len() != n {
                return Err((
                    format!("{field}.{name}.links"),
                    format!("must hold {n} entries (one a link), found {}", load.links.len()),
                ));
            }
            let finite = |p: &LoadProduct| {
                p.mass_kg_rad_per_nm.is_finite() && p.first_moment_kg_m_rad_per_nm.iter().all(|v| v.is_finite())
            };
            if !load.links.iter().all(finite) || !finite(&load.payload) {
                return Err((format!("{field}.{name}"), "must be finite".into()));
            }
        }
        Ok(())
    }
}
