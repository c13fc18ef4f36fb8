//! Text from the user's files (a robot's name, a path, an experiment's name) written into the
//! Markdown reports: escaped so that it shows as written, never as HTML, a table's column
//! break, a heading or emphasis (CommonMark 0.31, "Backslash escapes" and "Code spans"; GFM's
//! tables for `|`).

/// `text` as literal Markdown text, in a paragraph, a heading or a table cell: each ASCII
/// character with a meaning inside a line of Markdown backslash-escaped (`<` as `\<`, so no HTML tag opens;
/// `|` as `\|`, so no table cell ends), each control character written as its escape (`\n`),
/// so no line ends inside it.
pub fn text(text: &str) -> String {
    const SPECIAL: &str = "\\`*[]<>&|~";
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    for (i, &c) in chars.iter().enumerate() {
        let inside_a_word = |k: Option<usize>| k.and_then(|k| chars.get(k)).is_some_and(|n| n.is_alphanumeric());
        match c {
            c if c.is_control() => out.extend(c.escape_default()),
            // `snake_case` is no emphasis (an underscore between letters opens none).
            '_' if inside_a_word(i.checked_sub(1)) && inside_a_word(Some(i + 1)) => out.push(c),
            c if SPECIAL.contains(c) || c == '_' => {
                out.push('\\');
                out.push(c);
            }
            c => out.push(c),
        }
    }
    out
}

/// `text` as one inline code span in a paragraph or heading (not in a table: use [`text`]):
/// opened and closed by one backtick more than the longest run of backticks inside, padded by a
/// space where it begins or ends with one, each control character written as its escape. A code
/// span shows its content as written: no HTML, no emphasis.
pub fn code(text: &str) -> String {
    let body = crate::csv_lines::one_line(text);
    let longest_run = body.split(|c| c != '`').map(str::len).max().unwrap_or(0);
    let fence = "`".repeat(longest_run + 1);
    let pad = match body.starts_with('`') || body.ends_with('`') {
        true => " ",
        false => "",
    };
    format!("{fence}{pad}{body}{pad}{fence}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn html_table_breaks_and_line_ends_in_text_show_as_written() {
        let hostile = "<img src=x onerror=alert(1)>|a\nb *c* [d](e)";
        let t = text(hostile);
        assert!(!t.contains('\n'));
        // Every `<` and `|` is escaped: none stands bare.
        for (i, c) in t.char_indices() {
            if c == '<' || c == '|' {
                assert_eq!(&t[i - 1..i], "\\", "{t}");
            }
        }
        // A plain name is unchanged.
        assert_eq!(text("axis_6 ASEA IRB/L6 (7L)"), "axis_6 ASEA IRB/L6 (7L)");
        assert_eq!(text("_a_ *b*"), "\\_a\\_ \\*b\\*");
    }

    #[test]
    fn a_code_span_fence_is_longer_than_any_backtick_run_inside() {
        assert_eq!(code("data/a.csv"), "`data/a.csv`");
        assert_eq!(code("a`b"), "``a`b``");
        assert_eq!(code("``x"), "``` ``x ```");
        assert_eq!(code("a\nb"), "`a\\nb`");
    }
}
