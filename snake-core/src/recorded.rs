//! The files a robot or a world was read from, kept with it: what a trained model records, so that
//! editing a robot file never silently changes the robot a model acts on (issue 47).
//!
//! A [`RecordedFiles`] is the main file's path as it was given and the text of every file read to
//! build the robot or world: the robot file and the URDF it names (or a bare URDF alone), the world
//! file and its heightfield CSV. Each is keyed by its name relative to the main file's directory: the
//! main file by its file name, the others as the main file names them (`urdf: yaw-pitch-16.urdf`).
//! Its JSON form, `{"path": "robots/yaw-pitch-16.yaml", "files": {"yaw-pitch-16.yaml": "...",
//! "yaw-pitch-16.urdf": "..."}}`, is also what an env's `robot` or `world` keyword takes in place of
//! a path: the robot (world) of exactly those texts, read as if they lay at `path`
//! ([`RobotRef::from_record`](crate::RobotRef::from_record)). Visual mesh files of a URDF are not
//! recorded (they do not move the robot); only their presence is checked, beside `path`.

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{invalid, Result};

/// The texts of the files a robot or world was built from (see the module docs).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordedFiles {
    /// The main file (robot file, URDF or world file) as it was given.
    pub path: PathBuf,
    /// Every file read, by its name relative to the main file's directory.
    pub files: BTreeMap<String, String>,
}

impl RecordedFiles {
    /// The name of the main file among [`RecordedFiles::files`]: its file name.
    pub fn main_name(&self) -> String {
        main_name(&self.path)
    }

    /// The directory the names are relative to.
    pub fn dir(&self) -> &Path {
        self.path.parent().unwrap_or_else(|| Path::new(""))
    }

    /// How the files at `path` on disk (the main file there, the others beside it by the same names)
    /// differ from the recorded ones, one phrase per file that is missing, unreadable or other
    /// (`yaw-pitch-16.urdf differs`); empty when every one holds the recorded text.
    pub fn differences_at(&self, path: &Path) -> Vec<String> {
        let dir = path.parent().unwrap_or_else(|| Path::new(""));
        let main = self.main_name();
        self.files
            .iter()
            .filter_map(|(name, text)| {
                let on_disk = if *name == main {
                    path.to_path_buf()
                } else {
                    dir.join(name)
                };
                if !on_disk.exists() {
                    return Some(format!("{name} is missing"));
                }
                let cap = text.len() as u64;
                match crate::files::read_bytes(&on_disk, cap, "recorded file") {
                    Ok(bytes) if bytes == text.as_bytes() => None,
                    Ok(_) => Some(format!("{name} differs")),
                    // Larger than the recorded text: another file.
                    Err(_) if on_disk.is_file() => Some(format!("{name} differs")),
                    Err(_) => Some(format!("{name} cannot be read")),
                }
            })
            .collect()
    }
}

/// A path's file name as a recorded name.
pub(crate) fn main_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// Reads the files of one robot or world, from disk or from a record, and remembers what it read.
pub(crate) struct Reader<'a> {
    path: &'a Path,
    record: Option<&'a BTreeMap<String, String>>,
    read: RefCell<BTreeMap<String, String>>,
}

impl<'a> Reader<'a> {
    /// Reads the files on disk: the main file at `path`, the others relative to its directory.
    pub(crate) fn disk(path: &'a Path) -> Self {
        Reader {
            path,
            record: None,
            read: RefCell::new(BTreeMap::new()),
        }
    }

    /// Reads the recorded texts, as if they lay at `record.path`.
    pub(crate) fn record(record: &'a RecordedFiles) -> Self {
        Reader {
            path: &record.path,
            record: Some(&record.files),
            read: RefCell::new(BTreeMap::new()),
        }
    }

    /// The main file's path.
    pub(crate) fn path(&self) -> &'a Path {
        self.path
    }

    /// The directory the main file names others from.
    pub(crate) fn dir(&self) -> &'a Path {
        self.path.parent().unwrap_or_else(|| Path::new(""))
    }

    /// The main file's text (at most `cap` bytes; `what` names it in errors).
    pub(crate) fn main(&self, cap: u64, what: &str) -> Result<String> {
        self.read_at(main_name(self.path), self.path.to_path_buf(), cap, what)
    }

    /// The text of the file the main file names `name` (relative to its directory).
    pub(crate) fn named(&self, name: &Path, cap: u64, what: &str) -> Result<String> {
        self.read_at(
            name.to_string_lossy().into_owned(),
            self.dir().join(name),
            cap,
            what,
        )
    }

    fn read_at(&self, name: String, path: PathBuf, cap: u64, what: &str) -> Result<String> {
        let text = match self.record {
            None => crate::files::read_text(&path, cap, what)?,
            Some(files) => {
                let text = files.get(&name).ok_or_else(|| {
                    invalid(format!(
                        "{what} {}: not among the recorded files ({})",
                        path.display(),
                        shown_names(files)
                    ))
                })?;
                if text.len() as u64 > cap {
                    return Err(invalid(format!(
                        "{what} {}: the recorded text has {} bytes, more than the {cap} it may have",
                        path.display(),
                        text.len()
                    )));
                }
                text.clone()
            }
        };
        self.read.borrow_mut().insert(name, text.clone());
        Ok(text)
    }

    /// What was read, as a record of the main file's path; from a record, an error when it holds
    /// files that were not read (a record is exactly the files of its robot or world).
    pub(crate) fn finish(self) -> Result<RecordedFiles> {
        let read = self.read.into_inner();
        if let Some(files) = self.record {
            let extra: Vec<&str> = files
                .keys()
                .filter(|k| !read.contains_key(*k))
                .map(String::as_str)
                .collect();
            if !extra.is_empty() {
                return Err(invalid(format!(
                    "{}: the record holds files it does not use: {}",
                    self.path.display(),
                    list(&extra)
                )));
            }
        }
        Ok(RecordedFiles {
            path: self.path.to_path_buf(),
            files: read,
        })
    }
}

fn shown_names(files: &BTreeMap<String, String>) -> String {
    let names: Vec<&str> = files.keys().map(String::as_str).collect();
    list(&names)
}

/// Names for a message: the first few, and how many more.
fn list(names: &[&str]) -> String {
    const SHOWN: usize = 4;
    let mut out = names
        .iter()
        .take(SHOWN)
        .copied()
        .collect::<Vec<_>>()
        .join(", ");
    if names.len() > SHOWN {
        out.push_str(&format!(" and {} more", names.len() - SHOWN));
    }
    out
}

/// How a `robot` or `world` value deserialises: a path, or a record of its files.
pub(crate) enum FileOrRecord {
    Path(PathBuf),
    Record(RecordedFiles),
}

impl<'de> Deserialize<'de> for FileOrRecord {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct Visit;
        impl<'de> serde::de::Visitor<'de> for Visit {
            type Value = FileOrRecord;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a file's path, or a record of its files {path, files}")
            }
            fn visit_str<E: serde::de::Error>(
                self,
                v: &str,
            ) -> std::result::Result<Self::Value, E> {
                Ok(FileOrRecord::Path(PathBuf::from(v)))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> std::result::Result<Self::Value, A::Error> {
                RecordedFiles::deserialize(serde::de::value::MapAccessDeserializer::new(map))
                    .map(FileOrRecord::Record)
            }
        }
        d.deserialize_any(Visit)
    }
}
