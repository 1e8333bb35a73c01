//! What exact transport costs where many totals are needed (criterion; medians): `fit_spectrum` with its defaults on
//! measured in-vivo spectra (eight of data/xiao2016_skin_reflectance_400_700nm.csv, spread over its rows, one at a
//! time), `evaluate` of the albedo and of albedo + radius on one thread, and the albedo fit's table built cold (what the
//! first `fit_albedo` of a process pays). The per-texel lookup and the maps are `benches/maps.rs`; whole textures
//! `examples/albedo_fit_timing.rs`.
//!
//!     cargo bench --bench exact_speed

use criterion::{criterion_group, criterion_main, Criterion};
use spectral_skin::inverse::albedo::{AlbedoFitOptions, AlbedoTable};
use spectral_skin::inverse::{fit_spectrum, FitOptions};
use spectral_skin::{evaluate, Outputs, Request, SkinParams};

/// Eight measured spectra (wavelengths in nm, reflectance fractions), rows spread evenly over the file.
fn measured_spectra() -> (Vec<f64>, Vec<Vec<f64>>) {
    let text = include_str!("../data/xiao2016_skin_reflectance_400_700nm.csv");
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header = lines.next().expect("a header");
    let wavelengths: Vec<f64> =
        header.split(',').skip(1).map(|h| h.trim_start_matches('R').parse().expect("R<nm>")).collect();
    let rows: Vec<Vec<f64>> =
        lines.map(|l| l.split(',').skip(1).map(|v| v.parse().expect("a number")).collect()).collect();
    let step = rows.len() / 8;
    (wavelengths, (0..8).map(|k| rows[k * step + step / 2].clone()).collect())
}

fn bench_exact_speed(c: &mut Criterion) {
    let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let mut group = c.benchmark_group("exact_speed");
    group.sample_size(10);

    let (wavelengths, spectra) = measured_spectra();
    let options = FitOptions::default();
    group.bench_function("fit_spectrum_measured_x8", |b| {
        b.iter(|| spectra.iter().map(|r| fit_spectrum(&wavelengths, r, &options).unwrap().delta_e00).sum::<f64>())
    });

    let params = SkinParams::preset("caucasian").unwrap();
    for (name, outputs) in [
        ("evaluate_albedo_one_thread", Outputs { albedo: true, ..Outputs::default() }),
        ("evaluate_albedo_radius_one_thread", Outputs { albedo: true, radius: true, ..Outputs::default() }),
    ] {
        let request = Request::new(outputs);
        // The whole timing loop runs on the one-thread pool: each evaluation's parallel loops stay on that thread,
        // and no iteration pays a hand-off to another thread (a sleeping thread's wake-up took ~50 us on an idle
        // machine, more than the albedo's evaluation itself).
        group.bench_function(name, |b| one_thread.install(|| b.iter(|| evaluate(&params, &request).unwrap())));
    }

    group.bench_function("albedo_table_cold", |b| b.iter(|| AlbedoTable::build(&AlbedoFitOptions::default()).unwrap()));
    group.finish();
}

criterion_group!(benches, bench_exact_speed);
criterion_main!(benches);
