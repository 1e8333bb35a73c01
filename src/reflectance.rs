//! The reflectance of a stack of layers, composed one floor above the transports it uses: the total from the
//! adding-doubling ([`crate::transport`]) or the multipole ([`crate::diffusion`]), the profile's shape from the exact
//! table ([`crate::transport::profile_table`]) where it holds the stack, else from the multipole.

use std::sync::atomic::AtomicBool;

use crate::diffusion::{
    clamped_reflectance_profiles_cancellable, validate_radii, Boundaries, Combination, HankelQuadrature, LayerStack,
    MultipoleTerms, NegativeLobe,
};
use crate::error::SkinError;
use crate::layer::Layer;
use crate::numeric::safe_div;
use crate::transport::profile_table::exact_shape;
use crate::transport::{total_diffuse_reflectance_cancellable, Transport, DEFAULT_STREAMS};

/// Total diffuse reflectance and the radial profile (mm^-2) at `radii_mm` of a stack of layers under air, top to bottom,
/// with the default [`LayeredOptions`]: the exact total (adding-doubling, [`crate::transport`]) and the exact profile
/// shape where the table holds the stack, else the multipole's profile (the paper's boundaries, the default
/// combination, the whole series and the default quadrature) scaled to it. This exposes the solver alone, for checks against other solvers. [`multipole_reflectance`] is the multipole
/// alone; [`layered_reflectance_with`] chooses the transport and the boundaries and reports a negative lobe the clamp
/// removed.
pub fn layered_reflectance(layers: &[Layer], radii_mm: &[f64]) -> Result<(f64, Vec<f64>), SkinError> {
    let r = layered_reflectance_with(layers, radii_mm, &LayeredOptions::default())?;
    Ok((r.total, r.profile_per_mm2))
}

/// [`layered_reflectance`] with `Transport::Diffusion`: the layered multipole's own total and profile (DJ2005), for
/// checks of the diffusion model as such.
pub fn multipole_reflectance(layers: &[Layer], radii_mm: &[f64]) -> Result<(f64, Vec<f64>), SkinError> {
    let options = LayeredOptions { transport: Transport::Diffusion, ..LayeredOptions::default() };
    let r = layered_reflectance_with(layers, radii_mm, &options)?;
    Ok((r.total, r.profile_per_mm2))
}

/// The choices of [`layered_reflectance_with`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LayeredOptions {
    /// The multipole's boundary conditions (its profile's shape; with `Transport::Diffusion` its total too).
    pub boundaries: Boundaries,
    /// Where the total comes from: exact (the default) or the multipole's.
    pub transport: Transport,
    /// Streams of the adding-doubling solver (in `STREAMS_RANGE` whatever the transport; unused by
    /// `Transport::Diffusion`).
    pub streams: usize,
}

impl Default for LayeredOptions {
    fn default() -> Self {
        LayeredOptions { boundaries: Boundaries::Paper, transport: Transport::default(), streams: DEFAULT_STREAMS }
    }
}

/// What [`layered_reflectance_with`] returns.
#[derive(Debug, Clone, PartialEq)]
pub struct LayeredReflectance {
    /// Total diffuse reflectance.
    pub total: f64,
    /// R(r) at the radii asked for, mm^-2: with `Transport::AddingDoubling` the exact shape where the table holds the
    /// stack (one semi-infinite layer, or two with the skin's scattering ratio, index 1.4), else the multipole's
    /// clamped to zero and scaled to `total` (unscaled with `Transport::Diffusion`).
    pub profile_per_mm2: Vec<f64>,
    /// The negative lobe the clamp removed beyond round-off (only with `Boundaries::Paper` and the multipole's shape).
    pub negative_lobe: Option<NegativeLobe>,
    /// Where the profile's shape came from.
    pub shape: ProfileShape,
}

/// Where a profile's shape comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProfileShape {
    /// The exact transport's (`transport::profile_table`).
    Exact,
    /// The layered multipole's (scaled to the exact total unless the transport is diffusion).
    Multipole,
}

impl ProfileShape {
    pub fn name(self) -> &'static str {
        match self {
            ProfileShape::Exact => "exact",
            ProfileShape::Multipole => "multipole",
        }
    }
}

/// [`layered_reflectance`] with the transport and boundaries chosen, and the negative lobe the clamp removed.
pub fn layered_reflectance_with(
    layers: &[Layer],
    radii_mm: &[f64],
    options: &LayeredOptions,
) -> Result<LayeredReflectance, SkinError> {
    layered_reflectance_cancellable(layers, radii_mm, options, &AtomicBool::new(false))
}

/// [`layered_reflectance_with`] that stops once `cancel` is set (read before each radius), with
/// [`SkinError::interrupted`].
pub fn layered_reflectance_cancellable(
    layers: &[Layer],
    radii_mm: &[f64],
    options: &LayeredOptions,
    cancel: &AtomicBool,
) -> Result<LayeredReflectance, SkinError> {
    validate_radii(radii_mm)?;
    crate::transport::adding_doubling::validate_streams(options.streams)?;
    let stack = LayerStack::with_boundaries(layers, options.boundaries)?;
    let multipole_total = stack.reflectance_hat(0.0, Combination::Directional, MultipoleTerms::All);
    let total = match options.transport.exact_total() {
        false => multipole_total,
        true => total_diffuse_reflectance_cancellable(layers, options.streams, cancel)?,
    };
    if let Some(shape) = options.transport.exact_shape().then(|| exact_shape(layers)).flatten() {
        let mut profile_per_mm2 = Vec::with_capacity(radii_mm.len());
        for chunk in radii_mm.chunks(4096) {
            SkinError::check_cancel(cancel, "reflectance profile")?;
            profile_per_mm2.extend(chunk.iter().map(|&r| total * shape.normalized_profile_per_mm2(r)));
        }
        return Ok(LayeredReflectance { total, profile_per_mm2, negative_lobe: None, shape: ProfileShape::Exact });
    }
    let mut profiles = clamped_reflectance_profiles_cancellable(
        std::slice::from_ref(&stack),
        radii_mm,
        Combination::Directional,
        MultipoleTerms::All,
        &HankelQuadrature::default(),
        cancel,
    )?;
    let mut profile_per_mm2 = profiles.per_mm2.pop().unwrap_or_default();
    if options.transport.exact_total() {
        let scale = safe_div(total, multipole_total, 1.0);
        profile_per_mm2.iter_mut().for_each(|v| *v *= scale);
    }
    Ok(LayeredReflectance {
        total,
        profile_per_mm2,
        negative_lobe: profiles.negative_lobe,
        shape: ProfileShape::Multipole,
    })
}
