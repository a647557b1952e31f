//! URDF robots in snake-core against pybullet 3.2.7's `loadURDF`, bit for bit.
//!
//! Robots are generated at random (tree shapes, link and joint order shuffled in the file, boxes,
//! spheres, cylinders and capsules with origins, inertial frames, masses, links without `<inertial>`,
//! revolute, continuous, prismatic and fixed joints about random axes with rpy origins, limits, damping,
//! `<contact>` tags, collision groups and masks, anisotropic friction on some links), dropped onto the
//! plane and driven by random
//! joint targets for 10 s. `reference/urdf_reference.py` runs each in pybullet; after every step the base
//! pose and velocity, every movable joint's angle, velocity and motor torque must have identical bits.
//! Robot files whose motors have a maximum velocity (`motors: max_velocity`, `joints:`) are pybullet's
//! `setJointMotorControl2(maxVelocity=...)` on every movable joint, bit for bit as well.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use snake_core::{InertiaSource, Robot, RobotSpec, Simulation, StartPose};
use snakesim_tests::{assert_identical, read_csv, run_reference_script};

const TEN_SECONDS: usize = 2400;

/// One run, as `urdf_reference.py` reads it.
#[derive(Debug, Clone, Serialize)]
struct UrdfScenario {
    name: String,
    urdf: PathBuf,
    start: [f64; 4],
    inertia: String,
    friction: Vec<(i32, [f64; 3])>,
    kp: f64,
    kd: f64,
    /// Each movable joint's `maxVelocity`, `None` where it has none; absent: no joint has one.
    #[serde(skip_serializing_if = "Option::is_none")]
    max_velocity: Option<Vec<Option<f64>>>,
    targets: PathBuf,
}

fn origin(rng: &mut ChaCha8Rng, reach: f64, rpy: bool) -> String {
    let mut s = format!(
        "<origin xyz=\"{:?} {:?} {:?}\"",
        rng.gen_range(-reach..reach),
        rng.gen_range(-reach..reach),
        rng.gen_range(-reach..reach)
    );
    if rpy {
        let pi = std::f64::consts::PI;
        write!(
            s,
            " rpy=\"{:?} {:?} {:?}\"",
            rng.gen_range(-pi..pi),
            rng.gen_range(-pi..pi),
            rng.gen_range(-pi..pi)
        )
        .unwrap();
    }
    s + "/>"
}

/// Kinds of joints, to steer the generator.
#[derive(Clone, Copy)]
enum Mix {
    Any,
    /// Fixed joints only below a moving root: the robot is one rigid body made of several links, some
    /// of them without a collision shape.
    AllFixed,
    /// A root of mass 0 (a fixed base, as an arm on a table) with any joints below it.
    FixedBase,
}

/// A random robot as URDF text, and the target ranges of its movable joints in joint order (which the
/// caller learns by loading it).
fn random_urdf(rng: &mut ChaCha8Rng, links: usize, mix: Mix) -> String {
    let mut link_xml = Vec::new();
    for k in 0..links {
        let mut s = format!("  <link name=\"l{k}\">\n");
        if rng.gen_bool(0.85) || k == 0 {
            let fixed_base = k == 0 && matches!(mix, Mix::FixedBase);
            let mass = if fixed_base {
                0.0
            } else {
                rng.gen_range(0.05..2.0)
            };
            let scale = rng.gen_range(0.001..0.02);
            let (a, b, c) = (
                scale * rng.gen_range(1.0..2.0),
                scale * rng.gen_range(1.0..2.0),
                scale * rng.gen_range(1.0..2.0),
            );
            let off = if rng.gen_bool(0.3) { 0.1 * scale } else { 0.0 };
            let rpy = rng.gen_bool(0.5);
            writeln!(
                s,
                "    <inertial>{}<mass value=\"{mass:?}\"/>\
                 <inertia ixx=\"{a:?}\" ixy=\"{:?}\" ixz=\"{:?}\" iyy=\"{b:?}\" iyz=\"{:?}\" izz=\"{c:?}\"/></inertial>",
                origin(rng, 0.05, rpy),
                off * rng.gen_range(-1.0..1.0),
                off * rng.gen_range(-1.0..1.0),
                off * rng.gen_range(-1.0..1.0),
            )
            .unwrap();
        }
        // A link of a rigid robot may have no shape (its mass and inertia still count).
        let least = usize::from(!(matches!(mix, Mix::AllFixed) && k > 0));
        for _ in 0..rng.gen_range(least..=3) {
            let geometry = match rng.gen_range(0..4) {
                0 => format!(
                    "<box size=\"{:?} {:?} {:?}\"/>",
                    rng.gen_range(0.03..0.2),
                    rng.gen_range(0.03..0.2),
                    rng.gen_range(0.03..0.2)
                ),
                1 => format!("<sphere radius=\"{:?}\"/>", rng.gen_range(0.02..0.1)),
                2 => format!(
                    "<cylinder radius=\"{:?}\" length=\"{:?}\"/>",
                    rng.gen_range(0.02..0.08),
                    rng.gen_range(0.05..0.3)
                ),
                _ => format!(
                    "<capsule radius=\"{:?}\" length=\"{:?}\"/>",
                    rng.gen_range(0.02..0.08),
                    rng.gen_range(0.05..0.3)
                ),
            };
            let o = if rng.gen_bool(0.2) {
                String::new()
            } else {
                let rpy = rng.gen_bool(0.5);
                origin(rng, 0.05, rpy)
            };
            // Now and then a collision filter: group 2 with mask 1 never meets the plane (static group
            // 2, mask -3), any other group does.
            let filter = match rng.gen_range(0..12) {
                0 => " group=\"2\" mask=\"1\"",
                1 => " group=\"5\" mask=\"-1\"",
                _ => "",
            };
            writeln!(
                s,
                "    <collision{filter}>{o}<geometry>{geometry}</geometry></collision>"
            )
            .unwrap();
        }
        if rng.gen_bool(0.5) {
            s += "    <contact>";
            write!(
                s,
                "<lateral_friction value=\"{:?}\"/>",
                rng.gen_range(0.2..2.0)
            )
            .unwrap();
            if rng.gen_bool(0.2) {
                write!(
                    s,
                    "<rolling_friction value=\"{:?}\"/>",
                    rng.gen_range(0.0..0.01)
                )
                .unwrap();
            }
            if rng.gen_bool(0.2) {
                write!(
                    s,
                    "<spinning_friction value=\"{:?}\"/>",
                    rng.gen_range(0.0..0.01)
                )
                .unwrap();
            }
            if rng.gen_bool(0.2) {
                write!(s, "<restitution value=\"{:?}\"/>", rng.gen_range(0.0..0.5)).unwrap();
            }
            if rng.gen_bool(0.2) {
                s += "<friction_anchor/>";
            }
            if rng.gen_bool(0.15) {
                write!(
                    s,
                    "<stiffness value=\"{:?}\"/><damping value=\"{:?}\"/>",
                    rng.gen_range(1e4..1e5),
                    rng.gen_range(10.0..100.0)
                )
                .unwrap();
            }
            if rng.gen_bool(0.1) {
                write!(
                    s,
                    "<inertia_scaling value=\"{:?}\"/>",
                    rng.gen_range(0.5..2.0)
                )
                .unwrap();
            }
            s += "</contact>\n";
        }
        s += "  </link>\n";
        link_xml.push(s);
    }
    let mut joint_xml = Vec::new();
    for k in 1..links {
        let parent = rng.gen_range(0..k);
        let kind = match mix {
            Mix::AllFixed => "fixed",
            Mix::Any | Mix::FixedBase => match rng.gen_range(0..20) {
                0..=5 => "revolute",
                6..=11 => "continuous",
                12..=14 => "prismatic",
                _ => "fixed",
            },
        };
        let rpy = rng.gen_bool(0.6);
        let mut s = format!(
            "  <joint name=\"j{k}\" type=\"{kind}\">{}<parent link=\"l{parent}\"/><child link=\"l{k}\"/>",
            origin(rng, 0.3, rpy)
        );
        if kind != "fixed" {
            let axis = if rng.gen_bool(0.3) {
                [0.0, 0.0, 1.0]
            } else {
                let v: [f64; 3] = std::array::from_fn(|_| rng.gen_range(-1.0..1.0));
                let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                [v[0] / n, v[1] / n, v[2] / n]
            };
            write!(
                s,
                "<axis xyz=\"{:?} {:?} {:?}\"/>",
                axis[0], axis[1], axis[2]
            )
            .unwrap();
            let effort = rng.gen_range(0.5..20.0);
            match kind {
                "revolute" => write!(
                    s,
                    "<limit lower=\"{:?}\" upper=\"{:?}\" effort=\"{effort:?}\" velocity=\"3\"/>",
                    rng.gen_range(-1.5..-0.2),
                    rng.gen_range(0.2..1.5)
                ),
                "prismatic" => write!(
                    s,
                    "<limit lower=\"{:?}\" upper=\"{:?}\" effort=\"{effort:?}\" velocity=\"1\"/>",
                    rng.gen_range(-0.1..-0.02),
                    rng.gen_range(0.02..0.1)
                ),
                _ => write!(s, "<limit effort=\"{effort:?}\" velocity=\"5\"/>"),
            }
            .unwrap();
            if rng.gen_bool(0.3) {
                write!(
                    s,
                    "<dynamics damping=\"{:?}\" friction=\"0.1\"/>",
                    rng.gen_range(0.0..0.5)
                )
                .unwrap();
            }
        }
        s += "</joint>\n";
        joint_xml.push(s);
    }
    // The file order of links and joints is not the tree order: shuffle both.
    shuffle(rng, &mut link_xml);
    shuffle(rng, &mut joint_xml);
    format!(
        "<?xml version=\"1.0\"?>\n<robot name=\"random\">\n{}{}</robot>\n",
        link_xml.concat(),
        joint_xml.concat()
    )
}

fn shuffle<T>(rng: &mut ChaCha8Rng, v: &mut [T]) {
    for i in (1..v.len()).rev() {
        let j = rng.gen_range(0..=i);
        v.swap(i, j);
    }
}

/// Piecewise-constant random targets, one row per step, within (a little beyond) each joint's range.
fn random_targets(rng: &mut ChaCha8Rng, spec: &RobotSpec, steps: usize) -> Vec<Vec<f64>> {
    let ranges: Vec<f64> = spec
        .urdf
        .movable_joints()
        .iter()
        .map(|&j| match spec.urdf.joint(j).unwrap().kind {
            snake_core::urdf::JointKind::Prismatic => 0.15,
            _ => 1.8,
        })
        .collect();
    let mut current: Vec<f64> = ranges.iter().map(|_| 0.0).collect();
    let mut next_change = 0;
    (0..steps)
        .map(|step| {
            if step == next_change {
                for (c, r) in current.iter_mut().zip(&ranges) {
                    *c = rng.gen_range(-r..*r);
                }
                next_change += rng.gen_range(40..120);
            }
            current.clone()
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

fn run_ours(spec: &RobotSpec, s: &UrdfScenario, targets: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let [x, y, z, yaw] = s.start;
    let mut robot = Robot::new(spec, StartPose { x, y, z, yaw }).expect("robot builds");
    let m = robot.joints();
    let (mut q, mut qd, mut tau) = (vec![0.0; m], vec![0.0; m], vec![0.0; m]);
    let dt = 1.0 / 240.0;
    let mut rows = Vec::with_capacity(targets.len());
    for (k, row) in targets.iter().enumerate() {
        let step = (k + 1) as f64;
        if m > 0 {
            robot.set_targets(row).unwrap();
        }
        robot.step().expect("step");
        let base = robot.base_state().unwrap();
        robot.read_joint_states(&mut q, &mut qd, &mut tau).unwrap();
        let o = base.pose.orientation.coords;
        let mut out = vec![step, step * dt];
        out.extend(base.pose.position.iter());
        out.extend([o.x, o.y, o.z, o.w]);
        out.extend(&q);
        out.extend(base.linear_velocity.iter());
        out.extend(base.angular_velocity.iter());
        out.extend(&qd);
        out.extend(&tau);
        rows.push(out);
    }
    rows
}

/// Generates `count` robots from `seed`, runs each in both inertia modes, and compares.
fn check_random(tag: &str, seed: u64, count: usize, mix: Mix, steps: usize) {
    let dir = std::env::temp_dir().join(format!("snakesim-urdf-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut scenarios = Vec::new();
    let mut runs = Vec::new();
    for r in 0..count {
        let links = rng.gen_range(2..=7);
        let urdf = dir.join(format!("robot-{r}.urdf"));
        std::fs::write(&urdf, random_urdf(&mut rng, links, mix)).unwrap();
        let pi = std::f64::consts::PI;
        let start = [
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
            rng.gen_range(0.3..0.8),
            rng.gen_range(-pi..pi),
        ];
        for inertia in [InertiaSource::Shapes, InertiaSource::File] {
            let mut spec = RobotSpec::load(&urdf).expect("the generated URDF loads");
            spec.inertia = inertia;
            let mut friction = Vec::new();
            for link in 0..spec.urdf.links.len() {
                if rng.gen_bool(0.4) {
                    let a = [
                        rng.gen_range(0.01..1.0),
                        rng.gen_range(0.01..1.0),
                        rng.gen_range(0.01..1.0),
                    ];
                    spec.anisotropic_friction[link] = Some(a);
                    friction.push((link as i32 - 1, a));
                }
            }
            if rng.gen_bool(0.3) {
                spec.motors.kp = rng.gen_range(0.05..0.5);
                spec.motors.kd = rng.gen_range(0.3..1.5);
            }
            let targets = random_targets(&mut rng, &spec, steps);
            let name = format!("{tag}-{r}-{inertia}");
            let target_path = dir.join(format!("{name}.targets.csv"));
            write_targets(&target_path, &targets);
            scenarios.push(UrdfScenario {
                name: name.clone(),
                urdf: urdf.clone(),
                start,
                inertia: inertia.to_string(),
                friction,
                kp: spec.motors.kp,
                kd: spec.motors.kd,
                max_velocity: None,
                targets: target_path,
            });
            runs.push((spec, targets));
        }
    }
    let Some(out) = run_reference_script("urdf_reference.py", &scenarios, tag) else {
        return;
    };
    for (s, (spec, targets)) in scenarios.iter().zip(&runs) {
        let table = read_csv(&out.join(format!("{}.csv", s.name)));
        let ours = run_ours(spec, s, targets);
        assert!(
            ours.iter().flatten().all(|v| v.is_finite()),
            "{}: the robot left the finite range",
            s.name
        );
        assert_identical(&s.name, &table.header, &table.rows, &ours);
    }
    std::fs::remove_dir_all(&out).ok();
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn random_robots_both_inertia_modes() {
    check_random("random", 21, 8, Mix::Any, TEN_SECONDS);
}

#[test]
fn rigid_robots_of_fixed_joints() {
    check_random("fixed", 7, 4, Mix::AllFixed, TEN_SECONDS);
}

#[test]
fn robots_on_a_fixed_base() {
    check_random("base", 11, 3, Mix::FixedBase, TEN_SECONDS);
}

/// A random robot of at least two movable joints (the generator makes some of fixed joints only), and
/// its URDF's path.
fn random_movable_robot(rng: &mut ChaCha8Rng, dir: &Path, r: usize) -> (PathBuf, RobotSpec) {
    let urdf = dir.join(format!("robot-{r}.urdf"));
    loop {
        let links = rng.gen_range(3..=7);
        std::fs::write(&urdf, random_urdf(rng, links, Mix::Any)).unwrap();
        let spec = RobotSpec::load(&urdf).expect("the generated URDF loads");
        if spec.joint_names().len() >= 2 {
            return (urdf, spec);
        }
    }
}

/// The largest |difference| between two runs, over every step and column.
fn max_deviation(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    a.iter()
        .flatten()
        .zip(b.iter().flatten())
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// The largest |difference| of a joint angle (columns `q0..`) between two runs.
fn max_angle_deviation(header: &[String], a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    let angles: Vec<usize> = (0..header.len())
        .filter(|&c| header[c].starts_with('q') && !header[c].starts_with("qd"))
        .collect();
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| angles.iter().map(move |&c| (x[c] - y[c]).abs()))
        .fold(0.0, f64::max)
}

/// One robot file with a maximum velocity: its spec, the scenario with the limit and the same run
/// without it.
struct ServoRun {
    spec: RobotSpec,
    limited: UrdfScenario,
    free: UrdfScenario,
    targets: Vec<Vec<f64>>,
}

/// Writes `yaml` as robot file `name` in `dir`, loads it, and draws jumping targets for it.
fn servo_run(
    rng: &mut ChaCha8Rng,
    dir: &Path,
    name: &str,
    urdf: &Path,
    start: [f64; 4],
    yaml: &str,
) -> ServoRun {
    let file = dir.join(format!("{name}.yaml"));
    std::fs::write(&file, yaml).unwrap();
    let spec = RobotSpec::load(&file).expect("the robot file loads");
    let m = spec.joint_names().len();
    let limits: Vec<Option<f64>> = (0..m).map(|k| spec.max_velocity(k)).collect();
    assert!(
        limits.iter().all(Option::is_some),
        "{name}: every joint limited"
    );
    let targets = random_targets(rng, &spec, TEN_SECONDS);
    let target_path = dir.join(format!("{name}.targets.csv"));
    write_targets(&target_path, &targets);
    let limited = UrdfScenario {
        name: name.to_owned(),
        urdf: urdf.to_path_buf(),
        start,
        inertia: spec.inertia.to_string(),
        friction: Vec::new(),
        kp: spec.motors.kp,
        kd: spec.motors.kd,
        max_velocity: Some(limits),
        targets: target_path,
    };
    let free = UrdfScenario {
        name: format!("{name}-free"),
        max_velocity: None,
        ..limited.clone()
    };
    ServoRun {
        spec,
        limited,
        free,
        targets,
    }
}

/// Robot files with `motors: max_velocity` (and a `joints:` override on some) against pybullet's
/// `setJointMotorControl2(..., maxVelocity=V)` on every movable joint: random robots and the shipped
/// yaw-pitch-16 at the SEA Snake's speed, driven for 10 s by targets that jump by up to 3.6 rad (the
/// motor's target velocity, 0.1 * 240 * jump, reaches ~86 rad/s, far above every limit here). Every step
/// is identical, and pybullet's run without the limit moves the joints visibly differently.
#[test]
fn servos_with_a_maximum_velocity() {
    let dir = std::env::temp_dir().join(format!("snakesim-urdf-servo-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(47);
    let mut runs = Vec::new();
    for r in 0..4 {
        let (urdf, plain) = random_movable_robot(&mut rng, &dir, r);
        let pi = std::f64::consts::PI;
        let start = [
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
            rng.gen_range(0.3..0.8),
            rng.gen_range(-pi..pi),
        ];
        let inertia = if r % 2 == 0 { "shapes" } else { "file" };
        let mut yaml = format!(
            "urdf: robot-{r}.urdf\nstart: {start:?}\ninertia: {inertia}\n\
             motors: {{kp: {:?}, kd: {:?}, max_velocity: {:?}}}\n",
            rng.gen_range(0.05..0.5),
            rng.gen_range(0.3..1.5),
            rng.gen_range(0.5..3.0),
        );
        // Every other robot overrides one joint's limit.
        if r % 2 == 1 {
            let names = plain.joint_names();
            let name = names[rng.gen_range(0..names.len())];
            yaml += &format!(
                "joints:\n  {name}: {{max_velocity: {:?}}}\n",
                rng.gen_range(4.0..8.0)
            );
        }
        runs.push(servo_run(
            &mut rng,
            &dir,
            &format!("servo-{r}"),
            &urdf,
            start,
            &yaml,
        ));
    }
    let shipped = snakesim_tests::repo_root().join("robots/yaw-pitch-16.urdf");
    let yaml = format!(
        "urdf: {}\nstart: [0, 0, 0.0254, 0]\nmotors: {{kp: 0.1, kd: 1.0, max_velocity: 3.49}}\n",
        shipped.display()
    );
    let start = [0.0, 0.0, 0.0254, 0.0];
    runs.push(servo_run(
        &mut rng,
        &dir,
        "servo-yaw-pitch-16",
        &shipped,
        start,
        &yaml,
    ));
    let scenarios: Vec<&UrdfScenario> = runs.iter().flat_map(|r| [&r.limited, &r.free]).collect();
    let Some(out) = run_reference_script("urdf_reference.py", &scenarios, "urdf-servo") else {
        return;
    };
    for run in &runs {
        let limited = read_csv(&out.join(format!("{}.csv", run.limited.name)));
        let free = read_csv(&out.join(format!("{}.csv", run.free.name)));
        let ours = run_ours(&run.spec, &run.limited, &run.targets);
        assert_identical(&run.limited.name, &limited.header, &limited.rows, &ours);
        let deviation = max_deviation(&limited.rows, &ours);
        assert_eq!(deviation, 0.0, "{}", run.limited.name);
        // Without the limit (the robot file minus max_velocity): pybullet's array call, bit for bit.
        let mut unlimited = run.spec.clone();
        unlimited.motors.max_velocity = None;
        unlimited.max_velocities.iter_mut().for_each(|v| *v = None);
        let ours_free = run_ours(&unlimited, &run.free, &run.targets);
        assert_identical(&run.free.name, &free.header, &free.rows, &ours_free);
        let binds = max_angle_deviation(&limited.header, &limited.rows, &free.rows);
        eprintln!(
            "{}: deviation from pybullet {deviation:e}; joint angles with and without the limit \
             differ by up to {binds:.3} rad",
            run.limited.name
        );
        assert!(
            binds > 0.1,
            "{}: the limit does not bind (angles differ by {binds} rad)",
            run.limited.name
        );
    }
    std::fs::remove_dir_all(&out).ok();
    std::fs::remove_dir_all(&dir).ok();
}

/// The env on `robots/paper-cubes-5.yaml` is the built-in 5-joint env: the same observations, rewards
/// and flags, bit for bit, under the same random actions (both layouts, the physics trace on).
#[test]
fn env_on_the_paper_robot_file_is_the_built_in_env() {
    use snake_core::env::ObservationLayout;
    use snake_core::robot::RobotRef;
    use snake_core::{EnvConfig, ResetOptions, SnakeEnv};
    let file = snakesim_tests::repo_root().join("robots/paper-cubes-5.yaml");
    for layout in [ObservationLayout::Paper, ObservationLayout::Extended] {
        let built_in = EnvConfig {
            observation: layout,
            max_episode_steps: 600,
            ..EnvConfig::default()
        };
        let robot = EnvConfig {
            robot: Some(RobotRef::load(&file).unwrap()),
            ..built_in.clone()
        };
        assert_eq!(robot.observation_dim(), built_in.observation_dim());
        let (mut a, mut b) = (
            SnakeEnv::new(built_in).unwrap(),
            SnakeEnv::new(robot).unwrap(),
        );
        b.set_physics_trace(true);
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for episode in 0..2 {
            let (oa, _) = a.reset(Some(episode), ResetOptions::default()).unwrap();
            let (ob, _) = b.reset(Some(episode), ResetOptions::default()).unwrap();
            assert_eq!(oa, ob, "reset {episode}");
            loop {
                let action: Vec<f32> = (0..5).map(|_| rng.gen_range(-1.0..1.0)).collect();
                let (sa, sb) = (a.step(&action).unwrap(), b.step(&action).unwrap());
                let same = sa
                    .obs
                    .iter()
                    .zip(&sb.obs)
                    .all(|(x, y)| x.to_bits() == y.to_bits());
                assert!(same, "episode {episode} step {}", sa.info.episode_step);
                assert_eq!(sa.reward.to_bits(), sb.reward.to_bits());
                assert_eq!((sa.terminated, sa.truncated), (sb.terminated, sb.truncated));
                if sa.terminated || sa.truncated {
                    break;
                }
            }
        }
    }
}

/// An env on a robot file has one action value per movable joint and one (angle, velocity) pair per
/// movable joint in the observation; a serialised config names the robot by its path.
#[test]
fn env_layouts_follow_the_robot() {
    use snake_core::{EnvConfig, ResetOptions, SnakeEnv};
    let file = snakesim_tests::repo_root().join("robots/wheeled-8.yaml");
    let json = serde_json::json!({"robot": file, "max_episode_steps": 50}).to_string();
    let config: EnvConfig = serde_json::from_str(&json).unwrap();
    assert_eq!(config.joints(), 23);
    assert_eq!(config.action_dim(), 23);
    assert_eq!(config.observation_dim(), 2 + 2 * 23);
    let back: EnvConfig = serde_json::from_str(&serde_json::to_string(&config).unwrap()).unwrap();
    assert_eq!(back, config);
    let mut env = SnakeEnv::new(config).unwrap();
    env.set_physics_trace(true);
    let (obs, _) = env.reset(Some(1), ResetOptions::default()).unwrap();
    assert_eq!(obs.len(), 48);
    let step = env.step(&[0.3f32; 23]).unwrap();
    assert!(step.obs.iter().all(|v| v.is_finite()));
    let trace = env.physics_trace().unwrap();
    assert_eq!(trace.poses.len(), 24 * 7, "one pose per link");
    let bad = serde_json::json!({"robot": "/nonexistent/robot.urdf"}).to_string();
    let e = serde_json::from_str::<EnvConfig>(&bad)
        .unwrap_err()
        .to_string();
    assert!(e.contains("/nonexistent/robot.urdf: cannot read"), "{e}");
}
