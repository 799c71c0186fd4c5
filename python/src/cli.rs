//! The `mstar` command of the Python package (`[project.scripts]`,
//! `mstar/_cli.py`): the command-line program itself,
//! [`mstar_cli::main_from`], in the script's process.

use std::ffi::OsString;

use pyo3::prelude::*;

/// Runs the command-line program with the arguments `argv` (without the
/// program's name, which is `mstar`), GIL released: its output on the
/// process's standard output and error, its exit code returned. It installs
/// its own signal handlers (Ctrl-C stops it as it stops the program), so it
/// is for a process that ends after it: the console script.
#[pyfunction]
pub(crate) fn cli_main(py: Python<'_>, argv: Vec<OsString>) -> u8 {
    let args = std::iter::once(OsString::from("mstar")).chain(argv);
    py.detach(|| mstar_cli::main_from(args))
}
