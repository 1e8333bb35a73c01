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
