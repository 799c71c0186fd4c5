//! Signals: Ctrl-C (SIGINT), SIGTERM and SIGHUP stop a run at the next step, so that
//! the samples so far are kept and no temporary file outlives the program;
//! a file-size limit (SIGXFSZ) becomes a write error with a message.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

#[cfg(unix)]
use signal_hook::consts::{SIGHUP, SIGXFSZ};
use signal_hook::consts::{SIGINT, SIGTERM};

/// The signal a write to a closed pipe raises (the run's end is quiet, and
/// its exit status 141, as on Unix).
#[cfg(unix)]
pub const SIGPIPE: i32 = signal_hook::consts::SIGPIPE;
/// The signal a write to a closed pipe raises on Unix (the exit status of a
/// closed pipe is 141 everywhere).
#[cfg(not(unix))]
pub const SIGPIPE: i32 = 13;

/// The last stop signal received (0: none).
static RECEIVED: AtomicUsize = AtomicUsize::new(0);
/// Whether a stop signal has arrived: a second one then takes the default
/// action.
static STOPPING: AtomicBool = AtomicBool::new(false);

/// For the commands that integrate: SIGINT, SIGTERM and SIGHUP set the flag
/// [`received`] reads; a second one while the first is being handled (the
/// user insists) takes the default action: the program ends at once. For
/// every command: a write beyond the file-size limit (`ulimit -f`) returns an
/// error (EFBIG) instead of killing the program without a word. (SIGPIPE is
/// already ignored by Rust's start-up code: a closed pipe is an error, see
/// `output::say`.)
pub fn install(stop: bool) {
    // A handler that does nothing: the write fails with EFBIG instead. (A
    // handler cannot fail to install for a signal that is not forbidden.)
    #[cfg(unix)]
    let _ = signal_hook::flag::register(SIGXFSZ, &IGNORED);
    if stop {
        // A closed terminal (SIGHUP): the run is kept as for SIGTERM.
        #[cfg(unix)]
        let signals = [SIGINT, SIGTERM, SIGHUP];
        #[cfg(not(unix))]
        let signals = [SIGINT, SIGTERM];
        for signal in signals {
            // The order matters: the temporary file goes before the default
            // action, which is armed by the first signal and taken by the
            // next.
            #[cfg(unix)]
            remove_temporary_on_second(signal);
            let _ = signal_hook::flag::register_conditional_default(signal, &STOPPING);
            let _ = signal_hook::flag::register_usize(
                signal,
                &RECEIVED,
                usize::try_from(signal).unwrap_or(0),
            );
            let _ = signal_hook::flag::register(signal, &STOPPING);
        }
    }
}

/// The temporary file being written ([`removed_if_killed`]), as a C string
/// for `unlink(2)` in a signal handler; null when none.
#[cfg(unix)]
static TEMPORARY: std::sync::atomic::AtomicPtr<libc::c_char> =
    std::sync::atomic::AtomicPtr::new(std::ptr::null_mut());

/// Registers the handler that removes [`TEMPORARY`] when `signal` comes
/// while a stop signal is already being handled (the program then ends at
/// once, by the handler registered next).
#[cfg(unix)]
fn remove_temporary_on_second(signal: i32) {
    let action = || {
        let path = TEMPORARY.load(Ordering::SeqCst);
        if STOPPING.load(Ordering::SeqCst) && !path.is_null() {
            // SAFETY: `path` is a NUL-terminated string that is never freed
            // (`removed_if_killed` leaks it); unlink(2) is async-signal-safe.
            unsafe { libc::unlink(path) };
        }
    };
    // SAFETY: the action only reads atomics and calls unlink(2), which are
    // async-signal-safe; it allocates nothing and takes no lock.
    let _ = unsafe { signal_hook::low_level::register(signal, action) };
}

/// Runs `write`, which writes the temporary file `path`: a second stop
/// signal, which ends the program before `write` can clean up, removes the
/// file first. (The first one is `write`'s to handle: [`received`].)
pub fn removed_if_killed<T>(path: &std::path::Path, write: impl FnOnce() -> T) -> T {
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        // (Leaked: a handler running on another thread may still hold it.)
        let raw = std::ffi::CString::new(path.as_os_str().as_bytes())
            .map_or(std::ptr::null_mut(), std::ffi::CString::into_raw);
        TEMPORARY.store(raw, Ordering::SeqCst);
        let out = write();
        TEMPORARY.store(std::ptr::null_mut(), Ordering::SeqCst);
        out
    }
    #[cfg(not(unix))]
    {
        let _ = path;
        write()
    }
}

/// Set by SIGXFSZ, and never read.
#[cfg(unix)]
static IGNORED: AtomicBool = AtomicBool::new(false);

/// The stop signal received, if any.
pub fn received() -> Option<i32> {
    match RECEIVED.load(Ordering::SeqCst) {
        0 => None,
        s => i32::try_from(s).ok(),
    }
}

/// A run stopped by a signal: exits with 128 + the signal's number (130 for
/// SIGINT, 143 for SIGTERM), as a shell reports a program the signal killed.
#[derive(Debug)]
pub struct Interrupted {
    /// The signal.
    pub signal: i32,
    /// How far the run got, s.
    pub t: f64,
}

impl Interrupted {
    /// The exit status.
    pub fn code(&self) -> u8 {
        u8::try_from(128 + self.signal).unwrap_or(1)
    }
}

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let name = match self.signal {
            SIGINT => "SIGINT (Ctrl-C)".to_string(),
            SIGTERM => "SIGTERM".to_string(),
            #[cfg(unix)]
            SIGHUP => "SIGHUP (the terminal closed)".to_string(),
            SIGPIPE => "a closed pipe".to_string(),
            s => format!("signal {s}"),
        };
        write!(
            f,
            "interrupted by {name} at t = {} s",
            mstar::newmark::Short(self.t)
        )
    }
}

impl std::error::Error for Interrupted {}
