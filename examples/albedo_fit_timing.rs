//! Time the albedo-texture fit (src/inverse/albedo_maps.rs) on a 4096² texture: the face-like example parameter map's
//! albedo (by the fit's forward table), once as 8-bit sRGB (as a painted or photographed texture: colours repeat) and
//! once as float (nearly every texel distinct), cold (table built) and with the table cached in the process.
//!
//!     cargo run --release --example albedo_fit_timing -- [SIZE]
//!
//! Figures: docs/skin-atlas.md, "Fitting a texture". RAYON_NUM_THREADS sets the cores.

use std::time::Instant;

use spectral_skin::inverse::albedo::{table_coordinates, AlbedoFitOptions, AlbedoTable};
use spectral_skin::inverse::albedo_maps::{fit_albedo_map, EpidermisThickness};
use spectral_skin::maps::example::face_params;
use spectral_skin::skin::SkinParams;

/// sRGB encoding and decoding (IEC 61966-2-1), to quantise to 8 bits as a texture file does.
fn to_8bit(linear: f32) -> u8 {
    let v = linear.clamp(0.0, 1.0);
    let s = if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0).round() as u8
}

fn from_8bit(code: u8) -> f32 {
    let s = code as f32 / 255.0;
    if s <= 0.040_45 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}

fn main() {
    let size: usize = std::env::args().nth(1).map_or(4096, |s| s.parse().expect("SIZE"));
    let options = AlbedoFitOptions::default();
    let table = AlbedoTable::build(&options).unwrap();
    let params = face_params(size);
    let float: Vec<[f32; 3]> = (0..size * size)
        .map(|i| {
            let t = params.texel(i);
            let p = SkinParams::new(t[0] as f64, t[1] as f64, t[2] as f64, t[3] as f64).unwrap();
            table.albedo(table_coordinates(&p)).map(|v| v as f32)
        })
        .collect();
    let eight: Vec<[f32; 3]> = float.iter().map(|c| c.map(|v| from_8bit(to_8bit(v)))).collect();
    println!("{size}x{size}, {} threads", rayon::current_num_threads());
    let runs = [
        ("held 0.25 mm, first (cold table, in-process cache empty)", EpidermisThickness::Held),
        ("held 0.25 mm, second (table cached)", EpidermisThickness::Held),
        ("thickness chosen (the default), first (five more tables built)", EpidermisThickness::Chosen),
        ("thickness chosen (the default), second (tables cached)", EpidermisThickness::Chosen),
    ];
    for (name, texels) in [("8-bit", &eight), ("float", &float)] {
        for (run, thickness) in runs {
            if name == "float" && run.contains("first") {
                continue; // the tables are cached by then
            }
            let start = Instant::now();
            let fit = fit_albedo_map(texels, size, size, &options, thickness).unwrap();
            let s = fit.stats;
            println!(
                "{name} {run}: {:.2} s, thickness {} mm, {} distinct colours, table from cache {}, ΔE00 mean {:.4} max {:.4}, {} out of gamut",
                start.elapsed().as_secs_f64(),
                fit.extended[0],
                s.distinct_colours,
                s.table_from_cache,
                s.mean_delta_e00,
                s.max_delta_e00,
                s.out_of_gamut_texels
            );
            if let Some(i) =
                (0..texels.len()).max_by(|&a, &b| fit.residual_delta_e00[a].total_cmp(&fit.residual_delta_e00[b]))
            {
                println!("  worst texel {i}: colour {:?}, params {:?}", texels[i], fit.params[i]);
            }
        }
    }
}
