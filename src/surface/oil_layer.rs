//! DJ2006's oily surface layer (docs/model.md, Oil layer): its microfacet maths and albedos, shared by the surface
//! models ([`crate::surface::lobes`]). The mapping to the Principled BSDF's inputs is [`crate::surface::principled`].
//!
//! DJ2006's surface term is a Torrance-Sparrow lobe scaled by the oiliness rho_s:
//! `f_r = rho_s D G F / (4 cos_i cos_o)`, Beckmann `D` with m = 0.35, the V-cavity `G`, and the exact unpolarised
//! dielectric Fresnel term at eta = 1.4 (pbrt-v2 `Microfacet`, as DAM and YW use it). Its directional albedo
//! `rho_dr(theta_i)` (DJ2006 eq. 2) is the light the surface takes before the rest enters the skin: the BSSRDF carries
//! `(1 - rho_dr(omega_i)) (1 - rho_dr(omega_o))`.

use std::f64::consts::{FRAC_PI_2, PI};
use std::sync::OnceLock;

use crate::numeric::{clamp_nan_to_low, composite_gauss_legendre, gauss_legendre};

/// Beckmann roughness m of the oil layer: "values for sigma in the range 0.2 - 0.4 give good results for skin, and we
/// use sigma = 0.35" (DJ2006; DAM `Beckmann(0.35f)`; docs/model.md, Parameters and Oil layer).
pub const BECKMANN_ROUGHNESS_M: f64 = 0.35;
/// Index of refraction of the skin surface, "a constant index of refraction of 1.4 throughout the skin" (DJ2006;
/// DAM `FresnelDielectric(1., 1.4f)`; docs/model.md, Oil layer).
pub const SKIN_SURFACE_IOR: f64 = 1.4;

/// Smallest incidence cosine evaluated; below it the value at this cosine is returned (the limit is finite).
const MIN_COS_THETA_I: f64 = 1e-6;
/// Albedo quadrature over half-vectors (see [`torrance_sparrow_directional_albedo`]): panels in theta_h (per
/// region), Gauss-Legendre order per panel, and Gauss-Legendre order in phi (per piece between kinks of G).
pub(crate) const ALBEDO_THETA_PANELS: usize = 64;
const ALBEDO_THETA_ORDER: usize = 8;
const ALBEDO_PHI_ORDER: usize = 16;
/// Gauss-Legendre order in mu for hemispherical (cosine-weighted) averages of a directional albedo, over panels
/// [0, 0.1, 0.3, 0.6, 1] that follow its steep rise at grazing incidence.
const HEMISPHERE_MU_BREAKS: [f64; 5] = [0.0, 0.1, 0.3, 0.6, 1.0];
const HEMISPHERE_MU_ORDER: usize = 12;

/// `x` clamped to [0, 1], NaN mapped to 0.
pub(crate) fn clamp_unit_or_zero(x: f64) -> f64 {
    clamp_nan_to_low(x, 0.0, 1.0)
}

/// `F0(eta) = ((eta - 1) / (eta + 1))^2`: normal-incidence Fresnel reflectance, dimensionless (Cycles `F0_from_ior`).
pub fn f0_from_ior(eta: f64) -> f64 {
    let r = (eta - 1.0) / (eta + 1.0);
    r * r
}

/// `F_r(cos theta_i; eta)`: exact unpolarised Fresnel reflectance of a dielectric interface with relative index
/// eta = n_t / n_i, dimensionless (Cook & Torrance 1982 form; Cycles `fresnel_dielectric_cos`; pbrt-v2 `FrDiel`).
///
/// Total internal reflection (eta < 1 beyond the critical angle) gives 1. Total for all inputs: |cos| is clamped to
/// [0, 1] (NaN to 0, i.e. grazing), and eta that is not finite and positive gives 1.
pub fn fresnel_dielectric(cos_theta_i: f64, eta: f64) -> f64 {
    if !(eta > 0.0 && eta.is_finite()) {
        return 1.0;
    }
    let c = clamp_unit_or_zero(cos_theta_i.abs());
    let g2 = eta * eta - 1.0 + c * c;
    if g2 <= 0.0 {
        return 1.0;
    }
    let g = g2.sqrt();
    let a = (g - c) / (g + c);
    let b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
    (0.5 * a * a * (1.0 + b * b)).min(1.0)
}

/// `D(theta_h) = exp(-tan^2 theta_h / m^2) / (pi m^2 cos^4 theta_h)`: Beckmann distribution of microfacet normals,
/// sr^-1, normalised so that `int D cos theta_h d omega_h = 1` (docs/model.md, Oil layer). 0 for cos <= 0, m <= 0.
pub fn beckmann_d(cos_theta_h: f64, m: f64) -> f64 {
    let c2 = cos_theta_h * cos_theta_h;
    if !(cos_theta_h > 0.0 && m > 0.0) {
        return 0.0;
    }
    let tan2 = (1.0 - c2) / c2;
    (-tan2 / (m * m)).exp() / (PI * m * m * c2 * c2)
}

/// `G = min(1, 2 cos_h cos_o / (o.h), 2 cos_h cos_i / (o.h))`: Torrance-Sparrow V-cavity shadowing-masking,
/// dimensionless (docs/model.md, Oil layer; pbrt-v2 `Microfacet::G`). 0 for o.h <= 0.
pub fn v_cavity_g(cos_theta_h: f64, cos_theta_i: f64, cos_theta_o: f64, o_dot_h: f64) -> f64 {
    if o_dot_h.is_nan() || o_dot_h <= 0.0 {
        return 0.0;
    }
    let shadowing = 2.0 * cos_theta_h * cos_theta_i / o_dot_h;
    let masking = 2.0 * cos_theta_h * cos_theta_o / o_dot_h;
    shadowing.min(masking).clamp(0.0, 1.0)
}

/// `f_r(omega_i, omega_o) = rho_s D G F(o.h; 1.4) / (4 cos_i cos_o)`: DJ2006's surface BRDF, sr^-1, for unit
/// directions in the local frame, z = surface normal (docs/model.md, Oil layer). 0 unless both are above the surface.
pub fn torrance_sparrow_f_r(omega_i: [f64; 3], omega_o: [f64; 3], oiliness: f64) -> f64 {
    let (cos_i, cos_o) = (omega_i[2], omega_o[2]);
    if !(cos_i > 0.0 && cos_o > 0.0) {
        return 0.0;
    }
    let h = [omega_i[0] + omega_o[0], omega_i[1] + omega_o[1], cos_i + cos_o];
    let len = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
    let cos_h = h[2] / len;
    let o_dot_h = (omega_o[0] * h[0] + omega_o[1] * h[1] + cos_o * h[2]) / len;
    clamp_unit_or_zero(oiliness)
        * beckmann_d(cos_h, BECKMANN_ROUGHNESS_M)
        * v_cavity_g(cos_h, cos_i, cos_o, o_dot_h)
        * fresnel_dielectric(o_dot_h, SKIN_SURFACE_IOR)
        / (4.0 * cos_i * cos_o)
}

/// Gauss-Legendre rules of the albedo quadrature (theta_h, phi on [-1, 1]) and the hemispherical average (on [0, 1]).
struct Rules {
    theta: (Vec<f64>, Vec<f64>),
    phi: (Vec<f64>, Vec<f64>),
    mu: (Vec<f64>, Vec<f64>),
}

fn rules() -> &'static Rules {
    static RULES: OnceLock<Rules> = OnceLock::new();
    RULES.get_or_init(|| Rules {
        theta: gauss_legendre(ALBEDO_THETA_ORDER),
        phi: gauss_legendre(ALBEDO_PHI_ORDER),
        mu: composite_gauss_legendre(&HEMISPHERE_MU_BREAKS, HEMISPHERE_MU_ORDER),
    })
}

/// A microfacet reflection lobe `D G F / (4 cos_i cos_o)`: its D, its `G F`, and the values of i.h at which `G F`
/// has kinks in phi.
pub(crate) trait Lobe {
    /// `D(theta_h)`, sr^-1, normalised so that `int D cos_h d omega_h = 1`.
    fn d(&self, cos_h: f64) -> f64;
    /// `G F` at (cos_h, cos_i, cos_o, i.h).
    fn g_times_f(&self, cos_h: f64, cos_i: f64, cos_o: f64, i_dot_h: f64) -> f64;
    /// i.h where `G F` is not smooth, for the ring at cos_h (NaN for none).
    fn kinks(&self, cos_h: f64, cos_i: f64) -> [f64; 3];
}

/// DJ2006's lobe: V-cavity G times Fresnel at `eta` (`eta = None` for F = 1, the white furnace of the tests).
struct TorranceSparrowLobe {
    eta: Option<f64>,
}

impl Lobe for TorranceSparrowLobe {
    fn d(&self, cos_h: f64) -> f64 {
        beckmann_d(cos_h, BECKMANN_ROUGHNESS_M)
    }
    fn g_times_f(&self, cos_h: f64, cos_i: f64, cos_o: f64, i_dot_h: f64) -> f64 {
        v_cavity_g(cos_h, cos_i, cos_o, i_dot_h) * self.eta.map_or(1.0, |eta| fresnel_dielectric(i_dot_h, eta))
    }
    /// G's min switches where the shadowing term 2 cos_h cos_i / (i.h) = 1, where the masking term
    /// 2 cos_h cos_o / (i.h) = 1 (with cos_o = 2 (i.h) cos_h - cos_i), and where the two are equal (cos_o = cos_i).
    fn kinks(&self, cos_h: f64, cos_i: f64) -> [f64; 3] {
        let masking = 4.0 * cos_h * cos_h - 1.0;
        [2.0 * cos_h * cos_i, if masking > 0.0 { 2.0 * cos_h * cos_i / masking } else { f64::NAN }, cos_i / cos_h]
    }
}

/// Directional albedo `int f cos_o d omega_o` of a microfacet reflection lobe `D G F / (4 cos_i cos_o)`, computed in
/// half-vector form: with `cos_o d omega_o = 4 (i.h) cos_o d omega_h` it is
/// `int D(theta_h) sin theta_h dtheta_h int dphi G F (i.h) / cos_i`.
/// The mirror direction is above the horizon for every phi while `2 theta_h + theta_i <= pi/2`, for none once
/// `2 theta_h - theta_i >= pi/2`, and in between for `cos phi > cos_i (1 - 2 cos_h^2) / (2 cos_h sin_i sin_h)`.
/// theta_h is split there: the full-ring part by composite Gauss-Legendre, the partial part in
/// `theta_h = theta_0 + (theta_1 - theta_0)(1 - cos t) / 2` (which smooths the square-root ends of the phi range);
/// phi by Gauss-Legendre over its exact range (symmetric about phi = 0), split at the lobe's kinks.
pub(crate) fn microfacet_albedo(cos_theta_i: f64, panels: usize, lobe: &impl Lobe) -> f64 {
    let rules = rules();
    let (xt, wt) = (&rules.theta.0, &rules.theta.1);
    let (xp, wp) = (&rules.phi.0, &rules.phi.1);
    let cos_i = clamp_unit_or_zero(cos_theta_i).max(MIN_COS_THETA_I);
    let sin_i = (1.0 - cos_i * cos_i).sqrt();
    let theta_i = cos_i.acos();
    let theta_full = 0.5 * (FRAC_PI_2 - theta_i);
    let theta_none = 0.5 * (FRAC_PI_2 + theta_i);

    // D sin theta_h times the integral over phi of G F (i.h) / cos_i, at one theta_h.
    let ring = |theta_h: f64| -> f64 {
        let (sin_h, cos_h) = theta_h.sin_cos();
        let numerator = cos_i * (1.0 - 2.0 * cos_h * cos_h);
        let denominator = 2.0 * cos_h * sin_i * sin_h;
        let phi_max = if numerator <= -denominator {
            PI
        } else if numerator >= denominator {
            return 0.0;
        } else {
            (numerator / denominator).acos()
        };
        // Split [0, phi_max] where the lobe has kinks: i.h = K, i.e. cos phi = (K - cos_i cos_h) / (sin_i sin_h).
        let mut ends = [0.0, phi_max, phi_max, phi_max, phi_max];
        for (k, &i_dot_h) in lobe.kinks(cos_h, cos_i).iter().enumerate() {
            let c = (i_dot_h - cos_i * cos_h) / (sin_i * sin_h);
            if c.abs() < 1.0 {
                ends[k + 1] = c.acos().min(phi_max);
            }
        }
        ends.sort_by(f64::total_cmp);
        let mut integral = 0.0;
        for piece in ends.windows(2) {
            let half = 0.5 * (piece[1] - piece[0]);
            if half <= 0.0 {
                continue;
            }
            let sum: f64 = xp
                .iter()
                .zip(wp)
                .map(|(xj, wj)| {
                    let i_dot_h = sin_i * sin_h * (piece[0] + half * (xj + 1.0)).cos() + cos_i * cos_h;
                    let cos_o = 2.0 * i_dot_h * cos_h - cos_i;
                    if cos_o <= 0.0 || i_dot_h <= 0.0 {
                        return 0.0;
                    }
                    wj * lobe.g_times_f(cos_h, cos_i, cos_o, i_dot_h) * i_dot_h
                })
                .sum();
            integral += half * sum;
        }
        // Both symmetric halves of [-phi_max, phi_max].
        lobe.d(cos_h) * sin_h * 2.0 * integral / cos_i
    };

    let mut total = 0.0;
    // Full rings: theta_h in [0, theta_full].
    let width = theta_full / panels as f64;
    for p in 0..panels {
        let lo = width * p as f64;
        for (xi, wi) in xt.iter().zip(wt) {
            total += 0.5 * width * wi * ring(lo + 0.5 * width * (xi + 1.0));
        }
    }
    // Partial rings: theta_h in [theta_full, theta_none], in t with theta_h = theta_full + span (1 - cos t) / 2.
    let span = theta_none - theta_full;
    if span > 0.0 {
        let width = PI / panels as f64;
        for p in 0..panels {
            let lo = width * p as f64;
            for (xi, wi) in xt.iter().zip(wt) {
                let t = lo + 0.5 * width * (xi + 1.0);
                total += 0.5 * width * wi * ring(theta_full + 0.5 * span * (1.0 - t.cos())) * 0.5 * span * t.sin();
            }
        }
    }
    total
}

/// `rho_dr(theta_i) / rho_s` of DJ2006's Beckmann lobe with Fresnel at `eta` (None: F = 1).
fn torrance_sparrow_unit_albedo_with(cos_theta_i: f64, panels: usize, eta: Option<f64>) -> f64 {
    microfacet_albedo(cos_theta_i, panels, &TorranceSparrowLobe { eta })
}

/// `rho_dr(theta_i) / rho_s` with DJ2006's G and F.
fn torrance_sparrow_unit_albedo(cos_theta_i: f64, panels: usize) -> f64 {
    torrance_sparrow_unit_albedo_with(cos_theta_i, panels, Some(SKIN_SURFACE_IOR))
}

/// `rho_dr(theta_i) = int f_r cos theta_o d omega_o`: directional albedo of DJ2006's oily surface, dimensionless
/// (DJ2006 eq. 2; DAM `Wet::integrate_BRDF`; docs/model.md, Oil layer).
///
/// Quadrature over half-vectors h (cos_o d omega_o = 4 (i.h) cos_o d omega_h):
/// `rho_dr = rho_s int D sin theta_h dtheta_h int dphi G F (i.h) / cos_i`. theta_h is split where the ring of
/// half-vectors starts to mirror below the horizon (2 theta_h + theta_i = pi/2) and where it has gone
/// (2 theta_h - theta_i = pi/2); composite Gauss-Legendre, 64 panels x 8 nodes per part (the second in a cosine
/// substitution that smooths its square-root ends); in phi, 16 Gauss-Legendre nodes per piece over the exact range
/// where the mirror direction is above the horizon, split where the V-cavity G switches branch. Accuracy: 5e-7
/// relative at normal incidence (where a G kink falls across theta_h = 30 deg), ~2e-8 elsewhere (tests: a 4x finer
/// rule, and a direct integration over omega_o). About 1 ms a call; the Principled mapping
/// (`surface::principled`) uses the rho_s = 1 values, cached (rho_dr is linear in rho_s). Oiliness is clamped
/// to [0, 1] (NaN to 0); cos_theta_i to [1e-6, 1] (NaN and cos <= 0 to 1e-6: the grazing limit, 0.441 rho_s).
pub fn torrance_sparrow_directional_albedo(cos_theta_i: f64, oiliness: f64) -> f64 {
    clamp_unit_or_zero(oiliness) * torrance_sparrow_unit_albedo(cos_theta_i, ALBEDO_THETA_PANELS)
}

/// `2 int_0^1 f(mu) mu dmu`: cosine-weighted (diffuse-light) average of a directional albedo.
pub(crate) fn hemispherical_average(f: impl Fn(f64) -> f64) -> f64 {
    let (mu, w) = &rules().mu;
    mu.iter().zip(w).map(|(&m, &wm)| 2.0 * wm * m * f(m)).sum()
}

/// [`hemispherical_average`] with `f` evaluated at the nodes in parallel (for an `f` of milliseconds: a microfacet
/// albedo); the same sum in the same order.
pub(crate) fn hemispherical_average_par(f: impl Fn(f64) -> f64 + Sync) -> f64 {
    use rayon::prelude::*;
    let (mu, w) = &rules().mu;
    let values: Vec<f64> = mu.par_iter().map(|&m| f(m)).collect();
    mu.iter().zip(w).zip(values).map(|((&m, &wm), v)| 2.0 * wm * m * v).sum()
}

/// `rho_dr(0) / rho_s` and `rho_hemi / rho_s` of DJ2006's lobe, computed once (rho_dr is linear in rho_s).
pub(crate) fn torrance_sparrow_unit_albedos() -> (f64, f64) {
    static ALBEDOS: OnceLock<(f64, f64)> = OnceLock::new();
    *ALBEDOS.get_or_init(|| {
        (
            torrance_sparrow_unit_albedo(1.0, ALBEDO_THETA_PANELS),
            hemispherical_average(|mu| torrance_sparrow_unit_albedo(mu, ALBEDO_THETA_PANELS)),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::relative_error as rel;

    #[test]
    fn fresnel_limits() {
        let f0 = ((1.4f64 - 1.0) / (1.4 + 1.0)).powi(2);
        assert!((fresnel_dielectric(1.0, 1.4) - f0).abs() < 1e-15, "{}", fresnel_dielectric(1.0, 1.4));
        assert!((fresnel_dielectric(0.0, 1.4) - 1.0).abs() < 1e-15, "{}", fresnel_dielectric(0.0, 1.4));
        assert!(fresnel_dielectric(1e-4, 1.4) > 0.999, "{}", fresnel_dielectric(1e-4, 1.4));
        // Brewster-free textbook value: 45 deg on glass 1.5, Rs = 0.0920, Rp = 0.00847.
        let f45 = fresnel_dielectric(std::f64::consts::FRAC_1_SQRT_2, 1.5);
        assert!((f45 - 0.5 * (0.092_013 + 0.008_466)).abs() < 1e-5, "{f45}");
        // Monotonic in angle for eta > 1.
        let mut last = 0.0;
        for i in (0..=100).rev() {
            let f = fresnel_dielectric(i as f64 / 100.0, 1.4);
            assert!(f >= last, "not rising at cos {}", i as f64 / 100.0);
            last = f;
        }
        assert_eq!(fresnel_dielectric(0.5, 1.0), 0.0);
    }

    #[test]
    fn fresnel_total_internal_reflection() {
        let eta: f64 = 1.0 / 1.4;
        let cos_critical = (1.0 - eta * eta).sqrt();
        assert_eq!(fresnel_dielectric(cos_critical - 1e-6, eta), 1.0);
        assert_eq!(fresnel_dielectric(0.2, eta), 1.0);
        let inside = fresnel_dielectric(1.0, eta);
        assert!((inside - f0_from_ior(1.4)).abs() < 1e-15, "{inside}");
        assert!(fresnel_dielectric(cos_critical + 1e-3, eta) < 1.0, "{}", fresnel_dielectric(cos_critical + 1e-3, eta));
        for x in [f64::NAN, f64::INFINITY, -2.0] {
            let f = fresnel_dielectric(x, 1.4);
            assert!((0.0..=1.0).contains(&f), "x = {x}: {f}");
            assert_eq!(fresnel_dielectric(0.5, x), 1.0, "x = {x}");
        }
    }

    /// `int D cos_h d omega_h = 2 pi int_0^{pi/2} D cos sin dtheta = 1`, by Gauss-Legendre in theta (not the
    /// substitution the albedo quadrature relies on).
    #[test]
    fn beckmann_is_normalised() {
        let (x, w) = gauss_legendre(20);
        for m in [0.1, BECKMANN_ROUGHNESS_M, 0.6] {
            let panels = 200;
            let mut total = 0.0;
            for p in 0..panels {
                let half = 0.5 * std::f64::consts::FRAC_PI_2 / panels as f64;
                let lo = 2.0 * half * p as f64;
                for (xi, wi) in x.iter().zip(&w) {
                    let th: f64 = lo + half * (xi + 1.0);
                    total += half * wi * beckmann_d(th.cos(), m) * th.cos() * th.sin();
                }
            }
            total *= 2.0 * PI;
            assert!((total - 1.0).abs() < 1e-10, "m = {m}: {total}");
        }
    }

    /// Four times the theta_h panels changes rho_dr by < 1e-6 relative.
    #[test]
    fn albedo_quadrature_converged() {
        for mu in [1.0, 0.95, 0.7, 0.3, 0.05, 0.01] {
            let base = torrance_sparrow_unit_albedo(mu, ALBEDO_THETA_PANELS);
            let fine = torrance_sparrow_unit_albedo(mu, 4 * ALBEDO_THETA_PANELS);
            assert!(rel(base, fine) < 1e-6, "mu = {mu}: {base} vs {fine}");
        }
    }

    /// Independent check: rho_dr by direct integration of f_r cos_o over omega_o (theta_o, phi_o grid).
    #[test]
    fn albedo_matches_direct_integration() {
        let (x, w) = gauss_legendre(16);
        for mu in [1.0f64, 0.6, 0.25] {
            let sin_i = (1.0 - mu * mu).sqrt();
            let omega_i = [sin_i, 0.0, mu];
            let (nt, np) = (40, 40);
            let mut total = 0.0;
            for a in 0..nt {
                let ht = 0.5 * std::f64::consts::FRAC_PI_2 / nt as f64;
                for (xa, wa) in x.iter().zip(&w) {
                    let th = 2.0 * ht * a as f64 + ht * (xa + 1.0);
                    let (st, ct) = th.sin_cos();
                    for b in 0..np {
                        let hp = 0.5 * PI / np as f64;
                        for (xb, wb) in x.iter().zip(&w) {
                            let ph = 2.0 * hp * b as f64 + hp * (xb + 1.0);
                            let omega_o = [st * ph.cos(), st * ph.sin(), ct];
                            total += ht * wa * hp * wb * torrance_sparrow_f_r(omega_i, omega_o, 1.0) * ct * st;
                        }
                    }
                }
            }
            total *= 2.0; // phi in [0, pi], mirrored
            let quad = torrance_sparrow_directional_albedo(mu, 1.0);
            assert!(rel(quad, total) < 2e-6, "mu = {mu}: half-vector {quad} vs direct {total}");
        }
    }

    /// With F = 1 the lobe can at most return all light (V-cavity energy bound); with DJ2006's F, rho_dr <= rho_s.
    #[test]
    fn energy_bounds() {
        for i in 0..=50 {
            let mu = (i as f64 / 50.0).max(1e-3);
            let white = torrance_sparrow_unit_albedo_with(mu, ALBEDO_THETA_PANELS, None);
            assert!(white <= 1.0 + 1e-9 && white > 0.85, "mu = {mu}: white furnace {white}");
            let rho = torrance_sparrow_directional_albedo(mu, 1.0);
            assert!(rho > 0.0 && rho <= 1.0 * white, "mu = {mu}: {rho}");
        }
    }

    #[test]
    fn albedo_is_linear_in_oiliness() {
        for mu in [1.0, 0.5, 0.1] {
            let one = torrance_sparrow_directional_albedo(mu, 1.0);
            for rho_s in [0.0, 0.1, 0.3, 0.77] {
                let got = torrance_sparrow_directional_albedo(mu, rho_s);
                assert!((got - rho_s * one).abs() < 1e-15, "mu = {mu}, rho_s = {rho_s}");
            }
        }
    }

    /// At normal incidence the lobe sees F ~ F0 over its narrow range of i.h and G ~ 1, so rho_dr(0) ~ rho_s F0.
    #[test]
    fn normal_incidence_albedo_near_f0() {
        let f0 = f0_from_ior(SKIN_SURFACE_IOR);
        let rho = torrance_sparrow_directional_albedo(1.0, 1.0);
        assert!(rho > 0.5 * f0 && rho < 1.2 * f0, "rho_dr(0) = {rho}, F0 = {f0}");
        assert!((rho / f0 - 0.995).abs() < 0.01, "rho_dr(0) / F0 = {}", rho / f0);
    }
}
