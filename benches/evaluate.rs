//! Time of one `evaluate` for albedo only, albedo + radius, and a full RGB profile (criterion; median reported), with
//! the default transport (exact totals) and with the paper's diffusion totals, so that the transport's cost reads as a
//! ratio within one run; and the specular inputs alone per surface model (the measured surface's hemispherical albedo
//! is memoised per oiliness: this is its steady-state cost, the first call at an oiliness takes tens of ms).

use criterion::{criterion_group, criterion_main, Criterion};
use spectral_skin::surface::lobes::ALL_SURFACE_MODELS;
use spectral_skin::transport::ALL_TRANSPORTS;
use spectral_skin::{evaluate, Outputs, Request, SkinParams};

fn bench_evaluate(c: &mut Criterion) {
    let params = SkinParams::preset("caucasian").unwrap();
    let cases = [
        ("albedo", Outputs { albedo: true, ..Outputs::default() }),
        ("albedo+radius", Outputs { albedo: true, radius: true, ..Outputs::default() }),
        ("profile_rgb", Outputs { profile_rgb: true, ..Outputs::default() }),
    ];
    let mut group = c.benchmark_group("evaluate/caucasian");
    for (name, outputs) in cases {
        for transport in ALL_TRANSPORTS {
            let request = Request { transport, ..Request::new(outputs) };
            let id = format!("{name}/{}", transport.name());
            group.bench_function(id, |b| b.iter(|| evaluate(&params, &request).unwrap()));
        }
    }
    for surface in ALL_SURFACE_MODELS {
        let request = Request { surface, ..Request::new(Outputs { specular: true, ..Outputs::default() }) };
        group.bench_function(format!("specular/{}", surface.name()), |b| {
            b.iter(|| evaluate(&params, &request).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, bench_evaluate);
criterion_main!(benches);
