//! The model-version stamp for the project's doc scripts (scripts/lib/doc_stamp.py): the core's functions as they
//! are (src/stamp.rs), so Rust examples and Python scripts stamp alike. Underscored: tooling, not the public API.

use std::path::PathBuf;

use pyo3::prelude::*;

use crate::stamp;

use super::detach::detached;

/// The stamp (an HTML comment) of a Markdown doc written by ``command`` from this model.
#[pyfunction]
#[pyo3(name = "_markdown_stamp")]
pub(super) fn markdown_stamp_py(command: &str) -> String {
    stamp::markdown_stamp(command)
}

/// ``text`` with its block ``name`` (between ``<!-- BEGIN name -->`` and ``<!-- END name -->``) replaced by the
/// stamp and ``body``. Raises SpectralSkinError when the markers are missing.
#[pyfunction]
#[pyo3(name = "_replace_markdown_block")]
pub(super) fn replace_markdown_block_py(text: &str, name: &str, command: &str, body: &str) -> PyResult<String> {
    Ok(stamp::replace_markdown_block(text, name, command, body)?)
}

/// Stamps the PNG at ``path`` (a text chunk; pixels unchanged; staged and renamed).
#[pyfunction]
#[pyo3(name = "_stamp_png")]
pub(super) fn stamp_png_py(py: Python<'_>, path: PathBuf, command: &str) -> PyResult<()> {
    detached(py, || stamp::stamp_png(&path, command))
}

/// The model version a PNG's stamp names, or None.
#[pyfunction]
#[pyo3(name = "_png_stamp_version")]
pub(super) fn png_stamp_version_py(path: PathBuf) -> PyResult<Option<u32>> {
    Ok(stamp::png_stamp_version(&path)?)
}
