//! The report page: tables, plots and the reasons for the defaults.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use serde::Serialize;
use serde_json::Value;
use spectral_skin::maps::io::write_atomic;

use crate::checks::{Convergence, McRow, ShapeRow};
use crate::metrics::{log_to_relative, pareto_front};
use crate::plots::{write_plot, Plot, Series};
use crate::reference::Row;
use crate::sweeps::Sweep;

/// The default accuracy's errors for one preset.
#[derive(Debug, Clone, Serialize)]
pub struct PresetErrors {
    pub preset: &'static str,
    pub material: BTreeMap<&'static str, f64>,
    pub profile_log: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct Report {
    pub quick: bool,
    pub threads: usize,
    pub map_size: usize,
    pub convergence: Convergence,
    pub default_rows: Vec<PresetErrors>,
    pub monte_carlo: Vec<McRow>,
    pub shapes: Vec<ShapeRow>,
    pub sweeps: Vec<Sweep>,
    pub cycles: Option<Value>,
    pub peak_rss_mib: Option<f64>,
    pub seconds: f64,
}

pub fn read_cycles(path: &Path) -> Option<Value> {
    serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()
}

/// Columns in table order: key, header, formatter.
const COLUMNS: [(&str, &str); 18] = [
    ("wavelengths", "λ samples"),
    ("pixel_mm", "pixel (mm)"),
    ("albedo_rel", "albedo err (max rel.)"),
    ("albedo_knob", "albedo err, this knob"),
    ("delta_e00", "ΔE00"),
    ("radius_rel", "radius err (max rel.)"),
    ("radius_knob", "radius err, this knob"),
    ("edge_misfit", "edge misfit"),
    ("profile_log", "profile err (max, log)"),
    ("quadrature_log", "quadrature err (max, log)"),
    ("quadrature_log_all", "all presets"),
    ("profile_s", "profile time"),
    ("table_kib", "table (KiB)"),
    ("build_s", "build"),
    ("map_s", "map lookup"),
    ("table_build_s", "table build"),
    ("map_cold_s", "map, cold"),
    ("time_s", "time"),
];

fn fmt_seconds(s: f64) -> String {
    if s >= 1.0 {
        format!("{s:.2} s")
    } else if s >= 1e-3 {
        format!("{:.2} ms", s * 1e3)
    } else {
        format!("{:.1} µs", s * 1e6)
    }
}

fn fmt_percent(x: f64) -> String {
    if x > 100.0 {
        format!("×{:.1e}", 1.0 + x)
    } else if x == 0.0 {
        "0".into()
    } else if x >= 0.01 {
        format!("{:.2} %", 100.0 * x)
    } else {
        format!("{:.1e} %", 100.0 * x)
    }
}

/// A log error as a relative error while it is small, as a factor when it is not.
fn fmt_log_error(log_error: f64) -> String {
    if log_error < std::f64::consts::LN_2 {
        fmt_percent(log_to_relative(log_error))
    } else if log_error < 700.0 {
        format!("×{:.2e}", log_error.exp())
    } else {
        "×>1e300".into()
    }
}

fn fmt_metric(key: &str, v: f64) -> String {
    match key {
        "wavelengths" | "table_kib" => format!("{v:.0}"),
        "pixel_mm" => format!("{v:.4}"),
        "albedo_rel" | "radius_rel" | "albedo_knob" | "radius_knob" => fmt_percent(v),
        "profile_log" | "quadrature_log" | "quadrature_log_all" => fmt_log_error(v),
        "delta_e00" | "edge_misfit" => format!("{v:.4}"),
        _ if key.ends_with("_s") => fmt_seconds(v),
        _ => format!("{v:.4}"),
    }
}

/// A markdown table of rows, with the Pareto-front rows (on `metric`) starred and the default in bold.
fn table(rows: &[Row], metric: &str) -> String {
    let points: Vec<(f64, f64)> =
        rows.iter().map(|r| (r.time_s, r.metrics.get(metric).copied().unwrap_or(f64::NAN))).collect();
    let front = pareto_front(&points);
    let keys: Vec<(&str, &str)> = COLUMNS
        .iter()
        .cloned()
        .filter(|(k, _)| *k == "time_s" || rows.iter().any(|r| r.metrics.contains_key(k)))
        .collect();
    let mut out = String::from("| setting | ");
    for (_, h) in &keys {
        let _ = write!(out, "{h} | ");
    }
    out.push_str("front |\n|---|");
    for _ in &keys {
        out.push_str("---:|");
    }
    out.push_str(":---:|\n");
    for (i, r) in rows.iter().enumerate() {
        let name = format!("{} {}", r.series, r.label);
        let name = if r.is_default { format!("**{name} (default)**") } else { name };
        let _ = write!(out, "| {name} | ");
        for (k, _) in &keys {
            let v = if *k == "time_s" { Some(r.time_s) } else { r.metrics.get(k).copied() };
            let _ = write!(out, "{} | ", v.map(|v| fmt_metric(k, v)).unwrap_or_default());
        }
        let _ = writeln!(out, "{} |", if front.contains(&i) { "★" } else { "" });
    }
    out
}

fn metric_label(metric: &str) -> &'static str {
    match metric {
        "albedo_rel" => "albedo error (max relative over RGB and presets)",
        "radius_rel" => "radius error (max relative)",
        "albedo_knob" => "albedo error of this knob (vs converged, same λ grid)",
        "radius_knob" => "radius error of this knob (vs converged, same λ grid)",
        "profile_log" => "profile error (max |ln R/R_ref|, 0.01-10 mm)",
        "quadrature_log" => "quadrature error (max |ln R/R_ref|, 0.01-10 mm, same λ grid)",
        "pixel_rms" => "pixel error (rms relative, worst channel)",
        _ => "error",
    }
}

/// The plot of a sweep's rows: one series per row series, the Pareto front over all, the default circled.
fn plot_rows(title: &str, rows: &[Row], metric: &str, x_label: &str) -> Plot {
    let mut series: Vec<Series> = Vec::new();
    for r in rows {
        let Some(&y) = r.metrics.get(metric) else { continue };
        let y = y.max(1e-12);
        match series.iter_mut().find(|s| s.name == r.series) {
            Some(s) => s.points.push((r.time_s, y, r.label.clone())),
            None => series.push(Series { name: r.series.clone(), points: vec![(r.time_s, y, r.label.clone())] }),
        }
    }
    let points: Vec<(f64, f64)> =
        rows.iter().map(|r| (r.time_s, r.metrics.get(metric).copied().unwrap_or(f64::NAN).max(1e-12))).collect();
    let front = pareto_front(&points).into_iter().map(|i| points[i]).collect();
    let default = rows.iter().position(|r| r.is_default).map(|i| points[i]);
    Plot {
        title: title.to_string(),
        x_label: x_label.to_string(),
        y_label: metric_label(metric).to_string(),
        series,
        front,
        default,
    }
}

fn sweep<'a>(sweeps: &'a [Sweep], key: &str) -> Option<&'a Sweep> {
    sweeps.iter().find(|s| s.key == key)
}

/// Why each default sits where it does (the measured figures are in the tables next to it).
fn rationale(key: &str) -> &'static str {
    match key {
        "wavelengths" => include_str!("text/wavelengths.md"),
        "multipole" => include_str!("text/multipole.md"),
        "hankel" => include_str!("text/hankel.md"),
        "radius_fit" => include_str!("text/radius_fit.md"),
        "fft" => include_str!("text/fft.md"),
        "table" => include_str!("text/table.md"),
        "levels" => include_str!("text/levels.md"),
        "streams" => include_str!("text/streams.md"),
        "transport" => include_str!("text/transport.md"),
        _ => "",
    }
}

/// FFT route against the closed form at equal accuracy (caucasian): for each FFT setting, the cheapest closed-form
/// setting whose profile error is no larger. Returns (fft row, closed-form row, time ratio).
fn equal_accuracy(sweep: &Sweep) -> Vec<(&Row, &Row, f64)> {
    let (fft, closed): (Vec<&Row>, Vec<&Row>) = sweep.rows.iter().partition(|r| r.series.starts_with("FFT"));
    fft.into_iter()
        .filter_map(|f| {
            let e = f.metrics["quadrature_log"];
            closed
                .iter()
                .filter(|h| h.metrics["quadrature_log"] <= e)
                .min_by(|a, b| a.time_s.total_cmp(&b.time_s))
                .map(|h| (f, *h, f.time_s / h.time_s))
        })
        .collect()
}

/// The command that regenerates the report (its stamp names it).
pub const REGENERATE: &str = "bash scripts/accuracy_report.sh";

pub fn write(out_dir: &Path, report: &Report) -> Result<(), Box<dyn std::error::Error>> {
    let images = out_dir.join("images").join("accuracy");
    std::fs::create_dir_all(&images)?;
    std::fs::create_dir_all(out_dir.join("data"))?;
    let mut md = String::new();
    let r = report;
    let _ = writeln!(md, "{}\n", spectral_skin::stamp::markdown_stamp(REGENERATE));
    let _ = writeln!(md, "# What accuracy costs in time\n");
    let _ = writeln!(
        md,
        "Every accuracy knob of spectral-skin, measured as error against a converged reference and as time. Regenerate \
         with\n\n    bash scripts/accuracy_report.sh\n\n(the Cycles samples measurement through bpy, then \
         `cargo run --release --example accuracy_report`; about {:.0} minutes here). CI runs the reduced version \
         (`--quick`) so this code cannot rot. Numbers: `docs/data/accuracy.json`.\n",
        (r.seconds / 60.0).ceil().max(1.0)
    );
    if r.quick {
        let _ = writeln!(
            md,
            "> **Reduced run (`--quick`)**: few settings, {0}² maps, few photons. Not the published figures.\n",
            r.map_size
        );
    }
    let _ = writeln!(
        md,
        "Errors of zero (the reference itself) and below 1e-12 are drawn at 1e-12 on the log axes. Times are medians of repeated runs of one evaluation (caucasian preset) on one thread of this machine (maps: {} \
         threads); errors are the worst over the three presets (caucasian, asian, african), against \
         the converged reference; *this knob* columns compare with the reference on the same wavelength grid, which \
         isolates the knob from the wavelength sampling. Colours are linear Rec.709. Every knob is varied with the \
         others at their defaults. ★ marks the Pareto front: no other setting is clearly faster (by more than {:.0} %, \
         the timing noise here) and no less accurate, or no slower and less than half as wrong. The default is in bold \
         and circled in red on the plots.\n",
        r.threads,
        100.0 * (crate::metrics::TIME_TOLERANCE - 1.0)
    );

    // Levels first: what users pick.
    if let Some(levels) = sweep(&r.sweeps, "levels") {
        let _ = writeln!(md, "## Accuracy levels\n\n{}\n", rationale("levels"));
        let _ = writeln!(md, "{}", table(&levels.rows, "albedo_rel"));
        let _ = writeln!(
            md,
            "`time` is one evaluation of albedo + radius; `profile time` one RGB profile on 41 radii; `map, cold` a \
             {0}² face map computed in memory (no file I/O) with its lookup table built (no cache), of which `table \
             build` is the build.\n",
            r.map_size
        );
        let _ = writeln!(md, "Settings of each level (`spectral_skin::AccuracyLevel`, Python `accuracy=`, CLI `--accuracy`, add-on *Accuracy*):\n");
        for level in spectral_skin::accuracy::ALL_ACCURACY_LEVELS {
            let _ = writeln!(md, "- `{}`: `{}`", level.name(), serde_json::to_string(&level.accuracy())?);
        }
        md.push('\n');
    }

    // References.
    let c = &r.convergence;
    let _ = writeln!(md, "## The references\n");
    let _ = writeln!(
        md,
        "**Converged evaluation** (`Accuracy::reference()`): 1 nm wavelength steps (the resolution of the CIE tables, \
         so a finer step cannot change a colour), the whole multipole series in closed form, 16 radius-fit frequencies \
         per decade, an inverse-Hankel grid twice as fine with 12-point panels and a 1e-15 cut-off. **Check that it \
         converged**: refining every knob once more (`{}`) changes the albedo by {}, the radius by {} and the profile \
         by {} (worst over presets).\n",
        serde_json::to_string(&c.finer)?,
        fmt_percent(c.albedo_rel),
        fmt_percent(c.radius_rel),
        fmt_log_error(c.profile_log)
    );
    let _ = writeln!(md, "**Default against the reference** (acceptance: albedo within 0.21 %: 0.2 % from the numerical knobs and 0.01 % from \
         the transport's 10 streams against the reference's 32, checked apart in `tests/physics/accuracy.rs`; radius within 1 %):\n");
    let _ = writeln!(md, "| preset | albedo err (max rel.) | ΔE00 | radius err (max rel.) | edge misfit | profile err |\n|---|---:|---:|---:|---:|---:|");
    for d in &r.default_rows {
        let _ = writeln!(
            md,
            "| {} | {} | {:.4} | {} | {:.4} | {} |",
            d.preset,
            fmt_percent(d.material["albedo_rel"]),
            d.material["delta_e00"],
            fmt_percent(d.material["radius_rel"]),
            d.material["edge_misfit"],
            fmt_log_error(d.profile_log)
        );
    }
    let _ = writeln!(
        md,
        "\nThe edge misfit is ‖E_Burley − E_model‖ / ‖E_model − step‖ of the half-plane edge response against the \
         reference multipole transfer function: the part of the skin's blur a Burley profile cannot reproduce (its \
         floor, with the reference's own fit, is the shape mismatch of the two profiles).\n"
    );
    let _ = writeln!(md, "### Transport against Monte Carlo\n");
    let _ = writeln!(
        md,
        "The error of the transport itself: total diffuse reflectance of the two-layer slab by the paper's diffusion \
         (closed-form multipole) and by the exact adding-doubling solver at 4-32 streams, against the project's Monte \
         Carlo photon walk (`tests/support/mc.rs`: isotropic scattering with σs = σs′, Fresnel boundaries at n = 1.4, \
         validated against Beer–Lambert, energy conservation and Chandrasekhar's H-function in \
         `tests/physics/monte_carlo.rs`). Columns: each total / MC − 1.\n"
    );
    let streams_header: String = crate::checks::MC_STREAMS.iter().map(|n| format!(" {n} streams |")).collect();
    let streams_rule: String = crate::checks::MC_STREAMS.iter().map(|_| "---:|").collect();
    let _ = writeln!(
        md,
        "| preset | λ (nm) | epidermis α′ | Monte Carlo ± s.e. | diffusion |{streams_header} photons |\n\
         |---|---:|---:|---:|---:|{streams_rule}---:|"
    );
    for m in &r.monte_carlo {
        let exact: String =
            m.adding_doubling.iter().map(|t| format!(" {:+.2} % |", 100.0 * (t / m.monte_carlo - 1.0))).collect();
        let _ = writeln!(
            md,
            "| {} | {:.0} | {:.3} | {:.5} ± {:.5} | {:+.1} % |{exact} {} |",
            m.preset,
            m.wavelength_nm,
            m.epidermis_albedo,
            m.monte_carlo,
            m.monte_carlo_se,
            100.0 * m.relative_difference,
            m.photons
        );
    }
    let _ = writeln!(md, "\n{}\n", include_str!("text/monte_carlo.md"));
    write_shapes(&mut md, &r.shapes);

    // Knobs.
    for key in ["streams", "transport", "wavelengths", "multipole", "hankel", "radius_fit", "fft", "table"] {
        let Some(s) = sweep(&r.sweeps, key) else { continue };
        let _ = writeln!(md, "## {}\n\n{}\n", s.title, rationale(key));
        let file = format!("{key}.png");
        let x_label = format!("time of one evaluation ({}), s", s.timed);
        let plot = plot_rows(s.title, &s.rows, s.plot_metric, &x_label);
        write_plot(&out_dir.join("images").join("accuracy").join(&file), &plot)?;
        let _ = writeln!(md, "![{}](images/accuracy/{file})\n", s.title);
        let _ = writeln!(md, "Time: one evaluation of {}. Front (★) on {}.\n", s.timed, metric_label(s.plot_metric));
        let _ = writeln!(md, "{}", table(&s.rows, s.plot_metric));
        if key == "fft" {
            write_equal_accuracy(&mut md, s);
        }
    }

    write_cycles(&mut md, r, out_dir)?;
    let _ = writeln!(
        md,
        "---\nGenerated by `examples/accuracy_report` in {:.0} s{}.",
        r.seconds,
        r.peak_rss_mib.map(|m| format!(", peak memory {m:.0} MiB")).unwrap_or_default()
    );
    write_atomic(&out_dir.join("accuracy-vs-time.md"), md.as_bytes())?;
    write_atomic(&out_dir.join("data").join("accuracy.json"), serde_json::to_string_pretty(report)?.as_bytes())?;
    Ok(())
}

/// The profile shapes against the Monte Carlo: r50, r90 and Burley d per preset and wavelength.
fn write_shapes(md: &mut String, rows: &[ShapeRow]) {
    if rows.is_empty() {
        return;
    }
    let _ = writeln!(md, "### Profile shape against Monte Carlo\n");
    let _ = writeln!(
        md,
        "The blur: the encircled-energy radii r50 and r90 of the radial profile R(r) and the Burley d the radius fit \
         picks from its transform, by the exact shapes' table (the default) and by the multipole's shape scaled to the \
         exact total (`adding_doubling_diffusion_shape`), against the same Monte Carlo photon walk with radial bins \
         (`tests/support/profile_figures.rs`). Columns: each figure / MC − 1.\n"
    );
    let _ = writeln!(
        md,
        "| preset | λ (nm) | MC r50 (mm) | MC r90 (mm) | MC d (mm) | exact r50 | exact r90 | exact d | diffusion-shape r50 \
         | diffusion-shape r90 | diffusion-shape d | photons |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    let pct = |x: f64| format!("{:+.1} %", 100.0 * x);
    for m in rows {
        let _ = writeln!(
            md,
            "| {} | {:.0} | {:.4} | {:.4} | {:.4} | {} | {} | {} | {} | {} | {} | {} |",
            m.preset,
            m.wavelength_nm,
            m.mc_r50_mm,
            m.mc_r90_mm,
            m.mc_d_mm,
            pct(m.exact[0]),
            pct(m.exact[1]),
            pct(m.exact[2]),
            pct(m.diffusion_shape[0]),
            pct(m.diffusion_shape[1]),
            pct(m.diffusion_shape[2]),
            m.photons
        );
    }
    let _ = writeln!(md, "\n{}\n", include_str!("text/shapes.md"));
}

fn write_equal_accuracy(md: &mut String, sweep: &Sweep) {
    let pairs = equal_accuracy(sweep);
    let _ = writeln!(md, "**Speed at equal accuracy.** For each FFT setting, the cheapest closed-form setting whose profile error is no larger:\n");
    let _ = writeln!(md, "| FFT setting | FFT profile err | FFT time | closed-form setting | its error | its time | FFT time / closed-form time |\n|---|---:|---:|---|---:|---:|---:|");
    for (f, h, ratio) in &pairs {
        let _ = writeln!(
            md,
            "| {} {} | {} | {} | {} {} | {} | {} | **{:.0}×** |",
            f.series,
            f.label,
            fmt_log_error(f.metrics["quadrature_log"]),
            fmt_seconds(f.time_s),
            h.series,
            h.label,
            fmt_log_error(h.metrics["quadrature_log"]),
            fmt_seconds(h.time_s),
            ratio
        );
    }
    if let Some(best) =
        pairs.iter().min_by(|a, b| a.0.metrics["quadrature_log"].total_cmp(&b.0.metrics["quadrature_log"]))
    {
        let ratios: Vec<f64> = pairs.iter().map(|p| p.2).collect();
        let (lo, hi) = ratios.iter().fold((f64::INFINITY, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
        let default_time = sweep.rows.iter().find(|h| h.is_default).map(|h| h.time_s);
        let _ = writeln!(
            md,
            "\n**The closed-form route is {:.0}× faster than the FFT route at the FFT's best accuracy** ({} {}: profile \
             error {} in {}, against {} {} in {}); over all FFT settings the ratio is {:.0}× to {:.0}×.{}\n",
            best.2,
            best.0.series,
            best.0.label,
            fmt_log_error(best.0.metrics["quadrature_log"]),
            fmt_seconds(best.0.time_s),
            best.1.series,
            best.1.label,
            fmt_seconds(best.1.time_s),
            lo,
            hi,
            default_time.map(|t| format!(" The closed-form default takes {}.", fmt_seconds(t))).unwrap_or_default()
        );
    }
}

fn write_cycles(md: &mut String, r: &Report, out_dir: &Path) -> Result<(), Box<dyn std::error::Error>> {
    let _ = writeln!(md, "## Cycles render samples\n\n{}\n", include_str!("text/cycles.md"));
    let Some(data) = &r.cycles else {
        let _ = writeln!(
            md,
            "*Not measured in this run: `scripts/reports/cycles_samples.py` writes `docs/data/cycles_samples.json`.*\n"
        );
        return Ok(());
    };
    let cases = data["cases"].as_array().cloned().unwrap_or_default();
    let worst = |v: &Value| {
        v.as_array().map(|a| a.iter().filter_map(|x| x.as_f64()).map(f64::abs).fold(0.0, f64::max)).unwrap_or(f64::NAN)
    };
    let mut rows: Vec<Row> = Vec::new();
    for case in &cases {
        let mut metrics = BTreeMap::new();
        metrics.insert("pixel_rms", worst(&case["pixel_rms_error_rel_rgb"]));
        metrics.insert("mean_error", worst(&case["mean_error_rel_rgb"]));
        rows.push(Row {
            series: format!("{} {}", case["method"].as_str().unwrap_or("?"), case["preset"].as_str().unwrap_or("?")),
            label: format!("{}", case["samples"].as_u64().unwrap_or(0)),
            time_s: case["seconds"].as_f64().unwrap_or(f64::NAN),
            metrics,
            is_default: false,
            accuracy: None,
        });
    }
    let px = data["image_px"]
        .as_array()
        .map(|a| a.iter().filter_map(|v| v.as_u64()).map(|v| v.to_string()).collect::<Vec<_>>().join("×"))
        .unwrap_or_default();
    let plot =
        plot_rows("Cycles: pixel error against render time", &rows, "pixel_rms", &format!("render time ({px} px), s"));
    write_plot(&out_dir.join("images").join("accuracy").join("cycles_samples.png"), &plot)?;
    let _ = writeln!(
        md,
        "Blender {}, Cycles CPU, {} threads, {px} px of a flat slab lit by a uniform white sky; labels are samples per \
         pixel.\n\n![Cycles samples](images/accuracy/cycles_samples.png)\n",
        data["blender"].as_str().unwrap_or("?"),
        data["threads"].as_u64().unwrap_or(0)
    );
    let _ = writeln!(md, "| method, preset | samples | render time | pixel err (rms rel., worst channel) | region mean err |\n|---|---:|---:|---:|---:|");
    for row in &rows {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} |",
            row.series,
            row.label,
            fmt_seconds(row.time_s),
            fmt_percent(row.metrics["pixel_rms"]),
            fmt_percent(row.metrics["mean_error"])
        );
    }
    md.push('\n');
    Ok(())
}
