//! `fit_albedo` and `fit_albedo_map`: the parameters that reproduce an albedo colour or texture
//! (src/inverse/albedo.rs).

use numpy::{PyArray1, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::color::ALL_WORKING_SPACES;
use crate::inverse::albedo::{fit_albedo_cancellable, AlbedoFitOptions};
use crate::inverse::albedo_maps::{
    fit_albedo_tiles_with_progress, AlbedoMapFit, AlbedoTile, EpidermisThickness, TextureFit,
};
use crate::skin::params::EXTENDED_PARAMS;
use crate::transport::ExactTotals;

use super::convert::{
    by_name, float_array, real_arg, real_vector, shape_text, streams_arg, to_py, transport_arg, FloatArray,
};
use super::detach::{detached, detached_interruptible};
use super::errors::{internal, invalid, SpectralSkinWarning};
use super::progress::Progress;

/// The options from the keyword arguments (None: the defaults of src/inverse/albedo.rs).
#[allow(clippy::too_many_arguments)]
fn options_from(
    working_space: &str,
    extended: [Option<&Bound<'_, PyAny>>; 3],
    oiliness: Option<&Bound<'_, PyAny>>,
    melanin_blend_prior: Option<&Bound<'_, PyAny>>,
    prior_weight: Option<&Bound<'_, PyAny>>,
    ambiguity_delta_e: Option<&Bound<'_, PyAny>>,
    transport: &str,
    streams: Option<&Bound<'_, PyAny>>,
    rgb_gains: Option<[f64; 3]>,
) -> PyResult<AlbedoFitOptions> {
    let defaults = AlbedoFitOptions::default();
    let streams = streams_arg(streams)?;
    let mut o = AlbedoFitOptions {
        working_space: by_name("working_space", working_space, &ALL_WORKING_SPACES)?,
        transport: transport_arg(transport)?,
        streams: streams.unwrap_or(defaults.streams),
        // Streams given ask for solved totals at them; else the shipped table's.
        exact_totals: if streams.is_some() { ExactTotals::Solve } else { defaults.exact_totals },
        ..defaults
    };
    for ((spec, obj), value) in EXTENDED_PARAMS.iter().zip(extended).zip(&mut o.extended) {
        if let Some(v) = real_arg(spec.name, obj)? {
            *value = v.0;
        }
    }
    for (name, obj, value) in [
        ("oiliness", oiliness, &mut o.oiliness),
        ("melanin_blend_prior", melanin_blend_prior, &mut o.melanin_blend_prior),
        ("prior_weight", prior_weight, &mut o.prior_weight),
        ("ambiguity_delta_e", ambiguity_delta_e, &mut o.ambiguity_delta_e),
    ] {
        if let Some(v) = real_arg(name, obj)? {
            *value = v.0;
        }
    }
    if let Some(g) = rgb_gains {
        o.rgb_gains = g;
    }
    Ok(o.validated()?)
}

/// ``mask``: None, or an (H, W) array (bool, or float: non-zero) marking the skin texels of an (H, W) albedo.
fn mask_arg(obj: Option<&Bound<'_, PyAny>>, height: usize, width: usize) -> PyResult<Option<Vec<bool>>> {
    const EXPECTED: &str = "an (H, W) array the albedo's height and width: True (or non-zero) where the texel is skin";
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(None);
    };
    // The shape first, before anything is copied: a broadcast view of any size costs nothing.
    if let Ok(untyped) = obj.cast::<numpy::PyUntypedArray>() {
        if untyped.shape() != [height, width] {
            return Err(invalid(
                "mask",
                format!("must be {EXPECTED} ({height}, {width}); got shape {}", shape_text(untyped.shape())),
            ));
        }
    }
    let (shape, values): (Vec<usize>, Vec<bool>) = if let Ok(a) = obj.cast::<numpy::PyArrayDyn<bool>>() {
        let readonly = a.try_readonly().map_err(|e| pyo3::exceptions::PyTypeError::new_err(e.to_string()))?;
        (readonly.as_array().shape().to_vec(), readonly.as_array().iter().copied().collect())
    } else {
        let array = float_array("mask", obj, 2, EXPECTED)?
            .ok_or_else(|| pyo3::exceptions::PyTypeError::new_err(format!("mask must be {EXPECTED}")))?;
        let plane = array.plane(None)?;
        if let Some(i) = plane.iter().position(|v| v.is_nan()) {
            return Err(invalid("mask", format!("texel (x, y) = ({}, {}) is NaN: {EXPECTED}", i % width, i / width)));
        }
        (array.shape(), plane.iter().map(|&v| v != 0.0).collect())
    };
    if shape != [height, width] {
        return Err(invalid(
            "mask",
            format!("must be {EXPECTED} ({height}, {width}); got shape {}", shape_text(&shape)),
        ));
    }
    Ok(Some(values))
}

/// An (H, W, 3) float array's texels as the core takes them, row-major: one pass over the data (float64 converted),
/// any strides.
fn rgb_texels(array: &FloatArray<'_>) -> PyResult<Vec<[f32; 3]>> {
    fn of<T: numpy::Element + Copy>(a: &Bound<'_, PyArrayDyn<T>>, f: impl Fn(T) -> f32) -> PyResult<Vec<[f32; 3]>> {
        let readonly = a
            .try_readonly()
            .map_err(|e| pyo3::exceptions::PyTypeError::new_err(format!("cannot read the array: {e}")))?;
        let view = readonly.as_array();
        Ok(match view.as_slice() {
            Some(values) => values.chunks_exact(3).map(|c| [f(c[0]), f(c[1]), f(c[2])]).collect(),
            None => view.rows().into_iter().map(|c| [f(c[0]), f(c[1]), f(c[2])]).collect(),
        })
    }
    match array {
        FloatArray::F32(a) => of(a, |v| v),
        FloatArray::F64(a) => of(a, |v| v as f32),
    }
}

/// ``rgb_gains``: None, three numbers, or (with ``auto``) the string "auto"; returns the gains given and whether
/// "auto" was asked for.
fn gains_arg(obj: Option<&Bound<'_, PyAny>>, auto: bool) -> PyResult<(Option<[f64; 3]>, bool)> {
    let expected = if auto { "None, \"auto\" or 3 numbers (R, G, B)" } else { "None or 3 numbers (R, G, B)" };
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok((None, false));
    };
    if let Ok(text) = obj.extract::<String>() {
        if auto && text == "auto" {
            return Ok((None, true));
        }
        return Err(invalid("rgb_gains", format!("must be {expected}; got {text:?}")));
    }
    let values = real_vector("rgb_gains", obj, expected, 3)?;
    let gains: [f64; 3] = values
        .as_slice()
        .try_into()
        .map_err(|_| invalid("rgb_gains", format!("must be {expected}; got {} numbers", values.len())))?;
    Ok((Some(gains), false))
}

/// The parameters whose model albedo is closest in CIEDE2000 to a colour (docs/skin-atlas.md, "Fitting a colour").
///
/// The extended physiology is held (default: the paper's); the melanin blend, which RGB cannot always separate from
/// the haemoglobin, is pulled toward ``melanin_blend_prior`` with ``prior_weight`` ΔE00 per unit.
///
/// Arguments:
///     rgb: the target albedo, linear RGB in ``working_space`` (3 numbers; out-of-gamut colours are allowed).
///     working_space: "Linear Rec.709", "Linear Rec.2020" or "ACEScg".
///     epidermis_thickness_mm: held fixed, mm, 0.01..0.5; None: 0.25.
///     baseline_absorption_scale: held fixed, 0..10; None: 1.
///     blood_oxygenation: held fixed, 0..1; None: 0.75.
///     oiliness: written into the result (the albedo does not depend on it), 0..1; None: 0.3.
///     melanin_blend_prior: the melanin blend the prior pulls toward, 0..1; None: 0.7.
///     prior_weight: the prior's weight, ΔE00 per unit of melanin blend, 0..100; None: 0.2.
///     ambiguity_delta_e: the ΔE00 within which parameters reproduce the colour, for "in_gamut" and "ambiguity";
///         None: 0.5.
///     transport: the model whose albedo is fitted, "adding_doubling" (exact totals; the default) or "diffusion"
///         (the paper's), as for :func:`evaluate`.
///     streams: adding-doubling streams per hemisphere, even, 2..64; given, every exact total is solved at them;
///         None: skin's totals from the shipped table of 32-stream totals.
///     rgb_gains: None, or 3 factors (R, G, B, each 1/64..64) the colour is multiplied by before the fit (exposure and
///         white balance).
///
/// Returns:
///     A dict: "params" (the seven parameters by name), "target_rgb" (the colour fitted: after ``rgb_gains``), "albedo_rgb" (the fit's model albedo, direct
///     evaluation), "delta_e00", "in_gamut", "ambiguity" ({"delta_e00", "melanin", "melanin_blend", "hemoglobin":
///     [min, max] over the set, "members": [[C_m, beta_m, C_h, ΔE00], ...]}), "table_from_cache", "transport",
///     "streams".
///
/// Raises:
///     SpectralSkinError: a value out of range or not finite, an unknown working space.
///     TypeError: an argument of the wrong type.
#[pyfunction]
#[pyo3(
    name = "fit_albedo",
    signature = (
        rgb, *, working_space = "Linear Rec.709", epidermis_thickness_mm = None, baseline_absorption_scale = None,
        blood_oxygenation = None, oiliness = None, melanin_blend_prior = None, prior_weight = None,
        ambiguity_delta_e = None, transport = "adding_doubling", streams = None, rgb_gains = None
    )
)]
#[allow(clippy::too_many_arguments)]
pub(super) fn fit_albedo_py<'py>(
    py: Python<'py>,
    rgb: &Bound<'py, PyAny>,
    working_space: &str,
    epidermis_thickness_mm: Option<&Bound<'py, PyAny>>,
    baseline_absorption_scale: Option<&Bound<'py, PyAny>>,
    blood_oxygenation: Option<&Bound<'py, PyAny>>,
    oiliness: Option<&Bound<'py, PyAny>>,
    melanin_blend_prior: Option<&Bound<'py, PyAny>>,
    prior_weight: Option<&Bound<'py, PyAny>>,
    ambiguity_delta_e: Option<&Bound<'py, PyAny>>,
    transport: &str,
    streams: Option<&Bound<'py, PyAny>>,
    rgb_gains: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let values = real_vector("rgb", rgb, "3 numbers (linear RGB)", 3)?;
    let (gains, _) = gains_arg(rgb_gains, false)?;
    let target: [f64; 3] = values
        .as_slice()
        .try_into()
        .map_err(|_| invalid("rgb", format!("must be 3 numbers (linear RGB); got {}", values.len())))?;
    let options = options_from(
        working_space,
        [epidermis_thickness_mm, baseline_absorption_scale, blood_oxygenation],
        oiliness,
        melanin_blend_prior,
        prior_weight,
        ambiguity_delta_e,
        transport,
        streams,
        gains,
    )?;
    let cancel = std::sync::atomic::AtomicBool::new(false);
    let fit = detached_interruptible(py, &cancel, || fit_albedo_cancellable(target, &options, &cancel))?;
    to_py(py, &fit)
}

/// Fit every texel of an albedo texture (docs/skin-atlas.md, "Fitting a texture"): a forward table at the extended
/// physiology, the nearest node and a Levenberg-Marquardt refinement per distinct colour. The epidermis thickness is
/// chosen for the texture unless ``epidermis_thickness_mm`` holds it.
///
/// Arguments:
///     albedo: (H, W, 3) float32 or float64, linear RGB in ``working_space``. A NaN or infinite texel is an error
///         naming it.
///     epidermis_thickness_mm: None (the default): one thickness for the whole texture, the candidate of 0.05..0.5 mm
///         with the least mean ΔE00 over its texels, never worse on it than the paper's 0.25; a number: held for
///         every texel (mm, 0.01..0.5).
///     rgb_gains: None, 3 factors (R, G, B) the texture is multiplied by before the fit (exposure and white
///         balance), or "auto": the least gains that bring the most texels inside skin's colours (none for a texture
///         inside them already: its exposure and melanin stay), estimated on the texture (for a photograph) and
///         applied; ``AlbedoMapFit.gains`` reports them.
///     mask: None, or an (H, W) array, True (bool) or non-zero (float) where the texel is skin: only those take part
///         in the thickness choice, the gains, the diagnosis and the figures (``stats``); the others (hair, eyes,
///         background) are fitted too, each to the skin colour nearest it.
///     working_space, baseline_absorption_scale, blood_oxygenation, oiliness, melanin_blend_prior, prior_weight,
///     ambiguity_delta_e, transport, streams: as for :func:`fit_albedo`.
///     progress: None, or a callable ``progress(done, total)`` told how many texels of ``total`` (H x W) are done,
///         as for :func:`maps`: once with 0 before the fit, with the same ``done`` while a forward table is built,
///         the gains are estimated or the thickness is screened, then about once per percent as the texture's
///         colours are fitted and its texels filled in, the last call with ``total`` (from the core's worker
///         threads, taking the GIL for each call). Returning False cancels: the work under way is finished, the rest
///         skipped, nothing is returned and InterruptedError is raised. An exception raised by the callback cancels
///         the same way and is re-raised.
///
/// Returns:
///     An :class:`AlbedoMapFit`: the parameter maps, the extended physiology they hold for, the residual, the
///     figures, and ``write(path)``, which writes the parameter EXR that ``maps`` and the add-on read.
///
/// Raises:
///     SpectralSkinError: a non-finite texel, a value out of range, another shape.
///     TypeError: another dtype; a progress that is not callable.
///     KeyboardInterrupt: Ctrl-C during the fit.
///     InterruptedError: the progress callback returned False.
///
/// Warns:
///     SpectralSkinWarning: the texture does not look like an albedo (over a quarter of its texels outside skin's
///         colours, ``stats["outside_skin_texels"]``): the message gives the likely reasons and the gains measured on
///         it (``AlbedoMapFit.diagnosis``, ``.gains``).
#[pyfunction]
#[pyo3(
    name = "fit_albedo_map",
    signature = (
        albedo, *, working_space = "Linear Rec.709", epidermis_thickness_mm = None, baseline_absorption_scale = None,
        blood_oxygenation = None, oiliness = None, melanin_blend_prior = None, prior_weight = None,
        ambiguity_delta_e = None, transport = "adding_doubling", streams = None, rgb_gains = None, mask = None,
        progress = None
    )
)]
#[allow(clippy::too_many_arguments)]
pub(super) fn fit_albedo_map_py(
    py: Python<'_>,
    albedo: &Bound<'_, PyAny>,
    working_space: &str,
    epidermis_thickness_mm: Option<&Bound<'_, PyAny>>,
    baseline_absorption_scale: Option<&Bound<'_, PyAny>>,
    blood_oxygenation: Option<&Bound<'_, PyAny>>,
    oiliness: Option<&Bound<'_, PyAny>>,
    melanin_blend_prior: Option<&Bound<'_, PyAny>>,
    prior_weight: Option<&Bound<'_, PyAny>>,
    ambiguity_delta_e: Option<&Bound<'_, PyAny>>,
    transport: &str,
    streams: Option<&Bound<'_, PyAny>>,
    rgb_gains: Option<&Bound<'_, PyAny>>,
    mask: Option<&Bound<'_, PyAny>>,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<AlbedoMapFitPy> {
    let progress = Progress::from_arg("fit_albedo_map", progress)?;
    let (gains, auto_gains) = gains_arg(rgb_gains, true)?;
    const EXPECTED: &str = "an (H, W, 3) float array of linear RGB";
    let array = float_array("albedo", albedo, 3, EXPECTED)?
        .ok_or_else(|| pyo3::exceptions::PyTypeError::new_err(format!("albedo must be {EXPECTED}")))?;
    let shape = array.shape();
    if shape[2] != 3 {
        return Err(invalid("albedo", format!("must be {EXPECTED}; got shape {}", shape_text(&shape))));
    }
    let (height, width) = (shape[0], shape[1]);
    // Before any copy: a broadcast view of any size costs nothing until its planes are gathered.
    crate::maps::io::check_texel_count("albedo", width, height)?;
    let texels = rgb_texels(&array)?;
    let options = options_from(
        working_space,
        [epidermis_thickness_mm, baseline_absorption_scale, blood_oxygenation],
        oiliness,
        melanin_blend_prior,
        prior_weight,
        ambiguity_delta_e,
        transport,
        streams,
        gains,
    )?;
    let thickness = if epidermis_thickness_mm.is_some_and(|t| !t.is_none()) {
        EpidermisThickness::Held
    } else {
        EpidermisThickness::Chosen
    };
    let texture = TextureFit { thickness, auto_gains };
    let mask = mask_arg(mask, height, width)?;
    // Ctrl-C (and a progress callback's False or exception) stops the thickness choice, the table builds and the
    // texels' fits through one flag.
    let hook = progress.as_ref();
    let own_flag = AtomicBool::new(false);
    let cancel = hook.map_or(&own_flag, |h| &h.stopped);
    let fit = detached_interruptible(py, cancel, || {
        let report = |done: usize, total: usize| {
            if let Some(h) = hook {
                h.report(done, total)
            }
        };
        report(0, texels.len());
        let tile = AlbedoTile { label: "albedo texture".into(), width, height, texels: &texels, mask: mask.as_deref() };
        let progress = hook.map(|_| &report as &(dyn Fn(usize, usize) + Sync));
        let fit = fit_albedo_tiles_with_progress(&[tile], &options, texture, progress, cancel);
        // A stopped fit is an error; the callback's answer (or exception) is what the caller sees.
        if hook.is_some_and(Progress::stopped) {
            return Ok(None);
        }
        Ok(Some(fit?.remove(0)))
    })?;
    drop(texels);
    let Some(fit) = fit else {
        return Err(progress.map(Progress::into_error).unwrap_or_else(|| internal("stopped without a progress hook")));
    };
    if let Some(diagnosis) = &fit.diagnosis {
        PyErr::warn(py, &py.get_type::<SpectralSkinWarning>(), &std::ffi::CString::new(diagnosis.as_str())?, 1)?;
    }
    Ok(AlbedoMapFitPy { fit })
}

/// The result of :func:`fit_albedo_map`: the fitted parameter maps of an albedo texture, what they hold for, and how
/// well they fit. Read-only; ``write`` saves it as the parameter EXR that ``spectral-skin maps --params``,
/// :func:`read_parameter_map` and the add-on's Parameter Map read.
#[pyclass(frozen, name = "AlbedoMapFit", module = "spectral_skin")]
pub(super) struct AlbedoMapFitPy {
    fit: AlbedoMapFit,
}

#[pymethods]
impl AlbedoMapFitPy {
    /// (H, W, 4) float32: melanin, melanin_blend, hemoglobin, oiliness per texel (row 0 at the top).
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let f = &self.fit;
        let values: Vec<f32> = f.params.iter().flatten().copied().collect();
        Ok(PyArray1::from_vec(py, values).reshape([f.height, f.width, 4]).map_err(internal)?.into_any())
    }

    /// (H, W) float32: ΔE00 between each texel and the albedo of its parameters (by the fit's table).
    #[getter]
    fn residual_delta_e00<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let f = &self.fit;
        Ok(PyArray1::from_slice(py, &f.residual_delta_e00).reshape([f.height, f.width]).map_err(internal)?.into_any())
    }

    /// The extended physiology every texel holds for, by name (epidermis_thickness_mm chosen or held; the others
    /// held).
    #[getter]
    fn extended<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let extended = PyDict::new(py);
        for (spec, v) in EXTENDED_PARAMS.iter().zip(self.fit.extended) {
            extended.set_item(spec.name, v)?;
        }
        Ok(extended)
    }

    /// {"texels", "masked_out_texels", "distinct_colours", "table_from_cache", "max_delta_e00", "mean_delta_e00",
    /// "outside_skin_texels" (the texels outside skin's colours, more than 2 ΔE00 from every colour skin can have,
    /// of those the mask marks: the count ``diagnosis`` judges), "options" (with "transport" and "streams")}.
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.fit.stats)
    }

    /// How the epidermis thickness was chosen ({"screened": [[mm, mean ΔE00], ...], "sampled_texels": None (every
    /// texel) or a count, "whole_texture": [[mm, mean ΔE00 over every texel], ...], "chosen_mm"}); None when held.
    #[getter]
    fn thickness<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.fit.thickness)
    }

    /// The exposure and white-balance gains estimated on the texture ({"rgb_gains", "exposure_stops",
    /// "epidermis_thickness_mm", "median_delta_e00_before", "median_delta_e00_after", "sampled_texels"}): the least
    /// correction that brings the most sampled texels inside skin's colours (none for a texture inside them already),
    /// applied with ``rgb_gains="auto"``, else measured as the remedy of ``diagnosis``; None when neither.
    #[getter]
    fn gains<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.fit.gains)
    }

    /// Why the texture does not look like an albedo (its texels outside skin's colours, the likely reasons, the
    /// remedies with the gains measured), or None.
    #[getter]
    fn diagnosis(&self) -> Option<String> {
        self.fit.diagnosis.clone()
    }

    /// (H, W): the texture's height and width.
    #[getter]
    fn shape(&self) -> (usize, usize) {
        (self.fit.height, self.fit.width)
    }

    /// Write the parameter EXR to ``path`` (float; channels melanin, melanin_blend, hemoglobin, oiliness per texel
    /// and the extended physiology as channels of one value each) and, if given, the residual to
    /// ``residual_path`` (ΔE00, channel Y): staged and renamed into place together, their folders created.
    ///
    /// Raises:
    ///     SpectralSkinIOError: a file that cannot be written (the message names it); nothing is left half-written.
    ///
    /// With ``tiles`` (a UDIM tile set stacked top to bottom, as [(tile number, rows), ...] covering the fit's rows:
    /// each tile 1001 to 2000, given once), ``path`` (and ``residual_path``) must hold ``<UDIM>``; each tile's rows
    /// are written as that tile's file (``params.1001.exr``, ...), all staged first and renamed into place together.
    #[pyo3(signature = (path, residual_path = None, tiles = None))]
    fn write(
        &self,
        py: Python<'_>,
        path: PathBuf,
        residual_path: Option<PathBuf>,
        tiles: Option<Vec<(i64, i64)>>,
    ) -> PyResult<()> {
        use crate::maps::udim::{is_tile_set, stacked_tile_rows, tile_path};
        let Some(tiles) = tiles else {
            return detached(py, || self.fit.write(&path, residual_path.as_deref()));
        };
        for p in std::iter::once(&path).chain(&residual_path) {
            if !is_tile_set(p) {
                return Err(invalid("path", format!("{} must hold <UDIM> to write a tile set", p.display())));
            }
        }
        let rows = stacked_tile_rows("tiles", &tiles, self.fit.height)?;
        detached(py, || {
            let mut staged = Vec::new();
            for &(tile, first, count) in &rows {
                let part = self.fit.rows(first, count)?;
                let residual = residual_path.as_ref().map(|r| tile_path(r, tile));
                staged.extend(part.stage(&tile_path(&path, tile), residual.as_deref())?);
            }
            crate::maps::io::commit_all(staged)
        })
    }

    fn __repr__(&self) -> String {
        let f = &self.fit;
        format!(
            "AlbedoMapFit({} x {}, epidermis_thickness_mm={}, mean ΔE00 {:.3}, max {:.3})",
            f.width, f.height, f.extended[0], f.stats.mean_delta_e00, f.stats.max_delta_e00
        )
    }
}
