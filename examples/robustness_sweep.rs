//! The random sweeps behind the tables of docs/robustness.md: layer splitting, monotonicity in absorption and negative
//! profile lobes, by class, over seeded random cases, each for the paper's extrapolated boundaries and for the capped
//! ones (`diffusion::Boundaries`); then the skin presets and thin epidermis under both. The property tests in
//! tests/physics/robustness_properties.rs assert the classes that hold; this prints how far the others are off.
//!
//!     cargo run --release --example robustness_sweep            # about a minute

use spectral_skin::color::spectrum_to_rgb;
use spectral_skin::diffusion::{
    raw_reflectance_profiles, Boundaries, Combination, HankelQuadrature, LayerStack, MultipoleTerms,
};
use spectral_skin::evaluate::Prepared;
use spectral_skin::layer::Layer;
use spectral_skin::skin::skin_layers;
use spectral_skin::{Outputs, Request, SkinParams};

const BOTH: [Boundaries; 2] = [Boundaries::Paper, Boundaries::Capped];

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

fn stack(layers: &[Layer], e: Boundaries) -> LayerStack {
    LayerStack::with_boundaries(layers, e).unwrap()
}

fn total(layers: &[Layer], e: Boundaries) -> f64 {
    stack(layers, e).reflectance_hat(0.0, Combination::Directional, MultipoleTerms::All)
}

/// The raw (unclamped) profile at `radii`.
fn raw_profile(stack: &LayerStack, radii: &[f64]) -> Vec<f64> {
    let q = HankelQuadrature::default();
    raw_reflectance_profiles(std::slice::from_ref(stack), radii, Combination::Directional, MultipoleTerms::All, &q)
        .pop()
        .unwrap()
}

/// The most negative value relative to the largest magnitude (0 if none is negative).
fn min_over_peak(p: &[f64]) -> f64 {
    let peak = p.iter().map(|v| v.abs()).fold(0.0, f64::max);
    if peak == 0.0 {
        return 0.0;
    }
    p.iter().cloned().fold(0.0, f64::min) / peak
}

/// `per_decade` log-spaced radii from `lo` to `hi` mm.
fn log_radii(lo: f64, hi: f64, per_decade: f64) -> Vec<f64> {
    let n = ((hi / lo).log10() * per_decade).round() as usize;
    (0..=n).map(|i| lo * (hi / lo).powf(i as f64 / n as f64)).collect()
}

/// Whether any slab of the stack has an extrapolation distance past the thickness plus the other one.
fn beyond_cap(layers: &[Layer]) -> bool {
    stack(layers, Boundaries::Paper)
        .slabs()
        .iter()
        .any(|s| s.zb_top_mm > s.thickness_mm + s.zb_bottom_mm || s.zb_bottom_mm > s.thickness_mm + s.zb_top_mm)
}

const CLASSES: [&str; 5] = ["tau < 0.01", "0.01 <= tau < 0.1", "0.1 <= tau < 1", "1 <= tau < 3", "tau >= 3"];

fn class(tau: f64) -> usize {
    [0.01, 0.1, 1.0, 3.0].iter().take_while(|&&edge| tau >= edge).count()
}

/// Negative lobes in `count` random stacks from `draw`: (stacks, with a slab beyond the cap, negative below -1e-9 of
/// the largest |R| per extrapolation, most negative ratio per extrapolation).
fn negative_lobes(
    count: usize,
    radii: &[f64],
    mut draw: impl FnMut() -> Vec<Layer>,
) -> (usize, usize, [usize; 2], [f64; 2]) {
    let (mut beyond, mut negative, mut worst) = (0, [0; 2], [0.0f64; 2]);
    for _ in 0..count {
        let layers = draw();
        beyond += beyond_cap(&layers) as usize;
        for (k, e) in BOTH.into_iter().enumerate() {
            let ratio = min_over_peak(&raw_profile(&stack(&layers, e), radii));
            negative[k] += (ratio < -1e-9) as usize;
            worst[k] = worst[k].min(ratio);
        }
    }
    (count, beyond, negative, worst)
}

fn main() {
    split_and_monotonicity();
    println!();
    monotonicity_whole_domain();
    println!();
    negative_lobe_tables();
    println!();
    skin();
}

/// A layer (coefficients 1e-8 to 1e5 per mm log-uniform, index 1 to 2) over a random semi-infinite layer; split into a
/// piece of optical thickness tau over the rest (the whole 3 to 30 mfp thicker), and 10 % more absorption in a layer
/// of thickness tau over the same base.
fn split_and_monotonicity() {
    let cases = 100_000;
    let mut rng = Lcg(7);
    let mut n = [0usize; 5];
    let mut split_worst = [[0.0f64; 5]; 2];
    let (mut mono_bad, mut mono_worst) = ([[0usize; 5]; 2], [[0.0f64; 5]; 2]);
    for _ in 0..cases {
        let (sa, ss) = (rng.log_uniform(1e-8, 1e5), rng.log_uniform(1e-8, 1e5));
        let (ior, ior_below) = (1.0 + rng.uniform(), 1.0 + rng.uniform());
        let st = sa + ss;
        let piece_tau = rng.log_uniform(1e-6, 30.0);
        let whole_tau = piece_tau + rng.log_uniform(3.0, 30.0);
        let below = Layer {
            thickness_mm: f64::INFINITY,
            sigma_a_per_mm: rng.log_uniform(1e-3, 10.0),
            sigma_s_reduced_per_mm: rng.log_uniform(1e-3, 10.0),
            ior: ior_below,
        };
        let (piece, whole) = (piece_tau / st, whole_tau / st);
        if whole > 1e6 || piece < 1e-11 || whole - piece < 1e-11 {
            continue;
        }
        let layer = |t: f64| Layer { thickness_mm: t, sigma_a_per_mm: sa, sigma_s_reduced_per_mm: ss, ior };
        let c = class(piece_tau);
        n[c] += 1;
        let more = Layer { sigma_a_per_mm: (sa * 1.1).min(1e5), ..layer(piece) };
        for (k, e) in BOTH.into_iter().enumerate() {
            // Splitting: one layer of whole_tau against a piece of piece_tau over the rest.
            let (a, b) = (total(&[layer(whole), below], e), total(&[layer(piece), layer(whole - piece), below], e));
            split_worst[k][c] = split_worst[k][c].max(((a - b) / a).abs());
            // Monotonicity: 10 % more absorption in a layer of piece_tau.
            let (r0, r1) = (total(&[layer(piece), below], e), total(&[more, below], e));
            let rise = (r1 - r0) / r0;
            if rise > 1e-9 && r1 - r0 > 1e-15 {
                mono_bad[k][c] += 1;
                mono_worst[k][c] = mono_worst[k][c].max(rise);
            }
        }
    }
    println!("| class (optical thickness of the piece / layer) | cases | split: worst relative, paper / capped | monotone: rises > 1e-9 (and 1e-15), paper / capped | monotone: worst rise, paper / capped |");
    println!("|---|---|---|---|---|");
    for c in 0..5 {
        println!(
            "| {} | {} | {:.2e} / {:.2e} | {} / {} | {:.2e} / {:.2e} |",
            CLASSES[c],
            n[c],
            split_worst[0][c],
            split_worst[1][c],
            mono_bad[0][c],
            mono_bad[1][c],
            mono_worst[0][c],
            mono_worst[1][c]
        );
    }
}

/// A random stack of the whole accepted domain (the property tests' distribution): 1-4 layers, coefficients 1e-8 to
/// 1e5 per mm, thicknesses 1e-6 to 1e3 mm (the last semi-infinite half of the time), index 1 to 2.
fn any_stack(rng: &mut Lcg) -> Vec<Layer> {
    let count = 1 + (rng.uniform() * 4.0) as usize;
    let semi_infinite = rng.uniform() < 0.5;
    (0..count)
        .map(|i| Layer {
            thickness_mm: if semi_infinite && i + 1 == count { f64::INFINITY } else { rng.log_uniform(1e-6, 1e3) },
            sigma_a_per_mm: rng.log_uniform(1e-8, 1e5),
            sigma_s_reduced_per_mm: rng.log_uniform(1e-8, 1e5),
            ior: 1.0 + rng.uniform(),
        })
        .collect()
}

/// 10 % more absorption in one random layer of a random stack of the whole domain, by the layer's optical thickness.
fn monotonicity_whole_domain() {
    let mut rng = Lcg(11);
    let mut n = [0usize; 5];
    let (mut bad, mut worst) = ([[0usize; 5]; 2], [[0.0f64; 5]; 2]);
    for _ in 0..200_000 {
        let layers = any_stack(&mut rng);
        let k = (rng.uniform() * layers.len() as f64) as usize;
        let mut more = layers.clone();
        more[k].sigma_a_per_mm = (more[k].sigma_a_per_mm * 1.1).min(1e5);
        let l = layers[k];
        let c = class((l.sigma_a_per_mm + l.sigma_s_reduced_per_mm) * l.thickness_mm);
        n[c] += 1;
        for (e, b) in BOTH.into_iter().enumerate() {
            let (r0, r1) = (total(&layers, b), total(&more, b));
            if r1 - r0 > 1e-9 * r0 && r1 - r0 > 1e-15 {
                bad[e][c] += 1;
                worst[e][c] = worst[e][c].max((r1 - r0) / r0);
            }
        }
    }
    println!("| layer with 10 % more absorption, in a stack of the whole domain | cases | rises > 1e-9 (and 1e-15), paper / capped | worst rise, paper / capped |");
    println!("|---|---|---|---|");
    for c in 0..5 {
        println!(
            "| {} | {} | {} / {} | {:.2e} / {:.2e} |",
            CLASSES[c], n[c], bad[0][c], bad[1][c], worst[0][c], worst[1][c]
        );
    }
}

/// Negative lobes of the raw profile: skin-like random stacks of 2-3 layers (issue 10 class 2) and random stacks of
/// the whole accepted domain (the property tests' distribution).
fn negative_lobe_tables() {
    let mut rng = Lcg(99);
    let skin_like = negative_lobes(10_000, &log_radii(1e-3, 20.0, 15.0), || {
        let count = 2 + (rng.uniform() * 2.0) as usize;
        (0..count)
            .map(|i| Layer {
                thickness_mm: if i + 1 == count { f64::INFINITY } else { rng.log_uniform(0.01, 0.5) },
                sigma_a_per_mm: rng.log_uniform(1e-3, 3.0),
                sigma_s_reduced_per_mm: rng.log_uniform(1.0, 30.0),
                ior: 1.3 + 0.2 * rng.uniform(),
            })
            .collect()
    });
    let mut rng = Lcg(3);
    let domain = negative_lobes(3_000, &log_radii(1e-6, 1e4, 8.0), || any_stack(&mut rng));
    println!("| stacks (raw profile) | count | a slab beyond z_b = d + z_b,other | negative < -1e-9 of max abs R: paper / capped | most negative / max abs R: paper / capped |");
    println!("|---|---|---|---|---|");
    for (name, (count, beyond, negative, worst)) in [
        ("skin-like, 2-3 layers, 0.001-20 mm (15 radii a decade)", skin_like),
        ("whole domain, 1-4 layers, 1e-6-1e4 mm (8 a decade)", domain),
    ] {
        println!(
            "| {name} | {count} | {beyond} | {} ({:.1} %) / {} | {:.2e} / {:.2e} |",
            negative[0],
            100.0 * negative[0] as f64 / count as f64,
            negative[1],
            worst[0],
            worst[1]
        );
    }
}

/// The presets with the default epidermis (0.25 mm) and thinner ones, under both extrapolations: where the epidermis is
/// past the cap, the raw profile's most negative value, and the linear Rec.709 albedo at the default accuracy.
fn skin() {
    println!("| preset | epidermis mm | wavelengths past the cap | min raw R / max R: paper / capped | albedo paper | albedo capped | largest spectral change |");
    println!("|---|---|---|---|---|---|---|");
    let radii = log_radii(1e-3, 20.0, 30.0);
    for thickness in [0.25, 0.12, 0.08, 0.06] {
        let request = Request::new(Outputs { albedo: true, ..Outputs::default() });
        let prepared = Prepared::new(&request).unwrap();
        for name in ["caucasian", "asian", "african"] {
            let params = SkinParams { epidermis_thickness_mm: thickness, ..SkinParams::preset(name).unwrap() };
            let layers: Vec<[Layer; 2]> =
                prepared.wavelengths_nm().iter().map(|&w| skin_layers(&params, &request.model, w)).collect();
            let past: Vec<f64> = prepared
                .wavelengths_nm()
                .iter()
                .zip(&layers)
                .filter(|(_, l)| beyond_cap(&l[..]))
                .map(|(&w, _)| w)
                .collect();
            let mut worst = [0.0f64; 2];
            let mut totals = [vec![], vec![]];
            for (k, e) in BOTH.into_iter().enumerate() {
                for l in &layers {
                    let s = stack(l, e);
                    worst[k] = worst[k].min(min_over_peak(&raw_profile(&s, &radii)));
                    totals[k].push(s.reflectance_hat(0.0, Combination::Directional, MultipoleTerms::All));
                }
            }
            let albedo = totals.clone().map(|t| spectrum_to_rgb(&t, prepared.rgb_weights()));
            let change = totals[0].iter().zip(&totals[1]).map(|(a, b)| (b / a - 1.0).abs()).fold(0.0, f64::max);
            let range = match (past.first(), past.last()) {
                (Some(a), Some(b)) => format!("{} of {} ({a:.0}-{b:.0} nm)", past.len(), layers.len()),
                _ => format!("0 of {}", layers.len()),
            };
            let rgb = |a: [f64; 3]| format!("{:.4}, {:.4}, {:.4}", a[0], a[1], a[2]);
            println!(
                "| {name} | {thickness} | {range} | {:.1e} / {:.1e} | {} | {} | {:.1} % |",
                worst[0],
                worst[1],
                rgb(albedo[0]),
                rgb(albedo[1]),
                100.0 * change
            );
        }
    }
}
