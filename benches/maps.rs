//! Map pipeline costs (criterion): table build (and the build before exact profile shapes, for the ratio), per-texel
//! table lookup (the scalar one of all nine outputs, and the pipeline's row lookup of Base Color and radius on one
//! thread over texels that never repeat), and the whole pipeline on a 256² example (table strategy) and a 256² mask
//! with 16 tuples (distinct-tuple strategy). The full size sweep with peak memory is
//! `scripts/reports/maps_report.py` (writes docs/maps-performance.md); maps against their copy floor,
//! `cargo run --release --example maps_floor`.

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
    // The pipeline's lookup (`lookup_method_rows`: Base Color and radius, a row at a time) on one thread, over texels
    // that never repeat their neighbour (a noise map: no run is skipped): 1e5 texels in rows of 4096.
    let noise: [Vec<f32>; 3] = std::array::from_fn(|p| {
        (0..100_000u32).map(|i| (i as f32 * [0.618_034, 0.414_214, 0.732_051][p]).fract()).collect()
    });
    let (melanin, blend, hemoglobin): (Vec<f32>, Vec<f32>, Vec<f32>) = (
        noise[0].iter().map(|u| 0.5 * u * u * u).collect(),
        noise[1].clone(),
        noise[2].iter().map(|u| 0.1 * u * u * u).collect(),
    );
    let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    group.bench_function("table_lookup_rows_1e5_texels_one_thread", |b| {
        let mut out: Vec<Vec<f32>> = vec![vec![0f32; 4096]; 6];
        b.iter(|| {
            one_thread.install(|| {
                for start in (0..100_000).step_by(4096) {
                    let end = (start + 4096).min(100_000);
                    let n = end - start;
                    let [c0, c1, c2, r0, r1, r2] = out.as_mut_slice() else { unreachable!("six planes") };
                    table.lookup_method_rows(
                        &melanin[start..end],
                        &blend[start..end],
                        &hemoglobin[start..end],
                        [&mut c0[..n], &mut c1[..n], &mut c2[..n]],
                        [&mut r0[..n], &mut r1[..n], &mut r2[..n]],
                    );
                }
                out[0][0]
            })
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
