//! Time of one `evaluate` for albedo only, albedo + radius, and a full RGB profile (criterion; median reported).

use criterion::{criterion_group, criterion_main, Criterion};
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
        let request = Request::new(outputs);
        group.bench_function(name, |b| b.iter(|| evaluate(&params, &request).unwrap()));
    }
    group.finish();
}

criterion_group!(benches, bench_evaluate);
criterion_main!(benches);
