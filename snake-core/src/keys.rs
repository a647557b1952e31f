//! Configuration values as JSON, read into typed ones with the key path of every error: the env's
//! keywords ([`crate::env::keywords`]) and snake-rl's run configuration both go through here.
//!
//! ```
//! use serde_json::json;
//! use snake_core::keys::{from_value, merge};
//!
//! let mut base = json!({"reward": {"progress_weight": 1.0, "energy_weight": 0.0}});
//! merge(&mut base, &json!({"reward": {"energy_weight": 0.5}}));
//! assert_eq!(base["reward"]["progress_weight"], 1.0);
//! let e = from_value::<snake_core::RewardConfig>(json!({"bogus": 1}), "reward").unwrap_err();
//! assert!(e.message().starts_with("reward.bogus: unknown field `bogus`"));
//! ```

use serde::de::DeserializeOwned;
use serde_json::Value;

use crate::error::{invalid, invalid_at};
use crate::files::{quoted_excerpts, withheld_unless_name};
use crate::Result;

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

/// Deserialises `value` as `T`, naming the key path of the first error (prefixed by `prefix`); the
/// error carries the path apart from what is wrong ([`crate::Invalid::key`]).
pub fn from_value<T: DeserializeOwned>(value: Value, prefix: &str) -> Result<T> {
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
        let inner = quoted_excerpts(&e.into_inner().to_string());
        if path.is_empty() {
            invalid(inner)
        } else {
            invalid_at(path, inner)
        }
    })
}

/// A key path as serde_path_to_error writes it (`a.b[0].c`, `.` for the root), each key shown as
/// [`withheld_unless_name`] shows it.
fn shown_path(path: &serde_path_to_error::Path) -> String {
    use serde_path_to_error::Segment;
    let mut out = String::new();
    for segment in path {
        let part = match segment {
            Segment::Seq { index } => {
                out.push_str(&format!("[{index}]"));
                continue;
            }
            Segment::Map { key } => withheld_unless_name(key),
            Segment::Enum { variant } => withheld_unless_name(variant),
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

/// Integer fields that accept YAML/JSON integers and integral floats (`2e7`), nothing else:
/// `#[serde(deserialize_with = "snake_core::keys::integer::deserialize")]`.
pub mod integer {
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

    /// A non-negative integer (an integral float included) as `T`.
    pub fn deserialize<'de, D: Deserializer<'de>, T: TryFrom<u64>>(d: D) -> Result<T, D::Error> {
        let v = d.deserialize_any(Integral)?;
        T::try_from(v).map_err(|_| de::Error::custom(format!("{v} is too large")))
    }

    /// The same for an optional field (`null`: `None`).
    pub mod option {
        use serde::{Deserialize, Deserializer};

        /// A non-negative integer as `Some(T)`, or `None` for null.
        pub fn deserialize<'de, D: Deserializer<'de>, T: TryFrom<u64>>(
            d: D,
        ) -> Result<Option<T>, D::Error> {
            #[derive(Deserialize)]
            struct Wrap<T: TryFrom<u64>>(#[serde(deserialize_with = "super::deserialize")] T);
            Option::<Wrap<T>>::deserialize(d).map(|o| o.map(|Wrap(v)| v))
        }
    }
}

/// The one of `all` whose `name_of` is `name`; the error (a `what`) lists the names.
pub(crate) fn by_name<T: Copy>(
    all: &[T],
    name_of: fn(T) -> &'static str,
    name: &str,
    what: &str,
) -> Result<T> {
    all.iter()
        .copied()
        .find(|c| name_of(*c) == name)
        .ok_or_else(|| {
            let names: Vec<_> = all.iter().map(|c| name_of(*c)).collect();
            // `invalid` caps the message, so a hostile name cannot flood it.
            invalid(format!(
                "unknown {what} '{name}' (expected one of: {})",
                names.join(", ")
            ))
        })
}
