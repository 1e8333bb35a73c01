//! The adding-doubling totals against the project's own Monte Carlo (tests/support/mc.rs: an independent photon
//! simulation of the same layered slab, isotropic scattering with the reduced coefficient, Fresnel at every index
//! step, photons starting just below the surface: per unit refracted power, as the totals are).
//!
//! Stacks: fair skin (the caucasian preset at 550 nm), an optically thin epidermis, an absorbing epidermis, dark skin
//! (the african preset at 450 and 550 nm) and a homogeneous medium. Each: 16 streams within the Monte Carlo's
//! standard error plus 0.3 %; the default stream count within 1 %. The diffusion total's excess is printed beside.
//!
//! Run with `cargo test --release --test physics exact_transport:: -- --nocapture` to see the figures.

use crate::support::mc::{simulate, McConfig, McLayer};
use spectral_skin::diffusion::{Combination, Layer, LayerStack, MultipoleTerms};
use spectral_skin::skin::{skin_layers, SkinModel, SkinParams};
use spectral_skin::transport::{total_diffuse_reflectance, DEFAULT_STREAMS};

fn layer(thickness_mm: f64, sigma_a_per_mm: f64, sigma_s_reduced_per_mm: f64) -> Layer {
    Layer { thickness_mm, sigma_a_per_mm, sigma_s_reduced_per_mm, ior: 1.4 }
}

fn preset_layers(preset: &str, wavelength_nm: f64) -> Vec<Layer> {
    skin_layers(&SkinParams::preset(preset).unwrap(), &SkinModel::default(), wavelength_nm).to_vec()
}

fn check(name: &str, layers: &[Layer], photons: u64, seed: u64) {
    let mc = simulate(&McLayer::isotropic_stack(layers), &McConfig::new(photons, seed, vec![]));
    let exact = total_diffuse_reflectance(layers, 16).unwrap();
    let default = total_diffuse_reflectance(layers, DEFAULT_STREAMS).unwrap();
    let diffusion =
        LayerStack::new(layers).unwrap().reflectance_hat(0.0, Combination::Directional, MultipoleTerms::All);
    let rel = |x: f64| x / mc.reflectance - 1.0;
    let se = mc.reflectance_se / mc.reflectance;
    println!(
        "{name}: MC {:.5} +- {:.5} ({photons} photons); adding-doubling 16 streams {exact:.5} ({:+.3} %), {DEFAULT_STREAMS} \
         streams {default:.5} ({:+.3} %); diffusion {diffusion:.5} ({:+.1} %)",
        mc.reflectance,
        mc.reflectance_se,
        100.0 * rel(exact),
        100.0 * rel(default),
        100.0 * rel(diffusion)
    );
    assert!(
        rel(exact).abs() <= se + 0.003,
        "{name}: 16 streams {exact} vs MC {} +- {}",
        mc.reflectance,
        mc.reflectance_se
    );
    assert!(rel(default).abs() <= 0.01, "{name}: {DEFAULT_STREAMS} streams {default} vs MC {}", mc.reflectance);
}

#[test]
fn fair_skin() {
    check("caucasian 550 nm", &preset_layers("caucasian", 550.0), 400_000, 201);
}

#[test]
fn thin_epidermis() {
    check("thin epidermis", &[layer(0.25, 0.5, 2.5), layer(f64::INFINITY, 0.02, 1.25)], 400_000, 202);
}

#[test]
fn absorbing_epidermis() {
    check("absorbing epidermis", &[layer(0.25, 5.0, 4.0), layer(f64::INFINITY, 0.02, 1.25)], 1_000_000, 203);
}

#[test]
fn dark_skin() {
    check("african 450 nm", &preset_layers("african", 450.0), 6_000_000, 204);
    check("african 550 nm", &preset_layers("african", 550.0), 1_000_000, 205);
}

#[test]
fn asian_blue() {
    check("asian 450 nm", &preset_layers("asian", 450.0), 1_000_000, 206);
}

#[test]
fn homogeneous() {
    check("homogeneous", &[layer(f64::INFINITY, 0.1, 1.0)], 400_000, 207);
}

/// The radial profile's shape: `layered_reflectance`'s profile (the multipole's shape, scaled to the exact total)
/// against the Monte Carlo's, as encircled-energy radii r50 and r90 (the radii holding half and 90 % of the reflected
/// light). Printed for fair, thin-epidermis and dark stacks; asserted at the measured figures plus a margin, so a
/// regression shows. Measured: fair skin -7.6 % / -5.9 %; thin epidermis -45 % / -13 %; asian 450 nm +198 % / +37 %;
/// african 550 nm +301 % / +97 %: where the epidermis absorbs, most of the light that returns leaves within a
/// fraction of a mean free path after a few scatterings, which diffusion spreads over the diffusion length. Scaling
/// the shape to the exact total cannot move these radii (docs/model.md, Exact transport).
#[test]
fn profile_encircled_energy() {
    use crate::support::mc::log_edges;
    use spectral_skin::diffusion::layered_reflectance;
    let cases: [(&str, Vec<Layer>, f64, f64); 4] = [
        ("caucasian 550 nm", preset_layers("caucasian", 550.0), 0.10, 0.10),
        ("thin epidermis", vec![layer(0.25, 0.5, 2.5), layer(f64::INFINITY, 0.02, 1.25)], 0.5, 0.2),
        ("asian 450 nm", preset_layers("asian", 450.0), 2.2, 0.45),
        ("african 550 nm", preset_layers("african", 550.0), 3.3, 1.1),
    ];
    for (name, layers, r50_bound, r90_bound) in cases {
        let mfp_mm = 1.0 / (layers[1].sigma_a_per_mm + layers[1].sigma_s_reduced_per_mm);
        let edges = log_edges(0.002 * mfp_mm, 30.0 * mfp_mm, 60, true);
        let mc = simulate(&McLayer::isotropic_stack(&layers), &McConfig::new(400_000, 301, edges.clone()));
        let mc_cdf: Vec<f64> = mc.cumulative_reflectance_at_edges().iter().map(|c| c / mc.reflectance).collect();
        // The model's encircled energy at the same edges: 2 pi r R(r) integrated by 8-point Gauss-Legendre per bin.
        let (x, w) = gauss_legendre_01(8);
        let mut cdf = vec![0.0];
        let mut acc = 0.0;
        let mut model_total = 0.0;
        for k in 0..edges.len() - 1 {
            let (a, b) = (edges[k], edges[k + 1]);
            let radii: Vec<f64> = x.iter().map(|xi| a + (b - a) * xi).collect();
            let (total, profile) = layered_reflectance(&layers, &radii).unwrap();
            model_total = total;
            acc += radii
                .iter()
                .zip(&profile)
                .zip(&w)
                .map(|((r, p), wi)| 2.0 * std::f64::consts::PI * r * p * (b - a) * wi)
                .sum::<f64>();
            cdf.push(acc);
        }
        let cdf: Vec<f64> = cdf.iter().map(|c| c / model_total).collect();
        let (m50, m90) = (radius_at(&edges, &cdf, 0.5), radius_at(&edges, &cdf, 0.9));
        let (t50, t90) = (radius_at(&edges, &mc_cdf, 0.5), radius_at(&edges, &mc_cdf, 0.9));
        println!(
            "{name}: r50 model {m50:.4} / MC {t50:.4} mm ({:+.1} %), r90 {m90:.4} / {t90:.4} mm ({:+.1} %)",
            100.0 * (m50 / t50 - 1.0),
            100.0 * (m90 / t90 - 1.0)
        );
        assert!((m50 / t50 - 1.0).abs() < r50_bound, "{name}: r50 {m50} vs MC {t50}, bound {r50_bound}");
        assert!((m90 / t90 - 1.0).abs() < r90_bound, "{name}: r90 {m90} vs MC {t90}, bound {r90_bound}");
    }
}

/// Radius where a cumulative curve given at `edges` reaches `level` (log-linear interpolation in r).
fn radius_at(edges: &[f64], cdf: &[f64], level: f64) -> f64 {
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
fn gauss_legendre_01(n: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut x, mut w) = (vec![0.0; n], vec![0.0; n]);
    for i in 0..n {
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
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
