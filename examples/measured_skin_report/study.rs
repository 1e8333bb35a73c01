//! Issue 39's study (`--study`): what leaves light skin's Q-band residual. The fit with the model sampled at the
//! measured wavelengths (as before the bandpass), then each candidate cause alone and in pairs (the instrument's
//! bandpass, a free blood oxygenation, vessel packaging), and what the fitted epidermis thickness trades against, each
//! on the same spectra, printed per ITA class (docs/measured-skin.md, Skin types and the Q bands).

use std::path::Path;

use spectral_skin::color::difference::ciede2000;
use spectral_skin::inverse::aperture::{CM2600D_MAV, CM2600D_SAV};
use spectral_skin::inverse::{Aperture, Bandpass, FitOptions, SpectrumFit, SpectrumFitter, Specular};
use spectral_skin::skin::chromophores::{BloodSpectrum, EumelaninShape};
use spectral_skin::skin::optics::EPIDERMAL_HEMOGLOBIN;
use spectral_skin::skin::scattering::ScatteringShape;
use spectral_skin::skin::SkinModel;
use spectral_skin::stamp::write_markdown_blocks;

use super::classes::{class_rows, class_table, print_class_table, worst_over_best};
use super::data::quantile;
use super::{run, DOC};

/// The vessel radii tried, mm: the superficial dermal plexus's capillaries and venules (about 0.005 to 0.05 mm in
/// radius; Braverman 2000, src/skin/chromophores.rs).
const RADII_MM: [f64; 3] = [0.005, 0.015, 0.04];

/// `o` with `name` freed too.
fn freeing(mut o: FitOptions, name: &str) -> FitOptions {
    o.free.push(name.to_string());
    o
}

fn with_oxygenation(o: FitOptions) -> FitOptions {
    freeing(o, "blood_oxygenation")
}

/// The eumelanin shapes tried beside DJ2006's λ^-3.33 (src/skin/chromophores.rs, `EumelaninShape`): Jacques' melanosome
/// law λ^-3.48; shallower (-2, -2.5, -3) and steeper (-4) power laws that bracket it (brackets, not published
/// values); and Zonios et al.'s exponential at three slopes (0.006 nm^-1 is eq. 3's local slope at 550 nm; their
/// in-vivo slopes are steeper than in vitro).
fn shapes() -> Vec<(String, EumelaninShape)> {
    let mut list = Vec::new();
    for e in [-2.0, -2.5, -3.0, -3.48, -4.0] {
        list.push((format!("eumelanin λ^{e}"), EumelaninShape::PowerLaw { exponent: e }));
    }
    for k in [0.006, 0.009, 0.012] {
        list.push((format!("eumelanin exp(-{k} λ)"), EumelaninShape::Exponential { k_per_nm: k }));
    }
    list
}

fn with_scattering(mut o: FitOptions, shape: ScatteringShape) -> FitOptions {
    o.request.model.scattering_shape = shape;
    o
}

/// The reduced-scattering shapes tried beside DJ2006's eq. 8 (src/skin/scattering.rs, `ScatteringShape`; issue 39,
/// dark skin's red-end residual): the dermis of Jacques and Li's mcxyz tissue list (62 % Rayleigh at 500 nm, Mie
/// λ^-1.0), steeper than eq. 8 in the red; and single power laws λ^-1.0 and λ^-1.5, the range of b the brief names for
/// skin (Jacques 2013, eq. 1), flatter than eq. 8 in the blue.
fn scattering_shapes() -> Vec<(String, ScatteringShape)> {
    vec![
        ("scattering mcxyz dermis".to_string(), ScatteringShape::MieRayleigh { f_ray: 0.62, b_mie: 1.0 }),
        ("scattering λ^-1.0".to_string(), ScatteringShape::MieRayleigh { f_ray: 0.0, b_mie: 1.0 }),
        ("scattering λ^-1.5".to_string(), ScatteringShape::MieRayleigh { f_ray: 0.0, b_mie: 1.5 }),
    ]
}

fn with_aperture(mut o: FitOptions, aperture: Aperture) -> FitOptions {
    o.aperture = Some(aperture);
    o
}

fn with_radius(mut o: FitOptions, radius_mm: f64) -> FitOptions {
    o.request.model.blood_vessel_radius_mm = radius_mm;
    o
}

/// The label suffix of a candidate fitted to the spectra with their last point (700 nm) continued at the slope of the
/// two before it ([`continued_700`]), and scored against the spectra as measured.
const CONTINUED_700: &str = ", 700 nm continued";

/// `spectrum` with its last value replaced by the straight continuation of the two before it.
fn continued_700(spectrum: &[f64]) -> Vec<f64> {
    let mut v = spectrum.to_vec();
    let n = v.len();
    v[n - 1] = 2.0 * v[n - 2] - v[n - 3];
    v
}

/// `fits` (of altered spectra) scored against `measured`: each fit's ΔE00 recomputed from the measured spectrum's colour.
fn scored_against(
    mut fits: Vec<SpectrumFit>,
    measured: &[Vec<f64>],
    wl: &[f64],
    options: &FitOptions,
) -> Vec<SpectrumFit> {
    let fitter = SpectrumFitter::new(wl, options).expect("fitter");
    for (fit, spectrum) in fits.iter_mut().zip(measured) {
        fit.delta_e00 = ciede2000(fitter.lab(spectrum), fitter.lab(&fit.fitted_reflectance));
    }
    fits
}

/// Pushes onto `list` the default fit and the default with the oxygenation free and a Fresnel surface, each with
/// `change` made to its model, labelled "default, NAME" and "default + oxygenation, fresnel, NAME".
fn push_both(list: &mut Vec<(String, FitOptions)>, name: &str, change: impl Fn(&mut SkinModel)) {
    let default = FitOptions::default();
    let oxygenation_fresnel = FitOptions { specular: Specular::Fresnel, ..with_oxygenation(default.clone()) };
    for (prefix, mut options) in [("default", default), ("default + oxygenation, fresnel", oxygenation_fresnel)] {
        change(&mut options.request.model);
        list.push((format!("{prefix}, {name}"), options));
    }
}

/// The candidates: (label, options).
fn candidates() -> Vec<(String, FitOptions)> {
    let fwhm = |w: f64| FitOptions { bandpass: Bandpass::FwhmNm(w), ..FitOptions::default() };
    let points = fwhm(0.0);
    let default = FitOptions::default();
    let mut list = vec![
        ("points (the fit before)".to_string(), points.clone()),
        ("points + oxygenation".to_string(), with_oxygenation(points.clone())),
    ];
    // The bandpass scan: does the residual keep falling as the modelled bandpass widens (something beside it
    // flattens the bands) or turn (it explains what it can)?
    for w in [10.0, 12.5, 15.0, 17.5, 20.0] {
        list.push((format!("bandpass {w} nm"), fwhm(w)));
    }
    list.push(("default (bandpass 1.5 x spacing)".to_string(), default.clone()));
    list.push(("bandpass 10 nm + oxygenation".to_string(), with_oxygenation(fwhm(10.0))));
    list.push(("default + oxygenation".to_string(), with_oxygenation(default.clone())));
    for r in RADII_MM {
        list.push((format!("points + packaging R {r} mm"), with_radius(points.clone(), r)));
        list.push((format!("default + packaging R {r} mm"), with_radius(default.clone(), r)));
    }
    // What the thin epidermis of many fits buys: the thickness held at a published value (0.08 mm: Sandby-Møller et
    // al. 2003's 0.05-0.1 mm), and the surface reflection held at Fresnel's (the free offset trades against it).
    let held = |mut o: FitOptions| {
        o.free.retain(|n| n != "epidermis_thickness_mm");
        o.fixed[4] = Some(0.08);
        o
    };
    let fresnel = |o: FitOptions| FitOptions { specular: Specular::Fresnel, ..o };
    list.push(("default, thickness 0.08 mm".to_string(), held(default.clone())));
    list.push(("default + oxygenation, thickness 0.08 mm".to_string(), held(with_oxygenation(default.clone()))));
    list.push(("default, fresnel".to_string(), fresnel(default.clone())));
    list.push(("default + oxygenation, fresnel".to_string(), fresnel(with_oxygenation(default.clone()))));
    // The melanin spectrum's shape (issue 39, What is left): the default fit and the default with the oxygenation
    // free and a Fresnel surface, with each eumelanin shape.
    for (name, shape) in shapes() {
        push_both(&mut list, &name, |m| m.eumelanin_shape = shape);
    }
    // The measured spectra's last point (issue 39, What is left): every group flattens abruptly from 690 to 700 nm.
    // Fitted to the spectra with 700 nm continued at the 680-690 nm slope; scored against the spectra as measured.
    list.push((format!("default{CONTINUED_700}"), default.clone()));
    list.push((format!("default + oxygenation, fresnel{CONTINUED_700}"), fresnel(with_oxygenation(default.clone()))));
    // The scattering spectrum's shape (issue 39, What is left: dark skin's red-end residual).
    for (name, shape) in scattering_shapes() {
        push_both(&mut list, &name, |m| m.scattering_shape = shape);
    }
    // Epidermal β-carotene (issue 39, What is left: the blue residual's shape), at fixed concentrations.
    for umol in [1.0, 3.0, 10.0] {
        push_both(&mut list, &format!("carotene {umol} umol/L"), |m| m.epidermal_carotene_umol_per_l = umol);
    }
    // Whole blood's measured spectrum instead of haemoglobin in solution (issue 39: the Q bands' depth).
    let whole_blood = |mut o: FitOptions| {
        o.request.model.blood_spectrum = BloodSpectrum::WholeBlood2014;
        o
    };
    list.push(("points, whole blood".to_string(), whole_blood(points.clone())));
    list.push(("default, whole blood".to_string(), whole_blood(default.clone())));
    list.push(("default + oxygenation, whole blood".to_string(), whole_blood(with_oxygenation(default.clone()))));
    list.push(("default, fresnel, whole blood".to_string(), whole_blood(fresnel(default.clone()))));
    list.push((
        "default + oxygenation, fresnel, whole blood".to_string(),
        whole_blood(fresnel(with_oxygenation(default.clone()))),
    ));
    // Blood in the epidermis layer (Donner et al. 2008's C_he), at fixed fractions.
    for fraction in [0.002, 0.005, 0.01] {
        push_both(&mut list, &format!("epidermal blood {fraction}"), |m| m.epidermal_hemoglobin = fraction);
    }
    // The same fitted per spectrum (freed by name, 0..0.1), with the oxygenation free, with a free and a Fresnel
    // surface, and with whole blood's spectrum (its Q bands shallower, its Soret band weaker: blood in the
    // epidermis might make up the violet).
    let blood_fitted = |o: FitOptions| freeing(o, EPIDERMAL_HEMOGLOBIN.name);
    list.push(("default, epidermal blood fitted".to_string(), blood_fitted(default.clone())));
    list.push((
        "default + oxygenation, fresnel, epidermal blood fitted".to_string(),
        blood_fitted(fresnel(with_oxygenation(default.clone()))),
    ));
    list.push((
        "default + oxygenation, epidermal blood fitted".to_string(),
        blood_fitted(with_oxygenation(default.clone())),
    ));
    // The same with a wider bandpass (the Q bands' depth is what the bandpass scan traded against the 580 nm edge).
    for w in [17.5, 20.0] {
        list.push((
            format!("bandpass {w} nm + oxygenation, fresnel, epidermal blood fitted"),
            blood_fitted(fresnel(with_oxygenation(fwhm(w)))),
        ));
    }
    list.push((
        "default + oxygenation, fresnel, whole blood, epidermal blood fitted".to_string(),
        whole_blood(blood_fitted(fresnel(with_oxygenation(default.clone())))),
    ));
    list.push((
        "default + oxygenation, whole blood, epidermal blood fitted".to_string(),
        whole_blood(blood_fitted(with_oxygenation(default.clone()))),
    ));
    // The instrument's aperture (issue 39, What is left): the light the skin carries out of the measured disc, with
    // either of the CM-2600d's masks (the data do not say which).
    for (name, aperture) in [("aperture MAV", CM2600D_MAV), ("aperture SAV", CM2600D_SAV)] {
        list.push((format!("default, {name}"), with_aperture(default.clone(), aperture)));
        list.push((
            format!("default + oxygenation, fresnel, {name}"),
            with_aperture(fresnel(with_oxygenation(default.clone())), aperture),
        ));
        for (shape_name, shape) in scattering_shapes() {
            list.push((
                format!("default + oxygenation, fresnel, {name}, {shape_name}"),
                with_aperture(with_scattering(fresnel(with_oxygenation(default.clone())), shape), aperture),
            ));
        }
    }
    list
}

/// The labels of an `--only` argument (separated by ';'); None: every candidate.
fn labels_of(only: Option<&str>) -> Option<Vec<&str>> {
    only.map(|o| o.split(';').map(str::trim).collect())
}

/// Run the candidates named in `only` (labels separated by ';'; all when None) on `spectra` and print each one's
/// class table, then a summary line per candidate; returns each candidate's label and class table (markdown).
pub fn study(wl: &[f64], spectra: &[Vec<f64>], only: Option<&str>) -> Vec<(String, String)> {
    let wanted = labels_of(only);
    let mut summary = Vec::new();
    let mut tables = Vec::new();
    for (label, options) in candidates() {
        if wanted.as_ref().is_some_and(|w| !w.contains(&label.as_str())) {
            continue;
        }
        let mut r = if label.ends_with(CONTINUED_700) {
            let altered: Vec<Vec<f64>> = spectra.iter().map(|s| continued_700(s)).collect();
            run(&label, wl, &altered, &options)
        } else {
            run(&label, wl, spectra, &options)
        };
        if label.ends_with(CONTINUED_700) {
            r.fits = scored_against(r.fits, spectra, wl, &options);
        }
        let rows = class_rows(&r.fits, spectra, wl);
        println!("\n### {label}\n");
        print_class_table(&rows);
        if options.free.iter().any(|n| n == EPIDERMAL_HEMOGLOBIN.name) {
            print_fitted_blood(&r.fits);
        }
        tables.push((label.clone(), class_table(&rows)));
        print_residual_spectra(&r.fits, spectra, wl);
        super::common::print_common_residual(&r.fits, spectra, wl);
        let de: Vec<f64> = r.fits.iter().map(|f| f.delta_e00).collect();
        let rms: Vec<f64> = r.fits.iter().map(|f| f.rms).collect();
        let thickness: Vec<f64> = r.fits.iter().map(|f| f.params.epidermis_thickness_mm).collect();
        let light_dark = (rows.first().map_or(0.0, |r| r.q_rms), rows.last().map_or(0.0, |r| r.q_rms));
        let worst = rows.iter().filter(|r| r.n >= 20).map(|r| r.median_de).fold(0.0, f64::max);
        summary.push(format!(
            "| {label} | {:.4} | {:.2} | {worst:.2} | {:.2} | {:.4} / {:.4} | {:.3} / {:.3} / {:.3} | {:.0} |",
            quantile(&rms, 0.5),
            quantile(&de, 0.5),
            worst_over_best(&rows),
            light_dark.0,
            light_dark.1,
            quantile(&thickness, 0.1),
            quantile(&thickness, 0.5),
            quantile(&thickness, 0.9),
            r.seconds
        ));
    }
    println!("\n### Summary\n");
    println!(
        "| fit | median RMS | median ΔE00 | worst class median | worst / best | Q-band rms lightest / darkest class | \
         epidermis mm p10 / median / p90 | s |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for line in summary {
        println!("{line}");
    }
    tables
}

/// Each class's p10 / median / p90 of the fitted epidermal blood fraction.
fn print_fitted_blood(fits: &[SpectrumFit]) {
    let cells: Vec<String> = spectral_skin::color::ita::ITA_CLASSES
        .iter()
        .filter_map(|class| {
            let members = super::classes::members(fits, class);
            let values: Vec<f64> = members.iter().map(|&i| fits[i].epidermal_hemoglobin).collect();
            (!values.is_empty()).then(|| {
                let q = |p: f64| quantile(&values, p);
                format!("{} {:.4} / {:.4} / {:.4}", class.label, q(0.1), q(0.5), q(0.9))
            })
        })
        .collect();
    println!("Epidermal blood fitted (p10 / median / p90): {}", cells.join(", "));
}

/// Each class's mean residual (measured - fitted) at every wavelength, in thousandths.
fn print_residual_spectra(fits: &[spectral_skin::inverse::SpectrumFit], spectra: &[Vec<f64>], wl: &[f64]) {
    println!("\nMean residual per class, 1e-3 (wavelengths {} to {} nm):\n", wl[0], wl[wl.len() - 1]);
    for class in &spectral_skin::color::ita::ITA_CLASSES {
        let (name, members) = (class.label, super::classes::members(fits, class));
        if members.is_empty() {
            continue;
        }
        let cells: Vec<String> = (0..wl.len())
            .map(|k| {
                let mean = members.iter().map(|&i| spectra[i][k] - fits[i].fitted_reflectance[k]).sum::<f64>()
                    / members.len() as f64;
                format!("{:+.1}", 1e3 * mean)
            })
            .collect();
        let lab_bias: Vec<String> = (0..3)
            .map(|c| {
                let d: Vec<f64> = members.iter().map(|&i| fits[i].lab_measured[c] - fits[i].lab_fitted[c]).collect();
                format!(
                    "{:+.2} (|{:.2}|)",
                    d.iter().sum::<f64>() / d.len() as f64,
                    quantile(&d.iter().map(|v| v.abs()).collect::<Vec<_>>(), 0.5)
                )
            })
            .collect();
        println!("    {name:<22} {}   ΔL*, Δa*, Δb* mean (median |.|): {}", cells.join(" "), lab_bias.join(", "));
    }
}

/// The per-class tables of docs/measured-skin.md (Skin types and the Q bands; Instrument aperture; Blood in the
/// epidermis), each written into its block `measured-skin classes NAME`, stamped with `command`: the fit before the
/// bandpass, the default, the default with the oxygenation free (with a free and with a Fresnel surface reflection),
/// and the last through the SAV aperture and with blood in the epidermis.
const CLASS_TABLES: [(&str, &str); 8] = [
    ("classes points", "points (the fit before)"),
    ("classes default", "default (bandpass 1.5 x spacing)"),
    ("classes oxygenation", "default + oxygenation"),
    ("classes oxygenation fresnel", "default + oxygenation, fresnel"),
    ("classes oxygenation fresnel aperture", "default + oxygenation, fresnel, aperture SAV"),
    ("classes oxygenation fresnel epidermal blood", "default + oxygenation, fresnel, epidermal blood 0.005"),
    ("classes oxygenation fresnel epidermal blood fitted", "default + oxygenation, fresnel, epidermal blood fitted"),
    ("classes oxygenation epidermal blood fitted", "default + oxygenation, epidermal blood fitted"),
];

/// The tables made again on the spectra whose red end rises (`--red-rising`; docs/measured-skin.md, Which spectra),
/// each block's name with [`RISING_SUFFIX`].
const RISING_TABLES: [&str; 5] = [
    "classes default",
    "classes oxygenation fresnel",
    "classes oxygenation fresnel epidermal blood",
    "classes oxygenation fresnel epidermal blood fitted",
    "classes oxygenation epidermal blood fitted",
];

/// The block-name suffix of the tables of the spectra whose red end rises.
const RISING_SUFFIX: &str = " rising red";

/// Fits `spectra` with each of [`CLASS_TABLES`]' candidates (only [`RISING_TABLES`]' when `rising_only`: the spectra
/// are the screened ones; only those labelled in `only`, separated by ';', when given) and writes each class table
/// into its block of DOC, stamped with `command`.
pub fn by_class(wl: &[f64], spectra: &[Vec<f64>], command: &str, rising_only: bool, only: Option<&str>) {
    let wanted = labels_of(only);
    let tables: Vec<(String, &str)> = CLASS_TABLES
        .iter()
        .filter(|(name, _)| !rising_only || RISING_TABLES.contains(name))
        .filter(|(_, label)| !wanted.as_ref().is_some_and(|w| !w.contains(label)))
        .map(|(name, label)| {
            let suffix = if rising_only { RISING_SUFFIX } else { "" };
            (format!("measured-skin {name}{suffix}"), *label)
        })
        .collect();
    let labels: Vec<&str> = tables.iter().map(|(_, label)| *label).collect();
    let made = study(wl, spectra, Some(&labels.join(";")));
    let blocks: Vec<(&str, &str)> = tables
        .iter()
        .map(|(name, label)| {
            let table = made.iter().find(|(l, _)| l == label).unwrap_or_else(|| panic!("no candidate {label:?}"));
            (name.as_str(), table.1.as_str())
        })
        .collect();
    write_markdown_blocks(Path::new(DOC), command, &blocks).unwrap();
    eprintln!("wrote {} blocks of {DOC}", blocks.len());
}
