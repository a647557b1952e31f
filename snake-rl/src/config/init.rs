//! Initialisation by imitation, the run's `init` table.

use serde::{Deserialize, Serialize};
use snake_core::controllers::HeldWave;
use snake_core::imitation::{Demonstrator, Imitated};
use snake_core::keys::integer;
use snake_core::EnvConfig;

use super::{check_range, check_real, key_err, limits, ConfigError, Schedule};

/// Initialisation by imitation (the run's `init` table, native trainer): before PPO, the training
/// envs are driven by a controller in their own action space for `steps` env steps; the actor's
/// mean is fitted to its actions (behaviour cloning: mean squared error, Adam, `epochs` passes in
/// minibatches of `batch_size`), the action noise set to `log_std`, and with `critic` the value
/// network fitted to the controller's discounted returns. With `normalize`, the observation and
/// return statistics are first updated from the imitation data, so that the fit sees what PPO will.
/// With `anchor`, PPO's loss keeps the policy near the fitted one (see [`InitConfig::anchor`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitConfig {
    /// The controller: `sine` (pybullet snake.py's wave as joint targets) or `steered_sine` (the same
    /// steered back to the goal's line) in the `joints` action mode; `gait` or `steer` (the
    /// baselines) in the `gait` action mode; see [`Imitated`].
    pub imitate: Imitated,
    /// The amplitude and frequency actions `gait` or `steer` hold, each in [-1, 1] (absent: 0 and
    /// 0, the middle of their ranges, as `baseline:steer`): a harder-driven fixed wave can be the
    /// better controller to start from (the sand task's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hold: Option<HeldWave>,
    /// Env steps of the controller (summed over the envs, 65536).
    #[serde(
        default = "InitConfig::default_steps",
        deserialize_with = "integer::deserialize"
    )]
    pub steps: u64,
    /// Passes over the imitation data (10).
    #[serde(
        default = "InitConfig::default_epochs",
        deserialize_with = "integer::deserialize"
    )]
    pub epochs: usize,
    /// Minibatch size (256).
    #[serde(
        default = "InitConfig::default_batch_size",
        deserialize_with = "integer::deserialize"
    )]
    pub batch_size: usize,
    /// Adam's learning rate (1e-3).
    #[serde(default = "InitConfig::default_learning_rate")]
    pub learning_rate: f64,
    /// The policy's log standard deviation after the fit (-1.6: about 0.2 of the action range).
    #[serde(default = "InitConfig::default_log_std")]
    pub log_std: f64,
    /// Also fit the value network to the controller's discounted returns (false).
    #[serde(default)]
    pub critic: bool,
    /// Holds PPO's policy near the fitted one (absent: no anchor): the fitted policy, frozen (the
    /// checkpoint at 0 timesteps), acts beside every rollout on the states PPO's policy visits, and
    /// `anchor * mean((mean_action - fitted_mean_action)^2)` joins PPO's loss (the penalty towards a
    /// reference policy of RL fine-tuning; with equal noise, a KL divergence up to scale). A number,
    /// or `lin_<w>` to let go linearly over the run. The controller itself is no anchor: its wave
    /// follows its own clock, so in states off its own path its actions belong to another phase.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub anchor: Option<Schedule>,
}

impl InitConfig {
    fn default_steps() -> u64 {
        65_536
    }
    fn default_epochs() -> usize {
        10
    }
    fn default_batch_size() -> usize {
        256
    }
    fn default_learning_rate() -> f64 {
        1e-3
    }
    fn default_log_std() -> f64 {
        -1.6
    }

    /// An `init` table imitating `imitate`, every other key its default.
    pub fn new(imitate: impl Into<Imitated>) -> Self {
        InitConfig {
            imitate: imitate.into(),
            hold: None,
            steps: Self::default_steps(),
            epochs: Self::default_epochs(),
            batch_size: Self::default_batch_size(),
            learning_rate: Self::default_learning_rate(),
            log_std: Self::default_log_std(),
            critic: false,
            anchor: None,
        }
    }

    /// Checks the table against the run's env; errors name the key path (`init.steps`).
    pub fn validate(&self, env: &EnvConfig, n_envs: usize) -> Result<(), ConfigError> {
        use limits::*;
        check_range("init.steps", self.steps, 1, MAX_INIT_STEPS)?;
        let row_bytes = 4 * (env.observation_dim() + env.action_dim() + 4) as u64;
        if self.steps.saturating_mul(row_bytes) > MAX_INIT_BYTES {
            return Err(key_err(
                "init.steps",
                format!(
                    "{} steps of {} floats would take more than {} GiB",
                    self.steps,
                    row_bytes / 4,
                    MAX_INIT_BYTES >> 30
                ),
            ));
        }
        check_range("init.epochs", self.epochs as u64, 1, MAX_EPOCHS)?;
        check_range("init.batch_size", self.batch_size as u64, 1, MAX_INIT_BATCH)?;
        if self.batch_size as u64 > self.steps {
            return Err(key_err(
                "init.batch_size",
                format!(
                    "must be at most init.steps = {}, got {}",
                    self.steps, self.batch_size
                ),
            ));
        }
        check_real("init.learning_rate", self.learning_rate, true)?;
        check_real("init.log_std", self.log_std, false)?;
        check_range(
            "init.log_std",
            self.log_std,
            LOG_STD_INIT[0],
            LOG_STD_INIT[1],
        )?;
        if let Some(anchor) = self.anchor {
            check_real("init.anchor", anchor.initial(), false)?;
            check_range("init.anchor", anchor.initial(), 0.0, MAX_ANCHOR_WEIGHT)?;
        }
        // The controller's errors about `hold` carry its key; the others are about the env it
        // cannot drive, which `init.imitate` chose.
        self.demonstrator(env, n_envs)
            .map(drop)
            .map_err(|e| match &e {
                snake_core::Error::InvalidArgument(i) if i.key().is_some() => {
                    key_err(format!("init.{}", i.key().unwrap_or_default()), i.detail())
                }
                _ => key_err("init.imitate", e.message()),
            })
    }

    /// The controller as a run's log names it: `steer`, or `steer holding amplitude 0.5, frequency
    /// 1` with `hold`.
    pub fn controller_label(&self) -> String {
        match self.hold {
            None => self.imitate.name().to_string(),
            Some(h) => format!(
                "{} holding amplitude {}, frequency {}",
                self.imitate.name(),
                h.amplitude,
                h.frequency
            ),
        }
    }

    /// The controller bound to `n_envs` envs of `env`.
    pub fn demonstrator(&self, env: &EnvConfig, n_envs: usize) -> snake_core::Result<Demonstrator> {
        Demonstrator::new(self.imitate, self.hold, env, n_envs)
    }
}
