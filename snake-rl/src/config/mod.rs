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

use serde_json::{Map, Value};
use snake_core::env::Task;
use snake_core::{EnvConfig, Preset};

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

mod init;
mod layers;
pub mod limits;
mod ppo;
mod run;
mod schedule;
#[cfg(test)]
mod tests;

pub use init::InitConfig;
pub use layers::{from_value, merge, merge_layer, parse_overrides, parse_yaml};
pub use ppo::PpoConfig;
pub use run::{RunConfig, TrainerKind, EVAL_SEED_OFFSET, IDENTITY_KEYS};
pub use schedule::Schedule;
/// The env's keywords live beside the env, in snake-core ([`snake_core::env::keywords`]).
pub use snake_core::env::keywords::LEGACY_ASSIST_KEYS;

impl From<snake_core::Error> for ConfigError {
    /// A snake-core error about a configuration value: its key path kept apart, as snake-core keeps
    /// it ([`snake_core::Invalid::key`]).
    fn from(e: snake_core::Error) -> Self {
        match e {
            snake_core::Error::InvalidArgument(m) => match m.key() {
                Some(key) => key_err(key, m.detail()),
                None => err(m.to_string()),
            },
            other => err(other.to_string()),
        }
    }
}

/// The env of a run's `env` table ([`snake_core::env::keywords::env_config`]), errors as
/// configuration errors.
pub fn env_config(
    joints: usize,
    preset: Preset,
    table: &Map<String, Value>,
    prefix: &str,
) -> Result<EnvConfig, ConfigError> {
    Ok(snake_core::env::keywords::env_config(
        joints, preset, table, prefix,
    )?)
}

/// The env of `snakesim.SnakeEnv(**keywords)` ([`snake_core::env::keywords::env_from_keywords`]),
/// errors as configuration errors.
pub fn env_from_keywords(keywords: &Map<String, Value>) -> Result<EnvConfig, ConfigError> {
    Ok(snake_core::env::keywords::env_from_keywords(keywords)?)
}

/// Every env keyword with its default for `task` ([`snake_core::env::keywords::env_keyword_defaults`]).
pub fn env_keyword_defaults(task: Task) -> Map<String, Value> {
    snake_core::env::keywords::env_keyword_defaults(task)
}

/// A value that a range check reads as a number.
trait Real: Copy {
    fn real(self) -> f64;
}

impl Real for u64 {
    fn real(self) -> f64 {
        self as f64
    }
}

impl Real for f64 {
    fn real(self) -> f64 {
        self
    }
}

/// `key: must be in [low, high], got value` ([`snake_core::limits::check_key_range`]).
fn check_range<T: Real>(key: &str, value: T, low: T, high: T) -> Result<(), ConfigError> {
    Ok(snake_core::limits::check_key_range(
        key,
        value.real(),
        low.real(),
        high.real(),
    )?)
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
