//! Images in, texture maps out: reading the parameter planes (EXR, PNG, TIFF, JPEG or constants) and albedo textures
//! (EXR, PNG, TIFF, JPEG), and writing scene-linear EXR outputs atomically.
//!
//! Conventions shared by every function here:
//! - Planes are row-major, `width * height` long, row 0 at the top (the first row of the EXR data window, the first
//!   row of a PNG or TIFF as stored; a TIFF orientation tag is ignored).
//! - EXR files must be single-part, flat (not deep) and without sub-sampled channels; of a mip- or rip-mapped file
//!   only the full-resolution level is read. Only the size of the data window matters, not its position.
//! - Written EXRs are single-part scan-line files whose channels are stored sorted by name (as OpenEXR requires):
//!   an RGB file holds `B`, `G`, `R` in that order on disk; readers look channels up by name.
//! - Outputs are written to a hidden temporary file beside the destination (`.<name>.<random>.tmp`) and renamed into
//!   place only once complete, so a failure never leaves a half-written or clobbered file.
//!
//! Files, along the seams: `read.rs` (the one reader of input images for every front: parameter maps and albedo
//! textures from EXR, PNG, TIFF, JPEG or bytes in memory, checked before decoding),
//! `encode.rs` (EXR encoding of output planes) and `staging.rs` (temporary files renamed into place together).

mod encode;
mod read;
mod staging;

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

pub use encode::{
    auto_sample_rows, choose_compression, resolve_compression, stage_channels_exr, stage_files, stage_rgb_exr,
    write_channels_exr, write_rgb_exr, ExrStream, PlaneFile, STREAM_ROWS,
};
pub use read::{
    read_albedo_texture, read_exr_channels, read_params, read_params_from_bytes, read_rgb_image, AlbedoTexture,
};
pub use staging::{
    check_output_dir, commit_all, create_output_dir, output_folder_of, stage_bytes, write_atomic, Staged,
};

use crate::skin::params::{ParamSpec, EXTENDED_DEFAULTS, EXTENDED_PARAMS, PAPER_PARAMS as PARAMS};

/// The names of the four parameters ([`PARAMS`]: melanin, melanin_blend, hemoglobin, oiliness). These are also the channel names
/// a multi-channel parameter EXR must use (exact, case-sensitive).
pub const PARAM_CHANNELS: [&str; 4] = [PARAMS[0].name, PARAMS[1].name, PARAMS[2].name, PARAMS[3].name];

/// The allowed range `(min, max)` of each parameter ([`PARAMS`]), in [`PARAM_CHANNELS`] order (unitless volume fractions and
/// shares). An integer PNG/TIFF/JPEG value `v` of bit depth `b` maps to `min + (max - min) * v / (2^b - 1)`.
pub const PARAM_RANGES: [(f64, f64); 4] = [PARAMS[0].range(), PARAMS[1].range(), PARAMS[2].range(), PARAMS[3].range()];

/// The names of the extended physiology ([`EXTENDED_PARAMS`]: epidermis_thickness_mm, baseline_absorption_scale,
/// blood_oxygenation): optional channels of a parameter EXR, named exactly so; a missing one takes the value given for
/// it, else its default (the paper's value).
pub const EXTENDED_CHANNELS: [&str; 3] = [EXTENDED_PARAMS[0].name, EXTENDED_PARAMS[1].name, EXTENDED_PARAMS[2].name];

/// The allowed range of each extended parameter, in [`EXTENDED_CHANNELS`] order; an integer PNG/TIFF/JPEG value maps
/// onto it as for [`PARAM_RANGES`].
pub const EXTENDED_RANGES: [(f64, f64); 3] =
    [EXTENDED_PARAMS[0].range(), EXTENDED_PARAMS[1].range(), EXTENDED_PARAMS[2].range()];

/// [`PARAM_CHANNELS`] then [`EXTENDED_CHANNELS`]: every parameter a map can hold, indexed as `crate::skin::params::PARAMS`.
pub(crate) const ALL_CHANNELS: [&str; 7] = [
    PARAM_CHANNELS[0],
    PARAM_CHANNELS[1],
    PARAM_CHANNELS[2],
    PARAM_CHANNELS[3],
    EXTENDED_CHANNELS[0],
    EXTENDED_CHANNELS[1],
    EXTENDED_CHANNELS[2],
];

/// The ranges of [`ALL_CHANNELS`].
pub(crate) const ALL_RANGES: [(f64, f64); 7] = [
    PARAM_RANGES[0],
    PARAM_RANGES[1],
    PARAM_RANGES[2],
    PARAM_RANGES[3],
    EXTENDED_RANGES[0],
    EXTENDED_RANGES[1],
    EXTENDED_RANGES[2],
];

/// The forms a one-parameter image may take, for every refusal's message (fronts show it as it is).
///
/// Integer images (PNG, TIFF, JPEG) are data, not colour: a value `v` of bit depth `b` maps to
/// `min + (max - min) * v / (2^b - 1)` of the parameter's range with no sRGB decoding, whatever colour profile the
/// file declares (the convention of greyscale maps since the first release, kept for RGB files with R = G = B).
pub const PARAM_IMAGE_FORMS: &str = "a single-channel EXR (values are the parameter itself), an EXR with a channel \
     named like the parameter, an RGB or RGBA EXR with R = G = B in every texel (a grey image, as Blender saves one; \
     alpha ignored), or an 8- or 16-bit PNG, TIFF or JPEG that is greyscale or RGB(A) with R = G = B (values mapped \
     0..1 onto the parameter's range, no sRGB decoding; alpha ignored)";

/// The forms an albedo texture may take, for every refusal's message.
pub const ALBEDO_IMAGE_FORMS: &str = "an EXR with channels R, G, B (or <layer>.R, <layer>.G, <layer>.B of one \
     layer; A ignored), linear in the working space; or an 8- or 16-bit RGB(A) or greyscale PNG, TIFF or JPEG, \
     sRGB-encoded (decoded to linear with the sRGB formula, IEC 61966-2-1; alpha ignored)";

/// Why a request of constants alone is refused (the reader's and [`super::request`]'s one message): a map gives the
/// size of the outputs.
pub const NO_MAP_GIVEN: &str = "every parameter is a constant, so there is no map size: expected at least one map \
     (params, or a parameter's own map: at least one array or file); for one material, evaluate it instead";

/// The largest image accepted or written, in texels (16384 x 16384). Larger headers are rejected before any
/// allocation, so a corrupt size field gives an error instead of an out-of-memory abort.
pub const MAX_TEXELS: usize = 1 << 28;

/// Every image, array and map of `width x height` texels, read, given or written, must have 1 to [`MAX_TEXELS`]
/// texels; `what` names it in the error.
pub fn check_texel_count(what: impl Into<String>, width: usize, height: usize) -> Result<(), crate::error::SkinError> {
    if width == 0 || height == 0 || width.checked_mul(height).map_or(true, |n| n > MAX_TEXELS) {
        return Err(crate::error::SkinError::invalid(
            what,
            format!("expected 1 to {MAX_TEXELS} texels (16384 x 16384); got {width} wide x {height} high"),
        ));
    }
    Ok(())
}

/// One parameter's source.
#[derive(Debug, Clone, PartialEq)]
pub enum ParamSource {
    /// A one-parameter image, any of [`PARAM_IMAGE_FORMS`]: an EXR (values taken as the parameter itself) or an
    /// 8/16-bit PNG, TIFF or JPEG (mapped 0..1 onto the parameter's range, see [`PARAM_RANGES`]).
    File(PathBuf),
    /// The same value everywhere, in the parameter's own unit (not range-checked here).
    Constant(f64),
}

/// Where the four parameters come from.
#[derive(Debug, Clone, PartialEq)]
pub enum ParamInputs {
    /// One EXR with channels named as in [`PARAM_CHANNELS`] (all four required unless `constants` gives the missing
    /// ones). A constant given for a channel that the file also has overrides that channel (it is not read).
    Multi { path: PathBuf, constants: [Option<f64>; 4] },
    /// One source per parameter, in [`PARAM_CHANNELS`] order.
    Separate([ParamSource; 4]),
    /// The paper's four from `inputs` (a `Multi` or `Separate`), the extended physiology from `extended`, in
    /// [`EXTENDED_CHANNELS`] order: a constant, a single-channel file (as a `Separate` source, of the same size), or
    /// None: the channel of that name in a `Multi` file if it has one, else the parameter's default. `Multi` and
    /// `Separate` alone are this with every entry None.
    Extended { inputs: Box<ParamInputs>, extended: [Option<ParamSource>; 3] },
}

/// A parameter plane: per-texel values, or one constant.
#[derive(Debug, Clone, PartialEq)]
pub enum Plane {
    /// `width * height` values, row-major, row 0 at the top.
    Texels(Vec<f32>),
    /// One value for every texel.
    Constant(f32),
}

impl Plane {
    /// The value of texel `index` (row-major). Panics if `index` is out of bounds of a `Texels` plane.
    #[inline]
    pub fn value(&self, index: usize) -> f32 {
        match self {
            Plane::Texels(values) => values[index],
            Plane::Constant(value) => *value,
        }
    }

    /// True for a constant plane.
    pub fn is_constant(&self) -> bool {
        matches!(self, Plane::Constant(_))
    }
}

/// The loaded parameters: row-major planes of width x height (row 0 at the top, as EXR stores it), in
/// [`PARAM_CHANNELS`] order, each in the parameter's own unit (volume fraction / share, as in
/// [`crate::skin::SkinParams`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ParamImage {
    pub width: usize,
    pub height: usize,
    pub planes: [Plane; 4],
    /// The extended physiology, in [`EXTENDED_CHANNELS`] order (constants at the defaults unless a map or value gave
    /// them).
    pub extended: [Plane; 3],
    /// What the reader accepted but a user should know (an alpha channel ignored, channels of no parameter's name):
    /// one sentence each, naming the file; fronts show them as warnings.
    pub notes: Vec<String>,
}

/// The extended physiology at its defaults (the paper's values), as constant planes.
pub fn default_extended() -> [Plane; 3] {
    EXTENDED_DEFAULTS.map(|v| Plane::Constant(v as f32))
}

impl ParamImage {
    /// The paper's four planes, the extended physiology at its defaults.
    pub fn new(width: usize, height: usize, planes: [Plane; 4]) -> ParamImage {
        ParamImage { width, height, planes, extended: default_extended(), notes: Vec::new() }
    }

    /// Plane `p` of all seven, indexed as `crate::skin::params::PARAMS` (the four, then the extended physiology).
    pub fn plane(&self, p: usize) -> &Plane {
        if p < 4 {
            &self.planes[p]
        } else {
            &self.extended[p - 4]
        }
    }

    /// The plane of the parameter `spec` (one of `crate::skin::params::PARAMS`, found by name).
    pub fn plane_of(&self, spec: &ParamSpec) -> &Plane {
        let p = ALL_CHANNELS.iter().position(|name| *name == spec.name).expect("every parameter has a plane");
        self.plane(p)
    }

    /// Number of texels, `width * height`.
    pub fn texel_count(&self) -> usize {
        self.width * self.height
    }

    /// The four parameter values of texel `index` (row-major), in [`PARAM_CHANNELS`] order.
    #[inline]
    pub fn texel(&self, index: usize) -> [f32; 4] {
        [
            self.planes[0].value(index),
            self.planes[1].value(index),
            self.planes[2].value(index),
            self.planes[3].value(index),
        ]
    }
}

/// Output encoding: the sample precision and the compression of every written EXR. The default is half floats with
/// the compression chosen per file ([`Compression::Auto`]); see docs/maps-performance.md for the measured trade-off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct ExrOptions {
    /// Sample precision of the written files.
    pub precision: Precision,
    /// Lossless compression of the written files.
    pub compression: Compression,
}

impl ExrOptions {
    /// 32-bit floats, PIZ: the encoding of parameter maps written for the examples and tests (exact inputs).
    pub const FLOAT_PIZ: ExrOptions = ExrOptions { precision: Precision::Float, compression: Compression::Piz };
}

/// Sample precision of written EXRs. Python's `precision=` and the CLI's `--precision` take the serde names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum), value(rename_all = "snake_case"))]
#[serde(rename_all = "snake_case")]
pub enum Precision {
    /// 16-bit half floats, rounded to nearest: a relative error of at most 2^-11 (0.049 %) in half's normal range
    /// (6.1e-5 to 65504; larger values become infinite), and at most 3e-8 absolute below it.
    #[default]
    Half,
    /// 32-bit floats: the computed values as they are.
    Float,
}

/// Every precision, the default first.
pub const ALL_PRECISIONS: [Precision; 2] = [Precision::Half, Precision::Float];

/// Lossless EXR compression of written files. Python's `compression=` and the CLI's `--compression` take the serde
/// names. `Auto` (the default) compresses a sample of each file's blocks with the precision's candidate (ZIPS for
/// half, PIZ for float, see [`Compression::auto_candidate`]) and writes the file uncompressed when that would save less than
/// [`AUTO_MIN_SAVING`] of its size (maps that vary everywhere, like noise), else with the candidate. Figures:
/// docs/maps-performance.md.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum), value(rename_all = "snake_case"))]
#[serde(rename_all = "snake_case")]
pub enum Compression {
    /// ZIPS (half) or PIZ (float), or none, chosen per file from a sample of its blocks.
    #[default]
    Auto,
    /// PIZ wavelet compression, 32 scan lines per block (Blender's "PIZ").
    Piz,
    /// ZIP, 16 scan lines per block (OpenEXR `ZIP_COMPRESSION`, Blender's "ZIP").
    Zip,
    /// ZIP, one scan line per block (OpenEXR `ZIPS_COMPRESSION`, Blender's "ZIPS").
    Zips,
    /// Run-length encoding (OpenEXR `RLE_COMPRESSION`, Blender's "RLE").
    Rle,
    /// No compression.
    None,
}

/// Every compression, the default first.
pub const ALL_COMPRESSIONS: [Compression; 6] =
    [Compression::Auto, Compression::Piz, Compression::Zip, Compression::Zips, Compression::Rle, Compression::None];

/// [`Compression::Auto`] compresses a file only if its candidate shrinks a sample of its blocks by at least this share.
/// At 4096² (docs/maps-performance.md) smooth maps shrink by over 60 % (float, PIZ) and 90 % (half, ZIPS), while noise
/// shrinks by 8 % (float, PIZ) and 22 % (half, PIZ; 13 % with ZIPS in a run of `--compression zips`) at two to four
/// times the CPU time of the uncompressed run: the threshold keeps such maps uncompressed.
pub const AUTO_MIN_SAVING: f64 = 0.25;

impl Compression {
    /// The codec [`Compression::Auto`] tries for `precision`: ZIPS for half (on the 4096² face, 7.8 MB against PIZ's
    /// 12.7 MB at the same CPU time), PIZ for float (ZIP is a few per cent smaller there at about 1.5 times the CPU).
    pub fn auto_candidate(precision: Precision) -> Compression {
        match precision {
            Precision::Half => Compression::Zips,
            Precision::Float => Compression::Piz,
        }
    }

    /// The exr crate's compression; `None` for `Auto`, which is resolved per file first.
    fn to_exr(self) -> Option<exr::compression::Compression> {
        use exr::compression::Compression as C;
        match self {
            Compression::Auto => None,
            Compression::Piz => Some(C::PIZ),
            Compression::Zip => Some(C::ZIP16),
            Compression::Zips => Some(C::ZIP1),
            Compression::Rle => Some(C::RLE),
            Compression::None => Some(C::Uncompressed),
        }
    }
}

/// Run a decoder, turning a panic inside a third-party decoder (on a corrupt file) into an error message.
fn guard<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    catch_unwind(AssertUnwindSafe(f)).map_err(|payload| {
        let text = crate::numeric::panic_message(payload.as_ref()).unwrap_or_else(|| "decoder panicked".to_string());
        format!("corrupt file: {text}")
    })
}
