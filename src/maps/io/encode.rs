//! EXR encoding of output planes: single-part scan-line files written a block of rows at a time ([`ExrStream`]: a
//! writer thread per file, fed rows in order, compressing each block's chunks in parallel), staged beside their
//! destination (see [`super::staging`]). Whole planes in memory go through the same writer ([`stage_files`]).
//! [`Compression::Auto`] is resolved here, per file, from a sample of its blocks.

use std::cell::Cell;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::thread::JoinHandle;

use exr::block::chunk::{Chunk, CompressedBlock, CompressedScanLineBlock};
use exr::block::writer::ChunksWriter;
use exr::block::UncompressedBlock;
use exr::meta::attribute::{ChannelDescription, LineOrder, SampleType, Text};
use exr::meta::header::Header;
use exr::meta::BlockDescription;
use exr::prelude::f16;
use rayon::prelude::*;

use super::staging::{create_temp, Staged};
use super::{guard, Compression, ExrOptions, Precision, AUTO_MIN_SAVING};
use crate::error::SkinError;

/// Rows a stream is fed at a time (the last block of an image may be shorter): a multiple of every scan-line
/// compression's block height (1, 16, 32), so each fed block is whole compression blocks; it bounds the rows held
/// per file (256 rows of an 8192-wide RGB float map: 24 MiB).
pub const STREAM_ROWS: usize = 256;

/// Stage an RGB EXR (channels `R`, `G`, `B`) from three row-major planes of `width * height` values each (row 0 at
/// the top; units are the caller's: reflectance for albedo, millimetres for radius). Samples are converted to f16
/// on the fly for [`Precision::Half`].
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
    let mut staged = stage_files(width, height, &[(path.to_path_buf(), channels.to_vec())], options)?;
    Ok(staged.remove(0))
}

/// One file of [`stage_files`]: its path and its named planes.
pub type PlaneFile<'a> = (PathBuf, Vec<(&'a str, &'a [f32])>);

/// Stage several EXRs of one size from planes in memory, all streams fed a block of rows at a time together (each
/// file's writer thread compresses while the others do: both cores stay busy). The one way planes become files.
pub fn stage_files(
    width: usize,
    height: usize,
    files: &[PlaneFile<'_>],
    options: ExrOptions,
) -> Result<Vec<Staged>, SkinError> {
    let mut streams = Vec::with_capacity(files.len());
    for (path, channels) in files {
        let what = format!("output {}", path.display());
        let names: Vec<&str> = channels.iter().map(|(n, _)| *n).collect();
        check_channels(&what, width, height, &names)?;
        let texels = width * height;
        if let Some((name, plane)) = channels.iter().find(|(_, p)| p.len() != texels) {
            return Err(SkinError::invalid(
                what,
                format!("channel {name}: expected {width}x{height} = {texels} values; got {}", plane.len()),
            ));
        }
        let compression = resolve_compression(width, height, channels, options)
            .map_err(|e| SkinError::io(path, format!("cannot write output EXR: {e}")))?;
        streams.push(ExrStream::start(path, width, height, &names, ExrOptions { compression, ..options })?);
    }
    for first_row in (0..height).step_by(STREAM_ROWS) {
        let rows = STREAM_ROWS.min(height - first_row);
        let span = first_row * width..(first_row + rows) * width;
        for (stream, (_, channels)) in streams.iter_mut().zip(files) {
            stream.send(first_row, channels.iter().map(|(_, p)| p[span.clone()].to_vec()).collect())?;
        }
    }
    streams.into_iter().map(ExrStream::finish).collect()
}

/// Check an output's size and channel names as the writer needs them.
fn check_channels(what: &str, width: usize, height: usize, names: &[&str]) -> Result<(), SkinError> {
    super::check_texel_count(what, width, height)?;
    if names.is_empty() {
        return Err(SkinError::invalid(what, "expected at least one channel; got none"));
    }
    for (i, name) in names.iter().enumerate() {
        if name.is_empty() || name.len() > 255 || Text::new_or_none(name).is_none() {
            return Err(SkinError::invalid(
                what,
                format!("channel name {name:?}: expected 1 to 255 Latin-1 characters"),
            ));
        }
        if names[..i].contains(name) {
            return Err(SkinError::invalid(what, format!("channel {name} is given twice")));
        }
    }
    Ok(())
}

/// Rows `first_row..` of a streamed file's channels (in the order the stream was started with), row-major.
struct RowBlock {
    first_row: usize,
    planes: Vec<Vec<f32>>,
}

/// An EXR being written a block of rows at a time by a thread of its own: [`ExrStream::send`] the rows in order from
/// row 0 (each block [`STREAM_ROWS`] rows, the last one the rest), then [`ExrStream::finish`] for the staged file.
/// Dropped before it is finished (a cancelled or failed run), its temporary file is deleted.
pub struct ExrStream {
    path: PathBuf,
    width: usize,
    channels: usize,
    sender: Option<SyncSender<RowBlock>>,
    worker: Option<JoinHandle<Result<Staged, SkinError>>>,
}

impl ExrStream {
    /// Start writing `path` (staged beside it) with these channels; `options.compression` must be resolved (not
    /// [`Compression::Auto`]: see [`resolve_compression`] and [`choose_compression`]).
    pub fn start(
        path: &Path,
        width: usize,
        height: usize,
        channels: &[&str],
        options: ExrOptions,
    ) -> Result<ExrStream, SkinError> {
        let what = format!("output {}", path.display());
        check_channels(&what, width, height, channels)?;
        let failed = |e: String| SkinError::io(path, format!("cannot write output EXR: {e}"));
        let exr_compression = options
            .compression
            .to_exr()
            .ok_or_else(|| failed("internal error: the compression was not resolved".into()))?;
        let header = exr_header(width, height, channels, options.precision, exr_compression).map_err(failed)?;
        let order = stored_order(channels);
        let temp = create_temp(path)?;
        // One block queued while the writer compresses the one before: the rows held per file stay two blocks.
        let (sender, receiver) = sync_channel::<RowBlock>(1);
        let (target, precision, compression) = (path.to_path_buf(), options.precision, options.compression);
        let worker = std::thread::spawn(move || {
            write_stream(temp, &target, header, &order, width, height, precision, receiver)
                .map(|staged| staged.with_compression(compression))
        });
        Ok(ExrStream {
            path: path.to_path_buf(),
            width,
            channels: channels.len(),
            sender: Some(sender),
            worker: Some(worker),
        })
    }

    /// The next rows, from `first_row` (the row after the last block sent), one plane per channel in the order the
    /// stream was started with.
    pub fn send(&mut self, first_row: usize, planes: Vec<Vec<f32>>) -> Result<(), SkinError> {
        if planes.len() != self.channels || planes.iter().any(|p| p.len() % self.width.max(1) != 0) {
            return Err(SkinError::invalid(
                format!("output {}", self.path.display()),
                format!("internal error: a block of {} planes for {} channels", planes.len(), self.channels),
            ));
        }
        let sent = self.sender.as_ref().map(|s| s.send(RowBlock { first_row, planes }).is_ok()).unwrap_or(false);
        if sent {
            return Ok(());
        }
        // The writer stopped: its error says why.
        self.sender = None;
        match self.join() {
            Err(e) => Err(e),
            Ok(_) => Err(SkinError::io(&self.path, "cannot write output EXR: the writer stopped early")),
        }
    }

    /// Wait for the writer: the staged file, complete.
    pub fn finish(mut self) -> Result<Staged, SkinError> {
        self.sender = None;
        self.join()
    }

    fn join(&mut self) -> Result<Staged, SkinError> {
        let worker =
            self.worker.take().ok_or_else(|| SkinError::io(&self.path, "cannot write output EXR: finished twice"))?;
        worker.join().unwrap_or_else(|_| Err(SkinError::io(&self.path, "cannot write output EXR: the writer panicked")))
    }
}

impl Drop for ExrStream {
    fn drop(&mut self) {
        // Closing the channel ends the writer (with an error: the file is incomplete), which deletes its temporary.
        self.sender = None;
        if let Some(worker) = self.worker.take() {
            let _ = worker.join();
        }
    }
}

/// The writer thread of an [`ExrStream`]: every block received, compressed and written in order, then the file
/// flushed and synced.
#[allow(clippy::too_many_arguments)] // one thread's inputs, moved in once
fn write_stream(
    mut temp: tempfile::NamedTempFile,
    path: &Path,
    header: Header,
    order: &[usize],
    width: usize,
    height: usize,
    precision: Precision,
    receiver: Receiver<RowBlock>,
) -> Result<Staged, SkinError> {
    let failed = |e: String| SkinError::io(path, format!("cannot write output EXR: {e}"));
    {
        let mut out = BufWriter::with_capacity(1 << 20, temp.as_file_mut());
        let written = guard(|| {
            exr::block::write(&mut out, std::iter::once(header).collect(), true, |meta, chunk_writer| {
                write_blocks(&meta.headers, chunk_writer, order, width, height, precision, receiver)
            })
        });
        match written {
            Ok(Ok(())) => {}
            Ok(Err(e)) => return Err(failed(e.to_string())),
            Err(panic) => return Err(failed(panic)),
        }
        out.flush().map_err(|e| SkinError::io_caused(path, format!("cannot write output EXR: {e}"), e))?;
    }
    temp.as_file().sync_all().map_err(|e| SkinError::io_caused(path, format!("cannot write output EXR: {e}"), e))?;
    Ok(Staged::from_temp(temp, path))
}

/// Compress and write every block of rows `receiver` gives, in increasing order; an error if they do not cover the
/// image's rows exactly (a stream dropped early: the file is discarded).
fn write_blocks(
    headers: &[Header],
    chunk_writer: &mut impl ChunksWriter,
    order: &[usize],
    width: usize,
    height: usize,
    precision: Precision,
    receiver: Receiver<RowBlock>,
) -> exr::error::UnitResult {
    let invalid = |m: &str| exr::error::Error::Invalid(m.to_string().into());
    let lines = headers[0].compression.scan_lines_per_block();
    let mut next_row = 0;
    for block in receiver.iter() {
        let rows = block.planes.first().map_or(0, |p| p.len() / width.max(1));
        if block.first_row != next_row || next_row + rows > height || (rows % lines != 0 && next_row + rows != height) {
            return Err(invalid("a block of rows out of order"));
        }
        let sources: Vec<&[f32]> = order.iter().map(|&c| block.planes[c].as_slice()).collect();
        let chunks: Vec<Chunk> = (0..rows.div_ceil(lines))
            .into_par_iter()
            .map(|b| {
                let local = b * lines;
                let n = lines.min(rows - local);
                compress_block(headers, local, block.first_row + local, n, width, &sources, precision)
            })
            .collect::<exr::error::Result<_>>()?;
        for (b, chunk) in chunks.into_iter().enumerate() {
            chunk_writer.write_chunk((block.first_row + b * lines) / lines, chunk)?;
        }
        next_row += rows;
    }
    if next_row != height {
        return Err(invalid("the image's rows were not all given"));
    }
    Ok(())
}

/// The chunk of the `lines` rows from row `local` of `sources` (the file's rows from `row`): ZIP and ZIPS blocks
/// built by [`zip_block`], the others by the exr crate.
fn compress_block(
    headers: &[Header],
    local: usize,
    row: usize,
    lines: usize,
    width: usize,
    sources: &[&[f32]],
    precision: Precision,
) -> exr::error::Result<Chunk> {
    let y_coordinate = i32::try_from(row).map_err(|_| exr::error::Error::Invalid("image height".into()))?;
    if matches!(headers[0].compression, exr::compression::Compression::ZIP1 | exr::compression::Compression::ZIP16) {
        let block = CompressedScanLineBlock {
            y_coordinate,
            compressed_pixels_le: zip_block(local, lines, width, sources, precision),
        };
        return Ok(Chunk { layer_index: 0, compressed_block: CompressedBlock::ScanLine(block) });
    }
    let failed = Cell::new(false);
    let index = block_index(row, lines, width);
    let block = fill_block(&headers[0], index, local, width, sources, precision, &failed);
    if failed.get() {
        return Err(exr::error::Error::Invalid("a pixel line did not match the image layout".into()));
    }
    block.compress_to_chunk(headers)
}

/// The index of the scan-line block of `lines` rows from `row`.
fn block_index(row: usize, lines: usize, width: usize) -> exr::block::BlockIndex {
    exr::block::BlockIndex {
        layer: 0,
        pixel_position: exr::math::Vec2(0, row),
        pixel_size: exr::math::Vec2(width, lines),
        level: exr::math::Vec2(0, 0),
    }
}

/// How many blocks [`Compression::Auto`] compresses to decide (evenly spaced over the image; all of a smaller one).
const AUTO_SAMPLE_BLOCKS: usize = 32;

/// The rows [`Compression::Auto`] tries for an image of `height` rows at `precision`: (first row, rows) of each
/// sampled block of the precision's candidate compression, in increasing order.
pub fn auto_sample_rows(height: usize, precision: Precision) -> Vec<(usize, usize)> {
    let lines = Compression::auto_candidate(precision).to_exr().map_or(1, |c| c.scan_lines_per_block());
    let blocks = height.div_ceil(lines);
    let picked: Vec<usize> = if blocks <= AUTO_SAMPLE_BLOCKS {
        (0..blocks).collect()
    } else {
        (0..AUTO_SAMPLE_BLOCKS).map(|i| (2 * i + 1) * blocks / (2 * AUTO_SAMPLE_BLOCKS)).collect()
    };
    picked.into_iter().map(|b| (b * lines, lines.min(height - b * lines))).collect()
}

/// The compression `options` mean for these planes: itself, or for [`Compression::Auto`] what
/// [`choose_compression`] makes of the rows of [`auto_sample_rows`].
pub fn resolve_compression(
    width: usize,
    height: usize,
    channels: &[(&str, &[f32])],
    options: ExrOptions,
) -> Result<Compression, String> {
    if options.compression != Compression::Auto {
        return Ok(options.compression);
    }
    let rows = auto_sample_rows(height, options.precision);
    let sample: Vec<Vec<f32>> = channels
        .iter()
        .map(|(_, plane)| rows.iter().flat_map(|&(y, n)| &plane[y * width..(y + n) * width]).copied().collect())
        .collect();
    let named: Vec<(&str, &[f32])> = channels.iter().zip(&sample).map(|((n, _), s)| (*n, s.as_slice())).collect();
    choose_compression(width, &named, options)
}

/// [`Compression::Auto`] resolved from `sample`, the rows of [`auto_sample_rows`] stacked (each sampled block whole
/// compression blocks of the candidate): the precision's candidate ([`Compression::auto_candidate`]) if it shrinks
/// those blocks (built as the writer builds them) by at least [`AUTO_MIN_SAVING`], else none.
pub fn choose_compression(width: usize, sample: &[(&str, &[f32])], options: ExrOptions) -> Result<Compression, String> {
    if options.compression != Compression::Auto {
        return Ok(options.compression);
    }
    let candidate = Compression::auto_candidate(options.precision);
    let height = sample.first().map_or(0, |(_, p)| p.len() / width.max(1));
    if height == 0 {
        return Ok(Compression::None);
    }
    let names: Vec<&str> = sample.iter().map(|(n, _)| *n).collect();
    let header = exr_header(width, height, &names, options.precision, candidate.to_exr().ok_or("no candidate")?)?;
    let order = stored_order(&names);
    let sources: Vec<&[f32]> = order.iter().map(|&c| sample[c].1).collect();
    let lines = header.compression.scan_lines_per_block();
    let headers = [header];
    let sizes = guard(|| {
        (0..height.div_ceil(lines))
            .into_par_iter()
            .map(|b| {
                let n = lines.min(height - b * lines);
                let chunk = compress_block(&headers, b * lines, b * lines, n, width, &sources, options.precision)?;
                Ok((n * width * headers[0].channels.bytes_per_pixel, compressed_len(&chunk.compressed_block)))
            })
            .collect::<exr::error::Result<Vec<(usize, usize)>>>()
    });
    match sizes {
        Ok(Ok(sizes)) => {
            let (raw, packed) = sizes.iter().fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
            Ok(if (packed as f64) <= (1.0 - AUTO_MIN_SAVING) * raw as f64 { candidate } else { Compression::None })
        }
        Ok(Err(e)) => Err(e.to_string()),
        Err(panic) => Err(panic),
    }
}

/// Bytes of a compressed scan-line block's pixel data.
fn compressed_len(block: &CompressedBlock) -> usize {
    match block {
        CompressedBlock::ScanLine(b) => b.compressed_pixels_le.len(),
        _ => 0,
    }
}

/// The header of a single-part scan-line file of these channels (stored sorted by name).
fn exr_header(
    width: usize,
    height: usize,
    channels: &[&str],
    precision: Precision,
    compression: exr::compression::Compression,
) -> Result<Header, String> {
    let sample_type = match precision {
        Precision::Half => SampleType::F16,
        Precision::Float => SampleType::F32,
    };
    let mut descriptions = Vec::with_capacity(channels.len());
    for c in stored_order(channels) {
        let name = channels[c];
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

/// The channels' indices in stored order (sorted by name).
fn stored_order(channels: &[&str]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..channels.len()).collect();
    order.sort_by(|&a, &b| channels[a].as_bytes().cmp(channels[b].as_bytes()));
    order
}

/// One uncompressed block of the file (`index`), built straight from the planes: `local` is the block's first row
/// within `sources`; a line that does not match the layout sets `failed`.
fn fill_block(
    header: &Header,
    index: exr::block::BlockIndex,
    local: usize,
    width: usize,
    sources: &[&[f32]],
    precision: Precision,
    failed: &Cell<bool>,
) -> UncompressedBlock {
    let row0 = index.pixel_position.1;
    UncompressedBlock::from_lines(&header.channels, index, |line| {
        let (x, y, n) = (line.location.position.0, line.location.position.1, line.location.sample_count);
        let start = (y - row0 + local) * width + x;
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

/// Deflate level of ZIP and ZIPS blocks (zlib-rs levels, 1 to 9). On the 4096² face example's half-float maps
/// (docs/maps-performance.md) level 4 gives files about 9 % larger than the exr crate's miniz_oxide at its level 4
/// in half its CPU time; level 1 would be a third faster again but 45 % larger.
const ZIP_LEVEL: u32 = 4;

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
