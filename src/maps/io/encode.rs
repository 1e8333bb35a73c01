//! EXR encoding of output planes: single-part scan-line files, blocks built straight from the planes and compressed
//! in parallel, staged beside their destination (see [`super::staging`]). [`Compression::Auto`] is resolved here,
//! per file, from a sample of its blocks.

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
use super::{guard, Compression, ExrOptions, Precision, AUTO_MIN_SAVING};
use crate::error::SkinError;

/// Stage an RGB EXR (channels `R`, `G`, `B`) from three row-major planes of `width * height` values each (row 0 at
/// the top; units are the caller's: reflectance for albedo, millimetres for radius). Samples are converted to f16
/// on the fly for [`Precision::Half`] (no extra copy of the planes is made).
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
/// unique, non-empty, at most 255 bytes of Latin-1. They are stored sorted by name. [`Staged::compression`] tells
/// the compression written (what [`Compression::Auto`] chose).
pub fn stage_channels_exr(
    path: &Path,
    width: usize,
    height: usize,
    channels: &[(&str, &[f32])],
    options: ExrOptions,
) -> Result<Staged, SkinError> {
    let what = format!("output {}", path.display());
    super::check_texel_count(&what, width, height)?;
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

    let compression = resolve_compression(width, height, channels, options)
        .map_err(|e| SkinError::io(path, format!("cannot write output EXR: {e}")))?;
    let mut temp = create_temp(path)?;
    {
        let mut out = BufWriter::with_capacity(1 << 20, temp.as_file_mut());
        write_exr_to(&mut out, width, height, channels, options.precision, compression)
            .map_err(|e| SkinError::io(path, format!("cannot write output EXR: {e}")))?;
        out.flush().map_err(|e| SkinError::io_caused(path, format!("cannot write output EXR: {e}"), e))?;
    }
    temp.as_file().sync_all().map_err(|e| SkinError::io_caused(path, format!("cannot write output EXR: {e}"), e))?;
    Ok(Staged::from_temp(temp, path).with_compression(compression))
}

/// How many blocks [`Compression::Auto`] compresses to decide (evenly spaced over the image; all of a smaller one).
const AUTO_SAMPLE_BLOCKS: usize = 32;

/// The compression `options` mean for these planes: itself, or for [`Compression::Auto`] the precision's candidate
/// ([`Compression::auto_candidate`]) if it shrinks a sample of the blocks (built as the writer builds them) by at
/// least [`AUTO_MIN_SAVING`], else none. The planes must have been checked as [`stage_channels_exr`] checks them.
pub fn resolve_compression(
    width: usize,
    height: usize,
    channels: &[(&str, &[f32])],
    options: ExrOptions,
) -> Result<Compression, String> {
    if options.compression != Compression::Auto {
        return Ok(options.compression);
    }
    let candidate = Compression::auto_candidate(options.precision);
    let header = exr_header(width, height, channels, options.precision, candidate.to_exr().ok_or("no candidate")?)?;
    let sources = sorted_sources(channels);
    let lines = header.compression.scan_lines_per_block();
    let blocks = height.div_ceil(lines);
    let picked: Vec<usize> = if blocks <= AUTO_SAMPLE_BLOCKS {
        (0..blocks).collect()
    } else {
        (0..AUTO_SAMPLE_BLOCKS).map(|i| (2 * i + 1) * blocks / (2 * AUTO_SAMPLE_BLOCKS)).collect()
    };
    if matches!(candidate, Compression::Zip | Compression::Zips) {
        // The writer's own ZIP blocks (`zip_block`), as the file would hold them.
        let sizes = guard(|| {
            use rayon::prelude::*;
            picked
                .par_iter()
                .map(|&b| {
                    let y = b * lines;
                    let n = lines.min(height - y);
                    (
                        n * width * header.channels.bytes_per_pixel,
                        zip_block(y, n, width, &sources, options.precision).len(),
                    )
                })
                .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
        })?;
        let (raw, packed) = sizes;
        return Ok(if (packed as f64) <= (1.0 - AUTO_MIN_SAVING) * raw as f64 { candidate } else { Compression::None });
    }
    let headers = [header];
    let failed = Cell::new(false);
    let sizes = guard(|| {
        use rayon::prelude::*;
        let uncompressed: Vec<UncompressedBlock> = picked
            .iter()
            .map(|&b| {
                let y = b * lines;
                let index = exr::block::BlockIndex {
                    layer: 0,
                    pixel_position: exr::math::Vec2(0, y),
                    pixel_size: exr::math::Vec2(width, lines.min(height - y)),
                    level: exr::math::Vec2(0, 0),
                };
                fill_block(&headers[0], index, width, &sources, options.precision, &failed)
            })
            .collect();
        let raw: usize = uncompressed.iter().map(|b| b.data.len()).sum();
        let packed: Result<Vec<usize>, exr::error::Error> = uncompressed
            .into_par_iter()
            .map(|b| b.compress_to_chunk(&headers).map(|c| compressed_len(&c.compressed_block)))
            .collect();
        packed.map(|p| (raw, p.iter().sum::<usize>()))
    });
    match sizes {
        Ok(Ok(_)) if failed.get() => Err("internal error: a pixel line did not match the image layout".to_string()),
        Ok(Ok((raw, packed))) if (packed as f64) <= (1.0 - AUTO_MIN_SAVING) * raw as f64 => Ok(candidate),
        Ok(Ok(_)) => Ok(Compression::None),
        Ok(Err(e)) => Err(e.to_string()),
        Err(panic) => Err(panic),
    }
}

/// Bytes of a compressed scan-line block's pixel data.
fn compressed_len(block: &exr::block::chunk::CompressedBlock) -> usize {
    match block {
        exr::block::chunk::CompressedBlock::ScanLine(b) => b.compressed_pixels_le.len(),
        _ => 0,
    }
}

/// The header of a single-part scan-line file of these channels (stored sorted by name).
fn exr_header(
    width: usize,
    height: usize,
    channels: &[(&str, &[f32])],
    precision: Precision,
    compression: exr::compression::Compression,
) -> Result<Header, String> {
    let sample_type = match precision {
        Precision::Half => SampleType::F16,
        Precision::Float => SampleType::F32,
    };
    let mut descriptions = Vec::with_capacity(channels.len());
    for (name, _) in sorted(channels) {
        let name = Text::new_or_none(name).ok_or_else(|| format!("invalid channel name {name:?}"))?;
        descriptions.push(ChannelDescription::named(name, sample_type));
    }
    let layer_name = Text::new_or_none("").ok_or("invalid layer name")?;
    let mut header = Header::new(layer_name, (width, height), descriptions.into_iter().collect()).with_encoding(
        compression,
        BlockDescription::ScanLines,
        LineOrder::Increasing,
    );
    header.own_attributes.layer_name = None;
    Ok(header)
}

/// The channels sorted by name, as they are stored.
fn sorted<'a>(channels: &[(&'a str, &'a [f32])]) -> Vec<(&'a str, &'a [f32])> {
    let mut order = channels.to_vec();
    order.sort_by(|a, b| a.0.as_bytes().cmp(b.0.as_bytes()));
    order
}

/// The planes in stored (name) order.
fn sorted_sources<'a>(channels: &[(&'a str, &'a [f32])]) -> Vec<&'a [f32]> {
    sorted(channels).into_iter().map(|(_, plane)| plane).collect()
}

/// One uncompressed block of the file, built straight from the planes; a line that does not match the layout sets
/// `failed`.
fn fill_block(
    header: &Header,
    index: exr::block::BlockIndex,
    width: usize,
    sources: &[&[f32]],
    precision: Precision,
    failed: &Cell<bool>,
) -> UncompressedBlock {
    UncompressedBlock::from_lines(&header.channels, index, |line| {
        let (x, y, n) = (line.location.position.0, line.location.position.1, line.location.sample_count);
        let start = y * width + x;
        let Some(row) = sources.get(line.location.channel).and_then(|s| s.get(start..start + n)) else {
            failed.set(true);
            return;
        };
        let ok = match precision {
            Precision::Half => line.write_samples(|i| f16::from_f32(row[i])).is_ok(),
            Precision::Float => line.write_samples_from_slice(row).is_ok(),
        };
        if !ok {
            failed.set(true);
        }
    })
}

/// Encode an EXR block by block straight from the planes (no full-image copy).
fn write_exr_to<W: std::io::Write + std::io::Seek>(
    out: W,
    width: usize,
    height: usize,
    channels: &[(&str, &[f32])],
    precision: Precision,
    compression: Compression,
) -> Result<(), String> {
    let exr_compression = compression.to_exr().ok_or("internal error: the compression was not resolved")?;
    let header = exr_header(width, height, channels, precision, exr_compression)?;
    let sources = sorted_sources(channels);
    let failed = Cell::new(false);

    if matches!(compression, Compression::Zip | Compression::Zips) {
        let lines = header.compression.scan_lines_per_block();
        let written = guard(|| {
            exr::block::write(out, std::iter::once(header).collect(), true, |_, chunk_writer| {
                write_zip_chunks(chunk_writer, width, height, lines, &sources, precision)
            })
        });
        return match written {
            Ok(Ok(())) => Ok(()),
            Ok(Err(e)) => Err(e.to_string()),
            Err(panic) => Err(panic),
        };
    }
    let written = guard(|| {
        exr::block::write(out, std::iter::once(header).collect(), true, |meta, chunk_writer| {
            let header = &meta.headers[0];
            let blocks = meta.collect_ordered_blocks(|block_index| {
                fill_block(header, block_index, width, &sources, precision, &failed)
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

/// Deflate level of ZIP and ZIPS blocks (zlib-rs levels, 1 to 9). On the 4096² face example's half-float maps
/// (docs/maps-performance.md) level 4 gives files about 9 % larger than the exr crate's miniz_oxide at its level 4
/// in half its CPU time; level 1 would be a third faster again but 45 % larger.
const ZIP_LEVEL: u32 = 4;

/// Scan lines whose blocks are compressed together before they are written in order (bounds the compressed data
/// held at once: at most the raw size of this many lines).
const ZIP_BATCH_LINES: usize = 256;

/// One thread's ZIP working state: the deflate stream (reset per block) and the block buffers.
struct ZipState {
    compress: flate2::Compress,
    separated: Vec<u8>,
    predicted: Vec<u8>,
    halves: Vec<f16>,
}

thread_local! {
    static ZIP_STATE: std::cell::RefCell<Option<ZipState>> = const { std::cell::RefCell::new(None) };
}

/// The raw little-endian data of the scan lines `y0..y0 + lines`: line by line, each channel's samples in stored
/// order.
fn raw_lines(y0: usize, lines: usize, width: usize, sources: &[&[f32]], precision: Precision) -> Vec<u8> {
    let mut raw = Vec::new();
    for y in y0..y0 + lines {
        for plane in sources {
            let row = &plane[y * width..(y + 1) * width];
            match precision {
                Precision::Half => raw.extend(row.iter().flat_map(|&v| f16::from_f32(v).to_bits().to_le_bytes())),
                Precision::Float => raw.extend(row.iter().flat_map(|v| v.to_le_bytes())),
            }
        }
    }
    raw
}

/// The stored bytes of the ZIP (or ZIPS) scan-line block of `lines` lines from row `y0`, as OpenEXR's zip
/// compressor makes them (ImfZip.cpp; the exr crate's `compression::zip` does the same): the block's raw data
/// ([`raw_lines`]), its bytes split into those at even and those at odd positions, a byte-wise difference predictor
/// (`d[i] = t[i] - t[i - 1] + 128`, wrapping), then zlib. A block that does not shrink is stored raw, as the format
/// allows and OpenEXR does.
fn zip_block(y0: usize, lines: usize, width: usize, sources: &[&[f32]], precision: Precision) -> Vec<u8> {
    use half::slice::HalfFloatSliceExt;
    ZIP_STATE.with(|cell| {
        let mut slot = cell.borrow_mut();
        let state = slot.get_or_insert_with(|| ZipState {
            compress: flate2::Compress::new(flate2::Compression::new(ZIP_LEVEL), true),
            separated: Vec::new(),
            predicted: Vec::new(),
            halves: Vec::new(),
        });
        let ZipState { compress, separated, predicted, halves } = state;
        let samples = lines * width * sources.len();
        let n = samples * if precision == Precision::Half { 2 } else { 4 };
        separated.resize(n, 0);
        match precision {
            // A half sample's two little-endian bytes sit at an even and an odd position: its low byte goes to the
            // first half, its high byte to the second, in sample order.
            Precision::Half => {
                let (low, high) = separated.split_at_mut(samples);
                let mut at = 0;
                for y in y0..y0 + lines {
                    for plane in sources {
                        halves.resize(width, f16::ZERO);
                        halves.convert_from_f32_slice(&plane[y * width..(y + 1) * width]);
                        for ((l, h), v) in low[at..at + width].iter_mut().zip(&mut high[at..at + width]).zip(&*halves) {
                            [*l, *h] = v.to_bits().to_le_bytes();
                        }
                        at += width;
                    }
                }
            }
            Precision::Float => {
                let raw = raw_lines(y0, lines, width, sources, precision);
                let (even, odd) = separated.split_at_mut(n / 2);
                for ((e, o), pair) in even.iter_mut().zip(odd.iter_mut()).zip(raw.chunks_exact(2)) {
                    (*e, *o) = (pair[0], pair[1]);
                }
            }
        }
        predicted.resize(n, 0);
        if n > 0 {
            predicted[0] = separated[0];
            for ((d, t), before) in predicted[1..].iter_mut().zip(&separated[1..]).zip(&separated[..n - 1]) {
                *d = t.wrapping_sub(*before).wrapping_add(128);
            }
        }
        compress.reset();
        // Room for the raw size only: a stream that does not end within it is no smaller, and the block is stored raw.
        let mut packed = Vec::with_capacity(n);
        match compress.compress_vec(predicted, &mut packed, flate2::FlushCompress::Finish) {
            Ok(flate2::Status::StreamEnd) if packed.len() < n => packed,
            _ => raw_lines(y0, lines, width, sources, precision),
        }
    })
}

/// Write every block of a ZIP or ZIPS file (`lines` per block) in increasing order, compressing a batch of blocks
/// in parallel at a time.
fn write_zip_chunks(
    chunk_writer: &mut impl ChunksWriter,
    width: usize,
    height: usize,
    lines: usize,
    sources: &[&[f32]],
    precision: Precision,
) -> exr::error::UnitResult {
    use exr::block::chunk::{Chunk, CompressedBlock, CompressedScanLineBlock};
    use rayon::prelude::*;
    let blocks = height.div_ceil(lines);
    let batch = (ZIP_BATCH_LINES / lines).max(1);
    for first in (0..blocks).step_by(batch) {
        let packed: Vec<Vec<u8>> = (first..blocks.min(first + batch))
            .into_par_iter()
            .map(|b| zip_block(b * lines, lines.min(height - b * lines), width, sources, precision))
            .collect();
        for (b, bytes) in (first..).zip(packed) {
            let y_coordinate =
                i32::try_from(b * lines).map_err(|_| exr::error::Error::Invalid("image height".into()))?;
            let block = CompressedScanLineBlock { y_coordinate, compressed_pixels_le: bytes };
            chunk_writer
                .write_chunk(b, Chunk { layer_index: 0, compressed_block: CompressedBlock::ScanLine(block) })?;
        }
    }
    Ok(())
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
