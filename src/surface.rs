// TEMPORARY placeholder until the surface module lands (helper-2 replaces this file).
use serde::Serialize;
#[derive(Debug, Clone, Copy, Serialize)]
pub struct SpecularParams { pub oiliness: f64, pub specular_ior_level: f64, pub roughness: f64, pub ior: f64, pub beckmann_m: f64, pub directional_albedo_normal: f64, pub hemispherical_albedo: f64 }
pub fn specular_from_oiliness(oiliness: f64) -> SpecularParams { SpecularParams { oiliness, specular_ior_level: 0.5 * oiliness, roughness: 0.35f64.sqrt(), ior: 1.4, beckmann_m: 0.35, directional_albedo_normal: 0.0, hemispherical_albedo: 0.0 } }
