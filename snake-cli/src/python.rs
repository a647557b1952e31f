//! Finding the project's Python (the snakesim package: Rerun recordings; pybullet: benchmarks).

use std::path::{Path, PathBuf};

/// A Python of the project: `explicit`, else $SNAKESIM_PYTHON, else .venv/bin/python here or in the repository.
pub(crate) fn find_python(explicit: Option<&Path>) -> Option<PathBuf> {
    if let Some(p) = explicit {
        return Some(p.to_path_buf());
    }
    if let Some(p) = std::env::var_os("SNAKESIM_PYTHON") {
        return Some(PathBuf::from(p));
    }
    let here = PathBuf::from(".venv/bin/python");
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../.venv/bin/python");
    [here, repo].into_iter().find(|p| p.exists())
}
