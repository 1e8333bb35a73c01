//! Skin optics: parameters, chromophore spectra, scattering and the two-layer geometry (DJ2006 section 2).

pub mod chromophores;
pub mod optics;
pub mod params;
pub mod scattering;

pub use optics::{skin_layers, SkinModel, SKIN_IOR};
pub use params::{ParamSpec, Preset, SkinParams, PARAMS, PRESETS};
