//! Every parser of a file a user hands snakesim, under property tests (proptest) in CI: real files
//! (the shipped models, the shipped run configs, the fuzz seeds) mutated byte by byte, truncated and
//! spliced must give a value or a one-line error, never a panic; and every input the fuzzer ever
//! crashed on (fuzz/regressions/<target>/) stays fixed. The checks are the fuzz targets' own
//! (fuzz/src/checks.rs); `bash scripts/fuzz` runs the coverage-guided fuzzer on them.

use std::path::{Path, PathBuf};

use proptest::prelude::*;

#[path = "../fuzz/src/checks.rs"]
mod checks;
// `snake-cli run --targets`'s parser, the binary's own source file (checks::targets_csv uses it).
#[path = "../snake-cli/src/targets.rs"]
#[allow(dead_code)]
mod targets;

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

fn files(folder: &str, extension: Option<&str>) -> Vec<PathBuf> {
    let mut found: Vec<PathBuf> = std::fs::read_dir(Path::new(ROOT).join(folder))
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            p.is_file()
                && !p
                    .file_name()
                    .is_some_and(|n| n.to_string_lossy().starts_with('.'))
        })
        .filter(|p| extension.is_none_or(|x| p.extension().is_some_and(|e| e == x)))
        .collect();
    found.sort();
    found
}

/// The real inputs of each target: what users and the fuzzer start from.
fn seeds(target: &str) -> Vec<Vec<u8>> {
    let mut paths = files(&format!("fuzz/seeds/{target}"), None);
    match target {
        "model_file" => paths.extend(files("models", Some("safetensors"))),
        "run_config" => {
            paths.extend(files("snake-py/configs", Some("yaml")));
            paths.extend(files("experiments/rough-terrain-agents", Some("yaml")));
        }
        "urdf" => paths.extend(files("robots", Some("urdf"))),
        "robot_file" => paths.extend(files("robots", Some("yaml"))),
        "world_file" => {
            paths.extend(files("worlds", Some("yaml")));
            paths.extend(files("worlds", Some("csv")));
        }
        _ => {}
    }
    assert!(!paths.is_empty(), "no seeds for {target}");
    paths.iter().map(|p| std::fs::read(p).unwrap()).collect()
}

fn check(target: &str, bytes: &[u8]) {
    match target {
        "model_file" => checks::model_file(bytes),
        "run_config" => checks::run_config(bytes),
        "env_keywords" => checks::env_keywords(bytes),
        "urdf" => checks::urdf(bytes),
        "robot_file" => checks::robot_file(bytes),
        "targets_csv" => checks::targets_csv(bytes),
        "world_file" => checks::world_file(bytes),
        "fit_overrides" => checks::fit_overrides(bytes),
        _ => unreachable!("{target}"),
    }
}

const TARGETS: [&str; 8] = [
    "world_file",
    "fit_overrides",
    "targets_csv",
    "model_file",
    "run_config",
    "env_keywords",
    "urdf",
    "robot_file",
];

#[test]
fn the_seeds_parse() {
    for path in files("fuzz/seeds/model_file", None) {
        let bytes = std::fs::read(&path).unwrap();
        snake_rl::model::parse_policy(Path::new("seed"), &bytes).expect("a model seed loads");
    }
    // From their paths: a robot agent names its robot file relative to the repository's root, and
    // loading finds it beside models/ whatever the working directory (here tests/).
    for path in files("models", Some("safetensors")) {
        snake_rl::model::load_policy(&path).expect("a shipped model loads");
    }
    for bytes in seeds("run_config") {
        // A config's robot and world paths are relative to where it runs, the repository's root for
        // the shipped ones; this test runs in tests/.
        let text = std::str::from_utf8(&bytes)
            .unwrap()
            .replace("robot: robots/", &format!("robot: {ROOT}/robots/"))
            .replace("world: worlds/", &format!("world: {ROOT}/worlds/"));
        let layer = snake_rl::config::parse_yaml(&text).expect("a shipped config parses");
        snake_rl::config::RunConfig::from_layers(&[layer]).expect("a shipped config is valid");
    }
    for bytes in seeds("urdf") {
        let text = std::str::from_utf8(&bytes).unwrap();
        let robot =
            snake_core::urdf::UrdfRobot::parse(text, "seed").expect("a shipped URDF parses");
        robot
            .check_inertia(snake_core::urdf::InertiaSource::Shapes)
            .expect("a shipped URDF builds");
    }
    for path in files("robots", Some("yaml")) {
        snake_core::RobotRef::load(&path).expect("a shipped robot file loads");
    }
    for path in files("worlds", Some("yaml")) {
        snake_core::WorldRef::load(&path).expect("a shipped world file loads");
    }
    for bytes in seeds("env_keywords") {
        let serde_json::Value::Object(k) = serde_json::from_slice(&bytes).unwrap() else {
            panic!("a seed that is not a mapping");
        };
        snake_rl::config::env_from_keywords(&k).expect("a seed is valid");
    }
    for bytes in seeds("fit_overrides") {
        let overrides: snake_core::run_targets::Overrides =
            serde_json::from_slice(&bytes).expect("a seed parses");
        overrides.validate().expect("a seed is valid");
    }
}

#[test]
fn every_input_the_fuzzer_crashed_on_stays_fixed() {
    for target in TARGETS {
        for path in files(&format!("fuzz/regressions/{target}"), None) {
            check(target, &std::fs::read(&path).unwrap());
        }
    }
}

/// An edit of a real file: flip bytes, cut it short, or splice in bytes at a place.
#[derive(Debug, Clone)]
enum Edit {
    Set(usize, u8),
    Truncate(usize),
    Insert(usize, Vec<u8>),
}

fn edits() -> impl Strategy<Value = Vec<Edit>> {
    let edit = prop_oneof![
        4 => (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Set(i, b)),
        1 => any::<usize>().prop_map(Edit::Truncate),
        2 => (any::<usize>(), prop::collection::vec(any::<u8>(), 1..16))
            .prop_map(|(i, b)| Edit::Insert(i, b)),
    ];
    prop::collection::vec(edit, 1..8)
}

fn apply(mut bytes: Vec<u8>, edits: &[Edit]) -> Vec<u8> {
    for edit in edits {
        let n = bytes.len().max(1);
        match edit {
            Edit::Set(i, b) if !bytes.is_empty() => bytes[i % n] = *b,
            Edit::Set(..) => {}
            Edit::Truncate(i) => bytes.truncate(i % n),
            Edit::Insert(i, b) => {
                let at = i % (bytes.len() + 1);
                bytes.splice(at..at, b.iter().copied());
            }
        }
    }
    bytes
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn an_edited_model_file_is_a_model_or_one_line(seed in any::<prop::sample::Index>(), e in edits()) {
        let all = seeds("model_file");
        checks::model_file(&apply(all[seed.index(all.len())].clone(), &e));
    }

    #[test]
    fn an_edited_run_config_is_a_config_or_one_line(seed in any::<prop::sample::Index>(), e in edits()) {
        let all = seeds("run_config");
        checks::run_config(&apply(all[seed.index(all.len())].clone(), &e));
    }

    #[test]
    fn an_edited_urdf_is_a_robot_or_one_line(seed in any::<prop::sample::Index>(), e in edits()) {
        let all = seeds("urdf");
        checks::urdf(&apply(all[seed.index(all.len())].clone(), &e));
    }

    #[test]
    fn an_edited_robot_file_is_a_robot_or_one_line(seed in any::<prop::sample::Index>(), e in edits()) {
        let all = seeds("robot_file");
        checks::robot_file(&apply(all[seed.index(all.len())].clone(), &e));
    }

    #[test]
    fn an_edited_targets_table_is_targets_or_one_line(seed in any::<prop::sample::Index>(), e in edits()) {
        let all = seeds("targets_csv");
        checks::targets_csv(&apply(all[seed.index(all.len())].clone(), &e));
    }

    #[test]
    fn an_edited_world_file_is_a_world_or_one_line(seed in any::<prop::sample::Index>(), e in edits()) {
        let all = seeds("world_file");
        checks::world_file(&apply(all[seed.index(all.len())].clone(), &e));
    }

    #[test]
    fn edited_fit_overrides_are_a_trajectory_or_one_line(seed in any::<prop::sample::Index>(), e in edits()) {
        let all = seeds("fit_overrides");
        checks::fit_overrides(&apply(all[seed.index(all.len())].clone(), &e));
    }

    #[test]
    fn edited_env_keywords_are_a_config_or_one_line(seed in any::<prop::sample::Index>(), e in edits()) {
        let all = seeds("env_keywords");
        checks::env_keywords(&apply(all[seed.index(all.len())].clone(), &e));
    }
}

/// A rough ground's parameters over many orders of magnitude (a world file's `ground: rough`, the
/// env's `terrain.rough`): each either generates its grid or is refused in one line before anything
/// is allocated. Before the lattice check, a wavelength of 1e-9 panicked (capacity overflow) and
/// 3e-4 aborted the process asking for 22 GB.
fn log_uniform(low: f64, high: f64) -> impl Strategy<Value = f64> {
    (low.log10()..high.log10()).prop_map(|e| 10f64.powf(e))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn any_rough_ground_is_generated_or_refused_in_one_line(
        wavelength in log_uniform(1e-12, 1e3),
        spacing in log_uniform(1e-3, 1e3),
        size in log_uniform(1e-2, 2e4),
        hills in log_uniform(1e-12, 1e3),
    ) {
        let world = format!(
            "ground: {{rough: {{amplitude: 0.05, wavelength: {wavelength:e}, seed: 1, \
             size: [{size:e}, {size:e}], spacing: {spacing:e}}}}}\n"
        );
        checks::world_file(world.as_bytes());
        let keywords = format!(
            r#"{{"task": "rough", "joints": 2, "terrain": {{"rough": {{"wavelength": {wavelength:e},
               "hills_wavelength": {hills:e}, "spacing": {spacing:e}}}}}}}"#
        );
        checks::env_keywords(keywords.as_bytes());
    }
}

/// A robot file's `max_velocity` (`motors:` and per joint under `joints:`): zero, negative,
/// non-finite, beyond `limits::MAX_MOTOR_VELOCITY` or not a number is one line naming the file and the
/// key; `joints:` names only movable joints of the URDF. Left out, a motor has no limit.
#[test]
fn a_bad_max_velocity_is_one_line_naming_the_file_and_key() {
    let dir = std::env::temp_dir().join(format!("snakesim-max-velocity-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let box_link = |name: &str| {
        format!(
            "<link name=\"{name}\"><inertial><mass value=\"0.1\"/><inertia ixx=\"1e-4\" ixy=\"0\" \
             ixz=\"0\" iyy=\"1e-4\" iyz=\"0\" izz=\"1e-4\"/></inertial><collision><geometry>\
             <box size=\"0.1 0.1 0.1\"/></geometry></collision></link>"
        )
    };
    let urdf = format!(
        "<robot name=\"r\">{}{}{}<joint name=\"bend\" type=\"revolute\"><parent link=\"a\"/>\
         <child link=\"b\"/><origin xyz=\"0.2 0 0\"/><axis xyz=\"0 0 1\"/>\
         <limit lower=\"-1\" upper=\"1\" effort=\"5\" velocity=\"3\"/></joint>\
         <joint name=\"weld\" type=\"fixed\"><parent link=\"b\"/><child link=\"c\"/>\
         <origin xyz=\"0.2 0 0\"/></joint></robot>",
        box_link("a"),
        box_link("b"),
        box_link("c")
    );
    std::fs::write(dir.join("r.urdf"), urdf).unwrap();
    let load = |body: &str| {
        let file = dir.join("servo.yaml");
        std::fs::write(&file, format!("urdf: r.urdf\n{body}\n")).unwrap();
        snake_core::RobotSpec::load(&file)
    };
    let limit = snake_core::limits::MAX_MOTOR_VELOCITY;
    for value in [
        "0",
        "-1",
        "-0.0",
        ".nan",
        ".inf",
        "-.inf",
        "1e5",
        &format!("{:?}", limit * 1.001),
    ] {
        for (body, key) in [
            (
                format!("motors: {{max_velocity: {value}}}"),
                "motors: max_velocity",
            ),
            (
                format!("joints: {{bend: {{max_velocity: {value}}}}}"),
                "joints: bend: max_velocity",
            ),
        ] {
            let e = load(&body).expect_err(&body).to_string();
            assert!(!e.contains('\n'), "{body}: {e}");
            // A non-finite number is refused where the YAML is read, naming its key path (issue 57:
            // one check for every number of every file).
            let (key, expected) = if value.contains("nan") || value.contains("inf") {
                (key.replace(": ", "."), "must be a finite number, got ")
            } else {
                (key.to_owned(), "must be in (0, ")
            };
            assert!(
                e.contains("servo.yaml: ") && e.contains(&key) && e.contains(expected),
                "{body}: {e}"
            );
        }
    }
    for (body, expected) in [
        (
            "motors: {max_velocity: fast}",
            "servo.yaml: motors.max_velocity: invalid type",
        ),
        (
            "motors: {max_velocity: [1]}",
            "servo.yaml: motors.max_velocity: invalid type",
        ),
        ("motors: {max_speed: 1}", "unknown field `max_speed`"),
        ("joints: {bend: {speed: 1}}", "unknown field `speed`"),
        ("joints: {bend: 2}", "servo.yaml: joints.bend: invalid type"),
        (
            "joints: {neck: {max_velocity: 1}}",
            "servo.yaml: joints: neck: no such joint in",
        ),
        (
            "joints: {weld: {max_velocity: 1}}",
            "servo.yaml: joints: weld: a fixed joint has no motor in",
        ),
    ] {
        let e = load(body).expect_err(body).to_string();
        assert!(!e.contains('\n') && e.contains(expected), "{body}: {e}");
    }
    // The largest value is allowed; a joint's own value wins over the robot's; absent is no limit.
    let spec = load(&format!(
        "motors: {{max_velocity: {limit:?}}}\njoints: {{bend: {{max_velocity: 2.5}}}}"
    ))
    .unwrap();
    assert_eq!(
        (spec.motors.max_velocity, spec.max_velocity(0)),
        (Some(limit), Some(2.5))
    );
    let spec = load("motors: {max_velocity: 1.5}").unwrap();
    assert_eq!(spec.max_velocity(0), Some(1.5));
    let spec = load("motors: {kp: 0.2}").unwrap();
    assert_eq!(
        (spec.motors.max_velocity, spec.max_velocity(0)),
        (None, None)
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// `snakesim calibrate`'s candidates: any key at any value over many orders of magnitude (CMA-ES
/// tries whatever the user's bounds allow) gives a finite trajectory or a one-line error, never a
/// panic or a non-finite state passed on as a trajectory.
const FIT_KEYS: [&str; 12] = [
    "motors.kp",
    "motors.kd",
    "motors.max_velocity",
    "ground_friction",
    "lateral_friction",
    "anisotropic_friction.x",
    "anisotropic_friction.y",
    "anisotropic_friction.z",
    "skin_friction.forward",
    "skin_friction.backward",
    "skin_friction.transverse",
    "mass_scale",
];

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn any_fitted_value_is_a_trajectory_or_one_line(
        keys in prop::sample::subsequence(FIT_KEYS.to_vec(), 1..4),
        values in prop::collection::vec(prop_oneof![log_uniform(1e-9, 1e9), Just(0.0)], 4),
    ) {
        let fields: Vec<String> =
            keys.iter().zip(&values).map(|(k, v)| format!("\"{k}\": {v:e}")).collect();
        checks::fit_overrides(format!("{{{}}}", fields.join(", ")).as_bytes());
    }
}

/// Issue 57's regressions, kept in fuzz/regressions/: a non-finite YAML number is refused naming its
/// key path (serde would read it as "not given" and drop the setting), a password line is not quoted,
/// and a randomize scale that cannot build is refused before any reset.
#[test]
fn non_finite_numbers_password_lines_and_unbuildable_scales_are_refused() {
    let read = |target: &str, name: &str| {
        std::fs::read_to_string(format!("{ROOT}/fuzz/regressions/{target}/{name}")).unwrap()
    };
    let config = snake_rl::config::parse_yaml(&read("run_config", "non-finite-yaml.yaml"));
    let e = config.unwrap_err().0;
    assert!(e.contains("must be a finite number, got .nan"), "{e}");
    let dir = std::env::temp_dir().join(format!("snakesim-parsers-57-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, expected) in [
        (
            "non-finite-friction.yaml",
            "ground_friction: must be a finite number, got .nan",
        ),
        (
            "password-line.yaml",
            "unknown field <78 characters, not shown>",
        ),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, read("world_file", name)).unwrap();
        let e = snake_core::WorldSpec::load(&path).unwrap_err().to_string();
        assert!(e.contains(expected) && !e.contains("$6$"), "{e}");
    }
    std::fs::write(
        dir.join("x.urdf"),
        include_str!("../robots/paper-cubes-5.urdf"),
    )
    .unwrap();
    let robot = dir.join("r.yaml");
    std::fs::write(&robot, read("robot_file", "non-finite-motors.yaml")).unwrap();
    let e = snake_core::RobotSpec::load(&robot).unwrap_err().to_string();
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(
        e.contains("motors.kd: must be a finite number, got .inf"),
        "{e}"
    );
    let keywords: serde_json::Map<String, serde_json::Value> =
        serde_json::from_str(&read("env_keywords", "randomize-scale-1e-300.json")).unwrap();
    let e = snake_rl::config::env_from_keywords(&keywords).map_or_else(
        |e| e.0,
        |config| snake_core::SnakeEnv::new(config).unwrap_err().to_string(),
    );
    assert!(
        e.contains("randomize.mass_scale: must lie within 0.01 <= low <= high <= 100, got [1e-300, 1e-300]"),
        "{e}"
    );
}
