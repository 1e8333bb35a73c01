//! The argument types every pyfunction shares: the skin parameters ([`ParamArgs`]: the seven keywords, read as
//! numbers for one material or as map sources for `maps`), the knobs ([`Knobs`]: accuracy, wavelengths, working
//! space, target, boundaries, transport, streams, surface), and the typed choices they are read into ([`Named`],
//! [`Choice`], [`Streams`]): each choice's names and message come from the core's one list.
//!
//! Choices whose default is None are typed in the signatures (`surface: Option<Choice<SurfaceModel>>`,
//! `streams: Option<Streams>`); those with a named default stay `&str` there and are typed by [`named`] on the first
//! line, because pyo3 writes only a literal default into the `__text_signature__` that `help()`, `inspect` and the
//! add-on read (`transport="adding_doubling"`), and a literal is a `&str`.

use pyo3::prelude::*;

use crate::accuracy::{Accuracy, AccuracyLevel};
use crate::color::{
    RgbMapping, WavelengthPlacement, WorkingSpace, ALL_RGB_MAPPINGS, ALL_WAVELENGTH_PLACEMENTS, ALL_WORKING_SPACES,
};
use crate::diffusion::{Boundaries, Combination, MultipoleTerms, ALL_BOUNDARIES, ALL_COMBINATIONS};
use crate::evaluate::{Outputs, ProfileGrid, Request};
use crate::fit::blender_target::{Engine, Target};
use crate::fit::SubsurfaceMethod;
use crate::maps::io::{Compression, Precision, ALL_COMPRESSIONS, ALL_PRECISIONS};
use crate::maps::request::{ParamRequest, Source};
use crate::skin::params::{EXTENDED_PARAMS, PARAMS, PARAM_COUNT};
use crate::skin::{SkinModel, SkinParams};
use crate::surface::lobes::{SurfaceModel, ALL_SURFACE_MODELS};
use crate::transport::Transport;

use super::convert::{by_name, real_arg, resolve_params, streams_arg, to_u32, transport_arg, Count, Real};
use super::errors::invalid;

/// A core enum a keyword names: the keyword and how a name is read (the core's list of names, or its `from_name`,
/// whose error lists them).
pub(super) trait Named: Sized {
    fn from_keyword(name: &str) -> PyResult<Self>;
}

/// Enums read by their serde names from the core's `ALL_*` list; the error names the keyword and lists the names.
macro_rules! named_by_serde {
    ($($ty:ty => $keyword:literal, $all:expr;)*) => {$(
        impl Named for $ty {
            fn from_keyword(name: &str) -> PyResult<Self> {
                by_name($keyword, name, &$all)
            }
        }
    )*};
}

named_by_serde! {
    WavelengthPlacement => "wavelength_placement", ALL_WAVELENGTH_PLACEMENTS;
    Combination => "combination", ALL_COMBINATIONS;
    WorkingSpace => "working_space", ALL_WORKING_SPACES;
    RgbMapping => "rgb_mapping", ALL_RGB_MAPPINGS;
    Boundaries => "boundaries", ALL_BOUNDARIES;
    SurfaceModel => "surface", ALL_SURFACE_MODELS;
    Precision => "precision", ALL_PRECISIONS;
    Compression => "compression", ALL_COMPRESSIONS;
}

impl Named for Transport {
    fn from_keyword(name: &str) -> PyResult<Self> {
        transport_arg(name)
    }
}

impl Named for AccuracyLevel {
    fn from_keyword(name: &str) -> PyResult<Self> {
        Ok(AccuracyLevel::from_name(name)?)
    }
}

impl Named for Engine {
    fn from_keyword(name: &str) -> PyResult<Self> {
        Ok(Engine::from_name(name)?)
    }
}

impl Named for SubsurfaceMethod {
    fn from_keyword(name: &str) -> PyResult<Self> {
        Ok(SubsurfaceMethod::from_name(name)?)
    }
}

/// The choice `name` names (see [`Named`]).
pub(super) fn named<T: Named>(name: &str) -> PyResult<T> {
    T::from_keyword(name)
}

/// A choice typed in a signature (a keyword whose default is None): read from a str by [`Named`].
#[derive(Debug, Clone, Copy)]
pub(super) struct Choice<T>(pub(super) T);

impl<'a, 'py, T: Named> FromPyObject<'a, 'py> for Choice<T> {
    type Error = PyErr;

    fn extract(obj: pyo3::Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let name: String = obj.extract()?;
        Ok(Choice(T::from_keyword(&name)?))
    }
}

/// `streams=` typed: an even integer in the solver's range ([`streams_arg`]'s rule; a bool, str or float is a
/// TypeError).
#[derive(Debug, Clone, Copy)]
pub(super) struct Streams(pub(super) usize);

impl<'a, 'py> FromPyObject<'a, 'py> for Streams {
    type Error = PyErr;

    fn extract(obj: pyo3::Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let streams = streams_arg(Some(&*obj))?;
        streams.map(Streams).ok_or_else(|| invalid("streams", "None is no count of streams"))
    }
}

/// `model=` typed: the model's options ([`SkinModel`]) as a dict by their JSON names, the others at their defaults
/// (the "model" of an `evaluate` result reads back as it is); an unknown name or a value of the wrong kind is an
/// error naming it, a value out of range the core's error when the model is used. Not a dict: a TypeError.
#[derive(Debug, Clone, Copy)]
pub(super) struct Model(pub(super) SkinModel);

impl<'a, 'py> FromPyObject<'a, 'py> for Model {
    type Error = PyErr;

    fn extract(obj: pyo3::Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        if !obj.is_instance_of::<pyo3::types::PyDict>() {
            return Err(pyo3::exceptions::PyTypeError::new_err(format!(
                "model must be a dict {{option: value}} (e.g. {{\"epidermal_hemoglobin\": 0.01}}); got {}",
                super::convert::type_name(&obj)
            )));
        }
        reject_booleans("model", &obj)?;
        pythonize::depythonize::<SkinModel>(&obj).map(Model).map_err(|e| invalid(culprit(&obj), e.to_string()))
    }
}

/// The rule of every numeric argument inside `model=` too: True or False is no number (serde would read it as 1 or
/// 0). `name` is the entry's path, `model["NAME"]...`.
fn reject_booleans(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<()> {
    use super::convert::{is_boolean, type_name};
    if is_boolean(obj) {
        return Err(pyo3::exceptions::PyTypeError::new_err(format!(
            "{name} must be a number, a name or a dict; got {} {}",
            type_name(obj),
            obj.repr()?
        )));
    }
    if let Ok(dict) = obj.cast::<pyo3::types::PyDict>() {
        for (key, value) in dict.iter() {
            reject_booleans(&format!("{name}[{}]", key.repr()?), &value)?;
        }
    }
    Ok(())
}

/// The name of the `model=` entry that does not read (pythonize's error does not say which): `model["NAME"]`, the
/// first entry that fails alone, else `model`.
fn culprit(model: &Bound<'_, PyAny>) -> String {
    let Ok(dict) = model.cast::<pyo3::types::PyDict>() else { return "model".into() };
    for (key, value) in dict.iter() {
        let alone = pyo3::types::PyDict::new(model.py());
        if alone.set_item(&key, value).is_ok() && pythonize::depythonize::<SkinModel>(alone.as_any()).is_err() {
            return format!("model[{}]", key.repr().map_or_else(|_| "?".into(), |r| r.to_string()));
        }
    }
    "model".into()
}

/// The model of an optional `model=`: the given options, else the defaults (DJ2006's model).
pub(super) fn model_of(model: Option<Model>) -> SkinModel {
    model.map(|m| m.0).unwrap_or_default()
}

/// The streams of an optional `streams=`.
pub(super) fn streams_of(streams: Option<Streams>) -> Option<usize> {
    streams.map(|s| s.0)
}

/// The knobs the material fronts share (`evaluate`, `profile`, `maps`, `shader_table`), typed: each front sets
/// those it takes from its keywords and leaves the others at their defaults (a material's: no profile grid of its
/// own, the directional combination, the linear RGB mapping).
#[derive(Debug, Clone, Copy)]
pub(super) struct Knobs {
    pub(super) accuracy: AccuracyLevel,
    pub(super) wavelength_step_nm: Option<Real>,
    pub(super) wavelength_placement: Option<WavelengthPlacement>,
    pub(super) multipole_pairs: Option<Count>,
    pub(super) profile_r_min_mm: Option<Real>,
    pub(super) profile_r_max_mm: Option<Real>,
    pub(super) profile_count: Option<Count>,
    pub(super) combination: Combination,
    pub(super) working_space: WorkingSpace,
    pub(super) rgb_mapping: RgbMapping,
    pub(super) boundaries: Boundaries,
    pub(super) target: Target,
    /// Where the totals come from.
    pub(super) transport: Transport,
    /// Adding-doubling streams; None: the level's.
    pub(super) streams: Option<usize>,
    pub(super) surface: SurfaceModel,
    /// The model's options (`model=`); DJ2006's by default.
    pub(super) model: SkinModel,
}

impl Default for Knobs {
    fn default() -> Self {
        let request = Request::default();
        Knobs {
            accuracy: AccuracyLevel::Default,
            wavelength_step_nm: None,
            wavelength_placement: None,
            multipole_pairs: None,
            profile_r_min_mm: None,
            profile_r_max_mm: None,
            profile_count: None,
            combination: request.combination,
            working_space: request.working_space,
            rgb_mapping: request.rgb_mapping,
            boundaries: request.boundaries,
            target: request.target,
            transport: request.transport,
            streams: None,
            surface: request.surface,
            model: request.model,
        }
    }
}

impl Knobs {
    /// The core's request for `outputs` with these knobs: the level's settings, each knob given overriding its own.
    pub(super) fn request(&self, outputs: Outputs) -> PyResult<Request> {
        let level = self.accuracy.accuracy();
        let defaults = level.profile_grid;
        let count = match self.profile_count {
            Some(Count(n)) => to_u32("profile_count", "number of profile radii", n)? as usize,
            None => defaults.count,
        };
        let multipole_terms = match self.multipole_pairs {
            Some(Count(n)) => MultipoleTerms::Pairs(to_u32("multipole_pairs", "image pairs per side", n)?),
            None => level.multipole_terms,
        };
        let accuracy = Accuracy {
            wavelength_step_nm: self.wavelength_step_nm.map_or(level.wavelength_step_nm, |r| r.0),
            wavelength_placement: self.wavelength_placement.unwrap_or(level.wavelength_placement),
            multipole_terms,
            profile_grid: ProfileGrid {
                r_min_mm: self.profile_r_min_mm.map_or(defaults.r_min_mm, |r| r.0),
                r_max_mm: self.profile_r_max_mm.map_or(defaults.r_max_mm, |r| r.0),
                count,
            },
            ..level
        };
        // Streams given ask for solved totals at them; else the level's (the table, or the reference's solves).
        let accuracy = self.streams.map_or(accuracy, |n| accuracy.solved_at(n));
        Ok(Request {
            outputs,
            accuracy,
            combination: self.combination,
            working_space: self.working_space,
            rgb_mapping: self.rgb_mapping,
            boundaries: self.boundaries,
            target: self.target,
            transport: self.transport,
            surface: self.surface,
            model: self.model,
        })
    }
}

/// The skin parameters' keywords, in [`PARAMS`] order (melanin, melanin_blend, hemoglobin, oiliness, then the
/// extended physiology), each None when not given: one material's numbers (`evaluate`, `profile`), a map's sources
/// (`maps`), or the extended physiology alone (`shader_table`).
pub(super) struct ParamArgs<'a, 'py>(pub(super) [Option<&'a Bound<'py, PyAny>>; PARAM_COUNT]);

impl<'a, 'py> ParamArgs<'a, 'py> {
    /// The paper's four keywords and the extended physiology's three.
    pub(super) fn new(four: [Option<&'a Bound<'py, PyAny>>; 4], extended: [Option<&'a Bound<'py, PyAny>>; 3]) -> Self {
        let [m, b, h, o] = four;
        let [t, s, g] = extended;
        ParamArgs([m, b, h, o, t, s, g])
    }

    /// One material: a preset and/or the four (explicit ones override the preset's; without a preset all four are
    /// required), the extended physiology given, else the preset's, else the default. The core checks the ranges.
    pub(super) fn skin_params(&self, preset: Option<&str>) -> PyResult<SkinParams> {
        let mut values = [None; 4];
        for ((value, spec), obj) in values.iter_mut().zip(&PARAMS).zip(self.0) {
            *value = real_arg(spec.name, obj)?;
        }
        let params = resolve_params(preset, values)?;
        let mut all = params.values();
        for ((spec, obj), value) in PARAMS.iter().zip(self.0).zip(&mut all).skip(4) {
            if let Some(v) = real_arg(spec.name, obj)? {
                *value = v.0;
            }
        }
        Ok(SkinParams::from_values(all)?)
    }

    /// The extended physiology alone: each given value, checked against its range, else its default.
    pub(super) fn extended(&self) -> PyResult<[f64; 3]> {
        let mut extended = crate::skin::params::EXTENDED_DEFAULTS;
        for ((spec, obj), value) in EXTENDED_PARAMS.iter().zip(&self.0[4..]).zip(&mut extended) {
            if let Some(v) = real_arg(spec.name, *obj)? {
                *value = spec.check(v.0)?;
            }
        }
        Ok(extended)
    }

    /// The map sources of `maps`: `request` (the four-channel array's) with each parameter's own source, read by
    /// `source` (an (H, W) array's texels or a number).
    pub(super) fn map_request(
        &self,
        mut request: ParamRequest,
        source: impl Fn(&str, &Bound<'py, PyAny>) -> PyResult<Source>,
    ) -> PyResult<ParamRequest> {
        for (spec, obj) in PARAMS.iter().zip(self.0) {
            if let Some(obj) = obj {
                request = request.with(spec, source(spec.name, obj)?);
            }
        }
        Ok(request)
    }

    /// Which parameters are given.
    pub(super) fn given(&self) -> [bool; PARAM_COUNT] {
        self.0.map(|obj| obj.is_some())
    }
}
