//! Fits from colours and spectra back to physiology: albedo inversion, the exposure and white-balance gains, recovery
//! of known parameters, measured in-vivo spectra.
//!
//! One test crate of several modules: linked once (see docs/tests.md).

#[path = "../support/mod.rs"]
mod support;

mod inverse_albedo;
mod inverse_gains;
mod inverse_recovery;
mod measured_spectra;
mod palette;
