//! The `spectral-skin` command: every subcommand, its errors and exit codes, and `fit --maps`.
//!
//! One test crate of several modules: linked once (see docs/tests.md).

#[path = "../support/mod.rs"]
mod support;

mod cli;
mod cli_fit_maps;
