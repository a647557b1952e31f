//! Saved policies and training checkpoints: safetensors files whose tensors carry Stable-Baselines3's
//! `state_dict` names and whose JSON metadata says what the policy acts on.
//!
//! A policy file (`model.safetensors`) holds the network's tensors (float32), and, when the run
//! normalised observations, `obs_rms.mean` and `obs_rms.var` (float64). Its metadata (all strings):
//!
//! | key | value |
//! |---|---|
//! | `format` | `snakesim-ppo` |
//! | `format_version` | `1` |
//! | `arch` | `small`, `large`, or the widths as JSON (`{"shared":[],"pi":[256,256],"vf":[256,256]}`) |
//! | `obs_dim`, `act_dim` | observation and action lengths |
//! | `joints`, `preset` | the snake |
//! | `env` | the run's env keywords (JSON), as `snakesim.SnakeEnv` takes them |
//! | `env_config` | the complete resolved env configuration (JSON); on loading, values the `env` keywords now resolve differently are pinned to it (`pin_recorded_env`) |
//! | `env_files` | present when the env has a robot or world file: the texts of the files it was built from, `{"robot": {"path": "robots/yaw-pitch-16.yaml", "files": {"yaw-pitch-16.yaml": "...", "yaw-pitch-16.urdf": "..."}}, "world": {...}}` ([`snake_core::RecordedFiles`]); on loading, a file that differs from its record (or is missing) is replaced by the record ([`apply_env_files`]) |
//! | `observation` | the observation layout (`paper`, `extended`, `terrain`) |
//! | `action` | the action layout: `N joint targets in [-1, 1] x action_scale rad, head to tail` |
//! | `steer_assist` | present when `baseline:steer` shares the policy's actions: the assist (JSON, [`SteerAssist`]), applied between the policy and the env wherever the model acts |
//! | `normalize` | `true` when observations are normalised with `obs_rms` (clip 10, eps 1e-8) |
//! | `timesteps` | timesteps trained |
//!
//! A checkpoint (`checkpoints/model_<T>_steps.safetensors`) adds what resuming needs: Adam's moments
//! (`adam.exp_avg`, `adam.exp_avg_sq`), the return statistics (`ret_rms.*`), and in its metadata
//! Adam's step, the statistics' counts, the random generator's state, the updates done and the wall
//! time.

use std::collections::HashMap;
use std::path::Path;

use rand_chacha::ChaCha12Rng;
use safetensors::{Dtype, SafeTensors};
use serde_json::{Map, Value};
use snake_core::{EnvConfig, Preset, RecordedFiles, SteerAssist};

use crate::nn::{ActorCritic, Arch};
use crate::normalize::{Normalizer, RunningMeanStd};
use crate::optim::Adam;

/// The `format` tag of our files.
pub const FORMAT: &str = "snakesim-ppo";
/// The version of the layout described above.
pub const FORMAT_VERSION: &str = "1";

/// A model file that cannot be used; the message says which file and why.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct ModelError(pub String);

/// What a policy acts on: the snake and the env's keywords.
#[derive(Debug, Clone, PartialEq)]
pub struct EnvSpec {
    /// Joints N.
    pub joints: usize,
    /// The robot preset.
    pub preset: Preset,
    /// The other env keywords (as the run's `env` table).
    pub env: Map<String, Value>,
}

impl EnvSpec {
    /// The resolved env configuration.
    pub fn config(&self) -> Result<EnvConfig, crate::config::ConfigError> {
        crate::config::env_config(self.joints, self.preset, &self.env, "env")
    }
}

/// A trained policy: network, parameters, observation statistics and its env.
#[derive(Debug, Clone, PartialEq)]
pub struct SavedPolicy {
    /// The network.
    pub net: ActorCritic,
    /// Its parameters (layout [`ActorCritic::tensors`]).
    pub params: Vec<f32>,
    /// Observation statistics when the policy acts on normalised observations.
    pub obs_rms: Option<RunningMeanStd>,
    /// The env it was trained in.
    pub env: EnvSpec,
    /// `baseline:steer`'s share of its actions, when it was trained with one.
    pub steer_assist: Option<SteerAssist>,
    /// Timesteps it was trained for.
    pub timesteps: u64,
}

/// The state a run resumes from.
#[derive(Debug, Clone, PartialEq)]
pub struct Checkpoint {
    /// The policy.
    pub policy: SavedPolicy,
    /// Adam's state.
    pub adam: Adam,
    /// Observation and return statistics (runs with `normalize: true`).
    pub normalizer: Option<Normalizer>,
    /// The generator of actions and minibatches.
    pub rng: ChaCha12Rng,
    /// Updates done.
    pub n_updates: u64,
    /// Wall time of the run so far, seconds.
    pub wall_time: f64,
    /// Why it was written (`periodic`, `final`, `interrupt`, `non-finite`).
    pub reason: String,
    /// Written during the run's `init` (initialisation by imitation), before its end: a run resumed
    /// from it starts the initialisation over. Metadata `init: pending`, absent otherwise.
    pub init_pending: bool,
}

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn f64_bytes(v: &[f64]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// Writes `bytes` to `path` through a temporary file and a rename, so that a failure never leaves a
/// truncated file behind (nor destroys an older one).
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.tmp{}", std::process::id()));
    let result = std::fs::write(&tmp, bytes).and_then(|()| std::fs::rename(&tmp, path));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

struct Entry {
    name: String,
    dtype: Dtype,
    shape: Vec<usize>,
    data: Vec<u8>,
}

fn policy_entries(p: &SavedPolicy) -> (Vec<Entry>, HashMap<String, String>) {
    let mut entries: Vec<Entry> = p
        .net
        .tensors()
        .into_iter()
        .map(|t| Entry {
            data: f32_bytes(&p.params[t.offset..t.offset + t.len()]),
            name: t.name,
            dtype: Dtype::F32,
            shape: t.shape,
        })
        .collect();
    if let Some(rms) = &p.obs_rms {
        for (name, v) in [("obs_rms.mean", &rms.mean), ("obs_rms.var", &rms.var)] {
            entries.push(Entry {
                name: name.into(),
                dtype: Dtype::F64,
                shape: vec![v.len()],
                data: f64_bytes(v),
            });
        }
    }
    let config = p.env.config().ok();
    let mut meta: HashMap<String, String> = [
        ("format", FORMAT.to_owned()),
        ("format_version", FORMAT_VERSION.to_owned()),
        ("arch", p.net.arch().to_meta()),
        ("obs_dim", p.net.obs_dim().to_string()),
        ("act_dim", p.net.act_dim().to_string()),
        ("joints", p.env.joints.to_string()),
        ("preset", p.env.preset.name().to_owned()),
        ("env", Value::Object(p.env.env.clone()).to_string()),
        ("normalize", p.obs_rms.is_some().to_string()),
        ("timesteps", p.timesteps.to_string()),
        ("snakesim_version", env!("CARGO_PKG_VERSION").to_owned()),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_owned(), v))
    .collect();
    if let Some(c) = config {
        meta.insert(
            "env_config".into(),
            serde_json::to_string(&c).expect("serialises"),
        );
        if let Some(files) = env_files(&c) {
            meta.insert("env_files".into(), files.to_string());
        }
        meta.insert("observation".into(), c.observation.name().to_owned());
        meta.insert(
            "action".into(),
            match c.action.mode {
                snake_core::env::ActionMode::Joints => format!(
                    "{} joint targets in [-1, 1] x action_scale {} rad, head to tail",
                    c.joints(),
                    c.action_scale
                ),
                snake_core::env::ActionMode::Gait => format!(
                    "gait: steering {:?} rad, amplitude {:?} rad, frequency {:?} Hz, each from [-1, 1]{}",
                    c.action.steering,
                    c.action.amplitude,
                    c.action.frequency,
                    p.steer_assist
                        .map(|a| format!("; {}", a.describe()))
                        .unwrap_or_default()
                ),
                snake_core::env::ActionMode::Residual => format!(
                    "residual: {} corrections in [-1, 1] x {} rad added to the default wave, head to tail",
                    c.joints(),
                    c.action.residual_scale
                ),
            },
        );
    }
    if let Some(assist) = &p.steer_assist {
        meta.insert(
            "steer_assist".into(),
            serde_json::to_string(assist).expect("serialises"),
        );
    }
    if let Some(rms) = &p.obs_rms {
        meta.insert("obs_rms.count".into(), format!("{:?}", rms.count));
    }
    (entries, meta)
}

fn serialize(entries: &[Entry], meta: HashMap<String, String>) -> Vec<u8> {
    let views: Vec<(String, safetensors::tensor::TensorView<'_>)> = entries
        .iter()
        .map(|e| {
            let view = safetensors::tensor::TensorView::new(e.dtype, e.shape.clone(), &e.data)
                .expect("tensor sizes match their shapes");
            (e.name.clone(), view)
        })
        .collect();
    safetensors::serialize(views, Some(meta)).expect("tensors serialise")
}

/// Writes a policy file.
pub fn save_policy(path: &Path, policy: &SavedPolicy) -> std::io::Result<()> {
    let (entries, meta) = policy_entries(policy);
    write_atomically(path, &serialize(&entries, meta))
}

/// Writes a checkpoint.
pub fn save_checkpoint(path: &Path, c: &Checkpoint) -> std::io::Result<()> {
    let (mut entries, mut meta) = policy_entries(&c.policy);
    let n = c.policy.net.len();
    for (name, v) in [
        ("adam.exp_avg", &c.adam.exp_avg),
        ("adam.exp_avg_sq", &c.adam.exp_avg_sq),
    ] {
        entries.push(Entry {
            name: name.into(),
            dtype: Dtype::F32,
            shape: vec![n],
            data: f32_bytes(v),
        });
    }
    meta.insert("adam.step".into(), c.adam.step.to_string());
    if let Some(norm) = &c.normalizer {
        for (name, v) in [
            ("ret_rms.mean", &norm.ret_rms.mean),
            ("ret_rms.var", &norm.ret_rms.var),
        ] {
            entries.push(Entry {
                name: name.into(),
                dtype: Dtype::F64,
                shape: vec![v.len()],
                data: f64_bytes(v),
            });
        }
        meta.insert("ret_rms.count".into(), format!("{:?}", norm.ret_rms.count));
        meta.insert("normalize.gamma".into(), format!("{:?}", norm.gamma));
    }
    meta.insert(
        "rng".into(),
        serde_json::to_string(&c.rng).expect("the generator serialises"),
    );
    meta.insert("n_updates".into(), c.n_updates.to_string());
    meta.insert("wall_time".into(), format!("{:?}", c.wall_time));
    meta.insert("reason".into(), c.reason.clone());
    if c.init_pending {
        meta.insert("init".into(), "pending".into());
    }
    write_atomically(path, &serialize(&entries, meta))
}

/// A running statistic's count: SB3's starts at 1e-4 and only grows.
const COUNT_RANGE: std::ops::RangeInclusive<f64> = f64::MIN_POSITIVE..=f64::MAX;

/// A parsed file: its tensors and metadata.
struct Parsed<'a> {
    path: &'a Path,
    tensors: SafeTensors<'a>,
    meta: HashMap<String, String>,
}

impl<'a> Parsed<'a> {
    fn new(path: &'a Path, bytes: &'a [u8]) -> Result<Self, ModelError> {
        let bad = |why: String| {
            ModelError(crate::one_line(format!(
                "{} is not a snakesim model: {why}",
                path.display()
            )))
        };
        let (_, metadata) = SafeTensors::read_metadata(bytes)
            .map_err(|e| bad(format!("corrupt or truncated safetensors file ({e})")))?;
        let tensors = SafeTensors::deserialize(bytes)
            .map_err(|e| bad(format!("corrupt or truncated safetensors file ({e})")))?;
        let meta = metadata.metadata().clone().unwrap_or_default();
        match meta.get("format").map(String::as_str) {
            Some(FORMAT) => {}
            Some(other) => return Err(bad(format!("its format is '{other}', not '{FORMAT}'"))),
            None => return Err(bad("it has no 'format' metadata".into())),
        }
        if meta.get("format_version").map(String::as_str) != Some(FORMAT_VERSION) {
            return Err(bad(format!(
                "format version {:?} is not {FORMAT_VERSION} (made by another snakesim version)",
                meta.get("format_version")
            )));
        }
        Ok(Parsed {
            path,
            tensors,
            meta,
        })
    }

    fn error(&self, why: impl std::fmt::Display) -> ModelError {
        ModelError(crate::one_line(format!("{}: {why}", self.path.display())))
    }

    fn meta(&self, key: &str) -> Result<&str, ModelError> {
        self.meta
            .get(key)
            .map(String::as_str)
            .ok_or_else(|| self.error(format!("metadata '{key}' is missing")))
    }

    fn parse<T: std::str::FromStr>(&self, key: &str) -> Result<T, ModelError> {
        let text = self.meta(key)?;
        text.parse()
            .map_err(|_| self.error(format!("metadata '{key}' = '{text}' is not valid")))
    }

    /// A finite number in `range` (a count, a discount, a time): NaN or an impossible value in a
    /// model's metadata would poison every observation or step it touches, so it is refused by name.
    fn parse_in(&self, key: &str, range: std::ops::RangeInclusive<f64>) -> Result<f64, ModelError> {
        let value: f64 = self.parse(key)?;
        if !value.is_finite() || !range.contains(&value) {
            return Err(self.error(format!(
                "metadata '{key}' = {value} is out of range (expected a finite number in [{}, {}])",
                range.start(),
                range.end()
            )));
        }
        Ok(value)
    }

    /// Variances: finite (see [`Parsed::f64s`]) and never negative.
    fn variances(&self, name: &str, len: usize) -> Result<Vec<f64>, ModelError> {
        let v = self.f64s(name, len)?;
        if v.iter().any(|&x| x < 0.0) {
            return Err(self.error(format!("tensor '{name}' holds negative variances")));
        }
        Ok(v)
    }

    fn values<T, const B: usize>(
        &self,
        name: &str,
        dtype: Dtype,
        len: usize,
        from: fn([u8; B]) -> T,
    ) -> Result<Vec<T>, ModelError> {
        let view = self
            .tensors
            .tensor(name)
            .map_err(|_| self.error(format!("tensor '{name}' is missing")))?;
        if view.dtype() != dtype {
            return Err(self.error(format!(
                "tensor '{name}' is {:?}, expected {dtype:?}",
                view.dtype()
            )));
        }
        let count: usize = view.shape().iter().product();
        if count != len {
            return Err(self.error(format!(
                "tensor '{name}' has shape {:?} ({count} values), expected {len}",
                view.shape()
            )));
        }
        Ok(view
            .data()
            .chunks_exact(B)
            .map(|c| from(c.try_into().expect("chunk of B bytes")))
            .collect())
    }

    fn f32s(&self, name: &str, len: usize) -> Result<Vec<f32>, ModelError> {
        let v = self.values(name, Dtype::F32, len, f32::from_le_bytes)?;
        if v.iter().any(|x| !x.is_finite()) {
            return Err(self.error(format!("tensor '{name}' holds non-finite values")));
        }
        Ok(v)
    }

    fn f64s(&self, name: &str, len: usize) -> Result<Vec<f64>, ModelError> {
        let v = self.values(name, Dtype::F64, len, f64::from_le_bytes)?;
        if v.iter().any(|x| !x.is_finite()) {
            return Err(self.error(format!("tensor '{name}' holds non-finite values")));
        }
        Ok(v)
    }

    /// The policy, and notes for the user (a robot file that changed since training).
    fn policy(&self) -> Result<(SavedPolicy, Vec<String>), ModelError> {
        let arch: Arch = self
            .meta("arch")?
            .parse()
            .map_err(|e: String| self.error(e))?;
        let obs_dim: usize = self.parse("obs_dim")?;
        let act_dim: usize = self.parse("act_dim")?;
        let joints: usize = self.parse("joints")?;
        let preset: Preset = self
            .meta("preset")?
            .parse()
            .map_err(|e: snake_core::Error| self.error(e))?;
        let mut env: Map<String, Value> = serde_json::from_str(self.meta("env")?)
            .map_err(|e| self.error(format!("metadata 'env' is not a JSON mapping ({e})")))?;
        find_env_files(&mut env, self.path);
        let records = match self.meta.get("env_files") {
            None => Value::Object(Map::new()),
            Some(text) => serde_json::from_str::<Value>(text)
                .map_err(|e| self.error(format!("metadata 'env_files' is not JSON ({e})")))?,
        };
        let notes = apply_env_files(&mut env, &records)
            .map_err(|e| self.error(e))?
            .into_iter()
            .map(|n| crate::one_line(format!("{}: {n}", self.path.display())))
            .collect();
        let mut recorded = match self.meta.get("env_config") {
            None => None,
            Some(text) => Some(
                serde_json::from_str::<Value>(text)
                    .ok()
                    .filter(Value::is_object)
                    .ok_or_else(|| self.error("metadata 'env_config' is not a JSON mapping"))?,
            ),
        };
        let legacy = take_legacy_assist(&mut env, recorded.as_mut()).map_err(|e| self.error(e))?;
        let steer_assist = match (self.meta.get("steer_assist"), legacy) {
            (None, legacy) => legacy,
            (Some(_), Some(_)) => {
                return Err(
                    self.error("it records a steer_assist and the env's former action keys of one")
                )
            }
            (Some(text), None) => Some(serde_json::from_str(text).map_err(|e| {
                self.error(format!("metadata 'steer_assist' is not an assist ({e})"))
            })?),
        };
        let mut spec = EnvSpec {
            joints,
            preset,
            env,
        };
        let mut config = spec
            .config()
            .map_err(|e| self.error(format!("its env does not build: {e}")))?;
        if let Some(recorded) = recorded {
            (spec, config) =
                pin_recorded_env(spec, config, &recorded).map_err(|e| self.error(e))?;
        }
        if let Some(assist) = steer_assist {
            assist
                .bind(&config)
                .map_err(|e| self.error(format!("its steer_assist: {}", e.message())))?;
        }
        if (config.observation_dim(), config.action_dim()) != (obs_dim, act_dim) {
            return Err(self.error(format!(
                "its env has {} observations and {} actions, but the network has {obs_dim} and {act_dim}",
                config.observation_dim(),
                config.action_dim()
            )));
        }
        let space = 1..=snake_core::limits::MAX_SPACE_SIZE;
        if !space.contains(&obs_dim) || !space.contains(&act_dim) {
            return Err(self.error(format!(
                "implausible sizes obs_dim {obs_dim}, act_dim {act_dim}"
            )));
        }
        let net = ActorCritic::new(arch, obs_dim, act_dim);
        let mut params = vec![0.0f32; net.len()];
        for t in net.tensors() {
            let v = self.f32s(&t.name, t.len())?;
            params[t.offset..t.offset + t.len()].copy_from_slice(&v);
        }
        let normalize: bool = self.parse("normalize")?;
        let obs_rms = if normalize {
            Some(RunningMeanStd {
                mean: self.f64s("obs_rms.mean", obs_dim)?,
                var: self.variances("obs_rms.var", obs_dim)?,
                count: self.parse_in("obs_rms.count", COUNT_RANGE)?,
            })
        } else {
            None
        };
        let policy = SavedPolicy {
            net,
            params,
            obs_rms,
            env: spec,
            steer_assist,
            timesteps: self.parse("timesteps")?,
        };
        Ok((policy, notes))
    }
}

/// Models trained before the assist left the env record it as `action.steer_residual` and
/// `action.steer_near_goal` of their env keywords (and of `env_config`): those are taken out of both
/// and returned as the assist they meant, so such a model acts as it was trained.
fn take_legacy_assist(
    env: &mut Map<String, Value>,
    recorded: Option<&mut Value>,
) -> Result<Option<SteerAssist>, String> {
    let mut assist = Map::new();
    if let Some(Value::Object(action)) = env.get_mut("action") {
        for (old, new) in crate::config::LEGACY_ASSIST_KEYS {
            if let Some(v) = action.remove(old) {
                assist.insert(new.to_owned(), v);
            }
        }
    }
    // The resolved configuration is what the model was trained in: its values win.
    if let Some(Value::Object(action)) = recorded.and_then(|r| r.get_mut("action")) {
        for (old, new) in crate::config::LEGACY_ASSIST_KEYS {
            if let Some(v) = action.remove(old) {
                assist.insert(new.to_owned(), v);
            }
        }
    }
    // Written as false and 0 when off (the keys were left out then, but a hand-edited file may have
    // them): no assist.
    let off = |v: &Value| v == &Value::Bool(false) || v.as_f64() == Some(0.0);
    if assist.values().all(off) {
        return Ok(None);
    }
    serde_json::from_value(Value::Object(assist))
        .map(Some)
        .map_err(|e| {
            format!("its env's action.steer_residual or steer_near_goal is not valid ({e})")
        })
}

/// The env keys that name files. A model records them as they were given to the trainer, usually
/// relative to the directory it ran in (the repository's root for the shipped models:
/// `robots/yaw-pitch-16.yaml`).
const ENV_FILE_KEYS: [&str; 2] = ["robot", "world"];

/// The env a policy was trained in, exactly: its keywords resolve with today's defaults, so when a
/// task's defaults change after training they would resolve to another env, and evaluations (and
/// `--env-from`) would silently run that. Every value `recorded` (the resolved `env_config` written at
/// training) holds that today's resolution differs in is pinned as a keyword; the pinned keywords
/// must then build and resolve to the recorded values, or this is one line saying why not.
///
/// Robot and world files are compared by the keywords' paths (the recorded paths are the training
/// directory's). Keys the recorded configuration lacks (fields added after it was written, and those
/// written only when set, such as craters) are today's: new fields default to the old behaviour.
fn pin_recorded_env(
    spec: EnvSpec,
    config: EnvConfig,
    recorded: &Value,
) -> Result<(EnvSpec, EnvConfig), String> {
    let changes = recorded_changes(recorded, &config);
    if changes.is_empty() {
        return Ok((spec, config));
    }
    let mut env = Value::Object(spec.env.clone());
    for (path, value) in &changes {
        set_path(&mut env, path, value.clone());
    }
    let Value::Object(env) = env else {
        unreachable!("keywords stay a mapping")
    };
    let pinned = EnvSpec { env, ..spec };
    let first = |changes: &[(Vec<String>, Value)], now: &EnvConfig| {
        let (path, trained) = &changes[0];
        let now = lookup(
            &serde_json::to_value(now).expect("EnvConfig serialises"),
            path,
        )
        .map_or_else(|| "absent".to_owned(), Value::to_string);
        format!(
            "its env can no longer be built as it was trained: {} was {trained}, is now {now}",
            path.join(".")
        )
    };
    match pinned.config() {
        Ok(c) if recorded_changes(recorded, &c).is_empty() => Ok((pinned, c)),
        Ok(c) => Err(first(&recorded_changes(recorded, &c), &c)),
        Err(e) => Err(format!(
            "its env can no longer be built as it was trained: with its recorded values, {e}"
        )),
    }
}

/// The recorded leaves (path, recorded value) that `config` differs in; arrays are leaves, and the
/// robot and world files and `snake.joints` (the `joints` key's) are left out.
fn recorded_changes(recorded: &Value, config: &EnvConfig) -> Vec<(Vec<String>, Value)> {
    fn walk(
        recorded: &Value,
        now: Option<&Value>,
        path: &mut Vec<String>,
        out: &mut Vec<(Vec<String>, Value)>,
    ) {
        match recorded {
            Value::Object(fields) if !fields.is_empty() => {
                for (key, value) in fields {
                    let skip = (path.is_empty() && ENV_FILE_KEYS.contains(&key.as_str()))
                        || (path.len() == 1 && path[0] == "snake" && key == "joints");
                    if skip {
                        continue;
                    }
                    path.push(key.clone());
                    walk(value, now.and_then(|n| n.get(key)), path, out);
                    path.pop();
                }
            }
            _ if now == Some(recorded) => {}
            _ => out.push((path.clone(), recorded.clone())),
        }
    }
    let now = serde_json::to_value(config).expect("EnvConfig serialises");
    let mut out = Vec::new();
    walk(recorded, Some(&now), &mut Vec::new(), &mut out);
    out
}

fn lookup<'a>(value: &'a Value, path: &[String]) -> Option<&'a Value> {
    path.iter().try_fold(value, |v, key| v.get(key))
}

/// Sets `value` at `path`, making mappings on the way (replacing anything else there).
fn set_path(target: &mut Value, path: &[String], value: Value) {
    let Some((last, parents)) = path.split_last() else {
        *target = value;
        return;
    };
    let mut at = target;
    for key in parents {
        if !at.get(key).is_some_and(Value::is_object) {
            at[key.as_str()] = Value::Object(Map::new());
        }
        at = &mut at[key.as_str()];
    }
    at[last.as_str()] = value;
}

/// The `env_files` a model records of `config`: the texts of its robot and world files
/// (`{"robot": {"path": ..., "files": {name: text}}, "world": ...}`, [`snake_core::RecordedFiles`]),
/// as they were read when `config` was made; `None` without either.
pub fn env_files(config: &EnvConfig) -> Option<Value> {
    let mut files = Map::new();
    if let Some(robot) = &config.robot {
        files.insert("robot".into(), record_value(robot.files()));
    }
    if let Some(world) = &config.world {
        files.insert("world".into(), record_value(world.files()));
    }
    (!files.is_empty()).then_some(Value::Object(files))
}

fn record_value(files: &RecordedFiles) -> Value {
    serde_json::to_value(files).expect("recorded files serialise")
}

/// Applies a model's `env_files` (see [`env_files`]) to its env keywords, so that the env is the one
/// it was trained in: a `robot` or `world` path whose files (the main file there, the others beside
/// it by their recorded names) all hold the recorded texts is kept, and the env reads them as
/// before; otherwise the keyword becomes the record itself (`{"path": <the keyword's path>, "files":
/// ...}`, which the env builds from the recorded texts alone), and a note says so, one per file
/// replaced. A keyword that is a record already is kept. A record that does not build (a file it
/// lacks or does not use, a text its parser refuses) or does not fit the keywords (an unknown key, a
/// key the env has no file for, another file name) is an error, one line, and so is a `robot` or
/// `world` path without a record: the loader opens no file a model names but those of its record.
pub fn apply_env_files(
    env: &mut Map<String, Value>,
    records: &Value,
) -> Result<Vec<String>, String> {
    let Value::Object(records) = records else {
        return Err("metadata 'env_files' is not a JSON mapping".into());
    };
    let mut notes = Vec::new();
    for (key, record) in records {
        if !ENV_FILE_KEYS.contains(&key.as_str()) {
            return Err(format!(
                "metadata 'env_files' records '{key}', not a robot or world"
            ));
        }
        let record: RecordedFiles = serde_json::from_value(record.clone())
            .map_err(|e| format!("metadata 'env_files': {key}: {e}"))?;
        let path = match env.get(key.as_str()) {
            Some(Value::String(path)) => std::path::PathBuf::from(path),
            // Trained on a record already.
            Some(Value::Object(_)) => continue,
            _ => {
                return Err(format!(
                    "metadata 'env_files' records a {key} file, but its env has no {key} file"
                ))
            }
        };
        if path.file_name() != record.path.file_name() {
            return Err(format!(
                "metadata 'env_files' records the {key} {}, but its env's {key} is {}",
                record.path.display(),
                path.display()
            ));
        }
        // Whole and sound, whether or not it is used: exactly the files of a robot (world) that builds.
        let sound = if key == "robot" {
            snake_core::RobotRef::from_record(&record).map(drop)
        } else {
            snake_core::WorldRef::from_record(&record).map(drop)
        };
        sound.map_err(|e| format!("metadata 'env_files': {key}: {}", e.message()))?;
        let differences = record.differences_at(&path);
        if differences.is_empty() {
            continue;
        }
        notes.push(format!(
            "{key} {} changed since training ({}); the {key} recorded in the model is used",
            path.display(),
            differences.join(", ")
        ));
        let record = RecordedFiles {
            path,
            files: record.files,
        };
        env.insert(key.clone(), record_value(&record));
    }
    // A model's files come from its record: a path it names without one is never opened (a hostile
    // model could name any file on this machine, and its parser's error would quote it).
    for key in ENV_FILE_KEYS {
        if let (Some(Value::String(path)), false) = (env.get(key), records.contains_key(key)) {
            return Err(format!(
                "its env names the {key} file {} but the model holds no record of its files \
                 (docs/formats.md; scripts/record_env_files.py adds one to a model made before \
                 records)",
                snake_core::files::excerpt(path)
            ));
        }
    }
    Ok(notes)
}

/// Makes a model usable from any directory: a relative robot or world path that does not exist from
/// here is looked up from the model's directory and the one above it (`models/` and `robots/` sit side
/// by side in the repository; a run's model sits in its run directory), and replaced by the first
/// found. A path found nowhere is left as it is, for the env's own one-line error.
fn find_env_files(env: &mut Map<String, Value>, model: &Path) {
    let dir = model.parent().unwrap_or(Path::new(""));
    for key in ENV_FILE_KEYS {
        let Some(Value::String(file)) = env.get(key) else {
            continue;
        };
        let file = Path::new(file);
        if file.is_absolute() || file.exists() {
            continue;
        }
        let found = [Some(dir), dir.parent()]
            .into_iter()
            .flatten()
            .map(|base| base.join(file))
            .find(|candidate| candidate.is_file());
        if let Some(found) = found.as_deref().and_then(Path::to_str) {
            env.insert(key.to_string(), Value::String(found.to_string()));
        }
    }
}

fn read(path: &Path) -> Result<Vec<u8>, ModelError> {
    snake_core::files::read_bytes(path, snake_core::limits::MAX_MODEL_BYTES, "model")
        .map_err(|e| ModelError(e.message()))
}

/// Reads a policy file (or the policy of a checkpoint).
pub fn load_policy(path: &Path) -> Result<SavedPolicy, ModelError> {
    parse_policy(path, &read(path)?)
}

/// [`load_policy`], and what the user should be told about it, one line each (`<model>: robot
/// robots/yaw-pitch-16.yaml changed since training (...); the robot recorded in the model is used`).
pub fn load_policy_noted(path: &Path) -> Result<(SavedPolicy, Vec<String>), ModelError> {
    Parsed::new(path, &read(path)?)?.policy()
}

/// Reads a checkpoint.
pub fn load_checkpoint(path: &Path) -> Result<Checkpoint, ModelError> {
    parse_checkpoint(path, &read(path)?)
}

/// A policy from a file's bytes (`path` names it in messages): what [`load_policy`] does once the
/// file is read. Any bytes give a policy or a one-line error, never a panic (fuzzed:
/// fuzz/fuzz_targets/model_file.rs).
pub fn parse_policy(path: &Path, bytes: &[u8]) -> Result<SavedPolicy, ModelError> {
    Parsed::new(path, bytes)?.policy().map(|(policy, _)| policy)
}

/// [`load_checkpoint`], and what the user should be told about it (as [`load_policy_noted`]): a
/// note means its robot or world file changed since it was written, and its env keywords hold the
/// record in place of that path.
pub fn load_checkpoint_noted(path: &Path) -> Result<(Checkpoint, Vec<String>), ModelError> {
    checkpoint_noted(path, &read(path)?)
}

/// A checkpoint from a file's bytes, as [`parse_policy`].
pub fn parse_checkpoint(path: &Path, bytes: &[u8]) -> Result<Checkpoint, ModelError> {
    checkpoint_noted(path, bytes).map(|(checkpoint, _)| checkpoint)
}

fn checkpoint_noted(path: &Path, bytes: &[u8]) -> Result<(Checkpoint, Vec<String>), ModelError> {
    let p = Parsed::new(path, bytes)?;
    let (policy, notes) = p.policy()?;
    let n = policy.net.len();
    let mut adam = Adam::new(n);
    adam.exp_avg = p.f32s("adam.exp_avg", n)?;
    adam.exp_avg_sq = p.f32s("adam.exp_avg_sq", n)?;
    adam.step = p.parse("adam.step")?;
    let normalizer = match &policy.obs_rms {
        None => None,
        Some(obs_rms) => {
            let gamma = p.parse_in("normalize.gamma", 0.0..=1.0)?;
            let mut norm = Normalizer::new(policy.net.obs_dim(), 0, gamma);
            norm.obs_rms = obs_rms.clone();
            norm.ret_rms = RunningMeanStd {
                mean: p.f64s("ret_rms.mean", 1)?,
                var: p.variances("ret_rms.var", 1)?,
                count: p.parse_in("ret_rms.count", COUNT_RANGE)?,
            };
            Some(norm)
        }
    };
    let rng: ChaCha12Rng = serde_json::from_str(p.meta("rng")?)
        .map_err(|e| p.error(format!("metadata 'rng' is not a generator state ({e})")))?;
    let checkpoint = Checkpoint {
        adam,
        normalizer,
        rng,
        n_updates: p.parse("n_updates")?,
        wall_time: p.parse_in("wall_time", 0.0..=f64::MAX)?,
        reason: p.meta("reason")?.to_owned(),
        init_pending: p.meta.get("init").is_some_and(|v| v == "pending"),
        policy,
    };
    Ok((checkpoint, notes))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn models() -> Vec<std::path::PathBuf> {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../models");
        let mut found: Vec<_> = std::fs::read_dir(&dir)
            .expect("models/ is beside snake-rl")
            .map(|e| e.expect("readable").path())
            .filter(|p| p.extension().is_some_and(|e| e == "safetensors"))
            .collect();
        found.sort();
        found
    }

    fn meta_of(path: &Path) -> HashMap<String, String> {
        let bytes = std::fs::read(path).expect("readable");
        let (_, meta) = SafeTensors::read_metadata(&bytes).expect("a safetensors file");
        meta.metadata().clone().expect("metadata")
    }

    /// Every shipped model's keywords resolve today to exactly the env it was trained in (its
    /// recorded `env_config`, every key, both ways), so loading it pins nothing. A change to a task's
    /// defaults that would move a shipped model's env fails here.
    #[test]
    fn shipped_models_resolve_to_the_env_they_were_trained_in() {
        let found = models();
        assert!(found.len() >= 7, "{found:?}");
        for path in found {
            let meta = meta_of(&path);
            let policy = load_policy(&path).unwrap();
            let keywords: Map<String, Value> = serde_json::from_str(&meta["env"]).unwrap();
            let mut recorded: Value = serde_json::from_str(&meta["env_config"]).unwrap();
            let mut now = serde_json::to_value(policy.env.config().unwrap()).unwrap();
            for key in ENV_FILE_KEYS {
                assert_eq!(
                    recorded.get(key).is_some(),
                    keywords.contains_key(key),
                    "{path:?} {key}"
                );
                recorded.as_object_mut().unwrap().remove(key);
                now.as_object_mut().unwrap().remove(key);
            }
            assert_eq!(recorded, now, "{path:?}");
            let mut loaded = policy.env.env.clone();
            for key in ENV_FILE_KEYS {
                assert_eq!(loaded.remove(key).is_some(), keywords.contains_key(key));
            }
            let unfiled: Map<String, Value> = keywords
                .into_iter()
                .filter(|(k, _)| !ENV_FILE_KEYS.contains(&k.as_str()))
                .collect();
            assert_eq!(loaded, unfiled, "{path:?}: nothing pinned");
        }
    }

    /// A model whose recorded env differs from what its keywords give today.
    fn with_recorded(change: impl Fn(&mut Value)) -> Result<SavedPolicy, ModelError> {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../models/goal-10.safetensors");
        let (entries, mut meta) = policy_entries(&load_policy(&path).unwrap());
        let mut recorded: Value = serde_json::from_str(&meta["env_config"]).unwrap();
        change(&mut recorded);
        meta.insert("env_config".into(), recorded.to_string());
        parse_policy(&path, &serialize(&entries, meta))
    }

    #[test]
    fn a_changed_default_is_pinned_to_the_recorded_value() {
        let p = with_recorded(|r| {
            r["max_episode_steps"] = 700.into();
            r["reward"]["energy_weight"] = 0.25.into();
            r["goal_distribution"]["distance"] = serde_json::json!([4.0, 9.0]);
        })
        .unwrap();
        assert_eq!(
            Value::Object(p.env.env.clone()),
            serde_json::json!({
                "task": "goal",
                "max_episode_steps": 700,
                "reward": {"energy_weight": 0.25},
                "goal_distribution": {"distance": [4.0, 9.0]},
            })
        );
        let c = p.env.config().unwrap();
        assert_eq!(c.max_episode_steps, 700);
        assert_eq!(c.reward.energy_weight, 0.25);
        assert_eq!(c.goal_distribution.unwrap().distance, [4.0, 9.0]);
        // The keywords' other values are today's (the recorded ones are the same).
        assert_eq!(c.goal_radius, 1.0);
    }

    #[test]
    fn an_env_that_cannot_be_rebuilt_is_one_line() {
        let e = with_recorded(|r| r["goal_radius"] = (-1.0).into()).unwrap_err();
        assert!(
            e.0.contains("goal-10.safetensors: its env can no longer be built as it was trained: with its recorded values, "),
            "{e}"
        );
        assert!(e.0.contains("goal_radius"), "{e}");
        let e = with_recorded(|r| r["reward"]["no_such_term"] = 1.0.into()).unwrap_err();
        assert!(
            e.0.contains("with its recorded values, env.reward.no_such_term: unknown field"),
            "{e}"
        );
        let e = with_recorded(|r| *r = Value::Null).unwrap_err();
        assert!(
            e.0.ends_with("metadata 'env_config' is not a JSON mapping"),
            "{e}"
        );
    }
}
