//! Where snake-cli's results go: standard output that fails with an error instead of a panic, and
//! files that are written whole or not at all.
//!
//! - `say!` prints a line; a closed pipe (`snake-cli env ... | head -1`) or a full disk comes back as
//!   an error. `main` ends quietly with success on a closed pipe, like other Unix tools, and reports
//!   anything else in one line.
//! - [`OutputFile`] checks an output path before any simulation time is spent (its format, that it is
//!   not a directory, that its directory takes a new file) and writes through a temporary file beside
//!   it that is renamed over the target only when complete: a failed run never truncates or replaces
//!   an existing file.

use std::fmt;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

/// Prints one line to standard output, returning an error (never panicking) when it cannot.
macro_rules! say {
    ($($arg:tt)*) => {
        $crate::output::say_line(format_args!($($arg)*))
    };
}
pub(crate) use say;

/// A failed write to standard output.
#[derive(Debug)]
pub struct StdoutError(io::Error);

impl fmt::Display for StdoutError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "cannot write to standard output: {}", self.0)
    }
}

impl std::error::Error for StdoutError {}

/// What `say!` calls: the line, then a flush, so that an error shows at the line that caused it.
pub fn say_line(args: fmt::Arguments<'_>) -> Result<()> {
    let mut out = io::stdout().lock();
    out.write_fmt(args)
        .and_then(|()| out.write_all(b"\n"))
        .and_then(|()| out.flush())
        .map_err(|e| StdoutError(e).into())
}

/// True when `error` is standard output's reader having gone away (a closed pipe).
pub fn is_closed_pipe(error: &anyhow::Error) -> bool {
    error
        .chain()
        .filter_map(|e| e.downcast_ref::<StdoutError>())
        .any(|e| e.0.kind() == io::ErrorKind::BrokenPipe)
}

/// An output file being written: checked up front, written to a temporary file beside the target,
/// renamed over the target by [`OutputFile::commit`]; dropped uncommitted, it leaves the target as
/// it was.
#[derive(Debug)]
pub struct OutputFile {
    path: PathBuf,
    temp: PathBuf,
    committed: bool,
}

impl OutputFile {
    /// Checks that `path` can be written as `what` (e.g. "plot"), with one of `extensions` when that
    /// is not empty (compared without case), and creates the temporary file it is written through.
    pub fn new(path: &Path, what: &str, extensions: &[&str]) -> Result<Self> {
        let shown = path.display();
        let Some(name) = path.file_name().map(|n| n.to_string_lossy().into_owned()) else {
            bail!("cannot write {what} to {shown}: not a file name");
        };
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        if !extensions.is_empty()
            && !ext
                .as_deref()
                .is_some_and(|e| extensions.iter().any(|x| x.eq_ignore_ascii_case(e)))
        {
            bail!(
                "cannot write {what} to {shown}: the file name must end in .{}",
                extensions.join(" or .")
            );
        }
        if path.is_dir() {
            bail!("cannot write {what} to {shown}: it is a directory");
        }
        // The temporary file keeps the extension, for writers that choose the format by it.
        let temp_name = match &ext {
            Some(ext) => format!(".{name}.partial{}.{ext}", std::process::id()),
            None => format!(".{name}.partial{}", std::process::id()),
        };
        let temp = path.with_file_name(temp_name);
        std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&temp)
            .with_context(|| format!("cannot write {what} to {shown}"))?;
        Ok(OutputFile {
            path: path.to_path_buf(),
            temp,
            committed: false,
        })
    }

    /// Where to write the contents.
    pub fn temp_path(&self) -> &Path {
        &self.temp
    }

    /// The file it becomes.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Moves the finished contents over the target.
    pub fn commit(mut self) -> Result<()> {
        std::fs::rename(&self.temp, &self.path)
            .with_context(|| format!("cannot write {}", self.path.display()))?;
        self.committed = true;
        Ok(())
    }
}

impl Drop for OutputFile {
    fn drop(&mut self) {
        if !self.committed {
            // Best effort: the temporary file is ours alone (its name has our process id).
            let _ = std::fs::remove_file(&self.temp);
        }
    }
}

/// Refuses two outputs that name the same file (`--output x --plot x`): one would silently replace
/// the other. `outputs` are (flag, path) pairs.
pub fn check_distinct(outputs: &[(&str, &Path)]) -> Result<()> {
    let key = |p: &Path| -> PathBuf {
        // The same file under different spellings (`x.png`, `./x.png`, a link): compare where it is.
        let absolute = if p.is_absolute() {
            p.to_path_buf()
        } else {
            std::env::current_dir()
                .map(|d| d.join(p))
                .unwrap_or_else(|_| p.to_path_buf())
        };
        match (absolute.parent(), absolute.file_name()) {
            (Some(dir), Some(name)) => dir
                .canonicalize()
                .map(|d| d.join(name))
                .unwrap_or(absolute.clone()),
            _ => absolute,
        }
    };
    for (i, (flag_a, a)) in outputs.iter().enumerate() {
        for (flag_b, b) in &outputs[i + 1..] {
            if key(a) == key(b) {
                bail!(
                    "{flag_a} and {flag_b} name the same file {}; give each its own path",
                    a.display()
                );
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uncommitted_output_leaves_the_existing_file_alone() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("keep.csv");
        std::fs::write(&target, "precious").unwrap();
        let out = OutputFile::new(&target, "trajectory", &[]).unwrap();
        std::fs::write(out.temp_path(), "half a file").unwrap();
        drop(out);
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "precious");
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            1,
            "no temporary file left"
        );
    }

    #[test]
    fn committed_output_replaces_the_target() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("run.csv");
        std::fs::write(&target, "old").unwrap();
        let out = OutputFile::new(&target, "trajectory", &[]).unwrap();
        std::fs::write(out.temp_path(), "new").unwrap();
        out.commit().unwrap();
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "new");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn wrong_extension_and_directories_are_refused_before_anything_is_created() {
        let dir = tempfile::tempdir().unwrap();
        let keep = dir.path().join("keep.txt");
        std::fs::write(&keep, "precious").unwrap();
        let e = OutputFile::new(&keep, "plot", &["png"]).unwrap_err();
        assert!(e.to_string().contains("must end in .png"), "{e}");
        let e = OutputFile::new(dir.path(), "plot", &[]).unwrap_err();
        assert!(e.to_string().contains("directory"), "{e}");
        assert!(OutputFile::new(&dir.path().join("x.PNG"), "plot", &["png"]).is_ok());
        assert_eq!(std::fs::read_to_string(&keep).unwrap(), "precious");
    }

    #[test]
    fn the_same_file_twice_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("x.png");
        let b = dir.path().join(".").join("x.png");
        let e = check_distinct(&[("--output", &a), ("--plot", &b)]).unwrap_err();
        assert!(e.to_string().contains("--output and --plot"), "{e}");
        check_distinct(&[("--output", &a), ("--plot", &dir.path().join("y.png"))]).unwrap();
    }
}
