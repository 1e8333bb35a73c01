//! Time the albedo-texture fit (src/inverse/albedo_maps.rs) on a SIZE² texture (default 4096²): the face-like example
//! parameter map's albedo (by the fit's forward table), as 8-bit sRGB (as a painted or photographed texture: colours
//! repeat), as float, as float with 2 % multiplicative noise per channel (as a scan: hundreds of thousands of
//! distinct colours), and as a photograph: the albedo over-exposed (x 1.4) under a warm light (R x 1.25, B x 0.75), as
//! 8-bit sRGB (most of its texels outside skin's colours until the gains undo the light); cold (tables built) once,
//! then with the tables cached in the process, with and without the exposure and white-balance gains estimated
//! (`auto_gains`, Python `rgb_gains="auto"`). Each cached run is repeated REPEATS times (default 3) and the median
//! printed.
//!
//!     cargo run --release --example albedo_fit_timing -- [SIZE] [REPEATS] [TEXTURE [RUN]]
//!
//! TEXTURE (8-bit, float, noisy or photo) and RUN (held, chosen or auto) time that one texture and run alone, once
//! cold and REPEATS times cached: what `/usr/bin/time -v` measures the peak memory of (the process holds that texture
//! and one fit at a time).
//!
//! Figures: docs/skin-atlas.md, "Fitting a texture". RAYON_NUM_THREADS sets the cores.

use std::time::Instant;

use spectral_skin::inverse::albedo::{table_coordinates, AlbedoFitOptions, AlbedoTable};
use spectral_skin::inverse::albedo_maps::{fit_albedo_map, AlbedoMapFit, EpidermisThickness, TextureFit};
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

/// A deterministic value in [-1, 1) from an index (SplitMix64's finaliser).
fn noise(i: u64) -> f32 {
    let mut z = i.wrapping_add(0x9E37_79B9_7F4A_7C15).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 40) as f32 / (1u64 << 23) as f32 - 1.0
}

/// FNV-1a over the bits of the fit's parameters and residuals: equal checksums, equal maps.
fn checksum(fit: &AlbedoMapFit) -> u64 {
    let bits = fit.params.iter().flatten().chain(&fit.residual_delta_e00).map(|v| v.to_bits());
    bits.fold(0xcbf2_9ce4_8422_2325, |h, b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3))
}

fn describe(fit: &AlbedoMapFit) -> String {
    let s = fit.stats;
    format!(
        "maps {:016x}, thickness {} mm, {} distinct colours, gains {:?}, ΔE00 mean {:.4} max {:.4}, {} outside skin's \
         colours",
        checksum(fit),
        fit.extended[0],
        s.distinct_colours,
        fit.gains.as_ref().map(|g| g.rgb_gains.map(|v| (v * 1e4).round() / 1e4)),
        s.mean_delta_e00,
        s.max_delta_e00,
        s.outside_skin_texels
    )
}

fn main() {
    let size: usize = std::env::args().nth(1).map_or(4096, |s| s.parse().expect("SIZE"));
    let repeats: usize = std::env::args().nth(2).map_or(3, |s| s.parse().expect("REPEATS"));
    let only = std::env::args().nth(3);
    let only_run = std::env::args().nth(4);
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
    drop(params);
    let wanted = |name: &str| only.as_deref().map_or(true, |o| o == name);
    let eight: Vec<[f32; 3]> =
        if wanted("8-bit") { float.iter().map(|c| c.map(|v| from_8bit(to_8bit(v)))).collect() } else { Vec::new() };
    let noisy: Vec<[f32; 3]> = if wanted("noisy") {
        float
            .iter()
            .enumerate()
            .map(|(i, c)| [0, 1, 2].map(|k| c[k] * (1.0 + 0.02 * noise(3 * i as u64 + k as u64))))
            .collect()
    } else {
        Vec::new()
    };
    // The photograph's light: exposure x 1.4, warm (tests/inverse/inverse_gains.rs lights the fair face so).
    let light = [1.4 * 1.25, 1.4, 1.4 * 0.75];
    let photo: Vec<[f32; 3]> = if wanted("photo") {
        float.iter().map(|c| [0, 1, 2].map(|k| from_8bit(to_8bit(c[k] * light[k])))).collect()
    } else {
        Vec::new()
    };
    let float = if wanted("float") {
        float
    } else {
        drop(float);
        Vec::new()
    };
    println!("{size}x{size}, {} threads, median of {repeats} cached runs", rayon::current_num_threads());
    let chosen = TextureFit { thickness: EpidermisThickness::Chosen, auto_gains: false };
    let auto = TextureFit { auto_gains: true, ..chosen };
    let held = TextureFit { thickness: EpidermisThickness::Held, auto_gains: false };
    let runs = [
        ("held", "held 0.25 mm", held),
        ("chosen", "thickness chosen", chosen),
        ("auto", "thickness chosen, rgb_gains auto", auto),
    ];
    let runs: Vec<_> = runs.into_iter().filter(|r| only_run.as_deref().map_or(true, |o| o == r.0)).collect();
    let textures = [
        ("8-bit", "8-bit", &eight),
        ("float", "float", &float),
        ("noisy", "float + 2 % noise", &noisy),
        ("photo", "photograph (8-bit, x 1.4, warm)", &photo),
    ];
    let textures: Vec<_> = textures.into_iter().filter(|t| wanted(t.0)).collect();
    // Cold: the tables built (held: one; chosen: five more).
    for &(_, run, texture) in runs.iter().take(2) {
        let (_, name, texels) = textures[0];
        let start = Instant::now();
        let fit = fit_albedo_map(texels, size, size, &options, texture).unwrap();
        println!("{name} {run}, cold: {:.2} s, {}", start.elapsed().as_secs_f64(), describe(&fit));
    }
    for &(_, name, texels) in &textures {
        for &(_, run, texture) in &runs {
            let mut seconds = Vec::new();
            let mut last = String::new();
            for _ in 0..repeats {
                let start = Instant::now();
                let fit = fit_albedo_map(texels, size, size, &options, texture).unwrap();
                seconds.push(start.elapsed().as_secs_f64());
                last = describe(&fit); // the fit dropped before the next: one fit's memory at a time
            }
            seconds.sort_by(f64::total_cmp);
            println!(
                "{name} {run}: median {:.2} s (runs {:?}), {}",
                seconds[seconds.len() / 2],
                seconds.iter().map(|s| (s * 100.0).round() / 100.0).collect::<Vec<_>>(),
                last
            );
        }
    }
}
