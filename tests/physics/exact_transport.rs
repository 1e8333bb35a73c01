//! The adding-doubling totals against the project's own Monte Carlo (tests/support/mc.rs: an independent photon
//! simulation of the same layered slab, isotropic scattering with the reduced coefficient, Fresnel at every index
//! step, photons starting just below the surface: per unit refracted power, as the totals are).
//!
//! Stacks: fair skin (the caucasian preset at 550 nm), an optically thin epidermis, an absorbing epidermis, dark skin
//! (the african preset at 450 and 550 nm) and a homogeneous medium. Each: 16 streams (and the shipped table of totals, where it
//! holds the stack) within the Monte Carlo's standard error plus 0.3 %; the default stream count within 1 %. The diffusion total's excess is printed beside.
//!
//! Run with `cargo test --release --test physics exact_transport:: -- --nocapture` to see the figures.

use crate::support::mc::{simulate, McConfig, McLayer};
use spectral_skin::diffusion::{Combination, LayerStack, MultipoleTerms};
use spectral_skin::layer::Layer;
use spectral_skin::skin::{skin_layers, SkinModel, SkinParams};
use spectral_skin::transport::total_table::TotalTable;
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
    let table = TotalTable::shipped().total_of(layers);
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
    // The shipped table of totals (the default's source for two layers over a semi-infinite dermis) as the 16 streams.
    if let Some(table) = table {
        println!("{name}: table of totals {table:.5} ({:+.3} %)", 100.0 * rel(table));
        assert!(
            rel(table).abs() <= se + 0.003,
            "{name}: table {table} vs MC {} +- {}",
            mc.reflectance,
            mc.reflectance_se
        );
    }
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
