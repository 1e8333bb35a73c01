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

/// Replaces the blocks ``{name: body}`` of the Markdown doc at ``path`` (each between ``<!-- BEGIN name -->`` and
/// ``<!-- END name -->``) by the stamp of ``command`` and the body, in one atomic write. Raises SpectralSkinError
/// when a marker is missing (the doc unchanged), SpectralSkinIOError when it cannot be read or written.
#[pyfunction]
#[pyo3(name = "_write_markdown_blocks")]
pub(super) fn write_markdown_blocks_py(
    py: Python<'_>,
    path: PathBuf,
    command: &str,
    blocks: Vec<(String, String)>,
) -> PyResult<()> {
    let blocks: Vec<(&str, &str)> = blocks.iter().map(|(n, b)| (n.as_str(), b.as_str())).collect();
    detached(py, || stamp::write_markdown_blocks(&path, command, &blocks))
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
