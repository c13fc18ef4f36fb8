//! The arrows between the files of one layer: which file's items a file names (through `use`
//! trees and `crate::`/`super::`/`self::` paths, re-exports followed to the file that defines
//! the item), and the cycles those arrows make.
//!
//! A name is resolved by the module tree alone (no type checking): the longest prefix of the
//! path that is a module picks the file; a name that file imports (a `use`, public or not) is
//! followed to where it comes from; any other name is taken as defined there. Paths that start
//! at an external crate, or at a name imported under another name, are not followed.

use std::collections::{BTreeMap, BTreeSet};

/// A module's path from the crate root (`["calibration", "procedure", "error"]`).
pub type ModulePath = Vec<String>;

/// One leaf of a `use` tree: the full path as written and the name it binds (its last
/// segment, or its alias; `*` for a glob).
#[derive(Clone, Debug, PartialEq)]
struct UseLeaf {
    path: Vec<String>,
    binds: String,
}

/// The files of a crate as module paths and their shipped code (comments and strings removed).
pub struct Crate {
    code: BTreeMap<ModulePath, String>,
}

/// The module path of a file under `src/`: `a/b.rs` and `a/b/mod.rs` are `a::b`; `lib.rs`
/// and `main.rs` are the root.
pub fn module_path(relative: &std::path::Path) -> ModulePath {
    let mut parts: Vec<String> = relative.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    let last = parts.pop().unwrap_or_default();
    let stem = last.trim_end_matches(".rs");
    if !matches!(stem, "mod" | "lib" | "main") {
        parts.push(stem.to_string());
    }
    parts
}

/// Tokens of code: identifiers (keywords included), `::`, and single punctuation characters.
fn tokens(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let chars: Vec<char> = code.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_alphanumeric() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            out.push(chars[start..i].iter().collect());
        } else if c == ':' && chars.get(i + 1) == Some(&':') {
            out.push("::".into());
            i += 2;
        } else {
            if !c.is_whitespace() {
                out.push(c.to_string());
            }
            i += 1;
        }
    }
    out
}

/// The leaves of the `use` tree starting at `toks[*at]` (after `use`), up to its `;`.
fn use_tree(toks: &[String], at: &mut usize, prefix: &[String], out: &mut Vec<UseLeaf>) {
    let mut path = prefix.to_vec();
    while *at < toks.len() {
        let t = toks[*at].as_str();
        *at += 1;
        match t {
            "::" => {}
            "{" => {
                loop {
                    use_tree(toks, at, &path, out);
                    match toks.get(*at).map(String::as_str) {
                        Some(",") => *at += 1,
                        Some("}") => {
                            *at += 1;
                            break;
                        }
                        _ => break,
                    }
                    if toks.get(*at).map(String::as_str) == Some("}") {
                        *at += 1;
                        break;
                    }
                }
                return;
            }
            "as" => {
                let alias = toks.get(*at).cloned().unwrap_or_default();
                *at += 1;
                out.push(UseLeaf { path, binds: alias });
                return;
            }
            "," | "}" | ";" => {
                *at -= 1;
                if let Some(leaf) = leaf_of(path, prefix) {
                    out.push(leaf);
                }
                return;
            }
            "*" => {
                out.push(UseLeaf {
                    path,
                    binds: "*".into(),
                });
                return;
            }
            name => path.push(name.to_string()),
        }
    }
}

/// The leaf a finished path binds: `a::b` binds `b`; `a::{self}` binds `a`.
fn leaf_of(mut path: Vec<String>, prefix: &[String]) -> Option<UseLeaf> {
    if path.len() == prefix.len() {
        return None;
    }
    if path.last().is_some_and(|l| l == "self") {
        path.pop();
    }
    let binds = path.last()?.clone();
    Some(UseLeaf { path, binds })
}

/// A path as written and the number of inline modules (`mod m { .. }`) around it.
type Written = (Vec<String>, usize);

/// Every `use` leaf of `code` and every other `crate::`/`super::`/`self::` path in it, each
/// with the inline modules around it.
fn paths_of(code: &str) -> (Vec<(UseLeaf, usize)>, Vec<Written>) {
    let toks = tokens(code);
    let (mut uses, mut paths) = (Vec::new(), Vec::new());
    // The brace depths at which the inline modules around the current token opened.
    let (mut depth, mut inline) = (0usize, Vec::new());
    let mut i = 0;
    while i < toks.len() {
        match toks[i].as_str() {
            "use" => {
                i += 1;
                let mut leaves = Vec::new();
                use_tree(&toks, &mut i, &[], &mut leaves);
                uses.extend(leaves.into_iter().map(|l| (l, inline.len())));
                continue;
            }
            "mod" if toks.get(i + 2).is_some_and(|t| t == "{") => {
                inline.push(depth);
                depth += 1;
                i += 3;
                continue;
            }
            "{" => depth += 1,
            "}" => {
                depth = depth.saturating_sub(1);
                if inline.last() == Some(&depth) {
                    inline.pop();
                }
            }
            _ => {}
        }
        let starts_path = matches!(toks[i].as_str(), "crate" | "super" | "self")
            && (i == 0 || toks[i - 1] != "::")
            && toks.get(i + 1).is_some_and(|t| t == "::");
        if starts_path {
            let mut path = vec![toks[i].clone()];
            i += 1;
            while toks.get(i).is_some_and(|t| t == "::") && toks.get(i + 1).is_some_and(|t| is_ident(t)) {
                path.push(toks[i + 1].clone());
                i += 2;
            }
            paths.push((path, inline.len()));
            continue;
        }
        i += 1;
    }
    (uses, paths)
}

fn is_ident(t: &str) -> bool {
    t.chars().next().is_some_and(|c| c.is_alphabetic() || c == '_')
}

impl Crate {
    /// A crate from its files: module path and shipped code.
    pub fn new(code: BTreeMap<ModulePath, String>) -> Self {
        Crate { code }
    }

    /// `path` as written in module `from` inside `inline` inline modules, made absolute:
    /// `crate::`, `super::`, `self::`, or a child module's name; `None` for anything else (an
    /// external crate, an imported name). An inline module's items count as its file's.
    fn absolute(&self, from: &ModulePath, (path, inline): (&[String], usize)) -> Option<ModulePath> {
        let mut base = from.clone();
        let mut rest = path;
        let mut inline = inline;
        match rest.first().map(String::as_str) {
            Some("crate") => {
                base.clear();
                rest = &rest[1..];
            }
            Some("self") => rest = &rest[1..],
            Some("super") => {
                while rest.first().is_some_and(|s| s == "super") {
                    if inline > 0 {
                        inline -= 1;
                    } else {
                        base.pop()?;
                    }
                    rest = &rest[1..];
                }
            }
            Some(first) if inline == 0 => {
                let mut child = from.clone();
                child.push(first.to_string());
                if !self.code.contains_key(&child) {
                    return None;
                }
            }
            _ => return None,
        }
        base.extend(rest.iter().cloned());
        Some(base)
    }

    /// The module whose file defines what the absolute `path` names, following imports.
    fn defining_module(&self, path: &ModulePath, depth: usize) -> Option<ModulePath> {
        let k = (0..=path.len()).rev().find(|&k| self.code.contains_key(&path[..k]))?;
        let module = path[..k].to_vec();
        if k == path.len() || depth > 16 {
            return Some(module);
        }
        let name = &path[k];
        let (uses, _) = paths_of(&self.code[&module]);
        let Some((leaf, _)) = uses.iter().find(|(u, inline)| &u.binds == name && *inline == 0) else {
            return Some(module);
        };
        let mut target = self.absolute(&module, (&leaf.path, 0))?;
        target.extend(path[k + 1..].iter().cloned());
        self.defining_module(&target, depth + 1)
    }

    /// The arrows from each module under `layer` to the other modules under it whose items it
    /// names.
    pub fn arrows(&self, layer: &str) -> BTreeMap<ModulePath, BTreeSet<ModulePath>> {
        self.arrows_with_paths(layer)
            .into_iter()
            .map(|(m, targets)| (m, targets.into_keys().collect()))
            .collect()
    }

    /// [`Crate::arrows`] with, for each arrow, the paths as written that make it.
    pub fn arrows_with_paths(&self, layer: &str) -> BTreeMap<ModulePath, BTreeMap<ModulePath, Vec<String>>> {
        let inside = |m: &ModulePath| m.first().is_some_and(|f| f == layer);
        let mut arrows = BTreeMap::new();
        for (module, code) in self.code.iter().filter(|(m, _)| inside(m)) {
            let (uses, paths) = paths_of(code);
            let mut targets: BTreeMap<ModulePath, Vec<String>> = BTreeMap::new();
            for (path, inline) in uses.into_iter().map(|(u, inline)| (u.path, inline)).chain(paths) {
                let target = self
                    .absolute(module, (&path, inline))
                    .and_then(|p| self.defining_module(&p, 0));
                if let Some(t) = target.filter(|t| inside(t) && t != module) {
                    targets.entry(t).or_default().push(path.join("::"));
                }
            }
            arrows.insert(module.clone(), targets);
        }
        arrows
    }
}

/// The cycles of `arrows`, each once, as the modules around it (the strongly connected
/// components of more than one module).
pub fn cycles(arrows: &BTreeMap<ModulePath, BTreeSet<ModulePath>>) -> Vec<Vec<ModulePath>> {
    let reach = |from: &ModulePath| -> BTreeSet<ModulePath> {
        let mut seen = BTreeSet::new();
        let mut stack = vec![from.clone()];
        while let Some(m) = stack.pop() {
            for next in arrows.get(&m).into_iter().flatten() {
                if seen.insert(next.clone()) {
                    stack.push(next.clone());
                }
            }
        }
        seen
    };
    let reachable: BTreeMap<&ModulePath, BTreeSet<ModulePath>> = arrows.keys().map(|m| (m, reach(m))).collect();
    let mut done = BTreeSet::new();
    let mut out = Vec::new();
    for m in arrows.keys() {
        if done.contains(m) || !reachable[m].contains(m) {
            continue;
        }
        let component: Vec<ModulePath> = arrows
            .keys()
            .filter(|o| reachable[m].contains(*o) && reachable[*o].contains(m))
            .cloned()
            .collect();
        done.extend(component.iter().cloned());
        out.push(component);
    }
    out
}
