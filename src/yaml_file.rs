//! Loading YAML input (robot_cal_tools measurements, a UR `kinematics.yaml`) with aliases
//! bounded: the loader expands every alias into a copy of its anchored node, so a few hundred
//! bytes of nested aliases (the "billion laughs" file) would become gigabytes. The events are
//! counted first, each alias as the nodes it stands for, without building anything.

use yaml_rust2::parser::{Event, MarkedEventReceiver, Parser};
use yaml_rust2::scanner::Marker;
use yaml_rust2::{Yaml, YamlLoader};

/// The expanded document may hold at most this many times the nodes written (plus
/// [`ALIAS_ALLOWANCE`]): shared values (one camera pose named by every observation) expand a
/// few times; a nest of aliases expands exponentially.
pub const MAX_EXPANSION: usize = 16;
/// Nodes any file may add through aliases, however small it is.
pub const ALIAS_ALLOWANCE: usize = 100_000;

/// Why YAML text was not loaded.
#[derive(Debug, thiserror::Error)]
pub enum YamlError {
    /// Not YAML.
    #[error("line {line}: not YAML: {message}")]
    Syntax {
        /// 1-based line of the error.
        line: usize,
        /// What the parser said.
        message: String,
    },
    /// Aliases that expand beyond the bound.
    #[error(
        "its aliases (`*name`) expand {written} written nodes into more than {expanded}: a nest of aliases, not a measurement file (write the values out)"
    )]
    Aliases {
        /// Nodes written in the text.
        written: usize,
        /// Nodes after expansion, at least.
        expanded: usize,
    },
}

/// The documents of `text` (a leading byte-order mark skipped, as an editor on Windows writes
/// one), refused when their aliases expand beyond the bound.
pub fn load(text: &str) -> Result<Vec<Yaml>, YamlError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let syntax = |e: yaml_rust2::ScanError| YamlError::Syntax {
        line: e.marker().line(),
        message: e.info().to_owned(),
    };
    let mut count = Count::default();
    Parser::new_from_str(text).load(&mut count, true).map_err(syntax)?;
    let bound = count
        .written
        .saturating_mul(MAX_EXPANSION)
        .saturating_add(ALIAS_ALLOWANCE);
    if count.expanded > bound {
        return Err(YamlError::Aliases {
            written: count.written,
            expanded: bound,
        });
    }
    YamlLoader::load_from_str(text).map_err(syntax)
}

/// Nodes written and nodes after alias expansion, with the expanded size of each anchor.
#[derive(Default)]
struct Count {
    written: usize,
    expanded: usize,
    anchor_sizes: Vec<usize>,
    /// Open collections: (anchor id, expanded count at their start).
    open: Vec<(usize, usize)>,
}

impl Count {
    fn anchored(&mut self, id: usize, size: usize) {
        if id > 0 {
            if self.anchor_sizes.len() <= id {
                self.anchor_sizes.resize(id + 1, 0);
            }
            self.anchor_sizes[id] = size;
        }
    }
}

impl MarkedEventReceiver for Count {
    fn on_event(&mut self, event: Event, _mark: Marker) {
        match event {
            Event::Scalar(_, _, id, _) => {
                self.written += 1;
                self.expanded = self.expanded.saturating_add(1);
                self.anchored(id, 1);
            }
            Event::SequenceStart(id, _) | Event::MappingStart(id, _) => {
                self.written += 1;
                self.expanded = self.expanded.saturating_add(1);
                self.open.push((id, self.expanded - 1));
            }
            Event::SequenceEnd | Event::MappingEnd => {
                if let Some((id, start)) = self.open.pop() {
                    self.anchored(id, self.expanded - start);
                }
            }
            Event::Alias(id) => {
                self.written += 1;
                let size = self.anchor_sizes.get(id).copied().unwrap_or(1);
                self.expanded = self.expanded.saturating_add(size);
            }
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A byte-order mark before the first key leaves the key as written.
    #[test]
    fn a_byte_order_mark_is_skipped() {
        let docs = load("\u{feff}kinematics:\n  hash: calib_1\n").unwrap();
        assert_eq!(docs[0]["kinematics"]["hash"].as_str(), Some("calib_1"));
    }

    /// `levels` levels of ten aliases each to the level below: 10^levels leaves.
    fn laughs(levels: usize) -> String {
        let mut text = String::from("a0: &a0 [lol]\n");
        for k in 1..=levels {
            let refs = vec![format!("*a{}", k - 1); 10].join(", ");
            text.push_str(&format!("a{k}: &a{k} [{refs}]\n"));
        }
        text
    }

    #[test]
    fn a_nest_of_aliases_is_refused_before_it_is_expanded() {
        assert!(load(&laughs(3)).is_ok(), "1000 leaves are within the allowance");
        let error = load(&laughs(9)).unwrap_err().to_string();
        assert!(error.contains("aliases"), "{error}");
    }

    #[test]
    fn shared_values_load_as_the_loader_loads_them() {
        let text = "camera: &cam {x: 1, y: 2}\nobs1: {pose: *cam}\nobs2: {pose: *cam}\n";
        assert_eq!(load(text).unwrap(), YamlLoader::load_from_str(text).unwrap());
    }

    #[test]
    fn expansion_is_counted_as_the_loader_builds_it() {
        // Second path: the loader's own expansion, counted node by node.
        fn nodes(y: &Yaml) -> usize {
            1 + match y {
                Yaml::Array(a) => a.iter().map(nodes).sum(),
                Yaml::Hash(h) => h.iter().map(|(k, v)| nodes(k) + nodes(v)).sum(),
                _ => 0,
            }
        }
        for levels in 1..=4 {
            let text = laughs(levels);
            let mut count = Count::default();
            Parser::new_from_str(&text).load(&mut count, true).unwrap();
            let built = YamlLoader::load_from_str(&text).unwrap();
            assert_eq!(
                count.expanded,
                built.iter().map(nodes).sum::<usize>(),
                "{levels} levels"
            );
        }
    }
}
