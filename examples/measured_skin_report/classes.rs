//! The fits grouped by skin type: the ITA° class of the measured colour (`color::ita`), and per group the fit quality,
//! the mean residual in haemoglobin's Q bands and the fitted physiology (docs/measured-skin.md, Skin types and the Q
//! bands).

use spectral_skin::color::ita::{ita_class, ita_degrees, ItaClass, ITA_CLASSES};
use spectral_skin::inverse::SpectrumFit;

use super::data::{quantile, MIN_CLASS_SPECTRA};

/// The wavelengths where the residual of oxyhaemoglobin's "W" is read: its two Q-band peaks (542 and 577 nm in
/// Prahl's table) and the trough between them (560 nm), as the 10 nm data sample them.
pub const Q_BAND_NM: [f64; 3] = [540.0, 560.0, 580.0];

/// Whether `nm` lies in the Q bands as the report reads them (the "Q-band rms"): 530-590 nm, the two bands and the
/// trough with a sample either side.
pub fn in_q_bands(nm: f64) -> bool {
    (530.0..=590.0).contains(&nm)
}

/// The indices of the fits whose measured colour is of `class`.
pub fn members(fits: &[SpectrumFit], class: &ItaClass) -> Vec<usize> {
    (0..fits.len()).filter(|&i| ita_class(ita_degrees(fits[i].lab_measured)) == Some(class)).collect()
}

/// One class's figures.
pub struct ClassRow {
    pub name: &'static str,
    pub n: usize,
    pub median_de: f64,
    pub p90_de: f64,
    pub median_rms: f64,
    /// Mean of measured - fitted at [`Q_BAND_NM`].
    pub q_residual: [f64; 3],
    /// Root mean square over 530-590 nm of the class's mean residual (measured - fitted).
    pub q_rms: f64,
    /// The class's mean measured reflectance over 530-590 nm (what the Q-band rms is read against).
    pub q_level: f64,
    /// Root mean square of the class's mean residual at the wavelengths outside 530-590 nm: the misfit the Q bands
    /// are read against (a Q-band rms no larger than it leaves no blood signature).
    pub rms_outside_q: f64,
    /// Median fitted melanin, epidermis thickness (mm), haemoglobin, oxygenation, offset.
    pub medians: [f64; 5],
    /// p10 and p90 of the fitted epidermis thickness, mm.
    pub thickness_p10_p90: (f64, f64),
}

/// The rows of the classes that have spectra; `measured[i]` is the spectrum `fits[i]` fitted, on `wl`.
pub fn class_rows(fits: &[SpectrumFit], measured: &[Vec<f64>], wl: &[f64]) -> Vec<ClassRow> {
    let at = |nm: f64| wl.iter().position(|&w| (w - nm).abs() < 1e-9).expect("Q-band wavelength in the data");
    let q_index = Q_BAND_NM.map(at);
    let (band, outside): (Vec<usize>, Vec<usize>) = (0..wl.len()).partition(|&k| in_q_bands(wl[k]));
    let mut rows = Vec::new();
    for class in &ITA_CLASSES {
        let members = members(fits, class);
        if members.is_empty() {
            continue;
        }
        let n = members.len();
        let mean_residual =
            |k: usize| members.iter().map(|&i| measured[i][k] - fits[i].fitted_reflectance[k]).sum::<f64>() / n as f64;
        let rms_over =
            |ks: &[usize]| (ks.iter().map(|&k| mean_residual(k).powi(2)).sum::<f64>() / ks.len() as f64).sqrt();
        let q_rms = rms_over(&band);
        let q_level = band.iter().map(|&k| members.iter().map(|&i| measured[i][k]).sum::<f64>()).sum::<f64>()
            / (band.len() * n) as f64;
        let of = |f: &dyn Fn(&SpectrumFit) -> f64| members.iter().map(|&i| f(&fits[i])).collect::<Vec<f64>>();
        let de = of(&|f| f.delta_e00);
        let thickness = of(&|f| f.params.epidermis_thickness_mm);
        rows.push(ClassRow {
            name: class.label,
            n,
            median_de: quantile(&de, 0.5),
            p90_de: quantile(&de, 0.9),
            median_rms: quantile(&of(&|f| f.rms), 0.5),
            q_residual: q_index.map(mean_residual),
            q_rms,
            q_level,
            rms_outside_q: rms_over(&outside),
            medians: [
                quantile(&of(&|f| f.params.melanin), 0.5),
                quantile(&thickness, 0.5),
                quantile(&of(&|f| f.params.hemoglobin), 0.5),
                quantile(&of(&|f| f.params.blood_oxygenation), 0.5),
                quantile(&of(&|f| f.specular_offset), 0.5),
            ],
            thickness_p10_p90: (quantile(&thickness, 0.1), quantile(&thickness, 0.9)),
        });
    }
    rows
}

/// The worst class median ΔE00 over the best, among classes of at least [`MIN_CLASS_SPECTRA`] spectra.
pub fn worst_over_best(rows: &[ClassRow]) -> f64 {
    let medians: Vec<f64> = rows.iter().filter(|r| r.n >= MIN_CLASS_SPECTRA).map(|r| r.median_de).collect();
    let (lo, hi) = medians.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    hi / lo
}

/// The markdown table of `rows` (the body of the report's by-skin-type blocks in docs/measured-skin.md).
pub fn class_table(rows: &[ClassRow]) -> String {
    let mut table = String::from(
        "| group (ITA) | spectra | median ΔE00 | p90 ΔE00 | median RMS | residual 540 / 560 / 580 nm | Q-band rms | melanin | \
         epidermis mm (p10 / median / p90) | haemoglobin | oxygenation | offset |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let [m, t, h, g, o] = r.medians;
        table += &format!(
            "| {} | {} | {:.2} | {:.2} | {:.4} | {:+.4} / {:+.4} / {:+.4} | {:.4} | {:.3} | {:.3} / {:.3} / {:.3} | {:.4} | \
             {:.2} | {:.3} |\n",
            r.name,
            r.n,
            r.median_de,
            r.p90_de,
            r.median_rms,
            r.q_residual[0],
            r.q_residual[1],
            r.q_residual[2],
            r.q_rms,
            m,
            r.thickness_p10_p90.0,
            t,
            r.thickness_p10_p90.1,
            h,
            g,
            o
        );
    }
    table
}

/// Prints the markdown table of `rows`, the worst / best ratio of their median ΔE00, and each class's Q-band rms
/// relative to its mean measured reflectance there and against the rms of its mean residual elsewhere.
pub fn print_class_table(rows: &[ClassRow]) {
    print!("{}", class_table(rows));
    println!(
        "\nWorst / best class median ΔE00 (classes of {MIN_CLASS_SPECTRA} or more spectra): {:.2}",
        worst_over_best(rows)
    );
    let relative: Vec<String> =
        rows.iter().map(|r| format!("{} {:.2} %", r.name, 100.0 * r.q_rms / r.q_level)).collect();
    println!("Q-band rms / mean measured reflectance over 530-590 nm: {}", relative.join(", "));
    let against: Vec<String> =
        rows.iter().map(|r| format!("{} {:.4} / {:.4}", r.name, r.q_rms, r.rms_outside_q)).collect();
    println!("Q-band rms / rms of the mean residual outside 530-590 nm: {}", against.join(", "));
}
