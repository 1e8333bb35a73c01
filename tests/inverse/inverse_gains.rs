//! The exposure and white-balance gains (`rgb_gains="auto"`, src/inverse/albedo_gains.rs) against a photograph whose
//! light is known: the face-like example parameter map made fair (its melanin a quarter, 0.005 to 0.0075 outside the
//! freckles, the Caucasian preset's 0.005), its albedo by the core's `evaluate` (the forward model, not the fit's
//! table), then lit. Exposure trades against melanin inside skin's colours, so what the gains can recover is what
//! leaves skin's colours: a well-exposed photograph keeps its exposure (and its melanin), an over-exposed warm one
//! comes back towards its light. An under-exposed one is darker skin to any fit (docs/skin-atlas.md, "The gains").

use spectral_skin::color::WorkingSpace;
use spectral_skin::evaluate::{evaluate, Outputs, Request};
use spectral_skin::inverse::albedo::AlbedoFitOptions;
use spectral_skin::inverse::albedo_maps::{fit_albedo_map, AlbedoMapFit, TextureFit};
use spectral_skin::maps::example::face_params;
use spectral_skin::skin::SkinParams;

const SIZE: usize = 32;

/// The fair face's melanin per texel and its albedo (linear Rec.709).
fn fair_face() -> (Vec<f64>, Vec<[f64; 3]>) {
    let params = face_params(SIZE);
    let request = Request {
        working_space: WorkingSpace::LinearRec709,
        ..Request::new(Outputs { albedo: true, ..Outputs::default() })
    };
    (0..SIZE * SIZE)
        .map(|i| {
            let t = params.texel(i);
            let p = SkinParams::new(0.25 * t[0] as f64, t[1] as f64, t[2] as f64, t[3] as f64).unwrap();
            (p.melanin, evaluate(&p, &request).unwrap().diffuse_reflectance_rgb.unwrap())
        })
        .unzip()
}

/// A deterministic value in [0, 1) per texel (Knuth's multiplicative hash).
fn hash01(i: usize) -> f64 {
    ((i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40) as f64 / (1u64 << 24) as f64
}

/// The mean over the texels of the fitted melanin, and of the truth, where `keep` (the skin, not the highlights).
fn mean_melanin(fit: &AlbedoMapFit, truth: &[f64], keep: impl Fn(usize) -> bool) -> (f64, f64) {
    let kept: Vec<usize> = (0..truth.len()).filter(|&i| keep(i)).collect();
    let n = kept.len() as f64;
    (kept.iter().map(|&i| fit.params[i][0] as f64).sum::<f64>() / n, kept.iter().map(|&i| truth[i]).sum::<f64>() / n)
}

fn auto_fit(texels: &[[f64; 3]]) -> AlbedoMapFit {
    let texels: Vec<[f32; 3]> = texels.iter().map(|c| c.map(|v| v as f32)).collect();
    let texture = TextureFit { auto_gains: true, ..TextureFit::default() };
    fit_albedo_map(
        &texels,
        SIZE,
        SIZE,
        &AlbedoFitOptions { working_space: WorkingSpace::LinearRec709, ..Default::default() },
        texture,
    )
    .unwrap()
}

/// A well-exposed photograph of the fair face, shaded by 0.9 to 1.05 per texel and with a highlight (half-way to a
/// white of 0.9) on 5 % of its texels: the gains keep the exposure (within 0.1 stops) and the skin stays fair (mean
/// melanin of the texels without a highlight within 25 % of the truth). Before the exposure had a price the gains
/// took it 0.5 stops darker, to bring the highlights inside, and the melanin rose threefold.
#[test]
fn a_well_exposed_fair_face_keeps_its_exposure_and_its_melanin() {
    let (truth, albedo) = fair_face();
    let highlight = |i: usize| hash01(i) < 0.05;
    let photo: Vec<[f64; 3]> = albedo
        .iter()
        .enumerate()
        .map(
            |(i, c)| if highlight(i) { c.map(|v| 0.5 * v + 0.45) } else { c.map(|v| v * (0.9 + 0.15 * hash01(i + 7))) },
        )
        .collect();
    let fit = auto_fit(&photo);
    let g = fit.gains.as_ref().unwrap();
    let (fitted, made) = mean_melanin(&fit, &truth, |i| !highlight(i));
    println!(
        "well exposed: gains {:?} ({:+.3} stops), mean melanin {fitted:.5} against {made:.5}",
        g.rgb_gains, g.exposure_stops
    );
    assert!(g.exposure_stops.abs() <= 0.1, "{g:?}");
    assert!((fitted / made - 1.0).abs() <= 0.25, "mean melanin {fitted} against {made}: {g:?}");
}

/// The fair face over-exposed (x 1.4) under a warm light (R x 1.25, B x 0.75): the gains undo the white balance
/// (R/G and B/G within 15 % of the light's inverse), most of the exposure (within 0.3 stops of the -0.54 applied:
/// what is left the fit reads as a slightly fairer skin, never a darker one) and the melanin comes back within 25 %.
#[test]
fn an_over_exposed_warm_photograph_comes_back_towards_its_light() {
    let (truth, albedo) = fair_face();
    let light = [1.4 * 1.25, 1.4, 1.4 * 0.75];
    let photo: Vec<[f64; 3]> = albedo.iter().map(|c| [0, 1, 2].map(|k| c[k] * light[k])).collect();
    let fit = auto_fit(&photo);
    let g = fit.gains.as_ref().unwrap();
    let (fitted, made) = mean_melanin(&fit, &truth, |_| true);
    let stops = -(0.2126 * light[0] + 0.7152 * light[1] + 0.0722 * light[2]).log2(); // Rec.709 luminance (BT.709)
    println!(
        "over-exposed, warm: gains {:?} ({:+.3} stops, applied {stops:+.3}), mean melanin {fitted:.5} against \
         {made:.5}",
        g.rgb_gains, g.exposure_stops
    );
    for (c, name) in [(0, "R/G"), (2, "B/G")] {
        let (found, made) = (g.rgb_gains[c] / g.rgb_gains[1], light[1] / light[c]);
        assert!((found / made - 1.0).abs() <= 0.15, "{name}: {found} against the light's {made}");
    }
    assert!((g.exposure_stops - stops).abs() <= 0.3, "{g:?} against {stops} stops");
    assert!((fitted / made - 1.0).abs() <= 0.25, "mean melanin {fitted} against {made}: {g:?}");
}
