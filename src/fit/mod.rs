//! Blender-facing fits: the Subsurface Radius and Base Color per Cycles subsurface method (blender.md).

pub mod burley;
pub mod random_walk;

use serde::{Deserialize, Serialize};

/// Cycles' subsurface methods that spectral-skin maps to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SubsurfaceMethod {
    /// Christensen-Burley: Base Color is rendered exactly as the total diffuse reflectance (blender.md 3).
    Burley,
    /// Random Walk: a volumetric walk whose flat-slab albedo falls short of Base Color; compensated (blender.md 3).
    RandomWalk,
}

/// How the Christensen-Burley length is fitted to the model's profile (`burley`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum RadiusFit {
    /// Least squares on the edge response, through the transfer function on log-spaced frequencies (`fit_burley`).
    #[default]
    EdgeL2,
    /// Match the profile's second moment, from one low frequency (`fit_burley_second_moment`): one transform per
    /// wavelength instead of dozens, but a profile with a long tail gets too wide a radius.
    SecondMoment,
}

/// The default method: Christensen-Burley, because Cycles renders its Base Color exactly and its profile is a
/// closed form the fit can match (blender.md TL;DR).
pub const DEFAULT_METHOD: SubsurfaceMethod = SubsurfaceMethod::Burley;

impl SubsurfaceMethod {
    pub fn name(self) -> &'static str {
        match self {
            SubsurfaceMethod::Burley => "burley",
            SubsurfaceMethod::RandomWalk => "random_walk",
        }
    }
}
