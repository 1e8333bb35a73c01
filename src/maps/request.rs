//! What a map run reads, as one typed request indexed by parameter, and the input rules every front shares.
//!
//! Each of the seven parameters ([`crate::skin::params::PARAMS`]: the paper's four, then the extended physiology)
//! has at most one [`Source`]: one value everywhere, texels in memory (Python's arrays), or a file (an image, or with
//! `<UDIM>` in its name a tile set: one image per tile, [`super::udim`]). Beside them the four-channel input
//! ([`Combined`]: Python's `params` array, the CLI's `--params` EXR) gives each of the four a channel that its own
//! source, where given, replaces. The rules live here, once: each of the four needs a source, at least one source
//! is a map (a map gives the size), texels agree in (H, W) and stay under the texel bound, and a constant is in its
//! parameter's range unless the run clamps. The readers of files ([`super::io::read_params`]) own the rules of files
//! (existence, format, matching sizes, tile sets); the CLI and the binding only translate their arguments into a
//! [`ParamRequest`].

use std::path::PathBuf;

use super::io::{
    check_texel_count, default_extended, read_params, ParamImage, ParamInputs, ParamSource, Plane, NO_MAP_GIVEN,
};
use crate::error::SkinError;
use crate::skin::params::{ParamSpec, PAPER_PARAMS, PARAMS, PARAM_COUNT};

/// The paper's four, each of which needs a source (the extended physiology defaults to the paper's values).
const REQUIRED: usize = PAPER_PARAMS.len();

/// Row-major values of one (H, W) map, row 0 at the top.
#[derive(Debug, Clone, PartialEq)]
pub struct Texels {
    pub width: usize,
    pub height: usize,
    pub values: Vec<f32>,
}

/// Where one parameter's values come from.
#[derive(Debug, Clone, PartialEq)]
pub enum Source {
    /// One value for every texel, in the parameter's own unit.
    Constant(f64),
    /// A map held in memory.
    Texels(Texels),
    /// A one-parameter image ([`super::io::PARAM_IMAGE_FORMS`]), or a UDIM tile set when its name holds `<UDIM>`.
    File(PathBuf),
}

/// The four-channel input: a channel for each of the paper's four parameters.
#[derive(Debug, Clone, PartialEq)]
pub enum Combined {
    /// A parameter EXR with channels named like the parameters (and optionally the extended physiology's), or a UDIM
    /// tile set of them.
    File(PathBuf),
    /// The channels of an (H, W, 4) array, in [`PAPER_PARAMS`] order; None where the parameter has a source of its
    /// own (that channel is not copied).
    Texels { width: usize, height: usize, planes: [Option<Vec<f32>>; REQUIRED] },
}

/// The parameter sources of one map run. Build it with [`ParamRequest::with`]; [`ParamRequest::check`] applies the
/// rules, [`ParamRequest::into_image`] and [`ParamRequest::file_inputs`] hand it to the pipeline.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ParamRequest {
    pub combined: Option<Combined>,
    /// Each parameter's own source, in [`PARAMS`] order (see [`ParamRequest::source`]).
    pub sources: [Option<Source>; PARAM_COUNT],
}

/// The position of `spec` in [`PARAMS`].
fn index_of(spec: &ParamSpec) -> usize {
    PARAMS.iter().position(|p| p.name == spec.name).unwrap_or(PARAM_COUNT)
}

impl ParamRequest {
    /// A request with the four-channel input `combined` and no source of its own for any parameter.
    pub fn new(combined: Option<Combined>) -> Self {
        ParamRequest { combined, ..ParamRequest::default() }
    }

    /// This request with `source` for the parameter `spec` (one of [`PARAMS`]), replacing any it had.
    pub fn with(mut self, spec: &ParamSpec, source: Source) -> Self {
        if let Some(slot) = self.sources.get_mut(index_of(spec)) {
            *slot = Some(source);
        }
        self
    }

    /// The parameter `spec`'s own source, if given.
    pub fn source(&self, spec: &ParamSpec) -> Option<&Source> {
        self.sources.get(index_of(spec)).and_then(Option::as_ref)
    }

    /// Every input rule that needs no file read, in the order a caller meets them: each of the four has a source
    /// (its own or a channel of the four-channel input); at least one source is a map; the maps in memory agree in
    /// (H, W) and hold 1 to [`super::io::MAX_TEXELS`] texels; without `clamp`, every constant is finite and in its
    /// parameter's range ([`SkinError::BadConstant`]; with `clamp` it is clamped and reported with the planes).
    pub fn check(&self, clamp: bool) -> Result<(), SkinError> {
        let missing: Vec<&str> = PAPER_PARAMS
            .iter()
            .enumerate()
            .filter(|&(p, _)| self.sources[p].is_none() && !self.channel_given(p))
            .map(|(_, spec)| spec.name)
            .collect();
        if !missing.is_empty() {
            let names: Vec<&str> = PAPER_PARAMS.iter().map(|p| p.name).collect();
            return Err(SkinError::invalid(
                "parameters",
                format!(
                    "give params (the four-channel input) or a map or constant for each of {}; missing: {}",
                    names.join(", "),
                    missing.join(", ")
                ),
            ));
        }
        let has_map =
            self.combined.is_some() || self.sources.iter().flatten().any(|s| !matches!(s, Source::Constant(_)));
        if !has_map {
            return Err(SkinError::invalid("parameters", NO_MAP_GIVEN));
        }
        if let Some((width, height)) = self.texel_size()? {
            check_texel_count("shapes", width, height)?;
        }
        if !clamp {
            self.check_constants()?;
        }
        Ok(())
    }

    /// Whether the four-channel input gives parameter `p` (one of the four) a channel.
    fn channel_given(&self, p: usize) -> bool {
        match &self.combined {
            Some(Combined::File(_)) => true,
            Some(Combined::Texels { planes, .. }) => planes[p].is_some(),
            None => false,
        }
    }

    /// The (width, height) the maps in memory agree on; None without any. An error lists each map's (H, W).
    fn texel_size(&self) -> Result<Option<(usize, usize)>, SkinError> {
        let mut shapes: Vec<(String, usize, usize)> = Vec::new();
        if let Some(Combined::Texels { width, height, .. }) = &self.combined {
            shapes.push((format!("params ({height}, {width}, {REQUIRED})"), *width, *height));
        }
        for (spec, source) in PARAMS.iter().zip(&self.sources) {
            if let Some(Source::Texels(t)) = source {
                shapes.push((format!("{} ({}, {})", spec.name, t.height, t.width), t.width, t.height));
            }
        }
        let Some(&(_, width, height)) = shapes.first() else {
            return Ok(None);
        };
        if shapes.iter().any(|&(_, w, h)| (w, h) != (width, height)) {
            let listed: Vec<&str> = shapes.iter().map(|(n, _, _)| n.as_str()).collect();
            return Err(SkinError::invalid(
                "shapes",
                format!("the arrays must agree in (H, W); got {}", listed.join(", ")),
            ));
        }
        Ok(Some((width, height)))
    }

    /// Every constant finite and in its parameter's range.
    fn check_constants(&self) -> Result<(), SkinError> {
        for (spec, source) in PARAMS.iter().zip(&self.sources) {
            if let Some(Source::Constant(v)) = source {
                if !(*v >= spec.min && *v <= spec.max) {
                    return Err(SkinError::BadConstant {
                        parameter: spec.name,
                        min: spec.min,
                        max: spec.max,
                        value: *v,
                    });
                }
            }
        }
        Ok(())
    }

    /// The request as the file reader's inputs ([`read_params`], [`super::pipeline::run_maps`]), after
    /// [`ParamRequest::check`]. Only files and constants go there: a map in memory is refused (use
    /// [`ParamRequest::into_image`]), and so is a file of one of the four beside the four-channel file (its channel
    /// is replaced by a constant only).
    pub fn file_inputs(&self, clamp: bool) -> Result<ParamInputs, SkinError> {
        self.check(clamp)?;
        let file_source = |p: usize| -> Result<Option<ParamSource>, SkinError> {
            Ok(match &self.sources[p] {
                None => None,
                Some(Source::Constant(v)) => Some(ParamSource::Constant(*v)),
                Some(Source::File(path)) => Some(ParamSource::File(path.clone())),
                Some(Source::Texels(_)) => {
                    return Err(SkinError::invalid(
                        PARAMS[p].name,
                        "a map in memory cannot be read as a file: compute from memory (into_image) instead",
                    ))
                }
            })
        };
        let inputs = match &self.combined {
            Some(Combined::File(path)) => {
                let mut constants = [None; REQUIRED];
                for (p, constant) in constants.iter_mut().enumerate() {
                    *constant =
                        match file_source(p)? {
                            None => None,
                            Some(ParamSource::Constant(v)) => Some(v),
                            Some(ParamSource::File(_)) => return Err(SkinError::invalid(
                                PARAMS[p].name,
                                "a map file cannot replace a channel of the params file: give a constant for it, or \
                                 a map for each of the four instead of params",
                            )),
                        };
                }
                ParamInputs::Multi { path: path.clone(), constants }
            }
            Some(Combined::Texels { .. }) => {
                return Err(SkinError::invalid(
                    "params",
                    "an array cannot be read as a file: compute from memory (into_image) instead",
                ))
            }
            None => {
                let mut four = Vec::with_capacity(REQUIRED);
                for p in 0..REQUIRED {
                    // `check` found a source for each of the four.
                    four.push(file_source(p)?.unwrap_or(ParamSource::Constant(f64::NAN)));
                }
                ParamInputs::Separate(four.try_into().map_err(|_| SkinError::invalid("parameters", "not four"))?)
            }
        };
        let mut extended = [None, None, None];
        for (k, slot) in extended.iter_mut().enumerate() {
            *slot = file_source(REQUIRED + k)?;
        }
        Ok(ParamInputs::Extended { inputs: Box::new(inputs), extended })
    }

    /// The parameter planes, after [`ParamRequest::check`]: maps in memory as they are (no copy), files read with
    /// [`read_params`] (a map in memory beside files must have their size), constants as constant planes, an
    /// extended parameter without a source (nor a channel of the four-channel file) at its default. Values are not
    /// range-checked here ([`super::pipeline::check_planes`] does that).
    pub fn into_image(self, clamp: bool) -> Result<ParamImage, SkinError> {
        let size = {
            self.check(clamp)?;
            self.texel_size()?
        };
        let reads_files = matches!(self.combined, Some(Combined::File(_)))
            || self.sources.iter().flatten().any(|s| matches!(s, Source::File(_)));
        let mut image = match (reads_files, size) {
            (true, _) => read_params(&self.without_texels().file_inputs(true)?)?,
            // Each of the four is replaced below (`check` found a source for each).
            (false, Some((width, height))) => {
                ParamImage::new(width, height, std::array::from_fn(|_| Plane::Constant(0.0)))
            }
            (false, None) => return Err(SkinError::invalid("parameters", NO_MAP_GIVEN)),
        };
        if let Some((width, height)) = size.filter(|&s| s != (image.width, image.height)) {
            return Err(SkinError::invalid(
                "shapes",
                format!(
                    "the arrays must agree in (H, W) with the files; got ({height}, {width}), the files ({}, {})",
                    image.height, image.width
                ),
            ));
        }
        let ParamRequest { combined, sources } = self;
        if let Some(Combined::Texels { planes, .. }) = combined {
            for (p, plane) in planes.into_iter().enumerate() {
                if let Some(values) = plane {
                    image.planes[p] = Plane::Texels(values);
                }
            }
        }
        let defaults = default_extended();
        for (p, source) in sources.into_iter().enumerate() {
            let plane = match source {
                Some(Source::Constant(v)) => Plane::Constant(v as f32),
                Some(Source::Texels(t)) => Plane::Texels(t.values),
                // Read above (files), or the channel of the four-channel file, or the default.
                Some(Source::File(_)) => continue,
                None if reads_files || p < REQUIRED => continue,
                None => defaults[p - REQUIRED].clone(),
            };
            if p < REQUIRED {
                image.planes[p] = plane;
            } else {
                image.extended[p - REQUIRED] = plane;
            }
        }
        Ok(image)
    }

    /// This request with its maps in memory (its own, and the four-channel array's channels) replaced by a constant
    /// 0 (their planes are put in afterwards), so that what is left is files and constants only.
    fn without_texels(&self) -> ParamRequest {
        let mut sources = self.sources.clone().map(|s| match s {
            Some(Source::Texels(_)) => Some(Source::Constant(0.0)),
            other => other,
        });
        if let Some(Combined::Texels { planes, .. }) = &self.combined {
            for (source, plane) in sources.iter_mut().zip(planes) {
                if plane.is_some() {
                    *source = Some(Source::Constant(0.0));
                }
            }
        }
        let combined = match &self.combined {
            Some(Combined::File(path)) => Some(Combined::File(path.clone())),
            _ => None,
        };
        ParamRequest { combined, sources }
    }
}
