//! Core calls with the GIL released: panics become RuntimeErrors, long work watches for Ctrl-C.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::Duration;

use pyo3::prelude::*;

use crate::error::SkinError;

use super::errors::{internal, panic_error};

/// Run a core call with the GIL released. A panic (a bug: the core validates its input) becomes a RuntimeError
/// instead of crossing into Python as a PanicException.
pub(super) fn detached<T: Send>(py: Python<'_>, f: impl FnOnce() -> Result<T, SkinError> + Send) -> PyResult<T> {
    let result = py.detach(|| catch_unwind(AssertUnwindSafe(f)));
    match result {
        Ok(value) => Ok(value?),
        Err(payload) => Err(panic_error(payload)),
    }
}

/// How often a long call's own thread wakes to run Python's signal handlers (Ctrl-C) while the work runs.
pub(super) const SIGNAL_POLL: Duration = Duration::from_millis(100);

/// [`detached`] for long work that can stop early: the work runs on a scoped thread while the calling thread, with
/// the GIL released, wakes every [`SIGNAL_POLL`] to run Python's signal handlers (CPython runs them on the main
/// thread only, so the watching must happen here). An exception from a handler (KeyboardInterrupt for Ctrl-C) sets
/// `cancel`, waits for the work to stop at its next check, and is raised instead of the result.
pub(super) fn detached_interruptible<T: Send>(
    py: Python<'_>,
    cancel: &AtomicBool,
    f: impl FnOnce() -> Result<T, SkinError> + Send,
) -> PyResult<T> {
    let (sender, receiver) = mpsc::channel();
    let (result, interrupted) = std::thread::scope(|scope| {
        scope.spawn(move || {
            // Nothing to do if the receiver is gone: it only goes when this scope ends, after the work.
            let _ = sender.send(catch_unwind(AssertUnwindSafe(f)));
        });
        let mut interrupted: Option<PyErr> = None;
        let mut receiver = receiver;
        loop {
            // The receiver travels into the GIL-free closure and back (it is Send, not Sync).
            let (received, back) = py.detach(move || (receiver.recv_timeout(SIGNAL_POLL), receiver));
            receiver = back;
            match received {
                Ok(result) => return (Some(result), interrupted),
                Err(RecvTimeoutError::Timeout) => {
                    if interrupted.is_none() {
                        if let Err(e) = py.check_signals() {
                            cancel.store(true, Ordering::Relaxed);
                            interrupted = Some(e);
                        }
                    }
                }
                Err(RecvTimeoutError::Disconnected) => return (None, interrupted),
            }
        }
    });
    if let Some(e) = interrupted {
        return Err(e);
    }
    match result {
        Some(Ok(value)) => Ok(value?),
        Some(Err(payload)) => Err(panic_error(payload)),
        None => Err(internal("the worker thread ended without a result")),
    }
}
