//! EXR encoding of output planes: single-part scan-line files, blocks built straight from the planes and compressed
//! in parallel, staged beside their destination (see [`super::staging`]).

use std::cell::Cell;
use std::io::{BufWriter, Write};
use std::path::Path;

use exr::block::writer::ChunksWriter;
use exr::block::UncompressedBlock;
use exr::meta::attribute::{ChannelDescription, LineOrder, SampleType, Text};
use exr::meta::header::Header;
use exr::meta::BlockDescription;
use exr::prelude::f16;

use super::staging::{create_temp, Staged};
use super::{guard, ExrOptions, MAX_TEXELS};
use crate::error::SkinError;

/// Stage an RGB EXR (channels `R`, `G`, `B`) from three row-major planes of `width * height` values each (row 0 at
/// the top; units are the caller's: reflectance for albedo, millimetres for radius). Samples are converted to f16
/// on the fly when `options.half` is set (no extra copy of the planes is made).
pub fn stage_rgb_exr(
    path: &Path,
    width: usize,
    height: usize,
    planes: [&[f32]; 3],
    options: ExrOptions,
) -> Result<Staged, SkinError> {
    stage_channels_exr(path, width, height, &[("R", planes[0]), ("G", planes[1]), ("B", planes[2])], options)
}

/// Stage an EXR with arbitrary named channels (each a row-major plane of `width * height` values). Names must be
/// unique, non-empty, at most 255 bytes of Latin-1. They are stored sorted by name.
pub fn stage_channels_exr(
    path: &Path,
    width: usize,
    height: usize,
    channels: &[(&str, &[f32])],
    options: ExrOptions,
) -> Result<Staged, SkinError> {
    let what = format!("output {}", path.display());
    if width == 0 || height == 0 || width.checked_mul(height).map_or(true, |n| n > MAX_TEXELS) {
        return Err(SkinError::invalid(
            what,
            format!("expected a size of 1 to {MAX_TEXELS} texels; got {width}x{height}"),
        ));
    }
    if channels.is_empty() {
        return Err(SkinError::invalid(what, "expected at least one channel; got none"));
    }
    let texels = width * height;
    for (i, (name, plane)) in channels.iter().enumerate() {
        if plane.len() != texels {
            return Err(SkinError::invalid(
                what,
                format!("channel {name}: expected {width}x{height} = {texels} values; got {}", plane.len()),
            ));
        }
        if name.is_empty() || name.len() > 255 || Text::new_or_none(name).is_none() {
            return Err(SkinError::invalid(
                what,
                format!("channel name {name:?}: expected 1 to 255 Latin-1 characters"),
            ));
        }
        if channels[..i].iter().any(|(other, _)| other == name) {
            return Err(SkinError::invalid(what, format!("channel {name} is given twice")));
        }
    }

    let mut temp = create_temp(path)?;
    {
        let mut out = BufWriter::with_capacity(1 << 20, temp.as_file_mut());
        write_exr_to(&mut out, width, height, channels, options)
            .map_err(|e| SkinError::io(path, format!("cannot write output EXR: {e}")))?;
        out.flush().map_err(|e| SkinError::io_caused(path, format!("cannot write output EXR: {e}"), e))?;
    }
    temp.as_file().sync_all().map_err(|e| SkinError::io_caused(path, format!("cannot write output EXR: {e}"), e))?;
    Ok(Staged::from_temp(temp, path))
}

/// Encode an EXR block by block straight from the planes (no full-image copy).
fn write_exr_to<W: std::io::Write + std::io::Seek>(
    out: W,
    width: usize,
    height: usize,
    channels: &[(&str, &[f32])],
    options: ExrOptions,
) -> Result<(), String> {
    let sample_type = if options.half { SampleType::F16 } else { SampleType::F32 };
    let mut order: Vec<usize> = (0..channels.len()).collect();
    order.sort_by(|&a, &b| channels[a].0.as_bytes().cmp(channels[b].0.as_bytes()));
    let mut descriptions = Vec::with_capacity(order.len());
    for &i in &order {
        let name =
            Text::new_or_none(channels[i].0).ok_or_else(|| format!("invalid channel name {:?}", channels[i].0))?;
        descriptions.push(ChannelDescription::named(name, sample_type));
    }
    let layer_name = Text::new_or_none("").ok_or("invalid layer name")?;
    let mut header = Header::new(layer_name, (width, height), descriptions.into_iter().collect()).with_encoding(
        options.compression.to_exr(),
        BlockDescription::ScanLines,
        LineOrder::Increasing,
    );
    header.own_attributes.layer_name = None;
    let sources: Vec<&[f32]> = order.iter().map(|&i| channels[i].1).collect();
    let failed = Cell::new(false);

    let written = guard(|| {
        exr::block::write(out, std::iter::once(header).collect(), true, |meta, chunk_writer| {
            let header = &meta.headers[0];
            let blocks = meta.collect_ordered_blocks(|block_index| {
                UncompressedBlock::from_lines(&header.channels, block_index, |line| {
                    let (x, y, n) = (line.location.position.0, line.location.position.1, line.location.sample_count);
                    let start = y * width + x;
                    let Some(row) = sources.get(line.location.channel).and_then(|s| s.get(start..start + n)) else {
                        failed.set(true);
                        return;
                    };
                    let ok = if options.half {
                        line.write_samples(|i| f16::from_f32(row[i])).is_ok()
                    } else {
                        line.write_samples_from_slice(row).is_ok()
                    };
                    if !ok {
                        failed.set(true);
                    }
                })
            });
            chunk_writer.on_progress(|_| ()).compress_all_blocks_parallel(&meta, blocks)?;
            Ok(())
        })
    });
    match written {
        Ok(Ok(())) if !failed.get() => Ok(()),
        Ok(Ok(())) => Err("internal error: a pixel line did not match the image layout".to_string()),
        Ok(Err(e)) => Err(e.to_string()),
        Err(panic) => Err(panic),
    }
}

/// Write an RGB EXR (channels R, G, B) from three row-major planes, atomically (temp file in the same directory,
/// then rename). See [`stage_rgb_exr`]. The directory must exist.
pub fn write_rgb_exr(
    path: &Path,
    width: usize,
    height: usize,
    planes: [&[f32]; 3],
    options: ExrOptions,
) -> Result<(), SkinError> {
    stage_rgb_exr(path, width, height, planes, options)?.commit()
}

/// Write an EXR with arbitrary named f32 channels (for parameter maps: the example generator and tests),
/// atomically. See [`stage_channels_exr`]. The directory must exist.
pub fn write_channels_exr(
    path: &Path,
    width: usize,
    height: usize,
    channels: &[(&str, &[f32])],
    options: ExrOptions,
) -> Result<(), SkinError> {
    stage_channels_exr(path, width, height, channels, options)?.commit()
}
