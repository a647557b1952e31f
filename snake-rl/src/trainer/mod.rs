//! The training loop: SB3's `OnPolicyAlgorithm.learn` for PPO, with the run directory around it.
//!
//! Each iteration collects `n_steps` steps of every env (actions sampled from the policy, clipped
//! to [-1, 1] for the env, stored unclipped; a truncated episode's last reward gains `gamma` times
//! the value of its final observation), computes GAE, and runs one PPO update. Evaluations and
//! checkpoints follow the first update at or past each multiple of their frequency, so that the row
//! or checkpoint labelled T holds a policy trained on exactly T timesteps (SB3's callbacks evaluate
//! inside the rollout instead, before its update). Stopping on request saves the state of the last
//! complete update; resuming starts the next rollout there. Everything runs on one thread pool of `threads` threads: the envs step in parallel, and each
//! minibatch's gradient is split across the threads. A seed and a thread count give one run, bit for
//! bit.
//!
//! A run with an `init` table first imitates its controller ([`crate::imitate`]): the fitted policy
//! is evaluated at 0 timesteps, and PPO starts from it. A run stopped during the initialisation
//! starts it over on resume; its checkpoints afterwards hold the fitted policy.
//!
//! The files: `session.rs` (what a session starts from, the lock, [`train`]), `run.rs` (the
//! run's state, `learn`, evaluations, checkpoints), `rollout.rs` (`collect_rollouts`), `log.rs`
//! (TensorBoard, [`Summary`]), `observer.rs` ([`Observer`]). The features a run may have (imitation
//! init, the anchor, the energy ramp, the steering assist) are parts: each in its own file under
//! `parts/`, joining the run through one trait (`parts::Part`: its state, what it adds before
//! training, to a rollout, to the loss, to the log, to a saved policy and a checkpoint).

use std::path::PathBuf;

mod log;
mod observer;
mod parts;
mod rollout;
mod run;
mod session;

pub use log::{rss_mib, Summary};
pub use observer::{InitProgress, Observer, Progress, Silent};
pub use parts::imitate::INIT_SEED_OFFSET;
pub use session::{
    lock_run, native_versions, prepare, train, train_prepared, Prepared, ResumePoint, Session,
};

/// Why training stopped with an error. Every message is one line.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TrainError {
    /// The configuration or the run directory cannot be used.
    #[error("{0}")]
    Setup(String),
    /// Writing the run's files failed.
    #[error("{0}")]
    Io(String),
    /// An env failed (the simulation blew up or refused a value).
    #[error("env: {0}")]
    Env(#[from] snake_core::Error),
    /// A loss or gradient became NaN or infinite; the last good state was saved.
    #[error("{0}")]
    NonFinite(String),
}

impl From<crate::rundir::RunDirError> for TrainError {
    fn from(e: crate::rundir::RunDirError) -> Self {
        TrainError::Io(e.0)
    }
}

/// How a training session ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// The run reached its timesteps.
    Finished(Summary),
    /// Stopped on request (Ctrl-C); a checkpoint was saved.
    Interrupted(Summary, PathBuf),
}
