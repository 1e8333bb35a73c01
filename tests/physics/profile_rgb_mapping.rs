//! The RGB radial profile's colour mapping (issue 10, class 8): with the default linear map a channel is negative
//! at radii whose light lies outside the working space's gamut (every preset has such radii); `RgbMapping::
//! NonNegative` gives no negative value, keeps the luminance and leaves in-gamut radii untouched.
//!
//! The references are independent of the mapping: the luminance Y of each radius is integrated from the spectral
//! profile against the colour tables' Y weights (never through the RGB weights), and the RGB colours are turned back
//! into luminance with Rec.709's published luminance row (Lindbloom's sRGB-to-XYZ matrix, D65).

use spectral_skin::color::{RgbMapping, WavelengthGrid};
use spectral_skin::evaluate::ProfileGrid;
use spectral_skin::{evaluate, Outputs, Request, SkinParams, PRESETS};

/// The middle row of the published sRGB (Rec.709, D65) RGB-to-XYZ matrix (Lindbloom, white (0.95047, 1, 1.08883)).
const PUBLISHED_LUMA: [f64; 3] = [0.2126729, 0.7151522, 0.0721750];

/// Radii from the core to the far tail: 0.001 mm to 100 mm, where the tails of every preset are out of gamut.
const GRID: ProfileGrid = ProfileGrid { r_min_mm: 0.001, r_max_mm: 100.0, count: 96 };

struct Profiles {
    radii_mm: Vec<f64>,
    linear: Vec<[f64; 3]>,
    non_negative: Vec<[f64; 3]>,
    /// Y per radius from the spectral profile, relative to the white (Y of a perfect reflector = 1).
    luminance: Vec<f64>,
}

fn profiles(params: &SkinParams) -> Profiles {
    let request = |outputs: Outputs, rgb_mapping: RgbMapping| {
        let mut r = Request { rgb_mapping, ..Request::new(outputs) };
        r.accuracy.profile_grid = GRID;
        r
    };
    let rgb_request = |m| request(Outputs { profile_rgb: true, ..Outputs::default() }, m);
    let linear = evaluate(params, &rgb_request(RgbMapping::Linear)).unwrap().profile.unwrap();
    let non_negative = evaluate(params, &rgb_request(RgbMapping::NonNegative)).unwrap().profile.unwrap();
    let spectral_request = request(Outputs { profile_spectral: true, ..Outputs::default() }, RgbMapping::Linear);
    let spectral = evaluate(params, &spectral_request).unwrap();
    let wavelengths = spectral.wavelengths_nm.unwrap();
    let spectral = spectral.profile.unwrap().spectral_per_mm2.unwrap();
    // The Y weights of the same wavelengths (the colour tables integrated against the interpolated spectrum).
    let y_weights: Vec<f64> =
        WavelengthGrid { wavelengths_nm: wavelengths }.xyz_weights().iter().map(|w| w[1]).collect();
    let white_y: f64 = y_weights.iter().sum();
    let luminance = (0..linear.radii_mm.len())
        .map(|i| spectral.iter().zip(&y_weights).map(|(p, w)| p[i] * w).sum::<f64>() / white_y)
        .collect();
    Profiles {
        radii_mm: linear.radii_mm,
        linear: linear.rgb_per_mm2.unwrap(),
        non_negative: non_negative.rgb_per_mm2.unwrap(),
        luminance,
    }
}

fn luma(rgb: [f64; 3]) -> f64 {
    (0..3).map(|c| PUBLISHED_LUMA[c] * rgb[c]).sum()
}

#[test]
fn linear_profile_is_negative_in_every_presets_tail() {
    for preset in PRESETS {
        let p = profiles(&preset.params);
        let negative: Vec<f64> =
            p.radii_mm.iter().zip(&p.linear).filter(|(_, v)| v.iter().any(|&c| c < 0.0)).map(|(r, _)| *r).collect();
        assert!(!negative.is_empty(), "{}: no negative channel in 0.001-100 mm", preset.name);
        let peak = p.linear.iter().flatten().fold(0.0f64, |m, &v| m.max(v));
        let worst = p.linear.iter().flatten().fold(0.0f64, |m, &v| m.min(v));
        println!(
            "{}: {} of {} radii negative, from {:.3} mm; most negative {:.3e} mm^-2 = {:.2e} of the peak",
            preset.name,
            negative.len(),
            p.radii_mm.len(),
            negative[0],
            worst,
            worst / peak
        );
    }
}

#[test]
fn non_negative_profile_keeps_luminance_and_in_gamut_radii() {
    for preset in PRESETS {
        let p = profiles(&preset.params);
        let peak_y = p.luminance.iter().fold(0.0f64, |m, &v| m.max(v));
        let mut changed = 0;
        for i in 0..p.radii_mm.len() {
            let (lin, non) = (p.linear[i], p.non_negative[i]);
            let at = format!("{} at {:.4} mm: {lin:?} -> {non:?}", preset.name, p.radii_mm[i]);
            assert!(non.iter().all(|&c| c >= 0.0 && c.is_finite()), "{at}");
            if lin.iter().all(|&c| c >= 0.0) {
                assert_eq!(lin, non, "{at}: an in-gamut colour was changed");
                continue;
            }
            changed += 1;
            assert!(non.contains(&0.0), "{at}: not on the gamut boundary");
            // The luminance integrated from the spectrum, against the published row: equal within the tables'
            // white against Lindbloom's (1e-4 of the colour) and the quadrature's round-off.
            let y = p.luminance[i];
            let tolerance = 2e-4 * lin.iter().map(|c| c.abs()).sum::<f64>() + 1e-12 * peak_y;
            assert!(
                (luma(non) - y).abs() <= tolerance,
                "{at}: Y {} vs {y} from the spectrum, tolerance {tolerance:e}",
                luma(non)
            );
            assert!((luma(lin) - y).abs() <= tolerance, "{at}: linear Y {} vs {y}, tolerance {tolerance:e}", luma(lin));
        }
        assert!(changed > 0, "{}: nothing was out of gamut", preset.name);
    }
}
