//! `fit_spectra`: many measured spectra fitted with one fitter (its start table built once), in parallel, with
//! progress and cancelling.

use std::sync::atomic::AtomicBool;

use numpy::{AllowTypeChange, PyArrayLike2, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyList;

use crate::inverse::spectrum::{fit_spectra_cancellable, MAX_SPECTRA, MAX_SPECTRUM_WAVELENGTHS};

use super::args::Model;
use super::convert::{check_numeric_array, real_vector, reject_string, shape_text};
use super::detach::detached_interruptible;
use super::errors::{internal, invalid};
use super::inverse::{fit_dict, fit_options};
use super::progress::Progress;

const ROWS: &str = "a 2-D array (spectra, wavelengths) or a sequence of spectra, each a sequence of numbers";
const NUMBERS: &str = "a 1-D sequence or array of numbers";

/// Fit the model to many measured reflectance spectra on the same wavelengths: :func:`fit_spectrum` for each, with
/// one fitter (its start table, most of a single fit's time, built once) and the spectra fitted in parallel. With
/// the default options, every 8th spectrum of docs/measured-skin.md (549) took 48 s on 2 cores, 0.09 s a spectrum,
/// against 0.48 s a :func:`fit_spectrum` call; each fit is the one :func:`fit_spectrum` gives.
///
/// Arguments:
///     wavelengths_nm: the measured wavelengths, as for :func:`fit_spectrum`.
///     reflectances: the spectra, one row per spectrum (a 2-D array (N, K) or a sequence of N sequences), each one
///         value in 0..1 per wavelength; 1 to 100000 spectra.
///     free, fixed, specular, objective, starts, transport, streams, bandpass, aperture, model: as for
///         :func:`fit_spectrum`, the same for every spectrum.
///     progress: None, or a callable ``progress(done, total)`` told how many spectra of ``total`` are fitted (about
///         once per percent, from the worker threads, taking the GIL for each call). Returning False cancels: the
///         spectra not yet started are skipped and InterruptedError is raised; an exception raised by the callback
///         cancels the same way and is re-raised. Ctrl-C stops the work too (KeyboardInterrupt).
///
/// Returns:
///     A list of N dicts, each as :func:`fit_spectrum` returns, in the order of the rows.
///
/// Raises:
///     SpectralSkinError: as for :func:`fit_spectrum`; no spectra or more than 100000; a row that is not one value in
///         0..1 per wavelength (the message names it, ``reflectances[i]``), checked before any fit.
///     TypeError: an argument of the wrong type (e.g. a 1-D array: use :func:`fit_spectrum`); a progress that is not
///         callable.
///     InterruptedError: the progress callback returned False.
#[pyfunction]
#[pyo3(
    name = "fit_spectra",
    signature = (
        wavelengths_nm, reflectances, *, free = None, fixed = None, specular = None, objective = "reflectance",
        starts = None, transport = "adding_doubling", streams = None, bandpass = None, aperture = None, model = None,
        progress = None
    )
)]
#[allow(clippy::too_many_arguments)]
pub(super) fn fit_spectra_py<'py>(
    py: Python<'py>,
    wavelengths_nm: &Bound<'py, PyAny>,
    reflectances: &Bound<'py, PyAny>,
    free: Option<&Bound<'py, PyAny>>,
    fixed: Option<&Bound<'py, PyAny>>,
    specular: Option<&Bound<'py, PyAny>>,
    objective: &str,
    starts: Option<&Bound<'py, PyAny>>,
    transport: &str,
    streams: Option<&Bound<'py, PyAny>>,
    bandpass: Option<&Bound<'py, PyAny>>,
    aperture: Option<&str>,
    model: Option<Model>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyList>> {
    let wavelengths = real_vector("wavelengths_nm", wavelengths_nm, NUMBERS, MAX_SPECTRUM_WAVELENGTHS)?;
    let spectra = spectra_rows(reflectances)?;
    let options = fit_options(free, fixed, specular, objective, starts, transport, streams, bandpass, aperture, model)?;
    let progress = Progress::from_arg("fit_spectra", progress)?;
    let hook = progress.as_ref();
    let own_flag = AtomicBool::new(false);
    let cancel = hook.map_or(&own_flag, |h| &h.stopped);
    let total = spectra.len();
    let outcome = detached_interruptible(py, cancel, || {
        let report = |increment: usize| {
            if let Some(h) = hook {
                h.report(increment, total)
            }
        };
        report(0);
        Ok(fit_spectra_cancellable(&wavelengths, &spectra, &options, cancel, &|| report(1)))
    })?;
    if hook.is_some_and(Progress::stopped) {
        return Err(progress.map(Progress::into_error).unwrap_or_else(|| internal("stopped without a progress hook")));
    }
    let fits = outcome?;
    let list = PyList::empty(py);
    for fit in &fits {
        list.append(fit_dict(py, fit)?)?;
    }
    Ok(list)
}

/// The rows of `reflectances`: a 2-D numpy array of ints or floats (any strides; its size checked from the shape
/// before any copy), or a sequence of at most [`MAX_SPECTRA`] sequences of numbers (read up to one row past it).
fn spectra_rows(obj: &Bound<'_, PyAny>) -> PyResult<Vec<Vec<f64>>> {
    const NAME: &str = "reflectances";
    let Ok(untyped) = obj.cast::<PyUntypedArray>() else {
        reject_string(obj, &format!("{NAME} must be {ROWS}"))?;
        let mut rows = Vec::new();
        for (i, row) in obj.try_iter()?.enumerate() {
            if i == MAX_SPECTRA {
                return Err(invalid(NAME, format!("must hold at most {MAX_SPECTRA} spectra; got more")));
            }
            rows.push(real_vector(&format!("{NAME}[{i}]"), &row?, NUMBERS, MAX_SPECTRUM_WAVELENGTHS)?);
        }
        return Ok(rows);
    };
    check_numeric_array(NAME, untyped, ROWS, MAX_SPECTRA * MAX_SPECTRUM_WAVELENGTHS, 2)?;
    let shape = untyped.shape();
    if shape[0] > MAX_SPECTRA || shape[1] > MAX_SPECTRUM_WAVELENGTHS {
        let reason = format!(
            "must hold 1 to {MAX_SPECTRA} spectra of at most {MAX_SPECTRUM_WAVELENGTHS} values; got shape {}",
            shape_text(shape)
        );
        return Err(invalid(NAME, reason));
    }
    let values = obj
        .extract::<PyArrayLike2<'_, f64, AllowTypeChange>>()
        .map_err(|e| PyTypeError::new_err(format!("{NAME} must be {ROWS}: {e}")))?;
    Ok(values.as_array().rows().into_iter().map(|row| row.to_vec()).collect())
}
