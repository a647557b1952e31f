//! The native trainer end to end: the run directory it writes, bit-identical repeats, resuming,
//! stopping on request, refusals, and damaged model files.

use std::path::{Path, PathBuf};

use serde_json::{json, Map, Value};
use snake_rl::config::RunConfig;
use snake_rl::model;
use snake_rl::rundir::RunDir;
use snake_rl::trainer::{self, Observer, Outcome, Session, Silent};

/// A fresh, empty folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("snake-rl-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// A run that takes about a second: 2 envs x 256 steps per rollout, short episodes.
fn tiny(extra: Value) -> RunConfig {
    let mut layer = json!({
        "timesteps": 2048, "n_envs": 2, "eval_freq": 1024, "eval_episodes": 3, "checkpoint_freq": 1024,
        "threads": 2, "ppo": {"n_steps": 256, "batch_size": 64, "n_epochs": 2},
        "env": {"max_episode_steps": 100},
    });
    snake_rl::config::merge(&mut layer, &extra);
    RunConfig::from_layers(&[layer]).expect("a valid configuration")
}

fn session(config: RunConfig, dir: &Path, resume: bool) -> Session {
    Session {
        config,
        run_dir: dir.to_path_buf(),
        resume,
        versions: Map::new(),
    }
}

fn finished(outcome: Outcome) -> trainer::Summary {
    match outcome {
        Outcome::Finished(s) => s,
        Outcome::Interrupted(..) => panic!("interrupted"),
    }
}

fn evaluations(dir: &Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(dir.join("evaluations.csv"))
        .unwrap()
        .lines()
        .map(|l| l.split(',').map(str::to_owned).collect())
        .collect()
}

#[test]
fn a_run_writes_its_directory() {
    let dir = scratch("run");
    let s = finished(trainer::train(&session(tiny(json!({})), &dir, false), &mut Silent).unwrap());
    assert_eq!((s.start_timesteps, s.timesteps), (0, 2048));
    for file in [
        "config.yaml",
        "versions.json",
        "evaluations.csv",
        "model.safetensors",
    ] {
        assert!(dir.join(file).is_file(), "{file}");
    }
    let saved =
        RunConfig::from_yaml(&std::fs::read_to_string(dir.join("config.yaml")).unwrap()).unwrap();
    assert_eq!(
        saved,
        tiny(json!({})).resolved(),
        "config.yaml reads back as the resolved config"
    );
    let rows = evaluations(&dir);
    assert_eq!(rows[0].join(","), snake_rl::rundir::EVAL_FIELDS.join(","));
    let steps: Vec<&str> = rows[1..].iter().map(|r| r[0].as_str()).collect();
    assert_eq!(
        steps,
        ["1024", "2048"],
        "evaluated at each multiple of eval_freq, the last at the end"
    );
    let checkpoints: Vec<u64> = RunDir::open(&dir)
        .unwrap()
        .0
        .checkpoints()
        .iter()
        .map(|c| c.0)
        .collect();
    assert_eq!(checkpoints, [1024, 2048]);
    let note: Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("checkpoints/model_2048_steps.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(note["reason"], "final");
    let policy = model::load_policy(&dir.join("model.safetensors")).unwrap();
    assert_eq!(
        (policy.timesteps, policy.env.joints, policy.net.obs_dim()),
        (2048, 5, 12)
    );
    let c = model::load_checkpoint(&dir.join("checkpoints/model_2048_steps.safetensors")).unwrap();
    assert_eq!(c.policy.params, policy.params);
    assert!(c.adam.step > 0);
    let events = std::fs::read_dir(dir.join("tb/PPO_1")).unwrap().count();
    assert_eq!(events, 1, "one TensorBoard event file");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_seed_and_a_thread_count_give_the_same_run_bit_for_bit() {
    let (a, b) = (scratch("same-a"), scratch("same-b"));
    for dir in [&a, &b] {
        finished(trainer::train(&session(tiny(json!({})), dir, false), &mut Silent).unwrap());
    }
    // Parameters bit for bit (the files' metadata is a map whose order is not fixed).
    let params = |d: &Path| -> Vec<u32> {
        let p = model::load_policy(&d.join("model.safetensors")).unwrap();
        p.params.iter().map(|x| x.to_bits()).collect()
    };
    assert!(params(&a) == params(&b), "the two runs' parameters differ");
    let strip_wall = |rows: Vec<Vec<String>>| -> Vec<Vec<String>> {
        rows.into_iter()
            .map(|mut r| {
                r.pop();
                r
            })
            .collect()
    };
    assert_eq!(strip_wall(evaluations(&a)), strip_wall(evaluations(&b)));
    // Another seed learns something else.
    let c = scratch("same-c");
    finished(trainer::train(&session(tiny(json!({"seed": 7})), &c, false), &mut Silent).unwrap());
    assert!(
        params(&a) != params(&c),
        "another seed gave the same parameters"
    );
    for d in [a, b, c] {
        std::fs::remove_dir_all(d).ok();
    }
}

#[test]
fn one_thread_is_a_valid_run_too() {
    let dir = scratch("one-thread");
    finished(
        trainer::train(
            &session(tiny(json!({"threads": 1})), &dir, false),
            &mut Silent,
        )
        .unwrap(),
    );
    assert!(model::load_policy(&dir.join("model.safetensors")).is_ok());
    std::fs::remove_dir_all(&dir).ok();
}

/// Stops training once it has taken this many timesteps.
struct StopAfter(u64, u64);

impl Observer for StopAfter {
    fn on_step(&mut self, timesteps: u64) {
        self.1 = timesteps;
    }

    fn should_stop(&mut self) -> bool {
        self.1 >= self.0
    }
}

#[test]
fn stopping_saves_a_checkpoint_and_resume_continues() {
    let dir = scratch("resume");
    // 1200 timesteps: in the third rollout of 512, after the evaluation at 1024.
    let outcome = trainer::train(
        &session(tiny(json!({})), &dir, false),
        &mut StopAfter(1200, 0),
    )
    .unwrap();
    let Outcome::Interrupted(s, path) = outcome else {
        panic!("not interrupted")
    };
    assert_eq!(
        s.timesteps, 1024,
        "the state of the last complete update is saved"
    );
    assert_eq!(path, dir.join("checkpoints/model_1024_steps.safetensors"));
    assert!(
        dir.join("model.safetensors").is_file(),
        "the model is saved on interruption too"
    );
    let stopped_at = s.timesteps;

    // What is learnt cannot change on resume; the length of the run can.
    let err =
        trainer::train(&session(tiny(json!({"seed": 1})), &dir, true), &mut Silent).unwrap_err();
    assert!(
        err.to_string()
            .starts_with("cannot change seed when resuming"),
        "{err}"
    );
    let s = finished(
        trainer::train(
            &session(tiny(json!({"timesteps": 3072})), &dir, true),
            &mut Silent,
        )
        .unwrap(),
    );
    assert_eq!(s.start_timesteps, stopped_at);
    assert!(s.timesteps >= 3072);
    let steps: Vec<u64> = evaluations(&dir)[1..]
        .iter()
        .map(|r| r[0].parse().unwrap())
        .collect();
    assert_eq!(
        steps.first(),
        Some(&1024),
        "the evaluation before the checkpoint is kept"
    );
    assert!(
        steps.windows(2).all(|w| w[0] < w[1]),
        "evaluations stay in order: {steps:?}"
    );
    let err = trainer::train(
        &session(tiny(json!({"timesteps": 3072})), &dir, true),
        &mut Silent,
    )
    .unwrap_err();
    assert!(err.to_string().contains("already has"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn refusals_are_one_line_and_write_nothing() {
    let dir = scratch("refuse");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("keep.txt"), "precious").unwrap();
    let err = trainer::train(&session(tiny(json!({})), &dir, false), &mut Silent).unwrap_err();
    assert!(
        err.to_string().contains("already exists and is not empty"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        1,
        "nothing was added"
    );
    let err = trainer::train(&session(tiny(json!({})), &dir, true), &mut Silent).unwrap_err();
    assert!(err.to_string().contains("no readable config.yaml"), "{err}");
    let err = trainer::train(
        &session(tiny(json!({"trainer": "sb3"})), &scratch("sb3"), false),
        &mut Silent,
    )
    .unwrap_err();
    assert!(
        err.to_string()
            .starts_with("trainer sb3 is not the native trainer"),
        "{err}"
    );
    assert!(!err.to_string().contains('\n'));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn damaged_model_files_are_clear_errors() {
    let dir = scratch("damaged");
    finished(
        trainer::train(
            &session(tiny(json!({"timesteps": 512, "eval_freq": 0})), &dir, false),
            &mut Silent,
        )
        .unwrap(),
    );
    let good = std::fs::read(dir.join("model.safetensors")).unwrap();
    let bad = dir.join("bad.safetensors");
    let check = |bytes: &[u8], expected: &str| {
        std::fs::write(&bad, bytes).unwrap();
        let e = model::load_policy(&bad).unwrap_err().to_string();
        assert!(e.contains(expected), "expected '{expected}' in: {e}");
        assert!(!e.contains('\n'), "{e}");
    };
    check(
        &good[..good.len() / 2],
        "corrupt or truncated safetensors file",
    );
    check(b"garbage", "corrupt or truncated safetensors file");
    check(&[], "corrupt or truncated safetensors file");
    // Metadata that lies: edit the JSON header in place, keeping its length.
    let header_len = u64::from_le_bytes(good[..8].try_into().unwrap()) as usize;
    let header = String::from_utf8(good[8..8 + header_len].to_vec()).unwrap();
    let lie = |from: &str, to: &str| {
        assert_eq!(from.len(), to.len());
        let mut bytes = good.clone();
        let h = header.replacen(from, to, 1);
        assert_ne!(h, header, "{from} is in the header");
        bytes[8..8 + header_len].copy_from_slice(h.as_bytes());
        bytes
    };
    check(
        &lie("\"arch\":\"small\"", "\"arch\":\"large\""),
        "tensor 'features_extractor.shared_net.0.weight' is missing",
    );
    check(
        &lie("\"joints\":\"5\"", "\"joints\":\"6\""),
        "its env has 14 observations and 6 actions",
    );
    check(
        &lie("\"format\":\"snakesim-ppo\"", "\"format\":\"snakesim-xyz\""),
        "its format is 'snakesim-xyz'",
    );
    check(
        &lie("\"obs_dim\":\"12\"", "\"obs_dim\":\"x2\""),
        "metadata 'obs_dim' = 'x2' is not valid",
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_non_finite_loss_stops_training_after_saving_the_last_good_state() {
    // A learning rate of 1e10 is valid but absurd: one update sends log_std to +-1e10, and the next
    // update's loss is not finite.
    let dir = scratch("non-finite");
    let config = tiny(
        json!({"timesteps": 4096, "eval_freq": 0, "checkpoint_freq": 0, "ppo": {"learning_rate": 1e10}}),
    );
    let err = trainer::train(&session(config, &dir, false), &mut Silent).unwrap_err();
    let message = err.to_string();
    assert!(
        matches!(err, trainer::TrainError::NonFinite(_)),
        "{message}"
    );
    assert!(
        message.starts_with("training stopped at update "),
        "{message}"
    );
    assert!(message.contains("non-finite"), "{message}");
    assert!(!message.contains('\n'));
    let (steps, path) = RunDir::open(&dir)
        .unwrap()
        .0
        .checkpoints()
        .pop()
        .expect("a checkpoint was saved");
    assert!(message.contains(&path.display().to_string()), "{message}");
    let c = model::load_checkpoint(&path).expect("the saved state loads");
    assert!(c.policy.params.iter().all(|p| p.is_finite()));
    assert_eq!(c.reason, "non-finite");
    assert!(steps < 4096);
    std::fs::remove_dir_all(&dir).ok();
}

/// `energy_ramp` sets the training envs' energy weight: held at 0 (the ramp starts after the run), the
/// run learns exactly what a run without the term learns, while its evaluations, which use the
/// configured weight, pay for the energy; the same weight without the ramp changes what is learnt.
#[test]
fn energy_ramp_controls_the_training_reward() {
    let run = |name: &str, extra: Value| {
        let dir = scratch(name);
        finished(trainer::train(&session(tiny(extra), &dir, false), &mut Silent).unwrap());
        let params = model::load_policy(&dir.join("model.safetensors"))
            .unwrap()
            .params;
        let last_return: f64 = evaluations(&dir).last().unwrap()[1].parse().unwrap();
        std::fs::remove_dir_all(&dir).ok();
        (params, last_return)
    };
    let energy = json!({"env": {"reward": {"energy_weight": 5.0}}});
    let (plain, plain_return) = run("ramp-none", json!({}));
    let mut held = energy.clone();
    held["energy_ramp"] = json!([1_000_000, 2_000_000]);
    let (held_at_zero, held_return) = run("ramp-held", held);
    let (penalised, _) = run("ramp-off", energy);
    assert_eq!(held_at_zero, plain, "weight 0 throughout: the same run");
    assert!(
        held_return < plain_return,
        "evaluations use the configured weight: {held_return} against {plain_return}"
    );
    assert_ne!(
        penalised, plain,
        "the energy term without a ramp changes the run"
    );
}

/// Edits the robot file at the first evaluation, halfway through the run.
struct EditAtEvaluation(PathBuf);

impl Observer for EditAtEvaluation {
    fn on_evaluation(&mut self, _row: &snake_rl::rundir::EvaluationRow) {
        let text = std::fs::read_to_string(&self.0).unwrap();
        std::fs::write(&self.0, text.replace("kp: 0.1,", "kp: 0.4,")).unwrap();
    }
    fn on_note(&mut self, _message: &str) {}
}

#[test]
fn a_robot_file_edited_while_a_run_trains_is_not_what_its_models_record() {
    let dir = scratch("edited-robot");
    let bots = dir.with_extension("bots");
    std::fs::create_dir_all(&bots).unwrap();
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("../robots");
    let mut original = Map::new();
    for name in ["paper-cubes-5.yaml", "paper-cubes-5.urdf"] {
        let text = std::fs::read_to_string(shipped.join(name)).unwrap();
        std::fs::write(bots.join(name), &text).unwrap();
        original.insert(name.into(), Value::String(text));
    }
    let robot = bots.join("paper-cubes-5.yaml");
    let config = tiny(json!({"joints": 5, "env": {"robot": robot.to_str().unwrap()}}));
    let mut observer = EditAtEvaluation(robot.clone());
    finished(trainer::train(&session(config, &dir, false), &mut observer).unwrap());
    assert!(std::fs::read_to_string(&robot)
        .unwrap()
        .contains("kp: 0.4,"));
    for file in [
        dir.join("model.safetensors"),
        dir.join("checkpoints/model_2048_steps.safetensors"),
    ] {
        let bytes = std::fs::read(&file).unwrap();
        let (_, meta) = safetensors::SafeTensors::read_metadata(&bytes).unwrap();
        let meta = meta.metadata().clone().unwrap();
        let record: Value = serde_json::from_str(&meta["env_files"]).unwrap();
        assert_eq!(
            record["robot"]["files"],
            Value::Object(original.clone()),
            "{file:?}"
        );
        // Loaded, it acts on the robot as trained: its env keyword is the record itself.
        let (policy, notes) = model::load_policy_noted(&file).unwrap();
        assert!(policy.env.env["robot"].is_object(), "{file:?}");
        assert!(notes.is_empty(), "already a record: {notes:?}");
    }
    std::fs::remove_dir_all(&dir).ok();
    std::fs::remove_dir_all(&bots).ok();
}
