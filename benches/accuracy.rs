//! Criterion medians behind docs/accuracy-vs-time.md: one material evaluation (albedo + radius) at each named accuracy
//! level and wavelength placement, and one wavelength's radial profile by the closed-form route against the FFT route.
//! The full sweep of every knob, with errors, is `examples/accuracy_report` (scripts/accuracy_report.sh).

use criterion::{criterion_group, criterion_main, Criterion};
use spectral_skin::accuracy::ALL_ACCURACY_LEVELS;
use spectral_skin::color::WavelengthPlacement;
use spectral_skin::diffusion::{
    fft_reflectance_profiles, reflectance_profiles, Combination, FftGrid, HankelQuadrature, LayerStack, MultipoleTerms,
};
use spectral_skin::skin::skin_layers;
use spectral_skin::{evaluate, Accuracy, Outputs, Request, SkinModel, SkinParams};

fn bench_levels(c: &mut Criterion) {
    let params = SkinParams::preset("caucasian").unwrap();
    let mut group = c.benchmark_group("material/caucasian");
    for level in ALL_ACCURACY_LEVELS {
        let request = Request {
            accuracy: level.accuracy(),
            ..Request::new(Outputs { albedo: true, radius: true, ..Outputs::default() })
        };
        group.bench_function(level.name(), |b| b.iter(|| evaluate(&params, &request).unwrap()));
    }
    for (name, placement) in
        [("cmf_adapted_20nm", WavelengthPlacement::CmfAdapted), ("rgb_shortcut", WavelengthPlacement::RgbShortcut)]
    {
        let accuracy = Accuracy { wavelength_step_nm: 20.0, wavelength_placement: placement, ..Accuracy::default() };
        let request =
            Request { accuracy, ..Request::new(Outputs { albedo: true, radius: true, ..Outputs::default() }) };
        group.bench_function(name, |b| b.iter(|| evaluate(&params, &request).unwrap()));
    }
    group.finish();
}

fn bench_profile_routes(c: &mut Criterion) {
    let params = SkinParams::preset("caucasian").unwrap();
    let stack = [LayerStack::new(&skin_layers(&params, &SkinModel::default(), 550.0)).unwrap()];
    let radii: Vec<f64> = (0..41).map(|i| 0.01 * 1000f64.powf(i as f64 / 40.0)).collect();
    let (comb, terms) = (Combination::Directional, MultipoleTerms::All);
    let mut group = c.benchmark_group("profile_one_wavelength/caucasian_550nm");
    group.sample_size(10);
    group.bench_function("closed_form_default", |b| {
        b.iter(|| reflectance_profiles(&stack, &radii, comb, terms, &HankelQuadrature::default()))
    });
    for size in [256, 512] {
        let grid = FftGrid { size, extent_mm: 40.0 };
        group.bench_function(format!("fft_{size}_40mm"), |b| {
            b.iter(|| fft_reflectance_profiles(&stack, &radii, comb, terms, grid).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, bench_levels, bench_profile_routes);
criterion_main!(benches);
