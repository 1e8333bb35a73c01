//! The core's tables for fronts: presets, parameter ranges, Blender targets.

use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::fit::blender_target::describe_targets;
use crate::maps::io::PARAM_CHANNELS;
use crate::PRESETS;

use super::convert::json_to_py;
use super::errors::internal;

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
pub(super) fn parameter_ranges_py(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    for (name, range) in crate::maps::io::PARAM_CHANNELS.iter().zip(crate::maps::io::PARAM_RANGES) {
        d.set_item(name, range)?;
    }
    Ok(d)
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
    json_to_py(py, &serde_json::to_value(describe_targets()).map_err(internal)?)
}
