//! Training features as parts: one interface ([`Part`]) through which a feature joins a run, as
//! SB3's callbacks and rapier's `PhysicsHooks` do. A part holds its own state and adds, where it
//! has something to add, work before training, a column of the rollout buffer and a record beside
//! each step, the actions the envs get, a term's weight in the loss, scalars in each update's log,
//! and fields of a saved policy and a checkpoint. Every hook has a default that adds nothing.
//!
//! A new feature is a file here and one line in [`REGISTRY`]. The registry's order is the order of
//! the hooks' calls (the imitation's fit comes before the anchor takes the fitted policy; the log's
//! scalars follow it).

use std::sync::Arc;

use snake_core::{EnvConfig, VecSnakeEnv};

use super::run::Run;
use super::{Observer, TrainError};
use crate::buffer::RolloutBuffer;
use crate::config::RunConfig;
use crate::model::{Checkpoint, SavedPolicy};
use crate::policy::Policy;
use crate::ppo::{LossSettings, UpdateSettings, UpdateStats};
use crate::rundir::RunDir;

pub(crate) mod anchor;
pub(crate) mod energy_ramp;
pub(crate) mod imitate;
pub(crate) mod steer_assist;

/// What a part is built from: the session's configuration, env and run directory.
pub(crate) struct Setup<'a> {
    pub(crate) config: &'a RunConfig,
    pub(crate) env_config: &'a EnvConfig,
    pub(crate) dir: &'a RunDir,
    /// The session continues from a checkpoint (one written after the run's `init`, if it has
    /// one: a checkpoint written during it starts the run over).
    pub(crate) resumed: bool,
}

/// Builds a run's part when its configuration asks for the feature (`None` otherwise).
pub(crate) type Build = fn(&Setup<'_>) -> Result<Option<Box<dyn Part>>, TrainError>;

/// Every feature a run may have, in the order of the hooks' calls.
pub(crate) const REGISTRY: &[Build] = &[
    imitate::build,
    energy_ramp::build,
    anchor::build,
    steer_assist::build,
];

/// The parts a run's configuration asks for.
pub(crate) fn build(setup: &Setup<'_>) -> Result<Vec<Box<dyn Part>>, TrainError> {
    let mut parts = Vec::new();
    for build in REGISTRY {
        parts.extend(build(setup)?);
    }
    Ok(parts)
}

/// A feature of a training run. Every method has a default that adds nothing.
pub(crate) trait Part {
    /// Before the session's first rollout, with the run's state (every other part in it); false
    /// when stopping was asked for (the run then saves a checkpoint and ends).
    fn before_training(
        &mut self,
        _run: &mut Run,
        _pool: &Arc<rayon::ThreadPool>,
        _observer: &mut dyn Observer,
    ) -> Result<bool, TrainError> {
        Ok(true)
    }

    /// The rollout buffer of `n_envs` envs, once, when the rollouts start (a part that records
    /// something beside each step widens it).
    fn start_rollouts(&mut self, _n_envs: usize, buffer: RolloutBuffer) -> RolloutBuffer {
        buffer
    }

    /// Before each rollout, at `timesteps` trained: may change the envs (`env_config` as built).
    fn before_rollout(
        &mut self,
        _timesteps: u64,
        _env_config: &EnvConfig,
        _envs: &mut VecSnakeEnv,
    ) -> Result<(), TrainError> {
        Ok(())
    }

    /// Each step, after the policy's actions are sampled and before the envs step: what the part
    /// records in the buffer for the step it stores next, from the envs' raw observations
    /// (`n_envs x obs_dim`).
    fn on_step(&mut self, _raw_obs: &[f32], _n_envs: usize, _buffer: &mut RolloutBuffer) {}

    /// The actions the envs get in place of the policy's clipped ones (`n_envs x act_dim`); the
    /// first part that gives some decides.
    fn env_actions(
        &mut self,
        _raw_obs: &[f32],
        _clipped: &[f32],
        _n_envs: usize,
    ) -> Option<&[f64]> {
        None
    }

    /// Its share of the loss at `progress_remaining` (1 at the start, 0 at the end).
    fn loss(&self, _progress_remaining: f64, _loss: &mut LossSettings) {}

    /// The scalars it adds to each update's log.
    fn log(
        &self,
        _settings: &UpdateSettings,
        _stats: &UpdateStats,
        _scalars: &mut Vec<(&'static str, f64)>,
    ) {
    }

    /// The policy as it acts in the evaluations.
    fn acting_policy(&self, policy: Policy) -> Policy {
        policy
    }

    /// What it records in every saved policy (models and checkpoints).
    fn saved_policy(&self, _policy: &mut SavedPolicy) {}

    /// What it records in a checkpoint.
    fn checkpoint(&self, _checkpoint: &mut Checkpoint) {}
}

/// Stands in for a part while its own hook runs (see `Run::before_training`).
pub(crate) struct Absent;

impl Part for Absent {}
