//! The palette of measured skin tones (docs/measured-skin.md, section Palette; the `ita-*` presets of
//! src/skin/params.rs): the Xiao et al. 2016 in-vivo spectra (data/xiao2016_skin_reflectance_400_700nm.csv) grouped
//! by the ITA° class of their measured colour (`spectral_skin::color::ita`), each class's median spectrum (the median
//! at each wavelength) fitted with `fit_spectrum`'s defaults. Prints the table; with `--write`, rewrites the presets'
//! block in src/skin/params.rs and the section's table in docs/measured-skin.md (between their markers).
//!
//! cargo run --release --example palette [-- --write]

use spectral_skin::color::ita::{ita_class, ita_degrees, ItaClass, ITA_CLASSES};
use spectral_skin::inverse::{FitOptions, SpectrumFit, SpectrumFitter};

const DATA: &str = "data/xiao2016_skin_reflectance_400_700nm.csv";
const PARAMS_RS: &str = "src/skin/params.rs";
const DOC: &str = "docs/measured-skin.md";
/// The least spectra a class needs for its median to become a preset.
const MIN_SPECTRA: usize = 20;
/// The oiliness of every preset (the paper's presets' 0.3): a reflectance spectrum does not determine it.
const OILINESS: f64 = 0.3;

/// The wavelengths and spectra of the data file (comment lines start with '#'; then a header `index,R400,...`).
fn read_data(path: &str) -> (Vec<f64>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).expect("read the data file");
    let mut lines = spectral_skin::strip_utf8_bom(&text).lines().filter(|l| !l.starts_with('#'));
    let header = lines.next().expect("header");
    let wavelengths = header.split(',').skip(1).map(|h| h.trim_start_matches('R').parse().unwrap()).collect();
    let spectra = lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.split(',').skip(1).map(|v| v.parse().unwrap()).collect())
        .collect();
    (wavelengths, spectra)
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

/// A class, its spectra's count and median spectrum, and the fit of that median.
struct Tone {
    class: &'static ItaClass,
    count: usize,
    fit: SpectrumFit,
}

fn tones(wavelengths: &[f64], spectra: &[Vec<f64>]) -> Vec<Tone> {
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
        if members.len() < MIN_SPECTRA {
            eprintln!("{}: {} spectra, fewer than {MIN_SPECTRA}: no preset", class.name, members.len());
            continue;
        }
        let median_spectrum: Vec<f64> =
            (0..wavelengths.len()).map(|k| median(members.iter().map(|s| s[k]).collect())).collect();
        let fit = fitter.fit(&median_spectrum).expect("fit of a class median");
        out.push(Tone { class, count: members.len(), fit });
    }
    out
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

/// `text` with the lines between the line containing `begin` and the line containing `end` replaced by `body`.
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
        let doc = std::fs::read_to_string(DOC).expect("read the doc");
        let doc = replace_between(&doc, "<!-- BEGIN palette table", "<!-- END palette table", &table);
        std::fs::write(DOC, doc).expect("write the doc");
        eprintln!("wrote {PARAMS_RS} and {DOC}");
    }
}
