//! `snake-cli run --robot`: the shipped robots against pybullet 3.2.7, the paper's robot file against the
//! built-in snake, targets files, and one-line errors for bad robots.

use std::path::{Path, PathBuf};

use serde::Serialize;
use snake_core::{Gait, InertiaSource, RobotGait, RobotSpec};
use snakesim_tests::{assert_identical, read_csv, repo_root, run_reference_script};

mod common;
use common::snake_cli;

fn temp_dir(tag: &str) -> PathBuf {
    common::temp_dir("robots", tag)
}

fn robot(name: &str) -> PathBuf {
    repo_root().join("robots").join(name)
}

/// A scenario of `tests/reference/urdf_reference.py`.
#[derive(Serialize)]
struct UrdfScenario {
    name: String,
    urdf: PathBuf,
    start: [f64; 4],
    inertia: String,
    friction: Vec<(i32, [f64; 3])>,
    kp: f64,
    kd: f64,
    targets: PathBuf,
}

/// The targets `snake-cli run --gait sine` sets on a robot: the robot file's wave over the actuated
/// joints, 0 on passive ones.
fn gait_targets(spec: &RobotSpec, steps: usize) -> Vec<Vec<f64>> {
    let mut gait = RobotGait::new(spec.gait.clone().unwrap_or_default(), spec);
    let m = spec.urdf.movable_joints().len();
    (0..steps)
        .map(|_| {
            let mut row = vec![0.0; m];
            gait.next_targets(&mut row);
            row
        })
        .collect()
}

fn write_rows(path: &Path, rows: &[Vec<f64>]) {
    let text: String = rows
        .iter()
        .map(|r| {
            let cells: Vec<String> = r.iter().map(|v| format!("{v:?}")).collect();
            cells.join(",") + "\n"
        })
        .collect();
    std::fs::write(path, text).unwrap();
}

/// Every shipped robot, with its robot file's gait for 10 s, in both inertia modes: the CLI's trajectory
/// is pybullet's, bit for bit.
#[test]
fn shipped_robots_match_pybullet() {
    let dir = temp_dir("shipped");
    let mut scenarios = Vec::new();
    let mut runs = Vec::new();
    for name in ["paper-cubes-5", "yaw-pitch-16", "wheeled-8"] {
        for inertia in [InertiaSource::Shapes, InertiaSource::File] {
            let file = robot(&format!("{name}.yaml"));
            let mut spec = RobotSpec::load(&file).unwrap();
            spec.inertia = inertia;
            let start = spec.default_start();
            let targets = dir.join(format!("{name}-{inertia}.targets.csv"));
            write_rows(&targets, &gait_targets(&spec, 2400));
            let friction = spec
                .anisotropic_friction
                .iter()
                .enumerate()
                .filter_map(|(k, a)| a.map(|a| (k as i32 - 1, a)))
                .collect();
            let tag = format!("{name}-{inertia}");
            scenarios.push(UrdfScenario {
                name: tag.clone(),
                urdf: spec.urdf.source.clone().unwrap(),
                start: [start.x, start.y, start.z, start.yaw],
                inertia: inertia.to_string(),
                friction,
                kp: spec.motors.kp,
                kd: spec.motors.kd,
                targets,
            });
            runs.push((tag, file, inertia));
        }
    }
    let Some(out) = run_reference_script("urdf_reference.py", &scenarios, "shipped") else {
        return;
    };
    for (tag, file, inertia) in runs {
        let csv = dir.join(format!("{tag}.csv"));
        let inertia = inertia.to_string();
        let result = snake_cli(&[
            "run",
            "--robot",
            file.to_str().unwrap(),
            "--inertia",
            &inertia,
            "--seconds",
            "10",
            "--output",
            csv.to_str().unwrap(),
        ]);
        assert!(
            result.status.success(),
            "{tag}: {}",
            String::from_utf8_lossy(&result.stderr)
        );
        let ours = read_csv(&csv);
        let table = read_csv(&out.join(format!("{tag}.csv")));
        assert_eq!(
            ours.header[..],
            table.header[..ours.header.len()],
            "{tag}: CSV header"
        );
        let width = ours.header.len();
        let reference: Vec<Vec<f64>> = table.rows.iter().map(|r| r[..width].to_vec()).collect();
        assert_identical(&tag, &ours.header, &reference, &ours.rows);
    }
    std::fs::remove_dir_all(&out).ok();
    std::fs::remove_dir_all(&dir).ok();
}

/// `--robot robots/paper-cubes-5.yaml --gait sine` writes the same CSV, byte for byte, as `--joints 5`.
#[test]
fn paper_robot_file_is_the_built_in_snake() {
    let dir = temp_dir("paper");
    let (a, b) = (dir.join("joints.csv"), dir.join("robot.csv"));
    let file = robot("paper-cubes-5.yaml");
    for args in [
        vec!["run", "--joints", "5", "--output", a.to_str().unwrap()],
        vec![
            "run",
            "--robot",
            file.to_str().unwrap(),
            "--gait",
            "sine",
            "--output",
            b.to_str().unwrap(),
        ],
    ] {
        let out = snake_cli(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    assert!(
        std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(),
        "the robot file's CSV differs from --joints 5"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// `--targets`: columns in any order, one row per step; the run lasts as many steps as there are rows,
/// and the robot does what pybullet does with the same targets.
#[test]
fn targets_file_drives_the_robot() {
    let dir = temp_dir("targets");
    let file = robot("wheeled-8.urdf");
    let spec = RobotSpec::load(&file).unwrap();
    let names = spec.joint_names();
    let steps = 480;
    let rows: Vec<Vec<f64>> = (0..steps)
        .map(|k| {
            (0..names.len())
                .map(|j| 0.6 * ((k as f64) * 0.02 + j as f64).sin())
                .collect()
        })
        .collect();
    // The file's columns reversed: the CLI must put them back in joint order.
    let mut text = String::from("step");
    for n in names.iter().rev() {
        text += &format!(",{n}");
    }
    text.push('\n');
    for (k, r) in rows.iter().enumerate() {
        text += &(k + 1).to_string();
        for v in r.iter().rev() {
            text += &format!(",{v:?}");
        }
        text.push('\n');
    }
    let targets_csv = dir.join("targets.csv");
    std::fs::write(&targets_csv, text).unwrap();
    let plain = dir.join("plain.csv");
    write_rows(&plain, &rows);
    let out_csv = dir.join("out.csv");
    let start = "0,0,0.03,0.4";
    let result = snake_cli(&[
        "run",
        "--robot",
        file.to_str().unwrap(),
        "--targets",
        targets_csv.to_str().unwrap(),
        &format!("--start={start}"),
        "--anisotropic-friction",
        "1,0.5,0.8",
        "--output",
        out_csv.to_str().unwrap(),
    ]);
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    let ours = read_csv(&out_csv);
    assert_eq!(ours.rows.len(), steps);
    let scenario = UrdfScenario {
        name: "targets".into(),
        urdf: file,
        start: [0.0, 0.0, 0.03, 0.4],
        inertia: "shapes".into(),
        friction: (0..spec.urdf.links.len())
            .map(|k| (k as i32 - 1, [1.0, 0.5, 0.8]))
            .collect(),
        kp: 0.1,
        kd: 1.0,
        targets: plain,
    };
    let Some(out) = run_reference_script("urdf_reference.py", &[scenario], "targets") else {
        return;
    };
    let table = read_csv(&out.join("targets.csv"));
    let width = ours.header.len();
    let reference: Vec<Vec<f64>> = table.rows.iter().map(|r| r[..width].to_vec()).collect();
    assert_identical("targets", &ours.header, &reference, &ours.rows);
    std::fs::remove_dir_all(&out).ok();
    std::fs::remove_dir_all(&dir).ok();
}

/// Bad robots, robot files and targets: one line naming the file and the element, a failure, no panic,
/// nothing written.
#[test]
fn bad_robots_are_one_line_and_write_nothing() {
    let dir = temp_dir("bad");
    let write = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_owned()
    };
    let link = |n: &str| format!("<link name='{n}'/>");
    let fixed = |p: &str, c: &str| {
        format!("<joint name='{p}{c}' type='fixed'><parent link='{p}'/><child link='{c}'/></joint>")
    };
    let urdf = |body: String| format!("<robot name='r'>{body}</robot>");
    let ball = |n: &str| {
        format!("<link name='{n}'><collision><geometry><sphere radius='0.1'/></geometry></collision></link>")
    };
    let good = write(
        "good.urdf",
        &urdf(format!(
            "{}{}<joint name='j' type='continuous'><parent link='a'/><child link='b'/><limit effort='1'/></joint>",
            ball("a"),
            ball("b")
        )),
    );
    let yaw_pitch = robot("yaw-pitch-16.urdf");
    let wave = |name: &str, wave: &str| {
        write(
            name,
            &format!("urdf: {}\nwave: {wave}\n", yaw_pitch.display()),
        )
    };
    let cases: Vec<(Vec<String>, String)> = vec![
        (vec![write("notxml.urdf", "<robot name='r'><link")], "notxml.urdf: not XML".into()),
        (
            vec![write("missing.urdf", &urdf(format!("{}{}", link("a"), fixed("a", "x"))))],
            "child link 'x' does not exist".into(),
        ),
        (
            vec![write(
                "cycle.urdf",
                &urdf(format!(
                    "{}{}{}{}{}",
                    link("r"),
                    link("a"),
                    link("b"),
                    fixed("a", "b"),
                    fixed("b", "a")
                )),
            )],
            "cycle".into(),
        ),
        (
            vec![write("roots.urdf", &urdf(format!("{}{}", link("a"), link("b"))))],
            "two or more root links".into(),
        ),
        (
            vec![write(
                "mass.urdf",
                &urdf(
                    "<link name='a'><inertial><mass value='-2'/><inertia ixx='1' iyy='1' izz='1'/></inertial></link>"
                        .into(),
                ),
            )],
            "negative mass".into(),
        ),
        (
            vec![write(
                "zero.urdf",
                &urdf(format!(
                    "{}<link name='b'><inertial><mass value='0'/><inertia ixx='1' iyy='1' izz='1'/></inertial></link>{}",
                    link("a"),
                    fixed("a", "b")
                )),
            )],
            "only the root link may have mass 0".into(),
        ),
        (
            vec![write(
                "mesh.urdf",
                &urdf("<link name='a'><collision><geometry><mesh filename='gone.stl'/></geometry></collision></link>".into()),
            )],
            "mesh file 'gone.stl' not found".into(),
        ),
        (
            vec![write("keys.yaml", "urdf: good.urdf\nfriction: 3\n")],
            "keys.yaml: unknown field `friction`".into(),
        ),
        (
            vec![write("link.yaml", "urdf: good.urdf\nlinks:\n  nose: {anisotropic_friction: [1, 1, 1]}\n")],
            "links: nose: no such link".into(),
        ),
        (
            vec![wave("wave-name.yaml", "{gait: wiggle}")],
            "wave-name.yaml: wave: unknown gait 'wiggle'".into(),
        ),
        (
            vec![wave("wave-sine.yaml", "{gait: sine}")],
            "wave-sine.yaml: wave: gait sine is the envs' wave already".into(),
        ),
        (
            vec![wave("wave-param.yaml", "{gait: lateral, params: {period: 0}}")],
            "wave-param.yaml: wave: gait parameter period".into(),
        ),
        (
            vec![wave("wave-steer.yaml", "{gait: lateral, steering: 2}")],
            "wave-steer.yaml: wave: steering must be in (0, ".into(),
        ),
        (
            vec![wave("wave-key.yaml", "{gait: lateral, speed: 1}")],
            "wave-key.yaml: wave: unknown field `speed`".into(),
        ),
        (
            vec![write(
                "wave-joints.yaml",
                "urdf: good.urdf\nwave: {gait: sidewind}\n",
            )],
            "wave-joints.yaml: wave: gait sidewind needs".into(),
        ),
        (
            vec![
                good.clone(),
                "--targets".into(),
                write("ragged.csv", "step,j\n1,0.1\n2,0.1,0.3\n"),
            ],
            "ragged.csv:3: 3 cells".into(),
        ),
        (
            vec![good.clone(), "--targets".into(), write("names.csv", "step,k\n1,0\n")],
            "column \"k\" is not a movable joint".into(),
        ),
        (vec![write("robot.txt", "x")], "a robot is a .urdf file".into()),
        (
            vec![
                write(
                    "flat.urdf",
                    &urdf(
                        "<link name='a'><inertial><mass value='1'/><inertia ixx='1' iyy='1' izz='3'/></inertial>\
                         <collision><geometry><sphere radius='0.1'/></geometry></collision></link>"
                            .into(),
                    ),
                ),
                "--inertia".into(),
                "file".into(),
            ],
            "flat.urdf: <link name=\"a\"> (root link): <inertia> has principal moments".into(),
        ),
        (
            vec![write("noshape.urdf", &urdf(link("a")))],
            "has mass but no collision shape".into(),
        ),
        (vec![good.clone(), "--anisotropic-friction".into(), "1,-1,1".into()], "anisotropic friction".into()),
        (vec![good.clone(), "--joints".into(), "3".into()], "cannot be used with".into()),
    ];
    let output = dir.join("never.csv");
    for (extra, needle) in &cases {
        let mut args = vec!["run", "--robot"];
        args.extend(extra.iter().map(String::as_str));
        args.extend(["--output", output.to_str().unwrap()]);
        let out = snake_cli(&args);
        assert!(!out.status.success(), "{args:?} should fail");
        let stderr = String::from_utf8_lossy(&out.stderr);
        let first = stderr.lines().next().unwrap_or("");
        assert!(first.starts_with("error:"), "{args:?}: {stderr}");
        assert!(
            first.contains(needle.as_str()),
            "{args:?}: '{first}' should mention {needle}"
        );
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        assert!(!output.exists(), "{args:?} wrote {}", output.display());
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `snake-cli bench --robot` measures a robot on its gait.
#[test]
fn bench_measures_a_robot() {
    let file = robot("wheeled-8.yaml");
    let out = snake_cli(&[
        "bench",
        "--robot",
        file.to_str().unwrap(),
        "--steps",
        "240",
        "--repeats",
        "1",
        "--no-reference",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("wheeled-8 (24 links, 23 movable joints)"),
        "{text}"
    );
}
