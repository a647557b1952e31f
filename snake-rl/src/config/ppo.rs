//! PPO's hyperparameters, the run's `ppo` table.

use serde::{Deserialize, Serialize};
use snake_core::keys::integer;

use super::Schedule;

/// PPO's hyperparameters (SB3 2.x's names and meanings). The defaults are the paper's Table 1:
/// SB3's PPO defaults with `n_steps` 4096 and 10 epochs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PpoConfig {
    /// Adam's learning rate, a number or `lin_<initial>` (3e-4).
    pub learning_rate: Schedule,
    /// Steps per env per rollout (4096).
    #[serde(deserialize_with = "integer::deserialize")]
    pub n_steps: usize,
    /// Minibatch size (64).
    #[serde(deserialize_with = "integer::deserialize")]
    pub batch_size: usize,
    /// Passes over each rollout (10).
    #[serde(deserialize_with = "integer::deserialize")]
    pub n_epochs: usize,
    /// Discount (0.99).
    pub gamma: f64,
    /// GAE's lambda (0.95).
    pub gae_lambda: f64,
    /// Clip range of the probability ratio, a number or `lin_<initial>` (0.2).
    pub clip_range: Schedule,
    /// Clip range of the value around its rollout value (null: no clipping).
    pub clip_range_vf: Option<f64>,
    /// Normalise advantages per minibatch (true).
    pub normalize_advantage: bool,
    /// Entropy coefficient (0).
    pub ent_coef: f64,
    /// Value-loss coefficient (0.5).
    pub vf_coef: f64,
    /// Gradient norm clip (0.5).
    pub max_grad_norm: f64,
    /// Stop an update's epochs once the KL estimate exceeds 1.5 x this (null: never).
    pub target_kl: Option<f64>,
}

impl Default for PpoConfig {
    fn default() -> Self {
        PpoConfig {
            learning_rate: Schedule::Constant(3e-4),
            n_steps: 4096,
            batch_size: 64,
            n_epochs: 10,
            gamma: 0.99,
            gae_lambda: 0.95,
            clip_range: Schedule::Constant(0.2),
            clip_range_vf: None,
            normalize_advantage: true,
            ent_coef: 0.0,
            vf_coef: 0.5,
            max_grad_norm: 0.5,
            target_kl: None,
        }
    }
}
