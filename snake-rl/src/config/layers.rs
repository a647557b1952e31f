//! A configuration's layers, lowest precedence first: the defaults, YAML files, `--set KEY=VALUE`
//! overrides and flags, each a JSON mapping, merged key by key.

use serde::de;
use serde_json::{Map, Value};

use super::{err, key_err, ConfigError};
use crate::nn::Arch;

pub use snake_core::keys::merge;

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

pub(super) fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "a list",
        Value::Object(_) => "a mapping",
    }
}

/// Deserialises `value` as `T`, naming the key path of the first error (prefixed by `prefix`).
pub fn from_value<T: de::DeserializeOwned>(value: Value, prefix: &str) -> Result<T, ConfigError> {
    snake_core::keys::from_value(value, prefix).map_err(ConfigError::from)
}
