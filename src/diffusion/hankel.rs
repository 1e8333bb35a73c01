//! Radial profiles from Hankel-domain reflectance: R(r) = (1/2 pi) int_0^inf R~(s) J0(s r) s ds (model.md 6.2).
//!
//! The transform of the top layer alone, R~1+, decays only like e^(-l s) and its real-space form is known, so the
//! profile is split (model.md 6.2, recommendation 3):  R(r) = R1+(r) [image sum]  +  H^-1[R~ - R~1+](r).
//! The remainder is smooth and decays fast; it is integrated with Gauss-Legendre panels on one s-grid shared by all
//! radii and wavelengths. Panels are no wider than half a period of J0 at the largest radius, and no wider than a fixed
//! fraction of s near s = 0 where R~ varies on the scale sigma_tr. The grid ends where |R~ - R~1+| s^2 has fallen below
//! a tolerance relative to the total reflectance, per wavelength.

use std::f64::consts::PI;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::layered::{Combination, LayerStack};
use super::multipole::MultipoleTerms;
use crate::numeric::{clamp_zero, gauss_legendre};

/// Accuracy of the inverse Hankel quadrature.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HankelQuadrature {
    /// Gauss-Legendre nodes per panel.
    pub gauss_order: usize,
    /// Panel-width divisor: 1 is the default grid, 2 halves every panel.
    pub refinement: f64,
    /// The s-grid ends where |R~ - R~1+| s^2 < `cutoff` * R~(0).
    pub cutoff: f64,
}

impl Default for HankelQuadrature {
    /// The cheapest setting on the error-time front whose error is negligible (docs/accuracy-vs-time.md): 12 nodes on
    /// panels 4x the base width (up to two J0 periods at the largest radius), cut at 1e-9, stay within 1e-8 of the
    /// converged quadrature over 0.01-10 mm, 2-3x faster than 8 nodes on the base grid cut at 1e-13.
    fn default() -> Self {
        HankelQuadrature { gauss_order: 12, refinement: 0.25, cutoff: 1e-9 }
    }
}

/// Widest panel relative to its start frequency, near s = 0 (before refinement).
const RELATIVE_PANEL_WIDTH: f64 = 0.5;
/// Most panels limited by the J0 oscillation at the largest radius (628 mm^-1 at 20 mm). Skin needs a few hundred:
/// its remainder is below 1e-9 of the total there. Thin, nearly transparent layers can push the cut to 1e5 mm^-1 and
/// beyond; past this bound panels grow with s, which keeps the cost finite and leaves an aliasing error in the far
/// tail of the order of the remainder's size at the bound.
const MAX_OSCILLATION_PANELS: f64 = 4000.0;
/// Smallest structural frequency scale considered, mm^-1.
const MIN_STRUCTURE_PER_MM: f64 = 1e-4;
/// Log-spaced probe frequencies used to find where the remainder becomes negligible, mm^-1.
const PROBE_DECADES: (f64, f64) = (-3.0, 6.0);
const PROBES_PER_DECADE: f64 = 10.0;

/// Reflectance profiles R(r) in mm^-2 of several stacks (typically one per wavelength) at the same radii (mm).
/// Values below zero from quadrature noise far in the tail are clamped to zero.
pub fn reflectance_profiles(
    stacks: &[LayerStack],
    radii_mm: &[f64],
    combination: Combination,
    terms: MultipoleTerms,
    quadrature: &HankelQuadrature,
) -> Vec<Vec<f64>> {
    let remainder = |stack: &LayerStack, s: f64| stack.below_top_hat(s, combination, terms);
    // Where each stack's remainder stops mattering, and the structural scale near s = 0.
    let cuts: Vec<f64> = stacks
        .par_iter()
        .map(|stack| {
            let scale = stack.reflectance_hat(0.0, combination, terms).abs().max(f64::MIN_POSITIVE);
            cutoff_frequency(|s| remainder(stack, s), quadrature.cutoff * scale)
        })
        .collect();
    let s_cut = cuts.iter().cloned().fold(0.0, f64::max);
    let structure = stacks.iter().map(structure_frequency).fold(f64::INFINITY, f64::min);
    let r_max = radii_mm.iter().cloned().fold(0.0, f64::max);
    let oscillation_budget = MAX_OSCILLATION_PANELS * PI / r_max.max(f64::MIN_POSITIVE);
    let s_oscillation = oscillation_budget.min(s_cut);
    let (nodes, weights) = panel_grid(s_cut, s_oscillation, structure, r_max, quadrature);

    // Remainder at the nodes, per stack, zero beyond the stack's own cut.
    let samples: Vec<Vec<f64>> = stacks
        .par_iter()
        .zip(&cuts)
        .map(|(stack, &cut)| {
            let count = nodes.partition_point(|&s| s <= cut);
            let mut v: Vec<f64> = nodes[..count].iter().zip(&weights).map(|(&s, &w)| w * s * remainder(stack, s)).collect();
            v.resize(nodes.len(), 0.0);
            v
        })
        .collect();

    // For each radius: the top layer's image sum plus the quadrature of the remainder against J0.
    let per_radius: Vec<Vec<f64>> = radii_mm
        .par_iter()
        .map(|&r| {
            let j0: Vec<f64> = nodes.iter().map(|&s| libm::j0(s * r)).collect();
            stacks
                .iter()
                .zip(&samples)
                .map(|(stack, v)| {
                    let tail: f64 = v.iter().zip(&j0).map(|(a, b)| a * b).sum::<f64>() / (2.0 * PI);
                    clamp_zero(stack.top().reflectance(r, terms) + tail)
                })
                .collect()
        })
        .collect();
    // Transpose to per stack.
    (0..stacks.len()).map(|k| per_radius.iter().map(|row| row[k]).collect()).collect()
}

/// The smallest frequency scale on which a stack's transform varies near s = 0: its smallest sigma_tr or 1/(2L).
fn structure_frequency(stack: &LayerStack) -> f64 {
    stack
        .slabs()
        .iter()
        .flat_map(|slab| {
            let period = 2.0 * (slab.thickness_mm + slab.zb_top_mm + slab.zb_bottom_mm);
            [slab.sigma_tr_per_mm, 1.0 / period]
        })
        .fold(f64::INFINITY, f64::min)
        .max(MIN_STRUCTURE_PER_MM)
}

/// The frequency beyond which |f(s)| s^2 stays below `tolerance` on the probe grid (0 if it never exceeds it).
fn cutoff_frequency(f: impl Fn(f64) -> f64, tolerance: f64) -> f64 {
    let n = ((PROBE_DECADES.1 - PROBE_DECADES.0) * PROBES_PER_DECADE) as usize;
    let probe = |j: usize| 10f64.powf(PROBE_DECADES.0 + j as f64 / PROBES_PER_DECADE);
    (0..=n)
        .rev()
        .find(|&j| {
            let s = probe(j);
            let weight = f(s).abs() * s * s;
            weight > tolerance || weight.is_nan() // NaN counts as significant
        })
        .map(|j| probe((j + 1).min(n)))
        .unwrap_or(0.0)
}

/// Gauss-Legendre nodes and weights on panels covering [0, s_cut]; below `s_oscillation` no panel is wider than half
/// a period of J0 at `r_max`.
fn panel_grid(s_cut: f64, s_oscillation: f64, structure: f64, r_max: f64, q: &HankelQuadrature) -> (Vec<f64>, Vec<f64>) {
    let (x, w) = gauss_legendre(q.gauss_order.max(1));
    let refine = q.refinement.max(1e-3);
    let oscillation_limit = if r_max > 0.0 { PI / r_max / refine } else { f64::INFINITY };
    let (mut nodes, mut weights) = (Vec::new(), Vec::new());
    let mut a = 0.0;
    while a < s_cut {
        let relative = RELATIVE_PANEL_WIDTH * a.max(structure) / refine;
        let width = if a < s_oscillation { oscillation_limit.min(relative) } else { relative };
        let half = 0.5 * width;
        for (xi, wi) in x.iter().zip(&w) {
            nodes.push(a + half * (xi + 1.0));
            weights.push(half * wi);
        }
        a += width;
    }
    (nodes, weights)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diffusion::Layer;

    #[test]
    fn cutoff_finds_decay() {
        let c = cutoff_frequency(|s| (-s).exp(), 1e-13);
        assert!(c > 30.0 && c < 45.0, "{c}");
        assert_eq!(cutoff_frequency(|_| 0.0, 1e-13), 0.0);
    }

    /// A single layer's profile is its image sum; through the quadrature path with a fake split it must be recovered.
    #[test]
    fn inverse_of_single_slab_transform_is_its_image_sum() {
        // Invert R~1+ numerically (no split) and compare with the real-space image sum over 0.001..20 mm.
        let stack =
            LayerStack::new(&[Layer { thickness_mm: 0.25, sigma_a_per_mm: 0.26, sigma_s_reduced_per_mm: 6.08, ior: 1.4 }])
                .unwrap();
        let slab = *stack.top();
        let t = MultipoleTerms::All;
        let f = |s: f64| slab.reflectance_hat(s, t);
        let radii: Vec<f64> = (0..=40).map(|i| 1e-3 * 10f64.powf(i as f64 * 0.1)).filter(|r| *r <= 20.0).collect();
        let r_max = radii.iter().cloned().fold(0.0, f64::max);
        let cut = cutoff_frequency(f, 1e-16);
        // The unsplit transform decays only like e^(-l s), a harder integrand than the remainder production inverts:
        // checked on the base panel grid (refinement 1), where it holds to 1e-10 of the peak.
        let base = HankelQuadrature { refinement: 1.0, ..HankelQuadrature::default() };
        let (nodes, weights) = panel_grid(cut, cut, structure_frequency(&stack), r_max, &base);
        let peak = slab.reflectance(0.0, t);
        for &r in &radii {
            let numeric: f64 =
                nodes.iter().zip(&weights).map(|(&s, &w)| w * s * f(s) * libm::j0(s * r)).sum::<f64>() / (2.0 * PI);
            let exact = slab.reflectance(r, t);
            let err = (numeric - exact).abs();
            assert!(err < 1e-4 * exact + 1e-10 * peak, "r={r}: numeric {numeric} exact {exact}");
        }
    }
}
