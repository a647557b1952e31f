//! `snakesim._core`: the compiled half of the Python package. The public Python API is the thin typed
//! layer in `python/snakesim/`; this module only moves numpy arrays across and maps errors.

use std::sync::{Mutex, MutexGuard};

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use snake_core::env::{EnvConfig, Info, ResetOptions, SnakeEnv};
use snake_core::{StartPose, VecSnakeEnv};

mod native;

/// snake-core's errors as Python exceptions: bad input is a ValueError, a failing engine a RuntimeError.
fn to_py(error: snake_core::Error) -> PyErr {
    match error {
        snake_core::Error::InvalidArgument(m) => PyValueError::new_err(m),
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

/// Builds an [`EnvConfig`] from the keywords of `snakesim.SnakeEnv` as JSON (`joints`, `preset`,
/// `snake` overrides, every other key an `EnvConfig` field), checked by snake-rl's configuration.
fn parse_config(json: &str) -> PyResult<EnvConfig> {
    let value: serde_json::Value = serde_json::from_str(json)
        .map_err(|e| PyValueError::new_err(format!("invalid env keywords: {e}")))?;
    let serde_json::Value::Object(keywords) = value else {
        return Err(PyTypeError::new_err("env keywords must be a mapping"));
    };
    snake_rl::config::env_from_keywords(&keywords).map_err(config_error)
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

/// One snake environment (see `snakesim.SnakeEnv`).
#[pyclass(module = "snakesim._core")]
struct Env {
    inner: Mutex<SnakeEnv>,
}

impl Env {
    fn env(&self) -> MutexGuard<'_, SnakeEnv> {
        // A panic cannot happen while the lock is held (errors are values), so poisoning is not expected;
        // recover the data if it ever is.
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
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
    fn joints(&self) -> usize {
        self.env().config().joints()
    }

    /// Length of an action (the joints, or 3 in the gait action mode).
    #[getter]
    fn action_dim(&self) -> usize {
        self.env().action_dim()
    }

    /// Length of the observation.
    #[getter]
    fn observation_dim(&self) -> usize {
        self.env().observation_dim()
    }

    /// The goal of the current episode.
    #[getter]
    fn goal(&self) -> (f64, f64) {
        self.env().goal()
    }

    #[getter]
    fn goal_radius(&self) -> f64 {
        self.env().config().goal_radius
    }

    #[getter]
    fn half_extent(&self) -> f64 {
        self.env().config().snake.half_extent
    }

    /// The resolved configuration as JSON.
    fn config_json(&self) -> String {
        serde_json::to_string(self.env().config()).expect("EnvConfig serialises")
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
        let mut guard = self.env();
        let env: &mut SnakeEnv = &mut guard;
        let (obs, info) = py.detach(|| env.reset(seed, options)).map_err(to_py)?;
        Ok((PyArray1::from_vec(py, obs), info_dict(py, &info)?))
    }

    /// step(action) -> (obs, reward, terminated, truncated, info)
    fn step<'py>(&self, py: Python<'py>, action: &Bound<'py, PyAny>) -> PyResult<StepTuple<'py>> {
        let action = float_vector(action, "action")?;
        let mut guard = self.env();
        let env: &mut SnakeEnv = &mut guard;
        let result = py.detach(|| env.step(&action)).map_err(to_py)?;
        Ok((
            PyArray1::from_vec(py, result.obs),
            result.reward,
            result.terminated,
            result.truncated,
            info_dict(py, &result.info)?,
        ))
    }

    /// Pose of every cube, the head first: an (N + 1, 7) array of x, y, z, qx, qy, qz, qw.
    fn cube_poses<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let env = self.env();
        let snake = env
            .snake()
            .ok_or_else(|| PyRuntimeError::new_err("no world yet: call reset() first"))?;
        let poses = snake.cube_poses().map_err(to_py)?;
        let flat: Vec<f64> = poses
            .iter()
            .flat_map(|p| {
                let q = p.orientation.coords;
                [p.position.x, p.position.y, p.position.z, q.x, q.y, q.z, q.w]
            })
            .collect();
        Ok(PyArray1::from_vec(py, flat)
            .reshape([poses.len(), 7])?
            .into_any())
    }
}

/// Many snake environments stepped together on threads (see `snakesim.SnakeVecEnv`).
#[pyclass(module = "snakesim._core")]
struct VecEnv {
    inner: Mutex<VecSnakeEnv>,
}

impl VecEnv {
    fn envs(&self) -> MutexGuard<'_, VecSnakeEnv> {
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }
}

#[pymethods]
impl VecEnv {
    #[new]
    fn new(config_json: &str, num_envs: usize) -> PyResult<Self> {
        let envs = VecSnakeEnv::new(parse_config(config_json)?, num_envs).map_err(to_py)?;
        Ok(VecEnv {
            inner: Mutex::new(envs),
        })
    }

    #[getter]
    fn num_envs(&self) -> usize {
        self.envs().num_envs()
    }

    #[getter]
    fn joints(&self) -> usize {
        self.envs().config().joints()
    }

    #[getter]
    fn action_dim(&self) -> usize {
        self.envs().action_dim()
    }

    #[getter]
    fn observation_dim(&self) -> usize {
        self.envs().observation_dim()
    }

    /// reset(seed) -> obs of shape (num_envs, observation_dim); env i is seeded with seed + i.
    #[pyo3(signature = (seed=None))]
    fn reset<'py>(&self, py: Python<'py>, seed: Option<u64>) -> PyResult<Bound<'py, PyAny>> {
        let mut guard = self.envs();
        let envs: &mut VecSnakeEnv = &mut guard;
        let (m, d) = (envs.num_envs(), envs.observation_dim());
        let mut obs = vec![0.0f32; m * d];
        py.detach(|| envs.reset(seed, &mut obs)).map_err(to_py)?;
        Ok(PyArray1::from_vec(py, obs).reshape([m, d])?.into_any())
    }

    /// step(actions (num_envs, joints)) -> (obs, rewards, terminated, truncated, finals), where finals
    /// lists (env index, final observation, final info) for each episode that ended and was reset.
    fn step<'py>(
        &self,
        py: Python<'py>,
        actions: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let mut guard = self.envs();
        let envs: &mut VecSnakeEnv = &mut guard;
        let (m, n, d) = (envs.num_envs(), envs.action_dim(), envs.observation_dim());
        let actions: Vec<f64> = if let Ok(a) = actions.extract::<PyReadonlyArray2<'_, f32>>() {
            check_shape(a.shape(), m, n)?;
            a.as_array().iter().map(|&v| f64::from(v)).collect()
        } else if let Ok(a) = actions.extract::<PyReadonlyArray2<'_, f64>>() {
            check_shape(a.shape(), m, n)?;
            a.as_array().iter().copied().collect()
        } else {
            return Err(describe_array_error(actions, "actions", 2));
        };
        let mut obs = vec![0.0f32; m * d];
        let mut rewards = vec![0.0f64; m];
        let mut terminated = vec![false; m];
        let mut truncated = vec![false; m];
        // Bullet worlds are not Sync, so the finished episodes are copied out while the GIL is released.
        let finished: Vec<(usize, Vec<f32>, Info)> = py
            .detach(|| {
                envs.step(
                    &actions,
                    &mut obs,
                    &mut rewards,
                    &mut terminated,
                    &mut truncated,
                )
                .map(|f| {
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
        let obs = PyArray1::from_vec(py, obs).reshape([m, d])?;
        PyTuple::new(
            py,
            [
                obs.into_any(),
                PyArray1::from_vec(py, rewards).into_any(),
                PyArray1::from_vec(py, terminated).into_any(),
                PyArray1::from_vec(py, truncated).into_any(),
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
    Ok(())
}
