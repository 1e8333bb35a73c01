//! `spectral-skin fit-maps`: an albedo EXR made from a parameter map by `maps` (the core's forward pipeline) is fitted
//! back; the fitted map's albedo, again by `maps`, is within ΔE00 0.5 of the input texel by texel; measured skin
//! colours (as a float EXR and as an 8-bit sRGB PNG) go through `fit-maps` and `maps` with no flags and come back
//! within the fit's own residual (the parameter map carries the chosen thickness); a NaN texel is an error naming it
//! and writes nothing.

use std::process::Command;

use spectral_skin::color::difference::{ciede2000, LabConverter};
use spectral_skin::color::WorkingSpace;
use spectral_skin::maps::io::{
    read_exr_channels, write_channels_exr, write_rgb_exr, ExrOptions, EXTENDED_CHANNELS, PARAM_CHANNELS,
};

use crate::support::measured::measured_skin_colours;

fn cli(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_spectral-skin")).args(args).output().unwrap()
}

fn rgb(path: &std::path::Path) -> Vec<[f64; 3]> {
    let (w, h, ch) = read_exr_channels(path).unwrap();
    let p = |n: &str| &ch.iter().find(|(c, _)| c == n).unwrap().1;
    (0..w * h).map(|i| [p("R")[i] as f64, p("G")[i] as f64, p("B")[i] as f64]).collect()
}

#[test]
fn fit_maps_round_trip_through_maps() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let s = |p: &str| d.join(p).to_str().unwrap().to_string();
    // 8 x 2 parameters over the domain, albedo by `maps --exact`.
    let (w, h) = (8usize, 2usize);
    let planes: [Vec<f32>; 4] = [
        (0..16).map(|i| 0.5 * ((i % 8) as f32 / 7.0).powi(3)).collect(),
        (0..16).map(|i| (i / 8) as f32 * 0.8 + 0.1).collect(),
        (0..16).map(|i| 0.1 * (((i * 3) % 8) as f32 / 7.0).powi(3)).collect(),
        vec![0.3; 16],
    ];
    let named: Vec<(&str, &[f32])> = PARAM_CHANNELS.iter().copied().zip(planes.iter().map(Vec::as_slice)).collect();
    write_channels_exr(&d.join("truth.exr"), w, h, &named, ExrOptions::FLOAT_PIZ).unwrap();
    let maps = |params: &str, out: &str| {
        let o =
            cli(&["maps", "--params", params, "--out", out, "--exact", "--precision", "float", "--outputs", "albedo"]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    maps(&s("truth.exr"), &s("a"));
    let o = cli(&["fit-maps", "--albedo", &s("a/albedo.exr"), "--out", &s("params.exr"), "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (_, _, residual) = read_exr_channels(&d.join("residual.exr")).unwrap();
    assert_eq!(residual[0].0, "Y");
    assert!(residual[0].1.iter().all(|&r| (0.0..0.5).contains(&r)), "{residual:?}");
    maps(&s("params.exr"), &s("b"));
    let conv = LabConverter::new(WorkingSpace::LinearRec709);
    for (a, b) in rgb(&d.join("a/albedo.exr")).iter().zip(rgb(&d.join("b/albedo.exr"))) {
        let de = ciede2000(conv.lab(*a), conv.lab(b));
        assert!(de <= 0.5, "{a:?} {b:?} {de}");
    }
}

#[test]
fn fit_maps_names_a_nan_texel_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let mut r = vec![0.4f32; 6];
    r[4] = f32::NAN;
    let (g, b) = (vec![0.3f32; 6], vec![0.25f32; 6]);
    write_rgb_exr(&dir.path().join("albedo.exr"), 3, 2, [&r, &g, &b], ExrOptions::FLOAT_PIZ).unwrap();
    let out = dir.path().join("params.exr");
    let o =
        cli(&["fit-maps", "--albedo", dir.path().join("albedo.exr").to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("(x, y) = (1, 1)"), "{err}");
    let residual = dir.path().join("residual.exr");
    assert!(
        !out.exists() && !residual.exists(),
        "written on a failed fit: params {}, residual {}",
        out.exists(),
        residual.exists()
    );
}

/// The sRGB decoding formula (IEC 61966-2-1), written out here.
fn srgb_formula(encoded: f64) -> f64 {
    if encoded <= 0.04045 {
        encoded / 12.92
    } else {
        ((encoded + 0.055) / 1.055).powf(2.4)
    }
}

#[test]
fn fit_maps_takes_an_srgb_png_albedo_into_a_folder_it_creates() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Skin-like sRGB codes, 3 x 2.
    let codes: [[u8; 3]; 6] =
        [[224, 172, 150], [200, 150, 120], [150, 100, 80], [110, 70, 55], [240, 200, 180], [180, 120, 100]];
    image::RgbImage::from_raw(3, 2, codes.concat()).unwrap().save(d.join("albedo.png")).unwrap();
    // The same texture as a linear EXR, decoded here with the formula.
    let plane = |c: usize| -> Vec<f32> { codes.iter().map(|t| srgb_formula(f64::from(t[c]) / 255.0) as f32).collect() };
    let (r, g, b) = (plane(0), plane(1), plane(2));
    write_rgb_exr(&d.join("albedo.exr"), 3, 2, [&r, &g, &b], ExrOptions::FLOAT_PIZ).unwrap();
    let out_png = d.join("new/deeper/params.exr");
    let o = cli(&["fit-maps", "--albedo", d.join("albedo.png").to_str().unwrap(), "--out", out_png.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let residual_png = d.join("new/deeper/residual.exr");
    assert!(
        out_png.exists() && residual_png.exists(),
        "params written: {}, residual written: {}",
        out_png.exists(),
        residual_png.exists()
    );
    let out_exr = d.join("params_exr.exr");
    let o = cli(&[
        "fit-maps",
        "--albedo",
        d.join("albedo.exr").to_str().unwrap(),
        "--out",
        out_exr.to_str().unwrap(),
        "--residual",
        d.join("residual_exr.exr").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(read_exr_channels(&out_png).unwrap(), read_exr_channels(&out_exr).unwrap());
    // sRGB has Rec.709's primaries: another working space is refused for it, naming the file.
    let o = cli(&["fit-maps", "--albedo", d.join("albedo.png").to_str().unwrap(), "--working-space", "acescg"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("albedo.png") && err.contains("linear_rec709"), "{err}");
}

#[test]
fn fit_maps_into_an_unwritable_place_fails_before_reading_or_fitting() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("a_file"), "not a folder").unwrap();
    // The albedo does not even exist: the output folder is checked first, so the error is about it.
    let out = d.join("a_file/sub/params.exr");
    let o = cli(&["fit-maps", "--albedo", d.join("missing.png").to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(err.contains("a_file/sub") && err.contains("output folder") && !err.contains("missing.png"), "{err}");
}

/// sRGB encoding (IEC 61966-2-1) to 8 bits, written out here.
fn srgb_8bit(linear: f64) -> u8 {
    let v = linear.clamp(0.0, 1.0);
    let s = if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0).round() as u8
}

/// The median of ΔE00 values.
fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// 200 measured skin colours (Xiao et al. 2016, eight ethnic groups; 20 x 10 texels) through `fit-maps` then `maps
/// --params`, both with their defaults: the thickness `fit-maps` chose travels in the parameter map, so `maps`'s
/// albedo is within 0.1 ΔE00 of the fit's own residual at every texel, and the median within 0.5 (an 8-bit sRGB PNG
/// of the same colours: 0.6, against its decoded codes).
#[test]
fn measured_skin_colours_round_trip_through_the_defaults() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let s = |p: &str| d.join(p).to_str().unwrap().to_string();
    let colours = measured_skin_colours(200, WorkingSpace::LinearRec709);
    let (w, h) = (20usize, 10usize);
    let plane = |c: usize| -> Vec<f32> { colours.iter().map(|t| t[c] as f32).collect() };
    write_rgb_exr(&d.join("albedo.exr"), w, h, [&plane(0), &plane(1), &plane(2)], ExrOptions::FLOAT_PIZ).unwrap();
    let codes: Vec<u8> = colours.iter().flat_map(|t| t.map(srgb_8bit)).collect();
    image::RgbImage::from_raw(w as u32, h as u32, codes.clone()).unwrap().save(d.join("albedo.png")).unwrap();
    let conv = LabConverter::new(WorkingSpace::LinearRec709);
    for (input, bound) in [("albedo.exr", 0.5), ("albedo.png", 0.6)] {
        let o = cli(&["fit-maps", "--albedo", &s(input), "--out", &s("fit/params.exr"), "--json"]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let chosen = report["thickness"]["chosen_mm"].as_f64().unwrap();
        let (_, _, channels) = read_exr_channels(&d.join("fit/params.exr")).unwrap();
        let names: Vec<&str> = channels.iter().map(|(n, _)| n.as_str()).collect();
        let expected: Vec<&str> = PARAM_CHANNELS.iter().chain(&EXTENDED_CHANNELS).copied().collect();
        let mut sorted = expected.clone();
        sorted.sort_unstable();
        assert_eq!(names, sorted, "{input}: the parameter map's channels (EXR stores them sorted)");
        let thickness = &channels.iter().find(|(n, _)| n == "epidermis_thickness_mm").unwrap().1;
        assert!(thickness.iter().all(|&t| t == chosen as f32), "{input}: {chosen} {:?}", &thickness[..3]);
        let (_, _, residual) = read_exr_channels(&d.join("fit/residual.exr")).unwrap();
        let o = cli(&["maps", "--params", &s("fit/params.exr"), "--out", &s("out"), "--precision", "float"]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let target: Vec<[f64; 3]> = if input.ends_with(".png") {
            codes.chunks(3).map(|c| [0, 1, 2].map(|k| srgb_formula(f64::from(c[k]) / 255.0))).collect()
        } else {
            rgb(&d.join("albedo.exr"))
        };
        let mut round_trip = Vec::new();
        for (i, (a, b)) in target.iter().zip(rgb(&d.join("out/albedo.exr"))).enumerate() {
            let de = ciede2000(conv.lab(*a), conv.lab(b));
            let own = residual[0].1[i] as f64;
            assert!(de <= own + 0.1, "{input} texel {i}: {a:?} -> {b:?}: ΔE00 {de}, the fit's own {own}");
            round_trip.push(de);
        }
        let m = median(round_trip);
        println!("{input}: thickness {chosen} mm, round-trip ΔE00 median {m:.3}");
        assert!(m <= bound, "{input}: median ΔE00 {m} (bound {bound})");
    }
}

/// A UDIM tile set end to end: four parameter tiles (1001, 1002, 1011, 1012; heights differ) through `maps --params
/// params.<UDIM>.exr` give four albedo tiles, each the same as `maps` on that tile alone (the set is computed as one
/// texture, then split); `fit-maps` on the albedo set gives a parameter set with the same tiles and one thickness,
/// whose maps come back within the fit's residual + 0.1 ΔE00; a tile set in with a plain file out is refused.
#[test]
fn a_udim_tile_set_round_trips_through_fit_maps_and_maps() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let s = |p: &str| d.join(p).to_str().unwrap().to_string();
    let tiles = [1001u32, 1002, 1011, 1012];
    let w = 6usize;
    for (k, tile) in tiles.iter().enumerate() {
        let h = 2 + k % 2;
        let n = w * h;
        let planes: [Vec<f32>; 4] = [
            (0..n).map(|i| 0.4 * (((i + 3 * k) % 7) as f32 / 6.0).powi(3) + 0.002).collect(),
            (0..n).map(|i| ((i + k) % 5) as f32 / 4.0).collect(),
            (0..n).map(|i| 0.08 * (((i * 3 + k) % 6) as f32 / 5.0).powi(3) + 0.001).collect(),
            vec![0.3; n],
        ];
        let named: Vec<(&str, &[f32])> = PARAM_CHANNELS.iter().copied().zip(planes.iter().map(Vec::as_slice)).collect();
        write_channels_exr(&d.join(format!("truth.{tile}.exr")), w, h, &named, ExrOptions::FLOAT_PIZ).unwrap();
    }
    let maps = |params: &str, out: &str| {
        let o = cli(&["maps", "--params", params, "--out", out, "--precision", "float", "--outputs", "albedo"]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    maps(&s("truth.<UDIM>.exr"), &s("a"));
    let sidecar: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("a/skin_maps.json")).unwrap()).unwrap();
    assert_eq!(sidecar["report"]["tiles"], serde_json::json!(tiles), "{sidecar}");
    assert!(sidecar["outputs"]["albedo.<UDIM>.exr"]["compression"].is_string(), "{sidecar}");
    for tile in tiles {
        maps(&s(&format!("truth.{tile}.exr")), &s(&format!("alone{tile}")));
        assert_eq!(
            rgb(&d.join(format!("a/albedo.{tile}.exr"))),
            rgb(&d.join(format!("alone{tile}/albedo.exr"))),
            "tile {tile}"
        );
    }
    let plain = d.join("a/albedo.exr");
    assert!(!plain.exists(), "a UDIM run wrote {plain:?}");
    let o = cli(&["fit-maps", "--albedo", &s("a/albedo.<UDIM>.exr"), "--out", &s("fit/params.<UDIM>.exr"), "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["tiles"], serde_json::json!(tiles), "{report}");
    maps(&s("fit/params.<UDIM>.exr"), &s("b"));
    let conv = LabConverter::new(WorkingSpace::LinearRec709);
    for tile in tiles {
        let (_, _, residual) = read_exr_channels(&d.join(format!("fit/residual.{tile}.exr"))).unwrap();
        let (_, _, params) = read_exr_channels(&d.join(format!("fit/params.{tile}.exr"))).unwrap();
        let thickness = &params.iter().find(|(n, _)| n == "epidermis_thickness_mm").unwrap().1;
        assert!(
            thickness.iter().all(|&t| t as f64 == report["extended"][0].as_f64().unwrap() as f32 as f64),
            "tile {tile}: thickness {thickness:?}, reported {}",
            report["extended"][0]
        );
        let a = rgb(&d.join(format!("a/albedo.{tile}.exr")));
        let b = rgb(&d.join(format!("b/albedo.{tile}.exr")));
        for (i, (x, y)) in a.iter().zip(&b).enumerate() {
            let de = ciede2000(conv.lab(*x), conv.lab(*y));
            assert!(de <= residual[0].1[i] as f64 + 0.1, "tile {tile} texel {i}: {x:?} {y:?} {de}");
        }
    }
    let o = cli(&["fit-maps", "--albedo", &s("a/albedo.<UDIM>.exr"), "--out", &s("plain.exr")]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("<UDIM>") && err.contains("plain.exr"), "{err}");
    let o = cli(&["maps", "--params", &s("missing.<UDIM>.exr"), "--out", &s("c")]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("no tiles of missing.<UDIM>.exr"), "{err}");
}

/// The model's albedo (linear Rec.709, by `evaluate`) of four skins from fair to dark.
fn four_skin_albedos() -> Vec<[f64; 3]> {
    use spectral_skin::evaluate::{evaluate, Outputs, Request};
    let request = Request::new(Outputs { albedo: true, ..Outputs::default() });
    [(0.01, 0.7, 0.01), (0.05, 0.5, 0.02), (0.15, 0.7, 0.01), (0.3, 0.8, 0.03)]
        .iter()
        .map(|&(m, b, h)| {
            let p = spectral_skin::SkinParams::new(m, b, h, 0.3).unwrap();
            evaluate(&p, &request).unwrap().diffuse_reflectance_rgb.unwrap()
        })
        .collect()
}

/// A lit texture (the model's albedos x R 1.6, G 1.2, B 0.6): `fit-maps` warns that it is not an albedo and names
/// the gains measured; `--auto-gains` applies gains (in --json, and in the options recorded) and the texels come
/// inside; `--rgb-gains` takes three gains and refuses another count before any work.
#[test]
fn fit_maps_diagnoses_a_lit_texture_and_applies_gains() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let s = |p: &str| d.join(p).to_str().unwrap().to_string();
    let texels: Vec<[f64; 3]> = four_skin_albedos().iter().map(|a| [a[0] * 1.6, a[1] * 1.2, a[2] * 0.6]).collect();
    let plane = |c: usize| -> Vec<f32> { texels.iter().map(|t| t[c] as f32).collect() };
    write_rgb_exr(&d.join("lit.exr"), 2, 2, [&plane(0), &plane(1), &plane(2)], ExrOptions::FLOAT_PIZ).unwrap();
    let o = cli(&["fit-maps", "--albedo", &s("lit.exr"), "--out", &s("p.exr"), "--json"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.success() && err.contains("does not look like an albedo") && err.contains("--auto-gains"),
        "{err}"
    );
    let plain: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let o = cli(&["fit-maps", "--albedo", &s("lit.exr"), "--out", &s("p.exr"), "--json", "--auto-gains"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let gained: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(gained["gains"]["rgb_gains"], gained["stats"]["options"]["rgb_gains"], "{gained}");
    let mean = |v: &serde_json::Value| v["stats"]["mean_delta_e00"].as_f64().unwrap();
    assert!(mean(&gained) < 0.5 * mean(&plain), "{gained} {plain}");
    let o = cli(&["fit-maps", "--albedo", &s("lit.exr"), "--out", &s("q.exr"), "--rgb-gains", "0.625,0.8333,1.6667"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = cli(&["fit-maps", "--albedo", &s("missing.exr"), "--rgb-gains", "0.5,1"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("--rgb-gains takes three gains") && !err.contains("missing"), "{err}");
    // A negative first gain is a value for the range check, not a flag (issue 38 item 5: clap took `-1,1,1` for
    // one).
    let o = cli(&["fit-maps", "--albedo", &s("lit.exr"), "--out", &s("r.exr"), "--rgb-gains", "-1,1,1"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("rgb_gains[0]") && !err.contains("unexpected argument"), "{err}");
}

/// `fit-maps --mask`: skin over a green background; unmasked the background makes it warn, with a black-and-white
/// PNG mask (white = skin) it does not, and the figures count only the skin; a mask of another size is refused.
#[test]
fn fit_maps_takes_a_skin_mask() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let s = |p: &str| d.join(p).to_str().unwrap().to_string();
    // The top row: skin (the model's albedos, 8-bit sRGB); the bottom row: green.
    let mut codes: Vec<[u8; 3]> = four_skin_albedos().iter().map(|a| a.map(srgb_8bit)).collect();
    codes.extend([[20, 160, 30]; 4]);
    image::RgbImage::from_raw(4, 2, codes.concat()).unwrap().save(d.join("albedo.png")).unwrap();
    let mask: Vec<u8> = (0..8).map(|i| if i < 4 { 255 } else { 0 }).collect();
    image::GrayImage::from_raw(4, 2, mask).unwrap().save(d.join("mask.png")).unwrap();
    image::GrayImage::from_raw(2, 2, vec![255; 4]).unwrap().save(d.join("small.png")).unwrap();
    let o = cli(&["fit-maps", "--albedo", &s("albedo.png"), "--out", &s("p.exr"), "--json"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success() && err.contains("does not look like an albedo"), "{err}");
    let o = cli(&["fit-maps", "--albedo", &s("albedo.png"), "--out", &s("p.exr"), "--json", "--mask", &s("mask.png")]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success() && !err.contains("does not look like an albedo"), "{err}");
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["stats"]["masked_out_texels"], 4, "{report}");
    assert!(report["stats"]["max_delta_e00"].as_f64().unwrap() < 0.6, "{report}");
    let o = cli(&["fit-maps", "--albedo", &s("albedo.png"), "--out", &s("p.exr"), "--mask", &s("small.png")]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("must have one size"), "{err}");
    // A mask that is no image is named as the mask (issue 38 item 5: an empty CSV was blamed on the albedo texture).
    std::fs::write(d.join("empty.csv"), "").unwrap();
    let o = cli(&["fit-maps", "--albedo", &s("albedo.png"), "--out", &s("p.exr"), "--mask", &s("empty.csv")]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("skin mask") && !err.contains("albedo texture"), "{err}");
}

/// `fit-maps` writes OpenEXR only: `--out params.png` (it wrote EXR bytes under that name) and `--residual r.png`
/// are refused before anything is read or written (issue 38 item 5).
#[test]
fn fit_maps_refuses_output_names_it_would_not_honour() {
    let dir = tempfile::tempdir().unwrap();
    let s = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    for outputs in [["--out", "params.png"], ["--residual", "r.png"]] {
        let o = cli(&["fit-maps", "--albedo", &s("missing.exr"), outputs[0], &s(outputs[1])]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success()
                && err.contains(outputs[1])
                && err.contains("ending in .exr")
                && !err.contains("missing"),
            "{outputs:?}: {err}"
        );
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "nothing written");
}
