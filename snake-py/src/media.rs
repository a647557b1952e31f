//! Media for Python (docs/media.md): `_core.rft_alpha` (Li et al.'s law over numpy arrays, the Rust
//! function itself), `_core.probe_plate` (the plate experiment of `snake-cli probe`) and
//! `_core.robot_gait_targets` (a robot file's own gait as joint targets, for `simulate_robot`) and
//! `_core.sandfish_targets` (Maladen et al.'s wave from the gait library, the same).

use std::path::PathBuf;

use numpy::{PyArray2, PyArrayDyn, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use snake_core::gait::sandfish::{SandfishGait, SandfishWave};
use snake_core::media::granular::{alpha, Coefficients, CoefficientsFile};
use snake_core::media::probe::{granular, probe, Plate};
use snake_core::{Gait, JointRoles, RobotGait, RobotSpec, WorldSpec};

use crate::to_py;

/// rft_alpha(beta, gamma, coefficients_json='"generic"') -> (alpha_x, alpha_z): Li et al.'s
/// generic law (snake_core::media::granular::alpha) at every element of `beta` and `gamma` (radians,
/// float64 arrays of one shape); `coefficients_json` a table name or a table of the nine coefficients,
/// as JSON. Non-finite angles are refused.
#[pyfunction]
#[pyo3(signature = (beta, gamma, coefficients_json="\"generic\""))]
#[allow(clippy::type_complexity)]
fn rft_alpha<'py>(
    py: Python<'py>,
    beta: PyReadonlyArrayDyn<'py, f64>,
    gamma: PyReadonlyArrayDyn<'py, f64>,
    coefficients_json: &str,
) -> PyResult<(Bound<'py, PyArrayDyn<f64>>, Bound<'py, PyArrayDyn<f64>>)> {
    let file: CoefficientsFile = serde_json::from_str(coefficients_json).map_err(|e| {
        PyValueError::new_err(format!(
            "coefficients: expected a name or a table of A00, A10, B11, B01, B-11, C11, C01, C-11, D10: {e}"
        ))
    })?;
    let c = match file {
        CoefficientsFile::Named(name) => {
            Coefficients::named(&name, "coefficients").map_err(to_py)?
        }
        CoefficientsFile::Table(t) => {
            let resolved = snake_core::media::granular::GranularFile {
                area: [0.0, 0.0, 1.0, 1.0],
                surface: 0.0,
                depth: 1.0,
                zeta: 1.0,
                coefficients: CoefficientsFile::Table(t),
                friction: 0.0,
                element: 0.01,
                elastic: 0.002,
            };
            resolved
                .resolve("coefficients")
                .map_err(|e| {
                    PyValueError::new_err(
                        e.to_string()
                            .replace("coefficients: coefficients", "coefficients"),
                    )
                })?
                .coefficients
        }
    };
    if beta.shape() != gamma.shape() {
        return Err(PyValueError::new_err(format!(
            "beta and gamma must have one shape, got {:?} and {:?}",
            beta.shape(),
            gamma.shape()
        )));
    }
    let (b, g) = (beta.as_array(), gamma.as_array());
    if let Some(bad) = b.iter().chain(g.iter()).find(|v| !v.is_finite()) {
        return Err(PyValueError::new_err(format!(
            "beta and gamma must be finite, got {bad}"
        )));
    }
    let mut ax = b.to_owned();
    let mut az = b.to_owned();
    for ((x, z), (&bb, &gg)) in ax.iter_mut().zip(az.iter_mut()).zip(b.iter().zip(g.iter())) {
        (*x, *z) = alpha(bb, gg, &c);
    }
    Ok((
        PyArrayDyn::from_owned_array(py, ax),
        PyArrayDyn::from_owned_array(py, az),
    ))
}

/// probe_plate(world_path, length, width, beta, gamma, depth, speed) -> JSON of the result of
/// `snake-cli probe` (angles in degrees; snake_core::media::probe).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn probe_plate(
    world_path: PathBuf,
    length: f64,
    width: f64,
    beta: f64,
    gamma: f64,
    depth: f64,
    speed: f64,
) -> PyResult<String> {
    let plate = Plate {
        length,
        width,
        beta,
        gamma,
        depth,
        speed,
    };
    plate.check(|name| name.to_string()).map_err(to_py)?;
    let spec = WorldSpec::load(&world_path).map_err(to_py)?;
    let medium = granular(&spec.media).map_err(to_py)?;
    let r = probe(medium, &plate).map_err(to_py)?;
    Ok(serde_json::json!({"zeta": medium.zeta, "result": r}).to_string())
}

/// robot_gait_targets(robot_path, steps) -> the robot file's own gait (its `gait:` key) as joint
/// targets, float64 (steps, joints), one row per physics step, as `snake-cli run --robot` drives it.
#[pyfunction]
fn robot_gait_targets<'py>(
    py: Python<'py>,
    robot_path: PathBuf,
    steps: usize,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let spec = RobotSpec::load(&robot_path).map_err(to_py)?;
    let wave = spec.gait.clone().ok_or_else(|| {
        PyValueError::new_err(format!(
            "{}: the robot file sets no gait",
            robot_path.display()
        ))
    })?;
    if steps > snake_core::limits::MAX_TARGET_ROWS {
        return Err(PyValueError::new_err(format!(
            "steps: at most {}, got {steps}",
            snake_core::limits::MAX_TARGET_ROWS
        )));
    }
    let joints = spec.urdf.movable_joints().len();
    let mut gait = RobotGait::new(wave, &spec);
    let mut rows = vec![0.0; steps * joints];
    for row in rows.chunks_exact_mut(joints.max(1)) {
        gait.next_targets(row);
    }
    let array = numpy::ndarray::Array2::from_shape_vec((steps, joints), rows)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(PyArray2::from_owned_array(py, array))
}

/// sandfish_targets(robot_path, amplitude, wavelength, frequency, segment, steps) -> Maladen et al.'s
/// travelling sine wave (snake_core::gait::sandfish) on the robot's yaw joints as joint targets,
/// float64 (steps, joints), one row per physics step (1/240 s).
#[pyfunction]
fn sandfish_targets<'py>(
    py: Python<'py>,
    robot_path: PathBuf,
    amplitude: f64,
    wavelength: f64,
    frequency: f64,
    segment: f64,
    steps: usize,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let spec = RobotSpec::load(&robot_path).map_err(to_py)?;
    if steps > snake_core::limits::MAX_TARGET_ROWS {
        return Err(PyValueError::new_err(format!(
            "steps: at most {}, got {steps}",
            snake_core::limits::MAX_TARGET_ROWS
        )));
    }
    let wave = SandfishWave {
        amplitude,
        wavelength,
        frequency,
        segment,
    };
    let roles = JointRoles::of_urdf(&spec.urdf);
    let joints = roles.roles.len();
    let dt = snake_core::SnakeConfig::default().dt;
    let mut gait = SandfishGait::new(wave, &roles, dt).map_err(to_py)?;
    let mut rows = vec![0.0; steps * joints];
    for row in rows.chunks_exact_mut(joints.max(1)) {
        gait.next_targets(row);
    }
    let array = numpy::ndarray::Array2::from_shape_vec((steps, joints), rows)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(PyArray2::from_owned_array(py, array))
}

/// Adds `rft_alpha`, `probe_plate`, `robot_gait_targets` and `sandfish_targets` to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(sandfish_targets, m)?)?;
    m.add_function(wrap_pyfunction!(rft_alpha, m)?)?;
    m.add_function(wrap_pyfunction!(probe_plate, m)?)?;
    m.add_function(wrap_pyfunction!(robot_gait_targets, m)?)
}
