//! Radial profile figures of one stack on shared annuli: the analog Monte Carlo's (`super::mc`) and the product's
//! (`layered_reflectance_with`, exact or diffusion shape): r50, r90, the fitted Burley d and R(r) averaged per annulus.
//! Used by tests/physics/exact_profile.rs (the acceptance) and the accuracy report (its profile-shape rows).
#![allow(dead_code)]

use std::f64::consts::PI;

use super::mc::{log_edges, simulate, McConfig, McLayer, McResult};
use spectral_skin::diffusion::{Combination, LayerStack, MultipoleTerms};
use spectral_skin::fit::burley::{fit_burley, fit_frequencies};
use spectral_skin::layer::Layer;
use spectral_skin::reflectance::{layered_reflectance_with, LayeredOptions, ProfileShape};
use spectral_skin::transport::profile_table::{exact_shape, Shape};

/// Gauss-Legendre points per annulus.
const POINTS_PER_ANNULUS: usize = 8;
/// Largest spatial frequency the radius fit uses, in units of the first (`fit_frequencies`' argument).
const FIT_SPAN: f64 = 4.0;

/// The three figures a profile is judged by (mm).
#[derive(Debug, Clone, Copy)]
pub struct Figures {
    pub r50_mm: f64,
    pub r90_mm: f64,
    /// Burley d fitted to the normalised transform at the fit's frequencies.
    pub d_mm: f64,
}

impl Figures {
    /// Relative errors [r50, r90, d] against `truth`.
    pub fn relative_to(&self, truth: &Figures) -> [f64; 3] {
        [self.r50_mm / truth.r50_mm - 1.0, self.r90_mm / truth.r90_mm - 1.0, self.d_mm / truth.d_mm - 1.0]
    }
}

/// The Monte Carlo's profile of a stack on log annuli out to 60 dermal transport lengths.
pub struct McProfile {
    pub edges_mm: Vec<f64>,
    pub result: McResult,
    pub figures: Figures,
}

/// Simulates `layers` (isotropic scattering, sigma_s = sigma_s') with `photons` and `seed`.
pub fn monte_carlo(layers: &[Layer], photons: u64, seed: u64) -> McProfile {
    let derm = layers.last().expect("at least one layer");
    let mfp_mm = 1.0 / (derm.sigma_a_per_mm + derm.sigma_s_reduced_per_mm);
    let edges_mm = log_edges(1e-4, 60.0 * mfp_mm, 72, true);
    let result = simulate(&McLayer::isotropic_stack(layers), &McConfig::new(photons, seed, edges_mm.clone()));
    let cdf: Vec<f64> = result.cumulative_reflectance_at_edges().iter().map(|c| c / result.reflectance).collect();
    let (x, w) = gauss_legendre_01(POINTS_PER_ANNULUS);
    let s = fit_frequencies(FIT_SPAN);
    // The transform from the binned profile: J0 averaged over each annulus with the area weight.
    let n: Vec<f64> = s
        .iter()
        .map(|&sq| {
            let mut acc = result.reflectance_below_first_edge;
            for (b, pair) in edges_mm.windows(2).enumerate() {
                let (a, bb) = (pair[0], pair[1]);
                let mean_j0: f64 = x
                    .iter()
                    .zip(&w)
                    .map(|(xi, wi)| {
                        let r = a + (bb - a) * xi;
                        wi * libm::j0(sq * r) * 2.0 * r * (bb - a) / (bb * bb - a * a)
                    })
                    .sum();
                acc += result.profile_per_mm2[b] * PI * (bb * bb - a * a) * mean_j0;
            }
            acc / result.reflectance
        })
        .collect();
    let figures = Figures {
        r50_mm: radius_at(&edges_mm, &cdf, 0.5),
        r90_mm: radius_at(&edges_mm, &cdf, 0.9),
        d_mm: fit_burley(&s, &n).d_mm,
    };
    McProfile { edges_mm, result, figures }
}

/// The product's profile of a stack on given annuli.
pub struct ModelProfile {
    /// R(r) averaged over each annulus, mm^-2.
    pub annulus_mean_per_mm2: Vec<f64>,
    pub figures: Figures,
    pub shape: ProfileShape,
}

/// `layered_reflectance_with(layers, .., options)` averaged over the annuli of `edges_mm`, with its figures; d from
/// the transform of the same shape (the exact table's, or the multipole's).
pub fn model(layers: &[Layer], edges_mm: &[f64], options: &LayeredOptions) -> ModelProfile {
    let (x, w) = gauss_legendre_01(POINTS_PER_ANNULUS);
    // Every annulus' Gauss-Legendre radii in one call: one total and one shape for the stack.
    let radii: Vec<f64> =
        edges_mm.windows(2).flat_map(|pair| x.iter().map(move |xi| pair[0] + (pair[1] - pair[0]) * xi)).collect();
    let r = layered_reflectance_with(layers, &radii, options).expect("layered reflectance");
    let (total, shape) = (r.total, r.shape);
    let mut annulus_mean_per_mm2 = Vec::new();
    let mut cdf = vec![0.0];
    let mut acc = 0.0;
    for (pair, (radii, values)) in
        edges_mm.windows(2).zip(radii.chunks(POINTS_PER_ANNULUS).zip(r.profile_per_mm2.chunks(POINTS_PER_ANNULUS)))
    {
        let (a, bb) = (pair[0], pair[1]);
        let inside: f64 = radii.iter().zip(values).zip(&w).map(|((r, p), wi)| 2.0 * PI * r * p * (bb - a) * wi).sum();
        annulus_mean_per_mm2.push(inside / (PI * (bb * bb - a * a)));
        acc += inside;
        cdf.push(acc);
    }
    let cdf: Vec<f64> = cdf.iter().map(|c| c / total).collect();
    let s = fit_frequencies(FIT_SPAN);
    let n: Vec<f64> = match shape {
        ProfileShape::Exact => {
            let exact = exact_shape(layers).expect("an exact profile has a table shape");
            s.iter().map(|&sq| exact.normalized_transform(sq)).collect()
        }
        ProfileShape::Multipole => multipole_transform(layers, &s),
    };
    let figures = Figures {
        r50_mm: radius_at(edges_mm, &cdf, 0.5),
        r90_mm: radius_at(edges_mm, &cdf, 0.9),
        d_mm: fit_burley(&s, &n).d_mm,
    };
    ModelProfile { annulus_mean_per_mm2, figures, shape }
}

/// The multipole's normalised transform R~(s) / R~(0) at `s_per_mm`.
pub fn multipole_transform(layers: &[Layer], s_per_mm: &[f64]) -> Vec<f64> {
    let stack = LayerStack::new(layers).expect("layers");
    let m0 = stack.reflectance_hat(0.0, Combination::Directional, MultipoleTerms::All);
    s_per_mm.iter().map(|&s| stack.reflectance_hat(s, Combination::Directional, MultipoleTerms::All) / m0).collect()
}

/// Worst relative error of R(r) against the Monte Carlo over annuli of four bins each (one bin's photon noise is too
/// large to test 10 % against), where the Monte Carlo is above 1e-3 of its peak and known to 4 %; with the number of
/// annuli compared.
pub fn worst_profile_error(model: &ModelProfile, mc: &McProfile) -> (f64, usize) {
    let edges = &mc.edges_mm;
    let area = |b: usize| PI * (edges[b + 1].powi(2) - edges[b].powi(2));
    let groups: Vec<(f64, f64, f64)> = (0..model.annulus_mean_per_mm2.len() / 4)
        .map(|g| {
            let bins = 4 * g..4 * g + 4;
            let a: f64 = bins.clone().map(area).sum();
            let mc_mean: f64 = bins.clone().map(|b| mc.result.profile_per_mm2[b] * area(b)).sum::<f64>() / a;
            let mc_se =
                bins.clone().map(|b| (mc.result.profile_se_per_mm2[b] * area(b)).powi(2)).sum::<f64>().sqrt() / a;
            let model_mean: f64 = bins.map(|b| model.annulus_mean_per_mm2[b] * area(b)).sum::<f64>() / a;
            (model_mean, mc_mean, mc_se)
        })
        .collect();
    let peak = groups.iter().map(|g| g.1).fold(0.0f64, f64::max);
    let compared: Vec<&(f64, f64, f64)> = groups.iter().filter(|g| g.1 > 1e-3 * peak && g.2 < 0.04 * g.1).collect();
    (compared.iter().map(|g| (g.0 / g.1 - 1.0).abs()).fold(0.0f64, f64::max), compared.len())
}

/// Radius where a cumulative curve given at `edges` reaches `level` (log-linear interpolation in r).
pub fn radius_at(edges: &[f64], cdf: &[f64], level: f64) -> f64 {
    let k = cdf.partition_point(|&c| c < level);
    assert!(
        k >= 1 && k < cdf.len(),
        "level {level} outside the tabulated curve: index {k} of {}, from {:?} to {:?}",
        cdf.len(),
        cdf.first(),
        cdf.last()
    );
    let f = (level - cdf[k - 1]) / (cdf[k] - cdf[k - 1]);
    if edges[k - 1] == 0.0 {
        return edges[k] * f;
    }
    (edges[k - 1].ln() + f * (edges[k] / edges[k - 1]).ln()).exp()
}

/// Gauss-Legendre nodes and weights on [0, 1] (Newton on the Legendre recurrence).
pub fn gauss_legendre_01(n: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut x, mut w) = (vec![0.0; n], vec![0.0; n]);
    for i in 0..n {
        let mut z = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        loop {
            let (mut p0, mut p1) = (1.0, 0.0);
            for j in 0..n {
                let p2 = p1;
                p1 = p0;
                p0 = ((2 * j + 1) as f64 * z * p1 - j as f64 * p2) / (j + 1) as f64;
            }
            let dp = n as f64 * (z * p0 - p1) / (z * z - 1.0);
            let dz = p0 / dp;
            z -= dz;
            if dz.abs() < 1e-15 {
                x[i] = 0.5 * (1.0 - z);
                w[i] = 1.0 / ((1.0 - z * z) * dp * dp);
                break;
            }
        }
    }
    (x, w)
}

/// The energy `shape`'s normalised profile puts between `r_min_mm` and `r_max_mm`: the integral of
/// `normalized_profile_per_mm2` times 2 pi r dr by the midpoint rule on `n` steps in ln r.
pub fn profile_energy_by_quadrature(shape: &Shape, r_min_mm: f64, r_max_mm: f64, n: usize) -> f64 {
    let (lo, hi) = (r_min_mm.ln(), r_max_mm.ln());
    let step = (hi - lo) / n as f64;
    (0..n)
        .map(|i| {
            let r = (lo + step * (i as f64 + 0.5)).exp();
            shape.normalized_profile_per_mm2(r) * 2.0 * PI * r * r * step
        })
        .sum()
}
