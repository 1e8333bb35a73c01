//! The request-driven entry point: parameters and a [`Request`] in, only the requested outputs computed.

use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

pub use crate::accuracy::{Accuracy, AccuracyLevel, ProfileGrid};
use crate::color::{spectrum_to_rgb, ColourIntegration, RgbMapping, WorkingSpace};
use crate::diffusion::{clamped_reflectance_profiles_cancellable, Boundaries, Combination, LayerStack};
use crate::error::{check_range, SkinError};
use crate::fit::blender_target::{Target, TargetInfo};
use crate::fit::burley::{fit_burley_second_moment, BurleyFit, BurleyGrid, SECOND_MOMENT_FREQUENCY_PER_MM};
pub use crate::fit::MethodParams;
use crate::fit::{RadiusFit, SubsurfaceMethod, DEFAULT_METHOD};
use crate::layer::Layer;
use crate::skin::{skin_layers, SkinModel, SkinParams};
use crate::surface::lobes::SurfaceModel;
use crate::surface::principled::{specular_for, SpecularParams, SurfaceConstants};
use crate::transport::profile_table::{exact_shape, Shape};
use crate::transport::total_table::TotalTable;
use crate::transport::{total_diffuse_reflectance_cancellable, ExactTotals, Transport};

/// Which outputs to compute. Each costs only what it needs: albedo is one transform value per wavelength, the radius
/// a few dozen, a radial profile an inverse transform per wavelength.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub struct Outputs {
    /// RGB total diffuse reflectance (Base Color for Christensen-Burley).
    pub albedo: bool,
    /// Subsurface Radius (and Base Color) per Cycles method.
    pub radius: bool,
    /// RGB radial profile R(r) on the profile grid.
    pub profile_rgb: bool,
    /// Radial profile per wavelength.
    pub profile_spectral: bool,
    /// Total diffuse reflectance per wavelength.
    pub spectrum: bool,
    /// Principled specular inputs from the oiliness.
    pub specular: bool,
}

/// An output a material map run can compute (`maps`: Python's `outputs=`, the CLI's `--outputs`, one spelling).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum), value(rename_all = "snake_case"))]
#[serde(rename_all = "snake_case")]
pub enum MaterialOutput {
    /// Base Color (the albedo, or the method's Base Color with `Radius`).
    Albedo,
    /// Subsurface Radius (and the method's Base Color).
    Radius,
    /// Specular IOR Level.
    Specular,
}

/// Every material output.
pub const ALL_MATERIAL_OUTPUTS: [MaterialOutput; 3] =
    [MaterialOutput::Albedo, MaterialOutput::Radius, MaterialOutput::Specular];

impl Outputs {
    /// The [`Outputs`] that compute these material outputs.
    pub fn of_material(outputs: &[MaterialOutput]) -> Outputs {
        let wanted = |o| outputs.contains(&o);
        Outputs {
            albedo: wanted(MaterialOutput::Albedo),
            radius: wanted(MaterialOutput::Radius),
            specular: wanted(MaterialOutput::Specular),
            ..Outputs::default()
        }
    }

    pub fn all() -> Outputs {
        Outputs {
            albedo: true,
            radius: true,
            profile_rgb: true,
            profile_spectral: true,
            spectrum: true,
            specular: true,
        }
    }
    /// What a material needs: albedo, radius and specular.
    pub fn material() -> Outputs {
        Outputs { albedo: true, radius: true, specular: true, ..Outputs::default() }
    }
}

/// What to compute, how accurately, and with which model choices.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct Request {
    pub outputs: Outputs,
    pub accuracy: Accuracy,
    pub model: SkinModel,
    pub combination: Combination,
    pub working_space: WorkingSpace,
    /// The Blender version and engine the Principled inputs are for.
    pub target: Target,
    /// How the RGB radial profile's colours are formed: linearly (the default, with negative channels where the
    /// light is outside the gamut) or made non-negative at the same luminance ([`RgbMapping`]). Absent from JSON
    /// when linear.
    #[serde(default, skip_serializing_if = "RgbMapping::is_linear")]
    pub rgb_mapping: RgbMapping,
    /// The layers' boundary conditions: the paper's (the default) or capped, which makes every profile non-negative
    /// and the total monotone in absorption by construction ([`Boundaries`], docs/robustness.md). Absent from JSON
    /// when the paper's.
    #[serde(default, skip_serializing_if = "Boundaries::is_paper")]
    pub boundaries: Boundaries,
    /// How each wavelength's total diffuse reflectance is computed: exactly (adding-doubling, the default; the radial
    /// profile and the radius fit keep the multipole's shape scaled to that total) or by the paper's multipole
    /// ([`Transport`]). Always in JSON, so every result, sidecar and cache key names it.
    #[serde(default)]
    pub transport: Transport,
    /// The surface reflection the specular inputs stand in for (`surface::lobes::SurfaceModel`): the measured two-lobe
    /// surface (base lobe plus Coat; the default) or DJ2006's oil layer. Absent from JSON when the paper's, so a JSON
    /// without it (also one written before the field existed) reads as the paper's.
    #[serde(default = "SurfaceModel::absent", skip_serializing_if = "SurfaceModel::is_paper")]
    pub surface: SurfaceModel,
}

impl Request {
    pub fn new(outputs: Outputs) -> Request {
        Request { outputs, ..Request::default() }
    }
}

/// Base Color and radius for every method the target offers (serialised keyed by method name; a method the
/// target's Blender does not offer is absent).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Methods {
    pub burley: MethodParams,
    pub random_walk: MethodParams,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub random_walk_legacy: Option<MethodParams>,
    pub random_walk_skin: MethodParams,
}

impl Methods {
    /// `method`'s inputs, if the target offers it.
    pub fn get(&self, method: SubsurfaceMethod) -> Option<&MethodParams> {
        match method {
            SubsurfaceMethod::Burley => Some(&self.burley),
            SubsurfaceMethod::RandomWalk => Some(&self.random_walk),
            SubsurfaceMethod::RandomWalkLegacy => self.random_walk_legacy.as_ref(),
            SubsurfaceMethod::RandomWalkSkin => Some(&self.random_walk_skin),
        }
    }

    /// The offered methods with their inputs, in Blender's menu order.
    pub fn iter(&self) -> impl Iterator<Item = (SubsurfaceMethod, &MethodParams)> {
        SubsurfaceMethod::ALL.into_iter().filter_map(|m| self.get(m).map(|p| (m, p)))
    }
}

/// Radial profiles on a radius grid.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RadialProfile {
    pub radii_mm: Vec<f64>,
    /// R(r) per RGB channel, mm^-2 (if requested), formed as `Request::rgb_mapping` says. With the default
    /// [`RgbMapping::Linear`] a channel is negative at radii whose light lies outside the working space's gamut (in
    /// the far tail only red light is left; docs/cli.md, "Radial profiles", gives the figures per preset); with
    /// [`RgbMapping::NonNegative`] no value is negative. The spectral profiles are never negative.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rgb_per_mm2: Option<Vec<[f64; 3]>>,
    /// R(r) per wavelength: `spectral_per_mm2[k][i]` at wavelength k and radius i, mm^-2 (if requested).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spectral_per_mm2: Option<Vec<Vec<f64>>>,
    /// The deepest negative value a spectral profile had before the clamp to zero, beyond round-off: only the paper's
    /// boundaries give one, on a thin index-mismatched epidermis the dermis does not fill (none for the presets;
    /// docs/robustness.md). Absent when there was none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub negative_lobe: Option<SpectralLobe>,
}

impl std::fmt::Display for SpectralLobe {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let place = format!("at {} mm and {} nm", self.radius_mm, self.wavelength_nm);
        f.write_str(&crate::diffusion::NegativeLobe::message(&place, self.relative_to_peak, self.boundaries))
    }
}

/// [`crate::diffusion::NegativeLobe`] of an evaluation: which wavelength, where, and how deep.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SpectralLobe {
    pub wavelength_nm: f64,
    /// The request's boundaries (what the lobe comes from differs: `NegativeLobe::message`).
    pub boundaries: Boundaries,
    pub radius_mm: f64,
    /// The most negative value over that wavelength's largest magnitude on the profile grid.
    pub relative_to_peak: f64,
}

/// How much work an evaluation did (so callers and tests can see that only what was asked was computed).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
pub struct Work {
    pub wavelengths: usize,
    /// Hankel-domain reflectance values evaluated (wavelength x frequency).
    pub transform_samples: usize,
    /// Radial profiles inverted (one per wavelength).
    pub radial_profiles: usize,
    /// Burley fits of the Subsurface Radius (one per RGB channel of each parameter set whose radius was asked for).
    pub radius_fits: usize,
    /// Specular inputs computed from an oiliness (one per parameter set whose specular was asked for).
    pub specular_evaluations: usize,
    /// Exact (adding-doubling) totals solved (one per wavelength with `Transport::AddingDoubling`, none with
    /// `Transport::Diffusion`).
    pub transport_solves: usize,
    /// Exact totals read from the shipped table instead (`ExactTotals::Table`, where the table holds the stack).
    pub transport_table_lookups: usize,
}

/// The result of [`evaluate`]; fields not requested are `None`. Serialises to the CLI's stable JSON.
#[derive(Debug, Clone, Serialize)]
pub struct Evaluation {
    pub params: SkinParams,
    pub color_space: &'static str,
    pub accuracy: Accuracy,
    pub model: SkinModel,
    pub combination: Combination,
    /// The layers' boundary conditions ([`Boundaries`]).
    pub boundaries: Boundaries,
    /// How the totals were computed ([`Transport`]).
    pub transport: Transport,
    /// The Blender version and engine `methods` are for, and whether that version was tested.
    pub target: TargetInfo,
    /// The model's total diffuse reflectance (subsurface only): what a rendered flat slab must show.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub diffuse_reflectance_rgb: Option<[f64; 3]>,
    pub default_method: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub methods: Option<Methods>,
    /// The Burley fit per channel (d, radius, edge residual).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub radius_fit: Option<[BurleyFit; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub specular: Option<SpecularParams>,
    /// The surface's Principled inputs that no parameter changes (IOR, Roughness), always present: a front that
    /// drops the specular lobe (Specular IOR Level 0) still sets them without asking for `specular`.
    pub surface: SurfaceConstants,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wavelengths_nm: Option<Vec<f64>>,
    /// Total diffuse reflectance per wavelength.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spectral_reflectance: Option<Vec<f64>>,
    /// Where the radius fit's and the profile's shape came from, when either was asked: "exact" (the transport's table,
    /// `transport::profile_table`) or "multipole" (diffusion's, scaled to the totals).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub profile_shape: Option<&'static str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub profile: Option<RadialProfile>,
    pub work: Work,
    pub seconds: f64,
}

/// What a request needs that does not depend on the parameters: the validated request, the wavelength grid, the colour
/// weights and the fit frequencies. Build it once and evaluate many parameter sets with it (the map pipeline does).
#[derive(Debug, Clone)]
pub struct Prepared {
    request: Request,
    /// The wavelength grid, its RGB weights and their luminance (for `RgbMapping`), shared per process.
    colour: Arc<ColourIntegration>,
    fit_s: Vec<f64>,
    /// The edge-L2 fit's tables on `fit_s` (shared per process), None with the second-moment fit.
    burley: Option<Arc<BurleyGrid>>,
}

/// The per-texel outputs of a material: the RGB albedo, the Burley fit and every method's inputs for the target.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    pub albedo: [f64; 3],
    pub fits: [BurleyFit; 3],
    pub methods: Methods,
}

impl Prepared {
    pub fn new(request: &Request) -> Result<Prepared, SkinError> {
        request.accuracy.validate()?;
        validate_model(&request.model)?;
        let acc = &request.accuracy;
        let colour = ColourIntegration::of(acc.wavelength_placement, acc.wavelength_step_nm, request.working_space);
        let burley = match acc.radius_fit {
            RadiusFit::EdgeL2 => Some(BurleyGrid::of(acc.fit_frequencies_per_decade)),
            RadiusFit::SecondMoment => None,
        };
        let fit_s = burley.as_ref().map_or_else(|| vec![SECOND_MOMENT_FREQUENCY_PER_MM], |g| g.s_per_mm().to_vec());
        Ok(Prepared { request: *request, colour, fit_s, burley })
    }

    pub fn request(&self) -> &Request {
        &self.request
    }

    pub fn wavelengths_nm(&self) -> &[f64] {
        &self.colour.grid.wavelengths_nm
    }

    /// The weights that turn a spectrum on this request's wavelengths into linear RGB in its working space.
    pub fn rgb_weights(&self) -> &[[f64; 3]] {
        &self.colour.rgb_weights
    }

    /// The multipole's layer stack of `params` at each of this request's wavelengths.
    pub fn stacks(&self, params: &SkinParams) -> Result<Vec<LayerStack>, SkinError> {
        stacks_of(&self.optics(params, false)?.layers, self.request.boundaries)
    }

    fn optics(&self, params: &SkinParams, needs_shape: bool) -> Result<Optics, SkinError> {
        Optics::of(params, &self.request, &self.colour.grid.wavelengths_nm, needs_shape)
    }

    fn totals(&self, optics: &Optics, parallel: bool, cancel: &AtomicBool) -> Result<Totals, SkinError> {
        totals_of(optics, &self.request, parallel, cancel)
    }

    /// Burley fits per channel from the RGB transfer function on the fit frequencies: each wavelength's exact shape
    /// times its total where the table holds the stack, else the multipole's transform scaled to the total
    /// ([`Totals::scale`]).
    fn fits(&self, optics: &Optics, totals: &Totals, albedo: [f64; 3], parallel: bool) -> [BurleyFit; 3] {
        let s = &self.fit_s;
        let transform = |w: usize| self.transform(optics, totals, w, s);
        let transforms: Vec<Vec<f64>> = if parallel {
            (0..optics.wavelengths()).into_par_iter().map(transform).collect()
        } else {
            (0..optics.wavelengths()).map(transform).collect()
        };
        // RGB transfer function per frequency, normalised by the albedo.
        let rgb: Vec<[f64; 3]> = (0..s.len())
            .map(|i| spectrum_to_rgb(&transforms.iter().map(|t| t[i]).collect::<Vec<_>>(), &self.colour.rgb_weights))
            .collect();
        [0, 1, 2].map(|c| {
            let normalized: Vec<f64> = rgb.iter().map(|v| crate::numeric::safe_div(v[c], albedo[c], 0.0)).collect();
            match &self.burley {
                Some(grid) => grid.fit(&normalized),
                None => fit_burley_second_moment(normalized[0]),
            }
        })
    }

    /// Wavelength `w`'s transform R~(s) at `s_per_mm` (radians per mm) as the radius fit sees it: its exact shape
    /// times its total where the table holds the stack, else the multipole's transform scaled to the total.
    fn transform(&self, optics: &Optics, totals: &Totals, w: usize, s_per_mm: &[f64]) -> Vec<f64> {
        let (comb, terms) = (self.request.combination, self.request.accuracy.multipole_terms);
        match (&optics.shapes, &optics.stacks) {
            (Some(shapes), _) => {
                shapes[w].normalized_transforms(s_per_mm).into_iter().map(|n| n * totals.total[w]).collect()
            }
            (None, Some(stacks)) => {
                s_per_mm.iter().map(|&x| stacks[w].reflectance_hat(x, comb, terms) * totals.scale_of(w)).collect()
            }
            (None, None) => {
                unreachable!("Optics::of keeps the stacks where a shape is needed and no exact one is held")
            }
        }
    }

    /// Every wavelength's transform R~(s) at `s_per_mm` for one parameter set, as the radius fit sees it (the accuracy
    /// report's reference reads it on a denser frequency grid than the fit's).
    pub fn transforms(&self, params: &SkinParams, s_per_mm: &[f64]) -> Result<Vec<Vec<f64>>, SkinError> {
        let optics = self.optics(params, true)?;
        let totals = self.totals(&optics, false, &AtomicBool::new(false))?;
        Ok((0..optics.wavelengths()).map(|w| self.transform(&optics, &totals, w, s_per_mm)).collect())
    }

    /// The RGB albedo (total diffuse reflectance) of one parameter set, alone: one transform value per wavelength and
    /// no radius fit. It is [`Material::albedo`] to the last bit (the same sums), and the Base Color of a material
    /// without subsurface, whatever the method.
    pub fn albedo(&self, params: &SkinParams) -> Result<[f64; 3], SkinError> {
        self.albedo_cancellable(params, &AtomicBool::new(false))
    }

    /// [`Prepared::albedo`] that stops once `cancel` is set (read before each wavelength's transport solve), with
    /// [`SkinError::interrupted`].
    pub fn albedo_cancellable(&self, params: &SkinParams, cancel: &AtomicBool) -> Result<[f64; 3], SkinError> {
        let optics = self.optics(params, false)?;
        Ok(albedo_rgb(&self.totals(&optics, false, cancel)?.total, &self.colour.rgb_weights))
    }

    /// Albedo and both methods' Base Color and radius for one parameter set, computed on the calling thread (callers
    /// that evaluate many parameter sets parallelise across them).
    pub fn material(&self, params: &SkinParams) -> Result<Material, SkinError> {
        self.material_cancellable(params, &AtomicBool::new(false))
    }

    /// [`Prepared::material`] that stops once `cancel` is set (read before each wavelength's transport solve), with
    /// [`SkinError::interrupted`].
    pub fn material_cancellable(&self, params: &SkinParams, cancel: &AtomicBool) -> Result<Material, SkinError> {
        let optics = self.optics(params, true)?;
        let totals = self.totals(&optics, false, cancel)?;
        let albedo = albedo_rgb(&totals.total, &self.colour.rgb_weights);
        let fits = self.fits(&optics, &totals, albedo, false);
        Ok(Material { albedo, fits, methods: methods_from(&self.request.target, albedo, &fits)? })
    }
}

/// Compute what `request.outputs` asks for, and nothing else.
pub fn evaluate(params: &SkinParams, request: &Request) -> Result<Evaluation, SkinError> {
    evaluate_cancellable(params, request, &AtomicBool::new(false))
}

/// [`evaluate`] that stops once `cancel` is set, with [`SkinError::interrupted`]: it is read before each
/// wavelength's transport solve (at 64 streams tens of milliseconds each, and a 0.5 nm grid has 601 of them) and
/// each wavelength's radial profile (up to 10^5 radii).
pub fn evaluate_cancellable(
    params: &SkinParams,
    request: &Request,
    cancel: &AtomicBool,
) -> Result<Evaluation, SkinError> {
    let start = Instant::now();
    let prepared = Prepared::new(request)?;
    let params = params.validated()?;
    let out = request.outputs;
    let acc = &request.accuracy;

    let needs_layers = out.albedo || out.radius || out.spectrum || out.profile_rgb || out.profile_spectral;
    let needs_shape = out.radius || out.profile_rgb || out.profile_spectral;
    let optics = if needs_layers { prepared.optics(&params, needs_shape)? } else { Optics::default() };
    let mut work = Work { wavelengths: optics.wavelengths(), ..Work::default() };

    let all_totals = prepared.totals(&optics, true, cancel)?;
    work.transform_samples += optics.wavelengths(); // R~(0) of each wavelength: its total, however obtained
    work.transport_solves += all_totals.solves;
    work.transport_table_lookups += all_totals.lookups;
    let albedo = albedo_rgb(&all_totals.total, &prepared.colour.rgb_weights);
    let needs_albedo = out.albedo || out.radius;
    let profile_shape = needs_shape.then(|| optics.shape_name());

    let (methods, radius_fit) = if out.radius {
        let fits = prepared.fits(&optics, &all_totals, albedo, true);
        work.transform_samples += optics.wavelengths() * prepared.fit_s.len();
        work.radius_fits += fits.len();
        (Some(methods_from(&request.target, albedo, &fits)?), Some(fits))
    } else {
        (None, None)
    };

    let profile = if out.profile_rgb || out.profile_spectral {
        let profile = radial_profile(&prepared, &optics, &all_totals, cancel)?;
        work.radial_profiles = profile.spectral_count;
        Some(profile.profile)
    } else {
        None
    };

    let specular = match out.specular {
        true => Some(specular_for(request.surface, params.oiliness, request.target.engine)?),
        false => None,
    };
    work.specular_evaluations += usize::from(specular.is_some());
    Ok(Evaluation {
        params,
        color_space: request.working_space.name(),
        accuracy: *acc,
        model: request.model,
        combination: request.combination,
        boundaries: request.boundaries,
        transport: request.transport,
        target: request.target.info(),
        diffuse_reflectance_rgb: needs_albedo.then_some(albedo),
        default_method: DEFAULT_METHOD.name(),
        methods,
        radius_fit,
        specular,
        surface: SurfaceConstants::of(request.surface),
        wavelengths_nm: (out.spectrum || out.profile_spectral).then(|| prepared.colour.grid.wavelengths_nm.clone()),
        spectral_reflectance: out.spectrum.then_some(all_totals.total),
        profile_shape,
        profile,
        work,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// A radial profile and how many spectral profiles it was made of.
struct ProfileStep {
    profile: RadialProfile,
    spectral_count: usize,
}

/// The radial profile `prepared.request` asks for (RGB and/or spectral) of one parameter set: each wavelength's exact
/// profile where the profile table holds its stack, else the multipole's, clamped at 0 (a negative lobe reported) and
/// scaled to the wavelength's total.
fn radial_profile(
    prepared: &Prepared,
    optics: &Optics,
    all_totals: &Totals,
    cancel: &AtomicBool,
) -> Result<ProfileStep, SkinError> {
    let request = &prepared.request;
    let (out, acc) = (request.outputs, &request.accuracy);
    let radii = acc.profile_grid.radii_mm();
    let (spectral, negative_lobe) = match (&optics.shapes, &optics.stacks) {
        (Some(shapes), _) => (exact_profiles(shapes, &all_totals.total, &radii, cancel)?, None),
        (None, None) => {
            unreachable!("Optics::of keeps the stacks where a shape is needed and no exact one is held")
        }
        (None, Some(stacks)) => {
            let clamped = clamped_reflectance_profiles_cancellable(
                stacks,
                &radii,
                request.combination,
                acc.multipole_terms,
                &acc.hankel,
                cancel,
            )?;
            let negative_lobe = clamped.negative_lobe.map(|l| SpectralLobe {
                wavelength_nm: prepared.colour.grid.wavelengths_nm[l.profile],
                boundaries: l.boundaries,
                radius_mm: l.radius_mm,
                relative_to_peak: l.relative_to_peak,
            });
            // Each wavelength's profile keeps the multipole's shape, scaled to its total (x 1 with diffusion). The
            // clamp and the lobe's depth relative to the peak do not change under a positive scale.
            let spectral: Vec<Vec<f64>> = clamped
                .per_mm2
                .into_iter()
                .enumerate()
                .map(|(w, p)| {
                    let k = all_totals.scale_of(w);
                    if k == 1.0 {
                        p
                    } else {
                        p.into_iter().map(|v| v * k).collect()
                    }
                })
                .collect();
            (spectral, negative_lobe)
        }
    };
    let rgb = out.profile_rgb.then(|| {
        (0..radii.len())
            .map(|i| {
                let rgb =
                    spectrum_to_rgb(&spectral.iter().map(|p| p[i]).collect::<Vec<_>>(), &prepared.colour.rgb_weights);
                request.rgb_mapping.apply(rgb, prepared.colour.luminance)
            })
            .collect()
    });
    let spectral_count = spectral.len();
    let profile = RadialProfile {
        radii_mm: radii,
        rgb_per_mm2: rgb,
        spectral_per_mm2: out.profile_spectral.then_some(spectral),
        negative_lobe,
    };
    Ok(ProfileStep { profile, spectral_count })
}

/// The layers of one parameter set at each wavelength (what the exact solver and its tables take), with what the
/// request needs of them beyond the totals: the exact shapes, or the multipole's stacks.
#[derive(Debug, Clone, Default)]
struct Optics {
    layers: Vec<[Layer; 2]>,
    /// Each wavelength's exact shape, where a shape is needed, the request's transport takes exact shapes and the
    /// profile table holds every wavelength's stack (a finite dermis is not held); else None.
    shapes: Option<Vec<Shape>>,
    /// The multipole's stacks (the request's boundaries), only where the multipole is used: its totals
    /// (`Transport::Diffusion`) or its shape (a shape needed and no exact one).
    stacks: Option<Vec<LayerStack>>,
}

impl Optics {
    /// The layers of `params` at each of `wavelengths_nm` with the request's model (validated), and their exact shapes
    /// or multipole stacks where the request needs them (`needs_shape`: a radius or a profile is asked for).
    fn of(
        params: &SkinParams,
        request: &Request,
        wavelengths_nm: &[f64],
        needs_shape: bool,
    ) -> Result<Optics, SkinError> {
        let layers: Vec<[Layer; 2]> = wavelengths_nm.iter().map(|&w| skin_layers(params, &request.model, w)).collect();
        layers.iter().try_for_each(|l| crate::layer::validate_layers(l))?;
        let shapes = if needs_shape && request.transport.exact_shape() {
            layers.iter().map(|l| exact_shape(l)).collect()
        } else {
            None
        };
        let needs_multipole = request.transport == Transport::Diffusion || (needs_shape && shapes.is_none());
        let stacks = needs_multipole.then(|| stacks_of(&layers, request.boundaries)).transpose()?;
        Ok(Optics { layers, shapes, stacks })
    }

    fn wavelengths(&self) -> usize {
        self.layers.len()
    }

    fn shape_name(&self) -> &'static str {
        match self.shapes {
            Some(_) => crate::reflectance::ProfileShape::Exact.name(),
            None => crate::reflectance::ProfileShape::Multipole.name(),
        }
    }
}

/// The multipole's stack of each wavelength's layers with `boundaries`.
fn stacks_of(layers: &[[Layer; 2]], boundaries: Boundaries) -> Result<Vec<LayerStack>, SkinError> {
    layers.iter().map(|l| LayerStack::with_boundaries(l, boundaries)).collect()
}

/// Each wavelength's total diffuse reflectance, and the factor that scales the multipole's transform (and so its radial
/// profile) to it.
struct Totals {
    total: Vec<f64>,
    /// `total / R~(0)` of the multipole where the multipole's stacks are at hand (1 where the multipole's total is 0);
    /// None: 1 (`Transport::Diffusion`, or no multipole used).
    scale: Option<Vec<f64>>,
    /// Exact totals solved.
    solves: usize,
    /// Exact totals read from the table of totals.
    lookups: usize,
}

impl Totals {
    /// Wavelength `w`'s factor on the multipole's transform.
    fn scale_of(&self, w: usize) -> f64 {
        self.scale.as_ref().map_or(1.0, |s| s[w])
    }
}

/// Each wavelength's exact profile at `radii`: its total times its shape's normalised profile; stops once `cancel` is
/// set.
fn exact_profiles(
    shapes: &[Shape],
    totals: &[f64],
    radii: &[f64],
    cancel: &AtomicBool,
) -> Result<Vec<Vec<f64>>, SkinError> {
    shapes
        .iter()
        .zip(totals)
        .map(|(shape, &total)| {
            SkinError::check_cancel(cancel, "reflectance profile")?;
            Ok(radii.iter().map(|&r| total * shape.normalized_profile_per_mm2(r)).collect())
        })
        .collect()
}

/// How far above 1 a total or an albedo channel may come from round-off alone (measured: 4e-16 for a multipole total
/// of a skin absorbing nothing, 1e-15 for its RGB); such a value is 1. A larger excess is left as it is, for the checks
/// downstream to see.
const ROUND_OFF_ABOVE_ONE: f64 = 1e-12;

/// `v`, or 1 where `v` exceeds 1 by round-off only ([`ROUND_OFF_ABOVE_ONE`]).
fn one_at_round_off(v: f64) -> f64 {
    if v > 1.0 && v < 1.0 + ROUND_OFF_ABOVE_ONE {
        1.0
    } else {
        v
    }
}

/// The RGB albedo of per-wavelength totals: a perfect reflector is (1, 1, 1), not 1 + 1e-15.
fn albedo_rgb(totals: &[f64], weights: &[[f64; 3]]) -> [f64; 3] {
    spectrum_to_rgb(totals, weights).map(one_at_round_off)
}

/// The total diffuse reflectance of each wavelength: the multipole's `R~(0)` (the request's combination and multipole
/// terms), or with `Transport::AddingDoubling` the exact one at the request's streams. The one place totals come from.
fn totals_of(optics: &Optics, request: &Request, parallel: bool, cancel: &AtomicBool) -> Result<Totals, SkinError> {
    let (comb, terms) = (request.combination, request.accuracy.multipole_terms);
    let multipole: Option<Vec<f64>> =
        optics.stacks.as_ref().map(|stacks| stacks.iter().map(|s| s.reflectance_hat(0.0, comb, terms)).collect());
    match request.transport {
        Transport::Diffusion => {
            let multipole = multipole.expect("Optics::of keeps the stacks for the diffusion transport");
            // A skin that absorbs nothing reflects exactly everything; the multipole's sum reaches 1 + 4e-16.
            let total = multipole.into_iter().map(one_at_round_off).collect();
            Ok(Totals { total, scale: None, solves: 0, lookups: 0 })
        }
        Transport::AddingDoubling | Transport::AddingDoublingDiffusionShape => {
            let streams = request.accuracy.streams;
            let table = (request.accuracy.exact_totals == ExactTotals::Table).then(TotalTable::shipped);
            let looked_up: Vec<Option<f64>> =
                optics.layers.iter().map(|layers| table.and_then(|t| t.total_of(layers))).collect();
            let solve = |(layers, held): (&[Layer; 2], &Option<f64>)| match held {
                Some(total) => Ok(*total),
                None => total_diffuse_reflectance_cancellable(layers, streams, cancel),
            };
            let pairs = optics.layers.iter().zip(&looked_up);
            let total: Vec<f64> = if parallel && looked_up.iter().any(Option::is_none) {
                pairs.collect::<Vec<_>>().into_par_iter().map(solve).collect::<Result<_, _>>()?
            } else {
                pairs.map(solve).collect::<Result<_, _>>()?
            };
            let scale =
                multipole.map(|m| total.iter().zip(&m).map(|(&t, &m)| crate::numeric::safe_div(t, m, 1.0)).collect());
            let lookups = looked_up.iter().filter(|t| t.is_some()).count();
            Ok(Totals { solves: total.len() - lookups, lookups, total, scale })
        }
    }
}

/// The model's total diffuse reflectance (subsurface only) of `params` at arbitrary wavelengths, as
/// [`Evaluation::spectral_reflectance`] computes it on the request's own grid, with the request's transport (and
/// streams), model, combination, boundaries and multipole terms (its outputs and wavelength grid are not used;
/// `params` is not validated: the caller does). The forward model of the spectrum fits (`crate::inverse`).
pub fn diffuse_reflectance_at(
    params: &SkinParams,
    request: &Request,
    wavelengths_nm: &[f64],
    cancel: &AtomicBool,
) -> Result<Vec<f64>, SkinError> {
    Ok(totals_of(&Optics::of(params, request, wavelengths_nm, false)?, request, false, cancel)?.total)
}

/// Every method's inputs on `target` from the albedo and the Burley fit (`fit::blender_target`).
fn methods_from(target: &Target, albedo: [f64; 3], fits: &[BurleyFit; 3]) -> Result<Methods, SkinError> {
    let radius = fits.map(|f| f.radius_mm);
    let map = |m: SubsurfaceMethod| target.map(m, albedo, radius);
    let offers_legacy = target.methods().any(|m| m == SubsurfaceMethod::RandomWalkLegacy);
    Ok(Methods {
        burley: map(SubsurfaceMethod::Burley)?,
        random_walk: map(SubsurfaceMethod::RandomWalk)?,
        random_walk_legacy: if offers_legacy { Some(map(SubsurfaceMethod::RandomWalkLegacy)?) } else { None },
        random_walk_skin: map(SubsurfaceMethod::RandomWalkSkin)?,
    })
}

pub(crate) fn validate_model(m: &SkinModel) -> Result<(), SkinError> {
    check_range("eumelanin_k_per_mm", "eumelanin constant K_em", m.eumelanin_k_per_mm, 0.0, 1e13)?;
    let max_radius = crate::skin::chromophores::MAX_VESSEL_RADIUS_MM;
    check_range("blood_vessel_radius_mm", "dermal blood vessel radius, mm", m.blood_vessel_radius_mm, 0.0, max_radius)?;
    let max_carotene = crate::skin::chromophores::MAX_CAROTENE_UMOL_PER_L;
    let carotene = m.epidermal_carotene_umol_per_l;
    check_range("epidermal_carotene_umol_per_l", "epidermal beta-carotene, umol/L", carotene, 0.0, max_carotene)?;
    crate::skin::optics::EPIDERMAL_HEMOGLOBIN.check(m.epidermal_hemoglobin)?;
    match m.eumelanin_shape {
        crate::skin::chromophores::EumelaninShape::Dj2006 => {}
        crate::skin::chromophores::EumelaninShape::PowerLaw { exponent } => {
            check_range("eumelanin_shape.exponent", "eumelanin power-law exponent", exponent, -8.0, 0.0)?;
        }
        crate::skin::chromophores::EumelaninShape::Exponential { k_per_nm } => {
            check_range("eumelanin_shape.k_per_nm", "eumelanin exponential slope, nm^-1", k_per_nm, 0.0, 0.05)?;
        }
    }
    if let crate::skin::scattering::ScatteringShape::MieRayleigh { f_ray, b_mie } = m.scattering_shape {
        check_range("scattering_shape.f_ray", "Rayleigh fraction of the scattering at 500 nm", f_ray, 0.0, 1.0)?;
        check_range("scattering_shape.b_mie", "Mie scattering power-law exponent", b_mie, 0.0, 4.0)?;
    }
    if !(m.dermis_thickness_mm.is_infinite() && m.dermis_thickness_mm > 0.0) {
        check_range("dermis_thickness_mm", "dermis thickness (or infinity)", m.dermis_thickness_mm, 1e-3, 1e4)?;
    }
    Ok(())
}
