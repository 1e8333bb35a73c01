//! The one reader of input images, for every front (CLI, Python, add-on): parameter maps ([`read_params`],
//! [`read_params_from_bytes`]: one value per texel) and albedo textures ([`read_albedo_texture`]: linear RGB per
//! texel). Every file's header is checked before any pixel data is decoded; every refusal names the file, what was
//! found and what is accepted ([`PARAM_IMAGE_FORMS`], [`ALBEDO_IMAGE_FORMS`]).

use std::fs::File;
use std::io::{BufRead, BufReader, Cursor, Read, Seek, SeekFrom};
use std::path::Path;

use exr::block::reader::ChunksReader;
use exr::meta::attribute::SampleType;
use exr::meta::header::Header;
use exr::meta::{BlockDescription, MetaData};
use exr::prelude::f16;
use rayon::prelude::*;

use super::{
    guard, ParamImage, ParamInputs, ParamSource, Plane, ALBEDO_IMAGE_FORMS, ALL_CHANNELS, ALL_RANGES,
    EXTENDED_CHANNELS, NO_MAP_GIVEN, PARAM_CHANNELS, PARAM_IMAGE_FORMS,
};
use crate::error::SkinError;
use crate::skin::params::EXTENDED_DEFAULTS;

/// Read and check the parameter inputs.
///
/// Every file is opened and its header checked before any pixel data is decoded: all files exist and are EXR, PNG,
/// TIFF or JPEG (recognised by content, not extension); their sizes agree (the error lists each file's size); a
/// multi-channel EXR has every channel not given as a constant (the error lists the channels found); one-parameter
/// files are one of [`PARAM_IMAGE_FORMS`].
///
/// - A one-parameter EXR must have exactly one channel (any name, any sample type), or else a channel named like the
///   parameter (so a multi-channel parameter EXR can also serve as a separate source), or else be R, G, B (optionally
///   A; bare or as `<layer>.R` etc. of one layer) with R = G = B exactly in every texel: a grey image as Blender saves
///   one (the alpha is ignored, with a note). RGB with differing channels is refused naming the first texel that
///   differs. Values are taken as the parameter itself; f16 and u32 samples are converted to f32.
/// - A one-parameter PNG, TIFF or JPEG must be 8 or 16 bits, greyscale or RGB with R = G = B exactly in every texel
///   (an alpha channel is ignored, with a note). Float images are rejected. The values are data, not colour (no sRGB
///   decoding): `v` maps to `min + (max - min) * v / (2^bits - 1)` of the parameter's range ([`PARAM_RANGES`]),
///   computed in f64 (so 255 in an 8-bit melanin map gives exactly 0.5).
/// - A multi-channel parameter EXR's channels of no parameter's name (a misspelt `hemoglobn`) are ignored with a note
///   naming them and the known names.
/// - The notes go into [`ParamImage::notes`], one sentence each naming the file, for fronts to show as warnings.
/// - Constants are used as given (converted to f32).
///
/// - Before an EXR's pixel data is read, its offset table and every chunk's declared size are checked against the
///   file's length: a damaged file is an error naming the chunk, never an allocation of the size it claims.
///
/// The extended physiology ([`super::EXTENDED_CHANNELS`], `ParamInputs::Extended`) follows the same rules: a
/// multi-channel EXR may hold channels of those names (optional: a missing one is the value given for it, else its
/// default), a one-parameter file of an extended parameter is read like the four's (an integer PNG/TIFF onto its
/// range) and must have the maps' size.
///
/// If every source is a constant there is no size to use: that is an error asking for at least one map.
/// Values are not range-checked here (NaN, infinities and out-of-range values pass through).
pub fn read_params(inputs: &ParamInputs) -> Result<ParamImage, SkinError> {
    fn input(s: &ParamSource) -> Input<'_> {
        match s {
            ParamSource::File(path) => Input::File(Source::Path(path)),
            ParamSource::Constant(value) => Input::Constant(*value),
        }
    }
    let (inputs, extended): (&ParamInputs, [Option<Input<'_>>; 3]) = match inputs {
        ParamInputs::Extended { inputs, extended } => {
            (inputs.as_ref(), std::array::from_fn(|k| extended[k].as_ref().map(input)))
        }
        other => (other, [None, None, None]),
    };
    match inputs {
        ParamInputs::Multi { path, constants } => read_multi(Source::Path(path), constants, &extended),
        ParamInputs::Separate(sources) => read_separate(&std::array::from_fn(|p| {
            if p < 4 {
                input(&sources[p])
            } else {
                extended[p - 4].unwrap_or(Input::Constant(EXTENDED_DEFAULTS[p - 4]))
            }
        })),
        ParamInputs::Extended { .. } => {
            Err(SkinError::invalid("parameter inputs", "ParamInputs::Extended inside ParamInputs::Extended"))
        }
    }
}

/// [`read_params`] for one file already in memory (a packed image, a download, a fuzzer's input): the same reader
/// and the same rules, with `label` standing for the file's name in messages.
///
/// - `parameter` None: a four-channel parameter EXR, as `ParamInputs::Multi` without constants (every channel of
///   [`PARAM_CHANNELS`] required).
/// - `parameter` Some(p): a one-parameter EXR, PNG or TIFF for parameter `p` (an index into [`PARAM_CHANNELS`]), as
///   that parameter's `ParamSource::File`; the other three planes are `Plane::Constant(NaN)` (no value given), which
///   [`crate::maps::pipeline::check_planes`] refuses unless they are replaced.
pub fn read_params_from_bytes(bytes: &[u8], label: &str, parameter: Option<usize>) -> Result<ParamImage, SkinError> {
    let source = Source::Bytes { label: Path::new(label), bytes };
    match parameter {
        None => read_multi(source, &[None; 4], &[None; 3]),
        Some(p) if p < PARAM_CHANNELS.len() => read_separate(&std::array::from_fn(|k| {
            if k == p {
                Input::File(source)
            } else if k < 4 {
                Input::Constant(f64::NAN)
            } else {
                Input::Constant(EXTENDED_DEFAULTS[k - 4])
            }
        })),
        Some(p) => Err(SkinError::invalid(
            "parameter index",
            format!(
                "expected 0 to {} (an index into {}); got {p}",
                PARAM_CHANNELS.len() - 1,
                PARAM_CHANNELS.join(", ")
            ),
        )),
    }
}

/// Where one input file's bytes come from: a file, opened afresh for each pass, or bytes in memory. `label` names it
/// in messages.
#[derive(Clone, Copy)]
enum Source<'a> {
    Path(&'a Path),
    Bytes { label: &'a Path, bytes: &'a [u8] },
}

/// A parameter's input inside the reader: a file's bytes or a constant.
#[derive(Clone, Copy)]
enum Input<'a> {
    File(Source<'a>),
    Constant(f64),
}

impl<'a> Source<'a> {
    fn label(&self) -> &'a Path {
        match *self {
            Source::Path(path) => path,
            Source::Bytes { label, .. } => label,
        }
    }

    /// A buffered, seekable reader from the first byte.
    fn open(&self, what: &str) -> Result<SourceReader<'a>, SkinError> {
        match *self {
            Source::Path(path) => open_file(path, what).map(|f| SourceReader::File(BufReader::new(f))),
            Source::Bytes { bytes, .. } => Ok(SourceReader::Bytes(Cursor::new(bytes))),
        }
    }
}

/// The reader of a [`Source`].
enum SourceReader<'a> {
    File(BufReader<File>),
    Bytes(Cursor<&'a [u8]>),
}

impl Read for SourceReader<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        match self {
            SourceReader::File(r) => r.read(buf),
            SourceReader::Bytes(r) => r.read(buf),
        }
    }
}

impl BufRead for SourceReader<'_> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        match self {
            SourceReader::File(r) => r.fill_buf(),
            SourceReader::Bytes(r) => r.fill_buf(),
        }
    }
    fn consume(&mut self, amount: usize) {
        match self {
            SourceReader::File(r) => r.consume(amount),
            SourceReader::Bytes(r) => r.consume(amount),
        }
    }
}

impl Seek for SourceReader<'_> {
    fn seek(&mut self, position: SeekFrom) -> std::io::Result<u64> {
        match self {
            SourceReader::File(r) => r.seek(position),
            SourceReader::Bytes(r) => r.seek(position),
        }
    }
}

fn read_multi(
    src: Source<'_>,
    constants: &[Option<f64>; 4],
    extended: &[Option<Input<'_>>; 3],
) -> Result<ParamImage, SkinError> {
    let what = "parameter EXR";
    let path = src.label();
    let probe = probe_exr(src, what)?;
    let mut wanted: Vec<(usize, usize)> = Vec::new(); // (parameter index, channel index in the file)
    let mut missing: Vec<&str> = Vec::new();
    for (p, name) in PARAM_CHANNELS.iter().enumerate() {
        if constants[p].is_some() {
            continue;
        }
        match probe.channels.iter().position(|(c, _)| c == name) {
            Some(c) => wanted.push((p, c)),
            None => missing.push(name),
        }
    }
    if !missing.is_empty() {
        return Err(SkinError::invalid(
            what,
            format!(
                "{}: missing channel{} {}; expected channels named {} (or a constant for each missing one); found \
                 channels: {}",
                path.display(),
                if missing.len() > 1 { "s" } else { "" },
                missing.join(", "),
                PARAM_CHANNELS.join(", "),
                probe.channel_list()
            ),
        ));
    }
    // The extended physiology: optional channels, unless a value or a file of their own is given.
    let mut extended_files: Vec<(usize, Source<'_>, FileProbe)> = Vec::new();
    for (k, name) in EXTENDED_CHANNELS.iter().enumerate() {
        match extended[k] {
            Some(Input::Constant(_)) => {}
            Some(Input::File(file)) => {
                let file_probe = probe_param_file(file, 4 + k)?;
                if (file_probe.width(), file_probe.height()) != (probe.width, probe.height) {
                    return Err(SkinError::invalid(
                        "parameter maps",
                        format!(
                            "expected all maps to have the same size (width x height); found {} {} is {}x{}, {name} {} \
                             is {}x{}",
                            what,
                            path.display(),
                            probe.width,
                            probe.height,
                            file.label().display(),
                            file_probe.width(),
                            file_probe.height()
                        ),
                    ));
                }
                extended_files.push((4 + k, file, file_probe));
            }
            None => {
                if let Some(c) = probe.channels.iter().position(|(c, _)| c == name) {
                    wanted.push((4 + k, c));
                }
            }
        }
    }
    let mut notes = Vec::new();
    let unknown: Vec<&str> =
        probe.channels.iter().map(|(c, _)| c.as_str()).filter(|c| !ALL_CHANNELS.contains(c)).collect();
    if !unknown.is_empty() {
        notes.push(format!(
            "{}: ignored channel{} {} (not a parameter's name); a parameter EXR's channels are named exactly {}",
            path.display(),
            if unknown.len() > 1 { "s" } else { "" },
            unknown.join(", "),
            ALL_CHANNELS.join(", ")
        ));
    }
    let indices: Vec<usize> = wanted.iter().map(|&(_, c)| c).collect();
    let mut read = read_exr_planes(src, what, &probe, &indices)?.into_iter();
    let mut planes: [Plane; 7] = std::array::from_fn(|p| {
        let value = if p < 4 {
            constants[p].unwrap_or(f64::NAN)
        } else {
            match extended[p - 4] {
                Some(Input::Constant(v)) => v,
                _ => EXTENDED_DEFAULTS[p - 4],
            }
        };
        Plane::Constant(value as f32)
    });
    for &(p, _) in &wanted {
        // One plane was read per wanted channel, in the same order.
        if let Some(values) = read.next() {
            planes[p] = Plane::Texels(values);
        }
    }
    for (p, file, file_probe) in &extended_files {
        planes[*p] = Plane::Texels(read_probed(*file, *p, file_probe, &mut notes)?);
    }
    Ok(image_of(probe.width, probe.height, planes, notes))
}

/// The four planes and the extended physiology's three as a [`ParamImage`].
fn image_of(width: usize, height: usize, planes: [Plane; 7], notes: Vec<String>) -> ParamImage {
    let [m, b, h, o, e0, e1, e2] = planes;
    ParamImage { width, height, planes: [m, b, h, o], extended: [e0, e1, e2], notes }
}

/// The note for an ignored alpha channel.
fn alpha_note(path: &Path, what: &str) -> String {
    format!("{}: the alpha channel of the {what} is ignored", path.display())
}

/// Decode a one-parameter file whose header `probe` has been checked; notes (an ignored alpha) go to `notes`.
fn read_probed(src: Source<'_>, p: usize, probe: &FileProbe, notes: &mut Vec<String>) -> Result<Vec<f32>, SkinError> {
    let what = map_name(p);
    let path = src.label();
    match probe {
        FileProbe::Exr { probe, channels, alpha } => {
            let mut planes = read_exr_planes(src, &what, probe, channels)?;
            if let [r, g, b] = planes.as_slice() {
                let names: Vec<&str> = channels.iter().map(|&c| probe.channels[c].0.as_str()).collect();
                check_grey(path, &what, probe.width, &names, |i| [r[i], g[i], b[i]], r.len())?;
            }
            if *alpha {
                notes.push(alpha_note(path, &what));
            }
            Ok(planes.swap_remove(0))
        }
        FileProbe::Integer { width, height, color } => {
            if color.has_alpha() {
                notes.push(alpha_note(path, &what));
            }
            read_integer_image(src, &what, p, *width, *height)
        }
    }
}

/// An error unless `texel(i)`'s three values are equal for every texel `i < count` (a grey RGB image): the message
/// names the channels and the first texel (x, y) that differs.
fn check_grey(
    path: &Path,
    what: &str,
    width: usize,
    names: &[&str],
    texel: impl Fn(usize) -> [f32; 3],
    count: usize,
) -> Result<(), SkinError> {
    // Equal as numbers (0 = -0), NaN with NaN (the range check reports NaN texels later, naming them).
    let same = |a: f32, b: f32| a == b || (a.is_nan() && b.is_nan());
    let differs = |i: usize| {
        let [r, g, b] = texel(i);
        !(same(r, g) && same(r, b))
    };
    match (0..count).find(|&i| differs(i)) {
        None => Ok(()),
        Some(i) => {
            let [r, g, b] = texel(i);
            Err(SkinError::invalid(
                what,
                format!(
                    "{}: found channels {} that differ (first at texel (x, y) = ({}, {}): {} {r}, {} {g}, {} {b}), so \
                     the image is not grey; expected {PARAM_IMAGE_FORMS}",
                    path.display(),
                    names.join(", "),
                    i % width.max(1),
                    i / width.max(1),
                    names[0],
                    names[1],
                    names[2],
                ),
            ))
        }
    }
}

fn read_separate(sources: &[Input<'_>; 7]) -> Result<ParamImage, SkinError> {
    // Phase 1: headers only.
    let mut probes: Vec<(usize, Source<'_>, FileProbe)> = Vec::new();
    for (p, source) in sources.iter().enumerate() {
        if let Input::File(src) = source {
            probes.push((p, *src, probe_param_file(*src, p)?));
        }
    }
    let Some((_, _, first)) = probes.first() else {
        return Err(SkinError::invalid("parameters", NO_MAP_GIVEN));
    };
    let (width, height) = (first.width(), first.height());
    if probes.iter().any(|(_, _, probe)| probe.width() != width || probe.height() != height) {
        let sizes: Vec<String> = probes
            .iter()
            .map(|(p, src, probe)| {
                format!("{} {} is {}x{}", ALL_CHANNELS[*p], src.label().display(), probe.width(), probe.height())
            })
            .collect();
        return Err(SkinError::invalid(
            "parameter maps",
            format!("expected all maps to have the same size (width x height); found {}", sizes.join(", ")),
        ));
    }

    // Phase 2: decode.
    let mut planes: [Plane; 7] = std::array::from_fn(|p| match &sources[p] {
        Input::Constant(value) => Plane::Constant(*value as f32),
        Input::File(_) => Plane::Constant(f32::NAN), // replaced below
    });
    let mut notes = Vec::new();
    for (p, src, probe) in &probes {
        planes[*p] = Plane::Texels(read_probed(*src, *p, probe, &mut notes)?);
    }
    Ok(image_of(width, height, planes, notes))
}

fn map_name(p: usize) -> String {
    format!("{} map", ALL_CHANNELS[p])
}

/// What phase 1 learnt about one file.
enum FileProbe {
    /// An EXR and the indices of the channels to read: one, or R, G, B of a grey image (`alpha`: it has an A too).
    Exr { probe: ExrProbe, channels: Vec<usize>, alpha: bool },
    /// An 8/16-bit PNG, TIFF or JPEG of colour type `color` (greyscale or RGB, with or without alpha).
    Integer { width: usize, height: usize, color: image::ColorType },
}

impl FileProbe {
    fn width(&self) -> usize {
        match self {
            FileProbe::Exr { probe, .. } => probe.width,
            FileProbe::Integer { width, .. } => *width,
        }
    }
    fn height(&self) -> usize {
        match self {
            FileProbe::Exr { probe, .. } => probe.height,
            FileProbe::Integer { height, .. } => *height,
        }
    }
}

/// The header facts of a readable EXR.
struct ExrProbe {
    width: usize,
    height: usize,
    channels: Vec<(String, SampleType)>,
}

impl ExrProbe {
    fn channel_list(&self) -> String {
        if self.channels.is_empty() {
            "none".to_string()
        } else {
            self.channels.iter().map(|(name, _)| name.as_str()).collect::<Vec<_>>().join(", ")
        }
    }
}

const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

fn open_file(path: &Path, what: &str) -> Result<File, SkinError> {
    if path.is_dir() {
        return Err(SkinError::io(path, format!("cannot read {what}: expected a file, found a directory")));
    }
    // A FIFO, socket or device is refused before it is opened: opening a FIFO waits for a writer, forever.
    if let Ok(meta) = std::fs::metadata(path) {
        if !meta.is_file() {
            return Err(SkinError::io(
                path,
                format!("cannot read {what}: expected a regular file, found a FIFO, socket or device"),
            ));
        }
    }
    File::open(path).map_err(|e| {
        SkinError::io_caused(path, format!("cannot read {what}: {e} (expected an existing, readable file)"), e)
    })
}

fn is_exr(src: Source<'_>, what: &str) -> Result<bool, SkinError> {
    let path = src.label();
    let mut magic = [0u8; 4];
    let mut file = src.open(what)?;
    let mut filled = 0;
    while filled < 4 {
        match file.read(&mut magic[filled..]) {
            Ok(0) => break,
            Ok(n) => filled += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(SkinError::io_caused(path, format!("cannot read {what}: {e}"), e)),
        }
    }
    Ok(filled == 4 && magic == EXR_MAGIC)
}

fn check_size(path: &Path, what: &str, width: usize, height: usize) -> Result<(), SkinError> {
    super::check_texel_count(format!("{what} ({})", path.display()), width, height)
}

/// Header of an EXR: single part, flat, full-resolution channels.
fn probe_exr(src: Source<'_>, what: &str) -> Result<ExrProbe, SkinError> {
    let path = src.label();
    let reader = src.open(what)?;
    let meta = guard(|| MetaData::read_from_buffered(reader, false)).and_then(|r| r.map_err(|e| e.to_string()));
    let meta = meta.map_err(|e| {
        SkinError::io(path, format!("cannot read {what}: not a valid OpenEXR header ({e}); expected an EXR file"))
    })?;
    probe_from_headers(path, what, &meta.headers)
}

fn probe_from_headers(path: &Path, what: &str, headers: &[Header]) -> Result<ExrProbe, SkinError> {
    if headers.len() != 1 {
        let names: Vec<String> = headers
            .iter()
            .map(|h| h.own_attributes.layer_name.as_ref().map(|n| n.to_string()).unwrap_or_else(|| "(unnamed)".into()))
            .collect();
        return Err(SkinError::invalid(
            what,
            format!(
                "{}: expected a single-part EXR; found {} parts ({})",
                path.display(),
                headers.len(),
                names.join(", ")
            ),
        ));
    }
    let header = &headers[0];
    if header.deep {
        return Err(SkinError::invalid(what, format!("{}: expected a flat EXR; found deep data", path.display())));
    }
    for channel in &header.channels.list {
        if channel.sampling.0 != 1 || channel.sampling.1 != 1 {
            return Err(SkinError::invalid(
                what,
                format!(
                    "{}: expected full-resolution channels; channel {} is sub-sampled {}x{}",
                    path.display(),
                    channel.name,
                    channel.sampling.0,
                    channel.sampling.1
                ),
            ));
        }
    }
    let (width, height) = (header.layer_size.0, header.layer_size.1);
    check_size(path, what, width, height)?;
    Ok(ExrProbe {
        width,
        height,
        channels: header.channels.list.iter().map(|c| (c.name.to_string(), c.sample_type)).collect(),
    })
}

/// Header check of a one-parameter file.
fn probe_param_file(src: Source<'_>, p: usize) -> Result<FileProbe, SkinError> {
    let what = map_name(p);
    let path = src.label();
    if is_exr(src, &what)? {
        let probe = probe_exr(src, &what)?;
        let (channels, alpha) = if probe.channels.len() == 1 {
            (vec![0], false)
        } else if let Some(c) = probe.channels.iter().position(|(c, _)| c == ALL_CHANNELS[p]) {
            (vec![c], false)
        } else {
            match rgb_layout(&probe) {
                Ok(Some(layout)) if layout.others.is_empty() => (layout.rgb.to_vec(), layout.alpha.is_some()),
                _ => {
                    return Err(SkinError::invalid(
                        what,
                        format!(
                            "{}: found channels {}; expected {PARAM_IMAGE_FORMS} (here: a channel named {})",
                            path.display(),
                            probe.channel_list(),
                            ALL_CHANNELS[p],
                        ),
                    ))
                }
            }
        };
        return Ok(FileProbe::Exr { probe, channels, alpha });
    }
    let reader = image_reader(src, &what)?;
    let decoder = guard(|| {
        reader.into_decoder().map(|d| (image::ImageDecoder::dimensions(&d), image::ImageDecoder::color_type(&d)))
    })
    .and_then(|r| r.map_err(|e| e.to_string()))
    .map_err(|e| SkinError::io(path, format!("cannot read {what}: cannot decode the image header ({e})")))?;
    let ((w, h), color) = decoder;
    check_color(path, &what, color, PARAM_IMAGE_FORMS)?;
    let (width, height) = (w as usize, h as usize);
    check_size(path, &what, width, height)?;
    Ok(FileProbe::Integer { width, height, color })
}

/// Where the R, G, B (and A) channels of an EXR are: bare `R`, `G`, `B`, else `<layer>.R` etc. of the one layer that
/// has all three. `others`: the channels that are none of them. `Ok(None)`: no such channels; `Err`: several layers
/// have them (the message lists the layers).
struct RgbLayout {
    rgb: [usize; 3],
    alpha: Option<usize>,
    others: Vec<usize>,
}

fn rgb_layout(probe: &ExrProbe) -> Result<Option<RgbLayout>, String> {
    let find = |name: &str| probe.channels.iter().position(|(c, _)| c == name);
    let mut prefixes: Vec<&str> = probe
        .channels
        .iter()
        .filter_map(|(c, _)| c.strip_suffix('R'))
        .filter(|prefix| prefix.is_empty() || prefix.ends_with('.'))
        .filter(|prefix| find(&format!("{prefix}G")).is_some() && find(&format!("{prefix}B")).is_some())
        .collect();
    prefixes.sort_unstable();
    let prefix = match prefixes.as_slice() {
        [] => return Ok(None),
        [one] => *one,
        several if several.contains(&"") => "",
        several => {
            let layers: Vec<&str> = several.iter().map(|p| p.trim_end_matches('.')).collect();
            return Err(format!("several layers have R, G, B channels ({}): which one is meant", layers.join(", ")));
        }
    };
    let at = |c: &str| find(&format!("{prefix}{c}"));
    let (Some(r), Some(g), Some(b)) = (at("R"), at("G"), at("B")) else { return Ok(None) };
    let alpha = at("A");
    let others =
        (0..probe.channels.len()).filter(|i| ![Some(r), Some(g), Some(b), alpha].contains(&Some(*i))).collect();
    Ok(Some(RgbLayout { rgb: [r, g, b], alpha, others }))
}

/// An image reader for a PNG or TIFF, recognised by content.
fn image_reader<'a>(src: Source<'a>, what: &str) -> Result<image::ImageReader<SourceReader<'a>>, SkinError> {
    let path = src.label();
    let reader = image::ImageReader::new(src.open(what)?)
        .with_guessed_format()
        .map_err(|e| SkinError::io_caused(path, format!("cannot read {what}: {e}"), e))?;
    match reader.format() {
        Some(image::ImageFormat::Png) | Some(image::ImageFormat::Tiff) | Some(image::ImageFormat::Jpeg) => Ok(reader),
        Some(other) => Err(SkinError::invalid(
            what,
            format!("{}: expected an EXR, PNG, TIFF or JPEG file; found {other:?}", path.display()),
        )),
        None => Err(SkinError::invalid(
            what,
            format!("{}: expected an EXR, PNG, TIFF or JPEG file; found an unrecognised format", path.display()),
        )),
    }
}

/// Decode a PNG, TIFF or JPEG whole, after [`check_complete`]: the one decoding step of both readers.
fn decode_complete(src: Source<'_>, what: &str) -> Result<image::DynamicImage, SkinError> {
    let path = src.label();
    let reader = image_reader(src, what)?;
    if let Some(format) = reader.format() {
        check_complete(src, what, format)?;
    }
    guard(|| reader.decode())
        .and_then(|r| r.map_err(|e| e.to_string()))
        .map_err(|e| SkinError::io(path, format!("cannot read {what}: cannot decode the image ({e})")))
}

/// An error naming the file unless it holds everything its format says must be there. Decoders differ in what they
/// do at a missing end: JPEG decoders fill it with grey (a JPEG cut at 60 % of its bytes decoded with 42 % of its
/// texels wrong) and PNG's never reads its IEND chunk, so the structure is walked here, for every format the same
/// rule: a PNG's chunks, each inside the file, up to IEND; a JPEG's segments and entropy-coded scans up to the EOI
/// marker. A TIFF's decoder reads every strip or tile at its offset and fails at the file's end, and an EXR's chunks
/// are checked against the file's length ([`check_chunks`]), so for those the decoder's own error is the refusal
/// (`tests/maps/truncated_images.rs` cuts every format at every 1/40 of its bytes and at its last four). Bytes after
/// the end (padding) are no damage.
fn check_complete(src: Source<'_>, what: &str, format: image::ImageFormat) -> Result<(), SkinError> {
    let path = src.label();
    let mut reader = src.open(what)?;
    let (name, result) = match format {
        image::ImageFormat::Png => ("PNG", png_complete(&mut reader)),
        image::ImageFormat::Jpeg => ("JPEG", jpeg_complete(&mut reader)),
        _ => return Ok(()),
    };
    match result {
        Ok(None) => Ok(()),
        Ok(Some(missing)) => Err(SkinError::io(
            path,
            format!(
                "cannot read {what}: the {name} file is truncated or damaged ({missing}); nothing was read from it"
            ),
        )),
        Err(e) => Err(SkinError::io_caused(path, format!("cannot read {what}: {e}"), e)),
    }
}

/// The next byte, or None at the end of the file.
fn next_byte(r: &mut impl BufRead) -> std::io::Result<Option<u8>> {
    let byte = r.fill_buf()?.first().copied();
    if byte.is_some() {
        r.consume(1);
    }
    Ok(byte)
}

/// Skip `n` bytes; false if the file ends first.
fn skip_bytes(r: &mut impl BufRead, mut n: u64) -> std::io::Result<bool> {
    while n > 0 {
        let available = r.fill_buf()?.len() as u64;
        if available == 0 {
            return Ok(false);
        }
        let step = available.min(n);
        r.consume(step as usize);
        n -= step;
    }
    Ok(true)
}

fn read_array<const N: usize>(r: &mut impl BufRead) -> std::io::Result<Option<[u8; N]>> {
    let mut buf = [0u8; N];
    for b in &mut buf {
        match next_byte(r)? {
            Some(v) => *b = v,
            None => return Ok(None),
        }
    }
    Ok(Some(buf))
}

/// None if a PNG's chunks, from the signature on, each fit in the file up to and including IEND; else what is
/// missing.
fn png_complete(r: &mut impl BufRead) -> std::io::Result<Option<String>> {
    if !skip_bytes(r, 8)? {
        return Ok(Some("no signature".to_string()));
    }
    let mut chunks = 0usize;
    loop {
        let Some(head) = read_array::<8>(r)? else {
            return Ok(Some(format!("the file ends after {chunks} chunks, before the IEND chunk")));
        };
        let length = u64::from(u32::from_be_bytes([head[0], head[1], head[2], head[3]]));
        let kind = String::from_utf8_lossy(&head[4..8]).into_owned();
        if !skip_bytes(r, length + 4)? {
            return Ok(Some(format!("chunk {chunks} ({kind}) is cut short")));
        }
        if kind == "IEND" {
            return Ok(None);
        }
        chunks += 1;
    }
}

/// None if a JPEG's segments and scans reach its end-of-image marker (EOI) after at least one scan; else what is
/// missing. Markers are found as the standard frames them: a segment's length skips its body; inside a scan's
/// entropy-coded data 0xFF 0x00 is a stuffed byte, 0xFF 0xD0..0xD7 a restart marker, any other marker ends the scan.
fn jpeg_complete(r: &mut impl BufRead) -> std::io::Result<Option<String>> {
    const SOI: u8 = 0xD8;
    const EOI: u8 = 0xD9;
    const SOS: u8 = 0xDA;
    let ends = |at: &str| Ok(Some(format!("the file ends {at}, before the end-of-image marker")));
    if read_array::<2>(r)? != Some([0xFF, SOI]) {
        return Ok(Some("no start-of-image marker".to_string()));
    }
    let mut scans = 0usize;
    // The marker to handle next (read after a scan's data), or None: read one.
    let mut pending: Option<u8> = None;
    loop {
        let marker = match pending.take() {
            Some(m) => m,
            None => {
                if next_byte(r)? != Some(0xFF) {
                    return Ok(Some(format!("no marker where one must be, after {scans} scans")));
                }
                let mut m = 0xFF;
                while m == 0xFF {
                    match next_byte(r)? {
                        Some(v) => m = v,
                        None => return ends("inside a marker"),
                    }
                }
                m
            }
        };
        match marker {
            EOI if scans > 0 => return Ok(None),
            EOI => return Ok(Some("an end-of-image marker before any scan".to_string())),
            0x01 | 0xD0..=0xD7 => continue,
            _ => {}
        }
        let Some(length) = read_array::<2>(r)? else { return ends("inside a segment's length") };
        let length = u64::from(u16::from_be_bytes(length));
        if length < 2 || !skip_bytes(r, length - 2)? {
            return ends(&format!("inside a segment (marker 0x{marker:02X})"));
        }
        if marker != SOS {
            continue;
        }
        scans += 1;
        // The scan's entropy-coded data, up to the next marker.
        loop {
            let Some(byte) = next_byte(r)? else { return ends(&format!("inside scan {scans}")) };
            if byte != 0xFF {
                continue;
            }
            let mut next = 0xFF;
            while next == 0xFF {
                match next_byte(r)? {
                    Some(v) => next = v,
                    None => return ends(&format!("inside scan {scans}")),
                }
            }
            if next != 0x00 && !(0xD0..=0xD7).contains(&next) {
                pending = Some(next);
                break;
            }
        }
    }
}

/// An error (naming the file, what it is and `accepted`) unless `color` is 8- or 16-bit greyscale or RGB, with or
/// without alpha.
fn check_color(path: &Path, what: &str, color: image::ColorType, accepted: &str) -> Result<(), SkinError> {
    use image::ColorType as C;
    match color {
        C::L8 | C::L16 | C::La8 | C::La16 | C::Rgb8 | C::Rgb16 | C::Rgba8 | C::Rgba16 => Ok(()),
        other => Err(SkinError::invalid(
            what,
            format!(
                "{}: found {} ({} channels, {} bits); expected {accepted}",
                path.display(),
                color_name(other),
                other.channel_count(),
                other.bits_per_pixel() / u16::from(other.channel_count()),
            ),
        )),
    }
}

fn color_name(color: image::ColorType) -> &'static str {
    use image::ColorType as C;
    match color {
        C::L8 | C::L16 => "greyscale",
        C::La8 | C::La16 => "greyscale + alpha",
        C::Rgb8 | C::Rgb16 => "RGB",
        C::Rgba8 | C::Rgba16 => "RGBA",
        C::Rgb32F => "float RGB",
        C::Rgba32F => "float RGBA",
        _ => "an unsupported colour type",
    }
}

/// Decode a greyscale PNG/TIFF and map its integer values onto parameter `p`'s range.
fn read_integer_image(
    src: Source<'_>,
    what: &str,
    p: usize,
    width: usize,
    height: usize,
) -> Result<Vec<f32>, SkinError> {
    let path = src.label();
    let img = decode_complete(src, what)?;
    if img.width() as usize != width || img.height() as usize != height {
        return Err(SkinError::invalid(
            what,
            format!(
                "{}: expected {width}x{height} as its header said; decoded {}x{} (file changed while reading?)",
                path.display(),
                img.width(),
                img.height()
            ),
        ));
    }
    let (min, max) = ALL_RANGES[p];
    let map8 = |v: u8| (min + (max - min) * f64::from(v) / 255.0) as f32;
    let map16 = |v: u16| (min + (max - min) * f64::from(v) / 65535.0) as f32;
    // RGB(A): R = G = B exactly in every texel, else an error naming the first texel that differs.
    let grey = |raw: &[u16], step: usize| {
        let texel = |i: usize| [raw[i * step], raw[i * step + 1], raw[i * step + 2]].map(f32::from);
        check_grey(path, what, width, &["R", "G", "B"], texel, raw.len() / step)
    };
    let widen = |raw: &[u8]| raw.iter().map(|&v| u16::from(v)).collect::<Vec<u16>>();
    let values: Vec<f32> = match img {
        image::DynamicImage::ImageLuma8(buf) => buf.as_raw().iter().map(|&v| map8(v)).collect(),
        image::DynamicImage::ImageLumaA8(buf) => buf.as_raw().chunks_exact(2).map(|la| map8(la[0])).collect(),
        image::DynamicImage::ImageLuma16(buf) => buf.as_raw().iter().map(|&v| map16(v)).collect(),
        image::DynamicImage::ImageLumaA16(buf) => buf.as_raw().chunks_exact(2).map(|la| map16(la[0])).collect(),
        image::DynamicImage::ImageRgb8(buf) => {
            grey(&widen(buf.as_raw()), 3)?;
            buf.as_raw().chunks_exact(3).map(|c| map8(c[0])).collect()
        }
        image::DynamicImage::ImageRgba8(buf) => {
            grey(&widen(buf.as_raw()), 4)?;
            buf.as_raw().chunks_exact(4).map(|c| map8(c[0])).collect()
        }
        image::DynamicImage::ImageRgb16(buf) => {
            grey(buf.as_raw(), 3)?;
            buf.as_raw().chunks_exact(3).map(|c| map16(c[0])).collect()
        }
        image::DynamicImage::ImageRgba16(buf) => {
            grey(buf.as_raw(), 4)?;
            buf.as_raw().chunks_exact(4).map(|c| map16(c[0])).collect()
        }
        other => {
            return Err(check_color(path, what, other.color(), PARAM_IMAGE_FORMS).err().unwrap_or_else(|| {
                SkinError::invalid(what, format!("{}: expected {PARAM_IMAGE_FORMS}", path.display()))
            }))
        }
    };
    if values.len() != width * height {
        return Err(SkinError::invalid(
            what,
            format!("{}: expected {} texels; decoded {}", path.display(), width * height, values.len()),
        ));
    }
    Ok(values)
}

/// Read the channels at `indices` (indices into the file's sorted channel list) of a probed EXR into f32 planes,
/// decompressing blocks in parallel (panics included: see below) and writing samples straight into the planes.
fn read_exr_planes(
    src: Source<'_>,
    what: &str,
    probe: &ExrProbe,
    indices: &[usize],
) -> Result<Vec<Vec<f32>>, SkinError> {
    let path = src.label();
    let decode_error =
        |e: String| SkinError::io(path, format!("cannot read {what}: EXR data is truncated or corrupt ({e})"));
    let (width, height) = (probe.width, probe.height);
    let texels = width * height;
    let file = src.open(what)?;

    let result = guard(|| -> Result<Vec<Vec<f32>>, ReadFailure> {
        let reader = exr::block::read(file, false).map_err(ReadFailure::Exr)?;
        // Re-check the header: the file could have changed since it was probed.
        let again = probe_from_headers(path, what, reader.headers()).map_err(ReadFailure::Skin)?;
        if again.width != width || again.height != height || again.channels != probe.channels {
            return Err(ReadFailure::Skin(SkinError::invalid(
                what,
                format!("{}: the file changed while being read", path.display()),
            )));
        }
        check_chunks(src, what, reader.meta_data()).map_err(ReadFailure::Skin)?;
        let mut slot_of_channel: Vec<Option<usize>> = vec![None; probe.channels.len()];
        for (slot, &c) in indices.iter().enumerate() {
            slot_of_channel[c] = Some(slot);
        }
        let types: Vec<SampleType> = probe.channels.iter().map(|(_, t)| *t).collect();
        let mut planes: Vec<Vec<f32>> = indices.iter().map(|_| vec![0.0f32; texels]).collect();
        let mut counted = vec![0usize; indices.len()];
        if indices.is_empty() {
            return Ok(planes);
        }

        // One line of half samples at a time, converted to f32 as a slice (F16C where the CPU has it).
        let mut halves: Vec<f16> = Vec::new();
        let chunks = reader
            .filter_chunks(false, |_, tile, block| block.layer == 0 && tile.is_largest_resolution_level())
            .map_err(ReadFailure::Exr)?;
        // Decompressed here, in parallel batches on rayon's pool, not by exr's own pool: a decoder that panics on a
        // damaged block (exr 1.74's B44 subtracts with overflow where overflow checks are on: found by fuzzing) would
        // abort the process from exr's spawned job, while a panic in a parallel iterator reaches this thread, where
        // `guard` turns it into an error. Batches bound the decompressed blocks held at once.
        let meta = chunks.meta_data().clone();
        let mut insert = |block: exr::block::UncompressedBlock| -> exr::error::UnitResult {
            let channels = &meta.headers[block.index.layer].channels;
            for line in block.lines(channels) {
                let Some(slot) = slot_of_channel.get(line.location.channel).copied().flatten() else {
                    continue;
                };
                let (x, y, n) = (line.location.position.0, line.location.position.1, line.location.sample_count);
                if y >= height || x.checked_add(n).map_or(true, |end| end > width) {
                    return Err(exr::error::Error::Invalid("pixel block outside the data window".into()));
                }
                let start = y * width + x;
                let dst = &mut planes[slot][start..start + n];
                match types[line.location.channel] {
                    SampleType::F32 => line.read_samples_into_slice(dst)?,
                    SampleType::F16 => {
                        use half::slice::HalfFloatSliceExt;
                        halves.resize(n, f16::ZERO);
                        line.read_samples_into_slice(&mut halves)?;
                        halves.convert_to_f32_slice(dst);
                    }
                    SampleType::U32 => {
                        for (d, s) in dst.iter_mut().zip(line.read_samples::<u32>()) {
                            *d = s? as f32;
                        }
                    }
                }
                counted[slot] += n;
            }
            Ok(())
        };
        const BATCH_CHUNKS: usize = 64;
        let mut chunks = chunks;
        loop {
            let batch: Vec<exr::block::chunk::Chunk> =
                chunks.by_ref().take(BATCH_CHUNKS).collect::<exr::error::Result<_>>().map_err(ReadFailure::Exr)?;
            if batch.is_empty() {
                break;
            }
            let blocks: Vec<exr::block::UncompressedBlock> = batch
                .into_par_iter()
                .map(|chunk| exr::block::UncompressedBlock::decompress_chunk(chunk, &meta, false))
                .collect::<exr::error::Result<_>>()
                .map_err(ReadFailure::Exr)?;
            for block in blocks {
                insert(block).map_err(ReadFailure::Exr)?;
            }
        }
        for (slot, &c) in indices.iter().enumerate() {
            if counted[slot] != texels {
                return Err(ReadFailure::Message(format!(
                    "channel {} has {} of {} texels",
                    probe.channels[c].0, counted[slot], texels
                )));
            }
        }
        Ok(planes)
    });
    match result {
        Ok(Ok(planes)) => Ok(planes),
        Ok(Err(ReadFailure::Skin(e))) => Err(e),
        Ok(Err(ReadFailure::Exr(e))) => Err(decode_error(e.to_string())),
        Ok(Err(ReadFailure::Message(m))) => Err(decode_error(m)),
        Err(panic) => Err(decode_error(panic)),
    }
}

/// Check that every chunk of a probed EXR lies inside the file before any chunk is read: the offset table fits, each
/// offset points into the file, and each chunk's declared data size ends within it. The exr crate allocates and
/// zero-fills a chunk's declared size (up to the largest block the header allows) before reading it, so without this
/// a few hundred damaged bytes could make it touch a gigabyte (found by fuzzing: docs/robustness.md, "Fuzzing").
///
/// The layout is OpenEXR's ("OpenEXR File Layout", single-part files): after the header, one u64 offset per chunk;
/// at each offset a scan-line chunk is `y: i32, size: i32, data` and a tile chunk `x, y, level x, level y: i32,
/// size: i32, data`, each preceded by `part: i32` when the file has the multi-part flag.
fn check_chunks(src: Source<'_>, what: &str, meta: &MetaData) -> Result<(), SkinError> {
    let path = src.label();
    let damaged = |reason: String| {
        SkinError::io(path, format!("cannot read {what}: EXR data is truncated or corrupt ({reason})"))
    };
    let io_error = |e: std::io::Error| damaged(e.to_string());
    let [header] = meta.headers.as_slice() else {
        return Err(damaged("expected one part".into()));
    };
    let mut reader = src.open(what)?;
    let file_len = reader.seek(SeekFrom::End(0)).map_err(io_error)?;
    reader.seek(SeekFrom::Start(0)).map_err(io_error)?;
    // Where the header ends: what reading it again consumed.
    let mut counting = CountingReader { inner: &mut reader, count: 0 };
    guard(|| MetaData::read_from_buffered(&mut counting, false))
        .and_then(|r| r.map_err(|e| e.to_string()))
        .map_err(damaged)?;
    let table_start = counting.count;
    let chunks = header.chunk_count as u64;
    let table_end = chunks.checked_mul(8).and_then(|n| n.checked_add(table_start));
    if table_end.map_or(true, |end| end > file_len) {
        return Err(damaged(format!("an offset table of {chunks} chunks does not fit in {file_len} bytes")));
    }
    let table_end = table_end.unwrap_or(file_len);
    let mut table = vec![0u8; (table_end - table_start) as usize];
    reader.seek(SeekFrom::Start(table_start)).map_err(io_error)?;
    reader.read_exact(&mut table).map_err(io_error)?;
    // The i32 fields before the size: the part number if multi-part, then y (scan lines) or x, y, levels (tiles).
    let before_size = 4
        * (usize::from(meta.requirements.is_multilayer())
            + if matches!(header.blocks, BlockDescription::ScanLines) { 1 } else { 4 });
    let mut fields = vec![0u8; before_size + 4];
    for (index, entry) in table.chunks_exact(8).enumerate() {
        let offset = u64::from_le_bytes(entry.try_into().unwrap_or([0xff; 8]));
        if offset.checked_add(fields.len() as u64).map_or(true, |end| end > file_len) || offset < table_end {
            return Err(damaged(format!(
                "chunk {index} starts at byte {offset}, outside the data of a {file_len}-byte file"
            )));
        }
        reader.seek(SeekFrom::Start(offset)).map_err(io_error)?;
        reader.read_exact(&mut fields).map_err(io_error)?;
        let size = i32::from_le_bytes([
            fields[before_size],
            fields[before_size + 1],
            fields[before_size + 2],
            fields[before_size + 3],
        ]);
        let end = offset + fields.len() as u64 + u64::try_from(size).unwrap_or(u64::MAX / 2);
        if size < 0 || end > file_len {
            return Err(damaged(format!(
                "chunk {index} at byte {offset} claims {size} bytes; the file ends at {file_len}"
            )));
        }
    }
    Ok(())
}

/// A reader that counts the bytes read through it.
struct CountingReader<R> {
    inner: R,
    count: u64,
}

impl<R: Read> Read for CountingReader<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.count += n as u64;
        Ok(n)
    }
}

enum ReadFailure {
    Exr(exr::error::Error),
    Skin(SkinError),
    Message(String),
}

/// Read all channels of an EXR as f32 planes by name, in the file's (alphabetical) channel order. Returns
/// `(width, height, channels)`; planes are row-major, row 0 at the top. f16 and u32 samples are converted to f32.
/// The file must be a single-part flat EXR (as written by [`write_rgb_exr`] and [`write_channels_exr`]).
#[allow(clippy::type_complexity)] // the plain tuple is the documented API
pub fn read_exr_channels(path: &Path) -> Result<(usize, usize, Vec<(String, Vec<f32>)>), SkinError> {
    let what = "EXR";
    let src = Source::Path(path);
    let probe = probe_exr(src, what)?;
    let indices: Vec<usize> = (0..probe.channels.len()).collect();
    let planes = read_exr_planes(src, what, &probe, &indices)?;
    let named = probe.channels.iter().map(|(name, _)| name.clone()).zip(planes).collect();
    Ok((probe.width, probe.height, named))
}

/// An albedo texture as the fits take it: linear RGB per texel, row-major, row 0 at the top.
#[derive(Debug, Clone, PartialEq)]
pub struct AlbedoTexture {
    pub width: usize,
    pub height: usize,
    /// Linear RGB of each texel (`width * height`), in the working space the caller says the file is in.
    pub texels: Vec<[f32; 3]>,
    /// How the file was read, for messages: "linear EXR", "8-bit sRGB PNG" and the like.
    pub encoding: String,
    /// True for an integer image decoded from sRGB (whose primaries are Rec.709's); false for a linear EXR.
    pub srgb_decoded: bool,
    /// What was accepted but a user should know (an ignored alpha or other channels), one sentence each naming the
    /// file; fronts show them as warnings.
    pub notes: Vec<String>,
}

/// The sRGB transfer function's inverse (IEC 61966-2-1): an encoded value in 0..1 to linear.
fn srgb_to_linear(encoded: f64) -> f64 {
    if encoded <= 0.04045 {
        encoded / 12.92
    } else {
        ((encoded + 0.055) / 1.055).powf(2.4)
    }
}

/// Read an albedo texture, any of [`ALBEDO_IMAGE_FORMS`] (recognised by content, not extension): an EXR's R, G, B
/// (bare, or `<layer>.R` etc. of the one layer that has them) taken as linear; an 8- or 16-bit PNG, TIFF or JPEG
/// (greyscale or RGB) decoded from sRGB to linear with the sRGB formula, computed in f64. An alpha channel and an
/// EXR's other channels are ignored with a note. Values are not range-checked here (the fit checks them).
pub fn read_albedo_texture(path: &Path) -> Result<AlbedoTexture, SkinError> {
    read_rgb_image(path, "albedo texture")
}

/// [`read_albedo_texture`]'s reading for another RGB image (a skin mask), with `what` naming it in messages.
pub fn read_rgb_image(path: &Path, what: &str) -> Result<AlbedoTexture, SkinError> {
    let src = Source::Path(path);
    let mut notes = Vec::new();
    if is_exr(src, what)? {
        let probe = probe_exr(src, what)?;
        let refuse = |found: String| {
            SkinError::invalid(what, format!("{}: {found}; expected {ALBEDO_IMAGE_FORMS}", path.display()))
        };
        let layout = rgb_layout(&probe)
            .map_err(|several| refuse(format!("found channels {}: {several}", probe.channel_list())))?
            .ok_or_else(|| refuse(format!("found channels {}, no R, G, B", probe.channel_list())))?;
        let ignored: Vec<&str> =
            layout.alpha.iter().chain(&layout.others).map(|&c| probe.channels[c].0.as_str()).collect();
        if !ignored.is_empty() {
            notes.push(format!(
                "{}: channel{} {} of the {what} ignored (only R, G, B are read)",
                path.display(),
                if ignored.len() > 1 { "s" } else { "" },
                ignored.join(", ")
            ));
        }
        let planes = read_exr_planes(src, what, &probe, &layout.rgb)?;
        let texels = (0..probe.width * probe.height).map(|i| [planes[0][i], planes[1][i], planes[2][i]]).collect();
        return Ok(AlbedoTexture {
            width: probe.width,
            height: probe.height,
            texels,
            encoding: "linear EXR".to_string(),
            srgb_decoded: false,
            notes,
        });
    }
    // The header first: colour type and size checked before any pixel is decoded.
    let reader = image_reader(src, what)?;
    let format = reader.format().map(|f| format!("{f:?}").to_uppercase()).unwrap_or_default();
    let ((w, h), color) = guard(|| {
        reader.into_decoder().map(|d| (image::ImageDecoder::dimensions(&d), image::ImageDecoder::color_type(&d)))
    })
    .and_then(|r| r.map_err(|e| e.to_string()))
    .map_err(|e| SkinError::io(path, format!("cannot read {what}: cannot decode the image header ({e})")))?;
    check_color(path, what, color, ALBEDO_IMAGE_FORMS)?;
    let (width, height) = (w as usize, h as usize);
    check_size(path, what, width, height)?;
    let img = decode_complete(src, what)?;
    if (img.width() as usize, img.height() as usize, img.color()) != (width, height, color) {
        return Err(SkinError::invalid(
            what,
            format!("{}: the image changed while being read (header and pixels disagree)", path.display()),
        ));
    }
    if color.has_alpha() {
        notes.push(alpha_note(path, what));
    }
    let bits = color.bits_per_pixel() / u16::from(color.channel_count());
    let texels: Vec<[f32; 3]> = if bits == 8 {
        let table: Vec<f32> = (0..=255u8).map(|v| srgb_to_linear(f64::from(v) / 255.0) as f32).collect();
        img.into_rgb8().as_raw().chunks_exact(3).map(|c| [c[0], c[1], c[2]].map(|v| table[usize::from(v)])).collect()
    } else {
        let table: Vec<f32> = (0..=65535u16).map(|v| srgb_to_linear(f64::from(v) / 65535.0) as f32).collect();
        img.into_rgb16().as_raw().chunks_exact(3).map(|c| [c[0], c[1], c[2]].map(|v| table[usize::from(v)])).collect()
    };
    Ok(AlbedoTexture {
        width,
        height,
        texels,
        encoding: format!("{bits}-bit sRGB {format}"),
        srgb_decoded: true,
        notes,
    })
}
