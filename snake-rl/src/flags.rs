//! The run configuration's command-line flags, defined once. `snake-cli train` (clap) and `snakesim
//! train` (argparse, from `snakesim._core.run_config_flags()`) build their flags from [`FLAGS`]: each
//! flag sets the configuration key of its name, and [`RunConfig`]'s checks judge the value (ranges,
//! names), so a flag's limits are its key's, and a help text quotes the default of
//! [`RunConfig::default`].

use std::path::PathBuf;

use serde_json::{json, Value};

use crate::config::{limits, RunConfig, TrainerKind, EVAL_SEED_OFFSET};
use crate::nn::Arch;

/// What a flag takes.
#[derive(Debug, Clone, Copy)]
pub enum FlagValue {
    /// A whole number in `[min, max]` (underscores allowed, as `20_000_000`); the configuration checks
    /// the rest of its range, naming the key.
    Integer {
        /// Smallest value the flag takes.
        min: u64,
        /// Largest, where the command line checks it.
        max: Option<u64>,
    },
    /// One of the names the function gives.
    Choice(fn() -> Vec<&'static str>),
    /// Present or absent: present sets the key to `true`.
    Switch,
    /// Text the configuration checks.
    Text,
}

/// One configuration key's flag.
#[derive(Debug, Clone, Copy)]
pub struct Flag {
    /// The configuration key (`n_envs`); the flag is `--n-envs`.
    pub key: &'static str,
    /// What it takes.
    pub value: FlagValue,
    /// What it does, without its default (see [`Flag::help`]).
    pub about: &'static str,
    /// Only the SB3 trainer (through Python) reads it: `snake-cli train` has no such flag.
    pub sb3_only: bool,
}

fn trainers() -> Vec<&'static str> {
    vec![TrainerKind::Native.name(), TrainerKind::Sb3.name()]
}

fn archs() -> Vec<&'static str> {
    Arch::NAMES.to_vec()
}

fn presets() -> Vec<&'static str> {
    snake_core::Preset::ALL.iter().map(|p| p.name()).collect()
}

/// A whole number of at least `min`.
const fn at_least(min: u64) -> FlagValue {
    FlagValue::Integer { min, max: None }
}

const fn flag(key: &'static str, value: FlagValue, about: &'static str) -> Flag {
    Flag {
        key,
        value,
        about,
        sb3_only: false,
    }
}

/// Every run-configuration flag, in the order `--help` lists them. (`--trainer` chooses between the
/// trainers, so only `snakesim train`, which runs both, offers it.)
pub const FLAGS: &[Flag] = &[
    Flag {
        sb3_only: true,
        ..flag(
            "trainer",
            FlagValue::Choice(trainers),
            "native: snake-rl, the whole loop in Rust; sb3: Stable-Baselines3",
        )
    },
    flag("joints", at_least(1), "Snake joints"),
    flag(
        "arch",
        FlagValue::Choice(archs),
        "Network: small (pi/vf [64, 64]) or large (shared [128, 128] first); other widths: \
         --set arch.pi=[256,256] (and arch.vf, arch.shared)",
    ),
    flag("preset", FlagValue::Choice(presets), "Robot preset"),
    flag("timesteps", at_least(1), "Total timesteps"),
    flag("n_envs", at_least(1), "Parallel envs"),
    flag(
        "seed",
        FlagValue::Integer {
            min: 0,
            max: Some(limits::MAX_SEED),
        },
        "Seed",
    ),
    flag(
        "eval_freq",
        at_least(0),
        "Evaluate every N timesteps; 0: at the end only",
    ),
    flag("eval_episodes", at_least(1), "Episodes per evaluation"),
    flag("eval_seed", at_least(0), "Seed of the evaluation episodes"),
    flag(
        "checkpoint_freq",
        at_least(0),
        "Checkpoint every N timesteps; 0: only the final one",
    ),
    flag(
        "normalize",
        FlagValue::Switch,
        "Normalise observations and rewards (SB3's VecNormalize)",
    ),
    flag(
        "threads",
        at_least(1),
        "Native trainer: threads for the envs and the updates",
    ),
    Flag {
        sb3_only: true,
        ..flag(
            "device",
            FlagValue::Text,
            "SB3 trainer: torch device, auto, cpu, cuda or cuda:N",
        )
    },
    Flag {
        sb3_only: true,
        ..flag(
            "torch_threads",
            at_least(1),
            "SB3 trainer: torch CPU threads",
        )
    },
];

impl Flag {
    /// `--n-envs` for the key `n_envs`.
    pub fn name(&self) -> String {
        format!("--{}", self.key.replace('_', "-"))
    }

    /// The help text: what it does and its default.
    pub fn help(&self) -> String {
        let defaults = serde_json::to_value(RunConfig::default()).expect("serialises");
        let default = match (self.key, &defaults[self.key]) {
            ("eval_seed", Value::Null) => format!("seed + {EVAL_SEED_OFFSET}"),
            ("threads", Value::Null) => "one per core".into(),
            ("torch_threads", Value::Null) => "torch's".into(),
            (_, Value::String(s)) => s.clone(),
            (_, Value::Bool(false)) => "off".into(),
            (_, v) => v.to_string(),
        };
        format!("{} (default {default})", self.about)
    }

    /// The flag as data, for the Python command line: key, flag, value kind, choices, help.
    pub fn describe(&self) -> Value {
        let (kind, choices, range) = match self.value {
            FlagValue::Integer { min, max } => ("integer", vec![], json!([min, max])),
            FlagValue::Choice(names) => ("choice", names(), Value::Null),
            FlagValue::Switch => ("switch", vec![], Value::Null),
            FlagValue::Text => ("text", vec![], Value::Null),
        };
        json!({
            "key": self.key,
            "flag": self.name(),
            "value": kind,
            "choices": choices,
            "range": range,
            "help": self.help(),
            "sb3_only": self.sb3_only,
        })
    }
}

/// A whole number as the command line writes it (`20000000`, `20_000_000`), in `[min, max]`.
pub fn parse_integer(text: &str, min: u64, max: Option<u64>) -> Result<u64, String> {
    let value: u64 = text
        .replace('_', "")
        .parse()
        .map_err(|_| format!("expected an integer, got '{text}'"))?;
    if value < min {
        return Err(format!("expected an integer >= {min}, got {value}"));
    }
    match max {
        Some(max) if value > max => Err(format!("expected an integer <= {max}, got {value}")),
        _ => Ok(value),
    }
}

/// Where a run goes when no `--run-dir` is given: `runs/ppo-ARCH-JOINTS-PRESET-seedSEED`, the same
/// for both trainers and both commands.
pub fn default_run_dir(config: &RunConfig) -> PathBuf {
    PathBuf::from("runs").join(format!(
        "ppo-{}-{}-{}-seed{}",
        config.arch.name().unwrap_or("custom"),
        config.joints,
        config.preset,
        config.seed
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_flag_is_a_configuration_key_that_takes_its_value() {
        let defaults = serde_json::to_value(RunConfig::default()).unwrap();
        for f in FLAGS {
            assert!(
                defaults.get(f.key).is_some(),
                "{} is no configuration key",
                f.key
            );
            let value = match f.value {
                FlagValue::Integer { .. } => json!(2),
                FlagValue::Choice(names) => json!(names()[0]),
                FlagValue::Switch => json!(true),
                FlagValue::Text => json!("cpu"),
            };
            let layer = json!({ f.key: value });
            RunConfig::from_layers(&[layer]).unwrap_or_else(|e| panic!("{}: {e}", f.key));
        }
    }

    #[test]
    fn help_quotes_the_default() {
        let by_key = |k: &str| FLAGS.iter().find(|f| f.key == k).unwrap().help();
        assert_eq!(by_key("timesteps"), "Total timesteps (default 20000000)");
        assert_eq!(
            by_key("eval_seed"),
            "Seed of the evaluation episodes (default seed + 1000)"
        );
        assert_eq!(by_key("arch").split(" (default ").nth(1), Some("small)"));
        assert_eq!(
            by_key("normalize"),
            "Normalise observations and rewards (SB3's VecNormalize) (default off)"
        );
        assert_eq!(parse_integer("20_000_000", 1, None), Ok(20_000_000));
        assert!(parse_integer("-1", 0, None).is_err());
        assert_eq!(
            parse_integer("4294967296", 0, Some(limits::MAX_SEED)),
            Err("expected an integer <= 4294967295, got 4294967296".into())
        );
    }
}
