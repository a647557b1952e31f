//! `steer_assist`: `baseline:steer` shares the agent's gait actions (residual steering, the
//! hand-over near the goal), between the policy and the envs in the rollouts and the evaluations,
//! and recorded in every saved policy so that a model acts as it trained.

use snake_core::AssistedEnv;

use super::{Part, Setup};
use crate::model::SavedPolicy;
use crate::policy::Policy;
use crate::trainer::TrainError;

struct SteerAssist {
    /// The run's assist, bound to its env.
    assist: AssistedEnv,
    /// The assist as configured, which saved policies record.
    recorded: snake_core::SteerAssist,
    /// The envs' actions of the step (the assist's composition of the policy's).
    env_actions: Vec<f64>,
}

pub(crate) fn build(setup: &Setup<'_>) -> Result<Option<Box<dyn Part>>, TrainError> {
    let Some(assist) = setup.config.steer_assist else {
        return Ok(None);
    };
    let recorded = assist;
    let assist = assist
        .bind(setup.env_config)
        .map_err(|e| TrainError::Setup(e.message()))?;
    Ok(Some(Box::new(SteerAssist {
        assist,
        recorded,
        env_actions: vec![0.0; setup.config.n_envs * setup.env_config.action_dim()],
    })))
}

impl Part for SteerAssist {
    fn env_actions(&mut self, raw_obs: &[f32], clipped: &[f32], n_envs: usize) -> Option<&[f64]> {
        self.assist
            .apply(raw_obs, clipped, n_envs, &mut self.env_actions);
        Some(&self.env_actions)
    }

    fn acting_policy(&self, policy: Policy) -> Policy {
        policy.with_assist(Some(self.assist))
    }

    fn saved_policy(&self, policy: &mut SavedPolicy) {
        policy.steer_assist = Some(self.recorded);
    }
}
