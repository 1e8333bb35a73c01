//! Damaged images are refused (issue 38 item 3): every supported format (PNG, TIFF, JPEG, EXR), in every layout the
//! reader takes, cut at every 1/40 of its bytes and at its last bytes, is an error naming the file, for both readers
//! (a parameter map and an albedo texture), never a map decoded from what is left. A JPEG cut at 60 % of its bytes
//! used to be accepted with 42 % of its texels wrong: JPEG decoders fill a missing end with grey.

use std::io::Cursor;

use spectral_skin::maps::io::{read_albedo_texture, read_params_from_bytes};

const WIDTH: u32 = 48;
const HEIGHT: u32 = 40;

/// A grey value per texel with structure at every scale (so every part of the file matters).
fn grey(x: u32, y: u32) -> u8 {
    ((x * 5 + y * 3 + (x * y) % 17) % 256) as u8
}

fn encoded(image: image::DynamicImage, format: image::ImageFormat) -> Vec<u8> {
    let mut bytes = Cursor::new(Vec::new());
    image.write_to(&mut bytes, format).unwrap();
    bytes.into_inner()
}

fn grey8() -> image::DynamicImage {
    image::DynamicImage::ImageLuma8(image::GrayImage::from_fn(WIDTH, HEIGHT, |x, y| image::Luma([grey(x, y)])))
}

fn grey16() -> image::DynamicImage {
    image::DynamicImage::ImageLuma16(image::ImageBuffer::from_fn(WIDTH, HEIGHT, |x, y| {
        image::Luma([u16::from(grey(x, y)) * 257])
    }))
}

fn rgb8() -> image::DynamicImage {
    image::DynamicImage::ImageRgb8(image::RgbImage::from_fn(WIDTH, HEIGHT, |x, y| {
        let v = grey(x, y);
        image::Rgb([v, v, v])
    }))
}

fn exr_bytes(compression: exr::compression::Compression) -> Vec<u8> {
    use exr::prelude::*;
    let (w, h) = (WIDTH as usize, HEIGHT as usize);
    let value = |x: usize, y: usize| f32::from(grey(x as u32, y as u32)) / 255.0;
    let channels = SpecificChannels::rgb(|Vec2(x, y)| (value(x, y), value(x, y), value(x, y)));
    let layer = Layer::new(
        (w, h),
        LayerAttributes::default(),
        Encoding { compression, blocks: Blocks::ScanLines, line_order: LineOrder::Increasing },
        channels,
    );
    let mut bytes = Cursor::new(Vec::new());
    Image::from_layer(layer).write().to_buffered(&mut bytes).unwrap();
    bytes.into_inner()
}

/// Every layout of every format the readers take, as complete files: (name, bytes).
fn complete_files() -> Vec<(String, Vec<u8>)> {
    use image::ImageFormat::{Jpeg, Png, Tiff};
    let mut files = Vec::new();
    for (format, extension) in [(Png, "png"), (Tiff, "tif"), (Jpeg, "jpg")] {
        let layouts: Vec<(&str, image::DynamicImage)> = if format == Jpeg {
            vec![("grey8", grey8()), ("rgb8", rgb8())]
        } else {
            vec![("grey8", grey8()), ("grey16", grey16()), ("rgb8", rgb8())]
        };
        for (layout, image) in layouts {
            files.push((format!("{layout}.{extension}"), encoded(image, format)));
        }
    }
    use exr::compression::Compression;
    for (name, compression) in
        [("none", Compression::Uncompressed), ("zip", Compression::ZIP16), ("piz", Compression::PIZ)]
    {
        files.push((format!("rgb_{name}.exr"), exr_bytes(compression)));
    }
    files
}

/// The lengths a file is cut to: every 1/40 of it, and all but its last 1 to 4 bytes.
fn cuts(len: usize) -> Vec<usize> {
    let mut cuts: Vec<usize> = (1..40).map(|k| len * k / 40).chain((1..=4).map(|k| len - k)).collect();
    cuts.sort_unstable();
    cuts.dedup();
    cuts
}

#[test]
fn every_truncated_image_of_every_format_is_refused_by_both_readers() {
    let dir = tempfile::tempdir().unwrap();
    let mut accepted = Vec::new();
    for (name, bytes) in complete_files() {
        // The complete file is read by both readers (so a refusal below is the cut's).
        read_params_from_bytes(&bytes, &name, Some(0)).unwrap_or_else(|e| panic!("complete {name}: {e}"));
        let path = dir.path().join(&name);
        std::fs::write(&path, &bytes).unwrap();
        read_albedo_texture(&path).unwrap_or_else(|e| panic!("complete {name}: {e}"));
        for cut in cuts(bytes.len()) {
            let label = format!("{cut}_of_{name}");
            let part = &bytes[..cut];
            match read_params_from_bytes(part, &label, Some(0)) {
                Ok(_) => accepted.push(format!("parameter map {name} cut to {cut} of {} bytes", bytes.len())),
                Err(e) => assert!(e.to_string().contains(&label), "{label}: the message names no file: {e}"),
            }
            let path = dir.path().join(&label);
            std::fs::write(&path, part).unwrap();
            match read_albedo_texture(&path) {
                Ok(_) => accepted.push(format!("albedo texture {name} cut to {cut} of {} bytes", bytes.len())),
                Err(e) => assert!(e.to_string().contains(&label), "{label}: the message names no file: {e}"),
            }
        }
    }
    assert!(accepted.is_empty(), "{} truncated files accepted:\n{}", accepted.len(), accepted.join("\n"));
}

/// A complete file followed by bytes of no meaning (some writers pad) is still read: the check is for what the
/// format says must be there, not for the file's end.
#[test]
fn trailing_bytes_after_a_complete_image_are_no_damage() {
    for (name, mut bytes) in complete_files() {
        bytes.extend_from_slice(&[0u8; 16]);
        read_params_from_bytes(&bytes, &name, Some(0)).unwrap_or_else(|e| panic!("padded {name}: {e}"));
    }
}
