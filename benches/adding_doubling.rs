//! Time of one adding-doubling total (one wavelength: the epidermis doubled from a thin layer, the semi-infinite
//! dermis from its table, adding and the Fresnel boundary) per stream count, for a fair and a dark skin (criterion;
//! median reported). The goal: <= 50 us at the default stream count on one core.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use spectral_skin::skin::{skin_layers, SkinModel, SkinParams};
use spectral_skin::transport::total_diffuse_reflectance;

fn bench_adding_doubling(c: &mut Criterion) {
    let mut group = c.benchmark_group("adding_doubling");
    for (preset, wavelength_nm) in [("caucasian", 550.0), ("african", 450.0)] {
        let layers = skin_layers(&SkinParams::preset(preset).unwrap(), &SkinModel::default(), wavelength_nm);
        for streams in [4, 8, 16, 32] {
            // The first call builds the quadrature and the semi-infinite table, once per process.
            total_diffuse_reflectance(&layers, streams).unwrap();
            let id = BenchmarkId::new(format!("{preset}_{wavelength_nm}nm"), streams);
            group.bench_with_input(id, &layers, |b, layers| {
                b.iter(|| total_diffuse_reflectance(std::hint::black_box(layers), streams).unwrap())
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench_adding_doubling);
criterion_main!(benches);
