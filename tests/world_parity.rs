//! World files (ground, friction, obstacles) in snake-core against pybullet 3.2.7, bit for bit.
//!
//! Each scenario writes a world file, builds it with [`WorldSpec`] under the paper's cube snake (10
//! joints, snake.py's wave) or a URDF robot (robots/yaw-pitch-16.yaml, a sine wave on every joint) and
//! runs 10 s. `reference/world_reference.py` reads the same world file and builds it with pybullet's own
//! calls (createCollisionShape + createMultiBody, changeDynamics); after every step the base pose and
//! velocity and every joint's angle, velocity and motor torque must have identical bits. The rough
//! ground and the pegs are generators of snakesim: pybullet gets their expansion (a CSV, a list of
//! obstacles), as a user would write it.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use snake_core::world_file::{Ground, ObstacleShape};
use snake_core::{
    Gait, LateralUndulation, Preset, Robot, RobotSpec, Simulation, Snake, StartPose, WorldSpec,
};
use snakesim_tests::{assert_identical, read_csv, repo_root, run_reference_script};

const TEN_SECONDS: usize = 2400;
const DT: f64 = 1.0 / 240.0;

#[derive(Debug, Clone, Serialize)]
struct WorldScenario {
    name: String,
    /// The world file pybullet reads (the expansion, for generated worlds).
    world: PathBuf,
    body: String,
    start: [f64; 4],
    #[serde(skip_serializing_if = "Option::is_none")]
    joints: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    preset: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    steps: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    urdf: Option<PathBuf>,
    #[serde(skip_serializing_if = "Option::is_none")]
    inertia: Option<String>,
    friction: Vec<(i32, [f64; 3])>,
    kp: f64,
    kd: f64,
    /// Each movable joint's `maxVelocity` (the robot file's servo limits), `None` where it has none;
    /// absent: no joint has one.
    #[serde(skip_serializing_if = "Option::is_none")]
    max_velocity: Option<Vec<Option<f64>>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    targets: Option<PathBuf>,
}

fn num(v: f64) -> String {
    let s = format!("{v:?}");
    assert!(
        !s.contains('e'),
        "{s}: PyYAML reads exponents without a dot as text"
    );
    s
}

/// The world as a pybullet user writes it: generators expanded into a CSV and obstacles.
fn expanded(spec: &WorldSpec, dir: &Path, stem: &str, original: &str) -> PathBuf {
    let mut yaml = String::new();
    match &spec.ground {
        Ground::Heightfield(h) => {
            let csv = format!("{stem}.expanded.csv");
            std::fs::write(dir.join(&csv), h.to_csv()).unwrap();
            let [sx, sy, sz] = h.scale;
            writeln!(
                yaml,
                "ground: {{heightfield: {{file: {csv}, scale: [{}, {}, {}]}}}}",
                num(sx),
                num(sy),
                num(sz)
            )
            .unwrap();
        }
        // Plane and slope: the original's ground line is what pybullet reads.
        _ => {
            for line in original.lines().filter(|l| l.starts_with("ground:")) {
                writeln!(yaml, "{line}").unwrap();
            }
        }
    }
    if let Some(mu) = spec.ground_friction {
        writeln!(yaml, "ground_friction: {}", num(mu)).unwrap();
    }
    yaml += if spec.obstacles.is_empty() {
        "obstacles: []\n"
    } else {
        "obstacles:\n"
    };
    for o in &spec.obstacles {
        let p = o.position;
        let mut line = match o.shape {
            ObstacleShape::Box(h) => format!(
                "  - {{shape: box, half_extents: [{}, {}, {}]",
                num(h[0]),
                num(h[1]),
                num(h[2])
            ),
            ObstacleShape::Cylinder { radius, height } => format!(
                "  - {{shape: cylinder, radius: {}, height: {}",
                num(radius),
                num(height)
            ),
            ObstacleShape::Sphere(r) => format!("  - {{shape: sphere, radius: {}", num(r)),
        };
        write!(
            line,
            ", position: [{}, {}, {}], yaw: {}",
            num(p[0]),
            num(p[1]),
            num(p[2]),
            num(o.yaw)
        )
        .unwrap();
        if let Some(mu) = o.lateral_friction {
            write!(line, ", lateral_friction: {}", num(mu)).unwrap();
        }
        yaml += &line;
        yaml += "}\n";
    }
    let path = dir.join(format!("{stem}.expanded.yaml"));
    std::fs::write(&path, yaml).unwrap();
    path
}

fn state_row(sim: &dyn Simulation, step: usize, m: usize) -> Vec<f64> {
    let (mut q, mut qd, mut tau) = (vec![0.0; m], vec![0.0; m], vec![0.0; m]);
    sim.read_joint_states(&mut q, &mut qd, &mut tau).unwrap();
    let base = sim.base_state().unwrap();
    let o = base.pose.orientation.coords;
    let mut out = vec![step as f64, step as f64 * DT];
    out.extend(base.pose.position.iter());
    out.extend([o.x, o.y, o.z, o.w]);
    out.extend(&q);
    out.extend(base.linear_velocity.iter());
    out.extend(base.angular_velocity.iter());
    out.extend(&qd);
    out.extend(&tau);
    out
}

fn run_cubes(world: &WorldSpec, s: &WorldScenario) -> Vec<Vec<f64>> {
    let n = s.joints.unwrap();
    let config = Preset::Paper.config(n);
    let [x, y, z, yaw] = s.start;
    let mut snake = Snake::in_world(&config, StartPose { x, y, z, yaw }, world).unwrap();
    let body = snake.body();
    let mut gait = LateralUndulation::default();
    let mut targets = vec![0.0; n];
    let mut touched_obstacle = false;
    let rows = (1..=s.steps.unwrap())
        .map(|step| {
            gait.next_targets(&mut targets);
            snake
                .world_mut()
                .set_position_targets(body, &targets, 10.0, 0.1, 1.0)
                .unwrap();
            snake.step().unwrap();
            touched_obstacle |= snake.world().contacts(body).unwrap().iter().any(|c| {
                c.other_body
                    .is_some_and(|b| (1..=world.obstacles.len()).contains(&b.index()))
            });
            state_row(&snake, step, n)
        })
        .collect();
    // Worlds with obstacles are placed so that the snake runs into them.
    assert!(
        world.obstacles.is_empty() || touched_obstacle,
        "{}: no obstacle touched",
        s.name
    );
    rows
}

fn run_robot(
    world: &WorldSpec,
    spec: &RobotSpec,
    s: &WorldScenario,
    targets: &[Vec<f64>],
) -> Vec<Vec<f64>> {
    let [x, y, z, yaw] = s.start;
    let mut robot = Robot::in_world(spec, StartPose { x, y, z, yaw }, world).unwrap();
    let m = robot.joints();
    let mut touched_obstacle = false;
    let rows = targets
        .iter()
        .enumerate()
        .map(|(k, row)| {
            robot.set_targets(row).unwrap();
            robot.step().unwrap();
            let body = robot.body();
            touched_obstacle |= robot.world().contacts(body).unwrap().iter().any(|c| {
                c.other_body
                    .is_some_and(|b| (1..=world.obstacles.len()).contains(&b.index()))
            });
            state_row(&robot, k + 1, m)
        })
        .collect();
    assert!(
        world.obstacles.is_empty() || touched_obstacle,
        "{}: no obstacle touched",
        s.name
    );
    rows
}

/// A random heightfield CSV of `rows` x `lines` heights in [0, top), written with 17 digits.
fn random_csv(rng: &mut ChaCha8Rng, rows: usize, lines: usize, top: f64) -> String {
    let mut text = String::new();
    for _ in 0..lines {
        let line: Vec<String> = (0..rows)
            .map(|_| format!("{:.17}", rng.gen_range(0.0..top)))
            .collect();
        text += &line.join(",");
        text.push('\n');
    }
    text
}

/// Worlds for the cube snake (10 joints, 0.5 m cubes, heading towards -y from the origin).
fn cube_worlds(dir: &Path) -> Vec<(&'static str, String)> {
    let mut rng = ChaCha8Rng::seed_from_u64(22);
    std::fs::write(dir.join("hills.csv"), random_csv(&mut rng, 31, 27, 0.4)).unwrap();
    vec![
        ("plane-friction", "ground: {plane: {}}\nground_friction: 0.3\n".into()),
        ("slope-up", "ground: {slope: {degrees: 10}}\nground_friction: 0.9\n".into()),
        ("slope-down", "ground: {slope: {degrees: -7.5}}\n".into()),
        (
            "heightfield",
            "ground: {heightfield: {file: hills.csv, scale: [0.4, 0.45, 1.5]}}\nground_friction: 0.7\n"
                .into(),
        ),
        (
            "rough",
            "ground: {rough: {amplitude: 0.15, wavelength: 2.0, seed: 5, size: [14, 14]}}\n".into(),
        ),
        (
            "obstacles",
            "obstacles:\n\
             \x20 - {shape: box, half_extents: [0.3, 0.2, 0.25], position: [0.6, -1.2, 0.25], yaw: 0.4}\n\
             \x20 - {shape: cylinder, radius: 0.15, height: 0.8, position: [-0.7, -0.9, 0.4], lateral_friction: 0.1}\n\
             \x20 - {shape: sphere, radius: 0.3, position: [0.1, -2.4, 0.2], yaw: -1.0, lateral_friction: 2.0}\n\
             \x20 - {shape: box, half_extents: [2.0, 0.1, 0.3], position: [0.0, 2.0, 0.3]}\n\
             ground_friction: 0.6\n"
                .into(),
        ),
        (
            "pegs-on-hills",
            "ground: {heightfield: {file: hills.csv, scale: [0.4, 0.45, 0.3]}}\n\
             obstacles:\n\
             \x20 - {shape: cylinder, radius: 0.1, height: 1.0, position: [0.5, -0.5, 0.5], yaw: 0.3}\n\
             pegs: {spacing: 0.9, radius: 0.08, height: 0.6, jitter: 0.2, seed: 3, area: [-3, -4, 3, 3], keep_clear: 0.8, lateral_friction: 0.4}\n"
                .into(),
        ),
    ]
}

/// Worlds for yaw-pitch-16 (16 modules of 0.0254 m radius, about 1 m long).
fn robot_worlds(dir: &Path) -> Vec<(&'static str, String)> {
    let mut rng = ChaCha8Rng::seed_from_u64(16);
    std::fs::write(dir.join("bumps.csv"), random_csv(&mut rng, 40, 36, 0.03)).unwrap();
    vec![
        ("slope", "ground: {slope: {degrees: 10}}\nground_friction: 0.8\n".into()),
        (
            "heightfield",
            "ground: {heightfield: {file: bumps.csv, scale: [0.05, 0.06, 1.0]}}\n".into(),
        ),
        (
            "obstacles",
            "ground_friction: 1.2\nobstacles:\n\
             \x20 - {shape: box, half_extents: [0.05, 0.04, 0.05], position: [0.1, 0.3, 0.05], yaw: 0.7}\n\
             \x20 - {shape: cylinder, radius: 0.03, height: 0.1, position: [-0.08, 0.5, 0.05], lateral_friction: 0.2}\n\
             \x20 - {shape: sphere, radius: 0.04, position: [0.06, 0.75, 0.02], lateral_friction: 0.9}\n\
             pegs: {spacing: 0.15, radius: 0.012, height: 0.1, jitter: 0.04, seed: 9, area: [-0.3, -0.3, 0.3, 1.2], keep_clear: 0.0}\n"
                .into(),
        ),
    ]
}

fn robot_targets(m: usize) -> Vec<Vec<f64>> {
    (0..TEN_SECONDS)
        .map(|k| {
            let t = k as f64 * DT;
            (0..m)
                .map(|j| 0.7 * (2.0 * std::f64::consts::PI * 0.6 * t - 0.9 * j as f64).sin())
                .collect()
        })
        .collect()
}

fn write_targets(path: &Path, rows: &[Vec<f64>]) {
    let mut text = String::new();
    for row in rows {
        let cells: Vec<String> = row.iter().map(|v| format!("{v:?}")).collect();
        text += &cells.join(",");
        text.push('\n');
    }
    std::fs::write(path, text).unwrap();
}

#[test]
fn cube_snake_on_every_kind_of_world() {
    let dir = std::env::temp_dir().join(format!("snakesim-worlds-cubes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let config = Preset::Paper.config(10);
    let mut runs = Vec::new();
    for (stem, text) in cube_worlds(&dir) {
        let path = dir.join(format!("{stem}.yaml"));
        std::fs::write(&path, &text).unwrap();
        let spec = WorldSpec::load(&path).unwrap_or_else(|e| panic!("{stem}: {e}"));
        let lift = spec.ground_top(6.0);
        let scenario = WorldScenario {
            name: format!("cubes-{stem}"),
            world: expanded(&spec, &dir, stem, &text),
            body: "cubes".into(),
            start: [0.0, 0.0, config.half_extent + lift + 0.02, 0.0],
            joints: Some(10),
            preset: Some("paper".into()),
            steps: Some(TEN_SECONDS),
            urdf: None,
            inertia: None,
            friction: Vec::new(),
            kp: 0.1,
            kd: 1.0,
            max_velocity: None,
            targets: None,
        };
        runs.push((scenario, spec));
    }
    let scenarios: Vec<_> = runs.iter().map(|(s, _)| s.clone()).collect();
    let Some(out) = run_reference_script("world_reference.py", &scenarios, "worlds-cubes") else {
        return;
    };
    let flat = run_cubes(&WorldSpec::default(), &runs[0].0);
    for (s, spec) in &runs {
        let table = read_csv(&out.join(format!("{}.csv", s.name)));
        let ours = run_cubes(spec, s);
        // Each world must change the run, or it compared nothing but the plane.
        assert_ne!(
            ours.last(),
            flat.last(),
            "{}: the world changed nothing",
            s.name
        );
        assert!(ours.iter().flatten().all(|v| v.is_finite()), "{}", s.name);
        assert_identical(&s.name, &table.header, &table.rows, &ours);
    }
    std::fs::remove_dir_all(&out).ok();
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn urdf_robot_on_every_kind_of_world() {
    let dir = std::env::temp_dir().join(format!("snakesim-worlds-urdf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let robot_file = repo_root().join("robots/yaw-pitch-16.yaml");
    let robot = RobotSpec::load(&robot_file).unwrap();
    let friction: Vec<(i32, [f64; 3])> = robot
        .anisotropic_friction
        .iter()
        .enumerate()
        .filter_map(|(k, a)| a.map(|a| (k as i32 - 1, a)))
        .collect();
    let m = robot.urdf.movable_joints().len();
    let targets = robot_targets(m);
    let target_path = dir.join("targets.csv");
    write_targets(&target_path, &targets);
    let mut runs = Vec::new();
    for (stem, text) in robot_worlds(&dir) {
        let path = dir.join(format!("{stem}.yaml"));
        std::fs::write(&path, &text).unwrap();
        let spec = WorldSpec::load(&path).unwrap_or_else(|e| panic!("{stem}: {e}"));
        let start = robot.default_start();
        let scenario = WorldScenario {
            name: format!("urdf-{stem}"),
            world: expanded(&spec, &dir, stem, &text),
            body: "urdf".into(),
            start: [start.x, start.y, start.z + spec.ground_top(1.2) + 0.01, 0.3],
            joints: None,
            preset: None,
            steps: None,
            urdf: robot.urdf.source.clone(),
            inertia: Some(robot.inertia.to_string()),
            friction: friction.clone(),
            kp: robot.motors.kp,
            kd: robot.motors.kd,
            max_velocity: Some((0..m).map(|k| robot.max_velocity(k)).collect()),
            targets: Some(target_path.clone()),
        };
        runs.push((scenario, spec));
    }
    let scenarios: Vec<_> = runs.iter().map(|(s, _)| s.clone()).collect();
    let Some(out) = run_reference_script("world_reference.py", &scenarios, "worlds-urdf") else {
        return;
    };
    let flat = run_robot(&WorldSpec::default(), &robot, &runs[0].0, &targets);
    for (s, spec) in &runs {
        let table = read_csv(&out.join(format!("{}.csv", s.name)));
        let ours = run_robot(spec, &robot, s, &targets);
        assert_ne!(
            ours.last(),
            flat.last(),
            "{}: the world changed nothing",
            s.name
        );
        assert!(ours.iter().flatten().all(|v| v.is_finite()), "{}", s.name);
        assert_identical(&s.name, &table.header, &table.rows, &ours);
    }
    std::fs::remove_dir_all(&out).ok();
    std::fs::remove_dir_all(&dir).ok();
}
