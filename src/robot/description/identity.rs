//! The identity of a robot description: its name and a stable hash of its geometry
//! (`docs/formats.md#calibration-json`), recorded in `calibration.json` so that a calibration
//! is not used with another robot's description.

use super::RobotDescription;
use serde::{Deserialize, Serialize};

/// Which description a calibration (or a data file) was made with.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DescriptionIdentity {
    /// The description's `name`.
    pub name: String,
    /// [`RobotDescription::geometry_hash`]: `fnv1a64:` and 16 hex digits.
    pub geometry_hash: String,
}

impl std::fmt::Display for DescriptionIdentity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:?} (geometry {})", self.name, self.geometry_hash)
    }
}

/// Keys of a joint entry that are not geometry (masses, limits, noise, fit forms).
const NOT_GEOMETRY_JOINT_KEYS: [&str; 5] = ["mass_kg", "com_mm", "limits", "repeatability_sigma", "transmission_fit"];

/// FNV-1a, 64 bits.
pub(crate) struct Fnv(u64);

impl Fnv {
    /// The hash of no bytes (the FNV offset basis).
    pub(crate) fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }

    /// `fnv1a64:` and the hash as 16 lower-case hex digits.
    pub(crate) fn text(&self) -> String {
        format!("fnv1a64:{:016x}", self.0)
    }

    /// Hashes `bytes` in.
    pub(crate) fn bytes(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.0 ^= u64::from(*b);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }

    /// A tag byte, then the value's bytes (see [`RobotDescription::geometry_hash`]).
    pub(crate) fn value(&mut self, v: &serde_json::Value) {
        use serde_json::Value;
        match v {
            Value::Null => self.bytes(b"z"),
            Value::Bool(b) => self.bytes(&[b'b', u8::from(*b)]),
            Value::Number(n) => {
                // Every number as an f64; -0 as +0 (the same geometry).
                let x = n.as_f64().unwrap_or(f64::NAN);
                let x = x + 0.0;
                self.bytes(b"n");
                self.bytes(&x.to_bits().to_le_bytes());
            }
            Value::String(s) => {
                self.bytes(b"s");
                self.bytes(&(s.len() as u64).to_le_bytes());
                self.bytes(s.as_bytes());
            }
            Value::Array(items) => {
                self.bytes(b"a");
                self.bytes(&(items.len() as u64).to_le_bytes());
                items.iter().for_each(|i| self.value(i));
            }
            Value::Object(map) => {
                let mut keys: Vec<&String> = map.keys().collect();
                keys.sort();
                self.bytes(b"o");
                self.bytes(&(keys.len() as u64).to_le_bytes());
                for k in keys {
                    self.value(&Value::String(k.clone()));
                    self.value(&map[k]);
                }
            }
        }
    }
}

impl RobotDescription {
    /// A stable hash of the description's geometry: FNV-1a 64 over its numbers and kinds, as
    /// `fnv1a64:` and 16 lower-case hex digits.
    ///
    /// Hashed: the description as its JSON value (every default filled in, so omitted and
    /// explicit defaults agree) without `name`, `axis_targets` (where the calibration targets
    /// sit is not the robot's geometry), `instrument` (nor where the instrument stands), each joint's `mass_kg`, `com_mm`, `limits`,
    /// `repeatability_sigma` and `transmission_fit`, and each coupling's `fit`. The value is
    /// walked depth-first: an object as `o`, its key count (u64 LE) and its keys in byte order,
    /// each key as a string followed by its value; an array as `a`, its length and its items; a
    /// number as `n` and its IEEE-754 f64 bits (LE; -0 as +0); a string as `s`, its byte length
    /// and its UTF-8 bytes; a bool as `b` and 0 or 1; null as `z`.
    pub fn geometry_hash(&self) -> String {
        let mut value = serde_json::to_value(self).unwrap_or(serde_json::Value::Null);
        if let Some(top) = value.as_object_mut() {
            top.remove("name");
            top.remove("axis_targets");
            top.remove("instrument");
            for joint in top
                .get_mut("joints")
                .and_then(|j| j.as_array_mut())
                .into_iter()
                .flatten()
            {
                if let Some(joint) = joint.as_object_mut() {
                    NOT_GEOMETRY_JOINT_KEYS.iter().for_each(|k| {
                        joint.remove(*k);
                    });
                }
            }
            for coupling in top
                .get_mut("couplings")
                .and_then(|c| c.as_array_mut())
                .into_iter()
                .flatten()
            {
                if let Some(coupling) = coupling.as_object_mut() {
                    coupling.remove("fit");
                }
            }
        }
        let mut hash = Fnv::new();
        hash.value(&value);
        hash.text()
    }

    /// The description's name and geometry hash.
    pub fn identity(&self) -> DescriptionIdentity {
        DescriptionIdentity {
            name: self.name.clone(),
            geometry_hash: self.geometry_hash(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn irb() -> RobotDescription {
        RobotDescription::asea_irb6l()
    }

    #[test]
    fn fnv_matches_the_published_test_vectors() {
        // Fowler/Noll/Vo reference values of FNV-1a 64.
        for (text, expected) in [
            ("", 0xcbf2_9ce4_8422_2325u64),
            ("a", 0xaf63_dc4c_8601_ec8c),
            ("foobar", 0x8594_4171_f739_67e8),
        ] {
            let mut h = Fnv(0xcbf2_9ce4_8422_2325);
            h.bytes(text.as_bytes());
            assert_eq!(h.0, expected, "{text:?}");
        }
    }

    #[test]
    fn the_hash_follows_geometry_and_nothing_else() {
        let base = irb().geometry_hash();
        assert!(base.starts_with("fnv1a64:") && base.len() == 8 + 16, "{base}");
        let mut renamed = irb();
        renamed.name = "another name".into();
        renamed.joints[2].mass_kg += 1.0;
        renamed.joints[0].limits[1] -= 1.0;
        assert_eq!(renamed.geometry_hash(), base);
        let mut moved = irb();
        moved.rows[1].a_m += 1e-6;
        assert_ne!(moved.geometry_hash(), base);
        let mut tool = irb();
        tool.tool.targets_mm[0][2] += 0.001;
        assert_ne!(tool.geometry_hash(), base);
        let mut coupling = irb();
        coupling.couplings[0].slope = -0.999;
        assert_ne!(coupling.geometry_hash(), base);
        // The other shipped robot is another geometry.
        let other =
            RobotDescription::from_file(Path::new("scenarios/robots/boby-klimchik-arm.toml")).expect("shipped file");
        assert_ne!(other.geometry_hash(), base);
    }

    #[test]
    fn written_defaults_and_number_spellings_do_not_change_it() {
        let text = include_str!("../../../scenarios/robots/asea-irb6l.toml");
        let spelled = text
            .replace("a_m = -0.690", "a_m = -0.6900")
            .replace("beta_deg = -90.0\n", "beta_deg = -90.0\ngamma_deg = 0.0\nh_m = -0.0\n");
        assert_ne!(spelled, text);
        let d = RobotDescription::from_toml_str(&spelled, Path::new("x.toml")).unwrap();
        assert_eq!(d.geometry_hash(), irb().geometry_hash());
    }
}
