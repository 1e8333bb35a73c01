//! Python bindings (`spectral_skin._core`, built by maturin with the `python` feature). Bindings only: every function
//! reads its arguments under the GIL, makes one core call with the GIL released, and converts the result. No physics
//! lives here; names of outputs, combinations and working spaces come from the core's serde names.

use std::panic::{catch_unwind, AssertUnwindSafe};

use numpy::ndarray::Array2;
use numpy::{AllowTypeChange, PyArray1, PyArray2, PyArrayLike1};
use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList, PyString};
use serde::Serialize;
use serde_json::Value;

use crate::color::WorkingSpace;
use crate::diffusion::{Combination, Layer, MultipoleTerms};
use crate::error::SkinError;
use crate::evaluate::{Evaluation, MethodParams, ProfileGrid};
use crate::{Accuracy, Outputs, Request, SkinParams, PRESETS};

create_exception!(
    spectral_skin,
    SpectralSkinError,
    PyValueError,
    "Invalid input to spectral-skin. The message names the input, its allowed range and the value received."
);

impl From<SkinError> for PyErr {
    fn from(e: SkinError) -> PyErr {
        SpectralSkinError::new_err(e.to_string())
    }
}

/// The Outputs the material path needs: the default of `evaluate(outputs=...)`.
const MATERIAL_OUTPUTS: [&str; 3] = ["albedo", "radius", "specular"];
/// The combinations and working spaces accepted by name (their names are the core's serde names).
const COMBINATIONS: [Combination; 2] = [Combination::Directional, Combination::Symmetric];
const WORKING_SPACES: [WorkingSpace; 2] = [WorkingSpace::LinearRec709, WorkingSpace::LinearRec2020];
/// Names of the four parameters, in `SkinParams` order.
const PARAM_NAMES: [&str; 4] = ["melanin", "melanin_blend", "hemoglobin", "oiliness"];
/// The fields of one layer tuple, in order.
const LAYER_FIELDS: &str = "(thickness_mm, sigma_a_per_mm, sigma_s_reduced_per_mm, ior)";

/// Run a core call with the GIL released. A panic (a bug: the core validates its input) becomes a RuntimeError
/// instead of crossing into Python as a PanicException.
fn detached<T: Send>(py: Python<'_>, f: impl FnOnce() -> Result<T, SkinError> + Send) -> PyResult<T> {
    let result = py.detach(|| catch_unwind(AssertUnwindSafe(f)));
    match result {
        Ok(value) => Ok(value?),
        Err(payload) => {
            let message = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".to_string());
            Err(PyRuntimeError::new_err(format!("spectral-skin internal error (please report it): {message}")))
        }
    }
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
fn resolve_params(preset: Option<&str>, explicit: [Option<f64>; 4]) -> PyResult<SkinParams> {
    let base = preset.map(SkinParams::preset).transpose()?;
    let from_preset = base.map(|p| [p.melanin, p.melanin_blend, p.hemoglobin, p.oiliness]);
    let values: [Option<f64>; 4] = [0, 1, 2, 3].map(|i| explicit[i].or(from_preset.map(|p| p[i])));
    let missing: Vec<&str> = (0..4).filter(|&i| values[i].is_none()).map(|i| PARAM_NAMES[i]).collect();
    if !missing.is_empty() {
        let presets: Vec<&str> = PRESETS.iter().map(|p| p.name).collect();
        return Err(invalid(
            "parameters",
            format!(
                "give preset= (one of {}) or all of {}; missing: {}",
                presets.join(", "),
                PARAM_NAMES.join(", "),
                missing.join(", ")
            ),
        ));
    }
    let [m, b, h, o] = values.map(|v| v.unwrap_or(f64::NAN));
    Ok(SkinParams::new(m, b, h, o)?)
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
    wavelength_step_nm: f64,
    multipole_pairs: Option<i64>,
    profile_r_min_mm: Option<f64>,
    profile_r_max_mm: Option<f64>,
    profile_count: Option<i64>,
    combination: &'a str,
    working_space: &'a str,
}

impl Knobs<'_> {
    fn request(&self, outputs: Outputs) -> PyResult<Request> {
        let defaults = ProfileGrid::default();
        let count = match self.profile_count {
            Some(n) => to_u32("profile_count", "number of profile radii", n)? as usize,
            None => defaults.count,
        };
        let multipole_terms = match self.multipole_pairs {
            Some(n) => MultipoleTerms::Pairs(to_u32("multipole_pairs", "image pairs per side", n)?),
            None => MultipoleTerms::All,
        };
        let accuracy = Accuracy {
            wavelength_step_nm: self.wavelength_step_nm,
            multipole_terms,
            profile_grid: ProfileGrid {
                r_min_mm: self.profile_r_min_mm.unwrap_or(defaults.r_min_mm),
                r_max_mm: self.profile_r_max_mm.unwrap_or(defaults.r_max_mm),
                count,
            },
            ..Accuracy::default()
        };
        Ok(Request {
            outputs,
            accuracy,
            combination: by_name("combination", self.combination, &COMBINATIONS)?,
            working_space: by_name("working_space", self.working_space, &WORKING_SPACES)?,
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
        let field = |name: &str| json.get(name).cloned().unwrap_or(Value::Null);
        m.set_item("burley", method_dict(py, &field("burley"), &methods.burley)?)?;
        m.set_item("random_walk", method_dict(py, &field("random_walk"), &methods.random_walk)?)?;
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
        dict.set_item("profile", profile)?;
    }
    Ok(dict)
}

/// Evaluate the skin model for a preset and/or the four parameters; returns the CLI's JSON as a dict, with numpy
/// float64 arrays for array-valued outputs. Raises SpectralSkinError (a ValueError) on invalid input.
#[pyfunction]
#[pyo3(
    name = "evaluate",
    signature = (
        melanin = None, melanin_blend = None, hemoglobin = None, oiliness = None, *,
        preset = None, outputs = None, wavelength_step_nm = 5.0, multipole_pairs = None,
        profile_r_min_mm = None, profile_r_max_mm = None, profile_count = None,
        combination = "directional", working_space = "Linear Rec.709"
    )
)]
#[allow(clippy::too_many_arguments)]
fn evaluate_py<'py>(
    py: Python<'py>,
    melanin: Option<f64>,
    melanin_blend: Option<f64>,
    hemoglobin: Option<f64>,
    oiliness: Option<f64>,
    preset: Option<&str>,
    outputs: Option<&Bound<'py, PyAny>>,
    wavelength_step_nm: f64,
    multipole_pairs: Option<i64>,
    profile_r_min_mm: Option<f64>,
    profile_r_max_mm: Option<f64>,
    profile_count: Option<i64>,
    combination: &str,
    working_space: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let params = resolve_params(preset, [melanin, melanin_blend, hemoglobin, oiliness])?;
    let knobs = Knobs {
        wavelength_step_nm,
        multipole_pairs,
        profile_r_min_mm,
        profile_r_max_mm,
        profile_count,
        combination,
        working_space,
    };
    let request = knobs.request(parse_outputs(outputs)?)?;
    let evaluation = detached(py, move || crate::evaluate(&params, &request))?;
    evaluation_dict(py, &evaluation)
}

/// The radial reflectance profile R(r), mm^-2, on the profile grid: RGB (N, 3) or, with spectral=True, per
/// wavelength (K, N) with wavelengths_nm. Raises SpectralSkinError (a ValueError) on invalid input.
#[pyfunction]
#[pyo3(
    name = "profile",
    signature = (
        melanin = None, melanin_blend = None, hemoglobin = None, oiliness = None, *,
        preset = None, spectral = false, wavelength_step_nm = 5.0, multipole_pairs = None,
        profile_r_min_mm = None, profile_r_max_mm = None, profile_count = None,
        combination = "directional", working_space = "Linear Rec.709"
    )
)]
#[allow(clippy::too_many_arguments)]
fn profile_py<'py>(
    py: Python<'py>,
    melanin: Option<f64>,
    melanin_blend: Option<f64>,
    hemoglobin: Option<f64>,
    oiliness: Option<f64>,
    preset: Option<&str>,
    spectral: bool,
    wavelength_step_nm: f64,
    multipole_pairs: Option<i64>,
    profile_r_min_mm: Option<f64>,
    profile_r_max_mm: Option<f64>,
    profile_count: Option<i64>,
    combination: &str,
    working_space: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let params = resolve_params(preset, [melanin, melanin_blend, hemoglobin, oiliness])?;
    let knobs = Knobs {
        wavelength_step_nm,
        multipole_pairs,
        profile_r_min_mm,
        profile_r_max_mm,
        profile_count,
        combination,
        working_space,
    };
    let outputs = Outputs { profile_rgb: !spectral, profile_spectral: spectral, ..Outputs::default() };
    let request = knobs.request(outputs)?;
    let evaluation = detached(py, move || crate::evaluate(&params, &request))?;
    let p = evaluation.profile.as_ref().ok_or_else(|| internal("no profile in the evaluation"))?;
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

/// The named presets: {name: {melanin, melanin_blend, hemoglobin, oiliness, description}}.
#[pyfunction]
#[pyo3(name = "presets")]
fn presets_py(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let all = PyDict::new(py);
    for p in PRESETS {
        let d = PyDict::new(py);
        let q = p.params;
        for (name, value) in PARAM_NAMES.iter().zip([q.melanin, q.melanin_blend, q.hemoglobin, q.oiliness]) {
            d.set_item(name, value)?;
        }
        d.set_item("description", p.description)?;
        all.set_item(p.name, d)?;
    }
    Ok(all)
}

/// One layer from a 4-sequence of numbers.
fn extract_layer(index: usize, item: &Bound<'_, PyAny>) -> PyResult<Layer> {
    reject_string(item, &format!("layers[{index}] must be a tuple {LAYER_FIELDS}"))?;
    let values: Vec<f64> = item.extract().map_err(|e: PyErr| {
        PyTypeError::new_err(format!("layers[{index}] must be a tuple of 4 numbers {LAYER_FIELDS}: {e}"))
    })?;
    match values[..] {
        [thickness_mm, sigma_a_per_mm, sigma_s_reduced_per_mm, ior] => {
            Ok(Layer { thickness_mm, sigma_a_per_mm, sigma_s_reduced_per_mm, ior })
        }
        _ => Err(invalid(format!("layer {index}"), format!("expected 4 values {LAYER_FIELDS}; got {}", values.len()))),
    }
}

/// Total diffuse reflectance and radial profile R(r) (mm^-2, at radii_mm) of a stack of layers under air, top to
/// bottom, each (thickness_mm, sigma_a_per_mm, sigma_s_reduced_per_mm, ior); thickness inf for a semi-infinite
/// last layer. Raises SpectralSkinError (a ValueError) on invalid input.
#[pyfunction]
#[pyo3(name = "layered_reflectance", signature = (layers, radii_mm))]
fn layered_reflectance_py<'py>(
    py: Python<'py>,
    layers: &Bound<'py, PyAny>,
    radii_mm: &Bound<'py, PyAny>,
) -> PyResult<(f64, Bound<'py, PyArray1<f64>>)> {
    reject_string(layers, &format!("layers must be a list of tuples {LAYER_FIELDS}"))?;
    let layers: Vec<Layer> =
        layers.try_iter()?.enumerate().map(|(i, item)| extract_layer(i, &item?)).collect::<PyResult<_>>()?;
    reject_string(radii_mm, "radii_mm must be a 1-D array-like of radii in mm")?;
    let radii: Vec<f64> = radii_mm
        .extract::<PyArrayLike1<'py, f64, AllowTypeChange>>()
        .map_err(|e| PyTypeError::new_err(format!("radii_mm must be a 1-D array-like of radii in mm: {e}")))?
        .as_array()
        .iter()
        .copied()
        .collect();
    let (total, profile) = detached(py, move || crate::diffusion::layered_reflectance(&layers, &radii))?;
    Ok((total, PyArray1::from_vec(py, profile)))
}

/// spectral-skin's compiled core: Donner & Jensen 2006's spectral skin BSSRDF.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("SpectralSkinError", m.py().get_type::<SpectralSkinError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(evaluate_py, m)?)?;
    m.add_function(wrap_pyfunction!(profile_py, m)?)?;
    m.add_function(wrap_pyfunction!(presets_py, m)?)?;
    m.add_function(wrap_pyfunction!(layered_reflectance_py, m)?)?;
    Ok(())
}
