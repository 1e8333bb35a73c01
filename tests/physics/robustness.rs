//! Regression tests for the hard cases of issue 10: each reproducer gets a right answer (against an independent
//! reference computed here) or a clear error. The property tests over the whole domain are in
//! `tests/physics/robustness_properties.rs`.

use std::f64::consts::PI;

use crate::support::mc::{simulate, McConfig, McLayer};
use spectral_skin::accuracy::ProfileGrid;
use spectral_skin::diffusion::{
    raw_reflectance_profiles, reflectance_profiles, Boundaries, ClampedProfiles, Combination, HankelQuadrature,
    LayerStack, MultipoleTerms, PEAK_PROBE_MM, ROUND_OFF_OF_PEAK,
};
use spectral_skin::evaluate::Prepared;
use spectral_skin::fit::SubsurfaceMethod;
use spectral_skin::layer::Layer;
use spectral_skin::reflectance::{
    layered_reflectance, layered_reflectance_with, multipole_reflectance, LayeredOptions,
};
use spectral_skin::skin::{skin_layers, SkinModel};
use spectral_skin::transport::Transport;
use spectral_skin::{Outputs, Request, SkinParams};

const INF: f64 = f64::INFINITY;

fn layer(thickness_mm: f64, sigma_a_per_mm: f64, sigma_s_reduced_per_mm: f64, ior: f64) -> Layer {
    Layer { thickness_mm, sigma_a_per_mm, sigma_s_reduced_per_mm, ior }
}

/// Gauss-Legendre nodes and weights on [-1, 1] (Golub-Welsch would do; Newton on P_n is enough here).
fn gauss(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let mut z = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 0.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, 0.0);
                for j in 0..n {
                    let p2 = p1;
                    p1 = p0;
                    p0 = ((2 * j + 1) as f64 * z * p1 - j as f64 * p2) / (j + 1) as f64;
                }
                dp = n as f64 * (z * p0 - p1) / (z * z - 1.0);
                z -= p0 / dp;
            }
            (z, 2.0 / ((1.0 - z * z) * dp * dp))
        })
        .collect()
}

/// Independent reference: the whole transform R~(s) (no split into a known part) integrated against J0(s r) on
/// uniform panels a quarter of a J0 period wide, 16 nodes each, up to where R~(s) s has fallen by 1e-17.
fn brute_force_profile(stack: &LayerStack, r_mm: f64) -> f64 {
    let f = |s: f64| stack.reflectance_hat(s, Combination::Directional, MultipoleTerms::All);
    let scale = f(0.0);
    let mut s_end = 1.0;
    while f(s_end).abs() * s_end > 1e-17 * scale {
        s_end *= 1.1;
    }
    let width = (0.5 * PI / r_mm.max(1e-3)).min(0.05);
    let nodes = gauss(16);
    let mut sum = 0.0;
    let mut a = 0.0;
    while a < s_end {
        for &(x, w) in &nodes {
            let s = a + 0.5 * width * (x + 1.0);
            sum += 0.5 * width * w * s * f(s) * libm::j0(s * r_mm);
        }
        a += width;
    }
    sum / (2.0 * PI)
}

/// Issue 10, class 1: a profile value did not depend only on its radius (the s-grid followed the largest radius).
#[test]
fn profile_value_does_not_depend_on_the_other_radii() {
    let layers = [layer(0.25, 0.3, 6.0, 1.4), layer(INF, 0.2, 3.0, 1.4)];
    // The multipole's profile as such (the brute-force reference below is the multipole's).
    let (_, alone) = multipole_reflectance(&layers, &[3.0, 10.0]).unwrap();
    let (_, with_far) = multipole_reflectance(&layers, &[3.0, 10.0, 1e6]).unwrap();
    let stack = LayerStack::new(&layers).unwrap();
    for (k, r) in [3.0, 10.0].into_iter().enumerate() {
        let reference = brute_force_profile(&stack, r);
        for value in [alone[k], with_far[k]] {
            assert!(
                (value - reference).abs() < 1e-3 * reference.abs() + 1e-11,
                "r={r}: {value} vs reference {reference}"
            );
        }
    }
    assert!(with_far[2].abs() < 1e-12, "R(1 km) = {}", with_far[2]);

    // The Caucasian preset at 6.3 mm, with the profile grid ending at 10 mm or at 1e4 mm.
    let request = Request::new(Outputs { profile_rgb: true, ..Outputs::default() });
    let stacks = Prepared::new(&request).unwrap().stacks(&SkinParams::preset("caucasian").unwrap()).unwrap();
    let q = HankelQuadrature::default();
    let near = reflectance_profiles(&stacks, &[6.3, 10.0], Combination::Directional, MultipoleTerms::All, &q);
    let far = reflectance_profiles(&stacks, &[6.3, 1e4], Combination::Directional, MultipoleTerms::All, &q);
    for (k, stack) in stacks.iter().enumerate().step_by(8) {
        let reference = brute_force_profile(stack, 6.3);
        let peak = stack.reflectance_hat(0.0, Combination::Directional, MultipoleTerms::All);
        for value in [near[k][0], far[k][0]] {
            assert!((value - reference).abs() < 1e-3 * reference + 1e-10 * peak, "stack {k}: {value} vs {reference}");
        }
    }
}

/// Issue 10, class 2: holes. `[(0.0134, 0.0021, 17.0, 1.39), (inf, 1.64, 1.17, 1.31)]` gave [3.86, 0, 0, 4.3e-3] at
/// 0.05, 0.1, 0.3, 0.5 mm: the top layer's z_b,0 (0.125 mm) exceeds d + z_b,d (0.064 mm), so its own R(r) turns
/// negative at r of the order of the extended slab, and the dark layer below does not fill the lobe. With the paper's
/// extrapolation the raw profile is still negative there; with the capped one it is positive at every radius of
/// 0.001-20 mm and equals a brute-force inverse transform of the whole R~(s) (no split into the image sum).
#[test]
fn capped_boundaries_have_no_holes() {
    let layers = [layer(0.0134, 0.0021, 17.0, 1.39), layer(INF, 1.64, 1.17, 1.31)];
    let q = HankelQuadrature::default();
    let raw = |stack: &LayerStack, radii: &[f64]| {
        raw_reflectance_profiles(std::slice::from_ref(stack), radii, Combination::Directional, MultipoleTerms::All, &q)
            .pop()
            .unwrap()
    };
    let paper = LayerStack::with_boundaries(&layers, Boundaries::Paper).unwrap();
    let top = paper.top();
    assert!(top.zb_top_mm > top.thickness_mm + top.zb_bottom_mm, "{top:?}");
    let hole = raw(&paper, &[0.08, 0.1, 0.2]);
    assert!(hole.iter().all(|&v| v < 0.0), "the paper's extrapolation: {hole:?}");

    let capped = LayerStack::with_boundaries(&layers, Boundaries::Capped).unwrap();
    let radii: Vec<f64> = (0..=86).map(|i| 1e-3 * 10f64.powf(i as f64 / 20.0)).collect(); // 0.001-20 mm
    let profile = raw(&capped, &radii);
    let peak = profile[0];
    // Positive up to 5 mm, where R has fallen to 1e-13 of its peak; beyond, zero within round-off (the layer below
    // decays like e^(-3.7 r / mm)).
    for (&r, &v) in radii.iter().zip(&profile) {
        assert!(v > 0.0 || (r > 5.0 && v > -1e-16 * peak), "R({r}) = {v}, peak {peak}: {profile:?}");
    }
    // 0.001, 0.01, 0.1, 0.2, 0.32, 1, 3.2 and 10 mm.
    for k in [0, 20, 40, 46, 50, 60, 70, 80] {
        let r = radii[k];
        let reference = brute_force_profile(&capped, r);
        assert!(
            (profile[k] - reference).abs() < 1e-3 * reference + 1e-9 * peak,
            "r={r}: {} vs brute force {reference}",
            profile[k]
        );
    }
}

/// `Boundaries::Capped` is the paper's slab, bit for bit, wherever neither cap acts (the Caucasian preset at
/// 380-560 nm, the African one everywhere, a semi-infinite layer), and continuous where a cap starts to act.
#[test]
fn capped_boundaries_are_the_paper_slab_where_consistent() {
    let request = Request::new(Outputs { albedo: true, ..Outputs::default() });
    let prepared = Prepared::new(&request).unwrap();
    let mut unchanged = 0;
    for name in ["caucasian", "african"] {
        let params = SkinParams::preset(name).unwrap();
        for &w in prepared.wavelengths_nm() {
            let layers = skin_layers(&params, &request.model, w);
            let paper = LayerStack::with_boundaries(&layers, Boundaries::Paper).unwrap();
            let capped = LayerStack::with_boundaries(&layers, Boundaries::Capped).unwrap();
            let top = paper.top();
            if top.zb_top_mm <= top.thickness_mm + top.zb_bottom_mm {
                unchanged += 1;
                assert_eq!(paper.slabs(), capped.slabs(), "{name} {w} nm");
            } else {
                assert!(name == "caucasian" && w > 560.0, "{name} {w} nm is past the cap");
            }
        }
    }
    assert!(unchanged >= 41 + 20, "{unchanged} stacks");

    // Where the cap starts to act: the top layer over an index-matched base has z_b,0 = d + z_b,d at d* = 2 D (A(1.4)
    // - A(1)); a relative step of 1e-9 in thickness across d* moves the total by O(1e-9) with the cap, as without.
    let (sa, ss) = (0.05, 4.0);
    let d_star = {
        let probe = LayerStack::new(&[layer(1.0, sa, ss, 1.4), layer(INF, 0.1, 2.0, 1.4)]).unwrap();
        probe.top().zb_top_mm - probe.top().zb_bottom_mm
    };
    let at =
        |d: f64, e: Boundaries| {
            LayerStack::with_boundaries(&[layer(d, sa, ss, 1.4), layer(INF, 0.1, 2.0, 1.4)], e)
                .unwrap()
                .reflectance_hat(0.0, Combination::Directional, MultipoleTerms::All)
        };
    let above = d_star * (1.0 + 1e-9);
    assert_eq!(at(above, Boundaries::Capped), at(above, Boundaries::Paper));
    let below = d_star * (1.0 - 1e-9);
    let step = (at(below, Boundaries::Capped) - at(above, Boundaries::Capped)).abs();
    assert!(step < 1e-8, "step across the cap {step}");
    let (capped, paper) = (at(0.5 * d_star, Boundaries::Capped), at(0.5 * d_star, Boundaries::Paper));
    assert!((capped - paper).abs() > 1e-3, "at d*/2 = {}: capped {capped} vs paper {paper}", 0.5 * d_star);
}

/// Why `Boundaries::Paper` stays the default (docs/robustness.md): against the Monte Carlo of the same transport
/// problem (tests/support/mc.rs: isotropic scattering with sigma_s = sigma_s', Fresnel boundaries), capping brings a
/// thin slab on its own closer, but the Caucasian preset in the red (its epidermis past the cap, the dermis below
/// filling the lobe) further away, and a thin epidermis much further. `--nocapture` prints the table.
#[test]
fn boundaries_against_monte_carlo() {
    let mut cases: Vec<(String, Vec<Layer>)> = vec![
        ("issue 10 reproducer".into(), vec![layer(0.0134, 0.0021, 17.0, 1.39), layer(INF, 1.64, 1.17, 1.31)]),
        ("0.1 mm slab alone, 0.01 / 10 per mm, n 1.4".into(), vec![layer(0.1, 0.01, 10.0, 1.4)]),
    ];
    for (name, w, d) in [("caucasian", 650.0, 0.25), ("caucasian", 750.0, 0.25), ("caucasian", 550.0, 0.08)] {
        let params = SkinParams { epidermis_thickness_mm: d, ..SkinParams::preset(name).unwrap() };
        let layers = skin_layers(&params, &SkinModel::default(), w).to_vec();
        cases.push((format!("{name} {w} nm, epidermis {d} mm"), layers));
    }
    println!("| stack | Monte Carlo (2e5 photons) | paper | capped |\n|---|---|---|---|");
    let mut error = Vec::new();
    for (k, (name, layers)) in cases.iter().enumerate() {
        let mc_layers = McLayer::isotropic_stack(layers);
        let mc = simulate(&mc_layers, &McConfig::new(200_000, 500 + k as u64, vec![0.0, 1.0]));
        let (paper, capped) = (total_with(layers, Boundaries::Paper), total_with(layers, Boundaries::Capped));
        let rel = |v: f64| v / mc.reflectance - 1.0;
        println!(
            "| {name} | {:.4} ± {:.4} | {paper:.4} ({:+.1} %) | {capped:.4} ({:+.1} %) |",
            mc.reflectance,
            mc.reflectance_se,
            100.0 * rel(paper),
            100.0 * rel(capped)
        );
        error.push((rel(paper).abs(), rel(capped).abs()));
    }
    assert!(error[1].1 < error[1].0, "the slab alone: {:?}", error[1]);
    for e in &error[2..] {
        assert!(e.0 + 0.02 < e.1, "skin: paper {} capped {}", e.0, e.1);
    }
}

/// The total diffuse reflectance of `layers` with the paper's boundaries.
fn total(layers: &[Layer]) -> f64 {
    total_with(layers, Boundaries::Paper)
}

/// The total diffuse reflectance of `layers` with `boundaries`.
fn total_with(layers: &[Layer], boundaries: Boundaries) -> f64 {
    LayerStack::with_boundaries(layers, boundaries).unwrap().reflectance_hat(
        0.0,
        Combination::Directional,
        MultipoleTerms::All,
    )
}

/// Issue 10, class 3: a vanishing layer vanishes (continuously: thickness -> 0 gives the stack without it), for a top,
/// middle and last layer of another index. A 1e-300 mm top layer changed the total from 0.614 to 0.547.
#[test]
fn vanishing_layer_vanishes() {
    let without = [layer(0.25, 0.3, 6.0, 1.4), layer(INF, 0.2, 3.0, 1.3)];
    let reference = total(&without);
    for t in [1e-11, 1e-9, 1e-7] {
        for (position, n) in [(0, 1.4), (0, 1.9), (1, 1.0), (1, 1.7)] {
            let mut with = without.to_vec();
            with.insert(position, layer(t, 0.5, 20.0, n));
            let value = total(&with);
            assert!(
                (value - reference).abs() < 1e-4 * reference * (t / 1e-7).max(1e-3),
                "t={t} at {position}: {value} vs {reference}"
            );
        }
    }
    // A vanishing finite last layer leaves the layer above resting on its own index.
    let finite = [layer(0.5, 0.1, 4.0, 1.4)];
    let with_last = [layer(0.5, 0.1, 4.0, 1.4), layer(1e-10, 0.1, 4.0, 1.8)];
    assert!((total(&with_last) - total(&finite)).abs() < 3e-5, "{} vs {}", total(&with_last), total(&finite));
}

/// Issue 10, class 3: splitting a layer into two identical pieces. Pieces of three reduced mean free paths or more agree
/// within 1.5 % of the total (measured worst 1.4 %, docs/robustness.md); a thin piece (here 1e-6 of a mfp) is continuous
/// with no split at all. Today's code was 424 % off below one mfp.
#[test]
fn splitting_a_layer_agrees() {
    for (sa, ss, n) in [(0.01, 1.0, 1.0), (0.3, 6.0, 1.4), (0.1, 10.0, 2.0)] {
        let whole = total(&[layer(INF, sa, ss, n)]);
        let mfp = 1.0 / (sa + ss);
        for pieces in [3.0, 10.0, 30.0] {
            let split = total(&[layer(pieces * mfp, sa, ss, n), layer(INF, sa, ss, n)]);
            assert!(((split - whole) / whole).abs() < 0.015, "{sa} {ss} {n} at {pieces} mfp: {split} vs {whole}");
        }
        let thin = total(&[layer(1e-6 * mfp, sa, ss, n), layer(INF, sa, ss, n)]);
        assert!(((thin - whole) / whole).abs() < 1e-5, "{sa} {ss} {n}: {thin} vs {whole}");
    }
}

/// Issue 10, class 5: indices where the F_dr fits break (A infinite at 3.85) are refused with a message naming ior and
/// its range; the edges of the range give finite reflectances in [0, 1].
#[test]
fn ior_outside_the_fits_range_is_a_clear_error() {
    for n in [0.9, 2.01, 2.94, 3.85, 3.9, f64::NAN] {
        let e = layered_reflectance(&[layer(INF, 0.1, 1.0, n)], &[1.0]).unwrap_err().to_string();
        assert!(e.contains("ior") && e.contains("[1, 2]"), "{n}: {e}");
    }
    // The second stack's index step is the multipole's to take (the exact transport refuses index steps).
    for layers in [vec![layer(INF, 0.1, 1.0, 2.0)], vec![layer(0.3, 0.1, 1.0, 2.0), layer(INF, 0.1, 1.0, 1.0)]] {
        let (r, profile) = multipole_reflectance(&layers, &[0.0, 1.0]).unwrap();
        assert!(r.is_finite() && (0.0..=1.0).contains(&r) && profile.iter().all(|p| p.is_finite()), "{r} {profile:?}");
    }
}

/// Issue 10, class 6: subnormal and huge magnitudes give an error naming the input, not NaN.
#[test]
fn extreme_magnitudes_are_clear_errors() {
    let cases = [
        (layer(INF, 0.1, 1e-310, 1.4), "sigma_s_reduced_per_mm"),
        (layer(INF, 0.1, 1e101, 1.4), "sigma_s_reduced_per_mm"),
        (layer(INF, 1e101, 1.0, 1.4), "sigma_a_per_mm"),
        (layer(1e101, 0.1, 1.0, 1.4), "thickness_mm"),
        (layer(1e-300, 0.1, 1.0, 1.4), "thickness_mm"),
    ];
    for (l, field) in cases {
        let e = layered_reflectance(&[l], &[1.0]).unwrap_err().to_string();
        assert!(e.contains(field) && e.contains("layer 0"), "{l:?}: {e}");
    }
    let e = layered_reflectance(&[layer(INF, 0.1, 1.0, 1.4)], &[1.0, 1e7]).unwrap_err().to_string();
    assert!(e.contains("radii_mm[1]"), "{e}");
    // A million radii ran 27 s (and ignored Ctrl-C): refused before any work, with the limit profiles have.
    let many = vec![1.0; 1_000_000];
    let e = layered_reflectance(&[layer(INF, 0.1, 1.0, 1.4)], &many).unwrap_err().to_string();
    let most = spectral_skin::accuracy::MAX_PROFILE_RADII;
    assert!(e.contains("radii_mm") && e.contains(&format!("at most {most}")), "{e}");
    // The edges of the accepted ranges give finite values.
    for l in [
        layer(INF, 1e-12, 1e6, 1.4),
        layer(INF, 1e6, 1e-12, 1.4),
        layer(1e-11, 1e6, 1e6, 1.4),
        layer(1e6, 1e-12, 1e-12, 1.0),
    ] {
        let (r, profile) = layered_reflectance(&[l], &[0.0, 1e-6, 1.0, 1e4]).unwrap();
        assert!(
            r.is_finite() && (0.0..=1.0).contains(&r) && profile.iter().all(|p| p.is_finite() && *p >= 0.0),
            "{l:?}: {r} {profile:?}"
        );
    }
}

/// A cached material table with a flipped byte is detected (checksum) and rebuilt, not used: the rebuilt table equals
/// a fresh build, and the cache file is rewritten whole.
#[test]
fn corrupted_table_cache_is_rebuilt() {
    use spectral_skin::maps::lut::{MaterialTable, TableResolution};
    use spectral_skin::Accuracy;
    let mut request = Request::new(Outputs { albedo: true, radius: true, ..Outputs::default() });
    request.accuracy = Accuracy::draft();
    let prepared = Prepared::new(&request).unwrap();
    let resolution = TableResolution { melanin: 2, melanin_blend: 2, hemoglobin: 2 };
    let dir = tempfile::tempdir().unwrap();
    let (fresh, cached) =
        MaterialTable::load_or_build(&prepared, SubsurfaceMethod::Burley, resolution, Some(dir.path())).unwrap();
    assert!(!cached, "{resolution:?}: the first load came from an empty cache folder {:?}", dir.path());
    assert!(
        MaterialTable::load_or_build(&prepared, SubsurfaceMethod::Burley, resolution, Some(dir.path())).unwrap().1,
        "{resolution:?}: the second load was built afresh, cache folder {:?}",
        dir.path()
    );
    let file = std::fs::read_dir(dir.path()).unwrap().next().unwrap().unwrap().path();
    let good = std::fs::read(&file).unwrap();
    let probe = |t: &MaterialTable| t.lookup(0.2, 0.5, 0.03);
    // The last node value, one in the middle, and a byte of the checksum (after the 23-byte magic line).
    for at in [good.len() - 1, good.len() / 2, 27] {
        let mut bad = good.clone();
        bad[at] ^= 0x10;
        std::fs::write(&file, &bad).unwrap();
        let (rebuilt, cached) =
            MaterialTable::load_or_build(&prepared, SubsurfaceMethod::Burley, resolution, Some(dir.path())).unwrap();
        assert!(!cached, "byte {at} flipped: the corrupted cache was used");
        assert_eq!(probe(&rebuilt), probe(&fresh), "byte {at} flipped");
        assert_eq!(std::fs::read(&file).unwrap(), good, "the cache file is rewritten");
    }
}

/// Sizes that would allocate gigabytes or run for hours are refused before any allocation, naming the input.
#[test]
fn sizes_are_bounded_before_allocation() {
    use spectral_skin::maps::example::{write_example_params, ExampleKind};
    use spectral_skin::maps::lut::TableResolution;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.exr");
    for size in [0, 99_999_999, 4_294_967_296] {
        let e = write_example_params(&out, ExampleKind::Face, size).unwrap_err().to_string();
        assert!(e.contains("size") && e.contains("8192"), "{size}: {e}");
        assert!(!out.exists(), "{size}: {out:?} written");
    }
    let e = TableResolution { melanin: 400, melanin_blend: 400, hemoglobin: 400 }.validate().unwrap_err().to_string();
    assert!(e.contains("table resolution") && e.contains("1000000"), "{e}");
}

/// Issue 10, class 2: a clamp may only remove round-off. The paper's lobe of the reproducer is clamped but reported
/// (radius and depth, checked against the raw profile the clamp saw); the capped stack reports none; and so does
/// every preset at the default accuracy, whose raw profiles are >= -1e-15 of their peak (docs/robustness.md).
#[test]
fn a_clamped_lobe_is_reported_not_hidden() {
    let layers = [layer(0.0134, 0.0021, 17.0, 1.39), layer(INF, 1.64, 1.17, 1.31)];
    let radii: Vec<f64> = (0..=86).map(|i| 1e-3 * 10f64.powf(i as f64 / 20.0)).collect();
    // The reproducer's index step and its lobe are the multipole's (the exact transport refuses index steps).
    let with = |boundaries| LayeredOptions { boundaries, transport: Transport::Diffusion, ..LayeredOptions::default() };
    let paper = layered_reflectance_with(&layers, &radii, &with(Boundaries::Paper)).unwrap();
    let lobe = paper.negative_lobe.expect("the paper's boundaries give this stack a negative lobe");
    let stack = LayerStack::new(&layers).unwrap();
    let q = HankelQuadrature::default();
    let raw = raw_reflectance_profiles(
        std::slice::from_ref(&stack),
        &radii,
        Combination::Directional,
        MultipoleTerms::All,
        &q,
    )
    .remove(0);
    let centre =
        raw_reflectance_profiles(&[stack], &[PEAK_PROBE_MM], Combination::Directional, MultipoleTerms::All, &q)[0][0];
    let (k, min) = raw.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1)).map(|(k, v)| (k, *v)).unwrap();
    let peak = raw.iter().fold(centre.abs(), |m, v| m.max(v.abs()));
    assert_eq!(lobe.radius_mm, radii[k]);
    assert!((0.08..=0.2).contains(&lobe.radius_mm), "{lobe:?}");
    assert!((lobe.relative_to_peak - min / peak).abs() < 1e-15 && lobe.relative_to_peak < -1e-4, "{lobe:?}");
    assert!(paper.profile_per_mm2.iter().all(|&v| v >= 0.0), "{:?}", paper.profile_per_mm2);
    assert!(lobe.to_string().contains("capped"), "the message names the way out: {lobe}");
    assert_eq!(lobe.boundaries, Boundaries::Paper, "the lobe names the boundaries of its stack");

    let capped = layered_reflectance_with(&layers, &radii, &with(Boundaries::Capped)).unwrap();
    assert_eq!(capped.negative_lobe, None);

    let request = Request::new(Outputs { profile_spectral: true, ..Outputs::default() });
    for preset in spectral_skin::PRESETS {
        let ev = spectral_skin::evaluate(&preset.params, &request).unwrap();
        assert_eq!(ev.profile.unwrap().negative_lobe, None, "{}", preset.name);
    }
}

/// Radii all in the far tail (20 to 200 mm, where a skin profile is about 1e-76 per mm² and the quadrature gives
/// round-off of 1e-20) are no lobe under either boundaries: the round-off threshold is read against the profile's
/// value near its centre, not against the largest magnitude of the round-off itself (which made it -1 of the peak).
#[test]
fn far_tail_round_off_is_no_lobe() {
    for boundaries in [Boundaries::Paper, Boundaries::Capped] {
        for (min_mm, max_mm) in [(20.0, 100.0), (50.0, 200.0)] {
            let mut request = Request::new(Outputs { profile_spectral: true, ..Outputs::default() });
            request.boundaries = boundaries;
            request.accuracy.profile_grid = ProfileGrid { r_min_mm: min_mm, r_max_mm: max_mm, count: 16 };
            for preset in spectral_skin::PRESETS {
                let ev = spectral_skin::evaluate(&preset.params, &request).unwrap();
                let profile = ev.profile.unwrap();
                assert_eq!(profile.negative_lobe, None, "{} {boundaries:?} {min_mm}-{max_mm} mm", preset.name);
            }
        }
    }
}

/// Round-off below `ROUND_OFF_OF_PEAK` of the peak is not a lobe; the deepest lobe over several profiles is the one
/// reported, at its own radius; a profile negative everywhere asked is -1 of its peak.
#[test]
fn lobes_are_told_apart_from_round_off() {
    let radii = [0.1, 1.0, 10.0];
    let none = ClampedProfiles::from_raw(vec![vec![1.0, -0.5 * ROUND_OFF_OF_PEAK, 0.0]], &radii, &[], &[]);
    assert_eq!(none.negative_lobe, None);
    assert_eq!(none.per_mm2, vec![vec![1.0, 0.0, 0.0]]);
    let two = ClampedProfiles::from_raw(
        vec![vec![2.0, -2e-3, 0.0], vec![1.0, 0.0, -3e-3], vec![-1.0, -2.0, -0.5]],
        &radii,
        &[],
        &[],
    );
    let lobe = two.negative_lobe.unwrap();
    assert_eq!((lobe.profile, lobe.radius_mm, lobe.relative_to_peak), (2, 1.0, -1.0));
    let one = ClampedProfiles::from_raw(vec![vec![2.0, -2e-3, 0.0], vec![1.0, 0.0, -3e-3]], &radii, &[], &[]);
    let lobe = one.negative_lobe.unwrap();
    assert_eq!((lobe.profile, lobe.radius_mm), (1, 10.0));
    assert!((lobe.relative_to_peak + 3e-3).abs() < 1e-15, "{lobe:?}");
    // The same tail values under a profile whose centre is 1e20 times larger: round-off, no lobe; a centre of the
    // tail's own size leaves the lobe.
    let tail = || vec![vec![1e-20, -1e-20, -2e-20]];
    assert_eq!(ClampedProfiles::from_raw(tail(), &radii, &[], &[1.0]).negative_lobe, None);
    let lobe = ClampedProfiles::from_raw(tail(), &radii, &[], &[1e-20]).negative_lobe.unwrap();
    assert_eq!((lobe.radius_mm, lobe.relative_to_peak), (10.0, -1.0));
}

/// The diffusion model's accuracy against Monte Carlo (the same transport problem: isotropic scattering with
/// sigma_s = sigma_s', Fresnel boundaries) for random skin-like two-layer stacks, by the top layer's optical thickness
/// tau = sigma_s' d (reduced mean free paths): docs/robustness.md, "Accuracy against Monte Carlo". Each class's worst
/// absolute error of the total reflectance, with either boundaries, must stay within the stated bound; the table
/// (also the relative errors) is printed with `-- --nocapture`. Monte Carlo: 20 000 photons a stack (standard error
/// below 0.004 in the total).
#[test]
fn diffusion_against_monte_carlo_by_top_layer_thickness() {
    // Stated bounds of the worst absolute error of the total (paper, capped): docs/robustness.md.
    const CLASSES: [(&str, f64, f64, f64, f64); 4] = [
        ("tau < 0.3", 0.0, 0.3, BOUND_PAPER[0], BOUND_CAPPED[0]),
        ("0.3 <= tau < 1", 0.3, 1.0, BOUND_PAPER[1], BOUND_CAPPED[1]),
        ("1 <= tau < 3", 1.0, 3.0, BOUND_PAPER[2], BOUND_CAPPED[2]),
        ("tau >= 3", 3.0, f64::INFINITY, BOUND_PAPER[3], BOUND_CAPPED[3]),
    ];
    // The measured worst (0.058, 0.066, 0.032, 0.052 and 0.122, 0.117, 0.032, 0.052) and a margin for changes of
    // the code that move the Monte Carlo's random stream or the model's last digits.
    const BOUND_PAPER: [f64; 4] = [0.08, 0.09, 0.05, 0.07];
    const BOUND_CAPPED: [f64; 4] = [0.16, 0.16, 0.05, 0.07];
    const PER_CLASS: usize = 16;
    let mut state = 0x5eed_u64;
    let mut uniform = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let log_uniform = |lo: f64, hi: f64, u: f64| (lo.ln() + u * (hi.ln() - lo.ln())).exp();
    // Per class: (|error| paper, |error| capped, relative paper, relative capped).
    let mut rows: Vec<Vec<[f64; 4]>> = vec![Vec::new(); CLASSES.len()];
    let mut k = 0u64;
    while rows.iter().any(|r| r.len() < PER_CLASS) && k < 1000 {
        let u: Vec<f64> = (0..7).map(|_| uniform()).collect();
        let top = layer(
            log_uniform(0.005, 0.5, u[0]),
            log_uniform(1e-3, 3.0, u[1]),
            log_uniform(1.0, 30.0, u[2]),
            1.3 + 0.2 * u[3],
        );
        let base = layer(INF, log_uniform(1e-2, 3.0, u[4]), log_uniform(1.0, 30.0, u[5]), 1.3 + 0.2 * u[6]);
        let tau = top.sigma_s_reduced_per_mm * top.thickness_mm;
        let c = CLASSES.iter().position(|&(_, lo, hi, _, _)| tau >= lo && tau < hi).unwrap();
        k += 1;
        if rows[c].len() >= PER_CLASS {
            continue;
        }
        let layers = [top, base];
        let mc_layers = McLayer::isotropic_stack(&layers);
        let mc = simulate(&mc_layers, &McConfig::new(20_000, 9000 + k, vec![0.0, 1.0]));
        let (paper, capped) = (total_with(&layers, Boundaries::Paper), total_with(&layers, Boundaries::Capped));
        let r = mc.reflectance;
        rows[c].push([(paper - r).abs(), (capped - r).abs(), (paper / r - 1.0).abs(), (capped / r - 1.0).abs()]);
    }
    println!(
        "| top layer (reduced mfp) | stacks | absolute error of the total: median, paper / capped | worst, paper / \
         capped | relative: median, paper / capped | bound (absolute), paper / capped |"
    );
    println!("|---|---|---|---|---|---|");
    for ((name, _, _, bound_paper, bound_capped), r) in CLASSES.iter().zip(&rows) {
        let median = |i: usize| {
            let mut v: Vec<f64> = r.iter().map(|e| e[i]).collect();
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let worst = |i: usize| r.iter().map(|e| e[i]).fold(0.0, f64::max);
        println!(
            "| {name} | {} | {:.3} / {:.3} | {:.3} / {:.3} | {:.1} % / {:.1} % | {} / {} |",
            r.len(),
            median(0),
            median(1),
            worst(0),
            worst(1),
            100.0 * median(2),
            100.0 * median(3),
            bound_paper,
            bound_capped
        );
        assert_eq!(r.len(), PER_CLASS, "{name}: too few stacks drawn");
        assert!(
            worst(0) <= *bound_paper && worst(1) <= *bound_capped,
            "{name}: past the stated bound: paper {} vs {bound_paper}, capped {} vs {bound_capped}",
            worst(0),
            worst(1)
        );
    }
}

/// A lobe's message names the boundaries it came under: the paper's recommend the capped ones; the capped ones (whose
/// exact profiles are non-negative) blame the numerical transform and do not recommend themselves. Before, every
/// lobe blamed "the paper's boundaries" and recommended capped, also to callers using capped.
#[test]
fn lobe_messages_name_the_boundaries_used() {
    use spectral_skin::diffusion::{Boundaries, NegativeLobe};
    let lobe =
        |boundaries| NegativeLobe { profile: 0, boundaries, radius_mm: 0.1, relative_to_peak: -0.01 }.to_string();
    let paper = lobe(Boundaries::Paper);
    assert!(paper.contains("the paper's boundaries") && paper.contains("boundaries \"capped\""), "{paper}");
    let capped = lobe(Boundaries::Capped);
    assert!(
        capped.contains("with the capped boundaries") && capped.contains("numerical inverse transform"),
        "{capped}"
    );
    assert!(!capped.contains("the paper's boundaries") && !capped.contains("boundaries \"capped\""), "{capped}");
}

/// Issue 23: a skin that absorbs nothing (no melanin, no blood, no baseline absorption) reflects everything that
/// enters; the paper's diffusion summed it to 1 + 4e-16. Every total and every albedo channel, by both transports,
/// stays within [0, 1], and reaches 1 to round-off.
#[test]
fn a_non_absorbing_skin_reflects_at_most_everything() {
    let params = SkinParams {
        melanin: 0.0,
        hemoglobin: 0.0,
        baseline_absorption_scale: 0.0,
        ..SkinParams::preset("caucasian").unwrap()
    };
    for transport in [Transport::Diffusion, Transport::AddingDoubling] {
        let outputs = Outputs { albedo: true, spectrum: true, ..Outputs::default() };
        let request = Request { transport, ..Request::new(outputs) };
        let ev = spectral_skin::evaluate(&params, &request).unwrap();
        let spectrum = ev.spectral_reflectance.unwrap();
        let albedo = ev.diffuse_reflectance_rgb.unwrap();
        let most = spectrum.iter().chain(&albedo).cloned().fold(f64::NEG_INFINITY, f64::max);
        let least = spectrum.iter().chain(&albedo).cloned().fold(f64::INFINITY, f64::min);
        assert!(most <= 1.0 && least > 1.0 - 1e-6, "{transport:?}: totals and albedo in [{least:e}, {most:e}]");
    }
}
