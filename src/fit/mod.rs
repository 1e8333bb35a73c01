//! Blender-facing fits: the Subsurface Radius and Base Color per Cycles subsurface method (docs/blender-targets.md).
//! The surface's Principled inputs are [`crate::surface::principled`]'s.

pub mod blender_target;
pub mod burley;
pub mod random_walk;
pub mod random_walk_skin;
pub mod walk_width;

use serde::{Deserialize, Serialize};

/// The Principled BSDF's subsurface methods that spectral-skin maps to (which a Blender version offers, and how it
/// renders them: `blender_target::VERSION_TABLE`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum), value(rename_all = "snake_case"))]
#[serde(rename_all = "snake_case")]
pub enum SubsurfaceMethod {
    /// Christensen-Burley: Base Color is rendered exactly as the total diffuse reflectance.
    Burley,
    /// Random Walk: a volumetric walk whose flat-slab albedo falls short of Base Color; compensated.
    RandomWalk,
    /// Random Walk (Legacy), Blender 5.2 and later: the walk `RANDOM_WALK` was up to 5.1.
    RandomWalkLegacy,
    /// Random Walk (Skin): radius rescaled through a dipole with the Subsurface IOR (measured flat response and
    /// width; tested per Blender version as blender_targets() lists).
    RandomWalkSkin,
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
/// closed form the fit can match (docs/blender-principled.md, section Subsurface Radius and Subsurface Scale).
pub const DEFAULT_METHOD: SubsurfaceMethod = SubsurfaceMethod::Burley;

impl SubsurfaceMethod {
    pub const ALL: [SubsurfaceMethod; 4] = [
        SubsurfaceMethod::Burley,
        SubsurfaceMethod::RandomWalk,
        SubsurfaceMethod::RandomWalkLegacy,
        SubsurfaceMethod::RandomWalkSkin,
    ];

    /// snake_case name (JSON, Python).
    pub fn name(self) -> &'static str {
        match self {
            SubsurfaceMethod::Burley => "burley",
            SubsurfaceMethod::RandomWalk => "random_walk",
            SubsurfaceMethod::RandomWalkLegacy => "random_walk_legacy",
            SubsurfaceMethod::RandomWalkSkin => "random_walk_skin",
        }
    }

    /// The Principled BSDF's `subsurface_method` identifier.
    pub fn blender_id(self) -> &'static str {
        match self {
            SubsurfaceMethod::Burley => "BURLEY",
            SubsurfaceMethod::RandomWalk => "RANDOM_WALK",
            SubsurfaceMethod::RandomWalkLegacy => "RANDOM_WALK_LEGACY",
            SubsurfaceMethod::RandomWalkSkin => "RANDOM_WALK_SKIN",
        }
    }

    /// The method named `name` (snake_case); the error lists the names.
    pub fn from_name(name: &str) -> Result<SubsurfaceMethod, crate::error::SkinError> {
        SubsurfaceMethod::ALL.into_iter().find(|m| m.name() == name).ok_or_else(|| {
            let names: Vec<&str> = SubsurfaceMethod::ALL.iter().map(|m| m.name()).collect();
            crate::error::SkinError::invalid(
                "subsurface method",
                format!("expected one of {}; got {name:?}", names.join(", ")),
            )
        })
    }
}

/// Base Color and Subsurface Radius for one subsurface method on one target.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MethodParams {
    /// Principled Base Color, linear RGB in the request's working space.
    pub base_color: [f64; 3],
    /// Principled Subsurface Radius x Subsurface Scale, mm per channel.
    pub subsurface_radius_mm: [f64; 3],
    /// The flat-slab albedo the target is expected to render with these inputs (equals the model's for Burley; for
    /// the random walks, lower where the target is out of the method's reach).
    pub expected_albedo: [f64; 3],
}
