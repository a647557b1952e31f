//! Initialisation by imitation (`init`): the fit, determinism, resume through it, bad input.

use std::path::{Path, PathBuf};

use serde_json::{json, Map, Value};
use snake_core::controllers::{Imitable, JointsSine};
use snake_core::{StepBuffers, VecSnakeEnv};
use snake_rl::config::{InitConfig, RunConfig};
use snake_rl::imitate;
use snake_rl::model;
use snake_rl::nn::{init_params, ActorCritic};
use snake_rl::trainer::{self, InitProgress, Observer, Outcome, Session, Silent};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("snake-rl-init-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// A run of about a second with an init of 512 controller steps.
fn tiny(extra: Value) -> RunConfig {
    let mut layer = json!({
        "timesteps": 1024, "n_envs": 2, "eval_freq": 512, "eval_episodes": 2, "checkpoint_freq": 512,
        "threads": 2, "ppo": {"n_steps": 256, "batch_size": 64, "n_epochs": 2},
        "env": {"max_episode_steps": 100},
        "init": {"imitate": "steered_sine", "steps": 512, "epochs": 3, "batch_size": 64, "critic": true},
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

fn params(dir: &Path) -> Vec<u32> {
    let p = model::load_policy(&dir.join("model.safetensors")).unwrap();
    p.params.iter().map(|x| x.to_bits()).collect()
}

/// Behaviour cloning on a tiny env (3 joints, 2 envs x 2048 steps of the steered sine, PPO-small):
/// the mean squared error to the controller's actions falls from that of the untrained network
/// (means near 0: about the actions' mean square; measured 0.054) to below 1e-3 in 20 epochs
/// (measured 2e-5: a residual of 0.005 rad per joint on a wave of 0.4 rad; the bound leaves a
/// factor 50 for other platforms' rounding, and is still 50 times below the start). Figures with
/// `--nocapture`.
#[test]
fn behaviour_cloning_fits_the_controller() {
    let config =
        RunConfig::from_yaml("joints: 3\nn_envs: 2\nenv: {max_episode_steps: 500}").unwrap();
    let env = config.env_config().unwrap();
    let mut envs = VecSnakeEnv::new(env.clone(), 2)
        .unwrap()
        .with_threads(1)
        .unwrap();
    let mut out = StepBuffers::for_envs(&envs);
    envs.reset(Some(3), &mut out.obs).unwrap();
    let mut controller = JointsSine::new(Imitable::SteeredSine, &env, 2).unwrap();
    let mut norm = snake_rl::normalize::Normalizer::new(env.observation_dim(), 2, 0.99);
    let data = imitate::collect(
        &mut controller,
        &mut envs,
        &mut out,
        4096,
        0.99,
        Some(&mut norm),
        &mut |_| false,
    )
    .unwrap()
    .unwrap();
    assert_eq!(data.rows, 4096);
    assert!(
        data.obs.iter().all(|x| x.abs() <= 10.0),
        "normalised observations"
    );
    let net = ActorCritic::new(config.arch.clone(), env.observation_dim(), env.action_dim());
    let mut rng = <rand_chacha::ChaCha12Rng as rand::SeedableRng>::seed_from_u64(1);
    let mut params = init_params(&net, &mut rng);
    let before = imitate::bc_loss(&net, &params, &data);
    let init = InitConfig {
        epochs: 20,
        batch_size: 64,
        critic: true,
        ..InitConfig::new(Imitable::SteeredSine)
    };
    let o = net.log_std_offset();
    let log_std = params[o..o + net.act_dim()].to_vec();
    let losses = imitate::fit(&net, &mut params, &data, &init, &mut rng, &mut |_| false).unwrap();
    let after = imitate::bc_loss(&net, &params, &data);
    println!(
        "bc mse before {before:.5}, after {after:.5}; critic loss first {:?}, last {:?}",
        losses[0].critic_loss,
        losses.last().unwrap().critic_loss
    );
    assert!(before > 0.02, "{before}");
    assert!(after < 1e-3, "mse after the fit {after}");
    assert!(losses.last().unwrap().critic_loss < losses[0].critic_loss);
    assert_eq!(
        params[o..o + net.act_dim()],
        log_std[..],
        "log_std is the trainer's to set"
    );
}

#[test]
fn a_seed_gives_one_initialised_run() {
    let (a, b, c) = (scratch("same-a"), scratch("same-b"), scratch("none"));
    for dir in [&a, &b] {
        trainer::train(&session(tiny(json!({})), dir, false), &mut Silent).unwrap();
    }
    assert!(params(&a) == params(&b), "two initialised runs differ");
    let mut plain = tiny(json!({}));
    plain.init = None;
    trainer::train(&session(plain, &c, false), &mut Silent).unwrap();
    assert!(params(&a) != params(&c), "the init changed nothing");
    // The fitted policy's noise is init.log_std until PPO moves it; the row at 0 is the fitted
    // policy alone.
    let evals = std::fs::read_to_string(a.join("evaluations.csv")).unwrap();
    assert!(evals.lines().nth(1).unwrap().starts_with("0,"), "{evals}");
    // Its progress is in TensorBoard (the tags are plain bytes of the event records).
    let tb = a
        .join(snake_rl::rundir::TB_DIR)
        .join(snake_rl::rundir::TB_RUN);
    let events: Vec<u8> = std::fs::read_dir(&tb)
        .unwrap()
        .flat_map(|e| std::fs::read(e.unwrap().path()).unwrap())
        .collect();
    for tag in [
        "init/bc_loss",
        "init/critic_loss",
        "init/seconds",
        "init/controller_ep_rew_mean",
    ] {
        assert!(
            events.windows(tag.len()).any(|w| w == tag.as_bytes()),
            "{tag} is not logged"
        );
    }
    for d in [a, b, c] {
        std::fs::remove_dir_all(d).ok();
    }
}

/// Stops during the init once the controller has taken `at` steps, or (`at` = None) counts the
/// init's reports.
struct StopInInit(Option<u64>, usize);

impl Observer for StopInInit {
    fn on_init(&mut self, p: &InitProgress) {
        self.1 += 1;
        if let Some(at) = self.0 {
            if p.steps >= at {
                self.0 = Some(0);
            }
        }
    }

    fn should_stop(&mut self) -> bool {
        self.0 == Some(0)
    }

    fn on_note(&mut self, _message: &str) {}
}

#[test]
fn resume_goes_through_the_init() {
    let (whole, stopped) = (scratch("whole"), scratch("stopped"));
    trainer::train(&session(tiny(json!({})), &whole, false), &mut Silent).unwrap();
    // Stopped during the init: the checkpoint says so, and resuming starts the init over.
    let outcome = trainer::train(
        &session(tiny(json!({})), &stopped, false),
        &mut StopInInit(Some(200), 0),
    )
    .unwrap();
    let Outcome::Interrupted(s, path) = outcome else {
        panic!("not interrupted")
    };
    assert_eq!(s.timesteps, 0);
    assert!(model::load_checkpoint(&path).unwrap().init_pending);
    let mut count = StopInInit(None, 0);
    trainer::train(&session(tiny(json!({})), &stopped, true), &mut count).unwrap();
    assert!(count.1 > 0, "the init was not done again");
    assert!(
        params(&whole) == params(&stopped),
        "a run resumed in its init differs"
    );
    // The fitted policy alone is kept as the checkpoint at 0 timesteps.
    let fitted =
        model::load_checkpoint(&whole.join("checkpoints/model_0_steps.safetensors")).unwrap();
    assert!(!fitted.init_pending);
    assert_eq!(fitted.reason, "init");
    // Stopped after the init: its checkpoints hold the fitted policy, and resuming does not redo it.
    std::fs::remove_dir_all(&stopped).ok();
    struct StopAt(u64, u64);
    impl Observer for StopAt {
        fn on_step(&mut self, t: u64) {
            self.1 = t;
        }
        fn should_stop(&mut self) -> bool {
            self.1 >= self.0
        }
        fn on_note(&mut self, _message: &str) {}
    }
    let outcome = trainer::train(
        &session(tiny(json!({})), &stopped, false),
        &mut StopAt(700, 0),
    )
    .unwrap();
    let Outcome::Interrupted(s, path) = outcome else {
        panic!("not interrupted")
    };
    assert_eq!(s.timesteps, 512);
    assert!(!model::load_checkpoint(&path).unwrap().init_pending);
    let mut count = StopInInit(None, 0);
    trainer::train(&session(tiny(json!({})), &stopped, true), &mut count).unwrap();
    assert_eq!(count.1, 0, "the init was done again");
    for d in [whole, stopped] {
        std::fs::remove_dir_all(d).ok();
    }
}

#[test]
fn bad_init_tables_name_the_key() {
    let error = |yaml: &str| RunConfig::from_yaml(yaml).unwrap_err().to_string();
    let cases = [
        (
            "init: {imitate: wiggle}",
            "init.imitate: unknown variant `wiggle`",
        ),
        ("init: {steps: 10}", "init: missing field `imitate`"),
        (
            "init: {imitate: sine, steps: 0}",
            "init.steps: must be in [1, 4194304], got 0",
        ),
        (
            "init: {imitate: sine, steps: 4194305}",
            "init.steps: must be in [1, 4194304]",
        ),
        (
            "init: {imitate: sine, epochs: 0}",
            "init.epochs: must be in [1,",
        ),
        (
            "init: {imitate: sine, steps: 100, batch_size: 200}",
            "init.batch_size: must be at most init.steps",
        ),
        (
            "init: {imitate: sine, log_std: 5}",
            "init.log_std: must be in [-20, 2], got 5",
        ),
        (
            "init: {imitate: sine, learning_rate: 0}",
            "init.learning_rate: must be positive",
        ),
        (
            "init: {imitate: sine, anchor: -1}",
            "init.anchor: must be in [0, 1000000], got -1",
        ),
        (
            "init: {imitate: sine, anchor: lin_2e6}",
            "init.anchor: must be in [0, 1000000], got 2000000",
        ),
        (
            "init: {imitate: sine, anchor: lin_x}",
            "init.anchor: expected a number or lin_<number>",
        ),
        (
            "init: {imitate: sine, bogus: 1}",
            "init.bogus: unknown field `bogus`",
        ),
        (
            "init: {imitate: sine}\nenv: {task: goal}",
            "init.imitate: sine sets joint targets: it needs action mode 'joints', got 'gait'",
        ),
        (
            "init: {imitate: sine}\ntrainer: sb3",
            "init: only the native trainer",
        ),
    ];
    for (yaml, start) in cases {
        let e = error(yaml);
        assert!(e.starts_with(start), "{yaml}: {e}");
        assert!(!e.contains('\n'), "{e}");
    }
    // No init: nothing serialised, so run configurations and models written before it are unchanged.
    assert!(!RunConfig::default().to_yaml().contains("\ninit:"));
    let c = RunConfig::from_yaml("init: {imitate: steered_sine}").unwrap();
    assert_eq!(RunConfig::from_yaml(&c.to_yaml()).unwrap(), c);
    assert_eq!(
        RunConfig::default().identity_difference(&c).unwrap().0,
        "init"
    );
}

/// The policy's mean squared distance to the steered sine on 2048 fresh steps of the controller, the
/// observations normalised with the model's statistics.
fn distance_to_controller(config: &RunConfig, model_file: &Path) -> f64 {
    let env = config.env_config().unwrap();
    let mut envs = VecSnakeEnv::new(env.clone(), 2)
        .unwrap()
        .with_threads(1)
        .unwrap();
    let mut out = StepBuffers::for_envs(&envs);
    envs.reset(Some(77), &mut out.obs).unwrap();
    let mut controller = JointsSine::new(Imitable::SteeredSine, &env, 2).unwrap();
    let data = imitate::collect(
        &mut controller,
        &mut envs,
        &mut out,
        2048,
        0.99,
        None,
        &mut |_| false,
    )
    .unwrap()
    .unwrap();
    let mut data = data;
    let policy = model::load_policy(model_file).unwrap();
    policy.obs_rms.as_ref().unwrap().normalize(&mut data.obs);
    imitate::bc_loss(&policy.net, &policy.params, &data)
}

/// `init.anchor`: a weight of 0 is PPO alone, bit for bit (the controller runs beside the rollouts
/// but no term joins the loss); with the fit itself made negligible (one epoch at a learning rate of
/// 1e-6), a heavy anchor alone brings PPO's policy towards the controller while plain PPO (at a
/// learning rate that moves it) walks away, and the anchor's loss is logged.
#[test]
fn an_anchor_keeps_the_policy_at_its_controller() {
    let run = |anchor: Value, name: &str| {
        let dir = scratch(name);
        let config = tiny(json!({
            "joints": 3, "normalize": true, "timesteps": 8192, "eval_freq": 0,
            "ppo": {"learning_rate": 1e-3, "n_epochs": 5, "max_grad_norm": 100.0},
            "init": {"epochs": 1, "learning_rate": 1e-6, "log_std": -1.0, "anchor": anchor},
        }));
        struct Show;
        impl Observer for Show {
            fn on_update(&mut self, p: &trainer::Progress) {
                eprintln!(
                    "DEBUG anchor_loss {:.6} policy {:.4}",
                    p.update.anchor_loss, p.update.policy_gradient_loss
                );
            }
            fn on_note(&mut self, _message: &str) {}
        }
        trainer::train(&session(config.clone(), &dir, false), &mut Show).unwrap();
        (config, dir)
    };
    let (plain_config, plain) = run(Value::Null, "anchor-none");
    assert!(plain_config.init.as_ref().unwrap().anchor.is_none());
    let (_, zero) = run(json!(0.0), "anchor-zero");
    assert!(params(&plain) == params(&zero), "anchor 0 changed the run");
    let (config, heavy) = run(json!(10000.0), "anchor-heavy");
    let (free, kept) = (
        distance_to_controller(&plain_config, &plain.join("model.safetensors")),
        distance_to_controller(&config, &heavy.join("model.safetensors")),
    );
    let start = distance_to_controller(
        &config,
        &heavy.join("checkpoints").join("model_0_steps.safetensors"),
    );
    println!(
        "mse to the controller: at the start {start:.5}; after PPO without anchor {free:.5}, \
         anchored {kept:.5}"
    );
    // Measured: 0.0076 at the start, 0.032 without the anchor, 0.0032 with it.
    assert!(
        kept < 0.5 * start && kept < 0.2 * free,
        "start {start}, anchored {kept}, free {free}"
    );
    let tb = heavy
        .join(snake_rl::rundir::TB_DIR)
        .join(snake_rl::rundir::TB_RUN);
    let events: Vec<u8> = std::fs::read_dir(&tb)
        .unwrap()
        .flat_map(|e| std::fs::read(e.unwrap().path()).unwrap())
        .collect();
    for tag in ["train/anchor_loss", "train/anchor_weight"] {
        assert!(
            events.windows(tag.len()).any(|w| w == tag.as_bytes()),
            "{tag} not logged"
        );
    }
    for d in [plain, zero, heavy] {
        std::fs::remove_dir_all(d).ok();
    }
}
