//! The conversion rules for arguments (numbers, sequences, names, arrays) and for results (JSON values, arrays).

use numpy::ndarray::{Array2, Array3, ArrayView2, Axis, Ix2, Ix3};
use numpy::{
    AllowTypeChange, Element, PyArray, PyArray2, PyArray3, PyArrayDescrMethods, PyArrayDyn, PyArrayLike1,
    PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyRuntimeError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyString};
use rayon::prelude::*;
use serde::Serialize;
use serde_json::Value;

use crate::error::SkinError;
use crate::evaluate::Outputs;
use crate::fit::blender_target::{BlenderVersion, Engine, Target, CURRENT_RELEASE};
use crate::maps::io::PARAM_CHANNELS;
use crate::skin::params::EXTENDED_DEFAULTS;
use crate::skin::{SkinParams, PRESETS};
use crate::transport::{Transport, ALL_TRANSPORTS, STREAMS_RANGE};

use super::errors::{internal, invalid};

/// The Outputs the material path needs: the default of `evaluate(outputs=...)`.
/// The outputs `maps` computes, by their names (the core's [`crate::evaluate::MaterialOutput`]).
pub(super) fn material_outputs() -> Vec<String> {
    crate::evaluate::ALL_MATERIAL_OUTPUTS.iter().map(serde_name).collect()
}

/// A TypeError if `obj` is a str or bytes where a sequence is expected (strings are iterable, so they would
/// otherwise be read character by character).
pub(super) fn reject_string(obj: &Bound<'_, PyAny>, expected: &str) -> PyResult<()> {
    if obj.is_instance_of::<PyString>() || obj.is_instance_of::<PyBytes>() {
        return Err(PyTypeError::new_err(format!("{expected}, not a string")));
    }
    Ok(())
}

/// The Python type of `obj`, for messages.
pub(super) fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type().name().map(|n| n.to_string()).unwrap_or_default()
}

/// True for Python's and numpy's booleans: they convert to numbers, but `True` as a concentration or a step is a
/// mistake, not a 1.
pub(super) fn is_boolean(obj: &Bound<'_, PyAny>) -> bool {
    obj.is_instance_of::<PyBool>() || type_name(obj) == "bool_" || type_name(obj) == "bool"
}

/// The one rule for every numeric argument: an int or a float (or a numpy scalar of either), never a bool, str or
/// bytes. A wrong type is a TypeError whose message names the argument (pyo3 only adds the name as a note).
pub(super) fn number_type_check(name: &str, obj: &Bound<'_, PyAny>, what: &str) -> PyResult<()> {
    if is_boolean(obj) || obj.is_instance_of::<PyString>() || obj.is_instance_of::<PyBytes>() {
        return Err(PyTypeError::new_err(format!("{name} must be {what}; got {} {}", type_name(obj), obj.repr()?)));
    }
    Ok(())
}

/// A real number (see [`number_type_check`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct Real(pub(super) f64);

/// An integer (see [`number_type_check`]); a float is a TypeError too.
#[derive(Debug, Clone, Copy)]
pub(super) struct Count(pub(super) i64);

pub(super) const A_NUMBER: &str = "a number (int or float)";
pub(super) const AN_INTEGER: &str = "an integer";

pub(super) fn real_of(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Real> {
    number_type_check(name, obj, A_NUMBER)?;
    obj.extract::<f64>()
        .map(Real)
        .map_err(|_| PyTypeError::new_err(format!("{name} must be {A_NUMBER}; got {}", type_name(obj))))
}

pub(super) fn count_of(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Count> {
    number_type_check(name, obj, AN_INTEGER)?;
    obj.extract::<i64>().map(Count).map_err(|_| {
        // An int too large for 64 bits is a value out of range, not a wrong type.
        if obj.is_instance_of::<pyo3::types::PyInt>() {
            let repr = obj.repr().map(|r| r.to_string()).unwrap_or_default();
            invalid(name, format!("must be an integer in [{}, {}]; got {repr}", i64::MIN, i64::MAX))
        } else {
            PyTypeError::new_err(format!("{name} must be {AN_INTEGER}; got {}", type_name(obj)))
        }
    })
}

/// An optional numeric keyword argument (None is absent).
pub(super) fn real_arg(name: &str, obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Real>> {
    obj.filter(|o| !o.is_none()).map(|o| real_of(name, o)).transpose()
}

pub(super) fn count_arg(name: &str, obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Count>> {
    obj.filter(|o| !o.is_none()).map(|o| count_of(name, o)).transpose()
}

/// `obj` as a sequence of at most `most` numbers under the rule of [`Real`]; a wrong element is a TypeError naming
/// `name[i]`. The iteration stops at element `most + 1` (an endless iterator is refused, not followed).
pub(super) fn real_sequence(name: &str, obj: &Bound<'_, PyAny>, expected: &str, most: usize) -> PyResult<Vec<f64>> {
    reject_string(obj, &format!("{name} must be {expected}"))?;
    let iter = obj
        .try_iter()
        .map_err(|_| PyTypeError::new_err(format!("{name} must be {expected}; got {}", type_name(obj))))?;
    let values: Vec<f64> = iter
        .take(most.saturating_add(1))
        .enumerate()
        .map(|(i, item)| Ok(real_of(&format!("{name}[{i}]"), &item?)?.0))
        .collect::<PyResult<_>>()?;
    if values.len() > most {
        return Err(too_many(name, expected, most, "more"));
    }
    Ok(values)
}

/// The error of an argument with more than `most` elements (`got`: how many, or "more" for an iterable).
fn too_many(name: &str, expected: &str, most: usize, got: &str) -> PyErr {
    invalid(name, format!("must be {expected} with at most {most} values; got {got}"))
}

/// The one size check of an array argument, read from its shape before anything is copied or converted (a broadcast
/// or strided view of any shape costs nothing): the product of the dimensions must be at most `most`. Not an array:
/// nothing to check here (a sequence is bounded while it is read, [`real_sequence`]).
pub(super) fn check_array_size(name: &str, obj: &Bound<'_, PyAny>, expected: &str, most: usize) -> PyResult<()> {
    let Ok(untyped) = obj.cast::<PyUntypedArray>() else {
        return Ok(());
    };
    let shape = untyped.shape();
    let count = shape.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
    if count.map_or(true, |n| n > most) {
        return Err(too_many(name, expected, most, &format!("shape {}", shape_text(shape))));
    }
    Ok(())
}

/// `obj` as a sequence of at most `most` integers under the rule of [`Count`]; a wrong element is a TypeError naming
/// `name[i]`; the iteration stops at element `most + 1`.
pub(super) fn count_sequence(name: &str, obj: &Bound<'_, PyAny>, expected: &str, most: usize) -> PyResult<Vec<i64>> {
    reject_string(obj, &format!("{name} must be {expected}"))?;
    let iter = obj
        .try_iter()
        .map_err(|_| PyTypeError::new_err(format!("{name} must be {expected}; got {}", type_name(obj))))?;
    let values: Vec<i64> = iter
        .take(most.saturating_add(1))
        .enumerate()
        .map(|(i, item)| Ok(count_of(&format!("{name}[{i}]"), &item?)?.0))
        .collect::<PyResult<_>>()?;
    if values.len() > most {
        return Err(too_many(name, expected, most, "more"));
    }
    Ok(values)
}

/// The serde name of a core enum value (e.g. "directional", "Linear Rec.709").
pub(super) fn serde_name<T: Serialize>(value: &T) -> String {
    match serde_json::to_value(value) {
        Ok(Value::String(s)) => s,
        _ => String::new(),
    }
}

/// The value among `candidates` whose serde name is `name`; the error lists the accepted names.
pub(super) fn by_name<T: Serialize + Copy>(what: &str, name: &str, candidates: &[T]) -> PyResult<T> {
    candidates.iter().copied().find(|c| serde_name(c) == name).ok_or_else(|| {
        let names: Vec<String> = candidates.iter().map(|c| format!("{:?}", serde_name(c))).collect();
        invalid(what, format!("unknown {what} {name:?}; valid: {}", names.join(", ")))
    })
}

/// Names in `outputs` (an iterable of str) to [`Outputs`]; the valid names are `Outputs`' field names.
pub(super) fn parse_outputs(outputs: Option<&Bound<'_, PyAny>>) -> PyResult<Outputs> {
    let names: Vec<String> = match outputs {
        None => material_outputs(),
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
/// required. The extended physiology is the preset's (the defaults). The core validates the ranges.
pub(super) fn resolve_params(preset: Option<&str>, explicit: [Option<Real>; 4]) -> PyResult<SkinParams> {
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
    let extended = base.map_or(EXTENDED_DEFAULTS, |p| p.extended_values());
    Ok(SkinParams::from_values([m, b, h, o, extended[0], extended[1], extended[2]])?)
}

/// `blender=` and `engine=` to a [`Target`]: the version as "MAJOR.MINOR" (or "MAJOR.MINOR.PATCH") or a tuple of
/// ints such as `bpy.app.version`; None is the current release. The core validates both and names the range.
pub(super) fn target_from(blender: Option<&Bound<'_, PyAny>>, engine: &str) -> PyResult<Target> {
    const EXPECTED: &str = "blender must be a version string such as \"5.3\" or a tuple such as (5, 3, 0)";
    let version = match blender {
        None => CURRENT_RELEASE,
        Some(obj) if obj.is_instance_of::<PyString>() => obj.extract::<String>()?.parse::<BlenderVersion>()?,
        Some(obj) => {
            if obj.is_instance_of::<PyBytes>() || is_boolean(obj) {
                return Err(PyTypeError::new_err(EXPECTED));
            }
            let parts = count_sequence("blender", obj, EXPECTED.trim_start_matches("blender must be "), 3)?;
            BlenderVersion::from_parts(&parts)?
        }
    };
    Ok(Target { blender: version, engine: Engine::from_name(engine)? })
}

/// An integer keyword to the `u32` the core takes; outside `u32` is an out-of-range error (the core checks its own,
/// narrower ranges).
pub(super) fn to_u32(name: &'static str, meaning: &'static str, value: i64) -> PyResult<u32> {
    u32::try_from(value).map_err(|_| {
        SkinError::OutOfRange { name, meaning, min: 0.0, max: u32::MAX as f64, value: value as f64 }.into()
    })
}

/// `transport=` by its serde name; the error lists the names ([`ALL_TRANSPORTS`]).
pub(super) fn transport_arg(name: &str) -> PyResult<Transport> {
    by_name("transport", name, &ALL_TRANSPORTS)
}

/// `streams=`: None, or an even integer in `STREAMS_RANGE` (the solver's rule; an error naming `streams` and the range
/// otherwise).
pub(super) fn streams_arg(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<usize>> {
    let Some(Count(n)) = count_arg("streams", obj)? else { return Ok(None) };
    let (lo, hi) = STREAMS_RANGE;
    let streams = usize::try_from(n)
        .map_err(|_| invalid("streams", format!("must be an even count in [{lo}, {hi}]; got {n}")))?;
    crate::transport::adding_doubling::validate_streams(streams)?;
    Ok(Some(streams))
}

/// `dict["model"]` (a serialised [`SkinModel`](crate::skin::SkinModel)) with the dermis thickness as a Python float:
/// JSON has no infinity, so serde writes a semi-infinite dermis as "inf"; a Python float has one (and `model=` reads
/// either).
pub(super) fn float_dermis(dict: &Bound<'_, pyo3::types::PyDict>, model: &crate::skin::SkinModel) -> PyResult<()> {
    dict.get_item("model")?
        .ok_or_else(|| internal("no model in the result"))?
        .set_item("dermis_thickness_mm", model.dermis_thickness_mm)
}

/// serde_json `Value` to plain Python objects (dict, list, str, int, float, bool, None), by pythonize. Results go
/// through the `Value` (not straight from the struct) so that they are what the CLI's JSON is: keys sorted, arrays as
/// lists, a non-finite float as None.
pub(super) fn json_to_py<'py>(py: Python<'py>, value: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(pythonize::pythonize(py, value)?)
}

/// A core value as the CLI's JSON would have it, as plain Python objects (see [`json_to_py`]).
pub(super) fn to_py<'py, T: Serialize>(py: Python<'py>, value: &T) -> PyResult<Bound<'py, PyAny>> {
    json_to_py(py, &serde_json::to_value(value).map_err(internal)?)
}

/// Rows of equal length to a 2-D float64 array.
pub(super) fn array2<'py>(
    py: Python<'py>,
    rows: usize,
    cols: usize,
    flat: Vec<f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    Ok(PyArray2::from_owned_array(py, Array2::from_shape_vec((rows, cols), flat).map_err(internal)?))
}

pub(super) fn rgb_rows<'py>(py: Python<'py>, rgb: &[[f64; 3]]) -> PyResult<Bound<'py, PyArray2<f64>>> {
    array2(py, rgb.len(), 3, rgb.iter().flatten().copied().collect())
}

pub(super) fn nested_rows<'py>(py: Python<'py>, rows: &[Vec<f64>]) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let cols = rows.first().map_or(0, Vec::len);
    array2(py, rows.len(), cols, rows.iter().flatten().copied().collect())
}

/// The rules of a numpy array of numbers, read from its header before any copy: at most `most` elements
/// ([`check_array_size`]), a dtype of ints or floats (else a TypeError: a bool, str or object array), `ndim`
/// dimensions; each error names `name` and says `expected`.
pub(super) fn check_numeric_array(
    name: &str,
    array: &Bound<'_, PyUntypedArray>,
    expected: &str,
    most: usize,
    ndim: usize,
) -> PyResult<()> {
    check_array_size(name, array.as_any(), expected, most)?;
    if !matches!(array.dtype().kind(), b'f' | b'i' | b'u') {
        return Err(PyTypeError::new_err(format!(
            "{name} must be {expected}; got an array of dtype {}",
            array.dtype()
        )));
    }
    if array.ndim() != ndim {
        return Err(invalid(name, format!("must be {expected}; got shape {}", shape_text(array.shape()))));
    }
    Ok(())
}

/// A 1-D numpy array of ints or floats (any strides, read-only too) or a sequence of numbers under the rule of
/// [`Real`], of at most `most` values (checked from the shape before any copy, [`check_array_size`]). A bool, str or
/// other dtype is a TypeError, another number of dimensions or too many values a SpectralSkinError; both name `name`.
pub(super) fn real_vector(name: &str, obj: &Bound<'_, PyAny>, expected: &str, most: usize) -> PyResult<Vec<f64>> {
    let Ok(untyped) = obj.cast::<PyUntypedArray>() else {
        return real_sequence(name, obj, expected, most);
    };
    check_numeric_array(name, untyped, expected, most, 1)?;
    let values = obj
        .extract::<PyArrayLike1<'_, f64, AllowTypeChange>>()
        .map_err(|e| PyTypeError::new_err(format!("{name} must be {expected}: {e}")))?;
    Ok(values.as_array().iter().copied().collect())
}

/// A numpy array of float32, or of float64 (converted to float32 while it is copied).
pub(super) enum FloatArray<'py> {
    F32(Bound<'py, PyArrayDyn<f32>>),
    F64(Bound<'py, PyArrayDyn<f64>>),
}

impl FloatArray<'_> {
    pub(super) fn shape(&self) -> Vec<usize> {
        match self {
            FloatArray::F32(a) => a.shape().to_vec(),
            FloatArray::F64(a) => a.shape().to_vec(),
        }
    }

    /// One row-major (H, W) plane as float32: the whole (H, W) array, or channel `c` of an (H, W, C) array. One pass
    /// over the data (a copy, converting float64); any strides.
    pub(super) fn plane(&self, channel: Option<usize>) -> PyResult<Vec<f32>> {
        match self {
            FloatArray::F32(a) => plane_of(a, channel, |v| v),
            FloatArray::F64(a) => plane_of(a, channel, |v| v as f32),
        }
    }
}

pub(super) fn plane_of<T: Element + Copy>(
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

/// Planar RGB to one row-major (H, W, 3) buffer, rows in parallel.
pub(super) fn interleave(width: usize, planes: [Vec<f32>; 3]) -> Vec<f32> {
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
pub(super) fn rgb_image(
    py: Python<'_>,
    height: usize,
    width: usize,
    data: Vec<f32>,
) -> PyResult<Bound<'_, PyArray3<f32>>> {
    Ok(PyArray::from_owned_array(py, Array3::from_shape_vec((height, width, 3), data).map_err(internal)?))
}

/// A shape as Python prints it: (8, 8, 4).
pub(super) fn shape_text(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!("({})", shape.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(", ")),
    }
}

/// `obj` as a float32/float64 array of `ndim` dimensions, or None if it is not a numpy array. Another dtype or
/// an unaligned array is a TypeError; another number of dimensions a SpectralSkinError.
pub(super) fn float_array<'py>(
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
    // The texel bound, from the shape, before any plane is copied (a broadcast view of any shape costs nothing).
    if let [height, width, ..] = *untyped.shape() {
        crate::maps::io::check_texel_count(name, width, height)?;
    }
    Ok(Some(array))
}
