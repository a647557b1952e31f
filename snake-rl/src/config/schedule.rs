//! Hyperparameters that may decay over training (`lin_<initial>`).

use serde::de::{self, Deserializer};
use serde::{Deserialize, Serialize, Serializer};

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
