//! `evaluate`, `profile` and `layered_reflectance`: one point of the model, or one stack of layers.

use std::sync::atomic::AtomicBool;

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use serde_json::Value;

use crate::accuracy::{MAX_LAYERS, MAX_PROFILE_RADII};
use crate::color::WavelengthPlacement;
use crate::evaluate::Outputs;
use crate::evaluate::{Evaluation, MethodParams};
use crate::layer::Layer;
use crate::reflectance::LayeredOptions;
use crate::surface::lobes::SurfaceModel;

use super::args::{model_of, named, streams_of, Choice, Knobs, Model, ParamArgs, Streams};
use super::convert::{
    count_arg, float_dermis, json_to_py, nested_rows, parse_outputs, real_arg, real_sequence, real_vector,
    reject_string, rgb_rows, target_from, to_py,
};
use super::detach::detached_interruptible;
use super::errors::{internal, invalid, warn_lobe};

/// The fields of one layer tuple, in order.
pub(super) const LAYER_FIELDS: &str = "(thickness_mm, sigma_a_per_mm, sigma_s_reduced_per_mm, ior)";

pub(super) fn method_dict<'py>(py: Python<'py>, value: &Value, m: &MethodParams) -> PyResult<Bound<'py, PyAny>> {
    let dict = json_to_py(py, value)?;
    dict.set_item("base_color", PyArray1::from_slice(py, &m.base_color))?;
    dict.set_item("subsurface_radius_mm", PyArray1::from_slice(py, &m.subsurface_radius_mm))?;
    dict.set_item("expected_albedo", PyArray1::from_slice(py, &m.expected_albedo))?;
    Ok(dict)
}

/// The CLI's JSON of an evaluation as a dict, with numpy arrays for the array-valued outputs.
pub(super) fn evaluation_dict<'py>(py: Python<'py>, e: &Evaluation) -> PyResult<Bound<'py, PyDict>> {
    let Value::Object(mut map) = serde_json::to_value(e).map_err(internal)? else {
        return Err(internal("an evaluation does not serialise to an object"));
    };
    // Array-valued fields are built from the struct, not converted element by element.
    for key in ["diffuse_reflectance_rgb", "wavelengths_nm", "spectral_reflectance", "profile", "methods"] {
        map.remove(key);
    }
    let dict = json_to_py(py, &Value::Object(map))?.cast_into::<PyDict>()?;
    float_dermis(&dict, &e.model)?;
    if let Some(rgb) = &e.diffuse_reflectance_rgb {
        dict.set_item("diffuse_reflectance_rgb", PyArray1::from_slice(py, rgb))?;
    }
    if let Some(methods) = &e.methods {
        let m = PyDict::new(py);
        let Value::Object(json) = serde_json::to_value(methods).map_err(internal)? else {
            return Err(internal("methods do not serialise to an object"));
        };
        for (method, params) in methods.iter() {
            let field = json.get(method.name()).cloned().unwrap_or(Value::Null);
            m.set_item(method.name(), method_dict(py, &field, params)?)?;
        }
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
        if let Some(lobe) = &p.negative_lobe {
            profile.set_item("negative_lobe", to_py(py, &lobe)?)?;
        }
        dict.set_item("profile", profile)?;
    }
    Ok(dict)
}

/// Evaluate the skin model; compute only the requested outputs.
///
/// Give a preset, or all four parameters; a preset with explicit parameters uses the explicit ones instead of the
/// preset's.
///
/// Arguments:
///     melanin: C_m, melanin volume fraction of the epidermis, 0..0.5.
///     melanin_blend: beta_m, eumelanin share of the melanin, 0..1 (the rest is pheomelanin).
///     hemoglobin: C_h, whole-blood volume fraction of the dermis, 0..0.1.
///     oiliness: rho_s, scale of the surface's specular lobe, 0..1.
///     epidermis_thickness_mm: the extended physiology (docs/model.md, section Extended physiology): thickness of
///         the epidermis, mm, 0.01..0.5; None: the preset's, else DJ2006's 0.25.
///     baseline_absorption_scale: scale on the melanin- and blood-free tissue absorption (DJ2006 eq. 5), 0..10;
///         None: the preset's, else 1.
///     blood_oxygenation: gamma, oxygenated share of the dermis's haemoglobin, 0..1; None: the preset's, else
///         DJ2006's 0.75.
///     preset: a preset name from :func:`presets` (case-insensitive).
///     outputs: names among "albedo", "radius", "profile_rgb", "profile_spectral", "spectrum", "specular".
///         None: ("albedo", "radius", "specular"), what a material needs.
///     accuracy: a named accuracy level, "draft", "default" or "reference" (docs/accuracy-vs-time.md); the
///         knobs below override its settings where given.
///     wavelength_step_nm: wavelength sampling step in nm (380-780 nm), 0.5..100; with "cmf_adapted" placement it
///         sets the count (the uniform step's); None: the level's (10 nm at "default").
///     wavelength_placement: "uniform" (every step nm), "cmf_adapted" (denser where the colour-matching functions
///         weigh most; the default level's) or "rgb_shortcut" (reflectance at 435.8, 546.1 and 700 nm taken as B, G,
///         R: the shortcut DJ2006 argues against, for comparison); None: the level's.
///     multipole_pairs: image-source pairs per side of the multipole; None: the whole series (closed form).
///     profile_r_min_mm: smallest radius of the log-spaced profile grid, mm; None: 0.001 mm.
///     profile_r_max_mm: largest radius of the profile grid, mm; None: 20 mm.
///     profile_count: number of profile radii; None: 64.
///     combination: transport through the epidermis from below: "directional" (the layer seen from below) or
///         "symmetric" (DJ2005's published form).
///     working_space: linear RGB space of every RGB output, named as Blender 5.0's working spaces:
///         "Linear Rec.709", "Linear Rec.2020" (both D65) or "ACEScg" (AP1 primaries, ACES white; the D65 XYZ is
///         Bradford-adapted to it, as Blender's OCIO config does). A perfect white reflector is (1, 1, 1) in each.
///     blender: the Blender version the Principled inputs are for: "MAJOR.MINOR" or "MAJOR.MINOR.PATCH" (e.g. "5.2";
///         a patch release means its minor release: "5.3.1" is 5.3) or a tuple such as ``bpy.app.version``; 4.2 or newer. A version newer than the tested ones uses
///         the newest known behaviour (``result["target"]["tested"]`` is False). None: the current release (5.3,
///         ``blender_targets()["current_release"]``).
///     engine: the render engine, "cycles" or "eevee" (EEVEE renders every subsurface method as Burley, with a
///         radius compensated for its albedo-dependent profile).
///     rgb_mapping: how the RGB profile's colour at each radius is formed (only "profile_rgb" uses it), as for
///         :func:`profile`: "linear" (exact; negative in a channel where the light is outside the gamut) or
///         "non_negative".
///     boundaries: the layers' boundary conditions: "paper" (DJ2005's extrapolated boundaries, the default) or
///         "capped" (each layer's extrapolation distances capped so that every exact radial profile is non-negative
///         and the total reflectance never rises with absorption; the numerical transform can still dip below zero,
///         reported as a lobe of these boundaries; it moves a thin or red-lit epidermis away from Monte Carlo:
///         docs/robustness.md, "Negative profile lobes").
///     transport: how each wavelength's total diffuse reflectance (the albedo, and the scale of the radial profile
///         and of the radius fit's transform) is computed, a name from :func:`transports`: "adding_doubling" (exact
///         radiative transfer; the default) or "diffusion" (the paper's layered multipole: reproduces DJ2006).
///     streams: quadrature directions per hemisphere of the adding-doubling solver, even, 2..64. Given, every exact
///         total is solved at them; None: skin's totals are read from the shipped table of 32-stream totals (the
///         reference level solves at 32) and others solved at the level's streams. Unused with transport="diffusion".
///     surface: the surface reflection the specular inputs stand in for: "measured" (two lobes, a broad base lobe
///         and a sharp Coat, reflecting like a dielectric at every oiliness: docs/model.md, "Principled mapping of
///         the measured surface") or "paper" (DJ2006's oil layer, one lobe scaled by the oiliness, no reflection on
///         dry skin); None: the core's default, "measured" (``surface_models()``).
///     model: the model's options beyond the parameters, a dict by name (docs/model.md, each option's section), e.g.
///         ``{"epidermal_hemoglobin": 0.01}``; options left out keep DJ2006's model, and a result's "model" reads back
///         as it is (a :func:`fit_spectrum` result's too: ``evaluate(**fit["params"], model=fit["model"])`` renders
///         the fit). None: DJ2006's model.
///
/// Returns:
///     The CLI's JSON as a dict. Always: "params", "color_space", "accuracy" (with "streams"), "model"
///     (model["dermis_thickness_mm"] is float("inf") for a semi-infinite dermis), "combination", "boundaries",
///     "transport", "target" ({"blender": "5.3", "engine": "cycles", "tested": True}; with "untested_reason", the
///     sentence a front shows, when tested is False), "default_method", "work"
///     ({"wavelengths", "transform_samples", "radial_profiles", "radius_fits", "specular_evaluations",
///     "transport_solves"}: what was computed),
///     "surface" ({"surface", "roughness", "ior", "coat_ior", "beckmann_m"}: the inputs no parameter changes),
///     "seconds". Per requested
///     output, numpy arrays where array-valued:
///     albedo or radius: "diffuse_reflectance_rgb" (3,);
///     radius: "methods", one entry per subsurface method the target's Blender offers ("burley", "random_walk",
///     "random_walk_skin", and "random_walk_legacy" from 5.2) -> {"base_color" (3,), "subsurface_radius_mm" (3,),
///     mm, "expected_albedo" (3,)} and "radius_fit" (a list of 3 dicts {"d_mm", "radius_mm", "edge_residual"}:
///     the Cycles Burley fit);
///     specular: "specular" {"surface", "oiliness", "specular_ior_level", "roughness", "ior", "coat_weight",
///     "coat_roughness", "coat_ior", "beckmann_m", "directional_albedo_normal", "hemispherical_albedo"};
///     spectrum: "wavelengths_nm" (K,), "spectral_reflectance" (K,);
///     profile_rgb / profile_spectral: "profile" {"radii_mm" (N,), "rgb_per_mm2" (N, 3) and/or
///     "spectral_per_mm2" (K, N), mm^-2, and "negative_lobe" {"wavelength_nm", "boundaries", "radius_mm",
///     "relative_to_peak"}
///     when a spectral profile was negative beyond round-off before its clamp to 0, also reported by a
///     SpectralSkinWarning} (and "wavelengths_nm" (K,) with profile_spectral).
///
/// Raises:
///     SpectralSkinError: a parameter or knob out of range or not finite, an unknown preset, output, combination,
///         working space or transport, or neither a preset nor all four parameters; a Blender version older than 4.2 or not
///         MAJOR.MINOR; an unknown engine; an unknown model option or one out of its range.
///     TypeError: an argument of the wrong type (e.g. outputs given as a single string, or a model that is not a
///         dict).
#[pyfunction]
#[pyo3(
    name = "evaluate",
    signature = (
        melanin = None, melanin_blend = None, hemoglobin = None, oiliness = None, *,
        epidermis_thickness_mm = None, baseline_absorption_scale = None, blood_oxygenation = None, preset = None, outputs = None, accuracy = "default", wavelength_step_nm = None, wavelength_placement = None,
        multipole_pairs = None,
        profile_r_min_mm = None, profile_r_max_mm = None, profile_count = None,
        combination = "directional", working_space = "Linear Rec.709", blender = None, engine = "cycles",
        rgb_mapping = "linear", boundaries = "paper", transport = "adding_doubling", streams = None,
        surface = None, model = None
    )
)]
#[allow(clippy::too_many_arguments)]
pub(super) fn evaluate_py<'py>(
    py: Python<'py>,
    melanin: Option<&Bound<'py, PyAny>>,
    melanin_blend: Option<&Bound<'py, PyAny>>,
    hemoglobin: Option<&Bound<'py, PyAny>>,
    oiliness: Option<&Bound<'py, PyAny>>,
    epidermis_thickness_mm: Option<&Bound<'py, PyAny>>,
    baseline_absorption_scale: Option<&Bound<'py, PyAny>>,
    blood_oxygenation: Option<&Bound<'py, PyAny>>,
    preset: Option<&str>,
    outputs: Option<&Bound<'py, PyAny>>,
    accuracy: &str,
    wavelength_step_nm: Option<&Bound<'py, PyAny>>,
    wavelength_placement: Option<Choice<WavelengthPlacement>>,
    multipole_pairs: Option<&Bound<'py, PyAny>>,
    profile_r_min_mm: Option<&Bound<'py, PyAny>>,
    profile_r_max_mm: Option<&Bound<'py, PyAny>>,
    profile_count: Option<&Bound<'py, PyAny>>,
    combination: &str,
    working_space: &str,
    blender: Option<&Bound<'py, PyAny>>,
    engine: &str,
    rgb_mapping: &str,
    boundaries: &str,
    transport: &str,
    streams: Option<Streams>,
    surface: Option<Choice<SurfaceModel>>,
    model: Option<Model>,
) -> PyResult<Bound<'py, PyDict>> {
    let params = ParamArgs::new(
        [melanin, melanin_blend, hemoglobin, oiliness],
        [epidermis_thickness_mm, baseline_absorption_scale, blood_oxygenation],
    )
    .skin_params(preset)?;
    let knobs = Knobs {
        accuracy: named(accuracy)?,
        wavelength_step_nm: real_arg("wavelength_step_nm", wavelength_step_nm)?,
        wavelength_placement: wavelength_placement.map(|c| c.0),
        multipole_pairs: count_arg("multipole_pairs", multipole_pairs)?,
        profile_r_min_mm: real_arg("profile_r_min_mm", profile_r_min_mm)?,
        profile_r_max_mm: real_arg("profile_r_max_mm", profile_r_max_mm)?,
        profile_count: count_arg("profile_count", profile_count)?,
        combination: named(combination)?,
        working_space: named(working_space)?,
        rgb_mapping: named(rgb_mapping)?,
        boundaries: named(boundaries)?,
        target: target_from(blender, engine)?,
        transport: named(transport)?,
        streams: streams_of(streams),
        surface: surface.map(|c| c.0).unwrap_or_default(),
        model: model_of(model),
    };
    let request = knobs.request(parse_outputs(outputs)?)?;
    let cancel = AtomicBool::new(false);
    let evaluation =
        detached_interruptible(py, &cancel, || crate::evaluate::evaluate_cancellable(&params, &request, &cancel))?;
    warn_lobe(py, evaluation.profile.as_ref().and_then(|p| p.negative_lobe))?;
    evaluation_dict(py, &evaluation)
}

/// The radial reflectance profile R(r) of the skin on a log-spaced radius grid.
///
/// The RGB profile is the spectral profile mapped into ``working_space``. With ``rgb_mapping="linear"`` (the
/// default) that map is linear: the exact colour at each radius, additive, and it integrates (2 pi r dr) to the RGB
/// albedo; but where the light is outside the space's gamut a channel is **negative**. Every preset has such radii:
/// in the far tail only red light is left, more saturated than the red primary (docs/cli.md, "Radial profiles", lists
/// the radii and sizes). ``rgb_mapping="non_negative"`` moves each such colour along the line towards the grey of the same
/// luminance (R = G = B = Y) until its most negative channel is 0: no value is negative, luminance and hue are kept,
/// radii inside the gamut are unchanged, but the profile no longer integrates exactly to the albedo. The spectral
/// profiles (``spectral=True``) are never negative: a negative lobe of the model itself (only with
/// ``boundaries="paper"``, none for the presets) is set to 0 and reported by a :class:`SpectralSkinWarning`.
///
/// Arguments:
///     melanin, melanin_blend, hemoglobin, oiliness, epidermis_thickness_mm, baseline_absorption_scale,
///         blood_oxygenation, preset: as for :func:`evaluate`.
///     spectral: False: RGB profiles; True: one profile per wavelength.
///     accuracy, wavelength_step_nm, wavelength_placement, multipole_pairs, profile_r_min_mm, profile_r_max_mm,
///         profile_count, combination, working_space: as for :func:`evaluate`.
///     rgb_mapping: "linear" or "non_negative", see above.
///     boundaries: "paper" or "capped", as for :func:`evaluate`.
///     transport, streams: as for :func:`evaluate` (the profile keeps the multipole's shape, scaled per wavelength to
///         the transport's total).
///     model: the model's options, as for :func:`evaluate`.
///
/// Returns:
///     {"radii_mm": (N,), "rgb_per_mm2": (N, 3)} in mm^-2, or with spectral=True
///     {"radii_mm": (N,), "spectral_per_mm2": (K, N), "wavelengths_nm": (K,)}.
///
/// Raises:
///     SpectralSkinError: as for :func:`evaluate`.
///     TypeError: an argument of the wrong type.
#[pyfunction]
#[pyo3(
    name = "profile",
    signature = (
        melanin = None, melanin_blend = None, hemoglobin = None, oiliness = None, *,
        epidermis_thickness_mm = None, baseline_absorption_scale = None, blood_oxygenation = None, preset = None, spectral = false, accuracy = "default", wavelength_step_nm = None, wavelength_placement = None,
        multipole_pairs = None,
        profile_r_min_mm = None, profile_r_max_mm = None, profile_count = None,
        combination = "directional", working_space = "Linear Rec.709", rgb_mapping = "linear", boundaries = "paper",
        transport = "adding_doubling", streams = None, model = None
    )
)]
#[allow(clippy::too_many_arguments)]
pub(super) fn profile_py<'py>(
    py: Python<'py>,
    melanin: Option<&Bound<'py, PyAny>>,
    melanin_blend: Option<&Bound<'py, PyAny>>,
    hemoglobin: Option<&Bound<'py, PyAny>>,
    oiliness: Option<&Bound<'py, PyAny>>,
    epidermis_thickness_mm: Option<&Bound<'py, PyAny>>,
    baseline_absorption_scale: Option<&Bound<'py, PyAny>>,
    blood_oxygenation: Option<&Bound<'py, PyAny>>,
    preset: Option<&str>,
    spectral: bool,
    accuracy: &str,
    wavelength_step_nm: Option<&Bound<'py, PyAny>>,
    wavelength_placement: Option<Choice<WavelengthPlacement>>,
    multipole_pairs: Option<&Bound<'py, PyAny>>,
    profile_r_min_mm: Option<&Bound<'py, PyAny>>,
    profile_r_max_mm: Option<&Bound<'py, PyAny>>,
    profile_count: Option<&Bound<'py, PyAny>>,
    combination: &str,
    working_space: &str,
    rgb_mapping: &str,
    boundaries: &str,
    transport: &str,
    streams: Option<Streams>,
    model: Option<Model>,
) -> PyResult<Bound<'py, PyDict>> {
    let params = ParamArgs::new(
        [melanin, melanin_blend, hemoglobin, oiliness],
        [epidermis_thickness_mm, baseline_absorption_scale, blood_oxygenation],
    )
    .skin_params(preset)?;
    let knobs = Knobs {
        accuracy: named(accuracy)?,
        wavelength_step_nm: real_arg("wavelength_step_nm", wavelength_step_nm)?,
        wavelength_placement: wavelength_placement.map(|c| c.0),
        multipole_pairs: count_arg("multipole_pairs", multipole_pairs)?,
        profile_r_min_mm: real_arg("profile_r_min_mm", profile_r_min_mm)?,
        profile_r_max_mm: real_arg("profile_r_max_mm", profile_r_max_mm)?,
        profile_count: count_arg("profile_count", profile_count)?,
        combination: named(combination)?,
        working_space: named(working_space)?,
        rgb_mapping: named(rgb_mapping)?,
        boundaries: named(boundaries)?,
        transport: named(transport)?,
        streams: streams_of(streams),
        model: model_of(model),
        ..Knobs::default()
    };
    let outputs = Outputs { profile_rgb: !spectral, profile_spectral: spectral, ..Outputs::default() };
    let request = knobs.request(outputs)?;
    let cancel = AtomicBool::new(false);
    let evaluation =
        detached_interruptible(py, &cancel, || crate::evaluate::evaluate_cancellable(&params, &request, &cancel))?;
    let p = evaluation.profile.as_ref().ok_or_else(|| internal("no profile in the evaluation"))?;
    warn_lobe(py, p.negative_lobe)?;
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

/// One layer from a 4-sequence of numbers.
pub(super) fn extract_layer(index: usize, item: &Bound<'_, PyAny>) -> PyResult<Layer> {
    reject_string(item, &format!("layers[{index}] must be a tuple {LAYER_FIELDS}"))?;
    let values = real_sequence(&format!("layers[{index}]"), item, &format!("a tuple of 4 numbers {LAYER_FIELDS}"), 4)?;
    match values[..] {
        [thickness_mm, sigma_a_per_mm, sigma_s_reduced_per_mm, ior] => {
            Ok(Layer { thickness_mm, sigma_a_per_mm, sigma_s_reduced_per_mm, ior })
        }
        _ => Err(invalid(format!("layer {index}"), format!("expected 4 values {LAYER_FIELDS}; got {}", values.len()))),
    }
}

/// Total diffuse reflectance and radial profile of a stack of layers under air.
///
/// The total comes from ``transport``: exact radiative transfer (adding-doubling, the default) or the layered
/// multipole (diffusion, DJ2005). The profile is the multipole's (directional combination, whole series, default
/// inverse-Hankel quadrature), scaled to the total. With the paper's boundaries a thin layer over layers that do not
/// fill it can give a profile that is negative at some radii (the model's own lobe); it is returned clamped to 0 and
/// reported by a :class:`SpectralSkinWarning` naming the radius and the depth relative to the peak.
/// ``boundaries="capped"`` gives a profile that is non-negative and, with ``transport="diffusion"``, a total that is
/// monotone in absorption by construction (docs/robustness.md, "Negative profile lobes").
///
/// Arguments:
///     layers: top to bottom, each (thickness_mm, sigma_a_per_mm, sigma_s_reduced_per_mm, ior): thickness in mm
///         (float("inf") for a semi-infinite last layer), absorption and reduced scattering coefficients in mm^-1,
///         index of refraction 1..2.
///     radii_mm: 1-D radii in mm, finite and >= 0.
///     boundaries: "paper" (the default) or "capped": the multipole's boundary conditions.
///     transport: "adding_doubling" (the default) or "diffusion" (the multipole alone), as for :func:`evaluate`.
///     streams: quadrature directions per hemisphere of the adding-doubling solver, even, 2..64; given, every exact
///         total is solved at them; None: the default level's (skin's totals from the shipped table).
///
/// Returns:
///     (total diffuse reflectance, R(r) at radii_mm in mm^-2 as a float64 array of the same length).
///
/// Raises:
///     SpectralSkinError: no layers or more than 16, a layer that is not 4 values, more than 100000 radii, a thickness outside 1e-11..1e6 mm (inf only for
///         the last layer), a coefficient other than 0 or 1e-12..1e6 per mm, an ior outside 1..2 (where the diffuse
///         Fresnel fits hold), a radius outside 0..1e6 mm, an unknown boundaries or transport, streams out of range.
///     TypeError: layers or radii_mm not sequences of numbers.
#[pyfunction]
#[pyo3(
    name = "layered_reflectance",
    signature = (layers, radii_mm, *, boundaries = "paper", transport = "adding_doubling", streams = None)
)]
pub(super) fn layered_reflectance_py<'py>(
    py: Python<'py>,
    layers: &Bound<'py, PyAny>,
    radii_mm: &Bound<'py, PyAny>,
    boundaries: &str,
    transport: &str,
    streams: Option<Streams>,
) -> PyResult<(f64, Bound<'py, PyArray1<f64>>)> {
    reject_string(layers, &format!("layers must be a list of tuples {LAYER_FIELDS}"))?;
    let layers: Vec<Layer> = layers
        .try_iter()?
        .take(MAX_LAYERS + 1)
        .enumerate()
        .map(|(i, item)| extract_layer(i, &item?))
        .collect::<PyResult<_>>()?;
    if layers.len() > MAX_LAYERS {
        return Err(invalid("layers", format!("at most {MAX_LAYERS} layers; got more")));
    }
    let radii = real_vector("radii_mm", radii_mm, "a 1-D array-like of radii in mm", MAX_PROFILE_RADII)?;
    let defaults = LayeredOptions::default();
    let options = LayeredOptions {
        boundaries: named(boundaries)?,
        transport: named(transport)?,
        streams: streams_of(streams).unwrap_or(defaults.streams),
    };
    let cancel = AtomicBool::new(false);
    let r = detached_interruptible(py, &cancel, || {
        crate::reflectance::layered_reflectance_cancellable(&layers, &radii, &options, &cancel)
    })?;
    warn_lobe(py, r.negative_lobe)?;
    Ok((r.total, PyArray1::from_vec(py, r.profile_per_mm2)))
}
