//! Every relative link of the README, ARCHITECTURE.md, CHANGELOG.md and `docs/` reaches a file
//! that exists and, where it names a heading (`FILE.md#anchor`), a heading or `<a id>` of that
//! file: a section moved between documents leaves no link behind. Anchors follow GitHub's rule
//! (lower case; letters, digits, `_`, `-` and spaces kept, spaces to `-`; a repeated heading
//! gets `-1`, `-2`, ...).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The Markdown files the links are read from.
fn documents() -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = ["README.md", "ARCHITECTURE.md", "CHANGELOG.md"]
        .iter()
        .map(|f| repo().join(f))
        .filter(|p| p.exists())
        .collect();
    let mut dirs = vec![repo().join("docs")];
    while let Some(dir) = dirs.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "md") {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// GitHub's anchor of a heading's text.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, '-' | '_' | ' '))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The lines outside fenced code blocks.
fn prose_lines(text: &str) -> Vec<&str> {
    let mut fenced = false;
    text.lines()
        .filter(|line| {
            if line.trim_start().starts_with("```") {
                fenced = !fenced;
                return false;
            }
            !fenced
        })
        .collect()
}

/// The anchors of a document: its headings' slugs (numbered when repeated) and `<a id="...">`.
fn anchors(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut repeats: BTreeMap<String, usize> = BTreeMap::new();
    for line in prose_lines(text) {
        if let Some(heading) = line.strip_prefix('#').map(|h| h.trim_start_matches('#'))
            && heading.starts_with(' ')
        {
            let base = slug(heading);
            let n = repeats.entry(base.clone()).or_insert(0);
            out.insert(if *n == 0 { base.clone() } else { format!("{base}-{n}") });
            *n += 1;
        }
        let mut rest = line;
        while let Some(i) = rest.find("<a id=\"") {
            rest = &rest[i + 7..];
            if let Some(end) = rest.find('"') {
                out.insert(rest[..end].to_owned());
            }
        }
    }
    out
}

/// The relative link targets `](target)` of a document, with the line they are on.
fn links(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut fenced = false;
    for (i, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        let mut rest = line;
        while let Some(start) = rest.find("](") {
            rest = &rest[start + 2..];
            let Some(end) = rest.find(')') else { break };
            let target = &rest[..end];
            if !target.contains("://") && !target.starts_with("mailto:") && !target.contains(' ') {
                out.push((i + 1, target.to_owned()));
            }
        }
    }
    out
}

#[test]
fn every_relative_link_reaches_its_file_and_heading() {
    let docs = documents();
    assert!(docs.len() > 5, "the documents are found: {docs:?}");
    let texts: BTreeMap<PathBuf, String> = docs
        .iter()
        .map(|p| (p.canonicalize().unwrap(), std::fs::read_to_string(p).unwrap()))
        .collect();
    let mut broken = Vec::new();
    let mut checked = 0;
    for (path, text) in &texts {
        for (line, target) in links(text) {
            let (file, anchor) = target
                .split_once('#')
                .map_or((target.as_str(), None), |(f, a)| (f, Some(a)));
            let resolved = if file.is_empty() {
                path.clone()
            } else {
                path.parent().unwrap().join(file)
            };
            let place = format!(
                "{}:{line}: {target}",
                path.strip_prefix(repo().canonicalize().unwrap())
                    .unwrap_or(path)
                    .display()
            );
            let Ok(resolved) = resolved.canonicalize() else {
                broken.push(format!("{place} (no such file)"));
                continue;
            };
            checked += 1;
            let Some(anchor) = anchor else { continue };
            let Some(target_text) = texts.get(&resolved) else {
                continue;
            };
            if !anchors(target_text).contains(anchor) {
                broken.push(format!("{place} (no such heading)"));
            }
        }
    }
    assert!(checked > 50, "links are read: {checked}");
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

#[test]
fn the_anchor_rule_is_githubs() {
    assert_eq!(
        slug("Refinement on free poses (`calibrate --refine`; measured 2026-11-24)"),
        "refinement-on-free-poses-calibrate---refine-measured-2026-11-24"
    );
    let text = "# A b\n\n```\n# not a heading\n```\n## A b\n<a id=\"x-y\"></a>\n";
    let found = anchors(text);
    assert_eq!(
        found,
        BTreeSet::from(["a-b".to_owned(), "a-b-1".to_owned(), "x-y".to_owned()])
    );
    assert!(Path::new(&repo()).join("docs").is_dir());
}
