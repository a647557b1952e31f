//! `energy_ramp`: the training envs' energy weight annealed in over the run
//! ([`RunConfig::energy_weight_at`]), set before each rollout and logged as `train/energy_weight`.

use snake_core::{EnvConfig, RewardConfig, VecSnakeEnv};

use super::{Part, Setup};
use crate::config::RunConfig;
use crate::ppo::{UpdateSettings, UpdateStats};
use crate::trainer::TrainError;

struct EnergyRamp {
    config: RunConfig,
    /// The weight of the last rollout.
    weight: Option<f64>,
}

pub(crate) fn build(setup: &Setup<'_>) -> Result<Option<Box<dyn Part>>, TrainError> {
    Ok(setup.config.energy_ramp.is_some().then(|| {
        Box::new(EnergyRamp {
            config: setup.config.clone(),
            weight: None,
        }) as Box<dyn Part>
    }))
}

impl Part for EnergyRamp {
    fn before_rollout(
        &mut self,
        timesteps: u64,
        env_config: &EnvConfig,
        envs: &mut VecSnakeEnv,
    ) -> Result<(), TrainError> {
        let configured = env_config.reward;
        let weight = self
            .config
            .energy_weight_at(timesteps, configured.energy_weight);
        envs.set_reward(RewardConfig {
            energy_weight: weight,
            ..configured
        })?;
        self.weight = Some(weight);
        Ok(())
    }

    fn log(
        &self,
        _settings: &UpdateSettings,
        _stats: &UpdateStats,
        scalars: &mut Vec<(&'static str, f64)>,
    ) {
        if let Some(w) = self.weight {
            scalars.push(("train/energy_weight", w));
        }
    }
}
