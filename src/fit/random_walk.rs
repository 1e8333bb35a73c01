//! Blender Cycles' `RANDOM_WALK` subsurface method (Cycles 5.0) in closed form, for choosing its Base Color and Radius.
//!
//! Cycles maps the Principled BSDF's Base Color `A` (per channel, clamped to [0, 1]) to a single-scattering albedo
//! `alpha` with a fit by Wrenninge, Villemin and Hery (Pixar), "Path Traced Subsurface Scattering using Anisotropic
//! Phase Functions and Non-Exponential Free Flights" (Pixar Technical Memo #17-07, 2017,
//! <https://graphics.pixar.com/library/PathTracedSubsurface/>), then runs an index-matched random walk with
//! `1/sigma_t' = Radius * Scale / (4 pi)`. Source: `subsurface_random_walk_remap` and
//! `subsurface_random_walk_coefficients` in `src/kernel/integrator/subsurface_random_walk.h` of the `blender/cycles`
//! mirror (`intern/cycles/kernel/integrator/subsurface_random_walk.h` in the Blender monorepo), branch `release/v5.0`;
//! the fit's constants below were transcribed from `blender/cycles` commit 695bae346ba1 and checked identical in
//! `blender/blender` commit 00dcfdf916c6 (Cycles 3.x). The g = 0 values agree with `release/v5.0` (2eba41024174;
//! docs/blender-principled.md, Random walk in Cycles 5.0). Cycles after 5.0 (`blender/cycles` 695bae346ba1) also has
//! d'Eon's Van de Hulst mapping ("A Hitchhiker's Guide to Multiple Scattering", eq. 53.7) for a new walk model and
//! keeps this fit as the legacy path. [`RandomWalkModel`] names the two alpha mappings; Blender 5.2 and later use the
//! Van de Hulst one for `RANDOM_WALK` and keep the fit for `RANDOM_WALK_LEGACY` (see `fit::blender_target`).
//!
//! For a thick flat slab seen straight down under a uniform white world (Specular IOR Level 0, so no surface
//! reflection and an index-matched boundary), the rendered value is the directional albedo of an isotropic,
//! index-matched half-space, `R(mu0) = 1 - H(mu0; alpha) sqrt(1 - alpha)` with Chandrasekhar's H-function
//! (Chandrasekhar, "Radiative Transfer", 1950, ch. V; renders in docs/blender-principled.md, Flat slab under a white
//! world). Cycles' Burley method, by contrast, renders exactly Base Color.

use std::sync::OnceLock;

use super::walk_width::{measured_k, MeasuredWalk};

use serde::Serialize;

use crate::numeric::{bisect, clamp_nan_to_low, illinois};
use crate::transport::half_space::h_normal_incidence;

/// Upper clamp of the single-scattering albedo in `subsurface_random_walk_remap` ("because of numerical precision").
pub const CYCLES_MAX_SINGLE_SCATTER_ALBEDO: f64 = 0.999999;
/// `min_alpha` of `subsurface_random_walk_coefficients`: a smaller alpha walks at 0.2, throughput times alpha / 0.2.
pub const CYCLES_MIN_SINGLE_SCATTER_ALBEDO: f64 = 0.2;
/// Largest Subsurface Anisotropy Cycles 5.0 accepts: `bssrdf_setup` clamps g to [0, 0.9] (bssrdf.h L294).
pub const CYCLES_MAX_ANISOTROPY: f64 = 0.9;

/// `a(g)`: polynomial coefficients, g^0..g^7 (Wrenninge et al. 2017 via `subsurface_random_walk_remap`, `A`).
#[rustfmt::skip]
const FIT_A: [f64; 8] = [
    1.8260523782, -1.28451056436, -1.79904629312, 9.19393289202,
    -22.8215585862, 32.0234874259, -23.6264803333, 7.21067002658,
];
/// `b(g) = 4.98511194385 + 0.127355959438 exp(poly(g))`: constant, factor and exponent polynomial (Cycles `B`).
const FIT_B_CONST: f64 = 4.98511194385;
const FIT_B_FACTOR: f64 = 0.127355959438;
#[rustfmt::skip]
const FIT_B_EXP: [f64; 8] = [
    0.0, 31.1491581433, -201.847017512, 841.576016723,
    -2018.09288505, 2731.71560286, -1935.41424244, 559.009054474,
];
/// `c(g)` (Cycles `C`).
#[rustfmt::skip]
const FIT_C: [f64; 8] = [
    1.09686102424, -0.394704063468, 1.05258115941, -8.83963712726,
    28.8643230661, -46.8802913581, 38.5402837518, -12.7181042538,
];
/// `d(g)` (Cycles `D`).
#[rustfmt::skip]
const FIT_D: [f64; 8] = [
    0.496310210422, 0.360146581622, -2.15139309747, 17.8896899217,
    -55.2984010333, 82.065982243, -58.5106008578, 15.8478295021,
];
/// `e(g) = 4.23190299701 + 0.00310603949088 exp(poly(g))` (Cycles `E`).
const FIT_E_CONST: f64 = 4.23190299701;
const FIT_E_FACTOR: f64 = 0.00310603949088;
#[rustfmt::skip]
const FIT_E_EXP: [f64; 8] = [
    0.0, 76.7316253952, -594.356773233, 2448.8834203,
    -5576.68528998, 7116.60171912, -4763.54467887, 1303.5318055,
];
/// `f(g)` (Cycles `F`).
#[rustfmt::skip]
const FIT_F: [f64; 8] = [
    2.40602999408, -2.51814844609, 9.18494908356, -79.2191708682,
    259.082868209, -403.613804597, 302.85712436, -87.4370473567,
];
/// Exponent of `blend = A^0.25` in `subsurface_random_walk_remap`.
const FIT_BLEND_EXPONENT: f64 = 0.25;

/// Van de Hulst's albedo inversion as d'Eon writes it ("A Hitchhiker's Guide to Multiple Scattering", v0.3.2,
/// eq. 53.7): `s = 4.09712 + 4.20863 A - sqrt(9.59217 + 41.6808 A + 17.7126 A^2)`. Transcribed from the Spectrum
/// overload of `subsurface_random_walk_remap` in `src/kernel/integrator/subsurface_random_walk.h`, `blender/cycles`
/// commit 695bae346ba1 (the 5.2 change, PR #156355).
const VAN_DE_HULST_OFFSET: f64 = 4.09712;
const VAN_DE_HULST_LINEAR: f64 = 4.20863;
const VAN_DE_HULST_ROOT: [f64; 3] = [9.59217, 41.6808, 17.7126];

/// Bisection steps on the Base Color (2^-60 of the bracket: below f64 resolution).
const BISECTION_STEPS: usize = 60;

/// `sum_k c_k g^k` (Horner).
fn polynomial(c: &[f64], g: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &ck| acc * g + ck)
}

/// `alpha(A, g)`: single-scattering albedo Cycles walks with for Base Color A and anisotropy g, before the
/// min-alpha rule (Wrenninge et al. 2017 fit, Cycles `subsurface_random_walk_remap`).
///
/// `alpha = (1 - blend) a(g) atan(b(g) A)^c(g) + blend d(g) atan(e(g) A)^f(g)`, `blend = A^0.25`, clamped to
/// [0, 0.999999]. A is clamped to [0, 1] as Cycles clamps Base Color; g to [0, 0.9] as Cycles 5.0 clamps Subsurface
/// Anisotropy; NaN counts as 0. Cycles evaluates this in f32; here it is f64 (differences ~1e-7).
pub fn cycles_single_scatter_albedo(base_color: f64, anisotropy: f64) -> f64 {
    let albedo = clamp_nan_to_low(base_color, 0.0, 1.0);
    let g = clamp_nan_to_low(anisotropy, 0.0, CYCLES_MAX_ANISOTROPY);
    let a = polynomial(&FIT_A, g);
    let b = FIT_B_CONST + FIT_B_FACTOR * polynomial(&FIT_B_EXP, g).exp();
    let c = polynomial(&FIT_C, g);
    let d = polynomial(&FIT_D, g);
    let e = FIT_E_CONST + FIT_E_FACTOR * polynomial(&FIT_E_EXP, g).exp();
    let f = polynomial(&FIT_F, g);
    let blend = albedo.powf(FIT_BLEND_EXPONENT);
    let alpha = (1.0 - blend) * a * (b * albedo).atan().powf(c) + blend * d * (e * albedo).atan().powf(f);
    clamp_nan_to_low(alpha, 0.0, CYCLES_MAX_SINGLE_SCATTER_ALBEDO)
}

/// `alpha(A, g)` of Cycles' Van de Hulst mapping (Blender 5.2 and later, `RANDOM_WALK`): with `s` of d'Eon's
/// eq. 53.7 (see `VAN_DE_HULST_OFFSET`), `alpha = (1 - s^2) / (1 - g s^2)`, clamped to [0, 0.999999], before the
/// min-alpha rule, dimensionless. A is clamped to [0, 1]; g to [-0.99, 0.99] as `bssrdf_setup` clamps it for
/// `RANDOM_WALK` in that commit; NaN counts as 0. alpha(0) = 0 and alpha rises to the clamp near A = 1.
pub fn van_de_hulst_single_scatter_albedo(base_color: f64, anisotropy: f64) -> f64 {
    let a = clamp_nan_to_low(base_color, 0.0, 1.0);
    let g = if anisotropy.is_nan() {
        0.0
    } else {
        anisotropy.clamp(-VAN_DE_HULST_MAX_ANISOTROPY, VAN_DE_HULST_MAX_ANISOTROPY)
    };
    let [r0, r1, r2] = VAN_DE_HULST_ROOT;
    let s = VAN_DE_HULST_OFFSET + VAN_DE_HULST_LINEAR * a - (r0 + r1 * a + r2 * a * a).sqrt();
    let s2 = s * s;
    // Cycles' safe_divide: 1 - g s^2 > 0 here, since |g| < 1 and s^2 <= 1 on [0, 1].
    clamp_nan_to_low((1.0 - s2) / (1.0 - g * s2), 0.0, CYCLES_MAX_SINGLE_SCATTER_ALBEDO)
}

/// Largest |Subsurface Anisotropy| Cycles' `RANDOM_WALK` accepts from 5.2 on (`bssrdf_setup`, `bssrdf.h`,
/// `blender/cycles` 695bae346ba1).
pub const VAN_DE_HULST_MAX_ANISOTROPY: f64 = 0.99;

/// How a Cycles random walk turns Base Color into the single-scattering albedo it walks with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RandomWalkModel {
    /// Wrenninge et al.'s fit ([`cycles_single_scatter_albedo`]): `RANDOM_WALK` up to 5.1, `RANDOM_WALK_LEGACY` and
    /// `RANDOM_WALK_SKIN` after.
    WrenningeFit,
    /// Van de Hulst / d'Eon eq. 53.7 ([`van_de_hulst_single_scatter_albedo`]): `RANDOM_WALK` from 5.2 on.
    VanDeHulst,
}

impl RandomWalkModel {
    /// Every model, in a fixed order (index of its cached inversion tables).
    pub const ALL: [RandomWalkModel; 2] = [RandomWalkModel::WrenningeFit, RandomWalkModel::VanDeHulst];

    /// The single-scattering albedo this model walks with for Base Color A at g = 0 (before the min-alpha rule).
    pub fn single_scatter_albedo(self, base_color: f64) -> f64 {
        match self {
            RandomWalkModel::WrenningeFit => cycles_single_scatter_albedo(base_color, 0.0),
            RandomWalkModel::VanDeHulst => van_de_hulst_single_scatter_albedo(base_color, 0.0),
        }
    }

    fn index(self) -> usize {
        self as usize
    }
}

/// Flat-slab value Cycles RW renders for Base Color A at g = 0, viewed straight down under a uniform white world,
/// dimensionless (docs/blender-principled.md, Flat slab under a white world).
///
/// `R = 1 - H(1; alpha) sqrt(1 - alpha)` with `alpha = alpha(A, 0)`; when alpha < 0.2, Cycles walks at 0.2 and
/// scales the throughput by alpha / 0.2, so R = (alpha / 0.2) R(1; 0.2). This matched bpy 5.0.1 renders within 0.3%
/// for A <= 0.8 (the renders and this model side by side: the table of that section; tests below). Not modelled:
/// Cycles' `BSSRDF_MAX_BOUNCES = 256` cap, which loses the paths still inside after 256 scatterings: 0.3% at
/// A = 0.8 and 10% at A = 0.95.
/// A is clamped to [0, 1], NaN counts as 0.
pub fn random_walk_flat_albedo(base_color: f64) -> f64 {
    flat_albedo(RandomWalkModel::WrenningeFit, base_color)
}

/// [`random_walk_flat_albedo`] for either alpha mapping: the flat-slab value a Cycles random walk renders for Base
/// Color A, from the single-scattering albedo `model` walks with. The H-function model, the min-alpha rule
/// (`subsurface_random_walk_coefficients`, unchanged in `blender/cycles` 695bae346ba1, where it applies after either
/// mapping) and what is not modelled (the 256-bounce cap) are the same for both.
pub fn flat_albedo(model: RandomWalkModel, base_color: f64) -> f64 {
    flat_albedo_of_single_scatter(model.single_scatter_albedo(base_color))
}

/// The flat-slab value of a walk with single-scattering albedo `alpha` (before the min-alpha rule), dimensionless.
pub fn flat_albedo_of_single_scatter(alpha: f64) -> f64 {
    let alpha = clamp_nan_to_low(alpha, 0.0, 1.0);
    let walked = alpha.max(CYCLES_MIN_SINGLE_SCATTER_ALBEDO);
    let throughput = alpha / walked;
    throughput * (1.0 - h_normal_incidence(walked) * (1.0 - walked).sqrt())
}

/// Base Color for Cycles RW that renders a wanted flat-slab albedo, and what it achieves.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RandomWalkColor {
    /// Base Color to set, in [0, A_sat] (A_sat: where the model's alpha reaches its clamp; 0.9175 for the fit).
    pub base_color: f64,
    /// The flat-slab value `base_color` renders: the target, unless saturated.
    pub achieved_albedo: f64,
    /// True when the target was above what RW reaches (or NaN); `base_color` is then the best achievable.
    pub saturated: bool,
}

/// Nodes of a monotonic flat-slab response on [0, A_sat], from which [`invert_response`] brackets its root.
pub(crate) struct ResponseTable {
    /// The smallest Base Color at which the response stops rising (the model's alpha reaches its clamp).
    pub a_sat: f64,
    /// (A, response(A)) on [0, A_sat], rising.
    pub nodes: Vec<(f64, f64)>,
}

/// Number of nodes of a [`ResponseTable`].
const RESPONSE_NODES: usize = 257;

impl ResponseTable {
    /// Tabulate `response` on [0, a_sat].
    pub fn new(a_sat: f64, response: impl Fn(f64) -> f64) -> ResponseTable {
        let nodes = (0..RESPONSE_NODES)
            .map(|i| {
                let a = a_sat * i as f64 / (RESPONSE_NODES - 1) as f64;
                (a, response(a))
            })
            .collect();
        ResponseTable { a_sat, nodes }
    }
}

/// `A_sat` of `model`: the smallest Base Color at which its alpha reaches 0.999999, by bisection.
fn saturation_of(model: RandomWalkModel) -> f64 {
    bisect(0.5, 1.0, BISECTION_STEPS, |mid| model.single_scatter_albedo(mid) >= CYCLES_MAX_SINGLE_SCATTER_ALBEDO).hi
}

/// The response table of `model`, computed once per model.
fn response_table(model: RandomWalkModel) -> &'static ResponseTable {
    static TABLES: [OnceLock<ResponseTable>; RandomWalkModel::ALL.len()] = [OnceLock::new(), OnceLock::new()];
    TABLES[model.index()].get_or_init(|| ResponseTable::new(saturation_of(model), |a| flat_albedo(model, a)))
}

/// `A_sat` of the Wrenninge fit (g = 0).
#[cfg(test)]
fn saturation_base_color() -> f64 {
    response_table(RandomWalkModel::WrenningeFit).a_sat
}

/// Base Color A such that [`random_walk_flat_albedo`]`(A)` equals `target_albedo` (dimensionless), the inverse of
/// Cycles RW's flat-slab response at g = 0 with the Wrenninge fit (Blender 4.2-5.1 `RANDOM_WALK`, and
/// `RANDOM_WALK_LEGACY`).
///
/// Solved on [0, A_sat], where the response rises monotonically from 0 to its maximum 0.99710 (alpha = 0.999999).
/// A target above that maximum gives A_sat with `saturated = true`. The target is clamped to [0, 1]; NaN gives
/// base color 0, achieved 0 and `saturated = true`. The 256-bounce cap is not modelled (see
/// [`random_walk_flat_albedo`]): above A ~ 0.8 Cycles renders less than `achieved_albedo`.
pub fn random_walk_base_color(target_albedo: f64) -> RandomWalkColor {
    base_color_for(RandomWalkModel::WrenningeFit, target_albedo)
}

/// [`random_walk_base_color`] for either alpha mapping: the Base Color whose [`flat_albedo`] under `model` is
/// `target_albedo`. Both mappings reach the same maximum (alpha clamped to 0.999999), so the same targets saturate.
pub fn base_color_for(model: RandomWalkModel, target_albedo: f64) -> RandomWalkColor {
    invert_response(target_albedo, response_table(model), |a| flat_albedo(model, a))
}

/// The root finder shared by every random-walk response: the Base Color in [0, A_sat] at which the monotonic
/// `response` (tabulated in `table`) equals `target_albedo`. NaN gives 0 with `saturated = true`; a target at or
/// above `response(A_sat)` gives A_sat (saturated if above); a target <= 0 gives 0.
pub(crate) fn invert_response(
    target_albedo: f64,
    table: &ResponseTable,
    response: impl Fn(f64) -> f64,
) -> RandomWalkColor {
    if target_albedo.is_nan() {
        return RandomWalkColor { base_color: 0.0, achieved_albedo: 0.0, saturated: true };
    }
    let target = target_albedo.clamp(0.0, 1.0);
    let a_sat = table.a_sat;
    let r_max = table.nodes[table.nodes.len() - 1].1;
    if target >= r_max {
        return RandomWalkColor { base_color: a_sat, achieved_albedo: r_max, saturated: target > r_max };
    }
    if target <= 0.0 {
        return RandomWalkColor { base_color: 0.0, achieved_albedo: 0.0, saturated: false };
    }
    // Bracket the root between two nodes of the cached response table, then refine by the Illinois variant of regula
    // falsi (superlinear on this smooth, monotonic response; a handful of evaluations instead of ~50 bisections).
    let nodes = &table.nodes;
    let k = nodes.partition_point(|&(_, r)| r < target).clamp(1, nodes.len() - 1);
    let ((lo, r_lo), (hi, r_hi)) = (nodes[k - 1], nodes[k]);
    let base_color = illinois((lo, r_lo - target), (hi, r_hi - target), BISECTION_STEPS, |a| response(a) - target);
    RandomWalkColor { base_color, achieved_albedo: response(base_color), saturated: false }
}

/// Width factor `w` of a walk under `model` at Base Color A, dimensionless: the walk's transport mean free path that
/// renders an edge like a Burley profile of length d is `w d`. `w = 1/k(A)` with k the edge-render calibration of
/// the model's walk (`walk_width`: bpy 5.0 `RANDOM_WALK` for the fit, bpy 5.3 `RANDOM_WALK` for Van de Hulst), its
/// trend continued above the measured Base Colors up to the model's saturation (where alpha stops changing).
pub fn width_factor(model: RandomWalkModel, base_color: f64) -> f64 {
    let walk = match model {
        RandomWalkModel::WrenningeFit => MeasuredWalk::WrenningeFit,
        RandomWalkModel::VanDeHulst => MeasuredWalk::VanDeHulst,
    };
    1.0 / measured_k(walk, base_color, response_table(model).a_sat)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::relative_error as rel;
    use crate::transport::half_space::{chandrasekhar_h, half_space_hemispherical_albedo};

    /// Wrenninge et al.'s coefficients at g = 0 as read in Cycles 5.0 (docs/blender-principled.md, Random walk in
    /// Cycles 5.0: a..f = 1.82605, 5.11247, ...).
    #[test]
    fn fit_coefficients_at_zero_anisotropy() {
        let b = FIT_B_CONST + FIT_B_FACTOR;
        let e = FIT_E_CONST + FIT_E_FACTOR;
        for (got, want) in [
            (FIT_A[0], 1.82605),
            (b, 5.11247),
            (FIT_C[0], 1.09686),
            (FIT_D[0], 0.49631),
            (e, 4.23501),
            (FIT_F[0], 2.40603),
        ] {
            assert!((got - want).abs() < 1e-5, "got {got}, documented {want}");
        }
    }

    /// Every A >= 0.918 gives alpha = 0.999999 (docs/blender-principled.md, Random walk in Cycles 5.0); the fit is
    /// monotonic below.
    #[test]
    fn fit_saturates_near_0918_and_is_monotonic() {
        let a_sat = saturation_base_color();
        assert!((a_sat - 0.918).abs() < 1e-3, "A_sat = {a_sat}");
        assert_eq!(cycles_single_scatter_albedo(0.95, 0.0), CYCLES_MAX_SINGLE_SCATTER_ALBEDO);
        let mut last = -1.0;
        for i in 0..=2000 {
            let a = a_sat * i as f64 / 2000.0;
            let alpha = cycles_single_scatter_albedo(a, 0.0);
            assert!(alpha > last, "alpha not increasing at A = {a}: {alpha} <= {last}");
            last = alpha;
        }
        for g in [0.0, 0.3, 0.6, 0.9] {
            let alpha = cycles_single_scatter_albedo(0.5, g);
            assert!(alpha > 0.0 && alpha < 1.0, "g = {g}: {alpha}");
        }
    }

    /// docs/blender-principled.md, Flat slab under a white world, the "RW theory" column: flat-slab value / Base Color.
    #[test]
    fn flat_albedo_matches_documented_theory_column() {
        for (a, ratio) in [(0.05, 0.7706), (0.2, 0.8082), (0.5, 0.8832), (0.8, 0.9653), (0.95, 1.0496)] {
            let got = random_walk_flat_albedo(a) / a;
            assert!((got - ratio).abs() < 1e-4, "A = {a}: {got} vs {ratio}");
        }
    }

    /// The same table, bpy 5.0.1 renders (Random Walk column): within 0.4% below A = 0.8.
    #[test]
    fn flat_albedo_close_to_renders() {
        for (a, rendered) in [(0.05, 0.7724), (0.2, 0.8072), (0.5, 0.8823), (0.8, 0.9624)] {
            let got = random_walk_flat_albedo(a) / a;
            assert!(rel(got, rendered) < 4e-3, "A = {a}: {got} vs rendered {rendered}");
        }
    }

    /// The fit targets the hemispherical albedo, R_hemi(alpha(A)) = 0.0505/0.202/0.505/0.812
    /// (docs/blender-principled.md, Random walk in Cycles 5.0).
    #[test]
    fn fit_targets_hemispherical_albedo() {
        for (a, want) in [(0.05, 0.0505), (0.2, 0.202), (0.5, 0.505), (0.8, 0.812)] {
            let got = half_space_hemispherical_albedo(cycles_single_scatter_albedo(a, 0.0));
            assert!((got - want).abs() < 1e-3, "A = {a}: {got} vs {want}");
        }
    }

    #[test]
    fn flat_albedo_is_monotonic_and_bounded() {
        let mut last = -1.0;
        for i in 0..=400 {
            let a = saturation_base_color() * i as f64 / 400.0;
            let r = random_walk_flat_albedo(a);
            assert!(r > last && r <= 1.0, "A = {a}: {r} after {last}");
            last = r;
        }
        assert_eq!(random_walk_flat_albedo(0.0), 0.0);
    }

    #[test]
    fn base_color_round_trip() {
        for i in 1..=90 {
            let t = 0.01 * i as f64;
            let c = random_walk_base_color(t);
            assert!(!c.saturated, "t = {t}");
            let back = random_walk_flat_albedo(c.base_color);
            assert!((back - t).abs() < 1e-12, "t = {t}: A = {}, back {back}", c.base_color);
            assert!((c.achieved_albedo - t).abs() < 1e-12, "t = {t}: achieved {}", c.achieved_albedo);
        }
        let mut last = 0.0;
        for i in 1..=99 {
            let a = random_walk_base_color(0.01 * i as f64).base_color;
            assert!(a > last, "base color not increasing at {i}");
            last = a;
        }
    }

    #[test]
    fn base_color_edges() {
        let nan = random_walk_base_color(f64::NAN);
        assert_eq!((nan.base_color, nan.achieved_albedo, nan.saturated), (0.0, 0.0, true));
        let zero = random_walk_base_color(-3.0);
        assert_eq!((zero.base_color, zero.achieved_albedo, zero.saturated), (0.0, 0.0, false));
        let top = random_walk_base_color(1.0);
        assert!(
            top.saturated && (top.base_color - saturation_base_color()).abs() < 1e-15,
            "{top:?} vs A_sat {}",
            saturation_base_color()
        );
        assert!((top.achieved_albedo - 0.9971).abs() < 1e-4, "R_max = {}", top.achieved_albedo);
        let inf = random_walk_base_color(f64::INFINITY);
        assert!(inf.saturated && inf.base_color == top.base_color, "{inf:?} vs {top:?}");
    }

    #[test]
    fn edge_inputs_do_not_panic_or_leak_nan() {
        for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -1.0, 2.0] {
            assert!(cycles_single_scatter_albedo(x, x).is_finite(), "x = {x}: {}", cycles_single_scatter_albedo(x, x));
            assert!(chandrasekhar_h(x, x).is_finite(), "x = {x}: {}", chandrasekhar_h(x, x));
            assert!(random_walk_flat_albedo(x).is_finite(), "x = {x}: {}", random_walk_flat_albedo(x));
        }
        assert_eq!(cycles_single_scatter_albedo(f64::NAN, 0.0), 0.0);
        assert_eq!(cycles_single_scatter_albedo(2.0, 0.0), cycles_single_scatter_albedo(1.0, 0.0));
    }
}
