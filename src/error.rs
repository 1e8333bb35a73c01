//! The one error type of the core. Every message names the input, the allowed range and what was received.

use thiserror::Error;

/// Errors the core reports for invalid input. No function of the core panics on bad input.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum SkinError {
    /// A scalar parameter is outside its allowed range or not finite.
    #[error("{name} must be in [{}, {}] ({meaning}); got {}", Number(*.min), Number(*.max), Number(*.value))]
    OutOfRange { name: &'static str, meaning: &'static str, min: f64, max: f64, value: f64 },
    /// An input that is not a single range (a layer list, a radius grid, a preset name) is invalid.
    #[error("invalid {name}: {reason}")]
    Invalid { name: String, reason: String },
    /// A file could not be read or written. `source` is the operating system's error where there is one (its text is
    /// part of `reason` too, so the message alone says everything).
    #[error("{path}: {reason}")]
    Io {
        path: String,
        reason: String,
        #[source]
        source: Option<IoSource>,
    },
    /// A parameter map holds NaN, infinite or out-of-range texels and clamping is off. The fields let each front
    /// word its own way to enable clamping (the CLI's `--clamp`, Python's `clamp=True`, the add-on's checkbox).
    #[error(
        "{}",
        bad_texels_message(.parameter, *.min, *.max, [*.nan, *.infinite, *.out_of_range], .first, "enable clamping")
    )]
    BadTexels {
        parameter: String,
        min: f32,
        max: f32,
        nan: usize,
        infinite: usize,
        out_of_range: usize,
        /// The first few bad texels as (x, y), y = 0 at the top row.
        first: Vec<(usize, usize)>,
    },
    /// A parameter given as one value for every texel of a map is NaN, infinite or out of range, and clamping is off.
    /// As [`SkinError::BadTexels`], each front words its own way to enable clamping.
    #[error("{}", bad_constant_message(.parameter, *.min, *.max, *.value, "enable clamping"))]
    BadConstant { parameter: &'static str, min: f64, max: f64, value: f64 },
}

impl SkinError {
    /// Long work stopped by its cancel flag (Ctrl-C, a progress callback): what stopped, and that nothing it would
    /// have produced was kept. The fronts turn it into their own interruption (Python's KeyboardInterrupt, exit 130).
    pub(crate) fn interrupted(what: &str) -> Self {
        SkinError::invalid(what, "interrupted (cancelled) before it finished; nothing was kept")
    }

    /// `Err(interrupted(what))` once `cancel` is set.
    pub(crate) fn check_cancel(cancel: &std::sync::atomic::AtomicBool, what: &str) -> Result<(), SkinError> {
        if cancel.load(std::sync::atomic::Ordering::Relaxed) {
            return Err(SkinError::interrupted(what));
        }
        Ok(())
    }

    pub(crate) fn io(path: &std::path::Path, reason: impl std::fmt::Display) -> Self {
        SkinError::Io { path: path.display().to_string(), reason: reason.to_string(), source: None }
    }

    /// [`SkinError::io`] caused by `source`: `reason` words the failure (with the source's text), `source` keeps the
    /// error itself (its kind and OS error code) for callers.
    pub(crate) fn io_caused(path: &std::path::Path, reason: impl std::fmt::Display, source: std::io::Error) -> Self {
        SkinError::Io {
            path: path.display().to_string(),
            reason: reason.to_string(),
            source: Some(IoSource(std::sync::Arc::new(source))),
        }
    }

    pub(crate) fn invalid(name: impl Into<String>, reason: impl Into<String>) -> Self {
        SkinError::Invalid { name: name.into(), reason: reason.into() }
    }
}

/// The operating system's error behind a [`SkinError::Io`], shared so that the error stays `Clone`. Two are equal
/// when their kind and text are.
#[derive(Debug, Clone)]
pub struct IoSource(pub std::sync::Arc<std::io::Error>);

impl IoSource {
    /// The error itself.
    pub fn error(&self) -> &std::io::Error {
        &self.0
    }
}

impl std::fmt::Display for IoSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

impl std::error::Error for IoSource {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.0.source()
    }
}

impl PartialEq for IoSource {
    fn eq(&self, other: &Self) -> bool {
        self.0.kind() == other.0.kind() && self.0.to_string() == other.0.to_string()
    }
}

/// The message of [`SkinError::BadConstant`], with `enable` saying how to enable clamping.
fn bad_constant_message(parameter: &str, min: f64, max: f64, value: f64, enable: &str) -> String {
    format!("invalid {parameter}: must be in [{min}, {max}]; got {value} ({enable} to clamp it)")
}

/// The message of [`SkinError::BadTexels`], with `enable` saying how to enable clamping (e.g. "pass clamp=True").
fn bad_texels_message(
    parameter: &str,
    min: f32,
    max: f32,
    [nan, infinite, out_of_range]: [usize; 3],
    first: &[(usize, usize)],
    enable: &str,
) -> String {
    format!(
        "invalid {parameter} map: values must be in [{min}, {max}]; found {nan} NaN, {infinite} infinite and \
         {out_of_range} out-of-range texels, first at (x, y) {first:?}; {enable} to clamp them into range instead"
    )
}

impl SkinError {
    /// The message, with the advice on clamping (for [`SkinError::BadTexels`] and [`SkinError::BadConstant`]) worded for a front: `enable` is how
    /// to enable clamping there ("pass clamp=True", "use --clamp"). Other errors: their usual message.
    pub fn with_clamp_advice(&self, enable: &str) -> String {
        match self {
            SkinError::BadTexels { parameter, min, max, nan, infinite, out_of_range, first } => {
                bad_texels_message(parameter, *min, *max, [*nan, *infinite, *out_of_range], first, enable)
            }
            SkinError::BadConstant { parameter, min, max, value } => {
                bad_constant_message(parameter, *min, *max, *value, enable)
            }
            other => other.to_string(),
        }
    }
}

/// A number in a message: as Rust writes it (`0.5`, `-0.1`) where that is short, else in scientific notation
/// (`1e308`, `-1e-300` were written out with hundreds of digits).
pub struct Number(pub f64);

impl std::fmt::Display for Number {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let plain = self.0.to_string();
        if plain.len() <= 24 {
            f.write_str(&plain)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}

/// Check that `value` is finite and in `[min, max]`.
pub(crate) fn check_range(
    name: &'static str,
    meaning: &'static str,
    value: f64,
    min: f64,
    max: f64,
) -> Result<f64, SkinError> {
    if value.is_finite() && value >= min && value <= max {
        Ok(value)
    } else {
        Err(SkinError::OutOfRange { name, meaning, min, max, value })
    }
}
