//! A session: what it starts from ([`Session`], [`prepare`]: a new run, or the checkpoint a resumed
//! one continues from), the run directory's lock, and [`train`].

use std::path::{Path, PathBuf};

use serde_json::{json, Map, Value};

use super::run::Run;
use super::{Observer, Outcome, TrainError};
use crate::config::{RunConfig, TrainerKind};
use crate::lock::WriterLock;
use crate::model::{self, Checkpoint};
use crate::rundir::{check_empty, lock_run_dir, RunDir};

/// The versions a native run records in versions.json (callers add their own, e.g. Python's).
pub fn native_versions() -> Map<String, Value> {
    let mut m = Map::new();
    m.insert("snakesim".into(), json!(env!("CARGO_PKG_VERSION")));
    m.insert("trainer".into(), json!("native"));
    m.insert("snake_rl".into(), json!(env!("CARGO_PKG_VERSION")));
    m.insert(
        "target".into(),
        json!(format!(
            "{}-{}",
            std::env::consts::ARCH,
            std::env::consts::OS
        )),
    );
    m
}

/// How to start: a new run, or resuming one.
#[derive(Debug, Clone)]
pub struct Session {
    /// The configuration (for a resumed run: the saved one with the allowed changes).
    pub config: RunConfig,
    /// The run directory.
    pub run_dir: PathBuf,
    /// Continue the run from its latest checkpoint.
    pub resume: bool,
    /// Versions to record besides [`native_versions`].
    pub versions: Map<String, Value>,
}

/// What a session starts from: the configuration to train with and, when resuming, the checkpoint.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The configuration (for a resumed run: the saved one with the allowed changes), resolved.
    pub config: RunConfig,
    /// The checkpoint a resumed run continues from.
    pub resume: Option<ResumePoint>,
}

/// The newest checkpoint of a run that loads, and the newer ones that did not.
#[derive(Debug, Clone)]
pub struct ResumePoint {
    /// Its timesteps.
    pub timesteps: u64,
    /// Its file.
    pub path: PathBuf,
    /// One line for each newer checkpoint that was skipped: its file and why it cannot be used.
    pub skipped: Vec<String>,
    /// One line for each robot or world file that changed since the checkpoint was written: the run
    /// resumes on the files it records, as a loaded model does (`<checkpoint>: robot R changed since
    /// training (...); the robot recorded in the model is used`).
    pub notes: Vec<String>,
    pub(super) checkpoint: Checkpoint,
    /// The checkpoint's env keywords hold a record in place of a changed file's path.
    pub(super) recorded_env: bool,
}

fn check_native(config: &RunConfig) -> Result<(), TrainError> {
    if config.trainer != TrainerKind::Native {
        return Err(TrainError::Setup(format!(
            "trainer {} is not the native trainer (run it with `snakesim train`)",
            config.trainer.name()
        )));
    }
    config.validate().map_err(|e| TrainError::Setup(e.0))
}

/// Takes the run directory's writer lock for a session ([`lock_run_dir`]: one writer per run
/// directory), after checking the configuration, so that a bad one leaves no folder behind.
pub fn lock_run(
    config: &RunConfig,
    run_dir: &Path,
    resume: bool,
) -> Result<WriterLock, TrainError> {
    check_native(config)?;
    lock_run_dir(run_dir, !resume).map_err(|e| TrainError::Setup(e.0))
}

/// Checks a session whose run directory `lock` holds, before anything is written: a new run's
/// directory must be empty; a resumed run must have a checkpoint below its timesteps, and may not
/// change what it learns. A resumed run continues from its newest checkpoint that loads; each newer
/// one that does not is named in [`ResumePoint::skipped`].
pub fn prepare(
    config: &RunConfig,
    lock: &WriterLock,
    resume: bool,
) -> Result<Prepared, TrainError> {
    check_native(config)?;
    let run_dir = lock.folder();
    if !resume {
        check_empty(run_dir).map_err(|e| TrainError::Setup(e.0))?;
        return Ok(Prepared {
            config: config.resolved(),
            resume: None,
        });
    }
    let (dir, saved) = RunDir::open(run_dir).map_err(|e| TrainError::Setup(e.0))?;
    let config = config.resolved();
    if let Some((key, was, now)) = saved.resolved().identity_difference(&config) {
        return Err(TrainError::Setup(format!(
            "cannot change {key} when resuming ({} has {was}, got {now})",
            run_dir.display()
        )));
    }
    let found = dir.checkpoints();
    if found.is_empty() {
        return Err(TrainError::Setup(format!(
            "cannot resume {}: it has no native checkpoints",
            run_dir.display()
        )));
    }
    let mut skipped = Vec::new();
    for (steps, path) in found.into_iter().rev() {
        match model::load_checkpoint_noted(&path) {
            Ok((checkpoint, notes)) if checkpoint.policy.timesteps == steps => {
                if steps >= config.timesteps {
                    return Err(TrainError::Setup(format!(
                        "{} already has {steps} timesteps (>= timesteps {}); pass a larger \
                         --timesteps to train on",
                        run_dir.display(),
                        config.timesteps
                    )));
                }
                return Ok(Prepared {
                    config,
                    resume: Some(ResumePoint {
                        timesteps: steps,
                        path,
                        skipped,
                        recorded_env: !notes.is_empty(),
                        notes: notes.into_iter().map(|n| n.replace('\n', " ")).collect(),
                        checkpoint,
                    }),
                });
            }
            Ok((checkpoint, _)) => skipped.push(format!(
                "skipped a checkpoint: {} holds {} timesteps, not the {steps} its name says",
                path.display(),
                checkpoint.policy.timesteps
            )),
            Err(e) => skipped.push(format!("skipped a checkpoint: {e}")),
        }
    }
    Err(TrainError::Setup(format!(
        "cannot resume {}: none of its checkpoints loads ({})",
        run_dir.display(),
        skipped.join("; ")
    )))
}

/// Trains: the run described by `session`, reporting to `observer`. Holds the run directory's lock
/// for the whole session.
pub fn train(session: &Session, observer: &mut dyn Observer) -> Result<Outcome, TrainError> {
    let lock = lock_run(&session.config, &session.run_dir, session.resume)?;
    let prepared = prepare(&session.config, &lock, session.resume)?;
    train_prepared(session, &lock, prepared, observer)
}

/// Trains a session already locked ([`lock_run`]) and prepared ([`prepare`]).
pub fn train_prepared(
    session: &Session,
    lock: &WriterLock,
    prepared: Prepared,
    observer: &mut dyn Observer,
) -> Result<Outcome, TrainError> {
    if lock.folder() != session.run_dir {
        return Err(TrainError::Setup(format!(
            "the lock held is for {}, not the run directory {}",
            lock.folder().display(),
            session.run_dir.display()
        )));
    }
    let Prepared { config, resume } = prepared;
    let threads = config
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, usize::from));
    let pool = std::sync::Arc::new(
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("snake-rl-{i}"))
            .build()
            .map_err(|e| TrainError::Setup(format!("cannot start {threads} threads: {e}")))?,
    );
    let mut versions = native_versions();
    versions.extend(session.versions.clone());
    let (dir, checkpoint) = if let Some(point) = resume {
        for line in point.skipped.iter().chain(&point.notes) {
            observer.on_note(line);
        }
        let (dir, _) = RunDir::open(&session.run_dir).map_err(|e| TrainError::Setup(e.0))?;
        dir.keep_evaluations_up_to(point.timesteps)?;
        dir.note_resume_versions(point.timesteps, &versions)?;
        // A file changed since the checkpoint: the run goes on with the robot and world it trained
        // on (the checkpoint's env keywords, the record in place of that path).
        let env = point
            .recorded_env
            .then(|| point.checkpoint.policy.env.env.clone());
        (dir, Some((point.checkpoint, env)))
    } else {
        (RunDir::create(lock, &config, &versions)?, None)
    };
    let mut run = Run::new(config, dir, threads, checkpoint)?;
    // The loop itself stays on the caller's thread (a Python caller checks for Ctrl-C there; only the
    // main thread can), the envs and the updates use the pool.
    run.learn(&pool, observer)
}
