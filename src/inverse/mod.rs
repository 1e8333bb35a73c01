//! Inverse problems: model parameters from measurements. [`spectrum`] fits a measured reflectance spectrum
//! (docs/measured-skin.md); [`albedo`] and [`albedo_maps`] fit an RGB colour and an albedo texture
//! (docs/skin-atlas.md); [`lm`] is the bounded least-squares solver of the spectrum fit.

pub mod albedo;
pub mod albedo_maps;
pub mod lm;
pub mod spectrum;

pub use spectrum::{fit_spectrum, FitOptions, Objective, SpectrumFit, SpectrumFitter, Specular, DEFAULT_FREE};
