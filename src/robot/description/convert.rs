//! Geometry given as a Denavit-Hartenberg table (`dh` rows, classic or modified) or as a URDF
//! file, converted to the phi-model rows and phi angles when a description is read
//! ([`crate::kinematics::phi_model_of`], the phi rule in its docs). After the conversion the
//! description holds `phi_deg`, `rows`, `placement` and `tool.frame` like any other, and no
//! `dh` or `urdf` key (a resolved scenario inlines the converted form).

use super::urdf_text::{MAX_URDF_DEPTH, nesting_beyond, parser_hint, urdf_text_problem};
use super::{DescriptionError, DhConventionEntry, JointEntry, Placement, RobotDescription, RowEntry, UrdfEntry};
use crate::kinematics::{DhConvention, DhParams, JointKind, PhiModel, SourceChain, UrdfJoint, phi_model_of};
use crate::measurement::format_f64;
use nalgebra::{Isometry3, Point3, Translation3, Unit, UnitQuaternion, Vector3};
use std::path::Path;

fn invalid(path: &Path, field: impl Into<String>, message: impl Into<String>) -> DescriptionError {
    DescriptionError::Invalid {
        path: path.to_owned(),
        field: field.into(),
        message: message.into(),
    }
}

impl RobotDescription {
    /// Converts `dh` rows or a `urdf` file to the phi-model in place; returns the source chain
    /// and the placement of its base as written.
    pub(super) fn convert_source(
        &mut self,
        path: &Path,
    ) -> Result<Option<(SourceChain, Isometry3<f64>)>, DescriptionError> {
        let has_dh = self.dh_convention.is_some() || self.joints.iter().any(|j| j.dh.is_some());
        if has_dh && self.joints.is_empty() {
            return Err(invalid(path, "joints", "at least one joint is required"));
        }
        let source = match (has_dh, self.urdf.clone()) {
            (false, None) => return Ok(None),
            (true, Some(_)) => {
                return Err(invalid(
                    path,
                    "urdf",
                    "give either `dh` rows or a `urdf` file, not both",
                ));
            }
            (true, None) => (self.dh_source(path)?, None),
            (false, Some(u)) => self.urdf_source(&u, path)?,
        };
        let (source, urdf_inertials) = source;
        if !self.rows.is_empty() {
            return Err(invalid(
                path,
                "rows",
                "the rows are converted from the `dh` table or the URDF: leave `rows` out",
            ));
        }
        if let Some(k) = self.joints.iter().position(|j| j.phi_deg != 0.0) {
            return Err(invalid(
                path,
                format!("joints[{k}].phi_deg"),
                "phi is chosen by the conversion rule: leave `phi_deg` out",
            ));
        }
        let written = self.placement.to_isometry();
        let model = phi_model_of(&source, &written)
            .ok_or_else(|| invalid(path, "joints", "the geometry has a singular row (coincident axes)"))?;
        for (j, p) in self.joints.iter_mut().zip(&model.joints) {
            j.phi_deg = p.phi_rad.to_degrees();
            j.dh = None;
        }
        if let (Some(inertials), SourceChain::Urdf { joints, .. }) = (urdf_inertials, &source) {
            self.take_urdf_inertials(joints, &inertials, &written, &model);
        }
        self.rows = model.rows.iter().map(RowEntry::from_row).collect();
        self.placement = Placement::from_isometry(&model.world_from_base);
        self.tool.frame = Placement::from_isometry(&model.last_link_from_tool);
        self.dh_convention = None;
        self.urdf = None;
        Ok(Some((source, written)))
    }

    /// The DH chain of the joints' `dh` rows.
    fn dh_source(&self, path: &Path) -> Result<SourceChain, DescriptionError> {
        let convention = match self.dh_convention {
            Some(DhConventionEntry::Classic) => DhConvention::Classic,
            Some(DhConventionEntry::Modified) => DhConvention::Modified,
            None => {
                return Err(invalid(
                    path,
                    "dh_convention",
                    "the joints have `dh` rows: say `dh_convention = \"classic\"` or `\"modified\"`",
                ));
            }
        };
        let mut rows = Vec::with_capacity(self.joints.len());
        for (k, j) in self.joints.iter().enumerate() {
            let d =
                j.dh.ok_or_else(|| invalid(path, format!("joints[{k}].dh"), "every joint needs its `dh` row"))?;
            if ![d.d_mm, d.theta_deg, d.a_mm, d.alpha_deg].iter().all(|v| v.is_finite()) {
                return Err(invalid(path, format!("joints[{k}].dh"), "values must be finite"));
            }
            for (key, deg) in [("theta_deg", d.theta_deg), ("alpha_deg", d.alpha_deg)] {
                if let Some(why) = super::validate::angle_deg_problem(deg) {
                    return Err(invalid(path, format!("joints[{k}].dh.{key}"), why));
                }
            }
            rows.push(DhParams {
                d_m: d.d_mm * 1e-3,
                theta_rad: d.theta_deg.to_radians(),
                a_m: d.a_mm * 1e-3,
                alpha_rad: d.alpha_deg.to_radians(),
            });
        }
        check_dh_lengths(&self.joints).map_err(|(field, message)| invalid(path, field, message))?;
        Ok(SourceChain::Dh {
            convention,
            kinds: self.joints.iter().map(|j| j.kind).collect(),
            rows,
            flange_from_tool: self.tool.frame.to_isometry(),
        })
    }

    /// Each joint's `mass_kg` and `com_mm` from the URDF's inertials (`inertials[k]`: mass
    /// \[kg\] and centre of mass in joint `k`'s child link \[m\]), the centre carried into the
    /// phi-model's moving frame of link `k` through both chains' frames at joint values 0.
    fn take_urdf_inertials(
        &mut self,
        joints: &[UrdfJoint],
        inertials: &[LinkInertial],
        world_from_urdf_base: &Isometry3<f64>,
        model: &PhiModel,
    ) {
        let world_from_phi_link = model.poses(&vec![0.0; model.dof()]).world_from_link;
        let mut base_from_child = Isometry3::identity();
        for (k, ((entry, joint), inertial)) in self.joints.iter_mut().zip(joints).zip(inertials).enumerate() {
            base_from_child *= joint.parent_from_joint;
            let com_world_m = world_from_urdf_base * base_from_child * inertial.com_m;
            let com_phi_m = world_from_phi_link[k].inverse() * com_world_m;
            entry.mass_kg = inertial.mass_kg;
            entry.com_mm = (com_phi_m.coords * 1e3).into();
        }
    }

    /// The URDF chain from `u.base_link` to `u.tip_link`; fills `joints` from it when empty,
    /// and then returns the links' inertials for [`Self::take_urdf_inertials`].
    fn urdf_source(
        &mut self,
        u: &UrdfEntry,
        path: &Path,
    ) -> Result<(SourceChain, Option<Vec<LinkInertial>>), DescriptionError> {
        let file = path.parent().unwrap_or(Path::new(".")).join(&u.file);
        let text = crate::presets::read_text(&file)
            .map_err(|e| invalid(path, "urdf.file", format!("reading {}: {e}", file.display())))?;
        if let Some((line, depth)) = nesting_beyond(&text, MAX_URDF_DEPTH) {
            return Err(invalid(
                path,
                "urdf.file",
                format!(
                    "{}: line {line}: elements nested {depth} deep; a URDF nests a few levels (`robot` > `link` > \
                     `visual` > `geometry` > `mesh`), axiscal reads at most {MAX_URDF_DEPTH}: point `urdf.file` at \
                     the robot's .urdf file (xacro expanded)",
                    file.display()
                ),
            ));
        }
        let not_urdf = |e: String| {
            let message = match crate::toml_file::not_xml(&text, &file) {
                Some(kind) => format!(
                    "{}: this is {kind}, not a URDF (the robot's XML, `<robot name=...>`): point `urdf.file` at the robot's .urdf file",
                    file.display()
                ),
                None => format!("{}: {e}", file.display()),
            };
            invalid(path, "urdf.file", message)
        };
        if let Some(problem) = urdf_text_problem(&text) {
            return Err(not_urdf(problem));
        }
        let robot = urdf_rs::read_from_string(&text).map_err(|e| {
            let said = e.to_string();
            let hint = parser_hint(&text, &said).unwrap_or_default();
            not_urdf(crate::csv_lines::shown_message(said.strip_prefix("custom: ").unwrap_or(&said)) + &hint)
        })?;
        let chain = urdf_chain(&robot, u).map_err(|m| invalid(path, "urdf", format!("{}: {m}", file.display())))?;
        let (joints, tail, entries, inertials) = chain;
        let mut taken = None;
        if self.joints.is_empty() {
            self.joints = entries;
            taken = Some(inertials);
        } else if self.joints.len() != joints.len() || self.joints.iter().zip(&joints).any(|(a, b)| a.kind != b.kind) {
            return Err(invalid(
                path,
                "joints",
                format!(
                    "the URDF chain has {} movable joints ({}); `joints` must match them in number and kind, or be left out",
                    joints.len(),
                    joints
                        .iter()
                        .map(|j| format!("{:?}", j.kind).to_lowercase())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
        let source = SourceChain::Urdf {
            joints,
            last_link_from_tool: tail * self.tool.frame.to_isometry(),
        };
        Ok((source, taken))
    }
}

/// No DH length is longer than a robot link
/// ([`crate::measurement::unit_check::MAX_ROW_LENGTH_M`]): the lengths are millimetres of an
/// arm (a table in metres is a unit slip of the description,
/// [`crate::measurement::unit_check::description_slips`]).
fn check_dh_lengths(joints: &[JointEntry]) -> Result<(), (String, String)> {
    let longest_mm = crate::measurement::unit_check::MAX_ROW_LENGTH_M * 1e3;
    let lengths = joints
        .iter()
        .enumerate()
        .filter_map(|(k, j)| j.dh.map(|d| (k, d)))
        .flat_map(|(k, d)| [(k, "d_mm", d.d_mm), (k, "a_mm", d.a_mm)]);
    for (k, key, v) in lengths {
        if v.abs() > longest_mm {
            return Err((
                format!("joints[{k}].dh.{key}"),
                format!(
                    "{} mm is longer than any robot link ({longest_mm} mm): DH lengths are in mm; this looks like \
                     micrometres or a slip",
                    format_f64(v)
                ),
            ));
        }
    }
    Ok(())
}

/// The mass a movable URDF joint moves on the chain: its child link's and those fixed below it.
#[derive(Clone, Copy, Debug, PartialEq)]
struct LinkInertial {
    /// \[kg\]
    mass_kg: f64,
    /// Centre of mass in the joint's child link \[m\] (the origin when the mass is 0).
    com_m: Point3<f64>,
}

impl LinkInertial {
    /// `link`'s `<inertial>` placed by `child_from_link`.
    fn of(link: Option<&urdf_rs::Link>, child_from_link: &Isometry3<f64>) -> Self {
        let Some(inertial) = link.map(|l| &l.inertial) else {
            return Self {
                mass_kg: 0.0,
                com_m: Point3::origin(),
            };
        };
        let c = inertial.origin.xyz;
        Self {
            mass_kg: inertial.mass.value,
            com_m: child_from_link * Point3::new(c[0], c[1], c[2]),
        }
    }

    /// `self` and `other` as one body.
    fn merged(self, other: Self) -> Self {
        let mass_kg = self.mass_kg + other.mass_kg;
        if mass_kg <= 0.0 {
            return self;
        }
        let com = (self.com_m.coords * self.mass_kg + other.com_m.coords * other.mass_kg) / mass_kg;
        Self {
            mass_kg,
            com_m: com.into(),
        }
    }
}

/// A URDF pose as an isometry (rpy: `Rz(yaw) Ry(pitch) Rx(roll)`, fixed axes, as URDF defines).
fn pose(p: &urdf_rs::Pose) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(p.xyz[0], p.xyz[1], p.xyz[2]),
        UnitQuaternion::from_euler_angles(p.rpy[0], p.rpy[1], p.rpy[2]),
    )
}

/// What [`urdf_chain`] finds: the movable joints, the last joint's child to the tip, the joint
/// entries, and each movable joint's moved mass on the chain.
type UrdfChain = (Vec<UrdfJoint>, Isometry3<f64>, Vec<JointEntry>, Vec<LinkInertial>);

/// The movable joints from the base link to the tip link (fixed joints merged into the next
/// joint's origin), the fixed transform from the last movable joint's child to the tip, and
/// joint entries (kind, limits in deg or mm) for a description without `joints`.
fn urdf_chain(robot: &urdf_rs::Robot, u: &UrdfEntry) -> Result<UrdfChain, String> {
    check_tree(robot, u.base_link.is_none())?;
    let children: std::collections::HashSet<&str> = robot.joints.iter().map(|j| j.child.link.as_str()).collect();
    for (key, name) in [("base_link", &u.base_link), ("tip_link", &u.tip_link)] {
        if let Some(name) = name {
            link_exists(robot, key, name)?;
        }
    }
    let base = match &u.base_link {
        Some(b) => b.clone(),
        None => robot
            .links
            .iter()
            .find(|l| !children.contains(l.name.as_str()))
            .map(|l| l.name.clone())
            .ok_or("no root link")?,
    };
    // Walk down from the base; at a branch the tip must be named.
    let mut path: Vec<&urdf_rs::Joint> = Vec::new();
    let mut link = base.clone();
    loop {
        if u.tip_link.as_deref() == Some(link.as_str()) {
            break;
        }
        let next: Vec<&urdf_rs::Joint> = robot.joints.iter().filter(|j| j.parent.link == link).collect();
        let pick = match (next.len(), &u.tip_link) {
            (0, None) => break,
            (0, Some(t)) => return Err(format!("tip link `{t}` is not below base link `{base}`")),
            (1, _) => next[0],
            (_, None) => return Err(branch_message(robot, &link, &next)),
            (_, Some(t)) => *next
                .iter()
                .find(|j| reaches(robot, &j.child.link, t))
                .ok_or_else(|| format!("tip link `{t}` is not below base link `{base}`"))?,
        };
        path.push(pick);
        link = pick.child.link.clone();
    }
    if u.tip_link.is_none()
        && let Some(off) = robot
            .joints
            .iter()
            .find(|j| !matches!(j.joint_type, urdf_rs::JointType::Fixed) && !path.iter().any(|p| p.name == j.name))
    {
        return Err(format!(
            "joint `{}` moves but is not on the chain from `{base}` down to `{link}`: a parent or child link misnamed \
             breaks the chain there; check the joint's `parent` and `child`, or name the `tip_link` of a branched robot",
            off.name
        ));
    }
    let link_named = |name: &str| robot.links.iter().find(|l| l.name == name);
    let mut joints = Vec::new();
    let mut entries = Vec::new();
    let mut inertials: Vec<LinkInertial> = Vec::new();
    let mut pending = Isometry3::identity();
    for j in path {
        check_joint_origin(j)?;
        link_named(&j.child.link).map(check_inertial).transpose()?;
        let kind = match j.joint_type {
            urdf_rs::JointType::Fixed => {
                pending *= pose(&j.origin);
                if let Some(moved) = inertials.last_mut() {
                    *moved = moved.merged(LinkInertial::of(link_named(&j.child.link), &pending));
                }
                continue;
            }
            urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => JointKind::Revolute,
            urdf_rs::JointType::Prismatic => JointKind::Prismatic,
            ref other => {
                return Err(format!(
                    "joint `{}` is {other:?}: only revolute, continuous, prismatic and fixed joints form a serial arm",
                    j.name
                ));
            }
        };
        let axis = Vector3::from(*j.axis.xyz);
        if !axis.iter().all(|c| c.is_finite()) || axis.norm() == 0.0 {
            return Err(format!("joint `{}` has a zero axis", j.name));
        }
        joints.push(UrdfJoint {
            kind,
            parent_from_joint: pending * pose(&j.origin),
            axis: Unit::new_normalize(axis),
        });
        pending = Isometry3::identity();
        entries.push(joint_entry(j, kind)?);
        inertials.push(LinkInertial::of(link_named(&j.child.link), &Isometry3::identity()));
    }
    if joints.is_empty() {
        return Err(format!("no movable joint between `{base}` and the tip"));
    }
    Ok((joints, pending, entries, inertials))
}

/// The URDF is one tree: joint and link names unique, every joint's parent and child a declared
/// link, each link the child of one joint at most, and (without a named `base_link`) one root.
/// A misspelt parent cut the chain there, and the robot lost its joints below it silently.
fn check_tree(robot: &urdf_rs::Robot, one_root: bool) -> Result<(), String> {
    let mut links = std::collections::HashSet::new();
    if let Some(l) = robot.links.iter().find(|l| !links.insert(l.name.as_str())) {
        return Err(format!("link `{}` is declared twice", l.name));
    }
    let mut names = std::collections::HashSet::new();
    let mut children = std::collections::HashSet::new();
    for j in &robot.joints {
        if !names.insert(j.name.as_str()) {
            return Err(format!("joint `{}` is declared twice", j.name));
        }
        for (end, link) in [("parent", &j.parent.link), ("child", &j.child.link)] {
            if !links.contains(link.as_str()) {
                return Err(format!(
                    "joint `{}`: its {end} link `{link}` is not declared (no <link name=\"{link}\">)",
                    j.name
                ));
            }
        }
        if !children.insert(j.child.link.as_str()) {
            return Err(format!(
                "link `{}` is the child of two joints (`{}` and another): a URDF is a tree",
                j.child.link, j.name
            ));
        }
    }
    let roots: Vec<&str> = robot
        .links
        .iter()
        .map(|l| l.name.as_str())
        .filter(|l| !children.contains(l))
        .collect();
    match roots.len() {
        0 => Err("every link is some joint's child: the joints form a loop, and a URDF is a tree".into()),
        1 => Ok(()),
        _ if !one_root => Ok(()),
        _ => Err(format!(
            "{} links are no joint's child ({}): a URDF has one root; connect them, or name the `base_link`",
            roots.len(),
            listed(&roots)
        )),
    }
}

/// `name` (the description's `urdf.KEY`) is a link of the URDF.
fn link_exists(robot: &urdf_rs::Robot, key: &str, name: &str) -> Result<(), String> {
    if robot.links.iter().any(|l| l.name == name) {
        return Ok(());
    }
    let links: Vec<&str> = robot.links.iter().map(|l| l.name.as_str()).collect();
    Err(format!(
        "`{key}`: no link named `{name}`; the URDF's links are {}",
        listed(&links)
    ))
}

/// A joint's `<origin>` is finite and no longer than a robot link
/// ([`crate::measurement::unit_check::MAX_ROW_LENGTH_M`]): a URDF is in metres, and lengths of
/// hundreds of metres are millimetres.
fn check_joint_origin(j: &urdf_rs::Joint) -> Result<(), String> {
    let (xyz, rpy) = (*j.origin.xyz, *j.origin.rpy);
    if !xyz.iter().chain(&rpy).all(|v| v.is_finite()) {
        return Err(format!(
            "joint `{}`: `<origin xyz=\"{}\" rpy=\"{}\">`: every value must be a finite number",
            j.name,
            triple(&xyz),
            triple(&rpy)
        ));
    }
    if let Some(v) = rpy.iter().find(|v| v.abs() > std::f64::consts::TAU * (1.0 + 1e-6)) {
        return Err(format!(
            "joint `{}`: `<origin rpy=\"{}\">`: {} rad is more than a turn: a URDF's angles are radians; these look like \
             degrees",
            j.name,
            triple(&rpy),
            format_f64(*v)
        ));
    }
    let length_m = Vector3::from(xyz).norm();
    let longest = crate::measurement::unit_check::MAX_ROW_LENGTH_M;
    if length_m > longest {
        return Err(format!(
            "joint `{}`: `<origin xyz=\"{}\">` is {} m from its parent, longer than any robot link \
             ({longest} m): a URDF's lengths are in metres; these look like millimetres",
            j.name,
            triple(&xyz),
            format_f64(length_m)
        ));
    }
    Ok(())
}

/// Three numbers as a URDF attribute writes them (`0.1 0 2`).
fn triple(v: &[f64; 3]) -> String {
    v.map(format_f64).join(" ")
}

/// A link's `<inertial>`: a finite mass >= 0 \[kg\] at a finite centre.
fn check_inertial(link: &urdf_rs::Link) -> Result<(), String> {
    let (mass, c) = (link.inertial.mass.value, *link.inertial.origin.xyz);
    if !(mass.is_finite() && mass >= 0.0) {
        return Err(format!(
            "link `{}`: `<inertial><mass value=\"{mass}\">`: a mass is a finite number >= 0 (kg)",
            link.name
        ));
    }
    if !c.iter().all(|v| v.is_finite()) {
        return Err(format!(
            "link `{}`: `<inertial><origin xyz=\"{}\">`: every value must be a finite number",
            link.name,
            triple(&c)
        ));
    }
    Ok(())
}

/// Whether `target` is `link` or below it.
fn reaches(robot: &urdf_rs::Robot, link: &str, target: &str) -> bool {
    below(robot, link).contains(&target)
}

/// `link` and the links below it, depth first (a stack, not recursion: a chain may be long).
fn below<'a>(robot: &'a urdf_rs::Robot, link: &'a str) -> Vec<&'a str> {
    let (mut out, mut stack) = (Vec::new(), vec![link]);
    while let Some(l) = stack.pop() {
        out.push(l);
        stack.extend(
            robot
                .joints
                .iter()
                .filter(|j| j.parent.link == l)
                .map(|j| j.child.link.as_str()),
        );
    }
    out
}

/// The most names an error lists before it says how many more there are.
const MAX_LISTED: usize = 12;

/// `names` for an error message, quoted: at most [`MAX_LISTED`], then how many more.
fn listed(names: &[&str]) -> String {
    let shown: Vec<String> = names.iter().take(MAX_LISTED).map(|n| format!("`{n}`")).collect();
    match names.len().saturating_sub(MAX_LISTED) {
        0 => shown.join(", "),
        more => format!("{} and {more} more", shown.join(", ")),
    }
}

/// Why the chain cannot pass `link`, where the joints `next` branch, without a `tip_link`:
/// the branches and the leaves below it (each a `tip_link` that can be named).
fn branch_message(robot: &urdf_rs::Robot, link: &str, next: &[&urdf_rs::Joint]) -> String {
    let branches: Vec<&str> = next.iter().map(|j| j.child.link.as_str()).collect();
    let under: std::collections::HashSet<&str> = below(robot, link).into_iter().collect();
    let parents: std::collections::HashSet<&str> = robot.joints.iter().map(|j| j.parent.link.as_str()).collect();
    let leaves: Vec<&str> = robot
        .links
        .iter()
        .map(|l| l.name.as_str())
        .filter(|l| under.contains(l) && !parents.contains(l))
        .collect();
    format!(
        "link `{link}` branches to {}: name the `tip_link`, the chain's last link (a leaf below it: {})",
        listed(&branches),
        listed(&leaves)
    )
}

/// The most turns either way a URDF's revolute (not continuous) joint's limits may give: a
/// robot's joints turn at most about a turn and a quarter (a wrist's +-455 deg); a limit of 45
/// or 180 is degrees written where a URDF takes radians.
const MAX_URDF_LIMIT_TURNS: f64 = 2.0;

/// A joint entry from a URDF joint: its kind and limits (deg or mm; a continuous joint or one
/// without limits, `lower` = `upper` as a missing `<limit>` reads, gets +-360 deg or +-1000
/// mm), its speed (deg/s or mm/s) and effort limits where the URDF gives them (a 0 there
/// means "not given"). Limits that are not finite numbers, are reversed or lie beyond
/// [`MAX_URDF_LIMIT_TURNS`], and a `<mimic>`, are an error naming the joint.
fn joint_entry(j: &urdf_rs::Joint, kind: JointKind) -> Result<JointEntry, String> {
    let l = &j.limit;
    let continuous = j.joint_type == urdf_rs::JointType::Continuous;
    // A continuous joint's `lower` and `upper` are not read.
    let bounds = if continuous { [0.0; 2] } else { [l.lower, l.upper] };
    if !bounds.iter().chain(&[l.velocity, l.effort]).all(|v| v.is_finite()) {
        return Err(format!(
            "joint `{}`: `<limit lower=\"{}\" upper=\"{}\" velocity=\"{}\" effort=\"{}\">`: every value must be a finite number",
            j.name, l.lower, l.upper, l.velocity, l.effort
        ));
    }
    if let Some(m) = &j.mimic {
        return Err(format!(
            "joint `{}`: `<mimic joint=\"{}\">`: a joint that follows another is a passive coupling, which a URDF \
             chain here cannot carry (it would be calibrated as a joint of its own): give the robot's `[[joints]]` and \
             `[[couplings]]` in the description (docs/formats.md#robot-description)",
            j.name, m.joint
        ));
    }
    let turns = |v: f64| v.abs() / std::f64::consts::TAU;
    if kind == JointKind::Revolute && !continuous && turns(l.lower).max(turns(l.upper)) > MAX_URDF_LIMIT_TURNS {
        return Err(format!(
            "joint `{}`: `<limit lower=\"{}\" upper=\"{}\">`: {} turns either way: a URDF's angles are radians; these \
             look like degrees (a joint that turns further is given in the description's `[[joints]]`, its limits in deg)",
            j.name,
            l.lower,
            l.upper,
            format_f64((turns(l.lower).max(turns(l.upper)) * 10.0).round() / 10.0)
        ));
    }
    if !continuous && l.lower > l.upper {
        return Err(format!(
            "joint `{}`: `<limit lower=\"{}\" upper=\"{}\">`: the lower limit is above the upper one; swap them",
            j.name, l.lower, l.upper
        ));
    }
    let (lo, hi) = (kind.to_file_units(l.lower), kind.to_file_units(l.upper));
    let limits = if !continuous && lo < hi {
        [lo, hi]
    } else {
        match kind {
            JointKind::Revolute => [-360.0, 360.0],
            JointKind::Prismatic => [-1000.0, 1000.0],
        }
    };
    let scale = kind.to_file_units(1.0);
    Ok(JointEntry {
        kind,
        phi_deg: 0.0,
        limits,
        mass_kg: 0.0,
        com_mm: [0.0; 3],
        transmission_fit: None,
        dh: None,
        repeatability_sigma: 0.0,
        max_velocity: (l.velocity > 0.0).then_some(l.velocity * scale),
        max_effort: (l.effort > 0.0).then_some(l.effort),
    })
}
