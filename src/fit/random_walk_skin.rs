//! Blender Cycles' `RANDOM_WALK_SKIN` subsurface method: what its Radius means, and its flat-slab response as
//! measured (best effort: no closed form of this walk's entry is modelled).
//!
//! Cycles rescales a Skin walk's radius per channel through a dipole inversion of Base Color with the Subsurface IOR:
//! `F_dr = -1.440/eta^2 + 0.710/eta + 0.668 + 0.0636 eta`, `A_F = (4/3)(1 + F_dr)/(1 - F_dr)`, `alpha'` solves
//! `Rd(alpha') = alpha'/2 (1 + e^(-A_F s')) e^(-s') = Base Color` with `s' = sqrt(3 (1 - alpha'))` (12 bisection
//! steps on [0, 1]), and the walk's transport mean free path is `Radius * Scale * sqrt(3 (1 - alpha'))` (no 1/(4 pi)).
//! Source: `bssrdf_dipole_compute_Rd`, `bssrdf_dipole_compute_alpha_prime` and `bssrdf_setup_radius` in
//! `src/kernel/closure/bssrdf.h`, `blender/cycles` commit 695bae346ba1 (the same in `release/v5.0`, docs/blender-targets.md,
//! Random Walk (Skin)). The walk then uses the Wrenninge fit for alpha, like `RANDOM_WALK` up to 5.1; its entry is half
//! cosine-distributed diffuse, half GGX refraction with roughness 1 at the Subsurface IOR (`subsurface.h`).

use super::random_walk::{invert_response, RandomWalkColor, ResponseTable};
use super::walk_width::{measured_k, MeasuredWalk};
use crate::numeric::{bisect, clamp_nan_to_low};

/// The Subsurface IOR this mapping assumes (Principled BSDF's default for the socket); the material must use it.
pub const SKIN_SUBSURFACE_IOR: f64 = 1.4;

/// The flat-slab response of a Skin walk as rendered, compiled in: `docs/data/random_walk_skin_flat.json` (written by
/// `<venv>/bin/python scripts/calibration/measure_skin_flat.py`: a thick slab under a uniform white world,
/// `RANDOM_WALK_SKIN`, Specular IOR Level 0, Subsurface IOR 1.4; the same figures to 4 digits in bpy 4.2, 5.0 and
/// 5.3).
const FLAT_RESPONSE_JSON: &str = include_str!("../../docs/data/random_walk_skin_flat.json");

#[derive(serde::Deserialize)]
struct FlatResponseFile {
    cases: Vec<FlatResponseCase>,
}

#[derive(serde::Deserialize)]
struct FlatResponseCase {
    base_color: f64,
    ratio: f64,
}

/// (Base Color, rendered value / Base Color) rows of the measured flat-slab response, rising in Base Color. The JSON
/// is part of the source: a malformed file is a build defect, caught by this module's tests.
fn measured_flat_ratio() -> &'static [(f64, f64)] {
    static ROWS: std::sync::OnceLock<Vec<(f64, f64)>> = std::sync::OnceLock::new();
    ROWS.get_or_init(|| {
        let file: FlatResponseFile =
            serde_json::from_str(FLAT_RESPONSE_JSON).expect("docs/data/random_walk_skin_flat.json parses");
        let mut rows: Vec<(f64, f64)> = file.cases.iter().map(|c| (c.base_color, c.ratio)).collect();
        rows.sort_by(|a, b| a.0.total_cmp(&b.0));
        rows
    })
}

/// The highest measured Base Color: a Skin walk is given no brighter one.
fn highest_measured_base_color() -> f64 {
    let t = measured_flat_ratio();
    t[t.len() - 1].0
}

/// Cycles' Rd below which `bssrdf_dipole_compute_alpha_prime` returns 0, and at or above which it returns 0.999999.
const DIPOLE_RD_LOW: f64 = 1e-4;
const DIPOLE_RD_HIGH: f64 = 0.995;
const DIPOLE_ALPHA_MAX: f64 = 0.999999;
/// Bisection steps of `bssrdf_dipole_compute_alpha_prime` (`max_num_iterations`).
const DIPOLE_BISECTION_STEPS: usize = 12;

/// `A_F` of the dipole: `(4/3)(1 + F_dr)/(1 - F_dr)` with Jensen's `F_dr` fit at relative IOR `eta` (clamped to
/// Cycles' [1.01, 3.8]).
fn dipole_a_f(eta: f64) -> f64 {
    let eta = clamp_nan_to_low(eta, 1.01, 3.8);
    let inv = 1.0 / eta;
    let f_dr = inv * (-1.440 * inv + 0.710) + 0.668 + 0.0636 * eta;
    (4.0 / 3.0) * (1.0 + f_dr) / (1.0 - f_dr)
}

/// `Rd(alpha')` of the dipole with boundary term `a_f`.
fn dipole_rd(alpha_prime: f64, a_f: f64) -> f64 {
    let s = (3.0 * (1.0 - alpha_prime)).sqrt();
    0.5 * alpha_prime * (1.0 + (-a_f * s).exp()) * (-s).exp()
}

/// `alpha'` as Cycles computes it for Base Color `rd` (per channel) and Subsurface IOR `eta`: the midpoint after 12
/// bisection steps, 0 below Rd 1e-4, 0.999999 at or above 0.995. Dimensionless.
pub fn skin_dipole_alpha_prime(rd: f64, eta: f64) -> f64 {
    if rd.is_nan() || rd < DIPOLE_RD_LOW {
        return 0.0;
    }
    if rd >= DIPOLE_RD_HIGH {
        return DIPOLE_ALPHA_MAX;
    }
    let a_f = dipole_a_f(eta);
    // Cycles keeps the upper end where Rd(mid) >= rd (neither side is NaN here) and returns the last midpoint.
    bisect(0.0, 1.0, DIPOLE_BISECTION_STEPS, |mid| dipole_rd(mid, a_f) >= rd).last_midpoint
}

/// `sqrt(3 (1 - alpha'))`: the factor Cycles multiplies a Skin Radius by to get the walk's transport mean free path,
/// for Base Color `base_color` at Subsurface IOR `eta`. Dimensionless, > 0 (>= 0.0017).
pub fn skin_radius_factor(base_color: f64, eta: f64) -> f64 {
    (3.0 * (1.0 - skin_dipole_alpha_prime(base_color, eta))).sqrt()
}

/// Width factor of a Skin walk at Base Color A, dimensionless: the walk's transport mean free path (Radius x Scale x
/// [`skin_radius_factor`]) that renders an edge like a Burley profile of length d is `w d`; `w = 1/k(A)` from the
/// bpy 5.0 `RANDOM_WALK_SKIN` edge renders (`walk_width`), held above the highest Base Color a Skin walk is given
/// (0.95, [`skin_base_color`]).
pub fn skin_width_factor(base_color: f64) -> f64 {
    1.0 / measured_k(MeasuredWalk::Skin, base_color, highest_measured_base_color())
}

/// Flat-slab value Cycles renders for a Skin walk with Base Color A, dimensionless: A times the measured ratio,
/// interpolated linearly between the measured Base Colors (0.005 to 0.95) and held beyond them. Measured at the
/// default Subsurface IOR (1.4) only: an interpolation of renders, not a model of the walk.
pub fn skin_flat_albedo(base_color: f64) -> f64 {
    let a = if base_color.is_nan() { 0.0 } else { base_color.clamp(0.0, 1.0) };
    let t = measured_flat_ratio();
    let ratio = if a <= t[0].0 {
        t[0].1
    } else if a >= t[t.len() - 1].0 {
        t[t.len() - 1].1
    } else {
        let k = t.partition_point(|&(x, _)| x < a).clamp(1, t.len() - 1);
        let ((x0, y0), (x1, y1)) = (t[k - 1], t[k]);
        y0 + (y1 - y0) * (a - x0) / (x1 - x0)
    };
    a * ratio
}

/// Base Color for a Skin walk whose flat slab renders `target_albedo`, by the shared root finder on the measured
/// response, up to the highest measured Base Color (0.95).
pub fn skin_base_color(target_albedo: f64) -> RandomWalkColor {
    static TABLE: std::sync::OnceLock<ResponseTable> = std::sync::OnceLock::new();
    let a_sat = highest_measured_base_color();
    let table = TABLE.get_or_init(|| ResponseTable::new(a_sat, skin_flat_albedo));
    invert_response(target_albedo, table, skin_flat_albedo)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Independent check of the bisection: Rd(alpha') from the dipole formula returns Base Color within the 2^-12
    /// bracket Cycles stops at.
    #[test]
    fn dipole_inversion_round_trips() {
        let a_f = dipole_a_f(SKIN_SUBSURFACE_IOR);
        for a in [0.01, 0.1, 0.3, 0.6, 0.9] {
            let ap = skin_dipole_alpha_prime(a, SKIN_SUBSURFACE_IOR);
            // Rd is monotonic; the true root lies within 2^-12 of the returned midpoint.
            let h = 0.5f64.powi(12);
            assert!(dipole_rd(ap - h, a_f) <= a && dipole_rd(ap + h, a_f) >= a, "A = {a}: alpha' = {ap}");
        }
        assert_eq!(skin_dipole_alpha_prime(0.0, 1.4), 0.0);
        assert_eq!(skin_dipole_alpha_prime(0.999, 1.4), DIPOLE_ALPHA_MAX);
        assert_eq!(skin_dipole_alpha_prime(f64::NAN, 1.4), 0.0);
    }

    /// The compiled-in measurements cover the african preset's Base Colors (0.02-0.04) and the response they give is
    /// rising, so the inversion is unique.
    #[test]
    fn measured_flat_response_is_rising_and_covers_dark_skin() {
        let t = measured_flat_ratio();
        assert!(t.len() >= 10 && t[0].0 <= 0.01 && highest_measured_base_color() >= 0.9, "{t:?}");
        for w in t.windows(2) {
            assert!(w[1].0 > w[0].0 && w[1].0 * w[1].1 > w[0].0 * w[0].1, "{w:?}");
        }
    }

    /// The measured response is rising, so the inversion is unique, and it round-trips.
    #[test]
    fn skin_base_color_round_trips() {
        for i in 1..=80 {
            let t = 0.01 * i as f64;
            let c = skin_base_color(t);
            assert!(!c.saturated && (skin_flat_albedo(c.base_color) - t).abs() < 1e-12, "t = {t}: {c:?}");
        }
        assert!(skin_base_color(0.99).saturated, "{:?}", skin_base_color(0.99));
    }
}
