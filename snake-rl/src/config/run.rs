//! [`RunConfig`]: everything that defines a training run, its defaults and its checks.

use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};
use snake_core::keys::integer;
use snake_core::{EnvConfig, Preset, SteerAssist};

use super::layers::{from_value, kind, merge_layer, parse_yaml};
use super::{
    check_range, check_real, check_schedule, env_config, err, limits, ConfigError, InitConfig,
    PpoConfig,
};
use crate::nn::Arch;

/// Which implementation of PPO trains the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TrainerKind {
    /// snake-rl, this crate: the whole loop in Rust.
    #[default]
    Native,
    /// Stable-Baselines3 2.x through the `snakesim` Python package.
    Sb3,
}

impl TrainerKind {
    /// The configuration name.
    pub fn name(self) -> &'static str {
        match self {
            TrainerKind::Native => "native",
            TrainerKind::Sb3 => "sb3",
        }
    }
}

/// Everything that defines a training run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RunConfig {
    /// `native` (this crate) or `sb3` (Stable-Baselines3 through Python).
    pub trainer: TrainerKind,
    /// Joints N of the snake (5).
    #[serde(deserialize_with = "integer::deserialize")]
    pub joints: usize,
    /// `small` (pi/vf [64, 64]), `large` (shared [128, 128] first), or the widths of each part, as
    /// SB3's `net_arch` with a shared trunk: `{shared: [], pi: [256, 256], vf: [256, 256]}` (a part left
    /// out takes small's widths).
    pub arch: Arch,
    /// The initial log standard deviation of every action's noise, as SB3's `log_std_init` (0.0).
    pub log_std_init: f64,
    /// The robot's masses: `paper` (every cube 0.06 kg) or `snakebot-gym` (links 1 kg).
    pub preset: Preset,
    /// Total env steps to train for (20,000,000).
    #[serde(deserialize_with = "integer::deserialize")]
    pub timesteps: u64,
    /// Envs stepped in parallel (16).
    #[serde(deserialize_with = "integer::deserialize")]
    pub n_envs: usize,
    /// Seed of the networks, the actions and the training envs (42).
    #[serde(deserialize_with = "integer::deserialize")]
    pub seed: u64,
    /// Evaluate every this many timesteps (250,000; 0: only at the end).
    #[serde(deserialize_with = "integer::deserialize")]
    pub eval_freq: u64,
    /// Deterministic episodes per evaluation (10).
    #[serde(deserialize_with = "integer::deserialize")]
    pub eval_episodes: usize,
    /// Seed of the evaluation episodes (null: seed + 1000).
    #[serde(deserialize_with = "integer::option::deserialize")]
    pub eval_seed: Option<u64>,
    /// Checkpoint every this many timesteps (1,000,000; 0: none besides the final one).
    #[serde(deserialize_with = "integer::deserialize")]
    pub checkpoint_freq: u64,
    /// Normalise observations and rewards as SB3's `VecNormalize` (false, as the paper).
    pub normalize: bool,
    /// SB3 trainer: torch device, `auto`, `cpu`, `cuda` or `cuda:N`.
    pub device: String,
    /// SB3 trainer: torch CPU threads (null: torch's default).
    #[serde(deserialize_with = "integer::option::deserialize")]
    pub torch_threads: Option<usize>,
    /// Native trainer: threads for the envs and the updates (null: one per core).
    #[serde(deserialize_with = "integer::option::deserialize")]
    pub threads: Option<usize>,
    /// Native trainer: anneals `env.reward.energy_weight` in. The training envs' weight is 0 until the
    /// first timestep count, rises linearly to the configured weight at the second and stays there
    /// (null: the configured weight throughout). Evaluations always use the configured weight.
    pub energy_ramp: Option<[u64; 2]>,
    /// Native trainer: `baseline:steer` shares the agent's gait actions (`{residual: true}`,
    /// `{near_goal: METRES}` or both; [`SteerAssist`]), between the policy and the envs of training
    /// and evaluation; recorded in the model and applied again wherever the model is loaded (null:
    /// none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub steer_assist: Option<SteerAssist>,
    /// Native trainer: before PPO, fit the policy to a controller by imitation ([`InitConfig`];
    /// null: none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub init: Option<InitConfig>,
    /// PPO's hyperparameters.
    pub ppo: PpoConfig,
    /// More env keywords, as `snakesim.SnakeEnv` takes them (goal, goal_radius, max_episode_steps,
    /// observation, reward, start, snake, ...); `joints` and `preset` are the top-level keys.
    pub env: Map<String, Value>,
}

impl Default for RunConfig {
    fn default() -> Self {
        RunConfig {
            trainer: TrainerKind::Native,
            joints: snake_core::config::DEFAULT_JOINTS,
            arch: Arch::Small,
            log_std_init: 0.0,
            preset: snake_core::config::DEFAULT_PRESET,
            timesteps: 20_000_000,
            n_envs: 16,
            seed: 42,
            eval_freq: 250_000,
            eval_episodes: 10,
            eval_seed: None,
            checkpoint_freq: 1_000_000,
            normalize: false,
            device: "auto".into(),
            torch_threads: None,
            threads: None,
            energy_ramp: None,
            steer_assist: None,
            init: None,
            ppo: PpoConfig::default(),
            env: Map::new(),
        }
    }
}

/// Keys whose change would make a resumed run learn something else; `--resume` refuses them.
pub const IDENTITY_KEYS: &[&str] = &[
    "trainer",
    "joints",
    "arch",
    "log_std_init",
    "preset",
    "n_envs",
    "seed",
    "eval_seed",
    "normalize",
    "energy_ramp",
    "steer_assist",
    "init",
    "ppo",
    "env",
];

/// Offset of the default evaluation seed from the training seed.
pub const EVAL_SEED_OFFSET: u64 = 1000;

impl RunConfig {
    /// A configuration from layers of keys over the defaults (each a JSON mapping), checked.
    pub fn from_layers(layers: &[Value]) -> Result<Self, ConfigError> {
        let mut merged = serde_json::to_value(RunConfig::default()).expect("defaults serialise");
        for layer in layers {
            if !layer.is_object() {
                return Err(err(format!(
                    "a configuration must be a mapping of keys to values, got {}",
                    kind(layer)
                )));
            }
            merge_layer(&mut merged, layer);
        }
        let config: RunConfig = from_value(merged, "")?;
        config.validate()?;
        Ok(config)
    }

    /// A configuration from YAML text over the defaults, checked.
    pub fn from_yaml(text: &str) -> Result<Self, ConfigError> {
        Self::from_layers(&[parse_yaml(text)?])
    }

    /// Checks every key; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ConfigError> {
        use limits::*;
        check_range("timesteps", self.timesteps, 1, MAX_TIMESTEPS)?;
        self.arch.check().map_err(err)?;
        check_real("log_std_init", self.log_std_init, false)?;
        check_range(
            "log_std_init",
            self.log_std_init,
            LOG_STD_INIT[0],
            LOG_STD_INIT[1],
        )?;
        check_range("n_envs", self.n_envs as u64, 1, MAX_ENVS)?;
        check_range("seed", self.seed, 0, MAX_SEED)?;
        if let Some(s) = self.eval_seed {
            check_range("eval_seed", s, 0, MAX_SEED)?;
        }
        check_range(
            "eval_episodes",
            self.eval_episodes as u64,
            1,
            MAX_EVAL_EPISODES,
        )?;
        let device_ok = matches!(self.device.as_str(), "auto" | "cpu" | "cuda")
            || self
                .device
                .strip_prefix("cuda:")
                .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()));
        if !device_ok {
            return Err(err(format!(
                "device: expected auto, cpu, cuda or cuda:N, got '{}'",
                self.device
            )));
        }
        if let Some(t) = self.torch_threads {
            check_range("torch_threads", t as u64, 1, MAX_THREADS)?;
        }
        if let Some(t) = self.threads {
            check_range("threads", t as u64, 1, MAX_THREADS)?;
        }
        let p = &self.ppo;
        check_schedule("ppo.learning_rate", p.learning_rate)?;
        check_schedule("ppo.clip_range", p.clip_range)?;
        check_range("ppo.n_steps", p.n_steps as u64, 1, MAX_TIMESTEPS)?;
        check_range("ppo.n_epochs", p.n_epochs as u64, 1, MAX_EPOCHS)?;
        let rollout = p.n_steps as u64 * self.n_envs as u64;
        if rollout < 2 {
            return Err(err(
                "ppo.n_steps: n_steps * n_envs must be at least 2 (PPO needs a rollout of 2 steps)",
            ));
        }
        if p.batch_size < 2 || p.batch_size as u64 > rollout {
            return Err(err(format!(
                "ppo.batch_size: must be in [2, n_steps * n_envs = {rollout}], got {}",
                p.batch_size
            )));
        }
        check_range("ppo.gamma", p.gamma, 0.0, 1.0)?;
        check_range("ppo.gae_lambda", p.gae_lambda, 0.0, 1.0)?;
        if let Some(c) = p.clip_range_vf {
            check_real("ppo.clip_range_vf", c, true)?;
        }
        check_real("ppo.ent_coef", p.ent_coef, false)?;
        check_real("ppo.vf_coef", p.vf_coef, false)?;
        if p.vf_coef < 0.0 {
            return Err(err(format!("ppo.vf_coef: must be >= 0, got {}", p.vf_coef)));
        }
        check_real("ppo.max_grad_norm", p.max_grad_norm, true)?;
        if let Some(kl) = p.target_kl {
            check_real("ppo.target_kl", kl, true)?;
        }
        let env = self.env_config()?;
        if let Some([from, to]) = self.energy_ramp {
            if from > to || to > MAX_TIMESTEPS {
                return Err(err(format!(
                    "energy_ramp: expected [from, to] timesteps with from <= to <= {MAX_TIMESTEPS}, \
                     got [{from}, {to}]"
                )));
            }
            if env.reward.energy_weight == 0.0 {
                return Err(err(
                    "energy_ramp: env.reward.energy_weight is 0, so there is nothing to anneal in",
                ));
            }
            if self.trainer != TrainerKind::Native {
                return Err(err(
                    "energy_ramp: only the native trainer anneals the energy weight (trainer: native)",
                ));
            }
        }
        if let Some(assist) = self.steer_assist {
            if self.trainer != TrainerKind::Native {
                return Err(err(
                    "steer_assist: only the native trainer applies it (trainer: native)",
                ));
            }
            assist.bind(&env)?;
        }
        if let Some(init) = &self.init {
            if self.trainer != TrainerKind::Native {
                return Err(err(
                    "init: only the native trainer initialises by imitation (trainer: native)",
                ));
            }
            init.validate(&env, self.n_envs)?;
            if self.steer_assist.is_some() {
                // Under the assist the policy's steering is added to steer's: the controller's
                // actions are not what the policy should output.
                return Err(err(
                    "init: a run with steer_assist cannot imitate a controller (the policy's \
                     steering is a correction to steer's); use one or the other",
                ));
            }
        }
        let row_bytes = 4 * (env.observation_dim() + env.action_dim() + 8) as u64;
        if rollout.saturating_mul(row_bytes) > MAX_ROLLOUT_BYTES {
            return Err(err(format!(
                "ppo.n_steps: a rollout of n_steps * n_envs = {rollout} steps would take {:.1} GiB \
                 (at most {} GiB)",
                (rollout as f64) * row_bytes as f64 / (1u64 << 30) as f64,
                MAX_ROLLOUT_BYTES >> 30
            )));
        }
        Ok(())
    }

    /// The env the run trains in.
    pub fn env_config(&self) -> Result<EnvConfig, ConfigError> {
        env_config(self.joints, self.preset, &self.env, "env")
    }

    /// The training envs' energy weight after `timesteps` timesteps (see [`RunConfig::energy_ramp`]),
    /// given the configured one.
    pub fn energy_weight_at(&self, timesteps: u64, configured: f64) -> f64 {
        match self.energy_ramp {
            None => configured,
            Some([from, _]) if timesteps < from => 0.0,
            Some([_, to]) if timesteps >= to => configured,
            Some([from, to]) => configured * (timesteps - from) as f64 / (to - from) as f64,
        }
    }

    /// The evaluation seed: `eval_seed`, else `seed + 1000`.
    pub fn eval_seed(&self) -> u64 {
        self.eval_seed.unwrap_or(self.seed + EVAL_SEED_OFFSET)
    }

    /// The configuration as saved with a run: every key, the evaluation seed resolved.
    pub fn resolved(&self) -> RunConfig {
        RunConfig {
            eval_seed: Some(self.eval_seed()),
            ..self.clone()
        }
    }

    /// YAML text, keys in the documented order.
    pub fn to_yaml(&self) -> String {
        serde_norway::to_string(self).expect("a run configuration serialises")
    }

    /// The first identity key (see [`IDENTITY_KEYS`]) on which `self` and `other` differ.
    pub fn identity_difference(&self, other: &RunConfig) -> Option<(&'static str, Value, Value)> {
        let a = serde_json::to_value(self).expect("serialises");
        let b = serde_json::to_value(other).expect("serialises");
        IDENTITY_KEYS
            .iter()
            .find(|k| a[**k] != b[**k])
            .map(|k| (*k, a[*k].clone(), b[*k].clone()))
    }
}
