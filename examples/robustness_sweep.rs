//! The random sweeps behind the table of docs/robustness.md: layer splitting, monotonicity in absorption and negative
//! profile lobes, by class, over seeded random cases (the property tests in tests/robustness_properties.rs assert
//! the classes that hold; this prints how far the others are off).
//!
//!     cargo run --release --example robustness_sweep            # 10^5 cases per sweep, about 10 s

use spectral_skin::diffusion::{
    raw_reflectance_profiles, Combination, HankelQuadrature, Layer, LayerStack, MultipoleTerms,
};

/// A 64-bit LCG (Knuth's MMIX constants): reproducible without a dependency.
struct Lcg(u64);

impl Lcg {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn log_uniform(&mut self, lo: f64, hi: f64) -> f64 {
        (lo.ln() + self.uniform() * (hi.ln() - lo.ln())).exp()
    }
}

fn total(layers: &[Layer]) -> f64 {
    LayerStack::new(layers).unwrap().reflectance_hat(0.0, Combination::Directional, MultipoleTerms::All)
}

const CLASSES: [&str; 4] = ["tau < 0.1", "0.1 <= tau < 1", "1 <= tau < 3", "tau >= 3"];

fn class(tau: f64) -> usize {
    [0.1, 1.0, 3.0].iter().take_while(|&&edge| tau >= edge).count()
}

fn main() {
    let cases = 100_000;
    let mut rng = Lcg(7);
    let (mut split_n, mut split_worst) = ([0usize; 4], [0.0f64; 4]);
    let (mut mono_n, mut mono_bad, mut mono_worst) = ([0usize; 4], [0usize; 4], [0.0f64; 4]);
    for _ in 0..cases {
        let (sa, ss) = (rng.log_uniform(1e-8, 1e5), rng.log_uniform(1e-8, 1e5));
        let (n, n_below) = (1.0 + rng.uniform(), 1.0 + rng.uniform());
        let st = sa + ss;
        let piece_tau = rng.log_uniform(1e-6, 30.0);
        let whole_tau = piece_tau + rng.log_uniform(3.0, 30.0);
        let below = Layer {
            thickness_mm: f64::INFINITY,
            sigma_a_per_mm: rng.log_uniform(1e-3, 10.0),
            sigma_s_reduced_per_mm: rng.log_uniform(1e-3, 10.0),
            ior: n_below,
        };
        let (piece, whole) = (piece_tau / st, whole_tau / st);
        if whole > 1e6 || piece < 1e-11 || whole - piece < 1e-11 {
            continue;
        }
        let layer = |t: f64| Layer { thickness_mm: t, sigma_a_per_mm: sa, sigma_s_reduced_per_mm: ss, ior: n };
        let k = class(piece_tau);
        // Splitting: one layer of whole_tau against a piece of piece_tau over the rest.
        let (a, b) = (total(&[layer(whole), below]), total(&[layer(piece), layer(whole - piece), below]));
        split_n[k] += 1;
        split_worst[k] = split_worst[k].max(((a - b) / a).abs());
        // Monotonicity: 10 % more absorption in a layer of piece_tau.
        let more = Layer { sigma_a_per_mm: (sa * 1.1).min(1e5), ..layer(piece) };
        let (r0, r1) = (total(&[layer(piece), below]), total(&[more, below]));
        mono_n[k] += 1;
        let rise = (r1 - r0) / r0;
        if rise > 1e-9 {
            mono_bad[k] += 1;
            mono_worst[k] = mono_worst[k].max(rise);
        }
    }
    println!("| class (optical thickness of the piece / layer) | split: cases | split: worst relative | monotone: cases | monotone: rises > 1e-9 | monotone: worst rise |");
    println!("|---|---|---|---|---|---|");
    for k in 0..4 {
        println!(
            "| {} | {} | {:.2e} | {} | {} | {:.2e} |",
            CLASSES[k], split_n[k], split_worst[k], mono_n[k], mono_bad[k], mono_worst[k]
        );
    }

    // Negative lobes: skin-like random stacks of 2-3 layers (issue 10 class 2), raw profile before the clamp.
    let radii = [0.05, 0.1, 0.3, 0.5, 1.0, 3.0, 10.0];
    let (mut stacks, mut negative, mut zero_flux_only) = (0, 0, 0);
    for _ in 0..cases / 10 {
        let count = 2 + (rng.uniform() * 2.0) as usize;
        let layers: Vec<Layer> = (0..count)
            .map(|i| Layer {
                thickness_mm: if i + 1 == count { f64::INFINITY } else { rng.log_uniform(0.01, 0.5) },
                sigma_a_per_mm: rng.log_uniform(1e-3, 3.0),
                sigma_s_reduced_per_mm: rng.log_uniform(1.0, 30.0),
                ior: 1.3 + 0.2 * rng.uniform(),
            })
            .collect();
        let stack = LayerStack::new(&layers).unwrap();
        let q = HankelQuadrature::default();
        let p = raw_reflectance_profiles(
            std::slice::from_ref(&stack),
            &radii,
            Combination::Directional,
            MultipoleTerms::All,
            &q,
        )
        .pop()
        .unwrap();
        let peak = p.iter().cloned().fold(0.0, f64::max);
        stacks += 1;
        if p.iter().any(|&v| v < -1e-9 * peak) {
            negative += 1;
            let top = stack.top();
            if top.zb_top_mm > top.thickness_mm + top.zb_bottom_mm {
                zero_flux_only += 1;
            }
        }
    }
    println!();
    println!(
        "skin-like 2-3 layer stacks: {stacks}; with a negative value below -1e-9 of the peak at 0.05-10 mm: {negative} \
         ({:.1} %), of which with the top layer's z_b,0 > d + z_b,d: {zero_flux_only}",
        100.0 * negative as f64 / stacks as f64
    );
}
