//! Diffusion: the multipole slab model, the layer combination and radial profiles (docs/model.md, sections Multipole
//! to Radial profiles). The reflectance that composes it with the exact transport is one floor up
//! ([`crate::reflectance`]).

pub mod boundary;
pub mod fft_route;
pub mod hankel;
pub mod layered;
pub mod multipole;

pub use fft_route::{fft_reflectance_profiles, fft_reflectance_profiles_with, FftGrid, FftProfiles, PixelSampling};
pub use hankel::{
    clamped_reflectance_profiles, clamped_reflectance_profiles_cancellable, raw_reflectance_profiles,
    reflectance_profiles, ClampedProfiles, HankelQuadrature, NegativeLobe, MAX_RADIUS_MM, PEAK_PROBE_MM,
    ROUND_OFF_OF_PEAK,
};
pub use layered::{Boundaries, Combination, LayerStack, ALL_BOUNDARIES, ALL_COMBINATIONS};
pub use multipole::{MultipoleTerms, Slab};

use crate::error::SkinError;

/// The most radii of a profile (`profile_count`) or of a `layered_reflectance` call.
pub const MAX_PROFILE_RADII: usize = 100_000;

/// Radii must be in [0, `MAX_RADIUS_MM`], at most [`MAX_PROFILE_RADII`] of them.
pub fn validate_radii(radii_mm: &[f64]) -> Result<(), SkinError> {
    if radii_mm.len() > MAX_PROFILE_RADII {
        return Err(SkinError::invalid(
            "radii_mm",
            format!(
                "{} radii; at most {} (the profile's own limit: a profile that fine is a few seconds of work)",
                radii_mm.len(),
                MAX_PROFILE_RADII
            ),
        ));
    }
    if let Some((i, r)) = radii_mm.iter().enumerate().find(|(_, r)| !(**r >= 0.0 && **r <= MAX_RADIUS_MM)) {
        return Err(SkinError::invalid(
            "radii_mm",
            format!("radii must be >= 0 and <= {MAX_RADIUS_MM:e} mm; radii_mm[{i}] = {r}"),
        ));
    }
    Ok(())
}
