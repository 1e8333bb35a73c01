//! spectral-skin: Donner & Jensen 2006's spectral BSSRDF for human skin.
//!
//! Four physiological parameters per texel ([`SkinParams`]) give two layers' spectral optics ([`skin`], each a
//! [`layer::Layer`]), whose reflectance comes from the exact transport ([`transport`]) or the multipole diffusion
//! combined in the Hankel domain ([`diffusion`]), composed one floor up ([`reflectance`], and per wavelength in
//! [`evaluate`]), turned into colour ([`color`]) and into the inputs of Blender's Principled BSDF: Base Color and
//! Subsurface Radius ([`fit`]), the surface's reflection and its Principled inputs ([`surface`]). [`evaluate`]
//! computes only what a [`Request`] asks for.

pub mod accuracy;
#[cfg(feature = "cli")]
pub mod cli;
pub mod color;
pub mod diffusion;
pub mod error;
pub mod evaluate;
pub mod fit;
pub mod inverse;
pub mod layer;
pub mod maps;
mod numeric;
pub mod reflectance;
pub mod skin;
pub mod stamp;
pub mod surface;
mod table;
pub mod transport;

#[cfg(feature = "python")]
mod python;

pub use accuracy::{Accuracy, AccuracyLevel};
pub use error::SkinError;
pub use evaluate::{evaluate, Evaluation, MaterialOutput, Outputs, Request, ALL_MATERIAL_OUTPUTS};
pub use skin::{SkinModel, SkinParams, PRESETS};
pub use stamp::MODEL_VERSION;
pub use table::strip_utf8_bom;

/// One spelling of every value in every front: the CLI's value names (clap) are the serde names Python takes and
/// JSON writes.
#[cfg(all(test, feature = "cli"))]
mod one_spelling {
    use clap::ValueEnum;
    use serde::Serialize;

    fn check<T: ValueEnum + Serialize>(all: &[T]) {
        let clap_names: Vec<String> =
            T::value_variants().iter().map(|v| v.to_possible_value().unwrap().get_name().to_string()).collect();
        let serde_names: Vec<String> =
            all.iter().map(|v| serde_json::to_value(v).unwrap().as_str().unwrap().to_string()).collect();
        let mut sorted = (clap_names.clone(), serde_names.clone());
        sorted.0.sort();
        sorted.1.sort();
        assert_eq!(sorted.0, sorted.1, "clap {clap_names:?} vs serde {serde_names:?}");
    }

    #[test]
    fn cli_values_are_the_serde_names() {
        check(&crate::accuracy::ALL_ACCURACY_LEVELS);
        check(&crate::color::ALL_WAVELENGTH_PLACEMENTS);
        check(&crate::color::ALL_RGB_MAPPINGS);
        check(&crate::diffusion::ALL_COMBINATIONS);
        check(&crate::diffusion::ALL_BOUNDARIES);
        check(&crate::fit::SubsurfaceMethod::ALL);
        check(&crate::fit::blender_target::Engine::ALL);
        check(&crate::maps::io::ALL_COMPRESSIONS);
        check(&crate::maps::io::ALL_PRECISIONS);
        check(&crate::ALL_MATERIAL_OUTPUTS);
        check(&crate::transport::ALL_TRANSPORTS);
    }
}
