//! The palette of measured skin tones (the `ita-*` presets, src/skin/params.rs; docs/measured-skin.md, Palette)
//! against the measured spectra themselves (Xiao et al. 2016): each preset's model spectrum, plus the best constant
//! surface offset in the fit's range, has the colour of its class's median measured spectrum and lies in that class;
//! the palette spans the classes in order.

use std::sync::atomic::AtomicBool;

use crate::support::measured::xiao_spectra;
use spectral_skin::color::ita::{ita_class, ita_degrees, ITA_CLASSES};
use spectral_skin::evaluate::{diffuse_reflectance_at, Request};
use spectral_skin::inverse::{FitOptions, SpectrumFitter};
use spectral_skin::skin::PRESETS;

/// The largest ΔE00 (D65, CIE 1931 2°) allowed between a preset (with its best offset) and its class's median
/// spectrum: a difference at the threshold of a side-by-side comparison (CIEDE2000 ≈ 1, Sharma et al. 2005).
const MAX_DELTA_E00: f64 = 1.0;
/// The surface offset's range in the fit (`Specular::Free`).
const MAX_OFFSET: f64 = 0.1;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

#[test]
fn palette_presets_match_their_class_medians_in_order() {
    let (wl, spectra) = xiao_spectra(1);
    let fitter = SpectrumFitter::new(&wl, &FitOptions::default()).unwrap();
    let names: Vec<Option<&str>> =
        spectra.iter().map(|s| ita_class(ita_degrees(fitter.lab(s))).map(|c| c.name)).collect();
    let palette: Vec<_> = PRESETS.iter().filter(|p| p.name.starts_with("ita-")).collect();
    assert!(palette.len() >= 5, "the palette has {} presets", palette.len());
    let mut last_ita = f64::INFINITY;
    for preset in palette {
        let class = ITA_CLASSES.iter().find(|c| preset.name == format!("ita-{}", c.name)).expect(preset.name);
        let members: Vec<&Vec<f64>> =
            spectra.iter().zip(&names).filter(|(_, n)| **n == Some(class.name)).map(|(s, _)| s).collect();
        let target: Vec<f64> = (0..wl.len()).map(|k| median(members.iter().map(|s| s[k]).collect())).collect();
        let model = diffuse_reflectance_at(&preset.params, &Request::default(), &wl, &AtomicBool::new(false)).unwrap();
        // The least-squares constant offset, clamped to the fit's range.
        let offset =
            (target.iter().zip(&model).map(|(t, m)| t - m).sum::<f64>() / wl.len() as f64).clamp(0.0, MAX_OFFSET);
        let shown: Vec<f64> = model.iter().map(|m| m + offset).collect();
        let (lab_shown, lab_target) = (fitter.lab(&shown), fitter.lab(&target));
        let de = spectral_skin::color::ciede2000(lab_shown, lab_target);
        assert!(de <= MAX_DELTA_E00, "{}: ΔE00 {de:.2} to its class median (offset {offset:.3})", preset.name);
        let ita = ita_degrees(lab_shown);
        assert_eq!(ita_class(ita).map(|c| c.name), Some(class.name), "{}: ITA {ita:.1}°", preset.name);
        assert!(ita < last_ita, "{}: ITA {ita:.1}° not below the previous preset's {last_ita:.1}°", preset.name);
        last_ita = ita;
    }
}
