//! What one update takes and gives: its settings, its statistics, and the error of a non-finite loss or
//! gradient. A leaf of the `ppo` modules: the update (update.rs) and its two-branch form
//! (branches.rs) both use these, and neither uses the other's internals through them.

use super::loss::LossSettings;

/// The hyperparameters of one update (schedules already evaluated).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UpdateSettings {
    /// Passes over the rollout.
    pub n_epochs: usize,
    /// Rows per minibatch.
    pub batch_size: usize,
    /// The loss's settings.
    pub loss: LossSettings,
    /// Gradient norm clip.
    pub max_grad_norm: f64,
    /// Early-stop threshold (stop once approx_kl > 1.5 x target_kl).
    pub target_kl: Option<f64>,
    /// This update's learning rate.
    pub learning_rate: f64,
}

/// What SB3 logs after an update (`train/*`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct UpdateStats {
    /// Mean entropy loss over the minibatches.
    pub entropy_loss: f64,
    /// Mean clipped surrogate loss.
    pub policy_gradient_loss: f64,
    /// Mean value loss.
    pub value_loss: f64,
    /// Mean KL estimate over the last epoch's minibatches.
    pub approx_kl: f64,
    /// Mean fraction of clipped ratios.
    pub clip_fraction: f64,
    /// Mean squared distance to the anchor actions (0 without an anchor).
    pub anchor_loss: f64,
    /// The last minibatch's total loss.
    pub loss: f64,
    /// Explained variance of the rollout's values.
    pub explained_variance: f64,
    /// Mean standard deviation of the policy after the update.
    pub std: f64,
    /// Epochs run (fewer than `n_epochs` after an early stop).
    pub epochs: usize,
    /// Gradient steps taken.
    pub gradient_steps: usize,
    /// The update stopped early on `target_kl`.
    pub stopped_early: bool,
}

/// A non-finite loss or gradient: where it happened. The parameters are those before that minibatch.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("non-finite {what} in epoch {epoch}, minibatch {minibatch} of the update")]
pub struct NonFinite {
    /// `loss` or `gradient`.
    pub what: &'static str,
    /// Epoch (from 1).
    pub epoch: usize,
    /// Minibatch within the epoch (from 1).
    pub minibatch: usize,
}
