//! One writer per folder: a run directory (or a sweep folder) is written by one process at a time.
//!
//! The writer holds an exclusive OS lock (`flock` on Linux, through [`std::fs::File::try_lock`]) on
//! `<folder>/writer.lock` for its whole life. The kernel releases it when the process ends, however it
//! ends (Ctrl-C, `kill -9`, a crash), so a killed writer's folder can be taken over at once and no stale
//! lock is ever left to clear by hand. The file itself stays (deleting a lock file races with a process
//! that has just opened it); it holds who has the lock, for the message a second writer gets. Readers
//! (evaluate, plot, replay) never take it: every file they read is written whole (through a temporary
//! file renamed into place) or appended a row at a time.

use std::fs::{File, OpenOptions};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// The lock file's name, inside the folder it guards.
pub const LOCK_FILE: &str = "writer.lock";

/// How often a waiting writer tries again.
const RETRY: Duration = Duration::from_millis(100);

/// The folder is written by another process, or its lock cannot be taken; the message says which.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct LockError(pub String);

/// The exclusive right to write a folder; released when dropped (or when the process ends).
#[derive(Debug)]
pub struct WriterLock {
    folder: PathBuf,
    // Held open for the lock's life: closing the file releases the lock.
    _file: File,
}

impl WriterLock {
    /// Takes the lock of `folder` (which must exist), or fails at once naming the process that holds
    /// it. `what` names the folder in messages ("run directory", "sweep folder").
    pub fn acquire(folder: &Path, what: &str) -> Result<Self, LockError> {
        Self::acquire_waiting(folder, what, Duration::ZERO)
    }

    /// As [`WriterLock::acquire`], but waits up to `wait` for the holder to finish.
    pub fn acquire_waiting(folder: &Path, what: &str, wait: Duration) -> Result<Self, LockError> {
        let path = folder.join(LOCK_FILE);
        let fail =
            |e: std::io::Error| LockError(format!("cannot lock {what} {}: {e}", folder.display()));
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(fail)?;
        let deadline = Instant::now() + wait;
        loop {
            match file.try_lock() {
                Ok(()) => break,
                Err(std::fs::TryLockError::WouldBlock) if Instant::now() < deadline => {
                    std::thread::sleep(RETRY);
                }
                Err(std::fs::TryLockError::WouldBlock) => {
                    let mut holder = String::new();
                    // A lock file holds one short line; read no more than a page of it.
                    let _ = (&file).take(4096).read_to_string(&mut holder);
                    let waited = if wait.is_zero() {
                        String::new()
                    } else {
                        format!(" (waited {:.1} s)", wait.as_secs_f64())
                    };
                    return Err(LockError(format!(
                        "{what} {} is being written by another process{waited}: {}; wait for it to \
                         end or stop it, then try again",
                        folder.display(),
                        describe_holder(&holder)
                    )));
                }
                Err(std::fs::TryLockError::Error(e)) => return Err(fail(e)),
            }
        }
        // Ours now: say who we are, for the message of the next one who tries.
        let me = holder_record();
        file.set_len(0)
            .and_then(|()| file.rewind())
            .and_then(|()| file.write_all(me.as_bytes()))
            .map_err(fail)?;
        Ok(WriterLock {
            folder: folder.to_path_buf(),
            _file: file,
        })
    }

    /// The folder this lock guards.
    pub fn folder(&self) -> &Path {
        &self.folder
    }
}

/// `pid 123 on host, since <unix seconds>: <command line>`, one line.
fn holder_record() -> String {
    let since = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|h| h.trim().to_owned())
        .unwrap_or_default();
    let mut command: String = std::env::args().collect::<Vec<_>>().join(" ");
    if command.chars().count() > 200 {
        command = command.chars().take(200).collect::<String>() + "...";
    }
    format!(
        "pid {} on {} since {since}: {}\n",
        std::process::id(),
        if host.is_empty() { "?" } else { &host },
        command.replace('\n', " ")
    )
}

/// The holder's record as a phrase: `pid 123 on host, for 42 s: snake-cli train ...`.
fn describe_holder(record: &str) -> String {
    let line = record.lines().next().unwrap_or("").trim();
    let parsed = (|| {
        let (head, command) = line.split_once(": ")?;
        let rest = head.strip_prefix("pid ")?;
        let (pid, rest) = rest.split_once(" on ")?;
        let (host, since) = rest.split_once(" since ")?;
        let since: u64 = since.parse().ok()?;
        let now = SystemTime::now().duration_since(UNIX_EPOCH).ok()?.as_secs();
        Some(format!(
            "pid {pid} on {host}, for {} s: {command}",
            now.saturating_sub(since)
        ))
    })();
    parsed.unwrap_or_else(|| "a process that has not said who it is yet".into())
}

/// True when `folder` holds nothing but, perhaps, its lock file (a new run or sweep may use it).
pub fn is_empty_but_lock(folder: &Path) -> bool {
    match std::fs::read_dir(folder) {
        Ok(entries) => entries
            .flatten()
            .all(|e| e.file_name() == std::ffi::OsStr::new(LOCK_FILE)),
        Err(_) => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_lock_on_a_folder_is_refused_naming_the_holder_then_granted_after_release() {
        let dir = tempfile::tempdir().unwrap();
        let first = WriterLock::acquire(dir.path(), "run directory").unwrap();
        let err = WriterLock::acquire(dir.path(), "run directory").unwrap_err();
        let pid = std::process::id().to_string();
        assert!(
            err.0.contains("is being written by another process"),
            "{err}"
        );
        assert!(err.0.contains(&format!("pid {pid} on ")), "{err}");
        assert_eq!(err.0.lines().count(), 1);
        drop(first);
        let again = WriterLock::acquire(dir.path(), "run directory").unwrap();
        assert_eq!(again.folder(), dir.path());
        assert!(is_empty_but_lock(dir.path()));
    }

    #[test]
    fn a_waiting_writer_gets_the_lock_when_the_holder_lets_go() {
        let dir = tempfile::tempdir().unwrap();
        let first = WriterLock::acquire(dir.path(), "sweep folder").unwrap();
        let path = dir.path().to_path_buf();
        let waiter = std::thread::spawn(move || {
            WriterLock::acquire_waiting(&path, "sweep folder", Duration::from_secs(10)).map(|_| ())
        });
        std::thread::sleep(Duration::from_millis(300));
        drop(first);
        waiter.join().unwrap().unwrap();
        let _held = WriterLock::acquire(dir.path(), "sweep folder").unwrap();
        let start = Instant::now();
        let err =
            WriterLock::acquire_waiting(dir.path(), "sweep folder", Duration::from_millis(300))
                .unwrap_err();
        assert!(start.elapsed() >= Duration::from_millis(300));
        assert!(err.0.contains("(waited 0.3 s)"), "{err}");
    }

    #[test]
    fn a_missing_folder_is_one_line() {
        let dir = tempfile::tempdir().unwrap();
        let err = WriterLock::acquire(&dir.path().join("nope"), "run directory").unwrap_err();
        assert!(err.0.starts_with("cannot lock run directory "), "{err}");
        assert_eq!(err.0.lines().count(), 1);
    }
}
