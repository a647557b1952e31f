//! The native trainer (snake-rl) for Python: the run configuration, saved policies, and training with
//! progress reported to a Python object.

use std::path::PathBuf;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rand::SeedableRng;
use rand_chacha::ChaCha12Rng;
use serde_json::Value;
use snake_rl::config::{self, RunConfig};
use snake_rl::model::{self, SavedPolicy};
use snake_rl::policy::Policy;
use snake_rl::rundir::EvaluationRow;
use snake_rl::trainer::{self, Observer, Outcome, Progress, Session};

use super::config_error;
use crate::lock::PyWriterLock;

fn json_value(text: &str, what: &str) -> PyResult<Value> {
    serde_json::from_str(text)
        .map_err(|e| PyValueError::new_err(format!("{what} is not JSON: {e}")))
}

/// A configuration's `arch` (JSON: a name or a mapping of widths) in words, as a run names it.
#[pyfunction]
fn arch_label(arch: &str) -> PyResult<String> {
    let arch: snake_rl::nn::Arch = config::from_value(
        serde_json::from_str(arch).map_err(|e| PyValueError::new_err(format!("arch: {e}")))?,
        "arch",
    )
    .map_err(|e| PyValueError::new_err(e.0))?;
    Ok(arch.to_string())
}

/// `message` cut in its middle to `LIMITS["error_chars"]` characters, as snake-core cuts its own
/// errors: the one rule for every error line, Rust's and Python's.
#[pyfunction]
fn capped_message(message: String) -> String {
    snake_core::error::capped(message)
}

/// The defaults of a run configuration, as JSON.
#[pyfunction]
fn run_config_defaults() -> String {
    serde_json::to_string(&RunConfig::default()).expect("serialises")
}

/// The env keywords with their defaults for `task` (`paper`: `SnakeEnv`, `goal`: `SnakeGoalEnv`),
/// as JSON.
#[pyfunction]
#[pyo3(signature = (task = "paper"))]
fn env_keyword_defaults(task: &str) -> PyResult<String> {
    let task: snake_core::env::Task = snake_core::keys::from_value(Value::from(task), "task")
        .map_err(|e| PyValueError::new_err(e.message()))?;
    Ok(Value::Object(snake_core::env::keywords::env_keyword_defaults(task)).to_string())
}

/// A checked run configuration from layers (JSON mappings over the defaults, lowest first), as JSON.
#[pyfunction]
fn resolve_run_config(layers: Vec<String>) -> PyResult<String> {
    let layers = layers
        .iter()
        .map(|l| json_value(l, "a configuration layer"))
        .collect::<PyResult<Vec<_>>>()?;
    let config = RunConfig::from_layers(&layers).map_err(config_error)?;
    Ok(serde_json::to_string(&config).expect("serialises"))
}

/// Layers of keys (JSON mappings, lowest first) merged into one, key by key at every depth, without
/// defaults or checks: what a run's overrides are before they meet a base configuration.
#[pyfunction]
fn merge_layers(layers: Vec<String>) -> PyResult<String> {
    let mut out = Value::Object(serde_json::Map::new());
    for l in &layers {
        config::merge_layer(&mut out, &json_value(l, "a configuration layer")?);
    }
    Ok(out.to_string())
}

/// YAML text of a (checked) configuration given as JSON.
#[pyfunction]
fn run_config_yaml(config_json: &str) -> PyResult<String> {
    let config = RunConfig::from_layers(&[json_value(config_json, "the configuration")?])
        .map_err(config_error)?;
    Ok(config.to_yaml())
}

/// YAML text as JSON (YAML 1.2 scalars; an empty document is an empty mapping).
#[pyfunction]
fn parse_yaml(text: &str) -> PyResult<String> {
    let v = config::parse_yaml(text).map_err(|e| PyValueError::new_err(e.0))?;
    Ok(v.to_string())
}

/// `KEY=VALUE` overrides as one nested mapping, as JSON.
#[pyfunction]
fn parse_overrides(items: Vec<String>) -> PyResult<String> {
    let v = config::parse_overrides(&items).map_err(|e| PyValueError::new_err(e.0))?;
    Ok(v.to_string())
}

/// Observation statistics as numpy arrays: mean, variance, count.
type ObsStats<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>, f64);

/// The texts of the robot and world files of the env of `env_json` (env keywords, JSON), as a model
/// records them (metadata `env_files`, an SB3 zip's `snakesim_env_files`), as JSON; None without
/// either file.
#[pyfunction]
fn env_file_records(env_json: &str) -> PyResult<Option<String>> {
    let config = super::parse_config(env_json)?;
    Ok(model::env_files(&config).map(|v| v.to_string()))
}

/// A model's recorded files (JSON, see `env_file_records`) applied to its env keywords (JSON): the
/// keywords to build its env with (a file that no longer holds the recorded texts replaced by its
/// record) and a note for each file replaced. ValueError, one line, for a record that does not fit.
#[pyfunction]
fn apply_env_files(env_json: &str, records_json: &str) -> PyResult<(String, Vec<String>)> {
    let Value::Object(mut env) = json_value(env_json, "the env keywords")? else {
        return Err(PyValueError::new_err("the env keywords are not a mapping"));
    };
    let records = json_value(records_json, "the recorded files")?;
    let notes = model::apply_env_files(&mut env, &records)
        .map_err(|e| PyValueError::new_err(snake_core::error::one_line(e)))?;
    Ok((Value::Object(env).to_string(), notes))
}

/// A trained native policy (`model.safetensors` or a checkpoint), ready to act.
#[pyclass(module = "snakesim._core")]
struct NativePolicy {
    saved: SavedPolicy,
    path: String,
    notes: Vec<String>,
    policy: Mutex<(Policy, ChaCha12Rng)>,
}

fn model_error(e: model::ModelError) -> PyErr {
    PyValueError::new_err(e.0)
}

#[pymethods]
impl NativePolicy {
    #[new]
    #[pyo3(signature = (path, seed=0))]
    fn new(path: PathBuf, seed: u64) -> PyResult<Self> {
        let (saved, notes) = model::load_policy_noted(&path).map_err(model_error)?;
        // `act` gives the policy's own actions; the assist is applied by whoever steps the env
        // (snakesim's Agent.act, through `_core.SteerAssist`), as for any agent.
        let policy = Policy::from_saved(&saved);
        Ok(NativePolicy {
            path: path.display().to_string(),
            notes,
            saved,
            policy: Mutex::new((policy, ChaCha12Rng::seed_from_u64(seed))),
        })
    }

    /// The file it was loaded from.
    #[getter]
    fn path(&self) -> &str {
        &self.path
    }

    /// What loading it found that the user should know, one line each: a robot or world file that
    /// changed since training (the recorded one is used).
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.notes.clone()
    }

    /// The texts of the robot and world files its env is built from (metadata `env_files`), as
    /// JSON; None without either.
    fn env_files_json(&self) -> PyResult<Option<String>> {
        let config = self
            .saved
            .env
            .config()
            .map_err(|e| PyValueError::new_err(e.0))?;
        Ok(model::env_files(&config).map(|v| v.to_string()))
    }

    /// `small`, `large`, or the widths in words (`pi [256, 256], vf [256, 256]`).
    #[getter]
    fn arch(&self) -> String {
        self.saved.net.arch().to_string()
    }

    /// The widths of the network's tanh layers: `{"shared": [...], "pi": [...], "vf": [...]}`.
    #[getter]
    fn net_arch(&self) -> std::collections::BTreeMap<&'static str, Vec<usize>> {
        let net = self.saved.net.arch().net();
        [("shared", net.shared), ("pi", net.pi), ("vf", net.vf)].into()
    }

    #[getter]
    fn obs_dim(&self) -> usize {
        self.saved.net.obs_dim()
    }

    #[getter]
    fn act_dim(&self) -> usize {
        self.saved.net.act_dim()
    }

    #[getter]
    fn joints(&self) -> usize {
        self.saved.env.joints
    }

    #[getter]
    fn preset(&self) -> &'static str {
        self.saved.env.preset.name()
    }

    #[getter]
    fn timesteps(&self) -> u64 {
        self.saved.timesteps
    }

    #[getter]
    fn normalize(&self) -> bool {
        self.saved.obs_rms.is_some()
    }

    /// The env keywords it was trained with (besides joints and preset), as JSON.
    fn env_json(&self) -> String {
        Value::Object(self.saved.env.env.clone()).to_string()
    }

    /// The `steer_assist` it was trained with, as JSON (None without one).
    fn steer_assist_json(&self) -> Option<String> {
        self.saved
            .steer_assist
            .map(|a| serde_json::to_string(&a).expect("an assist serialises"))
    }

    /// Restarts the generator of sampled actions.
    fn seed(&self, seed: u64) {
        let mut guard = self.policy.lock().unwrap_or_else(|p| p.into_inner());
        guard.1 = ChaCha12Rng::seed_from_u64(seed);
    }

    /// act(obs (n, obs_dim) float32, deterministic) -> actions (n, act_dim) float32 in [-1, 1].
    #[pyo3(signature = (obs, deterministic=true))]
    fn act<'py>(
        &self,
        py: Python<'py>,
        obs: PyReadonlyArray2<'py, f32>,
        deterministic: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let shape = obs.shape();
        let (rows, d, n) = (shape[0], self.saved.net.obs_dim(), self.saved.net.act_dim());
        if shape[1] != d {
            return Err(PyValueError::new_err(format!(
                "obs must have shape (n, {d}), got {shape:?}"
            )));
        }
        let flat: Vec<f32> = obs.as_array().iter().copied().collect();
        if let Some(i) = flat.iter().position(|x| !x.is_finite()) {
            return Err(PyValueError::new_err(format!(
                "obs[{}, {}] must be finite, got {}",
                i / d,
                i % d,
                flat[i]
            )));
        }
        let mut actions = vec![0.0f32; rows * n];
        if rows > 0 {
            // Acting never releases the interpreter, so no other Python thread can wait on this lock
            // while holding it.
            let mut guard = self.policy.lock().unwrap_or_else(|p| p.into_inner());
            let (policy, rng) = &mut *guard;
            policy.act(&flat, rows, deterministic, rng, &mut actions);
        }
        Ok(PyArray1::from_vec(py, actions)
            .reshape([rows, n])?
            .into_any())
    }

    /// The parameters under SB3's state-dict names: name -> float32 array of the tensor's shape.
    fn tensors<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for t in self.saved.net.tensors() {
            let values = self.saved.params[t.offset..t.offset + t.len()].to_vec();
            d.set_item(
                &t.name,
                PyArray1::from_vec(py, values).reshape(t.shape.clone())?,
            )?;
        }
        Ok(d)
    }

    /// Observation statistics (mean, var, count) when it normalises observations, else None.
    fn obs_rms<'py>(&self, py: Python<'py>) -> Option<ObsStats<'py>> {
        self.saved.obs_rms.as_ref().map(|r| {
            (
                PyArray1::from_slice(py, &r.mean),
                PyArray1::from_slice(py, &r.var),
                r.count,
            )
        })
    }
}

/// Forwards training events to a Python object's optional methods `on_start(start, total)`,
/// `on_step(timesteps)` (at most every 0.1 s), `on_update(dict)` and `on_evaluation(dict)`; stops on
/// Ctrl-C (checked at most every 20 ms, on the calling thread) or when a method raises.
struct PyObserver {
    target: Py<PyAny>,
    error: Option<PyErr>,
    last_step: Instant,
    last_check: Instant,
}

impl PyObserver {
    fn call(
        &mut self,
        method: &str,
        args: impl for<'py> FnOnce(Python<'py>) -> PyResult<Bound<'py, PyAny>>,
    ) {
        if self.error.is_some() {
            return;
        }
        Python::attach(|py| {
            let target = self.target.bind(py);
            if !target.hasattr(method).unwrap_or(false) {
                return;
            }
            let result = args(py).and_then(|a| target.call_method1(method, (a,)));
            if let Err(e) = result {
                self.error = Some(e);
            }
        });
    }
}

fn evaluation_dict<'py>(py: Python<'py>, row: &EvaluationRow) -> PyResult<Bound<'py, PyAny>> {
    let d = PyDict::new(py);
    d.set_item("timesteps", row.timesteps)?;
    d.set_item("mean_return", row.mean_return)?;
    d.set_item("std_return", row.std_return)?;
    d.set_item("success_rate", row.success_rate)?;
    d.set_item("mean_steps_to_goal", row.mean_steps_to_goal)?;
    d.set_item("wall_time", row.wall_time)?;
    Ok(d.into_any())
}

impl Observer for PyObserver {
    fn on_start(&mut self, start: u64, total: u64) {
        if self.error.is_some() {
            return;
        }
        Python::attach(|py| {
            let target = self.target.bind(py);
            if target.hasattr("on_start").unwrap_or(false) {
                if let Err(e) = target.call_method1("on_start", (start, total)) {
                    self.error = Some(e);
                }
            }
        });
    }

    fn on_step(&mut self, timesteps: u64) {
        if self.last_step.elapsed() >= Duration::from_millis(100) {
            self.last_step = Instant::now();
            self.call("on_step", |py| Ok(timesteps.into_pyobject(py)?.into_any()));
        }
    }

    fn on_update(&mut self, p: &Progress) {
        let p = *p;
        self.call("on_update", move |py| {
            let d = PyDict::new(py);
            d.set_item("timesteps", p.timesteps)?;
            d.set_item("total", p.total)?;
            d.set_item("timesteps_per_second", p.timesteps_per_second)?;
            d.set_item("ep_rew_mean", p.ep_rew_mean)?;
            d.set_item("ep_success_rate", p.ep_success_rate)?;
            d.set_item("rollout_seconds", p.rollout_seconds)?;
            d.set_item("update_seconds", p.update_seconds)?;
            d.set_item("value_loss", p.update.value_loss)?;
            d.set_item("std", p.update.std)?;
            Ok(d.into_any())
        });
    }

    fn on_evaluation(&mut self, row: &EvaluationRow) {
        let row = *row;
        self.call("on_evaluation", move |py| evaluation_dict(py, &row));
    }

    fn on_note(&mut self, message: &str) {
        let handled = Python::attach(|py| self.target.bind(py).hasattr("on_note").unwrap_or(false));
        if handled {
            let message = message.to_owned();
            self.call("on_note", move |py| {
                Ok(message.into_pyobject(py)?.into_any())
            });
        } else {
            eprintln!("note: {message}");
        }
    }

    fn should_stop(&mut self) -> bool {
        if self.error.is_some() {
            return true;
        }
        if self.last_check.elapsed() >= Duration::from_millis(20) {
            self.last_check = Instant::now();
            if let Err(e) = Python::attach(|py| py.check_signals()) {
                self.error = Some(e);
                return true;
            }
        }
        false
    }
}

/// run_config_flags() -> JSON list: the run configuration's command-line flags (key, flag, value kind,
/// choices, help with the default, sb3_only), defined once in snake-rl (`snake_rl::flags::FLAGS`).
#[pyfunction]
fn run_config_flags() -> String {
    let flags: Vec<Value> = snake_rl::flags::FLAGS
        .iter()
        .map(|f| f.describe())
        .collect();
    serde_json::to_string(&flags).expect("serialises")
}

/// default_run_dir(config_json) -> str: where a run goes without --run-dir
/// (runs/ppo-ARCH-JOINTS-PRESET-seedSEED), for both trainers and both commands.
#[pyfunction]
fn default_run_dir(config_json: &str) -> PyResult<String> {
    let config = RunConfig::from_layers(&[json_value(config_json, "the configuration")?])
        .map_err(config_error)?;
    Ok(snake_rl::flags::default_run_dir(&config)
        .display()
        .to_string())
}

/// env_throughput(env_json, n_envs, threads, seconds, seed) -> env steps/s of the batched env with
/// uniform random actions, stepped as the native trainer steps it (no Python in the loop).
#[pyfunction]
fn env_throughput(
    py: Python<'_>,
    env_json: &str,
    n_envs: usize,
    threads: usize,
    seconds: f64,
    seed: u64,
) -> PyResult<f64> {
    let config = super::parse_config(env_json)?;
    py.detach(|| snake_rl::bench::env_throughput(&config, n_envs, threads, seconds, seed))
        .map_err(|e| match e {
            snake_core::Error::InvalidArgument(m) => PyValueError::new_err(m.to_string()),
            e => PyRuntimeError::new_err(e.to_string()),
        })
}

fn train_error(e: trainer::TrainError) -> PyErr {
    match e {
        trainer::TrainError::Setup(m) => PyValueError::new_err(m),
        trainer::TrainError::Io(m) => PyOSError::new_err(m),
        other => PyRuntimeError::new_err(other.to_string()),
    }
}

/// resume_point(config_json, lock) -> (timesteps, path, skipped): the checkpoint a resumed native run
/// continues from (its newest that loads) and one line per newer one skipped; ValueError when it
/// cannot be resumed.
#[pyfunction]
fn resume_point(
    py: Python<'_>,
    config_json: &str,
    lock: &Bound<'_, PyWriterLock>,
) -> PyResult<(u64, String, Vec<String>)> {
    let config = RunConfig::from_layers(&[json_value(config_json, "the configuration")?])
        .map_err(config_error)?;
    let held = lock.borrow().take()?;
    let prepared = py.detach(|| trainer::prepare(&config, &held, true));
    lock.borrow().put_back(held);
    let point = prepared
        .map_err(train_error)?
        .resume
        .expect("a resumed run has a resume point");
    Ok((
        point.timesteps,
        point.path.display().to_string(),
        point.skipped,
    ))
}

/// train(config_json, lock, resume, versions_json, observer) -> dict: trains a run with the native
/// trainer in the run directory that `lock` (from `lock_run_dir`) holds. The dict has the session's
/// figures, `interrupted` and, when interrupted, `checkpoint`; a KeyboardInterrupt during training
/// ends it that way (after saving), other errors raise.
#[pyfunction]
fn train<'py>(
    py: Python<'py>,
    config_json: &str,
    lock: &Bound<'py, PyWriterLock>,
    resume: bool,
    versions_json: &str,
    observer: Py<PyAny>,
) -> PyResult<Bound<'py, PyDict>> {
    let config = RunConfig::from_layers(&[json_value(config_json, "the configuration")?])
        .map_err(config_error)?;
    let Value::Object(versions) = json_value(versions_json, "versions")? else {
        return Err(PyValueError::new_err("versions must be a JSON mapping"));
    };
    let held = lock.borrow().take()?;
    let session = Session {
        config,
        run_dir: held.folder().to_path_buf(),
        resume,
        versions,
    };
    let mut obs = PyObserver {
        target: observer,
        error: None,
        last_step: Instant::now(),
        last_check: Instant::now(),
    };
    let outcome = py.detach(|| {
        trainer::prepare(&session.config, &held, resume)
            .and_then(|prepared| trainer::train_prepared(&session, &held, prepared, &mut obs))
    });
    lock.borrow().put_back(held);
    let outcome = outcome.map_err(train_error)?;
    let (summary, checkpoint) = match outcome {
        Outcome::Finished(s) => (s, None),
        Outcome::Interrupted(s, path) => (s, Some(path)),
    };
    if let Some(e) = obs.error.take() {
        if !e.is_instance_of::<pyo3::exceptions::PyKeyboardInterrupt>(py) {
            return Err(e);
        }
    }
    let d = PyDict::new(py);
    d.set_item("run_dir", summary.run_dir.display().to_string())?;
    d.set_item("start_timesteps", summary.start_timesteps)?;
    d.set_item("timesteps", summary.timesteps)?;
    d.set_item("seconds", summary.seconds)?;
    d.set_item("eval_seconds", summary.eval_seconds)?;
    d.set_item("rollout_seconds", summary.rollout_seconds)?;
    d.set_item("update_seconds", summary.update_seconds)?;
    d.set_item("threads", summary.threads)?;
    d.set_item("rss_mib", summary.rss_mib)?;
    d.set_item(
        "last_evaluation",
        summary
            .last_evaluation
            .map(|r| evaluation_dict(py, &r))
            .transpose()?,
    )?;
    d.set_item("interrupted", checkpoint.is_some())?;
    d.set_item("checkpoint", checkpoint.map(|p| p.display().to_string()))?;
    Ok(d)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(capped_message, m)?)?;
    m.add_function(wrap_pyfunction!(run_config_defaults, m)?)?;
    m.add_function(wrap_pyfunction!(env_keyword_defaults, m)?)?;
    m.add_function(wrap_pyfunction!(resolve_run_config, m)?)?;
    m.add_function(wrap_pyfunction!(run_config_yaml, m)?)?;
    m.add_function(wrap_pyfunction!(merge_layers, m)?)?;
    m.add_function(wrap_pyfunction!(parse_yaml, m)?)?;
    m.add_function(wrap_pyfunction!(parse_overrides, m)?)?;
    m.add_function(wrap_pyfunction!(train, m)?)?;
    m.add_function(wrap_pyfunction!(resume_point, m)?)?;
    m.add_function(wrap_pyfunction!(env_throughput, m)?)?;
    m.add_function(wrap_pyfunction!(run_config_flags, m)?)?;
    m.add_function(wrap_pyfunction!(default_run_dir, m)?)?;
    m.add_function(wrap_pyfunction!(arch_label, m)?)?;
    m.add_function(wrap_pyfunction!(env_file_records, m)?)?;
    m.add_function(wrap_pyfunction!(apply_env_files, m)?)?;
    m.add_class::<NativePolicy>()?;
    m.add("IDENTITY_KEYS", snake_rl::config::IDENTITY_KEYS.to_vec())?;
    m.add(
        "PRESETS",
        snake_core::Preset::ALL
            .iter()
            .map(|p| p.name())
            .collect::<Vec<_>>(),
    )?;
    m.add("ARCHS", snake_rl::nn::Arch::NAMES.to_vec())?;
    m.add("EVAL_SEED_OFFSET", snake_rl::config::EVAL_SEED_OFFSET)?;
    m.add("NATIVE_MODEL_FILE", snake_rl::rundir::MODEL_FILE)?;
    m.add("LIMITS", limits(m.py())?)?;
    Ok(())
}

/// Every limit on sizes, ranges and durations (snake-core's and the run configuration's), by name,
/// for the Python side's checks and messages: snake-core's table (`snake_core::limits::ALL`) whole,
/// then the run configuration's limits named by the same rule (`MAX_X` is `x`, a range `x_min` and
/// `x_max`).
fn limits(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    use snake_core::limits::{LimitValue, ALL};
    use snake_rl::config::limits as run;
    use LimitValue::{Float, Int};
    let run_limits: &[(&str, LimitValue)] = &[
        ("timesteps", Int(run::MAX_TIMESTEPS)),
        ("eval_episodes", Int(run::MAX_EVAL_EPISODES)),
        ("threads", Int(run::MAX_THREADS)),
        ("rollout_bytes", Int(run::MAX_ROLLOUT_BYTES)),
        ("epochs", Int(run::MAX_EPOCHS)),
        ("seed", Int(run::MAX_SEED)),
        ("net_layers", Int(run::MAX_NET_LAYERS)),
        ("net_width", Int(run::MAX_NET_WIDTH)),
        ("log_std_init_min", Float(run::LOG_STD_INIT[0])),
        ("log_std_init_max", Float(run::LOG_STD_INIT[1])),
        ("init_steps", Int(run::MAX_INIT_STEPS)),
        ("init_bytes", Int(run::MAX_INIT_BYTES)),
        ("init_batch", Int(run::MAX_INIT_BATCH)),
        ("anchor_weight", Float(run::MAX_ANCHOR_WEIGHT)),
        ("bench_seconds", Float(run::MAX_BENCH_SECONDS)),
        ("bench_sizes", Int(run::MAX_BENCH_SIZES as u64)),
        ("bench_repeats", Int(run::MAX_BENCH_REPEATS as u64)),
        ("sweep_seeds", Int(run::MAX_SWEEP_SEEDS)),
        ("sweep_trials", Int(run::MAX_SWEEP_TRIALS)),
        ("grid_values", Int(run::MAX_GRID_VALUES)),
        ("trial_failures", Int(run::MAX_TRIAL_FAILURES)),
        ("search_keys", Int(run::MAX_SEARCH_KEYS)),
        ("trial_name", Int(run::MAX_TRIAL_NAME)),
    ];
    let d = PyDict::new(py);
    for (name, value) in ALL.iter().chain(run_limits) {
        if d.contains(*name)? {
            return Err(PyValueError::new_err(format!("limit {name} named twice")));
        }
        match *value {
            Int(n) => d.set_item(*name, n)?,
            Float(x) => d.set_item(*name, x)?,
        }
    }
    Ok(d)
}
