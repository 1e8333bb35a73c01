//! The one error type of the core. Every message names the input, the allowed range and what was received.

use thiserror::Error;

/// Errors the core reports for invalid input. No function of the core panics on bad input.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum SkinError {
    /// A scalar parameter is outside its allowed range or not finite.
    #[error("{name} must be in [{min}, {max}] ({meaning}); got {value}")]
    OutOfRange {
        name: &'static str,
        meaning: &'static str,
        min: f64,
        max: f64,
        value: f64,
    },
    /// An input that is not a single range (a layer list, a radius grid, a preset name) is invalid.
    #[error("invalid {name}: {reason}")]
    Invalid { name: String, reason: String },
    /// A file could not be read or written.
    #[error("{path}: {reason}")]
    Io { path: String, reason: String },
}

impl SkinError {
    pub(crate) fn io(path: &std::path::Path, reason: impl std::fmt::Display) -> Self {
        SkinError::Io { path: path.display().to_string(), reason: reason.to_string() }
    }

    pub(crate) fn invalid(name: impl Into<String>, reason: impl Into<String>) -> Self {
        SkinError::Invalid { name: name.into(), reason: reason.into() }
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
