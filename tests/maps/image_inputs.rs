//! Inputs as artists have them (issue 22 item 2): every layout the one reader (src/maps/io/read.rs) takes for a
//! parameter map and for an albedo texture, written here with the exr and image crates (independent writers), and
//! checked against hand-written values and the sRGB formula (IEC 61966-2-1) computed here.

use std::path::{Path, PathBuf};

use exr::prelude::{AnyChannel, AnyChannels, FlatSamples, Image, WritableImage};
use spectral_skin::maps::io::{
    read_albedo_texture, read_params, ParamInputs, ParamSource, Plane, PARAM_CHANNELS, PARAM_RANGES,
};

fn texels(p: &Plane) -> &[f32] {
    match p {
        Plane::Texels(v) => v,
        Plane::Constant(c) => panic!("expected texels, got constant {c}"),
    }
}

/// `path` as the melanin map, the other three constants.
fn melanin_map(path: &Path) -> Result<spectral_skin::maps::io::ParamImage, spectral_skin::SkinError> {
    read_params(&ParamInputs::Separate([
        ParamSource::File(path.to_path_buf()),
        ParamSource::Constant(0.7),
        ParamSource::Constant(0.01),
        ParamSource::Constant(0.3),
    ]))
}

/// An EXR of f32 channels `(name, values)`, `width` wide, written by the exr crate.
fn write_exr(path: &Path, width: usize, height: usize, channels: Vec<(&str, Vec<f32>)>) {
    let list: Vec<AnyChannel<FlatSamples>> =
        channels.into_iter().map(|(name, values)| AnyChannel::new(name, FlatSamples::F32(values))).collect();
    let image = Image::from_channels((width, height), AnyChannels::sort(list.into()));
    image.write().to_file(path).unwrap();
}

/// The sRGB decoding formula (IEC 61966-2-1), written out here.
fn srgb_formula(encoded: f64) -> f64 {
    if encoded <= 0.04045 {
        encoded / 12.92
    } else {
        ((encoded + 0.055) / 1.055).powf(2.4)
    }
}

fn temp(dir: &tempfile::TempDir, name: &str) -> PathBuf {
    dir.path().join(name)
}

// The grey values of a 3 x 2 map, exact in f32.
const GREY: [f32; 6] = [0.0, 0.125, 0.25, 0.375, 0.5, 0.0625];

#[test]
fn grey_rgb_exr_like_blenders_is_a_parameter_map() {
    let dir = tempfile::tempdir().unwrap();
    let path = temp(&dir, "melanin_grey.exr");
    // What Blender's "Save As" OpenEXR RGB writes for a grey image: channels R, G, B, equal.
    exr::prelude::write_rgb_file(&path, 3, 2, |x, y| {
        let v = GREY[y * 3 + x];
        (v, v, v)
    })
    .unwrap();
    let img = melanin_map(&path).unwrap();
    assert_eq!(texels(&img.planes[0]), GREY);
    assert!(img.notes.is_empty(), "{:?}", img.notes);
}

#[test]
fn grey_rgba_exr_is_a_parameter_map_with_its_alpha_ignored_and_noted() {
    let dir = tempfile::tempdir().unwrap();
    let path = temp(&dir, "melanin_rgba.exr");
    exr::prelude::write_rgba_file(&path, 3, 2, |x, y| {
        let v = GREY[y * 3 + x];
        (v, v, v, 0.5)
    })
    .unwrap();
    let img = melanin_map(&path).unwrap();
    assert_eq!(texels(&img.planes[0]), GREY);
    assert_eq!(img.notes.len(), 1, "{:?}", img.notes);
    assert!(img.notes[0].contains("melanin_rgba.exr") && img.notes[0].contains("alpha"), "{:?}", img.notes);
}

#[test]
fn grey_layer_rgb_exr_is_a_parameter_map() {
    let dir = tempfile::tempdir().unwrap();
    let path = temp(&dir, "layered.exr");
    let g = GREY.to_vec();
    write_exr(&path, 3, 2, vec![("ViewLayer.R", g.clone()), ("ViewLayer.G", g.clone()), ("ViewLayer.B", g)]);
    assert_eq!(texels(&melanin_map(&path).unwrap().planes[0]), GREY);
}

#[test]
fn non_grey_rgb_exr_is_refused_naming_the_file_the_channels_and_the_texel() {
    let dir = tempfile::tempdir().unwrap();
    let path = temp(&dir, "colour.exr");
    exr::prelude::write_rgb_file(&path, 3, 2, |x, y| if (x, y) == (1, 0) { (0.2, 0.3, 0.2) } else { (0.1, 0.1, 0.1) })
        .unwrap();
    let e = melanin_map(&path).unwrap_err().to_string();
    assert!(e.contains("colour.exr") && e.contains("melanin map"), "{e}");
    assert!(e.contains("found channels R, G, B that differ"), "{e}");
    assert!(e.contains("(x, y) = (1, 0)") && e.contains("not grey"), "{e}");
    assert!(e.contains("expected a single-channel EXR"), "the accepted forms: {e}");

    // Channels that are neither one channel, the parameter's name nor R, G, B: refused listing them.
    let other = temp(&dir, "other.exr");
    write_exr(&other, 1, 1, vec![("X", vec![0.0]), ("Y", vec![0.0])]);
    let e = melanin_map(&other).unwrap_err().to_string();
    assert!(e.contains("other.exr") && e.contains("found channels X, Y") && e.contains("R = G = B"), "{e}");
}

#[test]
fn grey_rgb_png_is_a_parameter_map_and_a_coloured_one_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let codes = [0u8, 51, 128, 255];
    let rgb: Vec<u8> = codes.iter().flat_map(|&v| [v, v, v]).collect();
    let path = temp(&dir, "grey_rgb.png");
    image::RgbImage::from_raw(4, 1, rgb).unwrap().save(&path).unwrap();
    let img = melanin_map(&path).unwrap();
    let (min, max) = PARAM_RANGES[0];
    let expected: Vec<f32> = codes.iter().map(|&v| (min + (max - min) * f64::from(v) / 255.0) as f32).collect();
    assert_eq!(texels(&img.planes[0]), expected, "data, not colour: no sRGB decoding");
    assert!(img.notes.is_empty(), "{:?}", img.notes);

    // RGBA, 16-bit, grey: taken, alpha noted.
    let rgba: Vec<u16> = [0u16, 65535, 1000].iter().flat_map(|&v| [v, v, v, 7]).collect();
    let path16 = temp(&dir, "grey_rgba16.png");
    image::ImageBuffer::<image::Rgba<u16>, Vec<u16>>::from_raw(3, 1, rgba).unwrap().save(&path16).unwrap();
    let img = melanin_map(&path16).unwrap();
    assert_eq!(texels(&img.planes[0]), [0.0, 0.5, (0.5 * 1000.0 / 65535.0f64) as f32]);
    assert!(img.notes.len() == 1 && img.notes[0].contains("alpha"), "{:?}", img.notes);

    let colour = temp(&dir, "colour.png");
    image::RgbImage::from_raw(2, 1, vec![9, 9, 9, 10, 20, 30]).unwrap().save(&colour).unwrap();
    let e = melanin_map(&colour).unwrap_err().to_string();
    assert!(e.contains("colour.png") && e.contains("R, G, B") && e.contains("(x, y) = (1, 0)"), "{e}");
}

#[test]
fn greyscale_jpeg_is_a_parameter_map() {
    let dir = tempfile::tempdir().unwrap();
    let path = temp(&dir, "melanin.jpg");
    image::GrayImage::from_raw(8, 8, vec![128; 64]).unwrap().save(&path).unwrap();
    // The reference: the same file decoded by the image crate directly.
    let decoded = image::open(&path).unwrap().into_luma8();
    let img = melanin_map(&path).unwrap();
    let (min, max) = PARAM_RANGES[0];
    let expected: Vec<f32> =
        decoded.as_raw().iter().map(|&v| (min + (max - min) * f64::from(v) / 255.0) as f32).collect();
    assert_eq!(texels(&img.planes[0]), expected);
}

#[test]
fn unknown_channel_of_a_parameter_exr_is_noted_with_the_known_names() {
    let dir = tempfile::tempdir().unwrap();
    let path = temp(&dir, "params.exr");
    let mut channels: Vec<(&str, Vec<f32>)> = PARAM_CHANNELS.iter().map(|&c| (c, vec![0.01f32; 2])).collect();
    channels.push(("blood_oxygenaton", vec![0.9; 2]));
    write_exr(&path, 2, 1, channels);
    let img = read_params(&ParamInputs::Multi { path, constants: [None; 4] }).unwrap();
    assert_eq!(img.notes.len(), 1, "{:?}", img.notes);
    let note = &img.notes[0];
    assert!(note.contains("params.exr") && note.contains("blood_oxygenaton"), "{note}");
    assert!(note.contains("blood_oxygenation") && note.contains("epidermis_thickness_mm"), "known names: {note}");
}

#[test]
fn srgb_pngs_are_read_as_linear_albedo_within_1_in_65535_of_the_formula() {
    let dir = tempfile::tempdir().unwrap();
    // 8-bit: every code, in R; G and B other codes.
    let rgb: Vec<u8> = (0..=255u8).flat_map(|v| [v, 255 - v, v / 2]).collect();
    let p8 = temp(&dir, "albedo8.png");
    image::RgbImage::from_raw(16, 16, rgb.clone()).unwrap().save(&p8).unwrap();
    let t = read_albedo_texture(&p8).unwrap();
    assert_eq!((t.width, t.height, t.texels.len()), (16, 16, 256));
    assert!(t.srgb_decoded && t.notes.is_empty(), "srgb_decoded {}, notes {:?}", t.srgb_decoded, t.notes);
    for (texel, code) in t.texels.iter().zip(rgb.chunks_exact(3)) {
        for c in 0..3 {
            let reference = srgb_formula(f64::from(code[c]) / 255.0);
            assert!((f64::from(texel[c]) - reference).abs() <= 1.0 / 65535.0, "{code:?} {texel:?}");
        }
    }
    // 16-bit.
    let codes: Vec<u16> = (0..300u32).map(|i| ((i * 219) % 65536) as u16).chain([65535, 1, 2]).collect();
    let rgb16: Vec<u16> = codes.iter().flat_map(|&v| [v, 65535 - v, v / 3]).collect();
    let p16 = temp(&dir, "albedo16.png");
    image::ImageBuffer::<image::Rgb<u16>, Vec<u16>>::from_raw(codes.len() as u32, 1, rgb16.clone())
        .unwrap()
        .save(&p16)
        .unwrap();
    let t = read_albedo_texture(&p16).unwrap();
    for (texel, code) in t.texels.iter().zip(rgb16.chunks_exact(3)) {
        for c in 0..3 {
            let reference = srgb_formula(f64::from(code[c]) / 65535.0);
            assert!((f64::from(texel[c]) - reference).abs() <= 1.0 / 65535.0, "{code:?} {texel:?}");
        }
    }
}

#[test]
fn jpeg_and_rgba_png_albedos_are_read_and_alpha_is_noted() {
    let dir = tempfile::tempdir().unwrap();
    let jpg = temp(&dir, "albedo.jpg");
    let colour: Vec<u8> = (0..64).flat_map(|_| [200u8, 120, 90]).collect();
    image::RgbImage::from_raw(8, 8, colour).unwrap().save(&jpg).unwrap();
    let decoded = image::open(&jpg).unwrap().into_rgb8();
    let t = read_albedo_texture(&jpg).unwrap();
    for (texel, code) in t.texels.iter().zip(decoded.as_raw().chunks_exact(3)) {
        for c in 0..3 {
            let reference = srgb_formula(f64::from(code[c]) / 255.0);
            assert!(
                (f64::from(texel[c]) - reference).abs() <= 1.0 / 65535.0,
                "channel {c}: code {code:?} read as {texel:?}, formula {reference}"
            );
        }
    }

    let png = temp(&dir, "albedo_alpha.png");
    image::RgbaImage::from_raw(2, 1, vec![255, 0, 0, 10, 0, 0, 255, 255]).unwrap().save(&png).unwrap();
    let t = read_albedo_texture(&png).unwrap();
    assert_eq!(t.texels, [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]);
    assert!(
        t.notes.len() == 1 && t.notes[0].contains("albedo_alpha.png") && t.notes[0].contains("alpha"),
        "{:?}",
        t.notes
    );
}

#[test]
fn exr_albedos_bare_or_layered_and_refusals_name_the_channels() {
    let dir = tempfile::tempdir().unwrap();
    let bare = temp(&dir, "bare.exr");
    exr::prelude::write_rgba_file(&bare, 2, 1, |x, _| (0.1 * x as f32, 0.5, 0.25, 1.0)).unwrap();
    let t = read_albedo_texture(&bare).unwrap();
    assert_eq!(t.texels, [[0.0, 0.5, 0.25], [0.1, 0.5, 0.25]]);
    assert!(!t.srgb_decoded && t.notes.len() == 1 && t.notes[0].contains('A'), "{:?}", t.notes);

    let layered = temp(&dir, "layered.exr");
    write_exr(&layered, 1, 1, vec![("Combined.R", vec![0.4]), ("Combined.G", vec![0.3]), ("Combined.B", vec![0.2])]);
    assert_eq!(read_albedo_texture(&layered).unwrap().texels, [[0.4, 0.3, 0.2]]);

    let grey = temp(&dir, "Y.exr");
    write_exr(&grey, 1, 1, vec![("Y", vec![0.4])]);
    let e = read_albedo_texture(&grey).unwrap_err().to_string();
    assert!(
        e.contains("Y.exr") && e.contains("found channels Y") && e.contains("expected an EXR with channels R, G, B"),
        "{e}"
    );

    let two = temp(&dir, "two.exr");
    let ch = |n| (n, vec![0.5f32]);
    write_exr(&two, 1, 1, vec![ch("a.R"), ch("a.G"), ch("a.B"), ch("b.R"), ch("b.G"), ch("b.B")]);
    let e = read_albedo_texture(&two).unwrap_err().to_string();
    assert!(e.contains("two.exr") && e.contains("several layers") && e.contains("a, b"), "{e}");
}

/// A FIFO given as a map is refused at once, naming it (issue 38 item 5: opening it waited for a writer forever).
/// The read runs on a thread and must answer within a generous 30 s.
#[cfg(unix)]
#[test]
fn a_fifo_given_as_a_map_is_refused_not_waited_on() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = temp(&dir, "melanin.fifo");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success(), "mkfifo: {made:?}");
    let (send, receive) = std::sync::mpsc::channel();
    let path = fifo.clone();
    std::thread::spawn(move || send.send(melanin_map(&path).map(|_| ()).map_err(|e| e.to_string())));
    let answer = receive.recv_timeout(std::time::Duration::from_secs(30)).expect("the read blocked on the FIFO");
    let e = answer.expect_err("a FIFO is no map");
    assert!(e.contains("melanin.fifo") && e.contains("regular file"), "{e}");
}
