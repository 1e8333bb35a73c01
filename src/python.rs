//! Python bindings (`spectral_skin._core`, built by maturin with the `python` feature). Bindings only: every function
//! reads its arguments under the GIL, makes one core call with the GIL released, and converts the result. No physics
//! lives here; names of outputs, combinations and working spaces come from the core's serde names.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use numpy::ndarray::{Array2, Array3, ArrayView2, Axis, Ix2, Ix3};
use numpy::{
    AllowTypeChange, Element, PyArray, PyArray1, PyArray2, PyArray3, PyArrayDescrMethods, PyArrayDyn, PyArrayLike1,
    PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::create_exception;
use pyo3::exceptions::{PyInterruptedError, PyOSError, PyRuntimeError, PyTypeError, PyUserWarning, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyDict, PyList, PyString};
use rayon::prelude::*;
use serde::Serialize;
use serde_json::Value;

use crate::color::{ALL_RGB_MAPPINGS, ALL_WAVELENGTH_PLACEMENTS, ALL_WORKING_SPACES};
use crate::diffusion::{Layer, MultipoleTerms, ALL_BOUNDARIES, ALL_COMBINATIONS};
use crate::error::SkinError;
use crate::evaluate::{Evaluation, MethodParams, ProfileGrid};
use crate::fit::blender_target::{describe_targets, BlenderVersion, Engine, Target, CURRENT_RELEASE};
use crate::fit::SubsurfaceMethod;
use crate::maps::io::{
    read_params, ExrOptions, ParamImage, ParamInputs, ParamSource, Plane, ALL_COMPRESSIONS, ALL_PRECISIONS, MAX_TEXELS,
    PARAM_CHANNELS,
};
use crate::maps::lut::TableResolution;
use crate::maps::pipeline::{
    check_planes, commit_map_files, compute_maps_cancellable, output_name, stage_map_files, MapFiles, MapSettings,
    SpecularOutput, StrategyChoice, ALBEDO_FILE, RADIUS_FILE, SPECULAR_FILE,
};
use crate::{Accuracy, AccuracyLevel, Outputs, Request, SkinParams, PRESETS};

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
    "A result spectral-skin computed but changed on its way out (a negative profile lobe set to 0); the message says \
     what and how to avoid it."
);

create_exception!(
    spectral_skin,
    SpectralSkinIOError,
    PyOSError,
    "A file spectral-skin could not read or write (missing, unreadable, corrupt, or a folder it cannot write to). \
     An OSError whose message names the file and says what went wrong."
);

/// Warn (SpectralSkinWarning) about a negative lobe the clamp removed, so it is never hidden.
fn warn_lobe(py: Python<'_>, lobe: Option<impl std::fmt::Display>) -> PyResult<()> {
    match lobe {
        Some(lobe) => {
            let message = std::ffi::CString::new(lobe.to_string()).map_err(internal)?;
            PyErr::warn(py, &py.get_type::<SpectralSkinWarning>(), &message, 1)
        }
        None => Ok(()),
    }
}

impl From<SkinError> for PyErr {
    /// A SpectralSkinIOError (an OSError) for a file that cannot be read or written, else a SpectralSkinError. Bad texels in a parameter map also carry ``bad_texels``: {"parameter", "min", "max",
    /// "nan", "infinite", "out_of_range", "first"}, so a front can word its own advice (the add-on's checkbox).
    fn from(e: SkinError) -> PyErr {
        // No `filename` attribute: with one and no errno, OSError's str() turns into "[Errno None] None: path".
        if let SkinError::Io { .. } = &e {
            return SpectralSkinIOError::new_err(e.to_string());
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

/// The Outputs the material path needs: the default of `evaluate(outputs=...)`.
const MATERIAL_OUTPUTS: [&str; 3] = ["albedo", "radius", "specular"];
/// The fields of `SpecularParams` that do not depend on the oiliness: what `maps` returns in "specular" when the
/// oiliness varies (beside the per-texel "specular_ior_level").
const SPECULAR_CONSTANTS: [&str; 3] = ["roughness", "ior", "beckmann_m"];
/// The fields of one layer tuple, in order.
const LAYER_FIELDS: &str = "(thickness_mm, sigma_a_per_mm, sigma_s_reduced_per_mm, ior)";

/// Run a core call with the GIL released. A panic (a bug: the core validates its input) becomes a RuntimeError
/// instead of crossing into Python as a PanicException.
fn detached<T: Send>(py: Python<'_>, f: impl FnOnce() -> Result<T, SkinError> + Send) -> PyResult<T> {
    let result = py.detach(|| catch_unwind(AssertUnwindSafe(f)));
    match result {
        Ok(value) => Ok(value?),
        Err(payload) => Err(panic_error(payload)),
    }
}

/// How often a long call's own thread wakes to run Python's signal handlers (Ctrl-C) while the work runs.
const SIGNAL_POLL: Duration = Duration::from_millis(100);

/// [`detached`] for long work that can stop early: the work runs on a scoped thread while the calling thread, with
/// the GIL released, wakes every [`SIGNAL_POLL`] to run Python's signal handlers (CPython runs them on the main
/// thread only, so the watching must happen here). An exception from a handler (KeyboardInterrupt for Ctrl-C) sets
/// `cancel`, waits for the work to stop at its next check, and is raised instead of the result.
fn detached_interruptible<T: Send>(
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

/// A panic (a bug: the core validates its input) as a RuntimeError instead of a PanicException.
fn panic_error(payload: Box<dyn std::any::Any + Send>) -> PyErr {
    let message = crate::numeric::panic_message(payload.as_ref()).unwrap_or_else(|| "unknown panic".to_string());
    PyRuntimeError::new_err(format!("spectral-skin internal error (please report it): {message}"))
}

fn invalid(name: impl Into<String>, reason: impl Into<String>) -> PyErr {
    SkinError::invalid(name, reason).into()
}

/// A TypeError if `obj` is a str or bytes where a sequence is expected (strings are iterable, so they would
/// otherwise be read character by character).
fn reject_string(obj: &Bound<'_, PyAny>, expected: &str) -> PyResult<()> {
    if obj.is_instance_of::<PyString>() || obj.is_instance_of::<PyBytes>() {
        return Err(PyTypeError::new_err(format!("{expected}, not a string")));
    }
    Ok(())
}

/// The Python type of `obj`, for messages.
fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type().name().map(|n| n.to_string()).unwrap_or_default()
}

/// True for Python's and numpy's booleans: they convert to numbers, but `True` as a concentration or a step is a
/// mistake, not a 1.
fn is_boolean(obj: &Bound<'_, PyAny>) -> bool {
    obj.is_instance_of::<PyBool>() || type_name(obj) == "bool_" || type_name(obj) == "bool"
}

/// The one rule for every numeric argument: an int or a float (or a numpy scalar of either), never a bool, str or
/// bytes. A wrong type is a TypeError whose message names the argument (pyo3 only adds the name as a note).
fn number_type_check(name: &str, obj: &Bound<'_, PyAny>, what: &str) -> PyResult<()> {
    if is_boolean(obj) || obj.is_instance_of::<PyString>() || obj.is_instance_of::<PyBytes>() {
        return Err(PyTypeError::new_err(format!("{name} must be {what}; got {} {}", type_name(obj), obj.repr()?)));
    }
    Ok(())
}

/// A real number (see [`number_type_check`]).
#[derive(Debug, Clone, Copy)]
struct Real(f64);

/// An integer (see [`number_type_check`]); a float is a TypeError too.
#[derive(Debug, Clone, Copy)]
struct Count(i64);

const A_NUMBER: &str = "a number (int or float)";
const AN_INTEGER: &str = "an integer";

fn real_of(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Real> {
    number_type_check(name, obj, A_NUMBER)?;
    obj.extract::<f64>()
        .map(Real)
        .map_err(|_| PyTypeError::new_err(format!("{name} must be {A_NUMBER}; got {}", type_name(obj))))
}

fn count_of(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Count> {
    number_type_check(name, obj, AN_INTEGER)?;
    obj.extract::<i64>()
        .map(Count)
        .map_err(|_| PyTypeError::new_err(format!("{name} must be {AN_INTEGER}; got {}", type_name(obj))))
}

/// An optional numeric keyword argument (None is absent).
fn real_arg(name: &str, obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Real>> {
    obj.filter(|o| !o.is_none()).map(|o| real_of(name, o)).transpose()
}

fn count_arg(name: &str, obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Count>> {
    obj.filter(|o| !o.is_none()).map(|o| count_of(name, o)).transpose()
}

/// `obj` as a sequence of numbers under the rule of [`Real`]; a wrong element is a TypeError naming `name[i]`.
fn real_sequence(name: &str, obj: &Bound<'_, PyAny>, expected: &str) -> PyResult<Vec<f64>> {
    reject_string(obj, &format!("{name} must be {expected}"))?;
    let iter = obj
        .try_iter()
        .map_err(|_| PyTypeError::new_err(format!("{name} must be {expected}; got {}", type_name(obj))))?;
    iter.enumerate().map(|(i, item)| Ok(real_of(&format!("{name}[{i}]"), &item?)?.0)).collect()
}

/// `obj` as a sequence of integers under the rule of [`Count`]; a wrong element is a TypeError naming `name[i]`.
fn count_sequence(name: &str, obj: &Bound<'_, PyAny>, expected: &str) -> PyResult<Vec<i64>> {
    reject_string(obj, &format!("{name} must be {expected}"))?;
    let iter = obj
        .try_iter()
        .map_err(|_| PyTypeError::new_err(format!("{name} must be {expected}; got {}", type_name(obj))))?;
    iter.enumerate().map(|(i, item)| Ok(count_of(&format!("{name}[{i}]"), &item?)?.0)).collect()
}

/// The serde name of a core enum value (e.g. "directional", "Linear Rec.709").
fn serde_name<T: Serialize>(value: &T) -> String {
    match serde_json::to_value(value) {
        Ok(Value::String(s)) => s,
        _ => String::new(),
    }
}

/// The value among `candidates` whose serde name is `name`; the error lists the accepted names.
fn by_name<T: Serialize + Copy>(what: &str, name: &str, candidates: &[T]) -> PyResult<T> {
    candidates.iter().copied().find(|c| serde_name(c) == name).ok_or_else(|| {
        let names: Vec<String> = candidates.iter().map(|c| format!("{:?}", serde_name(c))).collect();
        invalid(what, format!("unknown {what} {name:?}; valid: {}", names.join(", ")))
    })
}

/// Names in `outputs` (an iterable of str) to [`Outputs`]; the valid names are `Outputs`' field names.
fn parse_outputs(outputs: Option<&Bound<'_, PyAny>>) -> PyResult<Outputs> {
    let names: Vec<String> = match outputs {
        None => MATERIAL_OUTPUTS.iter().map(|s| s.to_string()).collect(),
        Some(obj) => {
            reject_string(obj, "outputs must be an iterable of output names")?;
            obj.try_iter()?.map(|item| item?.extract::<String>()).collect::<PyResult<_>>()?
        }
    };
    let Ok(Value::Object(mut fields)) = serde_json::to_value(Outputs::default()) else {
        return Err(PyRuntimeError::new_err("spectral-skin internal error: Outputs does not serialise to an object"));
    };
    for name in &names {
        match fields.get_mut(name.as_str()) {
            Some(flag) => *flag = Value::Bool(true),
            None => {
                let valid: Vec<String> = fields.keys().map(|k| format!("{k:?}")).collect();
                return Err(invalid("outputs", format!("unknown output {name:?}; valid: {}", valid.join(", "))));
            }
        }
    }
    serde_json::from_value(Value::Object(fields))
        .map_err(|e| PyRuntimeError::new_err(format!("spectral-skin internal error: {e}")))
}

/// A preset and/or the four parameters: explicit parameters override the preset's; without a preset all four are
/// required. The core validates the ranges.
fn resolve_params(preset: Option<&str>, explicit: [Option<Real>; 4]) -> PyResult<SkinParams> {
    let explicit = explicit.map(|v| v.map(|r| r.0));
    let base = preset.map(SkinParams::preset).transpose()?;
    let from_preset = base.map(|p| [p.melanin, p.melanin_blend, p.hemoglobin, p.oiliness]);
    let values: [Option<f64>; 4] = [0, 1, 2, 3].map(|i| explicit[i].or(from_preset.map(|p| p[i])));
    let missing: Vec<&str> = (0..4).filter(|&i| values[i].is_none()).map(|i| PARAM_CHANNELS[i]).collect();
    if !missing.is_empty() {
        let presets: Vec<&str> = PRESETS.iter().map(|p| p.name).collect();
        return Err(invalid(
            "parameters",
            format!(
                "give preset= (one of {}) or all of {}; missing: {}",
                presets.join(", "),
                PARAM_CHANNELS.join(", "),
                missing.join(", ")
            ),
        ));
    }
    let [m, b, h, o] = values.map(|v| v.unwrap_or(f64::NAN));
    Ok(SkinParams::new(m, b, h, o)?)
}

/// `blender=` and `engine=` to a [`Target`]: the version as "MAJOR.MINOR" (or "MAJOR.MINOR.PATCH") or a tuple of
/// ints such as `bpy.app.version`; None is the current release. The core validates both and names the range.
fn target_from(blender: Option<&Bound<'_, PyAny>>, engine: &str) -> PyResult<Target> {
    const EXPECTED: &str = "blender must be a version string such as \"5.3\" or a tuple such as (5, 3, 0)";
    let version = match blender {
        None => CURRENT_RELEASE,
        Some(obj) if obj.is_instance_of::<PyString>() => obj.extract::<String>()?.parse::<BlenderVersion>()?,
        Some(obj) => {
            if obj.is_instance_of::<PyBytes>() || is_boolean(obj) {
                return Err(PyTypeError::new_err(EXPECTED));
            }
            let parts = count_sequence("blender", obj, EXPECTED.trim_start_matches("blender must be "))?;
            BlenderVersion::from_parts(&parts)?
        }
    };
    Ok(Target { blender: version, engine: Engine::from_name(engine)? })
}

/// An integer keyword to the `u32` the core takes; outside `u32` is an out-of-range error (the core checks its own,
/// narrower ranges).
fn to_u32(name: &'static str, meaning: &'static str, value: i64) -> PyResult<u32> {
    u32::try_from(value).map_err(|_| {
        SkinError::OutOfRange { name, meaning, min: 0.0, max: u32::MAX as f64, value: value as f64 }.into()
    })
}

/// The accuracy and model choices common to `evaluate` and `profile`.
struct Knobs<'a> {
    /// A named level (draft, default, reference); the knobs below override it where given.
    accuracy: &'a str,
    wavelength_step_nm: Option<Real>,
    wavelength_placement: Option<&'a str>,
    multipole_pairs: Option<Count>,
    profile_r_min_mm: Option<Real>,
    profile_r_max_mm: Option<Real>,
    profile_count: Option<Count>,
    combination: &'a str,
    working_space: &'a str,
    rgb_mapping: &'a str,
    boundaries: &'a str,
    target: Target,
}

impl Knobs<'_> {
    fn request(&self, outputs: Outputs) -> PyResult<Request> {
        let level = AccuracyLevel::from_name(self.accuracy)?.accuracy();
        let defaults = level.profile_grid;
        let count = match self.profile_count {
            Some(Count(n)) => to_u32("profile_count", "number of profile radii", n)? as usize,
            None => defaults.count,
        };
        let multipole_terms = match self.multipole_pairs {
            Some(Count(n)) => MultipoleTerms::Pairs(to_u32("multipole_pairs", "image pairs per side", n)?),
            None => level.multipole_terms,
        };
        let accuracy = Accuracy {
            wavelength_step_nm: self.wavelength_step_nm.map_or(level.wavelength_step_nm, |r| r.0),
            wavelength_placement: match self.wavelength_placement {
                Some(name) => by_name("wavelength_placement", name, &ALL_WAVELENGTH_PLACEMENTS)?,
                None => level.wavelength_placement,
            },
            multipole_terms,
            profile_grid: ProfileGrid {
                r_min_mm: self.profile_r_min_mm.map_or(defaults.r_min_mm, |r| r.0),
                r_max_mm: self.profile_r_max_mm.map_or(defaults.r_max_mm, |r| r.0),
                count,
            },
            ..level
        };
        Ok(Request {
            outputs,
            accuracy,
            combination: by_name("combination", self.combination, &ALL_COMBINATIONS)?,
            working_space: by_name("working_space", self.working_space, &ALL_WORKING_SPACES)?,
            rgb_mapping: by_name("rgb_mapping", self.rgb_mapping, &ALL_RGB_MAPPINGS)?,
            boundaries: by_name("boundaries", self.boundaries, &ALL_BOUNDARIES)?,
            target: self.target,
            ..Request::default()
        })
    }
}

/// serde_json `Value` to plain Python objects (dict, list, str, int, float, bool, None).
fn json_to_py<'py>(py: Python<'py>, value: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match value {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => b.into_pyobject(py)?.to_owned().into_any(),
        Value::Number(n) => {
            if let Some(i) = n.as_i64() {
                i.into_pyobject(py)?.into_any()
            } else if let Some(u) = n.as_u64() {
                u.into_pyobject(py)?.into_any()
            } else {
                n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any()
            }
        }
        Value::String(s) => PyString::new(py, s).into_any(),
        Value::Array(items) => {
            PyList::new(py, items.iter().map(|v| json_to_py(py, v)).collect::<PyResult<Vec<_>>>()?)?.into_any()
        }
        Value::Object(map) => {
            let dict = PyDict::new(py);
            for (k, v) in map {
                dict.set_item(k, json_to_py(py, v)?)?;
            }
            dict.into_any()
        }
    })
}

fn internal<E: std::fmt::Display>(e: E) -> PyErr {
    PyRuntimeError::new_err(format!("spectral-skin internal error: {e}"))
}

/// Rows of equal length to a 2-D float64 array.
fn array2<'py>(py: Python<'py>, rows: usize, cols: usize, flat: Vec<f64>) -> PyResult<Bound<'py, PyArray2<f64>>> {
    Ok(PyArray2::from_owned_array(py, Array2::from_shape_vec((rows, cols), flat).map_err(internal)?))
}

fn rgb_rows<'py>(py: Python<'py>, rgb: &[[f64; 3]]) -> PyResult<Bound<'py, PyArray2<f64>>> {
    array2(py, rgb.len(), 3, rgb.iter().flatten().copied().collect())
}

fn nested_rows<'py>(py: Python<'py>, rows: &[Vec<f64>]) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let cols = rows.first().map_or(0, Vec::len);
    array2(py, rows.len(), cols, rows.iter().flatten().copied().collect())
}

fn method_dict<'py>(py: Python<'py>, value: &Value, m: &MethodParams) -> PyResult<Bound<'py, PyAny>> {
    let dict = json_to_py(py, value)?;
    dict.set_item("base_color", PyArray1::from_slice(py, &m.base_color))?;
    dict.set_item("subsurface_radius_mm", PyArray1::from_slice(py, &m.subsurface_radius_mm))?;
    dict.set_item("expected_albedo", PyArray1::from_slice(py, &m.expected_albedo))?;
    Ok(dict)
}

/// The CLI's JSON of an evaluation as a dict, with numpy arrays for the array-valued outputs.
fn evaluation_dict<'py>(py: Python<'py>, e: &Evaluation) -> PyResult<Bound<'py, PyDict>> {
    let Value::Object(mut map) = serde_json::to_value(e).map_err(internal)? else {
        return Err(internal("an evaluation does not serialise to an object"));
    };
    // Array-valued fields are built from the struct, not converted element by element.
    for key in ["diffuse_reflectance_rgb", "wavelengths_nm", "spectral_reflectance", "profile", "methods"] {
        map.remove(key);
    }
    let dict = json_to_py(py, &Value::Object(map))?.cast_into::<PyDict>()?;
    // JSON has no infinity: serde_json writes a semi-infinite dermis as null. Python floats do.
    dict.get_item("model")?
        .ok_or_else(|| internal("no model in the evaluation"))?
        .set_item("dermis_thickness_mm", e.model.dermis_thickness_mm)?;
    if let Some(rgb) = &e.diffuse_reflectance_rgb {
        dict.set_item("diffuse_reflectance_rgb", PyArray1::from_slice(py, rgb))?;
    }
    if let Some(methods) = &e.methods {
        let m = PyDict::new(py);
        let Value::Object(json) = serde_json::to_value(methods).map_err(internal)? else {
            return Err(internal("methods do not serialise to an object"));
        };
        for (method, params) in methods.iter() {
            let field = json.get(method.name()).cloned().unwrap_or(Value::Null);
            m.set_item(method.name(), method_dict(py, &field, params)?)?;
        }
        dict.set_item("methods", m)?;
    }
    if let Some(w) = &e.wavelengths_nm {
        dict.set_item("wavelengths_nm", PyArray1::from_slice(py, w))?;
    }
    if let Some(r) = &e.spectral_reflectance {
        dict.set_item("spectral_reflectance", PyArray1::from_slice(py, r))?;
    }
    if let Some(p) = &e.profile {
        let profile = PyDict::new(py);
        profile.set_item("radii_mm", PyArray1::from_slice(py, &p.radii_mm))?;
        if let Some(rgb) = &p.rgb_per_mm2 {
            profile.set_item("rgb_per_mm2", rgb_rows(py, rgb)?)?;
        }
        if let Some(spectral) = &p.spectral_per_mm2 {
            profile.set_item("spectral_per_mm2", nested_rows(py, spectral)?)?;
        }
        if let Some(lobe) = &p.negative_lobe {
            profile.set_item("negative_lobe", json_to_py(py, &serde_json::to_value(lobe).map_err(internal)?)?)?;
        }
        dict.set_item("profile", profile)?;
    }
    Ok(dict)
}

/// Evaluate the skin model; compute only the requested outputs.
///
/// Give a preset, or all four parameters; a preset with explicit parameters uses the explicit ones instead of the
/// preset's.
///
/// Arguments:
///     melanin: C_m, melanin volume fraction of the epidermis, 0..0.5.
///     melanin_blend: beta_m, eumelanin share of the melanin, 0..1 (the rest is pheomelanin).
///     hemoglobin: C_h, whole-blood volume fraction of the dermis, 0..0.1.
///     oiliness: rho_s, scale of the surface's specular lobe, 0..1.
///     preset: a preset name from :func:`presets` (case-insensitive).
///     outputs: names among "albedo", "radius", "profile_rgb", "profile_spectral", "spectrum", "specular".
///         None: ("albedo", "radius", "specular"), what a material needs.
///     accuracy: a named accuracy level, "draft", "default" or "reference" (docs/accuracy-vs-time.md); the
///         knobs below override its settings where given.
///     wavelength_step_nm: wavelength sampling step in nm (380-780 nm), 0.5..100; with "cmf_adapted" placement it
///         sets the count (the uniform step's); None: the level's (10 nm at "default").
///     wavelength_placement: "uniform" (every step nm), "cmf_adapted" (denser where the colour-matching functions
///         weigh most; the default level's) or "rgb_shortcut" (reflectance at 435.8, 546.1 and 700 nm taken as B, G,
///         R: the shortcut DJ2006 argues against, for comparison); None: the level's.
///     multipole_pairs: image-source pairs per side of the multipole; None: the whole series (closed form).
///     profile_r_min_mm: smallest radius of the log-spaced profile grid, mm; None: 0.001 mm.
///     profile_r_max_mm: largest radius of the profile grid, mm; None: 20 mm.
///     profile_count: number of profile radii; None: 64.
///     combination: transport through the epidermis from below: "directional" (the layer seen from below) or
///         "symmetric" (DJ2005's published form).
///     working_space: linear RGB space of every RGB output, named as Blender 5.0's working spaces:
///         "Linear Rec.709", "Linear Rec.2020" (both D65) or "ACEScg" (AP1 primaries, ACES white; the D65 XYZ is
///         Bradford-adapted to it, as Blender's OCIO config does). A perfect white reflector is (1, 1, 1) in each.
///     blender: the Blender version the Principled inputs are for: "MAJOR.MINOR" (e.g. "5.2"; a patch level is
///         ignored) or a tuple such as ``bpy.app.version``; 4.2 or newer. A version newer than the tested ones uses
///         the newest known behaviour (``result["target"]["tested"]`` is False). None: the current release (5.3,
///         ``blender_targets()["current_release"]``).
///     engine: the render engine, "cycles" or "eevee" (EEVEE renders every subsurface method as Burley, with a
///         radius compensated for its albedo-dependent profile).
///     rgb_mapping: how the RGB profile's colour at each radius is formed (only "profile_rgb" uses it), as for
///         :func:`profile`: "linear" (exact; negative in a channel where the light is outside the gamut) or
///         "non_negative".
///     boundaries: the layers' boundary conditions: "paper" (DJ2005's extrapolated boundaries, the default) or
///         "capped" (each layer's extrapolation distances capped so that every radial profile is non-negative and
///         the total reflectance never rises with absorption, by construction; it moves a thin or red-lit epidermis
///         away from Monte Carlo: docs/robustness.md, "Negative profile lobes").
///
/// Returns:
///     The CLI's JSON as a dict. Always: "params", "color_space", "accuracy", "model" (model["dermis_thickness_mm"]
///     is float("inf") for a semi-infinite dermis), "combination", "target" ({"blender": "5.3", "engine":
///     "cycles", "tested": True}), "default_method", "work" ({"wavelengths",
///     "transform_samples", "radial_profiles"}), "seconds". Per requested output, numpy arrays where array-valued:
///     albedo or radius: "diffuse_reflectance_rgb" (3,);
///     radius: "methods", one entry per subsurface method the target's Blender offers ("burley", "random_walk",
///     "random_walk_skin", and "random_walk_legacy" from 5.2) -> {"base_color" (3,), "subsurface_radius_mm" (3,),
///     mm, "expected_albedo" (3,)} and "radius_fit" (a list of 3 dicts {"d_mm", "radius_mm", "edge_residual"}:
///     the Cycles Burley fit);
///     specular: "specular" {"oiliness", "specular_ior_level", "roughness", "ior", "beckmann_m",
///     "directional_albedo_normal", "hemispherical_albedo"};
///     spectrum: "wavelengths_nm" (K,), "spectral_reflectance" (K,);
///     profile_rgb / profile_spectral: "profile" {"radii_mm" (N,), "rgb_per_mm2" (N, 3) and/or
///     "spectral_per_mm2" (K, N), mm^-2, and "negative_lobe" {"wavelength_nm", "radius_mm", "relative_to_peak"}
///     when a spectral profile was negative beyond round-off before its clamp to 0, also reported by a
///     SpectralSkinWarning} (and "wavelengths_nm" (K,) with profile_spectral).
///
/// Raises:
///     SpectralSkinError: a parameter or knob out of range or not finite, an unknown preset, output, combination or
///         working space, or neither a preset nor all four parameters; a Blender version older than 4.2 or not
///         MAJOR.MINOR; an unknown engine.
///     TypeError: an argument of the wrong type (e.g. outputs given as a single string).
#[pyfunction]
#[pyo3(
    name = "evaluate",
    signature = (
        melanin = None, melanin_blend = None, hemoglobin = None, oiliness = None, *,
        preset = None, outputs = None, accuracy = "default", wavelength_step_nm = None, wavelength_placement = None,
        multipole_pairs = None,
        profile_r_min_mm = None, profile_r_max_mm = None, profile_count = None,
        combination = "directional", working_space = "Linear Rec.709", blender = None, engine = "cycles",
        rgb_mapping = "linear", boundaries = "paper"
    )
)]
#[allow(clippy::too_many_arguments)]
fn evaluate_py<'py>(
    py: Python<'py>,
    melanin: Option<&Bound<'py, PyAny>>,
    melanin_blend: Option<&Bound<'py, PyAny>>,
    hemoglobin: Option<&Bound<'py, PyAny>>,
    oiliness: Option<&Bound<'py, PyAny>>,
    preset: Option<&str>,
    outputs: Option<&Bound<'py, PyAny>>,
    accuracy: &str,
    wavelength_step_nm: Option<&Bound<'py, PyAny>>,
    wavelength_placement: Option<&str>,
    multipole_pairs: Option<&Bound<'py, PyAny>>,
    profile_r_min_mm: Option<&Bound<'py, PyAny>>,
    profile_r_max_mm: Option<&Bound<'py, PyAny>>,
    profile_count: Option<&Bound<'py, PyAny>>,
    combination: &str,
    working_space: &str,
    blender: Option<&Bound<'py, PyAny>>,
    engine: &str,
    rgb_mapping: &str,
    boundaries: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let explicit =
        [("melanin", melanin), ("melanin_blend", melanin_blend), ("hemoglobin", hemoglobin), ("oiliness", oiliness)];
    let mut values = [None; 4];
    for (value, (name, obj)) in values.iter_mut().zip(explicit) {
        *value = real_arg(name, obj)?;
    }
    let params = resolve_params(preset, values)?;
    let knobs = Knobs {
        accuracy,
        wavelength_step_nm: real_arg("wavelength_step_nm", wavelength_step_nm)?,
        wavelength_placement,
        multipole_pairs: count_arg("multipole_pairs", multipole_pairs)?,
        profile_r_min_mm: real_arg("profile_r_min_mm", profile_r_min_mm)?,
        profile_r_max_mm: real_arg("profile_r_max_mm", profile_r_max_mm)?,
        profile_count: count_arg("profile_count", profile_count)?,
        combination,
        working_space,
        rgb_mapping,
        boundaries,
        target: target_from(blender, engine)?,
    };
    let request = knobs.request(parse_outputs(outputs)?)?;
    let evaluation = detached(py, move || crate::evaluate(&params, &request))?;
    warn_lobe(py, evaluation.profile.as_ref().and_then(|p| p.negative_lobe))?;
    evaluation_dict(py, &evaluation)
}

/// The radial reflectance profile R(r) of the skin on a log-spaced radius grid.
///
/// The RGB profile is the spectral profile mapped into ``working_space``. With ``rgb_mapping="linear"`` (the
/// default) that map is linear: the exact colour at each radius, additive, and it integrates (2 pi r dr) to the RGB
/// albedo; but where the light is outside the space's gamut a channel is **negative**. Every preset has such radii:
/// in the far tail only red light is left, more saturated than the red primary (README.md, "Radial profiles", lists
/// the radii and sizes). ``rgb_mapping="non_negative"`` moves each such colour along the line towards the grey of the same
/// luminance (R = G = B = Y) until its most negative channel is 0: no value is negative, luminance and hue are kept,
/// radii inside the gamut are unchanged, but the profile no longer integrates exactly to the albedo. The spectral
/// profiles (``spectral=True``) are never negative: a negative lobe of the model itself (only with
/// ``boundaries="paper"``, none for the presets) is set to 0 and reported by a :class:`SpectralSkinWarning`.
///
/// Arguments:
///     melanin, melanin_blend, hemoglobin, oiliness, preset: as for :func:`evaluate`.
///     spectral: False: RGB profiles; True: one profile per wavelength.
///     accuracy, wavelength_step_nm, wavelength_placement, multipole_pairs, profile_r_min_mm, profile_r_max_mm,
///         profile_count, combination, working_space: as for :func:`evaluate`.
///     rgb_mapping: "linear" or "non_negative", see above.
///     boundaries: "paper" or "capped", as for :func:`evaluate`.
///
/// Returns:
///     {"radii_mm": (N,), "rgb_per_mm2": (N, 3)} in mm^-2, or with spectral=True
///     {"radii_mm": (N,), "spectral_per_mm2": (K, N), "wavelengths_nm": (K,)}.
///
/// Raises:
///     SpectralSkinError: as for :func:`evaluate`.
///     TypeError: an argument of the wrong type.
#[pyfunction]
#[pyo3(
    name = "profile",
    signature = (
        melanin = None, melanin_blend = None, hemoglobin = None, oiliness = None, *,
        preset = None, spectral = false, accuracy = "default", wavelength_step_nm = None, wavelength_placement = None,
        multipole_pairs = None,
        profile_r_min_mm = None, profile_r_max_mm = None, profile_count = None,
        combination = "directional", working_space = "Linear Rec.709", rgb_mapping = "linear", boundaries = "paper"
    )
)]
#[allow(clippy::too_many_arguments)]
fn profile_py<'py>(
    py: Python<'py>,
    melanin: Option<&Bound<'py, PyAny>>,
    melanin_blend: Option<&Bound<'py, PyAny>>,
    hemoglobin: Option<&Bound<'py, PyAny>>,
    oiliness: Option<&Bound<'py, PyAny>>,
    preset: Option<&str>,
    spectral: bool,
    accuracy: &str,
    wavelength_step_nm: Option<&Bound<'py, PyAny>>,
    wavelength_placement: Option<&str>,
    multipole_pairs: Option<&Bound<'py, PyAny>>,
    profile_r_min_mm: Option<&Bound<'py, PyAny>>,
    profile_r_max_mm: Option<&Bound<'py, PyAny>>,
    profile_count: Option<&Bound<'py, PyAny>>,
    combination: &str,
    working_space: &str,
    rgb_mapping: &str,
    boundaries: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let explicit =
        [("melanin", melanin), ("melanin_blend", melanin_blend), ("hemoglobin", hemoglobin), ("oiliness", oiliness)];
    let mut values = [None; 4];
    for (value, (name, obj)) in values.iter_mut().zip(explicit) {
        *value = real_arg(name, obj)?;
    }
    let params = resolve_params(preset, values)?;
    let knobs = Knobs {
        accuracy,
        wavelength_step_nm: real_arg("wavelength_step_nm", wavelength_step_nm)?,
        wavelength_placement,
        multipole_pairs: count_arg("multipole_pairs", multipole_pairs)?,
        profile_r_min_mm: real_arg("profile_r_min_mm", profile_r_min_mm)?,
        profile_r_max_mm: real_arg("profile_r_max_mm", profile_r_max_mm)?,
        profile_count: count_arg("profile_count", profile_count)?,
        combination,
        working_space,
        rgb_mapping,
        boundaries,
        target: Target::default(),
    };
    let outputs = Outputs { profile_rgb: !spectral, profile_spectral: spectral, ..Outputs::default() };
    let request = knobs.request(outputs)?;
    let evaluation = detached(py, move || crate::evaluate(&params, &request))?;
    let p = evaluation.profile.as_ref().ok_or_else(|| internal("no profile in the evaluation"))?;
    warn_lobe(py, p.negative_lobe)?;
    let dict = PyDict::new(py);
    dict.set_item("radii_mm", PyArray1::from_slice(py, &p.radii_mm))?;
    if let Some(rgb) = &p.rgb_per_mm2 {
        dict.set_item("rgb_per_mm2", rgb_rows(py, rgb)?)?;
    }
    if let Some(s) = &p.spectral_per_mm2 {
        dict.set_item("spectral_per_mm2", nested_rows(py, s)?)?;
    }
    if let Some(w) = &evaluation.wavelengths_nm {
        dict.set_item("wavelengths_nm", PyArray1::from_slice(py, w))?;
    }
    Ok(dict)
}

/// The named presets.
///
/// Returns:
///     {name: {"melanin", "melanin_blend", "hemoglobin", "oiliness", "description"}}; the names are accepted by
///     ``preset=`` of :func:`evaluate` and :func:`profile`.
#[pyfunction]
#[pyo3(name = "presets")]
fn presets_py(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let all = PyDict::new(py);
    for p in PRESETS {
        let d = PyDict::new(py);
        let q = p.params;
        for (name, value) in PARAM_CHANNELS.iter().zip([q.melanin, q.melanin_blend, q.hemoglobin, q.oiliness]) {
            d.set_item(name, value)?;
        }
        d.set_item("description", p.description)?;
        all.set_item(p.name, d)?;
    }
    Ok(all)
}

/// The allowed range of each parameter.
///
/// Returns:
///     {"melanin": (0.0, 0.5), "melanin_blend": (0.0, 1.0), "hemoglobin": (0.0, 0.1), "oiliness": (0.0, 1.0)}:
///     volume fractions (melanin of the epidermis, whole blood of the dermis), the eumelanin share, the oiliness.
#[pyfunction]
#[pyo3(name = "parameter_ranges")]
fn parameter_ranges_py(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    for (name, range) in crate::maps::io::PARAM_CHANNELS.iter().zip(crate::maps::io::PARAM_RANGES) {
        d.set_item(name, range)?;
    }
    Ok(d)
}

/// One layer from a 4-sequence of numbers.
fn extract_layer(index: usize, item: &Bound<'_, PyAny>) -> PyResult<Layer> {
    reject_string(item, &format!("layers[{index}] must be a tuple {LAYER_FIELDS}"))?;
    let values = real_sequence(&format!("layers[{index}]"), item, &format!("a tuple of 4 numbers {LAYER_FIELDS}"))?;
    match values[..] {
        [thickness_mm, sigma_a_per_mm, sigma_s_reduced_per_mm, ior] => {
            Ok(Layer { thickness_mm, sigma_a_per_mm, sigma_s_reduced_per_mm, ior })
        }
        _ => Err(invalid(format!("layer {index}"), format!("expected 4 values {LAYER_FIELDS}; got {}", values.len()))),
    }
}

/// A 1-D numpy array of ints or floats (any strides, read-only too) or a sequence of numbers under the rule of
/// [`Real`]. A bool, str or other dtype is a TypeError, another number of dimensions a SpectralSkinError; both name
/// `name`.
fn real_vector(name: &str, obj: &Bound<'_, PyAny>, expected: &str) -> PyResult<Vec<f64>> {
    let Ok(untyped) = obj.cast::<PyUntypedArray>() else {
        return real_sequence(name, obj, expected);
    };
    let kind = untyped.dtype().kind();
    if !matches!(kind, b'f' | b'i' | b'u') {
        return Err(PyTypeError::new_err(format!(
            "{name} must be {expected}; got an array of dtype {}",
            untyped.dtype()
        )));
    }
    if untyped.ndim() != 1 {
        return Err(invalid(name, format!("must be {expected}; got shape {}", shape_text(untyped.shape()))));
    }
    let values = obj
        .extract::<PyArrayLike1<'_, f64, AllowTypeChange>>()
        .map_err(|e| PyTypeError::new_err(format!("{name} must be {expected}: {e}")))?;
    Ok(values.as_array().iter().copied().collect())
}

/// Total diffuse reflectance and radial profile of a stack of layers under air (the diffusion solver alone).
///
/// Uses the directional combination, the whole multipole series and the default inverse-Hankel quadrature. With the
/// paper's boundaries a thin layer over layers that do not fill it can give a profile that is negative at some
/// radii (the model's own lobe); it is returned clamped to 0 and reported by a :class:`SpectralSkinWarning` naming
/// the radius and the depth relative to the peak. ``boundaries="capped"`` gives a profile that is non-negative and
/// a total that is monotone in absorption by construction (docs/robustness.md, "Negative profile lobes").
///
/// Arguments:
///     layers: top to bottom, each (thickness_mm, sigma_a_per_mm, sigma_s_reduced_per_mm, ior): thickness in mm
///         (float("inf") for a semi-infinite last layer), absorption and reduced scattering coefficients in mm^-1,
///         index of refraction 1..2.
///     radii_mm: 1-D radii in mm, finite and >= 0.
///     boundaries: "paper" (the default) or "capped".
///
/// Returns:
///     (total diffuse reflectance, R(r) at radii_mm in mm^-2 as a float64 array of the same length).
///
/// Raises:
///     SpectralSkinError: no layers, a layer that is not 4 values, a thickness outside 1e-11..1e6 mm (inf only for
///         the last layer), a coefficient other than 0 or 1e-12..1e6 per mm, an ior outside 1..2 (where the diffuse
///         Fresnel fits hold), or a radius outside 0..1e6 mm.
///     TypeError: layers or radii_mm not sequences of numbers.
#[pyfunction]
#[pyo3(name = "layered_reflectance", signature = (layers, radii_mm, *, boundaries = "paper"))]
fn layered_reflectance_py<'py>(
    py: Python<'py>,
    layers: &Bound<'py, PyAny>,
    radii_mm: &Bound<'py, PyAny>,
    boundaries: &str,
) -> PyResult<(f64, Bound<'py, PyArray1<f64>>)> {
    reject_string(layers, &format!("layers must be a list of tuples {LAYER_FIELDS}"))?;
    let layers: Vec<Layer> =
        layers.try_iter()?.enumerate().map(|(i, item)| extract_layer(i, &item?)).collect::<PyResult<_>>()?;
    let radii = real_vector("radii_mm", radii_mm, "a 1-D array-like of radii in mm")?;
    let boundaries = by_name("boundaries", boundaries, &ALL_BOUNDARIES)?;
    let r = detached(py, move || crate::diffusion::layered_reflectance_with(&layers, &radii, boundaries))?;
    warn_lobe(py, r.negative_lobe)?;
    Ok((r.total, PyArray1::from_vec(py, r.profile_per_mm2)))
}

// --- maps ---------------------------------------------------------------------------------------------------------

/// What `params` of `maps` must be, for messages.
const PARAMS_ARRAY: &str = "a float32 (H, W, 4) numpy array (channels melanin, melanin_blend, hemoglobin, oiliness)";
/// What a per-parameter keyword of `maps` must be, for messages.
const PARAM_ARRAY: &str = "a float32 (H, W) numpy array or a float";

/// A numpy array of float32, or of float64 (converted to float32 while it is copied).
enum FloatArray<'py> {
    F32(Bound<'py, PyArrayDyn<f32>>),
    F64(Bound<'py, PyArrayDyn<f64>>),
}

impl FloatArray<'_> {
    fn shape(&self) -> Vec<usize> {
        match self {
            FloatArray::F32(a) => a.shape().to_vec(),
            FloatArray::F64(a) => a.shape().to_vec(),
        }
    }

    /// One row-major (H, W) plane as float32: the whole (H, W) array, or channel `c` of an (H, W, C) array. One pass
    /// over the data (a copy, converting float64); any strides.
    fn plane(&self, channel: Option<usize>) -> PyResult<Vec<f32>> {
        match self {
            FloatArray::F32(a) => plane_of(a, channel, |v| v),
            FloatArray::F64(a) => plane_of(a, channel, |v| v as f32),
        }
    }
}

fn plane_of<T: Element + Copy>(
    array: &Bound<'_, PyArrayDyn<T>>,
    channel: Option<usize>,
    convert: impl Fn(T) -> f32,
) -> PyResult<Vec<f32>> {
    let readonly = array.try_readonly().map_err(|e| PyTypeError::new_err(format!("cannot read the array: {e}")))?;
    let view = readonly.as_array();
    let view: ArrayView2<'_, T> = match channel {
        None => view.into_dimensionality::<Ix2>().map_err(internal)?,
        Some(c) => view.into_dimensionality::<Ix3>().map_err(internal)?.index_axis_move(Axis(2), c),
    };
    Ok(match view.as_slice() {
        Some(values) => values.iter().map(|&v| convert(v)).collect(),
        None => view.iter().map(|&v| convert(v)).collect(),
    })
}

/// A shape as Python prints it: (8, 8, 4).
fn shape_text(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!("({})", shape.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(", ")),
    }
}

/// `obj` as a float32/float64 array of `ndim` dimensions, or None if it is not a numpy array. Another dtype or
/// an unaligned array is a TypeError; another number of dimensions a SpectralSkinError.
fn float_array<'py>(
    name: &str,
    obj: &Bound<'py, PyAny>,
    ndim: usize,
    expected: &str,
) -> PyResult<Option<FloatArray<'py>>> {
    let Ok(untyped) = obj.cast::<PyUntypedArray>() else {
        return Ok(None);
    };
    let array = if let Ok(a) = obj.cast::<PyArrayDyn<f32>>() {
        FloatArray::F32(a.clone())
    } else if let Ok(a) = obj.cast::<PyArrayDyn<f64>>() {
        FloatArray::F64(a.clone())
    } else {
        return Err(PyTypeError::new_err(format!(
            "{name} must be {expected}; got an array of dtype {} (float32 and float64 in native byte order are \
             accepted)",
            untyped.dtype()
        )));
    };
    if !untyped.is_aligned() {
        return Err(PyTypeError::new_err(format!("{name} must be an aligned array; pass {name}.copy()")));
    }
    if untyped.ndim() != ndim {
        return Err(invalid(name, format!("must be {expected}; got shape {}", shape_text(untyped.shape()))));
    }
    Ok(Some(array))
}

/// A per-parameter input of `maps`.
enum MapInput<'py> {
    Array(FloatArray<'py>),
    Constant(f64),
}

fn map_input<'py>(name: &str, obj: &Bound<'py, PyAny>) -> PyResult<MapInput<'py>> {
    if let Some(array) = float_array(name, obj, 2, PARAM_ARRAY)? {
        return Ok(MapInput::Array(array));
    }
    let type_error = || {
        let type_name = obj.get_type().name().map(|n| n.to_string()).unwrap_or_default();
        PyTypeError::new_err(format!("{name} must be {PARAM_ARRAY}; got {type_name}"))
    };
    if obj.is_instance_of::<PyString>() || obj.is_instance_of::<PyBytes>() || is_boolean(obj) {
        return Err(type_error());
    }
    obj.extract::<f64>().map(MapInput::Constant).map_err(|_| type_error())
}

/// `table_resolution=`: None for the default, else 3 node counts, each at least 2.
fn table_resolution(obj: Option<&Bound<'_, PyAny>>) -> PyResult<TableResolution> {
    const EXPECTED: &str = "a tuple (melanin, melanin_blend, hemoglobin) of node counts";
    let Some(obj) = obj else {
        return Ok(TableResolution::default());
    };
    let counts = count_sequence("table_resolution", obj, EXPECTED)?;
    let [m, b, h] = counts[..] else {
        return Err(invalid("table_resolution", format!("expected {EXPECTED}; got {} values", counts.len())));
    };
    let count = |axis: &str, n: i64| {
        usize::try_from(n)
            .ok()
            .filter(|&n| n >= 2)
            .ok_or_else(|| invalid("table_resolution", format!("need at least 2 nodes per axis; {axis} has {n}")))
    };
    let r = TableResolution {
        melanin: count("melanin", m)?,
        melanin_blend: count("melanin_blend", b)?,
        hemoglobin: count("hemoglobin", h)?,
    };
    // The core's bound (lut.rs, `TableResolution::validate`), checked before anything is allocated.
    r.validate()?;
    Ok(r)
}

/// Planar RGB to one row-major (H, W, 3) buffer, rows in parallel.
fn interleave(width: usize, planes: [Vec<f32>; 3]) -> Vec<f32> {
    let [p0, p1, p2] = planes;
    let mut out = vec![0f32; 3 * p0.len()];
    out.par_chunks_mut(3 * width).enumerate().for_each(|(y, row)| {
        let start = y * width;
        let (r0, r1, r2) = (&p0[start..start + width], &p1[start..start + width], &p2[start..start + width]);
        for (x, texel) in row.chunks_exact_mut(3).enumerate() {
            texel[0] = r0[x];
            texel[1] = r1[x];
            texel[2] = r2[x];
        }
    });
    out
}

/// An interleaved (H, W, 3) buffer to numpy, without copying it.
fn rgb_image(py: Python<'_>, height: usize, width: usize, data: Vec<f32>) -> PyResult<Bound<'_, PyArray3<f32>>> {
    Ok(PyArray::from_owned_array(py, Array3::from_shape_vec((height, width, 3), data).map_err(internal)?))
}

/// `maps(progress=...)`: a Python callable told (texels done, total texels) from the worker threads, about once per
/// percent (it takes the GIL for each call); returning False cancels (the core skips the rows not yet started). An
/// exception it raises cancels too and is re-raised by `maps`.
struct Progress {
    callback: Py<PyAny>,
    done: AtomicUsize,
    reported_percent: AtomicUsize,
    stopped: AtomicBool,
    error: Mutex<Option<PyErr>>,
}

impl Progress {
    fn new(callback: Py<PyAny>) -> Self {
        Progress {
            callback,
            done: AtomicUsize::new(0),
            reported_percent: AtomicUsize::new(0),
            stopped: AtomicBool::new(false),
            error: Mutex::new(None),
        }
    }

    fn stopped(&self) -> bool {
        self.stopped.load(Ordering::Relaxed)
    }

    /// `increment` more texels are done out of `total` (0 for the first call).
    fn report(&self, increment: usize, total: usize) {
        let done = self.done.fetch_add(increment, Ordering::Relaxed) + increment;
        let percent = done.saturating_mul(100) / total.max(1);
        if self.stopped() || (increment > 0 && self.reported_percent.fetch_max(percent, Ordering::Relaxed) >= percent) {
            return;
        }
        // Calls are serialised by the GIL but may arrive out of order (a thread that counted fewer texels can get the
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
    fn into_error(self) -> PyErr {
        match self.error.into_inner().ok().flatten() {
            Some(e) => e,
            None => PyInterruptedError::new_err("maps: cancelled by the progress callback (it returned False)"),
        }
    }
}

/// Parameter maps read from a file with the core's reader: the formats and rules of ``spectral-skin maps``.
///
/// Arguments:
///     path: the file.
///     name: None for the four-channel parameter EXR (as ``spectral-skin maps --params``; ``spectral-skin
///         example`` writes one): channels named melanin, melanin_blend, hemoglobin and oiliness, all required.
///         A parameter name ("melanin", "melanin_blend", "hemoglobin" or "oiliness") for that parameter's own map
///         (as ``--melanin`` etc.): an EXR with exactly one channel (any name) or with a channel named like the
///         parameter, whose values are the parameter itself; or an 8/16-bit greyscale PNG or TIFF, whose 0..1
///         values map linearly onto the parameter's range (:func:`parameter_ranges`).
///
/// Returns:
///     {parameter name: float32 (H, W) array, row 0 at the top}: the four parameters, or the one named. Values are
///     not range-checked (:func:`maps` does that).
///
/// Raises:
///     SpectralSkinError: a missing or unreadable file, an unsupported format, a missing channel or a multi-channel
///         file without the parameter's channel (the message names the file and the channels found), an unknown
///         name.
#[pyfunction]
#[pyo3(name = "read_parameter_map", signature = (path, name = None))]
fn read_parameter_map_py<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
    name: Option<&str>,
) -> PyResult<Bound<'py, PyDict>> {
    let inputs = match name {
        None => ParamInputs::Multi { path, constants: [None; 4] },
        Some(name) => {
            let Some(p) = PARAM_CHANNELS.iter().position(|c| *c == name) else {
                let expected = PARAM_CHANNELS.join(", ");
                return Err(invalid(
                    "name",
                    format!("expected one of {expected} (or None for the four-channel file); got {name:?}"),
                ));
            };
            ParamInputs::Separate(std::array::from_fn(|k| {
                if k == p {
                    ParamSource::File(path.clone())
                } else {
                    ParamSource::Constant(0.0)
                }
            }))
        }
    };
    let image = detached(py, move || read_params(&inputs))?;
    let dict = PyDict::new(py);
    let (height, width) = (image.height, image.width);
    for (parameter, plane) in PARAM_CHANNELS.iter().zip(image.planes) {
        if let Plane::Texels(values) = plane {
            let array = Array2::from_shape_vec((height, width), values).map_err(internal)?;
            dict.set_item(parameter, PyArray::from_owned_array(py, array))?;
        }
    }
    Ok(dict)
}

/// Principled BSDF texture maps (Base Color, Subsurface Radius, specular) from per-texel parameter maps.
///
/// The Python side of ``spectral-skin maps``, on numpy arrays instead of files. Row 0 is the top row, as numpy and
/// EXR store images. Each texel is evaluated as :func:`evaluate` would, by the cheapest strategy that is exact enough:
/// "constant" (one evaluation) when melanin, melanin_blend and hemoglobin each hold one value everywhere (floats, or
/// arrays of one value); "distinct_tuples" (one evaluation per distinct (melanin, melanin_blend, hemoglobin)) when
/// there are at most 2048 of them; otherwise "table": a lookup table built for the call and interpolated per texel,
/// worst error below 0.5 % in albedo and 1 % in radius (its measured figures are in ``report["strategy"]``).
/// ``exact=True`` evaluates every texel (or distinct tuple) directly instead of using the table: a few milliseconds
/// of CPU per texel.
///
/// The inputs are copied once into float32 planes (the core's type) before the GIL is released. float32 arrays are
/// copied as they are; float64 arrays are converted to float32 in that same pass (no extra copy, but the values are
/// rounded to float32 before the range check and the evaluation); non-contiguous arrays (slices, transposes, Fortran
/// order) are gathered in that pass too. No other dtype is accepted: convert with ``a.astype(np.float32)``.
///
/// Arguments:
///     params: (H, W, 4) array, channels melanin, melanin_blend, hemoglobin, oiliness (in that order); None when
///         each parameter is given by its keyword.
///     melanin: C_m, melanin volume fraction of the epidermis, 0..0.5: an (H, W) array, a float (the same value
///         everywhere), or None (take channel 0 of params). Given together with params, it replaces that channel.
///     melanin_blend: beta_m, eumelanin share of the melanin, 0..1; as melanin (channel 1).
///     hemoglobin: C_h, whole-blood volume fraction of the dermis, 0..0.1; as melanin (channel 2).
///     oiliness: rho_s, scale of the surface's specular lobe, 0..1; as melanin (channel 3).
///     method: the subsurface method the maps are for: "burley" (Christensen-Burley), "random_walk",
///         "random_walk_legacy" (Blender 5.2 and later only) or "random_walk_skin".
///     blender, engine: the target, as for :func:`evaluate`; the radius (and for the random walks Base Color) is
///         computed for it per texel (for EEVEE from each texel's own albedo).
///     exact: evaluate every texel (or distinct tuple) directly, never the table.
///     clamp: clamp NaN (to the minimum), infinite and out-of-range values into range and count them in
///         ``report["clamped"]``, instead of raising. The input arrays are not modified.
///     accuracy: a named accuracy level, "draft", "default" or "reference", as for :func:`evaluate`.
///     wavelength_step_nm, wavelength_placement: as for :func:`evaluate`.
///     working_space: linear RGB space of Base Color, as for :func:`evaluate`: "Linear Rec.709" (Blender's
///         default scene linear), "Linear Rec.2020" or "ACEScg"; use the scene's working space.
///     table_cache: keep a built lookup table in the per-user cache folder ($SPECTRAL_SKIN_CACHE_DIR, else
///         $XDG_CACHE_HOME/spectral-skin, else ~/.cache/spectral-skin) and reuse it (as the CLI does); False
///         always builds it afresh.
///     table_resolution: nodes per axis of the lookup table, (melanin, melanin_blend, hemoglobin), each >= 2;
///         None: the core's default (chosen for the error bound above; the report names it). Used only by "table".
///     progress: None, or a callable ``progress(done, total)`` told how many texels of ``total`` are done: once
///         with 0 before the computation, with the same ``done`` about once per percent of a lookup table's nodes
///         while one is built, then about once per percent as rows are filled (from the core's worker threads,
///         taking the GIL for each call; a "constant" map has no rows to report). Returning False cancels: the
///         rows (or table nodes) being computed are finished, the others skipped, nothing is returned and
///         InterruptedError is raised. An exception raised by the callback cancels the same way and is re-raised.
///     boundaries: the layers' boundary conditions, "paper" or "capped", as for :func:`evaluate` (a cached table
///         is kept per choice).
///
/// Ctrl-C (KeyboardInterrupt, or any exception a Python signal handler raises) stops the call the same way: the
/// calling thread checks for signals every 0.1 s while the work runs, the rows or table nodes being computed are
/// finished (a node is about a millisecond) and the exception is raised; a table stopped part-way is not cached.
///
/// Returns:
///     A dict:
///     "base_color": float32 (H, W, 3), Principled Base Color for ``method``, linear RGB in ``working_space``;
///     "radius_mm": float32 (H, W, 3), Principled Subsurface Radius x Subsurface Scale for ``method``, mm (with
///     Radius set to these values, Scale is 0.001 in a scene whose unit is the metre);
///     "specular": the specular constants, always: when the oiliness is one value everywhere (a float, or an
///     array of one value), {"oiliness", "specular_ior_level", "roughness", "ior", "beckmann_m",
///     "directional_albedo_normal", "hemispherical_albedo"} (as ``evaluate(...)["specular"]``); when it varies, the
///     ones that do not depend on it: {"roughness", "ior", "beckmann_m"} (Principled IOR is 1.4 everywhere);
///     "specular_ior_level": only when the oiliness varies, float32 (H, W): Principled Specular IOR Level per texel;
///     "report": what was done: {"crate_version", "width", "height", "method", "target" ({"blender", "engine",
///     "tested"}), "color_space", "strategy" ({"name":
///     "constant" | "distinct_tuples" | "table" | "exact", with its figures: "tuples"; "evaluations"; or
///     "resolution", "nodes", "from_cache", "build_seconds", "measured_error"}), "clamped" (one dict per parameter
///     with bad values: {"parameter", "nan", "infinite", "out_of_range", "first": [[x, y], ...]}),
///     "constant_parameters", "request" (accuracy and model), "seconds" ({"read", "compute", "write", "total"})}.
///     The arrays are new, writeable and C-contiguous (handed to numpy without a copy).
///
/// Raises:
///     SpectralSkinError: a NaN, infinite or out-of-range value without clamp=True (the message names the parameter,
///         its range, the counts and the first (x, y) coordinates); inputs whose (H, W) differ (the message lists
///         each input's shape); params not (H, W, 4) or a keyword array not (H, W); an empty map or one over 2^28
///         texels; only constants and no array; a parameter given neither by params nor by its keyword; an unknown
///         method, a method the target's Blender lacks, an unknown working space or engine, a Blender version older
///         than 4.2; a wavelength step out of range; a table resolution below 2 nodes per axis or over the core's node bound
///         (checked before anything is allocated).
///     TypeError: an input that is not a numpy array of float32 or float64 (or, for the keywords, a number): e.g. a
///         list, an integer array, a string, a bool (Python's or numpy's); a non-integer in table_resolution; a
///         progress that is not callable. The message names the argument. Non-contiguous and read-only arrays are
///         read as they are.
///     InterruptedError: the progress callback returned False.
///
/// A SpectralSkinError for NaN, infinite or out-of-range texels (clamp=False) also has an attribute
/// ``bad_texels``: {"parameter", "min", "max", "nan", "infinite", "out_of_range", "first": [(x, y), ...]}.
#[pyfunction]
#[pyo3(
    name = "maps",
    signature = (
        params = None, *, melanin = None, melanin_blend = None, hemoglobin = None, oiliness = None,
        method = "burley", exact = false, clamp = false, accuracy = "default", wavelength_step_nm = None,
        wavelength_placement = None,
        working_space = "Linear Rec.709", table_resolution = None, table_cache = true, blender = None,
        engine = "cycles", progress = None, boundaries = "paper"
    )
)]
#[allow(clippy::too_many_arguments)]
fn maps_py<'py>(
    py: Python<'py>,
    params: Option<&Bound<'py, PyAny>>,
    melanin: Option<&Bound<'py, PyAny>>,
    melanin_blend: Option<&Bound<'py, PyAny>>,
    hemoglobin: Option<&Bound<'py, PyAny>>,
    oiliness: Option<&Bound<'py, PyAny>>,
    method: &str,
    exact: bool,
    clamp: bool,
    accuracy: &str,
    wavelength_step_nm: Option<&Bound<'py, PyAny>>,
    wavelength_placement: Option<&str>,
    working_space: &str,
    table_resolution: Option<&Bound<'py, PyAny>>,
    table_cache: bool,
    blender: Option<&Bound<'py, PyAny>>,
    engine: &str,
    progress: Option<Bound<'py, PyAny>>,
    boundaries: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let start = Instant::now();
    if let Some(callback) = progress.as_ref().filter(|c| !c.is_callable()) {
        let type_name = callback.get_type().name().map(|n| n.to_string()).unwrap_or_default();
        return Err(PyTypeError::new_err(format!(
            "progress must be a callable (done, total) -> bool | None, or None; got {type_name}"
        )));
    }
    let progress = progress.map(|callback| Progress::new(callback.unbind()));
    // Settings first: their errors come before any copy.
    let knobs = Knobs {
        accuracy,
        wavelength_step_nm: real_arg("wavelength_step_nm", wavelength_step_nm)?,
        wavelength_placement,
        multipole_pairs: None,
        profile_r_min_mm: None,
        profile_r_max_mm: None,
        profile_count: None,
        combination: "directional",
        working_space,
        rgb_mapping: "linear",
        boundaries,
        target: target_from(blender, engine)?,
    };
    let method = SubsurfaceMethod::from_name(method)?;
    knobs.target.method_entry(method)?;
    let settings = MapSettings {
        method,
        strategy: if exact { StrategyChoice::Exact } else { StrategyChoice::Auto },
        clamp,
        table: self::table_resolution(table_resolution)?,
        table_cache: if table_cache { crate::maps::lut::default_cache_dir() } else { None },
        request: knobs.request(Outputs::material())?,
        ..MapSettings::default()
    };

    // The inputs and their shapes.
    let params = match params {
        None => None,
        Some(obj) => Some(
            float_array("params", obj, 3, PARAMS_ARRAY)?
                .ok_or_else(|| PyTypeError::new_err(format!("params must be {PARAMS_ARRAY} or None")))?,
        ),
    };
    let keywords = [melanin, melanin_blend, hemoglobin, oiliness];
    let mut inputs: Vec<Option<MapInput<'py>>> = Vec::with_capacity(4);
    for (name, obj) in PARAM_CHANNELS.iter().zip(keywords) {
        inputs.push(obj.map(|o| map_input(name, o)).transpose()?);
    }
    let mut shapes: Vec<(&str, Vec<usize>)> = Vec::new();
    if let Some(p) = &params {
        let shape = p.shape();
        if shape[2] != 4 {
            return Err(invalid("params", format!("must be {PARAMS_ARRAY}; got shape {}", shape_text(&shape))));
        }
        shapes.push(("params", shape));
    }
    for (name, input) in PARAM_CHANNELS.iter().zip(&inputs) {
        if let Some(MapInput::Array(a)) = input {
            shapes.push((name, a.shape()));
        }
    }
    let missing: Vec<&str> =
        (0..4).filter(|&c| params.is_none() && inputs[c].is_none()).map(|c| PARAM_CHANNELS[c]).collect();
    if !missing.is_empty() {
        return Err(invalid(
            "parameters",
            format!(
                "give params= ({PARAMS_ARRAY}) or each of {}; missing: {}",
                PARAM_CHANNELS.join(", "),
                missing.join(", ")
            ),
        ));
    }
    let Some((_, first)) = shapes.first() else {
        return Err(invalid(
            "parameters",
            "give at least one array (params or a per-parameter map): with only constants there is no map size \
             (for one material use evaluate())",
        ));
    };
    let (height, width) = (first[0], first[1]);
    if shapes.iter().any(|(_, s)| (s[0], s[1]) != (height, width)) {
        let listed: Vec<String> = shapes.iter().map(|(n, s)| format!("{n} {}", shape_text(s))).collect();
        return Err(invalid("shapes", format!("the arrays must agree in (H, W); got {}", listed.join(", "))));
    }
    if height == 0 || width == 0 || height.saturating_mul(width) > MAX_TEXELS {
        return Err(invalid(
            "shapes",
            format!("a map needs 1 to {MAX_TEXELS} texels; got (H, W) = ({height}, {width})"),
        ));
    }
    // Constants are checked here, with their own message; clamp=True leaves them to the check of the planes.
    if !clamp {
        for (c, input) in inputs.iter().enumerate() {
            if let Some(MapInput::Constant(v)) = input {
                let (lo, hi) = crate::maps::io::PARAM_RANGES[c];
                if !(*v >= lo && *v <= hi) {
                    let name = PARAM_CHANNELS[c];
                    let reason = format!("must be in [{lo}, {hi}]; got {v} (pass clamp=True to clamp it)");
                    return Err(invalid(name, reason));
                }
            }
        }
    }
    let mut planes = Vec::with_capacity(4);
    for (c, input) in inputs.iter().enumerate() {
        planes.push(match (input, &params) {
            (Some(MapInput::Constant(v)), _) => Plane::Constant(*v as f32),
            (Some(MapInput::Array(a)), _) => Plane::Texels(a.plane(None)?),
            (None, Some(p)) => Plane::Texels(p.plane(Some(c))?),
            (None, None) => return Err(internal("a parameter without a source")),
        });
    }
    let planes: [Plane; 4] = planes.try_into().map_err(|_| internal("not four planes"))?;
    let mut image = ParamImage { width, height, planes };
    drop(params);
    drop(inputs);

    // Check, compute and interleave with the GIL released.
    struct Computed {
        base_color: Vec<f32>,
        radius_mm: Vec<f32>,
        specular: SpecularOutput,
        report: crate::maps::MapReport,
    }
    let hook = progress.as_ref();
    // Ctrl-C (and a progress callback's False or exception) stops the work through one flag.
    let own_flag = AtomicBool::new(false);
    let cancel = hook.map_or(&own_flag, |h| &h.stopped);
    let computed = detached_interruptible(py, cancel, move || {
        let clamped = check_planes(&mut image, clamp)?;
        let read = start.elapsed().as_secs_f64();
        let report = |done: usize, total: usize| {
            if let Some(h) = hook {
                h.report(done, total)
            }
        };
        report(0, image.texel_count());
        if hook.is_some_and(Progress::stopped) {
            return Ok(None);
        }
        let progress = hook.map(|_| &report as &(dyn Fn(usize, usize) + Sync));
        let computed = compute_maps_cancellable(&image, &settings, progress, cancel);
        drop(image);
        // A stopped table build is an error; the callback's answer (or exception) is what the caller sees.
        if hook.is_some_and(Progress::stopped) {
            return Ok(None);
        }
        let mut result = computed?;
        let write = Instant::now();
        let base_color = interleave(width, std::mem::take(&mut result.base_color));
        let radius_mm = interleave(width, std::mem::take(&mut result.radius_mm));
        let specular = result.specular;
        let mut report = result.report;
        report.clamped = clamped;
        report.seconds.read = read;
        report.seconds.write = write.elapsed().as_secs_f64();
        Ok(Some(Computed { base_color, radius_mm, specular, report }))
    })?;
    let Some(computed) = computed else {
        return Err(progress.map(Progress::into_error).unwrap_or_else(|| internal("stopped without a progress hook")));
    };

    let dict = PyDict::new(py);
    dict.set_item("base_color", rgb_image(py, height, width, computed.base_color)?)?;
    dict.set_item("radius_mm", rgb_image(py, height, width, computed.radius_mm)?)?;
    match computed.specular {
        SpecularOutput::Map { specular_ior_level, constants } => {
            dict.set_item(
                "specular_ior_level",
                PyArray::from_owned_array(
                    py,
                    Array2::from_shape_vec((height, width), specular_ior_level).map_err(internal)?,
                ),
            )?;
            // Only the constants that do not depend on the oiliness (fit::principled_specular::specular_from_oiliness).
            let all = json_to_py(py, &serde_json::to_value(constants).map_err(internal)?)?;
            let kept = PyDict::new(py);
            for key in SPECULAR_CONSTANTS {
                kept.set_item(key, all.get_item(key)?)?;
            }
            dict.set_item("specular", kept)?
        }
        SpecularOutput::Constant(constants) => {
            dict.set_item("specular", json_to_py(py, &serde_json::to_value(constants).map_err(internal)?)?)?
        }
    }
    let mut report = computed.report;
    report.seconds.total = start.elapsed().as_secs_f64();
    let report_dict = json_to_py(py, &serde_json::to_value(&report).map_err(internal)?)?;
    // JSON has no infinity: serde_json writes a semi-infinite dermis as null. Python floats do.
    report_dict
        .get_item("request")?
        .get_item("model")?
        .set_item("dermis_thickness_mm", report.request.model.dermis_thickness_mm)?;
    dict.set_item("report", report_dict)?;
    Ok(dict)
}

/// An image of `write_maps`' result: its size and its channels as row-major planes.
struct ResultImage {
    height: usize,
    width: usize,
    planes: Vec<Vec<f32>>,
}

/// One image of `write_maps`' result as row-major planes: `channels` of them (an (H, W, channels) array, or (H, W)
/// for one channel). None when the key is absent or None.
fn result_planes(result: &Bound<'_, PyAny>, key: &str, channels: usize) -> PyResult<Option<ResultImage>> {
    let obj = match result.get_item(key) {
        Ok(obj) if !obj.is_none() => obj,
        Ok(_) => return Ok(None),
        Err(e) if e.is_instance_of::<pyo3::exceptions::PyKeyError>(result.py()) => return Ok(None),
        Err(e) => return Err(e),
    };
    let (ndim, expected) = if channels == 1 {
        (2, "a float32 (H, W) numpy array".to_string())
    } else {
        (3, format!("a float32 (H, W, {channels}) numpy array"))
    };
    let name = format!("result[{key:?}]");
    let array = float_array(&name, &obj, ndim, &expected)?
        .ok_or_else(|| PyTypeError::new_err(format!("{name} must be {expected} or None; got {}", type_name(&obj))))?;
    let shape = array.shape();
    if channels > 1 && shape[2] != channels {
        return Err(invalid(name, format!("must be {expected}; got shape {}", shape_text(&shape))));
    }
    let planes = if channels == 1 {
        vec![array.plane(None)?]
    } else {
        (0..channels).map(|c| array.plane(Some(c))).collect::<PyResult<_>>()?
    };
    Ok(Some(ResultImage { height: shape[0], width: shape[1], planes }))
}

/// Write the images of a :func:`maps` result as float EXRs, with the core's writer (that of ``spectral-skin maps``).
///
/// Each image present (and not None) becomes one file in ``folder`` (created if missing): "base_color" ->
/// ``albedo.exr`` (channels R, G, B), "radius_mm" -> ``radius.exr`` (R, G, B), "specular_ior_level" ->
/// ``specular.exr`` (Y); with ``prefix``, ``<prefix>_albedo.exr`` etc. Row 0 at the top; ``precision`` and
/// ``compression`` as the CLI's ``--precision`` and ``--compression``. The files are written as temporary files in
/// ``folder`` and renamed into place together once all are written, so a failure leaves the existing files as they were. Then the files of an earlier write with the same prefix that
/// this one did not write (``albedo.exr``, ``radius.exr``, ``specular.exr``, ``skin_maps.json``) are removed, so the
/// folder holds exactly this result's maps. No sidecar is written: the report is in the result.
///
/// Arguments:
///     result: a mapping with any of "base_color" (H, W, 3), "radius_mm" (H, W, 3) and "specular_ior_level" (H, W),
///         float32 or float64 numpy arrays (float64 is rounded to float32); other keys are ignored. A result of
///         :func:`maps`, or a part of one.
///     folder: the output folder.
///     prefix: None, or a file-name part prepended with "_" to each file name (no path separator).
///     precision: "half" (16-bit, within 0.049 % of each value; the default) or "float" (32-bit).
///     compression: "auto" (the default: ZIPS for half, PIZ for float, or none for a file that would shrink by under
///         25 %), "piz", "zip", "zips", "rle" or "none".
///
/// Returns:
///     {"albedo" | "radius" | "specular": path of the file written}, for the images written.
///
/// Raises:
///     SpectralSkinError: no image in ``result``, images whose (H, W) differ, an image of the wrong shape, a prefix
///         that is empty or holds a path separator; a file that cannot be written (the message names it).
///     TypeError: an image that is not a float32 or float64 numpy array.
#[pyfunction]
#[pyo3(name = "write_maps", signature = (result, folder, prefix = None, precision = "half", compression = "auto"))]
fn write_maps_py<'py>(
    py: Python<'py>,
    result: &Bound<'py, PyAny>,
    folder: std::path::PathBuf,
    prefix: Option<&str>,
    precision: &str,
    compression: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let exr = ExrOptions {
        precision: by_name("precision", precision, &ALL_PRECISIONS)?,
        compression: by_name("compression", compression, &ALL_COMPRESSIONS)?,
    };
    if let Some(prefix) = prefix {
        if prefix.is_empty() || prefix.contains(['/', '\\']) || prefix == "." || prefix == ".." {
            return Err(invalid(
                "prefix",
                format!("must be a non-empty file name part without / or \\; got {prefix:?}"),
            ));
        }
    }
    let base_color = result_planes(result, "base_color", 3)?;
    let radius_mm = result_planes(result, "radius_mm", 3)?;
    let specular = result_planes(result, "specular_ior_level", 1)?;
    let sizes: Vec<(&str, usize, usize)> =
        [("base_color", &base_color), ("radius_mm", &radius_mm), ("specular_ior_level", &specular)]
            .into_iter()
            .filter_map(|(name, image)| image.as_ref().map(|i| (name, i.height, i.width)))
            .collect();
    let Some(&(_, height, width)) = sizes.first() else {
        return Err(invalid("result", "holds none of base_color, radius_mm, specular_ior_level: nothing to write"));
    };
    if sizes.iter().any(|&(_, h, w)| (h, w) != (height, width)) {
        let listed: Vec<String> = sizes.iter().map(|(n, h, w)| format!("{n} ({h}, {w})")).collect();
        return Err(invalid("result", format!("the images must agree in (H, W); got {}", listed.join(", "))));
    }
    let rgb = |image: Option<ResultImage>| -> Option<[Vec<f32>; 3]> { image.and_then(|i| i.planes.try_into().ok()) };
    let (base_color, radius_mm) = (rgb(base_color), rgb(radius_mm));
    let specular = specular.and_then(|mut i| i.planes.pop());
    let written = detached(py, || {
        let files = MapFiles {
            width,
            height,
            base_color: base_color.as_ref(),
            radius_mm: radius_mm.as_ref(),
            specular_ior_level: specular.as_deref(),
        };
        let staged = stage_map_files(&folder, prefix, &files, exr)?;
        let written: Vec<std::path::PathBuf> = staged.iter().map(|s| s.target().to_path_buf()).collect();
        commit_map_files(&folder, prefix, staged)?;
        Ok(written)
    })?;
    let dict = PyDict::new(py);
    for (key, file) in [("albedo", ALBEDO_FILE), ("radius", RADIUS_FILE), ("specular", SPECULAR_FILE)] {
        let path = folder.join(output_name(prefix, file));
        if written.contains(&path) {
            dict.set_item(key, path)?;
        }
    }
    Ok(dict)
}

/// The Blender target table of the core, for fronts that derive their choices from it (the add-on).
///
/// Returns:
///     {"oldest_supported": "4.2", "current_release": "5.3", "default": {"blender", "engine", "tested"},
///     "tested_versions": ["4.2", ...], "engines": [{"name": "cycles"}, {"name": "eevee"}],
///     "methods": [{"name": "burley", "blender_id": "BURLEY"}, ...] (every method of any version),
///     "versions": one entry per table row, oldest first: {"version": "4.2", "tested": bool (Cycles), "eevee_tested": bool,
///     "engine_ids": {"cycles": "CYCLES", "eevee": "BLENDER_EEVEE_NEXT"}, "methods": [{"name", "blender_id",
///     "tested", "model"}, ...] in Blender's menu order}. A version resolves to the newest row at or below it.
#[pyfunction]
#[pyo3(name = "blender_targets")]
fn blender_targets_py(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    json_to_py(py, &serde_json::to_value(describe_targets()).map_err(internal)?)
}

/// spectral-skin's compiled core: Donner & Jensen 2006's spectral skin BSSRDF.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("SpectralSkinError", m.py().get_type::<SpectralSkinError>())?;
    m.add("SpectralSkinWarning", m.py().get_type::<SpectralSkinWarning>())?;
    m.add("SpectralSkinIOError", m.py().get_type::<SpectralSkinIOError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(evaluate_py, m)?)?;
    m.add_function(wrap_pyfunction!(profile_py, m)?)?;
    m.add_function(wrap_pyfunction!(presets_py, m)?)?;
    m.add_function(wrap_pyfunction!(parameter_ranges_py, m)?)?;
    m.add_function(wrap_pyfunction!(layered_reflectance_py, m)?)?;
    m.add_function(wrap_pyfunction!(maps_py, m)?)?;
    m.add_function(wrap_pyfunction!(blender_targets_py, m)?)?;
    m.add_function(wrap_pyfunction!(read_parameter_map_py, m)?)?;
    m.add_function(wrap_pyfunction!(write_maps_py, m)?)?;
    Ok(())
}
