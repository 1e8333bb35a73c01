//! The palette of measured skin tones (docs/measured-skin.md, section Palette; the `ita-*` presets of
//! src/skin/params.rs): the Xiao et al. 2016 in-vivo spectra (data/xiao2016_skin_reflectance_400_700nm.csv) grouped
//! by the ITA° class of their measured colour (`spectral_skin::color::ita`), each class's median spectrum (the median
//! at each wavelength) fitted in the paper's three parameters (melanin, melanin blend, haemoglobin) over one epidermis
//! for the whole palette: a spectrum cannot tell the epidermis's thickness from its melanin (docs/measured-skin.md,
//! Fitted parameters), so the palette's tones differ only in pigment and blood, and the thickness, scanned over the
//! published range, is the one whose worst class fits best; the baseline absorption and the oxygenation stay the
//! paper's. Prints the table; with `--write`, rewrites the presets' block in src/skin/params.rs and the section's
//! table in docs/measured-skin.md (between their markers).
//!
//! cargo run --release --example palette [-- --write]

#[path = "measured_skin_report/data.rs"]
mod data;

use data::{quantile, read_data, MIN_CLASS_SPECTRA};
use spectral_skin::color::ita::{ita_class, ita_degrees, ItaClass, ITA_CLASSES};
use spectral_skin::inverse::spectrum::PAPER_FREE;
use spectral_skin::inverse::{FitOptions, SpectrumFit, SpectrumFitter};
use spectral_skin::skin::params::PARAMS;

const DATA: &str = "data/xiao2016_skin_reflectance_400_700nm.csv";
const PARAMS_RS: &str = "src/skin/params.rs";
const DOC: &str = "docs/measured-skin.md";
/// The epidermis thicknesses tried (mm): 0.05 to 0.15 mm every 0.01, the published range of adult epidermis
/// (docs/model.md, Extended physiology).
const THICKNESSES_MM: [f64; 11] = [0.05, 0.06, 0.07, 0.08, 0.09, 0.10, 0.11, 0.12, 0.13, 0.14, 0.15];

/// A class, its spectra's count and median spectrum, and the fit of that median.
struct Tone {
    class: &'static ItaClass,
    count: usize,
    fit: SpectrumFit,
}

/// The fit options of the palette: the paper's three free, the epidermis `thickness_mm`.
fn options(thickness_mm: f64) -> FitOptions {
    let mut options = FitOptions { free: PAPER_FREE.iter().map(|s| s.to_string()).collect(), ..FitOptions::default() };
    let at = PARAMS.iter().position(|p| p.name == "epidermis_thickness_mm").expect("the thickness parameter");
    options.fixed[at] = Some(thickness_mm);
    options
}

/// The class medians, each with its count.
fn class_medians(wavelengths: &[f64], spectra: &[Vec<f64>]) -> Vec<(&'static ItaClass, usize, Vec<f64>)> {
    let fitter = SpectrumFitter::new(wavelengths, &FitOptions::default()).expect("fitter");
    let classes: Vec<Option<&ItaClass>> = spectra.iter().map(|s| ita_class(ita_degrees(fitter.lab(s)))).collect();
    let mut out = Vec::new();
    for class in &ITA_CLASSES {
        let members: Vec<&Vec<f64>> = spectra
            .iter()
            .zip(&classes)
            .filter(|(_, c)| c.map(|c| c.name) == Some(class.name))
            .map(|(s, _)| s)
            .collect();
        if members.len() < MIN_CLASS_SPECTRA {
            eprintln!("{}: {} spectra, fewer than {MIN_CLASS_SPECTRA}: no preset", class.name, members.len());
            continue;
        }
        let median_spectrum: Vec<f64> =
            (0..wavelengths.len()).map(|k| quantile(&members.iter().map(|s| s[k]).collect::<Vec<_>>(), 0.5)).collect();
        out.push((class, members.len(), median_spectrum));
    }
    out
}

/// The palette at the thickness whose worst class fits best.
fn tones(wavelengths: &[f64], spectra: &[Vec<f64>]) -> Vec<Tone> {
    let medians = class_medians(wavelengths, spectra);
    let at = |thickness_mm: f64| -> Vec<Tone> {
        let fitter = SpectrumFitter::new(wavelengths, &options(thickness_mm)).expect("fitter");
        let fit = |m: &Vec<f64>| fitter.fit(m).expect("fit of a class median");
        medians.iter().map(|(class, count, m)| Tone { class, count: *count, fit: fit(m) }).collect()
    };
    let worst = |tones: &[Tone]| tones.iter().map(|t| t.fit.delta_e00).fold(0.0, f64::max);
    let mut best = at(THICKNESSES_MM[0]);
    for &d in &THICKNESSES_MM[1..] {
        let tones = at(d);
        eprintln!("epidermis {d:.2} mm: worst ΔE00 {:.2}", worst(&tones));
        if worst(&tones) < worst(&best) {
            best = tones;
        }
    }
    best
}

fn table(tones: &[Tone]) -> String {
    let mut s = String::from(
        "| preset | ITA class of the spectra | spectra | ITA° of the median | melanin | melanin blend | haemoglobin | \
         epidermis mm | baseline scale | oxygenation | surface offset | ΔE00 fit vs median |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for t in tones {
        let p = &t.fit.params;
        s += &format!(
            "| ita-{} | {} | {} | {:.1} | {:.4} | {:.3} | {:.4} | {:.3} | {:.2} | {:.2} | {:.3} | {:.2} |\n",
            t.class.name,
            t.class.label,
            t.count,
            ita_degrees(t.fit.lab_measured),
            p.melanin,
            p.melanin_blend,
            p.hemoglobin,
            p.epidermis_thickness_mm,
            p.baseline_absorption_scale,
            p.blood_oxygenation,
            t.fit.specular_offset,
            t.fit.delta_e00
        );
    }
    s
}

fn presets_block(tones: &[Tone]) -> String {
    let mut s = String::new();
    for t in tones {
        let p = &t.fit.params;
        s += &format!(
            "    palette(\n        \"ita-{}\",\n        \"median of the {} in-vivo spectra of ITA class {} (Xiao et al. 2016); docs/measured-skin.md\",\n        [{:.4}, {:.3}, {:.4}, {:.3}, {:.2}, {:.2}],\n    ),\n",
            t.class.name,
            t.count,
            t.class.label,
            p.melanin,
            p.melanin_blend,
            p.hemoglobin,
            p.epidermis_thickness_mm,
            p.baseline_absorption_scale,
            p.blood_oxygenation
        );
    }
    s
}

/// `text` with the lines between the line containing `begin` and the line containing `end` replaced by `body` (for
/// params.rs; a doc's blocks are stamped: `spectral_skin::stamp::write_markdown_blocks`).
fn replace_between(text: &str, begin: &str, end: &str, body: &str) -> String {
    let start = text.find(begin).unwrap_or_else(|| panic!("marker {begin:?} not found"));
    let start = start + text[start..].find('\n').expect("line end") + 1;
    let stop = start + text[start..].find(end).unwrap_or_else(|| panic!("marker {end:?} not found"));
    let stop = text[..stop].rfind('\n').map_or(stop, |i| i + 1);
    format!("{}{}{}", &text[..start], body, &text[stop..])
}

fn main() {
    let write = std::env::args().any(|a| a == "--write");
    let (wavelengths, spectra) = read_data(DATA);
    let tones = tones(&wavelengths, &spectra);
    let table = table(&tones);
    println!("{table}");
    let worst = tones.iter().map(|t| t.fit.delta_e00).fold(0.0, f64::max);
    println!("worst ΔE00 of a preset to its class median: {worst:.2}");
    if write {
        let rs = std::fs::read_to_string(PARAMS_RS).expect("read params.rs");
        let rs = replace_between(&rs, "// BEGIN palette", "// END palette", &presets_block(&tones));
        std::fs::write(PARAMS_RS, rs).expect("write params.rs");
        let command = "cargo run --release --example palette -- --write";
        spectral_skin::stamp::write_markdown_blocks(std::path::Path::new(DOC), command, &[("palette table", &table)])
            .expect("write the doc");
        eprintln!("wrote {PARAMS_RS} and {DOC}");
    }
}
