//! Exact total reflectance of a layered slab by adding-doubling (Prahl 1995). Work in progress: the interface only.

use crate::diffusion::Layer;
use crate::error::SkinError;

/// Streams (quadrature directions per hemisphere) of the default accuracy level.
pub const DEFAULT_STREAMS: usize = 8;
/// Stream counts accepted.
pub const STREAMS_RANGE: (usize, usize) = (2, 64);

/// The total diffuse reflectance of `layers` (top to bottom, under air; the last may be semi-infinite) for a normally
/// incident beam, per unit power refracted into the top layer: the same quantity as the multipole's R(k = 0).
/// Scattering is isotropic with the reduced coefficient (the model's optics are reduced coefficients).
pub fn total_diffuse_reflectance(layers: &[Layer], streams: usize) -> Result<f64, SkinError> {
    let _ = streams;
    // Placeholder until the solver lands: the diffusion total.
    let stack = crate::diffusion::LayerStack::new(layers)?;
    Ok(stack.reflectance_hat(0.0, crate::diffusion::Combination::Directional, crate::diffusion::MultipoleTerms::All))
}
