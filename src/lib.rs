//! spectral-skin: Donner & Jensen 2006's spectral BSSRDF for human skin.
//!
//! Four physiological parameters per texel ([`SkinParams`]) give two layers' spectral optics ([`skin`]), whose
//! multipole diffusion profiles are combined in the Hankel domain ([`diffusion`]), turned into colour ([`color`]) and
//! into the inputs of Blender's Principled BSDF ([`fit`], [`surface`]). [`evaluate`] computes only what a
//! [`Request`] asks for.

pub mod accuracy;
pub mod color;
pub mod diffusion;
pub mod error;
pub mod evaluate;
pub mod fit;
pub mod maps;
mod numeric;
pub mod skin;
pub mod surface;
mod table;

#[cfg(feature = "python")]
mod python;

pub use accuracy::{Accuracy, AccuracyLevel};
pub use error::SkinError;
pub use evaluate::{evaluate, Evaluation, Outputs, Request};
pub use skin::{SkinModel, SkinParams, PRESETS};
