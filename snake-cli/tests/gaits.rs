//! The gait library through `snake-cli run`: each gait moves the yaw-pitch robot the way its name
//! says, and bad gait input is one line, a non-zero exit and no file.

use std::path::PathBuf;

mod common;
use common::snake_cli;

fn robot(name: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../robots")
        .join(name)
        .display()
        .to_string()
}

/// Runs a gait and returns the centre of mass's displacement (dx, dy) from the summary.
fn displacement(robot_file: &str, gait: &str, seconds: &str) -> (f64, f64) {
    let (_, dx, dy) = common::com_moved(&[
        "run",
        "--robot",
        robot_file,
        "--gait",
        gait,
        "--seconds",
        seconds,
    ]);
    (dx, dy)
}

// yaw-pitch-16 lies along +y from its head at the origin: along the body is y (head first is -y),
// across it is x.

#[test]
fn sidewind_moves_the_yaw_pitch_robot_sideways() {
    let (dx, dy) = displacement(&robot("yaw-pitch-16.yaml"), "sidewind", "6");
    assert!(
        dx.abs() > 0.5,
        "sidewinding moved only {dx:.3} m across the body"
    );
    assert!(
        dx.abs() > 2.5 * dy.abs(),
        "not sideways: ({dx:.3}, {dy:.3})"
    );
}

#[test]
fn lateral_moves_the_yaw_pitch_robot_forwards() {
    let (dx, dy) = displacement(&robot("yaw-pitch-16.yaml"), "lateral", "6");
    assert!(
        dy < -0.4,
        "lateral undulation moved only {dy:.3} m head first"
    );
    assert!(
        dy.abs() > 4.0 * dx.abs(),
        "not along the body: ({dx:.3}, {dy:.3})"
    );
}

#[test]
fn linear_and_roll_move_the_yaw_pitch_robot_as_named() {
    let (dx, dy) = displacement(&robot("yaw-pitch-16.yaml"), "linear", "6");
    assert!(
        dy < -0.3 && dy.abs() > 4.0 * dx.abs(),
        "linear: ({dx:.3}, {dy:.3})"
    );
    let (dx, dy) = displacement(&robot("yaw-pitch-16.yaml"), "roll", "6");
    assert!(
        dx.abs() > 0.3 && dx.abs() > 2.0 * dy.abs(),
        "roll: ({dx:.3}, {dy:.3})"
    );
}

/// `turn` spins the yaw-pitch robot in place: its root link's heading, from the trajectory CSV's
/// quaternions, turns by more than a full turn in 10 s while the centre of mass drifts less than one
/// body length (about 1 m).
#[test]
fn turn_spins_the_yaw_pitch_robot_in_place() {
    let csv = std::env::temp_dir().join(format!("snake-cli-turn-{}.csv", std::process::id()));
    let (moved, _, _) = common::com_moved(&[
        "run",
        "--robot",
        &robot("yaw-pitch-16.yaml"),
        "--gait",
        "turn",
        "--seconds",
        "10",
        "--output",
        csv.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(&csv).unwrap();
    let _ = std::fs::remove_file(&csv);
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (qx, qy, qz, qw) = (
        col("base_qx"),
        col("base_qy"),
        col("base_qz"),
        col("base_qw"),
    );
    let (mut turned, mut last) = (0.0f64, None::<f64>);
    for line in lines {
        let v: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
        let (x, y, z, w) = (v[qx], v[qy], v[qz], v[qw]);
        let yaw = (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z));
        if let Some(prev) = last {
            // Unwrapped: steps of 1/240 s turn far less than pi.
            let mut d = yaw - prev;
            d -= std::f64::consts::TAU * (d / std::f64::consts::TAU).round();
            turned += d;
        }
        last = Some(yaw);
    }
    assert!(
        turned.abs() > std::f64::consts::TAU,
        "turn rotated the robot by only {:.0} degrees in 10 s",
        turned.to_degrees()
    );
    assert!(moved < 1.0, "turn moved the centre of mass {moved:.2} m");
}

#[test]
fn lateral_and_turn_run_on_the_cube_snake() {
    let (dx, dy) = displacement(&robot("paper-cubes-5.yaml"), "lateral", "4");
    assert!(
        dy < -1.0 && dy.abs() > 4.0 * dx.abs(),
        "lateral: ({dx:.3}, {dy:.3})"
    );
    let out = snake_cli(&["run", "--joints", "6", "--gait", "turn", "--seconds", "1"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn bad_gait_input_is_one_line_and_writes_nothing() {
    let dir = std::env::temp_dir().join(format!("snake-cli-gaits-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("t.csv");
    let csv = csv.to_str().unwrap();
    let yp = robot("yaw-pitch-16.yaml");
    let cubes = robot("paper-cubes-5.yaml");
    let cases: &[(&[&str], &str)] = &[
        (&["--gait", "slither"], "unknown gait 'slither'"),
        (&["--gait", "sidewind"], "needs pitch joints"),
        (
            &["--gait", "linear", "--robot", &cubes],
            "needs pitch joints",
        ),
        (&["--gait", "roll", "--robot", &cubes], "needs pitch joints"),
        (
            &[
                "--robot",
                &yp,
                "--gait",
                "sidewind",
                "--gait-param",
                "wobble=1",
            ],
            "unknown gait parameter 'wobble'",
        ),
        (
            &["--gait", "sandfish", "--gait-param", "alpha=0.5"],
            "unknown gait parameter 'alpha' for gait sandfish",
        ),
        (
            &["--gait", "sandfish", "--gait-param", "wavelength=0"],
            "gait wavelength must be in (0,",
        ),
        (
            &["--gait", "sandfish", "--steer", "0.1"],
            "takes no steering",
        ),
        (
            &[
                "--robot",
                &yp,
                "--gait",
                "lateral",
                "--gait-param",
                "period",
            ],
            "not KEY=VALUE",
        ),
        (
            &[
                "--robot",
                &yp,
                "--gait",
                "lateral",
                "--gait-param",
                "period=fast",
            ],
            "not a number",
        ),
        (
            &[
                "--robot",
                &yp,
                "--gait",
                "lateral",
                "--gait-param",
                "period=inf",
            ],
            "must be finite",
        ),
        (
            &[
                "--robot",
                &yp,
                "--gait",
                "lateral",
                "--gait-param",
                "period=0",
            ],
            "period must be in",
        ),
        (
            &[
                "--robot",
                &yp,
                "--gait",
                "roll",
                "--gait-param",
                "amplitude_yaw=3",
            ],
            "amplitude_yaw must be in",
        ),
        (
            &["--robot", &yp, "--gait", "turn", "--steer", "5"],
            "offset_yaw must be in",
        ),
        (
            &["--gait", "sine", "--gait-param", "amplitude_yaw=0.3"],
            "unknown gait parameter 'amplitude_yaw' for gait sine",
        ),
        (&["--gait", "sine", "--gait-param", "period=-1"], "period"),
    ];
    for (args, expected) in cases {
        let mut all = vec!["run", "--seconds", "0.1", "--output", csv];
        all.extend_from_slice(args);
        let out = snake_cli(&all);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        // The first line is the error and names the problem (clap adds a usage hint below its own).
        let first = err.lines().next().unwrap_or("");
        assert!(first.starts_with("error:"), "{args:?}: {err}");
        assert!(
            first.contains(expected),
            "{args:?}: expected '{expected}' in: {first}"
        );
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(!std::path::Path::new(csv).exists(), "{args:?} wrote {csv}");
    }
}

/// The joint roles of the robot files, read from their axes at rest.
#[test]
fn robot_files_joint_roles() {
    use snake_core::{JointRole, JointRoles, RobotSpec};
    let roles = |name: &str| {
        let spec = RobotSpec::load(std::path::Path::new(&robot(name))).unwrap();
        JointRoles::of_urdf(&spec.urdf)
    };
    let yp = roles("yaw-pitch-16.yaml");
    assert_eq!(yp.roles.len(), 15);
    for (k, r) in yp.roles.iter().enumerate() {
        let expected = if k % 2 == 0 {
            JointRole::Yaw
        } else {
            JointRole::Pitch
        };
        assert_eq!(*r, expected, "joint {k}");
    }
    let wheeled = roles("wheeled-8.yaml");
    assert_eq!(wheeled.count(JointRole::Yaw), 7);
    assert_eq!(wheeled.count(JointRole::Pitch), 0);
    assert_eq!(
        wheeled.count(JointRole::Passive),
        16,
        "the wheels have no motor"
    );
    let cubes = roles("paper-cubes-5.yaml");
    assert_eq!(cubes.roles, vec![JointRole::Yaw; 5]);
}

#[test]
fn atlas_rewrites_its_own_markdown_and_no_input() {
    let dir = std::env::temp_dir().join(format!("snake-cli-atlas-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let md = dir.join("gaits.md");
    let begin = "<!-- atlas:begin (generated by snake-cli atlas; edits inside are replaced) -->";
    std::fs::write(
        &md,
        format!("# kept\n\n{begin}\nold table\n<!-- atlas:end -->\n\ntail kept\n"),
    )
    .unwrap();
    let cubes = robot("paper-cubes-5.yaml");
    let figures = dir.join("figures");
    let atlas = |robot: &str, out: &str| {
        snake_cli(&[
            "atlas",
            "--robot",
            robot,
            "--gait",
            "sine",
            "--ground",
            "plane",
            "--cycles",
            "1",
            "--out",
            out,
            "--figures",
            figures.to_str().unwrap(),
            "--plot-size",
            "200",
        ])
    };
    // The documented `snake-cli atlas` updates an existing file in place.
    let out = atlas(&cubes, md.to_str().unwrap());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&md).unwrap();
    assert!(
        text.starts_with("# kept\n") && text.ends_with("tail kept\n"),
        "{text}"
    );
    assert!(
        !text.contains("old table") && text.contains("| paper-cubes-5 | sine |"),
        "{text}"
    );
    // A robot file named as the output (through a link, the only way past the .md extension) is
    // still refused, and left as it was.
    let copy = dir.join("robot.yaml");
    std::fs::copy(&cubes, &copy).unwrap();
    std::fs::copy(robot("paper-cubes-5.urdf"), dir.join("paper-cubes-5.urdf")).unwrap();
    let link = dir.join("robot.md");
    std::os::unix::fs::symlink(&copy, &link).unwrap();
    let before = std::fs::read(&copy).unwrap();
    let out = atlas(copy.to_str().unwrap(), link.to_str().unwrap());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("one of this run's inputs"),
        "{err}"
    );
    assert_eq!(std::fs::read(&copy).unwrap(), before);
}

#[test]
fn the_atlas_says_when_the_sand_is_too_fine_for_a_robot() {
    // The paper's 0.5 m cubes in worlds/sand.yaml's 1 cm elements: more than the limit a link.
    let dir = std::env::temp_dir().join(format!("snake-cli-atlas-sand-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let md = dir.join("gaits.md");
    let sand = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../worlds/sand.yaml");
    let out = snake_cli(&[
        "atlas",
        "--robot",
        &robot("paper-cubes-5.yaml"),
        "--gait",
        "sine",
        "--ground",
        sand.to_str().unwrap(),
        "--cycles",
        "1",
        "--out",
        md.to_str().unwrap(),
        "--figures",
        dir.join("figures").to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&md).unwrap();
    assert!(
        text.contains("| paper-cubes-5 | sine | n/a | | needs coarser sand elements |"),
        "{text}"
    );
}
