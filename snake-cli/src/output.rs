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

/// An output file being written: checked up front, written to a temporary file, and moved to the
/// target by [`OutputFile::commit`]; dropped uncommitted, it leaves the target as it was.
///
/// What the target may be:
/// - a new path, or a regular file: the temporary file sits beside it and is renamed over it; a
///   link to a regular file keeps the link and replaces the file it points to;
/// - a character device (`/dev/null`, a terminal) or a FIFO that someone reads: written through,
///   never replaced by a file;
/// - never a FIFO that nobody reads, a socket or block device, a directory, or a file this run read
///   as an input
///   (`--output` onto the robot file), whatever path names it: refused in one line.
#[derive(Debug)]
pub struct OutputFile {
    path: PathBuf,
    temp: PathBuf,
    /// The target, open, when it is a character device or a FIFO: the contents are copied into it,
    /// not renamed over it. (Opened up front and held: a FIFO's reader would see the end of the
    /// stream if it were closed and opened again.)
    through: Option<std::fs::File>,
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
        let (target, through) = check_target(path, what)?;
        // The temporary file keeps the extension, for writers that choose the format by it; for a
        // device it goes to the temporary directory, not beside the device.
        let temp_name = match &ext {
            Some(ext) => format!(".{name}.partial{}.{ext}", std::process::id()),
            None => format!(".{name}.partial{}", std::process::id()),
        };
        let temp = if through.is_some() {
            std::env::temp_dir().join(format!("snake-cli{temp_name}"))
        } else {
            target.with_file_name(temp_name)
        };
        std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&temp)
            .with_context(|| format!("cannot write {what} to {shown}"))?;
        Ok(OutputFile {
            path: target,
            temp,
            through,
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

    /// Moves the finished contents to the target (renamed over a file, copied into a device).
    pub fn commit(mut self) -> Result<()> {
        let shown = self.path.display();
        if snake_core::files::is_input(&self.path) {
            bail!("cannot write {shown}: it is one of this run's inputs");
        }
        if let Some(device) = self.through.take() {
            let contents =
                std::fs::read(&self.temp).with_context(|| format!("cannot write {shown}"))?;
            write_through(device, &contents).with_context(|| format!("cannot write {shown}"))?;
            // The temporary file is removed on drop.
            return Ok(());
        }
        std::fs::rename(&self.temp, &self.path).with_context(|| format!("cannot write {shown}"))?;
        self.committed = true;
        Ok(())
    }
}

/// Writes `bytes` into a device or FIFO opened without blocking: a full pipe is waited on, a millisecond
/// at a time, until its reader takes more.
fn write_through(mut device: std::fs::File, mut bytes: &[u8]) -> io::Result<()> {
    while !bytes.is_empty() {
        match device.write(bytes) {
            Ok(0) => return Err(io::ErrorKind::WriteZero.into()),
            Ok(n) => bytes = &bytes[n..],
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                std::thread::sleep(std::time::Duration::from_millis(1))
            }
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    device.flush()
}

/// Where an output at `path` goes and, for a character device or a FIFO, the target opened for
/// writing through; refuses what must not be written (see [`OutputFile`]).
fn check_target(path: &Path, what: &str) -> Result<(PathBuf, Option<std::fs::File>)> {
    use std::os::unix::fs::FileTypeExt;
    use std::os::unix::fs::OpenOptionsExt;
    let shown = path.display();
    let meta = match std::fs::metadata(path) {
        Ok(meta) => meta,
        // A new file (or a link to nothing, which the file replaces).
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok((path.to_path_buf(), None)),
        Err(e) => bail!("cannot write {what} to {shown}: {e}"),
    };
    let kind = meta.file_type();
    if kind.is_dir() {
        bail!("cannot write {what} to {shown}: it is a directory");
    }
    if snake_core::files::is_input(path) {
        bail!("cannot write {what} to {shown}: it is one of this run's inputs");
    }
    if kind.is_char_device() || kind.is_fifo() {
        // Opened without blocking, so that a FIFO nobody reads is refused now rather than waited on
        // at the end of the run.
        return match std::fs::OpenOptions::new()
            .write(true)
            .custom_flags(libc::O_NONBLOCK)
            .open(path)
        {
            Ok(file) => Ok((path.to_path_buf(), Some(file))),
            Err(e) if e.raw_os_error() == Some(libc::ENXIO) => {
                bail!("cannot write {what} to {shown}: a FIFO that nobody reads")
            }
            Err(e) => bail!("cannot write {what} to {shown}: {e}"),
        };
    }
    if !kind.is_file() {
        bail!(
            "cannot write {what} to {shown}: not a regular file (a socket or block device); give a \
             file path"
        );
    }
    // A link to a regular file: replace the file, keep the link.
    let target = if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) {
        path.canonicalize()
            .with_context(|| format!("cannot write {what} to {shown}"))?
    } else {
        path.to_path_buf()
    };
    Ok((target, None))
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
    fn devices_are_written_through_and_fifos_refused_never_replaced() {
        use std::os::unix::fs::FileTypeExt;
        let out = OutputFile::new(Path::new("/dev/null"), "trajectory", &[]).unwrap();
        assert!(
            !out.temp_path().starts_with("/dev"),
            "no temporary file in /dev"
        );
        std::fs::write(out.temp_path(), "rows").unwrap();
        out.commit().unwrap();
        let full = OutputFile::new(Path::new("/dev/full"), "trajectory", &[]).unwrap();
        std::fs::write(full.temp_path(), "rows").unwrap();
        let e = full.commit().unwrap_err();
        assert!(format!("{e:#}").contains("No space left"), "{e:#}");
        for device in ["/dev/null", "/dev/full"] {
            let kind = std::fs::metadata(device).unwrap().file_type();
            assert!(kind.is_char_device(), "{device} is still a device");
        }
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("pipe.csv");
        assert!(std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success());
        let e = OutputFile::new(&fifo, "trajectory", &[]).unwrap_err();
        assert!(e.to_string().contains("a FIFO that nobody reads"), "{e}");
        // With a reader, the contents go through the FIFO.
        let reader = std::thread::spawn({
            let fifo = fifo.clone();
            move || std::fs::read_to_string(fifo).unwrap()
        });
        let out = loop {
            match OutputFile::new(&fifo, "trajectory", &[]) {
                Ok(out) => break out,
                Err(_) => std::thread::sleep(std::time::Duration::from_millis(10)),
            }
        };
        std::fs::write(out.temp_path(), "rows\n").unwrap();
        out.commit().unwrap();
        assert_eq!(reader.join().unwrap(), "rows\n");
        assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
    }

    #[test]
    fn a_link_keeps_pointing_at_the_file_it_replaces() {
        let dir = tempfile::tempdir().unwrap();
        let real = dir.path().join("real.csv");
        let link = dir.path().join("link.csv");
        std::fs::write(&real, "old").unwrap();
        std::os::unix::fs::symlink(&real, &link).unwrap();
        let out = OutputFile::new(&link, "trajectory", &[]).unwrap();
        std::fs::write(out.temp_path(), "new").unwrap();
        out.commit().unwrap();
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(std::fs::read_to_string(&real).unwrap(), "new");
    }

    #[test]
    fn an_input_of_the_run_is_never_an_output() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("robot.yaml");
        std::fs::write(&input, "urdf: r.urdf\n").unwrap();
        snake_core::files::read_text(&input, 1000, "robot file").unwrap();
        let other_name = dir.path().join(".").join("robot.yaml");
        let e = OutputFile::new(&other_name, "trajectory", &[]).unwrap_err();
        assert!(e.to_string().contains("one of this run's inputs"), "{e}");
        assert_eq!(std::fs::read_to_string(&input).unwrap(), "urdf: r.urdf\n");
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
