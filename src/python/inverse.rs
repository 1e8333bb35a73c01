//! `fit_spectrum`: model parameters from a measured reflectance spectrum.

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

use crate::inverse::aperture::Aperture;
use crate::inverse::bandpass::Bandpass;
use crate::inverse::spectrum::{
    FitOptions, Objective, SpectrumFit, Specular, ALL_OBJECTIVES, MAX_SPECTRUM_WAVELENGTHS,
};
use crate::skin::params::{PARAMS, PARAM_COUNT};

use super::args::{model_of, Model};
use super::convert::{
    by_name, count_arg, float_dermis, real_of, real_vector, reject_string, streams_arg, to_py, transport_arg, type_name,
};
use super::detach::detached_interruptible;
use super::errors::invalid;

/// Fit the model to a measured diffuse reflectance spectrum (docs/measured-skin.md).
///
/// The model is the skin's total diffuse reflectance (as ``evaluate(..., outputs=["spectrum"])`` computes it) at the
/// given wavelengths plus a constant surface reflection, which a spectrophotometer with the specular component
/// included sees and the model's diffuse reflectance lacks. The fit is bounded (each parameter in its range,
/// :func:`parameter_ranges`) and global: a coarse table of model spectra over the free parameters gives the start,
/// a bounded Levenberg-Marquardt refines it.
///
/// Arguments:
///     wavelengths_nm: the measured wavelengths, nm, strictly increasing, each in 380..780, at least 3 (and more
///         than the free parameters).
///     reflectance: the measured reflectance (a fraction, 0..1), one value per wavelength.
///     free: names of the fitted parameters, from :func:`parameters` except "oiliness" (it does not change the
///         diffuse reflectance), and "epidermal_hemoglobin" (blood in the epidermis, 0..0.1, a model option: 0, the
///         paper's model, when not free; docs/measured-skin.md, Blood in the epidermis); None: the default set
///         ("melanin", "melanin_blend", "hemoglobin", "epidermis_thickness_mm", "baseline_absorption_scale";
///         docs/measured-skin.md says why).
///     fixed: values of parameters that are not free, {name: value}; a parameter neither free nor given takes its
///         default (the paper's value of an extended parameter; oiliness 0.3, the presets' value); melanin,
///         melanin_blend and hemoglobin have no default and must be given when not free.
///     specular: the surface reflection added to the model: "free" (fitted, 0..0.1; the default), "fresnel" (the
///         normal-incidence Fresnel reflectance of index 1.4, 0.0278) or a number (0 for a measurement with the
///         specular component excluded).
///     bandpass: the measuring instrument's spectral bandpass the model is averaged over (a triangle, FWHM in nm):
///         "spacing" (as wide as the wavelengths' spacing, at most 20 nm; ASTM E308's assumption), a number 0..20
///         (0: the model sampled at the wavelengths themselves); None: the default (docs/measured-skin.md,
///         Instrument bandpass).
///     aperture: the instrument's lit and measured discs, to model the light the skin carries sideways out of the
///         measured one (its "edge loss", largest in the red): "cm2600d-mav", "cm2600d-sav" or the two radii in mm,
///         "LIT,MEASURED"; None: the skin's total reflectance (docs/measured-skin.md, Instrument aperture). Needs the
///         default transport.
///     objective: what is minimised: "reflectance" (the squared reflectance differences; the default) or
///         "cielab" (the squared CIELAB difference of the colours, the reflectance differences only breaking ties).
///     starts: how many of the start table's best entries are refined (the best fit is kept), 1..64; None: 4
///         (docs/measured-skin.md, the restart check).
///     transport: the model fitted, "adding_doubling" (exact totals; the default) or "diffusion" (the paper's), as
///         for :func:`evaluate`.
///     streams: adding-doubling streams per hemisphere, even, 2..64; given, every exact total is solved at them;
///         None: skin's totals from the shipped table of 32-stream totals.
///     model: the model fitted, its options as for :func:`evaluate` (a freed option must be left out of it); None:
///         DJ2006's model.
///
/// Returns:
///     A dict: "params" (every model parameter, fitted and fixed, by name), "epidermal_hemoglobin" (the blood in the
///         epidermis the fitted spectrum has: fitted when free, else the model's, 0 by default), "model" (the model's
///         options the fitted spectrum was computed with, the freed ones at their fitted values:
///         ``evaluate(**fit["params"], model=fit["model"])`` renders the fit), "free" (the fitted names), "specular"
///     ("free", "fresnel" or "fixed"), "specular_offset", "objective", "wavelengths_nm" (K,), "bandpass" ("spacing"
///     or "fwhm"), "bandpass_nm" (the FWHM at each wavelength), "aperture" (None or the discs' radii),
///     "fitted_reflectance" (K,) (model, averaged over the bandpass, times the aperture's measured fraction, plus
///     offset), "rms" (root-mean-square difference from the measurement), "delta_e00" (CIEDE2000 of the two spectra's
///     colours under D65), "lab_measured", "lab_fitted", "starts", "evaluations", "transport", "streams".
///
/// Raises:
///     SpectralSkinError: wavelengths outside 380..780 nm, not increasing or too few; a reflectance that is not one
///         finite value in 0..1 per wavelength; an unknown or repeated free parameter, or "oiliness"; a fixed value
///         out of range or for a free parameter; a paper parameter neither free nor fixed; an unknown specular or
///         objective; a specular number outside 0..0.1; an unknown bandpass or a number outside 0..20; an unknown
///         aperture or radii outside 0.001..100 mm (the measured disc inside the lit one); an aperture with a transport
///         other than "adding_doubling".
///     TypeError: an argument of the wrong type.
#[pyfunction]
#[pyo3(
    name = "fit_spectrum",
    signature = (
        wavelengths_nm, reflectance, *, free = None, fixed = None, specular = None, objective = "reflectance",
        starts = None, transport = "adding_doubling", streams = None, bandpass = None, aperture = None, model = None
    )
)]
#[allow(clippy::too_many_arguments)]
pub(super) fn fit_spectrum_py<'py>(
    py: Python<'py>,
    wavelengths_nm: &Bound<'py, PyAny>,
    reflectance: &Bound<'py, PyAny>,
    free: Option<&Bound<'py, PyAny>>,
    fixed: Option<&Bound<'py, PyAny>>,
    specular: Option<&Bound<'py, PyAny>>,
    objective: &str,
    starts: Option<&Bound<'py, PyAny>>,
    transport: &str,
    streams: Option<&Bound<'py, PyAny>>,
    bandpass: Option<&Bound<'py, PyAny>>,
    aperture: Option<&str>,
    model: Option<Model>,
) -> PyResult<Bound<'py, PyDict>> {
    const NUMBERS: &str = "a 1-D sequence or array of numbers";
    let wavelengths = real_vector("wavelengths_nm", wavelengths_nm, NUMBERS, MAX_SPECTRUM_WAVELENGTHS)?;
    let measured = real_vector("reflectance", reflectance, NUMBERS, MAX_SPECTRUM_WAVELENGTHS)?;
    let options = fit_options(free, fixed, specular, objective, starts, transport, streams, bandpass, aperture, model)?;
    let cancel = std::sync::atomic::AtomicBool::new(false);
    let fit = detached_interruptible(py, &cancel, || {
        crate::inverse::spectrum::fit_spectrum_cancellable(&wavelengths, &measured, &options, &cancel)
    })?;
    fit_dict(py, &fit)
}

/// A fit as the dict `fit_spectrum` returns (and `fit_spectra` one per spectrum).
pub(super) fn fit_dict<'py>(py: Python<'py>, fit: &SpectrumFit) -> PyResult<Bound<'py, PyDict>> {
    let dict = to_py(py, fit)?.cast_into::<PyDict>()?;
    float_dermis(&dict, &fit.model)?;
    dict.set_item("wavelengths_nm", PyArray1::from_slice(py, &fit.wavelengths_nm))?;
    dict.set_item("fitted_reflectance", PyArray1::from_slice(py, &fit.fitted_reflectance))?;
    Ok(dict)
}

/// The options of `fit_spectrum` and `fit_spectra` from their keywords (each named in its error).
#[allow(clippy::too_many_arguments)]
pub(super) fn fit_options(
    free: Option<&Bound<'_, PyAny>>,
    fixed: Option<&Bound<'_, PyAny>>,
    specular: Option<&Bound<'_, PyAny>>,
    objective: &str,
    starts: Option<&Bound<'_, PyAny>>,
    transport: &str,
    streams: Option<&Bound<'_, PyAny>>,
    bandpass: Option<&Bound<'_, PyAny>>,
    aperture: Option<&str>,
    model: Option<Model>,
) -> PyResult<FitOptions> {
    let mut options = FitOptions::default();
    if let Some(free) = free.filter(|f| !f.is_none()) {
        reject_string(free, "free must be a sequence of parameter names")?;
        options.free =
            free.try_iter()?.map(|item| item.and_then(|i| i.extract::<String>())).collect::<PyResult<Vec<String>>>()?;
    }
    if let Some(fixed) = fixed.filter(|f| !f.is_none()) {
        let dict = fixed.cast::<PyDict>().map_err(|_| {
            pyo3::exceptions::PyTypeError::new_err(format!(
                "fixed must be a dict {{name: value}}; got {}",
                type_name(fixed)
            ))
        })?;
        let mut values = [None; PARAM_COUNT];
        for (key, value) in dict.iter() {
            let name: String = key.extract()?;
            let Some(i) = PARAMS.iter().position(|p| p.name == name) else {
                let names: Vec<&str> = PARAMS.iter().map(|p| p.name).collect();
                return Err(invalid("fixed", format!("unknown parameter {name:?}; known: {}", names.join(", "))));
            };
            values[i] = Some(real_of(&format!("fixed[{name:?}]"), &value)?.0);
        }
        options.fixed = values;
    }
    options.specular = match specular.filter(|s| !s.is_none()) {
        None => Specular::Free,
        Some(s) if s.is_instance_of::<PyString>() => match s.extract::<String>()?.as_str() {
            "free" => Specular::Free,
            "fresnel" => Specular::Fresnel,
            other => return Err(invalid("specular", format!("unknown {other:?}; \"free\", \"fresnel\" or a number"))),
        },
        Some(s) => Specular::Fixed(real_of("specular", s)?.0),
    };
    options.bandpass = match bandpass.filter(|b| !b.is_none()) {
        None => options.bandpass,
        Some(b) if b.is_instance_of::<PyString>() => match b.extract::<String>()?.as_str() {
            "spacing" => Bandpass::Spacing,
            other => return Err(invalid("bandpass", format!("unknown {other:?}; \"spacing\" or a number"))),
        },
        Some(b) => Bandpass::FwhmNm(real_of("bandpass", b)?.0),
    };
    options.aperture = aperture.map(Aperture::parse).transpose()?;
    options.objective = by_name::<Objective>("objective", objective, &ALL_OBJECTIVES)?;
    if let Some(n) = count_arg("starts", starts)? {
        options.starts = usize::try_from(n.0).map_err(|_| invalid("starts", format!("must be >= 1; got {}", n.0)))?;
    }
    options.request.transport = transport_arg(transport)?;
    options.request.model = model_of(model);
    if let Some(n) = streams_arg(streams)? {
        options.request.accuracy = options.request.accuracy.solved_at(n);
    }
    Ok(options)
}
