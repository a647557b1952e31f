//! One writer per folder, for Python: the run directory's and the sweep folder's writer lock
//! (`snake_rl::lock`), held by a Python object for as long as the writer lives.

use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Duration;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use snake_rl::lock::WriterLock;

/// The exclusive right to write a folder (`writer.lock` inside it), taken by [`lock_run_dir`] or
/// [`lock_folder`]. Released by `release()`, at the end of a `with` block, when collected, or when
/// the process ends, however it ends.
#[pyclass(module = "snakesim._core", name = "WriterLock")]
pub struct PyWriterLock {
    folder: PathBuf,
    // None once released, and while the native trainer holds it (see `take`).
    inner: Mutex<Option<WriterLock>>,
}

impl PyWriterLock {
    fn new(lock: WriterLock) -> Self {
        PyWriterLock {
            folder: lock.folder().to_path_buf(),
            inner: Mutex::new(Some(lock)),
        }
    }

    /// Takes the lock out for a native caller (it is put back with [`PyWriterLock::put_back`]).
    pub fn take(&self) -> PyResult<WriterLock> {
        self.inner
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .take()
            .ok_or_else(|| {
                PyValueError::new_err(format!(
                    "the writer lock of {} was released",
                    self.folder.display()
                ))
            })
    }

    /// Gives back what [`PyWriterLock::take`] took.
    pub fn put_back(&self, lock: WriterLock) {
        *self.inner.lock().unwrap_or_else(|p| p.into_inner()) = Some(lock);
    }
}

#[pymethods]
impl PyWriterLock {
    /// The folder it guards.
    #[getter]
    fn folder(&self) -> String {
        self.folder.display().to_string()
    }

    /// True while held.
    #[getter]
    fn held(&self) -> bool {
        self.inner
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .is_some()
    }

    /// Lets go of the folder (nothing happens the second time).
    fn release(&self) {
        self.inner.lock().unwrap_or_else(|p| p.into_inner()).take();
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    #[pyo3(signature = (*_args))]
    fn __exit__(&self, _args: &Bound<'_, pyo3::types::PyTuple>) -> bool {
        self.release();
        false
    }

    fn __repr__(&self) -> String {
        format!(
            "WriterLock({:?}, held={})",
            self.folder.display().to_string(),
            if self.held() { "True" } else { "False" }
        )
    }
}

/// lock_run_dir(path, new_run) -> WriterLock: the run directory's writer lock, taken before anything
/// in it is read or written. A new run's folder must be absent or empty (it is created); a resumed
/// run's must exist. ValueError (one line, naming the process that writes it) when it is in use.
#[pyfunction]
fn lock_run_dir(py: Python<'_>, path: PathBuf, new_run: bool) -> PyResult<PyWriterLock> {
    py.detach(|| snake_rl::rundir::lock_run_dir(&path, new_run))
        .map(PyWriterLock::new)
        .map_err(|e| PyValueError::new_err(e.0))
}

/// lock_folder(path, what, wait_seconds=0.0) -> WriterLock: the writer lock of an existing folder (a
/// sweep's), waiting up to `wait_seconds` for its holder to finish. ValueError (one line, naming the
/// holder) when it stays in use.
#[pyfunction]
#[pyo3(signature = (path, what, wait_seconds = 0.0))]
fn lock_folder(
    py: Python<'_>,
    path: PathBuf,
    what: &str,
    wait_seconds: f64,
) -> PyResult<PyWriterLock> {
    if !(0.0..=86_400.0).contains(&wait_seconds) {
        return Err(PyValueError::new_err(format!(
            "wait_seconds must be in [0, 86400], got {wait_seconds}"
        )));
    }
    let wait = Duration::from_secs_f64(wait_seconds);
    py.detach(|| WriterLock::acquire_waiting(&path, what, wait))
        .map(PyWriterLock::new)
        .map_err(|e| PyValueError::new_err(e.0))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyWriterLock>()?;
    m.add_function(wrap_pyfunction!(lock_run_dir, m)?)?;
    m.add_function(wrap_pyfunction!(lock_folder, m)?)?;
    m.add("LOCK_FILE", snake_rl::lock::LOCK_FILE)?;
    Ok(())
}
