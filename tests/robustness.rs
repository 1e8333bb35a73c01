//! Regression tests for the hard cases of issue 10: each reproducer gets a right answer (against an independent
//! reference computed here) or a clear error. The property tests over the whole domain are in
//! `tests/robustness_properties.rs`.

use std::f64::consts::PI;

use spectral_skin::diffusion::{
    layered_reflectance, reflectance_profiles, Combination, HankelQuadrature, Layer, LayerStack,
    MultipoleTerms,
};
use spectral_skin::evaluate::Prepared;
use spectral_skin::{Outputs, Request, SkinParams};

const INF: f64 = f64::INFINITY;

fn layer(thickness_mm: f64, sigma_a_per_mm: f64, sigma_s_reduced_per_mm: f64, ior: f64) -> Layer {
    Layer {
        thickness_mm,
        sigma_a_per_mm,
        sigma_s_reduced_per_mm,
        ior,
    }
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
    let (_, alone) = layered_reflectance(&layers, &[3.0, 10.0]).unwrap();
    let (_, with_far) = layered_reflectance(&layers, &[3.0, 10.0, 1e6]).unwrap();
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
    let request = Request::new(Outputs {
        profile_rgb: true,
        ..Outputs::default()
    });
    let stacks = Prepared::new(&request)
        .unwrap()
        .stacks(&SkinParams::preset("caucasian").unwrap())
        .unwrap();
    let q = HankelQuadrature::default();
    let near = reflectance_profiles(
        &stacks,
        &[6.3, 10.0],
        Combination::Directional,
        MultipoleTerms::All,
        &q,
    );
    let far = reflectance_profiles(
        &stacks,
        &[6.3, 1e4],
        Combination::Directional,
        MultipoleTerms::All,
        &q,
    );
    for (k, stack) in stacks.iter().enumerate().step_by(8) {
        let reference = brute_force_profile(stack, 6.3);
        let peak = stack.reflectance_hat(0.0, Combination::Directional, MultipoleTerms::All);
        for value in [near[k][0], far[k][0]] {
            assert!(
                (value - reference).abs() < 1e-3 * reference + 1e-10 * peak,
                "stack {k}: {value} vs {reference}"
            );
        }
    }
}
