//! Inverse problems: model parameters from measurements. [`spectrum`] fits a measured reflectance spectrum
//! (docs/measured-skin.md); [`lm`] is the bounded least-squares solver the fits share.

pub mod lm;
pub mod spectrum;

pub use spectrum::{fit_spectrum, FitOptions, Objective, SpectrumFit, SpectrumFitter, Specular, DEFAULT_FREE};
