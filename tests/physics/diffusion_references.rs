//! The diffusion solver against independent references: direct quadrature of the real-space multipole formulas,
//! Jensen et al. 2001's closed form, thick-slab and split-layer limits, and energy bounds for hard inputs.

use std::f64::consts::PI;

use spectral_skin::diffusion::{LayerStack, MultipoleTerms, Slab};
use spectral_skin::layer::Layer;
use spectral_skin::reflectance::multipole_reflectance;

/// 2 pi int_0^inf f(r) J0(s r) r dr by the trapezoid rule in ln r (1000 points per decade, 1e-7 to 1e3 mm).
fn forward_hankel(f: impl Fn(f64) -> f64, s: f64) -> f64 {
    let (lo, hi, per_decade) = (-7.0, 3.0, 1000.0);
    let n = ((hi - lo) * per_decade) as usize;
    let h = (10f64).ln() / per_decade;
    (0..=n)
        .map(|k| {
            let r = 10f64.powf(lo + k as f64 / per_decade);
            let end = if k == 0 || k == n { 0.5 } else { 1.0 };
            end * f(r) * libm::j0(s * r) * r * r * h
        })
        .sum::<f64>()
        * 2.0
        * PI
}

/// The closed-form transforms (docs/model.md, Multipole) equal the numerical transform of the real-space sums,
/// for the truncated series and for the whole series, reflectance and transmittance, both boundary orders.
#[test]
fn closed_form_transforms_match_real_space_quadrature() {
    let slabs = [
        Slab::new(0.26062, 6.0823, 0.25, 1.4, 1.0), // Caucasian epidermis, 550 nm
        Slab::new(0.26062, 6.0823, 0.25, 1.0, 1.4), // the same seen from below
        Slab::new(1.5, 4.0, 0.8, 1.33, 1.2),
        Slab::new(0.05, 2.0, f64::INFINITY, 1.4, 1.0), // dipole
    ];
    for slab in slabs {
        for terms in [MultipoleTerms::Pairs(3), MultipoleTerms::All] {
            for s in [0.0, 1.0, 5.0] {
                let r_closed = slab.reflectance_hat(s, terms);
                let r_quad = forward_hankel(|r| slab.reflectance(r, terms), s);
                assert!((r_closed - r_quad).abs() < 1e-6, "R~ {slab:?} {terms:?} s={s}: {r_closed} vs {r_quad}");
                let t_closed = slab.transmittance_hat(s, terms);
                let t_quad = forward_hankel(|r| slab.transmittance(r, terms), s);
                assert!((t_closed - t_quad).abs() < 1e-6, "T~ {slab:?} {terms:?} s={s}: {t_closed} vs {t_quad}");
            }
        }
    }
}

fn layer(t: f64, sa: f64, ss: f64) -> Layer {
    Layer { thickness_mm: t, sigma_a_per_mm: sa, sigma_s_reduced_per_mm: ss, ior: 1.4 }
}

/// A slab much thicker than its diffusion length is the semi-infinite medium, in total and in profile.
#[test]
fn thick_slab_equals_semi_infinite() {
    let radii = [0.0, 0.1, 1.0, 5.0];
    let (t_thick, p_thick) = multipole_reflectance(&[layer(100.0, 0.02, 1.5)], &radii).unwrap();
    let (t_semi, p_semi) = multipole_reflectance(&[layer(f64::INFINITY, 0.02, 1.5)], &radii).unwrap();
    assert!((t_thick - t_semi).abs() < 1e-12, "total: thick slab {t_thick} vs semi-infinite {t_semi}");
    for (a, b) in p_thick.iter().zip(&p_semi) {
        assert!((a - b).abs() < 1e-9 * b, "{a} {b}");
    }
}

/// Two identical index-matched layers stacked equal one layer of the summed thickness. The adding equation joins the
/// layers through a virtual index-matched boundary (extrapolation distance 2 A(1) D), which the layered multipole
/// resolves only approximately (a Monte Carlo walk does not see the split at all). Measured: -1.4 % for a skin-like
/// 0.25 mm split over a semi-infinite base, -0.8 % to -1.7 % for the other semi-infinite cases, +0.9 % to -5.6 % for
/// finite stacks (worst: a 2 mm + 1 mm split of a weakly scattering slab). The bound, 6 %, still catches a wrong
/// combination (the symmetric form, or T1 used where R1 belongs, moves these totals by 10-40 %).
#[test]
fn split_layer_equals_whole() {
    let mut worst: f64 = 0.0;
    for (sa, ss, top) in [(0.05, 2.0, 0.3), (0.2, 6.0, 0.25), (0.02, 1.0, 2.0)] {
        for bottom in [1.0, f64::INFINITY] {
            let whole = multipole_reflectance(&[layer(top + bottom, sa, ss)], &[]).unwrap().0;
            let split = multipole_reflectance(&[layer(top, sa, ss), layer(bottom, sa, ss)], &[]).unwrap().0;
            let rel = (split - whole) / whole;
            println!(
                "split layer sa={sa} ss={ss} top={top} bottom={bottom}: whole {whole:.5} split {split:.5} ({:+.3} %)",
                100.0 * rel
            );
            worst = worst.max(rel.abs());
        }
    }
    assert!(worst < 0.06, "worst relative difference {worst}");
}

/// Hard inputs stay finite and conserve energy: R + T <= 1, profiles >= 0, no NaN.
#[test]
fn extreme_inputs_are_stable() {
    let radii = [0.0, 1e-3, 0.1, 10.0, 20.0];
    let extremes = [0.0, 1e-12, 1e-6, 1.0, 1e3, 1e6];
    for &sa in &extremes {
        for &ss in &extremes {
            if sa + ss == 0.0 {
                continue;
            }
            for t in [1e-4, 0.25, 50.0, f64::INFINITY] {
                let layers = [layer(0.25, sa, ss), layer(t, 0.1 * sa + 1e-3, ss)];
                let (total, profile) = multipole_reflectance(&layers, &radii).unwrap();
                assert!(total.is_finite() && (0.0..=1.0 + 1e-12).contains(&total), "sa={sa} ss={ss} t={t}: {total}");
                assert!(profile.iter().all(|v| v.is_finite() && *v >= 0.0), "sa={sa} ss={ss} t={t}: {profile:?}");
                let stack = LayerStack::new(&layers[..1]).unwrap();
                let slab = stack.top();
                let sum =
                    slab.reflectance_hat(0.0, MultipoleTerms::All) + slab.transmittance_hat(0.0, MultipoleTerms::All);
                assert!(sum <= 1.0 + 1e-12, "sa={sa} ss={ss}: R+T = {sum}");
            }
        }
    }
}
