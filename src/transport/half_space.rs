//! Chandrasekhar's H-function for isotropic scattering and the albedos of an index-matched, isotropically
//! scattering half-space (Chandrasekhar, "Radiative Transfer", 1950, ch. V): general radiative transfer, used by
//! `fit::random_walk` to predict what a Cycles random walk renders on a flat slab.

use std::sync::OnceLock;

use crate::numeric::{clamp_nan_to_low, composite_gauss_legendre};

/// Panel ends of the composite Gauss-Legendre rule on mu in [0, 1] for H, graded towards 0 where H has a mu ln mu term.
const H_PANEL_BREAKS: [f64; 15] = [0.0, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 5e-3, 0.02, 0.06, 0.13, 0.25, 0.4, 0.6, 0.8, 1.0];
/// Gauss-Legendre order per panel of that rule (14 panels x 12 = 168 nodes; H to ~1e-12, see the tests).
const H_PANEL_ORDER: usize = 12;
/// Iteration stops when no node's H changes by more than this (absolute).
const H_TOLERANCE: f64 = 1e-13;
/// Iteration cap; with the geometric-mean update the iteration takes about 40 sweeps for any a in (0, 1].
const H_MAX_ITERATIONS: usize = 10_000;

/// Gauss-Legendre nodes and weights on [0, 1] for the H-function, built once.
fn h_quadrature() -> &'static (Vec<f64>, Vec<f64>) {
    static RULE: OnceLock<(Vec<f64>, Vec<f64>)> = OnceLock::new();
    RULE.get_or_init(|| composite_gauss_legendre(&H_PANEL_BREAKS, H_PANEL_ORDER))
}

/// `1/H(mu) = sqrt(1 - a) + (a/2) sum_j w_j mu_j H_j / (mu + mu_j)`: the right side of the H equation on the nodes.
fn h_from_nodes(mu: f64, albedo: f64, nodes: &[f64], weights: &[f64], h: &[f64]) -> f64 {
    let sum: f64 = nodes.iter().zip(weights).zip(h).map(|((&mj, &wj), &hj)| wj * mj * hj / (mu + mj)).sum();
    1.0 / ((1.0 - albedo).sqrt() + 0.5 * albedo * sum)
}

/// H on the quadrature nodes for single-scattering albedo `albedo` in [0, 1], by iterating the sqrt(1 - a) form.
fn h_on_nodes(albedo: f64) -> Vec<f64> {
    let (nodes, weights) = h_quadrature();
    let mut h = vec![1.0; nodes.len()];
    let mut next = vec![0.0; nodes.len()];
    for _ in 0..H_MAX_ITERATIONS {
        let mut change: f64 = 0.0;
        for (i, &mu) in nodes.iter().enumerate() {
            // Geometric mean of H and its update: plain iteration maps c H to H / c, which oscillates at a = 1.
            next[i] = (h[i] * h_from_nodes(mu, albedo, nodes, weights, &h)).sqrt();
            change = change.max((next[i] - h[i]).abs());
        }
        std::mem::swap(&mut h, &mut next);
        if change < H_TOLERANCE {
            break;
        }
    }
    h
}

/// `H(mu; a)`: Chandrasekhar's H-function for isotropic scattering with single-scattering albedo a, dimensionless
/// (Chandrasekhar 1950, ch. V).
///
/// Solves `1/H(mu) = sqrt(1 - a) + (a/2) int_0^1 mu' H(mu') / (mu + mu') dmu'` (the form that converges fast up to
/// a = 1) by fixed-point iteration, with a geometric-mean update, on 168 Gauss-Legendre nodes in panels graded
/// towards mu = 0, then evaluates it at `mu` by the same equation (Nystrom interpolation). Accuracy: 1e-12 relative
/// or better against Chandrasekhar's integral representation for mu in [0, 1], a in [0.2, 1], and the moment
/// identity `int H = 2 (1 - sqrt(1 - a)) / a` to 1e-10 (tests); H(1; 1) = 2.9078105291. About 40 sweeps of
/// 168^2 terms (~1 ms); [`h_normal_incidence`] is a faster route for mu = 1. Inputs are clamped: mu to [0, 1],
/// a to [0, 1]; NaN counts as 0 (H(mu; 0) = 1, H(0; a) = 1).
pub fn chandrasekhar_h(mu: f64, albedo: f64) -> f64 {
    let mu = clamp_nan_to_low(mu, 0.0, 1.0);
    let albedo = clamp_nan_to_low(albedo, 0.0, 1.0);
    if albedo == 0.0 {
        return 1.0;
    }
    let (nodes, weights) = h_quadrature();
    let h = h_on_nodes(albedo);
    h_from_nodes(mu, albedo, nodes, weights, &h)
}

/// Panel ends in theta of the rule for [`h_normal_incidence`], graded towards 0, where the integrand's log peaks
/// (width sqrt(3 (1 - a)), 1.7e-3 at a = 0.999999; a log singularity at a = 1).
#[rustfmt::skip]
const H1_PANEL_BREAKS: [f64; 16] = [
    0.0, 1e-9, 1e-7, 1e-6, 6.25e-6, 2.5e-5, 1e-4, 4e-4, 1.6e-3, 6.4e-3, 0.0256, 0.1024, 0.4, 0.8, 1.2,
    std::f64::consts::FRAC_PI_2,
];
/// Gauss-Legendre order per panel of that rule (15 x 12 = 180 nodes).
const H1_PANEL_ORDER: usize = 12;
/// Below this theta, 1 - theta cot theta is taken from its series (the direct form cancels).
const THETA_COT_SERIES_BELOW: f64 = 1e-2;

/// `1 - theta cot theta`, accurate for small theta (series theta^2/3 + theta^4/45 + 2 theta^6/945 below 1e-2).
fn one_minus_theta_cot(theta: f64) -> f64 {
    if theta < THETA_COT_SERIES_BELOW {
        let t2 = theta * theta;
        t2 / 3.0 + t2 * t2 / 45.0 + 2.0 * t2 * t2 * t2 / 945.0
    } else {
        1.0 - theta / theta.tan()
    }
}

/// `H(1; a)` from Chandrasekhar's integral representation at mu = 1, dimensionless:
/// `ln H(1) = -(1/pi) int_0^{pi/2} ln(1 - a theta cot theta) dtheta` (Chandrasekhar 1950, ch. V, with the
/// characteristic function a/2 and t = tan theta; evaluated this way by Kawabata & Limaye, Astrophys. Space Sci.
/// 332, 365, 2011). A single quadrature of 180 nodes instead of the iteration of
/// [`chandrasekhar_h`] (about 1000 times faster); the two agree to 1e-10 (tests). [`h_normal_incidence`] reads a
/// table of it.
fn h_normal_incidence_quadrature(albedo: f64) -> f64 {
    let albedo = clamp_nan_to_low(albedo, 0.0, 1.0);
    // The rule's weights and 1 - theta cot theta at its nodes, computed once (the tangents cost half the time).
    static RULE: OnceLock<Vec<(f64, f64)>> = OnceLock::new();
    let rule = RULE.get_or_init(|| {
        let (nodes, weights) = composite_gauss_legendre(&H1_PANEL_BREAKS, H1_PANEL_ORDER);
        nodes.iter().zip(weights).map(|(&theta, w)| (w, one_minus_theta_cot(theta))).collect()
    });
    let integral: f64 = rule.iter().map(|&(w, c)| w * ((1.0 - albedo) + albedo * c).ln()).sum();
    (-integral / std::f64::consts::PI).exp()
}

/// Nodes of the table of `H(1; a)`, uniform in `s = sqrt(1 - a)` on [0, 1].
const H1_TABLE_NODES: usize = 1025;
/// Points of the Lagrange interpolation in that table (the end intervals use the nearest ones).
const H1_TABLE_POINTS: usize = 6;

/// `H(1; a)`, dimensionless: [`h_normal_incidence_quadrature`] tabulated once per process on 1025 nodes uniform in
/// `sqrt(1 - a)` (in which H is smooth up to a = 1) and read by 6-point Lagrange interpolation: within 1e-12 of the
/// quadrature (2e-11 for a above 1 - 1e-6, where the quadrature itself errs by 1e-11; tests), some 30 times faster (a flat-slab fit evaluates it a few dozen times per channel). `a` is
/// clamped to [0, 1], NaN counts as 0.
pub fn h_normal_incidence(albedo: f64) -> f64 {
    static TABLE: OnceLock<Vec<f64>> = OnceLock::new();
    let table = TABLE.get_or_init(|| {
        (0..H1_TABLE_NODES)
            .map(|i| {
                let s = i as f64 / (H1_TABLE_NODES - 1) as f64;
                h_normal_incidence_quadrature(1.0 - s * s)
            })
            .collect()
    });
    let albedo = clamp_nan_to_low(albedo, 0.0, 1.0);
    let x = (1.0 - albedo).sqrt() * (H1_TABLE_NODES - 1) as f64;
    let first = ((x.floor() as usize).saturating_sub(H1_TABLE_POINTS / 2 - 1)).min(H1_TABLE_NODES - H1_TABLE_POINTS);
    (first..first + H1_TABLE_POINTS)
        .map(|i| {
            let basis: f64 = (first..first + H1_TABLE_POINTS)
                .filter(|&j| j != i)
                .map(|j| (x - j as f64) / (i as f64 - j as f64))
                .product();
            basis * table[i]
        })
        .sum()
}

/// `R(mu0; a) = 1 - H(mu0; a) sqrt(1 - a)`: directional albedo of an index-matched, isotropically scattering
/// half-space lit from direction cosine mu0, dimensionless (Chandrasekhar 1950, ch. V).
pub fn half_space_directional_albedo(mu0: f64, albedo: f64) -> f64 {
    let albedo = clamp_nan_to_low(albedo, 0.0, 1.0);
    1.0 - chandrasekhar_h(mu0, albedo) * (1.0 - albedo).sqrt()
}

/// `R_hemi(a) = 2 int_0^1 R(mu; a) mu dmu`: the half-space's albedo under uniform (diffuse) light, dimensionless.
pub fn half_space_hemispherical_albedo(albedo: f64) -> f64 {
    let albedo = clamp_nan_to_low(albedo, 0.0, 1.0);
    if albedo == 0.0 {
        return 0.0;
    }
    let (nodes, weights) = h_quadrature();
    let h = h_on_nodes(albedo);
    let first_moment: f64 = nodes.iter().zip(weights).zip(&h).map(|((&mu, &w), &hj)| w * mu * hj).sum();
    1.0 - 2.0 * first_moment * (1.0 - albedo).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::gauss_legendre;
    use crate::numeric::relative_error as rel;

    /// `H(mu; a)` from Chandrasekhar's integral representation (1950, ch. V; Kawabata & Limaye 2011):
    /// `ln H(mu) = -(mu/pi) int_0^{pi/2} ln(1 - a theta cot theta) / (cos^2 theta + mu^2 sin^2 theta) dtheta`,
    /// by composite Gauss-Legendre with panels graded towards theta = 0 (log singularity at a = 1).
    fn h_integral_formula(mu: f64, albedo: f64) -> f64 {
        let (x, w) = gauss_legendre(20);
        let half_pi = std::f64::consts::FRAC_PI_2;
        // Panels graded geometrically towards theta = 0 (log peak) and towards pi/2 (peak of width mu).
        let mut breaks = vec![0.0];
        let mut t = 1e-12;
        while t < 0.1 {
            breaks.push(t);
            t *= 4.0;
        }
        for k in 0..40 {
            breaks.push(0.1 + (half_pi - 0.2) * k as f64 / 40.0);
        }
        let mut t = 0.1;
        while t > 1e-9 {
            breaks.push(half_pi - t);
            t /= 4.0;
        }
        breaks.push(half_pi);
        let mut integral = 0.0;
        for p in breaks.windows(2) {
            let half = 0.5 * (p[1] - p[0]);
            for (xi, wi) in x.iter().zip(&w) {
                let th: f64 = p[0] + half * (xi + 1.0);
                let (s, c) = th.sin_cos();
                let t = (1.0 - albedo) + albedo * one_minus_theta_cot(th);
                integral += half * wi * t.ln() / (c * c + mu * mu * s * s);
            }
        }
        (-mu / std::f64::consts::PI * integral).exp()
    }

    /// Chandrasekhar's (1950) table for a conservative (a = 1) isotropic atmosphere: H(1) = 2.90781,
    /// H(0.5) = 2.01278; and H(0) = 1 for every a.
    #[test]
    fn h_function_conservative_value() {
        let h1 = chandrasekhar_h(1.0, 1.0);
        assert!((h1 - 2.90781).abs() < 1e-5, "H(1; 1) = {h1}");
        let h_half = chandrasekhar_h(0.5, 1.0);
        assert!((h_half - 2.01278).abs() < 1e-5, "H(0.5; 1) = {h_half}");
        assert!((chandrasekhar_h(0.0, 0.9) - 1.0).abs() < 1e-12, "{}", chandrasekhar_h(0.0, 0.9));
        assert_eq!(chandrasekhar_h(0.5, 0.0), 1.0);
    }

    /// Independent check: Chandrasekhar's integral representation of H, at several albedos and angles.
    #[test]
    fn h_function_matches_integral_formula() {
        for a in [0.2, 0.5, 0.9, 0.99, 0.999999, 1.0] {
            for mu in [0.0, 1e-4, 0.01, 0.1, 0.3, 0.5, 0.8, 1.0] {
                let h = chandrasekhar_h(mu, a);
                let reference = h_integral_formula(mu, a);
                assert!(rel(h, reference) < 1e-12, "H({mu}; {a}) = {h}, integral formula {reference}");
            }
        }
    }

    /// The fast normal-incidence quadrature used by the flat-slab model agrees with the iterated H, for
    /// a = 1 - 10^(-k/4), k = 1..24 (0.44 .. 0.999999), and a = 0.05, 1.
    #[test]
    fn h_normal_incidence_matches_iteration() {
        for a in (1..=24).map(|k| 1.0 - 10f64.powf(-k as f64 / 4.0)).chain([0.05, 1.0]) {
            let fast = h_normal_incidence(a);
            let iterated = chandrasekhar_h(1.0, a);
            assert!(rel(fast, iterated) < 1e-10, "a = {a}: {fast} vs {iterated}");
        }
    }

    /// The table of H(1; a) against the quadrature it holds, between and on its nodes, up to a = 1: within 1e-12 (measured 4e-13),
    /// but within 2e-11 in the first interval (s = sqrt(1 - a) < 1e-3), where the quadrature's own error (about 1e-11
    /// against the iteration, from its integrand's log singularity at a = 1) is not smooth in s.
    #[test]
    fn h_normal_incidence_table_matches_quadrature() {
        let (mut near_one, mut elsewhere): (f64, f64) = (0.0, 0.0);
        for k in 0..=20_000 {
            let s = (k as f64 / 20_000.0).powi(2);
            let a = 1.0 - s * s;
            let e = rel(h_normal_incidence(a), h_normal_incidence_quadrature(a));
            if s < 1e-3 {
                near_one = near_one.max(e);
            } else {
                elsewhere = elsewhere.max(e);
            }
        }
        assert!(near_one < 2e-11 && elsewhere < 1e-12, "{near_one} {elsewhere}");
        assert_eq!(h_normal_incidence(f64::NAN), h_normal_incidence(0.0));
        assert!((h_normal_incidence(0.0) - 1.0).abs() < 1e-15);
    }

    /// Zeroth moment identity `int_0^1 H dmu = 2 (1 - sqrt(1 - a)) / a` (Chandrasekhar 1950, ch. V).
    #[test]
    fn h_function_zeroth_moment() {
        let (nodes, weights) = h_quadrature();
        for a in [0.1, 0.5, 0.9, 0.999999, 1.0] {
            let h = h_on_nodes(a);
            let m0: f64 = weights.iter().zip(&h).map(|(w, h)| w * h).sum();
            let want = 2.0 * (1.0 - (1.0 - a).sqrt()) / a;
            assert!(rel(m0, want) < 1e-10, "a = {a}: {m0} vs {want}");
            assert_eq!(nodes.len(), h.len(), "a = {a}");
        }
    }
}
