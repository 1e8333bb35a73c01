//! The core's tables for fronts: parameters, presets, accuracy levels, Blender targets.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::accuracy::ALL_ACCURACY_LEVELS;
use crate::fit::blender_target::describe_targets;
use crate::skin::PARAMS;
use crate::skin::PRESETS;
use crate::surface::lobes::{SurfaceModel, ALL_SURFACE_MODELS};
use crate::transport::{Transport, ALL_TRANSPORTS};

use super::convert::to_py;

/// The named presets.
///
/// Returns:
///     {name: {"melanin", "melanin_blend", "hemoglobin", "oiliness", "description"}}; the names are accepted by
///     ``preset=`` of :func:`evaluate` and :func:`profile`.
#[pyfunction]
#[pyo3(name = "presets")]
pub(super) fn presets_py(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let all = PyDict::new(py);
    for p in PRESETS {
        let d = PyDict::new(py);
        for (spec, value) in PARAMS.iter().zip(p.params.values()) {
            d.set_item(spec.name, value)?;
        }
        d.set_item("description", p.description)?;
        all.set_item(p.name, d)?;
    }
    Ok(all)
}

/// The model's parameters, from the core's parameter table: what fronts build their inputs from.
///
/// Returns:
///     One dict per parameter, in the order of :func:`evaluate`'s arguments and of a parameter map's channels:
///     {"name": "melanin" (the keyword and map channel), "symbol": "C_m" (DJ2006's, ASCII-spelled: "beta_m"),
///     "label": "Melanin" (a UI title), "description": "melanin volume fraction of the epidermis" (what it is),
///     "effect": what changing it does, "unit": "" (empty: dimensionless), "min": 0.0, "max": 0.5, "default": None
///     (None: it must be given, by value or by a preset), "source": where meaning and range come from}.
#[pyfunction]
#[pyo3(name = "parameters")]
pub(super) fn parameters_py(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let all = PyList::empty(py);
    for p in PARAMS {
        let d = PyDict::new(py);
        d.set_item("name", p.name)?;
        d.set_item("symbol", p.symbol)?;
        d.set_item("label", p.label)?;
        d.set_item("description", p.description)?;
        d.set_item("effect", p.effect)?;
        d.set_item("unit", p.unit)?;
        d.set_item("min", p.min)?;
        d.set_item("max", p.max)?;
        d.set_item("default", p.default)?;
        d.set_item("source", p.source)?;
        all.append(d)?;
    }
    Ok(all)
}

/// The allowed range of each parameter (:func:`parameters` has the rest of each one's description).
///
/// Returns:
///     {"melanin": (0.0, 0.5), "melanin_blend": (0.0, 1.0), "hemoglobin": (0.0, 0.1), "oiliness": (0.0, 1.0)}:
///     volume fractions (melanin of the epidermis, whole blood of the dermis), the eumelanin share, the oiliness.
#[pyfunction]
#[pyo3(name = "parameter_ranges")]
pub(super) fn parameter_ranges_py(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    for p in PARAMS {
        d.set_item(p.name, p.range())?;
    }
    Ok(d)
}

/// The named accuracy levels, cheapest first (docs/accuracy-vs-time.md).
///
/// Returns:
///     [{"name": "draft", "description": one line: what the level is for and how close it is to the reference},
///     {"name": "default", ...}, {"name": "reference", ...}]; the names are accepted by ``accuracy=`` of
///     :func:`evaluate`, :func:`profile` and :func:`maps`.
#[pyfunction]
#[pyo3(name = "accuracy_levels")]
pub(super) fn accuracy_levels_py(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let all = PyList::empty(py);
    for level in ALL_ACCURACY_LEVELS {
        let d = PyDict::new(py);
        d.set_item("name", level.name())?;
        d.set_item("description", level.description())?;
        all.append(d)?;
    }
    Ok(all)
}

/// The transports: how each wavelength's total diffuse reflectance is computed (docs/model.md), the default first.
///
/// Returns:
///     [{"name": "adding_doubling", "description": one line, "default": True}, {"name": "diffusion", ...,
///     "default": False}]; the names are accepted by ``transport=`` of :func:`evaluate`, :func:`profile`,
///     :func:`maps`, :func:`shader_table`, :func:`layered_reflectance` and the fits.
#[pyfunction]
#[pyo3(name = "transports")]
pub(super) fn transports_py(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let all = PyList::empty(py);
    for transport in ALL_TRANSPORTS {
        let d = PyDict::new(py);
        d.set_item("name", transport.name())?;
        d.set_item("description", transport.description())?;
        d.set_item("default", transport == Transport::default())?;
        all.append(d)?;
    }
    Ok(all)
}

/// The surface models: which surface reflection the specular inputs stand in for (docs/model.md), in the core's
/// order.
///
/// Returns:
///     [{"name": "measured", "description": one line, "default": bool}, {"name": "paper", ...}]; the names are
///     accepted by ``surface=`` of :func:`evaluate` and :func:`maps`; "default" marks what they take when not told.
#[pyfunction]
#[pyo3(name = "surface_models")]
pub(super) fn surface_models_py(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let all = PyList::empty(py);
    for model in ALL_SURFACE_MODELS {
        let d = PyDict::new(py);
        d.set_item("name", model.name())?;
        d.set_item("description", model.description())?;
        d.set_item("default", model == SurfaceModel::default())?;
        all.append(d)?;
    }
    Ok(all)
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
pub(super) fn blender_targets_py(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    to_py(py, &describe_targets())
}
