//! The exact profile shapes (data/profile_table.bin, src/transport/profile_table.rs) checked three ways:
//! - the table's totals against adding-doubling (a solver of the transfer equation sharing no code with the walk);
//! - the table's interpolated shape against fresh white walks at points between its nodes (the table and its
//!   interpolation, not the physics);
//! - the product's profiles and radii (`layered_reflectance`, `evaluate`) against the analog Monte Carlo of
//!   tests/support/mc.rs (absorption by weight, no white walk, no table): r50, r90, the fitted Burley d and R(r), for
//!   homogeneous and two-layer stacks from fair to very dark skin, thin and thick epidermis, 450, 550 and 650 nm.
//!
//! Run with `cargo test --release --test physics exact_profile -- --nocapture` to see the figures.

#[path = "../../examples/profile_table/walk.rs"]
mod walk;

use crate::support::mc::{log_edges, simulate, McConfig, McLayer};
use spectral_skin::diffusion::Layer;
use spectral_skin::diffusion::{layered_reflectance_with, Combination, LayerStack, LayeredOptions, MultipoleTerms};
use spectral_skin::fit::burley::{fit_burley, fit_frequencies};
use spectral_skin::skin::{skin_layers, SkinModel, SkinParams};
use spectral_skin::transport::profile_table::exact_shape;
use spectral_skin::transport::profile_table::{
    absorption_nodes, entries_from_moments, k_nodes, tau_nodes, ProfileTable, TableStack, MAX_PATH_MFP, R_BINS, SLICES,
};
use spectral_skin::transport::{total_diffuse_reflectance, Transport};

/// The dimensionless stack of a table node as layers in mm (mean free path 1 mm).
fn node_layers(tau: Option<f64>, a_top: f64, a_bottom: f64, ratio: f64) -> Vec<Layer> {
    let top = |thickness_mm| Layer { thickness_mm, sigma_a_per_mm: a_top, sigma_s_reduced_per_mm: 1.0, ior: 1.4 };
    match tau {
        None => vec![top(f64::INFINITY)],
        Some(t) => vec![
            top(t),
            Layer { thickness_mm: f64::INFINITY, sigma_a_per_mm: a_bottom, sigma_s_reduced_per_mm: ratio, ior: 1.4 },
        ],
    }
}

/// Every slice's totals at a spread of absorption pairs equal adding-doubling's (32 streams) within the photon noise:
/// the walk's physics (Fresnel top, layers, path lengths) checked by an independent solver.
#[test]
fn table_totals_equal_adding_doubling() {
    let table = ProfileTable::shipped();
    let (a, taus) = (absorption_nodes(), tau_nodes());
    let ratio = table.provenance.bottom_scattering_ratio;
    let mut worst = (0.0f64, String::new());
    for slice in 0..SLICES {
        let tau = taus.get(slice).copied();
        for (i, j) in [(0, 0), (4, 9), (8, 2), (10, 12), (13, 5), (16, 16), (19, 3)] {
            let node = table.node(slice, i, j);
            let exact = total_diffuse_reflectance(&node_layers(tau, a[i], a[j], ratio), 32).unwrap();
            // Relative standard error of a mean of photons each carrying weight 0 or <= 1: sqrt((1 - R) / (N R)).
            let se = ((1.0 - exact) / (table.provenance.photons as f64 * exact)).sqrt();
            let rel = node.total / exact - 1.0;
            if rel.abs() / (se + 1e-3) > worst.0 {
                worst = (rel.abs() / (se + 1e-3), format!("slice {slice} a ({}, {}): {rel:+.2e}", a[i], a[j]));
            }
            assert!(
                rel.abs() <= 4.0 * se + 2e-3,
                "slice {slice} (tau {tau:?}), a_top {} a_bottom {}: table total {} vs adding-doubling {exact} \
                 ({rel:+.2e}, photon noise {se:.1e})",
                a[i],
                a[j],
                node.total
            );
        }
    }
    println!("table totals vs adding-doubling, worst relative to (noise + 1e-3): {:.2} at {}", worst.0, worst.1);
}

/// Between the nodes the interpolated shape equals a fresh walk's at that very stack: the transform and the encircled
/// energy within 0.01, at four points off every node.
#[test]
fn table_shape_matches_fresh_walks_between_nodes() {
    let table = ProfileTable::shipped();
    let ratio = table.provenance.bottom_scattering_ratio;
    let k = k_nodes();
    for (tau, a_top, a_bottom, seed) in [
        (Some(0.37), 0.031, 0.0042, 11),
        (Some(2.1), 0.7, 0.05, 12),
        (Some(0.09), 6.5, 0.33, 13),
        (None, 0.15, 0.15, 14),
    ] {
        let w = walk::WhiteWalk {
            tau: tau.unwrap_or(f64::INFINITY),
            bottom_scattering: ratio,
            ior: 1.4,
            photons: 200_000,
            seed,
            max_path: MAX_PATH_MFP,
        };
        let fresh = &entries_from_moments(&walk::run(&w, &[a_top], &[a_bottom]).moments)[0];
        let shape = table.shape(&TableStack { tau, a_top, a_bottom, mfp_mm: 1.0 });
        let worst_n = k
            .iter()
            .zip(&fresh.transform)
            .map(|(&kq, &f)| (shape.normalized_transform(kq) - f).abs())
            .fold(0.0f64, f64::max);
        // The encircled energy (its cumulative sum over the bins) rather than each bin, whose photon noise in the
        // fresh walk is several per cent.
        let width = std::f64::consts::LN_10 / 10.0;
        let (mut table_cdf, mut fresh_cdf, mut worst_q) = (0.0, 0.0, 0.0f64);
        for c in 0..R_BINS {
            let r = 10f64.powf(-5.0 + (c as f64 + 0.5) / 10.0);
            table_cdf += shape.normalized_profile_per_mm2(r) * 2.0 * std::f64::consts::PI * r * r * width;
            fresh_cdf += fresh.energy_per_ln_r[c] * width;
            worst_q = worst_q.max((table_cdf - fresh_cdf).abs());
        }
        println!("tau {tau:?} a ({a_top}, {a_bottom}): |N - fresh| <= {worst_n:.4}, |encircled energy - fresh| <= {worst_q:.4}");
        assert!(worst_n < 0.01, "tau {tau:?} a ({a_top}, {a_bottom}): transform off by {worst_n}");
        assert!(worst_q < 0.01, "tau {tau:?} a ({a_top}, {a_bottom}): encircled energy off by {worst_q}");
    }
}

/// The stacks of the acceptance: presets from fair to very dark at 450, 550 and 650 nm with the paper's 0.25 mm
/// epidermis, a thin (0.06 mm) and a thick (0.5 mm) epidermis, and homogeneous (one semi-infinite layer) stacks.
fn acceptance_stacks() -> Vec<(String, Vec<Layer>)> {
    let preset = |name: &str, epidermis_mm: Option<f64>, nm: f64| {
        let mut p = SkinParams::preset(name).unwrap();
        if let Some(d) = epidermis_mm {
            p.epidermis_thickness_mm = d;
        }
        skin_layers(&p, &SkinModel::default(), nm).to_vec()
    };
    let mut out = Vec::new();
    for nm in [450.0, 550.0, 650.0] {
        for name in ["caucasian", "measured-medium", "asian", "african"] {
            out.push((format!("{name} {nm} nm"), preset(name, None, nm)));
        }
        out.push((format!("caucasian, 0.06 mm epidermis, {nm} nm"), preset("caucasian", Some(0.06), nm)));
        out.push((format!("african, 0.06 mm epidermis, {nm} nm"), preset("african", Some(0.06), nm)));
        out.push((format!("asian, 0.5 mm epidermis, {nm} nm"), preset("asian", Some(0.5), nm)));
        let [epi, derm] = preset("asian", None, nm)[..] else { unreachable!() };
        out.push((format!("homogeneous dermis {nm} nm"), vec![Layer { thickness_mm: f64::INFINITY, ..derm }]));
        out.push((
            format!("homogeneous epidermis (asian) {nm} nm"),
            vec![Layer { thickness_mm: f64::INFINITY, ..epi }],
        ));
    }
    out
}

/// A radial profile's figures: encircled-energy radii and the Burley d of the project's edge fit.
struct Figures {
    r50: f64,
    r90: f64,
    d: f64,
}

/// The acceptance of the exact shapes: against the analog Monte Carlo (tests/support/mc.rs), r50 and r90 within 10 %,
/// the fitted Burley d within 5 %, and R(r) averaged over each annulus (four bins) within 10 % wherever the Monte
/// Carlo's is above 1e-3 of its peak and known to 4 %; for every stack of [`acceptance_stacks`]. The diffusion shape's figures (the
/// shape before) are printed beside.
#[test]
fn exact_profiles_against_monte_carlo() {
    let (x, w) = gauss_legendre_01(8);
    let s = fit_frequencies(4.0);
    let mut worst = [0.0f64; 4];
    for (k, (name, layers)) in acceptance_stacks().into_iter().enumerate() {
        let derm = layers.last().unwrap();
        let mfp_mm = 1.0 / (derm.sigma_a_per_mm + derm.sigma_s_reduced_per_mm);
        let edges = log_edges(1e-4, 60.0 * mfp_mm, 72, true);
        let mc = simulate(&McLayer::isotropic_stack(&layers), &McConfig::new(300_000, 900 + k as u64, edges.clone()));
        // Monte Carlo figures: its encircled energy, and its transform from the binned profile (J0 averaged over each
        // annulus with the area weight).
        let mc_cdf: Vec<f64> = mc.cumulative_reflectance_at_edges().iter().map(|c| c / mc.reflectance).collect();
        let mc_n: Vec<f64> = s
            .iter()
            .map(|&sq| {
                let mut acc = mc.reflectance_below_first_edge;
                for b in 0..edges.len() - 1 {
                    let (a, bb) = (edges[b], edges[b + 1]);
                    let mean_j0: f64 = x
                        .iter()
                        .zip(&w)
                        .map(|(xi, wi)| {
                            let r = a + (bb - a) * xi;
                            wi * libm::j0(sq * r) * 2.0 * r * (bb - a) / (bb * bb - a * a)
                        })
                        .sum();
                    acc += mc.profile_per_mm2[b] * std::f64::consts::PI * (bb * bb - a * a) * mean_j0;
                }
                acc / mc.reflectance
            })
            .collect();
        let truth = Figures {
            r50: radius_at(&edges, &mc_cdf, 0.5),
            r90: radius_at(&edges, &mc_cdf, 0.9),
            d: fit_burley(&s, &mc_n).d_mm,
        };
        // The product's profile (layered_reflectance, default transport) averaged over each annulus.
        let options = LayeredOptions::default();
        let mut model_bins = Vec::new();
        let mut cdf = vec![0.0];
        let (mut acc, mut total) = (0.0, 0.0);
        for b in 0..edges.len() - 1 {
            let (a, bb) = (edges[b], edges[b + 1]);
            let radii: Vec<f64> = x.iter().map(|xi| a + (bb - a) * xi).collect();
            let r = layered_reflectance_with(&layers, &radii, &options).unwrap();
            assert_eq!(r.shape.name(), "exact", "{name}: the table must hold every acceptance stack");
            total = r.total;
            let inside: f64 = radii
                .iter()
                .zip(&r.profile_per_mm2)
                .zip(&w)
                .map(|((r, p), wi)| 2.0 * std::f64::consts::PI * r * p * (bb - a) * wi)
                .sum();
            model_bins.push(inside / (std::f64::consts::PI * (bb * bb - a * a)));
            acc += inside;
            cdf.push(acc);
        }
        // The disc below the first edge holds the 1/r near field: its share from the shape.
        let cdf: Vec<f64> = cdf.iter().map(|c| c / total).collect();
        let shape = exact_shape(&layers).unwrap();
        let model_n: Vec<f64> = s.iter().map(|&sq| shape.normalized_transform(sq)).collect();
        let model = Figures {
            r50: radius_at(&edges, &cdf, 0.5),
            r90: radius_at(&edges, &cdf, 0.9),
            d: fit_burley(&s, &model_n).d_mm,
        };
        // Before: the multipole's shape.
        let stack = LayerStack::new(&layers).unwrap();
        let m0 = stack.reflectance_hat(0.0, Combination::Directional, MultipoleTerms::All);
        let diffusion_n: Vec<f64> =
            s.iter().map(|&sq| stack.reflectance_hat(sq, Combination::Directional, MultipoleTerms::All) / m0).collect();
        let diffusion_d = fit_burley(&s, &diffusion_n).d_mm;
        // R(r) over annuli of four bins each (one bin's photon noise is too large to test 10 % against).
        let area = |b: usize| std::f64::consts::PI * (edges[b + 1].powi(2) - edges[b].powi(2));
        let groups: Vec<(f64, f64, f64)> = (0..model_bins.len() / 4)
            .map(|g| {
                let bins = 4 * g..4 * g + 4;
                let a: f64 = bins.clone().map(area).sum();
                let mc_mean: f64 = bins.clone().map(|b| mc.profile_per_mm2[b] * area(b)).sum::<f64>() / a;
                let mc_se = bins.clone().map(|b| (mc.profile_se_per_mm2[b] * area(b)).powi(2)).sum::<f64>().sqrt() / a;
                let model_mean: f64 = bins.map(|b| model_bins[b] * area(b)).sum::<f64>() / a;
                (model_mean, mc_mean, mc_se)
            })
            .collect();
        let peak = groups.iter().map(|g| g.1).fold(0.0f64, f64::max);
        let compared: Vec<&(f64, f64, f64)> = groups.iter().filter(|g| g.1 > 1e-3 * peak && g.2 < 0.04 * g.1).collect();
        assert!(compared.len() >= 3, "{name}: only {} annuli known well enough to compare", compared.len());
        let worst_r = compared.iter().map(|g| (g.0 / g.1 - 1.0).abs()).fold(0.0f64, f64::max);
        let rel = |m: f64, t: f64| m / t - 1.0;
        let errors = [rel(model.r50, truth.r50), rel(model.r90, truth.r90), rel(model.d, truth.d), worst_r];
        println!(
            "{name}: r50 {:.4} / MC {:.4} mm ({:+.1} %), r90 {:.4} / {:.4} ({:+.1} %), d {:.4} / {:.4} ({:+.1} %; \
             diffusion shape {:+.1} %), R(r) within {:.1} % ({} annuli)",
            model.r50,
            truth.r50,
            100.0 * errors[0],
            model.r90,
            truth.r90,
            100.0 * errors[1],
            model.d,
            truth.d,
            100.0 * errors[2],
            100.0 * rel(diffusion_d, truth.d),
            100.0 * worst_r,
            compared.len()
        );
        for (w, e) in worst.iter_mut().zip(errors) {
            *w = w.max(e.abs());
        }
        assert!(
            errors[0].abs() < 0.10 && errors[1].abs() < 0.10,
            "{name}: r50 {} / {}, r90 {} / {}",
            model.r50,
            truth.r50,
            model.r90,
            truth.r90
        );
        assert!(errors[2].abs() < 0.05, "{name}: Burley d {} vs MC {}", model.d, truth.d);
        assert!(worst_r < 0.10, "{name}: R(r) off by {worst_r} where the MC is above 1e-3 of its peak");
    }
    println!(
        "worst: r50 {:.1} %, r90 {:.1} %, d {:.1} %, R(r) {:.1} %",
        100.0 * worst[0],
        100.0 * worst[1],
        100.0 * worst[2],
        100.0 * worst[3]
    );
    let _ = Transport::default();
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
