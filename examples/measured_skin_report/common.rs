//! Whether the residual left in the Q bands is light skin's own or one the classes share, scaled by their reflectance
//! (docs/measured-skin.md, One residual for every skin type): each class's mean residual relative to its measured
//! reflectance, how closely its shape follows the light class's, and how much of it one correction for every class
//! takes away when estimated on the other half of the spectra.

use spectral_skin::color::ita::ITA_CLASSES;
use spectral_skin::inverse::SpectrumFit;

use super::classes::{in_q_bands, members};

/// The class every other class's relative residual is compared with (its `ItaClass::name`): the one issue 39 names.
const REFERENCE_CLASS: &str = "light";

/// The mean residual (measured − fitted) over `members` at each wavelength, relative to their mean measured
/// reflectance there (a ratio of means: a few dark spectra's small reflectances do not dominate it).
fn relative_residual(members: &[usize], fits: &[SpectrumFit], measured: &[Vec<f64>]) -> Vec<f64> {
    (0..measured[members[0]].len())
        .map(|k| {
            let residual: f64 = members.iter().map(|&i| measured[i][k] - fits[i].fitted_reflectance[k]).sum();
            let level: f64 = members.iter().map(|&i| measured[i][k]).sum();
            residual / level
        })
        .collect()
}

/// Pearson's correlation of `a` and `b`.
fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (ma, mb) = (mean(a), mean(b));
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let var = |v: &[f64], m: f64| v.iter().map(|x| (x - m).powi(2)).sum::<f64>();
    cov / (var(a, ma) * var(b, mb)).sqrt()
}

/// The rms over the Q bands of the mean over `members` of measured − `scale` × fitted.
fn q_rms(members: &[usize], fits: &[SpectrumFit], measured: &[Vec<f64>], wl: &[f64], scale: &[f64]) -> f64 {
    let n = members.len() as f64;
    let band: Vec<usize> = (0..wl.len()).filter(|&k| in_q_bands(wl[k])).collect();
    let mean =
        |k: usize| members.iter().map(|&i| measured[i][k] - scale[k] * fits[i].fitted_reflectance[k]).sum::<f64>() / n;
    (band.iter().map(|&k| mean(k).powi(2)).sum::<f64>() / band.len() as f64).sqrt()
}

/// Prints, per class: its relative mean residual over the Q bands (rms, %), the correlation of its relative mean
/// residual at every wavelength with the light class's, and the Q-band rms of its odd-numbered spectra before and
/// after one correction for every class (the mean of measured / fitted over the even-numbered spectra of all classes).
pub fn print_common_residual(fits: &[SpectrumFit], measured: &[Vec<f64>], wl: &[f64]) {
    let even: Vec<usize> = (0..fits.len()).step_by(2).collect();
    let correction: Vec<f64> = (0..wl.len())
        .map(|k| even.iter().map(|&i| measured[i][k] / fits[i].fitted_reflectance[k]).sum::<f64>() / even.len() as f64)
        .collect();
    let reference = ITA_CLASSES.iter().find(|c| c.name == REFERENCE_CLASS).expect("the light class");
    let reference_members = members(fits, reference);
    if reference_members.is_empty() {
        return;
    }
    let reference_shape = relative_residual(&reference_members, fits, measured);
    let ones = vec![1.0; wl.len()];
    println!(
        "\nOne residual for every class? (relative residual: the mean residual over the mean measured reflectance, \
         per wavelength; the correction: the mean of measured / fitted over the even-numbered spectra of every class, \
         applied to the odd-numbered)\n"
    );
    println!("| group (ITA) | Q-band rms of the relative residual | correlation with light's, 400-700 nm | Q-band rms, odd spectra: as fitted / corrected |");
    println!("|---|---|---|---|");
    for class in &ITA_CLASSES {
        let class_members = members(fits, class);
        let odd: Vec<usize> = class_members.iter().copied().filter(|i| i % 2 == 1).collect();
        if odd.is_empty() {
            continue;
        }
        let shape = relative_residual(&class_members, fits, measured);
        let band: Vec<f64> = (0..wl.len()).filter(|&k| in_q_bands(wl[k])).map(|k| shape[k]).collect();
        let band_rms = (band.iter().map(|v| v * v).sum::<f64>() / band.len() as f64).sqrt();
        println!(
            "| {} | {:.2} % | {:.2} | {:.4} / {:.4} |",
            class.label,
            100.0 * band_rms,
            correlation(&shape, &reference_shape),
            q_rms(&odd, fits, measured, wl, &ones),
            q_rms(&odd, fits, measured, wl, &correction)
        );
    }
    let cells: Vec<String> = correction.iter().map(|c| format!("{:+.1}", 100.0 * (c - 1.0))).collect();
    println!("\nThe correction, % (wavelengths {} to {} nm): {}", wl[0], wl[wl.len() - 1], cells.join(" "));
}
