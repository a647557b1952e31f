//! Shared machinery of the parity tests: scenarios, running them in snake-core, running them in the
//! pybullet reference (`reference/pybullet_reference.py`), and comparing the two bit for bit.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

use serde::{Deserialize, Serialize};
use snake_core::{Dynamics, Gait, JointControl, LateralUndulation, Preset, Snake, StartPose};

/// One reference run; serialised as the reference script reads it.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Scenario {
    /// File stem of the reference output.
    pub name: String,
    /// Number of joints.
    pub joints: usize,
    /// "paper" or "snakebot-gym".
    pub preset: String,
    /// x, y, z, yaw.
    pub start: [f64; 4],
    /// Physics steps.
    pub steps: u64,
    /// How the joints are driven.
    pub control: Control,
    /// changeDynamics keywords applied to every cube after the preset's friction.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub dynamics: BTreeMap<String, serde_json::Value>,
}

/// Joint drive of a scenario (see the reference script for the exact signals).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Control {
    /// gait | zero | position | velocity | torque
    pub mode: String,
    /// Gait steering.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steering: Option<f64>,
    /// Motor force (or torque amplitude in torque mode); 10 if absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force: Option<f64>,
    /// Position gain (position mode).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kp: Option<f64>,
    /// Velocity gain (position mode).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kd: Option<f64>,
    /// Target velocity (position mode).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target_velocity: Option<f64>,
    /// Motor velocity clamp (position mode).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_velocity: Option<f64>,
}

impl Scenario {
    /// A scenario driven by `mode` with everything else at its default.
    pub fn new(
        name: impl Into<String>,
        joints: usize,
        preset: &str,
        start: [f64; 4],
        steps: u64,
        mode: &str,
    ) -> Self {
        Scenario {
            name: name.into(),
            joints,
            preset: preset.into(),
            start,
            steps,
            control: Control {
                mode: mode.into(),
                ..Control::default()
            },
            dynamics: BTreeMap::new(),
        }
    }
}

const DT: f64 = 1.0 / 240.0;

/// The reference's test signal: amplitude * sin(2 pi * 0.8 * t + 0.7 * joint), in its operation order.
fn signal(step: u64, joint: usize, amplitude: f64) -> f64 {
    amplitude * (2.0 * std::f64::consts::PI * 0.8 * (step as f64 * DT) + 0.7 * joint as f64).sin()
}

fn dynamics_from(keywords: &BTreeMap<String, serde_json::Value>) -> Dynamics {
    let mut d = Dynamics::default();
    for (key, value) in keywords {
        let num = || {
            value
                .as_f64()
                .unwrap_or_else(|| panic!("{key} must be a number"))
        };
        match key.as_str() {
            "lateralFriction" => d.lateral_friction = Some(num()),
            "spinningFriction" => d.spinning_friction = Some(num()),
            "rollingFriction" => d.rolling_friction = Some(num()),
            "restitution" => d.restitution = Some(num()),
            "jointDamping" => d.joint_damping = Some(num()),
            "linearDamping" => d.linear_damping = Some(num()),
            "angularDamping" => d.angular_damping = Some(num()),
            "frictionAnchor" => d.friction_anchor = Some(num() != 0.0),
            "anisotropicFriction" => {
                let v: Vec<f64> = serde_json::from_value(value.clone()).expect("three numbers");
                d.anisotropic_friction = Some([v[0], v[1], v[2]]);
            }
            other => panic!("scenario uses an unsupported changeDynamics keyword {other}"),
        }
    }
    d
}

/// Runs a scenario in snake-core; one row per step in the reference's column order.
pub fn run_ours(s: &Scenario) -> Vec<Vec<f64>> {
    let preset: Preset = s.preset.parse().expect("known preset");
    let config = preset.config(s.joints);
    let [x, y, z, yaw] = s.start;
    let mut snake = Snake::new(&config, StartPose { x, y, z, yaw }).expect("snake builds");
    let body = snake.body();
    let n = s.joints;
    if !s.dynamics.is_empty() {
        let d = dynamics_from(&s.dynamics);
        for link in std::iter::once(None).chain((0..n).map(Some)) {
            snake
                .world_mut()
                .change_dynamics(body, link, &d)
                .expect("changeDynamics");
        }
    }
    let c = &s.control;
    let force = c.force.unwrap_or(10.0);
    let mut gait = LateralUndulation::default().with_steering(c.steering.unwrap_or(0.0));
    if c.mode == "torque" {
        for j in 0..n {
            let off = JointControl::Velocity {
                target_velocity: 0.0,
                max_force: 0.0,
                kd: 1.0,
            };
            snake.world_mut().set_joint_control(body, j, off).unwrap();
        }
    }
    let mut targets = vec![0.0; n];
    let mut rows = Vec::with_capacity(s.steps as usize);
    for step in 1..=s.steps {
        let k = step - 1;
        match c.mode.as_str() {
            "gait" => {
                gait.next_targets(&mut targets);
                snake
                    .world_mut()
                    .set_position_targets(body, &targets, force, 0.1, 1.0)
                    .unwrap();
            }
            "zero" => snake.set_targets(&vec![0.0; n]).unwrap(),
            mode => {
                for j in 0..n {
                    let control = match mode {
                        "position" => JointControl::Position {
                            target: signal(k, j, 0.5),
                            target_velocity: c.target_velocity.unwrap_or(0.0),
                            max_force: force,
                            kp: c.kp.expect("kp"),
                            kd: c.kd.expect("kd"),
                            max_velocity: c.max_velocity.filter(|v| *v > 0.0),
                        },
                        "velocity" => JointControl::Velocity {
                            target_velocity: signal(k, j, 3.0),
                            max_force: force,
                            kd: 1.0,
                        },
                        "torque" => JointControl::Torque(signal(k, j, force)),
                        other => panic!("unknown mode {other}"),
                    };
                    snake
                        .world_mut()
                        .set_joint_control(body, j, control)
                        .unwrap();
                }
            }
        }
        snake.step().expect("step");
        let base = snake.base_state().unwrap();
        let joints = snake.joint_states().unwrap();
        let q = base.pose.orientation.coords; // (x, y, z, w)
        let mut row = vec![step as f64, step as f64 * DT];
        row.extend(base.pose.position.iter());
        row.extend([q.x, q.y, q.z, q.w]);
        row.extend(joints.iter().map(|j| j.position));
        row.extend(base.linear_velocity.iter());
        row.extend(base.angular_velocity.iter());
        row.extend(joints.iter().map(|j| j.velocity));
        row.extend(joints.iter().map(|j| j.motor_torque));
        rows.push(row);
    }
    rows
}

/// Root of the repository (where `.venv/` lives).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ has a parent")
        .to_path_buf()
}

/// The Python that has pybullet 3.2.7: `$SNAKESIM_PYTHON`, else `.venv/bin/python` at the root.
///
/// Without either, a parity test cannot run: it prints one line saying how to create the reference
/// environment and returns `None`, and the caller skips its checks. `scripts/test` (and CI) set
/// `SNAKESIM_PYTHON`, which makes a missing interpreter a failure there rather than a skip.
pub fn reference_python() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("SNAKESIM_PYTHON") {
        let p = PathBuf::from(p);
        assert!(
            p.exists(),
            "SNAKESIM_PYTHON is {}, which does not exist",
            p.display()
        );
        return Some(p);
    }
    let venv = repo_root().join(".venv/bin/python");
    if venv.exists() {
        return Some(venv);
    }
    let test = std::thread::current()
        .name()
        .unwrap_or("parity test")
        .to_owned();
    // Straight to the process's stderr: libtest captures `eprintln!` of passing tests, and this note is
    // the only sign that parity was not checked.
    let _ = writeln!(
        std::io::stderr(),
        "{test}: skipped, parity with pybullet 3.2.7 not checked: no reference environment \
         ({}); create it with `bash scripts/setup`, then `bash scripts/test` (which adds pybullet \
         to .venv), or set SNAKESIM_PYTHON to a Python with pybullet==3.2.7",
        venv.display()
    );
    None
}

/// A CSV of the reference: header and rows of floats.
pub struct Table {
    /// Column names.
    pub header: Vec<String>,
    /// Rows, parsed as f64.
    pub rows: Vec<Vec<f64>>,
}

/// Reads a CSV whose cells are all numbers.
pub fn read_csv(path: &Path) -> Table {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header = lines
        .next()
        .expect("header")
        .split(',')
        .map(str::to_owned)
        .collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|c| c.parse::<f64>().unwrap_or_else(|e| panic!("{c}: {e}")))
                .collect()
        })
        .collect();
    Table { header, rows }
}

/// Runs `tests/reference/<script>` with the JSON of `spec` and a fresh output directory as its two
/// arguments; returns that directory (the caller reads and removes it), or `None` without a
/// reference environment (see [`reference_python`]). Panics with the script's stderr if it fails.
pub fn run_reference_script(script: &str, spec: &impl Serialize, tag: &str) -> Option<PathBuf> {
    let python = reference_python()?;
    let dir = std::env::temp_dir().join(format!("snakesim-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let spec_path = dir.join("spec.json");
    std::fs::write(&spec_path, serde_json::to_string(spec).unwrap()).unwrap();
    let out = Command::new(python)
        .arg(repo_root().join("tests/reference").join(script))
        .arg(&spec_path)
        .arg(&dir)
        .output()
        .expect("the reference Python starts");
    assert!(
        out.status.success(),
        "{script} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    Some(dir)
}

/// Runs the scenarios through the pybullet reference; returns one table per scenario, in order, or
/// `None` without a reference environment (see [`reference_python`]).
pub fn run_reference(scenarios: &[Scenario], tag: &str) -> Option<Vec<Table>> {
    let python = reference_python()?;
    let dir = std::env::temp_dir().join(format!("snakesim-parity-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let spec = dir.join("scenarios.json");
    std::fs::write(&spec, serde_json::to_string(scenarios).unwrap()).unwrap();
    let script = repo_root().join("tests/reference/pybullet_reference.py");
    let out = Command::new(python)
        .arg(&script)
        .arg(&spec)
        .arg(&dir)
        .output()
        .expect("the reference Python starts");
    assert!(
        out.status.success(),
        "pybullet reference failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let tables = scenarios
        .iter()
        .map(|s| read_csv(&dir.join(format!("{}.csv", s.name))))
        .collect();
    std::fs::remove_dir_all(&dir).ok();
    Some(tables)
}

/// Compares two runs bit for bit; on the first difference, says where and by how much.
pub fn assert_identical(name: &str, header: &[String], reference: &[Vec<f64>], ours: &[Vec<f64>]) {
    assert_eq!(reference.len(), ours.len(), "{name}: row counts differ");
    for (r, (a, b)) in reference.iter().zip(ours).enumerate() {
        assert_eq!(a.len(), b.len(), "{name}: column counts differ at row {r}");
        for (c, (x, y)) in a.iter().zip(b).enumerate() {
            if x.to_bits() != y.to_bits() && !(*x == 0.0 && *y == 0.0) {
                panic!(
                    "{name}: first difference at step {} column {}: pybullet {x:?}, ours {y:?} (diff {:e})",
                    r + 1,
                    header[c],
                    (x - y).abs()
                );
            }
        }
    }
}
