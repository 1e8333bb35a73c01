//! The measured-skin report (docs/measured-skin.md): fits the model to the Xiao et al. 2016 in-vivo spectra
//! (data/xiao2016_skin_reflectance_400_700nm.csv) with each parameter set and surface-reflection model, writes the
//! report's tables (markdown) into their blocks of docs/measured-skin.md (`<!-- BEGIN measured-skin ... -->`, once, at
//! the end) and its plots to docs/images/measured-skin/, each stamped with the model's version and the command
//! (`spectral_skin::stamp`), and prints the tables.
//!
//! cargo run --release --example measured_skin_report [-- --every N] (the doc's figures: `--every 16`)
//! cargo run --release --example measured_skin_report -- --classes [--every N] [--only "LABEL;LABEL"]: the per-class
//! tables of docs/measured-skin.md (Skin types and the Q bands): the fit before the bandpass, the default, and the
//! options (only the labelled ones with `--only`).
//! cargo run --release --example measured_skin_report -- --study [--every N] [--only "LABEL;LABEL"] [--class NAME]:
//! issue 39's study of the Q-band residual by skin type, every candidate (study.rs); NAME: an ITA class
//! (`color::ita::ITA_CLASSES`, e.g. dark), only its spectra. `--red-rising` (with `--study`): only the spectra whose
//! reflectance rises from 650 to 700 nm; with `--classes`, the tables of those spectra (their own blocks).

mod classes;
mod common;
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
const DOC: &str = "docs/measured-skin.md";

/// The parameter sets fitted, each with a free surface offset: the paper's three, then the extended ones; the fourth
/// is the default (`inverse::DEFAULT_FREE`).
const SETS: [(&str, &[&str]); 5] = [
    ("paper (C_m, beta_m, C_h)", &["melanin", "melanin_blend", "hemoglobin"]),
    ("+ thickness", &["melanin", "melanin_blend", "hemoglobin", "epidermis_thickness_mm"]),
    (
        "+ thickness + oxygenation",
        &["melanin", "melanin_blend", "hemoglobin", "epidermis_thickness_mm", "blood_oxygenation"],
    ),
    (
        "+ thickness + baseline",
        &["melanin", "melanin_blend", "hemoglobin", "epidermis_thickness_mm", "baseline_absorption_scale"],
    ),
    (
        "+ thickness + baseline + oxygenation",
        &[
            "melanin",
            "melanin_blend",
            "hemoglobin",
            "epidermis_thickness_mm",
            "baseline_absorption_scale",
            "blood_oxygenation",
        ],
    ),
];
/// The index in [`SETS`] of the default set.
const DEFAULT_SET: usize = 3;

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

/// The blocks of DOC the report writes, each between `<!-- BEGIN measured-skin NAME -->` and its END.
const BLOCK_NAMES: [&str; 9] = [
    "sets",
    "surface models",
    "free offset",
    "restart check",
    "fitted parameters",
    "paper blend",
    "presets",
    "by type paper",
    "by type default",
];

/// The generated blocks of the doc, by name, in the order the report makes them.
#[derive(Default)]
struct Blocks(Vec<(&'static str, String)>);

impl Blocks {
    /// Panics unless DOC has every block's markers: checked before the fits, not after them.
    fn check_doc() {
        let text = std::fs::read_to_string(DOC).unwrap_or_else(|e| panic!("{DOC}: {e}"));
        for name in BLOCK_NAMES {
            for marker in [format!("<!-- BEGIN measured-skin {name} -->"), format!("<!-- END measured-skin {name} -->")]
            {
                assert!(text.contains(&marker), "{DOC} has no line {marker:?}");
            }
        }
    }

    /// Prints `heading` and `body` and keeps `body` for the doc's block `measured-skin {name}`.
    fn add(&mut self, name: &'static str, heading: &str, body: String) {
        assert!(BLOCK_NAMES.contains(&name), "block {name:?} is not in BLOCK_NAMES");
        println!("\n{heading}\n\n{}", body.trim_end_matches('\n'));
        self.0.push((name, body));
    }

    /// Rewrites every block of DOC, stamped with `command`, in one atomic write.
    fn write(&self, command: &str) {
        let names: Vec<String> = self.0.iter().map(|(name, _)| format!("measured-skin {name}")).collect();
        let blocks: Vec<(&str, &str)> =
            names.iter().zip(&self.0).map(|(n, (_, body))| (n.as_str(), body.as_str())).collect();
        spectral_skin::stamp::write_markdown_blocks(Path::new(DOC), command, &blocks).unwrap();
        eprintln!("wrote {} blocks of {DOC}", self.0.len());
    }
}

/// The markdown table of `runs`' fit quality; `first` and `offset` head the first column and the offset's.
fn summary_table(first: &str, offset: &str, runs: &[Run]) -> String {
    let mut table = format!(
        "| {first} | median RMS | p90 RMS | median ΔE00 | p90 ΔE00 | RMS ≤ 0.02 | {offset} | s |\n\
         |---|---|---|---|---|---|---|---|\n"
    );
    for r in runs {
        table += &summary_row(r);
        table.push('\n');
    }
    table
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

/// Draws `series` into the PNG at `path` and stamps it with the model's version and `command`.
fn line_plot(path: &Path, command: &str, title: &str, axes: (&str, &str), series: &[Series], zero_line: bool) {
    draw_lines(path, title, axes, series, zero_line);
    spectral_skin::stamp::stamp_png(path, command).unwrap();
}

fn draw_lines(path: &Path, title: &str, (x_desc, y_desc): (&str, &str), series: &[Series], zero_line: bool) {
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

/// The spectra's fits with each of [`SETS`] and a free surface offset.
fn fit_sets(wl: &[f64], spectra: &[Vec<f64>]) -> Vec<Run> {
    SETS.iter().map(|(label, free)| run(label, wl, spectra, &options(free, Specular::Free))).collect()
}

/// The paper's and the default set with a Fresnel and a zero surface reflection.
fn fit_surface_models(wl: &[f64], spectra: &[Vec<f64>]) -> Vec<Run> {
    let mut runs = Vec::new();
    for (label, sp) in [("fresnel (0.0278)", Specular::Fresnel), ("fixed 0 (SCE)", Specular::Fixed(0.0))] {
        for (set_label, free) in [&SETS[0], &SETS[DEFAULT_SET]] {
            runs.push(run(&format!("{set_label}, specular {label}"), wl, spectra, &options(free, sp)));
        }
    }
    runs
}

/// The line on the free offset of the default set.
fn free_offset_line(default_run: &Run) -> String {
    let offs: Vec<f64> = default_run.fits.iter().map(|f| f.specular_offset).collect();
    format!(
        "Free offset of the default set: p10 {:.4}, median {:.4}, p90 {:.4}; at 0: {:.0} %",
        quantile(&offs, 0.1),
        quantile(&offs, 0.5),
        quantile(&offs, 0.9),
        100.0 * offs.iter().filter(|&&o| o <= 1e-9).count() as f64 / offs.len() as f64
    )
}

/// The restart check: on every 8th spectrum, the table's best 16 starts refined against the default's best 4, for the
/// paper's set, the default and the default with the oxygenation.
fn restart_table(wl: &[f64], spectra: &[Vec<f64>], runs: &[Run]) -> String {
    let mut table = String::from(
        "| free parameters | spectra | improved by > 1e-4 RMS | largest RMS gain | median RMS 4 starts | 16 starts |\n\
         |---|---|---|---|---|---|\n",
    );
    let sub: Vec<Vec<f64>> = spectra.iter().step_by(8).cloned().collect();
    for k in [0usize, DEFAULT_SET, 4] {
        let (label, free) = &SETS[k];
        let four: Vec<&SpectrumFit> = runs[k].fits.iter().step_by(8).collect();
        let sixteen =
            run(&format!("{label} x16"), wl, &sub, &FitOptions { starts: 16, ..options(free, Specular::Free) });
        let gains: Vec<f64> = four.iter().zip(&sixteen.fits).map(|(a, b)| a.rms - b.rms).collect();
        let improved = gains.iter().filter(|&&g| g > 1e-4).count();
        let rms4: Vec<f64> = four.iter().map(|f| f.rms).collect();
        let rms16: Vec<f64> = sixteen.fits.iter().map(|f| f.rms).collect();
        table += &format!(
            "| {label} | {} | {improved} | {:.5} | {:.5} | {:.5} |\n",
            sub.len(),
            gains.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
            quantile(&rms4, 0.5),
            quantile(&rms16, 0.5)
        );
    }
    table
}

/// The fitted parameters' p10 / median / p90 per set (a fixed parameter's value in parentheses).
fn params_table(runs: &[Run]) -> String {
    let shown: Vec<(usize, &str)> =
        PARAMS.iter().enumerate().filter(|(_, p)| p.name != "oiliness").map(|(i, p)| (i, p.name)).collect();
    let names: Vec<&str> = shown.iter().map(|s| s.1).collect();
    let mut table =
        format!("| free parameters | {} | offset |\n|---|{}---|\n", names.join(" | "), "---|".repeat(names.len()));
    for r in runs {
        let cells: Vec<String> = shown
            .iter()
            .map(|&(i, name)| {
                let v: Vec<f64> = r.fits.iter().map(|f| f.params.values()[i]).collect();
                if r.fits[0].free.contains(&name) {
                    format!("{:.3} / {:.3} / {:.3}", quantile(&v, 0.1), quantile(&v, 0.5), quantile(&v, 0.9))
                } else {
                    format!("({})", v[0])
                }
            })
            .collect();
        let off: Vec<f64> = r.fits.iter().map(|f| f.specular_offset).collect();
        table += &format!("| {} | {} | {:.3} |\n", r.label, cells.join(" | "), quantile(&off, 0.5));
    }
    table
}

/// The line on how often the paper's set puts the melanin blend at 0.
fn paper_blend_line(paper_run: &Run) -> String {
    let at_zero_blend = paper_run.fits.iter().filter(|f| f.params.melanin_blend < 1e-6).count();
    format!(
        "Paper set: melanin_blend at 0 in {:.0} % of fits",
        100.0 * at_zero_blend as f64 / paper_run.fits.len() as f64
    )
}

/// Data-driven presets: the default set's median fitted parameters over each third of the spectra by measured L*.
fn presets_lines(default_run: &Run) -> String {
    let mut by_l: Vec<&SpectrumFit> = default_run.fits.iter().collect();
    by_l.sort_by(|a, b| b.lab_measured[0].total_cmp(&a.lab_measured[0]));
    let third = by_l.len() / 3;
    let mut lines = String::new();
    for (name, part) in [("light", &by_l[..third]), ("medium", &by_l[third..2 * third]), ("dark", &by_l[2 * third..])] {
        let med = |i: usize| quantile(&part.iter().map(|f| f.params.values()[i]).collect::<Vec<_>>(), 0.5);
        let l: Vec<f64> = part.iter().map(|f| f.lab_measured[0]).collect();
        lines += &format!(
            "- {name} third: L* {:.1}..{:.1}; melanin {:.4}, melanin_blend {:.3}, hemoglobin {:.4}, thickness {:.3}, \
             baseline {:.2}\n",
            l.iter().cloned().fold(f64::INFINITY, f64::min),
            l.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
            med(0),
            med(1),
            med(2),
            med(4),
            med(5)
        );
    }
    lines
}

/// The report's plots, each stamped with `command`: the RMS and ΔE00 distributions, the mean signed residual and each
/// fitted parameter's distribution, per set.
fn plots(out: &Path, command: &str, runs: &[Run], wl: &[f64], spectra: &[Vec<f64>]) {
    let distribution = |value: &dyn Fn(&SpectrumFit) -> f64, max: f64| -> Vec<Series> {
        runs.iter().map(|r| (r.label.clone(), cdf(&r.fits.iter().map(value).collect::<Vec<_>>(), max))).collect()
    };
    let title = "RMS residual, cumulative share of spectra";
    line_plot(
        &out.join("rms_cdf.png"),
        command,
        title,
        ("RMS (reflectance)", "share"),
        &distribution(&|f| f.rms, 0.06),
        false,
    );
    let title = "CIEDE2000 of fit and measurement, cumulative share";
    let de = distribution(&|f| f.delta_e00, 8.0);
    line_plot(&out.join("delta_e00_cdf.png"), command, title, ("ΔE00", "share"), &de, false);
    let title = "Mean signed residual (fit - measurement)";
    let residual = mean_residuals(runs, wl, spectra);
    line_plot(&out.join("mean_residual.png"), command, title, ("wavelength, nm", "reflectance"), &residual, true);
    for (i, p) in PARAMS.iter().enumerate().filter(|(_, p)| p.name != "oiliness") {
        let series: Vec<Series> = runs
            .iter()
            .filter(|r| r.fits[0].free.contains(&p.name))
            .map(|r| (r.label.clone(), cdf(&r.fits.iter().map(|f| f.params.values()[i]).collect::<Vec<_>>(), p.max)))
            .collect();
        let (path, title) = (out.join(format!("param_{}.png", p.name)), format!("Fitted {}, cumulative share", p.name));
        line_plot(&path, command, &title, (p.name, "share"), &series, false);
    }
    eprintln!("plots in {}", out.display());
}

/// Each run's mean signed residual (fit - measurement) per wavelength.
fn mean_residuals(runs: &[Run], wl: &[f64], spectra: &[Vec<f64>]) -> Vec<Series> {
    let mean = |r: &Run, k: usize| {
        r.fits.iter().zip(spectra).map(|(f, m)| f.fitted_reflectance[k] - m[k]).sum::<f64>() / spectra.len() as f64
    };
    runs.iter().map(|r| (r.label.clone(), (0..wl.len()).map(|k| (wl[k], mean(r, k))).collect())).collect()
}

/// The main report: every table into its block of DOC and every plot, stamped with the command that made them.
fn report(wl: &[f64], spectra: &[Vec<f64>], command: &str) {
    Blocks::check_doc();
    let mut blocks = Blocks::default();
    let runs = fit_sets(wl, spectra);
    blocks.add(
        "sets",
        "Surface reflection fitted (free offset):",
        summary_table("free parameters", "median offset", &runs),
    );
    let surface_runs = fit_surface_models(wl, spectra);
    let table = summary_table("free parameters, specular", "offset", &surface_runs);
    blocks.add("surface models", "Other surface-reflection models:", table);
    let default_run = &runs[DEFAULT_SET];
    blocks.add("free offset", "Free offset:", free_offset_line(default_run));
    let heading = "Restart check (every 8th spectrum; the table's best 16 starts refined against the default 4):";
    blocks.add("restart check", heading, restart_table(wl, spectra, &runs));
    blocks.add("fitted parameters", "Fitted parameters (p10 / median / p90):", params_table(&runs));
    blocks.add("paper blend", "Paper set:", paper_blend_line(&runs[0]));
    let heading = "Presets (default set; median of each third of the spectra by measured L*):";
    blocks.add("presets", heading, presets_lines(default_run));
    for (name, label, r) in [("by type paper", "paper set", &runs[0]), ("by type default", "default set", default_run)]
    {
        let rows = classes::class_rows(&r.fits, spectra, wl);
        let heading = format!("By skin type, {label} (ITA of the measured colour; Chardon et al. 1991):");
        blocks.add(name, &heading, classes::class_table(&rows));
        println!("Worst / best class median ΔE00: {:.2}", classes::worst_over_best(&rows));
    }
    let out = Path::new(OUT);
    std::fs::create_dir_all(out).unwrap();
    plots(out, command, &runs, wl, spectra);
    blocks.write(command);
}

/// The command that regenerates what a run with `--every every` writes, as its stamps name it.
fn regenerate_command(every: usize) -> String {
    let command = "cargo run --release --example measured_skin_report";
    if every == 1 {
        command.to_string()
    } else {
        format!("{command} -- --every {every}")
    }
}

/// The spectra whose measured colour falls in the ITA class `name` (`color::ita::ITA_CLASSES`' names).
fn of_class(wl: &[f64], spectra: Vec<Vec<f64>>, name: &str) -> Vec<Vec<f64>> {
    use spectral_skin::color::ita::{ita_class, ita_degrees};
    let fitter = SpectrumFitter::new(wl, &FitOptions::default()).expect("fitter");
    spectra.into_iter().filter(|s| ita_class(ita_degrees(fitter.lab(s))).is_some_and(|c| c.name == name)).collect()
}

/// Whether `spectrum` rises from 650 to 700 nm, as skin's reflectance must: melanin and both haemoglobins absorb less
/// at 700 nm than at 650 (docs/measured-skin.md, What is left: 238 of the 4392 spectra fall instead).
fn red_end_rises(wl: &[f64], spectrum: &[f64]) -> bool {
    let at = |nm: f64| spectrum[wl.iter().position(|&w| w == nm).expect("650 and 700 nm in the data")];
    at(700.0) >= at(650.0)
}

fn main() {
    static FONT: &[u8] = include_bytes!("../accuracy_report/DejaVuSans.ttf");
    let _ = register_font("sans-serif", FontStyle::Normal, FONT);
    let args: Vec<String> = std::env::args().collect();
    let every: usize = args.iter().position(|a| a == "--every").map(|i| args[i + 1].parse().unwrap()).unwrap_or(1);
    let (wl, all) = read_data(DATA);
    let mut spectra: Vec<Vec<f64>> = all.iter().step_by(every).cloned().collect();
    if let Some(name) = args.iter().position(|a| a == "--class").map(|i| args[i + 1].as_str()) {
        spectra = of_class(&wl, spectra, name);
    }
    let rising_only = args.iter().any(|a| a == "--red-rising");
    if rising_only {
        spectra.retain(|s| red_end_rises(&wl, s));
    }
    let threads = rayon::current_num_threads();
    println!(
        "{} spectra (every {every}th of {}), {} wavelengths, {threads} threads",
        spectra.len(),
        all.len(),
        wl.len()
    );
    let only = args.iter().position(|a| a == "--only").map(|i| args[i + 1].as_str());
    if args.iter().any(|a| a == "--classes") {
        let every_arg = if every == 1 { String::new() } else { format!(" --every {every}") };
        let rising_arg = if rising_only { " --red-rising" } else { "" };
        let only_arg = only.map(|o| format!(" --only \"{o}\"")).unwrap_or_default();
        let command =
            format!("cargo run --release --example measured_skin_report -- --classes{every_arg}{rising_arg}{only_arg}");
        study::by_class(&wl, &spectra, &command, rising_only, only);
    } else if args.iter().any(|a| a == "--study") {
        study::study(&wl, &spectra, only);
    } else {
        report(&wl, &spectra, &regenerate_command(every));
    }
}
