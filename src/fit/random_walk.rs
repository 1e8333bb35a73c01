// TEMPORARY placeholder until the random-walk module lands (helper-2 replaces this file).
use serde::Serialize;
#[derive(Debug, Clone, Copy, Serialize)]
pub struct RandomWalkColor { pub base_color: f64, pub achieved_albedo: f64, pub saturated: bool }
pub fn random_walk_base_color(target_albedo: f64) -> RandomWalkColor { RandomWalkColor { base_color: target_albedo, achieved_albedo: target_albedo, saturated: false } }
pub fn random_walk_radius_scale(base_color: f64) -> f64 { 1.9 - base_color + 3.5 * (base_color - 0.8).powi(2) }
