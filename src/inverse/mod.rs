//! Inverse problems: model parameters from measurements. [`spectrum`] fits a measured reflectance spectrum
//! (docs/measured-skin.md); [`albedo`] and [`albedo_maps`] fit an RGB colour and an albedo texture
//! (docs/skin-atlas.md), [`albedo_gains`] says when a texture is not an albedo and estimates the exposure and
//! white-balance gains that bring it inside skin's colours; [`lm`] is the bounded least-squares solver of the spectrum fit.

pub mod albedo;
pub mod albedo_gains;
pub mod albedo_maps;
pub mod aperture;
pub mod bandpass;
pub mod lm;
pub mod spectrum;

pub use aperture::Aperture;
pub use bandpass::Bandpass;
pub use spectrum::{fit_spectrum, FitOptions, Objective, SpectrumFit, SpectrumFitter, Specular, DEFAULT_FREE};
