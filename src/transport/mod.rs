//! Radiative transfer beyond diffusion: exact solutions for simple geometries that the Blender mappings in `fit`
//! compare a renderer's walk against.

pub mod half_space;
