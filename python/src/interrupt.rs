//! Ctrl-C during long work: the work runs without the GIL on a helper thread while the calling
//! thread checks for Python signals every [`POLL`]; a signal handler's exception (the
//! `KeyboardInterrupt` of Ctrl-C) raises the flag the work asks before every step
//! ([`galerkin_vi::solve::solve_until`]) and every member, the work returns within a step, and
//! the exception is raised. Nothing of the stopped work is kept: no partial result reaches
//! Python.

use pyo3::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::Duration;

/// How often the calling thread checks for Python signals while the work runs (short work
/// finishes before the first check and never takes the GIL back).
const POLL: Duration = Duration::from_millis(20);

/// The flag the work reads: raised once a Python signal handler raised an exception.
pub struct Stop(AtomicBool);

impl Stop {
    /// Whether the work should stop before its next step (an atomic load).
    pub fn requested(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

/// Run `work` with the GIL released, interruptible by Ctrl-C (see the module docs). The
/// result is `work`'s, or the exception of the Python signal handler that stopped it.
pub fn interruptible<T: Send>(py: Python<'_>, work: impl FnOnce(&Stop) -> T + Send) -> PyResult<T> {
    let stop = Stop(AtomicBool::new(false));
    let (value, raised) = py.detach(|| {
        std::thread::scope(|scope| {
            let (done, finished) = mpsc::channel::<()>();
            let stop = &stop;
            let worker = scope.spawn(move || {
                let value = work(stop);
                // The receiver lives until the join below.
                let _ = done.send(());
                value
            });
            let mut raised: Option<PyErr> = None;
            while let Err(mpsc::RecvTimeoutError::Timeout) = finished.recv_timeout(POLL) {
                if raised.is_none() {
                    raised = Python::attach(|py| py.check_signals()).err();
                    stop.0.store(raised.is_some(), Ordering::Relaxed);
                }
            }
            match worker.join() {
                Ok(value) => (value, raised),
                // A panic keeps unwinding; pyo3 turns it into a PanicException.
                Err(panic) => std::panic::resume_unwind(panic),
            }
        })
    });
    match raised {
        Some(e) => Err(e),
        None => Ok(value),
    }
}
