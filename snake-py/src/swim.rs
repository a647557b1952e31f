//! `swim_targets`: Kelasidi et al.'s swimming gaits (snake-core's `gait::swim`) on a robot, as a table of
//! joint targets for `simulate_robot` (the water validation cases of `snakesim validate` drive Mamba
//! with it).

use std::path::PathBuf;

use numpy::{PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use snake_core::gait::{JointRoles, Swim, SwimParams, SwimPattern};
use snake_core::RobotSpec;

use crate::to_py;

/// swim_targets(robot_path, pattern, alpha, omega, delta, steps, offset=0.0, ramp=2.0, dt=1/240) ->
/// targets: `pattern` "lateral" (g = 1) or "eel" (g = (n - i)/(n + 1)), `alpha` and `delta` radians,
/// `omega` rad/s, `offset` (phi_0) radians, `ramp` seconds over which the wave grows; float64 of shape
/// (steps, joints) in the robot's movable-joint order, row s at t = s dt (the targets before step s + 1).
#[pyfunction]
#[pyo3(signature = (robot_path, pattern, alpha, omega, delta, steps, offset=0.0, ramp=2.0, dt=1.0/240.0))]
#[allow(clippy::too_many_arguments)]
fn swim_targets<'py>(
    py: Python<'py>,
    robot_path: PathBuf,
    pattern: &str,
    alpha: f64,
    omega: f64,
    delta: f64,
    steps: usize,
    offset: f64,
    ramp: f64,
    dt: f64,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let spec = RobotSpec::load(&robot_path).map_err(to_py)?;
    let pattern: SwimPattern = pattern.parse().map_err(to_py)?;
    let params = SwimParams {
        alpha,
        omega,
        delta,
        offset,
        ramp,
    };
    let swim = Swim::new(pattern, params, &JointRoles::of_urdf(&spec.urdf)).map_err(to_py)?;
    let most = snake_core::limits::MAX_TARGET_ROWS;
    if steps == 0 || steps > most {
        return Err(pyo3::exceptions::PyValueError::new_err(format!(
            "steps must be in [1, {most}], got {steps}"
        )));
    }
    if !(dt.is_finite() && dt > 0.0) {
        return Err(pyo3::exceptions::PyValueError::new_err(format!(
            "dt must be a positive finite number of seconds, got {dt}"
        )));
    }
    let joints = spec.urdf.movable_joints().len();
    let table = swim.table(dt, steps);
    numpy::PyArray1::from_vec(py, table).reshape([steps, joints])
}

/// Registers the function on `_core`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(swim_targets, m)?)
}
