//! Physical line numbers for CSV records read in one streaming pass.
//!
//! The csv crate reports where a record's read started (a byte offset) but its line counter
//! skips `#` comment lines, so a message would name the wrong line. [`LineTracking`] wraps
//! the source: as bytes pass through it notes where each line starts and whether that line is
//! a comment or blank; [`LineIndex::line_of`] then turns a record's byte offset into the
//! 1-based line of its first content line. Offsets are asked in increasing order (records
//! come in file order), so the index forgets every line start behind the last offset asked:
//! time is linear in the file and memory bounded by the reader's look-ahead.
//!
//! The same pass counts each line's commas, to find a `#` line that is a data row (an
//! experiment id starting with `#`): [`LineIndex::commented_row`].

use std::cell::RefCell;
use std::collections::VecDeque;
use std::io::Read;
use std::rc::Rc;

/// The CSV writer of every table axiscal writes: `,` between cells, `\n` after each record,
/// quotes only where needed, a cell holding `#` quoted too (axiscal's readers take `#` lines as
/// comments: an experiment id `#1` first in a row would start one).
pub fn writer<W: std::io::Write>(w: W) -> csv::Writer<W> {
    csv::WriterBuilder::new().comment(Some(b'#')).from_writer(w)
}

/// A table as [`writer`] writes it, into a string: `header`, then each of `rows`.
pub fn table_text(header: &[&str], rows: impl IntoIterator<Item = Vec<String>>) -> String {
    let mut w = writer(Vec::new());
    let written = std::iter::once(header.iter().map(|h| h.to_string()).collect())
        .chain(rows)
        .try_for_each(|row: Vec<String>| w.write_record(&row));
    // Writing into memory has no I/O to fail, and cells are UTF-8 strings.
    written
        .and_then(|()| w.flush().map_err(csv::Error::from))
        .expect("a CSV table into memory");
    String::from_utf8(w.into_inner().expect("a CSV table into memory")).expect("UTF-8 cells")
}

/// The separator, in words, a one-column CSV header `name` holds instead of commas (`;`, a
/// tab, `|`): the file was exported with another separator (often with decimal commas).
pub fn foreign_separator(name: &str) -> Option<&'static str> {
    [(';', "`;`"), ('\t', "a tab"), ('|', "`|`")]
        .into_iter()
        .find(|(c, _)| name.contains(*c))
        .map(|(_, words)| words)
}

/// A row with `fields` cells under a header of `columns` names, in words: a shifted row (a
/// decimal comma, a separator inside a value) would put its values in the wrong columns.
pub fn wider_than_header(fields: usize, columns: usize) -> String {
    format!(
        "the row has {fields} fields, the header {columns}: a decimal comma or a separator in a value, or a missing \
         header name?"
    )
}

/// Control bytes a text CSV never holds (C0 controls but tab, line feed, form feed and
/// carriage return; DEL): one of them in a file's start marks it as binary.
fn is_binary_byte(b: u8) -> bool {
    (b < 0x20 && !matches!(b, b'\t' | b'\n' | b'\r' | 0x0c)) || b == 0x7f
}

/// What a file whose first bytes are `start` is instead of a text CSV, by its first line that is
/// neither blank nor a `#` comment: binary (a control byte: C0 controls but tab, line feed, form
/// feed and carriage return; DEL), XML (a URDF: `<`), JSON (an object `{`, or an array `[` whose
/// line holds a quote or a comma or nothing more) or TOML (a `[table]` line, or a `key = value`
/// line: a bare or quoted key before the `=`); `None` when it may be a CSV.
pub fn not_text_csv(start: &[u8]) -> Option<String> {
    let head = &start[..start.len().min(4096)];
    if let Some(at) = head.iter().position(|&b| is_binary_byte(b)) {
        return Some(format!(
            "not a text file (binary): byte 0x{:02x} at offset {at}, a control character no CSV holds",
            head[at]
        ));
    }
    const CSV: &str =
        "a CSV whose first line names the columns (experiment,moved_joint,step,target,x_mm,y_mm,z_mm,cmd_1,..)";
    let text = String::from_utf8_lossy(head);
    let first = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))?;
    let json_array = first.starts_with('[') && (first == "[" || first.contains(['"', ',']));
    if first.starts_with('{') || json_array {
        return Some(format!("it looks like JSON (it starts with `{{` or `[`), not {CSV}"));
    }
    if first.starts_with('<') {
        let what = if text.contains("<robot") {
            "a URDF (XML): a robot description TOML points at it with `[urdf]` `file = ...`, given as --robot"
        } else {
            "XML"
        };
        return Some(format!("it looks like {what}, not {CSV}"));
    }
    let table = first.starts_with('[') && first.ends_with(']');
    let key = first.split_once('=').is_some_and(|(key, _)| {
        let key = key.trim();
        !key.is_empty() && key.chars().all(|c| c.is_ascii_alphanumeric() || "_-.\"".contains(c))
    });
    (table || key).then(|| {
        format!(
            "it looks like a TOML file (`key = value` lines, `[tables]`: a robot description, a scenario, a plan), not {CSV}; \
             a description is given as --robot"
        )
    })
}

/// What a number cell with a typographic minus sign holds, in words.
pub const TYPOGRAPHIC_MINUS: &str =
    "a typographic minus sign (U+2212 or a dash, as a word processor or spreadsheet writes)";

/// `text` with its typographic minus signs (U+2212, en and em dashes) as ASCII `-`, when that
/// makes a finite number of it.
pub fn with_ascii_minus(text: &str) -> Option<String> {
    let ascii = text.replace(['\u{2212}', '\u{2013}', '\u{2014}'], "-");
    (ascii != text && ascii.parse::<f64>().is_ok_and(f64::is_finite)).then_some(ascii)
}

/// Whether `cell` is a number written with a decimal comma (`-3108,48`: an optional sign,
/// digits, one comma, digits), as a locale with a decimal comma exports it.
pub fn is_decimal_comma(cell: &str) -> bool {
    cell.split_once(',').is_some_and(|(whole, fraction)| {
        let whole = whole.strip_prefix(['-', '+']).unwrap_or(whole);
        !whole.is_empty()
            && !fraction.is_empty()
            && whole.bytes().all(|b| b.is_ascii_digit())
            && fraction.bytes().all(|b| b.is_ascii_digit())
    })
}

/// What a file whose lines end in a lone carriage return is, and what to do (after its path).
pub const CR_ONLY: &str = "its lines end in a lone carriage return (CR, classic Mac OS line endings), not LF or \
                           CRLF: convert them, e.g. `tr '\\r' '\\n' < FILE > NEW.csv`";

/// Whether `start`, the start of a file, ends its lines in a lone carriage return ([`CR_ONLY`]):
/// a `\r` and no `\n`.
pub fn carriage_returns_only(start: &[u8]) -> bool {
    start.contains(&b'\r') && !start.contains(&b'\n')
}

/// A cell as an error message shows it: as written up to 60 characters, else its first 40 and
/// its length (`aaaa…[5000000 characters]`), so a 5 MB field does not become a 5 MB message.
pub fn shown_cell(text: &str) -> String {
    const WHOLE: usize = 60;
    const SHOWN: usize = 40;
    let count = text.chars().count();
    if count <= WHOLE {
        return text.to_owned();
    }
    let start: String = text.chars().take(SHOWN).collect();
    format!("{start}…[{count} characters]")
}

/// `text` as one line of a `#` comment: each control character (a newline or carriage return
/// in a path, which would end the comment and start a line of content) written as its escape
/// (`\n`).
pub fn one_line(text: &str) -> String {
    text.chars()
        .flat_map(|c| {
            let escaped: Vec<char> = match c.is_control() {
                true => c.escape_default().collect(),
                false => vec![c],
            };
            escaped
        })
        .collect()
}

/// A parser's message as an error shows it: each number longer than 20 characters written
/// short (serde writes a float in full: `1e308` as 309 digits), each word longer than
/// [`shown_cell`] keeps whole by its start and length, and the Rust types serde expects said
/// in words (`expected u64`: `expected a whole number from 0 to 18446744073709551615`).
pub fn shown_message(message: &str) -> String {
    plain_types(&message.split(' ').map(shown_word).collect::<Vec<_>>().join(" "))
}

/// `message` with serde's `expected u64` (and the other number types) said as what to write,
/// `a whole number from 0 to 18446744073709551615`, and its ` as i128` (how the parser held a
/// number out of range) left out.
fn plain_types(message: &str) -> String {
    const WHOLE_64: &str = "a whole number from 0 to 18446744073709551615";
    let words: [(&str, &str); 9] = [
        ("u8", "a whole number from 0 to 255"),
        ("u16", "a whole number from 0 to 65535"),
        ("u32", "a whole number from 0 to 4294967295"),
        ("u64", WHOLE_64),
        ("usize", WHOLE_64),
        ("i32", "a whole number from -2147483648 to 2147483647"),
        ("i64", "a whole number from -9223372036854775808 to 9223372036854775807"),
        ("f32", "a number"),
        ("f64", "a number"),
    ];
    let mut out = message.replace(" as i128", "").replace(" as u128", "");
    for (rust, plain) in words {
        let from = format!("expected {rust}");
        let mut at = 0;
        while let Some(found) = out[at..].find(&from).map(|i| i + at) {
            let end = found + from.len();
            let whole_word = out[end..]
                .chars()
                .next()
                .is_none_or(|c| !c.is_alphanumeric() && c != '_');
            if whole_word {
                out.replace_range(found..end, &format!("expected {plain}"));
            }
            at = found + 1;
        }
    }
    out
}

/// One word of [`shown_message`].
fn shown_word(word: &str) -> String {
    const LONG_NUMBER: usize = 20;
    let number = word.trim_matches(|c: char| !(c.is_ascii_digit() || c == '-' || c == '.'));
    if number.len() > LONG_NUMBER
        && let Ok(v) = number.parse::<f64>()
    {
        return word.replacen(number, &crate::measurement::format_f64(v), 1);
    }
    shown_cell(word)
}

/// What a line starts with, as far as record positions care.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum LineKind {
    /// Not seen yet (the line's first byte has not passed).
    Unknown,
    /// Starts with `\r`: blank if `\n` follows.
    CarriageReturn,
    /// An empty line: the csv reader skips it before a record.
    Skipped,
    /// A `#` comment line: skipped too.
    Comment,
    /// Anything else.
    Content,
}

#[derive(Debug, Default)]
struct Index {
    /// Bytes passed through so far.
    passed: u64,
    /// Line starts (byte offset, kind) not yet behind the last offset asked.
    starts: VecDeque<(u64, LineKind)>,
    /// Line starts already dropped from the front of `starts`.
    dropped: u64,
    /// Commas on the line being read so far.
    commas: usize,
    /// Fields of the line being read so far that are numbers (as far as their bytes show).
    numbers: usize,
    /// Bytes of the field being read other than white space, and whether all could be a number's.
    field: (usize, bool),
    /// Fields (commas + 1) of the last content line ended.
    content_fields: Option<usize>,
    /// The first comment line with as many fields as the content line before it: its line and
    /// fields ([`looks_like_row`]).
    commented_row: Option<(u64, usize)>,
}

impl Index {
    fn note(&mut self, bytes: &[u8]) {
        for (i, &b) in bytes.iter().enumerate() {
            let at = self.passed + i as u64;
            if let Some(last) = self.starts.back_mut() {
                match last.1 {
                    LineKind::Unknown => {
                        last.1 = match b {
                            b'#' => LineKind::Comment,
                            b'\n' => LineKind::Skipped,
                            b'\r' => LineKind::CarriageReturn,
                            _ => LineKind::Content,
                        }
                    }
                    LineKind::CarriageReturn => {
                        last.1 = if b == b'\n' {
                            LineKind::Skipped
                        } else {
                            LineKind::Content
                        }
                    }
                    _ => {}
                }
            }
            self.note_field_byte(b);
            if b == b'\n' {
                self.end_line();
                self.starts.push_back((at + 1, LineKind::Unknown));
            }
        }
        self.passed += bytes.len() as u64;
    }

    /// Counts the commas and number fields of the line being read.
    fn note_field_byte(&mut self, b: u8) {
        match b {
            b',' | b'\n' => {
                if self.field.0 > 0 && self.field.1 {
                    self.numbers += 1;
                }
                self.commas += usize::from(b == b',');
                self.field = (0, true);
            }
            b' ' | b'\t' | b'\r' => {}
            _ => {
                self.field.0 += 1;
                self.field.1 &= b.is_ascii_digit() || matches!(b, b'+' | b'-' | b'.' | b'e' | b'E');
            }
        }
    }

    /// Notes the fields of the line being read (the last one started), which just ended.
    fn end_line(&mut self) {
        if let Some(found) = self.wide_comment() {
            self.commented_row.get_or_insert(found);
        }
        if self.starts.back().is_some_and(|l| l.1 == LineKind::Content) {
            self.content_fields = Some(self.commas + 1);
        }
        self.commas = 0;
        self.numbers = 0;
    }

    /// The line being read, when it is a comment that looks like a row after the content line
    /// before it ([`looks_like_row`]): its 1-based line and fields.
    fn wide_comment(&self) -> Option<(u64, usize)> {
        let kind = self.starts.back()?.1;
        let fields = self.commas + 1;
        let numbers = self.numbers + usize::from(self.field.0 > 0 && self.field.1);
        (kind == LineKind::Comment && self.content_fields.is_some_and(|c| looks_like_row(fields, numbers, c)))
            .then(|| (self.dropped + self.starts.len() as u64, fields))
    }
}

/// The line starts seen by a [`LineTracking`] reader (shared with it).
#[derive(Clone, Debug)]
pub struct LineIndex(Rc<RefCell<Index>>);

impl LineIndex {
    /// The 1-based line of the record whose read started at byte `offset`: the first line at
    /// or after `offset` that is neither a comment nor blank. Offsets must not decrease from
    /// one call to the next (an earlier offset gives a line at or after the last one asked).
    pub fn line_of(&self, offset: u64) -> u64 {
        let mut index = self.0.borrow_mut();
        // Drop every line that starts before `offset`, then every skipped line that has a
        // successor (a trailing comment without a newline is where the record would start).
        while let Some(&(start, kind)) = index.starts.front() {
            let skipped = matches!(kind, LineKind::Skipped | LineKind::Comment);
            let skip_blank = start >= offset && skipped && index.starts.len() > 1;
            // The csv reader ends a CRLF record at `\r`: the next record's read starts at the
            // `\n`, one byte before its line (a line of that single byte would be blank).
            let before = index.starts.get(1).is_some_and(|next| next.0 <= offset + 1);
            if before || skip_blank {
                index.starts.pop_front();
                index.dropped += 1;
            } else {
                break;
            }
        }
        index.dropped + 1
    }

    /// The first `#` line with as many comma-separated fields as the line before it that is
    /// not a comment or blank (the header or a data row), most of them numbers
    /// ([`looks_like_row`]), among the bytes read so far: its 1-based line and fields. The csv
    /// reader skips it as a comment, but it looks like a data row whose first cell starts with
    /// `#` (an experiment `#axis1`), which would be dropped.
    pub fn commented_row(&self) -> Option<(u64, usize)> {
        let index = self.0.borrow();
        index.commented_row.or_else(|| index.wide_comment())
    }
}

/// Whether a `#` line of `fields` comma-separated fields, `numbers` of them numbers, is a data
/// row of a table whose rows have `columns` fields: as many fields, most of them numbers (a
/// remark in words, even with commas, is not).
pub fn looks_like_row(fields: usize, numbers: usize, columns: usize) -> bool {
    fields == columns && 2 * numbers > fields
}

/// Why a `#` line of `fields` fields among a table's rows is refused ([`LineIndex::commented_row`]).
pub fn commented_row(fields: usize) -> String {
    format!(
        "the line starts with `#` but has {fields} fields, most of them numbers: a comment line must not look like \
         a data row (read as a comment, it would be dropped silently): to leave the row out, delete it; a first \
         cell that starts with `#` (an experiment or id `#axis1`) must be quoted (`\"#axis1\"`)"
    )
}

/// A reader that notes line starts in a [`LineIndex`] as bytes pass through.
pub struct LineTracking<R> {
    inner: R,
    index: LineIndex,
}

impl<R: Read> LineTracking<R> {
    /// Wraps `inner`; the returned index answers for the bytes read through the wrapper.
    pub fn new(inner: R) -> (Self, LineIndex) {
        let index = LineIndex(Rc::new(RefCell::new(Index {
            starts: VecDeque::from([(0, LineKind::Unknown)]),
            ..Index::default()
        })));
        (
            LineTracking {
                inner,
                index: index.clone(),
            },
            index,
        )
    }
}

impl<R: Read> Read for LineTracking<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.index.0.borrow_mut().note(&buf[..n]);
        Ok(n)
    }
}

#[cfg(test)]
mod tests {

    /// A control character in a comment's text is written as its escape, the rest as given.
    #[test]
    fn a_comment_line_escapes_its_line_breaks() {
        assert_eq!(one_line("a\nb\r\tc é"), "a\\nb\\r\\tc é");
        assert_eq!(one_line("plain/path.csv"), "plain/path.csv");
        assert_eq!(one_line("x\u{7}").lines().count(), 1);
    }
    use super::*;

    /// Cells a hand-quoted writer gets wrong (a separator, a quote, a line break, a `#` first in
    /// a row) read back as written by a reader that skips `#` comment lines; plain cells are
    /// written bare.
    #[test]
    fn a_written_table_reads_back_cell_for_cell() {
        let rows = vec![
            vec!["#axis1".to_owned(), "a,b".into(), "say \"hi\"".into()],
            vec!["two\nlines".into(), String::new(), "x#y".into()],
            vec!["plain".into(), "1.5".into(), "-2".into()],
        ];
        let text = table_text(&["experiment", "b", "c"], rows.clone());
        assert!(text.ends_with("plain,1.5,-2\n"), "{text}");
        let mut reader = csv::ReaderBuilder::new()
            .comment(Some(b'#'))
            .from_reader(text.as_bytes());
        let read: Vec<Vec<String>> = reader
            .records()
            .map(|r| r.unwrap().iter().map(str::to_owned).collect())
            .collect();
        assert_eq!(read, rows);
    }

    /// Reads `text` as CSV with `#` comments through the tracker in chunks of `chunk` bytes;
    /// the line of the header and of each record.
    fn record_lines(text: &str, chunk: usize) -> Vec<u64> {
        struct Chunked<'a>(&'a [u8], usize);
        impl Read for Chunked<'_> {
            fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
                let n = self.0.len().min(self.1).min(buf.len());
                buf[..n].copy_from_slice(&self.0[..n]);
                self.0 = &self.0[n..];
                Ok(n)
            }
        }
        let (reader, index) = LineTracking::new(Chunked(text.as_bytes(), chunk));
        let mut csv = csv::ReaderBuilder::new()
            .comment(Some(b'#'))
            .has_headers(false)
            .flexible(true)
            .from_reader(reader);
        // csv-core returns a trailing comment without a newline, split over two reads, as one
        // empty record: readers skip those like blank lines.
        csv.records()
            .map(Result::unwrap)
            .filter(|r| !(r.len() == 1 && r[0].is_empty()))
            .map(|r| index.line_of(r.position().unwrap().byte()))
            .collect()
    }

    /// The same numbers counted the slow, obvious way: each record's first field is its line.
    fn expected(text: &str) -> Vec<u64> {
        text.lines()
            .filter(|l| !l.trim_end_matches('\r').is_empty() && !l.starts_with('#'))
            .filter_map(|l| l.split(',').next()?.trim().parse().ok())
            .collect()
    }

    #[test]
    fn a_long_cell_is_shown_by_its_start_and_length() {
        assert_eq!(shown_cell("12.5x"), "12.5x");
        let long = "a".repeat(5_000_000);
        assert_eq!(shown_cell(&long), format!("{}…[5000000 characters]", "a".repeat(40)));
        assert_eq!(shown_cell(&"é".repeat(61)).chars().filter(|&c| c == 'é').count(), 40);
    }

    #[test]
    fn a_message_shows_long_numbers_short_and_long_words_by_their_start() {
        let digits = format!("1{}", "0".repeat(308));
        let message = format!("invalid type: floating point `{digits}`, expected usize");
        assert_eq!(
            shown_message(&message),
            "invalid type: floating point `1e308`, expected a whole number from 0 to 18446744073709551615"
        );
        assert_eq!(shown_message("value 12.5 and -3"), "value 12.5 and -3");
        let long = "b".repeat(100);
        assert_eq!(
            shown_message(&format!("unknown `{long}`")),
            format!("unknown {}", shown_cell(&format!("`{long}`")))
        );
    }

    /// Serde's type names become what to write, whole words only; the parser's `as i128` goes.
    #[test]
    fn the_types_serde_expects_are_said_in_words() {
        assert_eq!(
            shown_message("invalid type: integer `18446744073709551616` as i128, expected u64"),
            "invalid type: integer `18446744073709551616`, expected a whole number from 0 to 18446744073709551615"
        );
        assert_eq!(
            shown_message("invalid type: string \"x\", expected f64; expected u8"),
            "invalid type: string \"x\", expected a number; expected a whole number from 0 to 255"
        );
        assert_eq!(shown_message("expected u64s or u64_x"), "expected u64s or u64_x");
        assert_eq!(
            shown_message("expected u32)"),
            "expected a whole number from 0 to 4294967295)"
        );
    }

    #[test]
    fn comments_blank_lines_and_crlf_are_counted() {
        let text = "# c\n2,a\n\n# c\n# c\n6,b\r\n7,c\r\n\r\n#\r\n10,d\n# end";
        for chunk in [1, 2, 3, 7, 64] {
            assert_eq!(record_lines(text, chunk), expected(text), "chunk {chunk}");
        }
        assert_eq!(expected(text), [2, 6, 7, 10]);
    }

    #[test]
    fn a_quoted_field_over_two_lines_keeps_the_count() {
        let text = "1,\"a\n# not a comment\"\n3,b\n";
        assert_eq!(record_lines(text, 4), [1, 3]);
    }

    proptest::proptest! {
        #[test]
        fn any_mix_of_lines_gives_each_record_its_line(
            kinds in proptest::collection::vec(0u8..5, 1..60),
            chunk in 1usize..20,
        ) {
            let mut text = String::new();
            for (i, k) in kinds.iter().enumerate() {
                let line = i + 1;
                text += &match k {
                    0 => "# comment\n".to_string(),
                    1 => "\n".to_string(),
                    2 => "\r\n".to_string(),
                    3 => format!("{line},x\r\n"),
                    _ => format!("{line},y\n"),
                };
            }
            proptest::prop_assert_eq!(record_lines(&text, chunk), expected(&text));
        }
    }
}
