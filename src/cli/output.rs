//! Where every command writes: one guard, so that nothing the user wrote is replaced without
//! `--force`, and never a file the same command reads.
//!
//! A command names its inputs ([`Outputs::input`]) and its outputs; an output is refused when
//! it is one of the inputs (compared as canonical paths, and on Unix also as the same file
//! reached by a hard link), and when it exists and `--force` was not given. Text outputs are
//! written to a temporary file beside the target and renamed over it, so an interrupted write
//! never leaves a half-written file in place of the old one.

use anyhow::{Context, Result, bail};
use std::io::Write;
use std::path::{Path, PathBuf};

/// One file the command reads, with the option or argument that named it.
#[derive(Debug)]
struct Input {
    what: String,
    path: PathBuf,
    canonical: PathBuf,
}

/// The outputs of one command run (see the module docs).
#[derive(Debug)]
pub struct Outputs {
    force: bool,
    inputs: Vec<Input>,
    /// The folder this command holds locked for its whole run ([`Outputs::hold_folder`]), and
    /// the handle that holds the lock.
    held: Option<(PathBuf, std::fs::File)>,
}

/// Refuses the output `-`: the outputs are files written whole through a temporary (a file
/// named `-` is what a user who meant stdout would not look for).
fn refuse_dash(path: &Path) -> Result<()> {
    if path.as_os_str() == "-" {
        bail!(
            "--out `-`: axiscal writes its outputs to files, not to stdout; name a file or folder (e.g. --out out.csv), \
             or ./- for a file named `-`"
        );
    }
    Ok(())
}

/// `path` with its folder resolved (symbolic links, `..`), also when the file does not exist
/// yet; `None` when the folder does not exist either (then it cannot be an input).
fn canonical(path: &Path) -> Option<PathBuf> {
    if let Ok(p) = path.canonicalize() {
        return Some(p);
    }
    let name = path.file_name()?;
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    Some(canonical(parent)?.join(name))
}

/// Whether `a` and `b` are the same existing file (a hard link of it counts).
#[cfg(unix)]
fn same_file(a: &Path, b: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn same_file(_: &Path, _: &Path) -> bool {
    false
}

impl Outputs {
    /// Outputs of a command run with `--force` given or not.
    pub fn new(force: bool) -> Self {
        Outputs {
            force,
            inputs: Vec::new(),
            held: None,
        }
    }

    /// Registers `path`, named by `what` (e.g. `--calibration`), as an input, and with it the
    /// files it names that the command reads too ([`super::referenced`]: a description's URDF,
    /// a scenario's robot, truth and plans). A path that does not exist is kept too: the
    /// command's reader reports it.
    pub fn input(mut self, what: &str, path: &Path) -> Self {
        self.push_input(what, path);
        for (what, file) in super::referenced::referenced_files(what, path) {
            self.push_input(&what, &file);
        }
        self
    }

    fn push_input(&mut self, what: &str, path: &Path) {
        if let Some(canonical) = canonical(path) {
            self.inputs.push(Input {
                what: what.to_owned(),
                path: path.to_owned(),
                canonical,
            });
        }
    }

    /// Registers `files` in each of `dirs` as inputs (e.g. the shards a merge reads).
    pub fn inputs_in(self, what: &str, dirs: &[PathBuf], files: &[&str]) -> Self {
        let mut this = self;
        for dir in dirs {
            for f in files {
                this = this.input(what, &dir.join(f));
            }
        }
        this
    }

    /// Refuses `path` as an output if it is an input of this command (whatever `--force`).
    pub fn check_not_input(&self, path: &Path) -> Result<()> {
        let Some(out) = canonical(path) else { return Ok(()) };
        if let Some(i) = self
            .inputs
            .iter()
            .find(|i| i.canonical == out || same_file(&i.path, path))
        {
            bail!(
                "{} is this command's own input ({} {}): refusing to write over it, even with --force; choose another output",
                path.display(),
                i.what,
                i.path.display()
            );
        }
        Ok(())
    }

    /// Refuses a folder output `dir` (`--out`) that is the folder of the input named `what`
    /// (e.g. the calibration's folder): that folder holds another command's set of files, of
    /// which this command's outputs would replace some by files of another layout.
    pub fn check_not_folder_of(&self, dir: &Path, what: &str) -> Result<()> {
        let Some(out) = canonical(dir) else { return Ok(()) };
        let input = self
            .inputs
            .iter()
            .find(|i| i.what == what && i.canonical.parent().is_some_and(|folder| folder == out.as_path()));
        if let Some(i) = input {
            let name = dir
                .file_name()
                .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
            bail!(
                "--out `{}` is the folder of {what} {}: it holds that run's own set of files, some of which this \
                 command would replace by files of another layout (a `residuals.csv`); choose another folder, e.g. \
                 --out {name}-validation",
                dir.display(),
                i.path.display()
            );
        }
        Ok(())
    }

    /// Checks that `path` may be written: not `-`, not an input, and absent unless `--force`.
    pub fn check(&self, path: &Path) -> Result<()> {
        refuse_dash(path)?;
        self.check_not_input(path)?;
        if let Ok(meta) = path.symlink_metadata()
            && !meta.is_file()
            && !meta.is_symlink()
        {
            bail!(
                "{} exists and is not a regular file (a device, a folder); refusing to replace it, even with --force",
                path.display()
            );
        }
        if let Some(target) = link_to_a_stream(path) {
            bail!(
                "{} is a link to {} (a device or a stream, not a regular file); refusing to replace it, even with \
                 --force: name a file for --out",
                path.display(),
                target.display()
            );
        }
        if !self.force && path.symlink_metadata().is_ok() {
            bail!("{} exists; pass --force to replace it", path.display());
        }
        Ok(())
    }

    /// Refuses a folder output `dir` (`--out`) that exists and is not a folder: the command
    /// writes several files into it.
    pub fn check_folder(dir: &Path) -> Result<()> {
        refuse_dash(dir)?;
        if let Ok(meta) = dir.metadata()
            && !meta.is_dir()
        {
            bail!(
                "--out `{}` is {}; --out names a folder (the command writes its files into it): choose another name",
                dir.display(),
                kind_of(&meta)
            );
        }
        Ok(())
    }

    /// Creates the folder `dir` and any missing parent; a parent that exists but is not a
    /// folder is named (the system's error says only "File exists").
    pub fn create_folder(dir: &Path) -> Result<()> {
        std::fs::create_dir_all(dir).or_else(|e| {
            let blocking = dir
                .ancestors()
                .find_map(|a| a.metadata().ok().filter(|m| !m.is_dir()).map(|m| (a, kind_of(&m))));
            match blocking {
                Some((a, kind)) => bail!(
                    "creating {}: `{}` is {kind}, not a folder: choose another --out",
                    dir.display(),
                    a.display()
                ),
                None => Err(e).with_context(|| format!("creating {}", dir.display())),
            }
        })
    }

    /// Refuses a folder output `dir` that exists and is not empty, unless `--force` (then its
    /// files are replaced one by one as they are written).
    pub fn check_empty_dir(&self, dir: &Path) -> Result<()> {
        Self::check_folder(dir)?;
        let not_empty = std::fs::read_dir(dir).is_ok_and(|mut entries| entries.next().is_some());
        if not_empty && !self.force {
            bail!("{} is not empty; pass --force to replace its files", dir.display());
        }
        self.check_not_input(dir)
    }

    /// [`Outputs::check`] for each of `names` in `dir`, before any of them is written.
    pub fn check_in(&self, dir: &Path, names: &[&str]) -> Result<()> {
        Self::check_folder(dir)?;
        names.iter().try_for_each(|n| self.check(&dir.join(n)))
    }

    /// Creates the folder of `path` (if it has one) for an output.
    pub fn create_parent(path: &Path) -> Result<()> {
        match path.parent() {
            Some(dir) if !dir.as_os_str().is_empty() => Self::create_folder(dir),
            _ => Ok(()),
        }
    }

    /// Writes `contents` to `path` after [`Outputs::check`], through a temporary file renamed
    /// over the target.
    pub fn write(&self, path: &Path, contents: impl AsRef<[u8]>) -> Result<()> {
        let mut file = self.create(path)?;
        file.write_all(contents.as_ref())
            .with_context(|| format!("writing {}", path.display()))?;
        file.commit()
    }

    /// Opens `path` for writing after [`Outputs::check`]: the bytes go to a temporary file
    /// that [`OutputFile::commit`] renames over `path` (dropped uncommitted, it is removed).
    pub fn create(&self, path: &Path) -> Result<OutputFile> {
        self.check(path)?;
        Self::create_parent(path)?;
        self.remove_orphaned_temporaries(
            path.parent()
                .filter(|d| !d.as_os_str().is_empty())
                .unwrap_or(Path::new(".")),
        );
        let name = path
            .file_name()
            .with_context(|| format!("{}: not a file name", path.display()))?;
        // The process id and a count of this process's outputs: two writers never share one.
        static OPENED: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let temporary = path.with_file_name(format!(
            ".{}.axiscal-{}-{}.tmp",
            name_within(&name.to_string_lossy(), TEMPORARY_STEM_BYTES),
            std::process::id(),
            OPENED.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
        ));
        let tracked = super::signals::track_temporary(&temporary);
        let file = std::fs::File::create(&temporary).map_err(|e| cannot_create(path, &temporary, e));
        // Held while the file is open: the sign that its run is alive, whatever PID namespace
        // it runs in (`remove_orphaned_temporaries`).
        let file = file.inspect(lock_held);
        let file = match file {
            Ok(file) => file,
            Err(e) => {
                if let Some(slot) = tracked {
                    super::signals::untrack_temporary(slot);
                }
                return Err(e);
            }
        };
        Ok(OutputFile {
            writer: Some(std::io::BufWriter::new(file)),
            temporary,
            target: path.to_owned(),
            replace: self.force,
            tracked,
        })
    }
}

/// The most bytes of an output's name kept in its temporary's name: with the dot, the process
/// id and the count (`.NAME.axiscal-PID-N.tmp`, at most 46 more bytes) it stays within the 255
/// bytes a file name may have, so any name the file system takes can be written.
const TEMPORARY_STEM_BYTES: usize = 200;

/// The longest start of `name` of at most `bytes` bytes that ends on a character boundary.
fn name_within(name: &str, bytes: usize) -> &str {
    let end = (0..=bytes.min(name.len()))
        .rev()
        .find(|&i| name.is_char_boundary(i))
        .unwrap_or(0);
    &name[..end]
}

/// The error of an output `path` whose temporary could not be created: it names the output
/// and the cause (a read-only file system, a folder without write permission); the temporary's
/// name, which the user never gave, comes last.
fn cannot_create(path: &Path, temporary: &Path, e: std::io::Error) -> anyhow::Error {
    let folder = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    anyhow::anyhow!(
        "cannot write {}: creating a file in {} fails: {e} (the output is written to a temporary beside it, {}, \
         then renamed): choose a writable folder",
        path.display(),
        folder.display(),
        temporary
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
    )
}

/// The process id in the name of one of axiscal's temporaries (`.NAME.axiscal-PID-N.tmp`, a
/// file; `.axiscal-PID-plots.tmp`, a folder of plots), if `name` is one.
fn temporary_owner(name: &str) -> Option<i32> {
    let rest = name.strip_prefix('.')?.strip_suffix(".tmp")?;
    let (_, tail) = rest.rsplit_once("axiscal-")?;
    let pid = match tail.strip_suffix("-plots") {
        Some(pid) => pid,
        None => tail.split_once('-')?.0,
    };
    pid.parse::<u32>()
        .ok()
        .and_then(|p| i32::try_from(p).ok())
        .filter(|&p| p > 0)
}

/// Takes the lock on `file` that marks an axiscal temporary (a file or the folder of plots) as
/// its run's while it is open (`flock`, released by the kernel when the run ends, however it
/// ends).
fn lock_held(file: &std::fs::File) {
    // A failure leaves the file unlocked, and an unlocked temporary of a live run is still
    // kept by its process id.
    let _ = file.try_lock();
}

/// Whether a run holds `path` ([`lock_held`]): the lock cannot be taken.
fn held_by_a_run(path: &Path) -> bool {
    let Ok(file) = std::fs::File::open(path) else {
        return true;
    };
    // The lock taken here goes with `file`.
    file.try_lock().is_err()
}

/// Whether `path` has the shape of an axiscal temporary ([`temporary_owner`] named it): a
/// regular file of this user, or a folder of plots of this user holding regular files only;
/// never a link.
fn shaped_as_temporary(path: &Path, plots: bool) -> bool {
    use std::os::unix::fs::MetadataExt;
    let Ok(m) = std::fs::symlink_metadata(path) else {
        return false;
    };
    // SAFETY: geteuid has no preconditions.
    let own = m.uid() == unsafe { libc::geteuid() };
    match plots {
        false => own && m.is_file(),
        true => {
            own && m.is_dir()
                && std::fs::read_dir(path)
                    .is_ok_and(|entries| entries.flatten().all(|e| e.file_type().is_ok_and(|t| t.is_file())))
        }
    }
}

impl Outputs {
    /// Removes from `dir` the temporaries of axiscal runs that no longer exist (killed by a
    /// signal no process can catch: SIGKILL, the out-of-memory killer), so they do not pile
    /// up. A temporary is removed only when its name is one (`.NAME.axiscal-PID-N.tmp`,
    /// `.axiscal-PID-plots.tmp`), its process id is gone, no run holds its lock (a run in
    /// another PID namespace, whose id means another process here), it has a temporary's shape
    /// ([`shaped_as_temporary`]) and it is not one of this command's inputs.
    fn remove_orphaned_temporaries(&self, dir: &Path) {
        let Ok(entries) = std::fs::read_dir(dir) else { return };
        for entry in entries.flatten() {
            let name = entry.file_name();
            let Some(pid) = name.to_str().and_then(temporary_owner) else {
                continue;
            };
            // SAFETY: signal 0 only asks whether the process exists; nothing is sent.
            let gone = unsafe { libc::kill(pid, 0) } == -1
                && std::io::Error::last_os_error().raw_os_error() == Some(libc::ESRCH);
            let path = entry.path();
            let plots = name.to_string_lossy().ends_with("-plots.tmp");
            if !gone || !shaped_as_temporary(&path, plots) || self.check_not_input(&path).is_err() {
                continue;
            }
            if held_by_a_run(&path) {
                continue;
            }
            let _ = match plots {
                true => std::fs::remove_dir_all(&path),
                false => std::fs::remove_file(&path),
            };
        }
    }
}

/// Flushes a CSV writer on an [`OutputFile`] and commits the file.
pub fn commit_csv(writer: csv::Writer<OutputFile>) -> Result<()> {
    let target = writer.get_ref().target.display().to_string();
    writer
        .into_inner()
        .map_err(|e| e.into_error())
        .with_context(|| format!("writing {target}"))?
        .commit()
}

/// An output being written (see [`Outputs::create`]).
pub struct OutputFile {
    writer: Option<std::io::BufWriter<std::fs::File>>,
    temporary: PathBuf,
    target: PathBuf,
    /// `--force`: the target may be replaced; otherwise it is put in place only if still absent.
    replace: bool,
    /// The temporary file's slot among those a signal removes.
    tracked: Option<usize>,
}

impl OutputFile {
    /// Flushes the file and puts it in place of the target.
    pub fn commit(self) -> Result<()> {
        self.finish()?.place()
    }

    /// Flushes and syncs the file, still under its temporary name: ready to be put in place.
    fn finish(mut self) -> Result<Staged> {
        if let Some(w) = self.writer.take() {
            let target = self.target.display().to_string();
            let file = w
                .into_inner()
                .map_err(|e| e.into_error())
                .with_context(|| format!("writing {target}"))?;
            file.sync_all().with_context(|| format!("writing {target}"))?;
        }
        Ok(Staged {
            temporary: std::mem::take(&mut self.temporary),
            target: std::mem::take(&mut self.target),
            replace: self.replace,
            tracked: self.tracked.take(),
        })
    }
}

/// A file written and synced under a temporary name, to be put in place of its target.
struct Staged {
    temporary: PathBuf,
    target: PathBuf,
    /// `--force`: the target may be replaced; otherwise it is put in place only if still absent.
    replace: bool,
    /// The temporary file's slot among those a signal removes.
    tracked: Option<usize>,
}

impl Staged {
    /// Puts the file in place of its target: renamed over it with `--force`; otherwise linked
    /// where no file is (atomically, unlike a check then a rename, so a second run writing the
    /// same output at the same time fails instead of replacing the first one's file).
    fn place(mut self) -> Result<()> {
        let target = self.target.display().to_string();
        let placed = if self.replace {
            std::fs::rename(&self.temporary, &self.target).with_context(|| format!("writing {target}"))
        } else {
            let linked = std::fs::hard_link(&self.temporary, &self.target);
            let _ = std::fs::remove_file(&self.temporary);
            linked.with_context(|| match self.target.symlink_metadata() {
                Ok(_) => format!("{target} appeared while this command ran (another run writing it?); not replaced; pass --force to replace it"),
                Err(_) => format!("writing {target}"),
            })
        };
        if placed.is_ok()
            && let Some(slot) = self.tracked.take()
        {
            super::signals::untrack_temporary(slot);
        }
        placed
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if let Some(slot) = self.tracked.take() {
            let _ = std::fs::remove_file(&self.temporary);
            super::signals::untrack_temporary(slot);
        }
    }
}

impl Write for OutputFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match &mut self.writer {
            Some(w) => w.write(buf),
            None => Err(std::io::Error::other("output already committed")),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.writer.as_mut().map_or(Ok(()), |w| w.flush())
    }
}

impl Drop for OutputFile {
    fn drop(&mut self) {
        if self.writer.take().is_some() || self.tracked.is_some() {
            let _ = std::fs::remove_file(&self.temporary);
        }
        if let Some(slot) = self.tracked.take() {
            super::signals::untrack_temporary(slot);
        }
    }
}

/// The files of one command written into one folder as a set ([`Outputs::staged_in`]): each is
/// written and synced under a temporary name beside its target, and none is put in place until
/// every one is written, so a failure on the way (a full disk, an error, a signal) leaves the
/// folder as it was. Placing them is then renames only.
pub struct StagedSet<'a> {
    outputs: &'a Outputs,
    dir: PathBuf,
    staged: Vec<Staged>,
    /// A hidden folder inside `dir` that plots are drawn into (removed when the set ends), and
    /// its slot among the temporaries a signal removes.
    plots_dir: Option<(PathBuf, Option<usize>, Option<std::fs::File>)>,
    /// Subfolders of `dir` the set created for its files, each with its slot among the
    /// temporaries a signal removes (when empty): removed if the set is dropped uncommitted.
    created: Vec<(PathBuf, Option<usize>)>,
}

impl Outputs {
    /// A set of files to write into `dir` (created if missing), each checked as
    /// [`Outputs::check`] would.
    pub fn staged_in(&self, dir: &Path) -> Result<StagedSet<'_>> {
        Self::check_folder(dir)?;
        Outputs::create_folder(dir)?;
        self.remove_orphaned_temporaries(dir);
        Ok(StagedSet {
            outputs: self,
            dir: dir.to_owned(),
            staged: Vec::new(),
            plots_dir: None,
            created: Vec::new(),
        })
    }
}

impl StagedSet<'_> {
    /// Writes `dir/name` under its temporary name (`name` may hold a subfolder: created now,
    /// and removed again, when left empty, if the set is not committed).
    pub fn write(&mut self, name: &str, contents: impl AsRef<[u8]>) -> Result<()> {
        self.write_with(name, |file| file.write_all(contents.as_ref()))
    }

    /// [`Self::write`] with the contents written by `write` into the temporary file as they are
    /// made (a large table is not held in memory first).
    pub fn write_with(&mut self, name: &str, write: impl FnOnce(&mut OutputFile) -> std::io::Result<()>) -> Result<()> {
        let target = self.dir.join(name);
        if let Some(sub) = target.parent().filter(|d| !d.exists()) {
            self.outputs.check_not_input(sub)?;
            Outputs::create_folder(sub)?;
            self.created
                .push((sub.to_owned(), super::signals::track_temporary(sub)));
        }
        let mut file = self.outputs.create(&target)?;
        write(&mut file).with_context(|| format!("writing {}", target.display()))?;
        self.staged.push(file.finish()?);
        Ok(())
    }

    /// Draws the files `names` with `draw` (given the folder to draw into) under temporary
    /// names: a hidden folder inside `dir`, its files placed with the others.
    pub fn draw<E: std::fmt::Display>(
        &mut self,
        names: &[&str],
        draw: impl FnOnce(&Path) -> std::result::Result<Vec<PathBuf>, E>,
    ) -> Result<()> {
        for name in names {
            self.outputs.check(&self.dir.join(name))?;
        }
        let plots_dir = self.dir.join(format!(".axiscal-{}-plots.tmp", std::process::id()));
        Outputs::create_folder(&plots_dir)?;
        let held = std::fs::File::open(&plots_dir).ok();
        held.iter().for_each(lock_held);
        self.plots_dir = Some((plots_dir.clone(), super::signals::track_temporary(&plots_dir), held));
        let tracked: Vec<Option<usize>> = names
            .iter()
            .map(|n| super::signals::track_temporary(&plots_dir.join(n)))
            .collect();
        let drawn = draw(&plots_dir);
        for (name, tracked) in names.iter().zip(tracked) {
            if drawn.is_err() || !plots_dir.join(name).is_file() {
                // Not drawn: nothing of it to place (the folder goes with the set).
                if let Some(slot) = tracked {
                    super::signals::untrack_temporary(slot);
                }
                continue;
            }
            self.staged.push(Staged {
                temporary: plots_dir.join(name),
                target: self.dir.join(name),
                replace: self.outputs.force,
                tracked,
            });
        }
        drawn.map(|_| ()).map_err(|e| anyhow::anyhow!("{e}"))
    }

    /// Puts every file in place, then removes the files of `stale` this set did not write (an
    /// earlier run's outputs that would no longer belong beside the new ones).
    /// A signal meanwhile waits until every file is placed ([`super::signals::deferred`]).
    pub fn commit(mut self, stale: &[&str]) -> Result<()> {
        // Two commands placing their sets into one folder at once (`--force` both) would
        // interleave their files: the folder's own lock makes each set's placing whole (held
        // already by a command that locked the folder for its whole run).
        let _placing = if self.outputs.holds(&self.dir) {
            None
        } else {
            Some(lock_folder(&self.dir)?)
        };
        let placed: Vec<PathBuf> = self.staged.iter().map(|f| f.target.clone()).collect();
        let staged = std::mem::take(&mut self.staged);
        for (_, tracked) in std::mem::take(&mut self.created) {
            if let Some(slot) = tracked {
                super::signals::untrack_temporary(slot);
            }
        }
        super::signals::deferred(|| {
            for file in staged {
                file.place()?;
            }
            for name in stale {
                let path = self.dir.join(name);
                if !placed.contains(&path) && path.exists() {
                    std::fs::remove_file(&path).with_context(|| format!("removing the stale {}", path.display()))?;
                }
            }
            Ok(())
        })
    }
}

impl Outputs {
    /// Creates the folder `dir` and locks it for the whole command (the lock a set's placing
    /// takes, [`StagedSet::commit`]), for a command that writes files into it as it goes (e.g.
    /// `blind`'s case folders): a second command writing into the folder at the same time is
    /// refused instead of mixing its files with this one's. Released when `self` is dropped.
    pub fn hold_folder(&mut self, dir: &Path) -> Result<()> {
        Self::check_folder(dir)?;
        Outputs::create_folder(dir)?;
        let folder = std::fs::File::open(dir).with_context(|| format!("opening {}", dir.display()))?;
        match folder.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => bail!(
                "{}: another axiscal command is writing into this folder (it holds the folder's lock); wait for it \
                 to finish or choose another --out",
                dir.display()
            ),
            Err(std::fs::TryLockError::Error(e)) => {
                return Err(e).with_context(|| format!("locking {}", dir.display()));
            }
        }
        self.held = Some((canonical(dir).unwrap_or_else(|| dir.to_owned()), folder));
        Ok(())
    }

    /// Whether this command holds `dir` locked ([`Outputs::hold_folder`]).
    fn holds(&self, dir: &Path) -> bool {
        self.held
            .as_ref()
            .is_some_and(|(held, _)| canonical(dir).is_some_and(|d| d == *held))
    }
}

/// An exclusive lock on the folder itself (`flock` on its handle, released when dropped; no
/// lock file left in the user's folder), waited for while another command holds it.
fn lock_folder(dir: &Path) -> Result<std::fs::File> {
    let folder = std::fs::File::open(dir).with_context(|| format!("opening {}", dir.display()))?;
    folder.lock().with_context(|| format!("locking {}", dir.display()))?;
    Ok(folder)
}

impl Drop for StagedSet<'_> {
    fn drop(&mut self) {
        self.staged.clear();
        for (dir, tracked) in self.created.drain(..).rev() {
            let _ = std::fs::remove_dir(&dir);
            if let Some(slot) = tracked {
                super::signals::untrack_temporary(slot);
            }
        }
        if let Some((dir, tracked, _held)) = self.plots_dir.take() {
            let _ = std::fs::remove_dir_all(&dir);
            if let Some(slot) = tracked {
                super::signals::untrack_temporary(slot);
            }
        }
    }
}

/// Where `path` is a symbolic link that reaches a device, a stream or the kernel's own files
/// (`/dev/stdout` -> `/proc/self/fd/1`), or lies among them: the place it reaches. Replacing
/// such a link would replace a system's file, not write the output. Every hop of the link is
/// looked at: `/proc/self/fd/1` itself resolves to whatever stdout is, a regular file too.
fn link_to_a_stream(path: &Path) -> Option<PathBuf> {
    if !path.symlink_metadata().ok()?.is_symlink() {
        return None;
    }
    let special = |p: &Path| ["/proc", "/dev", "/sys"].iter().any(|root| p.starts_with(root));
    let folder = canonical(path).and_then(|p| p.parent().map(Path::to_path_buf));
    if folder.as_deref().is_some_and(special) {
        return Some(path.to_path_buf());
    }
    let mut hop = path.to_path_buf();
    // A chain longer than the kernel follows (40) is not followed either.
    for _ in 0..40 {
        let Ok(next) = std::fs::read_link(&hop) else { break };
        hop = match hop.parent() {
            Some(parent) if next.is_relative() => parent.join(next),
            _ => next,
        };
        if special(&hop) {
            return Some(hop);
        }
    }
    std::fs::metadata(path).is_ok_and(|m| !m.is_file()).then_some(hop)
}

/// What a path that is not a folder is, in words: a file, a device, a FIFO, a socket.
fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt as _;
    let t = meta.file_type();
    if t.is_block_device() || t.is_char_device() {
        "a device"
    } else if t.is_fifo() {
        "a FIFO"
    } else if t.is_socket() {
        "a socket"
    } else {
        "a file"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_name_of_255_bytes_is_written_through_a_shorter_temporary() {
        let dir = tempfile::tempdir().unwrap();
        for name in ["a".repeat(251) + ".csv", "é".repeat(125) + ".csv"] {
            assert!(name.len() <= 255);
            let path = dir.path().join(&name);
            Outputs::new(false).write(&path, "x\n").unwrap();
            assert_eq!(std::fs::read_to_string(&path).unwrap(), "x\n");
        }
        assert_eq!(name_within("aé", 2), "a");
        assert_eq!(name_within("aé", 3), "aé");
    }

    #[test]
    fn temporaries_are_recognised_by_their_names_only() {
        assert_eq!(temporary_owner(".calibration.json.axiscal-123-4.tmp"), Some(123));
        assert_eq!(temporary_owner(".axiscal-77-plots.tmp"), Some(77));
        assert_eq!(temporary_owner(".my.axiscal-notes.tmp"), None);
        assert_eq!(temporary_owner("calibration.json"), None);
        assert_eq!(temporary_owner(".x.axiscal-12.tmp"), None);
        assert_eq!(
            temporary_owner(".x.axiscal-0-1.tmp"),
            None,
            "process 0 is a group, not a run"
        );
    }

    #[test]
    fn a_dead_runs_temporaries_are_removed_and_a_live_ones_kept() {
        let dir = tempfile::tempdir().unwrap();
        // A process that has exited: its id is free (reused only after a wrap-around).
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let dead = child.id();
        child.wait().unwrap();
        let live = std::process::id();
        let names = [
            format!(".a.csv.axiscal-{dead}-0.tmp"),
            format!(".axiscal-{dead}-plots.tmp"),
            format!(".a.csv.axiscal-{live}-0.tmp"),
            "user.tmp".to_string(),
        ];
        std::fs::write(dir.path().join(&names[0]), "x").unwrap();
        std::fs::create_dir(dir.path().join(&names[1])).unwrap();
        std::fs::write(dir.path().join(&names[2]), "x").unwrap();
        std::fs::write(dir.path().join(&names[3]), "x").unwrap();
        Outputs::new(false).remove_orphaned_temporaries(dir.path());
        let kept: Vec<bool> = names.iter().map(|n| dir.path().join(n).exists()).collect();
        assert_eq!(kept, [false, false, true, true]);
    }

    /// Named as a dead run's temporary but not one: a run's in another PID namespace (its lock
    /// held; here by this process), the command's own input, a link, a folder of plots holding
    /// a folder. Each is kept; a dead run's unheld file beside them goes.
    #[test]
    fn what_only_looks_like_a_dead_runs_temporary_is_kept() {
        let dir = tempfile::tempdir().unwrap();
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let dead = child.id();
        child.wait().unwrap();
        let at = |n: &str| dir.path().join(n);
        let [held, input, link, plots, orphan] = [
            format!(".a.csv.axiscal-{dead}-0.tmp"),
            format!(".b.csv.axiscal-{dead}-1.tmp"),
            format!(".c.csv.axiscal-{dead}-2.tmp"),
            format!(".axiscal-{dead}-plots.tmp"),
            format!(".d.csv.axiscal-{dead}-3.tmp"),
        ];
        for name in [&held, &input, &orphan] {
            std::fs::write(at(name), "x").unwrap();
        }
        std::fs::write(at("target.csv"), "x").unwrap();
        std::os::unix::fs::symlink(at("target.csv"), at(&link)).unwrap();
        std::fs::create_dir_all(at(&plots).join("sub")).unwrap();
        let holder = std::fs::File::open(at(&held)).unwrap();
        lock_held(&holder);
        Outputs::new(true)
            .input("--data", &at(&input))
            .remove_orphaned_temporaries(dir.path());
        let kept: Vec<bool> = [&held, &input, &link, &plots, &orphan]
            .iter()
            .map(|n| std::fs::symlink_metadata(at(n)).is_ok())
            .collect();
        assert_eq!(kept, [true, true, true, true, false]);
        assert!(at("target.csv").exists());
        drop(holder);
        Outputs::new(false).remove_orphaned_temporaries(dir.path());
        assert!(!at(&held).exists(), "its lock released, the dead run's temporary goes");
    }

    #[test]
    fn an_input_is_refused_by_any_spelling_and_even_with_force() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("poses.csv");
        std::fs::write(&input, "id\n").unwrap();
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        let outputs = Outputs::new(true).input("--poses", &input);
        let other_spelling = dir.path().join("sub").join("..").join("poses.csv");
        let e = outputs.check(&other_spelling).unwrap_err().to_string();
        assert!(e.contains("own input (--poses"), "{e}");
        #[cfg(unix)]
        {
            let link = dir.path().join("link.csv");
            std::os::unix::fs::symlink(&input, &link).unwrap();
            assert!(outputs.check(&link).is_err());
            let hard = dir.path().join("hard.csv");
            std::fs::hard_link(&input, &hard).unwrap();
            assert!(outputs.check(&hard).is_err());
        }
        assert!(outputs.check(&dir.path().join("new.csv")).is_ok());
        assert_eq!(std::fs::read_to_string(&input).unwrap(), "id\n");
    }

    #[test]
    fn an_existing_output_needs_force_and_is_replaced_whole() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a").join("out.txt");
        Outputs::new(false).write(&out, "one").unwrap();
        let e = Outputs::new(false).write(&out, "two").unwrap_err().to_string();
        assert!(e.contains("pass --force"), "{e}");
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "one");
        // Dropped before commit: the old file stays, no temporary is left behind.
        let mut f = Outputs::new(true).create(&out).unwrap();
        f.write_all(b"half").unwrap();
        drop(f);
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "one");
        assert_eq!(std::fs::read_dir(out.parent().unwrap()).unwrap().count(), 1);
        Outputs::new(true).write(&out, "two").unwrap();
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "two");
    }

    /// Two commands placing a set of files into one folder at once, both with `--force`: the
    /// folder always ends with one command's whole set, never a mix (each round of many files,
    /// so that placings without the folder's lock interleave).
    #[test]
    fn two_sets_placed_at_once_leave_one_whole_set() {
        let dir = tempfile::tempdir().unwrap();
        let names: Vec<String> = (0..40).map(|k| format!("f{k}.txt")).collect();
        let refs: Vec<&str> = names.iter().map(String::as_str).collect();
        for round in 0..20 {
            std::thread::scope(|scope| {
                for writer in ["a", "b"] {
                    let (dir, refs) = (dir.path(), &refs);
                    scope.spawn(move || {
                        let outputs = Outputs::new(true);
                        let mut set = outputs.staged_in(dir).unwrap();
                        for name in refs {
                            set.write(name, writer).unwrap();
                        }
                        set.commit(&[]).unwrap();
                    });
                }
            });
            let contents: std::collections::BTreeSet<String> = refs
                .iter()
                .map(|n| std::fs::read_to_string(dir.path().join(n)).unwrap())
                .collect();
            assert_eq!(contents.len(), 1, "round {round}: a mixed folder {contents:?}");
        }
    }

    /// Two writers of one absent output at once (two runs without `--force`): the first to
    /// commit wins, the second fails naming the target and leaves the first's file and no
    /// temporary; a device is never replaced, even with `--force`.
    #[test]
    fn a_second_writer_never_replaces_the_first() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out.txt");
        let mut first = Outputs::new(false).create(&out).unwrap();
        let mut second = Outputs::new(false).create(&out).unwrap();
        first.write_all(b"first").unwrap();
        second.write_all(b"second").unwrap();
        first.commit().unwrap();
        let e = format!("{:#}", second.commit().unwrap_err());
        assert!(e.contains("appeared while this command ran"), "{e}");
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "first");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        let e = Outputs::new(true)
            .check(Path::new("/dev/null"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a regular file"), "{e}");
    }
}
