//! A URDF file's text checked before it is parsed, so that a slip is said with its line and
//! element: element nesting deeper than a URDF has (which would exhaust the parser's stack),
//! elements not closed or closed out of order (a file cut short), a number the parser would
//! refuse without saying where (a decimal comma, a vector of two values), a joint type URDF
//! does not have, a joint without its parent or child link, an attribute URDF requires
//! missing, a root element other than `<robot>`, a file without elements; and a hint for the
//! parser's own refusal of a document type declaration's internal subset.
//!
//! The markup is that of XML 1.0 (W3C, 5th ed.): start tags `<name ...>` open an element (3.1)
//! unless empty-element tags `<name .../>`; end tags `</name>` close one; comments `<!-- -->`
//! (2.5), CDATA sections `<![CDATA[ ]]>` (2.7), the document type declaration
//! `<!DOCTYPE ... [ ... ]>` (2.8) and processing instructions `<? ?>` (2.6) open none; quoted
//! attribute values may hold `>` (3.1). The URDF elements and attributes are those of the ROS
//! URDF XML specification (wiki.ros.org/urdf/XML: `joint`, `link` and their children).

use crate::csv_lines::{is_decimal_comma, shown_cell};

/// The deepest element nesting a URDF may have (docs/formats.md#robot-description): real
/// URDFs nest 5 to 10 levels; the XML parser recurses once per level, so a file nested
/// thousands deep would exhaust the stack.
pub const MAX_URDF_DEPTH: usize = 100;

/// The joint types of URDF (`<joint type=...>`).
const JOINT_TYPES: [&str; 7] = [
    "revolute",
    "continuous",
    "prismatic",
    "fixed",
    "floating",
    "planar",
    "spherical",
];

/// What a piece of markup is.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    /// `<name ...>`.
    Start,
    /// `<name .../>`.
    Empty,
    /// `</name>`.
    End,
    /// A comment, CDATA section, declaration or processing instruction.
    Other,
}

/// One piece of markup: its 1-based line, kind, element name (a declaration's keyword) and
/// attribute text (the rest of a declaration).
struct Markup<'a> {
    line: usize,
    kind: Kind,
    name: &'a str,
    attributes: &'a str,
}

/// The markup of `text` in order: one linear pass over the bytes (module doc).
fn markup(text: &str) -> Vec<Markup<'_>> {
    let b = text.as_bytes();
    let (mut i, mut line, mut out) = (0, 1, Vec::new());
    // The index just past the first `end` at or after `from` (the text's end if none).
    let skip_to = |from: usize, end: &[u8]| {
        b[from..]
            .windows(end.len())
            .position(|w| w == end)
            .map_or(b.len(), |p| from + p + end.len())
    };
    while i < b.len() {
        if b[i] != b'<' {
            line += usize::from(b[i] == b'\n');
            i += 1;
            continue;
        }
        let rest = &b[i..];
        let (next, piece) = if rest.starts_with(b"<!--") {
            (skip_to(i + 4, b"-->"), None)
        } else if rest.starts_with(b"<![CDATA[") {
            (skip_to(i + 9, b"]]>"), None)
        } else if rest.starts_with(b"<?") {
            (skip_to(i + 2, b"?>"), None)
        } else if rest.starts_with(b"<!") {
            // A declaration (`<!DOCTYPE ...>`): its keyword as the name, the rest as attributes.
            let end = tag_end(b, i + 1).0;
            let body = &text[(i + 2).min(end)..end];
            let keyword_end = body.find(char::is_whitespace).unwrap_or(body.len());
            (end, Some((Kind::Other, &body[..keyword_end], &body[keyword_end..])))
        } else {
            let (end, empty) = tag_end(b, i + 1);
            let closing = rest.starts_with(b"</");
            // An unterminated tag (the text's end) keeps the rest of the text.
            let body_end = if b[end - 1] == b'>' {
                end - 1 - usize::from(empty)
            } else {
                end
            };
            let body = &text[(i + 1 + usize::from(closing)).min(body_end)..body_end];
            let name_end = body
                .find(|c: char| c.is_whitespace() || c == '/' || c == '>')
                .unwrap_or(body.len());
            let kind = match (closing, empty) {
                (true, _) => Kind::End,
                (false, true) => Kind::Empty,
                (false, false) => Kind::Start,
            };
            (end, Some((kind, &body[..name_end], &body[name_end..])))
        };
        let (kind, name, attributes) = piece.unwrap_or((Kind::Other, "", ""));
        out.push(Markup {
            line,
            kind,
            name,
            attributes,
        });
        line += b[i..next].iter().filter(|&&c| c == b'\n').count();
        i = next;
    }
    out
}

/// The index just past the `>` that ends the markup starting before `from`, skipping quoted
/// values and a declaration's `[...]` subset; and whether it is an empty-element tag (`/>`).
fn tag_end(b: &[u8], from: usize) -> (usize, bool) {
    let (mut quote, mut bracket) = (None, 0usize);
    for (k, &c) in b.iter().enumerate().skip(from) {
        match (quote, c) {
            (Some(q), _) if c == q => quote = None,
            (Some(_), _) => {}
            (None, b'"' | b'\'') => quote = Some(c),
            (None, b'[') => bracket += 1,
            (None, b']') => bracket = bracket.saturating_sub(1),
            (None, b'>') if bracket == 0 => return (k + 1, k > from && b[k - 1] == b'/'),
            _ => {}
        }
    }
    (b.len(), false)
}

/// The 1-based line where `text`'s element nesting first exceeds `max`, and that depth; `None`
/// when it stays within.
pub fn nesting_beyond(text: &str, max: usize) -> Option<(usize, usize)> {
    let mut depth = 0usize;
    for m in markup(text) {
        match m.kind {
            Kind::End => depth = depth.saturating_sub(1),
            Kind::Start => {
                depth += 1;
                if depth > max {
                    return Some((m.line, depth));
                }
            }
            Kind::Empty | Kind::Other => {}
        }
    }
    None
}

/// The attributes of a tag's attribute text, `name="value"` or `name='value'`, each with the
/// number of line breaks before it in the tag; they stop at the first that is not so written
/// (the parser says what is wrong there).
fn attributes(text: &str) -> Vec<(&str, &str, usize)> {
    let mut out = Vec::new();
    let mut rest = text;
    loop {
        let trimmed = rest.trim_start();
        let Some(eq) = trimmed.find('=') else { break };
        let name = trimmed[..eq].trim();
        let after = trimmed[eq + 1..].trim_start();
        let Some(quote) = after.chars().next().filter(|c| *c == '"' || *c == '\'') else {
            break;
        };
        let Some(close) = after[1..].find(quote) else { break };
        if name.is_empty() || name.contains(char::is_whitespace) {
            break;
        }
        let breaks = text[..text.len() - trimmed.len()].matches('\n').count();
        out.push((name, &after[1..1 + close], breaks));
        rest = &after[close + 2..];
    }
    out
}

/// The number of values a URDF attribute of `element` holds, for the numeric ones
/// (wiki.ros.org/urdf/XML); `None` for others.
fn numeric_arity(element: &str, attribute: &str) -> Option<usize> {
    match (element, attribute) {
        ("origin", "xyz" | "rpy") | ("axis", "xyz") | ("box", "size") | ("mesh", "scale") => Some(3),
        ("color", "rgba") => Some(4),
        ("limit", "lower" | "upper" | "effort" | "velocity")
        | ("mass", "value")
        | ("inertia", "ixx" | "ixy" | "ixz" | "iyy" | "iyz" | "izz")
        | ("dynamics", "damping" | "friction")
        | ("cylinder" | "capsule", "radius" | "length")
        | ("sphere", "radius")
        | ("mimic", "multiplier" | "offset")
        | ("safety_controller", "soft_lower_limit" | "soft_upper_limit" | "k_position" | "k_velocity")
        | ("calibration", "rising" | "falling") => Some(1),
        _ => None,
    }
}

/// What is wrong with one numeric attribute's value (`arity` values separated by spaces), in
/// words; `None` when nothing is.
fn number_problem(attribute: &str, value: &str, arity: usize) -> Option<String> {
    if value.contains('&') {
        // A character or entity reference (`&#10;`), which the parser resolves first.
        return None;
    }
    let tokens: Vec<&str> = value.split_whitespace().collect();
    if let Some(bad) = tokens.iter().find(|t| t.parse::<f64>().is_err()) {
        let by_commas: Vec<&str> = value.split(',').map(str::trim).collect();
        let hint = if value.contains("${") || value.contains("$(") {
            "; this is a xacro expression: expand the file first (`xacro robot.urdf.xacro > robot.urdf`)".to_string()
        } else if tokens.len() == arity && tokens.iter().all(|t| t.parse::<f64>().is_ok() || is_decimal_comma(t)) {
            format!(
                "; a URDF writes a decimal point (`{}`?)",
                shown_cell(&tokens.iter().map(|t| t.replace(',', ".")).collect::<Vec<_>>().join(" "))
            )
        } else if by_commas.len() == arity && by_commas.iter().all(|t| t.parse::<f64>().is_ok()) {
            format!(
                "; a URDF separates values by spaces (`{}`?)",
                shown_cell(&by_commas.join(" "))
            )
        } else {
            String::new()
        };
        return Some(format!("`{}` is not a number{hint}", shown_cell(bad)));
    }
    (tokens.len() != arity).then(|| {
        format!(
            "`{attribute}` holds {} value(s); it takes {arity}, separated by spaces",
            tokens.len()
        )
    })
}

/// An element open while the text is read: its name, line, `name` attribute, children seen.
struct Open<'a> {
    element: &'a str,
    line: usize,
    named: Option<&'a str>,
    children: Vec<&'a str>,
}

/// Where a problem lies, in words: `line N: joint `j`: ` (the nearest joint or link open).
fn place(line: usize, open: &[Open<'_>]) -> String {
    let owner = open
        .iter()
        .rev()
        .find(|o| matches!(o.element, "joint" | "link"))
        .map(|o| format!("{} `{}`: ", o.element, o.named.unwrap_or("?")));
    format!("line {line}: {}", owner.unwrap_or_default())
}

/// The first problem of one start or empty tag's attributes (module doc), `open` the elements
/// it is inside.
fn tag_problem(m: &Markup<'_>, open: &[Open<'_>]) -> Option<String> {
    let in_robot_part = open.len() >= 2 && matches!(open[1].element, "joint" | "link");
    let in_joint = open.len() == 1 && m.name == "joint";
    let own_name = attributes(m.attributes)
        .into_iter()
        .find(|a| a.0 == "name")
        .map(|a| a.1);
    let at = |line: usize| match (in_joint, own_name) {
        (true, Some(name)) => format!("line {line}: joint `{name}`: "),
        _ => place(line, open),
    };
    for (attribute, value, breaks) in attributes(m.attributes) {
        let line = m.line + breaks;
        if in_joint && attribute == "type" && !JOINT_TYPES.contains(&value) {
            return Some(format!(
                "{}joint type `{}`: a URDF joint is {}",
                at(line),
                shown_cell(value),
                JOINT_TYPES.map(|t| format!("`{t}`")).join(", ")
            ));
        }
        let arity = numeric_arity(m.name, attribute).filter(|_| in_robot_part || in_joint);
        if let Some(why) = arity.and_then(|n| number_problem(attribute, value, n)) {
            return Some(format!(
                "{}`<{} {attribute}=\"{}\">`: {why}",
                at(line),
                m.name,
                shown_cell(value)
            ));
        }
    }
    None
}

/// The attributes URDF requires of an element (wiki.ros.org/urdf/XML) at its place: a joint's
/// and a link's (in the robot), a joint's parent's, child's and mimic's (in a joint).
fn required_attributes(element: &str, open: &[Open<'_>]) -> &'static [&'static str] {
    match (open.len(), element) {
        (1, "joint") => &["name", "type"],
        (1, "link") => &["name"],
        (2, "parent" | "child") if open[1].element == "joint" => &["link"],
        (2, "mimic") if open[1].element == "joint" => &["joint"],
        _ => &[],
    }
}

/// The first problem of a start or empty tag's place and required attributes: the root
/// element not `<robot>`, an attribute URDF requires missing.
fn structure_problem(m: &Markup<'_>, open: &[Open<'_>]) -> Option<String> {
    if open.is_empty() && m.name != "robot" {
        return Some(format!(
            "line {}: the root element is `<{}>`: a URDF's is `<robot name=\"...\">`, holding the links and joints",
            m.line,
            shown_cell(m.name)
        ));
    }
    let given = attributes(m.attributes);
    let missing = required_attributes(m.name, open)
        .iter()
        .find(|r| !given.iter().any(|a| a.0 == **r))?;
    Some(format!(
        "{}`<{}>` has no `{missing}=\"...\"`: a URDF `<{}>` {}",
        place(m.line, open),
        m.name,
        m.name,
        match *missing {
            "link" => "names its link",
            "joint" => "names the joint it follows",
            "type" => "needs its type (`revolute`, `prismatic`, `fixed`, ...)",
            _ => "needs a name",
        }
    ))
}

/// What to add to the XML parser's message `said` on `text`: that a document type
/// declaration's internal subset is why it fails (the parser of urdf-rs reads an entity
/// declaration, or an element declaration, alone, but not the one followed by the other), and
/// what to do.
pub fn parser_hint(text: &str, said: &str) -> Option<String> {
    if !said.contains("Malformed XML") {
        return None;
    }
    let line = markup(text)
        .iter()
        .find(|m| m.kind == Kind::Other && m.name == "DOCTYPE" && m.attributes.contains('['))?
        .line;
    Some(format!(
        "; the document type declaration of line {line} holds an internal subset (`<!DOCTYPE robot [ ... ]>`), \
         which the URDF parser reads only in part (an `<!ENTITY` followed by another declaration fails): delete \
         the declarations a URDF does not need (`<!ELEMENT`, `<!ATTLIST`), keeping any `<!ENTITY` the file uses"
    ))
}

/// The first problem of `text` as a URDF (module doc), in words with its line; `None` when the
/// text has none of them (the parser may still refuse it).
pub fn urdf_text_problem(text: &str) -> Option<String> {
    let pieces = markup(text);
    let mut open: Vec<Open<'_>> = Vec::new();
    for m in &pieces {
        match m.kind {
            Kind::Other => {}
            Kind::Start | Kind::Empty => {
                if let Some(why) = structure_problem(m, &open).or_else(|| tag_problem(m, &open)) {
                    return Some(why);
                }
                let named = attributes(m.attributes)
                    .into_iter()
                    .find(|a| a.0 == "name")
                    .map(|a| a.1);
                let this = Open {
                    element: m.name,
                    line: m.line,
                    named,
                    children: Vec::new(),
                };
                if m.kind == Kind::Start {
                    open.push(this);
                } else if let Some(why) = joint_links_problem(&this, open.len()) {
                    return Some(why);
                } else if let Some(parent) = open.last_mut() {
                    parent.children.push(m.name);
                }
            }
            Kind::End => {
                if let Some(why) = close(m, &mut open) {
                    return Some(why);
                }
            }
        }
    }
    if !pieces.iter().any(|m| m.kind != Kind::Other) {
        return Some(
            "the file holds no element (it is empty, or only declarations and comments): a URDF is one \
             `<robot name=\"...\">` element holding the links and joints"
                .into(),
        );
    }
    let last = text.lines().count();
    open.first().map(|o| {
        format!(
            "`<{}>` of line {} is never closed: the file ends at line {last} (cut short, or its `</{}>` missing)",
            o.element, o.line, o.element
        )
    })
}

/// Closes the element open last with the end tag `m`: a problem when it closes another
/// element, none, or a joint without its parent or child link.
fn close<'a>(m: &Markup<'a>, open: &mut Vec<Open<'a>>) -> Option<String> {
    let Some(top) = open.pop() else {
        return Some(format!("line {}: `</{}>` closes no element", m.line, m.name));
    };
    if top.element != m.name {
        return Some(format!(
            "line {}: `</{}>` where `<{}>` of line {} is open: the elements are not nested properly (a closing tag misspelt, missing or in the wrong place)",
            m.line, m.name, top.element, top.line
        ));
    }
    if let Some(why) = joint_links_problem(&top, open.len()) {
        return Some(why);
    }
    if let Some(parent) = open.last_mut() {
        parent.children.push(top.element);
    }
    None
}

/// A joint of the robot (`depth` elements open around it) closed without its parent or child
/// link.
fn joint_links_problem(joint: &Open<'_>, depth: usize) -> Option<String> {
    if joint.element != "joint" || depth != 1 {
        return None;
    }
    let missing = ["parent", "child"].into_iter().find(|c| !joint.children.contains(c))?;
    Some(format!(
        "line {}: joint `{}` has no `<{missing} link=\"...\"/>`: a URDF joint names its parent and child links",
        joint.line,
        joint.named.unwrap_or("?")
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nesting_counts_elements_not_comments_declarations_or_empty_tags() {
        let deep = |n: usize| format!("<robot>{}{}</robot>", "<a>".repeat(n), "</a>".repeat(n));
        assert_eq!(nesting_beyond(&deep(99), 100), None);
        assert_eq!(nesting_beyond(&deep(100), 100), Some((1, 101)));
        let text = "<?xml version=\"1.0\"?>\n<!DOCTYPE r [<!ENTITY e \"<a>\">]>\n<!-- <a><a> -->\n\
                    <robot name=\"a>b\">\n<link name=\"x\"/><![CDATA[<a><a>]]>\n<a>\n</robot>";
        assert_eq!(nesting_beyond(text, 2), None);
        assert_eq!(nesting_beyond(text, 1), Some((6, 2)));
    }

    proptest::proptest! {
        /// Any text, markup-like or not, gives a problem or none, never a panic (a tag cut
        /// short inside a multi-byte character, a lone `<`).
        #[test]
        fn any_text_is_checked_without_a_panic(text in "(<|>|/|\"|'|=|robot|joint|link|origin|xyz|é|€| |\n|[a-z0-9.,-])*") {
            let _ = urdf_text_problem(&text);
            let _ = nesting_beyond(&text, 3);
        }
    }

    /// A two-joint URDF, each slip of the module doc made once in it: each is said with its
    /// line (and joint), the clean file has none.
    #[test]
    fn each_slip_is_said_with_its_line() {
        let clean = "<?xml version=\"1.0\"?>\n<robot name=\"r\">\n  <link name=\"a\"/>\n  <link name=\"b\">\n    \
                     <inertial><mass value=\"2.5\"/><origin xyz=\"0 0 0.1\"/></inertial>\n  </link>\n  \
                     <joint name=\"j1\" type=\"revolute\">\n    <parent link=\"a\"/><child link=\"b\"/>\n    \
                     <origin xyz=\"0 0 0.346\" rpy=\"0 0 0\"/><axis xyz=\"0 0 1\"/>\n    \
                     <limit lower=\"-3.14\" upper=\"3.14\" effort=\"0\" velocity=\"0\"/>\n  </joint>\n  \
                     <gazebo><origin xyz=\"not numbers\"/></gazebo>\n</robot>\n";
        assert_eq!(urdf_text_problem(clean), None);
        let said = |from: &str, to: &str| {
            assert_eq!(clean.matches(from).count(), 1, "{from}");
            urdf_text_problem(&clean.replace(from, to)).unwrap_or_default()
        };
        let comma = said("0 0 0.346", "0 0 0,346");
        assert!(
            comma.starts_with("line 9: joint `j1`: `<origin xyz=\"0 0 0,346\">`: `0,346` is not a number; a URDF writes a decimal point")
                && comma.contains("(`0 0 0.346`?)"),
            "{comma}"
        );
        assert!(
            said("xyz=\"0 0 1\"", "xyz=\"0 1\"")
                .contains("line 9: joint `j1`: `<axis xyz=\"0 1\">`: `xyz` holds 2 value(s); it takes 3")
        );
        assert!(
            said("value=\"2.5\"", "value=\"heavy\"")
                .contains("line 5: link `b`: `<mass value=\"heavy\">`: `heavy` is not a number")
        );
        assert!(
            said("type=\"revolute\"", "type=\"custom\"")
                .starts_with("line 7: joint `j1`: joint type `custom`: a URDF joint is `revolute`")
        );
        let separated = said("0 0 0.346", "0,0,0.346");
        assert!(
            separated.contains("a URDF separates values by spaces (`0 0 0.346`?)"),
            "{separated}"
        );
        assert_eq!(urdf_text_problem(&clean.replace("0 0 0.346", "0&#10;0&#9;0.346")), None);
        assert!(said("0 0 0.346", "0 0 ${l1}").ends_with("`${l1}` is not a number; this is a xacro expression: expand the file first (`xacro robot.urdf.xacro > robot.urdf`)"));
        assert!(said("<parent link=\"a\"/>", "").starts_with("line 7: joint `j1` has no `<parent link="));
        assert!(said("</robot>", "").starts_with("`<robot>` of line 2 is never closed: the file ends at line 13"));
        assert!(
            said("  </joint>", "  </joint_>").starts_with("line 11: `</joint_>` where `<joint>` of line 7 is open")
        );
        assert!(
            said("</inertial>", "</inertial></link>")
                .starts_with("line 6: `</link>` where `<robot>` of line 2 is open")
        );
        assert!(said(" type=\"revolute\"", "").starts_with("line 7: `<joint>` has no `type=\"...\"`"));
        assert!(said("<link name=\"a\"/>", "<link/>").starts_with("line 3: `<link>` has no `name=\"...\"`"));
        assert!(
            said("<child link=\"b\"/>", "<child/>").starts_with("line 8: joint `j1`: `<child>` has no `link=\"...\"`")
        );
        let self_closed = clean.replace(
            "<joint name=\"j1\" type=\"revolute\">",
            "<joint name=\"j1\" type=\"revolute\"/><joint name=\"j2\" type=\"fixed\">",
        );
        assert!(
            urdf_text_problem(&self_closed)
                .unwrap_or_default()
                .starts_with("line 7: joint `j1` has no `<parent link=")
        );
        assert!(
            said("<robot name=\"r\">", "<urdf name=\"r\"><robot>").starts_with("line 2: the root element is `<urdf>`")
        );
        for empty in ["", "  \n", "<?xml version=\"1.0\"?>\n<!-- nothing -->\n"] {
            assert!(
                urdf_text_problem(empty)
                    .unwrap_or_default()
                    .starts_with("the file holds no element")
            );
        }
        let subset = clean.replace(
            "<robot name",
            "<!DOCTYPE robot [\n<!ENTITY l \"0.1\">\n<!ELEMENT robot ANY>\n]>\n<robot name",
        );
        assert_eq!(urdf_text_problem(&subset), None);
        assert!(
            parser_hint(&subset, "Parse error; Line: 3, Column: 1, Reason: Malformed XML")
                .is_some_and(|h| h.contains("the document type declaration of line 2 holds an internal subset"))
        );
        assert_eq!(parser_hint(&subset, "Duplicate attribute"), None);
        assert_eq!(parser_hint(clean, "Malformed XML"), None);
    }
}
