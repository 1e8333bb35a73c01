//! The exception classes, the mapping of the core's SkinError onto them, and the warnings.

use pyo3::create_exception;
use pyo3::exceptions::{PyOSError, PyRuntimeError, PyUserWarning, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::error::SkinError;

create_exception!(
    spectral_skin,
    SpectralSkinError,
    PyValueError,
    "Invalid input to spectral-skin. The message names the input, its allowed range and the value received."
);

create_exception!(
    spectral_skin,
    SpectralSkinWarning,
    PyUserWarning,
    "A result spectral-skin computed but changed on its way out (a negative profile lobe set to 0), or an input it \
     read with something ignored (an alpha channel, a channel of no parameter's name); the message says what."
);

create_exception!(
    spectral_skin,
    SpectralSkinIOError,
    PyOSError,
    "A file spectral-skin could not read or write (missing, unreadable, corrupt, or a folder it cannot write to). \
     An OSError whose message names the file and says what went wrong."
);

/// Warn (SpectralSkinWarning) once per note of a reader (an input accepted with something ignored: the note names the
/// file and what).
pub(super) fn warn_notes(py: Python<'_>, notes: &[String]) -> PyResult<()> {
    for note in notes {
        let message = std::ffi::CString::new(note.as_str()).map_err(internal)?;
        PyErr::warn(py, &py.get_type::<SpectralSkinWarning>(), &message, 1)?;
    }
    Ok(())
}

/// Warn (SpectralSkinWarning) about a negative lobe the clamp removed, so it is never hidden.
pub(super) fn warn_lobe(py: Python<'_>, lobe: Option<impl std::fmt::Display>) -> PyResult<()> {
    match lobe {
        Some(lobe) => {
            let message = std::ffi::CString::new(lobe.to_string()).map_err(internal)?;
            PyErr::warn(py, &py.get_type::<SpectralSkinWarning>(), &message, 1)
        }
        None => Ok(()),
    }
}

impl From<SkinError> for PyErr {
    /// A SpectralSkinIOError (an OSError, with ``errno`` where the operating system gave one) for a file that cannot
    /// be read or written, else a SpectralSkinError. Bad texels in a parameter map also carry ``bad_texels``:
    /// {"parameter", "min", "max", "nan", "infinite", "out_of_range", "first"}, so a front can word its own advice
    /// (the add-on's checkbox).
    fn from(e: SkinError) -> PyErr {
        // No `filename` attribute: with one and no errno, OSError's str() turns into "[Errno None] None: path". The
        // operating system's error code, where there is one, is `errno` (str() stays the message: it shows errno only
        // with a strerror).
        if let SkinError::Io { source, .. } = &e {
            let err = SpectralSkinIOError::new_err(e.to_string());
            if let Some(code) = source.as_ref().and_then(|s| s.error().raw_os_error()) {
                // Only the attribute is lost if this fails; the message says it all.
                Python::attach(|py| {
                    let _ = err.value(py).setattr("errno", code);
                });
            }
            return err;
        }
        let err = SpectralSkinError::new_err(e.with_clamp_advice("pass clamp=True"));
        if let SkinError::BadTexels { parameter, min, max, nan, infinite, out_of_range, first } = e {
            Python::attach(|py| {
                let fields = PyDict::new(py);
                let set = || -> PyResult<()> {
                    fields.set_item("parameter", parameter)?;
                    fields.set_item("min", min)?;
                    fields.set_item("max", max)?;
                    fields.set_item("nan", nan)?;
                    fields.set_item("infinite", infinite)?;
                    fields.set_item("out_of_range", out_of_range)?;
                    fields.set_item("first", first)?;
                    err.value(py).setattr("bad_texels", &fields)
                };
                // Only the attribute is lost if this fails; the message says it all.
                let _ = set();
            });
        }
        err
    }
}

/// A panic (a bug: the core validates its input) as a RuntimeError instead of a PanicException.
pub(super) fn panic_error(payload: Box<dyn std::any::Any + Send>) -> PyErr {
    let message = crate::numeric::panic_message(payload.as_ref()).unwrap_or_else(|| "unknown panic".to_string());
    PyRuntimeError::new_err(format!("spectral-skin internal error (please report it): {message}"))
}

pub(super) fn invalid(name: impl Into<String>, reason: impl Into<String>) -> PyErr {
    SkinError::invalid(name, reason).into()
}

pub(super) fn internal<E: std::fmt::Display>(e: E) -> PyErr {
    PyRuntimeError::new_err(format!("spectral-skin internal error: {e}"))
}
