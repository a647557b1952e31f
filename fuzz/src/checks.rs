//! What every parser of a user's file must do with any input: give a value or a one-line error, never
//! a panic (or an abort, or a hang). One function per fuzz target, called by the target
//! (fuzz/fuzz_targets/) and by the regression test that replays fuzz/regressions/ and mutates real
//! files (tests/parsers.rs includes this file), so both check the same thing.

use std::path::Path;

use serde_json::Value;
use snake_rl::config::{env_from_keywords, parse_yaml, RunConfig};
use snake_rl::model::{parse_checkpoint, parse_policy};

fn one_line(message: &str) {
    assert!(
        !message.contains('\n'),
        "an error message of several lines: {message}"
    );
}

/// A model or checkpoint file (safetensors: header, metadata, tensors), as `snakesim evaluate` and
/// `--resume` read it.
pub fn model_file(bytes: &[u8]) {
    let path = Path::new("fuzzed.safetensors");
    if let Err(e) = parse_policy(path, bytes) {
        one_line(&e.0);
    }
    if let Err(e) = parse_checkpoint(path, bytes) {
        one_line(&e.0);
    }
}

/// A run configuration (YAML: `--config FILE.yaml`, a run's config.yaml); a valid one survives saving
/// and reloading unchanged.
pub fn run_config(bytes: &[u8]) {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    match parse_yaml(text).and_then(|layer| RunConfig::from_layers(&[layer])) {
        Ok(config) => {
            if config.validate().is_ok() {
                let again =
                    RunConfig::from_yaml(&config.to_yaml()).expect("a saved config reloads");
                assert_eq!(again, config);
            }
        }
        Err(e) => one_line(&e.0),
    }
}

/// The env's keywords (JSON: `snakesim.SnakeEnv(**kwargs)`, a model's `env` metadata).
pub fn env_keywords(bytes: &[u8]) {
    let Ok(Value::Object(keywords)) = serde_json::from_slice::<Value>(bytes) else {
        return;
    };
    if let Err(e) = env_from_keywords(&keywords) {
        one_line(&e.0);
    }
}
