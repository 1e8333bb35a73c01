//! Inverse problems: the parameters that reproduce a measurement.

pub mod albedo;
pub mod albedo_maps;
