//! The `progress=` callback of the long calls (`maps`, `fit_albedo_map`): a Python callable told (done, total) from
//! the core's worker threads, whose False answer (or exception) cancels the work through the core's flag.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;

use pyo3::exceptions::{PyInterruptedError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::PyBool;

/// A Python callable told (units done, total units) from the worker threads, about once per percent (it takes the
/// GIL for each call); returning False cancels (the core skips the work not yet started). An exception it raises
/// cancels too and is re-raised by the call (`what`, which also names the call in the cancel's InterruptedError).
pub(super) struct Progress {
    what: &'static str,
    callback: Py<PyAny>,
    done: AtomicUsize,
    reported_percent: AtomicUsize,
    /// The core's cancel flag: set by a False answer or an exception (and by Ctrl-C through the caller).
    pub(super) stopped: AtomicBool,
    error: Mutex<Option<PyErr>>,
}

impl Progress {
    /// The `progress` argument of `what`: None, or a callable (a TypeError naming the type otherwise).
    pub(super) fn from_arg(what: &'static str, progress: Option<Bound<'_, PyAny>>) -> PyResult<Option<Progress>> {
        let Some(callback) = progress.filter(|c| !c.is_none()) else {
            return Ok(None);
        };
        if !callback.is_callable() {
            let type_name = callback.get_type().name().map(|n| n.to_string()).unwrap_or_default();
            return Err(PyTypeError::new_err(format!(
                "progress must be a callable (done, total) -> bool | None, or None; got {type_name}"
            )));
        }
        Ok(Some(Progress {
            what,
            callback: callback.unbind(),
            done: AtomicUsize::new(0),
            reported_percent: AtomicUsize::new(0),
            stopped: AtomicBool::new(false),
            error: Mutex::new(None),
        }))
    }

    pub(super) fn stopped(&self) -> bool {
        self.stopped.load(Ordering::Relaxed)
    }

    /// `increment` more units are done out of `total` (0 for the first call, and for a tick that only asks whether
    /// to go on).
    pub(super) fn report(&self, increment: usize, total: usize) {
        let done = self.done.fetch_add(increment, Ordering::Relaxed) + increment;
        let percent = done.saturating_mul(100) / total.max(1);
        if self.stopped() || (increment > 0 && self.reported_percent.fetch_max(percent, Ordering::Relaxed) >= percent) {
            return;
        }
        // Calls are serialised by the GIL but may arrive out of order (a thread that counted fewer units can get the
        // GIL after the one that finished), so each call reports the count as it stands once the GIL is held: what
        // the callback sees never goes backwards, and the last call says total.
        Python::attach(|py| match self.callback.call1(py, (self.done.load(Ordering::Relaxed).min(total), total)) {
            Ok(answer) => {
                if answer.bind(py).is_instance_of::<PyBool>() && !answer.bind(py).is_truthy().unwrap_or(true) {
                    self.stopped.store(true, Ordering::Relaxed);
                }
            }
            Err(e) => {
                if let Ok(mut slot) = self.error.lock() {
                    slot.get_or_insert(e);
                }
                self.stopped.store(true, Ordering::Relaxed);
            }
        });
    }

    /// Why the work stopped: the callback's exception, or an InterruptedError for a False answer.
    pub(super) fn into_error(self) -> PyErr {
        match self.error.into_inner().ok().flatten() {
            Some(e) => e,
            None => PyInterruptedError::new_err(format!(
                "{}: cancelled by the progress callback (it returned False)",
                self.what
            )),
        }
    }
}
