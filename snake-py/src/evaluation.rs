//! The evaluation protocol (snake-rl's `evaluate`) for Python's actors: `snakesim evaluate`, the SB3
//! trainer's evaluations and the sweeps run the same episodes, measured the same way, as the native
//! trainer's evaluations.

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::{PyKeyboardInterrupt, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use snake_rl::evaluate::{self, Episode, EvalError, MAX_EVAL_ENVS};

use crate::{parse_config, to_py};

/// Most episodes of one evaluation (the run configuration's limit on `eval_episodes`).
fn max_episodes() -> usize {
    snake_rl::config::limits::MAX_EVAL_EPISODES as usize
}

fn episode_dict<'py>(py: Python<'py>, e: &Episode) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("ret", e.ret)?;
    d.set_item("steps", e.steps)?;
    d.set_item("success", e.success)?;
    d.set_item("seconds", e.seconds)?;
    d.set_item("distance", e.distance)?;
    d.set_item("path_length", e.path_length)?;
    d.set_item("work", e.work)?;
    d.set_item("weight", e.weight)?;
    d.set_item("speed", e.speed())?;
    d.set_item("path_efficiency", e.path_efficiency())?;
    d.set_item("cost_of_transport", e.cost_of_transport())?;
    if e.physics.values().next().is_some() {
        d.set_item("physics", crate::physics_dict(py, &e.physics)?)?;
    }
    Ok(d)
}

/// run_episodes(config_json, episodes, seed, act) -> list of episode dicts (ret, steps, success,
/// seconds, distance, path_length, work, weight, and the derived speed, path_efficiency and
/// cost_of_transport, None where undefined; under `randomize`, physics: the episode's draws).
/// `act(obs)` gets the observations of the envs that run at once, float32 of shape (m,
/// observation_dim), and returns their actions (m, action_dim), float32 or float64; env i is seeded
/// with seed + i (snake-rl's `evaluate::run_episodes_with`). `restart(i)`, where given, is called
/// when env i's episode ends (an actor with a clock per env restarts it). `progress(done)`, where
/// given, is called each time an episode that counts ends, with the number ended so far (1 to
/// `episodes`); it changes nothing of the episodes.
#[pyfunction]
#[pyo3(signature = (config_json, episodes, seed, act, restart=None, progress=None))]
fn run_episodes<'py>(
    py: Python<'py>,
    config_json: &str,
    episodes: usize,
    seed: u64,
    act: Bound<'py, PyAny>,
    restart: Option<Bound<'py, PyAny>>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyList>> {
    if !(1..=max_episodes()).contains(&episodes) {
        return Err(PyValueError::new_err(format!(
            "episodes must be in [1, {}], got {episodes}",
            max_episodes()
        )));
    }
    let config = parse_config(config_json)?;
    let (n, d) = (config.action_dim(), config.observation_dim());
    let mut failure: Option<PyErr> = None;
    let mut actor = |obs: &[f32], m: usize, actions: &mut [f64]| -> Result<(), EvalError> {
        let mut call = || -> PyResult<()> {
            let batch = PyArray1::from_slice(py, obs).reshape([m, d])?;
            let out = act.call1((batch,))?;
            if let Ok(a) = out.extract::<PyReadonlyArray2<'_, f32>>() {
                check_shape(a.shape(), m, n)?;
                for (slot, v) in actions.iter_mut().zip(a.as_array().iter()) {
                    *slot = f64::from(*v);
                }
            } else {
                let a =
                    out.extract::<PyReadonlyArray2<'_, f64>>().map_err(|_| {
                        PyValueError::new_err(format!(
                        "act must return a float32 or float64 array of shape ({m}, {n}), got {}",
                        out.get_type().name().map(|s| s.to_string()).unwrap_or_default()
                    ))
                    })?;
                check_shape(a.shape(), m, n)?;
                actions.copy_from_slice(a.as_slice()?);
            }
            Ok(())
        };
        call().map_err(|e| {
            let message = e.to_string();
            failure = Some(e);
            EvalError::Actor(message)
        })
    };
    // Either error ends the evaluation at once: at most one of `failure` and `restart_failure` is set.
    let mut restart_failure: Option<PyErr> = None;
    // Every episode's end reaches `restart`; those within their env's count are the evaluation's.
    let targets = evaluate::episode_targets(episodes);
    let mut ended = vec![0usize; targets.len()];
    let mut counted = 0usize;
    let mut on_restart = |env: usize| -> Result<(), EvalError> {
        let mut fail = |e: PyErr| {
            let message = e.to_string();
            restart_failure = Some(e);
            EvalError::Actor(message)
        };
        if let Some(restart) = &restart {
            restart.call1((env,)).map_err(&mut fail)?;
        }
        if ended[env] < targets[env] {
            ended[env] += 1;
            counted += 1;
            if let Some(progress) = &progress {
                progress.call1((counted,)).map_err(&mut fail)?;
            }
        }
        Ok(())
    };
    let mut interrupted: Option<PyErr> = None;
    let mut stop = || match py.check_signals() {
        Ok(()) => false,
        Err(e) => {
            interrupted = Some(e);
            true
        }
    };
    let result = evaluate::run_episodes_with(
        &mut actor,
        &mut on_restart,
        &config,
        episodes,
        seed,
        None,
        &mut stop,
    );
    match result {
        Ok(done) => {
            let list = PyList::empty(py);
            for e in &done {
                list.append(episode_dict(py, e)?)?;
            }
            Ok(list)
        }
        Err(EvalError::Env(e)) => Err(to_py(e)),
        Err(EvalError::Actor(message)) => Err(failure
            .or(restart_failure)
            .unwrap_or_else(|| PyValueError::new_err(message))),
        Err(EvalError::Interrupted) => {
            Err(interrupted
                .unwrap_or_else(|| PyKeyboardInterrupt::new_err("evaluation interrupted")))
        }
    }
}

fn check_shape(shape: &[usize], m: usize, n: usize) -> PyResult<()> {
    if shape == [m, n] {
        Ok(())
    } else {
        Err(PyValueError::new_err(format!(
            "act must return actions of shape ({m}, {n}), got {shape:?}"
        )))
    }
}

/// summarize(episodes) -> dict: snake-rl's `evaluate::summarize` of episode dicts as run_episodes
/// returns them (mean and population std of the return, success rate and its 95 % Wilson interval,
/// steps and seconds to goal of the successes, mean speed, path efficiency, cost of transport, length).
#[pyfunction]
fn summarize<'py>(
    py: Python<'py>,
    episodes: Vec<Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    if episodes.is_empty() {
        return Err(PyValueError::new_err(
            "summarize needs at least one episode",
        ));
    }
    let get = |d: &Bound<'py, PyDict>, key: &str| -> PyResult<Bound<'py, PyAny>> {
        d.get_item(key)?
            .ok_or_else(|| PyValueError::new_err(format!("an episode has no {key:?}")))
    };
    let mut parsed = Vec::with_capacity(episodes.len());
    for d in &episodes {
        parsed.push(Episode {
            ret: get(d, "ret")?.extract()?,
            steps: get(d, "steps")?.extract()?,
            success: get(d, "success")?.extract()?,
            seconds: get(d, "seconds")?.extract()?,
            distance: get(d, "distance")?.extract()?,
            path_length: get(d, "path_length")?.extract()?,
            work: get(d, "work")?.extract()?,
            weight: get(d, "weight")?.extract()?,
            physics: Default::default(),
        });
    }
    let s = evaluate::summarize(&parsed);
    let out = PyDict::new(py);
    out.set_item("episodes", s.episodes)?;
    out.set_item("success_rate", s.success_rate)?;
    out.set_item(
        "success_rate_ci95",
        vec![s.success_rate_ci95.0, s.success_rate_ci95.1],
    )?;
    out.set_item("mean_return", s.mean_return)?;
    out.set_item("std_return", s.std_return)?;
    out.set_item("mean_steps_to_goal", s.mean_steps_to_goal)?;
    out.set_item("mean_seconds_to_goal", s.mean_seconds_to_goal)?;
    out.set_item("mean_speed", s.mean_speed)?;
    out.set_item("mean_path_efficiency", s.mean_path_efficiency)?;
    out.set_item("mean_cost_of_transport", s.mean_cost_of_transport)?;
    out.set_item("mean_length", s.mean_length)?;
    Ok(out)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(run_episodes, m)?)?;
    m.add_function(wrap_pyfunction!(summarize, m)?)?;
    m.add("MAX_EVAL_ENVS", MAX_EVAL_ENVS)?;
    Ok(())
}
