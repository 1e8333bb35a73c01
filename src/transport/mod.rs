//! Radiative transfer beyond diffusion: the exact layered-slab solver that gives the model's totals
//! ([`adding_doubling`]), the exact shape of its radial profile, tabulated ([`profile_table`]), and exact solutions for simple geometries that the Blender mappings in `fit` compare a
//! renderer's walk against ([`half_space`]).

pub mod adding_doubling;
pub mod half_space;
mod matrix;
pub mod profile_table;
pub mod total_table;

use serde::{Deserialize, Serialize};

pub use adding_doubling::{
    total_diffuse_reflectance, total_diffuse_reflectance_cancellable, DEFAULT_STREAMS, STREAMS_RANGE,
};

/// How the total diffuse reflectance of a layer stack (the albedo, and the scale of its radial profile) is computed.
/// Python's `transport=`, the CLI's `--transport`, JSON and the add-on take the serde names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, Hash)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum), value(rename_all = "snake_case"))]
#[serde(rename_all = "snake_case")]
pub enum Transport {
    /// The default: the exact solution of the radiative transfer equation for the layered slab (adding-doubling,
    /// Prahl 1995) gives each wavelength's total, and the profile (and the radius fit's transform) has the exact shape
    /// of the skin's stack ([`profile_table`]); a stack the table does not hold keeps the multipole's shape, scaled
    /// to the exact total, and says so.
    #[default]
    AddingDoubling,
    /// Exact totals with the multipole's profile shape scaled to them: the default before the exact shapes, kept for
    /// comparison (docs/accuracy-vs-time.md).
    AddingDoublingDiffusionShape,
    /// The paper's: the layered multipole's own total (diffusion), 9-40 % too bright wherever skin absorbs.
    Diffusion,
}

/// Every transport, the default first.
pub const ALL_TRANSPORTS: [Transport; 3] =
    [Transport::AddingDoubling, Transport::AddingDoublingDiffusionShape, Transport::Diffusion];

impl Transport {
    /// The serde name ("adding_doubling", "adding_doubling_diffusion_shape", "diffusion").
    pub fn name(self) -> &'static str {
        match self {
            Transport::AddingDoubling => "adding_doubling",
            Transport::AddingDoublingDiffusionShape => "adding_doubling_diffusion_shape",
            Transport::Diffusion => "diffusion",
        }
    }

    /// One line for every front's help.
    pub fn description(self) -> &'static str {
        match self {
            Transport::AddingDoubling => {
                "exact radiative transfer: adding-doubling totals and the tabulated exact profile shape, right for \
                 every skin tone (default)"
            }
            Transport::AddingDoublingDiffusionShape => {
                "exact totals with the multipole's profile shape: the colour right, the blur diffusion's (too wide for \
                 dark skin)"
            }
            Transport::Diffusion => {
                "the paper's layered multipole diffusion: reproduces DJ2006, too bright for dark skin"
            }
        }
    }

    /// Whether the totals are exact (adding-doubling).
    pub fn exact_total(self) -> bool {
        self != Transport::Diffusion
    }

    /// Whether the profile's shape is the exact one (where the table holds the stack).
    pub fn exact_shape(self) -> bool {
        self == Transport::AddingDoubling
    }
}

/// Where an exact total comes from. Python's `streams=` and the CLI's `--streams` ask for `Solve` at the streams
/// given; the levels' settings are in `crate::accuracy`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, Hash)]
#[serde(rename_all = "snake_case")]
pub enum ExactTotals {
    /// Read from the shipped table of adding-doubling totals ([`total_table`], 32 streams; within 2.2e-5 of fresh
    /// solves for every skin stack) where it holds the stack (two layers over a semi-infinite dermis at skin's index),
    /// solved otherwise: the default, about 500 times cheaper than a solve.
    #[default]
    Table,
    /// Solved for every wavelength at the accuracy's streams.
    Solve,
}

impl ExactTotals {
    /// The serde name ("table", "solve").
    pub fn name(self) -> &'static str {
        match self {
            ExactTotals::Table => "table",
            ExactTotals::Solve => "solve",
        }
    }
}
