//! What a caller sees of a session while it trains: [`Observer`] and the progress it is given.

use crate::ppo::UpdateStats;
use crate::rundir::EvaluationRow;

/// Progress after each update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Timesteps so far.
    pub timesteps: u64,
    /// The run's total.
    pub total: u64,
    /// Timesteps per second of this session, evaluations and the initialisation excluded.
    pub timesteps_per_second: f64,
    /// Mean return of the last 100 training episodes.
    pub ep_rew_mean: Option<f64>,
    /// Success rate of the last 100 training episodes.
    pub ep_success_rate: Option<f64>,
    /// The update's statistics.
    pub update: UpdateStats,
    /// Seconds of the last rollout and update.
    pub rollout_seconds: f64,
    /// See `rollout_seconds`.
    pub update_seconds: f64,
}

/// Progress of a run's `init` (initialisation by imitation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InitProgress {
    /// Env steps of the controller so far (all envs).
    pub steps: u64,
    /// Of `init.steps` (rounded up to whole steps of every env).
    pub total_steps: u64,
    /// Epochs of the fit done.
    pub epoch: usize,
    /// Of `init.epochs`.
    pub epochs: usize,
    /// The last epoch's behaviour-cloning loss (mean squared error to the controller's actions).
    pub bc_loss: Option<f64>,
    /// The last epoch's critic loss, when the critic is fitted.
    pub critic_loss: Option<f64>,
}

/// Receives what happens during training; every method has a default that does nothing.
pub trait Observer {
    /// Training starts at `start` of `total` timesteps.
    fn on_start(&mut self, _start: u64, _total: u64) {}
    /// After every env step (of all envs); a cheap place to move a progress bar.
    fn on_step(&mut self, _timesteps: u64) {}
    /// During a run's `init` (initialisation by imitation): after every env step of the controller
    /// and every epoch of the fit.
    fn on_init(&mut self, _progress: &InitProgress) {}
    /// After every update.
    fn on_update(&mut self, _progress: &Progress) {}
    /// After every evaluation.
    fn on_evaluation(&mut self, _row: &EvaluationRow) {}
    /// Something the user should know that is not an error (a skipped checkpoint); one line.
    fn on_note(&mut self, message: &str) {
        eprintln!("note: {message}");
    }
    /// Asked between env steps: true stops training (a checkpoint is saved first).
    fn should_stop(&mut self) -> bool {
        false
    }
}

/// An observer that does nothing.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl Observer for Silent {
    fn on_note(&mut self, _message: &str) {}
}
