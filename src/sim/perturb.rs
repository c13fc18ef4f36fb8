//! Random perturbation of a nominal robot into a [`RobotModel`] for Monte-Carlo studies.
//!
//! A [`PerturbationSpec`] (TOML, `deny_unknown_fields`, units in key names) gives a
//! distribution ([`Spread`]) per kind of quantity; every instance of that quantity is drawn
//! independently. Absent keys leave the quantity nominal and draw nothing. Draws happen in a
//! fixed order (rows, placement, offsets, transmissions, coupling harmonics, four-bar), so a
//! seeded rng gives the same robot every time.

use crate::kinematics::JointKind;
use crate::robot::{
    CouplingFunction, FourBarGeometry, FourBarLinkage, ModelError, RobotDescription, RobotModel, Transmission,
    TransmissionFitForm,
};
use rand::{Rng, RngExt};
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};

/// A zero-mean distribution of one perturbation, in the unit its key names.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Spread {
    /// Gaussian, standard deviation `sigma`.
    Normal {
        /// Standard deviation.
        sigma: f64,
    },
    /// Uniform on `[-half_width, half_width]`.
    Uniform {
        /// Half the support width.
        half_width: f64,
    },
    /// Gaussian of standard deviation `sigma` restricted to `[-limit, limit]`, drawn by
    /// rejection (redraw until inside): exact, and cheap while `limit` is not far below `sigma`
    /// (acceptance `erf(limit / (sigma sqrt 2))`, 8 % at `limit = 0.1 sigma`).
    TruncatedNormal {
        /// Standard deviation of the untruncated Gaussian.
        sigma: f64,
        /// Truncation bound (> 0).
        limit: f64,
    },
}

impl Spread {
    fn validate(&self, field: &str) -> Result<(), ModelError> {
        let ok = match *self {
            Spread::Normal { sigma } => sigma.is_finite() && sigma >= 0.0,
            Spread::Uniform { half_width } => half_width.is_finite() && half_width >= 0.0,
            Spread::TruncatedNormal { sigma, limit } => {
                sigma.is_finite() && sigma >= 0.0 && limit.is_finite() && limit > 0.0 && limit >= 0.05 * sigma
            }
        };
        if ok {
            Ok(())
        } else {
            Err(ModelError::Invalid {
                field: field.to_owned(),
                message: format!("bad spread {self:?} (widths >= 0, truncation limit > 0.05 sigma)"),
            })
        }
    }

    /// One draw.
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        match *self {
            Spread::Normal { sigma } => normal(sigma).sample(rng),
            Spread::Uniform { half_width } if half_width > 0.0 => rng.random_range(-half_width..=half_width),
            Spread::Uniform { .. } => 0.0,
            Spread::TruncatedNormal { sigma, limit } => {
                let n = normal(sigma);
                loop {
                    let x = n.sample(rng);
                    if x.abs() <= limit {
                        return x;
                    }
                }
            }
        }
    }

    /// The standard deviation of a draw (truncated normal: by Simpson's rule on the density).
    pub fn std_dev(&self) -> f64 {
        match *self {
            Spread::Normal { sigma } => sigma,
            Spread::Uniform { half_width } => half_width / 3f64.sqrt(),
            Spread::TruncatedNormal { sigma, limit } if sigma > 0.0 => {
                let a = limit / sigma;
                let m = 2000;
                let h = 2.0 * a / m as f64;
                let (mut mass, mut second) = (0.0, 0.0);
                for i in 0..=m {
                    let x = -a + i as f64 * h;
                    let w = if i == 0 || i == m {
                        1.0
                    } else if i % 2 == 1 {
                        4.0
                    } else {
                        2.0
                    };
                    let d = (-0.5 * x * x).exp();
                    mass += w * d;
                    second += w * x * x * d;
                }
                sigma * (second / mass).sqrt()
            }
            Spread::TruncatedNormal { .. } => 0.0,
        }
    }
}

fn normal(sigma: f64) -> Normal<f64> {
    Normal::new(0.0, sigma).unwrap_or_else(|_| Normal::new(0.0, 0.0).expect("zero sigma is valid"))
}

fn draw<R: Rng + ?Sized>(spread: &Option<Spread>, rng: &mut R) -> f64 {
    spread.as_ref().map_or(0.0, |s| s.sample(rng))
}

/// Spreads of every phi-model row (eq. A3).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RowSpread {
    /// \[mm\]
    pub a_mm: Option<Spread>,
    /// \[mm\]
    pub b_mm: Option<Spread>,
    /// \[deg\]
    pub alpha_deg: Option<Spread>,
    /// \[deg\]
    pub beta_deg: Option<Spread>,
}

/// Spreads of the base placement, per component.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PlacementSpread {
    /// Each translation component \[mm\].
    pub translation_mm: Option<Spread>,
    /// Each of roll, pitch, yaw \[deg\].
    pub rpy_deg: Option<Spread>,
}

/// Spreads of the order-1 harmonic transmission error of each revolute joint (eq. 8).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TransmissionSpread {
    /// Coefficient of `sin(theta_a)` \[rad\].
    pub sin_rad: Option<Spread>,
    /// Coefficient of `cos(theta_a)` \[rad\].
    pub cos_rad: Option<Spread>,
    /// Scale error of each prismatic joint (eq. 13, `S_c = (1 + c_1) S`) \[ppm\].
    #[serde(default)]
    pub scale_ppm: Option<Spread>,
}

/// Spreads of an order-1 harmonic on a gear coupling (e.g. the 4->5 bevel gear, eq. 15).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CouplingHarmonicSpread {
    /// The driven joint (1-based); the description must couple it to the joint below.
    pub into: usize,
    /// Coefficient of `sin(N t)` \[rad\].
    pub sin_rad: Option<Spread>,
    /// Coefficient of `cos(N t)` \[rad\].
    pub cos_rad: Option<Spread>,
}

/// A four-bar coupling with manufacturing errors. The description holds no linkage
/// dimensions, so the nominal geometry is given here; its arm is replaced by the perturbed
/// distance between the two joint axes, keeping the linkage consistent with the geometry.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FourBarSpread {
    /// The driven joint (1-based).
    pub into: usize,
    /// Nominal dimensions (normally a parallelogram, giving the nominal slope -1).
    pub nominal: FourBarGeometry,
    /// Spread of each of crank, rod and lever lengths \[mm\].
    pub length_mm: Option<Spread>,
    /// Spread of each of the crank and lever angles \[deg\].
    pub angle_deg: Option<Spread>,
}

/// How to perturb a nominal robot (see module docs).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PerturbationSpec {
    /// Phi-model rows.
    #[serde(default)]
    pub rows: RowSpread,
    /// Base placement.
    #[serde(default)]
    pub placement: PlacementSpread,
    /// Transducer zero offsets of revolute joints \[deg\].
    pub transducer_offset_deg: Option<Spread>,
    /// Transducer zero offsets of prismatic joints \[mm\].
    pub transducer_offset_mm: Option<Spread>,
    /// Transmission errors of revolute joints.
    #[serde(default)]
    pub transmission: TransmissionSpread,
    /// Harmonic errors of gear couplings.
    #[serde(default)]
    pub coupling_harmonics: Vec<CouplingHarmonicSpread>,
    /// A four-bar coupling.
    pub four_bar: Option<FourBarSpread>,
    /// Repeatability jitter sigma per joint \[rad\] (revolute) or \[m\] (prismatic); empty = none.
    #[serde(default)]
    pub repeatability_sigma: Vec<f64>,
}

impl PerturbationSpec {
    /// Parses a spec from TOML; `label` names it in errors.
    pub fn from_toml_str(text: &str, label: &str) -> Result<Self, ModelError> {
        Ok(crate::toml_file::parse(text, std::path::Path::new(label))?)
    }

    fn validate(&self, desc: &RobotDescription) -> Result<(), ModelError> {
        let spreads = [
            ("rows.a_mm", &self.rows.a_mm),
            ("rows.b_mm", &self.rows.b_mm),
            ("rows.alpha_deg", &self.rows.alpha_deg),
            ("rows.beta_deg", &self.rows.beta_deg),
            ("placement.translation_mm", &self.placement.translation_mm),
            ("placement.rpy_deg", &self.placement.rpy_deg),
            ("transducer_offset_deg", &self.transducer_offset_deg),
            ("transducer_offset_mm", &self.transducer_offset_mm),
            ("transmission.sin_rad", &self.transmission.sin_rad),
            ("transmission.cos_rad", &self.transmission.cos_rad),
            ("transmission.scale_ppm", &self.transmission.scale_ppm),
        ];
        for (field, s) in spreads {
            if let Some(s) = s {
                s.validate(field)?;
            }
        }
        let coupled = |into: usize, field: String| {
            if desc.nominal_coupling_into(into).is_some() {
                Ok(())
            } else {
                Err(ModelError::Invalid {
                    field,
                    message: format!("the description has no coupling into joint {into}"),
                })
            }
        };
        for (i, c) in self.coupling_harmonics.iter().enumerate() {
            coupled(c.into, format!("coupling_harmonics[{i}].into"))?;
            for s in [&c.sin_rad, &c.cos_rad].into_iter().flatten() {
                s.validate(&format!("coupling_harmonics[{i}]"))?;
            }
        }
        if let Some(f) = &self.four_bar {
            coupled(f.into, "four_bar.into".into())?;
            for s in [&f.length_mm, &f.angle_deg].into_iter().flatten() {
                s.validate("four_bar")?;
            }
        }
        let n = desc.dof();
        if !self.repeatability_sigma.is_empty()
            && (self.repeatability_sigma.len() != n
                || self.repeatability_sigma.iter().any(|s| !(s.is_finite() && *s >= 0.0)))
        {
            return Err(ModelError::Invalid {
                field: "repeatability_sigma".into(),
                message: format!("needs {n} finite non-negative values"),
            });
        }
        Ok(())
    }
}

/// A random actual robot around the nominal `desc`: starts from [`RobotModel::ideal`] and adds
/// independent draws from `spec` (in the fixed order of the module docs) using `rng`.
pub fn perturb<R: Rng + ?Sized>(
    desc: &RobotDescription,
    spec: &PerturbationSpec,
    rng: &mut R,
) -> Result<RobotModel, ModelError> {
    spec.validate(desc)?;
    let mut t = RobotModel::ideal(desc);
    t.name = format!("{} (perturbed)", desc.name);
    for row in &mut t.rows {
        row.a_m += draw(&spec.rows.a_mm, rng) * 1e-3;
        row.b_m += draw(&spec.rows.b_mm, rng) * 1e-3;
        row.alpha_deg += draw(&spec.rows.alpha_deg, rng);
        row.beta_deg += draw(&spec.rows.beta_deg, rng);
    }
    for v in &mut t.placement.translation_mm {
        *v += draw(&spec.placement.translation_mm, rng);
    }
    for v in &mut t.placement.rpy_deg {
        *v += draw(&spec.placement.rpy_deg, rng);
    }
    for j in &mut t.joints {
        j.transducer_offset = match j.kind {
            JointKind::Revolute => draw(&spec.transducer_offset_deg, rng).to_radians(),
            JointKind::Prismatic => draw(&spec.transducer_offset_mm, rng) * 1e-3,
        };
    }
    // Each joint's transmission error is drawn in the form its description declares (a gear
    // joint's error is periodic in the gear angle): a robot of the family the calibrator fits.
    // Forms outside that family are unmodelled effects, switched on separately.
    for (j, entry) in t.joints.iter_mut().zip(&desc.joints) {
        if j.kind == JointKind::Revolute {
            let (sin, cos) = (
                vec![draw(&spec.transmission.sin_rad, rng)],
                vec![draw(&spec.transmission.cos_rad, rng)],
            );
            j.transmission = match entry.transmission_fit_form() {
                TransmissionFitForm::Gear { ratio, .. } => Transmission::Gear { ratio, sin, cos },
                TransmissionFitForm::Harmonic { .. } | TransmissionFitForm::Polynomial { .. } => {
                    Transmission::Harmonic { sin, cos }
                }
            };
        } else if spec.transmission.scale_ppm.is_some() {
            j.transmission = Transmission::Polynomial {
                c0: 0.0,
                c: vec![draw(&spec.transmission.scale_ppm, rng) * 1e-6],
            };
        }
    }
    for c in &spec.coupling_harmonics {
        let ratio = desc.nominal_coupling_into(c.into).unwrap_or(0.0);
        t.joints[c.into - 1].coupling_in = Some(CouplingFunction::Gear {
            ratio,
            sin: vec![draw(&c.sin_rad, rng)],
            cos: vec![draw(&c.cos_rad, rng)],
        });
    }
    if let Some(f) = &spec.four_bar {
        let mut g = f.nominal;
        g.arm_m = axis_distance_m(&t, f.into);
        g.crank_m += draw(&f.length_mm, rng) * 1e-3;
        g.rod_m += draw(&f.length_mm, rng) * 1e-3;
        g.lever_m += draw(&f.length_mm, rng) * 1e-3;
        g.crank_angle_rad += draw(&f.angle_deg, rng).to_radians();
        g.lever_angle_rad += draw(&f.angle_deg, rng).to_radians();
        t.joints[f.into - 1].coupling_in = Some(CouplingFunction::FourBar(g));
        t.four_bars.push(FourBarLinkage {
            from: f.into - 1,
            geometry: g,
        });
    }
    if !spec.repeatability_sigma.is_empty() {
        for (j, s) in t.joints.iter_mut().zip(&spec.repeatability_sigma) {
            j.repeatability_sigma = *s;
        }
    }
    t.validate()?;
    Ok(t)
}

/// Common-normal distance between axes `into - 1` and `into` (1-based) of the actual model at
/// zero joint values \[m\] (the two are parallel for a four-bar).
fn axis_distance_m(t: &RobotModel, into: usize) -> f64 {
    let poses = t.phi_model().poses(&vec![0.0; t.dof()]);
    let (a, b) = (poses.axis(into - 2), poses.axis(into - 1));
    let d = b.origin_m - a.origin_m;
    let dir = a.direction.into_inner();
    (d - dir * d.dot(&dir)).norm()
}

/// The chance that a robot's truth departs from its description, in any of its rows' values,
/// beyond [`largest_departure`]'s bound.
pub const DEPARTURE_FALSE_ALARM: f64 = 1e-6;

/// The values of a model's rows (`rows[k].a_m`, ...): lengths in mm, angles in deg (flagged).
fn row_values(model: &RobotModel) -> Vec<(String, f64, bool)> {
    let mut out = Vec::new();
    for (k, r) in model.rows.iter().enumerate() {
        out.push((format!("rows[{k}].a_m"), r.a_m * 1e3, false));
        out.push((format!("rows[{k}].b_m"), r.b_m * 1e3, false));
        out.push((format!("rows[{k}].h_m"), r.h_m * 1e3, false));
        out.push((format!("rows[{k}].alpha_deg"), r.alpha_deg, true));
        out.push((format!("rows[{k}].beta_deg"), r.beta_deg, true));
        out.push((format!("rows[{k}].gamma_deg"), r.gamma_deg, true));
    }
    out
}

/// `truth - nominal`, an angle's modulo 360 deg (in -180..180).
fn departure(truth: f64, nominal: f64, angle: bool) -> f64 {
    if angle {
        (truth - nominal + 180.0).rem_euclid(360.0) - 180.0
    } else {
        truth - nominal
    }
}

/// The RMS departure of `truth`'s rows from `nominal`'s (same row count): lengths \[mm\] and
/// angles \[deg\], over their nonzero departures. Of a real robot's identified truth against its
/// description, the size of a real robot's manufacturing errors.
pub fn row_departure_rms(truth: &RobotModel, nominal: &RobotModel) -> (f64, f64) {
    let (mut lengths, mut angles) = (Vec::new(), Vec::new());
    for ((_, t, angle), (_, n, _)) in row_values(truth).into_iter().zip(row_values(nominal)) {
        let d = departure(t, n, angle);
        if d != 0.0 {
            if angle { angles.push(d) } else { lengths.push(d) }
        }
    }
    let rms = |v: &[f64]| (v.iter().map(|d| d * d).sum::<f64>() / v.len().max(1) as f64).sqrt();
    (rms(&lengths), rms(&angles))
}

/// A row value of a truth model that departs from the description's nominal model beyond
/// what a robot's manufacturing errors give ([`largest_departure`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Departure {
    /// The value, as a truth file names it (`rows[2].a_m`).
    pub field: String,
    /// How far it departs (mm or deg).
    pub by: f64,
    /// The unit of `by`.
    pub unit: &'static str,
    /// `by` over the spread of that kind of value.
    pub spreads: f64,
    /// The bound in spreads: the normal deviate that all of the values compared stay within
    /// but with the chance [`DEPARTURE_FALSE_ALARM`].
    pub bound: f64,
}

/// The largest departure of `truth`'s rows from `nominal`'s (the description's nominal model),
/// counted in `spread` (a robot's manufacturing errors: lengths \[mm\], angles \[deg\], e.g.
/// [`row_departure_rms`] of a real robot), when beyond the normal deviate that all of the
/// values stay within but with the chance [`DEPARTURE_FALSE_ALARM`]: the truth is then another
/// robot's. `None` within the bound, or for models of other row counts.
pub fn largest_departure(truth: &RobotModel, nominal: &RobotModel, spread: (f64, f64)) -> Option<Departure> {
    if truth.rows.len() != nominal.rows.len() || !(spread.0 > 0.0 && spread.1 > 0.0) {
        return None;
    }
    let values = row_values(truth);
    let per_value = DEPARTURE_FALSE_ALARM / values.len().max(1) as f64;
    let bound = crate::numerics::stats::chi_square_quantile(1.0 - per_value, 1.0).sqrt();
    values
        .into_iter()
        .zip(row_values(nominal))
        .map(|((field, t, angle), (_, n, _))| {
            let by = departure(t, n, angle).abs();
            let (sigma, unit) = if angle { (spread.1, "deg") } else { (spread.0, "mm") };
            Departure {
                field,
                by,
                unit,
                spreads: by / sigma,
                bound,
            }
        })
        .filter(|d| d.spreads > bound)
        .max_by(|a, b| a.spreads.total_cmp(&b.spreads))
}
