//! The skin surface, in one place: the reflection at the skin's top before light enters it, and what Blender's
//! Principled BSDF takes for it.
//!
//! - [`oil_layer`]: DJ2006's oily layer, its Torrance-Sparrow microfacet maths (Beckmann D, V-cavity G, dielectric
//!   Fresnel) and directional albedos; the pieces the other two share.
//! - [`lobes`]: the surface as a reference model of its own, "measured" (two lobes under one Fresnel term, the
//!   default) or "paper" (the oil layer): [`lobes::SurfaceModel`], its BRDF, albedo and normal-incidence reflectance.
//! - [`principled`]: the Principled inputs that stand in for either model (Specular IOR Level, Roughness, IOR, Coat)
//!   per engine, and the albedo Principled's own lobe then has.

pub mod lobes;
pub mod oil_layer;
pub mod principled;
