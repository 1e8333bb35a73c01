//! Parameter maps in, texture maps out: reading the four parameter planes (EXR, PNG, TIFF or constants) and writing
//! scene-linear EXR outputs atomically.
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
//! Files, along the seams: `read.rs` (input sources: EXR, PNG, TIFF or bytes in memory, checked before decoding),
//! `encode.rs` (EXR encoding of output planes) and `staging.rs` (temporary files renamed into place together).

mod encode;
mod read;
mod staging;

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

pub use encode::{stage_channels_exr, stage_rgb_exr, write_channels_exr, write_rgb_exr};
pub use read::{read_exr_channels, read_params, read_params_from_bytes};
pub use staging::{commit_all, stage_bytes, write_atomic, Staged};

use crate::skin::params::PARAMS;

/// The names of the four parameters ([`PARAMS`]: melanin, melanin_blend, hemoglobin, oiliness). These are also the channel names
/// a multi-channel parameter EXR must use (exact, case-sensitive).
pub const PARAM_CHANNELS: [&str; 4] = [PARAMS[0].name, PARAMS[1].name, PARAMS[2].name, PARAMS[3].name];

/// The allowed range `(min, max)` of each parameter ([`PARAMS`]), in [`PARAM_CHANNELS`] order (unitless volume fractions and
/// shares). An integer PNG/TIFF value `v` of bit depth `b` maps to `min + (max - min) * v / (2^b - 1)`.
pub const PARAM_RANGES: [(f64, f64); 4] = [PARAMS[0].range(), PARAMS[1].range(), PARAMS[2].range(), PARAMS[3].range()];

/// The largest image accepted or written, in texels (16384 x 16384). Larger headers are rejected before any
/// allocation, so a corrupt size field gives an error instead of an out-of-memory abort.
pub const MAX_TEXELS: usize = 1 << 28;

/// One parameter's source.
#[derive(Debug, Clone, PartialEq)]
pub enum ParamSource {
    /// A single-channel image: an EXR (values taken as the parameter itself) or an 8/16-bit greyscale PNG or TIFF
    /// (mapped 0..1 onto the parameter's range, see [`PARAM_RANGES`]).
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
/// [`crate::SkinParams`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ParamImage {
    pub width: usize,
    pub height: usize,
    pub planes: [Plane; 4],
}

impl ParamImage {
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

/// Output encoding. The default is float (32-bit) samples with PIZ compression.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct ExrOptions {
    /// Write 16-bit half floats instead of 32-bit floats (values rounded to nearest; above 65504 become infinite).
    pub half: bool,
    /// Lossless compression of the written files.
    pub compression: Compression,
}

/// Lossless EXR compression of written files. PIZ is the default: faster than ZIP at about the same size. On maps that
/// hardly compress (noise) its Huffman coder is most of a run's CPU time, and `None` or half floats are the faster
/// choices (figures: docs/maps-performance.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Compression {
    /// ZIP, 16 scan lines per block (OpenEXR `ZIP_COMPRESSION`, Blender's "ZIP").
    Zip,
    /// PIZ wavelet compression (Blender's "PIZ").
    #[default]
    Piz,
    /// No compression.
    None,
}

impl Compression {
    fn to_exr(self) -> exr::compression::Compression {
        match self {
            Compression::Zip => exr::compression::Compression::ZIP16,
            Compression::Piz => exr::compression::Compression::PIZ,
            Compression::None => exr::compression::Compression::Uncompressed,
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
