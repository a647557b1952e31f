//! `snake-cli run` with skin friction (issue 27): a one-link robot (a block, no joints) driven by a
//! targets file with only the `step` column, its skin set in the robot file (whole robot or per link)
//! or by `--skin-friction`/`--skin-axis`; and one-line errors, writing nothing, for bad skin input.

use std::path::{Path, PathBuf};

use snakesim_tests::read_csv;

mod common;
use common::snake_cli;

fn temp_dir(tag: &str) -> PathBuf {
    common::temp_dir("skin", tag)
}

/// A 0.2 kg block of 0.2 x 0.06 x 0.04 m whose collision box is rolled and pitched in its link frame,
/// so that dropped from 0.1 m it lands on an edge and topples: its contacts slide, and friction shapes
/// where it comes to rest.
const BLOCK_URDF: &str = "<robot name='block'><link name='block'>\
    <inertial><mass value='0.2'/><inertia ixx='1e-4' iyy='1e-4' izz='1e-4' ixy='0' ixz='0' iyz='0'/></inertial>\
    <collision><origin rpy='0.4 0.3 0'/><geometry><box size='0.2 0.06 0.04'/></geometry></collision>\
    </link></robot>";

const SKIN_YAML: &str = "{forward: 0.1, backward: 0.3, transverse: 0.5, axis: x}";

/// The block and its targets file (one second of steps, no joint columns) in `dir`.
fn write_block(dir: &Path) -> PathBuf {
    std::fs::write(dir.join("block.urdf"), BLOCK_URDF).unwrap();
    let mut targets = String::from("step\n");
    for k in 1..=240 {
        targets += &format!("{k}\n");
    }
    let path = dir.join("targets.csv");
    std::fs::write(&path, targets).unwrap();
    path
}

fn run_block(dir: &Path, robot_yaml: &str, extra: &[&str], out: &str) -> Vec<u8> {
    let robot = dir.join(format!("{out}.yaml"));
    std::fs::write(&robot, format!("urdf: block.urdf\n{robot_yaml}")).unwrap();
    let csv = dir.join(format!("{out}.csv"));
    let targets = dir.join("targets.csv");
    let mut args = vec![
        "run",
        "--robot",
        robot.to_str().unwrap(),
        "--targets",
        targets.to_str().unwrap(),
        "--start=0,0,0.1,0",
        "--output",
        csv.to_str().unwrap(),
    ];
    args.extend(extra);
    let result = snake_cli(&args);
    assert!(
        result.status.success(),
        "{out}: {}",
        String::from_utf8_lossy(&result.stderr)
    );
    let stdout = String::from_utf8_lossy(&result.stdout);
    assert!(
        stdout.contains("1 links, 0 movable joints"),
        "{out}: {stdout}"
    );
    std::fs::read(csv).unwrap()
}

/// The one-link robot runs for as many steps as its targets file has rows and writes its trajectory;
/// skin set for the whole robot, for its one link, or on the command line (over the file's) moves it
/// identically, and differently from no skin or another axis.
#[test]
fn one_link_robot_with_skin_writes_its_csv() {
    let dir = temp_dir("block");
    write_block(&dir);
    let robot = run_block(&dir, &format!("skin_friction: {SKIN_YAML}\n"), &[], "robot");
    let table = read_csv(&dir.join("robot.csv"));
    assert_eq!(
        table.header[..5],
        ["step", "t", "base_x", "base_y", "base_z"].map(String::from)
    );
    assert_eq!(table.rows.len(), 240);
    let last = table.rows.last().unwrap();
    assert_eq!(last[0], 240.0);
    assert!(last.iter().all(|v| v.is_finite()), "{last:?}");
    // At rest after toppling, on its largest face: the box's centre (its link frame) 0.02 m up.
    assert!((last[4] - 0.02).abs() < 1e-3, "rests at z {}", last[4]);

    let link = run_block(
        &dir,
        &format!("links:\n  block: {{skin_friction: {SKIN_YAML}}}\n"),
        &[],
        "link",
    );
    let flags = run_block(
        &dir,
        "",
        &["--skin-friction", "0.1,0.3,0.5", "--skin-axis", "x"],
        "flags",
    );
    let over = run_block(
        &dir,
        "skin_friction: {forward: 1, backward: 1, transverse: 1, axis: y}\n",
        &["--skin-friction", "0.1,0.3,0.5", "--skin-axis", "x"],
        "over",
    );
    assert!(link == robot, "per-link skin differs from the robot's");
    assert!(
        flags == robot,
        "--skin-friction differs from the robot file's"
    );
    assert!(over == robot, "--skin-friction does not replace the file's");
    let plain = run_block(&dir, "", &[], "plain");
    let turned = run_block(
        &dir,
        "",
        &["--skin-friction", "0.1,0.3,0.5", "--skin-axis", "y"],
        "turned",
    );
    assert!(plain != robot, "skin friction changed nothing");
    assert!(turned != robot, "the skin axis changed nothing");
    std::fs::remove_dir_all(&dir).ok();
}

/// Bad skin input, on the command line (with the built-in snake or a robot) or in a robot file: one
/// line naming the flag or the file and key, a failure, no panic, nothing written.
#[test]
fn bad_skin_input_is_one_line_and_writes_nothing() {
    let dir = temp_dir("bad");
    let targets = write_block(&dir);
    let targets = targets.to_str().unwrap();
    let robot = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, format!("urdf: block.urdf\n{text}\n")).unwrap();
        p.to_str().unwrap().to_owned()
    };
    let plain = robot("plain.yaml", "");
    let on_robot = |flags: &[&str]| {
        let mut args = vec![
            "--robot".to_owned(),
            plain.clone(),
            "--targets".into(),
            targets.into(),
        ];
        args.extend(flags.iter().map(|s| s.to_string()));
        args
    };
    let with_file = |file: String| {
        vec![
            "--robot".to_owned(),
            file,
            "--targets".into(),
            targets.into(),
        ]
    };
    let owned = |flags: &[&str]| flags.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let cases: Vec<(Vec<String>, &str)> = vec![
        // The command line, a robot's and the built-in snake's.
        (
            on_robot(&["--skin-friction", "0.1,0.2"]),
            "'--skin-friction <SKIN_FRICTION>': '0.1,0.2' has 2 values; expected F,B,T",
        ),
        (
            on_robot(&["--skin-friction=-1,0.2,0.3"]),
            "--skin-friction '-1,0.2,0.3': forward must be finite and in [0, 10], got -1.0",
        ),
        (
            on_robot(&["--skin-friction", "nan,1,1"]),
            "--skin-friction 'nan,1,1': forward must be finite and in [0, 10], got NaN",
        ),
        (
            on_robot(&["--skin-friction", "1,inf,1"]),
            "--skin-friction '1,inf,1': backward must be finite",
        ),
        (
            on_robot(&["--skin-friction", "1,1,10.5"]),
            "--skin-friction '1,1,10.5': transverse must be finite and in [0, 10], got 10.5",
        ),
        (
            on_robot(&["--skin-friction", "1,,1"]),
            "'--skin-friction <SKIN_FRICTION>': '1,,1' is not F,B,T",
        ),
        (
            on_robot(&["--skin-friction", "1,1,1", "--skin-axis", "w"]),
            "'--skin-axis <SKIN_AXIS>': invalid argument: unknown skin axis 'w'",
        ),
        (
            owned(&["--skin-friction", "0.1,0.2"]),
            "'--skin-friction <SKIN_FRICTION>': '0.1,0.2' has 2 values",
        ),
        (
            owned(&["--skin-friction=-0.5,1,1"]),
            "--skin-friction '-0.5,1,1': forward must be finite",
        ),
        (
            owned(&["--skin-friction", "1,1,1", "--skin-axis", "up"]),
            "'--skin-axis <SKIN_AXIS>': invalid argument: unknown skin axis 'up'",
        ),
        // Robot files: the whole robot's skin and one link's.
        (
            with_file(robot("two.yaml", "skin_friction: [0.1, 0.2]")),
            "two.yaml: skin_friction: invalid type: sequence",
        ),
        (
            with_file(robot(
                "negative.yaml",
                "skin_friction: {forward: -0.1, backward: 0.2, transverse: 0.3}",
            )),
            "negative.yaml: skin_friction: forward must be finite and in [0, 10], got -0.1",
        ),
        (
            with_file(robot(
                "nan.yaml",
                "skin_friction: {forward: 0.1, backward: .nan, transverse: 0.3}",
            )),
            // Refused where the YAML is read (issue 57), naming the key path.
            "nan.yaml: skin_friction.backward: must be a finite number, got .nan",
        ),
        (
            with_file(robot(
                "big.yaml",
                "skin_friction: {forward: 0.1, backward: 0.2, transverse: 20}",
            )),
            "big.yaml: skin_friction: transverse must be finite and in [0, 10], got 20.0",
        ),
        (
            with_file(robot(
                "axis.yaml",
                "skin_friction: {forward: 0.1, backward: 0.2, transverse: 0.3, axis: w}",
            )),
            "axis.yaml: skin_friction.axis: unknown variant `w`",
        ),
        (
            with_file(robot(
                "missing.yaml",
                "skin_friction: {forward: 0.1, backward: 0.2}",
            )),
            "missing.yaml: skin_friction: missing field `transverse`",
        ),
        (
            with_file(robot(
                "nose.yaml",
                "links:\n  nose: {skin_friction: {forward: 0.1, backward: 0.2, transverse: 0.3}}",
            )),
            "nose.yaml: links: nose: no such link in",
        ),
        (
            with_file(robot(
                "link.yaml",
                "links:\n  block: {skin_friction: {forward: 0.1, backward: -0.2, transverse: 0.3}}",
            )),
            "link.yaml: links: block: skin_friction: backward must be finite and in [0, 10], got -0.2",
        ),
        (
            with_file(robot(
                "linkaxis.yaml",
                "links:\n  block: {skin_friction: {forward: 0.1, backward: 0.2, transverse: 0.3, axis: up}}",
            )),
            "linkaxis.yaml: links.block.skin_friction.axis: unknown variant `up`",
        ),
        (
            with_file(robot(
                "linkmissing.yaml",
                "links:\n  block: {skin_friction: {backward: 0.2, transverse: 0.3}}",
            )),
            "linkmissing.yaml: links.block.skin_friction: missing field `forward`",
        ),
    ];
    let output = dir.join("never.csv");
    for (extra, needle) in &cases {
        let mut args = vec!["run"];
        args.extend(extra.iter().map(String::as_str));
        args.extend(["--output", output.to_str().unwrap()]);
        let out = snake_cli(&args);
        assert!(!out.status.success(), "{args:?} should fail");
        let stderr = String::from_utf8_lossy(&out.stderr);
        let first = stderr.lines().next().unwrap_or("");
        assert!(first.starts_with("error:"), "{args:?}: {stderr}");
        assert!(
            first.contains(needle),
            "{args:?}: '{first}' should mention {needle}"
        );
        // Beyond the one line, at most clap's pointer to --help.
        let rest: Vec<&str> = stderr
            .lines()
            .skip(1)
            .filter(|l| !l.is_empty() && *l != "For more information, try '--help'.")
            .collect();
        assert!(rest.is_empty(), "{args:?}: more than one line: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        assert!(out.stdout.is_empty(), "{args:?} printed {:?}", out.stdout);
        assert!(!output.exists(), "{args:?} wrote {}", output.display());
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Hu et al.'s second finding, weight redistribution: lifting the parts of the body that would push
/// backwards raises the speed. yaw-pitch-16 on a skin of forward < backward < transverse (ground
/// friction 1), its lateral wave with and without the vertical wave that lifts it at the curvature
/// peaks: lifted it goes more than twice as far in 12 s; flat on isotropic skin it barely moves.
#[test]
fn lifting_the_body_raises_the_speed() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let robot = root.join("robots/yaw-pitch-16.yaml");
    let world = root.join("worlds/plane-mu1.yaml");
    let run = |pitch: &str, skin: &str| {
        common::com_moved(&[
            "run",
            "--robot",
            robot.to_str().unwrap(),
            "--world",
            world.to_str().unwrap(),
            "--gait",
            "lateral",
            "--gait-param",
            &format!("amplitude_pitch={pitch}"),
            "--skin-friction",
            skin,
            "--skin-axis",
            "-y",
            "--seconds",
            "12",
        ])
        .0
    };
    let (lifted, flat) = (run("0.15", "0.1,0.15,0.2"), run("0", "0.1,0.15,0.2"));
    assert!(
        lifted > 2.0 * flat,
        "lifted {lifted:.3} m, flat {flat:.3} m"
    );
    let flat_isotropic = run("0", "0.1,0.1,0.1");
    assert!(
        flat_isotropic < 0.1 * lifted,
        "flat on isotropic skin moved {flat_isotropic:.3} m"
    );
}
