//! `snakesim._core`: the compiled half of the Python package. The public Python API is the thin typed
//! layer in `python/snakesim/`; this module only moves numpy arrays across and maps errors.

use std::sync::Mutex;

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use snake_core::env::{EnvConfig, Info, ObservationStructure, Physics, ResetOptions, SnakeEnv};
use snake_core::{StartPose, StepBuffers, VecSnakeEnv};

mod controllers;
mod evaluation;
mod inputs;
mod lock;
mod media;
mod native;
mod simulate;
mod swim;

/// snake-core's errors as Python exceptions: bad input is a ValueError, a failing engine a RuntimeError.
fn to_py(error: snake_core::Error) -> PyErr {
    match error {
        snake_core::Error::InvalidArgument(m) => PyValueError::new_err(m.to_string()),
        other => PyRuntimeError::new_err(other.to_string()),
    }
}

/// A configuration error as Python expects it: a value of the wrong type is a TypeError, anything
/// else a ValueError; the message starts with the key path.
fn config_error(e: snake_rl::config::ConfigError) -> PyErr {
    if e.0.contains("invalid type:") {
        PyTypeError::new_err(e.0)
    } else {
        PyValueError::new_err(e.0)
    }
}

/// A configuration error as Python expects it (see [`config_error`]), from snake-core.
fn keyword_error(e: snake_core::Error) -> PyErr {
    let message = e.message();
    if message.contains("invalid type:") {
        PyTypeError::new_err(message)
    } else {
        PyValueError::new_err(message)
    }
}

/// Builds an [`EnvConfig`] from the keywords of `snakesim.SnakeEnv` as JSON (`joints`, `preset`,
/// `snake` overrides, every other key an `EnvConfig` field), checked where the env's keywords are
/// defined ([`snake_core::env::keywords`]).
fn parse_config(json: &str) -> PyResult<EnvConfig> {
    let value: serde_json::Value = serde_json::from_str(json)
        .map_err(|e| PyValueError::new_err(format!("invalid env keywords: {e}")))?;
    let serde_json::Value::Object(keywords) = value else {
        return Err(PyTypeError::new_err("env keywords must be a mapping"));
    };
    snake_core::env::keywords::env_from_keywords(&keywords).map_err(keyword_error)
}

fn info_dict<'py>(py: Python<'py>, info: &Info) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("distance", info.distance)?;
    d.set_item("success", info.success)?;
    d.set_item("episode_step", info.episode_step)?;
    d.set_item("episode_return", info.episode_return)?;
    d.set_item("time", info.time)?;
    d.set_item("goal", info.goal)?;
    d.set_item(
        "start",
        (info.start.x, info.start.y, info.start.z, info.start.yaw),
    )?;
    d.set_item("reward_goal", info.reward_terms.goal)?;
    d.set_item("reward_progress", info.reward_terms.progress)?;
    d.set_item("reward_smoothness", info.reward_terms.smoothness)?;
    d.set_item("reward_energy", info.reward_terms.energy)?;
    d.set_item("work", info.work)?;
    d.set_item("path_length", info.path_length)?;
    d.set_item("displacement", info.displacement)?;
    Ok(d)
}

/// The physics an episode drew, under `randomize`'s keys (the given ones only).
pub(crate) fn physics_dict<'py>(
    py: Python<'py>,
    physics: &Physics,
) -> PyResult<Bound<'py, PyDict>> {
    let p = PyDict::new(py);
    for (key, value) in physics.values() {
        if key == "latency_steps" {
            p.set_item(key, value as u32)?;
        } else {
            p.set_item(key, value)?;
        }
    }
    Ok(p)
}

/// A float vector from a numpy array of float32 or float64 (anything else is a TypeError).
fn float_vector(array: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<f64>> {
    if let Ok(a) = array.extract::<PyReadonlyArray1<'_, f32>>() {
        return Ok(a.as_array().iter().map(|&v| f64::from(v)).collect());
    }
    if let Ok(a) = array.extract::<PyReadonlyArray1<'_, f64>>() {
        return Ok(a.as_array().to_vec());
    }
    Err(describe_array_error(array, what, 1))
}

fn describe_array_error(array: &Bound<'_, PyAny>, what: &str, ndim: usize) -> PyErr {
    match array.cast::<numpy::PyUntypedArray>() {
        Ok(a) if a.ndim() != ndim => PyValueError::new_err(format!(
            "{what} must be a {ndim}-D array, got shape {:?}",
            a.shape()
        )),
        Ok(a) => PyTypeError::new_err(format!(
            "{what} must be a float32 or float64 array, got dtype {}",
            a.dtype()
        )),
        Err(_) => PyTypeError::new_err(format!("{what} must be a numpy array")),
    }
}

/// What `Env.step` returns: (obs, reward, terminated, truncated, info).
type StepTuple<'py> = (
    Bound<'py, PyArray1<f32>>,
    f64,
    bool,
    bool,
    Bound<'py, PyDict>,
);

/// Gymnasium's `observation_structure` (as in Swimmer-v5): the observation's part names and sizes, in
/// order, as a dict (Python's keeps the order) from the configuration's one description.
fn structure_dict(py: Python<'_>, structure: ObservationStructure) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    for (name, size) in structure.named() {
        d.set_item(name, size)?;
    }
    Ok(d)
}

/// One snake environment (see `snakesim.SnakeEnv`).
#[pyclass(module = "snakesim._core")]
struct Env {
    inner: Mutex<SnakeEnv>,
}

/// Runs `f` on the data behind `mutex` with the interpreter released: the lock is waited for without
/// the GIL, so a second Python thread using the same object waits its turn instead of deadlocking (a
/// thread holding the lock may need the GIL back). Calls from several threads are thus serialised.
fn locked<T: Send, R: Send>(
    py: Python<'_>,
    mutex: &Mutex<T>,
    f: impl FnOnce(&mut T) -> R + Send,
) -> R {
    py.detach(|| {
        // A panic cannot happen while the lock is held (errors are values), so poisoning is not
        // expected; recover the data if it ever is.
        let mut guard = mutex.lock().unwrap_or_else(|p| p.into_inner());
        f(&mut guard)
    })
}

impl Env {
    fn with<R: Send>(&self, py: Python<'_>, f: impl FnOnce(&mut SnakeEnv) -> R + Send) -> R {
        locked(py, &self.inner, f)
    }
}

#[pymethods]
impl Env {
    #[new]
    fn new(config_json: &str) -> PyResult<Self> {
        let env = SnakeEnv::new(parse_config(config_json)?).map_err(to_py)?;
        Ok(Env {
            inner: Mutex::new(env),
        })
    }

    /// Number of joints.
    #[getter]
    fn joints(&self, py: Python<'_>) -> usize {
        self.with(py, |e| e.config().joints())
    }

    /// The current episode's world as a viewer draws it (JSON: ground, obstacles): the laid-out
    /// terrain of the latest reset, else the configuration's world file, else the flat plane.
    fn world_json(&self, py: Python<'_>) -> String {
        self.with(py, |e| {
            let flat = snake_core::world_file::WorldSpec::default();
            let spec = e
                .episode_world()
                .or_else(|| e.config().world.as_ref().map(|w| w.spec()))
                .unwrap_or(&flat);
            serde_json::to_string(&spec.drawing()).expect("a drawing serialises")
        })
    }

    /// Length of an action (the joints, or 3 in the gait action mode).
    #[getter]
    fn action_dim(&self, py: Python<'_>) -> usize {
        self.with(py, |e| e.action_dim())
    }

    /// Length of the observation.
    #[getter]
    fn observation_dim(&self, py: Python<'_>) -> usize {
        self.with(py, |e| e.observation_dim())
    }

    /// The observation's named parts and their sizes, in order (Gymnasium's
    /// `observation_structure`); they sum to `observation_dim`.
    #[getter]
    fn observation_structure<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let structure = self.with(py, |e| e.config().observation_structure());
        structure_dict(py, structure)
    }

    /// The goal of the current episode.
    #[getter]
    fn goal(&self, py: Python<'_>) -> (f64, f64) {
        self.with(py, |e| e.goal())
    }

    #[getter]
    fn goal_radius(&self, py: Python<'_>) -> f64 {
        self.with(py, |e| e.config().goal_radius)
    }

    #[getter]
    fn half_extent(&self, py: Python<'_>) -> f64 {
        self.with(py, |e| e.config().snake.half_extent)
    }

    /// The shapes of every link of the env's robot (JSON: per link, the root first, a list of
    /// {kind, size, pose} in the link's centre-of-mass frame), or None for the built-in snake.
    fn robot_shapes(&self, py: Python<'_>) -> PyResult<Option<String>> {
        let drawing = self.with(py, |e| {
            e.config().robot.as_ref().map(|r| r.spec().drawing())
        });
        drawing
            .transpose()
            .map_err(to_py)
            .map(|d| d.map(|d| serde_json::to_string(&d).expect("shapes serialise")))
    }

    /// The resolved configuration as JSON.
    fn config_json(&self, py: Python<'_>) -> String {
        self.with(py, |e| {
            serde_json::to_string(e.config()).expect("EnvConfig serialises")
        })
    }

    /// reset(seed, start, goal) -> (obs, info)
    #[pyo3(signature = (seed=None, start=None, goal=None))]
    fn reset<'py>(
        &self,
        py: Python<'py>,
        seed: Option<u64>,
        start: Option<(f64, f64, f64, f64)>,
        goal: Option<(f64, f64)>,
    ) -> PyResult<(Bound<'py, PyArray1<f32>>, Bound<'py, PyDict>)> {
        let options = ResetOptions {
            start: start.map(|(x, y, z, yaw)| StartPose { x, y, z, yaw }),
            goal,
        };
        let (obs, info, physics) = self
            .with(py, |env| {
                let (obs, info) = env.reset(seed, options)?;
                let physics = env.config().randomize.is_some().then(|| *env.physics());
                Ok::<_, snake_core::Error>((obs, info, physics))
            })
            .map_err(to_py)?;
        let d = info_dict(py, &info)?;
        if let Some(physics) = physics {
            d.set_item("physics", physics_dict(py, &physics)?)?;
        }
        Ok((PyArray1::from_vec(py, obs), d))
    }

    /// step(action) -> (obs, reward, terminated, truncated, info)
    fn step<'py>(&self, py: Python<'py>, action: &Bound<'py, PyAny>) -> PyResult<StepTuple<'py>> {
        let action = float_vector(action, "action")?;
        let result = self.with(py, |env| env.step(&action)).map_err(to_py)?;
        Ok((
            PyArray1::from_vec(py, result.obs),
            result.reward,
            result.terminated,
            result.truncated,
            info_dict(py, &result.info)?,
        ))
    }

    /// Pose of every cube (every link of a robot), the head first: an (N + 1, 7) array of x, y, z,
    /// qx, qy, qz, qw (one row per link for a robot).
    fn cube_poses<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let flat: Option<Result<Vec<f64>, snake_core::Error>> = self.with(py, |env| {
            env.simulation().map(|snake| {
                snake.body_poses().map(|poses| {
                    poses
                        .iter()
                        .flat_map(|p| {
                            let q = p.orientation.coords;
                            [p.position.x, p.position.y, p.position.z, q.x, q.y, q.z, q.w]
                        })
                        .collect()
                })
            })
        });
        let flat = flat
            .ok_or_else(|| PyRuntimeError::new_err("no world yet: call reset() first"))?
            .map_err(to_py)?;
        let cubes = flat.len() / 7;
        Ok(PyArray1::from_vec(py, flat).reshape([cubes, 7])?.into_any())
    }

    /// Turns the physics trace on or off (see `physics_trace`).
    fn set_physics_trace(&self, py: Python<'_>, on: bool) {
        self.with(py, |env| env.set_physics_trace(on));
    }

    /// The state after each physics step of the latest reset or step (the trace must be on), as a
    /// dict of arrays with K rows: steps (K,) uint64, times (K,), poses (K, N + 1, 7), positions,
    /// velocities, torques and targets (K, N); None while the trace is off.
    fn physics_trace<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(trace) = self.with(py, |env| env.physics_trace().cloned()) else {
            return Ok(None);
        };
        let (k, n) = (trace.len(), trace.joints);
        let d = PyDict::new(py);
        d.set_item("steps", PyArray1::from_vec(py, trace.steps))?;
        d.set_item("times", PyArray1::from_vec(py, trace.times))?;
        d.set_item(
            "poses",
            PyArray1::from_vec(py, trace.poses).reshape([k, n + 1, 7])?,
        )?;
        for (name, values) in [
            ("positions", trace.positions),
            ("velocities", trace.velocities),
            ("torques", trace.torques),
            ("targets", trace.targets),
        ] {
            d.set_item(name, PyArray1::from_vec(py, values).reshape([k, n])?)?;
        }
        Ok(Some(d))
    }
}

/// Many snake environments stepped together on threads (see `snakesim.SnakeVecEnv`).
#[pyclass(module = "snakesim._core")]
struct VecEnv {
    inner: Mutex<VecSnakeEnv>,
    /// (num_envs, action_dim, observation_dim): fixed at construction, read without the lock.
    dims: (usize, usize, usize),
}

impl VecEnv {
    fn with<R: Send>(&self, py: Python<'_>, f: impl FnOnce(&mut VecSnakeEnv) -> R + Send) -> R {
        locked(py, &self.inner, f)
    }
}

#[pymethods]
impl VecEnv {
    #[new]
    fn new(config_json: &str, num_envs: usize) -> PyResult<Self> {
        let envs = VecSnakeEnv::new(parse_config(config_json)?, num_envs).map_err(to_py)?;
        Ok(VecEnv {
            dims: (envs.num_envs(), envs.action_dim(), envs.observation_dim()),
            inner: Mutex::new(envs),
        })
    }

    #[getter]
    fn num_envs(&self, py: Python<'_>) -> usize {
        self.with(py, |e| e.num_envs())
    }

    #[getter]
    fn joints(&self, py: Python<'_>) -> usize {
        self.with(py, |e| e.config().joints())
    }

    #[getter]
    fn action_dim(&self, py: Python<'_>) -> usize {
        self.with(py, |e| e.action_dim())
    }

    #[getter]
    fn observation_dim(&self, py: Python<'_>) -> usize {
        self.with(py, |e| e.observation_dim())
    }

    /// Each env's observation structure (see `Env.observation_structure`).
    #[getter]
    fn observation_structure<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let structure = self.with(py, |e| e.config().observation_structure());
        structure_dict(py, structure)
    }

    /// The physics each env's current episode drew (a dict per env, `Env.reset`'s
    /// `info["physics"]`), or None without `randomize`.
    fn physics<'py>(&self, py: Python<'py>) -> PyResult<Option<Vec<Bound<'py, PyDict>>>> {
        let drawn: Option<Vec<Physics>> = self.with(py, |envs| {
            envs.config()
                .randomize
                .is_some()
                .then(|| envs.envs().map(|e| *e.physics()).collect())
        });
        drawn
            .map(|all| all.iter().map(|p| physics_dict(py, p)).collect())
            .transpose()
    }

    /// reset(seed) -> obs of shape (num_envs, observation_dim); env i is seeded with seed + i.
    #[pyo3(signature = (seed=None))]
    fn reset<'py>(&self, py: Python<'py>, seed: Option<u64>) -> PyResult<Bound<'py, PyAny>> {
        let (m, d, obs) = self
            .with(py, |envs| {
                let (m, d) = (envs.num_envs(), envs.observation_dim());
                let mut obs = vec![0.0f32; m * d];
                envs.reset(seed, &mut obs).map(|()| (m, d, obs))
            })
            .map_err(to_py)?;
        Ok(PyArray1::from_vec(py, obs).reshape([m, d])?.into_any())
    }

    /// reset_each(seeds) -> obs of shape (num_envs, observation_dim); env i is seeded with seeds[i]
    /// (None: it continues its stream). `seeds` holds num_envs values.
    fn reset_each<'py>(
        &self,
        py: Python<'py>,
        seeds: Vec<Option<u64>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (m, d) = (self.dims.0, self.dims.2);
        let mut obs = vec![0.0f32; m * d];
        self.with(py, |envs| envs.reset_each(&seeds, &mut obs))
            .map_err(to_py)?;
        Ok(PyArray1::from_vec(py, obs).reshape([m, d])?.into_any())
    }

    /// step(actions (num_envs, joints)) -> (obs, rewards, terminated, truncated, finals), where finals
    /// lists (env index, final observation, final info) for each episode that ended and was reset.
    fn step<'py>(
        &self,
        py: Python<'py>,
        actions: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let (m, n, d) = self.dims;
        let actions: Vec<f64> = if let Ok(a) = actions.extract::<PyReadonlyArray2<'_, f32>>() {
            check_shape(a.shape(), m, n)?;
            a.as_array().iter().map(|&v| f64::from(v)).collect()
        } else if let Ok(a) = actions.extract::<PyReadonlyArray2<'_, f64>>() {
            check_shape(a.shape(), m, n)?;
            a.as_array().iter().copied().collect()
        } else {
            return Err(describe_array_error(actions, "actions", 2));
        };
        // Bullet worlds are not Sync, so the finished episodes are copied out while the GIL is released.
        let mut out = StepBuffers::new(m, d);
        let finished: Vec<(usize, Vec<f32>, Info)> = self
            .with(py, |envs| {
                envs.step_into(&actions, &mut out).map(|f| {
                    f.iter()
                        .map(|f| (f.env, f.observation.to_vec(), *f.info))
                        .collect()
                })
            })
            .map_err(to_py)?;
        let finals = PyList::empty(py);
        for (env, final_obs, info) in &finished {
            finals.append((
                *env,
                PyArray1::from_slice(py, final_obs),
                info_dict(py, info)?,
            ))?;
        }
        let obs = PyArray1::from_vec(py, out.obs).reshape([m, d])?;
        PyTuple::new(
            py,
            [
                obs.into_any(),
                PyArray1::from_vec(py, out.rewards).into_any(),
                PyArray1::from_vec(py, out.terminated).into_any(),
                PyArray1::from_vec(py, out.truncated).into_any(),
                finals.into_any(),
            ],
        )
    }
}

fn check_shape(shape: &[usize], m: usize, n: usize) -> PyResult<()> {
    if shape == [m, n] {
        Ok(())
    } else {
        Err(PyValueError::new_err(format!(
            "actions must have shape ({m}, {n}) (num_envs, joints), got {shape:?}"
        )))
    }
}

/// The compiled core of snakesim.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<Env>()?;
    m.add_class::<VecEnv>()?;
    native::register(m)?;
    controllers::register(m)?;
    evaluation::register(m)?;
    inputs::register(m)?;
    lock::register(m)?;
    simulate::register(m)?;
    media::register(m)?;
    swim::register(m)?;
    Ok(())
}
