//! The files this process reads, in one set (`snake_core::files`'s): Rust's readers (robots, URDFs,
//! worlds, heightfields, targets, models) add to it as they read, the Python package's readers
//! (`snakesim.files`) through `remember_input`, and every output check of the `snakesim` command and
//! library asks `is_input` before writing, so that no output replaces a file the run reads, however
//! its path is spelled (links and hard links included).

use std::path::PathBuf;

use pyo3::prelude::*;

/// is_input(path) -> True when `path` (after links) is a file this process has read as an input.
#[pyfunction]
fn is_input(path: PathBuf) -> bool {
    snake_core::files::is_input(&path)
}

/// remember_input(path): `path` (after links) joins the files this process has read.
#[pyfunction]
fn remember_input(path: PathBuf) {
    snake_core::files::remember_input_path(&path)
}

/// forget_input(path): `path` leaves the files this process has read, for a writer that replaces its
/// own earlier output after reading it (a run's state: its configuration, a sweep's manifest).
#[pyfunction]
fn forget_input(path: PathBuf) {
    snake_core::files::forget_input(&path)
}

/// Adds `is_input`, `remember_input` and `forget_input` to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(is_input, m)?)?;
    m.add_function(wrap_pyfunction!(remember_input, m)?)?;
    m.add_function(wrap_pyfunction!(forget_input, m)?)
}
