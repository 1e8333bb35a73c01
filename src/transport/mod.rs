//! Radiative transfer beyond diffusion: the exact layered-slab solver that gives the model's totals
//! ([`adding_doubling`]), and exact solutions for simple geometries that the Blender mappings in `fit` compare a
//! renderer's walk against ([`half_space`]).

pub mod adding_doubling;
pub mod half_space;
mod matrix;

use serde::{Deserialize, Serialize};

pub use adding_doubling::{total_diffuse_reflectance, DEFAULT_STREAMS, STREAMS_RANGE};

/// How the total diffuse reflectance of a layer stack (the albedo, and the scale of its radial profile) is computed.
/// Python's `transport=`, the CLI's `--transport`, JSON and the add-on take the serde names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, Hash)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum), value(rename_all = "snake_case"))]
#[serde(rename_all = "snake_case")]
pub enum Transport {
    /// The default: the exact solution of the radiative transfer equation for the layered slab (adding-doubling,
    /// Prahl 1995) gives each wavelength's total; the radial profile keeps the multipole's shape, scaled to it.
    #[default]
    AddingDoubling,
    /// The paper's: the layered multipole's own total (diffusion), 9-40 % too bright wherever skin absorbs.
    Diffusion,
}

/// Every transport, the default first.
pub const ALL_TRANSPORTS: [Transport; 2] = [Transport::AddingDoubling, Transport::Diffusion];

impl Transport {
    /// The serde name ("adding_doubling", "diffusion").
    pub fn name(self) -> &'static str {
        match self {
            Transport::AddingDoubling => "adding_doubling",
            Transport::Diffusion => "diffusion",
        }
    }

    /// One line for every front's help.
    pub fn description(self) -> &'static str {
        match self {
            Transport::AddingDoubling => {
                "exact totals (adding-doubling radiative transfer) with the multipole's profile shape: right for every \
                 skin tone (default)"
            }
            Transport::Diffusion => {
                "the paper's layered multipole diffusion: reproduces DJ2006, too bright for dark skin"
            }
        }
    }
}
