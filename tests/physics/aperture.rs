//! The instrument aperture's measured fraction (src/inverse/aperture.rs) against the analog Monte Carlo of
//! tests/support/mc.rs: the light a skin stack returns inside the measured disc of a uniformly lit larger disc, from
//! the Monte Carlo's own radial distribution (no table, no interpolation), the discs' overlap applied to both.
//! Also: the encircled energy the fraction reads equals the profile it integrates, and the quadrature has converged.
//!
//! Run with `cargo test --release --test physics aperture -- --nocapture` to see the figures.

use crate::support::mc::{log_edges, simulate, McConfig, McLayer};
use crate::support::profile_figures::profile_energy_by_quadrature;
use spectral_skin::inverse::aperture::{Aperture, CM2600D_MAV, CM2600D_SAV, FRACTION_STEP_NM};
use spectral_skin::skin::{skin_layers, SkinModel, SkinParams};
use spectral_skin::transport::profile_table::exact_shape;

/// Radial edges for a Monte Carlo read through `aperture`: log-spaced up to a - b, 64 even annuli over the rim
/// a - b .. a + b, log-spaced beyond.
fn edges_for(aperture: &Aperture) -> Vec<f64> {
    let (a, b) = (aperture.illuminated_radius_mm, aperture.measured_radius_mm);
    let mut edges = log_edges(1e-3, a - b, 40, true);
    edges.extend((1..=64).map(|k| a - b + 2.0 * b * k as f64 / 64.0));
    edges.extend(log_edges(a + b, 200.0, 20, false).into_iter().skip(1));
    edges
}

/// The skin stacks where the edge loss is largest and smallest: fair and dark skin in the red, where light travels
/// furthest, and fair skin in the Q bands.
#[test]
fn measured_fraction_matches_monte_carlo() {
    let mut worst = 0.0f64;
    for (preset, nm, aperture, name) in [
        ("ita-very-light", 700.0, CM2600D_SAV, "SAV"),
        ("ita-very-light", 650.0, CM2600D_MAV, "MAV"),
        ("ita-dark", 700.0, CM2600D_SAV, "SAV"),
        ("ita-light", 560.0, CM2600D_SAV, "SAV"),
    ] {
        let layers = skin_layers(&SkinParams::preset(preset).unwrap(), &SkinModel::default(), nm);
        let edges = edges_for(&aperture);
        let mc = simulate(&McLayer::isotropic_stack(&layers), &McConfig::new(400_000, 7, edges.clone()));
        let cdf = mc.cumulative_reflectance_at_edges();
        let inner = edges.iter().position(|&e| e >= aperture.illuminated_radius_mm - aperture.measured_radius_mm);
        let inner = inner.expect("a - b is an edge");
        let rim: f64 = (inner..inner + 64)
            .map(|k| (cdf[k + 1] - cdf[k]) * aperture.overlap_weight(0.5 * (edges[k] + edges[k + 1])))
            .sum();
        let monte_carlo = (cdf[inner] + rim) / mc.reflectance;
        let table = aperture.kernel().measured_fraction(&exact_shape(&layers).unwrap());
        let diff = table - monte_carlo;
        worst = worst.max(diff.abs());
        println!(
            "{preset} {nm} nm {name}: measured fraction table {table:.4}, Monte Carlo {monte_carlo:.4} ({diff:+.4}); \
             edge loss {:.4} vs {:.4}",
            1.0 - table,
            1.0 - monte_carlo
        );
        // The loss is 0.01-0.14 here; 0.004 is the Monte Carlo's noise (about 1e-3) plus the table's interpolation.
        assert!(diff.abs() < 4e-3, "{preset} {nm} nm {name}: table {table} vs Monte Carlo {monte_carlo}");
    }
    println!("worst |table - Monte Carlo| {worst:.4}");
}

/// The encircled energy equals the profile integrated (2 pi r dr, midpoint in ln r) from 1e-9 mm, and the
/// aperture's Gauss-Chebyshev rim quadrature is within 1e-5 of 4096 midpoint panels.
#[test]
fn encircled_energy_integrates_the_profile_and_the_rim_quadrature_converges() {
    let mut worst_rim = 0.0f64;
    for preset in ["ita-very-light", "ita-dark", "caucasian"] {
        for nm in [450.0, 580.0, 700.0] {
            let layers = skin_layers(&SkinParams::preset(preset).unwrap(), &SkinModel::default(), nm);
            let shape = exact_shape(&layers).unwrap();
            let radii = [0.0, 1e-3, 0.05, 0.5, 1.5, 4.0, 9.5, 30.0];
            let energy = shape.encircled_energy(&radii);
            for (&r, &e) in radii.iter().zip(&energy) {
                let integral = profile_energy_by_quadrature(&shape, 1e-9, r.max(1e-9), 100_000);
                assert!((e - integral).abs() < 1e-5, "{preset} {nm} nm r {r}: {e} vs {integral}");
            }
            for aperture in [CM2600D_MAV, CM2600D_SAV] {
                let coarse = aperture.kernel().measured_fraction(&shape);
                let (a, b) = (aperture.illuminated_radius_mm, aperture.measured_radius_mm);
                let fine_edges: Vec<f64> = (0..=4096).map(|k| a - b + 2.0 * b * k as f64 / 4096.0).collect();
                let e = shape.encircled_energy(&fine_edges);
                let fine = e[0]
                    + e.windows(2)
                        .enumerate()
                        .map(|(k, w)| {
                            (w[1] - w[0]) * aperture.overlap_weight(a - b + 2.0 * b * (k as f64 + 0.5) / 4096.0)
                        })
                        .sum::<f64>();
                worst_rim = worst_rim.max((coarse - fine).abs());
                assert!(
                    (coarse - fine).abs() < 1e-5,
                    "{preset} {nm} nm: Gauss-Chebyshev {coarse} vs 4096 panels {fine}"
                );
            }
        }
    }
    println!("worst |Gauss-Chebyshev - 4096 panels| {worst_rim:.1e}");
}

/// What a 15 nm bandpass averages, the reflectance times the measured fraction: with the fraction computed every
/// FRACTION_STEP_NM and interpolated between (what the fit does), within 2e-4 of reflectance of the average with the
/// fraction at every nanometre, on the presets from fair to dark, both masks, 400-700 nm; the fraction taken only at
/// the measured wavelength (one per 10 nm) misses by more.
#[test]
fn fractions_every_step_match_every_nanometre_through_the_bandpass() {
    use spectral_skin::evaluate::{diffuse_reflectance_at, Request};
    let model = SkinModel::default();
    let nodes: Vec<f64> = (385..=715).map(f64::from).collect();
    let never = std::sync::atomic::AtomicBool::new(false);
    let (mut worst, mut worst_at_centre) = (0.0f64, 0.0f64);
    for preset in ["ita-very-light", "ita-intermediate", "ita-dark", "caucasian"] {
        let params = SkinParams::preset(preset).unwrap();
        let r = diffuse_reflectance_at(&params, &Request::default(), &nodes, &never).unwrap();
        let shape_at = |nm: f64| exact_shape(&skin_layers(&params, &model, nm));
        for aperture in [CM2600D_MAV, CM2600D_SAV] {
            let kernel = aperture.kernel();
            let exact: Vec<f64> = nodes.iter().map(|&nm| kernel.measured_fraction(&shape_at(nm).unwrap())).collect();
            let stepped = kernel.fractions(&nodes, shape_at).unwrap();
            for centre in (0..31).map(|i| 400.0 + 10.0 * i as f64) {
                let average = |f: &[f64]| {
                    let (mut sum, mut weights) = (0.0, 0.0);
                    for (k, &nm) in nodes.iter().enumerate() {
                        let w = (1.0 - (nm - centre).abs() / 15.0).max(0.0);
                        sum += w * r[k] * f[k];
                        weights += w;
                    }
                    sum / weights
                };
                let reference = average(&exact);
                let centre_fraction = exact[nodes.iter().position(|&nm| nm == centre).unwrap()];
                let at_centre = average(&vec![1.0; nodes.len()]) * centre_fraction;
                let difference = (average(&stepped) - reference).abs();
                worst = worst.max(difference);
                worst_at_centre = worst_at_centre.max((at_centre - reference).abs());
                assert!(difference < 2e-4, "{preset} {centre} nm: every {FRACTION_STEP_NM} nm off by {difference}");
            }
        }
    }
    println!("worst: every {FRACTION_STEP_NM} nm {worst:.1e}, at the measured wavelength only {worst_at_centre:.1e}");
    assert!(worst_at_centre > worst, "the step buys nothing: {worst_at_centre} vs {worst}");
}

/// The measured fraction grows toward 1 as the lit disc widens around a fixed measured disc (light from further out
/// makes up for what leaves), from equal discs (the hardest case: the rim reaches the centre) to one 100 times wider.
#[test]
fn fraction_grows_to_one_as_the_lit_disc_widens() {
    for preset in ["ita-very-light", "ita-dark"] {
        for nm in [450.0, 700.0] {
            let shape = exact_shape(&skin_layers(&SkinParams::preset(preset).unwrap(), &SkinModel::default(), nm));
            let shape = shape.unwrap();
            let fractions: Vec<f64> = [1.0, 1.5, 2.0, 4.0, 100.0]
                .iter()
                .map(|&k| Aperture { illuminated_radius_mm: k, measured_radius_mm: 1.0 })
                .map(|a| a.kernel().measured_fraction(&shape))
                .collect();
            assert!(fractions.windows(2).all(|w| w[1] >= w[0]), "{preset} {nm} nm: {fractions:?}");
            assert!(fractions[0] > 0.0 && fractions[4] > 0.999, "{preset} {nm} nm: {fractions:?}");
        }
    }
}
