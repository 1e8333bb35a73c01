//! Map pipeline costs (criterion): table build (and the build before exact profile shapes, for the ratio), per-texel table lookup, and the whole pipeline on a 256² example
//! (table strategy) and a 256² mask with 16 tuples (distinct-tuple strategy). The full size sweep with peak memory
//! is `scripts/reports/maps_report.py` (writes docs/maps-performance.md).

use criterion::{criterion_group, criterion_main, Criterion};
use spectral_skin::evaluate::Prepared;
use spectral_skin::maps::example::face_params;
use spectral_skin::maps::io::{default_extended, ParamImage, Plane};
use spectral_skin::maps::lut::{MaterialTable, TableResolution};
use spectral_skin::maps::{compute_maps, MapSettings};
use spectral_skin::transport::Transport;
use spectral_skin::{Outputs, Request};

fn bench_maps(c: &mut Criterion) {
    let prepared = Prepared::new(&Request::new(Outputs::material())).unwrap();
    let mut group = c.benchmark_group("maps");
    group.sample_size(10);
    group.bench_function("table_build_default", |b| {
        b.iter(|| {
            MaterialTable::build(&prepared, spectral_skin::fit::DEFAULT_METHOD, TableResolution::default()).unwrap()
        })
    });
    // The cold table before exact profile shapes (33 x 7 x 17 nodes, the multipole's shape): the baseline of the
    // exact shapes' cost bound (a cold table at most 2x this), measured in the same run.
    let before = Prepared::new(&Request {
        transport: Transport::AddingDoublingDiffusionShape,
        ..Request::new(Outputs::material())
    })
    .unwrap();
    let before_resolution = TableResolution { melanin_blend: 7, ..TableResolution::default() };
    group.bench_function("table_build_diffusion_shape_33x7x17", |b| {
        b.iter(|| MaterialTable::build(&before, spectral_skin::fit::DEFAULT_METHOD, before_resolution).unwrap())
    });
    let table =
        MaterialTable::build(&prepared, spectral_skin::fit::DEFAULT_METHOD, TableResolution::default()).unwrap();
    group.bench_function("table_lookup_1e5_texels", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for i in 0..100_000u32 {
                let u = (i as f32 * 0.618_034).fract();
                let t = table.lookup(0.5 * u * u * u, u, 0.1 * (1.0 - u).powi(3));
                sum += t.albedo[0];
            }
            sum
        })
    });
    let face = face_params(256);
    group.bench_function("pipeline_table_256", |b| {
        b.iter(|| compute_maps(&face, &MapSettings::default(), None).unwrap())
    });
    let mask: Vec<f32> = (0..256 * 256).map(|i| 0.02 * ((i / 16) % 16) as f32).collect();
    let masked = ParamImage {
        width: 256,
        height: 256,
        planes: [Plane::Texels(mask), Plane::Constant(0.6), Plane::Constant(0.01), Plane::Constant(0.2)],
        extended: default_extended(),
        notes: Vec::new(),
    };
    group.bench_function("pipeline_distinct_256", |b| {
        b.iter(|| compute_maps(&masked, &MapSettings::default(), None).unwrap())
    });
    group.finish();
}

criterion_group!(benches, bench_maps);
criterion_main!(benches);
