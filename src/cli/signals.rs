//! Signals. Every command: SIGINT, SIGTERM or SIGHUP removes the temporary files of the outputs
//! being written, then ends the process as the signal would ([`install_cleanup`]); while a set
//! of finished outputs is being put in place ([`deferred`]) the signal waits for it. Long runs
//! ([`install`]): the first SIGINT or SIGTERM asks the run to stop (the trials in flight finish,
//! what was done is saved, the exit code is 128 + the signal), a second one removes the
//! temporary files and ends the process at once (every finished trial is already in
//! `trials.csv`, so `--resume` still works).

use std::ffi::{CString, c_char};
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicI32, AtomicPtr, Ordering};

/// Temporary files a signal removes: at most this many open at once (more are not tracked).
const TEMPORARY_SLOTS: usize = 4096;

/// The tracked temporary files' paths, as C strings a handler may read at any moment: a slot is
/// cleared when its file is committed or dropped, and its string is never freed (a handler may
/// still hold it), a few bytes per output written.
static TEMPORARIES: [AtomicPtr<c_char>; TEMPORARY_SLOTS] =
    [const { AtomicPtr::new(std::ptr::null_mut()) }; TEMPORARY_SLOTS];

/// Tracks `path` (a file, or a folder removed once its tracked files are) for removal by a
/// signal; the slot to pass to [`untrack_temporary`] (`None`:
/// every slot in use, or a path with a NUL byte; the file is then not removed by a signal).
pub fn track_temporary(path: &Path) -> Option<usize> {
    use std::os::unix::ffi::OsStrExt;
    let c = CString::new(path.as_os_str().as_bytes()).ok()?.into_raw();
    let slot = TEMPORARIES.iter().position(|s| {
        s.compare_exchange(std::ptr::null_mut(), c, Ordering::SeqCst, Ordering::SeqCst)
            .is_ok()
    });
    if slot.is_none() {
        // SAFETY: `c` came from `into_raw` above and was never shared.
        drop(unsafe { CString::from_raw(c) });
    }
    slot
}

/// Stops tracking the file of `slot` (committed, or removed by its owner).
pub fn untrack_temporary(slot: usize) {
    TEMPORARIES[slot].store(std::ptr::null_mut(), Ordering::SeqCst);
}

/// Removes every tracked temporary file, then every tracked temporary folder left empty
/// (async-signal-safe: atomics, `unlink` and `rmdir`; each fails harmlessly on the other kind).
fn remove_temporaries() {
    for remove in [
        libc::unlink as unsafe extern "C" fn(*const c_char) -> libc::c_int,
        libc::rmdir,
    ] {
        for slot in &TEMPORARIES {
            let path = slot.load(Ordering::SeqCst);
            if !path.is_null() {
                // SAFETY: a tracked pointer is a NUL-terminated string that is never freed.
                unsafe { remove(path) };
            }
        }
    }
}

/// How many [`deferred`] sections are running: while one is, a cleanup signal is held.
static PLACING: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
/// The cleanup signal held while outputs were being placed (0: none).
static HELD: AtomicI32 = AtomicI32::new(0);

/// Runs `place` (renames that put a set of finished outputs in place of the old ones) with
/// SIGINT, SIGTERM and SIGHUP held: a signal arriving meanwhile ends the process once every
/// file is placed, so that a folder never holds part of a new set beside part of the old one.
pub fn deferred<T>(place: impl FnOnce() -> T) -> T {
    PLACING.fetch_add(1, Ordering::SeqCst);
    let out = place();
    if PLACING.fetch_sub(1, Ordering::SeqCst) == 1 {
        let held = HELD.swap(0, Ordering::SeqCst);
        if held != 0 {
            end_by(held);
        }
    }
    out
}

/// Removes the temporaries and ends the process as `signal` would (async-signal-safe).
fn end_by(signal: libc::c_int) {
    remove_temporaries();
    // SAFETY: signal and raise are async-signal-safe; the default action then ends the process
    // as the signal would have.
    unsafe {
        libc::signal(signal, libc::SIG_DFL);
        libc::raise(signal);
    }
}

#[cfg(unix)]
extern "C" fn on_cleanup_signal(signal: libc::c_int) {
    if PLACING.load(Ordering::SeqCst) > 0 {
        HELD.store(signal, Ordering::SeqCst);
        return;
    }
    end_by(signal);
}

/// Installs the cleanup handlers for SIGINT, SIGTERM and SIGHUP (module docs), and ignores
/// SIGXFSZ: a write beyond the file-size limit (`ulimit -f`) then fails as an error the command
/// reports (exit 2, its temporary files removed) instead of ending the process.
pub fn install_cleanup() {
    #[cfg(unix)]
    for signal in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP] {
        let handler = on_cleanup_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
        // SAFETY: the handler only touches atomics and calls unlink, signal and raise.
        unsafe { libc::signal(signal, handler) };
    }
    #[cfg(unix)]
    // SAFETY: ignoring a signal installs no code.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN)
    };
}

/// The first signal received (0: none).
static RECEIVED: AtomicI32 = AtomicI32::new(0);
/// Set with `RECEIVED`, for the runner's stop check.
pub static STOP: AtomicBool = AtomicBool::new(false);

#[cfg(unix)]
extern "C" fn on_signal(signal: libc::c_int) {
    // Only async-signal-safe work here: atomics and _exit.
    if RECEIVED.swap(signal, Ordering::SeqCst) != 0 {
        remove_temporaries();
        // SAFETY: _exit is async-signal-safe and ends the process without unwinding.
        unsafe { libc::_exit(128 + signal) };
    }
    STOP.store(true, Ordering::SeqCst);
}

/// Installs the handlers (no-op where there are no POSIX signals).
pub fn install() {
    #[cfg(unix)]
    for signal in [libc::SIGINT, libc::SIGTERM] {
        let handler = on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
        // SAFETY: the handler only touches atomics and calls _exit (async-signal-safe).
        unsafe { libc::signal(signal, handler) };
    }
}

/// The signal that asked the run to stop, if any.
pub fn received() -> Option<i32> {
    Some(RECEIVED.load(Ordering::SeqCst)).filter(|&s| s != 0)
}

/// The signal's name for messages.
pub fn name(signal: i32) -> String {
    match signal {
        2 => "SIGINT".into(),
        15 => "SIGTERM".into(),
        s => format!("signal {s}"),
    }
}
