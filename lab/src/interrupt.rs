//! Ctrl-C during a streamed run: the first SIGINT asks the run to stop after the step in
//! progress, so that the rows computed so far are committed to the output instead of being
//! lost with the temporary file; a second SIGINT ends the process at once, as usual. Outside a
//! [`catch`] guard SIGINT keeps its default action (a study stops at once).

use std::sync::atomic::{AtomicBool, Ordering};

static REQUESTED: AtomicBool = AtomicBool::new(false);

#[cfg(unix)]
extern "C" fn on_sigint(_: libc::c_int) {
    REQUESTED.store(true, Ordering::SeqCst);
    // A second Ctrl-C ends the process at once (signal() is async-signal-safe).
    // SAFETY: restoring the default disposition of SIGINT has no preconditions.
    unsafe {
        libc::signal(libc::SIGINT, libc::SIG_DFL);
    }
}

/// While alive, the first SIGINT sets [`requested`] instead of ending the process; dropped, the
/// previous disposition of SIGINT is restored.
pub struct Guard {
    #[cfg(unix)]
    previous: libc::sighandler_t,
}

/// Catch SIGINT until the returned guard is dropped (on non-Unix systems, a no-op).
pub fn catch() -> Guard {
    REQUESTED.store(false, Ordering::SeqCst);
    #[cfg(unix)]
    {
        let handler = on_sigint as extern "C" fn(libc::c_int) as libc::sighandler_t;
        // SAFETY: the handler only stores to an atomic and calls signal(), both
        // async-signal-safe.
        let previous = unsafe { libc::signal(libc::SIGINT, handler) };
        Guard { previous }
    }
    #[cfg(not(unix))]
    Guard {}
}

impl Drop for Guard {
    fn drop(&mut self) {
        #[cfg(unix)]
        // SAFETY: restores the disposition that was in place before `catch`.
        unsafe {
            libc::signal(libc::SIGINT, self.previous);
        }
    }
}

/// Whether a SIGINT arrived since [`catch`].
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}
