//! Diffusion: the multipole slab model, the layer combination and radial profiles (docs/model.md, sections Multipole to Radial profiles).

pub mod boundary;
pub mod fft_route;
pub mod hankel;
pub mod layered;
pub mod multipole;

pub use fft_route::{fft_reflectance_profiles, fft_reflectance_profiles_with, FftGrid, FftProfiles, PixelSampling};
pub use hankel::{raw_reflectance_profiles, reflectance_profiles, HankelQuadrature, MAX_RADIUS_MM};
pub use layered::{
    Boundaries, Combination, Layer, LayerStack, COEFFICIENT_RANGE_PER_MM, IOR_RANGE, THICKNESS_RANGE_MM,
};
pub use multipole::{MultipoleTerms, Slab};

use crate::error::SkinError;

/// Total diffuse reflectance and the radial profile (mm^-2) at `radii_mm` of a stack of layers under air, top to bottom,
/// with the default combination, the whole multipole series and the default quadrature. This exposes the solver alone,
/// for checks against other solvers.
pub fn layered_reflectance(layers: &[Layer], radii_mm: &[f64]) -> Result<(f64, Vec<f64>), SkinError> {
    validate_radii(radii_mm)?;
    let stack = LayerStack::new(layers)?;
    let total = stack.reflectance_hat(0.0, Combination::Directional, MultipoleTerms::All);
    let profile = reflectance_profiles(
        std::slice::from_ref(&stack),
        radii_mm,
        Combination::Directional,
        MultipoleTerms::All,
        &HankelQuadrature::default(),
    )
    .pop()
    .unwrap_or_default();
    Ok((total, profile))
}

/// Radii must be in [0, `MAX_RADIUS_MM`].
pub fn validate_radii(radii_mm: &[f64]) -> Result<(), SkinError> {
    if let Some((i, r)) = radii_mm.iter().enumerate().find(|(_, r)| !(**r >= 0.0 && **r <= MAX_RADIUS_MM)) {
        return Err(SkinError::invalid(
            "radii_mm",
            format!("radii must be >= 0 and <= {MAX_RADIUS_MM:e} mm; radii_mm[{i}] = {r}"),
        ));
    }
    Ok(())
}
