//! What every parser of a user's file must do with any input: give a value or a one-line error, never
//! a panic (or an abort, or a hang). One function per fuzz target, called by the target
//! (fuzz/fuzz_targets/) and by the regression test that replays fuzz/regressions/ and mutates real
//! files (tests/parsers.rs includes this file), so both check the same thing.

use std::path::Path;

use serde_json::Value;
use snake_core::robot::{Robot, RobotSpec, Simulation};
use snake_core::run_targets::{run_targets, Overrides};
use snake_core::urdf::{InertiaSource, UrdfRobot};
use snake_core::world_file::{parse_heightfield_csv, Ground};
use snake_core::{StartPose, WorldSpec};
use snake_rl::config::{env_from_keywords, parse_yaml, RunConfig};
use snake_rl::model::{parse_checkpoint, parse_policy};

fn one_line(message: &str) {
    assert!(
        !message.contains('\n'),
        "an error message of several lines: {message}"
    );
    // Numbers in errors are short (1e300, not Rust's 301 digits), so no line is cut inside one.
    let longest_digits = message
        .split(|c: char| !c.is_ascii_digit())
        .map(str::len)
        .max()
        .unwrap_or(0);
    assert!(
        longest_digits <= 40,
        "an error message with a number of {longest_digits} digits: {message}"
    );
}

/// A model or checkpoint file (safetensors: header, metadata, tensors), as `snakesim evaluate` and
/// `--resume` read it.
pub fn model_file(bytes: &[u8]) {
    let path = Path::new("fuzzed.safetensors");
    if let Err(e) = parse_policy(path, bytes) {
        one_line(&e.0);
    }
    if let Err(e) = parse_checkpoint(path, bytes) {
        one_line(&e.0);
    }
}

/// A run configuration (YAML: `--config FILE.yaml`, a run's config.yaml); a valid one survives saving
/// and reloading unchanged.
pub fn run_config(bytes: &[u8]) {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    match parse_yaml(text).and_then(|layer| RunConfig::from_layers(&[layer])) {
        Ok(config) => {
            if config.validate().is_ok() {
                let again =
                    RunConfig::from_yaml(&config.to_yaml()).expect("a saved config reloads");
                assert_eq!(again, config);
            }
        }
        Err(e) => one_line(&e.0),
    }
}

/// The env's keywords (JSON: `snakesim.SnakeEnv(**kwargs)`, a model's `env` metadata); a config that
/// parses is made into an env and reset once, where its terrain is drawn and allocated (a rough
/// ground's noise lattice, its grid, pegs): an env or a one-line error, never a panic or an abort.
pub fn env_keywords(bytes: &[u8]) {
    let Ok(Value::Object(keywords)) = serde_json::from_slice::<Value>(bytes) else {
        return;
    };
    match env_from_keywords(&keywords) {
        Ok(config) => {
            // Small snakes only: a reset of many joints is slow, not wrong.
            if config.snake.joints > 16 {
                return;
            }
            let reset = snake_core::SnakeEnv::new(config)
                .and_then(|mut env| env.reset(Some(1), Default::default()));
            if let Err(e) = reset {
                one_line(&e.to_string());
            }
        }
        Err(e) => one_line(&e.0),
    }
}

/// A joint-targets table (`snake-cli run --targets FILE.csv`) for a robot of three movable joints
/// `j0, j1, j2`: rows of finite targets, or a one-line error.
pub fn targets_csv(bytes: &[u8]) {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    match crate::targets::TargetTable::parse(text, "fuzzed.csv", &["j0", "j1", "j2"]) {
        Ok(table) => assert!(table
            .rows
            .iter()
            .all(|r| r.len() == 3 && r.iter().all(|v| v.is_finite()))),
        Err(e) => one_line(&format!("{e:#}")),
    }
}

/// `snakesim calibrate`'s physics overrides (JSON of `--fit` keys: `_core.simulate_robot`'s
/// `overrides_json`) on the shipped paper-cubes-5 robot driven by 8 rows of targets: a trajectory of
/// 8 finite rows, or a one-line error (an unknown key, a value out of its range, one the engine
/// refuses), never a panic or an abort.
pub fn fit_overrides(bytes: &[u8]) {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    let overrides = match Overrides::from_json(text) {
        Ok(o) => o,
        Err(e) => return one_line(&e.to_string()),
    };
    if let Err(e) = overrides.validate() {
        one_line(&e.to_string());
    }
    let urdf = include_bytes!("../../robots/paper-cubes-5.urdf");
    with_file("paper-cubes-5.urdf", urdf, |path| {
        let spec = RobotSpec::load(path).expect("the shipped robot loads");
        let joints = spec.urdf.movable_joints().len();
        let targets: Vec<f64> = (0..8 * joints)
            .map(|i| 0.3 * ((i % 5) as f64 - 2.0))
            .collect();
        let start = StartPose {
            z: 0.3,
            ..StartPose::resting(0.25)
        };
        match run_targets(&spec, start, &WorldSpec::default(), &overrides, &targets) {
            Ok(trajectory) => {
                assert_eq!(
                    (trajectory.base.len(), trajectory.joints.len()),
                    (8, 8 * joints)
                );
                assert!(trajectory.base.iter().flatten().all(|v| v.is_finite()));
                assert!(trajectory.joints.iter().all(|v| v.is_finite()));
            }
            Err(e) => one_line(&e.to_string()),
        }
    });
}

/// A robot that parsed and passed its checks is built in Bullet and stepped: a file that makes the
/// engine abort, or turn the state non-finite silently, is the worst a crafted robot could do.
fn build_and_step(spec: &RobotSpec) {
    let start = StartPose {
        z: 1.0,
        ..StartPose::resting(0.25)
    };
    let Ok(mut robot) = Robot::new(spec, start) else {
        return;
    };
    let targets = vec![0.3; robot.joints()];
    for _ in 0..8 {
        if robot
            .set_targets(&targets)
            .and_then(|()| robot.step())
            .is_err()
        {
            return;
        }
    }
}

/// A URDF file (`snake-cli run --robot x.urdf`, a robot file's `urdf:`): parsed, its inertias checked
/// both ways pybullet reads them, and built when they pass.
pub fn urdf(bytes: &[u8]) {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    match UrdfRobot::parse(text, "fuzzed.urdf") {
        Ok(robot) => {
            for source in [InertiaSource::Shapes, InertiaSource::File] {
                if let Err(e) = robot.check_inertia(source) {
                    one_line(&e.to_string());
                }
            }
            if robot.check_inertia(InertiaSource::Shapes).is_ok() {
                with_file("fuzzed.urdf", bytes, |path| match RobotSpec::load(path) {
                    Ok(spec) => build_and_step(&spec),
                    Err(e) => one_line(&e.to_string()),
                });
            }
        }
        Err(e) => one_line(&e.to_string()),
    }
}

/// A robot file (YAML around a URDF: motors, friction, start, gait), next to the shipped paper-cubes-5
/// URDF that it may name.
pub fn robot_file(bytes: &[u8]) {
    let urdf = include_bytes!("../../robots/paper-cubes-5.urdf");
    with_file("paper-cubes-5.urdf", urdf, |_| {
        with_file("fuzzed.yaml", bytes, |path| match RobotSpec::load(path) {
            Ok(spec) => {
                if spec.urdf.check_inertia(spec.inertia).is_ok() {
                    build_and_step(&spec);
                }
            }
            Err(e) => one_line(&e.to_string()),
        })
    });
}

/// A world file (`snake-cli run --world`, the env's `world`) next to a small heightfield `hills.csv`
/// that it may name, and the same bytes as a heightfield CSV: a world or grid, or a one-line error;
/// a small world that loads is built under a 2-joint snake and stepped.
pub fn world_file(bytes: &[u8]) {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    match parse_heightfield_csv(text, "fuzzed.csv") {
        Ok((rows, columns, heights)) => {
            assert!(rows >= 2 && columns >= 2 && heights.len() == rows * columns);
            assert!(heights.iter().all(|h| h.is_finite()));
        }
        Err(e) => one_line(&e.to_string()),
    }
    with_file("hills.csv", b"0,0.1,0\n0.2,0,0.1\n", |_| {
        with_file("fuzzed.yaml", bytes, |path| match WorldSpec::load(path) {
            Ok(world) => {
                // Building 10,000 pegs or 2 million samples is allowed but slow: fuzz small worlds.
                let samples = match &world.ground {
                    Ground::Heightfield(h) => h.heights.len(),
                    _ => 0,
                };
                if world.obstacles.len() <= 64 && samples <= 1 << 14 {
                    let config = snake_core::Preset::Paper.config(2);
                    let start = StartPose {
                        z: 1.0,
                        ..StartPose::resting(0.25)
                    };
                    if let Ok(mut snake) = snake_core::Snake::in_world(&config, start, &world) {
                        for _ in 0..8 {
                            if snake
                                .set_targets(&[0.3, -0.3])
                                .and_then(|()| snake.step())
                                .is_err()
                            {
                                return;
                            }
                        }
                    }
                }
            }
            Err(e) => one_line(&e.to_string()),
        })
    });
}

/// Calls `f` with the path of a file named `name`, holding `bytes`, in this thread's own scratch
/// folder (robot and world files name their URDF or CSV relative to themselves). Per thread, not per
/// process: the test harness runs the checks on several threads at once, and one thread's clean-up
/// must not remove the folder under another's file.
fn with_file(name: &str, bytes: &[u8], f: impl FnOnce(&Path)) {
    let thread = format!("{:?}", std::thread::current().id());
    let thread: String = thread.chars().filter(char::is_ascii_digit).collect();
    let folder =
        std::env::temp_dir().join(format!("snakesim-fuzz-{}-{thread}", std::process::id()));
    std::fs::create_dir_all(&folder).expect("a scratch folder");
    let path = folder.join(name);
    std::fs::write(&path, bytes).expect("a scratch file");
    f(&path);
    // Nothing left behind: the file, then the folder once the outermost call's file is gone too.
    let _ = std::fs::remove_file(&path);
    let _ = std::fs::remove_dir(&folder);
}
