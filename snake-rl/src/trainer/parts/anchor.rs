//! `init.anchor`: PPO's loss holds the policy near the one its `init` fitted. The fitted policy,
//! frozen, acts beside the rollouts: each step its action means in the envs' states (from their raw
//! observations, normalised with its own statistics, as its model file acts) go into the rollout
//! buffer, and the loss adds `weight * mean((mean_action - anchor_action)^2)` (`ppo/loss.rs`),
//! the weight following its schedule. Logged as `train/anchor_weight` and `train/anchor_loss`.

use std::sync::Arc;

use super::{Part, Setup};
use crate::buffer::RolloutBuffer;
use crate::config::Schedule;
use crate::model::{self, SavedPolicy};
use crate::nn::Workspace;
use crate::ppo::{LossSettings, UpdateSettings, UpdateStats};
use crate::trainer::run::Run;
use crate::trainer::{Observer, TrainError};

struct Anchor {
    weight: Schedule,
    /// The fitted policy: read from the checkpoint at 0 timesteps when the session resumes after
    /// the init, else taken once the init has fitted it.
    policy: Option<SavedPolicy>,
    /// Its workspace and the step's observations normalised with its statistics (allocated when
    /// the rollouts start).
    ws: Option<Workspace>,
    obs: Vec<f32>,
}

pub(crate) fn build(setup: &Setup<'_>) -> Result<Option<Box<dyn Part>>, TrainError> {
    let Some(weight) = setup.config.init.as_ref().and_then(|i| i.anchor) else {
        return Ok(None);
    };
    let policy = if setup.resumed {
        let path = setup.dir.checkpoint_path(0);
        Some(model::load_policy(&path).map_err(|e| {
            TrainError::Setup(format!(
                "init.anchor: the run resumes after its init, whose fitted policy it anchors to: {e}"
            ))
        })?)
    } else {
        None
    };
    Ok(Some(Box::new(Anchor {
        weight,
        policy,
        ws: None,
        obs: Vec::new(),
    })))
}

impl Part for Anchor {
    fn before_training(
        &mut self,
        run: &mut Run,
        _pool: &Arc<rayon::ThreadPool>,
        _observer: &mut dyn Observer,
    ) -> Result<bool, TrainError> {
        // After the init's part (the registry's order): the policy now is the fitted one.
        if self.policy.is_none() {
            self.policy = Some(run.saved_policy());
        }
        Ok(true)
    }

    fn start_rollouts(&mut self, n_envs: usize, buffer: RolloutBuffer) -> RolloutBuffer {
        let policy = self
            .policy
            .as_ref()
            .expect("the fitted policy before the rollouts");
        self.ws = Some(policy.net.workspace(n_envs));
        self.obs = vec![0.0; n_envs * policy.net.obs_dim()];
        buffer.with_anchors()
    }

    fn on_step(&mut self, raw_obs: &[f32], n_envs: usize, buffer: &mut RolloutBuffer) {
        let (Some(p), Some(ws)) = (&self.policy, &mut self.ws) else {
            return;
        };
        self.obs.copy_from_slice(raw_obs);
        if let Some(rms) = &p.obs_rms {
            rms.normalize(&mut self.obs);
        }
        p.net.forward(&p.params, &self.obs, n_envs, ws);
        buffer.set_anchors(&ws.mean[..n_envs * p.net.act_dim()]);
    }

    fn loss(&self, progress_remaining: f64, loss: &mut LossSettings) {
        loss.anchor_weight = self.weight.at(progress_remaining) as f32;
    }

    fn log(
        &self,
        settings: &UpdateSettings,
        stats: &UpdateStats,
        scalars: &mut Vec<(&'static str, f64)>,
    ) {
        scalars.push((
            "train/anchor_weight",
            f64::from(settings.loss.anchor_weight),
        ));
        scalars.push(("train/anchor_loss", stats.anchor_loss));
    }
}
