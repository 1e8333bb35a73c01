//! `shader_table` and `write_shader_table`: the material table as images for the add-on's live node group.

use std::sync::atomic::AtomicBool;

use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::evaluate::Outputs;
use crate::fit::SubsurfaceMethod;
use crate::maps::shader_table::{ShaderTable, ShaderTableMeta, DEFAULT_SHADER_TABLE_RESOLUTION, SHADER_TABLE_EXR};

use super::args::{named, streams_of, Knobs, ParamArgs, Streams};
use super::convert::{interleave, json_to_py, rgb_image, target_from, type_name};
use super::detach::{detached, detached_interruptible};
use super::errors::{internal, invalid};
use super::maps::table_resolution;
use super::maps_write::result_planes;

/// Base Color and Subsurface Radius tabulated as two images for Blender's shader: the node group samples them with
/// the Image Texture node (Linear interpolation, Extend, Non-Color) from live melanin, melanin blend and haemoglobin
/// values, with no baking. The Python side of ``spectral-skin shader-table``.
///
/// The table is the map pipeline's lookup table (the one :func:`maps` interpolates): natural logarithms of each
/// output at nodes on cube-root warped C_m and C_h axes and a linear beta_m axis. The images hold one slice per
/// melanin-blend node, side by side along x; a slice is a guard column, the melanin nodes, a guard column (copies of
/// the outer nodes); haemoglobin node k is texel row k from the bottom (Blender's v = 0), i.e. row ``H - 1 - k`` of
/// the arrays, whose row 0 is the top as in the files. Texel centres sit on the nodes, so for the node counts
/// (n_m, n_b, n_h) in the metadata the node group computes
///
///     u_m = clamp(C_m / 0.5, 0, 1) ** (1/3);  u_h = clamp(C_h / 0.1, 0, 1) ** (1/3)
///     b = clamp(beta_m, 0, 1) * (n_b - 1);  j = min(floor(b), n_b - 2);  t = b - j
///     x(j) = (j * (n_m + 2) + 1 + u_m * (n_m - 1) + 0.5) / W;  y = (u_h * (n_h - 1) + 0.5) / n_h
///     output = exp(mix(image(x(j), y), image(x(j + 1), y), t))
///
/// which is the table's trilinear lookup; its error against direct evaluation is in docs/shader-table.md (below 1 %
/// for the default). The surface's inputs need no table: :func:`surface_input_nodes`.
///
/// Arguments:
///     method: the subsurface method, as for :func:`maps`.
///     blender, engine: the target, as for :func:`evaluate`.
///     resolution: nodes per axis (melanin, melanin_blend, hemoglobin), each >= 2; None: the default, 33 x 9 x 17
///         (chosen on the error/size/time front of docs/shader-table.md).
///     accuracy, working_space, boundaries: as for :func:`maps`.
///     table_cache: reuse (and store) the table in the per-user cache folder that :func:`maps` uses.
///     epidermis_thickness_mm, baseline_absorption_scale, blood_oxygenation: the extended physiology baked into every
///         node (the table is over melanin, melanin blend and haemoglobin only): a float, or None for the default
///         (the paper's value, 0.25 mm, 1 and 0.75). The metadata's "extended" records them, so a front rebuilds the
///         table when they change; each value has its own cached table.
///     transport, streams: as for :func:`maps` (the metadata's "request" names them; each has its own cached table).
///
/// Ctrl-C stops the build (within a node's evaluation, about a millisecond) and raises KeyboardInterrupt.
///
/// Returns:
///     {"base_color_log": float32 (H, W, 3), ln Base Color; "radius_log": float32 (H, W, 3), ln (Subsurface Radius
///     x Subsurface Scale in mm); "metadata": {"format", "crate_version", "model_version", "method", "blender", "engine",
///     "color_space", "width", "height", "slice_width", "gutter", "melanin", "melanin_blend", "hemoglobin" (each
///     {"nodes", "min", "max", "warp": "cube_root" | "linear"}), "stored": "ln", "request" (as JSON: a semi-infinite
///     dermis thickness is None), "extended" ({"epidermis_thickness_mm", "baseline_absorption_scale",
///     "blood_oxygenation": the values baked in})}}.
///
/// Raises:
///     SpectralSkinError: an unknown method, engine, working space, transport or accuracy level, streams out of
///         range, a method the target lacks, a resolution below 2 nodes per axis or over the table's node bound, an
///         extended parameter out of its range (the message names it and the range).
///     TypeError: a resolution that is not a sequence of integers.
#[pyfunction]
#[pyo3(
    name = "shader_table",
    signature = (
        *, method = "burley", blender = None, engine = "cycles", resolution = None, accuracy = "default",
        working_space = "Linear Rec.709", boundaries = "paper", table_cache = true, epidermis_thickness_mm = None,
        baseline_absorption_scale = None, blood_oxygenation = None, transport = "adding_doubling", streams = None
    )
)]
#[allow(clippy::too_many_arguments)]
pub(super) fn shader_table_py<'py>(
    py: Python<'py>,
    method: &str,
    blender: Option<&Bound<'py, PyAny>>,
    engine: &str,
    resolution: Option<&Bound<'py, PyAny>>,
    accuracy: &str,
    working_space: &str,
    boundaries: &str,
    table_cache: bool,
    epidermis_thickness_mm: Option<&Bound<'py, PyAny>>,
    baseline_absorption_scale: Option<&Bound<'py, PyAny>>,
    blood_oxygenation: Option<&Bound<'py, PyAny>>,
    transport: &str,
    streams: Option<Streams>,
) -> PyResult<Bound<'py, PyDict>> {
    let extended =
        ParamArgs::new([None; 4], [epidermis_thickness_mm, baseline_absorption_scale, blood_oxygenation]).extended()?;
    let knobs = Knobs {
        accuracy: named(accuracy)?,
        working_space: named(working_space)?,
        boundaries: named(boundaries)?,
        target: target_from(blender, engine)?,
        transport: named(transport)?,
        streams: streams_of(streams),
        ..Knobs::default()
    };
    let method: SubsurfaceMethod = named(method)?;
    knobs.target.method_entry(method)?;
    let request = knobs.request(Outputs::material())?;
    let resolution = match resolution {
        None => DEFAULT_SHADER_TABLE_RESOLUTION,
        Some(_) => table_resolution(resolution).map_err(|e| rename(py, e))?,
    };
    let cache = if table_cache { crate::maps::lut::default_cache_dir() } else { None };
    let cancel = AtomicBool::new(false);
    let shader = detached_interruptible(py, &cancel, || {
        let prepared = crate::evaluate::Prepared::new(&request)?;
        ShaderTable::load_or_build_cancellable(&prepared, method, resolution, extended, cache.as_deref(), &cancel)
    })?;
    let (w, h) = (shader.meta().width, shader.meta().height);
    let dict = PyDict::new(py);
    dict.set_item("base_color_log", rgb_image(py, h, w, interleave(w, shader.base_color_log().clone()))?)?;
    dict.set_item("radius_log", rgb_image(py, h, w, interleave(w, shader.radius_log().clone()))?)?;
    let meta = serde_json::to_value(shader.meta()).map_err(internal)?;
    dict.set_item("metadata", json_to_py(py, &meta)?)?;
    Ok(dict)
}

/// `table_resolution`'s messages name its own argument; here it is `resolution`.
fn rename(py: Python<'_>, e: PyErr) -> PyErr {
    let text = e.value(py).to_string();
    if e.is_instance_of::<pyo3::exceptions::PyTypeError>(py) {
        pyo3::exceptions::PyTypeError::new_err(text.replace("table_resolution", "resolution"))
    } else {
        invalid("resolution", text.replace("table_resolution", "resolution"))
    }
}

/// Write a :func:`shader_table` result: ``shader_base_color.exr`` and ``shader_radius.exr`` (RGB, 32-bit float,
/// PIZ, row 0 at the top; load them in Blender as Non-Color) and ``shader_table.json`` (the metadata, with the file
/// names), into ``folder`` (created if missing); with ``prefix``, ``<prefix>_shader_base_color.exr`` etc. The files
/// are written as temporary files and renamed into place together once all are written.
///
/// Arguments:
///     result: a mapping with "base_color_log" and "radius_log" (float32 or float64 (H, W, 3) arrays) and
///         "metadata" (the dict :func:`shader_table` returned), as :func:`shader_table` returns.
///     folder: the output folder.
///     prefix: None, or a file-name part prepended with "_" to each file name (no path separator).
///
/// Returns:
///     {"base_color" | "radius" | "metadata": path of the file written}.
///
/// Raises:
///     SpectralSkinError: a missing image or metadata, metadata of another format or whose layout does not match
///         the images, a non-finite texel, a prefix that is empty or holds a path separator; a file that cannot be
///         written (the message names it).
///     TypeError: an image that is not a float32 or float64 numpy array.
#[pyfunction]
#[pyo3(name = "write_shader_table", signature = (result, folder, prefix = None))]
pub(super) fn write_shader_table_py<'py>(
    py: Python<'py>,
    result: &Bound<'py, PyAny>,
    folder: std::path::PathBuf,
    prefix: Option<&str>,
) -> PyResult<Bound<'py, PyDict>> {
    let planes = |key: &str| -> PyResult<(usize, usize, [Vec<f32>; 3])> {
        let image = result_planes(result, key, 3)?
            .ok_or_else(|| invalid("result", format!("has no {key:?} image (a shader_table() result has)")))?;
        let planes = image.planes.try_into().map_err(|_| internal("not three planes"))?;
        Ok((image.height, image.width, planes))
    };
    let (h0, w0, base_color_log) = planes("base_color_log")?;
    let (h1, w1, radius_log) = planes("radius_log")?;
    let metadata = result
        .get_item("metadata")
        .map_err(|_| invalid("result", "has no \"metadata\" (a shader_table() result has)"))?;
    let text: String = py.import("json")?.call_method1("dumps", (&metadata,))?.extract()?;
    let meta: ShaderTableMeta = serde_json::from_str(&text).map_err(|e| {
        invalid(
            "result[\"metadata\"]",
            format!("is not a shader table's metadata ({e}); got a {}", type_name(&metadata)),
        )
    })?;
    if (h0, w0) != (meta.height, meta.width) || (h1, w1) != (meta.height, meta.width) {
        return Err(invalid(
            "result",
            format!(
                "the images must be (H, W) = ({}, {}) as the metadata says; got base_color_log ({h0}, {w0}), \
                 radius_log ({h1}, {w1})",
                meta.height, meta.width
            ),
        ));
    }
    let paths = detached(py, || {
        let table = ShaderTable::from_parts(meta, base_color_log, radius_log)?;
        table.write(&folder, prefix, SHADER_TABLE_EXR)
    })?;
    let dict = PyDict::new(py);
    for (key, path) in ["base_color", "radius", "metadata"].into_iter().zip(paths) {
        dict.set_item(key, path)?;
    }
    Ok(dict)
}
