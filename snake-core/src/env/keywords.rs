//! The env's keywords: the one reading of `snakesim.SnakeEnv(**keywords)`, of a run configuration's
//! `env` table (snake-rl's `RunConfig`) and of `snake-cli env`'s flags into an [`EnvConfig`], every
//! check included. `joints` and `preset` choose the snake, `task` the defaults
//! ([`EnvConfig::for_task`]), the `snake` table overrides the preset's parameters, and every other key
//! is an [`EnvConfig`] field over the task's defaults. Errors name the key path
//! ([`crate::Invalid::key`]).
//!
//! ```
//! use snake_core::env::keywords::env_from_keywords;
//!
//! let keywords = serde_json::json!({"joints": 7, "task": "goal", "goal_radius": 0.5});
//! let config = env_from_keywords(keywords.as_object().unwrap())?;
//! assert_eq!((config.joints(), config.goal_radius), (7, 0.5));
//! let bad = serde_json::json!({"joints": 0});
//! let e = env_from_keywords(bad.as_object().unwrap()).unwrap_err();
//! assert_eq!(e.message(), "joints: must be in [1, 128], got 0");
//! # Ok::<(), snake_core::Error>(())
//! ```

use serde::Deserialize;
use serde_json::{Map, Value};

use super::{EnvConfig, Task};
use crate::config::{Preset, DEFAULT_JOINTS, DEFAULT_PRESET};
use crate::error::{invalid, invalid_at};
use crate::keys::{from_value, integer, merge};
use crate::{Error, Result};

/// The env's former `action` keys of the steering assist and the [`crate::SteerAssist`] keys they
/// became: keywords with them get an error saying where they went, a model recorded with them is read
/// with its assist (snake-rl's `model::take_legacy_assist`).
pub const LEGACY_ASSIST_KEYS: [(&str, &str); 2] = [
    ("steer_residual", "residual"),
    ("steer_near_goal", "near_goal"),
];

/// The env of a `preset` snake of `joints` joints and the keywords `table` (every keyword but
/// `joints` and `preset`). Errors name the key path under `prefix` (a run's `env` table), except those
/// about `joints`, a key of its own (the run's top level, or SnakeEnv's keyword).
pub fn env_config(
    joints: usize,
    preset: Preset,
    table: &Map<String, Value>,
    prefix: &str,
) -> Result<EnvConfig> {
    let at = |key: &str| {
        if prefix.is_empty() {
            key.to_owned()
        } else {
            format!("{prefix}.{key}")
        }
    };
    crate::limits::check_joints(joints)?;
    for key in ["joints", "preset"] {
        if table.contains_key(key) {
            return Err(invalid(format!(
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
            return Err(invalid(format!(
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
            return Err(invalid(format!(
                "{}: expected a mapping of snake parameters",
                at("snake")
            )));
        };
        if overrides.contains_key("joints") {
            return Err(invalid(format!(
                "{}: set joints with the joints key, not inside snake",
                at("snake.joints")
            )));
        }
        merge(&mut snake, &Value::Object(overrides));
    }
    object.insert("snake".into(), snake);
    merge(&mut base, &Value::Object(object));
    let config: EnvConfig = from_value(base, prefix)?;
    config.validate().map_err(|e| under(prefix, e))?;
    if task == Task::Swim && !config.has_water() {
        return Err(invalid(format!(
            "{}: task swim needs a world with water (e.g. world: worlds/pool.yaml, docs/media.md)",
            at("world")
        )));
    }
    Ok(config)
}

/// The env of `snakesim.SnakeEnv(**keywords)`: the keywords as one mapping, `joints` and `preset`
/// among them (defaults [`DEFAULT_JOINTS`] and [`DEFAULT_PRESET`]).
pub fn env_from_keywords(keywords: &Map<String, Value>) -> Result<EnvConfig> {
    let mut table = keywords.clone();
    let joints: usize = match table.remove("joints") {
        None => DEFAULT_JOINTS,
        Some(v) => {
            #[derive(Deserialize)]
            struct Joints(#[serde(deserialize_with = "integer::deserialize")] usize);
            let Joints(j) = from_value(v, "joints")?;
            j
        }
    };
    let preset: Preset = match table.remove("preset") {
        None => DEFAULT_PRESET,
        Some(v) => from_value(v, "preset")?,
    };
    env_config(joints, preset, &table, "")
}

/// Every env keyword with its default for `task` (`snakesim.SnakeEnv`: paper, `SnakeGoalEnv`:
/// goal), `snake` (the preset's parameters) left out.
pub fn env_keyword_defaults(task: Task) -> Map<String, Value> {
    let mut map = Map::new();
    map.insert("joints".into(), Value::from(DEFAULT_JOINTS));
    map.insert("preset".into(), Value::from(DEFAULT_PRESET.name()));
    let env = EnvConfig::for_task(task, DEFAULT_PRESET, DEFAULT_JOINTS);
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

/// An error of a configuration nested at `prefix`: its key path under `prefix`.
fn under(prefix: &str, e: Error) -> Error {
    match e {
        Error::InvalidArgument(m) => Error::InvalidArgument(m.under(prefix)),
        other if prefix.is_empty() => other,
        other => invalid_at(prefix, other.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kw(text: &str) -> Map<String, Value> {
        serde_json::from_str(text).unwrap()
    }

    fn e(text: &str) -> String {
        env_from_keywords(&kw(text)).unwrap_err().message()
    }

    #[test]
    fn keywords_choose_the_snake_and_the_task() {
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
    }

    #[test]
    fn errors_name_the_keyword() {
        assert!(e(r#"{"joints": 2.5}"#).starts_with("joints: invalid type: floating point `2.5`"));
        assert_eq!(e(r#"{"joints": 0}"#), "joints: must be in [1, 128], got 0");
        assert!(e(r#"{"joints": true}"#).starts_with("joints: invalid type: boolean"));
        assert!(e(r#"{"preset": "x"}"#).starts_with("preset: unknown variant `x`"));
        assert!(e(r#"{"action_scale": "2"}"#).starts_with("action_scale: invalid type: string"));
        assert!(e(r#"{"task": "run"}"#).starts_with("task: unknown variant `run`"));
        assert!(e(r#"{"action": {"steer_residual": true}}"#)
            .starts_with("action.steer_residual: baseline:steer left the env"));
        let table = kw(r#"{"goal_radius": -1}"#);
        let nested = env_config(5, Preset::Paper, &table, "env").unwrap_err();
        let Error::InvalidArgument(m) = nested else {
            panic!("an invalid argument")
        };
        assert_eq!(m.key(), Some("env.goal_radius"));
    }

    #[test]
    fn defaults_are_the_tasks() {
        let d = env_keyword_defaults(Task::Paper);
        assert_eq!(d["joints"], 5);
        assert_eq!(d["max_episode_steps"], 5000);
        assert!(!d.contains_key("snake"));
        let g = env_keyword_defaults(Task::Goal);
        assert_eq!(g["max_episode_steps"], 600);
        assert_eq!(g["action"]["mode"], "gait");
    }
}
