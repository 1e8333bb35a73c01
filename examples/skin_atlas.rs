//! The skin-colour atlas (docs/skin-atlas.md): the model's albedo over melanin x haemoglobin for a few melanin blends
//! and epidermis thicknesses, with measured skin colours (Xiao et al. 2016) placed where the albedo fit puts them.
//!
//!     cargo run --release --example skin_atlas -- [XIAO_CSV] [OUT_DIR] [DOC]
//!
//! XIAO_CSV: default data/xiao2016_skin_reflectance_400_700nm.csv; OUT_DIR: default docs/images; DOC: default
//! docs/skin-atlas.md. Writes skin-atlas-epidermis-<mm>.png per thickness (one panel per melanin blend) and the table
//! of measured colours into DOC's block `measured colours`, each stamped with the model's version.

use std::fmt::Write;
use std::path::PathBuf;

use image::{Rgb, RgbImage};
use rayon::prelude::*;
use spectral_skin::color::{spectral_rgb_weights, spectrum_to_rgb, WavelengthGrid, WorkingSpace};
use spectral_skin::inverse::albedo::{fit_albedo, AlbedoFitOptions};

const BLENDS: [f64; 3] = [0.0, 0.5, 1.0];
const THICKNESSES_MM: [f64; 3] = [0.1, 0.25, 0.5];
/// Cells per axis and pixels per cell of a panel.
const CELLS: usize = 48;
const CELL_PX: usize = 4;
const GAP_PX: usize = 8;
/// Measured colours marked: the spectra at these percentiles of luminance.
const PERCENTILES: [f64; 9] = [2.0, 10.0, 25.0, 40.0, 50.0, 60.0, 75.0, 90.0, 98.0];
/// The command the stamps name.
const REGENERATE: &str = "cargo run --release --example skin_atlas";

fn srgb8(linear: f64) -> u8 {
    let v = linear.clamp(0.0, 1.0);
    let s = if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0).round() as u8
}

/// Linear Rec.709 (white = 1, D65, CIE 1931 2°) of each spectrum in the CSV (400-700 nm at 10 nm; the 380-400 and
/// 700-780 nm of the colour integral take the end values, where the CMFs weigh little).
fn measured_colours(path: &PathBuf) -> Vec<(usize, [f64; 3])> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let grid = WavelengthGrid::uniform(10.0);
    let weights = spectral_rgb_weights(&grid, WorkingSpace::LinearRec709);
    spectral_skin::strip_utf8_bom(&text)
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("index"))
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.trim().parse().unwrap()).collect();
            let r = &v[1..]; // 400..700 nm, 31 values
            let spectrum: Vec<f64> = grid
                .wavelengths_nm
                .iter()
                .map(|&w| r[(((w - 400.0) / 10.0).round().clamp(0.0, 30.0)) as usize])
                .collect();
            (v[0] as usize, spectrum_to_rgb(&spectrum, &weights))
        })
        .collect()
}

fn main() {
    let mut args = std::env::args().skip(1);
    let csv = PathBuf::from(args.next().unwrap_or("data/xiao2016_skin_reflectance_400_700nm.csv".into()));
    let out = PathBuf::from(args.next().unwrap_or("docs/images".into()));
    let doc = PathBuf::from(args.next().unwrap_or("docs/skin-atlas.md".into()));
    let mut measured = measured_colours(&csv);
    measured.sort_by(|a, b| {
        (0.2126 * a.1[0] + 0.7152 * a.1[1] + 0.0722 * a.1[2])
            .total_cmp(&(0.2126 * b.1[0] + 0.7152 * b.1[1] + 0.0722 * b.1[2]))
    });
    let marks: Vec<(f64, usize, [f64; 3])> = PERCENTILES
        .iter()
        .map(|&p| {
            let (i, c) = measured[((p / 100.0) * (measured.len() - 1) as f64).round() as usize];
            (p, i, c)
        })
        .collect();
    let panel = CELLS * CELL_PX;
    let mut table = String::new();
    table.push_str("| percentile | spectrum | sRGB | C_m | beta_m | C_h | ΔE00 | ambiguity beta_m | ambiguity C_h |\n");
    table.push_str("|---|---|---|---|---|---|---|---|---|\n");
    for (p, i, c) in &marks {
        let fit = fit_albedo(*c, &AlbedoFitOptions::default()).unwrap();
        let a = &fit.ambiguity;
        let _ = writeln!(
            table,
            "| {p} | {i} | #{:02x}{:02x}{:02x} | {:.4} | {:.2} | {:.4} | {:.2} | {:.2}-{:.2} | {:.4}-{:.4} |",
            srgb8(c[0]),
            srgb8(c[1]),
            srgb8(c[2]),
            fit.params.melanin,
            fit.params.melanin_blend,
            fit.params.hemoglobin,
            fit.delta_e00,
            a.melanin_blend[0],
            a.melanin_blend[1],
            a.hemoglobin[0],
            a.hemoglobin[1]
        );
    }
    spectral_skin::stamp::write_markdown_blocks(&doc, REGENERATE, &[("measured colours", &table)]).unwrap();
    print!("{table}");
    for t in THICKNESSES_MM {
        let width = BLENDS.len() * panel + (BLENDS.len() - 1) * GAP_PX;
        let mut img = RgbImage::from_pixel(width as u32, panel as u32, Rgb([255, 255, 255]));
        for (b_i, &blend) in BLENDS.iter().enumerate() {
            let options = AlbedoFitOptions { extended: [t, 1.0, 0.75], ..AlbedoFitOptions::default() };
            let prepared = options.prepared().unwrap();
            let cells: Vec<[f64; 3]> = (0..CELLS * CELLS)
                .into_par_iter()
                .map(|n| {
                    let (x, y) = (n % CELLS, n / CELLS);
                    let u = [(x as f64 + 0.5) / CELLS as f64, blend, 1.0 - (y as f64 + 0.5) / CELLS as f64];
                    prepared.albedo(&options.params_at(u)).unwrap()
                })
                .collect();
            let x0 = b_i * (panel + GAP_PX);
            for (n, c) in cells.iter().enumerate() {
                let (x, y) = (n % CELLS, n / CELLS);
                for dy in 0..CELL_PX {
                    for dx in 0..CELL_PX {
                        img.put_pixel((x0 + x * CELL_PX + dx) as u32, (y * CELL_PX + dy) as u32, Rgb(c.map(srgb8)));
                    }
                }
            }
            // The measured colours (filled with their own colour) where the fit at this blend puts them: a black border where
            // it reaches them within 2 ΔE00, a white one where not (the nearest reachable colour).
            let held = AlbedoFitOptions { melanin_blend_prior: blend, prior_weight: 100.0, ..options };
            for (_, _, c) in &marks {
                let fit = fit_albedo(*c, &held).unwrap();
                let u = spectral_skin::inverse::albedo::table_coordinates(&fit.params);
                let (cx, cy) = ((u[0] * panel as f64) as i64, ((1.0 - u[2]) * panel as f64) as i64);
                for dy in -4i64..=4 {
                    for dx in -4i64..=4 {
                        let (px, py) = (cx + dx, cy + dy);
                        if px < 0 || py < 0 || px >= panel as i64 || py >= panel as i64 {
                            continue;
                        }
                        let border = dx.abs() == 4 || dy.abs() == 4;
                        let reached = fit.delta_e00 <= 2.0;
                        let colour = match (border, reached) {
                            (true, true) => Rgb([0, 0, 0]),
                            (true, false) => Rgb([255, 255, 255]),
                            (false, _) => Rgb(c.map(srgb8)),
                        };
                        img.put_pixel((x0 as i64 + px) as u32, py as u32, colour);
                    }
                }
            }
        }
        let path = out.join(format!("skin-atlas-epidermis-{t:.2}mm.png"));
        img.save(&path).unwrap();
        spectral_skin::stamp::stamp_png(&path, REGENERATE).unwrap();
        eprintln!("wrote {}", path.display());
    }
}
