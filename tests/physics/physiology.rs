//! Physiological trends, request-driven evaluation and property tests over the whole parameter domain.

use proptest::prelude::*;
use spectral_skin::{evaluate, Outputs, Request, SkinParams};

fn albedo(p: SkinParams) -> [f64; 3] {
    evaluate(&p, &Request::new(Outputs { albedo: true, ..Outputs::default() }))
        .unwrap()
        .diffuse_reflectance_rgb
        .unwrap()
}

/// More melanin darkens every channel, and blue most (melanin absorbs most at short wavelengths), from light to
/// medium skin (C_m 0.02 -> 0.1; ratios dark/light R G B at blend 1: 0.303 0.302 0.294). Further, the exact totals
/// saturate in the blue: once the epidermis hides the dermis, what is left is the epidermis's own scattering near the
/// surface, which more melanin lowers only slowly, while red still loses its dermal light (C_m 0.02 -> 0.2 at blend
/// 1: 0.153 0.163 0.159; diffusion, which overstates that near-surface light, kept blue the most darkened there).
#[test]
fn melanin_darkens_blue_most() {
    for blend in [0.0, 0.5, 1.0] {
        let light = albedo(SkinParams::new(0.02, blend, 0.01, 0.3).unwrap());
        let dark = albedo(SkinParams::new(0.1, blend, 0.01, 0.3).unwrap());
        let ratio: Vec<f64> = (0..3).map(|c| dark[c] / light[c]).collect();
        assert!(ratio.iter().all(|r| *r < 1.0), "blend {blend}: {ratio:?}");
        assert!(ratio[2] < ratio[1] && ratio[2] < ratio[0], "blend {blend}: {ratio:?}");
    }
}

/// More blood lowers green relative to red in light skin (haemoglobin's Q-bands at 542 and 576 nm). In pigmented
/// skin the epidermis absorbs the green before it reaches the blood, and the shift fades (measured, C_h 0.002 -> 0.02:
/// G/R falls by 0.137 at C_m = 0, 0.092 at 0.005, 0.034 at 0.02, and changes by under 0.007 from C_m = 0.05 up),
/// as erythema is harder to see on dark skin.
#[test]
fn hemoglobin_lowers_green_relative_to_red() {
    let shift = |melanin: f64| {
        let pale = albedo(SkinParams::new(melanin, 0.7, 0.002, 0.3).unwrap());
        let flushed = albedo(SkinParams::new(melanin, 0.7, 0.02, 0.3).unwrap());
        assert!(flushed[1] < pale[1], "C_m {melanin}: more blood must lower green: {flushed:?} vs {pale:?}");
        flushed[1] / flushed[0] - pale[1] / pale[0]
    };
    let light: Vec<f64> = [0.0, 0.005, 0.02].iter().map(|&m| shift(m)).collect();
    assert!(light.iter().all(|d| *d < -0.02), "{light:?}");
    assert!(light.windows(2).all(|w| w[1] > w[0]), "the shift fades with melanin: {light:?}");
    for m in [0.05, 0.15, 0.3] {
        let s = shift(m);
        assert!(s.abs() < light[2].abs(), "C_m {m}: shift {s} vs {} at C_m 0.02", light[2]);
    }
}

/// Albedo alone computes no radial profile and no fit; each output appears only when asked for.
#[test]
fn only_requested_outputs_are_computed() {
    let p = SkinParams::preset("asian").unwrap();
    let ev = evaluate(&p, &Request::new(Outputs { albedo: true, ..Outputs::default() })).unwrap();
    assert_eq!(ev.work.radial_profiles, 0);
    assert_eq!(ev.work.transform_samples, ev.work.wavelengths, "one transform value per wavelength");
    assert_eq!((ev.work.radius_fits, ev.work.specular_evaluations), (0, 0), "no fit, no specular: not asked");
    assert!(
        ev.methods.is_none() && ev.profile.is_none() && ev.specular.is_none() && ev.spectral_reflectance.is_none(),
        "albedo alone computed methods {}, profile {}, specular {}, spectral reflectance {}",
        ev.methods.is_some(),
        ev.profile.is_some(),
        ev.specular.is_some(),
        ev.spectral_reflectance.is_some()
    );

    let ev = evaluate(&p, &Request::new(Outputs { specular: true, ..Outputs::default() })).unwrap();
    assert_eq!(ev.work.wavelengths, 0, "specular alone needs no spectral work");
    assert_eq!((ev.work.radius_fits, ev.work.specular_evaluations, ev.work.radial_profiles), (0, 1, 0));
    assert!(
        ev.specular.is_some() && ev.diffuse_reflectance_rgb.is_none(),
        "specular alone: specular {:?}, albedo {:?}",
        ev.specular,
        ev.diffuse_reflectance_rgb
    );

    let ev = evaluate(&p, &Request::new(Outputs { albedo: true, radius: true, ..Outputs::default() })).unwrap();
    assert_eq!(ev.work.radial_profiles, 0, "the radius fit works in the frequency domain");
    assert_eq!((ev.work.radius_fits, ev.work.specular_evaluations), (3, 0), "one fit per RGB channel");
    assert!(ev.methods.is_some(), "albedo and radius: no methods, work {:?}", ev.work);

    let ev = evaluate(&p, &Request::new(Outputs { profile_rgb: true, ..Outputs::default() })).unwrap();
    assert_eq!(ev.work.radial_profiles, ev.work.wavelengths);
    assert_eq!((ev.work.radius_fits, ev.work.specular_evaluations), (0, 0), "a profile needs no fit");
    let profile = ev.profile.unwrap();
    assert!(
        profile.rgb_per_mm2.is_some() && profile.spectral_per_mm2.is_none(),
        "RGB profile alone: rgb {}, spectral {}",
        profile.rgb_per_mm2.is_some(),
        profile.spectral_per_mm2.is_some()
    );
}

/// The RGB profile integrates (2 pi r dr) to the RGB albedo: profile and total agree.
#[test]
fn rgb_profile_integrates_to_albedo() {
    for preset in ["caucasian", "african"] {
        let mut request = Request::new(Outputs { albedo: true, profile_rgb: true, ..Outputs::default() });
        request.accuracy.profile_grid.count = 400;
        request.accuracy.profile_grid.r_min_mm = 1e-5;
        request.accuracy.profile_grid.r_max_mm = 60.0;
        let ev = evaluate(&SkinParams::preset(preset).unwrap(), &request).unwrap();
        let a = ev.diffuse_reflectance_rgb.unwrap();
        let prof = ev.profile.unwrap();
        let r = &prof.radii_mm;
        let rgb = prof.rgb_per_mm2.unwrap();
        for c in 0..3 {
            // Trapezoid in ln r of 2 pi r^2 R(r), plus the disc inside r_min.
            let g: Vec<f64> = r.iter().zip(&rgb).map(|(r, v)| 2.0 * std::f64::consts::PI * r * r * v[c]).collect();
            let inner = std::f64::consts::PI * r[0] * r[0] * rgb[0][c];
            let integral: f64 =
                inner + (1..r.len()).map(|i| 0.5 * (g[i] + g[i - 1]) * (r[i] / r[i - 1]).ln()).sum::<f64>();
            assert!(
                ((integral - a[c]) / a[c]).abs() < 2e-3,
                "{preset} channel {c}: integral {integral} albedo {}",
                a[c]
            );
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// Anywhere in the domain: finite albedo in (0, 1), finite positive radii, expected albedos <= albedo.
    #[test]
    fn whole_domain_is_finite(m in 0.0..=0.5f64, b in 0.0..=1.0f64, h in 0.0..=0.1f64, o in 0.0..=1.0f64) {
        let ev = evaluate(&SkinParams::new(m, b, h, o).unwrap(), &Request::new(Outputs::material())).unwrap();
        let a = ev.diffuse_reflectance_rgb.unwrap();
        prop_assert!(a.iter().all(|v| v.is_finite() && *v > 0.0 && *v < 1.0), "{a:?}");
        let methods = ev.methods.unwrap();
        for (_, mp) in methods.iter() {
            prop_assert!(mp.subsurface_radius_mm.iter().all(|v| v.is_finite() && *v > 0.0), "{mp:?}");
            prop_assert!(mp.base_color.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)), "{mp:?}");
            prop_assert!((0..3).all(|c| mp.expected_albedo[c] <= a[c] + 1e-9), "{mp:?} vs albedo {a:?}");
        }
        let s = ev.specular.unwrap();
        prop_assert!(s.specular_ior_level.is_finite() && s.roughness.is_finite(), "{s:?}");
    }
}
