//! `snake-cli run --rrd`: a Rerun recording of the run, made by the snakesim Python package.
//!
//! snake-cli writes the physics trace (see [`crate::trace`]) and `snakesim convert` logs it with
//! Rerun's Python SDK. Rerun's Rust SDK is not linked in: its current release (0.41, the viewer's
//! version in requirements.lock) needs a newer Rust than this project's toolchain, and the newest one
//! that builds here pulls in ~540 crates against the workspace's ~190 (measured figures in docs/architecture.md, "Rerun recordings from `snake-cli run --rrd`").

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use anyhow::{bail, Context, Result};

use crate::output::OutputFile;

/// How to run `snakesim`: a Python with the package (`python -m snakesim`) or the command itself.
#[derive(Debug)]
pub struct Converter {
    program: PathBuf,
    prefix: Vec<OsString>,
}

/// What to say when there is no converter.
const HOW_TO_GET_IT: &str = "--rrd needs the snakesim Python package with rerun-sdk: run \
    `bash scripts/setup` (it creates .venv), or set SNAKESIM_PYTHON to a Python that has them";

impl Converter {
    /// Finds `snakesim` ($SNAKESIM_PYTHON, .venv/bin/python here or in the repository, else the
    /// `snakesim` command on PATH) and checks that it can make recordings.
    pub fn find() -> Result<Self> {
        let candidate = match crate::python::find_python(None) {
            Some(python) => Converter {
                program: python,
                prefix: vec!["-m".into(), "snakesim".into()],
            },
            None => match find_on_path("snakesim") {
                Some(program) => Converter {
                    program,
                    prefix: Vec::new(),
                },
                None => bail!("{HOW_TO_GET_IT}"),
            },
        };
        let ok = Command::new(&candidate.program)
            .args(&candidate.prefix)
            .args(["convert", "--check"])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            bail!(
                "{HOW_TO_GET_IT} ({} cannot make recordings)",
                candidate.program.display()
            );
        }
        Ok(candidate)
    }

    /// `snakesim convert TRACE --rrd WRITE_TO`; errors carry its one-line message.
    pub fn convert(&self, trace: &Path, write_to: &Path, shown: &Path) -> Result<()> {
        let out = Command::new(&self.program)
            .args(&self.prefix)
            .arg("convert")
            .arg(trace)
            .arg("--rrd")
            .arg(write_to)
            .arg("--quiet")
            .stdin(Stdio::null())
            .output()
            .with_context(|| format!("cannot run {}", self.program.display()))?;
        if !out.status.success() {
            let stderr = String::from_utf8_lossy(&out.stderr);
            let last = stderr.lines().rev().find(|l| !l.trim().is_empty());
            bail!(
                "cannot write recording to {}: {}",
                shown.display(),
                last.unwrap_or("snakesim convert failed")
                    .trim_start_matches("snakesim convert: error: ")
            );
        }
        Ok(())
    }
}

fn find_on_path(name: &str) -> Option<PathBuf> {
    std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|dir| dir.join(name))
            .find(|p| p.is_file())
    })
}

/// Refuses a run longer than a recording holds (`flag`: --rrd or --trace, whose file it would be).
pub fn check_seconds(flag: &str, seconds: f64) -> Result<()> {
    let max = snake_core::limits::MAX_RECORDING_SECONDS;
    if seconds > max {
        bail!("{flag} records at most {max} simulated seconds, got --seconds {seconds}");
    }
    Ok(())
}

/// Where the physics trace goes: the user's --trace file, or a temporary one for --rrd alone.
pub enum TraceFile {
    /// `--trace PATH`, written through a temporary file.
    Output(OutputFile),
    /// Removed when dropped.
    Temporary(tempfile::TempPath),
}

impl TraceFile {
    /// A temporary trace file.
    pub fn temporary() -> Result<Self> {
        let file = tempfile::Builder::new()
            .prefix("snakesim-trace-")
            .suffix(".csv")
            .tempfile()
            .context("cannot create a temporary trace file")?;
        Ok(TraceFile::Temporary(file.into_temp_path()))
    }

    /// Where the rows are written.
    pub fn write_path(&self) -> &Path {
        match self {
            TraceFile::Output(f) => f.temp_path(),
            TraceFile::Temporary(p) => p,
        }
    }

    /// The name errors show.
    pub fn shown_path(&self) -> &Path {
        match self {
            TraceFile::Output(f) => f.path(),
            TraceFile::Temporary(p) => p,
        }
    }

    /// Puts a --trace file in place; returns where the finished trace is (kept alive by the result).
    pub fn commit(self) -> Result<FinishedTrace> {
        match self {
            TraceFile::Output(f) => {
                let path = f.path().to_path_buf();
                f.commit()?;
                Ok(FinishedTrace::Kept(path))
            }
            TraceFile::Temporary(p) => Ok(FinishedTrace::Temporary(p)),
        }
    }
}

/// A complete trace file.
pub enum FinishedTrace {
    /// The user's file.
    Kept(PathBuf),
    /// Removed when dropped.
    Temporary(tempfile::TempPath),
}

impl std::ops::Deref for FinishedTrace {
    type Target = Path;
    fn deref(&self) -> &Path {
        match self {
            FinishedTrace::Kept(p) => p,
            FinishedTrace::Temporary(p) => p,
        }
    }
}
