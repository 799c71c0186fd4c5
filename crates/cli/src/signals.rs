//! Signals: Ctrl-C (SIGINT), SIGTERM and SIGHUP stop a run at the next step, so that
//! the samples so far are kept and no temporary file outlives the program;
//! a file-size limit (SIGXFSZ) becomes a write error with a message.

use std::sync::atomic::{AtomicI32, Ordering};

/// The first stop signal received (0: none).
static RECEIVED: AtomicI32 = AtomicI32::new(0);

/// Records the signal for the integration loop; a second one while the first
/// is being handled (the user insists) takes the default action: the program
/// ends at once.
extern "C" fn on_stop(signal: libc::c_int) {
    if RECEIVED.swap(signal, Ordering::SeqCst) != 0 {
        // SAFETY: signal and raise are async-signal-safe.
        unsafe {
            libc::signal(signal, libc::SIG_DFL);
            libc::raise(signal);
        }
    }
}

/// For the commands that integrate: SIGINT, SIGTERM and SIGHUP set the flag
/// [`received`] reads. For every command: a write beyond the file-size limit
/// (`ulimit -f`) returns an error (EFBIG) instead of killing the program
/// without a word. (SIGPIPE is already ignored by Rust's start-up code: a
/// closed pipe is an error, see `output::say`.)
pub fn install(stop: bool) {
    // SAFETY: the handler only touches an atomic and calls async-signal-safe
    // functions; SIG_IGN needs no handler.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
        if stop {
            let handler = on_stop as extern "C" fn(libc::c_int) as libc::sighandler_t;
            libc::signal(libc::SIGINT, handler);
            libc::signal(libc::SIGTERM, handler);
            // A closed terminal: the run is kept as for SIGTERM.
            libc::signal(libc::SIGHUP, handler);
        }
    }
}

/// The stop signal received, if any.
pub fn received() -> Option<i32> {
    match RECEIVED.load(Ordering::SeqCst) {
        0 => None,
        s => Some(s),
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
            libc::SIGINT => "SIGINT (Ctrl-C)".to_string(),
            libc::SIGTERM => "SIGTERM".to_string(),
            libc::SIGHUP => "SIGHUP (the terminal closed)".to_string(),
            libc::SIGPIPE => "a closed pipe".to_string(),
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
