//! Water in robot files and worlds (issue 60): a robot file's `water` keys reach each link (a link's
//! over the robot's, the robot's over the water's), bad values are one line naming the file and key,
//! and a robot floats where Archimedes puts it.

use std::path::PathBuf;

use snake_core::media::water::CoefficientsFile;
use snake_core::{Robot, RobotSpec, Simulation, StartPose, WorldRef};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn robot_file(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("snakesim-water-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let urdf = repo().join("robots/mamba-10.urdf");
    std::fs::copy(&urdf, dir.join("mamba-10.urdf")).unwrap();
    let path = dir.join("robot.yaml");
    std::fs::write(&path, format!("urdf: mamba-10.urdf\n{text}")).unwrap();
    path
}

#[test]
fn a_links_water_keys_go_over_the_robots() {
    let path = robot_file(
        "keys",
        "water: {drag: 1.5, linear: 0.5}\nlinks:\n  link9: {water: {drag: 3.0, added_mass: 0.5}}\n",
    );
    let spec = RobotSpec::load(&path).unwrap();
    let robot = CoefficientsFile {
        drag: Some(1.5),
        linear: Some(0.5),
        ..Default::default()
    };
    assert_eq!(spec.water[0], Some(robot));
    assert_eq!(
        spec.water[9],
        Some(CoefficientsFile {
            drag: Some(3.0),
            added_mass: Some(0.5),
            linear: Some(0.5),
            ..Default::default()
        })
    );
}

#[test]
fn bad_water_keys_are_one_line_naming_file_and_key() {
    let path = robot_file("negative", "links:\n  link3: {water: {drag: -1}}\n");
    let e = RobotSpec::load(&path).unwrap_err().to_string();
    assert!(e.contains("robot.yaml: links: link3: water: drag"), "{e}");
    assert!(!e.contains('\n'), "{e}");
    let path = robot_file("unknown", "water: {cd: 1}\n");
    let e = RobotSpec::load(&path).unwrap_err().to_string();
    assert!(e.contains("robot.yaml") && e.contains("cd"), "{e}");
    let path = robot_file("nan", "water: {added_mass: .nan}\n");
    let e = RobotSpec::load(&path).unwrap_err().to_string();
    assert!(e.contains("water") && e.contains("added_mass"), "{e}");
}

/// mamba-10 held straight floats with its links' weight equal to the water they displace: 1 kg per
/// link of 998.2 kg/m^3 water is 1.00180 litres of the 1.14511 a link has, 87.49 %: a horizontal
/// cylinder that deep (the circular segment) has its axis 2.85 cm under the surface.
#[test]
fn mamba_floats_at_the_draft_archimedes_gives() {
    let spec = RobotSpec::load(&repo().join("robots/mamba-10.yaml")).unwrap();
    let pool = WorldRef::load(&repo().join("worlds/pool.yaml")).unwrap();
    let start = StartPose {
        z: 0.98,
        ..spec.default_start()
    };
    let mut robot = Robot::in_world(&spec, start, pool.spec()).unwrap();
    robot.set_targets(&[0.0; 9]).unwrap();
    for _ in 0..2400 {
        robot.step().unwrap();
    }
    let z = robot.base_state().unwrap().pose.position.z;
    // The submerged fraction f of a circle whose centre lies d under the surface: solve for d.
    let (r, f) = (
        0.045f64,
        1.0 / (998.2 * std::f64::consts::PI * 0.045 * 0.045 * 0.18),
    );
    let segment = |d: f64| {
        let h = (r + d) / (2.0 * r);
        let theta = 2.0 * (1.0 - 2.0 * h).acos();
        (theta - theta.sin()) / std::f64::consts::TAU
    };
    let (mut lo, mut hi) = (-r, r);
    for _ in 0..60 {
        let mid = (lo + hi) / 2.0;
        if segment(mid) < f {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let depth = 1.0 - z;
    assert!(
        (depth - lo).abs() < 1e-4,
        "axis {depth} m under, Archimedes {lo} m"
    );
}

/// Mean head speed of mamba-10 swimming lateral undulation (alpha 30 deg, omega 70 deg/s, delta 40
/// deg) over the four whole cycles after 5 s, in `pool`.
fn swim_speed(pool: &snake_core::WorldSpec) -> f64 {
    use snake_core::gait::{JointRoles, Swim, SwimParams, SwimPattern};
    let spec = RobotSpec::load(&repo().join("robots/mamba-10.yaml")).unwrap();
    let swim = Swim::new(
        SwimPattern::Lateral,
        SwimParams {
            alpha: 30f64.to_radians(),
            omega: 70f64.to_radians(),
            delta: 40f64.to_radians(),
            offset: 0.0,
            ramp: 2.0,
        },
        &JointRoles::of_urdf(&spec.urdf),
    )
    .unwrap();
    let mut robot = Robot::in_world(&spec, spec.default_start(), pool).unwrap();
    let period = std::f64::consts::TAU / 70f64.to_radians();
    let (settle, window) = (
        (5.0 / robot.dt()).round() as usize,
        (4.0 * period / robot.dt()).round() as usize,
    );
    let mut q = [0.0; 9];
    let mut start = None;
    for s in 0..settle + window {
        swim.targets_at(robot.time() + robot.dt(), &mut q);
        robot.set_targets(&q).unwrap();
        robot.step().unwrap();
        if s + 1 == settle {
            start = Some(robot.base_state().unwrap().pose.position);
        }
    }
    let end = robot.base_state().unwrap().pose.position;
    (end - start.unwrap()).xy().norm() / (window as f64 * robot.dt())
}

/// The added mass's relaxation (docs/media.md) does not change the steady swimming speed: half the
/// dead-beat gain, or 1.5 times it, moves the speed by under 0.5 %.
#[test]
fn swimming_speed_does_not_depend_on_the_added_mass_relaxation() {
    let pool = WorldRef::load(&repo().join("worlds/pool.yaml")).unwrap();
    let with = |relaxation: f64| {
        let mut spec = pool.spec().clone();
        for m in &mut spec.media {
            if let snake_core::media::Medium::Water(w) = m {
                w.relaxation = relaxation;
            }
        }
        swim_speed(&spec)
    };
    let base = with(1.0);
    for r in [0.5, 1.5] {
        let v = with(r);
        assert!(
            (v - base).abs() < 0.005 * base,
            "relaxation {r}: {v} m/s against {base} m/s"
        );
    }
}

/// `--gait swim` and `--gait eel` (GaitChoice) swim mamba-10 head first (-y, where its head points)
/// in the pool, as the gait library's gaits do on the ground.
#[test]
fn the_swimming_gaits_swim_head_first() {
    use snake_core::gait::{Gait, GaitChoice, GaitKind, JointRoles, LateralUndulation};
    let spec = RobotSpec::load(&repo().join("robots/mamba-10.yaml")).unwrap();
    let pool = WorldRef::load(&repo().join("worlds/pool.yaml")).unwrap();
    for kind in GaitKind::SWIMMING {
        let choice = GaitChoice::new(
            kind,
            &[],
            0.0,
            &JointRoles::of_urdf(&spec.urdf),
            LateralUndulation::default(),
            1.0 / 240.0,
        )
        .unwrap();
        let GaitChoice::Swim(mut gait) = choice else {
            panic!("{kind} is a swimming gait");
        };
        let mut robot = Robot::in_world(&spec, spec.default_start(), pool.spec()).unwrap();
        let mut q = [0.0; 9];
        for _ in 0..240 * 15 {
            gait.next_targets(&mut q);
            robot.set_targets(&q).unwrap();
            robot.step().unwrap();
        }
        let p = robot.base_state().unwrap().pose.position;
        assert!(p.y < -1.0 && p.x.abs() < 0.5, "{kind}: head at {p:?}");
    }
}

/// `snakesim calibrate --fit water.KEY=...` (run_targets::Overrides): the fitted coefficient reaches
/// every link, over the robot file's and each link's own, in the simulation and in the fitted robot
/// file alike; a bad value is named.
#[test]
fn water_fit_keys_set_every_links_coefficient() {
    use snake_core::run_targets::Overrides;
    let path = robot_file(
        "fit",
        "water: {drag: 1.5, linear: 0.5}\nlinks:\n  link9: {water: {drag: 3.0, added_mass: 0.5}}\n",
    );
    let overrides =
        Overrides::from_json(r#"{"water.drag": 2.5, "water.skin_friction": 0.1}"#).unwrap();
    let mut spec = RobotSpec::load(&path).unwrap();
    let mut plane = snake_core::WorldSpec::default();
    let e = overrides
        .apply_to_spec(&mut spec.clone(), &mut plane)
        .unwrap_err()
        .to_string();
    assert!(e.contains("water.") && e.contains("no water"), "{e}");
    let mut world = WorldRef::load(&repo().join("worlds/pool.yaml"))
        .unwrap()
        .spec()
        .clone();
    overrides.apply_to_spec(&mut spec, &mut world).unwrap();
    for (k, w) in spec.water.iter().enumerate() {
        let w = w.expect("every link");
        assert_eq!(
            (w.drag, w.skin_friction),
            (Some(2.5), Some(0.1)),
            "link {k}"
        );
        assert_eq!(w.linear, Some(0.5));
    }
    assert_eq!(spec.water[9].unwrap().added_mass, Some(0.5));
    let text = std::fs::read_to_string(&path).unwrap();
    let mut file: snake_core::RobotFile = serde_norway::from_str(&text).unwrap();
    overrides.apply_to_file(&mut file).unwrap();
    assert_eq!(file.water.unwrap().drag, Some(2.5));
    assert_eq!(file.links["link9"].water.unwrap().drag, Some(2.5));
    assert_eq!(file.links["link9"].water.unwrap().added_mass, Some(0.5));
    let bad = Overrides::from_json(r#"{"water.added_mass": -1}"#).unwrap();
    let e = bad.validate().unwrap_err().to_string();
    assert!(e.contains("water.added_mass"), "{e}");
}

/// Buoyancy works against the world's gravity, not a constant: a chain of cubes under Mars's gravity
/// (3.71 m/s^2) floats at Archimedes' draft `m / (rho A)`, which does not depend on gravity (weight and
/// lift scale together). With Earth's gravity in the buoyancy alone it would float 2.64 times higher.
#[test]
fn buoyancy_works_against_the_worlds_gravity() {
    use snake_core::{Snake, SnakeConfig};
    let pool = WorldRef::load(&repo().join("worlds/pool.yaml")).unwrap();
    let (h, mass, rho) = (0.05, 0.5, 998.2);
    let config = SnakeConfig {
        joints: 2,
        half_extent: h,
        base_mass: mass,
        link_mass: mass,
        gravity: -3.71,
        ..SnakeConfig::default()
    };
    let start = StartPose {
        x: 0.0,
        y: 0.0,
        z: 1.0,
        yaw: 0.0,
    };
    let mut snake = Snake::in_world(&config, start, pool.spec()).unwrap();
    snake.set_targets(&[0.0; 2]).unwrap();
    for _ in 0..240 * 20 {
        snake.step().unwrap();
    }
    let z = snake.base_state().unwrap().pose.position.z;
    let draft = 1.0 - (z - h);
    let archimedes = mass / (rho * (2.0 * h) * (2.0 * h));
    assert!(
        (draft - archimedes).abs() < 0.01 * archimedes,
        "draft {draft} m, Archimedes {archimedes} m"
    );
}

/// In a world with water, a link without volume (no collision shape) is refused in one line naming
/// the robot file and the link.
#[test]
fn a_link_without_volume_in_water_names_the_file_and_link() {
    let path = robot_file("hollow", "inertia: file\n");
    let urdf = path.with_file_name("mamba-10.urdf");
    let text = std::fs::read_to_string(&urdf).unwrap();
    let start = text.find("<link name=\"link4\">").unwrap();
    let collision = start + text[start..].find("<collision>").unwrap();
    let end = collision + text[collision..].find("</collision>").unwrap() + "</collision>".len();
    std::fs::write(&urdf, format!("{}{}", &text[..collision], &text[end..])).unwrap();
    let spec = RobotSpec::load(&path).unwrap();
    let pool = WorldRef::load(&repo().join("worlds/pool.yaml")).unwrap();
    let e = Robot::in_world(&spec, spec.default_start(), pool.spec())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("robot.yaml: links: link4: has no volume") && !e.contains('\n'),
        "{e}"
    );
    // Out of water the same robot is fine.
    Robot::in_world(
        &spec,
        spec.default_start(),
        &snake_core::WorldSpec::default(),
    )
    .unwrap();
}

fn swim_env(extra: serde_json::Value) -> snake_core::Result<snake_core::EnvConfig> {
    let mut keywords = serde_json::json!({
        "task": "swim",
        "robot": repo().join("robots/mamba-10.yaml"),
    });
    if let (Some(k), serde_json::Value::Object(extra)) = (keywords.as_object_mut(), extra) {
        k.extend(extra);
    }
    snake_core::env_from_keywords(keywords.as_object().unwrap())
}

/// The swimming task (`task: swim`): its built-in pool is `worlds/pool.yaml`'s water; mamba-10
/// steered straight on swims across it, its head at the surface; a world without water is refused.
#[test]
fn the_swim_task_swims_in_its_pool_and_needs_water() {
    use snake_core::{ResetOptions, SnakeEnv};
    let config = swim_env(serde_json::json!({})).unwrap();
    let pool = WorldRef::load(&repo().join("worlds/pool.yaml")).unwrap();
    assert_eq!(config.world.as_ref().unwrap().spec(), pool.spec());
    assert_eq!(config.goal_distribution.unwrap().distance, [3.0, 6.0]);
    let mut env = SnakeEnv::new(config).unwrap();
    let (_, info) = env.reset(Some(3), ResetOptions::default()).unwrap();
    let start = info.start;
    let mut last = None;
    for _ in 0..150 {
        last = Some(env.step(&[0.0f32, 0.0, 0.0]).unwrap());
    }
    let head = env
        .body()
        .unwrap()
        .sim()
        .base_state()
        .unwrap()
        .pose
        .position;
    let moved = (head.x - start.x).hypot(head.y - start.y);
    assert!(moved > 1.0, "5 s of swimming moved the head {moved} m");
    assert!((head.z - 1.0).abs() < 0.1, "the head at z {head:?}");
    assert!(!last.unwrap().terminated || moved > 1.0);

    let dir = std::env::temp_dir().join(format!("snakesim-swim-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let dry = dir.join("dry.yaml");
    std::fs::write(&dry, "ground_friction: 0.5\n").unwrap();
    let e = swim_env(serde_json::json!({"world": dry}))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("world: task swim needs a world with water"),
        "{e}"
    );
}

/// `randomize: {current_speed, current_heading}` draws the water's current at each reset: mamba-10
/// held straight across it drifts at the drawn current's velocity (no drag at the current's
/// velocity, the law's eqs. 7-8), within 1 %; without water the key is refused, naming it. (Along its
/// axis it would drift at 93 % of it: pybullet's default damping of every link, 0.04, acts on the
/// absolute velocity, and along the axis the water's drag is weak; docs/media.md.)
#[test]
fn a_randomized_current_carries_a_passive_body() {
    use snake_core::{ResetOptions, SnakeEnv};
    // From +x towards -x: across the body, which lies along +y from the head.
    let heading = std::f64::consts::PI;
    let config = swim_env(serde_json::json!({
        "action": {"mode": "joints"},
        "start": {"yaw": [0.0, 0.0]},
        "goal_distribution": {"distance": [50.0, 50.0]},
        "randomize": {"current_speed": [0.3, 0.3], "current_heading": [heading, heading]},
    }))
    .unwrap();
    let mut env = SnakeEnv::new(config).unwrap();
    env.reset(Some(1), ResetOptions::default()).unwrap();
    let position = |env: &SnakeEnv| {
        env.body()
            .unwrap()
            .sim()
            .base_state()
            .unwrap()
            .pose
            .position
    };
    // 30 env steps a second (8 physics steps each): 20 s to settle, then 1 s measured.
    for _ in 0..30 * 20 {
        env.step(&[0.0f32; 9]).unwrap();
    }
    let a = position(&env);
    for _ in 0..30 {
        env.step(&[0.0f32; 9]).unwrap();
    }
    let v = (position(&env) - a) / 1.0;
    let expected = nalgebra::Vector3::new(0.3 * heading.cos(), 0.3 * heading.sin(), 0.0);
    assert!(
        (v.xy() - expected.xy()).norm() < 0.01 * 0.3,
        "drift {v:?}, current {expected:?}"
    );

    let e = snake_core::env_from_keywords(
        serde_json::json!({"task": "goal", "randomize": {"current_speed": [0.0, 0.1]}})
            .as_object()
            .unwrap(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("randomize.current_speed: needs a world with water"),
        "{e}"
    );
}

/// worlds/amphibious.yaml: mamba-10-amphibious started on the shore crawls off it with Kelasidi et
/// al.'s lateral undulation, ends wholly in the water, floating where Archimedes puts it (the surface
/// 0.25 m up, the axis 2.85 cm under it: `mamba_floats_at_the_draft_archimedes_gives`), and swims
/// there: at least 1 m in its last 10 s.
#[test]
fn a_robot_on_the_shore_crawls_into_the_water_and_swims() {
    use snake_core::gait::{Gait, GaitChoice, GaitKind, JointRoles, LateralUndulation};
    let spec = RobotSpec::load(&repo().join("robots/mamba-10-amphibious.yaml")).unwrap();
    let world = WorldRef::load(&repo().join("worlds/amphibious.yaml")).unwrap();
    let GaitChoice::Swim(mut gait) = GaitChoice::new(
        GaitKind::Swim,
        &[],
        0.0,
        &JointRoles::of_urdf(&spec.urdf),
        LateralUndulation::default(),
        1.0 / 240.0,
    )
    .unwrap() else {
        panic!("swim is a swimming gait");
    };
    let mut robot = Robot::in_world(&spec, spec.default_start(), world.spec()).unwrap();
    let mut q = [0.0; 9];
    let mut run = |robot: &mut Robot, seconds: usize| {
        for _ in 0..240 * seconds {
            gait.next_targets(&mut q);
            robot.set_targets(&q).unwrap();
            robot.step().unwrap();
        }
    };
    run(&mut robot, 30);
    let shore_edge = -0.5;
    let before = robot.base_state().unwrap().pose.position;
    run(&mut robot, 10);
    let after = robot.base_state().unwrap().pose.position;
    let links = robot.world().link_poses(robot.body()).unwrap();
    for (k, pose) in links.iter().enumerate() {
        assert!(
            pose.position.y < shore_edge,
            "link {} still over the shore at {:?}",
            k + 1,
            pose.position
        );
    }
    assert!(
        (after.z - (0.25 - 0.0285)).abs() < 1e-3,
        "the head floats at z {}",
        after.z
    );
    let swum = (after - before).xy().norm();
    assert!(swum > 1.0, "swam {swum} m in 10 s");
}
