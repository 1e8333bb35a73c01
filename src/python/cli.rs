//! The `spectral-skin` command a `pip install` of the wheel puts on PATH: `spectral_skin._cli:main` (the
//! `[project.scripts]` entry of pyproject.toml) runs the core's command line ([`crate::cli`]) in the Python process.

use std::ffi::OsString;
use std::panic::{catch_unwind, AssertUnwindSafe};

use pyo3::prelude::*;

use super::errors::panic_error;

/// _cli_main(argv)
/// --
///
/// Run the ``spectral-skin`` command line on ``argv`` (the program's name first, as ``sys.argv``) and return its exit
/// status (0; 2 for an error, printed to stderr; 130 when stopped by Ctrl-C). The entry point of the console script
/// (``spectral_skin._cli``), not an API: the command line installs its own Ctrl-C handler, and help, ``--version``
/// and argument errors end the process.
#[pyfunction]
#[pyo3(name = "_cli_main")]
pub(super) fn cli_main_py(py: Python<'_>, argv: Vec<OsString>) -> PyResult<u8> {
    py.detach(|| catch_unwind(AssertUnwindSafe(|| crate::cli::main(argv)))).map_err(panic_error)
}
