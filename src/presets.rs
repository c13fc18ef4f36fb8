//! The shipped robot descriptions, truth models, plans (`scenarios/robots/*.toml`) and
//! scenarios (`scenarios/*.toml`), compiled into the program so that an installed binary finds
//! them from any folder.
//!
//! A shipped file has a *virtual path* under [`SHIPPED_ROOT`] (e.g.
//! `<shipped>/scenarios/robots/asea-irb6l.toml`): the readers ([`read_text`], and through it
//! [`crate::toml_file::read`]) serve its compiled-in text, and a file it names (a scenario's
//! `robot = "robots/..."`) resolves against its folder like any file's reference does, so it
//! reaches the shipped file too. A real file of the same relative path is never consulted.

use std::path::{Component, Path, PathBuf};

/// The root of the virtual paths of the shipped files (not a folder on disk).
pub const SHIPPED_ROOT: &str = "<shipped>";

/// What a shipped file is: which option takes it, and the list shown when a name is not found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// A nominal robot description (`--robot`; `scenarios/robots/`).
    Description,
    /// A simulated robot's truth model (`simulate --truth`; `scenarios/robots/*-truth`).
    Truth,
    /// An axis-experiment plan (`--plan`; `scenarios/robots/*-plan`).
    Plan,
    /// The manufacturing errors a truth is drawn with (`scenarios/robots/default-perturbation`).
    Perturbation,
    /// A Monte-Carlo scenario (`scenarios/`).
    Scenario,
}

impl Kind {
    /// In words, for messages.
    pub fn words(self) -> &'static str {
        match self {
            Kind::Description => "robot description",
            Kind::Truth => "truth model",
            Kind::Plan => "campaign plan",
            Kind::Perturbation => "perturbation",
            Kind::Scenario => "scenario",
        }
    }

    /// Where the command line takes it.
    fn taken_by(self) -> &'static str {
        match self {
            Kind::Description => "`--robot` (and `simulate --truth`)",
            Kind::Truth => "`simulate --truth`",
            Kind::Plan => "`--plan` of `simulate` and `plan`",
            Kind::Perturbation => "a scenario's `[truth] perturbation`",
            Kind::Scenario => "`axiscal run`",
        }
    }
}

/// One shipped file.
#[derive(Debug, Clone, Copy)]
pub struct Preset {
    /// Its name on the command line (the file stem, e.g. `asea-irb6l`).
    pub name: &'static str,
    /// Its path in the source tree, relative to the repository (e.g. `scenarios/robots/x.toml`).
    pub source_path: &'static str,
    /// What it is.
    pub kind: Kind,
    /// Its text.
    pub text: &'static str,
}

macro_rules! shipped {
    ($kind:ident, $name:literal, $path:literal) => {
        Preset {
            name: $name,
            source_path: $path,
            kind: Kind::$kind,
            text: include_str!(concat!("../", $path)),
        }
    };
}

/// Every shipped file (a test checks the list against the folders).
pub const PRESETS: &[Preset] = &[
    shipped!(Truth, "arm6-dh-truth", "scenarios/robots/arm6-dh-truth.toml"),
    shipped!(Description, "arm6-dh", "scenarios/robots/arm6-dh.toml"),
    shipped!(Description, "ur5e-dh", "scenarios/robots/ur5e-dh.toml"),
    shipped!(Plan, "arm6-jitter-plan", "scenarios/robots/arm6-jitter-plan.toml"),
    shipped!(Plan, "arm6-joint1-plan", "scenarios/robots/arm6-joint1-plan.toml"),
    shipped!(Description, "arm7-dh", "scenarios/robots/arm7-dh.toml"),
    shipped!(
        Truth,
        "asea-irb6l-paper-truth",
        "scenarios/robots/asea-irb6l-paper-truth.toml"
    ),
    shipped!(Description, "asea-irb6l", "scenarios/robots/asea-irb6l.toml"),
    shipped!(
        Plan,
        "asea-irb6l-optimized-plan",
        "scenarios/robots/asea-irb6l-optimized-plan.toml"
    ),
    shipped!(
        Plan,
        "asea-irb6l-table1-plan",
        "scenarios/robots/asea-irb6l-table1-plan.toml"
    ),
    shipped!(
        Description,
        "boby-klimchik-arm",
        "scenarios/robots/boby-klimchik-arm.toml"
    ),
    shipped!(
        Perturbation,
        "default-perturbation",
        "scenarios/robots/default-perturbation.toml"
    ),
    shipped!(
        Truth,
        "positioner-2axis-truth",
        "scenarios/robots/positioner-2axis-truth.toml"
    ),
    shipped!(
        Description,
        "positioner-2axis",
        "scenarios/robots/positioner-2axis.toml"
    ),
    shipped!(Truth, "scara-rrpr-truth", "scenarios/robots/scara-rrpr-truth.toml"),
    shipped!(Description, "scara-rrpr", "scenarios/robots/scara-rrpr.toml"),
    shipped!(Plan, "table-prpp-plan", "scenarios/robots/table-prpp-plan.toml"),
    shipped!(Truth, "table-prpp-truth", "scenarios/robots/table-prpp-truth.toml"),
    shipped!(Description, "table-prpp", "scenarios/robots/table-prpp.toml"),
    shipped!(Scenario, "ci-smoke", "scenarios/ci-smoke.toml"),
    shipped!(Scenario, "compliance", "scenarios/compliance.toml"),
    shipped!(Scenario, "iso9283", "scenarios/iso9283.toml"),
    shipped!(Scenario, "noise-sweep", "scenarios/noise-sweep.toml"),
    shipped!(Scenario, "paper", "scenarios/paper.toml"),
    shipped!(Scenario, "perturbed-fleet", "scenarios/perturbed-fleet.toml"),
    shipped!(Scenario, "plan-optimize", "scenarios/plan-optimize.toml"),
    shipped!(Scenario, "span-study", "scenarios/span-study.toml"),
    shipped!(Scenario, "scara-rrpr", "scenarios/scara-rrpr.toml"),
    shipped!(Scenario, "table-prpp", "scenarios/table-prpp.toml"),
];

/// A name that is neither an existing file nor a shipped file of the kinds an option takes.
#[derive(Debug, thiserror::Error)]
#[error("{given}: {problem} (shipped {what}: {names})")]
pub struct UnknownPreset {
    /// What the user gave.
    pub given: String,
    /// `no such file, and not a shipped robot description`, or where a shipped file of that
    /// name but another kind goes (`a shipped truth model, for ...`).
    pub problem: String,
    /// The kinds taken, in words (`truth models and robot descriptions`).
    pub what: String,
    /// The shipped names of those kinds, comma-separated.
    pub names: String,
}

impl Preset {
    /// Its virtual path (`<shipped>/scenarios/...`).
    pub fn virtual_path(&self) -> PathBuf {
        Path::new(SHIPPED_ROOT).join(self.source_path)
    }
}

/// The names of the shipped files of `kind`.
pub fn names(kind: Kind) -> Vec<&'static str> {
    PRESETS.iter().filter(|p| p.kind == kind).map(|p| p.name).collect()
}

/// The path to read for `given` on the command line: `given` itself when it is an existing
/// file (a user's file always wins), else the virtual path of the shipped file of that name
/// (`asea-irb6l`, also with `.toml`) and one of the `accepted` kinds, else an error listing the
/// shipped names of those kinds (and where a shipped file of that name and another kind goes).
pub fn resolve(given: &Path, accepted: &[Kind]) -> Result<PathBuf, UnknownPreset> {
    if given.is_file() || given.starts_with(SHIPPED_ROOT) {
        return Ok(given.to_owned());
    }
    let text = given.to_string_lossy();
    let stem = text.strip_suffix(".toml").unwrap_or(&text);
    // The old default spelled the path in the checkout: accept it anywhere.
    let found = PRESETS
        .iter()
        .find(|p| p.name == stem)
        .or_else(|| PRESETS.iter().find(|p| given.ends_with(p.source_path)));
    match found {
        Some(p) if accepted.contains(&p.kind) => Ok(p.virtual_path()),
        _ => {
            let what = accepted.iter().map(|k| k.words()).collect::<Vec<_>>().join(" or ");
            Err(UnknownPreset {
                given: text.into_owned(),
                problem: match found {
                    Some(p) => format!("a shipped {}, for {}, not a {what}", p.kind.words(), p.kind.taken_by()),
                    None => match std::fs::metadata(given) {
                        Ok(meta) => not_regular(&meta).to_owned(),
                        Err(_) => format!("no such file, and not a shipped {what}"),
                    },
                },
                what: accepted
                    .iter()
                    .map(|k| format!("{}s", k.words()))
                    .collect::<Vec<_>>()
                    .join(" and "),
                names: accepted.iter().flat_map(|&k| names(k)).collect::<Vec<_>>().join(", "),
            })
        }
    }
}

/// `path` with `.` and `..` folded lexically (a virtual path has no links to follow).
fn lexical(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out
}

/// The compiled-in text of a virtual path, `None` for any other path.
pub fn shipped_text(path: &Path) -> Option<&'static str> {
    let inner = lexical(path);
    let relative = inner.strip_prefix(SHIPPED_ROOT).ok()?;
    PRESETS
        .iter()
        .find(|p| Path::new(p.source_path) == relative)
        .map(|p| p.text)
}

/// Reads a text file, or serves a shipped file's text for its virtual path (a virtual path
/// that names no shipped file is "not found"). A file in another encoding is refused with
/// what to do ([`check_encoding`]), from its first KiB, and a byte that is not UTF-8 as soon as
/// it is read: a binary file named by mistake (a video, a disk image) is refused after a
/// mebibyte, not read whole.
pub fn read_text(path: &Path) -> std::io::Result<String> {
    use std::io::Read;
    if path.starts_with(SHIPPED_ROOT) {
        return shipped_text(path)
            .map(str::to_owned)
            .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::NotFound, "no such shipped file"));
    }
    regular_file(path)?;
    let mut file = std::fs::File::open(path)?;
    let mut bytes = Vec::new();
    (&mut file).take(1024).read_to_end(&mut bytes)?;
    check_encoding(&bytes)?;
    let mut valid = utf8_prefix(&bytes, 0)?;
    let mut chunk = vec![0u8; 1 << 20];
    loop {
        let n = match file.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        bytes.extend_from_slice(&chunk[..n]);
        valid = utf8_prefix(&bytes, valid)?;
    }
    String::from_utf8(bytes).map_err(|e| not_utf8(e.utf8_error().valid_up_to()))
}

/// How many bytes of `bytes` are known UTF-8, checking on from `valid` (a sequence cut at the
/// end waits for the next read); an error at the first byte that is not UTF-8.
fn utf8_prefix(bytes: &[u8], valid: usize) -> std::io::Result<usize> {
    match std::str::from_utf8(&bytes[valid..]) {
        Ok(_) => Ok(bytes.len()),
        Err(e) if e.error_len().is_none() => Ok(valid + e.valid_up_to()),
        Err(e) => Err(not_utf8(valid + e.valid_up_to())),
    }
}

/// The error of a text file whose byte at offset `at` is not UTF-8.
fn not_utf8(at: usize) -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::InvalidData,
        format!("not UTF-8 text (byte {} is not UTF-8): save it as UTF-8", at + 1),
    )
}

/// Refuses an input that is not a regular file (after links): a device never ends
/// (`/dev/zero`), a pipe is read once and may block, a folder has no text. Checked before
/// the file is opened, so a pipe with no writer does not hang the check.
pub fn regular_file(path: &Path) -> std::io::Result<()> {
    let meta = std::fs::metadata(path)?;
    if meta.is_file() {
        Ok(())
    } else {
        Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            not_regular(&meta),
        ))
    }
}

/// What an existing path that is not a regular file is, and what to do, in words.
fn not_regular(meta: &std::fs::Metadata) -> &'static str {
    if meta.is_dir() {
        "a folder, not a regular file: name a file in it"
    } else {
        "not a regular file (a device or a pipe): save the data to a file and name that"
    }
}

/// The bytes a text file starts with, refused when they are UTF-16 or UTF-32 (every text
/// reader reads UTF-8): a byte-order mark says so, and so do NUL bytes in a quarter or more of
/// the first KiB (UTF-16 of Latin text has one in every other byte, UTF-32 three in four; no
/// UTF-8 text has them). A UTF-8 byte-order mark is fine (the readers skip it).
pub fn check_encoding(start: &[u8]) -> std::io::Result<()> {
    const MARKS: [(&[u8], &str); 4] = [
        (&[0xFF, 0xFE, 0, 0], "UTF-32 (byte-order mark FF FE 00 00)"),
        (&[0, 0, 0xFE, 0xFF], "UTF-32 (byte-order mark 00 00 FE FF)"),
        (&[0xFF, 0xFE], "UTF-16 (byte-order mark FF FE)"),
        (&[0xFE, 0xFF], "UTF-16 (byte-order mark FE FF)"),
    ];
    let head = &start[..start.len().min(1024)];
    let nuls = head.iter().filter(|&&b| b == 0).count();
    let encoding = match MARKS.iter().find(|(mark, _)| start.starts_with(mark)) {
        Some((_, words)) => (*words).to_owned(),
        None if 4 * nuls < head.len().max(1) => return Ok(()),
        None => format!(
            "{} ({nuls} of its first {} bytes are NUL; or it is not text)",
            if 8 * nuls > 5 * head.len() { "UTF-32" } else { "UTF-16" },
            head.len()
        ),
    };
    Err(std::io::Error::new(
        std::io::ErrorKind::InvalidData,
        format!("the file is {encoding}; save it as UTF-8"),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Text of multi-byte characters cut at every chunk boundary reads as `std` reads it; a byte
    /// that is not UTF-8 two mebibytes in is named by its offset, the one `std` names.
    #[test]
    fn text_is_checked_as_it_is_read() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.toml");
        // 3-byte and 4-byte characters: the chunks (1 KiB, then 1 MiB) end inside them.
        let text: String = "a = \"\u{20ac}\u{1f916}x\"\n".repeat(300_000);
        std::fs::write(&path, &text).unwrap();
        assert_eq!(read_text(&path).unwrap(), std::fs::read_to_string(&path).unwrap());
        let mut bytes = text.into_bytes();
        bytes[2_500_000] = 0xFF;
        std::fs::write(&path, &bytes).unwrap();
        let std_offset = String::from_utf8(bytes).unwrap_err().utf8_error().valid_up_to();
        let err = read_text(&path).unwrap_err().to_string();
        assert!(err.contains(&format!("byte {} is not UTF-8", std_offset + 1)), "{err}");
    }

    /// UTF-16 and UTF-32, with a byte-order mark or without (NUL bytes), are named; UTF-8, with
    /// its byte-order mark too, passes.
    #[test]
    fn utf16_and_utf32_are_named() {
        let text = "experiment,step\naxis1,0\n";
        let utf16_le: Vec<u8> = text.encode_utf16().flat_map(u16::to_le_bytes).collect();
        let utf16_be: Vec<u8> = text.encode_utf16().flat_map(u16::to_be_bytes).collect();
        let utf32_le: Vec<u8> = text.chars().flat_map(|c| u32::from(c).to_le_bytes()).collect();
        let cases: [(Vec<u8>, &str); 5] = [
            (
                [&[0xFF, 0xFE][..], &utf16_le].concat(),
                "UTF-16 (byte-order mark FF FE)",
            ),
            (
                [&[0xFE, 0xFF][..], &utf16_be].concat(),
                "UTF-16 (byte-order mark FE FF)",
            ),
            (
                [&[0xFF, 0xFE, 0, 0][..], &utf32_le].concat(),
                "UTF-32 (byte-order mark FF FE 00 00)",
            ),
            (utf16_be, "UTF-16 (24 of its first 48 bytes are NUL"),
            (utf32_le, "UTF-32 (72 of its first 96 bytes are NUL"),
        ];
        for (bytes, words) in cases {
            let e = check_encoding(&bytes).unwrap_err().to_string();
            assert!(
                e.starts_with(&format!("the file is {words}")) && e.ends_with("save it as UTF-8"),
                "{e}"
            );
        }
        assert!(check_encoding(format!("\u{feff}{text}").as_bytes()).is_ok());
        assert!(check_encoding(b"").is_ok());
    }

    #[test]
    fn the_list_holds_every_shipped_toml_file_once() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut on_disk: Vec<String> = ["scenarios", "scenarios/robots"]
            .iter()
            .flat_map(|dir| {
                std::fs::read_dir(root.join(dir))
                    .unwrap()
                    .map(|e| e.unwrap().path())
                    .filter(|p| p.extension().is_some_and(|x| x == "toml"))
                    .map(|p| p.strip_prefix(root).unwrap().to_string_lossy().into_owned())
                    .collect::<Vec<_>>()
            })
            .collect();
        on_disk.sort();
        let mut listed: Vec<String> = PRESETS.iter().map(|p| p.source_path.to_owned()).collect();
        listed.sort();
        assert_eq!(listed, on_disk, "add a new shipped file to PRESETS");
        for p in PRESETS {
            let stem = Path::new(p.source_path).file_stem().unwrap();
            assert_eq!(stem, p.name);
        }
    }

    #[test]
    fn names_resolve_to_shipped_text_and_references_resolve_against_the_naming_file() {
        let robot = resolve(Path::new("asea-irb6l"), &[Kind::Description]).unwrap();
        assert_eq!(
            read_text(&robot).unwrap(),
            include_str!("../scenarios/robots/asea-irb6l.toml")
        );
        // A scenario's `robot = "robots/x.toml"`, joined to the scenario's folder.
        let scenario = resolve(Path::new("paper.toml"), &[Kind::Scenario]).unwrap();
        let named = scenario.parent().unwrap().join("robots/../robots/scara-rrpr.toml");
        assert_eq!(
            read_text(&named).unwrap(),
            include_str!("../scenarios/robots/scara-rrpr.toml")
        );
        let e = resolve(Path::new("no-such-robot"), &[Kind::Description])
            .unwrap_err()
            .to_string();
        assert!(e.contains("asea-irb6l") && !e.contains("ci-smoke"), "{e}");
        // Descriptions are listed apart from truth models and plans, and a truth model
        // named where a description is expected says where it goes.
        assert!(
            !e.contains("-truth") && !e.contains("-plan") && !e.contains("perturbation"),
            "{e}"
        );
        let e = resolve(Path::new("scara-rrpr-truth"), &[Kind::Description])
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("scara-rrpr-truth: a shipped truth model, for `simulate --truth`, not a robot description"),
            "{e}"
        );
        assert!(resolve(Path::new("scara-rrpr-truth"), &[Kind::Truth, Kind::Description]).is_ok());
        assert!(resolve(Path::new("scara-rrpr"), &[Kind::Truth, Kind::Description]).is_ok());
        assert!(read_text(&Path::new(SHIPPED_ROOT).join("x.toml")).is_err());
    }
}
