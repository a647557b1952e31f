//! The configuration of a training run: one typed structure, the single source of every default
//! (the paper's Table 1 for PPO), limit and check. The `snakesim` and `snake-cli` commands, the YAML
//! files in `snake-py/configs/` and the Python package all read it from here.
//!
//! A configuration is built from layers, lowest precedence first: the defaults, a YAML file, then
//! `KEY=VALUE` overrides (`--set ppo.n_steps=256`, values in YAML syntax) and command-line flags.
//! Mappings merge key by key at every depth. Unknown keys, values of the wrong type and impossible
//! values are errors whose message starts with the key's path (`ppo.learning_rate: ...`).
//!
//! ```
//! use snake_rl::config::RunConfig;
//!
//! let config = RunConfig::from_yaml("joints: 10\nppo: {n_steps: 2048}\n")?;
//! assert_eq!((config.joints, config.ppo.n_steps, config.ppo.batch_size), (10, 2048, 64));
//! let error = RunConfig::from_yaml("ppo: {batch_size: 0}").unwrap_err();
//! assert!(error.to_string().starts_with("ppo.batch_size"));
//! # Ok::<(), snake_rl::config::ConfigError>(())
//! ```

use serde::de::{self, Deserializer};
use serde::{Deserialize, Serialize, Serializer};
use serde_json::{Map, Value};
use snake_core::controllers::{Imitable, JointsSine};
use snake_core::env::Task;
use snake_core::{EnvConfig, Preset, SteerAssist};

use crate::nn::Arch;

/// A configuration that cannot be used; the message names the key path and what is wrong. The key
/// path is also kept apart ([`ConfigError::key`]), so that a caller can name the flag that set a key
/// without taking the message apart.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct ConfigError(pub String, Option<(String, String)>);

impl ConfigError {
    /// The key path the error is about (`env.max_episode_steps`), when it is about one.
    pub fn key(&self) -> Option<&str> {
        self.1.as_ref().map(|(key, _)| key.as_str())
    }

    /// What is wrong, without the key path.
    pub fn detail(&self) -> &str {
        self.1.as_ref().map_or(&self.0, |(_, detail)| detail)
    }
}

fn err(message: impl Into<String>) -> ConfigError {
    ConfigError(crate::one_line(message.into()), None)
}

/// An error about the value at the key path `key`.
fn key_err(key: impl Into<String>, detail: impl Into<String>) -> ConfigError {
    let (key, detail) = (key.into(), crate::one_line(detail.into()));
    ConfigError(
        crate::one_line(format!("{key}: {detail}")),
        Some((key, detail)),
    )
}

/// Limits of a run's sizes: each keeps a typo from asking for an impossible run.
pub mod limits {
    /// Most parallel envs of a run (snake-core's batched env's limit).
    pub const MAX_ENVS: u64 = snake_core::limits::MAX_ENVS as u64;
    /// Most timesteps of a run (10^12: decades at our speed).
    pub const MAX_TIMESTEPS: u64 = 1_000_000_000_000;
    /// Most episodes of one evaluation.
    pub const MAX_EVAL_EPISODES: u64 = 100_000;
    /// Most threads (native trainer) or torch threads (SB3 trainer).
    pub const MAX_THREADS: u64 = 256;
    /// Most memory the rollout buffer may take, bytes.
    pub const MAX_ROLLOUT_BYTES: u64 = 4 << 30;
    /// Most optimisation epochs per rollout.
    pub const MAX_EPOCHS: u64 = 10_000;
    /// Largest seed: SB3 and numpy take seeds below 2^32, so both trainers share that range.
    pub const MAX_SEED: u64 = u32::MAX as u64;
    /// Longest throughput measurement, seconds.
    pub const MAX_BENCH_SECONDS: f64 = 3600.0;
    /// Most training seeds of one sweep (`snakesim sweep --seeds`).
    pub const MAX_SWEEP_SEEDS: u64 = 1000;
    /// Most trials of one sweep or search.
    pub const MAX_SWEEP_TRIALS: u64 = 10_000;
    /// Most values of one `--grid` key or one search choice.
    pub const MAX_GRID_VALUES: u64 = 1000;
    /// Most retries of a failed trial (`--max-failures`).
    pub const MAX_TRIAL_FAILURES: u64 = 100;
    /// Most keys of a search space.
    pub const MAX_SEARCH_KEYS: u64 = 100;
    /// Longest name of a sweep trial's folder, characters (a config name and its grid point).
    pub const MAX_TRIAL_NAME: u64 = 100;
    /// Most tanh layers of one part of a network (`arch.shared`, `arch.pi`, `arch.vf`).
    pub const MAX_NET_LAYERS: u64 = crate::nn::MAX_LAYERS as u64;
    /// Widest tanh layer of a network.
    pub const MAX_NET_WIDTH: u64 = crate::nn::MAX_WIDTH as u64;
    /// Bounds of `log_std_init`: SB3's own bounds of a learnt log standard deviation (SAC's
    /// `LOG_STD_MIN`, `LOG_STD_MAX`), beyond which the noise is 0 or swamps the action.
    pub const LOG_STD_INIT: [f64; 2] = [-20.0, 2.0];
    /// Most env steps of the controller an `init` imitates (`init.steps`): 2^22, a few minutes of
    /// stepping on 2 cores.
    pub const MAX_INIT_STEPS: u64 = 1 << 22;
    /// Most memory the imitation data may take, bytes.
    pub const MAX_INIT_BYTES: u64 = 2 << 30;
    /// Most minibatch size of the imitation fit (`init.batch_size`).
    pub const MAX_INIT_BATCH: u64 = 1 << 16;
    /// Largest weight of the anchor to the fitted policy (`init.anchor`). The surrogate's gradient
    /// in the action means grows as 1 / std (about 20 at the init's std of 0.05) while the anchor's
    /// is its weight times the distance to the fitted policy (hundredths): weights that balance them
    /// are in the thousands, and a million leaves PPO nothing to say.
    pub const MAX_ANCHOR_WEIGHT: f64 = 1e6;
    /// Most joint counts one `snake-cli bench` measures.
    pub const MAX_BENCH_SIZES: usize = 16;
    /// Most runs per joint count of `snake-cli bench`.
    pub const MAX_BENCH_REPEATS: usize = 100;
}

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

/// A hyperparameter constant over training or decaying linearly to 0 with the remaining progress
/// (`lin_<initial>`, the notation of rl-baselines3-zoo), as SB3's schedules take it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Schedule {
    /// The same value throughout.
    Constant(f64),
    /// `initial * progress_remaining`, progress_remaining going from 1 to 0.
    Linear(f64),
}

impl Schedule {
    /// The value with `progress_remaining` (1 at the start of training, 0 at the end) left.
    pub fn at(self, progress_remaining: f64) -> f64 {
        match self {
            Schedule::Constant(v) => v,
            Schedule::Linear(v) => v * progress_remaining,
        }
    }

    /// The value at the start of training.
    pub fn initial(self) -> f64 {
        self.at(1.0)
    }
}

impl Serialize for Schedule {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Schedule::Constant(v) => s.serialize_f64(*v),
            Schedule::Linear(v) => s.serialize_str(&format!("lin_{v:?}")),
        }
    }
}

impl<'de> Deserialize<'de> for Schedule {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Number(f64),
            Text(String),
        }
        let bad = || {
            de::Error::custom(
                "expected a number or lin_<number> (linear decay to 0), e.g. lin_3e-4",
            )
        };
        match Raw::deserialize(d).map_err(|_| bad())? {
            Raw::Number(v) => Ok(Schedule::Constant(v)),
            Raw::Text(t) => {
                let v = t.strip_prefix("lin_").ok_or_else(bad)?;
                v.parse::<f64>().map(Schedule::Linear).map_err(|_| bad())
            }
        }
    }
}

/// Integer fields accept YAML/JSON integers and integral floats (`2e7`), nothing else.
mod integer {
    use serde::de::{self, Deserializer, Visitor};

    struct Integral;

    impl Visitor<'_> for Integral {
        type Value = u64;

        fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("a non-negative integer")
        }

        fn visit_u64<E: de::Error>(self, v: u64) -> Result<u64, E> {
            Ok(v)
        }

        fn visit_i64<E: de::Error>(self, v: i64) -> Result<u64, E> {
            u64::try_from(v).map_err(|_| E::invalid_value(de::Unexpected::Signed(v), &self))
        }

        fn visit_f64<E: de::Error>(self, v: f64) -> Result<u64, E> {
            // Below 2^53 every integer is exact in a double: 2e7 is 20000000.
            if v.fract() == 0.0 && (0.0..9_007_199_254_740_992.0).contains(&v) {
                Ok(v as u64)
            } else if v.fract() == 0.0 {
                Err(E::invalid_value(de::Unexpected::Float(v), &self))
            } else {
                Err(E::invalid_type(de::Unexpected::Float(v), &self))
            }
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>, T: TryFrom<u64>>(d: D) -> Result<T, D::Error> {
        let v = d.deserialize_any(Integral)?;
        T::try_from(v).map_err(|_| de::Error::custom(format!("{v} is too large")))
    }

    pub mod option {
        use serde::{Deserialize, Deserializer};

        pub fn deserialize<'de, D: Deserializer<'de>, T: TryFrom<u64>>(
            d: D,
        ) -> Result<Option<T>, D::Error> {
            #[derive(Deserialize)]
            struct Wrap<T: TryFrom<u64>>(#[serde(deserialize_with = "super::deserialize")] T);
            Option::<Wrap<T>>::deserialize(d).map(|o| o.map(|Wrap(v)| v))
        }
    }
}

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
            joints: 5,
            arch: Arch::Small,
            log_std_init: 0.0,
            preset: Preset::Paper,
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
    /// steered back to the goal's line); see [`Imitable`].
    pub imitate: Imitable,
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
    pub fn new(imitate: Imitable) -> Self {
        InitConfig {
            imitate,
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
        JointsSine::new(self.imitate, env, n_envs)
            .map(drop)
            .map_err(|e| key_err("init.imitate", e.message()))
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

/// The env's former `action` keys of the steering assist and the [`SteerAssist`] keys they became:
/// a run configuration with them gets an error saying where they went, a model recorded with them
/// is read with its assist (`model::take_legacy_assist`).
pub const LEGACY_ASSIST_KEYS: [(&str, &str); 2] = [
    ("steer_residual", "residual"),
    ("steer_near_goal", "near_goal"),
];

/// Offset of the default evaluation seed from the training seed.
pub const EVAL_SEED_OFFSET: u64 = 1000;

/// A configuration `base` updated by the layer `overlay`, as [`merge`] does, except that widths given
/// for some parts of the network (`arch: {pi: [256, 256]}`) replace those parts of the network `base`
/// names (`large` keeps its trunk), not the whole network.
pub fn merge_layer(base: &mut Value, overlay: &Value) {
    if let (Some(Value::String(name)), Some(Value::Object(_))) =
        (base.get("arch"), overlay.get("arch"))
    {
        if let Some(named) = Arch::named(name) {
            base["arch"] = serde_json::to_value(named.net()).expect("widths serialise");
        }
    }
    merge(base, overlay);
}

/// `base` updated by `overlay`: mappings merge key by key at every depth, anything else replaces.
pub fn merge(base: &mut Value, overlay: &Value) {
    match (base, overlay) {
        (Value::Object(b), Value::Object(o)) => {
            for (k, v) in o {
                match b.get_mut(k) {
                    Some(existing) if existing.is_object() && v.is_object() => merge(existing, v),
                    _ => {
                        b.insert(k.clone(), v.clone());
                    }
                }
            }
        }
        (b, o) => *b = o.clone(),
    }
}

/// Parses YAML text into a JSON value (YAML 1.2 scalars: `3e-4` is a number, `yes` a string).
pub fn parse_yaml(text: &str) -> Result<Value, ConfigError> {
    snake_core::files::check_yaml_shape(text, "the config").map_err(|e| err(e.message()))?;
    let value = yaml_value(text, "", |e| {
        let at = e
            .location()
            .map(|l| format!(" (line {}, column {})", l.line(), l.column()))
            .unwrap_or_default();
        let message = e.to_string();
        let first = message.split(" at line").next().unwrap_or(&message);
        err(format!(
            "not valid YAML{at}: {}",
            snake_core::files::quoted_excerpts(first)
        ))
    })?;
    Ok(if value.is_null() {
        Value::Object(Map::new())
    } else {
        value
    })
}

/// YAML text as a JSON value, with every non-finite number (`.nan`, `.inf`) refused naming its key
/// path under `prefix` (serde would make it a `null`, which reads as "not given"); `parse_error` words
/// the parser's own errors.
fn yaml_value(
    text: &str,
    prefix: &str,
    parse_error: impl Fn(serde_norway::Error) -> ConfigError,
) -> Result<Value, ConfigError> {
    let yaml: serde_norway::Value = serde_norway::from_str(text).map_err(&parse_error)?;
    if let Err(e) = snake_core::files::check_finite_yaml(&yaml, "") {
        let e = match e {
            snake_core::Error::InvalidArgument(invalid) => invalid.under(prefix),
            other => snake_core::Invalid::new(other.to_string()),
        };
        return Err(match e.key() {
            Some(key) => key_err(key, e.detail()),
            None => err(e.to_string()),
        });
    }
    serde_norway::from_value(yaml).map_err(parse_error)
}

/// `KEY=VALUE` overrides (`ppo.n_steps=256`, `env.reward.progress_weight=1`) as one nested mapping;
/// values are YAML.
pub fn parse_overrides<S: AsRef<str>>(items: &[S]) -> Result<Value, ConfigError> {
    let mut out = Value::Object(Map::new());
    for item in items {
        let item = item.as_ref();
        let (key, text) = item.split_once('=').ok_or_else(|| {
            err(format!(
                "--set expects KEY=VALUE (e.g. ppo.n_steps=256), got '{item}'"
            ))
        })?;
        let key = key.trim();
        if key.is_empty() || key.split('.').any(str::is_empty) {
            return Err(err(format!(
                "--set: '{key}' is not a key path (e.g. ppo.n_steps)"
            )));
        }
        let value = if text.trim().is_empty() {
            Value::Null
        } else {
            yaml_value(text, key, |_| {
                err(format!(
                    "--set {key}: cannot parse the value {} as YAML",
                    snake_core::files::excerpt(text)
                ))
            })
            .map_err(|e| err(format!("--set {}", e.0)))?
        };
        let mut nested = value;
        for part in key.rsplit('.') {
            let mut map = Map::new();
            map.insert(part.to_owned(), nested);
            nested = Value::Object(map);
        }
        merge(&mut out, &nested);
    }
    Ok(out)
}

/// Deserialises `value` as `T`, naming the key path of the first error (prefixed by `prefix`).
pub fn from_value<T: de::DeserializeOwned>(value: Value, prefix: &str) -> Result<T, ConfigError> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let path = shown_path(e.path());
        let path = match (prefix.is_empty(), path.as_str()) {
            (true, ".") => String::new(),
            (true, p) => p.to_owned(),
            (false, ".") => prefix.to_owned(),
            (false, p) => format!("{prefix}.{p}"),
        };
        // serde quotes the keys and values it refuses whole: cut, or withheld where they do not read
        // as names (a file that is not a configuration).
        let inner = snake_core::files::quoted_excerpts(&e.into_inner().to_string());
        if path.is_empty() {
            err(inner)
        } else {
            key_err(path, inner)
        }
    })
}

/// A key path as serde_path_to_error writes it (`a.b[0].c`, `.` for the root), each key shown as
/// [`snake_core::files::withheld_unless_name`] shows it.
fn shown_path(path: &serde_path_to_error::Path) -> String {
    use serde_path_to_error::Segment;
    let mut out = String::new();
    for segment in path {
        let part = match segment {
            Segment::Seq { index } => {
                out.push_str(&format!("[{index}]"));
                continue;
            }
            Segment::Map { key } => snake_core::files::withheld_unless_name(key),
            Segment::Enum { variant } => snake_core::files::withheld_unless_name(variant),
            Segment::Unknown => "?".to_owned(),
        };
        if !out.is_empty() {
            out.push('.');
        }
        out.push_str(&part);
    }
    if out.is_empty() {
        ".".to_owned()
    } else {
        out
    }
}

/// The env of a run (and of `snakesim.SnakeEnv(**keywords)`): `joints` and `preset` choose the
/// snake, `task` (`paper` or `goal`) the defaults ([`EnvConfig::for_task`]), the `snake` table
/// overrides the preset's parameters, every other key is an [`EnvConfig`] field over the task's
/// defaults. Errors name the key path under `prefix`.
pub fn env_config(
    joints: usize,
    preset: Preset,
    table: &Map<String, Value>,
    prefix: &str,
) -> Result<EnvConfig, ConfigError> {
    let at = |key: &str| {
        if prefix.is_empty() {
            key.to_owned()
        } else {
            format!("{prefix}.{key}")
        }
    };
    let max = snake_core::config::MAX_JOINTS;
    if !(1..=max).contains(&joints) {
        // `joints` is a key of its own (the run's top level, or SnakeEnv's keyword), not of `env`.
        return Err(key_err(
            "joints",
            format!("must be in [1, {max}], got {joints}"),
        ));
    }
    for key in ["joints", "preset"] {
        if table.contains_key(key) {
            return Err(err(format!(
                "{}: set {key} at the top level, not in the env table",
                at(key)
            )));
        }
    }
    if let Some(Value::Object(action)) = table.get("action") {
        if let Some((old, new)) = LEGACY_ASSIST_KEYS
            .iter()
            .find(|(old, _)| action.contains_key(*old))
        {
            return Err(err(format!(
                "{}: baseline:steer left the env: set `steer_assist: {{{new}: ...}}` at the run's top level, or wrap the env in snakesim.wrappers.SteerAssist({new}=...)",
                at(&format!("action.{old}"))
            )));
        }
    }
    let mut object = table.clone();
    let task: Task = match object.remove("task") {
        None => Task::default(),
        Some(v) => from_value(v, &at("task"))?,
    };
    let mut base = serde_json::to_value(EnvConfig::for_task(task, preset, joints))
        .expect("EnvConfig serialises");
    let mut snake = serde_json::to_value(preset.config(joints)).expect("SnakeConfig serialises");
    if let Some(overrides) = object.remove("snake") {
        let Value::Object(overrides) = overrides else {
            return Err(err(format!(
                "{}: expected a mapping of snake parameters",
                at("snake")
            )));
        };
        if overrides.contains_key("joints") {
            return Err(err(format!(
                "{}: set joints with the joints key, not inside snake",
                at("snake.joints")
            )));
        }
        merge(&mut snake, &Value::Object(overrides));
    }
    object.insert("snake".into(), snake);
    merge(&mut base, &Value::Object(object));
    let config: EnvConfig = from_value(base, prefix)?;
    config.validate().map_err(|e| with_path(prefix, e))?;
    Ok(config)
}

/// The env of `snakesim.SnakeEnv(**keywords)`: the keywords as one mapping, `joints` and `preset`
/// among them (defaults 5 and `paper`).
pub fn env_from_keywords(keywords: &Map<String, Value>) -> Result<EnvConfig, ConfigError> {
    let mut table = keywords.clone();
    let defaults = RunConfig::default();
    let joints: usize = match table.remove("joints") {
        None => defaults.joints,
        Some(v) => {
            #[derive(Deserialize)]
            struct Joints(#[serde(deserialize_with = "integer::deserialize")] usize);
            let Joints(j) = from_value(v, "joints")?;
            j
        }
    };
    let preset: Preset = match table.remove("preset") {
        None => defaults.preset,
        Some(v) => from_value(v, "preset")?,
    };
    env_config(joints, preset, &table, "")
}

/// Every env keyword with its default for `task` (`snakesim.SnakeEnv`: paper, `SnakeGoalEnv`:
/// goal), `snake` (the preset's parameters) left out.
pub fn env_keyword_defaults(task: Task) -> Map<String, Value> {
    let defaults = RunConfig::default();
    let mut map = Map::new();
    map.insert("joints".into(), Value::from(defaults.joints));
    map.insert("preset".into(), Value::from(defaults.preset.name()));
    let env = EnvConfig::for_task(task, defaults.preset, defaults.joints);
    let Value::Object(env) = serde_json::to_value(env).expect("serialises") else {
        unreachable!("EnvConfig serialises to a mapping")
    };
    for (k, v) in env {
        if k != "snake" {
            map.insert(k, v);
        }
    }
    // No robot: the built-in snake (the field is left out of serialised configs when unset).
    map.entry("robot").or_insert(Value::Null);
    // No world file: the flat plane.
    map.entry("world").or_insert(Value::Null);
    // No random terrain.
    map.entry("terrain").or_insert(Value::Null);
    // The default height map (left out of serialised configs while it is the default).
    map.entry("height_map").or_insert(Value::Null);
    // Nominal physics every episode.
    map.entry("randomize").or_insert(Value::Null);
    map
}

/// A snake-core error of a configuration nested at `prefix` (the run's `env` table) as a
/// configuration error: its key path under `prefix` (snake-core keeps the path apart from the
/// message, [`snake_core::Invalid`]).
fn with_path(prefix: &str, e: snake_core::Error) -> ConfigError {
    match e {
        snake_core::Error::InvalidArgument(m) => {
            let m = m.under(prefix);
            match m.key() {
                Some(key) => key_err(key, m.detail()),
                None => err(m.to_string()),
            }
        }
        other if prefix.is_empty() => err(other.to_string()),
        other => key_err(prefix, other.to_string()),
    }
}

fn check_range<T: PartialOrd + std::fmt::Display + Copy>(
    key: &str,
    value: T,
    low: T,
    high: T,
) -> Result<(), ConfigError> {
    if value < low || value > high {
        return Err(key_err(
            key,
            format!("must be in [{low}, {high}], got {value}"),
        ));
    }
    Ok(())
}

fn check_real(key: &str, value: f64, positive: bool) -> Result<(), ConfigError> {
    if !value.is_finite() {
        return Err(key_err(key, format!("must be finite, got {value}")));
    }
    if positive && value <= 0.0 {
        return Err(key_err(key, format!("must be positive, got {value}")));
    }
    Ok(())
}

fn check_schedule(key: &str, schedule: Schedule) -> Result<(), ConfigError> {
    check_real(key, schedule.initial(), true)
}

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
        check_range(
            "joints",
            self.joints as u64,
            1,
            snake_core::config::MAX_JOINTS as u64,
        )?;
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
            assist.bind(&env).map_err(|e| with_path("", e))?;
        }
        if let Some(init) = &self.init {
            if self.trainer != TrainerKind::Native {
                return Err(err(
                    "init: only the native trainer initialises by imitation (trainer: native)",
                ));
            }
            init.validate(&env, self.n_envs)?;
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

fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "a list",
        Value::Object(_) => "a mapping",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn error(yaml: &str) -> String {
        RunConfig::from_yaml(yaml).unwrap_err().to_string()
    }

    #[test]
    fn defaults_are_table_1() {
        let c = RunConfig::default();
        let p = &c.ppo;
        assert_eq!(p.learning_rate, Schedule::Constant(3e-4));
        assert_eq!((p.n_steps, p.batch_size, p.n_epochs), (4096, 64, 10));
        assert_eq!((p.gamma, p.gae_lambda), (0.99, 0.95));
        assert_eq!(p.clip_range, Schedule::Constant(0.2));
        assert_eq!((p.ent_coef, p.vf_coef, p.max_grad_norm), (0.0, 0.5, 0.5));
        assert!(c.validate().is_ok());
    }

    #[test]
    fn yaml_round_trips() {
        let c = RunConfig::from_yaml(
            "joints: 10\narch: large\npreset: snakebot-gym\ntimesteps: 2e7\nppo: {learning_rate: lin_1e-3, \
             target_kl: 0.02}\nenv: {goal: [3, -4], reward: {progress_weight: 2}}",
        )
        .unwrap();
        assert_eq!(c.timesteps, 20_000_000);
        assert_eq!(c.ppo.learning_rate, Schedule::Linear(1e-3));
        let again = RunConfig::from_yaml(&c.to_yaml()).unwrap();
        assert_eq!(again, c);
        assert_eq!(c.env_config().unwrap().goal, (3.0, -4.0));
    }

    #[test]
    fn arch_takes_widths_as_sb3_net_arch() {
        use crate::nn::NetArch;
        let c =
            RunConfig::from_yaml("arch: {pi: [256, 256], vf: [128]}\nlog_std_init: -0.5").unwrap();
        let net = NetArch {
            shared: vec![],
            pi: vec![256, 256],
            vf: vec![128],
        };
        assert_eq!(c.arch, Arch::Custom(net));
        assert_eq!(c.log_std_init, -0.5);
        assert_eq!(c.arch.to_string(), "pi [256, 256], vf [128]");
        assert_eq!(RunConfig::from_yaml(&c.to_yaml()).unwrap(), c);
        assert_eq!(c.arch.to_meta().parse::<Arch>().unwrap(), c.arch);
        // The paper's widths are the paper's networks, by name.
        let large = "arch: {shared: [128, 128], pi: [64, 64], vf: [64, 64]}";
        assert_eq!(RunConfig::from_yaml(large).unwrap().arch, Arch::Large);
        assert_eq!(RunConfig::from_yaml("arch: {}").unwrap().arch, Arch::Small);
        assert_eq!(Arch::Large.to_meta(), "large");
        // Widths of some parts over a named network change those parts only.
        let layers = [
            serde_json::json!({"arch": "large"}),
            serde_json::json!({"arch": {"pi": [256]}}),
        ];
        let c = RunConfig::from_layers(&layers).unwrap();
        assert_eq!(
            c.arch.net(),
            NetArch {
                shared: vec![128, 128],
                pi: vec![256],
                vf: vec![64, 64]
            }
        );
    }

    #[test]
    fn errors_name_the_key_path() {
        assert!(error("bogus: 1").starts_with("bogus: unknown field `bogus`, expected one of"));
        assert!(error("ppo: {n_stepz: 1}").starts_with("ppo.n_stepz: unknown field `n_stepz`"));
        assert!(error("ppo: {learning_rate: 0}").starts_with("ppo.learning_rate: must be positive"));
        assert!(
            error("ppo: {learning_rate: abc}").starts_with("ppo.learning_rate: expected a number")
        );
        assert!(error("ppo: {n_epochs: 0}").starts_with("ppo.n_epochs: must be in [1,"));
        assert!(error("ppo: {n_steps: 2.5}").starts_with(
            "ppo.n_steps: invalid type: floating point `2.5`, expected a non-negative integer"
        ));
        assert!(error("ppo: {batch_size: 100000}")
            .starts_with("ppo.batch_size: must be in [2, n_steps"));
        assert!(error("n_envs: -1")
            .starts_with("n_envs: invalid value: integer `-1`, expected a non-negative integer"));
        assert!(error("seed: 4294967296").starts_with("seed: must be in [0, 4294967295]"));
        assert!(error("arch: huge").starts_with("arch: unknown variant `huge`"));
        assert!(error("arch: {pi: []}").starts_with("arch.pi: must have 1 to 8 layers, got 0"));
        assert!(error("arch: {shared: [64, 0]}")
            .starts_with("arch.shared: layer widths must be in [1, 1024], got 0"));
        assert!(error("arch: {pi: [64, 1025]}")
            .starts_with("arch.pi: layer widths must be in [1, 1024], got 1025"));
        assert!(error("arch: {vf: [1, 1, 1, 1, 1, 1, 1, 1, 1]}")
            .starts_with("arch.vf: must have 1 to 8 layers, got 9"));
        assert!(error("arch: {heads: [64]}").starts_with("arch.heads: unknown field `heads`"));
        assert!(error("arch: {pi: [-1]}").starts_with("arch.pi[0]: invalid value"));
        assert!(error("arch: 3").starts_with("arch: invalid type: integer `3`"));
        assert!(error("log_std_init: 3").starts_with("log_std_init: must be in [-20, 2], got 3"));
        assert!(error("env: {reward: {progress_weight: a}}")
            .starts_with("env.reward.progress_weight: invalid type"));
        assert!(
            error("env: {goal: [true, false]}").starts_with("env.goal[0]: invalid type: boolean")
        );
        assert!(error("env: {max_episode_steps: 2.9}")
            .starts_with("env.max_episode_steps: invalid type: floating point"));
        assert!(error("env: {joints: 3}").starts_with("env.joints: set joints at the top level"));
        assert!(error("env: {snake: {link_mass: -1}}")
            .starts_with("env.snake.link_mass: must be positive"));
        assert!(
            error("env: {goal_radius: -1}").starts_with("env.goal_radius: must be in [0, 10000]")
        );
        assert!(error("- 1").starts_with("a configuration must be a mapping"));
        assert!(error("ppo: [1").starts_with("not valid YAML (line 2, column 1): did not find"));
    }

    #[test]
    fn energy_ramp_anneals_the_weight_in_and_is_checked() {
        let c = RunConfig::from_yaml(
            "energy_ramp: [100, 300]\nenv: {task: goal, reward: {energy_weight: 0.04}}",
        )
        .unwrap();
        let w = c.env_config().unwrap().reward.energy_weight;
        assert_eq!(w, 0.04);
        assert_eq!(c.energy_weight_at(0, w), 0.0);
        assert_eq!(c.energy_weight_at(99, w), 0.0);
        assert_eq!(c.energy_weight_at(100, w), 0.0);
        assert_eq!(c.energy_weight_at(200, w), 0.02);
        assert_eq!(c.energy_weight_at(300, w), 0.04);
        assert_eq!(c.energy_weight_at(10_000, w), 0.04);
        let step =
            RunConfig::from_yaml("energy_ramp: [50, 50]\nenv: {reward: {energy_weight: 0.5}}")
                .unwrap();
        assert_eq!(
            (
                step.energy_weight_at(49, 0.5),
                step.energy_weight_at(50, 0.5)
            ),
            (0.0, 0.5)
        );
        assert_eq!(RunConfig::default().energy_weight_at(0, 0.3), 0.3);
        assert!(
            error("energy_ramp: [300, 100]\nenv: {reward: {energy_weight: 1}}")
                .starts_with("energy_ramp: expected [from, to] timesteps with from <= to")
        );
        assert!(error("energy_ramp: [0, 100]")
            .starts_with("energy_ramp: env.reward.energy_weight is 0"));
        assert!(
            error("trainer: sb3\nenergy_ramp: [0, 1]\nenv: {reward: {energy_weight: 1}}")
                .starts_with("energy_ramp: only the native trainer")
        );
        assert!(error("energy_ramp: [-1, 2]").starts_with("energy_ramp"));
        assert!(IDENTITY_KEYS.contains(&"energy_ramp"));
    }

    #[test]
    fn overrides_nest_and_merge() {
        let o = parse_overrides(&[
            "ppo.learning_rate=3e-4",
            "env.reward.progress_weight=1",
            "joints=7",
        ])
        .unwrap();
        let base = parse_yaml("env: {reward: {smoothness_weight: 0.5}}").unwrap();
        let c = RunConfig::from_layers(&[base, o]).unwrap();
        assert_eq!(c.ppo.learning_rate, Schedule::Constant(3e-4));
        assert_eq!(c.joints, 7);
        let r = c.env_config().unwrap().reward;
        assert_eq!((r.progress_weight, r.smoothness_weight), (1.0, 0.5));
        assert!(parse_overrides(&["ppo.n_steps"]).is_err());
        assert!(parse_overrides(&["ppo..n=1"]).is_err());
    }

    #[test]
    fn env_keywords() {
        let kw = |text: &str| -> Map<String, Value> { serde_json::from_str(text).unwrap() };
        let c = env_from_keywords(&kw(
            r#"{"joints": 7, "preset": "snakebot-gym", "goal": [1, 2]}"#,
        ))
        .unwrap();
        assert_eq!(
            (c.joints(), c.snake.link_mass, c.goal),
            (7, 1.0, (1.0, 2.0))
        );
        assert_eq!(
            env_from_keywords(&Map::new()).unwrap(),
            EnvConfig::default()
        );
        let e = |text: &str| env_from_keywords(&kw(text)).unwrap_err().0;
        assert!(e(r#"{"joints": 2.5}"#).starts_with("joints: invalid type: floating point `2.5`"));
        assert!(e(r#"{"joints": 0}"#).starts_with("joints: must be in [1, 128], got 0"));
        assert!(e(r#"{"joints": true}"#).starts_with("joints: invalid type: boolean"));
        assert!(e(r#"{"preset": "x"}"#).starts_with("preset: unknown variant `x`"));
        assert!(e(r#"{"action_scale": "2"}"#).starts_with("action_scale: invalid type: string"));
        let d = env_keyword_defaults(Task::Paper);
        assert_eq!(d["joints"], 5);
        assert_eq!(d["max_episode_steps"], 5000);
        assert!(!d.contains_key("snake"));
        let g = env_keyword_defaults(Task::Goal);
        assert_eq!(g["max_episode_steps"], 600);
        assert_eq!(g["action"]["mode"], "gait");
        // A goal-task table over the task's defaults; null switches the goal distribution off.
        let c = env_from_keywords(&kw(
            r#"{"task": "goal", "joints": 10, "goal_distribution": {"distance": [2, 3]}}"#,
        ))
        .unwrap();
        let goals = c.goal_distribution.unwrap();
        assert_eq!(goals.distance, [2.0, 3.0]);
        assert_eq!(goals.bearing, [-std::f64::consts::PI, std::f64::consts::PI]);
        assert_eq!(
            (c.joints(), c.action_dim(), c.max_episode_steps),
            (10, 3, 600)
        );
        let c = env_from_keywords(&kw(r#"{"task": "goal", "goal_distribution": null}"#)).unwrap();
        assert_eq!(c.goal_distribution, None);
        assert_eq!(
            env_from_keywords(&kw("{}")).unwrap(),
            EnvConfig::default(),
            "the paper's env without keywords"
        );
        assert!(e(r#"{"task": "run"}"#).starts_with("task: unknown variant `run`"));
    }

    #[test]
    fn identity_keys_are_found() {
        let a = RunConfig::default();
        let mut b = a.clone();
        b.timesteps = 5;
        assert_eq!(a.identity_difference(&b), None);
        b.ppo.gamma = 0.9;
        assert_eq!(a.identity_difference(&b).unwrap().0, "ppo");
    }
}
