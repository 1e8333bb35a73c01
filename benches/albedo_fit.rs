//! The albedo-texture fit's cost per distinct colour (criterion), the hot path of `fit_albedo_map`: a 16 x 16 float
//! texture of the forward table's own albedos at low-discrepancy coordinates (all distinct, all in gamut, so that no
//! gains are estimated) fitted on the cached table at the held epidermis thickness, on one thread: the time divided
//! by the distinct count printed is the time per colour. The whole-texture timings (4096², 8-bit and float, cold and
//! cached) are `examples/albedo_fit_timing.rs`.
//!
//!     cargo bench --bench albedo_fit

use criterion::{criterion_group, criterion_main, Criterion};
use spectral_skin::inverse::albedo::{AlbedoFitOptions, AlbedoTable};
use spectral_skin::inverse::albedo_maps::{fit_albedo_map, EpidermisThickness};

const SIDE: usize = 16;

fn colours(table: &AlbedoTable) -> Vec<[f32; 3]> {
    (0..SIDE * SIDE)
        .map(|k| {
            // Additive recurrence on the plastic number's powers (R3 sequence): even cover of the table's cube.
            let u = [1.0, 2.0, 3.0].map(|d: f64| ((k as f64 + 0.5) * (0.754_877_666 * d).fract()).fract());
            table.albedo(u).map(|v| v as f32)
        })
        .collect()
}

fn bench_albedo_fit(c: &mut Criterion) {
    let options = AlbedoFitOptions::default();
    let table = AlbedoTable::build(&options).unwrap();
    let texels = colours(&table);
    let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let fit = || fit_albedo_map(&texels, SIDE, SIDE, &options, EpidermisThickness::Held).unwrap();
    // The first call builds the process's cached table; the timed calls find it.
    let first = fit();
    // Divide the time by this count (colours that coincide within the fit's quantisation are fitted once).
    println!("albedo_fit: {} distinct colours of {}", first.stats.distinct_colours, SIDE * SIDE);
    let mut group = c.benchmark_group("albedo_fit");
    group.sample_size(10);
    group.bench_function("fit_16x16_float_texture_one_thread", |b| b.iter(|| one_thread.install(fit)));
    group.finish();
}

criterion_group!(benches, bench_albedo_fit);
criterion_main!(benches);
