//! `maps`, `read_parameter_map` and `map_kinds`: texture maps from parameter maps, with progress and cancelling.
//! The binding translates its arguments into the core's request ([`crate::maps::request::ParamRequest`], which owns
//! the input rules) and settings, makes one call with the GIL released, and hands the result to [`MapsPy`].

use std::sync::atomic::AtomicBool;
use std::time::Instant;

use numpy::ndarray::Array2;
use numpy::PyArray;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList, PyString};

use crate::color::WavelengthPlacement;
use crate::evaluate::Outputs;
use crate::maps::io::{read_params, ParamInputs, ParamSource, Plane, ALL_CHANNELS, EXTENDED_CHANNELS, PARAM_CHANNELS};
use crate::maps::kinds::MAP_KINDS;
use crate::maps::lut::TableResolution;
use crate::maps::pipeline::{check_planes, compute_maps_cancellable};
use crate::maps::request::{Combined, ParamRequest, Source, Texels};
use crate::maps::{MapSettings, StrategyChoice};
use crate::surface::lobes::SurfaceModel;

use super::args::{model_of, named, streams_of, Choice, Knobs, Model, ParamArgs, Streams};
use super::convert::{
    count_sequence, float_array, interleave, is_boolean, material_outputs, parse_outputs, real_arg, serde_name,
    shape_text, target_from,
};
use super::detach::{detached, detached_interruptible};
use super::errors::{internal, invalid, warn_notes};
use super::maps_result::{Computed, MapsPy};
use super::progress::Progress;

/// What `params` of `maps` must be, for messages.
const PARAMS_ARRAY: &str = "a float32 (H, W, 4) numpy array (channels melanin, melanin_blend, hemoglobin, oiliness)";
/// What a per-parameter keyword of `maps` must be, for messages.
const PARAM_ARRAY: &str = "a float32 (H, W) numpy array or a float";

/// A per-parameter keyword of `maps` as the core's source: an (H, W) array's texels (copied once into float32) or
/// a number. Anything else is a TypeError naming the keyword.
fn map_source(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Source> {
    if let Some(array) = float_array(name, obj, 2, PARAM_ARRAY)? {
        let shape = array.shape();
        return Ok(Source::Texels(Texels { width: shape[1], height: shape[0], values: array.plane(None)? }));
    }
    let type_error = || {
        let type_name = obj.get_type().name().map(|n| n.to_string()).unwrap_or_default();
        PyTypeError::new_err(format!("{name} must be {PARAM_ARRAY}; got {type_name}"))
    };
    if obj.is_instance_of::<PyString>() || obj.is_instance_of::<PyBytes>() || is_boolean(obj) {
        return Err(type_error());
    }
    obj.extract::<f64>().map(Source::Constant).map_err(|_| type_error())
}

/// `params` of `maps` as the core's four-channel input: its channels copied once into float32 planes, except those
/// a keyword of their own replaces (`given`, in the parameters' order).
fn combined_texels(obj: &Bound<'_, PyAny>, given: &[bool]) -> PyResult<Combined> {
    let array = float_array("params", obj, 3, PARAMS_ARRAY)?
        .ok_or_else(|| PyTypeError::new_err(format!("params must be {PARAMS_ARRAY} or None")))?;
    let shape = array.shape();
    if shape[2] != PARAM_CHANNELS.len() {
        return Err(invalid("params", format!("must be {PARAMS_ARRAY}; got shape {}", shape_text(&shape))));
    }
    let mut planes = [None, None, None, None];
    for (c, plane) in planes.iter_mut().enumerate() {
        if !given[c] {
            *plane = Some(array.plane(Some(c))?);
        }
    }
    Ok(Combined::Texels { width: shape[1], height: shape[0], planes })
}

/// The sources `maps` was given, translated into the core's request: `params`' channels and each keyword's array or
/// number. The rules (each of the four given, shapes that agree, constants in range) are the request's.
fn param_request(params: Option<&Bound<'_, PyAny>>, keywords: &ParamArgs<'_, '_>) -> PyResult<ParamRequest> {
    let combined = params.map(|obj| combined_texels(obj, &keywords.given())).transpose()?;
    keywords.map_request(ParamRequest::new(combined), map_source)
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

/// The kinds of texture map :func:`maps` computes and :func:`write_maps` writes, in the order results list them: each
/// one's name (the key of a :class:`Maps` and of ``write_maps``' result, and the file stem), file, channels and unit,
/// the Principled BSDF input it feeds, the colour space to load it in, and the output that asks for it.
///
/// Returns:
///     [{"name": "albedo", "file": "albedo.exr", "channels": ["R", "G", "B"], "unit": "" (dimensionless) or "mm",
///     "principled_input": "Base Color", "color_space": None (the working space the maps were computed in) or
///     "Non-Color", "output": the ``outputs=`` name that computes it ("albedo", "radius" or "specular")}, ...]: albedo,
///     radius, specular, coat_weight, coat_roughness. The specular and coat maps exist only where the oiliness
///     varies (else ``specular_constants`` hold their values), the coat maps only with ``surface="measured"``.
#[pyfunction]
#[pyo3(name = "map_kinds")]
pub(super) fn map_kinds_py(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let all = PyList::empty(py);
    for kind in MAP_KINDS {
        let d = PyDict::new(py);
        d.set_item("name", kind.name)?;
        d.set_item("file", kind.file)?;
        d.set_item("channels", kind.channels.to_vec())?;
        d.set_item("unit", kind.unit)?;
        d.set_item("principled_input", kind.principled_input)?;
        d.set_item("color_space", kind.color_space)?;
        d.set_item("output", serde_name(&kind.output))?;
        all.append(d)?;
    }
    Ok(all)
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
///     model: the model's options, one set for the whole map, as for :func:`evaluate` (a cached table is kept per
///         set); None: DJ2006's model.
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
///     "report": what was done: {"crate_version", "model_version", "width", "height", "method", "target" ({"blender", "engine",
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
        epidermis_thickness_mm = None, baseline_absorption_scale = None, blood_oxygenation = None, method = "burley",
        outputs = None, exact = false, clamp = false, accuracy = "default", wavelength_step_nm = None,
        wavelength_placement = None, working_space = "Linear Rec.709", table_resolution = None, table_cache = true,
        blender = None, engine = "cycles", progress = None, boundaries = "paper", transport = "adding_doubling",
        streams = None, surface = None, model = None
    )
)]
#[allow(clippy::too_many_arguments)] // the keywords of the Python function
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
    wavelength_placement: Option<Choice<WavelengthPlacement>>,
    working_space: &str,
    table_resolution: Option<&Bound<'py, PyAny>>,
    table_cache: bool,
    blender: Option<&Bound<'py, PyAny>>,
    engine: &str,
    progress: Option<Bound<'py, PyAny>>,
    boundaries: &str,
    transport: &str,
    streams: Option<Streams>,
    surface: Option<Choice<SurfaceModel>>,
    model: Option<Model>,
) -> PyResult<MapsPy> {
    let start = Instant::now();
    let progress = Progress::from_arg("maps", progress)?;
    // Settings first: their errors come before any copy.
    let knobs = Knobs {
        accuracy: named(accuracy)?,
        wavelength_step_nm: real_arg("wavelength_step_nm", wavelength_step_nm)?,
        wavelength_placement: wavelength_placement.map(|c| c.0),
        working_space: named(working_space)?,
        target: target_from(blender, engine)?,
        boundaries: named(boundaries)?,
        transport: named(transport)?,
        streams: streams_of(streams),
        surface: surface.map(|c| c.0).unwrap_or_default(),
        model: model_of(model),
        ..Knobs::default()
    };
    let settings = MapSettings {
        method: knobs.target.method_entry(named(method)?)?.method,
        strategy: if exact { StrategyChoice::Exact } else { StrategyChoice::Auto },
        clamp,
        table: self::table_resolution(table_resolution)?,
        table_cache: if table_cache { crate::maps::lut::default_cache_dir() } else { None },
        request: knobs.request(map_outputs(outputs)?)?,
        ..MapSettings::default()
    };
    let sources = ParamArgs::new(
        [melanin, melanin_blend, hemoglobin, oiliness],
        [epidermis_thickness_mm, baseline_absorption_scale, blood_oxygenation],
    );
    let request = param_request(params, &sources)?;
    let computed = compute(py, request, &settings, progress, start)?;
    MapsPy::of(py, computed, start)
}

/// Read `request`'s planes, check them, compute the maps with `settings` and interleave Base Color and radius, the
/// GIL released. Ctrl-C (and the progress callback's False or exception) stops the work through one flag; then the
/// callback's answer (or exception), or KeyboardInterrupt, is what the caller sees.
fn compute(
    py: Python<'_>,
    request: ParamRequest,
    settings: &MapSettings,
    progress: Option<Progress>,
    start: Instant,
) -> PyResult<Computed> {
    let hook = progress.as_ref();
    let own_flag = AtomicBool::new(false);
    let cancel = hook.map_or(&own_flag, |h| &h.stopped);
    let computed = detached_interruptible(py, cancel, move || {
        let mut image = request.into_image(settings.clamp)?;
        let clamped = check_planes(&mut image, settings.clamp)?;
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
        let computed = compute_maps_cancellable(&image, settings, progress, cancel);
        drop(image);
        // A stopped table build is an error; the callback's answer (or exception) is what the caller sees.
        if hook.is_some_and(Progress::stopped) {
            return Ok(None);
        }
        let mut result = computed?;
        let write = Instant::now();
        let (height, width) = (result.height, result.width);
        let base_color = result.base_color.take().map(|p| interleave(width, p));
        let radius_mm = result.radius_mm.take().map(|p| interleave(width, p));
        let mut report = result.report;
        report.clamped = clamped;
        report.seconds.read = read;
        report.seconds.write = write.elapsed().as_secs_f64();
        Ok(Some(Computed { height, width, base_color, radius_mm, specular: result.specular.take(), report }))
    })?;
    computed.ok_or_else(|| {
        progress.map(Progress::into_error).unwrap_or_else(|| internal("stopped without a progress hook"))
    })
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
