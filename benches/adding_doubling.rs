//! Time of one adding-doubling total (one wavelength) per stream count, for a fair and a dark skin (criterion; median
//! reported). The goal: <= 50 us at the default stream count on one core.
//!
//! Two cases: `whole_stack`, the epidermis doubled from a thin layer, the semi-infinite dermis from its table, adding
//! and the Fresnel boundary (each iteration perturbs the epidermis's absorption in its last bits so that the solver's
//! per-thread cache of the upper layers misses, as in a fit that varies melanin); `dermis_only`, the same stack again,
//! served by that cache (as in a table row or a fit that varies only the blood).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use spectral_skin::skin::{skin_layers, SkinModel, SkinParams};
use spectral_skin::transport::total_diffuse_reflectance;

fn bench_adding_doubling(c: &mut Criterion) {
    let mut group = c.benchmark_group("adding_doubling");
    for (preset, wavelength_nm) in [("caucasian", 550.0), ("african", 450.0)] {
        let layers = skin_layers(&SkinParams::preset(preset).unwrap(), &SkinModel::default(), wavelength_nm);
        for streams in [4, 8, 10, 12, 16, 32] {
            // The first call builds the quadrature and the semi-infinite table, once per process.
            total_diffuse_reflectance(&layers, streams).unwrap();
            let id = BenchmarkId::new(format!("dermis_only/{preset}_{wavelength_nm}nm"), streams);
            group.bench_with_input(id, &layers, |b, layers| {
                b.iter(|| total_diffuse_reflectance(std::hint::black_box(layers), streams).unwrap())
            });
            let id = BenchmarkId::new(format!("whole_stack/{preset}_{wavelength_nm}nm"), streams);
            let mut k = 0u64;
            group.bench_with_input(id, &layers, |b, layers| {
                b.iter(|| {
                    k += 1;
                    let mut fresh = *layers;
                    fresh[0].sigma_a_per_mm *= 1.0 + 1e-12 * (k % 1_000_000) as f64;
                    total_diffuse_reflectance(std::hint::black_box(&fresh), streams).unwrap()
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench_adding_doubling);
criterion_main!(benches);
