//! A built-in example parameter map: a face-like layout (not anatomy, a test card) with lips rich in blood, blushed
//! cheeks, freckles rich in melanin, an oily T-zone and smooth variation everywhere, so every pipeline strategy and
//! every parameter is exercised. Deterministic: the same size gives the same map.

use std::path::Path;

use super::io::{write_channels_exr, Compression, ExrOptions, ParamImage, Plane, Precision, PARAM_CHANNELS};
use crate::error::SkinError;

/// Squared elliptical distance of (x, y) from a centre with radii (rx, ry), all in [0, 1] image units.
fn ellipse(x: f32, y: f32, cx: f32, cy: f32, rx: f32, ry: f32) -> f32 {
    ((x - cx) / rx).powi(2) + ((y - cy) / ry).powi(2)
}

/// Smooth bump: 1 at the centre of an ellipse, 0 outside (d2 = squared elliptical distance).
fn bump(d2: f32) -> f32 {
    if d2 >= 1.0 {
        0.0
    } else {
        (1.0 - d2).powi(2)
    }
}

/// A small deterministic hash to place freckles (splitmix64).
fn hash(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The example map at `size` x `size` texels (row 0 at the top).
pub fn face_params(size: usize) -> ParamImage {
    let n = size.max(1);
    let freckles: Vec<(f32, f32, f32)> = (0..160u64)
        .map(|k| {
            let h = hash(k);
            let u = (h & 0xFFFF) as f32 / 65535.0;
            let v = ((h >> 16) & 0xFFFF) as f32 / 65535.0;
            let r = 0.006 + 0.01 * ((h >> 32) & 0xFF) as f32 / 255.0;
            // Across the cheeks and nose: a band around y = 0.5.
            (0.2 + 0.6 * u, 0.4 + 0.22 * v, r)
        })
        .collect();
    let mut planes = [vec![0f32; n * n], vec![0f32; n * n], vec![0f32; n * n], vec![0f32; n * n]];
    for j in 0..n {
        for i in 0..n {
            let (x, y) = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
            let lips = bump(ellipse(x, y, 0.5, 0.8, 0.16, 0.05));
            let cheeks = bump(ellipse(x, y, 0.28, 0.58, 0.12, 0.09)) + bump(ellipse(x, y, 0.72, 0.58, 0.12, 0.09));
            let tzone = bump(ellipse(x, y, 0.5, 0.18, 0.32, 0.08)) + bump(ellipse(x, y, 0.5, 0.45, 0.07, 0.25));
            let freckle: f32 = freckles.iter().map(|&(fx, fy, r)| bump(ellipse(x, y, fx, fy, r, r))).sum();
            let t = y; // forehead to chin: slightly more pigment lower down
            let melanin = 0.02 + 0.01 * t + 0.09 * freckle.min(1.0) - 0.01 * lips;
            let melanin_blend = 0.65 + 0.15 * x;
            let hemoglobin = 0.008 + 0.002 * t + 0.018 * cheeks.min(1.0) + 0.05 * lips;
            let oiliness = 0.12 + 0.5 * tzone.min(1.0) + 0.2 * lips;
            let k = j * n + i;
            planes[0][k] = melanin.clamp(0.0, 0.5);
            planes[1][k] = melanin_blend.clamp(0.0, 1.0);
            planes[2][k] = hemoglobin.clamp(0.0, 0.1);
            planes[3][k] = oiliness.clamp(0.0, 1.0);
        }
    }
    let [a, b, c, d] = planes;
    ParamImage::new(n, n, [Plane::Texels(a), Plane::Texels(b), Plane::Texels(c), Plane::Texels(d)])
}

/// Which example map.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum), value(rename_all = "snake_case"))]
pub enum ExampleKind {
    /// The face-like test card: distinct values nearly everywhere (the table strategy).
    Face,
    /// Sixteen blocks of distinct parameters, like an 8-bit mask (the distinct-tuple strategy).
    Mask,
    /// One value everywhere (the constant strategy).
    Uniform,
}

/// An example map of the given kind.
pub fn example_params(kind: ExampleKind, size: usize) -> ParamImage {
    let n = size.max(1);
    let block = |i: usize, j: usize| (4 * j / n) * 4 + 4 * i / n; // 0..16
    let plane = |f: &dyn Fn(usize, usize) -> f32| Plane::Texels((0..n * n).map(|k| f(k % n, k / n)).collect());
    match kind {
        ExampleKind::Face => face_params(n),
        ExampleKind::Mask => ParamImage::new(
            n,
            n,
            [
                plane(&|i, j| 0.01 + 0.03 * (block(i, j) % 4) as f32),
                plane(&|i, j| 0.25 * (block(i, j) / 4) as f32),
                plane(&|_, _| 0.01),
                plane(&|i, j| 0.1 + 0.05 * (block(i, j) % 4) as f32),
            ],
        ),
        ExampleKind::Uniform => {
            ParamImage::new(n, n, [plane(&|_, _| 0.05), plane(&|_, _| 0.7), plane(&|_, _| 0.01), plane(&|_, _| 0.3)])
        }
    }
}

/// Write the face example map as one EXR with the four parameter channels.
pub fn write_face_params(path: &Path, size: usize) -> Result<(), SkinError> {
    write_example_params(path, ExampleKind::Face, size)
}

/// Largest example side, texels: 8192 x 8192 x 4 channels of f32 is 1 GiB in memory before it is written.
pub const MAX_EXAMPLE_SIZE: usize = 8192;

/// `size` if it is in [1, `MAX_EXAMPLE_SIZE`], else an error naming it (checked before anything is allocated).
pub fn check_example_size(size: usize) -> Result<usize, SkinError> {
    if (1..=MAX_EXAMPLE_SIZE).contains(&size) {
        Ok(size)
    } else {
        Err(SkinError::invalid(
            "size",
            format!("the example side must be in [1, {MAX_EXAMPLE_SIZE}] texels; got {size}"),
        ))
    }
}

/// The encoding of the example files: half floats (each parameter rounded to 11 significant bits, a relative error
/// of at most 2^-11 = 0.049 %, far below what changes a material visibly), PIZ. On the 4096² face this is a 6.5 MB
/// file instead of 44.5 MB in float, its PIZ decode in `maps` takes about a third of the float file's CPU time, and its
/// rows repeat each parameter tuple over about a dozen texels, which the lookup skips (docs/maps-performance.md has
/// both inputs' figures).
pub const EXAMPLE_EXR: ExrOptions = ExrOptions { precision: Precision::Half, compression: Compression::Piz };

/// Write an example map as one EXR with the four parameter channels ([`EXAMPLE_EXR`]).
pub fn write_example_params(path: &Path, kind: ExampleKind, size: usize) -> Result<(), SkinError> {
    write_example_params_encoded(path, kind, size, EXAMPLE_EXR)
}

/// [`write_example_params`] in another encoding (float samples keep the computed parameters exactly).
pub fn write_example_params_encoded(
    path: &Path,
    kind: ExampleKind,
    size: usize,
    encoding: ExrOptions,
) -> Result<(), SkinError> {
    let image = example_params(kind, check_example_size(size)?);
    let planes: Vec<&[f32]> = image
        .planes
        .iter()
        .map(|p| match p {
            Plane::Texels(v) => v.as_slice(),
            Plane::Constant(_) => unreachable!("the example has no constant plane"),
        })
        .collect();
    let channels: Vec<(&str, &[f32])> = PARAM_CHANNELS.iter().cloned().zip(planes).collect();
    write_channels_exr(path, image.width, image.height, &channels, encoding)
}
