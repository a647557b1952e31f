//! `simulate_robot`: a robot file driven by joint targets with named physics replaced, as `snake-cli
//! run --robot R --targets T.csv --output L.csv` runs it (snake-core's `run_targets`): the simulation
//! `snakesim calibrate` fits to a log.

use std::path::PathBuf;

use numpy::{PyArray2, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use snake_core::run_targets::{run_targets, Overrides};
use snake_core::{RobotSpec, StartPose, WorldRef, WorldSpec};

use crate::to_py;

/// simulate_robot(robot_path, targets, world_path=None, start=None, overrides_json="{}") ->
/// (base, joints): `targets` float64 of shape (steps, joints) in the robot's movable-joint order;
/// `start` (x, y, z, yaw) or None for the robot file's start (raised by the world's ground, as
/// `snake-cli run` does); `overrides_json` an object of `snakesim calibrate` fit keys. Returns the base
/// pose after every step (steps, 7: x, y, z, qx, qy, qz, qw) and the joint angles (steps, joints).
#[pyfunction]
#[pyo3(signature = (robot_path, targets, world_path=None, start=None, overrides_json="{}"))]
#[allow(clippy::type_complexity)]
fn simulate_robot<'py>(
    py: Python<'py>,
    robot_path: PathBuf,
    targets: PyReadonlyArray2<'py, f64>,
    world_path: Option<PathBuf>,
    start: Option<(f64, f64, f64, f64)>,
    overrides_json: &str,
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
    let out = py
        .detach(|| run_targets(&spec, start, &world_spec, &overrides, &rows))
        .map_err(to_py)?;
    let base: Vec<f64> = out.base.iter().flatten().copied().collect();
    let base = numpy::PyArray1::from_vec(py, base).reshape([steps, 7])?;
    let q = numpy::PyArray1::from_vec(py, out.joints).reshape([steps, joints])?;
    Ok((base, q))
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

/// Adds `simulate_robot` and `robot_joint_names` to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(simulate_robot, m)?)?;
    m.add_function(wrap_pyfunction!(robot_joint_names, m)?)
}
