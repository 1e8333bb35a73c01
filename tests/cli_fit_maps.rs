//! `spectral-skin fit-maps`: an albedo EXR made from a parameter map by `maps` (the core's forward pipeline) is fitted
//! back; the fitted map's albedo, again by `maps`, is within ΔE00 0.5 of the input texel by texel; a NaN texel is
//! an error naming it and writes nothing.

use std::process::Command;

use spectral_skin::color::difference::{ciede2000, LabConverter};
use spectral_skin::color::WorkingSpace;
use spectral_skin::maps::io::{read_exr_channels, write_channels_exr, write_rgb_exr, ExrOptions, PARAM_CHANNELS};

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
    assert!(!out.exists() && !dir.path().join("residual.exr").exists());
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
    assert!(out_png.exists() && d.join("new/deeper/residual.exr").exists());
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
