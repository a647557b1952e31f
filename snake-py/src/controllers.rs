//! The hand controllers and the steering assist (snake-core's `controllers`) for Python:
//! `snakesim.agents.baselines` and `snakesim.wrappers.SteerAssist` act through them, so each is
//! written once.

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use snake_core::controllers::{HeldWave, Imitable, JointsSine as CoreSine};
use snake_core::{AssistedEnv, ControlledEnv, HandController, SteerAssist as CoreAssist};

use crate::{parse_config, to_py};

/// Observations `(rows, observation_dim)` as one flat float32 vector, checked.
fn observations(obs: &PyReadonlyArray2<'_, f32>, dim: usize) -> PyResult<(Vec<f32>, usize)> {
    let shape = obs.shape();
    if shape[1] != dim {
        return Err(PyValueError::new_err(format!(
            "obs must have shape (n, {dim}), got {shape:?}"
        )));
    }
    Ok((obs.as_array().iter().copied().collect(), shape[0]))
}

/// Actions `(rows, 3)` of float32 or float64 as float64 (the values as they are).
fn gait_actions(actions: &Bound<'_, PyAny>, rows: usize) -> PyResult<Vec<f64>> {
    let n = snake_core::controllers::GAIT_ACTION_LEN;
    let (shape, values): (Vec<usize>, Vec<f64>) =
        if let Ok(a) = actions.extract::<PyReadonlyArray2<'_, f32>>() {
            (
                a.shape().to_vec(),
                a.as_array().iter().map(|&v| f64::from(v)).collect(),
            )
        } else if let Ok(a) = actions.extract::<PyReadonlyArray2<'_, f64>>() {
            (a.shape().to_vec(), a.as_array().iter().copied().collect())
        } else {
            return Err(PyTypeError::new_err(
                "actions must be a 2-D float32 or float64 array",
            ));
        };
    if shape != [rows, n] {
        return Err(PyValueError::new_err(format!(
            "actions must have shape ({rows}, {n}), got {shape:?}"
        )));
    }
    if let Some(v) = values.iter().find(|v| !v.is_finite()) {
        return Err(PyValueError::new_err(format!(
            "actions must be finite, got {v}"
        )));
    }
    Ok(values)
}

fn to_array<'py>(py: Python<'py>, values: Vec<f64>, rows: usize) -> PyResult<Bound<'py, PyAny>> {
    let n = snake_core::controllers::GAIT_ACTION_LEN;
    Ok(PyArray1::from_vec(py, values)
        .reshape([rows, n])?
        .into_any())
}

/// hand_actions(name, config_json, obs (n, observation_dim) float32, amplitude=0.0, frequency=0.0)
/// -> actions (n, 3) float64 of the hand controller `baseline:NAME` in the env of `config_json`
/// (SnakeEnv's keywords as JSON), holding the amplitude and frequency actions at the values given
/// (snake-core's `HeldWave`; 0: the middle of their ranges, as `baseline:NAME` does).
#[pyfunction]
#[pyo3(signature = (name, config_json, obs, amplitude=0.0, frequency=0.0))]
fn hand_actions<'py>(
    py: Python<'py>,
    name: &str,
    config_json: &str,
    obs: PyReadonlyArray2<'py, f32>,
    amplitude: f64,
    frequency: f64,
) -> PyResult<Bound<'py, PyAny>> {
    let controller = HandController::from_name(name).map_err(to_py)?;
    let hold = HeldWave {
        amplitude,
        frequency,
    };
    hold.validate().map_err(to_py)?;
    let config = parse_config(config_json)?;
    let on = ControlledEnv::of(&config, "the baselines").map_err(to_py)?;
    let (flat, rows) = observations(&obs, on.observation_dim())?;
    let mut out = vec![0.0; rows * snake_core::controllers::GAIT_ACTION_LEN];
    controller.act_holding(&on, &flat, rows, &mut out, hold);
    to_array(py, out, rows)
}

/// The hand controllers' names.
#[pyfunction]
fn hand_controller_names() -> Vec<&'static str> {
    HandController::ALL.iter().map(|c| c.name()).collect()
}

/// SteerAssist(config_json, residual=False, near_goal=0.0): `baseline:steer` sharing an agent's gait
/// actions in the env of `config_json` (snake-core's `SteerAssist`); `SteerAssist.from_json` reads the
/// JSON a model records.
#[pyclass(module = "snakesim._core", frozen)]
struct SteerAssist {
    bound: AssistedEnv,
}

#[pymethods]
impl SteerAssist {
    #[new]
    #[pyo3(signature = (config_json, residual=false, near_goal=0.0))]
    fn new(config_json: &str, residual: bool, near_goal: f64) -> PyResult<Self> {
        Self::bound(
            CoreAssist {
                residual,
                near_goal,
            },
            config_json,
        )
    }

    /// The assist a model records (its JSON) in the env of `config_json`.
    #[staticmethod]
    fn from_json(assist_json: &str, config_json: &str) -> PyResult<Self> {
        let assist: CoreAssist = serde_json::from_str(assist_json)
            .map_err(|e| PyValueError::new_err(format!("steer_assist: {e}")))?;
        Self::bound(assist, config_json)
    }

    #[getter]
    fn residual(&self) -> bool {
        self.bound.assist().residual
    }

    #[getter]
    fn near_goal(&self) -> f64 {
        self.bound.assist().near_goal
    }

    /// The assist as JSON (as a model records it).
    fn to_json(&self) -> String {
        serde_json::to_string(&self.bound.assist()).expect("an assist serialises")
    }

    /// apply(obs (n, observation_dim) float32, actions (n, 3)) -> the env's actions (n, 3) float64.
    fn apply<'py>(
        &self,
        py: Python<'py>,
        obs: PyReadonlyArray2<'py, f32>,
        actions: Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let dim = obs.shape()[1];
        let (flat, rows) = observations(&obs, dim)?;
        let agent = gait_actions(&actions, rows)?;
        let mut out = vec![0.0; agent.len()];
        // The observation's length is the env's: `bind` checked the layout, apply reads by it.
        self.check_dim(dim)?;
        self.bound.apply(&flat, &agent, rows, &mut out);
        to_array(py, out, rows)
    }
}

impl SteerAssist {
    fn bound(assist: CoreAssist, config_json: &str) -> PyResult<Self> {
        let config = parse_config(config_json)?;
        let bound = assist.bind(&config).map_err(to_py)?;
        Ok(SteerAssist { bound })
    }

    fn check_dim(&self, dim: usize) -> PyResult<()> {
        let expected = self.bound.observation_dim();
        if dim != expected {
            return Err(PyValueError::new_err(format!(
                "obs must have shape (n, {expected}), got (n, {dim})"
            )));
        }
        Ok(())
    }
}

/// The joint-target controllers' names (`init.imitate`, `baseline:NAME` of the paper's env).
#[pyfunction]
fn joint_controller_names() -> Vec<&'static str> {
    Imitable::ALL.iter().map(|c| c.name()).collect()
}

/// JointsSine(name, config_json, envs): snake-core's `JointsSine` (`sine`, `steered_sine`), pybullet
/// snake.py's wave as joint targets for `envs` envs of the env of `config_json`, a clock per env:
/// `act(obs (envs, observation_dim) float32) -> actions (envs, joints) float32` advances every
/// env's wave by one env step, `reset(env)` restarts one (its episode ended).
#[pyclass(module = "snakesim._core")]
struct JointsSine {
    inner: CoreSine,
}

#[pymethods]
impl JointsSine {
    #[new]
    fn new(name: &str, config_json: &str, envs: usize) -> PyResult<Self> {
        let kind = Imitable::from_name(name).map_err(to_py)?;
        let config = parse_config(config_json)?;
        let max = snake_core::limits::MAX_ENVS;
        if !(1..=max).contains(&envs) {
            return Err(PyValueError::new_err(format!(
                "envs must be in [1, {max}], got {envs}"
            )));
        }
        let inner = CoreSine::new(kind, &config, envs).map_err(to_py)?;
        Ok(JointsSine { inner })
    }

    #[getter]
    fn envs(&self) -> usize {
        self.inner.envs()
    }

    fn act<'py>(
        &mut self,
        py: Python<'py>,
        obs: PyReadonlyArray2<'py, f32>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (flat, rows) = observations(&obs, self.inner.observation_dim())?;
        if rows != self.inner.envs() {
            return Err(PyValueError::new_err(format!(
                "obs must have one row per env ({}), got {rows}",
                self.inner.envs()
            )));
        }
        let n = self.inner.action_dim();
        let mut out = vec![0.0f32; rows * n];
        self.inner.act(&flat, &mut out);
        Ok(PyArray1::from_vec(py, out).reshape([rows, n])?.into_any())
    }

    fn reset(&mut self, env: usize) -> PyResult<()> {
        if env >= self.inner.envs() {
            return Err(PyValueError::new_err(format!(
                "env must be in [0, {}), got {env}",
                self.inner.envs()
            )));
        }
        self.inner.reset(env);
        Ok(())
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(hand_actions, m)?)?;
    m.add_function(wrap_pyfunction!(hand_controller_names, m)?)?;
    m.add_function(wrap_pyfunction!(joint_controller_names, m)?)?;
    m.add_class::<SteerAssist>()?;
    m.add_class::<JointsSine>()?;
    Ok(())
}
