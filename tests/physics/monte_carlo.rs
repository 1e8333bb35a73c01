//! The diffusion solver against an independent Monte Carlo reference (tests/support/mc.rs).
//!
//! (a) The Monte Carlo on its own, against analytic results that involve no diffusion code:
//!     energy conservation, Beer-Lambert, Fresnel (normal and oblique), the exact single-scattering
//!     radial profile (which checks exit positions), and Chandrasekhar's plane albedo.
//! (b) `multipole_reflectance` (`layered_reflectance` with `Transport::Diffusion`) against the Monte Carlo for
//!     skin-like stacks (isotropic scattering with sigma_s = sigma_s', so the two solve the same transport problem;
//!     diffusion is an approximation of it, known to be a few per cent off for high albedo and worse for low albedo).
//!
//! Run with `cargo test --release --test physics monte_carlo:: -- --nocapture` to see the measured figures.

use crate::support::mc::{annulus_area, fresnel_unpolarized, log_edges, simulate, McConfig, McLayer, McResult};

use crate::support::profile_figures::{gauss_legendre_01, radius_at};
use spectral_skin::layer::Layer;
use spectral_skin::reflectance::multipole_reflectance;
use spectral_skin::skin::{skin_layers, SkinModel, SkinParams};

fn semi_infinite(sigma_a: f64, sigma_s: f64, ior: f64) -> Vec<McLayer> {
    vec![McLayer { thickness_mm: f64::INFINITY, sigma_a_per_mm: sigma_a, sigma_s_per_mm: sigma_s, ior }]
}

/// Chandrasekhar's H(mu) for isotropic scattering with single-scattering albedo `a`, from
/// 1/H(mu) = sqrt(1-a) + (a/2) * int_0^1 mu' H(mu') / (mu + mu') dmu', iterated on Gauss-Legendre nodes.
fn chandrasekhar_h(a: f64, mu: f64) -> f64 {
    let (x, w) = gauss_legendre_01(64);
    let s = (1.0 - a).sqrt();
    let rhs = |h: &[f64], m: f64| -> f64 {
        let integral: f64 = x.iter().zip(&w).zip(h).map(|((&xj, &wj), &hj)| wj * xj * hj / (m + xj)).sum();
        1.0 / (s + 0.5 * a * integral)
    };
    let mut h = vec![1.0; x.len()];
    for _ in 0..10_000 {
        let next: Vec<f64> = x.iter().map(|&m| rhs(&h, m)).collect();
        let change = next.iter().zip(&h).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        h = next;
        if change < 1e-15 {
            break;
        }
    }
    // Self-check: the zeroth moment of H is (2/a)(1 - sqrt(1-a)).
    let moment: f64 = w.iter().zip(&h).map(|(wj, hj)| wj * hj).sum();
    let expect = 2.0 / a * (1.0 - s);
    assert!((moment - expect).abs() < 1e-10, "H moment {moment} vs {expect}");
    rhs(&h, mu)
}

/// (i) A non-absorbing semi-infinite medium reflects everything (whatever the index): every
/// photon comes back, except those stopped by the collision cap, whose share shrinks like n^-1/2.
#[test]
fn mc_non_absorbing_semi_infinite_reflects_everything() {
    for ior in [1.0, 1.4] {
        let mut cfg = McConfig::new(20_000, 11, vec![]);
        cfg.max_collisions_per_photon = 200_000;
        let r = simulate(&semi_infinite(0.0, 2.0, ior), &cfg);
        println!(
            "non-absorbing, ior {ior}: R = {:.5} +- {:.5}, unfinished {:.5}, T {}, events {}",
            r.reflectance, r.reflectance_se, r.unfinished, r.transmittance, r.scattering_events
        );
        assert_eq!(r.transmittance, 0.0, "ior {ior}");
        assert!(r.absorbed.abs() < 1e-12, "ior {ior}: absorbed {}", r.absorbed);
        assert!(
            (r.reflectance + r.unfinished - 1.0).abs() < 1e-12,
            "ior {ior}: R {} + unfinished {} != 1",
            r.reflectance,
            r.unfinished
        );
        assert!(r.unfinished < 0.01, "too many photons still inside after the cap: {}", r.unfinished);
    }
}

/// (ii) A non-scattering, index-matched slab transmits exp(-sigma_a d) ballistically and reflects nothing.
#[test]
fn mc_non_scattering_slab_beer_lambert() {
    let (sigma_a, d) = (1.3, 0.6);
    let layers = vec![
        McLayer { thickness_mm: 0.25, sigma_a_per_mm: sigma_a, sigma_s_per_mm: 0.0, ior: 1.0 },
        McLayer { thickness_mm: d - 0.25, sigma_a_per_mm: sigma_a, sigma_s_per_mm: 0.0, ior: 1.0 },
    ];
    let n = 200_000;
    let r = simulate(&layers, &McConfig::new(n, 12, vec![]));
    let expect = (-sigma_a * d).exp();
    let binomial_se = (expect * (1.0 - expect) / n as f64).sqrt();
    println!("Beer-Lambert: T = {:.5} +- {:.5} (expect {expect:.5})", r.transmittance, r.transmittance_se);
    assert_eq!(r.reflectance, 0.0);
    assert!((r.transmittance - expect).abs() < 4.0 * binomial_se, "T {} vs {expect}", r.transmittance);
}

/// Fresnel at normal incidence between two interfaces: a clear 1.4 layer over a clear 1.0 layer.
/// Starting inside, R = R0 (1 - R0) sum R0^2k = R0 / (1 + R0) with R0 = ((1.4 - 1)/(1.4 + 1))^2.
#[test]
fn mc_fresnel_normal_incidence_two_interfaces() {
    let layers = vec![
        McLayer { thickness_mm: 0.3, sigma_a_per_mm: 0.0, sigma_s_per_mm: 0.0, ior: 1.4 },
        McLayer { thickness_mm: 1.0, sigma_a_per_mm: 0.0, sigma_s_per_mm: 0.0, ior: 1.0 },
    ];
    let n = 400_000;
    let r = simulate(&layers, &McConfig::new(n, 13, vec![]));
    let r0 = (0.4f64 / 2.4).powi(2);
    let expect = r0 / (1.0 + r0);
    let se = (expect * (1.0 - expect) / n as f64).sqrt();
    println!("two clear interfaces: R = {:.5} (expect {expect:.5}), T = {:.5}", r.reflectance, r.transmittance);
    assert!((r.reflectance - expect).abs() < 4.0 * se, "R {} vs {expect}, 4 se = {}", r.reflectance, 4.0 * se);
    assert!((r.reflectance + r.transmittance - 1.0).abs() < 1e-12, "R {} + T {} != 1", r.reflectance, r.transmittance);
}

/// The Fresnel function: unpolarised reflectance at normal incidence, total internal reflection
/// past the critical angle, the reciprocity relation between internal and external hemispherical
/// diffuse reflectance, r_i = 1 - (1 - r_e)/n^2, and the Egan-Hilgeman fit Fdr(1.4) = 0.5295.
#[test]
fn fresnel_function() {
    let (r, c) = fresnel_unpolarized(1.4, 1.0, 1.0);
    assert!(
        (r - (0.4f64 / 2.4).powi(2)).abs() < 1e-15 && (c - 1.0).abs() < 1e-15,
        "normal incidence: R {r} vs {}, cosine {c}",
        (0.4f64 / 2.4).powi(2)
    );
    let crit = (1.0f64 / 1.4).asin();
    assert_eq!(fresnel_unpolarized(1.4, 1.0, (crit + 1e-6).cos()).0, 1.0);
    let below = fresnel_unpolarized(1.4, 1.0, (crit - 1e-3).cos()).0;
    assert!(below < 1.0, "1e-3 rad inside the critical angle {crit}: R {below}");
    let (x, w) = gauss_legendre_01(400);
    let diffuse = |n1: f64, n2: f64| -> f64 {
        // Split at the critical angle for the internal case so the quadrature sees smooth pieces.
        let mu_c = if n1 > n2 { (1.0 - (n2 / n1).powi(2)).sqrt() } else { 0.0 };
        let tir = mu_c * mu_c; // 2 * int_0^mu_c mu dmu
        let span = 1.0 - mu_c;
        tir + x
            .iter()
            .zip(&w)
            .map(|(&xi, &wi)| {
                let mu = mu_c + span * xi;
                2.0 * span * wi * mu * fresnel_unpolarized(n1, n2, mu).0
            })
            .sum::<f64>()
    };
    let (ri, re) = (diffuse(1.4, 1.0), diffuse(1.0, 1.4));
    println!("diffuse Fresnel n = 1.4: internal {ri:.5}, external {re:.5}");
    assert!((ri - (1.0 - (1.0 - re) / 1.96)).abs() < 1e-6, "internal {ri} vs 1 - (1 - {re}) / 1.96");
    let eta = 1.4f64;
    let fdr_fit = -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta;
    assert!((ri - fdr_fit).abs() < 0.015, "{ri} vs fit {fdr_fit}");
}

/// (iv) Exit positions and oblique Fresnel: the single-scattering radial profile of a semi-infinite
/// medium at normal incidence, which has a closed form up to one integral over the exit cosine mu.
/// A photon scattered once at depth z leaves at r = z tan(theta) with probability
/// e^(-sigma_t z / mu) (1 - F(mu)), so the fraction leaving in the annulus [r0, r1) is
/// (1/2) int_0^1 (1 - F(mu)) [e^(-sigma_t c r0 / t) - e^(-sigma_t c r1 / t)] / c dmu,
/// with t = tan(theta) = sqrt(1 - mu^2)/mu and c = 1 + 1/mu. The MC stops photons at their second collision.
#[test]
fn mc_single_scattering_radial_profile() {
    let sigma_t = 2.0;
    let edges = log_edges(0.01 / sigma_t, 10.0 / sigma_t, 15, true);
    let (x, w) = gauss_legendre_01(64);
    for (ior, seed) in [(1.0f64, 41u64), (1.4, 42)] {
        // Exit cosines below mu_c are totally reflected. Substituting mu = mu_c + (1 - mu_c) u^2
        // removes the square-root behaviour of F at mu_c; 40 panels of 64 nodes in u.
        let mu_c = if ior > 1.0 { (1.0 - 1.0 / (ior * ior)).sqrt() } else { 0.0 };
        let escape_in = |r0: f64, r1: f64| -> f64 {
            let panels = 40;
            let mut sum = 0.0;
            for p in 0..panels {
                for (xi, wi) in x.iter().zip(&w) {
                    let u = (p as f64 + xi) / panels as f64;
                    let du = wi / panels as f64;
                    let mu = mu_c + (1.0 - mu_c) * u * u;
                    let dmu = 2.0 * (1.0 - mu_c) * u * du;
                    if mu <= 0.0 {
                        continue;
                    }
                    let t = (1.0 - mu * mu).max(0.0).sqrt() / mu;
                    let c = 1.0 + 1.0 / mu;
                    let far = |r: f64| {
                        if r.is_infinite() {
                            0.0
                        } else if r == 0.0 {
                            1.0
                        } else {
                            (-sigma_t * c * r / t).exp()
                        }
                    };
                    let transmit = 1.0 - fresnel_unpolarized(ior, 1.0, mu).0;
                    sum += 0.5 * transmit * (far(r0) - far(r1)) / c * dmu;
                }
            }
            sum
        };
        let mut cfg = McConfig::new(1_000_000, seed, edges.clone());
        cfg.max_collisions_per_photon = 1;
        let mc = simulate(&semi_infinite(0.0, sigma_t, ior), &cfg);
        let total = escape_in(0.0, f64::INFINITY);
        if ior == 1.0 {
            assert!((total - 0.5 * (1.0 - std::f64::consts::LN_2)).abs() < 1e-9, "closed form {total}");
        }
        println!(
            "single scattering, ior {ior}: R1 exact {total:.5}, MC {:.5} +- {:.5}",
            mc.reflectance, mc.reflectance_se
        );
        assert!(
            (mc.reflectance - total).abs() < 4.0 * mc.reflectance_se,
            "ior {ior}: MC {} +- {} vs exact {total}",
            mc.reflectance,
            mc.reflectance_se
        );
        let mut worst: f64 = 0.0;
        for k in 0..edges.len() - 1 {
            let area = annulus_area(edges[k], edges[k + 1]);
            let got = mc.profile_per_mm2[k] * area;
            let expect = escape_in(edges[k], edges[k + 1]);
            // Every weight is 1 here, so the count in a bin is binomial.
            let se = (expect * (1.0 - expect) / mc.photons as f64).sqrt().max(1e-7);
            worst = worst.max((got - expect).abs() / se);
            assert!(
                (got - expect).abs() < 4.5 * se,
                "ior {ior}, bin {}..{} mm: MC {got} +- {se}, exact {expect}",
                edges[k],
                edges[k + 1]
            );
        }
        let over = escape_in(edges[edges.len() - 1], f64::INFINITY);
        assert!(
            (mc.reflectance_beyond_last_edge - over).abs() < 4.5 * (over / 1e6).sqrt() + 1e-6,
            "ior {ior}: beyond {} mm: MC {} vs exact {over}",
            edges[edges.len() - 1],
            mc.reflectance_beyond_last_edge
        );
        println!("single scattering, ior {ior}: {} radial bins, worst deviation {worst:.2} se", edges.len() - 1);
    }
}

/// (iii) Semi-infinite, index-matched, isotropic scattering at normal incidence:
/// R = 1 - H(1) sqrt(1 - a) (Chandrasekhar's plane albedo).
#[test]
fn mc_matches_chandrasekhar_plane_albedo() {
    for (a, seed) in [(0.5, 21u64), (0.9, 22), (0.99, 23)] {
        let h1 = chandrasekhar_h(a, 1.0);
        let expect = 1.0 - h1 * (1.0 - a).sqrt();
        let r = simulate(&semi_infinite(1.0 - a, a, 1.0), &McConfig::new(400_000, seed, vec![]));
        let diff = r.reflectance - expect;
        println!(
            "Chandrasekhar a = {a}: H(1) = {h1:.6}, R_exact = {expect:.5}, R_mc = {:.5} +- {:.5} ({:+.2} se)",
            r.reflectance,
            r.reflectance_se,
            diff / r.reflectance_se
        );
        assert!(diff.abs() < 4.0 * r.reflectance_se + 5e-4, "a = {a}: MC {} vs exact {expect}", r.reflectance);
    }
}

/// Bookkeeping and determinism: every photon's weight ends up reflected, transmitted or
/// absorbed; the radial histogram adds up to the reflectance; the same seed gives identical results.
#[test]
fn mc_bookkeeping_and_determinism() {
    let layers = vec![
        McLayer { thickness_mm: 0.25, sigma_a_per_mm: 1.0, sigma_s_per_mm: 6.0, ior: 1.4 },
        McLayer { thickness_mm: 0.5, sigma_a_per_mm: 0.2, sigma_s_per_mm: 3.0, ior: 1.33 },
        McLayer { thickness_mm: 2.0, sigma_a_per_mm: 0.1, sigma_s_per_mm: 2.0, ior: 1.5 },
    ];
    let cfg = McConfig::new(50_000, 31, log_edges(0.01, 5.0, 20, true));
    let a = simulate(&layers, &cfg);
    let b = simulate(&layers, &cfg);
    let total = a.reflectance + a.transmittance + a.absorbed + a.unfinished;
    println!("three layers: R {:.5} T {:.5} A {:.5} sum {total}", a.reflectance, a.transmittance, a.absorbed);
    assert!((total - 1.0).abs() < 1e-9, "energy balance {total}");
    let cdf = a.cumulative_reflectance_at_edges();
    assert!(
        (cdf.last().unwrap() + a.reflectance_beyond_last_edge - a.reflectance).abs() < 1e-12,
        "histogram {} + beyond {} vs R {}",
        cdf.last().unwrap(),
        a.reflectance_beyond_last_edge,
        a.reflectance
    );
    assert!(a.transmittance > 0.0 && a.reflectance > 0.0, "T {} R {}", a.transmittance, a.reflectance);
    assert_eq!(a.reflectance.to_bits(), b.reflectance.to_bits());
    assert_eq!(a.profile_per_mm2, b.profile_per_mm2);
    let c = simulate(&layers, &McConfig { seed: 32, ..cfg });
    assert_ne!(a.reflectance, c.reflectance);
}

// ---------------------------------------------------------------------------------------------
// (b) Diffusion against Monte Carlo.
//
// What to expect. The totals agree to a few per cent for high albedo. The profile *shape* does not
// agree as well: the classical dipole/multipole puts the whole collimated source at one depth
// (1 transport mean free path), so near the entry point it is too flat and too low, it overshoots by
// up to ~65 % around 0.5-2 mfp, and it sits 10-20 % low in the far tail (same decay rate). That is a
// property of the model, not of this solver: a textbook dipole written independently gives the same
// ratios against this MC (e.g. albedo 0.99, n = 1: +30 % at 1.7 mfp), while the MC's own exit
// positions are checked exactly by `mc_single_scattering_radial_profile`. The profile bounds below
// are therefore set from the measured model error with margin, and chosen to catch scale errors
// (a wrong length unit, transport coefficient or boundary) rather than to demand accuracy the
// model does not have.

/// What one comparison measured (printed whole by a failing assertion).
#[derive(Debug)]
#[allow(dead_code)]
struct Comparison {
    r_diffusion: f64,
    r_mc: f64,
    r_mc_se: f64,
    /// (diffusion - MC) / MC for the total diffuse reflectance.
    rel_total: f64,
    /// Root mean square of (diffusion - MC) / MC over the profile bins between `lo_mfp` and `hi_mfp`.
    profile_rms: f64,
    /// The signed (diffusion - MC) / MC of largest magnitude over those bins, and that bin's radius (mm).
    profile_worst: (f64, f64),
    /// Largest difference of the normalised radial CDFs (share of the reflectance within r) over all edges.
    cdf_max: f64,
    /// Radii (mm) holding 50 % and 90 % of the reflectance: (diffusion, MC).
    r50: (f64, f64),
    r90: (f64, f64),
    /// Logarithmic decay rates -d ln R / dr (mm^-1) between 5 and 15 mfp: (diffusion, MC).
    tail_decay: (f64, f64),
    /// 2 pi int_0^{20 mfp} R(r) r dr of the diffusion profile divided by the diffusion total.
    profile_integral_ratio: f64,
}

/// Gauss-Legendre nodes per bin, for averaging the diffusion profile over annuli.
const NODES_PER_BIN: usize = 6;

/// Least-squares slope of ln(values) against radius over the bins whose centres lie in [lo, hi].
fn log_slope(centres: &[f64], values: &[f64], lo: f64, hi: f64) -> f64 {
    let pts: Vec<(f64, f64)> = centres
        .iter()
        .zip(values)
        .filter(|(r, v)| **r >= lo && **r <= hi && **v > 0.0)
        .map(|(r, v)| (*r, v.ln()))
        .collect();
    assert!(pts.len() >= 3, "too few bins for a slope in [{lo}, {hi}] mm: {pts:?}");
    let n = pts.len() as f64;
    let (mx, my) = (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    sxy / sxx
}

/// Runs both solvers on `layers` and compares totals and profiles. Bins: a central disc, then
/// 8 log-spaced bins per decade from 0.02 to 20 transport mean free paths `mfp_mm`; the profile is
/// compared bin by bin between `lo_mfp` and `hi_mfp` mfp. `MC_DUMP=1` prints every bin.
fn compare(name: &str, layers: &[Layer], photons: u64, seed: u64, mfp_mm: f64, lo_mfp: f64, hi_mfp: f64) -> Comparison {
    let mc_layers = McLayer::isotropic_stack(layers);
    let edges = log_edges(0.02 * mfp_mm, 20.0 * mfp_mm, 24, true);
    let nbins = edges.len() - 1;
    let start = std::time::Instant::now();
    let mc: McResult = simulate(&mc_layers, &McConfig::new(photons, seed, edges.clone()));
    let mc_seconds = start.elapsed().as_secs_f64();

    // Diffusion profile at Gauss nodes in every bin (weights include the 2 pi r area element).
    let (x, w) = gauss_legendre_01(NODES_PER_BIN);
    let mut radii = Vec::new();
    let mut area_weights = Vec::new();
    for k in 0..nbins {
        let (a, b) = (edges[k], edges[k + 1]);
        for (xi, wi) in x.iter().zip(&w) {
            let r = a + (b - a) * xi;
            radii.push(r);
            area_weights.push(2.0 * std::f64::consts::PI * r * (b - a) * wi);
        }
    }
    let start = std::time::Instant::now();
    let (r_diffusion, profile) = multipole_reflectance(layers, &radii).expect("diffusion solver");
    let diffusion_seconds = start.elapsed().as_secs_f64();
    assert!(
        r_diffusion.is_finite() && profile.iter().all(|v| v.is_finite()),
        "{name}: non-finite diffusion output: total {r_diffusion}, profile {profile:?}"
    );
    let bin_weight: Vec<f64> = (0..nbins)
        .map(|k| (0..NODES_PER_BIN).map(|j| profile[k * NODES_PER_BIN + j] * area_weights[k * NODES_PER_BIN + j]).sum())
        .collect();
    let diff_bins: Vec<f64> = (0..nbins).map(|k| bin_weight[k] / annulus_area(edges[k], edges[k + 1])).collect();
    let centres: Vec<f64> =
        (0..nbins).map(|k| if k == 0 { 0.5 * edges[1] } else { (edges[k] * edges[k + 1]).sqrt() }).collect();
    if std::env::var("MC_DUMP").is_ok() {
        for k in 0..nbins {
            println!(
                "  {name}: bin {:.4}-{:.4} mm: diffusion {:.4e}, MC {:.4e} +- {:.1e}, ratio {:.3}",
                edges[k],
                edges[k + 1],
                diff_bins[k],
                mc.profile_per_mm2[k],
                mc.profile_se_per_mm2[k],
                diff_bins[k] / mc.profile_per_mm2[k]
            );
        }
    }

    // Profile bins fully inside [lo, hi].
    let (lo, hi) = (lo_mfp * mfp_mm, hi_mfp * mfp_mm);
    let mut sq = 0.0;
    let mut se_sq = 0.0;
    let mut count = 0;
    let mut worst = (0.0f64, 0.0);
    for k in 0..nbins {
        if edges[k] < lo * (1.0 - 1e-9) || edges[k + 1] > hi * (1.0 + 1e-9) {
            continue;
        }
        let mc_bin = mc.profile_per_mm2[k];
        assert!(mc_bin > 0.0, "{name}: empty MC bin at {}..{} mm: {mc_bin}", edges[k], edges[k + 1]);
        let rel = (diff_bins[k] - mc_bin) / mc_bin;
        sq += rel * rel;
        se_sq += (mc.profile_se_per_mm2[k] / mc_bin).powi(2);
        count += 1;
        if rel.abs() > worst.0.abs() {
            worst = (rel, centres[k]);
        }
    }
    assert!(count >= 6, "{name}: only {count} profile bins in range");
    let profile_rms = (sq / count as f64).sqrt();
    let profile_mc_rel_se = (se_sq / count as f64).sqrt();

    // Normalised radial CDFs at the edges.
    let mc_cdf: Vec<f64> = mc.cumulative_reflectance_at_edges().iter().map(|c| c / mc.reflectance).collect();
    let mut diff_cdf = vec![0.0];
    for k in 0..nbins {
        diff_cdf.push(diff_cdf[k] + bin_weight[k] / r_diffusion);
    }
    let cdf_max = diff_cdf.iter().zip(&mc_cdf).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    let profile_integral_ratio = diff_cdf[nbins];
    let r50 = (radius_at(&edges, &diff_cdf, 0.5), radius_at(&edges, &mc_cdf, 0.5));
    let r90 = (radius_at(&edges, &diff_cdf, 0.9), radius_at(&edges, &mc_cdf, 0.9));
    let tail_decay = (
        -log_slope(&centres, &diff_bins, 5.0 * mfp_mm, 15.0 * mfp_mm),
        -log_slope(&centres, &mc.profile_per_mm2, 5.0 * mfp_mm, 15.0 * mfp_mm),
    );

    let rel_total = (r_diffusion - mc.reflectance) / mc.reflectance;
    println!(
        "{name}: R_diffusion = {r_diffusion:.5}, R_MC = {:.5} +- {:.5} ({photons} photons, T_MC = {:.4}): rel. diff {:+.2} % ({:+.0} MC se)",
        mc.reflectance,
        mc.reflectance_se,
        mc.transmittance,
        100.0 * rel_total,
        (r_diffusion - mc.reflectance) / mc.reflectance_se
    );
    println!(
        "{name}: profile over {lo_mfp}-{hi_mfp} mfp ({lo:.3}-{hi:.3} mm, {count} bins): rms rel. diff {:.1} % (MC rel. se {:.1} %), worst {:+.1} % at r = {:.3} mm; max |CDF diff| {:.3}",
        100.0 * profile_rms,
        100.0 * profile_mc_rel_se,
        100.0 * worst.0,
        worst.1,
        cdf_max,
    );
    println!(
        "{name}: r50 diffusion {:.4} / MC {:.4} mm, r90 {:.4} / {:.4} mm, tail decay (5-15 mfp) {:.3} / {:.3} mm^-1, diffusion profile integral to {:.2} mm / total = {:.4}",
        r50.0, r50.1, r90.0, r90.1, tail_decay.0, tail_decay.1, edges[nbins], profile_integral_ratio
    );
    println!(
        "{name}: MC {:.2} s ({:.1} M scattering events/s), diffusion {:.3} s for {} radii",
        mc_seconds,
        mc.scattering_events as f64 / mc_seconds / 1e6,
        diffusion_seconds,
        radii.len()
    );
    Comparison {
        r_diffusion,
        r_mc: mc.reflectance,
        r_mc_se: mc.reflectance_se,
        rel_total,
        profile_rms,
        profile_worst: worst,
        cdf_max,
        r50,
        r90,
        tail_decay,
        profile_integral_ratio,
    }
}

fn transport_mfp_mm(l: &Layer) -> f64 {
    1.0 / (l.sigma_a_per_mm + l.sigma_s_reduced_per_mm)
}

/// Bounds for a high-albedo case: measured model error plus margin (see the section comment).
fn assert_high_albedo_agreement(c: &Comparison) {
    // Total: measured +4.1 % (semi-infinite dermis) and +0.6 % (two layers). A(1.0) in place of
    // A(1.4) moves the dipole total by ~+35 %, the symmetric combination by ~+18 %.
    assert!(c.rel_total.abs() < 0.08, "total diffuse reflectance: {c:?}");
    // The diffusion profile must integrate to its own total.
    assert!((c.profile_integral_ratio - 1.0).abs() < 0.02, "profile integral vs total: {c:?}");
    // Shape: measured rms ~36-38 %, CDF difference ~0.12, r50 within ~10 %, r90 within ~5 %.
    assert!(c.profile_rms < 0.5, "profile rms: {c:?}");
    assert!(c.cdf_max < 0.18, "radial CDF: {c:?}");
    assert!((c.r50.0 / c.r50.1 - 1.0).abs() < 0.25, "r50: {c:?}");
    assert!((c.r90.0 / c.r90.1 - 1.0).abs() < 0.2, "r90: {c:?}");
    // Far tail: same exponential decay (diffusion's sigma_tr against transport's), within 10 %.
    assert!((c.tail_decay.0 / c.tail_decay.1 - 1.0).abs() < 0.1, "tail decay: {c:?}");
}

/// Homogeneous semi-infinite skin-like medium: the Caucasian dermis at 550 nm on its own
/// (albedo 0.948, ior 1.4): a single dipole.
#[test]
fn diffusion_vs_mc_caucasian_dermis_550_semi_infinite() {
    let [_, dermis] = skin_layers(&SkinParams::preset("caucasian").unwrap(), &SkinModel::default(), 550.0);
    let c = compare("caucasian dermis 550 nm", &[dermis], 1_000_000, 101, transport_mfp_mm(&dermis), 0.3, 5.0);
    assert_high_albedo_agreement(&c);
}

/// Two-layer Caucasian skin at 550 nm: epidermis 0.25 mm over a semi-infinite dermis, ior 1.4
/// both. Radii in units of the dermis mean free path (0.31 mm), where most of the light spreads.
#[test]
fn diffusion_vs_mc_caucasian_two_layer_550() {
    let layers = skin_layers(&SkinParams::preset("caucasian").unwrap(), &SkinModel::default(), 550.0);
    let c = compare("caucasian two-layer 550 nm", &layers, 1_000_000, 102, transport_mfp_mm(&layers[1]), 0.3, 5.0);
    assert_high_albedo_agreement(&c);
}

/// Two-layer African skin at 450 nm: epidermis albedo about 0.17 and 13 mean free paths thick,
/// where diffusion is known to be poor. A documented measurement: only finiteness and a loose
/// bound on the total are asserted (measured: diffusion ~40 % above MC).
#[test]
fn diffusion_vs_mc_african_two_layer_450_low_albedo() {
    let layers = skin_layers(&SkinParams::preset("african").unwrap(), &SkinModel::default(), 450.0);
    let epi = layers[0];
    println!(
        "african two-layer 450 nm: epidermis albedo {:.3}, mfp {:.4} mm",
        epi.sigma_s_reduced_per_mm / (epi.sigma_a_per_mm + epi.sigma_s_reduced_per_mm),
        transport_mfp_mm(&epi)
    );
    let c = compare("african two-layer 450 nm", &layers, 1_000_000, 103, transport_mfp_mm(&epi), 0.3, 5.0);
    assert!(c.r_diffusion > 0.0 && c.r_mc > 0.0, "{c:?}");
    assert!(c.rel_total.abs() < 1.0, "total: {c:?}");
    assert!((c.profile_integral_ratio - 1.0).abs() < 0.02, "profile integral vs total: {c:?}");
}
