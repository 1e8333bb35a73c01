//! The measured-skin report (docs/measured-skin.md): fits the model to the Xiao et al. 2016 in-vivo spectra
//! (data/xiao2016_skin_reflectance_400_700nm.csv) with each parameter set and surface-reflection model, prints the
//! report's tables (markdown) and writes its plots to docs/images/measured-skin/.
//!
//! cargo run --release --example measured_skin_report [-- --every N]
//! cargo run --release --example measured_skin_report -- --classes [--every N]: the per-class table of
//! docs/measured-skin.md (Skin types and the Q bands): the fit before the bandpass, the default, and the options.
//! cargo run --release --example measured_skin_report -- --study [--every N] [--only "LABEL;LABEL"]: issue 39's study
//! of the Q-band residual by skin type, every candidate (study.rs).

mod classes;
mod data;
mod study;

use std::path::Path;
use std::time::Instant;

use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};
use spectral_skin::inverse::{FitOptions, SpectrumFit, SpectrumFitter, Specular};
use spectral_skin::skin::params::PARAMS;

use data::{quantile, read_data};

const DATA: &str = "data/xiao2016_skin_reflectance_400_700nm.csv";
const OUT: &str = "docs/images/measured-skin";

const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

struct Run {
    label: String,
    fits: Vec<SpectrumFit>,
    seconds: f64,
}

fn options(free: &[&str], specular: Specular) -> FitOptions {
    FitOptions { free: free.iter().map(|s| s.to_string()).collect(), specular, ..FitOptions::default() }
}

fn run(label: &str, wl: &[f64], spectra: &[Vec<f64>], opts: &FitOptions) -> Run {
    let start = Instant::now();
    let fitter = SpectrumFitter::new(wl, opts).expect("fitter");
    let fits = fitter.fit_many(spectra).into_iter().map(|f| f.expect("fit")).collect();
    let seconds = start.elapsed().as_secs_f64();
    eprintln!("{label}: {seconds:.1} s (table {} spectra)", fitter.table_len());
    Run { label: label.to_string(), fits, seconds }
}

fn summary_row(r: &Run) -> String {
    let rms: Vec<f64> = r.fits.iter().map(|f| f.rms).collect();
    let de: Vec<f64> = r.fits.iter().map(|f| f.delta_e00).collect();
    let within = rms.iter().filter(|&&v| v <= 0.02).count() as f64 / rms.len() as f64;
    let off: Vec<f64> = r.fits.iter().map(|f| f.specular_offset).collect();
    format!(
        "| {} | {:.4} | {:.4} | {:.2} | {:.2} | {:.0} % | {:.3} | {:.0} |",
        r.label,
        quantile(&rms, 0.5),
        quantile(&rms, 0.9),
        quantile(&de, 0.5),
        quantile(&de, 0.9),
        100.0 * within,
        quantile(&off, 0.5),
        r.seconds
    )
}

type Series = (String, Vec<(f64, f64)>);

fn line_plot(path: &Path, title: &str, x_desc: &str, y_desc: &str, series: &[Series], zero_line: bool) {
    let all = || series.iter().flat_map(|s| s.1.iter());
    let (x0, x1) = all().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let (y0, y1) = all().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.1), b.max(p.1)));
    let pad = 0.05 * (y1 - y0).max(1e-9);
    let root = BitMapBackend::new(path, (900, 560)).into_drawing_area();
    root.fill(&WHITE).unwrap();
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(14)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, (y0 - pad)..(y1 + pad))
        .unwrap();
    chart.configure_mesh().x_desc(x_desc).y_desc(y_desc).label_style(("sans-serif", 14)).draw().unwrap();
    if zero_line {
        chart.draw_series(LineSeries::new(vec![(x0, 0.0), (x1, 0.0)], BLACK.mix(0.4))).unwrap();
    }
    for (k, (name, pts)) in series.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        chart
            .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
            .unwrap()
            .label(name.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .draw()
        .unwrap();
    root.present().unwrap();
}

/// The empirical distribution function of `values`, clipped at `max`.
fn cdf(values: &[f64], max: f64) -> Vec<(f64, f64)> {
    let mut v: Vec<f64> = values.iter().map(|x| x.min(max)).collect();
    v.sort_by(f64::total_cmp);
    let n = v.len() as f64;
    v.iter().enumerate().map(|(i, &x)| (x, (i + 1) as f64 / n)).collect()
}

fn main() {
    static FONT: &[u8] = include_bytes!("../accuracy_report/DejaVuSans.ttf");
    let _ = register_font("sans-serif", FontStyle::Normal, FONT);
    let args: Vec<String> = std::env::args().collect();
    let every: usize = args.iter().position(|a| a == "--every").map(|i| args[i + 1].parse().unwrap()).unwrap_or(1);
    let (wl, all) = read_data(DATA);
    let spectra: Vec<Vec<f64>> = all.iter().step_by(every).cloned().collect();
    let header = format!(
        "{} spectra (every {every}th of {}), {} threads",
        spectra.len(),
        all.len(),
        rayon::current_num_threads()
    );
    if args.iter().any(|a| a == "--classes") {
        println!("{header}");
        study::by_class(&wl, &spectra);
        return;
    }
    if args.iter().any(|a| a == "--study") {
        println!("{header}");
        study::study(&wl, &spectra, args.iter().position(|a| a == "--only").map(|i| args[i + 1].as_str()));
        return;
    }
    let out = Path::new(OUT);
    std::fs::create_dir_all(out).unwrap();
    println!(
        "{} spectra (every {every}th of {}), {} wavelengths, {} threads\n",
        spectra.len(),
        all.len(),
        wl.len(),
        rayon::current_num_threads()
    );

    let paper = ["melanin", "melanin_blend", "hemoglobin"];
    let thick = ["melanin", "melanin_blend", "hemoglobin", "epidermis_thickness_mm"];
    let thick_base = ["melanin", "melanin_blend", "hemoglobin", "epidermis_thickness_mm", "baseline_absorption_scale"];
    let thick_oxy = ["melanin", "melanin_blend", "hemoglobin", "epidermis_thickness_mm", "blood_oxygenation"];
    let all_ext = [
        "melanin",
        "melanin_blend",
        "hemoglobin",
        "epidermis_thickness_mm",
        "baseline_absorption_scale",
        "blood_oxygenation",
    ];
    let sets: Vec<(&str, &[&str])> = vec![
        ("paper (C_m, beta_m, C_h)", &paper),
        ("+ thickness", &thick),
        ("+ thickness + oxygenation", &thick_oxy),
        ("+ thickness + baseline", &thick_base),
        ("+ thickness + baseline + oxygenation", &all_ext),
    ];
    let mut runs = Vec::new();
    for (label, free) in &sets {
        runs.push(run(label, &wl, &spectra, &options(free, Specular::Free)));
    }
    println!("Surface reflection fitted (free offset):\n");
    println!("| free parameters | median RMS | p90 RMS | median ΔE00 | p90 ΔE00 | RMS ≤ 0.02 | median offset | s |");
    println!("|---|---|---|---|---|---|---|---|");
    for r in &runs {
        println!("{}", summary_row(r));
    }
    let mut spec_runs = Vec::new();
    for (label, sp) in [("fresnel (0.0278)", Specular::Fresnel), ("fixed 0 (SCE)", Specular::Fixed(0.0))] {
        for (set_label, free) in [&sets[0], &sets[3]] {
            spec_runs.push(run(&format!("{set_label}, specular {label}"), &wl, &spectra, &options(free, sp)));
        }
    }
    println!("\nOther surface-reflection models:\n");
    println!("| free parameters, specular | median RMS | p90 RMS | median ΔE00 | p90 ΔE00 | RMS ≤ 0.02 | offset | s |");
    println!("|---|---|---|---|---|---|---|---|");
    for r in &spec_runs {
        println!("{}", summary_row(r));
    }
    // Offsets of the default set.
    let default_run = &runs[3];
    let offs: Vec<f64> = default_run.fits.iter().map(|f| f.specular_offset).collect();
    println!(
        "\nFree offset of the default set: p10 {:.4}, median {:.4}, p90 {:.4}; at 0: {:.0} %",
        quantile(&offs, 0.1),
        quantile(&offs, 0.5),
        quantile(&offs, 0.9),
        100.0 * offs.iter().filter(|&&o| o <= 1e-9).count() as f64 / offs.len() as f64
    );

    // Restart check: the table's best 16 starts refined against the default's best 4, on every 8th spectrum.
    println!("\nRestart check (every 8th spectrum; the table's best 16 starts refined against the default 4):\n");
    println!(
        "| free parameters | spectra | improved by > 1e-4 RMS | largest RMS gain | median RMS 4 starts | 16 starts |"
    );
    println!("|---|---|---|---|---|---|");
    let sub: Vec<Vec<f64>> = spectra.iter().step_by(8).cloned().collect();
    for k in [0usize, 3, 4] {
        let (label, free) = &sets[k];
        let one: Vec<SpectrumFit> = runs[k].fits.iter().step_by(8).cloned().collect();
        let eight =
            run(&format!("{label} x16"), &wl, &sub, &FitOptions { starts: 16, ..options(free, Specular::Free) });
        let gains: Vec<f64> = one.iter().zip(&eight.fits).map(|(a, b)| a.rms - b.rms).collect();
        let improved = gains.iter().filter(|&&g| g > 1e-4).count();
        let r1: Vec<f64> = one.iter().map(|f| f.rms).collect();
        let r8: Vec<f64> = eight.fits.iter().map(|f| f.rms).collect();
        println!(
            "| {label} | {} | {improved} | {:.5} | {:.5} | {:.5} |",
            sub.len(),
            gains.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
            quantile(&r1, 0.5),
            quantile(&r8, 0.5)
        );
    }

    // Fitted parameter distributions of each set.
    println!("\nFitted parameters (p10 / median / p90):\n");
    let header: Vec<&str> = PARAMS.iter().filter(|p| p.name != "oiliness").map(|p| p.name).collect();
    println!("| free parameters | {} | offset |", header.join(" | "));
    println!("|---|{}---|", "---|".repeat(header.len()));
    for r in &runs {
        let mut cells = Vec::new();
        for (i, p) in PARAMS.iter().enumerate() {
            if p.name == "oiliness" {
                continue;
            }
            let v: Vec<f64> = r.fits.iter().map(|f| f.params.values()[i]).collect();
            if r.fits[0].free.contains(&p.name) {
                cells.push(format!("{:.3} / {:.3} / {:.3}", quantile(&v, 0.1), quantile(&v, 0.5), quantile(&v, 0.9)));
            } else {
                cells.push(format!("({})", v[0]));
            }
        }
        let off: Vec<f64> = r.fits.iter().map(|f| f.specular_offset).collect();
        println!("| {} | {} | {:.3} |", r.label, cells.join(" | "), quantile(&off, 0.5));
    }
    let at_zero_blend = runs[0].fits.iter().filter(|f| f.params.melanin_blend < 1e-6).count();
    println!(
        "\nPaper set: melanin_blend at 0 in {:.0} % of fits",
        100.0 * at_zero_blend as f64 / runs[0].fits.len() as f64
    );

    // Data-driven presets: median fitted parameters of the thirds by measured L*.
    println!("\nPresets (default set; median of each third of the spectra by measured L*):\n");
    let mut by_l: Vec<&SpectrumFit> = default_run.fits.iter().collect();
    by_l.sort_by(|a, b| b.lab_measured[0].total_cmp(&a.lab_measured[0]));
    let third = by_l.len() / 3;
    for (name, part) in [("light", &by_l[..third]), ("medium", &by_l[third..2 * third]), ("dark", &by_l[2 * third..])] {
        let med = |i: usize| quantile(&part.iter().map(|f| f.params.values()[i]).collect::<Vec<_>>(), 0.5);
        let l: Vec<f64> = part.iter().map(|f| f.lab_measured[0]).collect();
        println!(
            "measured-{name}: L* {:.1}..{:.1}; melanin {:.4}, melanin_blend {:.3}, hemoglobin {:.4}, thickness {:.3}, \
             baseline {:.2}",
            l.iter().cloned().fold(f64::INFINITY, f64::min),
            l.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
            med(0),
            med(1),
            med(2),
            med(4),
            med(5)
        );
    }

    // Skin-type groups by the individual typology angle of the measured colour (classes.rs): the paper set's and the
    // default set's fit quality, Q-band residual and physiology per group.
    for (label, r) in [("paper set", &runs[0]), ("default set", default_run)] {
        println!("\nBy skin type, {label} (ITA of the measured colour; Chardon et al. 1991):\n");
        classes::print_class_table(&classes::class_rows(&r.fits, &spectra, &wl));
    }

    // Plots.
    let rms_series: Vec<Series> =
        runs.iter().map(|r| (r.label.clone(), cdf(&r.fits.iter().map(|f| f.rms).collect::<Vec<_>>(), 0.06))).collect();
    line_plot(
        &out.join("rms_cdf.png"),
        "RMS residual, cumulative share of spectra",
        "RMS (reflectance)",
        "share",
        &rms_series,
        false,
    );
    let de_series: Vec<Series> = runs
        .iter()
        .map(|r| (r.label.clone(), cdf(&r.fits.iter().map(|f| f.delta_e00).collect::<Vec<_>>(), 8.0)))
        .collect();
    line_plot(
        &out.join("delta_e00_cdf.png"),
        "CIEDE2000 of fit and measurement, cumulative share",
        "ΔE00",
        "share",
        &de_series,
        false,
    );
    let residual_series: Vec<Series> = runs
        .iter()
        .map(|r| {
            let pts = (0..wl.len())
                .map(|k| {
                    let mean = r.fits.iter().zip(&spectra).map(|(f, m)| f.fitted_reflectance[k] - m[k]).sum::<f64>()
                        / spectra.len() as f64;
                    (wl[k], mean)
                })
                .collect();
            (r.label.clone(), pts)
        })
        .collect();
    line_plot(
        &out.join("mean_residual.png"),
        "Mean signed residual (fit - measurement)",
        "wavelength, nm",
        "reflectance",
        &residual_series,
        true,
    );
    for (i, p) in PARAMS.iter().enumerate() {
        if p.name == "oiliness" {
            continue;
        }
        let series: Vec<Series> = runs
            .iter()
            .filter(|r| r.fits[0].free.contains(&p.name))
            .map(|r| (r.label.clone(), cdf(&r.fits.iter().map(|f| f.params.values()[i]).collect::<Vec<_>>(), p.max)))
            .collect();
        line_plot(
            &out.join(format!("param_{}.png", p.name)),
            &format!("Fitted {}, cumulative share", p.name),
            p.name,
            "share",
            &series,
            false,
        );
    }
    eprintln!("plots in {OUT}");
}
