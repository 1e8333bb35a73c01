//! `maps`, `read_parameter_map` and `write_maps`: texture maps, with progress and cancelling.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use numpy::ndarray::{Array2, Array3};
use numpy::{PyArray, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::{PyKeyError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyIterator, PyList, PyString};
use rayon::prelude::*;

use crate::evaluate::Outputs;
use crate::evaluate::Request;
use crate::fit::SubsurfaceMethod;
use crate::maps::io::{
    default_extended, read_params, ExrOptions, ParamImage, ParamInputs, ParamSource, Plane, ALL_CHANNELS,
    ALL_COMPRESSIONS, ALL_PRECISIONS, ALL_RANGES, EXTENDED_CHANNELS, PARAM_CHANNELS,
};
use crate::maps::lut::TableResolution;
use crate::maps::pipeline::{
    check_planes, check_prefix, commit_map_files, compute_maps_cancellable, output_name, stage_map_files,
    tile_output_name, MapFiles, MapKind, MapSettings, SpecularOutput, StrategyChoice, ALBEDO_MAP, MAP_KINDS,
    RADIUS_MAP, SURFACE_MAP_KINDS,
};
use crate::maps::udim::{check_tile, stacked_tile_rows, tile_set_file_name, TileRows};
use crate::surface::principled::SpecularParams;

use super::convert::{
    by_name, count_sequence, float_array, is_boolean, material_outputs, parse_outputs, real_arg, shape_text,
    streams_arg, surface_arg, target_from, to_py, type_name, FloatArray, Knobs,
};
use super::detach::{detached, detached_interruptible};
use super::errors::{internal, invalid, warn_notes};
use super::progress::Progress;

/// The fields of `SpecularParams` that do not depend on the oiliness: what `maps` returns in "specular_constants"
/// when the oiliness varies (beside the per-texel maps), and for the `paper` surface its Coat (weight 0).
pub(super) const SPECULAR_CONSTANTS: [&str; 5] = ["surface", "roughness", "ior", "coat_ior", "beckmann_m"];
/// The Coat fields that are one value under the `paper` surface (no Coat) even when the oiliness varies.
const PAPER_COAT_CONSTANTS: [&str; 2] = ["coat_weight", "coat_roughness"];

/// What `params` of `maps` must be, for messages.
pub(super) const PARAMS_ARRAY: &str =
    "a float32 (H, W, 4) numpy array (channels melanin, melanin_blend, hemoglobin, oiliness)";
/// What a per-parameter keyword of `maps` must be, for messages.
pub(super) const PARAM_ARRAY: &str = "a float32 (H, W) numpy array or a float";

/// A per-parameter input of `maps`.
pub(super) enum MapInput<'py> {
    Array(FloatArray<'py>),
    Constant(f64),
}

pub(super) fn map_input<'py>(name: &str, obj: &Bound<'py, PyAny>) -> PyResult<MapInput<'py>> {
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
pub(super) fn table_resolution(obj: Option<&Bound<'_, PyAny>>) -> PyResult<TableResolution> {
    const EXPECTED: &str = "a tuple (melanin, melanin_blend, hemoglobin) of node counts";
    let Some(obj) = obj else {
        return Ok(TableResolution::default());
    };
    let counts = count_sequence("table_resolution", obj, EXPECTED, 3)?;
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

/// Parameter maps read from a file with the core's reader: the formats and rules of ``spectral-skin maps``.
///
/// Arguments:
///     path: the file.
///     name: None for the four-channel parameter EXR (as ``spectral-skin maps --params``; ``spectral-skin
///         example`` writes one): channels named melanin, melanin_blend, hemoglobin and oiliness, all required.
///         A parameter name ("melanin", "melanin_blend", "hemoglobin" or "oiliness") for that parameter's own map
///         (as ``--melanin`` etc.): an EXR with exactly one channel (any name), with a channel named like the
///         parameter, or with R, G, B (A) whose R = G = B (a grey image as Blender saves one), whose values are the
///         parameter itself; or an 8/16-bit PNG, TIFF or JPEG, greyscale or RGB(A) with R = G = B, whose 0..1
///         values map linearly onto the parameter's range (:func:`parameter_ranges`). An extended parameter's name
///         ("epidermis_thickness_mm", "baseline_absorption_scale", "blood_oxygenation") reads its own map the same
///         way.
///
/// Returns:
///     {parameter name: float32 (H, W) array, row 0 at the top}: the four parameters and any of the extended
///     physiology's channels the file has (optional channels named like them), or the one named. Values are not
///     range-checked (:func:`maps` does that).
///
/// Raises:
///     SpectralSkinError: a missing or unreadable file, an unsupported format, a missing channel or a multi-channel
///         file without the parameter's channel, an RGB image that is not grey (the message names the file, what it
///         found and what is accepted), an unknown name.
///
/// Warns:
///     SpectralSkinWarning: what was accepted but ignored (an alpha channel; a channel of no parameter's name in
///         the four-channel file, with the known names), once per file.
#[pyfunction]
#[pyo3(name = "read_parameter_map", signature = (path, name = None))]
pub(super) fn read_parameter_map_py<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
    name: Option<&str>,
) -> PyResult<Bound<'py, PyDict>> {
    let inputs = match name {
        None => ParamInputs::Multi { path, constants: [None; 4] },
        Some(name) => {
            let Some(p) = ALL_CHANNELS.iter().position(|c| *c == name) else {
                let expected = ALL_CHANNELS.join(", ");
                return Err(invalid(
                    "name",
                    format!("expected one of {expected} (or None for the four-channel file); got {name:?}"),
                ));
            };
            let source = |k: usize| if k == p { Some(ParamSource::File(path.clone())) } else { None };
            ParamInputs::Extended {
                inputs: Box::new(ParamInputs::Separate(std::array::from_fn(|k| {
                    source(k).unwrap_or(ParamSource::Constant(0.0))
                }))),
                extended: std::array::from_fn(|k| source(4 + k)),
            }
        }
    };
    let image = detached(py, move || read_params(&inputs))?;
    warn_notes(py, &image.notes)?;
    let dict = PyDict::new(py);
    let (height, width) = (image.height, image.width);
    let channels = PARAM_CHANNELS.iter().chain(EXTENDED_CHANNELS.iter());
    for (parameter, plane) in channels.zip(image.planes.into_iter().chain(image.extended)) {
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
/// "constant" (one evaluation) when melanin, melanin_blend and hemoglobin (and the extended physiology) each hold one
/// value everywhere (floats, or arrays of one value); "distinct_tuples" (one evaluation per distinct (melanin,
/// melanin_blend, hemoglobin), with the extended physiology when it varies) when there are at most 2048 of them;
/// otherwise "table": a lookup table built for the call and interpolated per texel, worst error below 0.5 % in albedo
/// and 1 % in radius at the paper's extended physiology (its measured figures are in ``report["strategy"]``), or
/// "exact" when an extended parameter varies (the table is over the three concentrations only).
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
///     epidermis_thickness_mm, baseline_absorption_scale, blood_oxygenation: the extended physiology
///         (:func:`parameters`; docs/model.md, "Extended physiology"): an (H, W) array, a float, or None (the
///         default: the paper's value, 0.25 mm, 1 and 0.75). One value everywhere is baked into the lookup table
///         (cached per value); an array that varies makes every distinct tuple (at most 2048) or else every texel
///         be evaluated directly (no table: a few milliseconds of CPU per texel, like ``exact=True``).
///     method: the subsurface method the maps are for: "burley" (Christensen-Burley), "random_walk",
///         "random_walk_legacy" (Blender 5.2 and later only) or "random_walk_skin".
///     blender, engine: the target, as for :func:`evaluate`; the radius (and for the random walks Base Color) is
///         computed for it per texel (for EEVEE from each texel's own albedo).
///     outputs: the maps to compute, names among "albedo" (Base Color), "radius" (Subsurface Radius) and
///         "specular" (the specular inputs); None (the default) is all three. Without "radius" no radius is fitted
///         (``report["work"]["radius_fits"]`` is 0, a table holds the albedo alone) and Base Color is the albedo,
///         whatever the method (the Base Color of a material without subsurface); without "specular" no specular
///         input is computed. An output not asked for is absent from the result.
///     exact: evaluate every texel (or distinct tuple) directly, never the table.
///     clamp: clamp NaN (to the minimum), infinite and out-of-range values into range and count them in
///         ``report["clamped"]``, instead of raising. The input arrays are not modified.
///     accuracy: a named accuracy level, "draft", "default" or "reference", as for :func:`evaluate`.
///     wavelength_step_nm, wavelength_placement: as for :func:`evaluate`.
///     working_space: linear RGB space of Base Color, as for :func:`evaluate`: "Linear Rec.709" (Blender's
///         default scene linear), "Linear Rec.2020" or "ACEScg"; use the scene's working space.
///     table_cache: keep a built lookup table in the per-user cache folder ($SPECTRAL_SKIN_CACHE_DIR, else
///         spectral-skin in the platform's cache folder: $XDG_CACHE_HOME or ~/.cache on Linux, ~/Library/Caches
///         on macOS, %LOCALAPPDATA% on Windows) and reuse it (as the CLI does); False always builds it afresh.
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
///     transport, streams: how the totals are computed, "adding_doubling" (the default) or "diffusion", and the
///         adding-doubling streams, as for :func:`evaluate` (a cached table is kept per choice).
///     surface: the surface reflection the specular maps stand in for, "paper" or "measured", as for
///         :func:`evaluate`; with "measured" the specular output also holds the Coat (maps when the oiliness varies).
///
/// Ctrl-C (KeyboardInterrupt, or any exception a Python signal handler raises) stops the call the same way: the
/// calling thread checks for signals every 0.1 s while the work runs, the rows or table nodes being computed are
/// finished (a node is about a millisecond) and the exception is raised; a table stopped part-way is not cached.
///
/// Returns:
///     A :class:`Maps`, read-only, which reads like a dict of the outputs asked for (an output not asked for is
///     absent; each is also an attribute, None when absent) and writes itself (``Maps.write``: one image, or a UDIM
///     tile set stacked top to bottom):
///     "albedo": float32 (H, W, 3), Principled Base Color for ``method`` (without "radius": the albedo), linear RGB
///     in ``working_space``;
///     "radius": float32 (H, W, 3), Principled Subsurface Radius x Subsurface Scale for ``method``, mm (with Radius
///     set to these values, Scale is 0.001 in a scene whose unit is the metre);
///     "specular": only when the oiliness varies, float32 (H, W): Principled Specular IOR Level per texel;
///     "coat_weight", "coat_roughness": only when the oiliness varies and ``surface="measured"``, float32 (H, W):
///     Principled Coat Weight and Coat Roughness per texel;
///     "specular_constants" (with the "specular" output): the specular inputs that are one value: when the oiliness
///     is one value everywhere (a float, or an array of one value), {"surface", "oiliness", "specular_ior_level",
///     "roughness", "ior", "coat_weight", "coat_roughness", "coat_ior", "beckmann_m", "directional_albedo_normal",
///     "hemispherical_albedo"} (as ``evaluate(...)["specular"]``); when it varies, the ones that do not depend on it:
///     {"surface", "roughness", "ior", "coat_ior", "beckmann_m"}, and for ``surface="paper"`` also "coat_weight" (0:
///     no Coat) and "coat_roughness" (Principled IOR and Coat IOR are 1.4 everywhere);
///     "report": what was done: {"crate_version", "width", "height", "method", "target" ({"blender", "engine",
///     "tested"}), "color_space", "strategy" ({"name":
///     "constant" | "distinct_tuples" | "table" | "exact" | "none" (neither Base Color nor radius asked for), with
///     its figures: "tuples"; "evaluations"; or
///     "resolution", "nodes", "from_cache", "build_seconds", "measured_error"}), "clamped" (one dict per parameter
///     with bad values: {"parameter", "nan", "infinite", "out_of_range", "first": [[x, y], ...]}),
///     "constant_parameters" (the names of the parameters, the four and the extended physiology, that are one value
///     everywhere), "constant_values" ({name: value} of those), "request" (accuracy, model and transport), "work" ({"texels", "evaluations",
///     "table_nodes_built", "table_lookups", "radius_fits", "specular_evaluations", "outputs": {"albedo",
///     "radius", "specular"}}: what was computed), "seconds" ({"read", "compute", "write", "total"})}.
///     The arrays are new and C-contiguous, handed to numpy without a copy and flagged read-only (numpy refuses to
///     write into them or to make them writeable again: ``np.array(a)`` is a writeable copy).
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
        epidermis_thickness_mm = None, baseline_absorption_scale = None, blood_oxygenation = None, method = "burley", outputs = None, exact = false, clamp = false, accuracy = "default", wavelength_step_nm = None,
        wavelength_placement = None,
        working_space = "Linear Rec.709", table_resolution = None, table_cache = true, blender = None,
        engine = "cycles", progress = None, boundaries = "paper", transport = "adding_doubling", streams = None,
        surface = None
    )
)]
#[allow(clippy::too_many_arguments)]
pub(super) fn maps_py<'py>(
    py: Python<'py>,
    params: Option<&Bound<'py, PyAny>>,
    melanin: Option<&Bound<'py, PyAny>>,
    melanin_blend: Option<&Bound<'py, PyAny>>,
    hemoglobin: Option<&Bound<'py, PyAny>>,
    oiliness: Option<&Bound<'py, PyAny>>,
    epidermis_thickness_mm: Option<&Bound<'py, PyAny>>,
    baseline_absorption_scale: Option<&Bound<'py, PyAny>>,
    blood_oxygenation: Option<&Bound<'py, PyAny>>,
    method: &str,
    outputs: Option<&Bound<'py, PyAny>>,
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
    transport: &str,
    streams: Option<&Bound<'py, PyAny>>,
    surface: Option<&str>,
) -> PyResult<MapsPy> {
    let start = Instant::now();
    let progress = Progress::from_arg("maps", progress)?;
    // Settings first: their errors come before any copy.
    let knobs = Knobs {
        wavelength_step_nm: real_arg("wavelength_step_nm", wavelength_step_nm)?,
        wavelength_placement,
        streams: streams_arg(streams)?,
        ..Knobs::material(accuracy, working_space, boundaries, target_from(blender, engine)?, transport)
    };
    let method = SubsurfaceMethod::from_name(method)?;
    knobs.target.method_entry(method)?;
    let settings = MapSettings {
        method,
        strategy: if exact { StrategyChoice::Exact } else { StrategyChoice::Auto },
        clamp,
        table: self::table_resolution(table_resolution)?,
        table_cache: if table_cache { crate::maps::lut::default_cache_dir() } else { None },
        request: Request { surface: surface_arg(surface)?, ..knobs.request(map_outputs(outputs)?)? },
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
    let keywords = [
        melanin,
        melanin_blend,
        hemoglobin,
        oiliness,
        epidermis_thickness_mm,
        baseline_absorption_scale,
        blood_oxygenation,
    ];
    let mut inputs: Vec<Option<MapInput<'py>>> = Vec::with_capacity(ALL_CHANNELS.len());
    for (name, obj) in ALL_CHANNELS.iter().zip(keywords) {
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
    for (name, input) in ALL_CHANNELS.iter().zip(&inputs) {
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
    crate::maps::io::check_texel_count("shapes", width, height)?;
    // Constants are checked here, with their own message; clamp=True leaves them to the check of the planes.
    if !clamp {
        for (c, input) in inputs.iter().enumerate() {
            if let Some(MapInput::Constant(v)) = input {
                let (lo, hi) = ALL_RANGES[c];
                if !(*v >= lo && *v <= hi) {
                    let name = ALL_CHANNELS[c];
                    let reason = format!("must be in [{lo}, {hi}]; got {v} (pass clamp=True to clamp it)");
                    return Err(invalid(name, reason));
                }
            }
        }
    }
    let mut planes = Vec::with_capacity(ALL_CHANNELS.len());
    for (c, input) in inputs.iter().enumerate() {
        planes.push(match (input, &params) {
            (Some(MapInput::Constant(v)), _) => Plane::Constant(*v as f32),
            (Some(MapInput::Array(a)), _) => Plane::Texels(a.plane(None)?),
            (None, Some(p)) if c < 4 => Plane::Texels(p.plane(Some(c))?),
            // The extended physiology defaults to the paper's values.
            (None, _) if c >= 4 => default_extended()[c - 4].clone(),
            (None, _) => return Err(internal("a parameter without a source")),
        });
    }
    let [p0, p1, p2, p3, e0, e1, e2]: [Plane; 7] = planes.try_into().map_err(|_| internal("not seven planes"))?;
    let mut image = ParamImage { width, height, planes: [p0, p1, p2, p3], extended: [e0, e1, e2], notes: Vec::new() };
    drop(params);
    drop(inputs);

    // Check, compute and interleave with the GIL released.
    struct Computed {
        base_color: Option<Vec<f32>>,
        radius_mm: Option<Vec<f32>>,
        specular: Option<SpecularOutput>,
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
        let base_color = result.base_color.take().map(|p| interleave(width, p));
        let radius_mm = result.radius_mm.take().map(|p| interleave(width, p));
        let specular = result.specular.take();
        let mut report = result.report;
        report.clamped = clamped;
        report.seconds.read = read;
        report.seconds.write = write.elapsed().as_secs_f64();
        Ok(Some(Computed { base_color, radius_mm, specular, report }))
    })?;
    let Some(computed) = computed else {
        return Err(progress.map(Progress::into_error).unwrap_or_else(|| internal("stopped without a progress hook")));
    };

    let (albedo, radius, surface, specular_constants) = {
        let rgb = |data: Option<Vec<f32>>| {
            data.map(|d| rgb_image(py, height, width, d).and_then(|a| frozen(a.as_any()).map(|()| a.unbind())))
                .transpose()
        };
        let (base_color, radius_mm) = (rgb(computed.base_color)?, rgb(computed.radius_mm)?);
        let plane = |texels: Vec<f32>| -> PyResult<Py<PyArray2<f32>>> {
            let array =
                PyArray::from_owned_array(py, Array2::from_shape_vec((height, width), texels).map_err(internal)?);
            frozen(array.as_any())?;
            Ok(array.unbind())
        };
        let (surface, constants) = match computed.specular {
            None => (Vec::new(), None),
            Some(SpecularOutput::Constant(constants)) => (Vec::new(), Some(constants)),
            Some(SpecularOutput::Map { specular_ior_level, coat, constants }) => {
                let [level, weight, roughness] = SURFACE_MAP_KINDS;
                let mut maps = vec![(level, plane(specular_ior_level)?)];
                if let Some(coat) = coat {
                    maps.push((weight, plane(coat.weight)?));
                    maps.push((roughness, plane(coat.roughness)?));
                }
                (maps, Some(constants))
            }
        };
        (base_color, radius_mm, surface, constants)
    };
    let mut report = computed.report;
    report.seconds.total = start.elapsed().as_secs_f64();
    Ok(MapsPy { height, width, albedo, radius, surface, specular_constants, report })
}

/// Flag a numpy array the core made read-only. Its memory belongs to the core's container (no writeable buffer), so
/// numpy also refuses to make it (or a view of it) writeable again: the array is frozen.
fn frozen(array: &Bound<'_, PyAny>) -> PyResult<()> {
    array.getattr("flags")?.setattr("writeable", false)
}

/// Whether numpy lets `array` be written into.
fn writeable(array: &Bound<'_, PyAny>) -> PyResult<bool> {
    array.getattr("flags")?.getattr("writeable")?.extract()
}

/// The keys of a :func:`maps` result that are not maps, after the maps ([`MAP_KINDS`] order) in the order the result
/// lists those present.
const CONSTANTS_KEY: &str = "specular_constants";
const REPORT_KEY: &str = "report";

/// The result of :func:`maps`: the texture maps of the outputs asked for, the specular constants and the report.
/// Read-only: its arrays are flagged not writeable (numpy refuses writes into them; copy one with ``np.array(a)``
/// to change it) and ``specular_constants`` and ``report`` are new dicts on each access. Each map has one name,
/// the same as the output that asks for it and the file it is written to (``albedo`` -> ``albedo.exr``).
///
/// Attributes (None when the output was not asked for):
///     albedo: float32 (H, W, 3), Principled Base Color (see :func:`maps`).
///     radius: float32 (H, W, 3), Principled Subsurface Radius x Subsurface Scale, mm.
///     specular: float32 (H, W), Principled Specular IOR Level per texel; None also when the oiliness is one value
///         everywhere (``specular_constants`` then holds the level).
///     coat_weight, coat_roughness: float32 (H, W), Principled Coat Weight and Coat Roughness per texel (the
///         ``measured`` surface with varying oiliness); None otherwise (``specular_constants`` then holds them).
///     specular_constants: the specular inputs that are one value (dict; see :func:`maps`).
///     report: what was done (dict; see :func:`maps`).
///     shape: (H, W).
///
/// It reads like a dict: ``result["albedo"]``, ``"radius" in result``,
/// ``result.keys()`` (those present, in the order above: an output not asked for is absent), ``result.get(key)``,
/// ``result.items()``, ``len(result)``, iteration over the keys, ``dict(result)``; it is a
/// ``collections.abc.Mapping``.
///
/// ``write(folder)`` writes its maps as EXRs with the core's writer, straight from its arrays (see ``Maps.write``).
#[pyclass(frozen, mapping, name = "Maps", module = "spectral_skin")]
pub(super) struct MapsPy {
    height: usize,
    width: usize,
    albedo: Option<Py<PyArray3<f32>>>,
    radius: Option<Py<PyArray3<f32>>>,
    /// The single-channel surface maps ([`SURFACE_MAP_KINDS`]) present, in that order.
    surface: Vec<(MapKind, Py<PyArray2<f32>>)>,
    /// The specular constants; with the surface maps (the oiliness varies) only those of `SPECULAR_CONSTANTS`
    /// (and for `paper` its Coat's) are shown.
    specular_constants: Option<SpecularParams>,
    report: crate::maps::MapReport,
}

impl MapsPy {
    /// The value of `key`, or None when the result has no such key.
    fn item<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Option<Bound<'py, PyAny>>> {
        Ok(if key == ALBEDO_MAP.name {
            self.albedo.as_ref().map(|a| a.bind(py).clone().into_any())
        } else if key == RADIUS_MAP.name {
            self.radius.as_ref().map(|a| a.bind(py).clone().into_any())
        } else if key == CONSTANTS_KEY {
            self.specular_dict(py)?
        } else if key == REPORT_KEY {
            Some(self.report_dict(py)?)
        } else {
            self.surface_map(py, key).map(Bound::into_any)
        })
    }

    /// The surface map named `key` (a [`SURFACE_MAP_KINDS`] name), if held.
    fn surface_map<'py>(&self, py: Python<'py>, key: &str) -> Option<Bound<'py, PyArray2<f32>>> {
        self.surface.iter().find(|(k, _)| k.name == key).map(|(_, a)| a.bind(py).clone())
    }

    /// The keys present: the maps in [`MAP_KINDS`] order, then "specular_constants" and "report".
    fn present(&self) -> Vec<&'static str> {
        let mut keys: Vec<&'static str> = MAP_KINDS
            .iter()
            .map(|k| k.name)
            .filter(|&name| match name {
                n if n == ALBEDO_MAP.name => self.albedo.is_some(),
                n if n == RADIUS_MAP.name => self.radius.is_some(),
                n => self.surface.iter().any(|(k, _)| k.name == n),
            })
            .collect();
        if self.specular_constants.is_some() {
            keys.push(CONSTANTS_KEY);
        }
        keys.push(REPORT_KEY);
        keys
    }

    fn specular_dict<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let Some(constants) = &self.specular_constants else {
            return Ok(None);
        };
        let all = to_py(py, constants)?;
        if self.surface.is_empty() {
            return Ok(Some(all));
        }
        // Only the constants that do not depend on the oiliness (surface::principled::surface_inputs).
        let kept = PyDict::new(py);
        let paper_coat: &[&str] = if constants.surface.is_paper() { &PAPER_COAT_CONSTANTS } else { &[] };
        for key in SPECULAR_CONSTANTS.iter().chain(paper_coat) {
            kept.set_item(key, all.get_item(key)?)?;
        }
        Ok(Some(kept.into_any()))
    }

    fn report_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let report = to_py(py, &self.report)?;
        // JSON has no infinity: serde_json writes a semi-infinite dermis as null. Python floats do.
        report
            .get_item("request")?
            .get_item("model")?
            .set_item("dermis_thickness_mm", self.report.request.model.dermis_thickness_mm)?;
        Ok(report)
    }

    /// Write the held maps, borrowed from the arrays (read-only, C-contiguous float32: the core made them).
    fn write_as<'py>(
        &self,
        py: Python<'py>,
        folder: &Path,
        prefix: Option<&str>,
        exr: ExrOptions,
        tiling: Tiling,
    ) -> PyResult<Bound<'py, PyDict>> {
        let base_color = self.albedo.as_ref().map(|a| a.bind(py).try_readonly()).transpose().map_err(internal)?;
        let radius_mm = self.radius.as_ref().map(|a| a.bind(py).try_readonly()).transpose().map_err(internal)?;
        let surface: Vec<(MapKind, _)> = self
            .surface
            .iter()
            .map(|(k, a)| a.bind(py).try_readonly().map(|r| (*k, r)))
            .collect::<Result<_, _>>()
            .map_err(internal)?;
        let images = MapImages::new(
            self.height,
            self.width,
            base_color.as_ref().map(|a| a.as_slice()).transpose().map_err(internal)?,
            radius_mm.as_ref().map(|a| a.as_slice()).transpose().map_err(internal)?,
            surface.iter().map(|(k, a)| a.as_slice().map(|s| (*k, s))).collect::<Result<_, _>>().map_err(internal)?,
        )?;
        write_images(py, &images, folder, prefix, exr, tiling)
    }
}

#[pymethods]
impl MapsPy {
    /// float32 (H, W, 3), Principled Base Color (read-only); None without the "albedo" output.
    #[getter]
    fn albedo<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray3<f32>>> {
        self.albedo.as_ref().map(|a| a.bind(py).clone())
    }

    /// float32 (H, W, 3), Principled Subsurface Radius x Subsurface Scale, mm (read-only); None without the "radius"
    /// output.
    #[getter]
    fn radius<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray3<f32>>> {
        self.radius.as_ref().map(|a| a.bind(py).clone())
    }

    /// float32 (H, W), Principled Specular IOR Level per texel (read-only); None without the "specular" output or
    /// when the oiliness is one value everywhere.
    #[getter]
    fn specular<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f32>>> {
        self.surface_map(py, SURFACE_MAP_KINDS[0].name)
    }

    /// float32 (H, W), Principled Coat Weight per texel (read-only); None unless the oiliness varies under the
    /// "measured" surface.
    #[getter]
    fn coat_weight<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f32>>> {
        self.surface_map(py, SURFACE_MAP_KINDS[1].name)
    }

    /// float32 (H, W), Principled Coat Roughness per texel (read-only); as ``coat_weight``.
    #[getter]
    fn coat_roughness<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f32>>> {
        self.surface_map(py, SURFACE_MAP_KINDS[2].name)
    }

    /// The specular inputs that are one value (a new dict; see :func:`maps`); None without the "specular" output.
    #[getter]
    fn specular_constants<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.specular_dict(py)
    }

    /// What was done (a new dict; see :func:`maps`).
    #[getter]
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.report_dict(py)
    }

    /// (H, W): the maps' height and width.
    #[getter]
    fn shape(&self) -> (usize, usize) {
        (self.height, self.width)
    }

    fn __getitem__<'py>(&self, py: Python<'py>, key: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let found = match key.cast::<PyString>() {
            Ok(k) => self.item(py, k.to_str()?)?,
            Err(_) => None,
        };
        found.ok_or_else(|| PyKeyError::new_err(key.clone().unbind()))
    }

    fn __contains__(&self, key: &Bound<'_, PyAny>) -> PyResult<bool> {
        Ok(match key.cast::<PyString>() {
            Ok(k) => self.present().contains(&k.to_str()?),
            Err(_) => false,
        })
    }

    fn __len__(&self) -> usize {
        self.present().len()
    }

    fn __iter__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyIterator>> {
        PyList::new(py, self.present())?.try_iter()
    }

    /// The keys present, in the order "albedo", "radius", "specular", "coat_weight", "coat_roughness",
    /// "specular_constants", "report" (a ``KeysView``, as a dict's).
    fn keys<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        mapping_view(slf, "KeysView")
    }

    /// The values of ``keys()`` (a ``ValuesView``).
    fn values<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        mapping_view(slf, "ValuesView")
    }

    /// The (key, value) pairs of ``keys()`` (an ``ItemsView``).
    fn items<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        mapping_view(slf, "ItemsView")
    }

    /// ``result[key]`` if present, else ``default``.
    #[pyo3(signature = (key, default = None))]
    fn get<'py>(
        &self,
        py: Python<'py>,
        key: &Bound<'py, PyAny>,
        default: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Option<Bound<'py, PyAny>>> {
        let found = match key.cast::<PyString>() {
            Ok(k) => self.item(py, k.to_str()?)?,
            Err(_) => None,
        };
        Ok(found.or(default))
    }

    /// Write the maps this result holds as float EXRs with the core's writer (that of ``spectral-skin maps``),
    /// straight from its arrays, in ``folder`` (created if missing): ``albedo`` -> ``albedo.exr`` (channels R, G, B),
    /// ``radius`` -> ``radius.exr`` (R, G, B), ``specular`` -> ``specular.exr`` (Y), ``coat_weight`` ->
    /// ``coat_weight.exr`` (Y), ``coat_roughness`` -> ``coat_roughness.exr`` (Y); the file names and everything else
    /// as :func:`write_maps`.
    ///
    /// Arguments:
    ///     folder: the output folder.
    ///     prefix: None, or a file-name part prepended with "_" to each file name (no path separator).
    ///     precision: "half" (the default) or "float"; compression: "auto" (the default), "piz", "zip", "zips",
    ///         "rle" or "none" (as :func:`write_maps`).
    ///     tiles: None for one image; or a UDIM tile set stacked top to bottom: [(tile, rows), ...] in stacking
    ///         order, each tile 1001 to 2000 and given once, each at least one row, the rows adding up to H. Each
    ///         tile's rows become that tile's files (``albedo.1001.exr``, ...), which Blender loads as
    ///         ``albedo.<UDIM>.exr``.
    ///
    /// Every file (of every tile) is written as a temporary file in ``folder`` first and all are renamed into place
    /// together once all are written, so a failure leaves the existing files as they were. Then the files of an
    /// earlier write with the same prefix (and tiles) that this one did not write are removed.
    ///
    /// Returns:
    ///     {map name: path}, for the maps written; for a tile set the path holds ``<UDIM>``
    ///     (``<folder>/albedo.<UDIM>.exr``).
    ///
    /// Raises:
    ///     SpectralSkinError: a bad prefix, precision or compression; ``tiles`` that are not such pairs (the message
    ///         names ``tiles``, what is wrong and what is expected).
    ///     SpectralSkinIOError: a file that cannot be written (the message names it); nothing is changed.
    #[pyo3(signature = (folder, prefix = None, precision = "half", compression = "auto", tiles = None))]
    fn write<'py>(
        &self,
        py: Python<'py>,
        folder: PathBuf,
        prefix: Option<&str>,
        precision: &str,
        compression: &str,
        tiles: Option<Vec<(i64, i64)>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let exr = write_options(prefix, precision, compression)?;
        let tiling = Tiling::of(None, tiles, self.height)?;
        self.write_as(py, &folder, prefix, exr, tiling)
    }

    fn __repr__(&self) -> String {
        let strategy = serde_json::to_value(&self.report.strategy)
            .ok()
            .and_then(|v| v.get("name").and_then(|n| n.as_str().map(str::to_string)))
            .unwrap_or_default();
        let keys: Vec<&str> = self.present().into_iter().filter(|k| *k != "report").collect();
        format!("Maps({} x {}, {}; strategy {strategy})", self.width, self.height, keys.join(", "))
    }
}

/// A ``collections.abc`` view (`kind`: "KeysView", "ValuesView" or "ItemsView") of a result, as a dict's.
fn mapping_view<'py>(maps: &Bound<'py, MapsPy>, kind: &str) -> PyResult<Bound<'py, PyAny>> {
    maps.py().import("collections.abc")?.getattr(kind)?.call1((maps,))
}

/// How a write lays the rows out in files.
enum Tiling {
    /// One image: the untiled files, or (`Some`) the files of that one UDIM tile.
    One(Option<u32>),
    /// A UDIM tile set stacked top to bottom: each tile's rows its own files.
    Set(TileRows),
}

impl Tiling {
    /// From `tile` (write_maps' one tile) and `tiles` (a stacked tile set of an image `height` rows high).
    fn of(tile: Option<i64>, tiles: Option<Vec<(i64, i64)>>, height: usize) -> PyResult<Tiling> {
        Ok(match (tile, tiles) {
            (Some(_), Some(_)) => {
                return Err(invalid("tiles", "give tile (one tile's image) or tiles (a stacked tile set), not both"))
            }
            (Some(t), None) => Tiling::One(Some(check_tile("tile", t)?)),
            (None, Some(t)) => Tiling::Set(stacked_tile_rows("tiles", &t, height)?),
            (None, None) => Tiling::One(None),
        })
    }
}

/// The EXR options of a write, after checking the prefix.
fn write_options(prefix: Option<&str>, precision: &str, compression: &str) -> PyResult<ExrOptions> {
    let exr = ExrOptions {
        precision: by_name("precision", precision, &ALL_PRECISIONS)?,
        compression: by_name("compression", compression, &ALL_COMPRESSIONS)?,
    };
    check_prefix(prefix)?;
    Ok(exr)
}

/// The maps one write puts in files, row-major float32 texels: (H, W, 3) interleaved Base Color and radius, (H, W)
/// surface maps (Specular IOR Level, Coat Weight, Coat Roughness). Borrowed: from a [`MapsPy`]'s arrays, or from (or
/// gathered out of) the arrays given to `write_maps`.
struct MapImages<'a> {
    height: usize,
    width: usize,
    base_color: Option<&'a [f32]>,
    radius_mm: Option<&'a [f32]>,
    surface: Vec<(MapKind, &'a [f32])>,
}

impl<'a> MapImages<'a> {
    /// The images, each checked to hold (H, W, channels) values.
    fn new(
        height: usize,
        width: usize,
        base_color: Option<&'a [f32]>,
        radius_mm: Option<&'a [f32]>,
        surface: Vec<(MapKind, &'a [f32])>,
    ) -> PyResult<Self> {
        let sized = [(base_color, 3), (radius_mm, 3)].into_iter().chain(surface.iter().map(|&(_, s)| (Some(s), 1)));
        for (texels, channels) in sized {
            if texels.is_some_and(|t| t.len() != height * width * channels) {
                return Err(internal("an image whose size is not its shape's"));
            }
        }
        Ok(MapImages { height, width, base_color, radius_mm, surface })
    }
}

/// Interleaved RGB rows (`width` texels each) to three planes, rows in parallel.
fn deinterleave(width: usize, texels: &[f32]) -> [Vec<f32>; 3] {
    let n = texels.len() / 3;
    let (mut p0, mut p1, mut p2) = (vec![0f32; n], vec![0f32; n], vec![0f32; n]);
    p0.par_chunks_mut(width)
        .zip(p1.par_chunks_mut(width))
        .zip(p2.par_chunks_mut(width))
        .zip(texels.par_chunks(3 * width))
        .for_each(|(((r0, r1), r2), row)| {
            for (x, texel) in row.chunks_exact(3).enumerate() {
                r0[x] = texel[0];
                r1[x] = texel[1];
                r2[x] = texel[2];
            }
        });
    [p0, p1, p2]
}

/// Write `images` as laid out by `tiling` with the core's writer, the GIL released: every file of every tile
/// staged, then all committed together ([`commit_map_files`], which also removes this prefix's files of those tiles
/// that this write did not write). Returns {"albedo" | "radius" | "specular": path} of the maps written (for a tile
/// set, the path with `<UDIM>`).
fn write_images<'py>(
    py: Python<'py>,
    images: &MapImages<'_>,
    folder: &Path,
    prefix: Option<&str>,
    exr: ExrOptions,
    tiling: Tiling,
) -> PyResult<Bound<'py, PyDict>> {
    let parts: Vec<(Option<u32>, usize, usize)> = match &tiling {
        Tiling::One(tile) => vec![(*tile, 0, images.height)],
        Tiling::Set(rows) => rows.iter().map(|&(tile, first, rows)| (Some(tile), first, rows)).collect(),
    };
    detached(py, || {
        let w = images.width;
        let mut staged = Vec::new();
        for &(tile, first, rows) in &parts {
            // One tile's planes at a time: the writer reads planes; they are dropped once the tile is staged.
            let rgb =
                |texels: Option<&[f32]>| texels.map(|t| deinterleave(w, &t[3 * w * first..3 * w * (first + rows)]));
            let (base_color, radius_mm) = (rgb(images.base_color), rgb(images.radius_mm));
            let files = MapFiles {
                width: w,
                height: rows,
                base_color: base_color.as_ref(),
                radius_mm: radius_mm.as_ref(),
                surface: images.surface.iter().map(|&(k, s)| (k, &s[w * first..w * (first + rows)])).collect(),
            };
            staged.extend(stage_map_files(folder, prefix, tile, &files, exr)?);
        }
        let tiles: Vec<Option<u32>> = parts.iter().map(|p| p.0).collect();
        commit_map_files(folder, prefix, &tiles, staged)
    })?;
    let dict = PyDict::new(py);
    for kind in &MAP_KINDS {
        let (key, file) = (kind.name, kind.file);
        let present = match key {
            k if k == ALBEDO_MAP.name => images.base_color.is_some(),
            k if k == RADIUS_MAP.name => images.radius_mm.is_some(),
            k => images.surface.iter().any(|(s, _)| s.name == k),
        };
        if present {
            let name = match &tiling {
                Tiling::One(tile) => tile_output_name(prefix, *tile, file),
                Tiling::Set(_) => tile_set_file_name(&output_name(prefix, file)),
            };
            dict.set_item(key, folder.join(name))?;
        }
    }
    Ok(dict)
}

/// An image of `write_maps`' result: its size and its channels as row-major planes.
pub(super) struct ResultImage {
    pub(super) height: usize,
    pub(super) width: usize,
    pub(super) planes: Vec<Vec<f32>>,
}

/// One image of a result mapping, checked: a float array of `channels` channels ((H, W, channels), or (H, W) for
/// one channel), with its shape. None when the key is absent or None.
fn result_array<'py>(
    result: &Bound<'py, PyAny>,
    key: &str,
    channels: usize,
) -> PyResult<Option<(FloatArray<'py>, Vec<usize>)>> {
    let obj = match result.get_item(key) {
        Ok(obj) if !obj.is_none() => obj,
        Ok(_) => return Ok(None),
        Err(e) if e.is_instance_of::<PyKeyError>(result.py()) => return Ok(None),
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
    Ok(Some((array, shape)))
}

/// One image of `write_maps`' result as row-major planes: `channels` of them (an (H, W, channels) array, or (H, W)
/// for one channel). None when the key is absent or None.
pub(super) fn result_planes(result: &Bound<'_, PyAny>, key: &str, channels: usize) -> PyResult<Option<ResultImage>> {
    let Some((array, shape)) = result_array(result, key, channels)? else {
        return Ok(None);
    };
    let planes = if channels == 1 {
        vec![array.plane(None)?]
    } else {
        (0..channels).map(|c| array.plane(Some(c))).collect::<PyResult<_>>()?
    };
    Ok(Some(ResultImage { height: shape[0], width: shape[1], planes }))
}

/// The texels of an image given to `write_maps`, row-major: a read-only C-contiguous float32 array (a :func:`maps`
/// result's) is read in place; any other is gathered into a float32 copy first (under the GIL, so nothing can change
/// it while the GIL is released for the write).
enum Texels<'py> {
    InPlace(PyReadonlyArrayDyn<'py, f32>),
    Copied(Vec<f32>),
}

impl<'py> Texels<'py> {
    fn of(array: FloatArray<'py>) -> PyResult<Self> {
        let unreadable = |e: numpy::BorrowError| PyTypeError::new_err(format!("cannot read the array: {e}"));
        Ok(match array {
            FloatArray::F32(a) if a.is_c_contiguous() && !writeable(a.as_any())? => {
                Texels::InPlace(a.try_readonly().map_err(unreadable)?)
            }
            FloatArray::F32(a) => {
                Texels::Copied(a.try_readonly().map_err(unreadable)?.as_array().iter().copied().collect())
            }
            FloatArray::F64(a) => {
                Texels::Copied(a.try_readonly().map_err(unreadable)?.as_array().iter().map(|&v| v as f32).collect())
            }
        })
    }

    fn as_slice(&self) -> PyResult<&[f32]> {
        match self {
            Texels::InPlace(a) => a.as_slice().map_err(internal),
            Texels::Copied(v) => Ok(v),
        }
    }
}

/// Write the images of a :func:`maps` result as float EXRs, with the core's writer (that of ``spectral-skin maps``).
///
/// Each image present (and not None) becomes one file in ``folder`` (created if missing): "albedo" -> ``albedo.exr``
/// (channels R, G, B), "radius" -> ``radius.exr`` (R, G, B), "specular" -> ``specular.exr`` (Y), "coat_weight" and
/// "coat_roughness" -> ``coat_weight.exr`` and ``coat_roughness.exr`` (Y); with ``prefix``,
/// ``<prefix>_albedo.exr`` etc.; with ``tile`` (a UDIM tile number), ``albedo.1001.exr`` etc., one tile of a tile set Blender loads as ``albedo.<UDIM>.exr``; with ``tiles``, a tile
/// set stacked top to bottom, each tile's rows as that tile's files. Row 0 at the top; ``precision`` and
/// ``compression`` as the CLI's ``--precision`` and ``--compression``. The files (of every tile) are written as
/// temporary files in ``folder`` and renamed into place together once all are written, so a failure leaves the
/// existing files as they were. Then the files of an earlier write with the same prefix (and tiles) that this one
/// did not write (any of those files, and ``skin_maps.json``) are removed, so the folder
/// holds exactly this result's maps. No sidecar is written: the report is in the result.
///
/// A :class:`Maps` is written from its own arrays (as ``result.write(...)``). Read-only C-contiguous float32 arrays
/// (a :class:`Maps`' arrays, or slices of rows of them) are read in place; other arrays are copied (float64 rounded
/// to float32) first.
///
/// Arguments:
///     result: a :class:`Maps` (the result of :func:`maps`), or a mapping with any of "albedo" (H, W, 3), "radius"
///         (H, W, 3, mm), "specular", "coat_weight" and "coat_roughness" (H, W), float32 or float64 numpy arrays
///         (float64 is rounded to float32);
///         other keys are ignored.
///     folder: the output folder.
///     prefix: None, or a file-name part prepended with "_" to each file name (no path separator).
///     precision: "half" (16-bit, within 0.049 % of each value; the default) or "float" (32-bit).
///     compression: "auto" (the default: ZIPS for half, PIZ for float, or none for a file that would shrink by under
///         25 %), "piz", "zip", "zips", "rle" or "none".
///     tile: None, or the UDIM tile (1001 to 2000) the images are, written into each file name.
///     tiles: None, or the images as a UDIM tile set stacked top to bottom, as ``Maps.write``'s ``tiles``:
///         [(tile, rows), ...], each tile 1001 to 2000 given once, the rows adding up to H. Not with ``tile``.
///
/// Returns:
///     {map name ("albedo", "radius", "specular", "coat_weight", "coat_roughness"): path of the file written}, for
///     the images written; for ``tiles`` the path
///     holds ``<UDIM>``.
///
/// Raises:
///     SpectralSkinError: no image in ``result``, images whose (H, W) differ, an image of the wrong shape, a prefix
///         that is empty or holds a path separator, a tile out of range, ``tiles`` that are not such pairs (the
///         message names ``tiles``), both ``tile`` and ``tiles``.
///     SpectralSkinIOError: a file that cannot be written (the message names it).
///     TypeError: an image that is not a float32 or float64 numpy array.
#[pyfunction]
#[pyo3(
    name = "write_maps",
    signature = (result, folder, prefix = None, precision = "half", compression = "auto", tile = None, tiles = None)
)]
#[allow(clippy::too_many_arguments)]
pub(super) fn write_maps_py<'py>(
    py: Python<'py>,
    result: &Bound<'py, PyAny>,
    folder: PathBuf,
    prefix: Option<&str>,
    precision: &str,
    compression: &str,
    tile: Option<i64>,
    tiles: Option<Vec<(i64, i64)>>,
) -> PyResult<Bound<'py, PyDict>> {
    if let Some(t) = tile {
        check_tile("tile", t)?;
    }
    let exr = write_options(prefix, precision, compression)?;
    if let Ok(maps) = result.cast::<MapsPy>() {
        let maps = maps.get();
        return maps.write_as(py, &folder, prefix, exr, Tiling::of(tile, tiles, maps.height)?);
    }
    let mut images = Vec::with_capacity(MAP_KINDS.len());
    for kind in &MAP_KINDS {
        let key = kind.name;
        images.push(result_array(result, key, kind.channels.len())?.map(|(a, shape)| (key, shape, a)));
    }
    let sizes: Vec<(&str, usize, usize)> = images.iter().flatten().map(|(key, s, _)| (*key, s[0], s[1])).collect();
    let Some(&(_, height, width)) = sizes.first() else {
        let names: Vec<&str> = MAP_KINDS.iter().map(|k| k.name).collect();
        return Err(invalid("result", format!("holds none of {}: nothing to write", names.join(", "))));
    };
    if sizes.iter().any(|&(_, h, w)| (h, w) != (height, width)) {
        let listed: Vec<String> = sizes.iter().map(|(n, h, w)| format!("{n} ({h}, {w})")).collect();
        return Err(invalid("result", format!("the images must agree in (H, W); got {}", listed.join(", "))));
    }
    let tiling = Tiling::of(tile, tiles, height)?;
    let texels: Vec<Option<Texels>> =
        images.into_iter().map(|image| image.map(|(_, _, a)| Texels::of(a)).transpose()).collect::<PyResult<_>>()?;
    let slice = |i: usize| texels[i].as_ref().map(Texels::as_slice).transpose();
    let mut surface = Vec::new();
    for (i, kind) in MAP_KINDS.iter().enumerate().skip(2) {
        if let Some(s) = slice(i)? {
            surface.push((*kind, s));
        }
    }
    let images = MapImages::new(height, width, slice(0)?, slice(1)?, surface)?;
    write_images(py, &images, &folder, prefix, exr, tiling)
}

/// The maps `maps(outputs=...)` asks for: names among the material outputs ("albedo", "radius", "specular"), at
/// least one; None is all three.
fn map_outputs(outputs: Option<&Bound<'_, PyAny>>) -> PyResult<Outputs> {
    let parsed = parse_outputs(outputs)?;
    let material =
        Outputs { albedo: parsed.albedo, radius: parsed.radius, specular: parsed.specular, ..Outputs::default() };
    if parsed != material || material == Outputs::default() {
        return Err(invalid(
            "outputs",
            format!("maps computes {}: give one or more of them (or None for all)", material_outputs().join(", ")),
        ));
    }
    Ok(material)
}
