//! Radial profiles from Hankel-domain reflectance: R(r) = (1/2 pi) int_0^inf R~(s) J0(s r) s ds (docs/model.md, Radial profiles).
//!
//! The transform of the top layer alone, R~1+, decays only like e^(-l s) and its real-space form is known, so the
//! profile is split (docs/model.md, Radial profiles):  R(r) = R1+(r) [image sum]  +  H^-1[R~ - R~1+](r).
//! The remainder is smooth and decays fast. It is sampled once per stack at Gauss-Legendre nodes on panels that grow
//! geometrically in s (each panel a fixed fraction wider than where it starts, from a first panel [0, 1e-6 mm^-1]) up
//! to where |R~ - R~1+| s^2 has fallen below a tolerance relative to the total reflectance. The panels depend on
//! neither the radii nor the other stacks, so a profile value depends only on its own stack and radius.
//!
//! Each radius then weighs the same samples with its own kernel. On a panel over which J0(s r) turns through less
//! than half a period, the kernel is Gauss-Legendre times J0. On a panel where it oscillates faster, J0 is written as
//! Re[H0(s r)], H0 = J0 + i Y0, and H0(s r) e^(-i s r) is smooth there (its modulus and phase vary slowly once s r is
//! past pi): a Filon rule integrates the polynomial through the samples of that smooth part against e^(i s r) exactly,
//! using the plane-wave expansion e^(i w x) = sum_n (2n+1) i^n j_n(w) P_n(x) truncated at the panel's order. The cost
//! per radius is thus the same for 1 mm and 10^4 mm, and no radius limits the grid of another.

use std::f64::consts::PI;
use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::layered::{Boundaries, Combination, LayerStack};
use super::multipole::MultipoleTerms;
use crate::error::SkinError;
use crate::numeric::{clamp_zero, gauss_legendre, legendre_table, spherical_bessel_j};

/// Accuracy of the inverse Hankel quadrature.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HankelQuadrature {
    /// Gauss-Legendre nodes per panel.
    pub gauss_order: usize,
    /// Panel-width divisor: 1 is the base grid, 2 halves every panel.
    pub refinement: f64,
    /// The s-grid ends where |R~ - R~1+| s^2 < `cutoff` * R~(0).
    pub cutoff: f64,
}

impl Default for HankelQuadrature {
    /// The cheapest setting on the error-time front whose error is negligible (docs/accuracy-vs-time.md): 12 nodes on
    /// panels half as wide as they start (refinement 1), cut at 1e-9.
    fn default() -> Self {
        HankelQuadrature { gauss_order: 12, refinement: 1.0, cutoff: 1e-9 }
    }
}

/// Width of a panel relative to where it starts, before refinement.
const RELATIVE_PANEL_WIDTH: f64 = 0.5;
/// The first panel is [0, FIRST_PANEL_PER_MM]; the geometric panels start there. J0(s r) turns through less than
/// half a period on it for every radius up to `MAX_RADIUS_MM`.
const FIRST_PANEL_PER_MM: f64 = 1e-6;
/// Largest radius a profile accepts, mm (1 km: far past any tail that is not zero to double precision).
pub const MAX_RADIUS_MM: f64 = 1e6;
/// Probe frequencies for the cut-off, log-spaced, mm^-1: up to 1e9 (a layer of 1e5 mm^-1 decays by e^-20 at 2e6).
const PROBE_DECADES: (f64, f64) = (-3.0, 9.0);
const PROBES_PER_DECADE: f64 = 10.0;
/// A panel is integrated by Gauss-Legendre times J0 while its half-width times r is at most this (half a period).
const GAUSS_MAX_HALF_PHASE: f64 = PI / 2.0;

/// Raw profile values above this fraction of the profile's largest magnitude below zero are round-off of the
/// quadrature: with capped boundaries, where every exact profile is >= 0, the worst of the property tests and sweeps
/// is -1.3e-9 of it (docs/robustness.md). Below, the value is the model's own negative lobe.
pub const ROUND_OFF_OF_PEAK: f64 = 1e-8;

/// The deepest negative value a profile had before the clamp to zero, beyond round-off ([`ROUND_OFF_OF_PEAK`]): the
/// paper's boundaries on a slab whose top extrapolation distance exceeds its thickness plus the bottom one, where
/// the layers below do not fill the lobe (`Slab::capped`, docs/robustness.md). Reported, never hidden.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct NegativeLobe {
    /// Which profile of the call (the stack's index; in `evaluate`, the wavelength's).
    pub profile: usize,
    /// The boundaries of that profile's stack: what the lobe comes from differs (see [`NegativeLobe::message`]).
    pub boundaries: Boundaries,
    /// Where the most negative value is, mm.
    pub radius_mm: f64,
    /// The most negative value over the profile's largest magnitude at the radii asked for (-1 when all are negative).
    pub relative_to_peak: f64,
}

impl NegativeLobe {
    /// What a front tells its user about a lobe at `place` (e.g. "at 0.1 mm") under `boundaries`, the one text for
    /// every front: with the paper's boundaries it is the model's (a layer thinner than its extrapolation distances),
    /// with the capped ones, whose exact profiles are non-negative, the numerical inverse transform's.
    pub fn message(place: &str, relative_to_peak: f64, boundaries: Boundaries) -> String {
        let cause = match boundaries {
            Boundaries::Paper => {
                "the paper's boundaries on a layer thinner than its extrapolation distances (docs/robustness.md, \
                 \"Negative profile lobes\"); with boundaries \"capped\" every exact profile is non-negative"
            }
            Boundaries::Capped => {
                "with the capped boundaries every exact profile is non-negative, so this is the error of the numerical \
                 inverse transform (docs/robustness.md, \"Negative profile lobes\"); accuracy \"reference\" reduces it"
            }
        };
        format!("the radial profile had a negative lobe {place}, {relative_to_peak:.2e} of its peak, set to 0: {cause}")
    }
}

impl std::fmt::Display for NegativeLobe {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let place = format!("at {} mm (profile {})", self.radius_mm, self.profile);
        f.write_str(&NegativeLobe::message(&place, self.relative_to_peak, self.boundaries))
    }
}

/// The radius, mm, at which each profile's scale is read for the round-off threshold ([`ROUND_OFF_OF_PEAK`]): near
/// the centre, where a diffusion profile peaks. The radii a caller asks for may all lie in the far tail (20 to 100 mm),
/// where the values themselves are round-off (1e-20 where the profile is about 1e-76): measured against their own
/// largest magnitude they would read as a lobe of -1 of the peak.
pub const PEAK_PROBE_MM: f64 = 1e-3;

/// Profiles clamped to zero, and the deepest negative lobe the clamp removed (`None`: only round-off was removed).
#[derive(Debug, Clone, PartialEq)]
pub struct ClampedProfiles {
    pub per_mm2: Vec<Vec<f64>>,
    pub negative_lobe: Option<NegativeLobe>,
}

impl ClampedProfiles {
    /// Clamp raw profiles (one per stack, at `radii_mm`) to zero and find the deepest lobe beyond round-off of the
    /// profile's peak: the largest magnitude over `radii_mm` and its value at [`PEAK_PROBE_MM`], `centre` (one per
    /// profile; empty: the radii alone). `stacks` are the profiles' stacks, whose boundaries the lobe names (a
    /// profile without its stack counts as the paper's).
    pub fn from_raw(raw: Vec<Vec<f64>>, radii_mm: &[f64], stacks: &[LayerStack], centre: &[f64]) -> ClampedProfiles {
        let mut negative_lobe: Option<NegativeLobe> = None;
        for (profile, values) in raw.iter().enumerate() {
            let at_centre = centre.get(profile).map_or(0.0, |v| v.abs());
            let peak = values.iter().fold(at_centre, |m, v| m.max(v.abs()));
            let Some((i, &min)) = values.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1)) else { continue };
            let relative_to_peak = min / peak;
            if min < 0.0
                && relative_to_peak < -ROUND_OFF_OF_PEAK
                && negative_lobe.map_or(true, |l| relative_to_peak < l.relative_to_peak)
            {
                let boundaries = stacks.get(profile).map_or(Boundaries::Paper, LayerStack::boundaries);
                negative_lobe = Some(NegativeLobe { profile, boundaries, radius_mm: radii_mm[i], relative_to_peak });
            }
        }
        let per_mm2 = raw.into_iter().map(|p| p.into_iter().map(clamp_zero).collect()).collect();
        ClampedProfiles { per_mm2, negative_lobe }
    }
}

/// Reflectance profiles R(r) in mm^-2 of several stacks (typically one per wavelength) at the same radii (mm),
/// clamped to zero, with the deepest negative lobe the clamp removed beyond round-off: with `Boundaries::Paper` (the
/// default) a stack can have one ([`NegativeLobe`]); with `Boundaries::Capped` only round-off is removed.
/// `raw_reflectance_profiles` gives the values unclamped.
pub fn clamped_reflectance_profiles(
    stacks: &[LayerStack],
    radii_mm: &[f64],
    combination: Combination,
    terms: MultipoleTerms,
    quadrature: &HankelQuadrature,
) -> ClampedProfiles {
    let (raw, centre) =
        split_centre(raw_reflectance_profiles(stacks, &with_centre(radii_mm), combination, terms, quadrature));
    ClampedProfiles::from_raw(raw, radii_mm, stacks, &centre)
}

/// `radii_mm` and [`PEAK_PROBE_MM`] last: one more radius per call, for the profiles' scale.
fn with_centre(radii_mm: &[f64]) -> Vec<f64> {
    radii_mm.iter().copied().chain([PEAK_PROBE_MM]).collect()
}

/// Profiles computed at [`with_centre`]'s radii: the profiles at the radii asked for, and each one's value at
/// [`PEAK_PROBE_MM`].
fn split_centre(mut raw: Vec<Vec<f64>>) -> (Vec<Vec<f64>>, Vec<f64>) {
    let centre = raw.iter_mut().map(|p| p.pop().unwrap_or(0.0)).collect();
    (raw, centre)
}

/// [`clamped_reflectance_profiles`] that stops once `cancel` is set (read before each radius: 10^5 radii at 401
/// wavelengths are a minute and a half of work), with [`SkinError::interrupted`].
pub fn clamped_reflectance_profiles_cancellable(
    stacks: &[LayerStack],
    radii_mm: &[f64],
    combination: Combination,
    terms: MultipoleTerms,
    quadrature: &HankelQuadrature,
    cancel: &AtomicBool,
) -> Result<ClampedProfiles, SkinError> {
    raw_profiles(stacks, &with_centre(radii_mm), combination, terms, quadrature, cancel)
        .map(|raw| {
            let (raw, centre) = split_centre(raw);
            ClampedProfiles::from_raw(raw, radii_mm, stacks, &centre)
        })
        .ok_or_else(|| SkinError::interrupted("reflectance profile"))
}

/// [`clamped_reflectance_profiles`]' values alone, for callers that check the lobe another way or not at all.
pub fn reflectance_profiles(
    stacks: &[LayerStack],
    radii_mm: &[f64],
    combination: Combination,
    terms: MultipoleTerms,
    quadrature: &HankelQuadrature,
) -> Vec<Vec<f64>> {
    clamped_reflectance_profiles(stacks, radii_mm, combination, terms, quadrature).per_mm2
}

/// [`reflectance_profiles`] before the clamp of negative round-off, for checks of the quadrature.
pub fn raw_reflectance_profiles(
    stacks: &[LayerStack],
    radii_mm: &[f64],
    combination: Combination,
    terms: MultipoleTerms,
    quadrature: &HankelQuadrature,
) -> Vec<Vec<f64>> {
    // A flag nobody sets: the profiles always come back.
    raw_profiles(stacks, radii_mm, combination, terms, quadrature, &AtomicBool::new(false)).unwrap_or_default()
}

/// [`raw_reflectance_profiles`], `None` once `cancel` is set.
fn raw_profiles(
    stacks: &[LayerStack],
    radii_mm: &[f64],
    combination: Combination,
    terms: MultipoleTerms,
    quadrature: &HankelQuadrature,
    cancel: &AtomicBool,
) -> Option<Vec<Vec<f64>>> {
    let remainder = |stack: &LayerStack, s: f64| stack.below_top_hat(s, combination, terms);
    // Where each stack's remainder stops mattering.
    let cuts: Vec<f64> = stacks
        .par_iter()
        .map(|stack| {
            let scale = stack.reflectance_hat(0.0, combination, terms).abs().max(f64::MIN_POSITIVE);
            cutoff_frequency(|s| remainder(stack, s), quadrature.cutoff * scale)
        })
        .collect();
    let s_cut = cuts.iter().cloned().fold(0.0, f64::max);
    let grid = PanelGrid::new(s_cut, quadrature);

    // Remainder times s at the nodes, per stack, on the panels that start below the stack's own cut (zero beyond).
    let samples: Vec<Vec<f64>> = stacks
        .par_iter()
        .zip(&cuts)
        .map(|(stack, &cut)| {
            let count = grid.panels.partition_point(|p| p.start() < cut) * grid.order;
            let mut v: Vec<f64> = grid.nodes[..count].iter().map(|&s| s * remainder(stack, s)).collect();
            v.resize(grid.nodes.len(), 0.0);
            v
        })
        .collect();

    // For each radius: the top layer's image sum plus the remainder weighed by the radius' kernel.
    let per_radius: Vec<Vec<f64>> = radii_mm
        .par_iter()
        .map(|&r| {
            if cancel.load(Ordering::Relaxed) {
                return None;
            }
            let kernel = grid.kernel(r);
            let row = stacks
                .iter()
                .zip(&samples)
                .map(|(stack, v)| {
                    let tail: f64 = v.iter().zip(&kernel).map(|(a, b)| a * b).sum::<f64>() / (2.0 * PI);
                    stack.top().reflectance(r, terms) + tail
                })
                .collect();
            Some(row)
        })
        .collect::<Option<_>>()?;
    // Transpose to per stack.
    Some((0..stacks.len()).map(|k| per_radius.iter().map(|row| row[k]).collect()).collect())
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

/// One panel of the s-grid: [centre - half, centre + half], mm^-1.
#[derive(Debug, Clone, Copy)]
struct Panel {
    centre: f64,
    half: f64,
}

impl Panel {
    fn start(&self) -> f64 {
        self.centre - self.half
    }
}

/// Gauss-Legendre panels covering [0, s_cut]: [0, FIRST_PANEL_PER_MM], then each panel `RELATIVE_PANEL_WIDTH /
/// refinement` times as wide as its start. The lattice depends only on the quadrature settings; `s_cut` only says
/// where it stops.
struct PanelGrid {
    order: usize,
    panels: Vec<Panel>,
    /// Gauss-Legendre abscissae and weights on [-1, 1].
    x: Vec<f64>,
    w: Vec<f64>,
    /// Nodes in s, panel by panel.
    nodes: Vec<f64>,
    /// `legendre[n][j] = P_n(x_j)`.
    legendre: Vec<Vec<f64>>,
}

impl PanelGrid {
    fn new(s_cut: f64, q: &HankelQuadrature) -> PanelGrid {
        let order = q.gauss_order.max(2);
        let (x, w) = gauss_legendre(order);
        let growth = RELATIVE_PANEL_WIDTH / q.refinement.max(1e-3);
        let mut panels = Vec::new();
        let mut a = 0.0;
        while a < s_cut {
            let width = if a == 0.0 { FIRST_PANEL_PER_MM } else { growth * a };
            panels.push(Panel { centre: a + 0.5 * width, half: 0.5 * width });
            a += width;
        }
        let nodes = panels.iter().flat_map(|p| x.iter().map(move |xi| p.centre + p.half * xi)).collect();
        let legendre = legendre_table(order, &x);
        PanelGrid { order, panels, x, w, nodes, legendre }
    }

    /// Weights that turn the samples s R~(s) at the nodes into int_0^s_cut s R~(s) J0(s r) ds.
    fn kernel(&self, r_mm: f64) -> Vec<f64> {
        let mut kernel = Vec::with_capacity(self.nodes.len());
        for panel in &self.panels {
            let omega = panel.half * r_mm;
            if omega <= GAUSS_MAX_HALF_PHASE {
                for (xi, wi) in self.x.iter().zip(&self.w) {
                    kernel.push(panel.half * wi * libm::j0((panel.centre + panel.half * xi) * r_mm));
                }
                continue;
            }
            // Filon: int_-1^1 F(x) e^(i omega x) dx ~ sum_j F(x_j) W_j, with W_j = w_j sum_n (2n+1) i^n j_n(omega) P_n(x_j)
            // exact for F of degree < order; here F = H0(s r) e^(-i s r) (times the samples), smooth on the panel.
            let jn = spherical_bessel_j(self.order, omega);
            // (2n+1) i^n j_n(omega) as (re, im).
            let coeff: Vec<(f64, f64)> = (0..self.order)
                .map(|n| {
                    let m = (2 * n + 1) as f64 * jn[n];
                    match n % 4 {
                        0 => (m, 0.0),
                        1 => (0.0, m),
                        2 => (-m, 0.0),
                        _ => (0.0, -m),
                    }
                })
                .collect();
            for (j, (&xi, &wi)) in self.x.iter().zip(&self.w).enumerate() {
                let (mut wr, mut wim) = (0.0, 0.0);
                for (n, &(cr, ci)) in coeff.iter().enumerate() {
                    let p = self.legendre[n][j];
                    wr += cr * p;
                    wim += ci * p;
                }
                let sr = (panel.centre + panel.half * xi) * r_mm;
                let (h_re, h_im) = (libm::j0(sr), libm::y0(sr));
                // H0(s r) e^(-i omega x_j)
                let (c, s) = ((omega * xi).cos(), (omega * xi).sin());
                let (f_re, f_im) = (h_re * c + h_im * s, h_im * c - h_re * s);
                // Re[W_j F_j]
                kernel.push(panel.half * wi * (wr * f_re - wim * f_im));
            }
        }
        kernel
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layer::Layer;

    #[test]
    fn cutoff_finds_decay() {
        let c = cutoff_frequency(|s| (-s).exp(), 1e-13);
        assert!(c > 30.0 && c < 45.0, "{c}");
        assert_eq!(cutoff_frequency(|_| 0.0, 1e-13), 0.0);
    }

    /// The kernel integrates a known transform pair at small and very large radii: the 2-D transform of
    /// e^(-r^2/(4a)) / (4 pi a) is e^(-a s^2), so int_0^inf s e^(-a s^2) J0(s r) ds = e^(-r^2/(4a)) / (2a).
    /// At large r the integrand turns through thousands of periods on the panels the Filon rule covers.
    #[test]
    fn kernel_inverts_a_gaussian_at_every_radius() {
        let a = 0.01;
        let grid = PanelGrid::new(80.0, &HankelQuadrature::default());
        for r in [0.0, 0.05, 0.3, 1.0] {
            let k = grid.kernel(r);
            let numeric: f64 = grid.nodes.iter().zip(&k).map(|(&s, w)| w * s * (-a * s * s).exp()).sum();
            let exact = (-r * r / (4.0 * a)).exp() / (2.0 * a);
            assert!((numeric - exact).abs() < 1e-9 * (1.0 / (2.0 * a)), "r={r}: {numeric} vs {exact}");
        }
        // The Gaussian's transform at a radius of 1e3 mm: exp(-2.5e7) = 0, to the accuracy of the quadrature.
        for r in [30.0, 1e3, 1e5] {
            let k = grid.kernel(r);
            let numeric: f64 = grid.nodes.iter().zip(&k).map(|(&s, w)| w * s * (-a * s * s).exp()).sum();
            assert!(numeric.abs() < 1e-9 / (2.0 * a), "r={r}: {numeric}");
        }
    }

    /// A single layer's profile is its image sum; the quadrature alone (no split) must recover it at every radius.
    #[test]
    fn inverse_of_single_slab_transform_is_its_image_sum() {
        let stack = LayerStack::new(&[Layer {
            thickness_mm: 0.25,
            sigma_a_per_mm: 0.26,
            sigma_s_reduced_per_mm: 6.08,
            ior: 1.4,
        }])
        .unwrap();
        let slab = *stack.top();
        let t = MultipoleTerms::All;
        let f = |s: f64| slab.reflectance_hat(s, t);
        let radii: Vec<f64> = (0..=70).map(|i| 1e-3 * 10f64.powf(i as f64 * 0.1)).collect();
        let cut = cutoff_frequency(f, 1e-16);
        let grid = PanelGrid::new(cut, &HankelQuadrature::default());
        let peak = slab.reflectance(0.0, t);
        for &r in &radii {
            let k = grid.kernel(r);
            let numeric: f64 = grid.nodes.iter().zip(&k).map(|(&s, &w)| w * s * f(s)).sum::<f64>() / (2.0 * PI);
            let exact = slab.reflectance(r, t);
            let err = (numeric - exact).abs();
            assert!(err < 1e-4 * exact + 1e-10 * peak, "r={r}: numeric {numeric} exact {exact}");
        }
    }
}
