//! The run directory: one folder per training run, the same layout whichever trainer made it.
//!
//! ```text
//! config.yaml          the resolved configuration (seeds included); reloads equal
//! versions.json        versions of snakesim and of what trained it
//! evaluations.csv      timesteps, mean_return, std_return, success_rate, mean_steps_to_goal, wall_time
//! tb/PPO_1/            TensorBoard scalars (train/*, rollout/*, eval/*, time/*)
//! checkpoints/         model_<T>_steps.safetensors (native) or .zip (SB3), each with a .json note
//! model.safetensors    the final policy (native; SB3 runs have model.zip)
//! writer.lock          who writes the run now (see [`crate::lock`]: one writer per run directory)
//! ```

use std::fs::OpenOptions;
use std::io::Write;
use std::path::{Path, PathBuf};

use serde_json::{json, Map, Value};

use crate::config::{ConfigError, RunConfig};
use crate::lock::{is_empty_but_lock, WriterLock, LOCK_FILE};
use crate::model::write_atomically;

/// `config.yaml`.
pub const CONFIG_FILE: &str = "config.yaml";
/// `versions.json`.
pub const VERSIONS_FILE: &str = "versions.json";
/// `evaluations.csv`.
pub const EVALUATIONS_FILE: &str = "evaluations.csv";
/// TensorBoard's folder, and the run's subfolder in it (SB3's `tb_log_name` PPO, run 1).
pub const TB_DIR: &str = "tb";
/// See [`TB_DIR`].
pub const TB_RUN: &str = "PPO_1";
/// `checkpoints/`.
pub const CHECKPOINT_DIR: &str = "checkpoints";
/// The native trainer's final policy.
pub const MODEL_FILE: &str = "model.safetensors";
/// Columns of `evaluations.csv`.
pub const EVAL_FIELDS: [&str; 6] = [
    "timesteps",
    "mean_return",
    "std_return",
    "success_rate",
    "mean_steps_to_goal",
    "wall_time",
];

/// A run directory that cannot be used as asked; the message says why.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct RunDirError(pub String);

fn io(path: &Path, e: std::io::Error) -> RunDirError {
    RunDirError(format!(
        "cannot write to run directory {}: {e}",
        path.display()
    ))
}

/// How a run directory is named in messages.
const WHAT: &str = "run directory";

fn not_empty(path: &Path) -> RunDirError {
    RunDirError(format!(
        "run directory {} already exists and is not empty: pass --resume to continue it, or choose \
         another --run-dir",
        path.display()
    ))
}

/// A new run's folder holds nothing yet but its lock file.
pub(crate) fn check_empty(path: &Path) -> Result<(), RunDirError> {
    if is_empty_but_lock(path) {
        Ok(())
    } else {
        Err(not_empty(path))
    }
}

/// Takes the run directory's writer lock ([`crate::lock`]) before anything in it is read or written,
/// and holds it for as long as the returned lock lives. A new run's folder must be absent or empty
/// (it is created); a resumed run's must exist. A folder another process is writing is refused at
/// once, naming that process.
pub fn lock_run_dir(path: &Path, new_run: bool) -> Result<WriterLock, RunDirError> {
    let held = |e: crate::lock::LockError| RunDirError(e.0);
    if new_run {
        if path.exists() && !path.is_dir() {
            return Err(RunDirError(format!(
                "run directory {} exists and is not a directory",
                path.display()
            )));
        }
        if path.is_dir() && !is_empty_but_lock(path) {
            if path.join(LOCK_FILE).is_file() {
                // A run being written says so, rather than only "not empty".
                WriterLock::acquire(path, WHAT).map_err(held)?;
            }
            return Err(not_empty(path));
        }
        std::fs::create_dir_all(path).map_err(|e| io(path, e))?;
    } else if !path.is_dir() {
        return Err(RunDirError(format!(
            "cannot resume {}: no such directory",
            path.display()
        )));
    }
    let lock = WriterLock::acquire(path, WHAT).map_err(held)?;
    if new_run {
        // Another run may have started and ended there between the check above and the lock.
        check_empty(path)?;
    }
    Ok(lock)
}

/// One row of `evaluations.csv`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EvaluationRow {
    /// Timesteps trained when evaluated.
    pub timesteps: u64,
    /// Mean return of the episodes.
    pub mean_return: f64,
    /// Population standard deviation of the returns.
    pub std_return: f64,
    /// Fraction of episodes that reached the goal.
    pub success_rate: f64,
    /// Mean env steps to the goal of the successful episodes (None: no success).
    pub mean_steps_to_goal: Option<f64>,
    /// Wall time of the run when evaluated, seconds.
    pub wall_time: f64,
}

/// A run's folder.
#[derive(Debug, Clone)]
pub struct RunDir {
    path: PathBuf,
}

impl RunDir {
    /// A new run in `path`, locked by `lock` (see [`lock_run_dir`]) and empty but for the lock:
    /// writes config.yaml, versions.json and the evaluations.csv header.
    pub fn create(
        lock: &WriterLock,
        config: &RunConfig,
        versions: &Map<String, Value>,
    ) -> Result<Self, RunDirError> {
        let path = lock.folder();
        check_empty(path)?;
        std::fs::create_dir_all(path.join(CHECKPOINT_DIR)).map_err(|e| io(path, e))?;
        let dir = RunDir {
            path: path.to_path_buf(),
        };
        write_atomically(&dir.path.join(CONFIG_FILE), config.to_yaml().as_bytes())
            .map_err(|e| io(path, e))?;
        let text = serde_json::to_string_pretty(versions).expect("serialises") + "\n";
        write_atomically(&dir.path.join(VERSIONS_FILE), text.as_bytes())
            .map_err(|e| io(path, e))?;
        dir.rewrite_evaluations(&[])?;
        Ok(dir)
    }

    /// An existing run to resume: its saved configuration.
    pub fn open(path: &Path) -> Result<(Self, RunConfig), RunDirError> {
        let config_path = path.join(CONFIG_FILE);
        if !config_path.exists() {
            return Err(RunDirError(format!(
                "cannot resume {}: no readable {CONFIG_FILE} there",
                path.display()
            )));
        }
        let text = snake_core::files::read_text(
            &config_path,
            snake_core::limits::MAX_CONFIG_BYTES,
            "run config",
        )
        .map_err(|e| RunDirError(format!("cannot resume {}: {}", path.display(), e.message())))?;
        let config = RunConfig::from_yaml(&text)
            .map_err(|e: ConfigError| RunDirError(format!("{}: {e}", config_path.display())))?;
        Ok((
            RunDir {
                path: path.to_path_buf(),
            },
            config,
        ))
    }

    /// The folder.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The folder of TensorBoard's event files.
    pub fn tensorboard_dir(&self) -> PathBuf {
        self.path.join(TB_DIR).join(TB_RUN)
    }

    /// Path of the checkpoint at `timesteps`.
    pub fn checkpoint_path(&self, timesteps: u64) -> PathBuf {
        self.path
            .join(CHECKPOINT_DIR)
            .join(format!("model_{timesteps}_steps.safetensors"))
    }

    /// Native checkpoints, oldest first.
    pub fn checkpoints(&self) -> Vec<(u64, PathBuf)> {
        let mut found: Vec<(u64, PathBuf)> = std::fs::read_dir(self.path.join(CHECKPOINT_DIR))
            .into_iter()
            .flatten()
            .flatten()
            .filter_map(|e| {
                let name = e.file_name().to_string_lossy().into_owned();
                let steps = name
                    .strip_prefix("model_")?
                    .strip_suffix("_steps.safetensors")?;
                Some((steps.parse().ok()?, e.path()))
            })
            .collect();
        found.sort();
        found
    }

    /// Writes the note beside a checkpoint (`model_<T>_steps.json`: timesteps, wall time, reason).
    pub fn write_checkpoint_note(
        &self,
        timesteps: u64,
        wall_time: f64,
        reason: &str,
    ) -> Result<(), RunDirError> {
        let note = json!({"timesteps": timesteps, "wall_time": wall_time, "reason": reason});
        let path = self.checkpoint_path(timesteps).with_extension("json");
        write_atomically(&path, format!("{note}\n").as_bytes()).map_err(|e| io(&self.path, e))
    }

    fn csv_value(v: Option<f64>) -> String {
        match v {
            Some(x) if x.is_finite() => format!("{x:?}"),
            _ => "nan".into(),
        }
    }

    fn row_text(row: &EvaluationRow) -> String {
        format!(
            "{},{},{},{},{},{}\n",
            row.timesteps,
            Self::csv_value(Some(row.mean_return)),
            Self::csv_value(Some(row.std_return)),
            Self::csv_value(Some(row.success_rate)),
            Self::csv_value(row.mean_steps_to_goal),
            Self::csv_value(Some(row.wall_time)),
        )
    }

    /// Appends one evaluation to evaluations.csv.
    pub fn append_evaluation(&self, row: &EvaluationRow) -> Result<(), RunDirError> {
        let path = self.path.join(EVALUATIONS_FILE);
        let mut f = OpenOptions::new()
            .append(true)
            .open(&path)
            .map_err(|e| io(&self.path, e))?;
        f.write_all(Self::row_text(row).as_bytes())
            .map_err(|e| io(&self.path, e))
    }

    /// Keeps the evaluations up to `timesteps` (a resumed run redoes the later ones).
    pub fn keep_evaluations_up_to(&self, timesteps: u64) -> Result<(), RunDirError> {
        let path = self.path.join(EVALUATIONS_FILE);
        let text = if path.exists() {
            snake_core::files::read_text(&path, snake_core::limits::MAX_CSV_BYTES, "evaluations")
                .map_err(|e| RunDirError(e.message()))?
        } else {
            String::new()
        };
        let mut kept = Vec::new();
        for (k, line) in text.lines().enumerate().skip(1) {
            let steps = line
                .split(',')
                .next()
                .and_then(|v| v.trim().parse::<f64>().ok());
            match steps {
                Some(s) if s <= timesteps as f64 => kept.push(format!("{line}\n")),
                Some(_) => {}
                None => {
                    return Err(RunDirError(format!(
                        "{}: line {} is not an evaluation row: {}",
                        path.display(),
                        k + 1,
                        snake_core::files::excerpt(line)
                    )))
                }
            }
        }
        self.rewrite_evaluations(&kept)
    }

    fn rewrite_evaluations(&self, rows: &[String]) -> Result<(), RunDirError> {
        let mut text = EVAL_FIELDS.join(",") + "\n";
        for r in rows {
            text.push_str(r);
        }
        write_atomically(&self.path.join(EVALUATIONS_FILE), text.as_bytes())
            .map_err(|e| io(&self.path, e))
    }

    /// Records, in versions.json, that the run was resumed with other versions than it started with.
    pub fn note_resume_versions(
        &self,
        timesteps: u64,
        versions: &Map<String, Value>,
    ) -> Result<(), RunDirError> {
        let path = self.path.join(VERSIONS_FILE);
        let mut recorded: Map<String, Value> =
            snake_core::files::read_text(&path, snake_core::limits::MAX_CONFIG_BYTES, "versions")
                .ok()
                .and_then(|t| serde_json::from_str(&t).ok())
                .unwrap_or_default();
        let changed: Map<String, Value> = versions
            .iter()
            .filter(|(k, v)| recorded.get(*k) != Some(v))
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect();
        if changed.is_empty() {
            return Ok(());
        }
        let mut entry = changed;
        entry.insert("timesteps".into(), json!(timesteps));
        let list = recorded
            .entry("resumed_with")
            .or_insert_with(|| Value::Array(vec![]));
        if let Value::Array(items) = list {
            items.push(Value::Object(entry));
        }
        let text = serde_json::to_string_pretty(&recorded).expect("serialises") + "\n";
        write_atomically(&path, text.as_bytes()).map_err(|e| io(&self.path, e))
    }
}
