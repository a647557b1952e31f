//! `simulate_robot`: a robot file driven by joint targets with named physics replaced, as `snake-cli
//! run --robot R --targets T.csv --output L.csv` runs it (snake-core's `run_targets`): the simulation
//! `snakesim calibrate` fits to a log.

use std::ffi::OsString;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use numpy::{PyArray2, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use snake_core::run_targets::{run_targets_until, run_windows_until, Overrides, Windows};
use snake_core::{RecordedFiles, RobotRef, RobotSpec, StartPose, WorldRef, WorldSpec};

use crate::to_py;

/// simulate_robot(robot_path, targets, world_path=None, start=None, overrides_json="{}",
/// window=None, states=None) -> (base, joints): `targets` float64 of shape (steps, joints) in the
/// robot's movable-joint order;
/// `start` (x, y, z, yaw) or None for the robot file's start (raised by the world's ground, as
/// `snake-cli run` does); `overrides_json` an object of `snakesim calibrate` fit keys. Returns the base
/// pose after every step (steps, 7: x, y, z, qx, qy, qz, qw) and the joint angles (steps, joints).
/// With `window` (physics steps) the run is cut into windows, window i > 0 restarting from row i - 1 of
/// `states` (float64, (ceil(steps / window) - 1, 13 + 2 joints): the base's x, y, z, qx, qy, qz, qw,
/// vx, vy, vz, wx, wy, wz, the joint angles, the joint velocities; snake-core's `run_windows_until`).
/// Python's signal handlers run every 20 ms of the simulation, so Ctrl-C (KeyboardInterrupt) and
/// whatever a handler raises (snakesim's SIGTERM) end it within a physics step of that.
#[pyfunction]
#[pyo3(signature = (robot_path, targets, world_path=None, start=None, overrides_json="{}", window=None, states=None))]
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
fn simulate_robot<'py>(
    py: Python<'py>,
    robot_path: PathBuf,
    targets: PyReadonlyArray2<'py, f64>,
    world_path: Option<PathBuf>,
    start: Option<(f64, f64, f64, f64)>,
    overrides_json: &str,
    window: Option<usize>,
    states: Option<PyReadonlyArray2<'py, f64>>,
) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>)> {
    let spec = RobotSpec::load(&robot_path).map_err(to_py)?;
    let world = world_path
        .as_deref()
        .map(WorldRef::load)
        .transpose()
        .map_err(to_py)?;
    let overrides = Overrides::from_json(overrides_json).map_err(to_py)?;
    let joints = spec.urdf.movable_joints().len();
    let shape = targets.shape();
    if shape[1] != joints || shape[0] == 0 {
        return Err(PyValueError::new_err(format!(
            "targets must have shape (steps >= 1, {joints}) for {}, got {shape:?}",
            robot_path.display()
        )));
    }
    let rows = targets.as_slice()?.to_vec();
    let states: Option<Vec<f64>> = match (window, &states) {
        (None, None) => None,
        (Some(_), Some(s)) => Some(s.as_slice()?.to_vec()),
        _ => {
            return Err(PyValueError::new_err(
                "window and states go together: give both or neither",
            ))
        }
    };
    let world_spec = world
        .as_ref()
        .map_or_else(WorldSpec::default, |w| w.spec().clone());
    // As snake-cli run: an explicit start is kept; the robot file's is raised by the ground's highest
    // point under the body when a world is given.
    let start = match (start, &world) {
        (Some((x, y, z, yaw)), _) => StartPose { x, y, z, yaw },
        (None, None) => spec.default_start(),
        (None, Some(w)) => {
            let s = spec.default_start();
            StartPose {
                z: s.z + w.spec().ground_top(reach(&spec)),
                ..s
            }
        }
    };
    let steps = shape[0];
    let mut interrupted: Option<PyErr> = None;
    let mut last_check = Instant::now();
    let mut should_stop = || {
        if last_check.elapsed() < Duration::from_millis(20) {
            return false;
        }
        last_check = Instant::now();
        match Python::attach(|py| py.check_signals()) {
            Ok(()) => false,
            Err(e) => {
                interrupted = Some(e);
                true
            }
        }
    };
    let out = py
        .detach(|| match (window, &states) {
            (Some(length), Some(states)) => run_windows_until(
                &spec,
                start,
                &world_spec,
                &overrides,
                &rows,
                Windows { length, states },
                &mut should_stop,
            ),
            _ => run_targets_until(
                &spec,
                start,
                &world_spec,
                &overrides,
                &rows,
                &mut should_stop,
            ),
        })
        .map_err(to_py)?;
    let Some(out) = out else {
        return Err(interrupted.expect("a run stops only when a signal handler raised"));
    };
    let base: Vec<f64> = out.base.iter().flatten().copied().collect();
    let base = numpy::PyArray1::from_vec(py, base).reshape([steps, 7])?;
    let q = numpy::PyArray1::from_vec(py, out.joints).reshape([steps, joints])?;
    Ok((base, q))
}

/// fitted_robot_file(robot_path, overrides_json, urdf) -> str: the robot (a robot file or a URDF) with
/// the fit keys of `overrides_json` written in, as the YAML text of a robot file whose `urdf:` is
/// `urdf` (snake-core's `run_targets::fitted_robot_file`: the mapping `simulate_robot` applies, every
/// per-link and per-joint value included; keys a robot file cannot hold as comments).
#[pyfunction]
fn fitted_robot_file(robot_path: PathBuf, overrides_json: &str, urdf: &str) -> PyResult<String> {
    let overrides = Overrides::from_json(overrides_json).map_err(to_py)?;
    snake_core::run_targets::fitted_robot_file(&robot_path, &overrides, urdf).map_err(to_py)
}

/// snake-cli run's footprint of a robot over which a world's ground lifts the default start.
fn reach(spec: &RobotSpec) -> f64 {
    use snake_core::urdf::Geometry;
    let sizes: Vec<f64> = spec
        .urdf
        .links
        .iter()
        .flat_map(|l| l.collisions.iter())
        .map(|c| match c.geometry {
            Geometry::Box(s) => s.iter().copied().fold(0.0, f64::max) / 2.0,
            Geometry::Sphere(r) => r,
            Geometry::Cylinder { radius, .. } | Geometry::Capsule { radius, .. } => radius,
        })
        .collect();
    let half = if sizes.is_empty() {
        0.05
    } else {
        sizes.iter().sum::<f64>() / sizes.len() as f64
    };
    spec.urdf
        .links
        .iter()
        .filter_map(|l| l.joint.as_ref())
        .map(|j| {
            let [x, y, z] = j.origin.xyz;
            (x * x + y * y + z * z).sqrt()
        })
        .sum::<f64>()
        + 2.0 * half
}

/// robot_joint_names(robot_path) -> the robot's movable joints in pybullet's order (the columns of a
/// targets file; a trajectory's q0, q1, ... follow this order).
#[pyfunction]
fn robot_joint_names(robot_path: PathBuf) -> PyResult<Vec<String>> {
    let spec = RobotSpec::load(&robot_path).map_err(to_py)?;
    Ok(spec.joint_names().iter().map(|s| s.to_string()).collect())
}

/// The paths of the files a robot or world is read from ([`RecordedFiles`]): the main file as it was
/// given, the others (a URDF, a heightfield CSV) beside it by the names it gives them.
fn file_paths(files: &RecordedFiles) -> Vec<OsString> {
    let main = files.main_name();
    files
        .files
        .keys()
        .map(|name| {
            if *name == main {
                files.path.clone().into_os_string()
            } else {
                files.dir().join(name).into_os_string()
            }
        })
        .collect()
}

/// robot_files(robot_path) -> every file the robot is read from: the robot file and the URDF it
/// names (a bare URDF alone), as paths (the others joined to the robot file's folder). A command
/// that writes must not overwrite any of them.
#[pyfunction]
fn robot_files(robot_path: PathBuf) -> PyResult<Vec<OsString>> {
    Ok(file_paths(
        RobotRef::load(&robot_path).map_err(to_py)?.files(),
    ))
}

/// world_files(world_path) -> every file the world is read from: the world file and the heightfield
/// CSV it names, if any, as paths (as `robot_files`).
#[pyfunction]
fn world_files(world_path: PathBuf) -> PyResult<Vec<OsString>> {
    Ok(file_paths(
        WorldRef::load(&world_path).map_err(to_py)?.files(),
    ))
}

/// read_targets(path, joints) -> float64 (steps, joints): a targets CSV in the order of `joints` (the
/// robot's movable joints), parsed by snake-core's `tables` as `snake-cli run --targets` reads it, under
/// the same limits. ValueError naming the file and line.
#[pyfunction]
fn read_targets<'py>(
    py: Python<'py>,
    path: PathBuf,
    joints: Vec<String>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let names: Vec<&str> = joints.iter().map(String::as_str).collect();
    let table = snake_core::tables::read_targets(&path, &names).map_err(to_py)?;
    table_array(py, table)
}

/// read_log(path, joints, steps, dt) -> (values, velocities): a log CSV of `steps` physics steps of
/// `dt` s by a robot with `joints` movable joints, parsed by snake-core's `tables`: float64 (steps, 7 +
/// joints) after `step` and `t` (base pose, joints), or (steps, 13 + 2 joints) with the velocity
/// columns, and whether it holds them. ValueError naming the file and line.
#[pyfunction]
fn read_log<'py>(
    py: Python<'py>,
    path: PathBuf,
    joints: usize,
    steps: usize,
    dt: f64,
) -> PyResult<(Bound<'py, PyArray2<f64>>, bool)> {
    let log = snake_core::tables::read_log(&path, joints, steps, dt).map_err(to_py)?;
    Ok((table_array(py, log.table)?, log.velocities))
}

/// log_columns(joints, velocities) -> the header of a log (`snake-cli run --output`).
#[pyfunction]
fn log_columns(joints: usize, velocities: bool) -> Vec<String> {
    snake_core::tables::log_columns(joints, velocities)
}

fn table_array(
    py: Python<'_>,
    table: snake_core::tables::Table,
) -> PyResult<Bound<'_, PyArray2<f64>>> {
    let (rows, columns) = (table.rows, table.columns);
    numpy::PyArray1::from_vec(py, table.values)
        .reshape([rows, columns])
        .map_err(|e| PyValueError::new_err(e.to_string()))
}

/// Adds `simulate_robot`, `fitted_robot_file`, `robot_joint_names`, `robot_files`, `world_files`,
/// `read_targets`, `read_log`, `log_columns` and `NOT_IN_ROBOT_FILE` (the fit keys a robot file cannot
/// hold, from snake-core) to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let not_in_file: Vec<&str> = snake_core::run_targets::NOT_IN_ROBOT_FILE
        .iter()
        .map(|(k, _)| *k)
        .collect();
    m.add("NOT_IN_ROBOT_FILE", not_in_file)?;
    m.add_function(wrap_pyfunction!(read_targets, m)?)?;
    m.add_function(wrap_pyfunction!(read_log, m)?)?;
    m.add_function(wrap_pyfunction!(log_columns, m)?)?;
    m.add_function(wrap_pyfunction!(simulate_robot, m)?)?;
    m.add_function(wrap_pyfunction!(fitted_robot_file, m)?)?;
    m.add_function(wrap_pyfunction!(robot_joint_names, m)?)?;
    m.add_function(wrap_pyfunction!(robot_files, m)?)?;
    m.add_function(wrap_pyfunction!(world_files, m)?)
}
